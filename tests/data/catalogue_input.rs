//! Catalogue pages in: printed units read and converted, key figures turned into
//! points of the curves, and bad catalogue input refused with its file, line and column.

use std::path::Path;
use std::process::Command;
use vanefit::data::{Dataset, Kind};
use vanefit::units::Quantity;

const RIG_HEAD: &str =
    "[motor]\nname = \"test\"\nvanes = 5\ndisplacement_m3 = 3.8e-6\nexpansion_ratio = 1.071\n\n";

/// A dataset folder with `rig` (after the motor table) and the given files.
fn dataset(rig: &str, files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("rig.toml"), format!("{RIG_HEAD}{rig}")).unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    dir
}

/// `vanefit check DIR`: (exit status, stdout, stderr).
fn check(dir: &Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .arg("check")
        .arg(dir)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

const FIGURES: &str = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"90 psi(g)\"\n\n[experiment.figures]\nfree_speed = \"12000 r/min\"\nmax_power = \"0.134 hp\"\nspeed_at_max_power = \"6000 rpm\"\ntorque_at_max_power = \"1.4 lbf·in\"\nstall_torque = \"0.23 lbf·ft\"\nmin_start_torque = \"0.2 N·m\"\nair_at_max_power = \"7.9 cfm\"\nair_at_free_speed = \"250 Nl/min\"\n";

#[test]
fn key_figures_in_printed_units_become_points_of_the_curves() {
    let dir = dataset(FIGURES, &[]);
    let ds = Dataset::load(dir.path()).unwrap();
    let ex = &ds.experiments[0];
    assert_eq!(ex.kind, Kind::Catalogue);
    // 90 psi(g) = 90·6894.757293168361 Pa + 101325 Pa.
    let p = ex.p_supply_pa.unwrap();
    assert!(
        (p - (90.0 * 6_894.757_293_168_361 + 101_325.0)).abs() < 1e-6,
        "{p}"
    );
    let rec = &ex.recording;
    // Stall, max power, free speed: three rows, speed ascending as given.
    let speed = rec.values(Quantity::Speed).unwrap();
    let rpm = std::f64::consts::PI / 30.0;
    assert_eq!(speed.len(), 3);
    assert!((speed[0]).abs() < 1e-12 && (speed[1] - 6000.0 * rpm).abs() < 1e-9);
    assert!((speed[2] - 12_000.0 * rpm).abs() < 1e-9);
    let torque = rec.values(Quantity::Torque).unwrap();
    // 0.23 lbf·ft = 0.23·1.3558179483314004 N·m at stall; 0 at free speed; the max-power
    // row compares power, not its torque (the same information twice).
    assert!((torque[0] - 0.23 * 1.355_817_948_331_400_4).abs() < 1e-12);
    assert!(torque[1].is_nan() && torque[2] == 0.0);
    let power = rec.values(Quantity::Power).unwrap();
    assert!((power[1] - 0.134 * 745.699_871_582_270_2).abs() < 1e-9);
    let air = rec.values(Quantity::Flow1).unwrap();
    // 7.9 cfm of free air (100 kPa, 20 °C); 250 Nl/min (101.325 kPa, 0 °C).
    let rho_free = 100_000.0 / (287.052_87 * 293.15);
    let rho_n = 101_325.0 / (287.052_87 * 273.15);
    assert!((air[1] - 7.9 * 0.028_316_846_592 / 60.0 * rho_free).abs() < 1e-12);
    assert!((air[2] - 250.0e-3 / 60.0 * rho_n).abs() < 1e-12);
    // The minimum start torque is read, kept, and not a row.
    assert!(ex
        .figures
        .iter()
        .any(|f| f.key == "min_start_torque" && f.si == 0.2));
    // check prints it in the file's units and in SI.
    let (code, out, err) = check(dir.path());
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("stall torque") && out.contains("lbf_ft"),
        "{out}"
    );
    assert!(out.contains("not compared"), "{out}");
    assert!(out.contains("free air (ISO 1217)"), "{out}");
}

