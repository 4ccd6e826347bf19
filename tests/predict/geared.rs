//! Geared motors (docs/formats.md, "Geared motors"): the shipped catalogue page converted by
//! hand to a gearbox's output shaft (speeds ÷ G, torques × η·G, powers × η, air as printed:
//! the closed form, computed here and not by vanefit) must fit to the same motor-shaft
//! parameters as the page itself, and `predict` must print the output shaft's figures; a
//! gearbox of ratio 1 and efficiency 1 changes nothing; an efficiency the page does not
//! print widens the bands; bad gearbox keys exit 1 naming the key.

use super::catalogue_predict::vanefit;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const SHIPPED: &str = "measurements/ar034-synthetic-catalogue";

/// The factor by which a gearbox (G, η) multiplies a figure of quantity `key` (a rig.toml
/// figure key or a curve column name).
fn factor(key: &str, g: f64, eta: f64) -> f64 {
    if key.starts_with("air") {
        1.0
    } else if key.contains("speed") {
        1.0 / g
    } else if key.contains("torque") {
        eta * g
    } else if key.contains("power") {
        eta
    } else {
        1.0
    }
}

/// The shipped page as a geared motor's page: every figure and curve cell at the output
/// shaft of a gearbox (G, η), `gear_ratio` (and `gear_efficiency` when `printed`) under
/// `[motor]`.
fn geared_page(dir: &Path, g: f64, eta: f64, printed: bool) -> PathBuf {
    let out = dir.join(format!("geared-{g}-{eta}-{printed}"));
    std::fs::create_dir_all(&out).unwrap();
    let curves = std::fs::read_to_string(Path::new(SHIPPED).join("curves-6.3bar.csv")).unwrap();
    let mut lines = curves.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut text = header.join(",") + "\n";
    for l in lines {
        let cells: Vec<String> = l
            .split(',')
            .zip(&header)
            .map(|(c, h)| match c.parse::<f64>() {
                Ok(v) => format!("{:e}", v * factor(h, g, eta)),
                Err(_) => c.to_string(),
            })
            .collect();
        text.push_str(&(cells.join(",") + "\n"));
    }
    std::fs::write(out.join("curves-6.3bar.csv"), text).unwrap();
    let rig = std::fs::read_to_string(Path::new(SHIPPED).join("rig.toml")).unwrap();
    let mut converted = String::new();
    let mut in_figures = false;
    for line in rig.lines() {
        if line.starts_with('[') {
            in_figures = line == "[experiment.figures]";
        }
        let figure = line.split_once(" = \"").filter(|_| in_figures);
        match figure {
            Some((key, rest)) => {
                let (number, unit) = rest.trim_end_matches('"').split_once(' ').unwrap();
                let v: f64 = number.parse().unwrap();
                converted.push_str(&format!(
                    "{key} = \"{:e} {unit}\"\n",
                    v * factor(key, g, eta)
                ));
            }
            None => {
                converted.push_str(line);
                converted.push('\n');
            }
        }
        if line == "[motor]" {
            converted.push_str(&format!("gear_ratio = {g:?}\n"));
            if printed {
                converted.push_str(&format!("gear_efficiency = {eta:?}\n"));
            }
        }
    }
    std::fs::write(out.join("rig.toml"), converted).unwrap();
    out
}

/// Fits `ds` into `<dir>/<name>.json`; the fit file as JSON.
fn fit(ds: &Path, dir: &Path, name: &str) -> (PathBuf, serde_json::Value) {
    let file = dir.join(format!("{name}.json"));
    vanefit(&[
        "fit",
        ds.to_str().unwrap(),
        "--no-plots",
        "--out",
        file.to_str().unwrap(),
    ]);
    let doc = serde_json::from_str(&std::fs::read_to_string(&file).unwrap()).unwrap();
    (file, doc)
}

/// The estimated parameters of a fit file: name → (value, ci95).
fn estimates(doc: &serde_json::Value) -> BTreeMap<String, (f64, Option<[f64; 2]>)> {
    doc["parameters"]
        .as_object()
        .unwrap()
        .iter()
        .filter(|(_, e)| e["estimated"] == true)
        .map(|(n, e)| {
            let ci = serde_json::from_value(e["ci95"].clone()).ok();
            (n.clone(), (e["value"].as_f64().unwrap(), ci))
        })
        .collect()
}

