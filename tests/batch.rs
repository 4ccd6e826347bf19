//! `vanefit batch` and `vanefit merge` (docs/formats.md, "Batches: manifest, unit folders,
//! summary"), through the binary: shards
//! partition the units, results do not depend on the shard or thread count, finished units
//! are skipped, an interrupted fit resumes, a failing unit is recorded while the others
//! finish, a bad manifest is refused at its line and column, and `summary.csv` has exactly
//! the columns of (docs/formats.md, "Contracts added later").

use std::path::Path;
use std::process::{Command, Output};
use vanefit::batch::{plan, Manifest, Shard};

const BIN: &str = env!("CARGO_BIN_EXE_vanefit");

/// Short fits (three parameters, three starts, few iterations, curvature intervals), so
/// that a fleet runs in seconds; what is tested is the bookkeeping, not the estimate.
const FIT: &str = r#"
[fit]
starts = 3
seed = 7
max_iters = 200
uncertainty = "curvature"
estimate = ["c_in1", "c_out2", "t_coulomb"]
plots = false
"#;

fn vanefit(args: &[&str], cwd: &Path) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("the binary runs")
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status.code(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// A folder with `n` synthetic datasets (`ds/m1`..), optionally a broken one, and a
/// manifest `m.toml` over `ds/*` with `tasks`.
fn fleet(n: usize, broken: bool, tasks: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for i in 1..=n {
        let out = format!("ds/m{i}");
        let (noise, seed) = ((i % 3 + 1).to_string(), i.to_string());
        let o = vanefit(
            &["synth", &out, "--noise", &noise, "--seed", &seed],
            dir.path(),
        );
        assert!(o.status.success(), "{}", text(&o));
    }
    if broken {
        std::fs::create_dir_all(dir.path().join("ds/broken")).unwrap();
        std::fs::write(dir.path().join("ds/broken/rig.toml"), "[motor\n").unwrap();
    }
    let manifest = format!(
        "[batch]\ndatasets = [\"ds/*\"]\ntasks = [{tasks}]\n{FIT}\n[predict]\npressures = [4, 6]\n"
    );
    std::fs::write(dir.path().join("m.toml"), manifest).unwrap();
    dir
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn status_of(out: &Path, unit: &str) -> serde_json::Value {
    serde_json::from_str(&read(&out.join(unit).join("status.json"))).unwrap()
}

/// Every unit is in exactly one shard for every N, a predict is in its fit's shard, and
/// the unit order does not depend on N.
#[test]
fn shards_partition_the_units() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["b", "a", "c", "e", "d"] {
        std::fs::create_dir_all(dir.path().join("ds").join(name)).unwrap();
    }
    std::fs::write(dir.path().join("ds/README"), "not a dataset").unwrap();
    std::fs::write(
        dir.path().join("m.toml"),
        "[batch]\ndatasets = [\"ds/*\"]\ntasks = [\"predict\", \"fit\", \"diagnose\"]\n",
    )
    .unwrap();
    let m = Manifest::load(&dir.path().join("m.toml")).unwrap();
    let all = plan::units(&m);
    assert_eq!(
        all.len(),
        15,
        "5 datasets x 3 tasks (the README is no dataset)"
    );
    let names: Vec<&str> = all.iter().map(|u| u.dataset.as_str()).collect();
    assert_eq!(names[0], "a", "datasets sorted by name");
    assert_eq!(all[0].task.id(), "fit", "fit before diagnose and predict");
    for n in 1..=7 {
        let shards: Vec<Vec<plan::Unit>> = (1..=n)
            .map(|i| plan::select(&all, Shard { index: i, count: n }))
            .collect();
        for u in &all {
            let owners: Vec<usize> = (0..n).filter(|&k| shards[k].contains(u)).collect();
            assert_eq!(owners.len(), 1, "{} in shards {owners:?} of {n}", u.label());
            if u.task.id() == "predict" {
                let fit = all
                    .iter()
                    .find(|f| f.dataset == u.dataset && f.task.id() == "fit")
                    .unwrap();
                assert!(shards[owners[0]].contains(fit), "predict with its fit");
            }
        }
        assert_eq!(shards.iter().map(Vec::len).sum::<usize>(), all.len());
    }
}

/// Three shards on one thread, then merge, give the summary of one unsharded run on two
/// threads, byte for byte; the unit's fit is the one `vanefit fit` makes with the same
/// options; a second run skips every finished unit without touching it.
#[test]
fn shards_merge_to_the_unsharded_run_and_finished_units_are_skipped() {
    let dir = fleet(4, false, "\"fit\", \"predict\"");
    let p = dir.path();
    let one = vanefit(&["batch", "m.toml", "--out", "one", "--threads", "2"], p);
    assert!(one.status.success(), "{}", text(&one));
    for i in 1..=3 {
        let shard = format!("{i}/3");
        let o = vanefit(
            &[
                "batch",
                "m.toml",
                "--out",
                "three",
                "--shard",
                &shard,
                "--threads",
                "1",
            ],
            p,
        );
        assert!(o.status.success(), "{}", text(&o));
    }
    for out in ["one", "three"] {
        let o = vanefit(&["merge", out], p);
        assert!(o.status.success(), "{}", text(&o));
    }
    let (a, b) = (
        read(&p.join("one/summary.csv")),
        read(&p.join("three/summary.csv")),
    );
    assert_eq!(a, b, "sharded and unsharded summaries differ");
    assert_eq!(a.lines().count(), 1 + 8, "header and 4 datasets x 2 tasks");
    assert!(a.lines().skip(1).all(|l| l.contains(",done,")), "{a}");
    assert_eq!(
        read(&p.join("one/fleet.svg")),
        read(&p.join("three/fleet.svg"))
    );

    // The same fit as the command's.
    let o = vanefit(
        &[
            "fit",
            "ds/m2",
            "--starts",
            "3",
            "--seed",
            "7",
            "--max-iters",
            "200",
            "--uncertainty",
            "curvature",
            "--estimate",
            "c_in1,c_out2,t_coulomb",
            "--no-plots",
            "--out",
            "cmd.json",
        ],
        p,
    );
    assert!(o.status.success(), "{}", text(&o));
    let params = |f: &Path| {
        let v: serde_json::Value = serde_json::from_str(&read(f)).unwrap();
        (v["parameters"].clone(), v["cost"].clone())
    };
    assert_eq!(
        params(&p.join("cmd.json")),
        params(&p.join("one/m2/fit/fit.json"))
    );

    // A second run skips everything and rewrites nothing.
    let stamp = |f: &str| std::fs::metadata(p.join(f)).unwrap().modified().unwrap();
    let before = (
        stamp("one/m1/fit/fit.json"),
        stamp("one/m1/fit/status.json"),
    );
    let again = vanefit(&["batch", "m.toml", "--out", "one"], p);
    assert!(again.status.success(), "{}", text(&again));
    let out = String::from_utf8_lossy(&again.stdout);
    assert!(
        out.contains("0 done now, 8 finished before (skipped)"),
        "{out}"
    );
    let after = (
        stamp("one/m1/fit/fit.json"),
        stamp("one/m1/fit/status.json"),
    );
    assert_eq!(before, after);
}

/// A fit interrupted after some of its starts (status `running`, part of the starts file,
/// no fit file) resumes from the starts it finished and ends with the uninterrupted result.
#[test]
fn an_interrupted_fit_resumes() {
    let dir = fleet(2, false, "\"fit\"");
    let p = dir.path();
    let o = vanefit(&["batch", "m.toml", "--out", "r", "--threads", "1"], p);
    assert!(o.status.success(), "{}", text(&o));
    let unit = p.join("r/m1/fit");
    let whole = read(&unit.join("fit.json"));
    let starts = read(&unit.join("fit.starts.jsonl"));
    let lines: Vec<&str> = starts.lines().collect();
    assert_eq!(lines.len(), 1 + 3, "header and 3 starts");
    // The state a kill after the second start leaves: the status says running.
    std::fs::write(unit.join("fit.starts.jsonl"), lines[..3].join("\n") + "\n").unwrap();
    std::fs::remove_file(unit.join("fit.json")).unwrap();
    let mut status = status_of(&p.join("r"), "m1/fit");
    status["status"] = "running".into();
    std::fs::write(unit.join("status.json"), status.to_string()).unwrap();

    let o = vanefit(&["batch", "m.toml", "--out", "r", "--threads", "2"], p);
    assert!(o.status.success(), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("m1/fit: 3 starts, 2 read back from its starts file (resumed)"),
        "{err}"
    );
    assert!(err.contains("m2/fit: done before, skipped"), "{err}");
    let strip = |t: &str| {
        let mut v: serde_json::Value = serde_json::from_str(t).unwrap();
        v["run"] = serde_json::Value::Null; // wall time and threads
        v
    };
    assert_eq!(strip(&read(&unit.join("fit.json"))), strip(&whole));
    assert_eq!(read(&unit.join("fit.starts.jsonl")).lines().count(), 4);
    assert_eq!(status_of(&p.join("r"), "m1/fit")["status"], "done");
}

/// A broken dataset fails its units with the data layer's located message; the others
/// finish; the exit status is 1 with the count, or 0 with `--allow-failed-units`; the
/// merge lists the failure and exits 1. `summary.csv` has exactly the columns of
/// (docs/formats.md, "Contracts added later").
#[test]
fn a_failing_unit_is_recorded_and_the_others_finish() {
    let dir = fleet(2, true, "\"fit\", \"predict\"");
    let p = dir.path();
    let o = vanefit(&["batch", "m.toml", "--out", "r"], p);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("2 of 6 unit(s) failed"), "{err}");
    let fit = status_of(&p.join("r"), "broken/fit");
    assert_eq!(fit["status"], "failed");
    let msg = fit["message"].as_str().unwrap();
    assert!(msg.contains("rig.toml:1:"), "{msg}");
    let pred = status_of(&p.join("r"), "broken/predict");
    assert!(
        pred["message"].as_str().unwrap().contains("no fit"),
        "{pred}"
    );
    for ok in ["m1/fit", "m1/predict", "m2/fit", "m2/predict"] {
        assert_eq!(status_of(&p.join("r"), ok)["status"], "done", "{ok}");
    }
    let o = vanefit(
        &["batch", "m.toml", "--out", "r", "--allow-failed-units"],
        p,
    );
    assert!(o.status.success(), "{}", text(&o));

    let o = vanefit(&["merge", "r"], p);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let csv = read(&p.join("r/summary.csv"));
    let header = csv.lines().next().unwrap();
    let mut want = vec!["dataset", "task", "status", "message", "cost"]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>();
    for n in ["c_in1", "c_out2", "t_coulomb"] {
        want.extend([n.to_string(), format!("{n}_ci_lo"), format!("{n}_ci_hi")]);
    }
    assert_eq!(header, want.join(","));
    let mut rows = csv::Reader::from_reader(csv.as_bytes());
    let recs: Vec<csv::StringRecord> = rows.records().map(Result::unwrap).collect();
    assert_eq!(recs.len(), 6);
    let first3 = |r: &csv::StringRecord| r.iter().take(3).collect::<Vec<_>>().join(",");
    assert_eq!(first3(&recs[0]), "broken,fit,failed");
    assert!(recs[0][3].contains("rig.toml:1:"));
    let m1 = &recs[2];
    assert_eq!(first3(m1), "m1,fit,done");
    let num = |i: usize| m1[i].parse::<f64>().unwrap();
    assert!(num(4) > 0.0, "cost");
    assert!(
        num(6) < num(5) && num(5) < num(7),
        "c_in1 inside its interval"
    );
    assert!((1e-9..1e-7).contains(&num(5)), "c_in1 in SI m3/(s*Pa)");
    let md = read(&p.join("r/summary.md"));
    assert!(md.contains("`broken/fit`: failed"), "{md}");
    assert!(p.join("r/fleet.svg").exists());
}

