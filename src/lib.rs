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
//! {`diagnose`, `control`, `predict`, `export`} → `report` → `task` → `batch` (and the
//! command line, part of the `vanefit` binary, on top). SI units everywhere inside; `units`
//! converts at the file edge. They stay public for what builds on the model directly (the
//! tests, benches, fuzz targets and the Python package): the simulator, the cost, the
//! likelihood, the optimiser. Their items may change more often than the front door's.

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
pub mod predict;
pub mod prelude;
pub mod report;
pub mod sim;
pub mod task;
pub mod units;

pub use batch::{BatchOptions, BatchSettings, Manifest};
pub use data::dataset::Dataset;
pub use data::fitfile::FitFile;
pub use diagnose::{DiagnoseObserver, Diagnosis};
pub use estimate::multistart::Silent;
pub use estimate::RunObserver;
pub use model::effects::{Effect, EffectSet};
pub use model::motor::Motor;
pub use model::params::MotorParams;
pub use predict::Prediction;
pub use task::control::{run_study, write_study, CheckedStudy, ControlStudy, Study, StudyResult};
pub use task::diagnose::{
    diagnose, write_diagnosis, DiagnoseOptions, DiagnoseSettings, DiagnoseTaskError, Effort,
};
pub use task::fit::{fit, write_fit, Fit, FitError, FitObserver, FitOptions, FitSettings};
pub use task::predict::{
    predict, write_prediction, PredictOptions, PredictSettings, PredictTaskError,
};
pub use task::simulate::{motor_for, simulated_tables, SimulatedTable};
pub use task::synth::{synth_motor, write_synthetic, SynthOptions, SynthSettings};
pub use task::OptionError;
