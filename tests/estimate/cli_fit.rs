//! The `fit` and `simulate` commands end to end: a short fit writes a fit file that
//! `simulate --params` reads back, a resumed run reproduces it, and bad options exit 1 with
//! the option named (bad usage: 2).

use crate::common;
use common::{stderr, vanefit, DATASET};

use std::path::Path;

#[test]
fn short_fit_exports_a_fit_that_simulate_reads_back_and_resume_reproduces() {
    let dir = tempfile::tempdir().unwrap();
    let fit = dir.path().join("short.json");
    let fit_s = fit.to_str().unwrap();
    let args = [
        "fit",
        DATASET,
        "--starts",
        "3",
        "--max-iters",
        "60",
        "--uncertainty",
        "none",
        "--no-plots",
        "--out",
        fit_s,
    ];
    let o = vanefit(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&fit).unwrap();
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(doc["format"], "vanefit.fit/1");
    assert_eq!(doc["starts"]["total"], 3);
    assert!(doc["run"]["evaluations"].as_u64().unwrap() > 0);
    assert_eq!(doc["parameters"]["c_in1"]["estimated"], true);
    assert_eq!(doc["parameters"]["inertia"]["estimated"], false);
    assert!(Path::new(&dir.path().join("short.starts.jsonl")).exists());

    // Read without the source: the summary and the report name each parameter in words,
    // give conductances in m3/(s*Pa) and dm3/(s*bar), and say what cost J, chi2/dof and the
    // noise ratio are.
    let printed = String::from_utf8_lossy(&o.stdout).into_owned();
    let report = std::fs::read_to_string(dir.path().join("short.report.md")).unwrap();
    let c_in1 = doc["parameters"]["c_in1"]["value"].as_f64().unwrap();
    let dm3 = format!("{:.3}", c_in1 * 1e8);
    for text in [&printed, &report] {
        for needle in [
            "inlet port, supply → chamber 1",
            "leak, inlet side → exhaust",
            "Coulomb friction torque",
            "m3/(s*Pa)",
            "dm3/(s*bar)",
            &dm3[..4],
            "cost J = sum over experiments and channels",
            "chi2/dof = chi2/(rows − estimated parameters)",
            "noise ratio = √(mean over channels",
        ] {
            assert!(text.contains(needle), "{needle} missing from:\n{text}");
        }
    }
    assert!(
        report.contains("| `c_in1` | inlet port, supply → chamber 1 |"),
        "{report}"
    );
    // One χ² under one name: every "chi2 <number>" printed or reported is the fit file's
    // statistics.chi2, every "likelihood chi2 <number>" its likelihood_chi2.
    let stats = &doc["statistics"];
    let one = |key: &str| format!("{:.1}", stats[key].as_f64().unwrap());
    let (chi2, likelihood) = (one("chi2"), one("likelihood_chi2"));
    assert_ne!(chi2, likelihood, "the test needs two different numbers");
    for text in [&printed, &report] {
        let mut shown = 0;
        for (i, _) in text.match_indices("chi2 ") {
            let number: String = text[i + 5..]
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            if number.is_empty() {
                continue;
            }
            let want = if text[..i].ends_with("likelihood ") {
                &likelihood
            } else {
                &chi2
            };
            assert_eq!(
                &number,
                want,
                "at {:?}",
                &text[i.saturating_sub(30)..i + 12]
            );
            shown += 1;
        }
        assert!(shown >= 2, "chi2 and likelihood chi2 shown:\n{text}");
    }

    // The exported fit simulates.
    let sim_dir = dir.path().join("sim");
    let o = vanefit(&[
        "simulate",
        DATASET,
        "--params",
        fit_s,
        "--out",
        sim_dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let ramp = std::fs::read_to_string(sim_dir.join("ramp.csv")).unwrap();
    assert!(ramp.starts_with("t_s,p_port1_mpa,flow1_g_s,flow2_g_s,speed_rpm"));

    // Resuming a finished run reruns nothing and writes the same parameters.
    let o = vanefit(&[&args[..], &["--resume"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let again: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit).unwrap()).unwrap();
    assert_eq!(again["parameters"], doc["parameters"]);
    assert_eq!(again["cost"], doc["cost"]);

    // A last record torn by an interruption (a kill, a full disk) is cut off on resume, not
    // glued to: that start runs again, every line parses, each index once, same result.
    let starts = dir.path().join("short.starts.jsonl");
    let text = std::fs::read_to_string(&starts).unwrap();
    std::fs::write(&starts, &text[..text.len() - 25]).unwrap();
    let o = vanefit(&[&args[..], &["--resume"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&starts).unwrap();
    assert!(text.ends_with('\n'));
    let mut indices: Vec<u64> = text
        .lines()
        .skip(1)
        .map(|l| {
            serde_json::from_str::<serde_json::Value>(l).expect(l)["index"]
                .as_u64()
                .unwrap()
        })
        .collect();
    indices.sort_unstable();
    assert_eq!(indices, vec![0, 1, 2]);
    let torn: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit).unwrap()).unwrap();
    assert_eq!(torn["parameters"], doc["parameters"]);
}

/// A rerun leaves a clean clone clean: the fit file and its report hold no wall time and no
/// thread count (facts of the machine, printed only), so two runs of the same fit on
/// different thread counts write them byte for byte alike; a file that does carry the old
/// `run.wall_s` and `run.threads` is still read.
#[test]
fn a_fit_file_and_its_report_are_reproducible_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let run = |sub: &str, threads: &str| {
        let folder = dir.path().join(sub);
        std::fs::create_dir(&folder).unwrap();
        let fit = folder.join("short.json");
        let o = vanefit(&[
            "fit",
            DATASET,
            "--starts",
            "3",
            "--max-iters",
            "40",
            "--uncertainty",
            "none",
            "--no-plots",
            "--threads",
            threads,
            "--out",
            fit.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let printed = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(
            printed.contains(&format!(" s on {threads} thread(s)")),
            "the run's time and threads are printed:\n{printed}"
        );
        let json = std::fs::read(&fit).unwrap();
        let report = std::fs::read(folder.join("short.report.md")).unwrap();
        (fit, json, report)
    };
    let (fit, json_1, report_1) = run("one", "1");
    let (_, json_2, report_2) = run("two", "2");
    assert!(json_1 == json_2, "fit files differ between reruns");
    assert!(report_1 == report_2, "reports differ between reruns");
    let doc: serde_json::Value = serde_json::from_slice(&json_1).unwrap();
    let run_keys: Vec<&String> = doc["run"].as_object().unwrap().keys().collect();
    assert_eq!(run_keys, ["evaluations"]);
    let report = String::from_utf8(report_1).unwrap();
    assert!(!report.contains("thread"), "{report}");

    // An older file with the wall time and threads still reads.
    let mut old = doc.clone();
    old["run"]["wall_s"] = 1.38.into();
    old["run"]["threads"] = 2.into();
    std::fs::write(&fit, serde_json::to_string_pretty(&old).unwrap()).unwrap();
    let sim = dir.path().join("sim");
    let o = vanefit(&[
        "simulate",
        DATASET,
        "--params",
        fit.to_str().unwrap(),
        "--out",
        sim.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn bad_options_name_the_option_and_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.json");
    let out = out.to_str().unwrap();
    for (extra, needle) in [
        (vec!["--estimate", "c_in1,c_nope"], "c_nope"),
        (vec!["--bounds", "c_in1=1e-8:1e-9"], "c_in1"),
        (vec!["--bounds", "visc=abc"], "--bounds"),
    ] {
        let mut args = vec!["fit", DATASET, "--out", out];
        args.extend(extra);
        let o = vanefit(&args);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
    }
    // Values clap can check alone are bad usage, status 2 as the README says.
    for (extra, needle) in [
        (vec!["--starts", "0"], "--starts"),
        (vec!["--effects", "magic_friction"], "--effects"),
        (vec!["--threads", "0"], "--threads"),
    ] {
        let mut args = vec!["fit", DATASET, "--out", out];
        args.extend(extra);
        let o = vanefit(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
    }
    assert_eq!(
        vanefit(&["fit", DATASET]).status.code(),
        Some(2),
        "--out is required"
    );
    assert_eq!(vanefit(&["frobnicate"]).status.code(), Some(2));
    let o = vanefit(&["fit", "no/such/dataset", "--out", out]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no/such/dataset"));
}

#[test]
fn simulate_refuses_a_fit_file_with_an_unknown_parameter() {
    let dir = tempfile::tempdir().unwrap();
    let fit = dir.path().join("bad.json");
    std::fs::write(&fit, "{\n  \"format\": \"vanefit.fit/1\",\n  \"parameters\": {\n    \"c_inl\": {\"value\": 7e-9}\n  }\n}\n").unwrap();
    let o = vanefit(&[
        "simulate",
        DATASET,
        "--params",
        fit.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("bad.json:4") && e.contains("c_inl"), "{e}");
}

/// A copy of the shipped dataset with its datasheet only.
fn datasheet_only(dir: &Path) -> std::path::PathBuf {
    let ds = dir.join("datasheet-only");
    std::fs::create_dir_all(&ds).unwrap();
    std::fs::copy(
        Path::new(DATASET).join("datasheet.csv"),
        ds.join("datasheet.csv"),
    )
    .unwrap();
    let rig = std::fs::read_to_string(Path::new(DATASET).join("rig.toml")).unwrap();
    let head = rig
        .split("[[experiment]]\nkind = \"pressure_ramp\"")
        .next()
        .unwrap();
    std::fs::write(ds.join("rig.toml"), head).unwrap();
    ds
}

fn fit_json(dataset: &Path, out: &Path, uncertainty: &str, priors: &str) -> serde_json::Value {
    let o = vanefit(&[
        "fit",
        dataset.to_str().unwrap(),
        "--starts",
        "8",
        "--uncertainty",
        uncertainty,
        "--priors",
        priors,
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap()
}

/// 25 datasheet points cannot pin eight parameters. Without the motor prior the fit says so
/// parameter by parameter, in the file (`identifiable: false` with a reason, distinct from
/// the `null` of "not computed"), and the estimate is the same whether intervals are
/// computed or not.
#[test]
fn a_datasheet_only_fit_says_what_it_cannot_pin_and_one_estimate_is_exported() {
    let dir = tempfile::tempdir().unwrap();
    let ds = datasheet_only(dir.path());
    let with = fit_json(&ds, &dir.path().join("profile.json"), "profile", "none");
    let without = fit_json(&ds, &dir.path().join("none.json"), "none", "none");
    let names = vanefit::estimate::DEFAULT_ESTIMATED;
    let open: Vec<&str> = names
        .iter()
        .copied()
        .filter(|n| with["parameters"][n]["identifiable"] == false)
        .collect();
    assert!(open.len() >= 6, "only {open:?} flagged: {with:#}");
    for n in &open {
        let p = &with["parameters"][n];
        assert!(p["why"].as_str().is_some_and(|w| !w.is_empty()), "{p}");
        assert!(p["ci95"].is_null(), "{p}");
        assert!(p["bounds95"].is_array(), "{p}");
    }
    for n in names {
        assert!(without["parameters"][n]["identifiable"].is_null());
        assert_eq!(
            with["parameters"][n]["value"], without["parameters"][n]["value"],
            "{n}: the estimate depends on --uncertainty"
        );
    }
    assert_eq!(with["statistics"]["estimate"], "maximum_likelihood");
    assert_eq!(without["statistics"]["uncertainty"], "none");
    assert!(with["statistics"]["noise_reached"].is_boolean());
}

/// With the motor prior (the default) the same datasheet-only fit rests what the data cannot
/// pin on the prior: every interval it reports lies within the prior's own 95 % range
/// around the estimate (the data can only narrow it), and the file lists the prior.
#[test]
fn a_datasheet_only_fit_with_the_prior_is_never_less_certain_than_the_prior() {
    let dir = tempfile::tempdir().unwrap();
    let ds = datasheet_only(dir.path());
    let fit = fit_json(&ds, &dir.path().join("prior.json"), "profile", "size");
    let prior = fit["statistics"]["prior"]
        .as_array()
        .expect("statistics.prior");
    assert!(!prior.is_empty(), "{fit:#}");
    let mut bounded = 0;
    for entry in prior {
        let name = entry["parameter"].as_str().unwrap();
        let sd_ln = entry["sd_ln"].as_f64().unwrap();
        let p = &fit["parameters"][name];
        let Some(ci) = p["ci95"].as_array() else {
            continue;
        };
        let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
        // Half-width in ln v against the prior's 1.96 σ (5 % slack for the profile's grid).
        let half = 0.5 * (hi / lo).ln();
        assert!(
            half <= 1.05 * 1.96 * sd_ln,
            "{name}: ±{half} in ln v, prior ±{}",
            1.96 * sd_ln
        );
        bounded += 1;
    }
    assert!(
        bounded >= 6,
        "only {bounded} parameters with intervals: {fit:#}"
    );
}

/// A fit whose estimate is held by a bound says so: the terminal and the report name the
/// parameter and the bound, and the fit file lists it under `statistics.on_bound`. The
/// shipped dataset's Coulomb friction is 0.02 N·m; bounds that end at 0.01 N·m hold it.
#[test]
fn a_fit_held_by_a_bound_names_the_parameter_and_warns() {
    let dir = tempfile::tempdir().unwrap();
    let fit = dir.path().join("held.json");
    let o = vanefit(&[
        "fit",
        DATASET,
        "--starts",
        "3",
        "--max-iters",
        "200",
        "--uncertainty",
        "none",
        "--no-plots",
        "--bounds",
        "t_coulomb=1e-3:0.01",
        "--out",
        fit.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let printed = String::from_utf8_lossy(&o.stdout).into_owned();
    let report = std::fs::read_to_string(dir.path().join("held.report.md")).unwrap();
    for text in [&printed, &report] {
        assert!(
            text.contains("t_coulomb (Coulomb friction torque) ended on its upper bound"),
            "no bound warning in:\n{text}"
        );
        assert!(text.contains("unreliable"), "{text}");
    }
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit).unwrap()).unwrap();
    let hits = doc["statistics"]["on_bound"].as_array().expect("on_bound");
    assert_eq!(hits.len(), 1, "{hits:?}");
    assert_eq!(hits[0]["parameter"], "t_coulomb");
    assert_eq!(hits[0]["side"], "upper");
    assert!((hits[0]["bound"].as_f64().unwrap() - 0.01).abs() < 1e-12);
    // Only the held parameter: the others sit inside their ranges.
    assert!(!printed.contains("warning: c_"), "{printed}");
}
