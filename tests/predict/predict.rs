//! `vanefit predict` (docs/formats.md, "Contracts added later") end to end on the shipped fit: the
//! files and their fixed columns, the physics the numbers must show, extrapolation flags, refusals
//! of bad input, and the delta-method bands checked against Monte Carlo.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use vanefit::data::{FitFile, LogCovariance};
use vanefit::predict::{check_bands, predict, BandCheck, PredictOptions};
use vanefit::units::Unit;

const P_ATM: f64 = 101_325.0;

fn shipped_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fits/ar034-synthetic.json")
}

/// The shipped fit with `conditions`: as shipped when it has them, else the supply pressures
/// of measurements/ar034-synthetic (the ramp's lowest recorded p_port1, the datasheet's
/// 0.73 MPa), as `vanefit fit` now exports them.
fn fit_with_conditions(dir: &Path) -> PathBuf {
    let mut doc: Value =
        serde_json::from_str(&std::fs::read_to_string(shipped_path()).unwrap()).unwrap();
    if doc.get("conditions").is_none_or(Value::is_null) {
        doc["conditions"] = serde_json::json!({
            "p_atm_pa": P_ATM, "p_supply_range_pa": [100_355.1, 730_000.0]
        });
    }
    let path = dir.join("fit.json");
    std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    path
}

fn vanefit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(args)
        .output()
        .unwrap()
}

/// A CSV file as its header and rows of cells.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(String::from).collect())
        .collect();
    (header, rows)
}

fn column(header: &[String], rows: &[Vec<String>], name: &str) -> Vec<String> {
    let i = header.iter().position(|h| h == name).unwrap();
    rows.iter().map(|r| r[i].clone()).collect()
}

fn numbers(cells: &[String]) -> Vec<f64> {
    cells.iter().map(|c| c.parse().unwrap()).collect()
}

