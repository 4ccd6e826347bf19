//! `vanefit._core`: the Rust side of the Python package. Thin on purpose: every function
//! calls the library's typed functions the command line calls (so a seed gives the same
//! fit, and an error the same located message) — never the command line itself — returns
//! plain Python values, JSON or the text of the files the command writes, and leaves
//! DataFrames, result objects and documentation to `vanefit/__init__.py`. The GIL is
//! released while a fit, a diagnosis, a prediction or a batch of χ² evaluations runs.

mod control;
mod errors;
mod fitting;
mod observe;
mod sampling;
mod tasks;

use errors::{data_err, param_err, DataError, ParameterError, VanefitError};
use pyo3::prelude::*;
use pyo3::types::PyByteArray;
use std::path::PathBuf;
use tasks::load_fit;
use vanefit::data::Dataset;
use vanefit::data::FitFile;
use vanefit::estimate::DataObjective;
use vanefit::estimate::Objective;
use vanefit::estimate::{FitLikelihood, FitLikelihoodError};
use vanefit::model::PARAMS;
use vanefit::numerics::DefaultSolver;
use vanefit::objective::{CostModel, CostOptions};

/// A dataset read and checked by vanefit (rig.toml and its recordings).
#[pyclass(module = "vanefit._core", frozen)]
pub struct PyDataset {
    inner: Dataset,
    path: PathBuf,
}

#[pymethods]
impl PyDataset {
    /// The dataset's name (its folder's name unless rig.toml names it).
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// The folder it was read from.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    /// The experiments as JSON: file, kind, column names.
    fn experiments_json(&self) -> String {
        let list: Vec<serde_json::Value> = self
            .inner
            .experiments
            .iter()
            .map(|e| {
                serde_json::json!({
                    "file": e.file,
                    "kind": e.kind.id(),
                    "columns": e.recording.columns.iter().map(|c| c.name.clone()).collect::<Vec<_>>(),
                })
            })
            .collect();
        serde_json::Value::Array(list).to_string()
    }

    /// A recording's columns as written: (name, values in the column's unit) pairs; an
    /// empty cell is NaN.
    fn recording(&self, file: &str) -> PyResult<Vec<(String, Vec<f64>)>> {
        let ex = self
            .inner
            .experiments
            .iter()
            .find(|e| e.file == file)
            .ok_or_else(|| {
                let known: Vec<&str> = self
                    .inner
                    .experiments
                    .iter()
                    .map(|e| e.file.as_str())
                    .collect();
                ParameterError::new_err(format!(
                    "{file}: no such recording in dataset '{}' (it has {})",
                    self.inner.name,
                    known.join(", ")
                ))
            })?;
        Ok(ex
            .recording
            .columns
            .iter()
            .map(|c| {
                let v = c
                    .raw
                    .iter()
                    .map(|r| r.trim().parse().unwrap_or(f64::NAN))
                    .collect();
                (c.name.clone(), v)
            })
            .collect())
    }
}

/// Reads and checks a dataset folder.
#[pyfunction]
fn load_dataset(path: PathBuf) -> PyResult<PyDataset> {
    let inner = Dataset::load(&path).map_err(data_err)?;
    Ok(PyDataset { inner, path })
}

/// The dataset's nominal motor: every parameter's SI value by name.
#[pyfunction]
fn nominal_parameters(ds: &PyDataset) -> PyResult<Vec<(String, f64)>> {
    let p = ds.inner.nominal_params().map_err(data_err)?;
    Ok(PARAMS
        .iter()
        .filter_map(|s| p.get(s.name).map(|v| (s.name.to_string(), v)))
        .collect())
}

/// Reads and checks a fit file (or, given `text`, fit-file text that `path` names in
/// messages); returns its text as read, which the Python `Fit` keeps byte for byte.
#[pyfunction]
#[pyo3(signature = (path, text=None))]
fn read_fit(path: PathBuf, text: Option<String>) -> PyResult<String> {
    load_fit(&path, text.as_deref())?;
    match text {
        Some(t) => Ok(t),
        None => std::fs::read_to_string(&path)
            .map_err(|e| DataError::new_err(format!("{}: cannot read: {e}", path.display()))),
    }
}

