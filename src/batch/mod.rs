//! Fleets (docs/formats.md, "Contracts added later" and "Batches: manifest, unit folders,
//! summary"): one manifest, many datasets, the work split into units (dataset × task) that
//! run in deterministic shards on one machine or a Slurm cluster, each unit in its own
//! folder with a status file, resumable; `merge` collects the units into a fleet summary.
//!
//! The batch folder holds `batch.json` (what the batch is: its manifest, settings and every
//! unit, written by each shard alike), one folder per unit (`<dataset>/<task>/`, with
//! `status.json` and the task's own files) and, after `merge`, `summary.csv`, `summary.md`
//! and `fleet.svg`. A unit runs the same library function as its command (`task`), so a
//! unit's numbers are the command's, and results never depend on shards or threads.

pub(crate) mod manifest;
pub(crate) mod merge;
mod options;
pub mod plan;
mod progress;
pub(crate) mod run;
pub(crate) mod slurm;
pub(crate) mod status;

pub use manifest::{DatasetEntry, Manifest, ManifestError, TaskKind};
pub use slurm::{submit, SlurmError, SlurmOptions, Submitted};

pub use merge::{merge, summarize, MergeOutcome, Summary};
pub use options::{BatchOptions, BatchSettings};
pub use plan::{Shard, Unit};
pub use run::{run, RunOptions, RunOutcome};

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Why a folder's `batch.json` is not a batch record.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NotABatchWhy {
    /// It cannot be read.
    #[error(transparent)]
    Read(#[from] std::io::Error),
    /// It is not a record in JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// It is a record of another format (the format it names).
    #[error("format '{0}'")]
    Format(String),
}

/// Why a batch or a merge could not run (a unit's own failure is no error: it is recorded).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BatchError {
    /// The manifest is unusable.
    #[error(transparent)]
    Manifest(#[from] ManifestError),
    /// A file of the batch folder cannot be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The batch folder was made by another manifest or other settings.
    #[error("{}: holds a batch of other datasets, tasks or settings (made from {made_from}); use another --out or remove the folder", path.display())]
    OtherBatch {
        /// The batch folder.
        path: PathBuf,
        /// The manifest that made it.
        made_from: String,
    },
    /// `merge` of a folder that no batch wrote.
    #[error("{}: not a batch folder (no readable batch.json: {why}); run `vanefit batch` into it first", path.display())]
    NotABatch {
        /// The folder.
        path: PathBuf,
        /// What is wrong with its record.
        why: NotABatchWhy,
    },
    /// The worker pool cannot be built.
    #[error(transparent)]
    Engine(#[from] crate::estimate::EstimateError),
    /// The fleet plot cannot be drawn.
    #[error(transparent)]
    Plot(#[from] crate::report::plot::PlotError),
    /// Submitting to Slurm failed.
    #[error(transparent)]
    Slurm(#[from] slurm::SlurmError),
}

/// The format of `batch.json`.
const BATCH_FORMAT: &str = "vanefit.batch/1";

/// `batch.json`: what the batch in a folder is. Every shard writes the same record, and
/// refuses to run into a folder whose record differs (other datasets, tasks or settings),
/// so that one folder never mixes two batches.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BatchRecord {
    /// `BATCH_FORMAT`.
    pub format: String,
    /// The manifest (absolute path).
    pub manifest: PathBuf,
    /// The task tables as written in the manifest.
    pub settings: serde_json::Value,
    /// Every unit of the batch, in order.
    pub units: Vec<Unit>,
}

impl BatchRecord {
    /// The record of `manifest`'s batch.
    pub fn of(manifest: &Manifest) -> Self {
        Self {
            format: BATCH_FORMAT.into(),
            manifest: manifest.path.clone(),
            settings: manifest.settings.clone(),
            units: plan::units(manifest),
        }
    }

    /// Reads `out/batch.json`.
    pub fn read(out: &Path) -> Result<Self, BatchError> {
        let path = out.join("batch.json");
        let not_a_batch = |why: NotABatchWhy| BatchError::NotABatch {
            path: out.to_path_buf(),
            why,
        };
        let text = std::fs::read_to_string(&path).map_err(|e| not_a_batch(e.into()))?;
        Self::parse(out, &text)
    }

    /// The record whose `batch.json` in `out` holds `text` (as [`BatchRecord::read`]).
    pub fn parse(out: &Path, text: &str) -> Result<Self, BatchError> {
        let not_a_batch = |why: NotABatchWhy| BatchError::NotABatch {
            path: out.to_path_buf(),
            why,
        };
        let record: Self = serde_json::from_str(text).map_err(|e| not_a_batch(e.into()))?;
        if record.format != BATCH_FORMAT {
            return Err(not_a_batch(NotABatchWhy::Format(record.format)));
        }
        Ok(record)
    }

    /// Writes the record into `out`, or checks that the one there is the same (the manifest
    /// file may have moved; what counts is the units and the settings).
    pub fn claim(&self, out: &Path) -> Result<(), BatchError> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| BatchError::Io { path, source }
        };
        std::fs::create_dir_all(out).map_err(io(out))?;
        if let Ok(existing) = Self::read(out) {
            if existing.units != self.units || existing.settings != self.settings {
                return Err(BatchError::OtherBatch {
                    path: out.to_path_buf(),
                    made_from: existing.manifest.display().to_string(),
                });
            }
            return Ok(());
        }
        let path = out.join("batch.json");
        let text = serde_json::to_string_pretty(self).expect("plain data") + "\n";
        crate::io::write_atomic(&path, text.as_bytes()).map_err(io(&path))
    }
}
