//! Progress from Rust to a Python callable, and Ctrl-C. The fit and the diagnosis run with
//! the GIL released on rayon's threads; each event takes the GIL just long enough to call
//! back. The first exception the callback raises is kept, later calls are skipped, and it is
//! raised when the work returns. A fit also stops at its next round when the callback
//! raised or Python has a pending signal (`Python::check_signals`: Ctrl-C becomes
//! `KeyboardInterrupt`); its finished starts are then in the starts file, ready to resume.

use pyo3::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use vanefit::diagnose::{DiagnoseObserver, Progress};
use vanefit::estimate::{RunObserver, StartResult};

/// A callable and the first error it (or a signal handler) raised.
struct Callback {
    callable: Option<Py<PyAny>>,
    error: Mutex<Option<PyErr>>,
}

impl Callback {
    fn new(callable: Option<Py<PyAny>>) -> Self {
        Self {
            callable,
            error: Mutex::new(None),
        }
    }

    fn slot(&self) -> std::sync::MutexGuard<'_, Option<PyErr>> {
        match self.error.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        }
    }

    /// Calls back with `args` unless an earlier call failed.
    fn call<A>(&self, args: impl FnOnce(Python<'_>) -> A)
    where
        A: for<'py> pyo3::call::PyCallArgs<'py>,
    {
        let Some(f) = &self.callable else { return };
        let mut slot = self.slot();
        if slot.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = f.call1(py, args(py)) {
                *slot = Some(e);
            }
        });
    }

    /// Whether the work should stop: the callback failed, or a signal handler raised
    /// (checked on Python's main thread only; elsewhere signals wait for the main thread).
    fn failed_or_signalled(&self) -> bool {
        let mut slot = self.slot();
        if slot.is_some() {
            return true;
        }
        Python::attach(|py| {
            if let Err(e) = py.check_signals() {
                *slot = Some(e);
            }
        });
        slot.is_some()
    }

    fn raise(&self) -> PyResult<()> {
        match self.slot().take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// Calls `progress(done, total, best_cost)` after every start of a fit, and stops the fit
/// on Ctrl-C or when the callback raised.
pub struct PyFitProgress {
    callback: Callback,
    total: AtomicUsize,
    done: AtomicUsize,
}

impl PyFitProgress {
    /// An observer calling `progress` (none: silent, but still stopped by Ctrl-C).
    pub fn new(progress: Option<Py<PyAny>>) -> Self {
        Self {
            callback: Callback::new(progress),
            total: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
        }
    }

    /// Raises the callback's first exception (or the `KeyboardInterrupt`), if any.
    pub fn raise_callback_error(&self) -> PyResult<()> {
        self.callback.raise()
    }
}

impl vanefit::task::FitObserver for PyFitProgress {}

impl RunObserver for PyFitProgress {
    fn started(&self, total: usize, already_done: usize) {
        self.total.store(total, Ordering::SeqCst);
        self.done.store(already_done, Ordering::SeqCst);
        self.callback.call(|_| (already_done, total, f64::INFINITY));
    }

    fn start_finished(&self, _result: &StartResult, best_cost: f64) {
        let done = self.done.fetch_add(1, Ordering::SeqCst) + 1;
        let total = self.total.load(Ordering::SeqCst);
        self.callback.call(|_| (done, total, best_cost));
    }

    fn keep_going(&self) -> bool {
        !self.callback.failed_or_signalled()
    }
}

/// Calls `progress(elapsed_s, message)` at every phase of a diagnosis.
pub struct PyDiagnoseProgress {
    callback: Callback,
}

impl PyDiagnoseProgress {
    /// An observer calling `progress` (none: silent).
    pub fn new(progress: Option<Py<PyAny>>) -> Self {
        Self {
            callback: Callback::new(progress),
        }
    }

    /// Raises the callback's first exception, if any.
    pub fn raise_callback_error(&self) -> PyResult<()> {
        self.callback.raise()
    }
}

impl DiagnoseObserver for PyDiagnoseProgress {
    fn progress(&self, elapsed_s: f64, event: &Progress<'_>) {
        let text = event.to_string();
        self.callback.call(|_| (elapsed_s, text));
    }
}

/// Calls `progress(stage, done, total)` while a prediction samples its posterior
/// (`"sampling"`: steps of the walkers) and propagates the samples (`"propagating"`), at
/// each tenth of a stage: the work runs on rayon's threads, and a call per step would hold
/// them at the GIL.
pub struct PyPredictProgress {
    callback: Callback,
    last: Mutex<(String, usize)>,
}

impl PyPredictProgress {
    /// An observer calling `progress` (none: silent).
    pub fn new(progress: Option<Py<PyAny>>) -> Self {
        Self {
            callback: Callback::new(progress),
            last: Mutex::new((String::new(), 0)),
        }
    }

    /// Tells the callable of `done` of `total` in stage `what` when a new tenth is reached.
    pub fn tell(&self, what: &str, done: usize, total: usize) {
        let tenth = (10 * done) / total.max(1);
        {
            let mut last = match self.last.lock() {
                Ok(g) => g,
                Err(p) => p.into_inner(),
            };
            if last.0 == what && tenth <= last.1 {
                return;
            }
            *last = (what.to_string(), tenth);
        }
        self.callback.call(|_| (what.to_string(), done, total));
    }

    /// The callback's first exception, raised once the prediction returned.
    pub fn raise_callback_error(&self) -> PyResult<()> {
        self.callback.raise()
    }
}
