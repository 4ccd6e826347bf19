//! The likelihood rebuilt from a fit file (`estimate::fit::fit_likelihood`) is the fit's own: at
//! the exported parameters it gives the file's χ² to rounding, its parts add up, it rises
//! away from the estimate, and bad use gets a named error.

use std::path::Path;
use std::process::Command;
use vanefit::data::Dataset;
use vanefit::data::FitFile;
use vanefit::estimate::CHI2_95;
use vanefit::estimate::{FitLikelihood, FitLikelihoodError};

const DATASET: &str = "measurements/ar034-synthetic";

/// A short fit of the shipped dataset written by the CLI (curvature intervals: seconds).
fn short_fit(dir: &Path) -> FitFile {
    let out = dir.join("fit.json");
    let o = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(["fit", DATASET, "--starts", "2", "--max-iters", "150"])
        .args(["--uncertainty", "curvature", "--no-plots", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    FitFile::read(&out).unwrap()
}

#[test]
fn the_rebuilt_likelihood_gives_the_fits_own_chi2() {
    let dir = tempfile::tempdir().unwrap();
    let fit = short_fit(dir.path());
    let stats = fit.statistics.clone().unwrap();
    assert_eq!(stats.linearised_at.len(), fit.estimated.len());
    let ds = Dataset::load(Path::new(DATASET)).unwrap();
    let lik = FitLikelihood::from_fit(&ds, &fit).unwrap();
    assert_eq!(lik.names(), fit.estimated);
    let x = lik.estimate();
    let chi2 = lik.try_chi2(&x).unwrap();
    let stated = stats.likelihood_chi2.unwrap();
    let rel = (chi2 - stated).abs() / stated;
    assert!(rel < 1e-9, "rebuilt {chi2} vs file {stated} ({rel:e})");
    assert_eq!(lik.chi2_min(), stated);
    // Widening only lowers χ²; the threshold is χ²₁(0.95) times a scale ≥ 1.
    assert!(
        stated <= stats.goodness.chi2 + 1e-9 * stats.goodness.chi2,
        "{stated} vs {}",
        stats.goodness.chi2
    );
    let threshold = stats.profile_threshold.unwrap();
    assert_eq!(lik.threshold(), threshold);
    assert!((CHI2_95..1.5 * CHI2_95).contains(&threshold), "{threshold}");

    // The parts: data rows and nuisance priors add up to χ²; each channel's residuals are
    // (simulated + nuisance shift − data)/σ with the stated σ, so a shift-free channel
    // (none here has zero shift, but the prior part is positive) is consistent.
    let b = lik.breakdown(&x).unwrap();
    assert!(
        (b.chi2() - chi2).abs() <= 1e-9 * chi2,
        "{} vs {chi2}",
        b.chi2()
    );
    assert!(b.chi2_prior > 0.0 && b.chi2_prior < b.chi2_data);
    let n: usize = b.channels.iter().map(|c| c.rows.len()).sum();
    assert_eq!(n, stats.goodness.n_points);
    for c in &b.channels {
        assert_eq!(c.rows.len(), c.data.len());
        assert_eq!(c.rows.len(), c.simulated.len());
        assert!(c.sigma > 0.0, "{} {}", c.file, c.column);
    }
    assert_eq!(b.nuisances.len(), stats.nuisances.len());
    for (label, beta, _) in &b.nuisances {
        let stated = stats.nuisances[label].as_f64().unwrap();
        // The file's offsets are those of the unwidened target: same sign and size.
        assert!(beta * stated > 0.0, "{label}: {beta} vs {stated}");
    }

    // A move of 1 % on any parameter costs χ².
    for j in 0..x.len() {
        let mut y = x.clone();
        y[j] *= 1.01;
        assert!(lik.chi2(&y) > chi2, "{}", lik.names()[j]);
    }
}

#[test]
fn bad_use_gets_named_errors_and_never_nan() {
    let dir = tempfile::tempdir().unwrap();
    let mut fit = short_fit(dir.path());
    let ds = Dataset::load(Path::new(DATASET)).unwrap();
    let lik = FitLikelihood::from_fit(&ds, &fit).unwrap();
    let e = lik.try_chi2(&[1.0]).unwrap_err();
    assert!(
        matches!(e, FitLikelihoodError::Length { got: 1, .. }),
        "{e}"
    );
    assert!(e.to_string().contains("c_in1"), "{e}");
    let mut x = lik.estimate();
    x[0] = -1.0;
    assert!(matches!(
        lik.try_chi2(&x),
        Err(FitLikelihoodError::Param(_))
    ));
    assert!(lik.chi2(&x).is_finite());
    x[0] = f64::NAN;
    assert!(lik.chi2(&x).is_finite());

    fit.dataset = "another".into();
    let e = FitLikelihood::from_fit(&ds, &fit).err().unwrap();
    assert!(e.to_string().contains("another"), "{e}");
    fit.dataset = ds.name.clone();
    fit.statistics = None;
    assert!(matches!(
        FitLikelihood::from_fit(&ds, &fit),
        Err(FitLikelihoodError::NoStatistics(_))
    ));
}
