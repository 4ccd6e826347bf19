//! Tables and figures of the closed-loop studies: `step` (paper Fig. 19: `step.csv`,
//! `step.svg`) and `disturbance` (Fig. 20: `disturbance.csv`, `disturbance_open_loop.csv`,
//! `disturbance.svg`).

use super::{trace_figure, trace_table, ControlReportError, Writer};
use crate::control::study::disturbance::DisturbanceStudy;
use crate::control::study::step::StepStudy;

/// Writes the trace and the figure of `step`.
pub fn write_step(w: &mut Writer, r: &StepStudy) -> Result<(), ControlReportError> {
    let s = &r.settings;
    w.csv("step.csv", &trace_table(&r.trace))?;
    w.figure(
        "step.svg",
        &trace_figure(
            &format!(
                "Set-point step {:.0} -> {:.0} rpm",
                s.from_rpm(),
                s.to_rpm()
            ),
            &[("controlled", &r.trace)],
        ),
    )
}

/// Writes the traces with and without control and their figure of `disturbance`.
pub fn write_disturbance(w: &mut Writer, r: &DisturbanceStudy) -> Result<(), ControlReportError> {
    let s = &r.settings;
    w.csv("disturbance.csv", &trace_table(&r.trace))?;
    w.csv("disturbance_open_loop.csv", &trace_table(&r.open_trace))?;
    w.figure(
        "disturbance.svg",
        &trace_figure(
            &format!("Load step {} N*m at {:.0} rpm", s.load_step_nm(), s.rpm()),
            &[
                ("controlled", &r.trace),
                ("constant command", &r.open_trace),
            ],
        ),
    )
}
