//! `diagnose` as a task: load a dataset, diagnose it and write `diagnosis.json`,
//! `extended.json`, `report.md` and the plots, for the command line and `batch` alike.

use crate::data::dataset::{DataError, Dataset};
use crate::diagnose::Diagnosis;
use crate::diagnose::{diagnose_observed, DiagnoseError, DiagnoseObserver, DiagnoseOptions};
use crate::estimate::Engine;
use crate::report::diagnose::ReportError;
use std::path::{Path, PathBuf};

/// `vanefit diagnose` options (SPEC §6).
#[derive(clap::Args, Debug, Clone)]
pub struct DiagnoseArgs {
    /// Dataset folder (rig.toml and recordings).
    pub dataset: PathBuf,
    /// Start points of the baseline fit: the rig's nominal motor plus Latin-hypercube starts.
    #[arg(long, default_value_t = 4, value_parser = crate::task::at_least_one)]
    pub starts: usize,
    /// Seed of the start designs; a seed gives the same result whatever the thread count.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder: diagnosis.json, report.md and its SVG plots.
    #[arg(long)]
    pub out: PathBuf,
}

/// Why a diagnosis task failed (each message is the wrapped error's own, located where the
/// data layer knows the place).
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseTaskError {
    /// `starts` is 0.
    #[error("--starts must be at least 1")]
    NoStarts,
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

/// Diagnoses the dataset at `dataset` on `engine` and writes the results into `out`.
pub fn diagnose_to(
    engine: &Engine,
    dataset: &Path,
    opts: &DiagnoseOptions,
    observer: &dyn DiagnoseObserver,
    out: &Path,
) -> Result<Diagnosis, DiagnoseTaskError> {
    let ds = Dataset::load(dataset)?;
    diagnose_dataset_to(engine, &ds, opts, observer, out)
}

/// Diagnoses a loaded dataset on `engine` and writes the results into `out` (for callers
/// that load the dataset first, so that bad data is refused before `out` is created).
pub fn diagnose_dataset_to(
    engine: &Engine,
    ds: &Dataset,
    opts: &DiagnoseOptions,
    observer: &dyn DiagnoseObserver,
    out: &Path,
) -> Result<Diagnosis, DiagnoseTaskError> {
    if opts.starts == 0 {
        return Err(DiagnoseTaskError::NoStarts);
    }
    let d = diagnose_observed(ds, opts, engine, observer)?;
    crate::report::diagnose::write_all(&d, out)?;
    Ok(d)
}
