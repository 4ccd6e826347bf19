//! The control studies' options as values ([`ControlOpt`]), as `task::Opt` for the tasks.
//!
//! A message of the control layer names an option by its field (`StepOptions.t_step_s`,
//! what a library user sets); [`SettingsError::message_with`] and
//! [`ControlError::message_with`] name it otherwise, so that the command line can show its
//! flag (`--t-step-s`) and Python its keyword (`t_step_s`) by a `match` on the
//! [`ControlOpt`], without rewriting text.
//!
//! [`SettingsError::message_with`]: crate::control::SettingsError::message_with
//! [`ControlError::message_with`]: crate::control::ControlError::message_with

use std::fmt;

/// An option of a control study: a field of one of the `…Options` structs of
/// `control::study` (`MotorOptions`, `ValveOptions`, `PiOptions`, `GainOptions` and each
/// study's own). Displayed as the field's name (`StepOptions.t_step_s`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ControlOpt {
    /// `BodeOptions.p_mean_mpa`.
    BodePMean,
    /// `BodeOptions.f_min_hz`.
    BodeFMin,
    /// `BodeOptions.f_max_hz`.
    BodeFMax,
    /// `BodeOptions.points`.
    BodePoints,
    /// `ThrottleOptions.p_supply_mpa`.
    ThrottlePSupply,
    /// `ThrottleOptions.c_min_m3_s_pa`.
    ThrottleCMin,
    /// `ThrottleOptions.c_max_m3_s_pa`.
    ThrottleCMax,
    /// `ThrottleOptions.curves_m3_s_pa`.
    ThrottleCurves,
    /// `ThrottleOptions.points`.
    ThrottlePoints,
    /// `StepOptions.from_rpm`.
    StepFrom,
    /// `StepOptions.to_rpm`.
    StepTo,
    /// `StepOptions.t_step_s`.
    StepTStep,
    /// `StepOptions.duration_s`.
    StepDuration,
    /// `DisturbanceOptions.rpm`.
    DisturbanceRpm,
    /// `DisturbanceOptions.load_step_nm`.
    DisturbanceLoadStep,
    /// `DisturbanceOptions.t_step_s`.
    DisturbanceTStep,
    /// `DisturbanceOptions.duration_s`.
    DisturbanceDuration,
    /// `MinSpeedOptions.p_max_mpa`.
    MinSpeedPMax,
    /// `MinSpeedOptions.ramp_s`.
    MinSpeedRamp,
    /// `MinSpeedOptions.factor`.
    MinSpeedFactor,
    /// `MinSpeedOptions.floor_rpm`.
    MinSpeedFloor,
    /// `MinSpeedOptions.stage_s`.
    MinSpeedStage,
    /// `DesignOptions.pm_deg`.
    DesignPhaseMargin,
    /// `DesignOptions.crossover_hz`.
    DesignCrossover,
    /// `DesignOptions.p_mean_mpa`.
    DesignPMean,
    /// `DesignOptions.step_rpm`.
    DesignStep,
    /// `DesignOptions.duration_s`.
    DesignDuration,
    /// `MotorOptions.params`.
    MotorParams,
    /// `MotorOptions.effects`.
    MotorEffects,
    /// `MotorOptions.brake_nm_s_rad`.
    MotorBrake,
    /// `ValveOptions.tau_s`.
    ValveTau,
    /// `ValveOptions.u_max_v`.
    ValveUMax,
    /// `ValveOptions.p_max_bar_g`.
    ValvePMax,
    /// `PiOptions.ts_ms`.
    PiSampleTime,
    /// `PiOptions.speed_unit_rpm`.
    PiSpeedUnit,
    /// `PiOptions.anti_windup`.
    PiAntiWindup,
    /// `GainOptions.kp`.
    GainKp,
    /// `GainOptions.ki`.
    GainKi,
}

