//! The history of a run (pyPESTO's `history`): an append-only results file of finished
//! starts (JSON lines after a header naming the run), read back to resume.

use super::StartResult;
use crate::estimate::error::{EstimateError, ForeignStart, ResultsLineError};
use crate::estimate::optimize::settings::MultiStartSettings;
use crate::estimate::problem::space::ParamSpace;
use serde::{Deserialize, Serialize};
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

/// Header line of a results file: what run it belongs to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Header {
    format: String,
    seed: u64,
    starts: usize,
    parameters: Vec<String>,
    effects: Vec<String>,
}

const RESULTS_FORMAT: &str = "vanefit.starts/1";

/// Why a whole, readable record cannot be a finished start of a run with `n` parameters
/// (an edited or foreign file): the optimizer would be handed points of the wrong dimension
/// (a panic) and the best start chosen by a cost no run can give. `None` when it can be.
fn not_of_this_run(r: &StartResult, n: usize) -> Option<ForeignStart> {
    let index = r.index;
    for (key, point) in [("theta0", &r.theta0), ("theta", &r.theta)] {
        if point.len() != n {
            return Some(ForeignStart::Coordinates {
                index,
                key,
                len: point.len(),
                n,
            });
        }
    }
    if !r.theta0.iter().chain(&r.theta).all(|v| v.is_finite()) {
        return Some(ForeignStart::NotFiniteCoordinate { index });
    }
    if !r.cost.is_finite() || !r.history.iter().all(|c| c.is_finite()) {
        return Some(ForeignStart::NotFiniteCost { index });
    }
    None
}

/// Append-only file of finished starts (JSON lines). Workers append the starts they finish
/// concurrently; a lock keeps each record a line of its own.
pub struct ResultsFile {
    path: PathBuf,
    appending: std::sync::Mutex<()>,
}

impl ResultsFile {
    /// The results file at `path` (nothing is read or written yet).
    pub fn new(path: &Path) -> Self {
        Self {
            path: path.to_path_buf(),
            appending: std::sync::Mutex::new(()),
        }
    }

    fn header(space: &ParamSpace, cfg: &MultiStartSettings) -> Header {
        Header {
            format: RESULTS_FORMAT.into(),
            seed: cfg.seed(),
            starts: cfg.starts(),
            parameters: space.names(),
            effects: space.effects.ids(),
        }
    }

    fn io(&self, source: std::io::Error) -> EstimateError {
        EstimateError::Io {
            path: self.path.clone(),
            source,
        }
    }

    fn bad_line(&self, line: usize, why: impl Into<ResultsLineError>) -> EstimateError {
        EstimateError::ResultsLine {
            path: self.path.clone(),
            line,
            why: why.into(),
        }
    }

    /// Reads finished starts of a matching earlier run (empty if there is no file).
    pub(crate) fn load(
        &self,
        space: &ParamSpace,
        cfg: &MultiStartSettings,
    ) -> Result<Vec<StartResult>, EstimateError> {
        let file = match std::fs::File::open(&self.path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
            Err(e) => return Err(self.io(e)),
        };
        let mut lines = std::io::BufReader::new(file).lines();
        let Some(first) = lines.next() else {
            return Ok(Vec::new());
        };
        let first = first.map_err(|e| self.bad_line(1, e))?;
        let header: Header = serde_json::from_str(&first).map_err(|e| self.bad_line(1, e))?;
        if header != Self::header(space, cfg) {
            return Err(self.bad_line(1, ResultsLineError::OtherRun));
        }
        let mut out = Vec::new();
        self.cut_torn_line()?;
        for (i, line) in lines.enumerate() {
            let line = line.map_err(|e| self.bad_line(i + 2, e))?;
            // A line cut short by an interruption is simply not finished.
            if let Ok(r) = serde_json::from_str::<StartResult>(&line) {
                if let Some(why) = not_of_this_run(&r, space.len()) {
                    return Err(self.bad_line(i + 2, ResultsLineError::NotOfThisRun(why)));
                }
                if r.index < cfg.starts() && !out.iter().any(|o: &StartResult| o.index == r.index) {
                    out.push(r);
                }
            }
        }
        Ok(out)
    }

    /// Cuts off a last line that an interruption (a kill, a full disk) left without its
    /// newline, so that the next record is appended on a line of its own instead of being
    /// glued to the torn one (and the torn start, not being finished, is simply run again).
    fn cut_torn_line(&self) -> Result<(), EstimateError> {
        let bytes = std::fs::read(&self.path).map_err(|e| self.io(e))?;
        if bytes.last().is_none_or(|b| *b == b'\n') {
            return Ok(());
        }
        let keep = bytes.iter().rposition(|b| *b == b'\n').map_or(0, |i| i + 1);
        let f = std::fs::OpenOptions::new()
            .write(true)
            .open(&self.path)
            .map_err(|e| self.io(e))?;
        f.set_len(keep as u64).map_err(|e| self.io(e))?;
        f.sync_data().map_err(|e| self.io(e))
    }

    /// Starts the file with the run's header.
    pub(crate) fn create(
        &self,
        space: &ParamSpace,
        cfg: &MultiStartSettings,
    ) -> Result<(), EstimateError> {
        let header = serde_json::to_string(&Self::header(space, cfg)).expect("plain data");
        crate::io::write_atomic(&self.path, (header + "\n").as_bytes()).map_err(|e| self.io(e))
    }

    /// Rewrites the file with its starts in start order (temp + rename) once a run has
    /// ended: workers append starts as they finish, so the order of the lines depends on
    /// timing, while a finished run's file should not. Each line is kept as written.
    pub(crate) fn sort(&self) -> Result<(), EstimateError> {
        /// The start index of a record (the rest is kept as text).
        #[derive(Deserialize)]
        struct Index {
            index: usize,
        }
        let text = std::fs::read_to_string(&self.path).map_err(|e| self.io(e))?;
        let mut lines = text.lines();
        let Some(header) = lines.next() else {
            return Ok(());
        };
        let mut starts = std::collections::BTreeMap::new();
        for line in lines {
            if let Ok(r) = serde_json::from_str::<Index>(line) {
                starts.entry(r.index).or_insert(line);
            }
        }
        let mut sorted = String::from(header) + "\n";
        for line in starts.values() {
            sorted += line;
            sorted.push('\n');
        }
        crate::io::write_atomic(&self.path, sorted.as_bytes()).map_err(|e| self.io(e))
    }

    /// Appends finished starts, each a whole line written at once, and syncs them to disk.
    pub(crate) fn append(&self, results: &[StartResult]) -> Result<(), EstimateError> {
        if results.is_empty() {
            return Ok(());
        }
        // A worker that panicked while holding the lock wrote whole lines or a torn last one,
        // which `load` cuts: the file is still usable.
        let _one_writer = self
            .appending
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&self.path)
            .map_err(|e| self.io(e))?;
        let mut text = String::new();
        for r in results {
            text += &(serde_json::to_string(r).expect("plain data") + "\n");
        }
        f.write_all(text.as_bytes()).map_err(|e| self.io(e))?;
        f.sync_data().map_err(|e| self.io(e))
    }
}
