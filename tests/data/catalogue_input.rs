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
    refused(rig7, &[], &["needs its supply pressure"]);
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
