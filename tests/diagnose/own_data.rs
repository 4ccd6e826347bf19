//! The diagnosis on vanefit's own synthetic data: the clean dataset, concealed effects and
//! the uncatalogued torque in the normal run, every case in the full results table.

use crate::cases::*;
use vanefit::diagnose::{to_json, DiagnoseOptions};
#[test]
fn clean_dataset_has_no_mismatch_and_the_output_follows_spec() {
    let d = assert_case("clean");
    // diagnosis.json exactly in the form of (docs/formats.md, "Diagnosis"), report and
    // plots next to it.
    let dir = tempfile::tempdir().unwrap();
    vanefit::report::diagnose::write_all(&d, dir.path()).unwrap();
    let text = std::fs::read_to_string(dir.path().join("diagnosis.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(
        keys,
        [
            "format",
            "mismatch",
            "baseline",
            "locations",
            "candidates",
            "selected",
            "extended"
        ]
    );
    assert_eq!(v["format"], "vanefit.diagnosis/1");
    assert_eq!(v["mismatch"], false);
    assert_eq!(v["selected"].as_array().unwrap().len(), 0);
    assert_eq!(v["baseline"], v["extended"]);
    for k in ["cost", "noise_ratio"] {
        assert!(v["baseline"][k].as_f64().unwrap() > 0.0);
    }
    let candidates = v["candidates"].as_array().unwrap();
    assert_eq!(candidates.len(), 7, "{candidates:?}");
    for c in candidates {
        let o = c.as_object().unwrap();
        assert_eq!(
            o.keys().collect::<Vec<_>>(),
            ["effect", "cost", "delta_bic"]
        );
        assert!(o["delta_bic"].as_f64().unwrap() > -10.0);
    }
    assert!(!candidates.iter().any(|c| c["effect"] == "valve_dynamics"));
    assert_eq!(to_json(&d), v);
    let report = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(report.contains("valve_dynamics"), "{report}");
    // Read without the source. Every parameter id with its meaning, conductances
    // also in the catalogues' dm3/(s*bar), and what cost J and the noise ratio are.
    for needle in [
        "`c_1e` (leak, inlet side → exhaust)",
        "`t_coulomb` (Coulomb friction torque)",
        "dm3/(s*bar)",
        "cost J = sum over experiments and channels",
        "noise ratio = √(mean over channels",
    ] {
        assert!(report.contains(needle), "{needle}");
    }
    for f in [
        "ranking.svg",
        "overlay.datasheet.svg",
        "residuals.ramp.svg",
        "overlay.throttle.svg",
    ] {
        assert!(dir.path().join(f).is_file(), "{f}");
        assert!(report.contains(f), "{f}");
    }
}

#[test]
fn concealed_breakaway_friction_is_named() {
    let d = assert_case("breakaway_friction");
    // Concealed to the point that the baseline's noise ratio is within noise: only the
    // refit of the candidates shows it.
    let v = to_json(&d);
    assert_eq!(v["selected"][0]["category"], "torque_loss");
    assert_eq!(
        v["selected"][0]["parameters"]
            .as_object()
            .unwrap()
            .keys()
            .collect::<Vec<_>>(),
        ["t_static", "w_stribeck"]
    );
}

#[test]
fn concealed_dead_volume_carryover_is_named() {
    let d = assert_case("dead_volume_carryover");
    assert!(!d.locations.is_empty());
    assert_eq!(to_json(&d)["selected"][0]["category"], "inlet_flow");
}

/// In the full table; left out of the normal run to keep it short.
#[test]
#[ignore]
fn concealed_sensor_lag_is_named() {
    assert_case("sensor_lag");
}

#[test]
fn uncatalogued_torque_is_discovered_and_modelled() {
    let d = assert_case("uncatalogued torque");
    let v = to_json(&d);
    let s = &v["selected"][0];
    assert_eq!(s["effect"], "uncatalogued");
    assert_eq!(s["category"], "torque_loss");
    assert_eq!(s["balance"], "torque");
    assert!(s["formula"].as_str().unwrap().contains("p2*omega"), "{s}");
    // The extended model's fit file carries the term and still reads as a fit file.
    let dir = tempfile::tempdir().unwrap();
    vanefit::report::diagnose::write_all(&d, dir.path()).unwrap();
    let path = dir.path().join("extended.json");
    let file = vanefit::data::FitFile::read(&path).unwrap();
    assert_eq!(file.extra, d.extended.fitted.extra);
    // The fit file holds values only; the extended model's intervals are the diagnosis's
    // (diagnosis.json `extended.intervals`, the report's table), and the term's holds the
    // coefficient the data were made with (3e-11 N·m/(Pa·rad/s)).
    assert!(file.ci95.is_empty() && file.statistics.is_none());
    let report = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(
        report.contains("The extended model's 95 % intervals"),
        "{report}"
    );
    let intervals = v["extended"]["intervals"]
        .as_array()
        .expect("extended.intervals");
    let term = intervals
        .iter()
        .find(|i| i.get("formula").is_some())
        .expect("an interval for the discovered term");
    let (lo, hi) = (term["lo"].as_f64().unwrap(), term["hi"].as_f64().unwrap());
    assert!(lo < 3e-11 && 3e-11 < hi, "{term}");
}

/// The table for the README (every case, the command line's settings).
#[test]
#[ignore]
fn full_results_table() {
    let names = [
        "clean",
        "breakaway_friction",
        "vane_friction_speed_squared",
        "speed_dependent_leakage",
        "dead_volume_carryover",
        "incomplete_filling",
        "pressure_dependent_friction",
        "sensor_lag",
        "uncatalogued torque",
        "uncatalogued leak",
    ];
    let opts = DiagnoseOptions::full(4, 1);
    let mut md = String::from(
        "| case | detected | ΔBIC | truth | recovered | noise ratio before → after | each experiment fitted alone (limit) | wall s | ok |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut failures = Vec::new();
    for name in names {
        let (row, _) = run(name, &opts);
        let alone: Vec<String> = row
            .alone
            .iter()
            .map(|(r, l)| format!("{r:.3} ({l:.3})"))
            .collect();
        md += &format!(
            "| {} | {} | {:.1} | {} | {} | {:.3} → {:.3} | {} | {:.1} | {} |\n",
            row.name,
            row.detected,
            row.delta_bic,
            row.truth,
            row.recovered,
            row.ratios.0,
            row.ratios.1,
            alone.join(", "),
            row.wall_s,
            match &row.ok {
                Ok(()) => "yes".to_string(),
                Err(e) => format!("NO: {e}"),
            }
        );
        if let Err(e) = row.ok {
            failures.push(format!("{name}: {e}"));
        }
        eprintln!("{md}");
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/diagnosis-results.md");
    std::fs::write(&path, &md).unwrap();
    println!("{md}");
    assert!(failures.is_empty(), "{failures:?}");
}

/// Static friction 3× Coulomb with a Stribeck speed of 8 rad/s starts the motor
/// late in the ramp; breakaway friction alone explains it, its Stribeck speed estimated.
/// ω_s is weakly determined by the ramp: χ² at the truth is 7389 (7519 points), the fit
/// ends at 7322 with ω_s 10.9, an earlier fit stalled at 7344 with ω_s 1.1; within 50%.
#[test]
fn stiction_is_breakaway_friction_with_its_stribeck_speed() {
    let d = assert_rig_case("stiction");
    assert_eq!(d.selected[0].category.id(), "torque_loss");
}

/// A leak V1 -> Ve growing with (p1 - pe)² is found as that leak path, in words
/// (the normal run has the twin-data version of this case).
#[test]
#[ignore]
fn quadratic_internal_leak_is_a_leak_path() {
    let d = assert_rig_case("dp2 leak v1-ve");
    let v = to_json(&d);
    let s = &v["selected"][0];
    assert_eq!(s["effect"], "uncatalogued");
    assert_eq!(s["category"], "internal_leakage");
    assert_eq!(s["balance"], "leak_path");
    assert_eq!(
        (s["from"].as_str(), s["to"].as_str()),
        (Some("v1"), Some("ve"))
    );
    let words = s["description"].as_str().unwrap();
    assert!(
        words.contains("square of the pressure difference"),
        "{words}"
    );
    // The extended fit file carries the path and reads back.
    let dir = tempfile::tempdir().unwrap();
    vanefit::report::diagnose::write_all(&d, dir.path()).unwrap();
    let file = vanefit::data::FitFile::read(&dir.path().join("extended.json")).unwrap();
    assert_eq!(file.extra, d.extended.fitted.extra);
}

/// Speed-dependent leakage with ω² vane friction is found as the pair (the pair is
/// tried because a discovered torque-loss term stands in for the ω² friction).
#[test]
fn leakage_and_vane_friction_are_found_as_a_pair() {
    assert_rig_case("leakage+vane pair");
}
