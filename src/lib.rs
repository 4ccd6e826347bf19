#![warn(missing_docs)]
#![deny(rustdoc::broken_intra_doc_links)]
//! vanefit: estimate the physical parameters of pneumatic vane motors from datasheets and
//! test-rig recordings, and find the physics that a model leaves out.
//!
//! # The front door
//!
//! Each piece of work is a task with typed options in and a typed result out. Options are
//! plain structs with public fields and defaults; `check()` turns them into settings that
//! the task accepts, or an [`OptionError`] that names the field. Results are types that
//! the report and file writers take. `use vanefit::prelude::*;` brings all of it in.
//!
//! | work | options → settings | task | result | files |
//! |---|---|---|---|---|
//! | fit a dataset | [`FitOptions`] → [`FitSettings`] | [`fit()`] | [`Fit`] | [`write_fit`] |
//! | find missing physics | [`DiagnoseOptions`] → [`DiagnoseSettings`] | [`diagnose()`] | [`Diagnosis`] | [`write_diagnosis`] |
//! | predict a fit elsewhere | [`PredictOptions`] → [`PredictSettings`] | [`predict()`] | [`Prediction`] | [`write_prediction`] |
//! | a speed-control study | [`ControlStudy`] → [`CheckedStudy`] | [`run_study`] | [`StudyResult`] | [`write_study`] |
//! | a synthetic dataset | [`SynthOptions`] → [`SynthSettings`] | [`synth_motor`] | the motor | [`write_synthetic`] |
//! | a fleet | [`BatchOptions`] → [`BatchSettings`] | [`BatchSettings::run`] | [`batch::RunOutcome`] | unit folders |
//!
//! ```no_run
//! use vanefit::prelude::*;
//!
//! let settings = FitOptions { starts: 8, ..FitOptions::default() }.check()?;
//! let fit = vanefit::fit(
//!     std::path::Path::new("measurements/ar034-synthetic"),
//!     &settings,
//!     None,
//!     &Silent,
//! )?;
//! println!("χ² {:.1} over {} points", fit.outcome.chi2, fit.outcome.n_points);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! Progress reaches the caller through observer traits ([`FitObserver`], whose
//! [`RunObserver::keep_going`] can stop a fit between rounds of starts, and
//! [`DiagnoseObserver`]); [`Silent`] observes nothing.
//!
//! # The layers (advanced)
//!
//! Below the front door the folders are the layers, each depending only on the ones before
//! it: `units` → `io` → `numerics` → `model` → `sim` → `data` → `objective` → `estimate` →
//! {`diagnose`, `control`, `predict`, `export`} → `plan` → `report` → `task` → `batch` (and the
//! command line, part of the `vanefit` binary, on top). SI units everywhere inside; `units`
//! converts at the file edge. Each layer is a namespace for what builds on the model
//! directly (the command line, tests, benches, fuzz targets, the Python package and the FMU
//! library): the simulator, the cost, the likelihood, the optimiser. Its files are private;
//! the layer's root re-exports the items used outside it and every type its public items
//! mention, so a path is `vanefit::<layer>::<Item>` (`vanefit::model::Motor`,
//! `vanefit::estimate::FitOutcome`). A few submodules stay public because their functions
//! are named by the module (`sim::steady::free`, `estimate::multistart::run`,
//! `batch::plan::units`, `diagnose::discover::formula`, `export::petab::write`, the writers
//! of `report::{fit, predict, diagnose, control}`). Items below the front door may change
//! more often than the front door's.

pub mod batch;
pub mod control;
pub mod data;
pub mod diagnose;
pub mod estimate;
pub mod export;
pub mod io;
pub mod model;
pub mod numerics;
pub mod objective;
pub mod plan;
pub mod predict;
pub mod prelude;
pub mod report;
pub mod sim;
pub mod task;
pub mod units;

pub use batch::{BatchOptions, BatchSettings, Manifest};
pub use data::{Dataset, FitFile};
pub use diagnose::{DiagnoseObserver, Diagnosis};
pub use estimate::{RunObserver, Silent};
pub use model::{Effect, EffectSet, Motor, MotorParams};
pub use predict::Prediction;
// The layers `diagnose` and `predict` share their names with these two functions.
pub use task::diagnose::diagnose;
pub use task::predict::predict;
pub use task::{
    fit, motor_for, run_study, simulated_tables, synth_motor, write_diagnosis, write_fit,
    write_prediction, write_study, write_synthetic, CheckedStudy, ControlStudy, DiagnoseOptions,
    DiagnoseSettings, DiagnoseTaskError, Effort, Fit, FitError, FitObserver, FitOptions,
    FitSettings, Opt, OptionError, PredictOptions, PredictSettings, PredictTaskError,
    SimulatedTable, Study, StudyResult, SynthOptions, SynthSettings,
};
