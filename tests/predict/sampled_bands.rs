//! Bands from posterior samples (`predict --bands`): without `--data` the dataset the fit
//! file records is sampled; `auto` falls back to the delta method, saying why, when the
//! samples do not converge or the dataset is not found; a seed gives the same bands
//! whatever the thread count, and where the posterior is close to Gaussian the samples'
//! bands agree with the delta method's.

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
        data: None,
        sampling,
        progress: &|_, _, _| {},
    };
    predict_with(fit, &options, &request).unwrap()
}

/// `predict` run in the package root: (exit status, stdout, stderr).
fn predict_run(args: &[&str]) -> (Option<i32>, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .arg("predict")
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (o.status.code(), text(&o.stdout), text(&o.stderr))
}

/// `bands.json` of a prediction written into `dir`.
fn bands_json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("bands.json")).unwrap()).unwrap()
}

/// A short run of the sampler (seconds), as options of `predict`.
const SHORT: [&str; 6] = ["--steps", "200", "--burn-in", "100", "--draws", "60"];

#[test]
fn without_data_predict_samples_the_dataset_the_fit_file_records() {
    let dir = tempfile::tempdir().unwrap();
    let fit = catalogue_fit(dir.path(), &[]);
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit).unwrap()).unwrap();
    // Recorded relative to the fit file's folder: it leads back to the dataset.
    let rel = doc["dataset_path"].as_str().expect("dataset_path recorded");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert_eq!(
        dir.path().join(rel).canonicalize().unwrap(),
        root.join(CATALOGUE).canonicalize().unwrap()
    );
    let out = dir.path().join("samples");
    let (code, stdout, stderr) = predict_run(
        &[
            fit.to_str().unwrap(),
            "--bands",
            "samples",
            "--out",
            out.to_str().unwrap(),
        ]
        .into_iter()
        .chain(SHORT)
        .collect::<Vec<_>>(),
    );
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stdout.contains("posterior sampled on the dataset ar034-synthetic-catalogue at")
            && stdout.contains("(the fit file's dataset_path)"),
        "{stdout}"
    );
    // Progress of the sampling on stderr.
    assert!(stderr.contains("sampling: "), "{stderr}");
    let json = bands_json(&out);
    assert_eq!(json["method"], "samples");
    assert_eq!(json["dataset"]["found"], true);
    let p = &json["sampling"]["parameters"]["c_out2"];
    assert!(p["rhat"].as_f64().unwrap() >= 1.0 && p["ess_bulk"].as_f64().unwrap() > 1.0);
    assert!(p["q025"].as_f64().unwrap() < p["q975"].as_f64().unwrap());
    // 200 steps do not converge: `samples` uses them anyway, and says so.
    let reason = json["reason"].as_str().unwrap();
    assert!(
        reason.starts_with("bands from 60 posterior samples (R̂ ≤"),
        "{reason}"
    );
    let md = std::fs::read_to_string(out.join("predict.md")).unwrap();
    assert!(md.contains("did NOT converge"), "{md}");

    // An older fit file (no dataset_path) in a folder beside `measurements/`: by its name.
    let mut older = doc.clone();
    older.as_object_mut().unwrap().remove("dataset_path");
    let fits = dir.path().join("tree/fits");
    std::fs::create_dir_all(&fits).unwrap();
    std::os::unix::fs::symlink(
        root.join("measurements"),
        dir.path().join("tree/measurements"),
    )
    .unwrap();
    let old = fits.join("old.json");
    std::fs::write(&old, serde_json::to_string_pretty(&older).unwrap()).unwrap();
    let out = dir.path().join("old");
    let args = [
        old.to_str().unwrap(),
        "--bands",
        "samples",
        "--out",
        out.to_str().unwrap(),
    ];
    let (code, stdout, stderr) = predict_run(&args.into_iter().chain(SHORT).collect::<Vec<_>>());
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("found by its name"), "{stdout}");
    assert_eq!(bands_json(&out)["method"], "samples");
}

