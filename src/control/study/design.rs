//! `design`: PI gains for a phase margin (and optionally a crossover) on the linearised
//! valve + motor, checked by a closed-loop simulation of the nonlinear motor against the
//! paper's gains.

use super::bode::linear_at;
use super::{positive, Plant};
use crate::control::closed_loop::{
    step_metrics, Loop, PiController, Scenario, StepMetrics, Steps, Trace,
};
use crate::control::design::{design_pi, margins, open_loop, Margins, Target};
use crate::control::error::{ControlError, SettingsError};
use crate::control::linear::{log_grid, rad_s, unwrapped_phase_deg};
use crate::control::option::ControlOpt;
use crate::control::{rpm, RAD_S_PER_RPM};
use crate::numerics::DefaultSolver;
use nalgebra::Complex;

/// Time of the set-point step of the check simulation, s.
const T_STEP_S: f64 = 0.1;

/// The options of `design` as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct DesignOptions {
    /// Requested phase margin (`--pm-deg`), degrees.
    pub pm_deg: f64,
    /// Requested crossover (`--crossover-hz`), Hz; `None`: the highest at which a PI gives
    /// the phase margin.
    pub crossover_hz: Option<f64>,
    /// Mean supply pressure of the operating point (`--p-mean-mpa`), MPa absolute.
    pub p_mean_mpa: f64,
    /// Set-point step of the check simulation (`--step-rpm`), rpm.
    pub step_rpm: f64,
    /// Length of the check simulation (`--duration-s`), s.
    pub duration_s: f64,
}

impl DesignOptions {
    /// Checks every option.
    pub fn check(&self) -> Result<DesignSettings, SettingsError> {
        let pm = self.pm_deg;
        if !(pm > 0.0 && pm < 90.0) {
            return Err(SettingsError::PhaseMargin(pm));
        }
        let target = match self.crossover_hz {
            Some(f) => Target::Bandwidth {
                crossover_rad_s: rad_s(positive(ControlOpt::DesignCrossover, f)?),
                pm_deg: pm,
            },
            None => Target::PhaseMargin { pm_deg: pm },
        };
        Ok(DesignSettings {
            target,
            p_mean_mpa: positive(ControlOpt::DesignPMean, self.p_mean_mpa)?,
            step_rpm: positive(ControlOpt::DesignStep, self.step_rpm)?,
            duration_s: positive(ControlOpt::DesignDuration, self.duration_s)?,
        })
    }
}

/// The checked settings of `design`.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignSettings {
    target: Target,
    p_mean_mpa: f64,
    step_rpm: f64,
    duration_s: f64,
}

impl DesignSettings {
    /// What the design aims at.
    pub fn target(&self) -> Target {
        self.target
    }

    /// Mean supply pressure of the operating point, Pa absolute.
    pub fn p_mean_pa(&self) -> f64 {
        self.p_mean_mpa * 1e6
    }

    /// Set-point step of the check simulation, rpm.
    pub fn step_rpm(&self) -> f64 {
        self.step_rpm
    }

    /// Set-point step of the check simulation, rad/s.
    fn step_rad_s(&self) -> f64 {
        self.step_rpm * RAD_S_PER_RPM
    }

    /// Length of the check simulation, s.
    pub fn duration_s(&self) -> f64 {
        self.duration_s
    }
}

/// One controller of the comparison: its gains, margins on the linear loop and the
/// simulated step of the nonlinear one.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignRun {
    /// The controller.
    pub pi: PiController,
    /// Its margins on the linearised loop.
    pub margins: Margins,
    /// The simulated set-point step.
    pub trace: Trace,
    /// The step's figures of merit.
    pub metrics: StepMetrics,
    /// Open-loop response C·P at `DesignStudy::f_hz`.
    pub(crate) open_loop: Vec<Complex<f64>>,
    /// Its phase, degrees, unwrapped from the lowest frequency.
    pub(crate) open_loop_phase_deg: Vec<f64>,
}

/// The results of `design`.
#[derive(Debug, Clone, PartialEq)]
pub struct DesignStudy {
    /// The settings it was run with.
    pub settings: DesignSettings,
    /// The loop (its controller's settings other than the gains apply to both runs).
    pub lp: Loop,
    /// Speed of the operating point, rad/s.
    pub w0_rad_s: f64,
    /// Frequencies of the open-loop responses, Hz.
    pub f_hz: Vec<f64>,
    /// The designed controller.
    pub designed: DesignRun,
    /// The paper's gains, (0.85 s + 4)/s.
    pub paper: DesignRun,
}

impl DesignStudy {
    /// An error if the designed loop does not settle in the check simulation (no settling
    /// time, or a final error above 2 % of the step).
    pub fn check_settled(&self) -> Result<(), ControlError> {
        let m = &self.designed.metrics;
        if m.settling_time_s.is_nan()
            || rpm(m.final_error_rad_s).abs() > 0.02 * self.settings.step_rpm
        {
            return Err(ControlError::NotSettled {
                duration_s: self.settings.duration_s,
                final_error_rpm: rpm(m.final_error_rad_s),
            });
        }
        Ok(())
    }
}

/// Runs `design` on the plant; `lp` gives the valve and the controller's settings other
/// than the gains.
pub fn study(plant: &Plant, lp: &Loop, s: &DesignSettings) -> Result<DesignStudy, ControlError> {
    let motor = plant.motor();
    let lin = linear_at(motor, plant.load(), s.p_mean_pa())?;
    let designed = design_pi(&lin, &lp.valve, &lp.pi, s.target)?;
    let paper = PiController {
        kp: 0.85,
        ki: 4.0,
        ..lp.pi
    };
    let w0 = lin.op.speed_rad_s();
    let step = s.step_rad_s();
    let solver = DefaultSolver::default();
    let f = log_grid(1e-3, 1e2, 300);
    let run = |pi: PiController| -> Result<DesignRun, ControlError> {
        let l = Loop { pi, ..*lp };
        let start = l.settled_at(motor, w0)?;
        let sc = Scenario {
            duration_s: s.duration_s,
            setpoint_rad_s: Steps::step(w0, T_STEP_S, w0 + step),
            load_torque_nm: Steps::constant(0.0),
        };
        let trace = l.simulate(motor, &solver, &sc, &start)?;
        let open: Vec<_> = f
            .iter()
            .map(|f| open_loop(&lin, &lp.valve, &pi, rad_s(*f)))
            .collect();
        Ok(DesignRun {
            pi,
            margins: margins(&lin, &lp.valve, &pi),
            metrics: step_metrics(&trace, T_STEP_S, w0, w0 + step),
            trace,
            open_loop_phase_deg: unwrapped_phase_deg(&open),
            open_loop: open,
        })
    };
    let designed = run(designed)?;
    let paper = run(paper)?;
    Ok(DesignStudy {
        settings: s.clone(),
        lp: *lp,
        w0_rad_s: w0,
        f_hz: f,
        designed,
        paper,
    })
}
