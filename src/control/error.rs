//! Why a control study could not be done: [`SettingsError`] for a bad option value, found
//! before any work, and [`ControlError`] for everything else. They carry the options they
//! name as [`ControlOpt`] values; their messages name them by their fields, `Type.field`
//! (e.g. `ThrottleOptions.points`), as `task::OptionError` names the tasks' options, and
//! `message_with` by any other names: the command line shows its flags, Python its
//! keywords.

use crate::control::option::ControlOpt;
use crate::data::fitfile::FitFileError;
use crate::numerics::ode::SolveError;
use crate::sim::steady::SteadyError;
use std::fmt;

/// A bad option value of a control study (a field of its `…Options`). Its message names
/// the options by their fields ([`ControlOpt::field`], e.g. `ThrottleOptions.points 1: must
/// be at least 2`); [`SettingsError::message_with`] by any other names (the command line's
/// flags, Python's keywords).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SettingsError {
    /// A quantity that must be a finite number > 0.
    NotPositive {
        /// The option, e.g. [`ControlOpt::PiSampleTime`].
        option: ControlOpt,
        /// The value given.
        value: f64,
    },
    /// A quantity that must be a finite number ≥ 0.
    Negative {
        /// The option, e.g. [`ControlOpt::GainKp`].
        option: ControlOpt,
        /// The value given.
        value: f64,
    },
    /// A quantity that must be finite (of either sign).
    NotFinite {
        /// The option, e.g. [`ControlOpt::DisturbanceLoadStep`].
        option: ControlOpt,
        /// The value given.
        value: f64,
    },
    /// An absolute pressure at or below atmosphere (101 325 Pa).
    NotAboveAtmosphere {
        /// The option, e.g. [`ControlOpt::ThrottlePSupply`].
        option: ControlOpt,
        /// The value given, MPa absolute.
        value: f64,
    },
    /// The upper end of a range at or below its lower end.
    EmptyRange {
        /// The upper end, e.g. [`ControlOpt::BodeFMax`].
        option: ControlOpt,
        /// The value given.
        value: f64,
        /// The lower end.
        lower: ControlOpt,
    },
    /// Too few grid points for the study.
    TooFewPoints {
        /// The option, e.g. [`ControlOpt::ThrottlePoints`].
        option: ControlOpt,
        /// The value given.
        value: usize,
        /// The least the study needs.
        min: usize,
    },
    /// An item of `ThrottleOptions.curves_m3_s_pa` ([`ControlOpt::ThrottleCurves`]) that is
    /// neither `none` nor a number.
    NotAConductance(String),
    /// `ThrottleOptions.curves_m3_s_pa` ([`ControlOpt::ThrottleCurves`]) without any item.
    NoCurves(String),
    /// A controller sample time above 100 ms, ms ([`ControlOpt::PiSampleTime`]).
    SampleTimeTooLong(f64),
    /// An unknown `PiOptions.anti_windup` scheme ([`ControlOpt::PiAntiWindup`]).
    AntiWindup(#[from] UnknownAntiWindup),
    /// Back-calculation ([`ControlOpt::PiAntiWindup`]) needs both gains
    /// ([`ControlOpt::GainKp`], [`ControlOpt::GainKi`]) for its tracking time K_p/K_i.
    BackCalculationWithoutGains,
    /// An unknown effect in `MotorOptions.effects` ([`ControlOpt::MotorEffects`]; the
    /// model's message).
    Effects(#[from] crate::model::effects::UnknownEffect),
    /// A step time at or after the end of the scenario.
    StepAfterEnd {
        /// The step time, e.g. [`ControlOpt::StepTStep`].
        option: ControlOpt,
        /// The value given, s.
        value: f64,
        /// The scenario's length, e.g. [`ControlOpt::StepDuration`].
        end: ControlOpt,
    },
    /// `MinSpeedOptions.factor` ([`ControlOpt::MinSpeedFactor`]) outside (0, 1).
    Factor(f64),
    /// `MinSpeedOptions.stage_s` ([`ControlOpt::MinSpeedStage`]) not longer than the hold
    /// window plus 1 s, s.
    StageTooShort(f64),
    /// `DesignOptions.pm_deg` ([`ControlOpt::DesignPhaseMargin`]) outside (0, 90).
    PhaseMargin(f64),
}

impl SettingsError {
    /// The option at fault (the first of those the message names).
    pub fn option(&self) -> ControlOpt {
        use SettingsError as E;
        match self {
            E::NotPositive { option, .. }
            | E::Negative { option, .. }
            | E::NotFinite { option, .. }
            | E::NotAboveAtmosphere { option, .. }
            | E::EmptyRange { option, .. }
            | E::TooFewPoints { option, .. }
            | E::StepAfterEnd { option, .. } => *option,
            E::NotAConductance(_) | E::NoCurves(_) => ControlOpt::ThrottleCurves,
            E::SampleTimeTooLong(_) => ControlOpt::PiSampleTime,
            E::AntiWindup(_) | E::BackCalculationWithoutGains => ControlOpt::PiAntiWindup,
            E::Effects(_) => ControlOpt::MotorEffects,
            E::Factor(_) => ControlOpt::MinSpeedFactor,
            E::StageTooShort(_) => ControlOpt::MinSpeedStage,
            E::PhaseMargin(_) => ControlOpt::DesignPhaseMargin,
        }
    }

    /// The message with every option it names called `name(option)` (e.g. the command
    /// line's flag); [`fmt::Display`] is `message_with(&ControlOpt::field)`.
    pub fn message_with(&self, name: &dyn Fn(ControlOpt) -> &'static str) -> String {
        use ControlOpt as O;
        use SettingsError as E;
        match self {
            E::NotPositive { option, value } => {
                format!("{} {value}: must be a number > 0", name(*option))
            }
            E::Negative { option, value } => {
                format!("{} {value}: must be a number >= 0", name(*option))
            }
            E::NotFinite { option, value } => {
                format!("{} {value}: must be a number", name(*option))
            }
            E::NotAboveAtmosphere { option, value } => format!(
                "{} {value}: must be above atmospheric (0.101325)",
                name(*option)
            ),
            E::EmptyRange {
                option,
                value,
                lower,
            } => format!(
                "{} {value}: must be larger than {}",
                name(*option),
                name(*lower)
            ),
            E::TooFewPoints { option, value, min } => {
                format!("{} {value}: must be at least {min}", name(*option))
            }
            E::NotAConductance(item) => format!(
                "{} {item}: must be \"none\" or a conductance > 0",
                name(O::ThrottleCurves)
            ),
            E::NoCurves(list) => format!(
                "{} {list}: must be a non-empty list",
                name(O::ThrottleCurves)
            ),
            E::SampleTimeTooLong(ts_ms) => {
                format!("{} {ts_ms}: must be at most 100 ms", name(O::PiSampleTime))
            }
            E::AntiWindup(e) => format!("{}: {e}", name(O::PiAntiWindup)),
            E::BackCalculationWithoutGains => format!(
                "{} back-calculation needs {} > 0 and {} > 0 (tracking time kp/ki)",
                name(O::PiAntiWindup),
                name(O::GainKp),
                name(O::GainKi)
            ),
            E::Effects(e) => format!("{}: {e}", name(O::MotorEffects)),
            E::StepAfterEnd { option, value, end } => {
                format!("{} {value}: must be before {}", name(*option), name(*end))
            }
            E::Factor(v) => format!("{} {v}: must be between 0 and 1", name(O::MinSpeedFactor)),
            E::StageTooShort(v) => {
                format!("{} {v}: must be longer than 3 s", name(O::MinSpeedStage))
            }
            E::PhaseMargin(v) => format!(
                "{} {v}: must be between 0 and 90",
                name(O::DesignPhaseMargin)
            ),
        }
    }
}

impl fmt::Display for SettingsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message_with(&ControlOpt::field))
    }
}