#[test]
fn auto_falls_back_to_the_delta_method_with_the_reason_when_the_samples_do_not_converge() {
    let dir = tempfile::tempdir().unwrap();
    let fit = catalogue_fit(dir.path(), &[]);
    let out = dir.path().join("auto");
    // 20 steps of 8 chains (or 16+ walkers) cannot reach R̂ < 1.01 and an ESS of 400.
    let (code, stdout, stderr) = predict_run(&[
        fit.to_str().unwrap(),
        "--steps",
        "20",
        "--burn-in",
        "10",
        "--draws",
        "40",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let json = bands_json(&out);
    assert_eq!(json["method"], "delta");
    assert_eq!(json["asked"], "auto");
    assert_eq!(json["sampling"]["converged"], false);
    let rhat = json["sampling"]["rhat_max"].as_f64().unwrap();
    let reason = json["reason"].as_str().unwrap();
    assert!(
        reason.starts_with("delta-method bands: the samples did not converge (largest R̂")
            && reason.contains(&format!("{rhat:.3}")),
        "{reason}"
    );
    assert!(stdout.contains(reason), "{stdout}");
    let md = std::fs::read_to_string(out.join("predict.md")).unwrap();
    assert!(
        md.contains("Delta-method bands: the samples did not converge"),
        "{md}"
    );
    assert!(md.contains("Not used for the bands"), "{md}");
    // Convergence is decided before propagating: no sample was run through the figures.
    assert_eq!(json["sampling"]["draws"], 0);
    assert_eq!(json["sampling"]["propagated"], false);
    assert!(!stderr.contains("propagating"), "{stderr}");
    assert!(
        md.contains("none was propagated through the figures"),
        "{md}"
    );
    // The fit file's own reasons against the delta method are still said.
    if let Some(w) = json["delta_unreliable"].as_str() {
        assert!(
            md.contains(&format!("not close to Gaussian here ({w})")),
            "{md}"
        );
        assert!(!md.contains("NOT to be trusted"), "{md}");
    }
    assert!(!md.contains("POSTERIOR SAMPLES"), "{md}");

    // `delta` is instant: no sampling, and the reason is that it was asked.
    let out = dir.path().join("delta");
    let (code, _, stderr) = predict_run(&[
        fit.to_str().unwrap(),
        "--bands",
        "delta",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(!stderr.contains("sampling"), "{stderr}");
    let json = bands_json(&out);
    assert_eq!(json["reason"], "delta-method bands (--bands delta)");
    assert!(json["sampling"].is_null());
}

#[test]
fn a_dataset_that_is_not_found_gives_a_warning_and_delta_bands() {
    let dir = tempfile::tempdir().unwrap();
    let fit = catalogue_fit(dir.path(), &[]);
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit).unwrap()).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let other = root.join("measurements/ar034-synthetic");
    // A path that does not exist, and one that holds another dataset.
    for (k, (path, why)) in [
        (
            "../nowhere/ar034-synthetic-catalogue".to_string(),
            "no such folder",
        ),
        (
            other.to_str().unwrap().to_string(),
            "holds dataset ar034-synthetic, not ar034-synthetic-catalogue",
        ),
    ]
    .into_iter()
    .enumerate()
    {
        doc["dataset_path"] = path.clone().into();
        let moved = dir.path().join(format!("moved{k}.json"));
        std::fs::write(&moved, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
        let out = dir.path().join(format!("p{k}"));
        let (code, _, stderr) =
            predict_run(&[moved.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert_eq!(code, Some(0), "{stderr}");
        assert!(
            stderr.contains("WARNING: the dataset ar034-synthetic-catalogue was not found")
                && stderr.contains(why)
                && stderr.contains(&path),
            "{stderr}"
        );
        assert!(
            !stderr.contains("panicked") && !stderr.contains("sampling:"),
            "{stderr}"
        );
        let json = bands_json(&out);
        assert_eq!(json["method"], "delta");
        assert_eq!(json["dataset"]["found"], false);
        assert!(
            json["reason"]
                .as_str()
                .unwrap()
                .starts_with("delta-method bands: the dataset ar034-synthetic-catalogue was not found (looked at"),
            "{json}"
        );
        // `samples` cannot do without it: refused naming --data, status 1.
        let (code, _, stderr) = predict_run(&[
            moved.to_str().unwrap(),
            "--bands",
            "samples",
            "--out",
            dir.path().join("bad").to_str().unwrap(),
        ]);
        assert_eq!(code, Some(1), "{stderr}");
        assert!(
            stderr.contains("--data") && stderr.contains(why),
            "{stderr}"
        );
    }
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
    let auto = sampled(&fit, BandChoice::Delta, &s);
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
