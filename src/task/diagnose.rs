//! `diagnose` as a task: [`DiagnoseOptions`] → [`DiagnoseOptions::check`] →
//! [`DiagnoseSettings`]; load a dataset, diagnose it ([`diagnose`], [`diagnose_dataset`])
//! and write `diagnosis.json`, `extended.json`, `report.md` and the plots
//! ([`write_diagnosis`]), for the command line and `batch` alike.

use super::{Opt, OptionError};
use crate::data::dataset::{DataError, Dataset};
use crate::diagnose::Diagnosis;
use crate::diagnose::{diagnose_observed, DiagnoseError, DiagnoseObserver};
use crate::estimate::{Engine, EstimateError};
use crate::report::diagnose::ReportError;
use std::path::Path;

/// How much work a diagnosis does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Effort {
    /// The command line's: pairs always tried, held-out prediction of the three best
    /// candidates.
    #[default]
    Full,
    /// Reduced (tests, quick fleet scans): one baseline start, pairs only when needed,
    /// held-out prediction of the selected model only, the extended model's intervals from
    /// the curvature instead of profiles.
    Quick,
}

/// Options of a diagnosis as given (unchecked); [`DiagnoseOptions::check`] makes them
/// [`DiagnoseSettings`].
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Start points of the baseline fit (≥ 1): the rig's nominal motor plus Latin-hypercube
    /// starts.
    pub starts: usize,
    /// Seed of the start designs; a seed gives the same result whatever the thread count.
    pub seed: u64,
    /// Worker threads (`None`: one per core), ≥ 1. Results do not depend on it.
    pub threads: Option<usize>,
    /// How much work.
    pub effort: Effort,
}

impl Default for DiagnoseOptions {
    /// The command line's defaults: 4 starts, seed 1, full effort.
    fn default() -> Self {
        Self {
            starts: 4,
            seed: 1,
            threads: None,
            effort: Effort::Full,
        }
    }
}

impl DiagnoseOptions {
    /// Checks `starts` and `threads` (≥ 1).
    pub fn check(&self) -> Result<DiagnoseSettings, OptionError> {
        if self.starts == 0 {
            return Err(OptionError::of(Opt::DiagnoseStarts, " must be at least 1"));
        }
        if self.threads == Some(0) {
            return Err(OptionError::of(Opt::DiagnoseThreads, " must be at least 1"));
        }
        let mut engine = match self.effort {
            Effort::Full => crate::diagnose::DiagnoseOptions::full(self.starts, self.seed),
            Effort::Quick => crate::diagnose::DiagnoseOptions {
                starts: self.starts,
                ..crate::diagnose::DiagnoseOptions::quick(self.seed)
            },
        };
        engine.threads = self.threads;
        Ok(DiagnoseSettings {
            options: self.clone(),
            engine,
        })
    }
}

/// Checked [`DiagnoseOptions`]: private fields, read through the getters.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseSettings {
    options: DiagnoseOptions,
    engine: crate::diagnose::DiagnoseOptions,
}

impl DiagnoseSettings {
    /// The options these settings were checked from.
    pub fn options(&self) -> &DiagnoseOptions {
        &self.options
    }
    /// Worker threads (`None`: one per core).
    pub fn threads(&self) -> Option<usize> {
        self.options.threads
    }
    /// The diagnosis layer's own settings (budgets of every stage) for this effort.
    pub fn engine_options(&self) -> &crate::diagnose::DiagnoseOptions {
        &self.engine
    }
}

/// Why a diagnosis task failed (each message is the wrapped error's own, located where the
/// data layer knows the place).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DiagnoseTaskError {
    /// An option is bad (named by its field).
    #[error(transparent)]
    Option(#[from] OptionError),
    /// The thread pool cannot be built.
    #[error(transparent)]
    Engine(#[from] EstimateError),
    /// The dataset cannot be read.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The diagnosis failed.
    #[error(transparent)]
    Diagnose(#[from] DiagnoseError),
    /// Its results cannot be written.
    #[error(transparent)]
    Report(#[from] ReportError),
}

/// Loads the dataset at `dataset` and diagnoses it on a thread pool of its own.
pub fn diagnose(
    dataset: &Path,
    settings: &DiagnoseSettings,
    observer: &dyn DiagnoseObserver,
) -> Result<Diagnosis, DiagnoseTaskError> {
    let engine = Engine::with_threads(settings.threads())?;
    let ds = Dataset::load(dataset)?;
    diagnose_dataset(&engine, &ds, settings, observer)
}

/// Diagnoses a loaded dataset on a thread pool the caller owns.
pub fn diagnose_dataset(
    engine: &Engine,
    ds: &Dataset,
    settings: &DiagnoseSettings,
    observer: &dyn DiagnoseObserver,
) -> Result<Diagnosis, DiagnoseTaskError> {
    Ok(diagnose_observed(
        ds,
        settings.engine_options(),
        engine,
        observer,
    )?)
}

/// Writes a diagnosis into the folder `out`: `diagnosis.json`, `extended.json`,
/// `report.md` and the plots.
pub fn write_diagnosis(d: &Diagnosis, out: &Path) -> Result<(), DiagnoseTaskError> {
    crate::report::diagnose::write_all(d, out)?;
    Ok(())
}

/// Diagnoses the dataset at `dataset` on `engine` and writes the results into `out` (a
/// unit of a batch).
pub(crate) fn diagnose_to(
    engine: &Engine,
    dataset: &Path,
    settings: &DiagnoseSettings,
    observer: &dyn DiagnoseObserver,
    out: &Path,
) -> Result<Diagnosis, DiagnoseTaskError> {
    let ds = Dataset::load(dataset)?;
    let d = diagnose_dataset(engine, &ds, settings, observer)?;
    write_diagnosis(&d, out)?;
    Ok(d)
}
