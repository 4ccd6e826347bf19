//! The work of each command as a library function: typed options in, typed results out.
//!
//! Every task follows one pattern (linfa's `ParamGuard`, as `estimate::optimize::settings` does it):
//! an options struct with public fields and defaults (`FitOptions`, `DiagnoseOptions`,
//! `PredictOptions`, `SynthOptions`, `BatchOptions`, a `ControlStudy`), turned by `check()`
//! into settings with private fields (`FitSettings`, ...), so that a task never sees a bad
//! value. A bad value is an [`OptionError`] that names the option ([`Opt`]), shown as its
//! field (`FitOptions.bounds`); the command line shows its flag's name instead. Results are
//! types (`Fit`, `Diagnosis`, `Prediction`, `StudyResult`) that the report and file writers
//! consume.
//!
//! The command line calls these for one dataset and `batch` for every unit of a fleet, so
//! a unit of a batch leaves exactly the files, and the numbers, the command would.

pub(crate) mod control;
pub(crate) mod diagnose;
pub(crate) mod export;
pub mod fit;
mod option;
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
    displacement_first_line, displacement_start_line, fit, fit_to, page_displacement_of,
    pinning_lines, write_fit, write_fit_file, write_fit_to, Fit, FitError, FitObserver, FitOptions,
    FitPaths, FitSettings, FitWritten, ParamRange, Pinning, RangeSyntax,
};
pub use option::{Opt, OptionError};
pub use predict::{
    fit_atmosphere_pa, predict, predict_located, predict_observed, pressure_unit, pressure_units,
    source_name, write_prediction, PredictOptions, PredictSettings, PredictTaskError,
};
pub use simulate::{
    motor_for, simulated_tables, write_table, SimulateError, SimulatedColumn, SimulatedTable,
};
pub use synth::{synth_motor, write_synthetic, SynthOptions, SynthSettings, Synthesized};