#[test]
fn sparse_curves_and_figures_share_one_recording() {
    let curves =
        "speed_rpm,torque_nm,power_kw,air_l_s\n0,0.3,,2.0\n4000,0.21,0.088,\n8000,,0.087,4.3\n";
    let rig = "[[experiment]]\nkind = \"catalogue\"\nfile = \"p63.csv\"\np_supply = \"6.3 bar(g)\"\n\n[experiment.figures]\nfree_speed = \"12000 rpm\"\n";
    let dir = dataset(rig, &[("p63.csv", curves)]);
    let ds = Dataset::load(dir.path()).unwrap();
    let rec = &ds.experiments[0].recording;
    assert_eq!(rec.rows(), 4);
    let torque = rec.values(Quantity::Torque).unwrap();
    assert!(torque[2].is_nan() && torque[3] == 0.0);
    // The figure row is located in rig.toml.
    assert!(rec.lines[3] > 5);
    let (code, _, err) = check(dir.path());
    assert_eq!(code, 0, "{err}");
}

/// `check` refuses the dataset with exit 1 and a message containing every `needles`.
fn refused(rig: &str, files: &[(&str, &str)], needles: &[&str]) {
    let dir = dataset(rig, files);
    let (code, _, err) = check(dir.path());
    assert_eq!(code, 1, "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_catalogue_input_is_located() {
    // A power curve above torque·speed: 0.2 kW at 4000 rpm with 0.21 N·m (88 W).
    let curves = "speed_rpm,torque_nm,power_kw\n0,0.3,\n4000,0.21,0.2\n8000,0.1,0.087\n";
    let rig = "[[experiment]]\nkind = \"catalogue\"\nfile = \"c.csv\"\np_supply = \"6.3 bar_g\"\n";
    refused(
        rig,
        &[("c.csv", curves)],
        &["c.csv:3:3", "power_kw", "above torque·speed"],
    );
    // Power interpolated against the torque curve: 0.2 kW at 2000 rpm between 0.3 and 0.21 N·m.
    let curves = "speed_rpm,torque_nm,power_kw\n0,0.3,\n2000,,0.2\n4000,0.21,\n";
    refused(
        rig,
        &[("c.csv", curves)],
        &["c.csv:3:3", "above torque·speed"],
    );
    // A free speed below the speed at max power.
    let rig2 = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 bar_g\"\n[experiment.figures]\nspeed_at_max_power = \"6000 rpm\"\nmax_power = \"100 W\"\nfree_speed = \"5000 rpm\"\n";
    refused(
        rig2,
        &[],
        &["rig.toml:13:1", "free speed 5000 rpm is not above"],
    );
    // Max power inconsistent with torque·speed at max power.
    let rig3 = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 bar_g\"\n[experiment.figures]\nspeed_at_max_power = \"6000 rpm\"\nmax_power = \"200 W\"\ntorque_at_max_power = \"0.15 N·m\"\n";
    refused(
        rig3,
        &[],
        &["rig.toml:12:1", "above torque·speed at max power"],
    );
    // A unit that does not fit the quantity, in a figure and in a column name.
    let rig4 = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 bar_g\"\n[experiment.figures]\nstall_torque = \"0.3 kW\"\n";
    refused(
        rig4,
        &[],
        &["rig.toml:11:1", "'kW' is not a unit of torque", "lbf_ft"],
    );
    let curves = "speed_rpm,torque_kw\n0,0.3\n";
    refused(
        rig,
        &[("c.csv", curves)],
        &["c.csv:1:2", "unknown unit 'kw' for torque"],
    );
    // A pressure unit that is not one; a figure that is not one; a missing pressure.
    let rig5 = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 cfm\"\n[experiment.figures]\nstall_torque = \"0.3 N·m\"\n";
    refused(rig5, &[], &["rig.toml:9:1", "not a unit of pressure"]);
    let rig6 = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 bar_g\"\n[experiment.figures]\nrated_torque = \"0.3 N·m\"\n";
    refused(
        rig6,
        &[],
        &["rig.toml:11:1", "unknown key figure 'rated_torque'"],
    );
    let rig7 =
        "[[experiment]]\nkind = \"catalogue\"\n[experiment.figures]\nstall_torque = \"0.3 N·m\"\n";
    // Named at the experiment's table in rig.toml, where the key belongs.
    refused(
        rig7,
        &[],
        &[
            "rig.toml:8:1 (key 'kind')",
            "needs its supply pressure",
            "add p_supply",
        ],
    );
    // A figure that cannot be placed on a curve.
    let rig9 = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 bar_g\"\n[experiment.figures]\nstall_torque = \"0.3 N·m\"\nair_at_free_speed = \"4 l/s\"\n";
    refused(rig9, &[], &["rig.toml:12:1", "needs free_speed"]);
    // Negative values and a point without speed.
    let curves = "speed_rpm,torque_nm\n0,0.3\n,0.2\n";
    refused(rig, &[("c.csv", curves)], &["c.csv:3:1", "needs its speed"]);
    let curves = "speed_rpm,torque_nm\n0,0.3\n100,-0.2\n";
    refused(rig, &[("c.csv", curves)], &["c.csv:3:2", "must be >= 0"]);
    // Figures on a kind that is not a catalogue.
    let rig8 = "[[experiment]]\nkind = \"datasheet\"\nfile = \"c.csv\"\np_supply = \"6.3 bar_g\"\n[experiment.figures]\nstall_torque = \"0.3 N·m\"\n";
    refused(
        rig8,
        &[("c.csv", "speed_rpm,torque_nm\n0,0.3\n1,0.2\n2,0.1\n3,0.1\n")],
        &["catalogue\" only"],
    );
}

/// A true page passes the power check: torque T = 0.3 N·m·(1 − (n/10000 rpm)²) bows 50 %
/// above the straight line from stall to free speed at 5000 rpm (0.225 against 0.15 N·m),
/// so the printed power there (117.8 W) lies above the line's torque·speed (78.5 W) and
/// below the stall torque's (157 W), which bounds it (the torque falls with speed).
#[test]
fn a_curve_bowing_above_its_straight_line_is_not_refused() {
    let rig = "[[experiment]]\nkind = \"catalogue\"\nfile = \"c.csv\"\np_supply = \"6.3 bar_g\"\n";
    let curves = "speed_rpm,torque_nm,power_w\n0,0.3,\n5000,,117.8\n10000,0,\n";
    let dir = dataset(rig, &[("c.csv", curves)]);
    let (code, _, err) = check(dir.path());
    assert_eq!(code, 0, "{err}");
    // Above the bound it is refused, and the message says which torque bounds it.
    let curves = "speed_rpm,torque_nm,power_w\n0,0.3,\n5000,,170\n10000,0,\n";
    refused(
        rig,
        &[("c.csv", curves)],
        &[
            "c.csv:3:3",
            "printed at 0 rpm, which bounds it above as the torque falls",
        ],
    );
}

/// A figure of rig.toml refused by the power check is located at its key, called a key.
#[test]
fn a_figure_above_torque_speed_names_its_key() {
    let rig = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 bar_g\"\n[experiment.figures]\nstall_torque = \"0.1 N·m\"\nspeed_at_max_power = \"5000 rpm\"\nmax_power = \"100 W\"\n";
    refused(
        rig,
        &[],
        &["rig.toml:13:1 (key 'max_power')", "above torque·speed"],
    );
    // The same with a curve file beside the figures: still rig.toml, not the CSV.
    let rig = "[[experiment]]\nkind = \"catalogue\"\nfile = \"c.csv\"\np_supply = \"6.3 bar_g\"\n[experiment.figures]\nspeed_at_max_power = \"5000 rpm\"\nmax_power = \"100 W\"\n";
    refused(
        rig,
        &[("c.csv", "speed_rpm,torque_nm\n0,0.1\n")],
        &["rig.toml:13:1 (key 'max_power')", "above torque·speed"],
    );
}

/// A curve point beyond the printed free speed with a torque above zero (issue 45: the row
/// `22000,0.05,115` with free speed 20000 rpm) is refused at its cell; at or below the free
/// speed, or with a torque within reading tolerance of zero, it passes.
#[test]
fn a_curve_point_beyond_the_free_speed_is_refused_at_its_cell() {
    let rig = "[[experiment]]\nkind = \"catalogue\"\nfile = \"c.csv\"\np_supply = \"6.3 bar(g)\"\n[experiment.figures]\nfree_speed = \"20000 rpm\"\n";
    let curves = "speed_rpm,torque_nm,power_w\n0,0.3,\n10000,0.15,157\n22000,0.05,115\n";
    refused(
        rig,
        &[("c.csv", curves)],
        &[
            "c.csv:4:2 (column 'torque_nm')",
            "beyond the printed free speed 20000 rpm (rig.toml line 12)",
        ],
    );
    for ok in [
        "speed_rpm,torque_nm,power_w\n0,0.3,\n10000,0.15,157\n19000,0.05,99\n",
        "speed_rpm,torque_nm,power_w\n0,0.3,\n10000,0.15,157\n20500,0.001,2\n",
    ] {
        let dir = dataset(rig, &[("c.csv", ok)]);
        let (code, _, err) = check(dir.path());
        assert_eq!(code, 0, "{ok}: {err}");
    }
}

/// A catalogue experiment with neither a curve file nor figures says so at its table, not
/// "missing column for speed" of a file it does not have.
#[test]
fn a_page_with_neither_curves_nor_figures_says_so() {
    let rig = "[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 bar(g)\"\n";
    refused(
        rig,
        &[],
        &[
            "rig.toml:8:1 (key 'kind')",
            "neither curves nor key figures",
        ],
    );
    let dir = dataset(rig, &[]);
    let (_, _, err) = check(dir.path());
    assert!(!err.contains("missing column"), "{err}");
}

/// A duplicate key is named with its line and column, not by its first letter.
#[test]
fn a_duplicate_key_is_named() {
    let rig = format!("{FIGURES}max_power = \"0.1 kW\"\n");
    refused(
        &rig,
        &[],
        &["rig.toml:20:1 (key 'max_power')", "duplicate key"],
    );
    let dir = dataset(&rig, &[]);
    let (_, _, err) = check(dir.path());
    assert!(!err.contains("(value '"), "{err}");
}

/// `check .` names the dataset by its folder's real name; `check` prints units as people
/// write them (N·m, l/s, W), not column suffixes.
#[test]
fn check_names_the_folder_and_prints_units_as_people_write_them() {
    let curves = "speed_rpm,torque_nm,air_l_s\n0,0.3,2\n4000,0.2,3\n8000,0.1,4\n12000,0,5\n";
    let rig = "[[experiment]]\nkind = \"catalogue\"\nfile = \"c.csv\"\np_supply = \"6.3 bar(g)\"\n[experiment.figures]\nmax_power = \"0.126 kW\"\nspeed_at_max_power = \"6000 rpm\"\n";
    let dir = dataset(rig, &[("c.csv", curves)]);
    let out = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(["check", "."])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let name = dir.path().file_name().unwrap().to_string_lossy();
    assert!(text.starts_with(&format!("dataset {name} (")), "{text}");
    for shown in [
        "[N·m]",
        "[l/s]",
        "[rpm]",
        " kW ",
        "= kg/s",
        "N·m, ",
        "in l/s counts air",
    ] {
        assert!(text.contains(shown), "'{shown}' not in:\n{text}");
    }
    for suffix in ["[nm]", "[l_s]", " nm,", " kw ", " l_s ", "kg_s"] {
        assert!(!text.contains(suffix), "'{suffix}' in:\n{text}");
    }
}

/// Estimates and cost of `vanefit fit` on a dataset folder.
fn fitted(dir: &Path) -> (f64, Vec<(String, f64)>) {
    let out = dir.join("fit.json");
    let o = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(["fit", "--starts", "8", "--out"])
        .arg(&out)
        .arg(dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let fit: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let params = fit["parameters"]
        .as_object()
        .unwrap()
        .iter()
        .filter(|(_, p)| p["estimated"] == true)
        .map(|(k, p)| (k.clone(), p["value"].as_f64().unwrap()))
        .collect();
    (fit["cost"].as_f64().unwrap(), params)
}

/// A page printed in makers' spellings (U/min, min⁻¹, ft-lb, lb-ft, kgf·m, Nl/s, Nl/min,
/// psig) reads to the same SI values as the same page in SI units, and fits the same.
/// Each number is converted here by its closed form (lb = 0.45359237 kg, g_n = 9.80665
/// m/s², ft = 0.3048 m, in = 0.0254 m; ρn = 101325/(287.05287·273.15) kg/m³ of DIN 1343).
#[test]
fn a_page_in_makers_spellings_fits_like_the_page_in_si() {
    let lbf = 0.453_592_37 * 9.806_65;
    let lbf_ft = lbf * 0.3048;
    let psi = lbf / (0.0254 * 0.0254);
    let rho_n = 101_325.0 / (287.052_87 * 273.15);
    let rad_s = std::f64::consts::PI / 30.0;
    // The shipped page's figures (measurements/ar034-synthetic-catalogue), at 90 psi g.
    let (free, w_max, p_max, t_max, stall, air_max, air_free) =
        (12_200.0, 5_860.0, 97.9, 0.16, 0.294, 4.6e-3, 5.68e-3);
    let p_supply = 90.0 * psi + 101_325.0;
    let si = format!(
        "[[experiment]]\nkind = \"catalogue\"\np_supply_mpa = {}\n[experiment.figures]\nfree_speed = \"{} rad_s\"\nspeed_at_max_power = \"{} rad_s\"\nmax_power = \"{p_max} W\"\ntorque_at_max_power = \"{t_max} N·m\"\nstall_torque = \"{stall} N·m\"\nair_at_max_power = \"{air_max} kg_s\"\nair_at_free_speed = \"{air_free} kg_s\"\n",
        p_supply * 1e-6,
        free * rad_s,
        w_max * rad_s
    );
    let makers = format!(
        "[[experiment]]\nkind = \"catalogue\"\np_supply = \"90 psig\"\n[experiment.figures]\nfree_speed = \"{free} U/min\"\nspeed_at_max_power = \"{w_max} min⁻¹\"\nmax_power = \"{p_max} watts\"\ntorque_at_max_power = \"{} ft-lb\"\nstall_torque = \"{} kgf·m\"\nair_at_max_power = \"{} Nl/s\"\nair_at_free_speed = \"{} Nl/min\"\n",
        t_max / lbf_ft,
        stall / 9.806_65,
        air_max / (1e-3 * rho_n),
        air_free / (1e-3 * rho_n) * 60.0
    );
    let lb_ft = makers.replace("ft-lb", "lb-ft");
    let (a, b, c) = (
        dataset(&si, &[]),
        dataset(&makers, &[]),
        dataset(&lb_ft, &[]),
    );
    let load = |d: &tempfile::TempDir| Dataset::load(d.path()).unwrap();
    let (ds_si, ds_makers) = (load(&a), load(&b));
    let (ea, eb) = (&ds_si.experiments[0], &ds_makers.experiments[0]);
    assert!((ea.p_supply_pa.unwrap() / eb.p_supply_pa.unwrap() - 1.0).abs() < 1e-12);
    for (fa, fb) in ea.figures.iter().zip(&eb.figures) {
        assert_eq!(fa.key, fb.key);
        assert!(
            (fa.si / fb.si - 1.0).abs() < 1e-12,
            "{}: {} vs {}",
            fa.key,
            fa.si,
            fb.si
        );
    }
    let (cost_si, est_si) = fitted(a.path());
    for d in [&b, &c] {
        let (cost, est) = fitted(d.path());
        assert!(
            (cost / cost_si - 1.0).abs() < 1e-6,
            "cost {cost} vs {cost_si}"
        );
        assert_eq!(est.len(), est_si.len());
        for ((name, v), (_, v_si)) in est.iter().zip(&est_si) {
            assert!((v / v_si - 1.0).abs() < 1e-4, "{name}: {v} vs {v_si}");
        }
    }
}
