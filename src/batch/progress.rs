//! Progress of a batch as lines on stderr, so that a Slurm log (no terminal, no progress
//! bars) shows a live run: each unit when it starts and ends with units done/total, and a
//! running fit's starts every few seconds.

use crate::diagnose::{DiagnoseObserver, Progress as DiagnoseProgress};
use crate::estimate::optimize::multistart::{RunObserver, StartResult};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How often a running fit reports its starts.
const EVERY: Duration = Duration::from_secs(5);

/// The batch's clock and counters.
pub(crate) struct BatchProgress {
    t0: Instant,
    total: usize,
    finished: AtomicUsize,
    shard: String,
}

impl BatchProgress {
    /// Progress of `total` units of shard `shard`.
    pub fn new(total: usize, shard: String) -> Self {
        Self {
            t0: Instant::now(),
            total,
            finished: AtomicUsize::new(0),
            shard,
        }
    }

    /// One line: time since the batch started, the shard, units finished of total, text.
    pub fn line(&self, text: &str) {
        eprintln!(
            "[{:7.1} s] shard {} ({}/{} units): {text}",
            self.t0.elapsed().as_secs_f64(),
            self.shard,
            self.finished.load(Ordering::Relaxed),
            self.total
        );
    }

    /// A unit finished (done, failed or skipped).
    pub(crate) fn unit_finished(&self) {
        self.finished.fetch_add(1, Ordering::Relaxed);
    }

    /// An observer of one unit's fit or diagnosis, labelled `label`.
    pub fn unit<'a>(&'a self, label: &str) -> UnitProgress<'a> {
        UnitProgress {
            batch: self,
            label: label.to_string(),
            last: Mutex::new(Instant::now()),
            total: AtomicUsize::new(0),
            count: AtomicUsize::new(0),
            notes: Mutex::new(Vec::new()),
        }
    }
}

/// Progress of one unit.
pub(crate) struct UnitProgress<'a> {
    batch: &'a BatchProgress,
    label: String,
    last: Mutex<Instant>,
    total: AtomicUsize,
    count: AtomicUsize,
    /// What `vanefit fit` prints before it fits (a catalogue's pinning, its displacement),
    /// kept for the unit's own log (`fit.log`) rather than printed among other units'
    /// progress lines.
    notes: Mutex<Vec<String>>,
}

impl UnitProgress<'_> {
    /// The unit's notes so far, taken (empty: none).
    pub(crate) fn take_notes(&self) -> Vec<String> {
        std::mem::take(&mut *self.notes.lock().unwrap_or_else(|p| p.into_inner()))
    }

    fn note(&self, lines: impl IntoIterator<Item = String>) {
        self.notes
            .lock()
            .unwrap_or_else(|p| p.into_inner())
            .extend(lines);
    }
}

/// A batch keeps a catalogue's pinning and displacement (what `vanefit fit` prints) for
/// the unit's `fit.log`: printed here, they would interleave with other units' lines.
impl crate::task::fit::FitObserver for UnitProgress<'_> {
    fn pinning(&self, limit_pct: f64, rows: &[crate::task::fit::Pinning]) {
        self.note(crate::task::fit::pinning_lines(limit_pct, rows));
    }
    fn displacement(&self, estimate: &crate::estimate::fit::displacement::DisplacementEstimate) {
        self.note([crate::task::fit::displacement_start_line(estimate)]);
    }
}

impl RunObserver for UnitProgress<'_> {
    fn started(&self, total: usize, already_done: usize) {
        self.total.store(total, Ordering::Relaxed);
        self.count.store(already_done, Ordering::Relaxed);
        let resumed = if already_done > 0 {
            format!(", {already_done} read back from its starts file (resumed)")
        } else {
            String::new()
        };
        self.batch
            .line(&format!("{}: {total} starts{resumed}", self.label));
    }

    fn start_finished(&self, _result: &StartResult, best_cost: f64) {
        let n = self.count.fetch_add(1, Ordering::Relaxed) + 1;
        let mut last = self.last.lock().unwrap_or_else(|p| p.into_inner());
        if last.elapsed() >= EVERY {
            *last = Instant::now();
            let total = self.total.load(Ordering::Relaxed);
            self.batch.line(&format!(
                "{}: {n}/{total} starts, best J {best_cost:.4}",
                self.label
            ));
        }
    }
}

impl DiagnoseObserver for UnitProgress<'_> {
    fn progress(&self, elapsed_s: f64, event: &DiagnoseProgress<'_>) {
        self.batch
            .line(&format!("{} [{elapsed_s:.1} s]: {event}", self.label));
    }
}
