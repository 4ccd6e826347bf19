//! Table, summary and figure of `bode` (paper Figs. 16, 17): `bode.csv`, `bode_fit.json`,
//! `bode.svg`.

use super::{describe_load, pairs, ControlReportError, Table, Writer};
use crate::control::study::bode::BodeStudy;
use crate::control::{rpm, RAD_S_PER_RPM};
use crate::model::motor::idx;
use crate::report::plot::{Chart, Figure, Legend, Series};
use nalgebra::Complex;

/// (rad/s)/Pa → rpm/bar.
pub const RPM_PER_BAR: f64 = 1e5 / RAD_S_PER_RPM;

/// Writes the table, the fit summary and the figure of `bode`.
pub fn write(w: &mut Writer, r: &BodeStudy) -> Result<(), ControlReportError> {
    let mut t = Table::new(&[
        "f_hz",
        "motor_mag_rpm_per_bar",
        "motor_phase_deg",
        "fit_mag_rpm_per_bar",
        "fit_phase_deg",
        "valve_motor_mag_rpm_per_v",
        "valve_motor_phase_deg",
    ]);
    for k in 0..r.f_hz.len() {
        t.push(vec![
            r.f_hz[k],
            r.motor[k].norm() * RPM_PER_BAR,
            r.motor_phase_deg[k],
            r.fitted[k].norm() * RPM_PER_BAR,
            r.fitted_phase_deg[k],
            r.valve_motor[k].norm() * r.pi.speed_unit_rpm,
            r.valve_motor_phase_deg[k],
        ]);
    }
    w.csv("bode.csv", &t)?;
    w.bytes(
        "bode_fit.json",
        (serde_json::to_string_pretty(&summary(r)).expect("plain JSON") + "\n").as_bytes(),
    )?;
    w.figure("bode.svg", &figure(r))
}

/// `bode_fit.json`: operating point, poles, static gain and the two-lag fit.
fn summary(r: &BodeStudy) -> serde_json::Value {
    let op = &r.lin.op;
    let lags = r.fit.lags;
    let fit = &r.fit;
    serde_json::json!({
        "operating_point": {
            "p_supply_mpa": op.bc.p_port1_pa / 1e6,
            "speed_rpm": rpm(op.speed_rad_s()),
            "p1_mpa": op.x[idx::P1] / 1e6,
            "p2_mpa": op.x[idx::P2] / 1e6,
            "pe_mpa": op.x[idx::PE] / 1e6,
            "load": describe_load(&op.bc.load),
        },
        "poles_1_s": r.poles.iter().map(|p| [p.re, p.im]).collect::<Vec<_>>(),
        "static_gain_rpm_per_bar": r.lin.dc_gain() * RPM_PER_BAR,
        "two_lags": {
            "k_rpm_per_bar": lags.k * RPM_PER_BAR,
            "t1_s": lags.t1_s,
            "t2_s": lags.t2_s,
            "band_hz": [r.settings.f_min_hz(), r.settings.f_max_hz()],
            "rms_mag_db": fit.rms_mag_db,
            "max_mag_db": fit.max_mag_db,
            "rms_phase_deg": fit.rms_phase_deg,
            "max_phase_deg": fit.max_phase_deg,
        },
    })
}

/// Magnitudes scaled.
fn mags(z: &[Complex<f64>], scale: f64) -> Vec<f64> {
    z.iter().map(|z| z.norm() * scale).collect()
}

/// Motor and two-lag fit (Fig. 16), valve + motor (Fig. 17): magnitude and phase of each.
fn figure(r: &BodeStudy) -> Figure {
    let op = &r.lin.op;
    let lags = r.fit.lags;
    let f = &r.f_hz;
    let title = format!(
        "Motor {:.2} MPa, {:.0} rpm",
        op.bc.p_port1_pa / 1e6,
        rpm(op.speed_rad_s())
    );
    let mag = Chart::new(
        &format!("{title}: |speed/supply|"),
        "f [Hz]",
        "|G| [rpm/bar]",
    )
    .log_x()
    .log_y()
    .with(Series::line(
        "model",
        pairs(f, &mags(&r.motor, RPM_PER_BAR)),
    ))
    .with(Series::line(
        &format!(
            "K/((1+sT1)(1+sT2)), T1 {:.3} s, T2 {:.2} ms",
            lags.t1_s,
            lags.t2_s * 1e3
        ),
        pairs(f, &mags(&r.fitted, RPM_PER_BAR)),
    ))
    .legend(Legend::Right);
    let phase = Chart::new(&format!("{title}: phase"), "f [Hz]", "phase [deg]")
        .log_x()
        .with(Series::line("model", pairs(f, &r.motor_phase_deg)))
        .with(Series::line("two lags", pairs(f, &r.fitted_phase_deg)))
        .legend(Legend::Right);
    let pmag = Chart::new(
        "Valve + motor (open loop, Fig. 17)",
        "f [Hz]",
        "|P| [rpm/V]",
    )
    .log_x()
    .log_y()
    .with(Series::line(
        "valve + motor",
        pairs(f, &mags(&r.valve_motor, r.pi.speed_unit_rpm)),
    ))
    .legend(Legend::Right);
    let pph = Chart::new("Valve + motor: phase", "f [Hz]", "phase [deg]")
        .log_x()
        .with(Series::line(
            "valve + motor",
            pairs(f, &r.valve_motor_phase_deg),
        ))
        .legend(Legend::Right);
    Figure::new(vec![mag, phase, pmag, pph], 2)
}
