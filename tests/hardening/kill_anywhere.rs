//! Kill anywhere: `fit`, `diagnose` and `batch` killed with SIGKILL at many
//! moments and run again each time end with the result an uninterrupted run of the same seed
//! gives, no output file is ever seen half-written (a result is absent or whole JSON after
//! every kill), and the run that finishes leaves no temporary file of a killed one behind.

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

/// Every JSON file in `dir` and its subfolders is whole (it parses); returns how many
/// there are. (The starts file, JSON lines, may end in a torn line: resume cuts it.)
fn no_half_written_results(dir: &Path) -> usize {
    let mut n = 0;
    let Ok(entries) = std::fs::read_dir(dir) else {
        return 0;
    };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if e.path().is_dir() {
            n += no_half_written_results(&e.path());
        } else if name.ends_with(".json") {
            let text = std::fs::read_to_string(e.path()).unwrap();
            assert!(
                serde_json::from_str::<serde_json::Value>(&text).is_ok(),
                "{} half-written:\n{text}",
                e.path().display()
            );
            n += 1;
        }
    }
    n
}

/// The temporary files (of `write_atomic`'s naming scheme) in `dir` and its subfolders.
fn temporaries(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if e.path().is_dir() {
            found.extend(temporaries(&e.path()));
        } else if name.contains(".tmp") {
            found.push(e.path().display().to_string());
        }
    }
    found
}

/// Leaves in `dir` the temporary a run killed while writing `name` would have left: this
/// host's naming, the pid of a process that cannot exist (above the kernel's 2^22 limit).
/// Killing a run exactly inside a write is rare, so the test makes the leftover itself.
fn plant_stale_temporary(dir: &Path, name: &str) -> std::path::PathBuf {
    let mine = vanefit::io::temporary_name(name);
    let host = mine.split_once('-').map_or("", |(_, h)| h);
    let path = dir.join(format!(".{name}.tmp4194305-{host}"));
    std::fs::write(&path, "{\"half\": ").unwrap();
    path
}

/// A pseudo-random fraction in [0, 1) (a 64-bit LCG: the kill moments are reproducible).
fn next_fraction(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6_364_136_223_846_793_005)
        .wrapping_add(1_442_695_040_888_963_407);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

#[test]
fn fit_killed_anywhere_and_resumed_equals_an_uninterrupted_run() {
    let dir = tempfile::tempdir().unwrap();
    let reference = dir.path().join("ref/fit.json");
    let t0 = Instant::now();
    assert!(fit_command(&reference, false).status().unwrap().success());
    let full = t0.elapsed();

    let out = dir.path().join("killed/fit.json");
    // An early kill first: every start of this fit ends in its first round (80 iterations,
    // a stage is 100), and the run is killed the moment its starts file holds a finished
    // start. Each start is recorded when it ends, so the others are still running then, and
    // the next run must resume from the ones kept.
    let starts_file = out.with_extension("starts.jsonl");
    let finished_starts = || {
        std::fs::read_to_string(&starts_file).map_or(0, |t| {
            t.lines().skip(1).filter(|l| l.ends_with('}')).count()
        })
    };
    let mut child = fit_command(&out, false).spawn().unwrap();
    while finished_starts() == 0 && child.try_wait().unwrap().is_none() {
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = finished_starts();
    assert!(
        (1..6).contains(&kept),
        "killed inside the first round, {kept} of 6 starts kept (want some, not all)"
    );
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut kills = 1;
    for _ in 0..40 {
        let mut child = fit_command(&out, true).spawn().unwrap();
        let wait = full.mul_f64(0.05 + 0.6 * next_fraction(&mut state));
        std::thread::sleep(wait);
        if child.try_wait().unwrap().is_some() {
            break;
        }
        child.kill().unwrap();
        child.wait().unwrap();
        kills += 1;
        no_half_written_results(out.parent().unwrap());
    }
    // One more resume, after the last kill or after a round that finished by itself: it
    // ends the fit, and its writes remove the temporary a killed write would have left.
    let stale = plant_stale_temporary(out.parent().unwrap(), "fit.json");
    assert!(fit_command(&out, true).status().unwrap().success());
    assert!(!stale.exists(), "the killed run's temporary is removed");
    assert_eq!(temporaries(out.parent().unwrap()), Vec::<String>::new());
    eprintln!("kill points tried: {kills}, the first inside the first round ({kept} starts kept)");
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
    std::fs::create_dir_all(&out).unwrap();
    let stale = plant_stale_temporary(&out, "diagnosis.json");
    assert!(run(&out).wait().unwrap().success());
    assert!(!stale.exists(), "the killed run's temporary is removed");
    assert_eq!(temporaries(&out), Vec::<String>::new());
    let read = |d: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(d.join("diagnosis.json")).unwrap()).unwrap()
    };
    let (a, b) = (read(&reference), read(&out));
    for key in ["mismatch", "selected", "candidates", "locations"] {
        assert_eq!(a[key], b[key], "{key}");
    }
    assert!(!out.join(".vanefit.lock").exists(), "lock released");
}

