//! Catalogue → fit → predict: a catalogue page made by `synth --catalogue` at
//! 6.3 bar(g) is fitted alone and `predict` at 3–7 bar(g) is compared with the generator's
//! own catalogue rows (the truth's prediction) — within 2 % per figure and 0.02 per
//! correction factor for the default motor — and, for a motor whose parameters are not the
//! defaults the catalogue fit keeps fixed, within the error those fixed defaults leave.

use std::path::Path;
use std::process::Command;

/// Runs the built binary (in the package root, where cargo runs its tests); its stdout.
pub(crate) fn vanefit(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "vanefit {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// A CSV as rows of (column → value).
fn table(path: &Path) -> Vec<std::collections::BTreeMap<String, f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .filter_map(|(h, v)| v.parse().ok().map(|v| (h.to_string(), v)))
                .collect()
        })
        .collect()
}

const ROW: [&str; 7] = [
    "free_speed_rpm",
    "max_power_w",
    "speed_at_max_power_rpm",
    "torque_at_max_power_nm",
    "stall_torque_nm",
    "air_at_max_power_l_s_anr",
    "air_at_free_speed_l_s_anr",
];

/// Synth → fit → predict for the motor of `params` (default motor if `None`); returns the
/// largest relative row error and the largest factor error against the truth's prediction.
fn round_trip(dir: &Path, params: Option<&Path>) -> (f64, f64) {
    let ds = dir.join("catalogue");
    let ds_s = ds.to_str().unwrap();
    let mut synth = vec!["synth", ds_s, "--catalogue"];
    if let Some(p) = params {
        synth.extend(["--params", p.to_str().unwrap()]);
    }
    vanefit(&synth);
    let fit = dir.join("fit.json");
    let out = vanefit(&[
        "fit",
        ds_s,
        "--starts",
        "16",
        "--out",
        fit.to_str().unwrap(),
        "--no-plots",
    ]);
    assert!(out.contains("catalogue only"), "{out}");
    let pred = |file: &Path, dir: &Path| {
        vanefit(&[
            "predict",
            file.to_str().unwrap(),
            "--bands",
            "delta",
            "--pressures",
            "3,4,5,6,7",
            "--unit",
            "bar_g",
            "--out",
            dir.to_str().unwrap(),
        ]);
    };
    pred(&fit, &dir.join("fitted"));
    pred(&ds.join("truth.json"), &dir.join("truth"));
    let (mut row_err, mut factor_err) = (0.0f64, 0.0f64);
    let (a, b) = (
        table(&dir.join("fitted/catalogue.csv")),
        table(&dir.join("truth/catalogue.csv")),
    );
    assert_eq!(a.len(), 5);
    for (x, y) in a.iter().zip(&b) {
        for c in ROW {
            row_err = row_err.max((x[c] / y[c] - 1.0).abs());
        }
    }
    let (a, b) = (
        table(&dir.join("fitted/factors.csv")),
        table(&dir.join("truth/factors.csv")),
    );
    for (x, y) in a.iter().zip(&b) {
        for c in ["power", "speed", "torque", "air"] {
            factor_err = factor_err.max((x[c] - y[c]).abs());
        }
    }
    (row_err, factor_err)
}

#[test]
fn a_catalogue_at_one_pressure_predicts_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let (rows, factors) = round_trip(dir.path(), None);
    println!(
        "default motor: rows within {:.3} %, factors within {factors:.4}",
        100.0 * rows
    );
    assert!(rows < 0.02, "{rows}");
    assert!(factors < 0.02, "{factors}");
}

#[test]
fn fixed_defaults_that_are_not_the_truth_leave_a_stated_error() {
    // A motor off the defaults by 0.8–1.3× in every parameter the catalogue fit may keep
    // fixed: the prediction can be no better than those defaults allow.
    let dir = tempfile::tempdir().unwrap();
    let truth = dir.path().join("motor.json");
    let mut doc = serde_json::json!({
        "format": "vanefit.fit/1", "dataset": "off-default", "model": { "effects": [] },
        "parameters": {}
    });
    let defaults = vanefit::model::MotorParams::default();
    for (name, f) in [
        ("c_in1", 0.9),
        ("c_out2", 1.15),
        ("c_ext", 0.85),
        ("c_1e", 1.2),
        ("c_2e", 1.3),
        ("c_12", 0.8),
        ("t_coulomb", 1.25),
        ("visc", 0.8),
    ] {
        doc["parameters"][name] = serde_json::json!({
            "value": defaults.get(name).unwrap() * f,
            "unit": vanefit::model::spec(name).unwrap().unit,
            "estimated": false, "ci95": null
        });
    }
    std::fs::write(&truth, doc.to_string()).unwrap();
    let (rows, factors) = round_trip(dir.path(), Some(&truth));
    println!(
        "off-default motor: rows within {:.3} %, factors within {factors:.4}",
        100.0 * rows
    );
    // Measured: 4.1 % (the stall torque at 3 bar(g), from t_coulomb fixed 25 % low) and
    // 0.013; the factors stay within the 0.02.
    assert!(rows < 0.05, "{rows}");
    assert!(factors < 0.02, "{factors}");
    // The fit's own bands carry what the page cannot pin through the motor prior (the
    // defaults rest on it, not fixed), and so does the override ×/÷ 1.5: every truth lies
    // in its band either way.
    let spread = dir.path().join("spread");
    let fit = dir.path().join("fit.json");
    vanefit(&[
        "predict",
        fit.to_str().unwrap(),
        "--bands",
        "delta",
        "--fixed-spread",
        "1.5",
        "--out",
        spread.to_str().unwrap(),
    ]);
    let (a, b) = (
        table(&spread.join("catalogue.csv")),
        table(&dir.path().join("truth/catalogue.csv")),
    );
    let missed = |a: &[std::collections::BTreeMap<String, f64>]| {
        a.iter()
            .zip(&b)
            .flat_map(|(x, y)| {
                ROW.map(|c| !(x[&format!("{c}_lo")] <= y[c] && y[c] <= x[&format!("{c}_hi")]))
            })
            .filter(|m| *m)
            .count()
    };
    let without = table(&dir.path().join("fitted/catalogue.csv"));
    println!(
        "truths outside their band: {} of 35 without the spread, {} with",
        missed(&without),
        missed(&a)
    );
    assert_eq!(missed(&without), 0);
    assert_eq!(missed(&a), 0);
}
