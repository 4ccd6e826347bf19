//! Tables and figure of `min-speed`: `min_speed_steady.csv`, `min_speed_ramp.csv`,
//! `min_speed_attempts.csv`, `min_speed_controlled.csv`, `min_speed.svg`.

use super::{describe_load, trace_table, ControlReportError, Table, Writer};
use crate::control::rpm;
use crate::control::study::min_speed::MinSpeedStudy;
use crate::report::plot::{Chart, Figure, Legend, Series};

/// Writes the tables and the figure of `min-speed`.
pub fn write(w: &mut Writer, r: &MinSpeedStudy) -> Result<(), ControlReportError> {
    let mut t = Table::new(&["speed_rpm", "p_port1_mpa"]);
    for (w_, p) in &r.open.curve {
        t.push(vec![rpm(*w_), p / 1e6]);
    }
    w.csv("min_speed_steady.csv", &t)?;
    let mut t = Table::new(&["p_port1_mpa", "speed_rpm"]);
    for (p, w_) in &r.ramp {
        t.push(vec![p / 1e6, rpm(*w_)]);
    }
    w.csv("min_speed_ramp.csv", &t)?;
    let mut t = Table::new(&["setpoint_rpm", "mean_rpm", "min_rpm", "max_rpm", "held"]);
    for at in &r.controlled.attempts {
        t.push(vec![
            rpm(at.setpoint_rad_s),
            rpm(at.mean_rad_s),
            rpm(at.min_rad_s),
            rpm(at.max_rad_s),
            if at.held { 1.0 } else { 0.0 },
        ]);
    }
    w.csv("min_speed_attempts.csv", &t)?;
    w.csv(
        "min_speed_controlled.csv",
        &trace_table(&r.controlled.trace),
    )?;
    w.figure(
        "min_speed.svg",
        &Figure::new(vec![ramp_chart(r), loop_chart(r)], 2),
    )
}

/// Start-up on the pressure ramp: steady states, the simulated ramp, breakaway and jump.
fn ramp_chart(r: &MinSpeedStudy) -> Chart {
    let open = &r.open;
    let mut chart = Chart::new(
        &format!(
            "Start-up on a pressure ramp ({})",
            describe_load(&r.lp.load)
        ),
        "supply pressure [MPa abs]",
        "speed [rpm]",
    )
    .legend(Legend::Right)
    .with(Series::line(
        "steady states (p_eq)",
        open.curve.iter().map(|(w, p)| (p / 1e6, rpm(*w))).collect(),
    ))
    .with(Series::line(
        &format!("ramp {} s (simulated)", r.settings.ramp_s()),
        r.ramp.iter().map(|(p, w)| (p / 1e6, rpm(*w))).collect(),
    ));
    chart.series.push(Series::points(
        "breakaway",
        vec![(open.p_breakaway_pa / 1e6, 0.0)],
    ));
    if let Some(j) = open.jump {
        chart.series.push(Series::points(
            "jump",
            vec![
                (j.p_pa / 1e6, rpm(j.from_rad_s)),
                (j.p_pa / 1e6, rpm(j.to_rad_s)),
            ],
        ));
    }
    chart
}

/// The controlled staircase: set-point and speed against time.
fn loop_chart(r: &MinSpeedStudy) -> Chart {
    let tr = &r.controlled.trace;
    let pick = |v: &[f64]| {
        tr.t_s
            .iter()
            .zip(v)
            .map(|(t, w)| (*t, rpm(*w)))
            .collect::<Vec<_>>()
    };
    Chart::new(
        &format!(
            "Controlled: set-point lowered by {} every {} s",
            r.settings.factor(),
            r.settings.stage_s()
        ),
        "t [s]",
        "speed [rpm]",
    )
    .with(Series::line("set-point", pick(&tr.setpoint_rad_s)))
    .with(Series::line("speed", pick(&tr.speed_rad_s)))
}