/// A bad manifest is refused with file, line and column and exit status 1; a bad shard is
/// bad usage (2); a batch folder of another manifest is refused.
#[test]
fn a_bad_manifest_is_refused_where_it_is_wrong() {
    let dir = fleet(1, false, "\"fit\"");
    let p = dir.path();
    let cases: &[(&str, &str, &str)] = &[
        (
            "[batch]\ndatasets = [\"ds/*\"]\ntasks = [\"fitt\"]\n",
            "bad.toml:3:10",
            "unknown variant",
        ),
        (
            "[batch]\ndatasets = [\"nothing/*\"]\ntasks = [\"fit\"]\n",
            "bad.toml:2:13",
            "matches no dataset folder",
        ),
        (
            "[batch]\ndatasets = [\"ds/*\"]\ntasks = [\"fit\"]\n[fit]\nstarts = 0\n",
            "bad.toml:5:10",
            "at least 1",
        ),
        (
            "[batch]\ndatasets = [\"ds/*\"]\ntasks = [\"fit\"]\n[fit]\nstars = 3\n",
            "bad.toml:5:1",
            "unknown field",
        ),
        (
            "[batch]\ndatasets = [\"ds/*\"\ntasks = [\"fit\"]\n",
            "bad.toml:3:",
            "",
        ),
        (
            "[batch]\ndatasets = [\"ds/*\"]\ntasks = [\"fit\"]\n[predict]\nunit = \"furlong\"\n",
            "bad.toml:4:1",
            "not a pressure unit",
        ),
        // Globs that would walk the file system outside the manifest's folder.
        (
            "[batch]\ndatasets = [\"ds/*\", \"/*/*/*\"]\ntasks = [\"fit\"]\n",
            "bad.toml:2:21 (value '\"/*/*/*\"')",
            "is an absolute path: dataset globs stay inside the manifest's folder",
        ),
        (
            "[batch]\ndatasets = [\"../x/*\"]\ntasks = [\"fit\"]\n",
            "bad.toml:2:13",
            "climbs out with '..'",
        ),
        (
            "[batch]\ndatasets = [\"ds/.?/.?/*\"]\ntasks = [\"fit\"]\n",
            "bad.toml:2:13",
            "has a component that matches '..'",
        ),
    ];
    for (manifest, place, what) in cases {
        std::fs::write(p.join("bad.toml"), manifest).unwrap();
        let o = vanefit(&["batch", "bad.toml", "--out", "r"], p);
        assert_eq!(o.status.code(), Some(1), "{manifest}\n{}", text(&o));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(place) && err.contains(what),
            "{manifest}\nwant {place} {what}\n{err}"
        );
        assert!(!p.join("r").exists(), "nothing written for a bad manifest");
    }
    let o = vanefit(&["batch", "m.toml", "--out", "r", "--shard", "0/2"], p);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let o = vanefit(&["batch", "m.toml", "--out", "r"], p);
    assert!(o.status.success(), "{}", text(&o));
    let other = read(&p.join("m.toml")).replace("seed = 7", "seed = 8");
    std::fs::write(p.join("other.toml"), other).unwrap();
    let o = vanefit(&["batch", "other.toml", "--out", "r"], p);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("holds a batch of other"));
    let o = vanefit(&["merge", "ds"], p);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not a batch folder"));
}

