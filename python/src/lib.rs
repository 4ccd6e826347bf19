//! `vanefit._core`: the Rust side of the Python package. Thin on purpose: every function
//! calls the library code the command line calls (so a seed gives the same fit, and an
//! error the same located message), returns plain Python values or JSON text, and leaves
//! numpy arrays, dataclasses and documentation to `vanefit/__init__.py`. The GIL is
//! released while a fit, a diagnosis or a batch of χ² evaluations runs.

/// The command line's code (part of the `vanefit` binary, not of the library), for
/// `run_command` until every command has a typed Python function.
#[allow(dead_code)]
#[path = "../../src/cli/mod.rs"]
mod cli;
mod errors;
mod observe;

use errors::{data_err, param_err, DataError, ParameterError, VanefitError};
use observe::{PyDiagnoseProgress, PyFitProgress};
use pyo3::prelude::*;
use std::path::PathBuf;
use vanefit::data::dataset::Dataset;
use vanefit::data::fitfile::FitFile;
use vanefit::estimate::fit::DataObjective;
use vanefit::estimate::fit::UncertaintyMethod;
use vanefit::estimate::fit_likelihood::{FitLikelihood, FitLikelihoodError};
use vanefit::estimate::Objective;
use vanefit::model::params::PARAMS;
use vanefit::numerics::DefaultSolver;
use vanefit::objective::cost::{CostModel, CostOptions};
use vanefit::task::fit::{FitError, FitOptions};