/// An anti-windup scheme that is not one of `conditional`, `back-calculation`, `none`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown anti-windup '{0}' (known: conditional, back-calculation, none)")]
pub struct UnknownAntiWindup(pub String);

/// Why a control study failed. Where its message names options (a bad value, a set-point,
/// the advice after a failed design check) it names them by their fields, as
/// [`SettingsError`]; [`ControlError::message_with`] by any other names.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ControlError {
    /// A bad option value.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The fit file of `MotorOptions.params` could not be read.
    #[error(transparent)]
    FitFile(#[from] FitFileError),
    /// No steady state.
    #[error(transparent)]
    Steady(#[from] SteadyError),
    /// The ODE solver failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The operating point of a linearisation is at (or near) standstill.
    #[error(
        "operating point at {p_supply_mpa:.3} MPa supply: the motor is stalled (speed \
         {speed_rpm:.1} rpm, below {min_rpm:.0} rpm); the linearised model is valid only while \
         the motor turns — raise the supply pressure or reduce the load"
    )]
    Stalled {
        /// Supply pressure, MPa absolute.
        p_supply_mpa: f64,
        /// Steady speed found, rpm.
        speed_rpm: f64,
        /// Lowest speed at which the motor counts as running, rpm.
        min_rpm: f64,
    },
    /// The linearised motor has a pole with real part ≥ 0 (or NaN).
    #[error(
        "operating point at {p_supply_mpa:.3} MPa supply, {speed_rpm:.0} rpm is not stable \
         (pole {re:.3e}{im:+.3e}i 1/s); no frequency response there"
    )]
    Unstable {
        /// Supply pressure, MPa absolute.
        p_supply_mpa: f64,
        /// Speed of the operating point, rpm.
        speed_rpm: f64,
        /// Real part of the pole, 1/s.
        re: f64,
        /// Imaginary part of the pole, 1/s.
        im: f64,
    },
    /// A set-point above the steady speed at full valve command.
    #[error(
        "set-point {setpoint_rpm:.0} rpm is above the speed at full command ({full_rpm:.0} rpm)"
    )]
    AboveFullCommand {
        /// The set-point, rpm.
        setpoint_rpm: f64,
        /// Steady speed at full command, rpm.
        full_rpm: f64,
    },
    /// A set-point inside a band of speeds without a steady state.
    #[error(
        "no steady open-loop speed near {setpoint_rpm:.0} rpm (nearest {nearest_rpm:.0} rpm): \
         the speed jumps there as the supply pressure rises"
    )]
    NoSteadySpeed {
        /// The set-point, rpm.
        setpoint_rpm: f64,
        /// Nearest steady speed found, rpm.
        nearest_rpm: f64,
    },
    /// The solver failed within a controller sample interval.
    #[error("closed loop at t = {t_s:.3} s: {source}")]
    LoopStep {
        /// Start of the interval, s.
        t_s: f64,
        /// The solver's error.
        source: SolveError,
    },
    /// The plant's phase never falls to the phase the margin asks for.
    #[error(
        "the plant's phase never reaches {goal_deg:.0}°: no crossover for a {pm_deg:.0}° phase \
         margin"
    )]
    NoPhaseCrossing {
        /// Phase sought, degrees.
        goal_deg: f64,
        /// Requested phase margin, degrees.
        pm_deg: f64,
    },
    /// A design target with a crossover ≤ 0 or a phase margin outside (0°, 90°).
    #[error(
        "design target needs a crossover > 0 and a phase margin in (0°, 90°) (got \
         {crossover_rad_s} rad/s, {pm_deg}°)"
    )]
    BadTarget {
        /// Crossover, rad/s.
        crossover_rad_s: f64,
        /// Phase margin, degrees.
        pm_deg: f64,
    },
    /// A PI would have to add phase lead at the crossover.
    #[error(
        "a PI cannot give {pm_deg:.0}° phase margin at {crossover_rad_s:.3} rad/s: the plant's \
         phase there is {phase_deg:.1}°, the PI would have to add lead; choose a higher \
         crossover or a smaller phase margin"
    )]
    NeedsLead {
        /// Requested phase margin, degrees.
        pm_deg: f64,
        /// Crossover, rad/s.
        crossover_rad_s: f64,
        /// The plant's phase at the crossover, degrees.
        phase_deg: f64,
    },
    /// A PI would have to lag by 90° or more at the crossover.
    #[error(
        "a PI cannot give {pm_deg:.0}° phase margin at {crossover_rad_s:.3} rad/s: the plant's \
         phase there is {phase_deg:.1}° and a PI lags by less than 90°; choose a lower \
         crossover or a smaller phase margin"
    )]
    NeedsTooMuchLag {
        /// Requested phase margin, degrees.
        pm_deg: f64,
        /// Crossover, rad/s.
        crossover_rad_s: f64,
        /// The plant's phase at the crossover, degrees.
        phase_deg: f64,
    },
    /// The standing motor does not break away on the pressure ramp.
    #[error("the motor does not start on a ramp to {p_max_mpa:.3} MPa under this load")]
    NoStart {
        /// Top of the ramp, MPa absolute.
        p_max_mpa: f64,
    },
    /// No speed of the start-up grid has a steady supply pressure on the ramp.
    #[error("no steady speed on the ramp")]
    NoSteadyOnRamp,
    /// No steady state with a throttle fitted.
    #[error("{port} throttle C = {c_m3_s_pa:.3e} m3/(s*Pa): {source}")]
    Throttled {
        /// `inlet` or `outlet`.
        port: &'static str,
        /// Throttle conductance, m3/(s*Pa).
        c_m3_s_pa: f64,
        /// The steady-state solver's error.
        source: SteadyError,
    },
    /// No steady state at an imposed speed of a torque-speed curve.
    #[error(
        "torque-speed curve, {port} throttle {}: at {speed_rpm:.0} rpm: {source}",
        throttle_name(.c_m3_s_pa)
    )]
    TorqueSpeed {
        /// `inlet` or `outlet`.
        port: &'static str,
        /// Throttle conductance, m3/(s*Pa); `None`: no throttle.
        c_m3_s_pa: Option<f64>,
        /// The imposed speed, rpm.
        speed_rpm: f64,
        /// The steady-state solver's error.
        source: SteadyError,
    },
    /// The loop cannot be settled at the set-point an option asks for.
    #[error("{}", self.message_with(&ControlOpt::field))]
    SetPoint {
        /// The option, e.g. [`ControlOpt::StepFrom`].
        option: ControlOpt,
        /// The value given, rpm.
        value: f64,
        /// Why.
        source: Box<ControlError>,
    },
    /// The minimum-speed staircase could not be run from its start speed.
    #[error("{}", self.message_with(&ControlOpt::field))]
    StaircaseStart {
        /// Start speed, rpm.
        start_rpm: f64,
        /// Why.
        source: Box<ControlError>,
    },
    /// The designed PI does not settle in the check simulation (the message advises a larger
    /// [`ControlOpt::DesignPhaseMargin`] or a lower [`ControlOpt::DesignCrossover`]).
    #[error("{}", self.message_with(&ControlOpt::field))]
    NotSettled {
        /// Length of the check simulation, s.
        duration_s: f64,
        /// Mean error over its last 10 %, rpm.
        final_error_rpm: f64,
    },
}

