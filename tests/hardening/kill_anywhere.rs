//! Kill anywhere: `fit`, `diagnose` and `batch` killed with SIGKILL at many
//! moments and run again each time end with the result an uninterrupted run of the same seed
//! gives, no output file is ever seen half-written (a result is absent or whole JSON after
//! every kill), and the run that finishes leaves no temporary file of a killed one behind.
//!
//! Each kill is aimed by what the run itself writes (its status and starts files, its
//! progress lines), a seeded fraction into the stage it aims at, with the stages' lengths
//! measured again as the test goes: how many kills land mid-run, and in which phases, does
//! not depend on how fast the machine is, or was when the test began (a moment measured
//! once as a fraction of one uninterrupted run fell after the end of most runs once the
//! machine's load dropped).

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant, SystemTime};

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
    c.stdout(Stdio::null()).stderr(Stdio::null());
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

/// A file as last written: its length, modification time and (on unix) inode. Every write
/// changes it: an atomic write replaces the file by a new one (another inode), an append
/// makes it longer.
type Print = (u64, Option<SystemTime>, u64);

/// Every file under `dir` (not `dir` itself missing: then none) with its [`Print`].
fn files(dir: &Path) -> BTreeMap<PathBuf, Print> {
    let mut found = BTreeMap::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return found;
    };
    for e in entries.flatten() {
        let Ok(m) = e.metadata() else {
            continue; // a temporary renamed meanwhile
        };
        if m.is_dir() {
            found.extend(files(&e.path()));
        } else {
            #[cfg(unix)]
            let inode = std::os::unix::fs::MetadataExt::ino(&m);
            #[cfg(not(unix))]
            let inode = 0;
            found.insert(e.path(), (m.len(), m.modified().ok(), inode));
        }
    }
    found
}

/// The finished starts a starts file holds: its whole records after the header (a line an
/// append is still writing is not one).
fn finished_in(path: &Path) -> usize {
    std::fs::read_to_string(path).map_or(0, |t| {
        t.lines()
            .skip(1)
            .filter(|l| serde_json::from_str::<serde_json::Value>(l).is_ok())
            .count()
    })
}

/// How far a run of `fit` or `batch` got, judged only by what it wrote: each stage is a
/// write the run makes, in the order a run makes them, so a kill can be aimed at a stage
/// whatever the machine's speed. (A stage a run has no part of, such as a batch unit's
/// status for `fit`, is passed over.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Stage {
    /// Nothing written yet: starting up, claiming the output, loading the data, the
    /// catalogue's estimates before the search.
    Startup,
    /// A batch unit's status file written (`running`): the unit started.
    UnitStarted,
    /// A starts file written (its header, or a start appended): the rounds began.
    Rounds,
    /// A starts file holds more finished starts than when the run was started.
    StartFinished,
    /// A starts file written by this run holds every start: the fit's last steps (sorting
    /// the file, the intervals, writing the fit file).
    StartsDone,
    /// A batch unit's status file written saying `done`: a unit finished, another runs.
    UnitDone,
}

const STAGES: usize = Stage::UnitDone as usize + 1;

/// The output folder of a run as it was when the run was started.
struct Before {
    files: BTreeMap<PathBuf, Print>,
    finished: BTreeMap<PathBuf, usize>,
}

impl Before {
    fn of(dir: &Path) -> Self {
        let files = files(dir);
        let finished = files
            .keys()
            .filter(|p| p.to_string_lossy().ends_with("starts.jsonl"))
            .map(|p| (p.clone(), finished_in(p)))
            .collect();
        Self { files, finished }
    }

