//! The options of a batch run as given ([`BatchOptions`]), checked into [`BatchSettings`]
//! (linfa's `ParamGuard` pattern, as every task's options).

use super::plan::Shard;
use super::run::{run, RunOptions, RunOutcome};
use super::{BatchError, Manifest};
use crate::task::{Opt, OptionError};
use std::path::PathBuf;

/// How to run a shard of a batch, as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct BatchOptions {
    /// The batch folder.
    pub out: PathBuf,
    /// Which shard (default: the whole batch).
    pub shard: Shard,
    /// Worker threads (`None`: one per core), ≥ 1; results do not depend on it.
    pub threads: Option<usize>,
    /// Run units that failed before again (by default a failed unit is finished).
    pub retry_failed: bool,
}

impl BatchOptions {
    /// The whole batch into `out`, one thread per core.
    pub fn new(out: impl Into<PathBuf>) -> Self {
        Self {
            out: out.into(),
            shard: Shard::ALL,
            threads: None,
            retry_failed: false,
        }
    }

    /// Checks `threads` (≥ 1).
    pub fn check(&self) -> Result<BatchSettings, OptionError> {
        if self.threads == Some(0) {
            return Err(OptionError::of(Opt::BatchThreads, " must be at least 1"));
        }
        Ok(BatchSettings(RunOptions {
            out: self.out.clone(),
            shard: self.shard,
            threads: self.threads,
            retry_failed: self.retry_failed,
        }))
    }
}

/// Checked [`BatchOptions`] (private fields).
#[derive(Debug, Clone)]
pub struct BatchSettings(RunOptions);

impl BatchSettings {
    /// The shard run.
    pub fn shard(&self) -> Shard {
        self.0.shard
    }

    /// Runs the settings' shard of `manifest` ([`super::run()`]).
    pub fn run(&self, manifest: &Manifest) -> Result<RunOutcome, BatchError> {
        run(manifest, &self.0)
    }
}