/// The fit file at `fit` (its text `fit_text` when held in memory), or the nominal motor
/// of `ds` with `overrides` (SI) applied, as a fit file held in memory.
fn parameters(
    ds: &Dataset,
    fit: Option<PathBuf>,
    fit_text: Option<String>,
    overrides: Vec<(String, f64)>,
) -> PyResult<FitFile> {
    let mut f = match fit {
        Some(p) => load_fit(&p, fit_text.as_deref())?,
        None => FitFile::from_params(
            &ds.name,
            ds.nominal_params().map_err(data_err)?,
            vanefit::model::EffectSet::empty(),
        ),
    };
    for (name, v) in overrides {
        f.params = f.params.with(&name, v).map_err(param_err)?;
    }
    Ok(f)
}

/// A table's columns: (name with unit, values in that unit).
type Columns = Vec<(String, Vec<f64>)>;

/// Every experiment simulated: (file, [(column, values in the column's unit)]).
#[pyfunction]
#[pyo3(signature = (ds, fit=None, fit_text=None, overrides=Vec::new()))]
fn simulate(
    py: Python<'_>,
    ds: &PyDataset,
    fit: Option<PathBuf>,
    fit_text: Option<String>,
    overrides: Vec<(String, f64)>,
) -> PyResult<Vec<(String, Columns)>> {
    let f = parameters(&ds.inner, fit, fit_text, overrides)?;
    let motor = vanefit::task::motor_for(&ds.inner, Some(&f)).map_err(data_err)?;
    let tables = py
        .detach(|| vanefit::task::simulated_tables(&ds.inner, &motor))
        .map_err(|e| VanefitError::new_err(e.to_string()))?;
    Ok(tables
        .into_iter()
        .map(|t| {
            let cols = t.columns.into_iter().map(|c| (c.name, c.values)).collect();
            (t.file, cols)
        })
        .collect())
}

/// The cost J that `fit` minimises and its χ² (docs/model.md), with each channel's term, as
/// JSON.
#[pyfunction]
#[pyo3(signature = (ds, fit=None, fit_text=None, overrides=Vec::new()))]
fn cost(
    py: Python<'_>,
    ds: &PyDataset,
    fit: Option<PathBuf>,
    fit_text: Option<String>,
    overrides: Vec<(String, f64)>,
) -> PyResult<String> {
    let f = parameters(&ds.inner, fit, fit_text, overrides)?;
    let model = CostModel::new(&ds.inner, CostOptions::default()).map_err(data_err)?;
    py.detach(|| {
        let motor = vanefit::task::motor_for(&ds.inner, Some(&f)).map_err(|e| e.to_string())?;
        let objective = DataObjective {
            cost: &model,
            solver: Box::new(DefaultSolver::default()),
        };
        let ev = objective.evaluate(&motor);
        let v = model.evaluate(&motor, &DefaultSolver::default());
        let channels: Vec<serde_json::Value> = v
            .channels
            .iter()
            .map(|c| {
                serde_json::json!({
                    "file": c.file, "column": c.column, "kind": c.experiment_kind.id(),
                    "n": c.n, "weight": c.weight, "rms_normalized": c.rms_normalized,
                    "cost": c.cost,
                })
            })
            .collect();
        Ok(serde_json::json!({
            "cost": ev.cost, "chi2": ev.chi2, "n_points": ev.n_points,
            "failed": v.failed, "channels": channels,
        })
        .to_string())
    })
    .map_err(|e: String| VanefitError::new_err(e))
}

/// The likelihood a fit's estimate and intervals were measured on, rebuilt from its fit
/// file: χ² as a function of the estimated parameters (SI values), with the fit's motor
/// prior χ²_prior added when `priors` (docs/estimation.md, "Priors"): the objective the fit
/// minimised.
#[pyclass(module = "vanefit._core", frozen)]
struct PyLikelihood {
    inner: FitLikelihood,
    priors: bool,
}

impl PyLikelihood {
    /// χ² (plus χ²_prior when `priors`) at `x`.
    fn objective(&self, x: &[f64]) -> Result<f64, FitLikelihoodError> {
        let c = self.inner.try_chi2(x)?;
        Ok(if self.priors {
            c + self.inner.prior_chi2(x)
        } else {
            c
        })
    }
}

fn likelihood_err(e: FitLikelihoodError) -> PyErr {
    match e {
        FitLikelihoodError::Param(_) | FitLikelihoodError::Length { .. } => {
            ParameterError::new_err(e.to_string())
        }
        FitLikelihoodError::Simulation => VanefitError::new_err(e.to_string()),
        _ => DataError::new_err(e.to_string()),
    }
}