/// A dataset read and checked by vanefit (rig.toml and its recordings).
#[pyclass(module = "vanefit._core", frozen)]
struct PyDataset {
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

/// Reads and checks a fit file; returns it as JSON text (as vanefit would write it).
#[pyfunction]
fn read_fit(path: PathBuf) -> PyResult<String> {
    let f = FitFile::read(&path).map_err(data_err)?;
    Ok(f.to_json().to_string())
}

/// The fit file at `path`, or the nominal motor of `ds` with `overrides` (SI) applied, as
/// a fit file held in memory.
fn parameters(
    ds: &Dataset,
    fit: Option<PathBuf>,
    overrides: Vec<(String, f64)>,
) -> PyResult<FitFile> {
    let mut f = match fit {
        Some(p) => FitFile::read(&p).map_err(data_err)?,
        None => FitFile::from_params(
            &ds.name,
            ds.nominal_params().map_err(data_err)?,
            vanefit::model::effects::EffectSet::empty(),
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
#[pyo3(signature = (ds, fit=None, overrides=Vec::new()))]
fn simulate(
    py: Python<'_>,
    ds: &PyDataset,
    fit: Option<PathBuf>,
    overrides: Vec<(String, f64)>,
) -> PyResult<Vec<(String, Columns)>> {
    let f = parameters(&ds.inner, fit, overrides)?;
    let tables = py
        .detach(|| {
            let motor = vanefit::task::simulate::motor_for(&ds.inner, Some(&f))
                .map_err(|e| e.to_string())?;
            vanefit::task::simulate::simulated_tables(&ds.inner, &motor).map_err(|e| e.to_string())
        })
        .map_err(VanefitError::new_err)?;
    Ok(tables
        .into_iter()
        .map(|t| {
            let cols = t.columns.into_iter().map(|c| (c.name, c.values)).collect();
            (t.file, cols)
        })
        .collect())
}

/// The cost J that `fit` minimises and its χ² (SPEC §2), with each channel's term, as JSON.
#[pyfunction]
#[pyo3(signature = (ds, fit=None, overrides=Vec::new()))]
fn cost(
    py: Python<'_>,
    ds: &PyDataset,
    fit: Option<PathBuf>,
    overrides: Vec<(String, f64)>,
) -> PyResult<String> {
    let f = parameters(&ds.inner, fit, overrides)?;
    let model = CostModel::new(&ds.inner, CostOptions::default()).map_err(data_err)?;
    py.detach(|| {
        let motor =
            vanefit::task::simulate::motor_for(&ds.inner, Some(&f)).map_err(|e| e.to_string())?;
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

/// The error of a fit as the exception Python users catch.
fn fit_err(e: FitError) -> PyErr {
    use FitError as E;
    match e {
        E::Data(_) | E::Cost(_) => DataError::new_err(e.to_string()),
        E::Estimate(_) | E::Write { .. } | E::Plot(_) => VanefitError::new_err(e.to_string()),
        _ => ParameterError::new_err(e.to_string()),
    }
}

/// Fits a dataset exactly as `vanefit fit` does; returns the fit file and every start as
/// JSON, after writing the fit file (and its starts file) to `out` when given.
#[pyfunction]
#[pyo3(signature = (dataset, starts, seed, threads, effects, estimate, uncertainty, max_iters, out, progress))]
#[allow(clippy::too_many_arguments)]
fn fit(
    py: Python<'_>,
    dataset: PathBuf,
    starts: usize,
    seed: u64,
    threads: Option<usize>,
    effects: String,
    estimate: Option<String>,
    uncertainty: &str,
    max_iters: u64,
    out: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let uncertainty = match uncertainty {
        "profile" => UncertaintyMethod::Profile,
        "curvature" => UncertaintyMethod::Curvature,
        "none" => UncertaintyMethod::None,
        other => {
            return Err(ParameterError::new_err(format!(
                "uncertainty '{other}': must be 'profile', 'curvature' or 'none'"
            )))
        }
    };
    let effects = vanefit::model::effects::EffectSet::parse_list(&effects)
        .map_err(|e| ParameterError::new_err(e.to_string()))?;
    let options = FitOptions {
        starts,
        seed,
        threads,
        effects,
        estimate: estimate.map(|list| list.split(',').map(str::to_string).collect()),
        max_iters,
        uncertainty,
        ..FitOptions::default()
    };
    let settings = options
        .check()
        .map_err(|e| ParameterError::new_err(e.to_string()))?;
    let results = out
        .as_ref()
        .map(|o| vanefit::task::fit::side_path(o, "starts.jsonl"));
    let observer = PyFitProgress::new(progress);
    let run = py.detach(|| vanefit::task::fit::fit(&dataset, &settings, results, &observer));
    observer.raise_callback_error(py)?;
    let run = run.map_err(fit_err)?;
    if let Some(o) = &out {
        run.file
            .write(o)
            .map_err(|e| VanefitError::new_err(format!("{}: {e}", o.display())))?;
    }
    let starts: Vec<serde_json::Value> = run
        .outcome
        .run
        .results
        .iter()
        .map(|r| {
            let params: serde_json::Map<String, serde_json::Value> = run
                .setup
                .space
                .dims
                .iter()
                .zip(&r.theta)
                .map(|(d, t)| (d.name.clone(), d.value(*t).into()))
                .collect();
            serde_json::json!({
                "index": r.index, "cost": r.cost, "ending": serde_json::to_value(r.ending).unwrap_or_default(),
                "iterations": r.iterations, "evaluations": r.evaluations, "parameters": params,
            })
        })
        .collect();
    let mut doc = run.file.to_json();
    if let Some(obj) = doc.as_object_mut() {
        obj.insert("start_results".into(), serde_json::Value::Array(starts));
    }
    Ok(doc.to_string())
}

/// The likelihood a fit's estimate and intervals were measured on, rebuilt from its fit
/// file: χ² as a function of the estimated parameters (SI values).
#[pyclass(module = "vanefit._core", frozen)]
struct PyLikelihood {
    inner: FitLikelihood,
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
    /// Rebuilds the likelihood of the fit file at `fit` on dataset `ds`.
    #[new]
    fn new(py: Python<'_>, ds: &PyDataset, fit: PathBuf) -> PyResult<Self> {
        let f = FitFile::read(&fit).map_err(data_err)?;
        let inner = py
            .detach(|| FitLikelihood::from_fit(&ds.inner, &f))
            .map_err(likelihood_err)?;
        Ok(Self { inner })
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

    /// χ² at the estimate as the fit file states it.
    #[getter]
    fn chi2_min(&self) -> f64 {
        self.inner.chi2_min()
    }

    /// Rise of χ² that bounds a 95 % profile interval.
    #[getter]
    fn threshold(&self) -> f64 {
        self.inner.threshold()
    }

    /// χ² at `x` (SI); raises on a bad vector or a failed simulation.
    fn chi2(&self, py: Python<'_>, x: Vec<f64>) -> PyResult<f64> {
        py.detach(|| self.inner.try_chi2(&x))
            .map_err(likelihood_err)
    }

    /// The residual vector at `x` (SI): the compared rows after the nuisances' correction,
    /// then one row per nuisance prior; its squares sum to χ². Raises like `chi2`.
    fn residuals(&self, py: Python<'_>, x: Vec<f64>) -> PyResult<Vec<f64>> {
        py.detach(|| self.inner.residuals(&x))
            .map_err(likelihood_err)
    }

    /// χ² at `x` for an optimizer: always finite (a large penalty where `x` is invalid or
    /// the simulation fails).
    fn chi2_or_penalty(&self, py: Python<'_>, x: Vec<f64>) -> f64 {
        py.detach(|| self.inner.chi2(&x))
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
        Ok(serde_json::json!({
            "chi2": b.chi2(), "chi2_data": b.chi2_data, "chi2_prior": b.chi2_prior,
            "channels": channels, "nuisances": nuisances,
        })
        .to_string())
    }
}

/// Diagnoses a dataset as `vanefit diagnose` does; returns the diagnosis as JSON and writes
/// its files to `out` when given.
#[pyfunction]
#[pyo3(signature = (ds, starts, seed, threads, out, progress))]
fn diagnose(
    py: Python<'_>,
    ds: &PyDataset,
    starts: usize,
    seed: u64,
    threads: Option<usize>,
    out: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    use vanefit::diagnose::{diagnose_observed, DiagnoseOptions};
    if starts == 0 {
        return Err(ParameterError::new_err("starts must be at least 1"));
    }
    if threads == Some(0) {
        return Err(ParameterError::new_err("threads must be at least 1"));
    }
    let mut opts = DiagnoseOptions::full(starts, seed);
    opts.threads = threads;
    let observer = PyDiagnoseProgress::new(progress);
    let d = py.detach(|| {
        let engine =
            vanefit::estimate::Engine::with_threads(opts.threads).map_err(|e| e.to_string())?;
        let d =
            diagnose_observed(&ds.inner, &opts, &engine, &observer).map_err(|e| e.to_string())?;
        if let Some(o) = &out {
            vanefit::report::diagnose::write_all(&d, o).map_err(|e| e.to_string())?;
        }
        Ok::<_, String>(d)
    });
    observer.raise_callback_error(py)?;
    let d = d.map_err(VanefitError::new_err)?;
    let mut doc = vanefit::diagnose::to_json(&d);
    if let Some(obj) = doc.as_object_mut() {
        obj.insert("summary".into(), vanefit::diagnose::summary(&d).into());
        obj.insert(
            "extended_fit".into(),
            vanefit::diagnose::extended_fit_file(&d),
        );
    }
    Ok(doc.to_string())
}

/// Runs a `vanefit` command line in this process (`args` without the program name): the
/// same code and messages as the command. Bad usage raises ParameterError with clap's
/// text; a failure raises `error` (0: VanefitError, 1: DataError, 2: ParameterError).
#[pyfunction]
fn run_command(py: Python<'_>, args: Vec<String>, error: u8) -> PyResult<()> {
    use clap::Parser;
    let mut all = vec!["vanefit".to_string()];
    all.extend(args);
    let cli = cli::Cli::try_parse_from(&all)
        .map_err(|e| ParameterError::new_err(e.render().to_string().trim().to_string()))?;
    py.detach(|| cli::run(cli)).map_err(|e| match error {
        1 => DataError::new_err(e.0),
        2 => ParameterError::new_err(e.0),
        _ => VanefitError::new_err(e.0),
    })
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
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(run_command, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
