//! Prediction, PEtab export and synthetic datasets: the library's functions called with
//! typed values (no command line in between), returning the tables as the CSV text the
//! command writes (so a DataFrame read from it equals one read from the file) and writing
//! files only when the caller gives a folder.

use crate::errors::{data_err, param_err, DataError, ParameterError, VanefitError};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use vanefit::data::dataset::Dataset;
use vanefit::data::fitfile::FitFile;

/// A fit file from `path`, or from `text` (a fit held in memory; `path` then only names it
/// in messages).
pub fn load_fit(path: &Path, text: Option<&str>) -> PyResult<FitFile> {
    match text {
        Some(t) => FitFile::parse(path, t).map_err(data_err),
        None => FitFile::read(path).map_err(data_err),
    }
}

/// What the fitted motor does at other supply pressures or behind a nozzle, as `vanefit
/// predict`: JSON with the tables (`catalogue`, `factors`, `curves`: CSV text with the
/// command's columns and numbers), `notes`, `report` (the markdown of `predict.md`) and
/// `written` (the files, when `out` is given).
#[pyfunction]
#[pyo3(signature = (fit, fit_text, pressures, unit, reference, inlet_nozzle, outlet_nozzle, speed_grid_rpm, curve_points, fixed_spread, out))]
#[allow(clippy::too_many_arguments)]
pub fn predict(
    py: Python<'_>,
    fit: PathBuf,
    fit_text: Option<String>,
    pressures: Option<Vec<f64>>,
    unit: String,
    reference: Option<f64>,
    inlet_nozzle: Option<f64>,
    outlet_nozzle: Option<f64>,
    speed_grid_rpm: f64,
    curve_points: usize,
    fixed_spread: Option<f64>,
    out: Option<PathBuf>,
) -> PyResult<String> {
    use vanefit::report::predict as report;
    use vanefit::task::predict::{options, PredictArgs};
    let file = load_fit(&fit, fit_text.as_deref())?;
    let args = PredictArgs {
        fit: fit.clone(),
        pressures: pressures.map(|p| {
            p.iter()
                .map(|v| format!("{v:?}"))
                .collect::<Vec<_>>()
                .join(",")
        }),
        unit,
        reference,
        inlet_nozzle,
        outlet_nozzle,
        speed_grid_rpm,
        curve_points,
        fixed_spread,
        out: out.clone().unwrap_or_default(),
    };
    let (opts, unit) = options(&args, &file).map_err(param_err)?;
    let display = report::PressureDisplay {
        unit,
        p_atm_pa: opts.p_atm_pa,
    };
    let pr = py
        .detach(|| vanefit::predict::predict(&file, &opts))
        .map_err(|e| VanefitError::new_err(e.to_string()))?;
    let source = if file.dataset.is_empty() {
        fit.display().to_string()
    } else {
        format!("{} (fit of dataset {})", fit.display(), file.dataset)
    };
    let mut written = Vec::new();
    if let Some(dir) = &out {
        vanefit::io::out::check_dir(dir).map_err(|e| param_err(format!("out {e}")))?;
        std::fs::create_dir_all(dir)
            .map_err(|e| VanefitError::new_err(format!("{}: cannot create: {e}", dir.display())))?;
        py.detach(|| {
            report::write(&pr, &display, &source, dir, &mut |p: &Path| {
                written.push(p.display().to_string())
            })
        })
        .map_err(|e| VanefitError::new_err(e.to_string()))?;
    }
    Ok(serde_json::json!({
        "catalogue": report::catalogue_csv(&pr, &display),
        "factors": report::factors_csv(&pr, &display),
        "curves": report::curves_csv(&pr, &display),
        "notes": report::notes(&pr, &display),
        "report": report::markdown(&pr, &display, &source),
        "unit": display.unit.suffix(),
        "written": written,
    })
    .to_string())
}

