//! Bands from posterior samples (`predict --bands`): on a catalogue fit whose c_out2 is not
//! identifiable `auto` samples and says so, `delta` warns instead, a seed gives the same
//! bands whatever the thread count, and where the posterior is close to Gaussian the
//! samples' bands agree with the delta method's.

use std::path::{Path, PathBuf};
use std::process::Command;
use vanefit::data::Dataset;
use vanefit::data::FitFile;
use vanefit::estimate::FitLikelihood;
use vanefit::predict::{
    predict_with, BandChoice, BandMethod, BandRequest, PosteriorSource, PredictOptions, Prediction,
    SamplingOptions,
};

const CATALOGUE: &str = "measurements/ar034-synthetic-catalogue";

use super::catalogue_predict::vanefit;

/// A fit of the catalogue page (`extra`: more `fit` options) into `dir`.
fn catalogue_fit(dir: &Path, extra: &[&str]) -> PathBuf {
    let fit = dir.join("fit.json");
    let mut args = vec![
        "fit",
        CATALOGUE,
        "--no-plots",
        "--out",
        fit.to_str().unwrap(),
    ];
    args.extend(extra);
    vanefit(&args);
    fit
}

fn sampled(fit: &FitFile, choice: BandChoice, sampling: &SamplingOptions) -> Prediction {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let ds = Dataset::load(&root.join(CATALOGUE)).unwrap();
    let likelihood = FitLikelihood::from_fit(&ds, fit).unwrap();
    let options = PredictOptions {
        curve_points: 3,
        ..PredictOptions::new(fit.conditions.unwrap().p_atm_pa)
    };
    let request = BandRequest {
        choice,
        posterior: Some(PosteriorSource {
            likelihood: &likelihood,
            prior: None,
        }),
        sampling,
        progress: &|_, _, _| {},
    };
    predict_with(fit, &options, &request).unwrap()
}

#[test]
fn auto_samples_where_the_fit_is_not_identifiable_and_says_which_method_made_the_bands() {
    let dir = tempfile::tempdir().unwrap();
    let fit = catalogue_fit(dir.path(), &[]);
    let f = fit.to_str().unwrap();
    let out = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let short = ["--steps", "200", "--burn-in", "100", "--draws", "60"];
    let mut args = vec!["predict", f, "--data", CATALOGUE, "--out"];
    let o1 = out("auto");
    args.push(&o1);
    args.extend(short);
    vanefit(&args);
    let md = std::fs::read_to_string(dir.path().join("auto/predict.md")).unwrap();
    assert!(md.contains("POSTERIOR SAMPLES"), "{md}");
    // Why depends on the fit (with the motor prior c_out2 is pinned, but intervals are
    // lopsided); that a reason is given does not.
    assert!(
        md.contains("the delta method is not to be trusted here:"),
        "{md}"
    );
    assert!(
        md.contains("## Posterior samples") && md.contains("R̂"),
        "{md}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("auto/bands.json")).unwrap())
            .unwrap();
    assert_eq!(json["method"], "samples");
    let p = &json["sampling"]["parameters"]["c_out2"];
    assert!(p["rhat"].as_f64().unwrap() >= 1.0 && p["ess_bulk"].as_f64().unwrap() > 1.0);
    assert!(p["q025"].as_f64().unwrap() < p["q975"].as_f64().unwrap());

    let o2 = out("delta");
    vanefit(&["predict", f, "--bands", "delta", "--out", &o2]);
    let md = std::fs::read_to_string(dir.path().join("delta/predict.md")).unwrap();
    assert!(md.contains("delta method is NOT to be trusted"), "{md}");
    assert!(!md.contains("POSTERIOR SAMPLES"));
    let o3 = out("nodata");
    vanefit(&["predict", f, "--out", &o3]);
    let md = std::fs::read_to_string(dir.path().join("nodata/predict.md")).unwrap();
    assert!(md.contains("dataset was not given (--data)"), "{md}");

    // Samples without the dataset are refused, naming the option.
    let bad = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(["predict", f, "--bands", "samples", "--out", &out("bad")])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--data"));
}

#[test]
fn sampled_bands_for_a_seed_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let fit = FitFile::read(&catalogue_fit(dir.path(), &[])).unwrap();
    let s = SamplingOptions {
        steps: 60,
        burn_in: 20,
        draws: 40,
        ..SamplingOptions::default()
    };
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| sampled(&fit, BandChoice::Samples, &s))
    };
    let one = with(1);
    assert_eq!(one.bands.method, BandMethod::Samples);
    assert_eq!(one, with(2));
    let other = sampled(&fit, BandChoice::Samples, &SamplingOptions { seed: 2, ..s });
    assert_ne!(one.pressures[0].figures, other.pressures[0].figures);
}

