//! `disturbance` (paper §5.2, Fig. 20): the closed loop's rejection of a load-torque step,
//! compared with the same step at a constant command.

use super::{positive, step_window, Plant};
use crate::control::closed_loop::{
    disturbance_metrics, tail_mean_error, DisturbanceMetrics, Loop, Scenario, Steps, Trace,
};
use crate::control::error::{ControlError, SettingsError};
use crate::control::option::ControlOpt;
use crate::control::RAD_S_PER_RPM;
use crate::numerics::DefaultSolver;

/// The options of `disturbance` as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct DisturbanceOptions {
    /// Speed set-point (`--rpm`), rpm.
    pub rpm: f64,
    /// Extra load torque switched on at the step (`--load-step-nm`), N·m.
    pub load_step_nm: f64,
    /// Time of the step (`--t-step-s`), s.
    pub t_step_s: f64,
    /// Length of the simulation (`--duration-s`), s.
    pub duration_s: f64,
}

impl DisturbanceOptions {
    /// Checks every option.
    pub fn check(&self) -> Result<DisturbanceSettings, SettingsError> {
        let rpm = positive(ControlOpt::DisturbanceRpm, self.rpm)?;
        let load_step_nm = self.load_step_nm;
        if !load_step_nm.is_finite() {
            return Err(SettingsError::NotFinite {
                option: ControlOpt::DisturbanceLoadStep,
                value: load_step_nm,
            });
        }
        let (duration_s, t_step_s) = step_window(
            (ControlOpt::DisturbanceDuration, self.duration_s),
            (ControlOpt::DisturbanceTStep, self.t_step_s),
        )?;
        Ok(DisturbanceSettings {
            rpm,
            load_step_nm,
            t_step_s,
            duration_s,
        })
    }
}

/// The checked settings of `disturbance`.
#[derive(Debug, Clone, PartialEq)]
pub struct DisturbanceSettings {
    rpm: f64,
    load_step_nm: f64,
    t_step_s: f64,
    duration_s: f64,
}

impl DisturbanceSettings {
    /// Speed set-point, rpm.
    pub fn rpm(&self) -> f64 {
        self.rpm
    }

    /// Speed set-point, rad/s.
    pub fn setpoint_rad_s(&self) -> f64 {
        self.rpm * RAD_S_PER_RPM
    }

    /// Extra load torque after the step, N·m.
    pub fn load_step_nm(&self) -> f64 {
        self.load_step_nm
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

/// The results of `disturbance`.
#[derive(Debug, Clone, PartialEq)]
pub struct DisturbanceStudy {
    /// The settings it was run with.
    pub settings: DisturbanceSettings,
    /// The loop.
    pub lp: Loop,
    /// The controlled response.
    pub trace: Trace,
    /// The response at a constant command (the controller's gains set to zero).
    pub(crate) open_trace: Trace,
    /// Figures of merit of the controlled response (band: 1 % of the set-point, at least
    /// 5 rpm).
    pub metrics: DisturbanceMetrics,
    /// Mean error over the last 10 % of the constant-command response, rad/s.
    pub open_error_rad_s: f64,
}

/// Runs `disturbance` on the plant with the loop `lp`.
pub fn study(
    plant: &Plant,
    lp: &Loop,
    s: &DisturbanceSettings,
) -> Result<DisturbanceStudy, ControlError> {
    let m = plant.motor();
    let w = s.setpoint_rad_s();
    let start = lp.settled_at(m, w).map_err(|e| ControlError::SetPoint {
        option: ControlOpt::DisturbanceRpm,
        value: s.rpm,
        source: Box::new(e),
    })?;
    let sc = Scenario {
        duration_s: s.duration_s,
        setpoint_rad_s: Steps::constant(w),
        load_torque_nm: Steps::step(0.0, s.t_step_s, s.load_step_nm),
    };
    let solver = DefaultSolver::default();
    let trace = lp.simulate(m, &solver, &sc, &start)?;
    // Without control: the command stays where it was (the controller's gains set to zero).
    let open_trace = lp.without_control().simulate(m, &solver, &sc, &start)?;
    let metrics = disturbance_metrics(&trace, s.t_step_s, (0.01 * w).max(5.0 * RAD_S_PER_RPM));
    Ok(DisturbanceStudy {
        settings: s.clone(),
        lp: *lp,
        open_error_rad_s: tail_mean_error(&open_trace, 0.1),
        trace,
        open_trace,
        metrics,
    })
}