impl ControlError {
    /// The option at fault: that of a bad value ([`ControlError::Settings`]) or of a
    /// set-point that cannot be settled ([`ControlError::SetPoint`]); `None` for the rest.
    pub fn option(&self) -> Option<ControlOpt> {
        match self {
            ControlError::Settings(e) => Some(e.option()),
            ControlError::SetPoint { option, .. } => Some(*option),
            _ => None,
        }
    }

    /// The message with every option it names called `name(option)` (e.g. the command
    /// line's flag); [`fmt::Display`] is `message_with(&ControlOpt::field)`.
    pub fn message_with(&self, name: &dyn Fn(ControlOpt) -> &'static str) -> String {
        match self {
            ControlError::Settings(e) => e.message_with(name),
            ControlError::SetPoint {
                option,
                value,
                source,
            } => format!("{} {value}: {}", name(*option), source.message_with(name)),
            ControlError::StaircaseStart { start_rpm, source } => format!(
                "closed loop started at {start_rpm:.0} rpm (1.25 x the open-loop minimum, at \
                 least 1000 rpm): {}",
                source.message_with(name)
            ),
            ControlError::NotSettled {
                duration_s,
                final_error_rpm,
            } => format!(
                "the designed loop does not settle in the {duration_s} s check simulation (final \
                 error {final_error_rpm:.1} rpm); try a larger {} or a lower {}",
                name(ControlOpt::DesignPhaseMargin),
                name(ControlOpt::DesignCrossover)
            ),
            // The other messages name no option (their `#[error]` text is their own, not
            // this function's: it may not be, or this would call itself).
            other => other.to_string(),
        }
    }
}

