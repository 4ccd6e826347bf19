//! The tasks' options as values ([`Opt`]) and the error of a bad one ([`OptionError`]).
//!
//! A message names an option by its field (`FitOptions.starts`, what a library user sets);
//! [`OptionError::message_with`] names it otherwise, so that the command line can show its
//! flag (`--starts`) by a `match` on the [`Opt`], without rewriting text.

use std::fmt;

/// An option of a task: a field of its options struct (`FitOptions`, `DiagnoseOptions`,
/// `PredictOptions`, `SynthOptions`, `BatchOptions`) or an argument of a task function.
/// Displayed as the field's name (`FitOptions.starts`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Opt {
    /// `FitOptions.starts`.
    FitStarts,
    /// `FitOptions.threads`.
    FitThreads,
    /// `FitOptions.start_spread`.
    FitStartSpread,
    /// `FitOptions.bounds`.
    FitBounds,
    /// `FitOptions.estimate`.
    FitEstimate,
    /// `FitOptions.estimate`, `bounds` and `start_ranges` together (the parameter space
    /// they make).
    FitRanges,
    /// `DiagnoseOptions.starts`.
    DiagnoseStarts,
    /// `DiagnoseOptions.threads`.
    DiagnoseThreads,
    /// `PredictOptions.unit`.
    PredictUnit,
    /// `PredictOptions.pressures`.
    PredictPressures,
    /// `PredictOptions.reference`.
    PredictReference,
    /// `PredictOptions.inlet_nozzle_m3_s_pa`.
    PredictInletNozzle,
    /// `PredictOptions.outlet_nozzle_m3_s_pa`.
    PredictOutletNozzle,
    /// `PredictOptions.speed_grid_rpm`.
    PredictSpeedGrid,
    /// `PredictOptions.curve_points`.
    PredictCurvePoints,
    /// `PredictOptions.fixed_spread`.
    PredictFixedSpread,
    /// `PredictOptions.data`.
    PredictData,
    /// `PredictOptions.sampling.walkers`.
    PredictWalkers,
    /// `PredictOptions.sampling.steps`.
    PredictSteps,
    /// `PredictOptions.sampling.draws`.
    PredictDraws,
    /// `SynthOptions.pressures_bar_g`.
    SynthPressures,
    /// `SynthOptions.noise`.
    SynthNoise,
    /// `BatchOptions.threads`.
    BatchThreads,
    /// The `dataset` argument of `task::petab_problem`.
    ExportDataset,
}

impl Opt {
    /// The command line's flag that sets the option (`vanefit fit --starts`); a batch
    /// manifest's keys are the same options. Every option has one: a new option is a new arm.
    pub fn flag(self) -> &'static str {
        match self {
            Opt::FitStarts | Opt::DiagnoseStarts => "--starts",
            Opt::FitThreads | Opt::DiagnoseThreads | Opt::BatchThreads => "--threads",
            Opt::FitStartSpread => "--start-spread",
            Opt::FitBounds => "--bounds",
            Opt::FitEstimate => "--estimate",
            Opt::FitRanges => "--estimate/--bounds/--start-range",
            Opt::PredictUnit => "--unit",
            Opt::PredictPressures | Opt::SynthPressures => "--pressures",
            Opt::PredictReference => "--reference",
            Opt::PredictInletNozzle => "--inlet-nozzle",
            Opt::PredictOutletNozzle => "--outlet-nozzle",
            Opt::PredictSpeedGrid => "--speed-grid-rpm",
            Opt::PredictCurvePoints => "--curve-points",
            Opt::PredictFixedSpread => "--fixed-spread",
            Opt::PredictData => "--data",
            Opt::PredictWalkers => "--walkers",
            Opt::PredictSteps => "--steps",
            Opt::PredictDraws => "--draws",
            Opt::SynthNoise => "--noise",
            Opt::ExportDataset => "--dataset",
        }
    }

    /// Every option.
    pub const ALL: &'static [Opt] = &[
        Opt::FitStarts,
        Opt::FitThreads,
        Opt::FitStartSpread,
        Opt::FitBounds,
        Opt::FitEstimate,
        Opt::FitRanges,
        Opt::DiagnoseStarts,
        Opt::DiagnoseThreads,
        Opt::PredictUnit,
        Opt::PredictPressures,
        Opt::PredictReference,
        Opt::PredictInletNozzle,
        Opt::PredictOutletNozzle,
        Opt::PredictSpeedGrid,
        Opt::PredictCurvePoints,
        Opt::PredictFixedSpread,
        Opt::PredictData,
        Opt::PredictWalkers,
        Opt::PredictSteps,
        Opt::PredictDraws,
        Opt::SynthPressures,
        Opt::SynthNoise,
        Opt::BatchThreads,
        Opt::ExportDataset,
    ];

    /// The field's name, `Type.field` (e.g. `FitOptions.bounds`), as messages give it.
    pub fn field(self) -> &'static str {
        match self {
            Opt::FitStarts => "FitOptions.starts",
            Opt::FitThreads => "FitOptions.threads",
            Opt::FitStartSpread => "FitOptions.start_spread",
            Opt::FitBounds => "FitOptions.bounds",
            Opt::FitEstimate => "FitOptions.estimate",
            Opt::FitRanges => "FitOptions.estimate/bounds/start_ranges",
            Opt::DiagnoseStarts => "DiagnoseOptions.starts",
            Opt::DiagnoseThreads => "DiagnoseOptions.threads",
            Opt::PredictUnit => "PredictOptions.unit",
            Opt::PredictPressures => "PredictOptions.pressures",
            Opt::PredictReference => "PredictOptions.reference",
            Opt::PredictInletNozzle => "PredictOptions.inlet_nozzle_m3_s_pa",
            Opt::PredictOutletNozzle => "PredictOptions.outlet_nozzle_m3_s_pa",
            Opt::PredictSpeedGrid => "PredictOptions.speed_grid_rpm",
            Opt::PredictCurvePoints => "PredictOptions.curve_points",
            Opt::PredictFixedSpread => "PredictOptions.fixed_spread",
            Opt::PredictData => "PredictOptions.data",
            Opt::PredictWalkers => "PredictOptions.sampling.walkers",
            Opt::PredictSteps => "PredictOptions.sampling.steps",
            Opt::PredictDraws => "PredictOptions.sampling.draws",
            Opt::SynthPressures => "SynthOptions.pressures_bar_g",
            Opt::SynthNoise => "SynthOptions.noise",
            Opt::BatchThreads => "BatchOptions.threads",
            Opt::ExportDataset => "`dataset`",
        }
    }

    /// The option whose [`Opt::field`] is `field`.
    pub fn from_field(field: &str) -> Option<Opt> {
        Self::ALL.iter().copied().find(|o| o.field() == field)
    }
}

