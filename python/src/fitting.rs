//! The fit and the diagnosis: the library's own runs, with the GIL released, progress to a
//! Python callable and Ctrl-C honoured (`observe`). Each returns the result as the files
//! the command line writes hold it (the fit file's text, byte for byte; the diagnosis's
//! JSON), so the Python objects read and write exactly those files.

use crate::errors::{DataError, ParameterError, VanefitError};
use crate::observe::{PyDiagnoseProgress, PyFitProgress};
use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use std::path::PathBuf;
use vanefit::data::Dataset;
use vanefit::data::FitFile;
use vanefit::estimate::EstimateError;
use vanefit::estimate::UncertaintyMethod;
use vanefit::model::EffectSet;
use vanefit::task::OptionError;
use vanefit::task::{FitError, FitOptions};

/// The text of a fit file as `vanefit fit` writes it (`FitFile::write`).
pub fn fit_text(file: &FitFile) -> String {
    serde_json::to_string_pretty(&file.to_json()).expect("plain data") + "\n"
}

/// A bad option as ParameterError, named as the Python keyword (the field's name:
/// `FitOptions.starts` → `starts`).
pub fn option_err(e: &OptionError) -> PyErr {
    let field = e.field();
    let name = field.rsplit('.').next().unwrap_or(field);
    ParameterError::new_err(e.message_as(name))
}

/// The error of a fit as the exception Python users catch (Ctrl-C: KeyboardInterrupt).
fn fit_err(e: FitError) -> PyErr {
    use FitError as E;
    match e {
        E::Estimate(EstimateError::Interrupted) => PyKeyboardInterrupt::new_err(e.to_string()),
        E::Option(o) => option_err(&o),
        E::Data(_) | E::Cost(_) => DataError::new_err(e.to_string()),
        E::Estimate(_) | E::Write { .. } | E::Plot(_) => VanefitError::new_err(e.to_string()),
        _ => ParameterError::new_err(e.to_string()),
    }
}

fn uncertainty_of(name: &str) -> PyResult<UncertaintyMethod> {
    UncertaintyMethod::from_id(name).ok_or_else(|| {
        ParameterError::new_err(format!(
            "uncertainty '{name}': must be 'profile', 'curvature' or 'none'"
        ))
    })
}

/// Fits a dataset exactly as `vanefit fit` does. Returns the fit file's text and every
/// start as JSON (`index`, `cost`, `ending`, `iterations`, `evaluations`, `parameters`);
/// writes the fit file and its starts file (`<out>.starts.jsonl`) when `out` is given, and
/// with `resume` continues from that starts file. Ctrl-C (or an exception raised by
/// `progress`) stops the starts at their next round: the finished ones are in the starts
/// file, and the exception is raised.
#[pyfunction]
#[pyo3(signature = (dataset, starts, seed, threads, effects, estimate, uncertainty, max_iters, out, resume, progress, handoff=true))]
#[allow(clippy::too_many_arguments)]
pub fn fit(
    py: Python<'_>,
    dataset: PathBuf,
    starts: usize,
    seed: u64,
    threads: Option<usize>,
    effects: Vec<String>,
    estimate: Option<Vec<String>>,
    uncertainty: &str,
    max_iters: u64,
    out: Option<PathBuf>,
    resume: bool,
    progress: Option<Py<PyAny>>,
    handoff: bool,
) -> PyResult<(String, String)> {
    if resume && out.is_none() {
        return Err(ParameterError::new_err(
            "resume: give out=, the fit file whose starts file to resume",
        ));
    }
    let effects = EffectSet::parse_list(&effects.join(","))
        .map_err(|e| ParameterError::new_err(format!("effects: {e}")))?;
    let settings = FitOptions {
        starts,
        seed,
        threads,
        effects,
        estimate,
        max_iters,
        handoff,
        uncertainty: uncertainty_of(uncertainty)?,
        resume,
        ..FitOptions::default()
    }
    .check()
    .map_err(|e| option_err(&e))?;
    let results = out
        .as_ref()
        .map(|o| vanefit::task::side_path(o, "starts.jsonl"));
    let observer = PyFitProgress::new(progress);
    let run = py.detach(|| vanefit::task::fit(&dataset, &settings, results, &observer));
    // The callback's exception (or the KeyboardInterrupt) first: it is why a run stopped.
    observer.raise_callback_error()?;
    let mut run = run.map_err(fit_err)?;
    if let Some(o) = &out {
        // The Fit returned is the file written, its dataset_path included.
        run.file = vanefit::task::write_fit_file(&run.file, &dataset, o).map_err(fit_err)?;
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
                .map(|(d, t)| (d.name().to_string(), d.value(*t).into()))
                .collect();
            serde_json::json!({
                "index": r.index, "cost": r.cost,
                "ending": serde_json::to_value(r.ending).unwrap_or_default(),
                "iterations": r.iterations, "evaluations": r.evaluations, "parameters": params,
            })
        })
        .collect();
    Ok((
        fit_text(&run.file),
        serde_json::Value::Array(starts).to_string(),
    ))
}

/// Diagnoses a dataset as `vanefit diagnose` does; returns the texts of `diagnosis.json` and
/// `extended.json` (the chosen model's fit file) as the command writes them, and the
/// summary paragraph it prints; writes its files to `out` when given.
#[pyfunction]
#[pyo3(signature = (ds, starts, seed, threads, out, progress))]
pub fn diagnose(
    py: Python<'_>,
    ds: &crate::PyDataset,
    starts: usize,
    seed: u64,
    threads: Option<usize>,
    out: Option<PathBuf>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(String, String, String)> {
    use vanefit::task::{diagnose_dataset, write_diagnosis, DiagnoseOptions};
    let settings = DiagnoseOptions {
        starts,
        seed,
        threads,
        ..DiagnoseOptions::default()
    }
    .check()
    .map_err(|e| option_err(&e))?;
    let observer = PyDiagnoseProgress::new(progress);
    let inner: &Dataset = &ds.inner;
    let d = py.detach(|| {
        let engine = vanefit::estimate::Engine::with_threads(settings.threads())
            .map_err(|e| e.to_string())?;
        let d =
            diagnose_dataset(&engine, inner, &settings, &observer).map_err(|e| e.to_string())?;
        if let Some(o) = &out {
            write_diagnosis(&d, o).map_err(|e| e.to_string())?;
        }
        Ok::<_, String>(d)
    });
    observer.raise_callback_error()?;
    let d = d.map_err(VanefitError::new_err)?;
    let text = |v: serde_json::Value| serde_json::to_string_pretty(&v).expect("plain data") + "\n";
    Ok((
        text(vanefit::diagnose::to_json(&d)),
        text(vanefit::diagnose::extended_fit_file(&d)),
        vanefit::diagnose::summary(&d),
    ))
}