    /// The stage the run writing into `dir` (of fits of `starts` starts) has reached.
    fn stage(&self, dir: &Path, starts: usize) -> Stage {
        let mut reached = Stage::Startup;
        for (path, print) in files(dir) {
            if self.files.get(&path) == Some(&print) {
                continue; // not written by this run
            }
            let name = path.file_name().unwrap().to_string_lossy();
            let here = if name == "status.json" {
                let text = std::fs::read_to_string(&path).unwrap_or_default();
                if text.contains("\"status\": \"done\"") {
                    Stage::UnitDone
                } else {
                    Stage::UnitStarted
                }
            } else if name.ends_with("starts.jsonl") {
                let n = finished_in(&path);
                if n == starts {
                    Stage::StartsDone
                } else if n > self.finished.get(&path).copied().unwrap_or(0) {
                    Stage::StartFinished
                } else {
                    Stage::Rounds
                }
            } else {
                Stage::Startup
            };
            reached = reached.max(here);
        }
        reached
    }
}

/// How long runs of this test stay in each stage: from first being seen in it to first
/// being seen further on (or, in the last stage a run reaches, to its end). Measured on the
/// uninterrupted run and then again on every run that shows a stage's whole length, so it
/// follows the machine's speed as the test goes (another build starting or ending beside
/// it), and a kill aimed a fraction into a stage lands in it or a little further on.
#[derive(Default)]
struct Pace([Duration; STAGES]);

/// What became of a watched run.
struct Ran {
    /// It was killed (it was still running, and did not end by itself).
    killed: bool,
    /// It ended by itself with success.
    success: bool,
    /// The stage it had reached when it was killed or ended (read after the end, so it
    /// counts what it wrote between the last look and the kill).
    stage: Stage,
}

