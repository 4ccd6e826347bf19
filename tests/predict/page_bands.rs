//! Bands no wider than the page allows: at the page's own supply pressure, the band of a
//! figure the page prints is about the page's reading tolerance. The page says each figure
//! to `tolerance` (1σ, a share of its channel's full scale: the largest figure of that
//! quantity it prints; vanefit's default 2 %), so one reading alone pins a figure y to
//! ±1.96·tolerance·full scale/y, and a fit to all of the page's figures and curves can only
//! pin it better. The speed and torque at max power are left out: the power curve is flat
//! at its peak, so the page pins where it peaks more loosely than its height
//! (docs/validation.md, "Bands as wide as the data allow").

use crate::catalogue_predict::vanefit;
use std::collections::BTreeMap;

/// The shipped catalogue page (measurements/ar034-synthetic-catalogue, 6.3 bar g): its
/// printed figures in predict's columns, with the full scale each is read against.
const PRINTED: [(&str, f64, f64); 5] = [
    ("free_speed_rpm", 12200.0, 12200.0),
    ("max_power_w", 97.9, 97.9),
    ("stall_torque_nm", 0.294, 0.294),
    ("air_at_max_power_l_s_anr", 3.87, 4.78),
    ("air_at_free_speed_l_s_anr", 4.78, 4.78),
];

/// The page's reading tolerance (1σ of full scale): vanefit's default, as the page states none.
const TOLERANCE: f64 = 0.02;

#[test]
fn a_printed_figure_s_band_at_the_page_s_pressure_is_about_its_reading_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let fit = dir.path().join("fit.json");
    let out = dir.path().join("predict");
    vanefit(&[
        "fit",
        "measurements/ar034-synthetic-catalogue",
        "--out",
        fit.to_str().unwrap(),
        "--no-plots",
    ]);
    vanefit(&[
        "predict",
        fit.to_str().unwrap(),
        "--bands",
        "delta",
        "--pressures",
        "6.3",
        "--unit",
        "bar_g",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(out.join("catalogue.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let row: BTreeMap<&str, f64> = header
        .iter()
        .zip(lines.next().unwrap().split(','))
        .filter_map(|(h, v)| v.parse().ok().map(|v| (*h, v)))
        .collect();
    for (col, printed, full_scale) in PRINTED {
        let y = row[col];
        assert!((y / printed - 1.0).abs() < 0.02, "{col}: {y} vs {printed}");
        let half = 0.5 * (row[&*format!("{col}_hi")] - row[&*format!("{col}_lo")]) / y;
        let reading = 1.96 * TOLERANCE * full_scale / printed;
        println!(
            "{col}: band ±{:.1} %, one reading ±{:.1} %",
            100.0 * half,
            100.0 * reading
        );
        assert!(
            half <= reading,
            "{col}: band ±{:.1} % is wider than one reading of the page (±{:.1} %)",
            100.0 * half,
            100.0 * reading
        );
    }
}
