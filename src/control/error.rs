//! Why a control study could not be done: [`SettingsError`] for a bad option value, found
//! before any work, and [`ControlError`] for everything else. Options are named by their
//! field, `Type.field` (e.g. `ThrottleOptions.points`), as `task::OptionError` names them;
//! the command line shows its flags instead, Python its keywords.

use crate::data::fitfile::FitFileError;
use crate::numerics::ode::SolveError;
use crate::sim::steady::SteadyError;

/// A bad option value of a control study (a field of its `…Options`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SettingsError {
    /// A quantity that must be a finite number > 0.
    #[error("{option} {value}: must be a number > 0")]
    NotPositive {
        /// The option's field, e.g. `PiOptions.ts_ms`.
        option: &'static str,
        /// The value given.
        value: f64,
    },
    /// A quantity that must be a finite number ≥ 0.
    #[error("{option} {value}: must be a number >= 0")]
    Negative {
        /// The option's field, e.g. `GainOptions.kp`.
        option: &'static str,
        /// The value given.
        value: f64,
    },
    /// A quantity that must be finite (of either sign).
    #[error("{option} {value}: must be a number")]
    NotFinite {
        /// The option's field, e.g. `DisturbanceOptions.load_step_nm`.
        option: &'static str,
        /// The value given.
        value: f64,
    },
    /// An absolute pressure at or below atmosphere (101 325 Pa).
    #[error("{option} {value}: must be above atmospheric (0.101325)")]
    NotAboveAtmosphere {
        /// The option's field, e.g. `ThrottleOptions.p_supply_mpa`.
        option: &'static str,
        /// The value given, MPa absolute.
        value: f64,
    },
    /// The upper end of a range at or below its lower end.
    #[error("{option} {value}: must be larger than {lower}")]
    EmptyRange {
        /// The field of the upper end, e.g. `BodeOptions.f_max_hz`.
        option: &'static str,
        /// The value given.
        value: f64,
        /// The field of the lower end.
        lower: &'static str,
    },
    /// Too few grid points for the study.
    #[error("{option} {value}: must be at least {min}")]
    TooFewPoints {
        /// The option's field, e.g. `ThrottleOptions.points`.
        option: &'static str,
        /// The value given.
        value: usize,
        /// The least the study needs.
        min: usize,
    },
    /// An item of `ThrottleOptions.curves_m3_s_pa` that is neither `none` nor a number.
    #[error("ThrottleOptions.curves_m3_s_pa {0}: must be \"none\" or a conductance > 0")]
    NotAConductance(String),
    /// `ThrottleOptions.curves_m3_s_pa` without any item.
    #[error("ThrottleOptions.curves_m3_s_pa {0}: must be a non-empty list")]
    NoCurves(String),
    /// A controller sample time above 100 ms, ms.
    #[error("PiOptions.ts_ms {0}: must be at most 100 ms")]
    SampleTimeTooLong(f64),
    /// An unknown `PiOptions.anti_windup` scheme.
    #[error("PiOptions.anti_windup: {0}")]
    AntiWindup(#[from] UnknownAntiWindup),
    /// Back-calculation needs both gains for its tracking time K_p/K_i.
    #[error(
        "PiOptions.anti_windup back-calculation needs GainOptions.kp > 0 and GainOptions.ki > 0 \
         (tracking time kp/ki)"
    )]
    BackCalculationWithoutGains,
    /// An unknown effect in `MotorOptions.effects` (the model's message).
    #[error("MotorOptions.effects: {0}")]
    Effects(#[from] crate::model::effects::UnknownEffect),
    /// A step time at or after the end of the scenario.
    #[error("{option} {value}: must be before {end}")]
    StepAfterEnd {
        /// The field of the step time, e.g. `StepOptions.t_step_s`.
        option: &'static str,
        /// The value given, s.
        value: f64,
        /// The field of the scenario's length, e.g. `StepOptions.duration_s`.
        end: &'static str,
    },
    /// `MinSpeedOptions.factor` outside (0, 1).
    #[error("MinSpeedOptions.factor {0}: must be between 0 and 1")]
    Factor(f64),
    /// `MinSpeedOptions.stage_s` not longer than the hold window plus 1 s, s.
    #[error("MinSpeedOptions.stage_s {0}: must be longer than 3 s")]
    StageTooShort(f64),
    /// `DesignOptions.pm_deg` outside (0, 90).
    #[error("DesignOptions.pm_deg {0}: must be between 0 and 90")]
    PhaseMargin(f64),
}

/// An anti-windup scheme that is not one of `conditional`, `back-calculation`, `none`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown anti-windup '{0}' (known: conditional, back-calculation, none)")]
pub struct UnknownAntiWindup(pub String);

/// Why a control study failed.
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
    #[error("{option} {value}: {source}")]
    SetPoint {
        /// The option's field, e.g. `StepOptions.from_rpm`.
        option: &'static str,
        /// The value given, rpm.
        value: f64,
        /// Why.
        source: Box<ControlError>,
    },
    /// The minimum-speed staircase could not be run from its start speed.
    #[error(
        "closed loop started at {start_rpm:.0} rpm (1.25 x the open-loop minimum, at least 1000 \
         rpm): {source}"
    )]
    StaircaseStart {
        /// Start speed, rpm.
        start_rpm: f64,
        /// Why.
        source: Box<ControlError>,
    },
    /// The designed PI does not settle in the check simulation.
    #[error(
        "the designed loop does not settle in the {duration_s} s check simulation (final error \
         {final_error_rpm:.1} rpm); try a larger DesignOptions.pm_deg or a lower \
         DesignOptions.crossover_hz"
    )]
    NotSettled {
        /// Length of the check simulation, s.
        duration_s: f64,
        /// Mean error over its last 10 %, rpm.
        final_error_rpm: f64,
    },
}

/// A throttle for messages: its conductance, or `none`.
fn throttle_name(c_m3_s_pa: &Option<f64>) -> String {
    c_m3_s_pa.map_or("none".to_string(), |c| format!("{c:.3e} m3/(s*Pa)"))
}
