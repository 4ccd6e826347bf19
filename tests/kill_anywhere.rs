//! Issue 15, kill anywhere: `fit` killed with SIGKILL at many moments and resumed each time
//! ends with the fit an uninterrupted run of the same seed gives, and no output file is ever
//! seen half-written (the fit file is absent or whole JSON after every kill).

use std::path::Path;
use std::process::Command;
use std::time::Instant;

const DATASET: &str = "measurements/ar034-synthetic";

fn fit_command(out: &Path, resume: bool) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vanefit"));
    c.args([
        "fit",
        DATASET,
        "--starts",
        "6",
        "--max-iters",
        "80",
        "--seed",
        "5",
    ])
    .args([
        "--uncertainty",
        "none",
        "--no-plots",
        "--threads",
        "2",
        "--out",
    ])
    .arg(out);
    if resume {
        c.arg("--resume");
    }
    c.stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    c
}

/// The estimated values of a fit file.
fn estimate(path: &Path) -> serde_json::Value {
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    doc["parameters"].clone()
}

/// Every file beside the fit: whole (JSON parses, JSON lines each parse but a last torn one
/// that resume cuts) and no temporary file left visible as a result.
fn no_half_written_results(dir: &Path) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.ends_with(".json") {
            let text = std::fs::read_to_string(e.path()).unwrap();
            assert!(
                serde_json::from_str::<serde_json::Value>(&text).is_ok(),
                "{name} half-written"
            );
        }
    }
}

#[test]
fn fit_killed_anywhere_and_resumed_equals_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("ref/fit.json");
    let t0 = Instant::now();
    assert!(fit_command(&reference, false).status().unwrap().success());
    let full = t0.elapsed();

    let out = dir.path().join("killed/fit.json");
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut kills = 0;
    let mut finished = false;
    for round in 0..40 {
        let mut child = fit_command(&out, round > 0).spawn().unwrap();
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let frac = (state >> 11) as f64 / (1u64 << 53) as f64;
        let wait = full.mul_f64(0.05 + 0.6 * frac);
        std::thread::sleep(wait);
        if child.try_wait().unwrap().is_some() {
            finished = true;
            break;
        }
        child.kill().unwrap();
        child.wait().unwrap();
        kills += 1;
        no_half_written_results(out.parent().unwrap());
    }
    if !finished {
        assert!(fit_command(&out, true).status().unwrap().success());
    }
    eprintln!("kill points tried: {kills}");
    assert!(
        kills >= 3,
        "only {kills} kills: the fit ran too fast to interrupt"
    );
    assert_eq!(estimate(&out), estimate(&reference));
    assert!(!out.with_extension("lock").exists(), "lock released");
}

#[test]
fn diagnose_killed_at_random_moments_leaves_whole_files_and_reruns_to_the_same_result() {
    let dir = tempfile::tempdir().unwrap();
    let run = |out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_vanefit"))
            .args(["diagnose", DATASET, "--starts", "2", "--out"])
            .arg(out)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap()
    };
    let reference = dir.path().join("ref");
    let t0 = Instant::now();
    assert!(run(&reference).wait().unwrap().success());
    let full = t0.elapsed();
    let out = dir.path().join("killed");
    // A diagnosis does not resume: each kill must leave its files whole (or absent), and the
    // lock of the killed run must not block the next.
    for frac in [0.2, 0.55, 0.9, 0.97] {
        let mut child = run(&out);
        std::thread::sleep(full.mul_f64(frac));
        child.kill().unwrap();
        child.wait().unwrap();
        no_half_written_results(&out);
    }
    assert!(run(&out).wait().unwrap().success());
    let read = |d: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join("diagnosis.json")).unwrap()).unwrap()
    };
    let (a, b) = (read(&reference), read(&out));
    for key in ["mismatch", "selected", "candidates", "locations"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    assert!(!out.join(".vanefit.lock").exists(), "lock released");
}