#[pymethods]
impl PyLikelihood {
    /// Rebuilds the likelihood of the fit file at `fit` (its text `fit_text` when held in
    /// memory) on dataset `ds`; `priors`: add the fit's motor prior (as the fit did).
    #[new]
    #[pyo3(signature = (ds, fit, fit_text=None, priors=true))]
    fn new(
        py: Python<'_>,
        ds: &PyDataset,
        fit: PathBuf,
        fit_text: Option<String>,
        priors: bool,
    ) -> PyResult<Self> {
        let f = load_fit(&fit, fit_text.as_deref())?;
        let inner = py
            .detach(|| FitLikelihood::from_fit(&ds.inner, &f))
            .map_err(likelihood_err)?;
        Ok(Self { inner, priors })
    }

    /// Whether the motor prior is part of χ², the residuals and the posterior.
    #[getter]
    fn priors(&self) -> bool {
        self.priors
    }

    /// The motor prior of the estimated parameters: (name, median SI, σ of ln v, size
    /// exponent) each; empty for a fit made without priors.
    #[getter]
    fn prior_terms(&self) -> Vec<(String, f64, f64, f64)> {
        self.inner
            .prior_terms()
            .iter()
            .map(|t| {
                let t = &t.term;
                (t.name().to_string(), t.median, t.sd_ln, t.size_exponent)
            })
            .collect()
    }

    /// χ²_prior of the motor prior at `x` (SI), whether or not `priors` is on.
    fn prior_chi2(&self, x: Vec<f64>) -> PyResult<f64> {
        self.inner
            .prior_residuals(&x)
            .map(|r| r.iter().map(|v| v * v).sum())
            .map_err(likelihood_err)
    }

