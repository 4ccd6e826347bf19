//! Probe: a fit's posterior as the delta method takes it against the one the ensemble
//! sampler draws (docs/validation.md, "Sampled bands on a page").
//!
//! `cargo run --release --example page_posterior -- FIT.json DATASET_DIR [STEPS [BURN_IN [OTHER_FIT.json]]]`
//!
//! Prints, per estimated parameter, σ of ln θ from the fit's profile interval (what the
//! delta method uses), from the fit file's curvature covariance and from the samples; then
//! the correlations of the delta method's C = S·R·S, of the curvature and of the samples,
//! and the eigenvalues of the three covariances (the directions the data pin). Before that,
//! how far the posterior is from its Laplace approximation: importance sampling from the
//! sampler's t proposal (4000 draws), its effective sample size (Σw)²/Σw² and the Hill
//! estimate of the weights' Pareto tail index k̂ over the largest 20 % (k̂ > 0.7: the
//! proposal is no use as an importance density, Vehtari et al. 2024, "Pareto smoothed
//! importance sampling", JMLR 25). `SAMPLER=chains` samples with `estimate::run_chains`
//! (8 chains) instead of the ensemble; then each chain's mean of the parameter with the
//! largest R̂ shows whether chains sit in different places.

use nalgebra::DMatrix;
use std::path::Path;
use vanefit::estimate::{
    run_chains, run_ensemble_with, summarise, ChainSettings, Chains, EnsembleSettings,
    FitLikelihood, FitPosterior, Moves, TProposal,
};
use vanefit::estimate::{LogDensity, LogPrior};
use vanefit::predict::ParamUncertainty;
use vanefit::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: page_posterior FIT.json DATASET_DIR [STEPS [BURN_IN [OTHER_FIT.json]]]");
        std::process::exit(2);
    }
    let steps: usize = args.get(3).map_or(Ok(4000), |s| s.parse())?;
    let burn_in: usize = args.get(4).map_or(Ok(1000), |s| s.parse())?;
    let fit = FitFile::read(Path::new(&args[1]))?;
    let ds = Dataset::load(Path::new(&args[2]))?;
    let like = FitLikelihood::from_fit(&ds, &fit)?;
    let prior = |v: &[f64]| like.log_prior(v);
    let post = FitPosterior::new(&like).with_prior(&prior as &dyn LogPrior);
    let names = like.names();
    let d = names.len();
    let walkers = (4 * d).max(16).div_ceil(2) * 2;
    let centre = post.to_coords(&like.estimate());
    let unc = ParamUncertainty::of(&fit, None);
    // Starts: a small ball about the estimate, as predict's.
    let mut seed = 12345u64;
    let mut uniform = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    // START=laplace: starts drawn from N(x̂, Σ), Σ the fit file's curvature covariance in
    // the sampler's coordinates; else a ball of ±0.5 % about the estimate.
    let laplace = std::env::var("START").is_ok_and(|v| v == "laplace");
    let chol = fit.covariance.as_ref().and_then(|c| {
        let est = like.estimate();
        let log = like.log_scale();
        let idx: Vec<usize> = names
            .iter()
            .map(|n| c.parameters.iter().position(|m| m == n))
            .collect::<Option<_>>()?;
        let jac = |i: usize| if log[i] { 1.0 } else { est[i] };
        let m = DMatrix::from_fn(d, d, |i, j| c.matrix[idx[i]][idx[j]] * jac(i) * jac(j));
        m.cholesky().map(|ch| ch.l())
    });
    let starts: Vec<Vec<f64>> = (0..walkers)
        .map(|_| loop {
            let x: Vec<f64> = match (&chol, laplace) {
                (Some(l), true) => {
                    // Sum of 12 uniforms − 6: close enough to a standard normal for starts.
                    let z = nalgebra::DVector::from_fn(d, |_, _| {
                        (0..12).map(|_| uniform() + 0.5).sum::<f64>() - 6.0
                    });
                    let step = l * z;
                    centre
                        .iter()
                        .enumerate()
                        .map(|(i, c)| c + step[i])
                        .collect()
                }
                _ => centre.iter().map(|c| c + 0.01 * uniform()).collect(),
            };
            if post.log_density(&x).is_finite() {
                break x;
            }
        })
        .collect();
    let est = like.estimate();
    println!(
        "chi2 at the estimate {:.5} (file {:.5}), prior chi2 {:.4} (file {:.4}), log density {:.4}",
        like.chi2(&est),
        like.chi2_min(),
        like.prior_chi2(&est),
        like.prior_chi2_min(),
        post.log_density(&post.to_coords(&est))
    );
    // Another fit of the same page (e.g. with the friction fixed at the truth): its point.
    if let Some(other) = args.get(5) {
        let o = FitFile::read(Path::new(other))?;
        let v: Vec<f64> = names
            .iter()
            .map(|n| o.params.get(n).unwrap_or(f64::NAN))
            .collect();
        println!(
            "other fit: chi2 {:.5}, prior chi2 {:.4}, log density {:.4}",
            like.chi2(&v),
            like.prior_chi2(&v),
            post.log_density(&post.to_coords(&v))
        );
    }
    let settings = EnsembleSettings {
        walkers,
        steps,
        burn_in,
        seed: 1,
    };
    // DE=p: the differential-evolution move with probability p (else the stretch move alone).
    let moves = std::env::var("DE")
        .ok()
        .and_then(|v| v.parse().ok())
        .map_or(Moves::Stretch, |de| Moves::Mixed { de });
    // SAMPLER=chains: the Laplace-guided Metropolis–Hastings chains (8 chains) instead.
    let q = post.proposal()?;
    importance_check(&post, &q);
    let chains = if std::env::var("SAMPLER").is_ok_and(|v| v == "chains") {
        let s = ChainSettings {
            chains: 8,
            steps,
            burn_in,
            block: steps + burn_in,
            seed: 1,
        };
        run_chains(&post, &q, &s, None, &|_, _| {})?
    } else {
        run_ensemble_with(&post, &starts, &settings, moves, &|_, _| {})?
    };
    per_chain_means(&chains, &names);
    let diag = summarise(&chains.draws);
    let flat = chains.flat();
    let n = flat.len() as f64;
    let mean: Vec<f64> = (0..d)
        .map(|i| flat.iter().map(|x| x[i]).sum::<f64>() / n)
        .collect();
    let sample_cov = DMatrix::from_fn(d, d, |i, j| {
        flat.iter()
            .map(|x| (x[i] - mean[i]) * (x[j] - mean[j]))
            .sum::<f64>()
            / (n - 1.0)
    });
    // The fit file's curvature covariance, in the same order where it has the parameter.
    let curv = fit.covariance.as_ref().map(|c| {
        let idx: Vec<Option<usize>> = names
            .iter()
            .map(|n| c.parameters.iter().position(|m| m == n))
            .collect();
        DMatrix::from_fn(d, d, |i, j| match (idx[i], idx[j]) {
            (Some(a), Some(b)) => c.matrix[a][b],
            _ => f64::NAN,
        })
    });
    let delta_index: Vec<Option<usize>> = names
        .iter()
        .map(|n| unc.names.iter().position(|m| m == n))
        .collect();
    println!(
        "steps {steps} burn-in {burn_in} walkers {walkers} acceptance {:.3}",
        chains.mean_acceptance()
    );
    println!("| parameter | σ ln θ delta | σ curvature | σ samples | R̂ | ESS bulk |");
    println!("|---|---|---|---|---|---|");
    for i in 0..d {
        let ds = delta_index[i].map_or(f64::NAN, |j| unc.sd[j]);
        let cs = curv.as_ref().map_or(f64::NAN, |c| c[(i, i)].sqrt());
        println!(
            "| {} | {ds:.3} | {cs:.3} | {:.3} | {:.3} | {:.0} |",
            names[i],
            sample_cov[(i, i)].sqrt(),
            diag[i].rhat,
            diag[i].ess_bulk
        );
    }
    let corr = |m: &DMatrix<f64>, i: usize, j: usize| m[(i, j)] / (m[(i, i)] * m[(j, j)]).sqrt();
    println!("\ncorrelations (delta C / curvature / samples):");
    for i in 0..d {
        for j in (i + 1)..d {
            let dc = match (delta_index[i], delta_index[j]) {
                (Some(a), Some(b)) => corr(&unc.cov, a, b),
                _ => f64::NAN,
            };
            let cc = curv.as_ref().map_or(f64::NAN, |c| corr(c, i, j));
            let sc = corr(&sample_cov, i, j);
            if dc.abs() > 0.5 || cc.abs() > 0.5 || sc.abs() > 0.5 {
                println!(
                    "  {:>9} {:>9}: {dc:+.3} / {cc:+.3} / {sc:+.3}",
                    names[i], names[j]
                );
            }
        }
    }
    let eig = |m: &DMatrix<f64>| {
        let mut e: Vec<f64> = m
            .clone()
            .symmetric_eigen()
            .eigenvalues
            .iter()
            .copied()
            .collect();
        e.sort_by(f64::total_cmp);
        e.iter()
            .map(|v| format!("{:.2e}", v.max(0.0).sqrt()))
            .collect::<Vec<_>>()
            .join(" ")
    };
    println!(
        "\n√eigenvalues, delta C ({} parameters): {}",
        unc.names.len(),
        eig(&unc.cov)
    );
    if let Some(c) = &curv {
        println!("√eigenvalues, curvature: {}", eig(c));
    }
    println!("√eigenvalues, samples: {}", eig(&sample_cov));
    Ok(())
}