/// Runs `cmd`, which writes into `dir` (fits of `starts` starts), looking at what it wrote
/// every millisecond; with `kill_at = Some((stage, f))`, kills it `f` of `stage`'s length
/// (as `pace` has it) after it is first seen at `stage` or further, if it still runs then.
/// Learns the stages' lengths it sees into `pace`.
fn watch(
    mut cmd: Command,
    dir: &Path,
    starts: usize,
    pace: &mut Pace,
    kill_at: Option<(Stage, f64)>,
) -> Ran {
    let before = Before::of(dir);
    let mut child = cmd.spawn().unwrap();
    let t0 = Instant::now();
    // When the run was first seen at each stage or further.
    let mut first = [None::<Duration>; STAGES];
    let (mut ended_at, mut killed) = (None, false);
    loop {
        let stage = before.stage(dir, starts);
        let now = t0.elapsed();
        for t in &mut first[..=stage as usize] {
            t.get_or_insert(now);
        }
        if child.try_wait().unwrap().is_some() {
            ended_at = Some(now);
            break;
        }
        if let Some((at, f)) = kill_at {
            if first[at as usize].is_some_and(|t| now >= t + pace.0[at as usize].mul_f64(f)) {
                child.kill().unwrap();
                killed = true;
                break;
            }
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    let status = child.wait().unwrap();
    // A stage's length: to the next one seen (not seen in the same look: a stage this
    // kind of run has not, or too short to see), or to the end of a run that ended by itself.
    for s in 0..STAGES {
        let end = first.get(s + 1).copied().flatten().or(ended_at);
        if let (Some(from), Some(to)) = (first[s], end) {
            if to > from {
                pace.0[s] = to - from;
            }
        }
    }
    Ran {
        killed: killed && !status.success(),
        success: status.success(),
        stage: before.stage(dir, starts),
    }
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
    let mut pace = Pace::default();
    let ran = watch(
        fit_command(&reference, false),
        reference.parent().unwrap(),
        6,
        &mut pace,
        None,
    );
    assert!(ran.success, "the uninterrupted run");

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
        std::thread::sleep(Duration::from_millis(1));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let kept = finished_starts();
    assert!(
        (1..6).contains(&kept),
        "killed inside the first round, {kept} of 6 starts kept (want some, not all)"
    );
    // Then resumes, each killed at a seeded moment of a seeded stage of its own run (while
    // it starts up and loads; once it has finished a start of its own, among the others; or
    // after every start is in the file, in the fit's last steps and its writes), aimed by
    // what the run writes, not by a clock: until 30 were killed mid-run. A resume that
    // ends by itself (it finished the fit) is resumed again: a finished fit resumed redoes
    // its last steps and writes, which are killed in turn.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    // Kills while starting up, inside the round, in the last steps.
    let mut phases = [0, 1, 0];
    let (mut kills, mut runs) = (1, 0);
    while kills < 30 && runs < 60 {
        runs += 1;
        let stages: &[Stage] = if finished_starts() == 6 {
            &[Stage::Startup, Stage::StartsDone]
        } else {
            &[Stage::Startup, Stage::StartFinished, Stage::StartsDone]
        };
        let at = stages[(next_fraction(&mut state) * stages.len() as f64) as usize];
        let ran = watch(
            fit_command(&out, true),
            out.parent().unwrap(),
            6,
            &mut pace,
            Some((at, next_fraction(&mut state))),
        );
        if ran.killed {
            kills += 1;
            phases[match ran.stage {
                Stage::Startup | Stage::UnitStarted => 0,
                Stage::Rounds | Stage::StartFinished => 1,
                Stage::StartsDone | Stage::UnitDone => 2,
            }] += 1;
            no_half_written_results(out.parent().unwrap());
        } else {
            assert!(ran.success, "a resume that was not killed failed");
        }
    }
    // One more resume, after the last kill: it ends the fit, and its writes remove the
    // temporary a killed write would have left.
    let stale = plant_stale_temporary(out.parent().unwrap(), "fit.json");
    assert!(fit_command(&out, true).status().unwrap().success());
    assert!(!stale.exists(), "the killed run's temporary is removed");
    assert_eq!(temporaries(out.parent().unwrap()), Vec::<String>::new());
    eprintln!(
        "fit killed {kills} times in {} runs: {} while starting up, {} inside the round \
         (the first with {kept} starts kept), {} in the last steps",
        runs + 1,
        phases[0],
        phases[1],
        phases[2]
    );
    assert!(kills >= 30, "only {kills} kills in {} runs", runs + 1);
    assert!(
        phases[0] >= 2 && phases[2] >= 2,
        "kills while starting up, inside the round, in the last steps: {phases:?}"
    );
    assert_eq!(estimate(&out), estimate(&reference));
    assert!(!out.with_extension("lock").exists(), "lock released");
}

#[test]
fn diagnose_killed_at_random_moments_leaves_whole_files_and_reruns_to_the_same_result() {
    let dir = tempfile::tempdir().unwrap();
    let run = |out: &Path, stderr: Stdio| {
        Command::new(env!("CARGO_BIN_EXE_vanefit"))
            .args(["diagnose", DATASET, "--starts", "2", "--out"])
            .arg(out)
            .stdout(Stdio::null())
            .stderr(stderr)
            .spawn()
            .unwrap()
    };
    let reference = dir.path().join("ref");
    assert!(run(&reference, Stdio::null()).wait().unwrap().success());
    let out = dir.path().join("killed");
    // A diagnosis does not resume: each kill must leave its files whole (or absent), and the
    // lock of the killed run must not block the next. Each kill waits for a progress line the
    // run prints (its phases), then for a fraction of the time the run took to print it, or
    // for the first result file the run writes after it: so each lands in its phase whatever
    // the machine's speed. The first three have most of a diagnosis still to run.
    let moments = [
        ("baseline fit:", 0.0, false),     // inside the baseline fit
        ("refitting", 0.5, false),         // among the candidates' refits
        ("concealment: each", 0.0, false), // inside the concealment's fits
        ("done in", 0.0, false),           // as the results begin to be written
        ("done in", 0.0, true),            // once one is written: among the others
    ];
    let mut killed = Vec::new();
    for (line, fraction, after_a_file) in moments {
        let before = files(&out);
        let mut child = run(&out, Stdio::piped());
        let t0 = Instant::now();
        let (tx, rx) = std::sync::mpsc::channel();
        let stderr = child.stderr.take().unwrap();
        let reader = std::thread::spawn(move || {
            for l in BufReader::new(stderr).lines().map_while(Result::ok) {
                if tx.send(l).is_err() {
                    break;
                }
            }
        });
        // The line (none if the run ended first: its stderr closed).
        let seen = rx.iter().find(|l| l.contains(line)).map(|_| t0.elapsed());
        if let Some(t) = seen {
            std::thread::sleep(t.mul_f64(fraction));
            while after_a_file && child.try_wait().unwrap().is_none() {
                let written = files(&out).into_iter().any(|(p, print)| {
                    let name = p.file_name().unwrap().to_string_lossy();
                    !name.starts_with('.') && before.get(&p) != Some(&print)
                });
                if written {
                    break;
                }
                std::thread::sleep(Duration::from_micros(200));
            }
        }
        let running = child.try_wait().unwrap().is_none();
        if running {
            child.kill().unwrap();
        }
        let status = child.wait().unwrap();
        drop(rx);
        reader.join().unwrap();
        killed.push(running && !status.success());
        no_half_written_results(&out);
    }
    eprintln!("diagnosis killed mid-run at the moments {moments:?}: {killed:?}");
    assert!(
        killed[..3].iter().all(|&k| k),
        "the kills before the results are written all land mid-run: {killed:?}"
    );
    std::fs::create_dir_all(&out).unwrap();
    let stale = plant_stale_temporary(&out, "diagnosis.json");
    assert!(run(&out, Stdio::null()).wait().unwrap().success());
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
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    c
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
    let mut pace = Pace::default();
    let t0 = Instant::now();
    let ran = watch(
        batch_command(&manifest, &reference),
        &reference,
        6,
        &mut pace,
        None,
    );
    assert!(ran.success, "the uninterrupted run");
    let full = t0.elapsed();
    let expected = merge(&reference);

    // Kill sequences: a fresh batch folder, killed up to three times and run again each
    // time, the last time to the end; then merged. Each kill is aimed at a seeded stage of
    // the run (see `Stage`: starting up, a unit started, a fit's rounds, a start finished, a
    // fit's last steps, a unit done while others run), seen in what the run writes, and a
    // seeded fraction into it (by the stages' lengths as this test last measured them): so
    // where kills land does not depend on how fast the machine is, or was at the start. A
    // run that ends before its kill (the stage aimed at was not left to it) ends the
    // sequence. Sequences repeat until at least 15 kills were made mid-run, at least 2 in
    // each phase: starting up or a unit's setup, a fit's rounds, a fit's last steps, after
    // a unit finished.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let (mut kills, mut files_seen, mut sequences) = (0, 0, 0);
    let mut phases = [0usize; 4];
    while (kills < 15 || phases.iter().any(|&n| n < 2)) && sequences < 30 {
        sequences += 1;
        let out = dir.path().join(format!("killed{sequences}"));
        for _ in 0..3 {
            // A phase, then a stage of it: each phase is aimed at as often.
            let phase: &[Stage] = [
                &[Stage::Startup, Stage::UnitStarted][..],
                &[Stage::Rounds, Stage::StartFinished],
                &[Stage::StartsDone],
                &[Stage::UnitDone],
            ][(next_fraction(&mut state) * 4.0) as usize];
            let at = phase[(next_fraction(&mut state) * phase.len() as f64) as usize];
            let ran = watch(
                batch_command(&manifest, &out),
                &out,
                6,
                &mut pace,
                Some((at, next_fraction(&mut state))),
            );
            if !ran.killed {
                assert!(ran.success, "sequence {sequences}: a run not killed failed");
                break;
            }
            kills += 1;
            phases[match ran.stage {
                Stage::Startup | Stage::UnitStarted => 0,
                Stage::Rounds | Stage::StartFinished => 1,
                Stage::StartsDone => 2,
                Stage::UnitDone => 3,
            }] += 1;
            files_seen += no_half_written_results(&out);
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
        "batch killed mid-run {kills} times in {sequences} sequences: {} starting up or in a \
         unit's setup, {} in a fit's rounds, {} in a fit's last steps, {} after a unit had \
         finished ({files_seen} JSON files checked whole); uninterrupted run {full:?}",
        phases[0], phases[1], phases[2], phases[3]
    );
    assert!(kills >= 15, "only {kills} kills");
    assert!(
        phases.iter().all(|&n| n >= 2),
        "kills starting up, in rounds, in last steps, after a unit: {phases:?}"
    );
}