/// `predict` at 5 and 6.3 bar g into `<dir>/<name>`; stdout and the catalogue's rows.
fn predict(fit: &Path, dir: &Path, name: &str) -> (String, Vec<BTreeMap<String, String>>) {
    let out = dir.join(name);
    let stdout = vanefit(&[
        "predict",
        fit.to_str().unwrap(),
        "--bands",
        "delta",
        "--pressures",
        "5,6.3",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(out.join("catalogue.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect();
    (stdout, rows)
}

fn num(row: &BTreeMap<String, String>, key: &str) -> f64 {
    row[key].parse().unwrap()
}

#[test]
fn a_geared_page_fits_the_motor_and_predicts_its_output_shaft() {
    let dir = tempfile::tempdir().unwrap();
    let (g, eta) = (4.0, 0.9);
    let (plain_file, plain) = fit(Path::new(SHIPPED), dir.path(), "plain");
    let geared_ds = geared_page(dir.path(), g, eta, true);
    let (geared_file, geared) = fit(&geared_ds, dir.path(), "geared");
    let (a, b) = (estimates(&plain), estimates(&geared));
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (name, (v, _)) in &a {
        let w = b[name].0;
        assert!(
            (w / v - 1.0).abs() < 1e-6,
            "{name}: {v:e} ungeared, {w:e} from the geared page"
        );
    }
    assert_eq!(geared["gear"]["ratio"], 4.0);
    assert_eq!(geared["gear"]["efficiency"], 0.9);
    assert!(
        plain.get("gear").is_none(),
        "an ungeared fit file has no gear"
    );

    let (plain_out, plain_rows) = predict(&plain_file, dir.path(), "p-plain");
    let (geared_out, geared_rows) = predict(&geared_file, dir.path(), "p-geared");
    assert!(geared_out.contains("OUTPUT shaft"), "{geared_out}");
    assert!(!plain_out.contains("shaft,"), "{plain_out}");
    for (p, q) in plain_rows.iter().zip(&geared_rows) {
        assert_eq!(q["shaft"], "output");
        assert_eq!(num(q, "gear_ratio"), g);
        assert!(!p.contains_key("shaft"));
        // The motor shaft's figures, converted to the output by the closed form.
        for (key, tol) in [
            ("free_speed_rpm", 1e-6),
            ("stall_torque_nm", 1e-6),
            ("air_at_free_speed_l_s_anr", 1e-6),
            // At max power, the grids differ: 1 rpm at the motor shaft against 1 rpm at
            // the output (G rpm at the motor), so power is flat to ~(G·Δ/ω)², speed
            // within G/2 rpm of the optimum.
            ("max_power_w", 1e-4),
            ("speed_at_max_power_rpm", 2.0 * g / 1400.0),
            ("torque_at_max_power_nm", 2.0 * g / 5800.0),
        ] {
            let want = num(p, key) * factor(key, g, eta);
            let got = num(q, key);
            assert!(
                (got / want - 1.0).abs() < tol,
                "{key} at {}: {got} at the output, want {want}",
                p["p_supply_bar_g"]
            );
        }
    }
}

#[test]
fn a_gearbox_of_ratio_one_and_efficiency_one_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (plain_file, plain) = fit(Path::new(SHIPPED), dir.path(), "plain");
    let unity = geared_page(dir.path(), 1.0, 1.0, true);
    let (unity_file, geared) = fit(&unity, dir.path(), "unity");
    assert_eq!(estimates(&plain), estimates(&geared));
    let (_, a) = predict(&plain_file, dir.path(), "p-plain");
    let (_, b) = predict(&unity_file, dir.path(), "p-unity");
    for (p, q) in a.iter().zip(&b) {
        for (k, v) in p {
            assert_eq!(&q[k], v, "{k}");
        }
    }
}

#[test]
fn an_unprinted_efficiency_rests_on_its_prior_and_widens_the_bands() {
    let dir = tempfile::tempdir().unwrap();
    // One stage: the prior's median is 0.95; the page is made with it.
    let (g, eta) = (4.0, 0.95);
    let (plain_file, plain) = fit(Path::new(SHIPPED), dir.path(), "plain");
    let (printed_file, _) = fit(
        &geared_page(dir.path(), g, eta, true),
        dir.path(),
        "printed",
    );
    let (prior_file, prior) = fit(&geared_page(dir.path(), g, eta, false), dir.path(), "prior");
    assert_eq!(prior["gear"]["efficiency_printed"], false);
    assert_eq!(prior["gear"]["efficiency"], 0.95);
    let nuisances = &prior["statistics"]["nuisances"];
    assert!(
        nuisances
            .as_object()
            .unwrap()
            .keys()
            .any(|k| k.contains("gearbox")),
        "{nuisances}"
    );
    // Each motor-shaft estimate within the ungeared fit's own interval.
    let a = estimates(&plain);
    for (name, (v, _)) in estimates(&prior) {
        if let (_, Some([lo, hi])) = a[&name] {
            assert!(
                lo <= v && v <= hi,
                "{name} = {v:e} outside [{lo:e}, {hi:e}]"
            );
        }
    }
    let (_, printed_rows) = predict(&printed_file, dir.path(), "p-printed");
    let (_, prior_rows) = predict(&prior_file, dir.path(), "p-prior");
    let _ = predict(&plain_file, dir.path(), "p-plain");
    let width = |r: &BTreeMap<String, String>, k: &str| {
        (num(r, &format!("{k}_hi")) - num(r, &format!("{k}_lo"))) / num(r, k)
    };
    for (p, q) in printed_rows.iter().zip(&prior_rows) {
        for k in ["stall_torque_nm", "max_power_w"] {
            assert!(
                width(q, k) > width(p, k),
                "{k} at {}: band {:.4} with the prior, {:.4} printed",
                p["p_supply_bar_g"],
                width(q, k),
                width(p, k)
            );
        }
    }
}

/// `vanefit check` of the shipped page with `motor_lines` added under `[motor]`: exit
/// status and stderr.
fn check_with(dir: &Path, motor_lines: &str) -> (Option<i32>, String) {
    let ds = dir.join("bad");
    std::fs::create_dir_all(&ds).unwrap();
    std::fs::copy(
        Path::new(SHIPPED).join("curves-6.3bar.csv"),
        ds.join("curves-6.3bar.csv"),
    )
    .unwrap();
    let rig = std::fs::read_to_string(Path::new(SHIPPED).join("rig.toml")).unwrap();
    let rig = rig.replace("[motor]\n", &format!("[motor]\n{motor_lines}"));
    std::fs::write(ds.join("rig.toml"), rig).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(["check", ds.to_str().unwrap()])
        .output()
        .unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_gearbox_keys_exit_1_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    for (lines, key) in [
        ("gear_ratio = 0.0\n", "gear_ratio"),
        ("gear_ratio = -4.0\n", "gear_ratio"),
        ("gear_ratio = nan\n", "gear_ratio"),
        ("gear_ratio = inf\n", "gear_ratio"),
        (
            "gear_ratio = 4.0\ngear_efficiency = 0.0\n",
            "gear_efficiency",
        ),
        (
            "gear_ratio = 4.0\ngear_efficiency = 1.2\n",
            "gear_efficiency",
        ),
        (
            "gear_ratio = 4.0\ngear_efficiency = nan\n",
            "gear_efficiency",
        ),
        ("gear_efficiency = 0.9\n", "gear_efficiency"),
    ] {
        let (code, stderr) = check_with(dir.path(), lines);
        assert_eq!(code, Some(1), "{lines}: {stderr}");
        assert!(stderr.contains(key), "{lines}: {stderr}");
        // Located at the key's line of rig.toml (the line after [motor]).
        let line = if key == "gear_efficiency" && lines.starts_with("gear_ratio") {
            6
        } else {
            5
        };
        assert!(
            stderr.contains(&format!("rig.toml:{line}")),
            "{lines}: {stderr}"
        );
    }
    let (code, stderr) = check_with(dir.path(), "gear_ratio = 3.5\ngear_efficiency = 0.92\n");
    assert_eq!(code, Some(0), "{stderr}");
}

#[test]
fn a_rig_recording_with_a_gearbox_is_refused_at_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let ds = dir.path().join("rig");
    let from = Path::new("measurements/ar034-synthetic");
    std::fs::create_dir_all(&ds).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), ds.join(e.file_name())).unwrap();
    }
    let rig = std::fs::read_to_string(ds.join("rig.toml")).unwrap();
    std::fs::write(
        ds.join("rig.toml"),
        rig.replace("[motor]\n", "[motor]\ngear_ratio = 4.0\n"),
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(["check", ds.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("gear_ratio") && stderr.contains("motor shaft"),
        "{stderr}"
    );
}
