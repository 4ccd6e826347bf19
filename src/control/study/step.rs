//! `step` (paper §5.2, Fig. 19): the closed loop's response to a speed set-point step, from
//! the loop settled at the first set-point.

use super::{positive, step_window, Plant};
use crate::control::closed_loop::{step_metrics, Loop, Scenario, StepMetrics, Steps, Trace};
use crate::control::error::{ControlError, SettingsError};
use crate::control::option::ControlOpt;
use crate::control::RAD_S_PER_RPM;
use crate::model::motor::{idx, Boundary};
use crate::numerics::DefaultSolver;
use crate::sim::steady;
use crate::units::constants::P_ATM_PA;

/// The options of `step` as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct StepOptions {
    /// Set-point before the step (`--from-rpm`), rpm.
    pub from_rpm: f64,
    /// Set-point after the step (`--to-rpm`), rpm.
    pub to_rpm: f64,
    /// Time of the step (`--t-step-s`), s.
    pub t_step_s: f64,
    /// Length of the simulation (`--duration-s`), s.
    pub duration_s: f64,
}

impl StepOptions {
    /// Checks every option.
    pub fn check(&self) -> Result<StepSettings, SettingsError> {
        let from_rpm = positive(ControlOpt::StepFrom, self.from_rpm)?;
        let to_rpm = positive(ControlOpt::StepTo, self.to_rpm)?;
        let (duration_s, t_step_s) = step_window(
            (ControlOpt::StepDuration, self.duration_s),
            (ControlOpt::StepTStep, self.t_step_s),
        )?;
        Ok(StepSettings {
            from_rpm,
            to_rpm,
            t_step_s,
            duration_s,
        })
    }
}

/// The checked settings of `step`.
#[derive(Debug, Clone, PartialEq)]
pub struct StepSettings {
    from_rpm: f64,
    to_rpm: f64,
    t_step_s: f64,
    duration_s: f64,
}

impl StepSettings {
    /// Set-point before the step, rpm.
    pub fn from_rpm(&self) -> f64 {
        self.from_rpm
    }

    /// Set-point after the step, rpm.
    pub fn to_rpm(&self) -> f64 {
        self.to_rpm
    }

    /// Set-point before the step, rad/s.
    pub fn from_rad_s(&self) -> f64 {
        self.from_rpm * RAD_S_PER_RPM
    }

    /// Set-point after the step, rad/s.
    pub fn to_rad_s(&self) -> f64 {
        self.to_rpm * RAD_S_PER_RPM
    }

    /// Time of the step, s.
    pub fn t_step_s(&self) -> f64 {
        self.t_step_s
    }

    /// Length of the simulation, s.
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }
}

/// The results of `step`.
#[derive(Debug, Clone, PartialEq)]
pub struct StepStudy {
    /// The settings it was run with.
    pub settings: StepSettings,
    /// The loop.
    pub lp: Loop,
    /// The simulated response.
    pub trace: Trace,
    /// Its figures of merit.
    pub metrics: StepMetrics,
    /// Steady speed at full command, rad/s (above it the command saturates).
    pub full_speed_rad_s: f64,
}

/// Runs `step` on the plant with the loop `lp`.
pub fn study(plant: &Plant, lp: &Loop, s: &StepSettings) -> Result<StepStudy, ControlError> {
    let m = plant.motor();
    let (from, to) = (s.from_rad_s(), s.to_rad_s());
    let start = lp.settled_at(m, from).map_err(|e| ControlError::SetPoint {
        option: ControlOpt::StepFrom,
        value: s.from_rpm,
        source: Box::new(e),
    })?;
    let sc = Scenario {
        duration_s: s.duration_s,
        setpoint_rad_s: Steps::step(from, s.t_step_s, to),
        load_torque_nm: Steps::constant(0.0),
    };
    let trace = lp.simulate(m, &DefaultSolver::default(), &sc, &start)?;
    let metrics = step_metrics(&trace, s.t_step_s, from, to);
    let bc_full = Boundary::supplied(
        lp.valve.set_pressure_pa(lp.valve.u_max_v),
        P_ATM_PA,
        lp.load,
    );
    let full = steady::free(m, &bc_full, &steady::initial_guess(&bc_full))?;
    Ok(StepStudy {
        settings: s.clone(),
        lp: *lp,
        trace,
        metrics,
        full_speed_rad_s: full[idx::OMEGA],
    })
}
