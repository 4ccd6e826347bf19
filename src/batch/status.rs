//! A unit's status file (`<dataset>/<task>/status.json`), written atomically: `running` when
//! the unit starts, `done` or `failed` (with the reason) when it ends. A unit whose file says
//! `done` or `failed` is finished and skipped; one that says `running` was interrupted and
//! runs again (a fit resumes from its starts file).

use serde::{Deserialize, Serialize};
use std::path::Path;

/// The format of status files.
const STATUS_FORMAT: &str = "vanefit.unit/1";

/// Where a unit is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum State {
    /// Not started (no status file).
    Pending,
    /// Started and not finished: running now, or interrupted.
    Running,
    /// Finished with its results.
    Done,
    /// Finished without results; the message says why.
    Failed,
}

impl State {
    /// The name in status files and `summary.csv`.
    pub fn id(self) -> &'static str {
        match self {
            State::Pending => "pending",
            State::Running => "running",
            State::Done => "done",
            State::Failed => "failed",
        }
    }
}

/// The contents of a status file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct UnitStatus {
    /// [`STATUS_FORMAT`].
    pub format: String,
    /// The dataset's name.
    pub dataset: String,
    /// The task.
    pub task: String,
    /// Where the unit is.
    pub status: State,
    /// A done unit's result in one line, or a failed unit's reason.
    pub message: String,
    /// Seconds the last attempt took (0 while running).
    pub wall_s: f64,
}

impl UnitStatus {
    /// A status of `dataset`/`task`.
    pub fn new(dataset: &str, task: &str, status: State, message: String, wall_s: f64) -> Self {
        Self {
            format: STATUS_FORMAT.into(),
            dataset: dataset.into(),
            task: task.into(),
            status,
            message,
            wall_s,
        }
    }

    /// Reads the status file in `folder`; `None` when there is none or it cannot be read
    /// (a unit without a readable status is not finished: it runs).
    pub fn read(folder: &Path) -> Option<Self> {
        let text = std::fs::read_to_string(folder.join("status.json")).ok()?;
        Self::parse(&text)
    }

    /// A status file's text read; `None` when it is not one (as [`UnitStatus::read`]).
    pub fn parse(text: &str) -> Option<Self> {
        serde_json::from_str(text).ok()
    }

    /// Writes the status file into `folder` atomically.
    pub fn write(&self, folder: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string_pretty(self).expect("plain data") + "\n";
        crate::io::write_atomic(&folder.join("status.json"), text.as_bytes())
    }
}
