//! Progress from Rust to a Python callable. The fit and the diagnosis run with the GIL
//! released on rayon's threads; each event takes the GIL just long enough to call back. An
//! exception raised by the callback cannot stop the work (the library has no cancel), so
//! the first one is kept, later calls are skipped, and it is raised when the work returns.

use pyo3::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use vanefit::diagnose::{DiagnoseObserver, Progress};
use vanefit::estimate::{RunObserver, StartResult};

/// A callable and the first error it raised.
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

    /// Calls back with `args` unless an earlier call failed.
    fn call<A>(&self, args: impl FnOnce(Python<'_>) -> A)
    where
        A: for<'py> pyo3::call::PyCallArgs<'py>,
    {
        let Some(f) = &self.callable else { return };
        let mut slot = match self.error.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        };
        if slot.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = f.call1(py, args(py)) {
                *slot = Some(e);
            }
        });
    }

    fn raise(&self) -> PyResult<()> {
        let mut slot = match self.error.lock() {
            Ok(g) => g,
            Err(p) => p.into_inner(),
        };
        match slot.take() {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// Calls `progress(done, total, best_cost)` after every start of a fit.
pub struct PyFitProgress {
    callback: Callback,
    total: AtomicUsize,
    done: AtomicUsize,
}

impl PyFitProgress {
    /// An observer calling `progress` (none: silent).
    pub fn new(progress: Option<Py<PyAny>>) -> Self {
        Self {
            callback: Callback::new(progress),
            total: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
        }
    }

    /// Raises the callback's first exception, if any.
    pub fn raise_callback_error(&self, _py: Python<'_>) -> PyResult<()> {
        self.callback.raise()
    }
}

impl vanefit::task::fit::FitObserver for PyFitProgress {}

impl RunObserver for PyFitProgress {
    fn started(&self, total: usize, already_done: usize) {
        self.total.store(total, Ordering::SeqCst);
        self.done.store(already_done, Ordering::SeqCst);
    }

    fn start_finished(&self, _result: &StartResult, best_cost: f64) {
        let done = self.done.fetch_add(1, Ordering::SeqCst) + 1;
        let total = self.total.load(Ordering::SeqCst);
        self.callback.call(|_| (done, total, best_cost));
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
    pub fn raise_callback_error(&self, _py: Python<'_>) -> PyResult<()> {
        self.callback.raise()
    }
}

impl DiagnoseObserver for PyDiagnoseProgress {
    fn progress(&self, elapsed_s: f64, event: &Progress<'_>) {
        let text = event.to_string();
        self.callback.call(|_| (elapsed_s, text));
    }
}