#[test]
fn cli_writes_the_files_with_their_columns_and_the_physics_holds() {
    let dir = tempfile::tempdir().unwrap();
    let fit = fit_with_conditions(dir.path());
    let out = dir.path().join("p");
    let run = vanefit(&[
        "predict",
        fit.to_str().unwrap(),
        "--bands",
        "delta",
        "--pressures",
        "3,4,5,6,6.3,7,8",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(
        stdout.contains("| p_supply [bar g] |") && stdout.contains("wrote"),
        "{stdout}"
    );
    assert!(stdout.contains("EXTRAPOLATED"), "{stdout}");
    for f in [
        "catalogue.csv",
        "factors.csv",
        "curves.csv",
        "predict.md",
        "torque.svg",
        "power.svg",
        "air.svg",
        "factors.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let (h, rows) = read_csv(&out.join("catalogue.csv"));
    let fixed = [
        "p_supply_bar_g",
        "free_speed_rpm",
        "max_power_w",
        "speed_at_max_power_rpm",
        "torque_at_max_power_nm",
        "stall_torque_nm",
        "air_at_max_power_l_s_anr",
        "air_at_free_speed_l_s_anr",
    ];
    assert_eq!(h[..8], fixed.map(String::from));
    assert!(h.contains(&"max_power_w_lo".to_string()) && h.contains(&"extrapolated".into()));
    let power = numbers(&column(&h, &rows, "max_power_w"));
    assert!(power.windows(2).all(|w| w[1] > w[0]), "{power:?}");
    let flags = column(&h, &rows, "extrapolated");
    assert_eq!(
        flags,
        ["false", "false", "false", "false", "false", "true", "true"]
    );
    // The band holds the value.
    for name in &fixed[1..] {
        let (v, lo, hi) = (
            numbers(&column(&h, &rows, name)),
            numbers(&column(&h, &rows, &format!("{name}_lo"))),
            numbers(&column(&h, &rows, &format!("{name}_hi"))),
        );
        for k in 0..v.len() {
            assert!(
                lo[k] <= v[k] && v[k] <= hi[k] && lo[k] < hi[k],
                "{name} row {k}"
            );
        }
    }
    let (h, rows) = read_csv(&out.join("factors.csv"));
    assert_eq!(
        h[..5],
        ["p_supply_bar_g", "power", "speed", "torque", "air"].map(String::from)
    );
    let at_ref = &rows[4];
    assert_eq!(at_ref[0], "6.3");
    for name in ["power", "speed", "torque", "air"] {
        for suffix in ["", "_lo", "_hi"] {
            let i = h
                .iter()
                .position(|c| *c == format!("{name}{suffix}"))
                .unwrap();
            assert_eq!(at_ref[i].parse::<f64>().unwrap(), 1.0, "{name}{suffix}");
        }
    }
    let (h, rows) = read_csv(&out.join("curves.csv"));
    assert_eq!(
        h[..5],
        [
            "p_supply_bar_g",
            "speed_rpm",
            "torque_nm",
            "power_w",
            "air_l_s_anr"
        ]
        .map(String::from)
    );
    assert_eq!(rows.len(), 7 * 41);
    let md = std::fs::read_to_string(out.join("predict.md")).unwrap();
    assert!(
        md.contains("| 7 * |") && md.contains("1 rpm") && md.contains("held fixed"),
        "{md}"
    );
}

#[test]
fn an_inlet_nozzle_lowers_the_power_at_every_pressure() {
    let dir = tempfile::tempdir().unwrap();
    let fit = shipped_path();
    let power_with = |extra: &[&str], name: &str| {
        let out = dir.path().join(name);
        let mut args = vec![
            "predict",
            fit.to_str().unwrap(),
            "--bands",
            "delta",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let run = vanefit(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let (h, rows) = read_csv(&out.join("catalogue.csv"));
        numbers(&column(&h, &rows, "max_power_w"))
    };
    // A sharp-edged 2 mm orifice: C ≈ 0.8·(π/4)·(2 mm)²·1.99e-3 ≈ 5e-9 m³/(s·Pa).
    let open = power_with(&[], "open");
    let throttled = power_with(&["--inlet-nozzle", "5e-9"], "inlet");
    assert_eq!(open.len(), 5);
    for (a, b) in open.iter().zip(&throttled) {
        assert!(b < a, "{b} W with the nozzle vs {a} W without");
    }
}

#[test]
fn bad_input_is_refused_with_the_option_named_and_status_1() {
    let dir = tempfile::tempdir().unwrap();
    let fit = shipped_path();
    let fit = fit.to_str().unwrap();
    let broken = dir.path().join("broken.json");
    std::fs::write(&broken, "{ not json").unwrap();
    let out = dir.path().join("never");
    let out = out.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["missing-fit.json"], "missing-fit.json"),
        (vec![broken.to_str().unwrap()], "broken.json"),
        (vec![fit, "--pressures", "3,x,5"], "--pressures"),
        (vec![fit, "--pressures", ""], "--pressures"),
        (vec![fit, "--pressures", " , "], "--pressures"),
        (vec![fit, "--pressures", "-2"], "--pressures"),
        (
            vec![fit, "--pressures", "0", "--unit", "mpa"],
            "--pressures",
        ),
        (vec![fit, "--reference", "-5"], "--reference"),
        (
            vec![fit, "--inlet-nozzle", "5e-9", "--outlet-nozzle", "5e-9"],
            "--outlet-nozzle",
        ),
        (vec![fit, "--inlet-nozzle", "0"], "--inlet-nozzle"),
        (vec![fit, "--outlet-nozzle", "-1e-9"], "--outlet-nozzle"),
        (vec![fit, "--speed-grid-rpm", "0"], "--speed-grid-rpm"),
        (vec![fit, "--pressures", "0.1"], "does not start"),
    ];
    for (args, names) in cases {
        let mut all = vec!["predict"];
        all.extend(&args);
        all.extend(["--out", out]);
        let run = vanefit(&all);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains(names), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    // An unknown unit is bad usage, refused by the parser with the known units.
    let run = vanefit(&["predict", fit, "--unit", "psi_x", "--out", out]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--unit") && stderr.contains("bar_g"),
        "{stderr}"
    );
    assert!(!Path::new(out).exists(), "nothing is written on bad input");
}

#[test]
fn other_units_give_the_same_prediction() {
    let dir = tempfile::tempdir().unwrap();
    let fit = shipped_path();
    let run = |unit: &str, pressures: &str, reference: &str, name: &str| {
        let out = dir.path().join(name);
        let r = vanefit(&[
            "predict",
            fit.to_str().unwrap(),
            "--bands",
            "delta",
            "--unit",
            unit,
            "--pressures",
            pressures,
            "--reference",
            reference,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        read_csv(&out.join("catalogue.csv"))
    };
    let (hg, g) = run("bar_g", "4", "6", "g");
    let (ha, a) = run("mpa", "0.501325", "0.701325", "a");
    assert_eq!(ha[0], "p_supply_mpa");
    let (x, y) = (
        numbers(&column(&hg, &g, "max_power_w")),
        numbers(&column(&ha, &a, "max_power_w")),
    );
    assert!((x[0] - y[0]).abs() < 1e-6 * x[0], "{x:?} vs {y:?}");
}

#[test]
fn the_reference_row_is_the_row_at_the_reference_pressure() {
    let fit = FitFile::read(&shipped_path()).unwrap();
    let mut o = PredictOptions::new(P_ATM);
    o.pressures_pa = [5.0, 6.3].map(|p| Unit::BarG.to_si(p, P_ATM)).to_vec();
    let pr = predict(&fit, &o).unwrap();
    assert_eq!(pr.reference, pr.pressures[1].row);
    for f in pr.pressures[1].factors {
        assert_eq!((f.value, f.band95), (1.0, Some([1.0, 1.0])));
    }
    for p in &pr.pressures {
        let figures = p.figures.iter().chain(&p.factors);
        let curves = p
            .curve
            .iter()
            .flat_map(|c| [c.torque_nm, c.power_w, c.air_kg_s]);
        for b in figures.copied().chain(curves) {
            let [lo, hi] = b.band95.unwrap();
            assert!(lo <= b.value && b.value <= hi, "{b:?}");
        }
        // The curves run from standstill (stall torque) to the free speed (no torque).
        let (first, last) = (p.curve[0], p.curve[p.curve.len() - 1]);
        assert_eq!(first.torque_nm.value, p.row.stall_torque_nm);
        assert!(last.torque_nm.value.abs() < 1e-8);
        assert_eq!(last.speed_rad_s, p.row.free_speed_rad_s);
    }
}

/// The ratio of Monte-Carlo to delta-method band widths over every figure whose band has
/// a width (power at standstill and the factors at the reference pressure have none).
fn width_ratios(checks: &[BandCheck]) -> Vec<(String, f64)> {
    checks
        .iter()
        .filter(|c| c.delta[1] - c.delta[0] > 1e-9 * c.value.abs().max(1e-12))
        .map(|c| {
            let r = (c.monte_carlo[1] - c.monte_carlo[0]) / (c.delta[1] - c.delta[0]);
            (c.label.clone(), r)
        })
        .collect()
}

fn summary(name: &str, ratios: &[(String, f64)]) -> (f64, f64) {
    let mut r: Vec<f64> = ratios.iter().map(|x| x.1).collect();
    r.sort_by(f64::total_cmp);
    let (lo, hi) = (r[0], r[r.len() - 1]);
    println!(
        "{name}: {} figures, Monte-Carlo/delta band width ratio min {lo:.3}, median {:.3}, \
         max {hi:.3}",
        r.len(),
        r[r.len() / 2]
    );
    (lo, hi)
}

#[test]
fn delta_bands_agree_with_monte_carlo_on_the_shipped_fit() {
    let mut fit = FitFile::read(&shipped_path()).unwrap();
    let mut o = PredictOptions::new(P_ATM);
    o.pressures_pa = [3.0, 6.3, 8.0].map(|p| Unit::BarG.to_si(p, P_ATM)).to_vec();
    o.curve_points = 11;
    // As shipped (a covariance when the fit file has one, else independent intervals).
    let checks = check_bands(&fit, &o, 2000, 11).unwrap();
    let (lo, hi) = summary("shipped fit", &width_ratios(&checks));
    assert!(lo > 0.75 && hi < 1.25, "{lo} .. {hi}");
    // With strong correlations: the intervals' widths and a correlation of 0.6 between
    // every pair of parameters (positive definite), so that the bands depend on them.
    let sd: Vec<f64> = fit
        .estimated
        .iter()
        .map(|n| {
            let [a, b] = fit.ci95.iter().find(|(m, _)| m == n).unwrap().1;
            (b.ln() - a.ln()) / 3.92
        })
        .collect();
    let k = sd.len();
    fit.covariance = Some(LogCovariance {
        parameters: fit.estimated.clone(),
        matrix: (0..k)
            .map(|i| {
                (0..k)
                    .map(|j| sd[i] * sd[j] * if i == j { 1.0 } else { 0.6 })
                    .collect()
            })
            .collect(),
    });
    let correlated = check_bands(&fit, &o, 2000, 12).unwrap();
    let (lo, hi) = summary("correlated", &width_ratios(&correlated));
    assert!(lo > 0.75 && hi < 1.25, "{lo} .. {hi}");
    // The correlations change the bands: they are not the independent ones.
    fit.covariance = None;
    let independent = check_bands(&fit, &o, 2, 13).unwrap();
    let changed = independent
        .iter()
        .zip(&correlated)
        .filter(|(a, _)| (a.delta[1] - a.delta[0]) > 0.0)
        .map(|(a, b)| (b.delta[1] - b.delta[0]) / (a.delta[1] - a.delta[0]))
        .fold(1.0f64, |m, r| m.max(r));
    assert!(changed > 1.2, "{changed}");
}

/// A supply pressure ten times the fitted ones is not just marked `*`: predict warns loudly
/// (stderr, once per such pressure, naming it, the covered range and the sane one, a factor
/// of 2 on the absolute supply pressure), and says nothing of one inside that factor.
#[test]
fn a_pressure_far_beyond_the_fit_is_warned_about_loudly() {
    let dir = tempfile::tempdir().unwrap();
    let fit = fit_with_conditions(dir.path());
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(&fit).unwrap()).unwrap();
    let p_atm = doc["conditions"]["p_atm_pa"].as_f64().unwrap();
    let hi = doc["conditions"]["p_supply_range_pa"][1].as_f64().unwrap();
    // Just inside and far outside twice the highest absolute supply pressure, in bar g.
    let inside = ((2.0 * hi - p_atm) / 1e5 - 0.1).to_string();
    let far = "60";
    let out = dir.path().join("out");
    let run = vanefit(&[
        "predict",
        fit.to_str().unwrap(),
        "--bands",
        "delta",
        "--pressures",
        &format!("6,{inside},{far}"),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stderr = String::from_utf8_lossy(&run.stderr);
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("WARNING"))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    let limit = format!("{:.2}", (2.0 * hi - p_atm) / 1e5);
    let limit = limit.trim_end_matches('0').trim_end_matches('.');
    for needle in ["--pressures 60 bar g", "factor of 2", limit] {
        assert!(
            warnings[0].contains(needle),
            "{needle} missing: {}",
            warnings[0]
        );
    }
}