/// A diagnose unit writes the command's files, its verdict goes into the status message, a
/// row of `summary.csv` without fit columns, and the diagnoses table of `summary.md`.
#[test]
fn a_diagnose_unit_is_summarised() {
    let dir = fleet(1, false, "\"diagnose\"");
    let p = dir.path();
    let manifest = read(&p.join("m.toml")) + "\n[diagnose]\nstarts = 1\neffort = \"quick\"\n";
    std::fs::write(p.join("m.toml"), manifest).unwrap();
    let o = vanefit(&["batch", "m.toml", "--out", "r"], p);
    assert!(o.status.success(), "{}", text(&o));
    for f in ["diagnosis.json", "report.md", "extended.json"] {
        assert!(p.join("r/m1/diagnose").join(f).exists(), "{f}");
    }
    let status = status_of(&p.join("r"), "m1/diagnose");
    assert_eq!(status["status"], "done");
    let d: serde_json::Value =
        serde_json::from_str(&read(&p.join("r/m1/diagnose/diagnosis.json"))).unwrap();
    let mismatch = d["mismatch"].as_bool().unwrap();
    let msg = status["message"].as_str().unwrap();
    assert_eq!(msg.starts_with("mismatch"), mismatch, "{msg}");
    let o = vanefit(&["merge", "r"], p);
    assert!(o.status.success(), "{}", text(&o));
    let csv = read(&p.join("r/summary.csv"));
    assert_eq!(
        csv,
        format!("dataset,task,status,message,cost\nm1,diagnose,done,{msg}\n")
            .replace(&format!(",{msg}\n"), &format!(",{},\n", csv_cell(msg)))
    );
    let md = read(&p.join("r/summary.md"));
    let verdict = if mismatch { "yes" } else { "no" };
    assert!(md.contains(&format!("| m1 | {verdict} |")), "{md}");
}

