//! The work of each command as a library function: typed options in, typed results out.
//!
//! Every task follows one pattern (linfa's `ParamGuard`, as `estimate::settings` does it):
//! an options struct with public fields and defaults (`FitOptions`, `DiagnoseOptions`,
//! `PredictOptions`, `SynthOptions`, `BatchOptions`, a `ControlStudy`), turned by `check()`
//! into settings with private fields (`FitSettings`, ...), so that a task never sees a bad
//! value. A bad value is an [`OptionError`] that names the field (`FitOptions.bounds`);
//! the command line shows it under its flag's name instead. Results are types (`Fit`,
//! `Diagnosis`, `Prediction`, `StudyResult`) that the report and file writers consume.
//!
//! The command line calls these for one dataset and `batch` for every unit of a fleet, so
//! a unit of a batch leaves exactly the files, and the numbers, the command would.

pub(crate) mod control;
pub(crate) mod diagnose;
pub(crate) mod export;
pub(crate) mod fit;
pub(crate) mod predict;
pub(crate) mod simulate;
pub(crate) mod synth;

pub use crate::io::side_path;
pub use control::{run_study, write_study, CheckedStudy, ControlStudy, Study, StudyResult};
pub use diagnose::{
    diagnose, diagnose_dataset, write_diagnosis, DiagnoseOptions, DiagnoseSettings,
    DiagnoseTaskError, Effort,
};
pub use export::{export_fmu, petab_problem, ExportError, FmuExport, FmuOptions, PetabProblem};
pub use fit::{
    displacement_first_line, fit, page_displacement_of, pinning_lines, write_fit, Fit, FitError,
    FitObserver, FitOptions, FitSettings, FitWritten, ParamRange, Pinning, RangeSyntax,
};
pub use predict::{
    fit_atmosphere_pa, predict, predict_observed, pressure_unit, pressure_units, source_name,
    write_prediction, PredictOptions, PredictSettings, PredictTaskError,
};
pub use simulate::{
    motor_for, simulated_tables, write_table, SimulateError, SimulatedColumn, SimulatedTable,
};
pub use synth::{synth_motor, write_synthetic, SynthOptions, SynthSettings, Synthesized};

/// A bad value of an option, named by its field (`FitOptions.starts`). Its message is
/// `before`, the field's name, `after` (e.g. `FitOptions.starts must be at least 1`);
/// [`OptionError::message_as`] gives the same message under another name (a flag).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{before}{field}{after}")]
pub struct OptionError {
    field: &'static str,
    before: String,
    after: String,
}

impl OptionError {
    /// The message `field` + `after`, e.g. `("FitOptions.starts", " must be at least 1")`.
    pub fn new(field: &'static str, after: impl Into<String>) -> Self {
        Self {
            field,
            before: String::new(),
            after: after.into(),
        }
    }

    /// The message `before` + `field` + `after` (the field named within the sentence).
    pub fn within(
        field: &'static str,
        before: impl Into<String>,
        after: impl Into<String>,
    ) -> Self {
        Self {
            field,
            before: before.into(),
            after: after.into(),
        }
    }

    /// The field, `Type.field` (e.g. `FitOptions.bounds`).
    pub fn field(&self) -> &'static str {
        self.field
    }

    /// The message with the field called `name` (e.g. the command line's `--bounds`).
    pub fn message_as(&self, name: &str) -> String {
        format!("{}{name}{}", self.before, self.after)
    }
}