impl fmt::Display for Opt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.field())
    }
}

/// A bad value of an option. Its message is `before`, the option, `after` (e.g.
/// `FitOptions.starts must be at least 1`), with a second option after the first where
/// the fault is their combination (`A and B: ...`). [`fmt::Display`] names the options by
/// their fields; [`OptionError::message_with`] by any other names (the command line's
/// flags).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", render(*.opt, *.and, .before, .after, &Opt::field))]
pub struct OptionError {
    opt: Opt,
    and: Option<Opt>,
    before: String,
    after: String,
}

/// `before` + the option's name + ` and ` the second's + `after`.
fn render(
    opt: Opt,
    and: Option<Opt>,
    before: &str,
    after: &str,
    name: &dyn Fn(Opt) -> &'static str,
) -> String {
    match and {
        Some(other) => format!("{before}{} and {}{after}", name(opt), name(other)),
        None => format!("{before}{}{after}", name(opt)),
    }
}

impl OptionError {
    /// The message option + `after`, e.g. `(Opt::FitStarts, " must be at least 1")`.
    pub fn of(opt: Opt, after: impl Into<String>) -> Self {
        Self {
            opt,
            and: None,
            before: String::new(),
            after: after.into(),
        }
    }

    /// The message `before` + option + `after` (the option named within the sentence).
    pub fn of_within(opt: Opt, before: impl Into<String>, after: impl Into<String>) -> Self {
        Self {
            opt,
            and: None,
            before: before.into(),
            after: after.into(),
        }
    }

    /// The message `opt` and `other` + `after`: two options that may not go together.
    pub fn pair(opt: Opt, other: Opt, after: impl Into<String>) -> Self {
        Self {
            opt,
            and: Some(other),
            before: String::new(),
            after: after.into(),
        }
    }

    /// The option at fault (the first of two).
    pub fn opt(&self) -> Opt {
        self.opt
    }

    /// The field of the option at fault, `Type.field` (e.g. `FitOptions.bounds`).
    pub fn field(&self) -> &'static str {
        self.opt.field()
    }

    /// The message with the option at fault called `name` (a second option keeps its
    /// field's name).
    pub fn message_as(&self, name: &str) -> String {
        match self.and {
            Some(other) => format!("{}{name} and {other}{}", self.before, self.after),
            None => format!("{}{name}{}", self.before, self.after),
        }
    }

    /// The message with every option it names called `name(option)` (e.g. the command
    /// line's flag).
    pub fn message_with(&self, name: &dyn Fn(Opt) -> &'static str) -> String {
        render(self.opt, self.and, &self.before, &self.after, name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_name_their_options_one_to_one() {
        for o in Opt::ALL {
            assert_eq!(Opt::from_field(o.field()), Some(*o));
            assert_eq!(o.to_string(), o.field());
        }
    }

    #[test]
    fn messages_name_options_by_field_or_otherwise() {
        let e = OptionError::pair(Opt::PredictInletNozzle, Opt::PredictOutletNozzle, ": one");
        assert_eq!(
            e.to_string(),
            "PredictOptions.inlet_nozzle_m3_s_pa and PredictOptions.outlet_nozzle_m3_s_pa: one"
        );
        assert_eq!(
            e.message_as("inlet_nozzle_m3_s_pa"),
            "inlet_nozzle_m3_s_pa and PredictOptions.outlet_nozzle_m3_s_pa: one"
        );
        let short = |o: Opt| o.field().rsplit('.').next().unwrap_or_default();
        assert_eq!(
            e.message_with(&short),
            "inlet_nozzle_m3_s_pa and outlet_nozzle_m3_s_pa: one"
        );
        let e = OptionError::of_within(Opt::FitEstimate, "'x' is not in ", "");
        assert_eq!(e.opt(), Opt::FitEstimate);
        assert_eq!(e.to_string(), "'x' is not in FitOptions.estimate");
    }
}