    /// Names of the estimated parameters.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.inner.names()
    }

    /// Search bounds (lower, upper) of each, SI.
    #[getter]
    fn bounds(&self) -> Vec<(f64, f64)> {
        self.inner.bounds()
    }

    /// Whether each is searched on a log scale.
    #[getter]
    fn log_scale(&self) -> Vec<bool> {
        self.inner.log_scale()
    }

    /// The fit's estimate, SI.
    #[getter]
    fn estimate(&self) -> Vec<f64> {
        self.inner.estimate()
    }

    /// χ² at the estimate as the fit file states it (`likelihood_chi2`, plus `prior_chi2`
    /// when `priors`).
    #[getter]
    fn chi2_min(&self) -> f64 {
        if self.priors {
            self.inner.chi2_min() + self.inner.prior_chi2_min()
        } else {
            self.inner.chi2_min()
        }
    }

    /// Rise of χ² that bounds a 95 % profile interval.
    #[getter]
    fn threshold(&self) -> f64 {
        self.inner.threshold()
    }

    /// χ² at `x` (SI; plus χ²_prior when `priors`); raises on a bad vector or a failed
    /// simulation.
    fn chi2(&self, py: Python<'_>, x: Vec<f64>) -> PyResult<f64> {
        py.detach(|| self.objective(&x)).map_err(likelihood_err)
    }

    /// The residual vector at `x` (SI): the compared rows after the nuisances' correction,
    /// then one row per nuisance prior, then (when `priors`) one per motor prior term; its
    /// squares sum to χ². Raises like `chi2`.
    ///
    /// As the bytes of the values (little-endian f64, 8 bytes each), which the Python
    /// wrapper reads as a NumPy array in place: least-squares optimizers and finite
    /// differences call this tens of thousands of times, and a list of 3 812 floats and its
    /// conversion to an array took 0.28 of 0.74 ms per call on the shipped dataset.
    fn residuals<'py>(&self, py: Python<'py>, x: Vec<f64>) -> PyResult<Bound<'py, PyByteArray>> {
        let r = py
            .detach(|| {
                let mut r = self.inner.residuals(&x)?;
                if self.priors {
                    r.extend(self.inner.prior_residuals(&x)?);
                }
                Ok(r)
            })
            .map_err(likelihood_err)?;
        // Written straight into the bytearray (no byte vector in between).
        PyByteArray::new_with(py, 8 * r.len(), |bytes| {
            for (chunk, v) in bytes.chunks_exact_mut(8).zip(&r) {
                chunk.copy_from_slice(&v.to_le_bytes());
            }
            Ok(())
        })
    }

    /// χ² at `x` for an optimizer: always finite (a large penalty where `x` is invalid or
    /// the simulation fails).
    fn chi2_or_penalty(&self, py: Python<'_>, x: Vec<f64>) -> f64 {
        // Both parts are finite always (a penalty where the simulation fails, a large
        // residual where a value has no logarithm).
        py.detach(|| {
            let prior = if self.priors {
                self.inner.prior_chi2(&x)
            } else {
                0.0
            };
            self.inner.chi2(&x) + prior
        })
    }

    /// ln p at sampling coordinates `x` (ln θ of a log-scale parameter, θ otherwise):
    /// −½·(χ² − χ²_min)/s² of the likelihood, plus (when `priors`) the motor prior
    /// −½·(χ²_prior − χ²_prior,min), with a prior flat in `x` within the search bounds; −inf
    /// outside them or where the simulation fails.
    fn log_posterior(&self, py: Python<'_>, x: Vec<f64>) -> PyResult<f64> {
        sampling::log_posterior(&self.inner, self.priors, py, x)
    }

    /// The sampling coordinates of SI values.
    fn to_coords(&self, values: Vec<f64>) -> Vec<f64> {
        vanefit::estimate::FitPosterior::new(&self.inner).to_coords(&values)
    }

    /// The SI values at sampling coordinates.
    fn to_values(&self, x: Vec<f64>) -> Vec<f64> {
        vanefit::estimate::FitPosterior::new(&self.inner).to_values(&x)
    }

    /// Runs vanefit's ensemble sampler on the log-posterior from `starts` (one list of
    /// coordinates per walker): (chains[walker][step][param], ln p[walker][step],
    /// acceptance per walker).
    #[pyo3(signature = (starts, steps, burn_in=0, seed=1))]
    fn sample(
        &self,
        py: Python<'_>,
        starts: Vec<Vec<f64>>,
        steps: usize,
        burn_in: usize,
        seed: u64,
    ) -> PyResult<sampling::Run> {
        sampling::sample(&self.inner, self.priors, py, starts, steps, burn_in, seed)
    }

    /// χ² at `x` split into data and prior parts with every compared row, as JSON.
    fn breakdown(&self, py: Python<'_>, x: Vec<f64>) -> PyResult<String> {
        let b = py
            .detach(|| self.inner.breakdown(&x))
            .map_err(likelihood_err)?;
        let channels: Vec<serde_json::Value> = b
            .channels
            .iter()
            .map(|c| {
                serde_json::json!({
                    "file": c.file, "column": c.column, "rows": c.rows, "data": c.data,
                    "sigma": c.sigma, "simulated": c.simulated, "residuals": c.residuals,
                })
            })
            .collect();
        let nuisances: Vec<serde_json::Value> = b
            .nuisances
            .iter()
            .map(|(l, v, tau)| serde_json::json!({"label": l, "value": v, "prior_sd": tau}))
            .collect();
        let motor_prior: Vec<serde_json::Value> = self
            .inner
            .prior_terms()
            .iter()
            .zip(self.inner.prior_residuals(&x).map_err(likelihood_err)?)
            .map(|(t, r)| {
                let t = &t.term;
                serde_json::json!({
                    "parameter": t.name(), "median": t.median, "sd_ln": t.sd_ln,
                    "size_exponent": t.size_exponent, "residual": r,
                })
            })
            .collect();
        let chi2_motor_prior = self.inner.prior_chi2(&x);
        Ok(serde_json::json!({
            "chi2": b.chi2(), "chi2_data": b.chi2_data, "chi2_prior": b.chi2_prior,
            "chi2_motor_prior": chi2_motor_prior,
            "objective": b.chi2() + chi2_motor_prior,
            "channels": channels, "nuisances": nuisances, "motor_prior": motor_prior,
        })
        .to_string())
    }
}

/// The module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add_class::<PyDataset>()?;
    m.add_class::<PyLikelihood>()?;
    m.add_function(wrap_pyfunction!(load_dataset, m)?)?;
    m.add_function(wrap_pyfunction!(nominal_parameters, m)?)?;
    m.add_function(wrap_pyfunction!(read_fit, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(cost, m)?)?;
    m.add_function(wrap_pyfunction!(fitting::fit, m)?)?;
    m.add_function(wrap_pyfunction!(fitting::diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::predict, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::find_dataset, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::plan, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::export_petab, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::export_fmu, m)?)?;
    m.add_function(wrap_pyfunction!(tasks::synth, m)?)?;
    m.add_function(wrap_pyfunction!(control::control, m)?)?;
    m.add_function(wrap_pyfunction!(sampling::chain_diagnostics, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