#[test]
fn where_the_posterior_is_close_to_gaussian_samples_and_delta_agree() {
    // c_in1 and c_1e alone are pinned by the page: a near-Gaussian posterior, on which the
    // delta method is right and the samples' percentiles must give the same widths.
    let dir = tempfile::tempdir().unwrap();
    let fit = catalogue_fit(dir.path(), &["--estimate", "c_in1,c_1e"]);
    let fit = FitFile::read(&fit).unwrap();
    assert!(vanefit::predict::delta_unreliable(&fit).is_none());
    let s = SamplingOptions {
        steps: 1500,
        burn_in: 300,
        draws: 400,
        ..SamplingOptions::default()
    };
    let auto = sampled(&fit, BandChoice::Auto, &s);
    assert_eq!(auto.bands.method, BandMethod::Delta);
    let samples = sampled(&fit, BandChoice::Samples, &s);
    let mut ratios = Vec::new();
    for (a, b) in auto.pressures.iter().zip(&samples.pressures) {
        for (x, y) in a.figures.iter().zip(&b.figures) {
            let (d, m) = (x.band95.unwrap(), y.band95.unwrap());
            ratios.push((m[1] - m[0]) / (d[1] - d[0]));
        }
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    assert!(
        (0.8..1.25).contains(&median),
        "width ratios samples/delta: {ratios:?}"
    );
    assert!(ratios.iter().all(|r| (0.5..2.0).contains(r)), "{ratios:?}");
}

#[test]
fn a_killed_predict_resumes_from_its_checkpoint_to_the_same_files() {
    // Killed when its first checkpoint appears (an event the run writes, not a wall time),
    // run again with the same options: the same catalogue, factors and bands as a run that
    // was not killed. A checkpoint of other settings is refused, naming the file.
    let dir = tempfile::tempdir().unwrap();
    let fit = catalogue_fit(dir.path(), &[]);
    let out = |name: &str| dir.path().join(name);
    let args = |o: &Path, seed: &str| -> Vec<String> {
        let mut a: Vec<String> = ["predict", fit.to_str().unwrap(), "--bands", "samples"]
            .map(String::from)
            .to_vec();
        a.extend(
            [
                "--data",
                CATALOGUE,
                "--curve-points",
                "3",
                "--steps",
                "4000",
            ]
            .map(String::from),
        );
        a.extend(["--seed", seed, "--out", o.to_str().unwrap()].map(String::from));
        a
    };
    vanefit(
        &args(&out("whole"), "1")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    let checkpoint = out("killed").join("samples.checkpoint");
    let mut child = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(args(&out("killed"), "1"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    while !checkpoint.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "predict ended before its first checkpoint"
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(checkpoint.exists(), "the run was killed before it ended");
    let other = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(args(&out("killed"), "2"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert_eq!(other.status.code(), Some(1));
    let err = String::from_utf8_lossy(&other.stderr);
    assert!(
        err.contains("samples.checkpoint") && err.contains("seed"),
        "{err}"
    );
    vanefit(
        &args(&out("killed"), "1")
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert!(!checkpoint.exists());
    for file in ["catalogue.csv", "factors.csv", "bands.json"] {
        let a = std::fs::read(out("whole").join(file)).unwrap();
        let b = std::fs::read(out("killed").join(file)).unwrap();
        assert!(a == b, "{file} differs after the resume");
    }
}

#[test]
fn a_rig_fit_s_posterior_is_drawn_by_the_laplace_chains_and_matches_its_profile_intervals() {
    // The rig fit's posterior is close to its Laplace approximation (importance weights'
    // k̂ well below 0.7), so the Laplace-guided chains draw it; their 95 % intervals must
    // agree with the fit's profile intervals (a Gaussian likelihood in ln θ: the same
    // interval), found without any sampling.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("p");
    let fit = "fits/ar034-synthetic.json";
    vanefit(&[
        "predict",
        fit,
        "--bands",
        "samples",
        "--data",
        "measurements/ar034-synthetic",
        "--steps",
        "600",
        "--burn-in",
        "300",
        "--curve-points",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    let bands: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bands.json")).unwrap()).unwrap();
    let s = &bands["sampling"];
    assert_eq!(s["sampler"], "laplace_chains", "{s}");
    assert!(s["laplace_k_hat"].as_f64().unwrap() < 0.7, "{s}");
    let file = FitFile::read(Path::new(fit)).unwrap();
    for (name, [lo, hi]) in &file.ci95 {
        let p = &s["parameters"][name];
        let (q_lo, q_hi) = (p["q025"].as_f64().unwrap(), p["q975"].as_f64().unwrap());
        let width = (hi / lo).ln();
        let sampled = (q_hi / q_lo).ln();
        assert!(
            (sampled / width - 1.0).abs() < 0.15,
            "{name}: profile [{lo:.4e}, {hi:.4e}], samples [{q_lo:.4e}, {q_hi:.4e}]"
        );
        assert!(p["rhat"].as_f64().unwrap() < 1.02, "{name}: {p}");
    }
}
