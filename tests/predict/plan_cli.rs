//! `vanefit plan` on the shipped rig fit: its bands now are `predict`'s, a measurement of a
//! figure itself shrinks that figure's band as two independent normal estimates combine,
//! the ranking is by V per hour, and bad options are refused naming them.

use crate::common::{stderr, vanefit};
use serde_json::Value;
use std::path::Path;

const FIT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/fits/ar034-synthetic.json");
const Z95: f64 = 1.959_963_984_540_054;

/// The shipped fit without its profile intervals, written into `dir`: its bands then rest
/// on the curvature alone, whose update has the closed forms below.
fn curvature_fit(dir: &Path) -> String {
    let mut f: Value = serde_json::from_str(&std::fs::read_to_string(FIT).unwrap()).unwrap();
    for (_, p) in f["parameters"].as_object_mut().unwrap() {
        if let Some(ci) = p.get_mut("ci95") {
            *ci = Value::Null;
        }
    }
    let path = dir.join("curvature.json");
    std::fs::write(&path, serde_json::to_string(&f).unwrap()).unwrap();
    path.to_str().unwrap().to_string()
}

fn plan_json(dir: &Path, fit: &str) -> Value {
    let out = dir.join("plan");
    let o = vanefit(&[
        "plan",
        fit,
        "--pressures",
        "3,4,5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("plan.md").exists());
    serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap()
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

/// Column `name` of the CSV `text` at data row `row`.
fn cell(text: &str, row: usize, name: &str) -> f64 {
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let j = head.iter().position(|h| *h == name).unwrap();
    lines
        .nth(row)
        .unwrap()
        .split(',')
        .nth(j)
        .unwrap()
        .parse()
        .unwrap()
}

#[test]
fn bands_now_are_predicts_and_a_direct_measurement_combines_as_independent_estimates() {
    let tmp = tempfile::tempdir().unwrap();
    let fit = curvature_fit(tmp.path());
    let p = plan_json(tmp.path(), &fit);
    let pred = tmp.path().join("pred");
    let o = vanefit(&[
        "predict",
        &fit,
        "--pressures",
        "3,4,5",
        "--bands",
        "delta",
        "--out",
        pred.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cat = std::fs::read_to_string(pred.join("catalogue.csv")).unwrap();
    let targets = p["targets"].as_array().unwrap();
    // Stall torque at 4 bar g (the second pressure): predict's band, to rounding.
    let t = targets
        .iter()
        .find(|t| t["figure"] == "stall_torque" && (num(&t["p_supply_pa"]) - 501_325.0).abs() < 1.0)
        .unwrap();
    let i = targets.iter().position(|x| x == t).unwrap();
    let [lo, hi] = [num(&t["band95_before"][0]), num(&t["band95_before"][1])];
    for (v, col) in [(lo, "stall_torque_nm_lo"), (hi, "stall_torque_nm_hi")] {
        let want = cell(&cat, 1, col);
        assert!(
            (v / want - 1.0).abs() < 1e-3,
            "{col}: {v} vs predict's {want}"
        );
    }
    // The stall-torque measurement there: Var after = 1/(1/Var before + 1/σ²), the band
    // log-normal about the value (half-width 1.96·σ_y/y in ln y).
    let c = p["ranked"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["kind"] == "stall_torque" && (num(&c["p_supply_pa"]) - 501_325.0).abs() < 1.0)
        .unwrap();
    let y = num(&t["value_si"]);
    let sd_before = y * (hi / y).ln() / Z95;
    let sigma = num(&c["sigma_si"][0]);
    let sd_after = (1.0 / (1.0 / sd_before.powi(2) + 1.0 / sigma.powi(2))).sqrt();
    let promised = num(&c["shrinkage"][i]);
    assert!(
        (promised - (1.0 - sd_after / sd_before)).abs() < 1e-6,
        "{promised} vs {}",
        1.0 - sd_after / sd_before
    );
    // Ranked by V per hour, V = variance removed per cost; shrinkages are shares.
    let ranked = p["ranked"].as_array().unwrap();
    let keys: Vec<f64> = ranked.iter().map(|c| num(&c["v_per_hour"])).collect();
    assert!(keys.windows(2).all(|w| w[0] >= w[1]), "{keys:?}");
    for c in ranked {
        assert!((num(&c["v_per_hour"]) - num(&c["v_reduction"]) / num(&c["cost_h"])).abs() < 1e-12);
        assert!(num(&c["d_gain_nats"]) >= 0.0);
        assert!(c["shrinkage"]
            .as_array()
            .unwrap()
            .iter()
            .all(|s| (0.0..=1.0).contains(&num(s))));
    }
}

/// On the shipped catalogue page's fit (profile intervals wider than the curvature's,
/// `b_crit` open and held by the covariance), every band `plan` shows now is `predict`'s
/// delta band at the same pressure: each end over the value, which is free of units, to the
/// CSV's seven digits. (Before plan took predict's stretched covariance, its bands stood on
/// S·R·S: at 3 bar g the maximum power's was [27.4, 41.8] W against predict's [26.5, 43.2] W.)
#[test]
fn bands_now_are_predicts_on_a_catalogue_fit_with_wide_profiles() {
    let tmp = tempfile::tempdir().unwrap();
    let fit = tmp.path().join("page.json");
    let fit = fit.to_str().unwrap();
    let page = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/measurements/ar034-synthetic-catalogue"
    );
    let o = vanefit(&["fit", page, "--out", fit, "--no-plots"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let p = plan_json(tmp.path(), fit);
    let pred = tmp.path().join("pred");
    let args = ["--pressures", "3,4,5", "--bands", "delta", "--out"];
    let mut all = vec!["predict", fit];
    all.extend(args);
    all.push(pred.to_str().unwrap());
    let o = vanefit(&all);
    assert!(o.status.success(), "{}", stderr(&o));
    let cat = std::fs::read_to_string(pred.join("catalogue.csv")).unwrap();
    let columns = [
        ("max_power", "max_power_w"),
        ("free_speed", "free_speed_rpm"),
        ("stall_torque", "stall_torque_nm"),
        ("air_at_max_power", "air_at_max_power_l_s_anr"),
    ];
    let targets = p["targets"].as_array().unwrap();
    assert_eq!(targets.len(), 12);
    for t in targets {
        let row = [401_325.0, 501_325.0, 601_325.0]
            .iter()
            .position(|q| (num(&t["p_supply_pa"]) - q).abs() < 1.0)
            .unwrap();
        let (_, col) = columns.iter().find(|(f, _)| t["figure"] == *f).unwrap();
        let y = num(&t["value_si"]);
        let y_pred = cell(&cat, row, col);
        for (end, side) in [(0, "lo"), (1, "hi")] {
            let mine = num(&t["band95_before"][end]) / y;
            let theirs = cell(&cat, row, &format!("{col}_{side}")) / y_pred;
            assert!(
                (mine / theirs - 1.0).abs() < 2e-6,
                "{col}_{side} at row {row}: plan {mine} vs predict {theirs} (of the value)"
            );
        }
    }
}

#[test]
fn bad_options_are_refused_naming_them() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("bad");
    for (args, flag) in [
        (vec!["--pressures", "3,x"], "--pressures"),
        (vec!["--pressures", "-2"], "--pressures"),
        (vec!["--pressures", "3", "--speeds", "-5"], "--speeds"),
        (
            vec!["--pressures", "3", "--costs", "datasheet=0"],
            "--costs",
        ),
        (vec!["--pressures", "3", "--costs", "nosuch=1"], "--costs"),
        (
            vec!["--pressures", "3", "--candidates", "nosuch"],
            "--candidates",
        ),
        (vec!["--pressures", "3", "--top", "0"], "--top"),
        (
            vec!["--pressures", "3", "--fixed-spread", "0.5"],
            "--fixed-spread",
        ),
    ] {
        let mut all = vec!["plan", FIT, "--out", out.to_str().unwrap()];
        all.extend(args.iter());
        let o = vanefit(&all);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(flag), "{args:?}: {}", stderr(&o));
    }
    assert!(!out.join("plan.md").exists());
}

/// A fit whose motor does not start at an asked pressure, and one with no uncertainty to
/// shrink: exit 1 with why, nothing written, no panic.
#[test]
fn a_motor_that_does_not_start_or_a_fit_without_bands_is_refused_with_why() {
    let tmp = tempfile::tempdir().unwrap();
    let mut f: Value = serde_json::from_str(&std::fs::read_to_string(FIT).unwrap()).unwrap();
    f["parameters"]["t_coulomb"]["value"] = Value::from(100.0);
    let stuck = tmp.path().join("stuck.json");
    std::fs::write(&stuck, serde_json::to_string(&f).unwrap()).unwrap();
    let flat = curvature_fit(tmp.path());
    let mut g: Value = serde_json::from_str(&std::fs::read_to_string(&flat).unwrap()).unwrap();
    g.as_object_mut().unwrap().remove("covariance");
    std::fs::write(&flat, serde_json::to_string(&g).unwrap()).unwrap();
    for (fit, why) in [
        (stuck.to_str().unwrap(), "does not start"),
        (flat.as_str(), "neither a covariance nor intervals"),
    ] {
        let out = tmp.path().join("out");
        let o = vanefit(&[
            "plan",
            fit,
            "--pressures",
            "3",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(
            stderr(&o).contains(why) && !stderr(&o).contains("panicked"),
            "{}",
            stderr(&o)
        );
        assert!(!out.join("plan.json").exists());
    }
}