/// Writes the fit as a PEtab v1 problem into `out` (as `vanefit export-petab`); returns the
/// summary JSON (`measurements`, `observables`, `conditions`, `chi2_rows`, `chi2_priors`).
#[pyfunction]
#[pyo3(signature = (fit, fit_text, dataset, out))]
pub fn export_petab(
    py: Python<'_>,
    fit: PathBuf,
    fit_text: Option<String>,
    dataset: PathBuf,
    out: PathBuf,
) -> PyResult<String> {
    use vanefit::export::petab;
    if out.is_file() {
        return Err(ParameterError::new_err(format!(
            "out {}: is a file, not a folder",
            out.display()
        )));
    }
    vanefit::io::out::check_dir(&out).map_err(|e| param_err(format!("out {e}")))?;
    let file = load_fit(&fit, fit_text.as_deref())?;
    let ds = Dataset::load(&dataset).map_err(data_err)?;
    let (tables, summary) = py
        .detach(|| petab::tables(&ds, &file, &fit))
        .map_err(data_err)?;
    let _lock = vanefit::io::out::prepare_dir(&out).map_err(|e| param_err(format!("out {e}")))?;
    petab::write(&out, &tables).map_err(|e| VanefitError::new_err(e.to_string()))?;
    Ok(serde_json::json!({
        "measurements": summary.measurements, "observables": summary.observables,
        "conditions": summary.conditions, "chi2_rows": summary.chi2_rows,
        "chi2_priors": summary.chi2_priors,
    })
    .to_string())
}

/// Writes a synthetic dataset into `out` as `vanefit synth`: the three reference
/// experiments of the motor of `fit` (none: the default motor) with `effects` switched on
/// (none: the fit's), sensor noise `noise` times a typical rig's, and `truth.json`.
#[pyfunction]
#[pyo3(signature = (out, fit, fit_text, effects, noise, seed))]
pub fn synth(
    py: Python<'_>,
    out: PathBuf,
    fit: Option<PathBuf>,
    fit_text: Option<String>,
    effects: Option<String>,
    noise: f64,
    seed: u64,
) -> PyResult<()> {
    use vanefit::data::synth::{synthesize, write_dataset, SensorNoise, SynthPlan};
    use vanefit::model::effects::EffectSet;
    use vanefit::model::motor::Motor;
    use vanefit::model::params::MotorParams;
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(ParameterError::new_err(format!(
            "noise {noise}: must be a number >= 0"
        )));
    }
    let file = fit
        .as_deref()
        .map(|p| load_fit(p, fit_text.as_deref()))
        .transpose()?;
    let (params, mut fx) = match &file {
        Some(f) => (f.params.clone(), f.effects.clone()),
        None => (MotorParams::default(), EffectSet::empty()),
    };
    if let Some(list) = &effects {
        fx = EffectSet::parse_list(list).map_err(|m| param_err(format!("effects: {m}")))?;
    }
    let extra = file.as_ref().map(|f| f.extra.clone()).unwrap_or_default();
    let motor = Motor::new(params, fx.clone()).with_extra(&extra);
    let name = out.file_name().unwrap_or_default().to_string_lossy();
    let mut truth = FitFile::from_params(&name, motor.params.clone(), fx);
    truth.extra = extra;
    let _lock = vanefit::io::out::prepare_dir(&out).map_err(|e| param_err(format!("out {e}")))?;
    let plan = SynthPlan::default();
    let experiments = py
        .detach(|| {
            synthesize(
                &motor,
                &vanefit::numerics::DefaultSolver::default(),
                &plan,
                &SensorNoise::typical().scaled(noise),
                seed,
            )
        })
        .map_err(|e| VanefitError::new_err(e.to_string()))?;
    let description = format!("seed {seed}, noise x{noise}.");
    write_dataset(
        &out,
        &experiments,
        &plan,
        &motor,
        &motor.effects,
        &description,
    )
    .map_err(|e| DataError::new_err(e.to_string()))?;
    truth
        .write(&out.join("truth.json"))
        .map_err(|e| VanefitError::new_err(format!("{}: {e}", out.display())))?;
    Ok(())
}
