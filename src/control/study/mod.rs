//! The studies of `vanefit control <study>` (paper §5), each in three steps: its options as
//! given (`…Options`, public fields, unchecked) are checked once by `check()` into settings
//! (`…Settings`, private fields behind accessors, valid by construction), and the `study`
//! function computes the results into a plain struct. Nothing here prints or writes files:
//! the tables and figures are `report::control`'s, the summary lines the command line's.
//!
//! Options shared by the studies: the motor and its load ([`MotorOptions`] → [`Plant`]) and
//! the control loop ([`LoopOptions`] → `closed_loop::Loop`).

pub(crate) mod bode;
pub(crate) mod design;
pub(crate) mod disturbance;
pub(crate) mod min_speed;
pub(crate) mod step;
pub(crate) mod throttle;

pub use bode::{linear_at, BodeOptions, BodeStudy};
pub use design::{DesignOptions, DesignRun, DesignStudy};
pub use disturbance::{DisturbanceOptions, DisturbanceStudy};
pub use min_speed::{MinSpeedOptions, MinSpeedStudy};
pub use step::{StepOptions, StepStudy};
pub use throttle::{ThrottleOptions, ThrottleStudy};

use super::closed_loop::{AntiWindup, Loop, PiController, Valve, ValveDynamics};
use super::error::{ControlError, SettingsError};
use super::option::ControlOpt;
use crate::data::fitfile::FitFile;
use crate::model::effects::EffectSet;
use crate::model::gear::Gear;
use crate::model::motor::{Load, Motor};
use crate::model::params::MotorParams;
use crate::units::constants::P_ATM_PA;
use std::path::PathBuf;

/// `v` if it is a finite number > 0.
pub(crate) fn positive(option: ControlOpt, v: f64) -> Result<f64, SettingsError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(SettingsError::NotPositive { option, value: v })
    }
}

/// `v` if it is a finite number ≥ 0.
pub(crate) fn non_negative(option: ControlOpt, v: f64) -> Result<f64, SettingsError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(SettingsError::Negative { option, value: v })
    }
}

/// An absolute pressure option in MPa, checked to lie above atmosphere.
pub(crate) fn absolute_pressure_mpa(option: ControlOpt, mpa: f64) -> Result<f64, SettingsError> {
    let p = positive(option, mpa)? * 1e6;
    if p <= P_ATM_PA {
        return Err(SettingsError::NotAboveAtmosphere { option, value: mpa });
    }
    Ok(mpa)
}

/// A scenario's length and the time of its step, s, each with its option: the step must
/// fall inside the length.
pub(crate) fn step_window(
    (duration_opt, duration_s): (ControlOpt, f64),
    (t_step_opt, t_step_s): (ControlOpt, f64),
) -> Result<(f64, f64), SettingsError> {
    let dur = positive(duration_opt, duration_s)?;
    let t_step = non_negative(t_step_opt, t_step_s)?;
    if t_step >= dur {
        return Err(SettingsError::StepAfterEnd {
            option: t_step_opt,
            value: t_step,
            end: duration_opt,
        });
    }
    Ok((dur, t_step))
}

/// The motor and its load as every study's options give them (unchecked).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MotorOptions {
    /// Fit file (`--params`, vanefit.fit/1); `None`: the default motor.
    pub params: Option<PathBuf>,
    /// The fit file's text when the fit is held in memory (the Python package's `Fit`):
    /// read instead of the file, `params` (if any) then only names it in messages.
    pub params_text: Option<String>,
    /// Effects to switch on (`--effects`, comma-separated ids), overriding the fit file's.
    pub effects: Option<String>,
    /// Eddy-current brake on the shaft (`--brake-nm-s-rad`), N·m·s/rad; `None`: the study's
    /// default.
    pub brake_nm_s_rad: Option<f64>,
}

impl MotorOptions {
    /// Reads the fit file and checks the options. The fit file's discovered terms act in the
    /// motor as in `simulate`. `default_brake_nm_s_rad` is the study's brake when
    /// `--brake-nm-s-rad` is not given (0: no load).
    pub fn check(&self, default_brake_nm_s_rad: f64) -> Result<Plant, ControlError> {
        let fit = match (&self.params, &self.params_text) {
            (p, Some(text)) => {
                let name = p.clone().unwrap_or_else(|| PathBuf::from("<fit>"));
                Some(FitFile::parse(&name, text)?)
            }
            (Some(p), None) => Some(FitFile::read(p)?),
            (None, None) => None,
        };
        let (params, mut effects, extra, gear) = match fit {
            Some(f) => (f.params, f.effects, f.extra, f.gear),
            None => (MotorParams::default(), EffectSet::empty(), Vec::new(), None),
        };
        if let Some(list) = &self.effects {
            effects = EffectSet::parse_list(list).map_err(SettingsError::Effects)?;
        }
        let brake = non_negative(
            ControlOpt::MotorBrake,
            self.brake_nm_s_rad.unwrap_or(default_brake_nm_s_rad),
        )?;
        let load = if brake > 0.0 {
            Load::ViscousBrake { c_nm_s_rad: brake }
        } else {
            Load::None
        };
        Ok(Plant {
            motor: Motor::new(params, effects).with_extra(&extra),
            load,
            gear,
        })
    }
}

