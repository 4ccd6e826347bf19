//! Tables and figure of `design`: `design_step.csv`, `design_step_paper_gains.csv`,
//! `design_open_loop.csv`, `design.svg`.

use super::{pairs, trace_table, ControlReportError, Table, Writer};
use crate::control::closed_loop::Trace;
use crate::control::rpm;
use crate::control::study::design::DesignStudy;
use crate::report::plot::{Chart, Figure, Legend, Series};

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
    w.figure("design.svg", &figure(r))
}

/// Open-loop magnitude and phase of both controllers, and their simulated steps.
fn figure(r: &DesignStudy) -> Figure {
    let (d, p, f) = (&r.designed, &r.paper, &r.f_hz);
    let norms = |z: &[nalgebra::Complex<f64>]| z.iter().map(|z| z.norm()).collect::<Vec<_>>();
    let mag = Chart::new("Open loop |L| = |C P|", "f [Hz]", "|L|")
        .log_x()
        .log_y()
        .with(Series::line("designed", pairs(f, &norms(&d.open_loop))))
        .with(Series::line(
            "paper (0.85 s + 4)/s",
            pairs(f, &norms(&p.open_loop)),
        ))
        .with(Series::line("1", vec![(f[0], 1.0), (f[f.len() - 1], 1.0)]));
    let ph = Chart::new("Open loop phase", "f [Hz]", "phase [deg]")
        .log_x()
        .legend(Legend::Right)
        .with(Series::line("designed", pairs(f, &d.open_loop_phase_deg)))
        .with(Series::line(
            "paper (0.85 s + 4)/s",
            pairs(f, &p.open_loop_phase_deg),
        ));
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
    .with(Series::line("designed", xy(&d.trace, &d.trace.speed_rad_s)))
    .with(Series::line(
        "paper gains",
        xy(&p.trace, &p.trace.speed_rad_s),
    ));
    Figure::new(vec![mag, ph, step], 2)
}