/// Importance sampling from `q`: prints the effective sample size of the weights p/q of 4000
/// draws and the Hill estimate of their tail index k̂ (largest 20 %).
fn importance_check(post: &FitPosterior, q: &TProposal) {
    use rand::SeedableRng;
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(17);
    let mut logw: Vec<f64> = (0..4000)
        .map(|_| {
            let x = q.draw(&mut rng);
            post.log_density(&x) - q.log_q(&x)
        })
        .filter(|v| v.is_finite())
        .collect();
    logw.sort_by(|a, b| b.total_cmp(a));
    let top = logw[0];
    let w: Vec<f64> = logw.iter().map(|v| (v - top).exp()).collect();
    let ess = w.iter().sum::<f64>().powi(2) / w.iter().map(|v| v * v).sum::<f64>();
    let m = logw.len() / 5;
    let k_hat = logw[..m].iter().map(|v| v - logw[m]).sum::<f64>() / m as f64;
    println!(
        "importance sampling from the Laplace t proposal: {} of 4000 draws inside, ESS {ess:.1}, k̂ (Hill, top 20 %) {k_hat:.2}",
        logw.len()
    );
}

/// Each chain's mean of the parameter with the largest R̂.
fn per_chain_means(chains: &Chains, names: &[String]) {
    let diag = summarise(&chains.draws);
    let worst = (0..names.len())
        .max_by(|a, b| diag[*a].rhat.total_cmp(&diag[*b].rhat))
        .unwrap_or(0);
    let means: Vec<String> = chains
        .draws
        .iter()
        .map(|c| {
            format!(
                "{:.3}",
                c.iter().map(|x| x[worst]).sum::<f64>() / c.len() as f64
            )
        })
        .collect();
    println!(
        "per-chain means of {} (R̂ {:.3}): {}",
        names[worst],
        diag[worst].rhat,
        means.join(" ")
    );
}