impl ControlOpt {
    /// Every option.
    pub const ALL: &'static [ControlOpt] = &[
        ControlOpt::BodePMean,
        ControlOpt::BodeFMin,
        ControlOpt::BodeFMax,
        ControlOpt::BodePoints,
        ControlOpt::ThrottlePSupply,
        ControlOpt::ThrottleCMin,
        ControlOpt::ThrottleCMax,
        ControlOpt::ThrottleCurves,
        ControlOpt::ThrottlePoints,
        ControlOpt::StepFrom,
        ControlOpt::StepTo,
        ControlOpt::StepTStep,
        ControlOpt::StepDuration,
        ControlOpt::DisturbanceRpm,
        ControlOpt::DisturbanceLoadStep,
        ControlOpt::DisturbanceTStep,
        ControlOpt::DisturbanceDuration,
        ControlOpt::MinSpeedPMax,
        ControlOpt::MinSpeedRamp,
        ControlOpt::MinSpeedFactor,
        ControlOpt::MinSpeedFloor,
        ControlOpt::MinSpeedStage,
        ControlOpt::DesignPhaseMargin,
        ControlOpt::DesignCrossover,
        ControlOpt::DesignPMean,
        ControlOpt::DesignStep,
        ControlOpt::DesignDuration,
        ControlOpt::MotorParams,
        ControlOpt::MotorEffects,
        ControlOpt::MotorBrake,
        ControlOpt::ValveTau,
        ControlOpt::ValveUMax,
        ControlOpt::ValvePMax,
        ControlOpt::PiSampleTime,
        ControlOpt::PiSpeedUnit,
        ControlOpt::PiAntiWindup,
        ControlOpt::GainKp,
        ControlOpt::GainKi,
    ];

    /// The field's name, `Type.field` (e.g. `StepOptions.t_step_s`), as messages give it.
    pub fn field(self) -> &'static str {
        match self {
            ControlOpt::BodePMean => "BodeOptions.p_mean_mpa",
            ControlOpt::BodeFMin => "BodeOptions.f_min_hz",
            ControlOpt::BodeFMax => "BodeOptions.f_max_hz",
            ControlOpt::BodePoints => "BodeOptions.points",
            ControlOpt::ThrottlePSupply => "ThrottleOptions.p_supply_mpa",
            ControlOpt::ThrottleCMin => "ThrottleOptions.c_min_m3_s_pa",
            ControlOpt::ThrottleCMax => "ThrottleOptions.c_max_m3_s_pa",
            ControlOpt::ThrottleCurves => "ThrottleOptions.curves_m3_s_pa",
            ControlOpt::ThrottlePoints => "ThrottleOptions.points",
            ControlOpt::StepFrom => "StepOptions.from_rpm",
            ControlOpt::StepTo => "StepOptions.to_rpm",
            ControlOpt::StepTStep => "StepOptions.t_step_s",
            ControlOpt::StepDuration => "StepOptions.duration_s",
            ControlOpt::DisturbanceRpm => "DisturbanceOptions.rpm",
            ControlOpt::DisturbanceLoadStep => "DisturbanceOptions.load_step_nm",
            ControlOpt::DisturbanceTStep => "DisturbanceOptions.t_step_s",
            ControlOpt::DisturbanceDuration => "DisturbanceOptions.duration_s",
            ControlOpt::MinSpeedPMax => "MinSpeedOptions.p_max_mpa",
            ControlOpt::MinSpeedRamp => "MinSpeedOptions.ramp_s",
            ControlOpt::MinSpeedFactor => "MinSpeedOptions.factor",
            ControlOpt::MinSpeedFloor => "MinSpeedOptions.floor_rpm",
            ControlOpt::MinSpeedStage => "MinSpeedOptions.stage_s",
            ControlOpt::DesignPhaseMargin => "DesignOptions.pm_deg",
            ControlOpt::DesignCrossover => "DesignOptions.crossover_hz",
            ControlOpt::DesignPMean => "DesignOptions.p_mean_mpa",
            ControlOpt::DesignStep => "DesignOptions.step_rpm",
            ControlOpt::DesignDuration => "DesignOptions.duration_s",
            ControlOpt::MotorParams => "MotorOptions.params",
            ControlOpt::MotorEffects => "MotorOptions.effects",
            ControlOpt::MotorBrake => "MotorOptions.brake_nm_s_rad",
            ControlOpt::ValveTau => "ValveOptions.tau_s",
            ControlOpt::ValveUMax => "ValveOptions.u_max_v",
            ControlOpt::ValvePMax => "ValveOptions.p_max_bar_g",
            ControlOpt::PiSampleTime => "PiOptions.ts_ms",
            ControlOpt::PiSpeedUnit => "PiOptions.speed_unit_rpm",
            ControlOpt::PiAntiWindup => "PiOptions.anti_windup",
            ControlOpt::GainKp => "GainOptions.kp",
            ControlOpt::GainKi => "GainOptions.ki",
        }
    }

    /// The field's own name, without its struct (e.g. `t_step_s`).
    pub fn name(self) -> &'static str {
        let field = self.field();
        field.split_once('.').map_or(field, |(_, name)| name)
    }

    /// The option whose [`ControlOpt::field`] is `field`.
    pub fn from_field(field: &str) -> Option<ControlOpt> {
        Self::ALL.iter().copied().find(|o| o.field() == field)
    }
}

impl fmt::Display for ControlOpt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.field())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_name_their_options_one_to_one() {
        for o in ControlOpt::ALL {
            assert_eq!(ControlOpt::from_field(o.field()), Some(*o));
            assert_eq!(o.to_string(), o.field());
            assert!(o.field().ends_with(&format!("Options.{}", o.name())), "{o}");
        }
        assert_eq!(ControlOpt::StepTStep.name(), "t_step_s");
    }
}