/// A dataset's predict runs after its fit, whatever lies between them in the plan (here its
/// diagnose) and however many threads run the groups: every unit is done. (With a thread
/// per unit, a predict that did not wait would start beside the fit and fail.)
#[test]
fn a_predict_waits_for_its_fit_whatever_the_threads() {
    let dir = fleet(1, false, "\"fit\", \"diagnose\", \"predict\"");
    let p = dir.path();
    let manifest = read(&p.join("m.toml")) + "\n[diagnose]\nstarts = 1\neffort = \"quick\"\n";
    std::fs::write(p.join("m.toml"), manifest).unwrap();
    let o = vanefit(&["batch", "m.toml", "--out", "r", "--threads", "3"], p);
    assert!(o.status.success(), "{}", text(&o));
    for unit in ["m1/fit", "m1/diagnose", "m1/predict"] {
        let status = status_of(&p.join("r"), unit);
        assert_eq!(status["status"], "done", "{unit}: {status}");
    }
}

/// A CSV cell as the csv crate writes it (quoted when it holds a comma or a quote).
fn csv_cell(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A catalogue dataset's fit says what the pages pin (as `vanefit fit` prints it) in that
/// unit's own `fit.log`, not as a block among the batch's progress lines: stdout holds none
/// of it, and one progress line points to the log.
#[test]
fn a_catalogue_units_pinning_goes_to_its_log() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    let o = vanefit(&["synth", "ds/page", "--catalogue", "--seed", "3"], p);
    assert!(o.status.success(), "{}", text(&o));
    let manifest = "[batch]\ndatasets = [\"ds/*\"]\ntasks = [\"fit\"]\n\n[fit]\nstarts = 2\n\
                    seed = 1\nmax_iters = 60\nuncertainty = \"none\"\nplots = false\n";
    std::fs::write(p.join("m.toml"), manifest).unwrap();
    let o = vanefit(&["batch", "m.toml", "--out", "r"], p);
    assert!(o.status.success(), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(!stdout.contains("catalogue only"), "{}", text(&o));
    let log = read(&p.join("r/page/fit/fit.log"));
    assert!(
        log.starts_with("catalogue only: what it pins down"),
        "{log}"
    );
    assert!(log.lines().count() > 2, "{log}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    let pointers: Vec<&str> = stderr.lines().filter(|l| l.contains("fit.log")).collect();
    assert_eq!(pointers.len(), 1, "{stderr}");
    assert!(pointers[0].contains("page/fit: catalogue only"), "{stderr}");
}