/// A small fleet: the shipped dataset twice (`ds/m1`, `ds/m2`), each fitted (three
/// parameters, six starts, curvature intervals) and predicted at two pressures.
fn small_fleet(root: &Path) -> std::path::PathBuf {
    for m in ["m1", "m2"] {
        let to = root.join("ds").join(m);
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(DATASET).unwrap().flatten() {
            std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }
    let manifest = root.join("m.toml");
    std::fs::write(
        &manifest,
        r#"[batch]
datasets = ["ds/*"]
tasks = ["fit", "predict"]

[fit]
starts = 6
seed = 3
max_iters = 200
uncertainty = "curvature"
estimate = ["c_in1", "c_out2", "t_coulomb"]
plots = false

[predict]
pressures = [4, 6]
"#,
    )
    .unwrap();
    manifest
}

fn batch_command(manifest: &Path, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_vanefit"));
    c.arg("batch")
        .arg(manifest)
        .args(["--threads", "2", "--out"])
        .arg(out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null());
    c
}

/// How many units of the batch folder `out` say `done`.
fn units_done(out: &Path) -> usize {
    let Ok(datasets) = std::fs::read_dir(out) else {
        return 0;
    };
    let mut n = 0;
    for d in datasets.flatten().filter(|d| d.path().is_dir()) {
        for u in std::fs::read_dir(d.path()).unwrap().flatten() {
            let status = std::fs::read_to_string(u.path().join("status.json")).unwrap_or_default();
            n += usize::from(status.contains("\"status\": \"done\""));
        }
    }
    n
}

fn merge(out: &Path) -> String {
    let o = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .arg("merge")
        .arg(out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read_to_string(out.join("summary.csv")).unwrap()
}

#[test]
fn batch_killed_anywhere_and_rerun_merges_to_the_uninterrupted_summary() {
    let dir = tempfile::tempdir().unwrap();
    let manifest = small_fleet(dir.path());
    let reference = dir.path().join("ref");
    let t0 = Instant::now();
    assert!(batch_command(&manifest, &reference)
        .status()
        .unwrap()
        .success());
    let full = t0.elapsed();
    let expected = merge(&reference);

    // Kill sequences: a fresh batch folder, killed up to three times, each after 5 % to
    // 130 % of an uninterrupted run's time, and run again each time, the last time to the
    // end; then merged. (A fit's starts advance together and end late in its run, so only
    // the longer waits leave finished starts for the next run to resume from, or kill it
    // among the predictions; the shorter ones kill it at startup, while the batch record or
    // a status is written, or inside the fits.) Sequences repeat until at least 15 kills
    // were made.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let (mut kills, mut files_seen, mut sequences, mut late) = (0, 0, 0, 0);
    while kills < 15 && sequences < 20 {
        sequences += 1;
        let out = dir.path().join(format!("killed{sequences}"));
        for _ in 0..3 {
            let mut child = batch_command(&manifest, &out).spawn().unwrap();
            std::thread::sleep(full.mul_f64(0.05 + 1.25 * next_fraction(&mut state)));
            if child.try_wait().unwrap().is_some() {
                break;
            }
            child.kill().unwrap();
            child.wait().unwrap();
            kills += 1;
            files_seen += no_half_written_results(&out);
            late += usize::from(units_done(&out) > 0);
        }
        // To the end (it may have ended already: then it finds every unit done).
        assert!(batch_command(&manifest, &out).status().unwrap().success());
        let stale = plant_stale_temporary(&out, "summary.csv");
        assert_eq!(merge(&out), expected, "sequence {sequences}: summary.csv");
        assert!(!stale.exists(), "the killed run's temporary is removed");
        assert_eq!(temporaries(&out), Vec::<String>::new());
        assert!(!out.join(".vanefit.lock").exists(), "lock released");
    }
    eprintln!(
        "batch kill points tried: {kills} in {sequences} sequences, {late} after a unit had \
         finished ({files_seen} JSON files checked whole); uninterrupted run {full:?}"
    );
    assert!(kills >= 15, "only {kills} kills");
}