/// A throttle for messages: its conductance, or `none`.
fn throttle_name(c_m3_s_pa: &Option<f64>) -> String {
    c_m3_s_pa.map_or("none".to_string(), |c| format!("{c:.3e} m3/(s*Pa)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The messages name their options by field, or by any name `message_with` is given,
    /// nested errors too.
    #[test]
    fn messages_name_options_by_field_or_otherwise() {
        let e = ControlError::SetPoint {
            option: ControlOpt::StepFrom,
            value: 3.0,
            source: Box::new(ControlError::NotSettled {
                duration_s: 5.0,
                final_error_rpm: 12.0,
            }),
        };
        assert_eq!(e.option(), Some(ControlOpt::StepFrom));
        assert_eq!(
            e.to_string(),
            "StepOptions.from_rpm 3: the designed loop does not settle in the 5 s check \
             simulation (final error 12.0 rpm); try a larger DesignOptions.pm_deg or a lower \
             DesignOptions.crossover_hz"
        );
        assert_eq!(
            e.message_with(&ControlOpt::name),
            "from_rpm 3: the designed loop does not settle in the 5 s check simulation (final \
             error 12.0 rpm); try a larger pm_deg or a lower crossover_hz"
        );
        let e = SettingsError::BackCalculationWithoutGains;
        assert_eq!(e.option(), ControlOpt::PiAntiWindup);
        assert_eq!(
            e.message_with(&ControlOpt::name),
            "anti_windup back-calculation needs kp > 0 and ki > 0 (tracking time kp/ki)"
        );
    }
}
