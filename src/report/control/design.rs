//! Tables and figure of `design`: `design_step.csv`, `design_step_paper_gains.csv`,
//! `design_open_loop.csv`, `design.svg`, and `design.json` (both controllers' gains,
//! margins and step figures, for programs: the printed summary in numbers).

use super::{pairs, trace_table, ControlReportError, Table, Writer};
use crate::control::closed_loop::Trace;
use crate::control::rpm;
use crate::control::study::design::{DesignRun, DesignStudy};
use crate::report::plot::{Chart, Figure, Legend, Series};

/// The legend names of the two controllers, the same in every panel of `design.svg` (the
/// figure then gives each one colour throughout).
const DESIGNED: &str = "designed";
const PAPER: &str = "paper gains (0.85 s + 4)/s";

/// Writes the tables and the figure of `design`.
pub fn write(w: &mut Writer, r: &DesignStudy) -> Result<(), ControlReportError> {
    let (d, p) = (&r.designed, &r.paper);
    w.csv("design_step.csv", &trace_table(&d.trace))?;
    w.csv("design_step_paper_gains.csv", &trace_table(&p.trace))?;
    let mut t = Table::new(&[
        "f_hz",
        "designed_mag",
        "designed_phase_deg",
        "paper_mag",
        "paper_phase_deg",
    ]);
    for k in 0..r.f_hz.len() {
        t.push(vec![
            r.f_hz[k],
            d.open_loop[k].norm(),
            d.open_loop_phase_deg[k],
            p.open_loop[k].norm(),
            p.open_loop_phase_deg[k],
        ]);
    }
    w.csv("design_open_loop.csv", &t)?;
    w.json("design.json", &summary(r))?;
    w.figure("design.svg", &figure(r))
}

/// The printed summary of `design` in numbers: the operating point and, per controller, its
/// gains (V per speed unit, V per speed unit and second; the speed unit in rpm), margins on
/// the linear loop and figures of the simulated step. Units in the keys; a figure that does
/// not exist (no settling within the run) is `null`.
fn summary(r: &DesignStudy) -> serde_json::Value {
    let finite = |v: f64| v.is_finite().then_some(v);
    let run = |d: &DesignRun| {
        serde_json::json!({
            "kp_v_per_unit": d.pi.kp,
            "ki_v_per_unit_s": d.pi.ki,
            "speed_unit_rpm": d.pi.speed_unit_rpm,
            "crossover_rad_s": finite(d.margins.crossover_rad_s),
            "phase_margin_deg": finite(d.margins.phase_margin_deg),
            "gain_margin_db": finite(d.margins.gain_margin_db),
            "overshoot_pct": finite(d.metrics.overshoot_pct),
            "rise_time_s": finite(d.metrics.rise_time_s),
            "settling_time_s": finite(d.metrics.settling_time_s),
            "final_error_rpm": finite(rpm(d.metrics.final_error_rad_s)),
        })
    };
    serde_json::json!({
        "p_mean_pa": r.settings.p_mean_pa(),
        "speed_rpm": rpm(r.w0_rad_s),
        "step_rpm": r.settings.step_rpm(),
        "designed": run(&r.designed),
        "paper": run(&r.paper),
    })
}

/// Open-loop magnitude and phase of both controllers, and their simulated steps.
fn figure(r: &DesignStudy) -> Figure {
    let (d, p, f) = (&r.designed, &r.paper, &r.f_hz);
    let norms = |z: &[nalgebra::Complex<f64>]| z.iter().map(|z| z.norm()).collect::<Vec<_>>();
    let mag = Chart::new("Open loop |L| = |C P|", "f [Hz]", "|L|")
        .log_x()
        .log_y()
        .with(Series::line(DESIGNED, pairs(f, &norms(&d.open_loop))))
        .with(Series::line(PAPER, pairs(f, &norms(&p.open_loop))))
        .with(Series::line("1", vec![(f[0], 1.0), (f[f.len() - 1], 1.0)]));
    let ph = Chart::new("Open loop phase", "f [Hz]", "phase [deg]")
        .log_x()
        .legend(Legend::Right)
        .with(Series::line(DESIGNED, pairs(f, &d.open_loop_phase_deg)))
        .with(Series::line(PAPER, pairs(f, &p.open_loop_phase_deg)));
    let xy = |tr: &Trace, v: &[f64]| {
        tr.t_s
            .iter()
            .zip(v)
            .map(|(t, w)| (*t, rpm(*w)))
            .collect::<Vec<_>>()
    };
    let step = Chart::new(
        "Closed-loop check (nonlinear motor)",
        "t [s]",
        "speed [rpm]",
    )
    .legend(Legend::Right)
    .with(Series::line(
        "set-point",
        xy(&d.trace, &d.trace.setpoint_rad_s),
    ))
    .with(Series::line(DESIGNED, xy(&d.trace, &d.trace.speed_rad_s)))
    .with(Series::line(PAPER, xy(&p.trace, &p.trace.speed_rad_s)));
    Figure::new(vec![mag, ph, step], 2)
}