/// The checked motor (with the fit file's discovered terms) and the load on its shaft.
#[derive(Debug, Clone)]
pub struct Plant {
    motor: Motor,
    load: Load,
    gear: Option<Gear>,
}

impl Plant {
    /// The gearbox of a geared motor's fit: the studies run at the MOTOR shaft (its speed,
    /// torque and brake), which turns G times as fast as the gearbox's output (`None`: no
    /// gearbox).
    pub fn gear(&self) -> Option<Gear> {
        self.gear
    }

    /// The motor.
    pub fn motor(&self) -> &Motor {
        &self.motor
    }

    /// The load on the shaft (the eddy-current brake, or none).
    pub fn load(&self) -> Load {
        self.load
    }
}

/// The pressure control valve as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct ValveOptions {
    /// Time constant (`--valve-tau-s`), s; `None`: the parameter set's `valve_tau`.
    pub tau_s: Option<f64>,
    /// Command for full pressure (`--valve-u-max-v`), V.
    pub u_max_v: f64,
    /// Gauge pressure at full command (`--valve-p-max-bar-g`), bar.
    pub p_max_bar_g: f64,
}

impl ValveOptions {
    /// The motor's valve (`Valve::for_motor`: first or second order as its effects say) with
    /// the options applied.
    pub fn check(&self, motor: &Motor) -> Result<Valve, SettingsError> {
        let mut v = Valve::for_motor(motor, P_ATM_PA);
        if let Some(tau) = self.tau_s {
            let tau = positive(ControlOpt::ValveTau, tau)?;
            v.dynamics = match v.dynamics {
                ValveDynamics::FirstOrder { .. } => ValveDynamics::FirstOrder { tau_s: tau },
                ValveDynamics::SecondOrder { zeta, .. } => {
                    ValveDynamics::SecondOrder { tau_s: tau, zeta }
                }
            };
        }
        v.u_max_v = positive(ControlOpt::ValveUMax, self.u_max_v)?;
        v.p_max_gauge_pa = positive(ControlOpt::ValvePMax, self.p_max_bar_g)? * 1e5;
        Ok(v)
    }
}

/// PI gains as given (unchecked); the paper's G(s) = (0.85 s + 4)/s is kp 0.85, ki 4.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainOptions {
    /// Proportional gain (`--kp`), V per speed unit.
    pub kp: f64,
    /// Integral gain (`--ki`), V per speed unit per s.
    pub ki: f64,
}

/// Controller settings other than the gains, as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct PiOptions {
    /// Sample time (`--ts-ms`), ms.
    pub ts_ms: f64,
    /// Speed unit of the controller's error (`--speed-unit-rpm`), rpm.
    pub speed_unit_rpm: f64,
    /// `--anti-windup`: conditional, back-calculation or none.
    pub anti_windup: String,
}

impl PiOptions {
    /// The controller driving `valve`, with `gains` (`None`: the paper's, for a study that
    /// designs its own).
    pub fn check(
        &self,
        gains: Option<&GainOptions>,
        valve: &Valve,
    ) -> Result<PiController, SettingsError> {
        let base = PiController::default();
        let (kp, ki) = match gains {
            Some(g) => (
                non_negative(ControlOpt::GainKp, g.kp)?,
                non_negative(ControlOpt::GainKi, g.ki)?,
            ),
            None => (base.kp, base.ki),
        };
        let ts = positive(ControlOpt::PiSampleTime, self.ts_ms)? * 1e-3;
        if ts > 0.1 {
            return Err(SettingsError::SampleTimeTooLong(self.ts_ms));
        }
        let anti_windup: AntiWindup = self.anti_windup.parse()?;
        if anti_windup == AntiWindup::BackCalculation && (kp == 0.0 || ki == 0.0) {
            return Err(SettingsError::BackCalculationWithoutGains);
        }
        Ok(PiController {
            kp,
            ki,
            ts_s: ts,
            speed_unit_rpm: positive(ControlOpt::PiSpeedUnit, self.speed_unit_rpm)?,
            u_min_v: 0.0,
            u_max_v: valve.u_max_v,
            anti_windup,
        })
    }
}

