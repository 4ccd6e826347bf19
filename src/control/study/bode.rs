//! `bode` (paper §5.2, Figs. 16, 17): frequency response supply pressure → speed of the
//! linearised motor about an operating point, its fit by two first-order lags, and the
//! response command → speed of valve + motor.

use super::{positive, Plant, ValveOptions};
use crate::control::closed_loop::{PiController, Valve};
use crate::control::design::plant;
use crate::control::error::{ControlError, SettingsError};
use crate::control::linear::{
    fit_two_lags, log_grid, operating_point, rad_s, two_lag_guess, unwrapped_phase_deg, LagFit,
    LinearModel,
};
use crate::control::option::ControlOpt;
use crate::model::motor::{Boundary, Load, Motor};
use crate::units::constants::P_ATM_PA;
use nalgebra::Complex;

/// The options of `bode` as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct BodeOptions {
    /// Mean supply pressure of the operating point (`--p-mean-mpa`), MPa absolute.
    pub p_mean_mpa: f64,
    /// Lowest frequency (`--f-min-hz`), Hz.
    pub f_min_hz: f64,
    /// Highest frequency (`--f-max-hz`), Hz.
    pub f_max_hz: f64,
    /// Number of frequencies, log-spaced (`--points`).
    pub points: usize,
    /// The valve of the valve + motor response.
    pub valve: ValveOptions,
}

impl BodeOptions {
    /// Checks every option; the valve is the motor's unless the options say otherwise.
    pub fn check(&self, motor: &Motor) -> Result<BodeSettings, SettingsError> {
        let p_mean_mpa = positive(ControlOpt::BodePMean, self.p_mean_mpa)?;
        let f_min_hz = positive(ControlOpt::BodeFMin, self.f_min_hz)?;
        let f_max_hz = positive(ControlOpt::BodeFMax, self.f_max_hz)?;
        if f_max_hz <= f_min_hz {
            return Err(SettingsError::EmptyRange {
                option: ControlOpt::BodeFMax,
                value: f_max_hz,
                lower: ControlOpt::BodeFMin,
            });
        }
        if self.points < 5 {
            return Err(SettingsError::TooFewPoints {
                option: ControlOpt::BodePoints,
                value: self.points,
                min: 5,
            });
        }
        Ok(BodeSettings {
            p_mean_mpa,
            f_min_hz,
            f_max_hz,
            points: self.points,
            valve: self.valve.check(motor)?,
        })
    }
}

/// The checked settings of `bode`.
#[derive(Debug, Clone, PartialEq)]
pub struct BodeSettings {
    p_mean_mpa: f64,
    f_min_hz: f64,
    f_max_hz: f64,
    points: usize,
    valve: Valve,
}

impl BodeSettings {
    /// Mean supply pressure, Pa absolute.
    pub fn p_mean_pa(&self) -> f64 {
        self.p_mean_mpa * 1e6
    }

    /// Lowest frequency, Hz.
    pub fn f_min_hz(&self) -> f64 {
        self.f_min_hz
    }

    /// Highest frequency, Hz.
    pub fn f_max_hz(&self) -> f64 {
        self.f_max_hz
    }

    /// The frequencies, Hz, log-spaced.
    fn frequencies_hz(&self) -> Vec<f64> {
        log_grid(self.f_min_hz, self.f_max_hz, self.points)
    }

    /// The valve.
    pub fn valve(&self) -> &Valve {
        &self.valve
    }
}

/// The results of `bode`; every response is sampled at `f_hz`, phases unwrapped from the
/// lowest frequency.
#[derive(Debug, Clone, PartialEq)]
pub struct BodeStudy {
    /// The settings it was run with.
    pub settings: BodeSettings,
    /// The controller whose speed unit scales valve + motor (the paper's).
    pub pi: PiController,
    /// The linearised motor at the operating point.
    pub lin: LinearModel,
    /// Its poles, 1/s.
    pub poles: Vec<Complex<f64>>,
    /// Frequencies, Hz.
    pub f_hz: Vec<f64>,
    /// Speed per supply pressure of the linear model, (rad/s)/Pa.
    pub motor: Vec<Complex<f64>>,
    /// Phase of `motor`, degrees.
    pub(crate) motor_phase_deg: Vec<f64>,
    /// The two-lag fit of `motor`.
    pub fit: LagFit,
    /// The fitted K/((1+sT1)(1+sT2)), (rad/s)/Pa.
    pub fitted: Vec<Complex<f64>>,
    /// Phase of `fitted`, degrees.
    pub(crate) fitted_phase_deg: Vec<f64>,
    /// Valve + motor, speed unit per V (`design::plant`).
    pub(crate) valve_motor: Vec<Complex<f64>>,
    /// Phase of `valve_motor`, degrees.
    pub(crate) valve_motor_phase_deg: Vec<f64>,
}

/// The linearised motor at supply `p_mean_pa` under `load`.
pub fn linear_at(m: &Motor, load: Load, p_mean_pa: f64) -> Result<LinearModel, ControlError> {
    let op = operating_point(m, &Boundary::supplied(p_mean_pa, P_ATM_PA, load))?;
    LinearModel::linearise(m, &op)
}

/// Runs `bode` on the plant.
pub fn study(plant_: &Plant, s: &BodeSettings) -> Result<BodeStudy, ControlError> {
    let pi = PiController::default();
    let lin = linear_at(plant_.motor(), plant_.load(), s.p_mean_pa())?;
    let f = s.frequencies_hz();
    let w: Vec<f64> = f.iter().map(|f| rad_s(*f)).collect();
    let g: Vec<_> = w.iter().map(|w| lin.speed_per_supply(*w)).collect();
    let fit = fit_two_lags(&w, &g, two_lag_guess(&lin));
    let gf: Vec<_> = w.iter().map(|w| fit.lags.at(*w)).collect();
    let pl: Vec<_> = w.iter().map(|w| plant(&lin, &s.valve, &pi, *w)).collect();
    Ok(BodeStudy {
        settings: s.clone(),
        pi,
        poles: lin.poles(),
        lin,
        f_hz: f,
        motor_phase_deg: unwrapped_phase_deg(&g),
        motor: g,
        fit,
        fitted_phase_deg: unwrapped_phase_deg(&gf),
        fitted: gf,
        valve_motor_phase_deg: unwrapped_phase_deg(&pl),
        valve_motor: pl,
    })
}
