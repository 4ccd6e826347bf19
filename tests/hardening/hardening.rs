//! Hardened: a closed stdout, progress in logs, two runs on one output, outputs
//! checked before work, exit codes of bad usage, and `check` of a long recording.

use crate::common;
use common::{stderr, vanefit, DATASET};

use std::path::Path;
use std::process::{Command, Output, Stdio};

/// Runs vanefit with its stdout closed before it writes anything (a reader like `head -0`).
fn with_closed_stdout(args: &[&str]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    child.wait_with_output().unwrap()
}

/// Names of the temporary files of `write_atomic` left anywhere under `dir`.
fn leftovers(dir: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        if name.contains(".tmp") {
            found.push(name);
        }
        if e.path().is_dir() {
            found.extend(leftovers(&e.path()));
        }
    }
    found
}

#[test]
fn a_closed_stdout_ends_quietly_after_every_file_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let sim = dir.path().join("sim");
    let o = with_closed_stdout(&["simulate", DATASET, "--out", sim.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    for f in ["datasheet.csv", "ramp.csv", "throttle.csv"] {
        assert!(sim.join(f).is_file(), "{f} not written");
    }
    let bode = dir.path().join("bode");
    let o = with_closed_stdout(&["control", "bode", "--out", bode.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    assert!(bode.join("bode.svg").is_file());
    let o = with_closed_stdout(&["check", DATASET]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // A batch and its merge too (a manifest beside a copy of the shipped dataset: globs
    // stay inside the manifest's folder).
    let manifest = dir.path().join("fleet.toml");
    let ds = dir.path().join("ds");
    std::fs::create_dir_all(&ds).unwrap();
    for e in std::fs::read_dir(DATASET).unwrap().flatten() {
        std::fs::copy(e.path(), ds.join(e.file_name())).unwrap();
    }
    std::fs::write(
        &manifest,
        "[batch]\ndatasets = [\"ds\"]\ntasks = [\"fit\"]\n[fit]\nstarts = 2\nuncertainty = \"none\"\n",
    )
    .unwrap();
    let fleet = dir.path().join("fleet");
    let o = with_closed_stdout(&[
        "batch",
        manifest.to_str().unwrap(),
        "--out",
        fleet.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = with_closed_stdout(&["merge", fleet.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(fleet.join("summary.csv").is_file());
    assert!(leftovers(dir.path()).is_empty());
}

#[test]
fn a_fit_without_a_terminal_logs_starts_best_cost_and_phases_on_stderr() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fit.json");
    let o = vanefit(&[
        "fit",
        DATASET,
        "--starts",
        "3",
        "--max-iters",
        "60",
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("fit: starts 0/3"), "{e}");
    assert!(e.contains("fit: starts 3/3, best cost J "), "{e}");
    assert!(e.contains("fit: maximum likelihood"), "{e}");
    assert!(e.contains("fit: profiles (0/"), "{e}");
    assert!(e.contains("fit: profiles 16/16"), "{e}");
    assert!(!dir.path().join("fit.lock").exists(), "lock released");
}

#[test]
fn a_second_run_on_the_same_output_is_refused_and_a_stale_lock_taken_over() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fit.json");
    let out_s = out.to_str().unwrap();
    let fit = |out: &str| {
        vanefit(&[
            "fit",
            DATASET,
            "--starts",
            "2",
            "--max-iters",
            "40",
            "--uncertainty",
            "none",
            "--no-plots",
            "--out",
            out,
        ])
    };
    // This test process holds the lock as a running fit would.
    let lock = vanefit::io::OutputLock::acquire(&dir.path().join("fit.lock")).unwrap();
    let o = fit(out_s);
    assert_eq!(o.status.code(), Some(1));
    let want = format!(
        "output in use by pid {} (lock file {})",
        std::process::id(),
        dir.path().join("fit.lock").display()
    );
    assert!(stderr(&o).contains(&want), "{}", stderr(&o));
    assert!(!out.exists() && !dir.path().join("fit.starts.jsonl").exists());

    // The same for a diagnosis folder, before any work.
    let diag = dir.path().join("diag");
    std::fs::create_dir(&diag).unwrap();
    let held = vanefit::io::OutputLock::acquire(&diag.join(".vanefit.lock")).unwrap();
    let o = vanefit(&["diagnose", DATASET, "--out", diag.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("output in use by pid"),
        "{}",
        stderr(&o)
    );
    assert!(refused_before_work(&o), "{}", stderr(&o));
    drop((lock, held));

    // A lock file left by a killed run (its pid is gone): taken over, the run goes on.
    std::fs::write(dir.path().join("fit.lock"), "4000000\n").unwrap();
    let o = fit(out_s);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("of pid 4000000, which is no longer running"));
    assert!(out.is_file());
    assert!(!dir.path().join("fit.lock").exists(), "lock released");
}

/// A run refused before any work: nothing on stdout (no result, no "created folder") and
/// no progress line (`[  0.2 s] …`) on stderr, only the error. Judged by what the run
/// wrote, not by how long it took (a busy machine can take seconds to start a process).
fn refused_before_work(o: &Output) -> bool {
    o.stdout.is_empty() && !stderr(o).lines().any(|l| l.trim_start().starts_with('['))
}

#[test]
fn outputs_are_checked_before_any_work_and_leave_nothing_behind() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // `fit --out <an existing folder>`: refused at once, not after the search.
    std::fs::create_dir(d.join("folder")).unwrap();
    let o = vanefit(&["fit", DATASET, "--out", d.join("folder").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(refused_before_work(&o), "{}", stderr(&o));
    let want = format!(
        "--out {}: is a folder, not a file",
        d.join("folder").display()
    );
    assert!(stderr(&o).contains(&want), "{}", stderr(&o));
    assert_eq!(std::fs::read_dir(d.join("folder")).unwrap().count(), 0);

    // A parent path that is a file: named, not "File exists (os error 17)".
    std::fs::write(d.join("afile"), "x").unwrap();
    let want = format!(
        "cannot write here: {} is a file, not a folder",
        d.join("afile").display()
    );
    for args in [
        vec!["diagnose", DATASET, "--out"],
        vec!["simulate", DATASET, "--out"],
        vec!["control", "bode", "--out"],
    ] {
        let target = d.join("afile/sub");
        let mut args = args.clone();
        args.push(target.to_str().unwrap());
        let o = vanefit(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(stderr(&o).contains(&want), "{args:?}: {}", stderr(&o));
        assert!(refused_before_work(&o), "{args:?}: {}", stderr(&o));
    }

    // A missing parent folder is created, and said.
    let deep = d.join("new/deeper/sim");
    let o = vanefit(&["simulate", DATASET, "--out", deep.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("created folder"), "{}", stderr(&o));
    assert!(deep.join("ramp.csv").is_file());
    assert!(!deep.join(".vanefit.lock").exists());
    assert!(leftovers(d).is_empty(), "{:?}", leftovers(d));
}

#[test]
fn a_failed_atomic_write_removes_its_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    // The rename fails: the target is a folder that is not empty.
    let target = dir.path().join("report.md");
    std::fs::create_dir(&target).unwrap();
    std::fs::write(target.join("x"), "x").unwrap();
    assert!(vanefit::io::write_atomic(&target, b"text").is_err());
    assert!(
        leftovers(dir.path()).is_empty(),
        "{:?}",
        leftovers(dir.path())
    );
}

/// A starts file whose records are whole JSON but cannot be starts of the run (edited, or
/// copied from another run): `--resume` refuses it at the line instead of panicking in the
/// optimizer (a start of too few coordinates did: exit 101) or choosing a best start by a
/// cost no run gives. Found by hand while fuzzing the files a user's run reads back.
#[test]
fn a_starts_file_with_records_of_another_shape_is_refused_at_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fit.json");
    let fit = |resume: bool| {
        let mut args = vec![
            "fit",
            DATASET,
            "--starts",
            "2",
            "--max-iters",
            "40",
            "--estimate",
            "c_in1,c_out2,t_coulomb",
            "--uncertainty",
            "none",
            "--no-plots",
            "--out",
            out.to_str().unwrap(),
        ];
        if resume {
            args.push("--resume");
        }
        vanefit(&args)
    };
    assert!(fit(false).status.success());
    let starts = dir.path().join("fit.starts.jsonl");
    let text = std::fs::read_to_string(&starts).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let record: serde_json::Value = serde_json::from_str(lines[1]).unwrap();
    let edited = |key: &str, value: serde_json::Value| {
        let mut r = record.clone();
        r[key] = value;
        format!("{}\n{}\n", lines[0], r)
    };
    for (key, value, why) in [
        (
            "theta",
            serde_json::json!([]),
            "coordinates where the run has 3 parameters",
        ),
        (
            "theta0",
            serde_json::json!([0.1, 0.2]),
            "coordinates where the run has 3 parameters",
        ),
        (
            "theta",
            serde_json::json!([1e308, 1e308, 1e308, 1e308]),
            "where the run has 3",
        ),
    ] {
        std::fs::write(&starts, edited(key, value)).unwrap();
        let o = fit(true);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{key}: {e}");
        assert!(e.contains(&format!("{}:2", starts.display())), "{e}");
        assert!(e.contains(why) && e.contains("drop --resume"), "{e}");
    }
}

#[test]
fn bad_usage_exits_2_and_bad_input_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x");
    let out = out.to_str().unwrap();
    for args in [
        vec!["fit", DATASET, "--out", out, "--starts", "0"],
        vec!["fit", DATASET, "--out", out, "--threads", "0"],
        vec!["fit", DATASET, "--out", out, "--effects", "warp_drive"],
        vec!["diagnose", DATASET, "--out", out, "--starts", "0"],
        vec!["synth", out, "--effects", "warp_drive"],
        vec!["control", "bode", "--out", out, "--effects", "warp_drive"],
    ] {
        let o = vanefit(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        let option = args.iter().rev().nth(1).unwrap();
        assert!(stderr(&o).contains(option), "{args:?}: {}", stderr(&o));
    }
    assert!(!Path::new(out).exists(), "nothing written on bad usage");
    let o = vanefit(&["check", "no/such/dataset"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
}

/// A ramp dataset of `rows` rows, interpolated from the shipped ramp with a little noise.
fn long_ramp(dir: &Path, rows: usize) {
    let src = std::fs::read_to_string(Path::new(DATASET).join("ramp.csv")).unwrap();
    let data: Vec<Vec<f64>> = src
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    let mut text = String::from("t_s,p_port1_mpa,flow1_g_s,flow2_g_s,speed_rpm\n");
    let mut state = 1u64;
    let mut noise = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    let m = data.len();
    for i in 0..rows {
        let x = (m - 1) as f64 * i as f64 / (rows - 1) as f64;
        let j = (x as usize).min(m - 2);
        let a = x - j as f64;
        let v: Vec<f64> = (0..5)
            .map(|k| data[j][k] * (1.0 - a) + data[j + 1][k] * a)
            .collect();
        text.push_str(&format!(
            "{:.9e},{:.7e},{:.7e},{:.7e},{:.7e}\n",
            v[0],
            v[1] * (1.0 + 1e-3 * noise()),
            v[2] + 1e-3 * noise(),
            v[3] + 1e-3 * noise(),
            v[4] + noise()
        ));
    }
    std::fs::write(dir.join("ramp.csv"), text).unwrap();
    let rig = std::fs::read_to_string(Path::new(DATASET).join("rig.toml")).unwrap();
    let head = rig.split("[[experiment]]").next().unwrap();
    std::fs::write(
        dir.join("rig.toml"),
        format!("{head}[[experiment]]\nkind = \"pressure_ramp\"\nfile = \"ramp.csv\"\nload = {{ kind = \"viscous_brake\", c_nm_s_rad = 1e-4 }}\n"),
    )
    .unwrap();
}

/// CPU seconds (user + system) that `vanefit check <dir>` takes, of that process alone
/// (wait4's resource usage, not the wall clock: the tests share the machine with others),
/// and what it printed.
#[cfg(unix)]
// The child is reaped by wait4 (for its resource usage), which clippy cannot see.
#[allow(clippy::zombie_processes)]
fn check_cpu_s(dir: &Path) -> (f64, String) {
    use std::io::Read;
    let mut child = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(["check", dir.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut out = String::new();
    child
        .stdout
        .take()
        .unwrap()
        .read_to_string(&mut out)
        .unwrap();
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: a zeroed rusage is a valid value of this plain C struct, and wait4 writes
    // into it and `status` only; `pid` is our own child, not yet waited for.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let got = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(got, pid, "wait4 failed");
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "{out}"
    );
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    (secs(usage.ru_utime) + secs(usage.ru_stime), out)
}

#[cfg(unix)]
#[test]
fn check_is_linear_in_the_rows() {
    // Before the fix: 6k rows 0.55 s, 20k 3.5 s, 60k 26 s (a split search refined at every
    // index around its best coarse step: quadratic, ×47 for ten times the rows). The cost
    // of ten times the rows is compared with the cost of the rows themselves, in CPU
    // seconds of the check alone, so that neither a busy machine nor a debug build decides:
    // linear gives at most ×10 (less with the fixed start-up cost), quadratic ×100.
    let small = tempfile::tempdir().unwrap();
    let large = tempfile::tempdir().unwrap();
    long_ramp(small.path(), 6_000);
    long_ramp(large.path(), 60_000);
    let (cpu_small, out_small) = check_cpu_s(small.path());
    let (cpu_large, out_large) = check_cpu_s(large.path());
    assert!(out_small.contains("(6000 rows)"), "{out_small}");
    assert!(out_large.contains("(60000 rows)"), "{out_large}");
    let ratio = cpu_large / cpu_small.max(1e-3);
    println!("check: {cpu_small:.3} CPU-s for 6 000 rows, {cpu_large:.3} for 60 000 (×{ratio:.1})");
    assert!(
        ratio < 25.0,
        "check: {cpu_small:.3} CPU-s for 6 000 rows, {cpu_large:.3} for 60 000 (×{ratio:.1})"
    );
}

#[test]
fn duplicated_columns_and_decimal_commas_are_located_and_named() {
    let dir = tempfile::tempdir().unwrap();
    let copy = |name: &str, edit: &dyn Fn(&str) -> String| {
        let ds = dir.path().join(name);
        std::fs::create_dir(&ds).unwrap();
        for f in ["rig.toml", "datasheet.csv", "ramp.csv", "throttle.csv"] {
            let text = std::fs::read_to_string(Path::new(DATASET).join(f)).unwrap();
            let text = if f == "ramp.csv" { edit(&text) } else { text };
            std::fs::write(ds.join(f), text).unwrap();
        }
        ds
    };
    let twice = copy("twice", &|t| t.replacen("flow2_g_s", "flow1_g_s", 1));
    let o = vanefit(&["check", twice.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("ramp.csv:1:4 (column 'flow1_g_s'): flow1 given twice"),
        "{}",
        stderr(&o)
    );
    let commas = copy("commas", &|t| {
        let mut lines = t.lines();
        let mut out = format!("{}\n", lines.next().unwrap());
        for l in lines {
            out.push_str(&l.replace('.', ","));
            out.push('\n');
        }
        out
    });
    let o = vanefit(&["check", commas.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("ramp.csv:2: malformed row: 10 fields where the header has 5"),
        "{e}"
    );
    assert!(e.contains("decimal comma"), "{e}");
}

/// The shipped fit file with one parameter's value replaced.
fn fit_with(dir: &Path, name: &str, value: f64) -> String {
    let text = std::fs::read_to_string("fits/ar034-synthetic.json").unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    doc["parameters"][name]["value"] = serde_json::json!(value);
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    path.to_str().unwrap().to_string()
}

/// Every CSV under `dir` free of NaN (a command's output is valid or not written).
fn no_nan_in(dir: &Path) {
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let text = std::fs::read_to_string(e.path()).unwrap_or_default();
        assert!(
            !text.to_lowercase().contains("nan"),
            "{}",
            e.path().display()
        );
    }
}

#[test]
fn numerical_faults_end_with_a_message_or_a_valid_result() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A motor that cannot turn (friction 100 N·m): simulate gives a valid standstill,
    // predict says why it has no catalogue.
    let stuck = fit_with(d, "t_coulomb", 100.0);
    let out = d.join("sim-stuck");
    let o = vanefit(&[
        "simulate",
        DATASET,
        "--params",
        &stuck,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    no_nan_in(&out);
    let o = vanefit(&[
        "predict",
        &stuck,
        "--out",
        d.join("p-stuck").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("the motor does not start"),
        "{}",
        stderr(&o)
    );
    no_nan_in(&d.join("p-stuck"));
    // A nozzle of zero conductance: refused, naming the option.
    let fit = "fits/ar034-synthetic.json";
    let o = vanefit(&[
        "predict",
        fit,
        "--inlet-nozzle",
        "0",
        "--out",
        d.join("p0").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--inlet-nozzle 0"), "{}", stderr(&o));
    // An inlet that all but stalls the motor: a message, no panic, no NaN written.
    let choked = fit_with(d, "c_in1", 1e-15);
    let out = d.join("sim-choked");
    let o = vanefit(&[
        "simulate",
        DATASET,
        "--params",
        &choked,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    assert!(o.status.code() == Some(1) || o.status.success());
    no_nan_in(&out);
}