/// The control loop as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct LoopOptions {
    /// The valve.
    pub valve: ValveOptions,
    /// The controller.
    pub pi: PiOptions,
    /// The gains; `None`: the paper's (the design study finds its own).
    pub gains: Option<GainOptions>,
}

impl LoopOptions {
    /// The loop around the plant's motor, under the plant's load.
    pub fn check(&self, plant: &Plant) -> Result<Loop, SettingsError> {
        let valve = self.valve.check(&plant.motor)?;
        let pi = self.pi.check(self.gains.as_ref(), &valve)?;
        Ok(Loop {
            valve,
            pi,
            load: plant.load,
        })
    }
}

impl Default for LoopOptions {
    /// The paper's loop, as `vanefit control` takes it by default: a 10 V valve up to
    /// 6 bar(g) with the motor's own time constant, a PI controller sampling every 1 ms on
    /// the speed error in units of 1000 rpm with conditional anti-windup, and the paper's
    /// gains kp 0.85, ki 4 (G(s) = (0.85 s + 4)/s).
    fn default() -> Self {
        LoopOptions {
            valve: ValveOptions {
                tau_s: None,
                u_max_v: 10.0,
                p_max_bar_g: 6.0,
            },
            pi: PiOptions {
                ts_ms: 1.0,
                speed_unit_rpm: 1000.0,
                anti_windup: "conditional".into(),
            },
            gains: Some(GainOptions { kp: 0.85, ki: 4.0 }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::throttle::{study, ThrottleOptions};
    use super::*;
    use crate::control::throttle::Port;
    use crate::model::extra::{BalanceId, ExtraTerm, PressureFactor, SpeedFactor};

    /// The free speed and the throttled speeds of a throttling study under a fit file.
    fn throttle_speeds(fit: &FitFile, dir: &std::path::Path) -> (f64, Vec<f64>) {
        let path = dir.join(format!("{}.json", fit.extra.len()));
        fit.write(&path).unwrap();
        let plant = MotorOptions {
            params: Some(path),
            ..MotorOptions::default()
        }
        .check(1e-4)
        .unwrap();
        let settings = ThrottleOptions {
            port: Port::Inlet,
            p_supply_mpa: 0.6,
            c_min_m3_s_pa: 1e-9,
            c_max_m3_s_pa: 1e-8,
            points: 3,
            curves_m3_s_pa: "none".into(),
        }
        .check()
        .unwrap();
        let r = study(&plant, &settings).unwrap();
        let speeds = r.speed.iter().map(|p| p.speed_rad_s).collect();
        (r.free_speed_rad_s, speeds)
    }

    /// A geared fit's gearbox reaches the studies' plant; an ungeared one has none.
    #[test]
    fn a_geared_fit_says_its_studies_are_at_the_motor_shaft() {
        let dir = tempfile::tempdir().unwrap();
        let mut fit = FitFile::from_params("demo", MotorParams::default(), EffectSet::empty());
        let plant = |fit: &FitFile| {
            let path = dir.path().join("fit.json");
            fit.write(&path).unwrap();
            MotorOptions {
                params: Some(path),
                ..MotorOptions::default()
            }
            .check(0.0)
            .unwrap()
        };
        assert_eq!(plant(&fit).gear(), None);
        fit.gear = Some(Gear::new(4.0, Some(0.9)));
        let g = plant(&fit).gear().unwrap();
        assert_eq!((g.ratio, g.efficiency), (4.0, 0.9));
    }

    #[test]
    fn discovered_terms_of_the_fit_file_act_in_the_studies() {
        let dir = tempfile::tempdir().unwrap();
        let plain = FitFile::from_params("demo", MotorParams::default(), EffectSet::empty());
        let mut with_term = plain.clone();
        // An extra viscous loss, 5e-5 N*m*s/rad: about 0.05 N*m at 1000 rad/s.
        with_term.extra = vec![ExtraTerm {
            balance: BalanceId::Torque,
            pressure: PressureFactor::One,
            speed: SpeedFactor::Omega,
            coefficient: 5e-5,
        }];
        let (free0, speeds0) = throttle_speeds(&plain, dir.path());
        let (free1, speeds1) = throttle_speeds(&with_term, dir.path());
        assert!(free1 < 0.99 * free0, "free speed {free1} vs {free0} rad/s");
        for (w1, w0) in speeds1.iter().zip(&speeds0) {
            assert!(w1 < w0, "throttled speed {w1} vs {w0} rad/s");
        }
    }
}
