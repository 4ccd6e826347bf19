//! Prediction, PEtab export and synthetic datasets: the library's functions called with
//! typed values (no command line in between), returning the tables as the CSV text the
//! command writes (so a DataFrame read from it equals one read from the file) and writing
//! files only when the caller gives a folder.

use crate::errors::{data_err, param_err, DataError, ParameterError, VanefitError};
use crate::fitting::option_err;
use pyo3::prelude::*;
use pyo3::types::PyByteArray;
use std::path::{Path, PathBuf};
use vanefit::data::Dataset;
use vanefit::data::FitFile;

/// A fit file from `path`, or from `text` (a fit held in memory; `path` then only names it
/// in messages).
pub fn load_fit(path: &Path, text: Option<&str>) -> PyResult<FitFile> {
    match text {
        Some(t) => FitFile::parse(path, t).map_err(data_err),
        None => FitFile::read(path).map_err(data_err),
    }
}

/// The kept posterior samples of a prediction for Python: the SI values
/// (walker × step × parameter) and ln p (walker × step) as little-endian f64 bytes, the
/// shape (walkers, steps, parameters) and the acceptance per walker.
pub type SamplesOut<'py> = (
    Bound<'py, PyByteArray>,
    Bound<'py, PyByteArray>,
    (usize, usize, usize),
    Vec<f64>,
);

/// `values` as little-endian f64 bytes.
fn f64_bytes<'py>(
    py: Python<'py>,
    values: impl Iterator<Item = f64>,
    n: usize,
) -> PyResult<Bound<'py, PyByteArray>> {
    PyByteArray::new_with(py, 8 * n, |bytes| {
        for (chunk, v) in bytes.chunks_exact_mut(8).zip(values) {
            chunk.copy_from_slice(&v.to_le_bytes());
        }
        Ok(())
    })
}

/// The kept samples of `s` for Python ([`SamplesOut`]).
fn samples_out<'py>(
    py: Python<'py>,
    s: &vanefit::predict::PosteriorSummary,
) -> PyResult<SamplesOut<'py>> {
    let k = &s.kept;
    let walkers = k.values.len();
    let steps = k.values.first().map_or(0, Vec::len);
    let d = s.names.len();
    let values = k.values.iter().flatten().flatten().copied();
    let lp = k.log_density.iter().flatten().copied();
    Ok((
        f64_bytes(py, values, walkers * steps * d)?,
        f64_bytes(py, lp, walkers * steps)?,
        (walkers, steps, d),
        k.acceptance.clone(),
    ))
}

/// `bands` as the library's choice: `auto`, `delta` or `samples`.
fn band_choice(bands: &str) -> PyResult<vanefit::predict::BandChoice> {
    use vanefit::predict::BandChoice;
    match bands {
        "auto" => Ok(BandChoice::Auto),
        "delta" => Ok(BandChoice::Delta),
        "samples" => Ok(BandChoice::Samples),
        other => Err(param_err(format!(
            "bands {other:?}: use \"auto\", \"delta\" or \"samples\""
        ))),
    }
}

/// What the fitted motor does at other supply pressures or behind a nozzle, as `vanefit
/// predict`: JSON with the tables (`catalogue`, `factors`, `curves`: CSV text with the
/// command's columns and numbers), `notes`, `report` (the markdown of `predict.md`),
/// `bands` (`bands.json`: the method, why, the posterior summary) and `written` (the
/// files, when `out` is given); and the kept posterior samples ([`SamplesOut`], `None`
/// when none were drawn). The dataset is `data`, else the one the fit file records
/// (`vanefit::data::locate`; `fit` = `<fit>`: a fit held in memory, looked up by name).
/// `progress(stage, done, total)` is called at each tenth of the sampling and of the
/// propagation of the samples.
#[pyfunction]
#[pyo3(signature = (fit, fit_text, pressures, unit, reference, inlet_nozzle, outlet_nozzle, speed_grid_rpm, curve_points, fixed_spread, out, data=None, bands=None, steps=None, burn_in=None, draws=None, seed=None, walkers=None, progress=None))]
#[allow(clippy::too_many_arguments)]
pub fn predict<'py>(
    py: Python<'py>,
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
    data: Option<PathBuf>,
    bands: Option<String>,
    steps: Option<usize>,
    burn_in: Option<usize>,
    draws: Option<usize>,
    seed: Option<u64>,
    walkers: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(String, Option<SamplesOut<'py>>)> {
    use vanefit::predict::SamplingOptions;
    use vanefit::task;
    use vanefit::task::PredictOptions;
    let file = load_fit(&fit, fit_text.as_deref())?;
    let d = SamplingOptions::default();
    let settings = PredictOptions {
        unit: task::pressure_unit(task::Opt::PredictUnit, &unit).map_err(|e| option_err(&e))?,
        pressures,
        reference,
        inlet_nozzle_m3_s_pa: inlet_nozzle,
        outlet_nozzle_m3_s_pa: outlet_nozzle,
        speed_grid_rpm,
        curve_points,
        fixed_spread,
        bands: band_choice(bands.as_deref().unwrap_or("auto"))?,
        data,
        sampling: SamplingOptions {
            walkers,
            steps: steps.unwrap_or(d.steps),
            burn_in: burn_in.unwrap_or(d.burn_in),
            draws: draws.unwrap_or(d.draws),
            seed: seed.unwrap_or(d.seed),
            // Beside the outputs, as `vanefit predict` keeps it (docs/cli.md, "predict").
            checkpoint: out.as_ref().map(|o| o.join("samples.checkpoint")),
            ..d
        },
    }
    .check(task::fit_atmosphere_pa(&file))
    .map_err(|e| option_err(&e))?;
    let fit_path = (fit.as_os_str() != "<fit>").then_some(fit.as_path());
    let observer = crate::observe::PyPredictProgress::new(progress);
    let tell = |what: &str, done: usize, total: usize| observer.tell(what, done, total);
    let pr = py.detach(|| task::predict_located(fit_path, &file, &settings, &tell));
    observer.raise_callback_error()?;
    let pr = pr.map_err(|e| match e {
        task::PredictTaskError::Option(o) => option_err(&o),
        other => VanefitError::new_err(other.to_string()),
    })?;
    let source = task::source_name(&fit, &file);
    let mut written = Vec::new();
    if let Some(dir) = &out {
        vanefit::io::check_dir(dir).map_err(|e| param_err(format!("out {e}")))?;
        written = py
            .detach(|| task::write_prediction(&pr, &settings, &source, dir))
            .map_err(|e| VanefitError::new_err(e.to_string()))?;
    }
    let samples = pr
        .bands
        .sampling
        .as_ref()
        .map(|s| samples_out(py, s))
        .transpose()?;
    Ok((prediction_json(&pr, &settings, &source, &written), samples))
}

/// The JSON `predict` hands to Python: the tables as CSV text, the notes, the report,
/// `bands.json`, the sampled parameters' names, the unit and the files written.
fn prediction_json(
    pr: &vanefit::predict::Prediction,
    settings: &vanefit::task::PredictSettings,
    source: &str,
    written: &[PathBuf],
) -> String {
    use vanefit::report::predict as report;
    let display = settings.display();
    serde_json::json!({
        "catalogue": report::catalogue_csv(pr, display),
        "factors": report::factors_csv(pr, display),
        "curves": report::curves_csv(pr, display),
        "notes": report::notes(pr, display),
        "report": report::markdown(pr, display, source),
        "bands": report::sampling_json(pr),
        "sampled": pr.bands.sampling.as_ref().map(|s| &s.names),
        "unit": display.unit.suffix(),
        "written": written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    })
    .to_string()
}

/// The dataset folder the fit was made from, by the rule `vanefit predict` follows
/// (`vanefit::data::locate`: the fit file's `dataset_path`, else `measurements/<dataset>`
/// beside its folder or in the current one; `fit` = `<fit>`: a fit held in memory):
/// (the folder or `None`, where it was found or looked for, in words).
#[pyfunction]
#[pyo3(signature = (fit, fit_text))]
pub fn find_dataset(fit: PathBuf, fit_text: Option<String>) -> PyResult<(Option<String>, String)> {
    use vanefit::data::locate::{locate_dataset, Located};
    let file = load_fit(&fit, fit_text.as_deref())?;
    let fit_path = (fit.as_os_str() != "<fit>").then_some(fit.as_path());
    let located = locate_dataset(fit_path, &file);
    let said = located.describe(&file.dataset);
    Ok(match located {
        Located::Found(dir, _) => (Some(dir.display().to_string()), said),
        _ => (None, said),
    })
}

/// Writes the fitted motor as an FMU to the file `out` (as `vanefit export-fmu`): the fit
/// file `fit`, or its text `fit_text` (held in memory; `fit` then only names it), and the
/// shared library `binary` (none: `$VANEFIT_FMU_BINARY`, else where the build left it).
/// Returns the summary JSON (`variables`, `model_parameters`, `bytes`, `guid`, `binary`).
/// A fit that cannot be read is a DataError, one the FMU cannot represent or a library not
/// found a ParameterError, a file that cannot be written a VanefitError.
#[pyfunction]
#[pyo3(signature = (fit, fit_text, out, binary))]
pub fn export_fmu(
    py: Python<'_>,
    fit: PathBuf,
    fit_text: Option<String>,
    out: PathBuf,
    binary: Option<PathBuf>,
) -> PyResult<String> {
    use vanefit::export::fmu::FmuError;
    if out.is_dir() {
        return Err(ParameterError::new_err(format!(
            "out {}: is a folder, not a file",
            out.display()
        )));
    }
    let opts = vanefit::task::FmuOptions {
        fit,
        fit_text,
        out,
        binary,
    };
    let done = py
        .detach(|| vanefit::task::export_fmu(&opts))
        .map_err(|e| match e {
            FmuError::FitFile(_) => data_err(e),
            FmuError::Unrepresentable { .. } | FmuError::NoBinary { .. } => param_err(e),
            _ => VanefitError::new_err(e.to_string()),
        })?;
    let s = &done.summary;
    Ok(serde_json::json!({
        "variables": s.variables, "model_parameters": s.model_parameters,
        "bytes": s.bytes, "guid": s.guid, "binary": done.binary,
    })
    .to_string())
}

/// Writes the fit as a PEtab v1 problem into `out` (as `vanefit export-petab`); returns the
/// summary JSON (`measurements`, `observables`, `conditions`, `chi2_rows`, `chi2_priors`,
/// `chi2_motor_priors`, `objective`).
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
    vanefit::io::check_dir(&out).map_err(|e| param_err(format!("out {e}")))?;
    let file = load_fit(&fit, fit_text.as_deref())?;
    let ds = Dataset::load(&dataset).map_err(data_err)?;
    let (tables, summary) = py
        .detach(|| petab::tables(&ds, &file, &fit))
        .map_err(data_err)?;
    let _lock = vanefit::io::prepare_dir(&out).map_err(|e| param_err(format!("out {e}")))?;
    petab::write(&out, &tables).map_err(|e| VanefitError::new_err(e.to_string()))?;
    Ok(serde_json::json!({
        "measurements": summary.measurements, "observables": summary.observables,
        "conditions": summary.conditions, "chi2_rows": summary.chi2_rows,
        "chi2_priors": summary.chi2_priors, "chi2_motor_priors": summary.chi2_motor_priors,
        "objective": summary.objective(),
    })
    .to_string())
}

/// Writes a synthetic dataset into `out` as `vanefit synth`: the three reference
/// experiments of the motor of `fit` (none: the default motor) with `effects` switched on
/// (none: the fit's), sensor noise `noise` times a typical rig's, and `truth.json`; or, with
/// `catalogue`, catalogue pages at `pressures_bar_g`.
#[pyfunction]
#[pyo3(signature = (out, fit, fit_text, effects, noise, seed, catalogue, pressures_bar_g))]
#[allow(clippy::too_many_arguments)]
pub fn synth(
    py: Python<'_>,
    out: PathBuf,
    fit: Option<PathBuf>,
    fit_text: Option<String>,
    effects: Option<Vec<String>>,
    noise: f64,
    seed: u64,
    catalogue: bool,
    pressures_bar_g: Vec<f64>,
) -> PyResult<()> {
    use vanefit::model::EffectSet;
    use vanefit::task::{synth_motor, write_synthetic, SynthOptions};
    let effects = effects
        .map(|list| EffectSet::parse_list(&list.join(",")))
        .transpose()
        .map_err(|e| param_err(format!("effects: {e}")))?;
    let settings = SynthOptions {
        effects,
        noise,
        seed,
        catalogue,
        pressures_bar_g,
    }
    .check()
    .map_err(|e| option_err(&e))?;
    let file = fit
        .as_deref()
        .map(|p| load_fit(p, fit_text.as_deref()))
        .transpose()?;
    let name = out.file_name().unwrap_or_default().to_string_lossy();
    let (motor, truth) = synth_motor(&name, file.as_ref(), &settings);
    let _lock = vanefit::io::prepare_dir(&out).map_err(|e| param_err(format!("out {e}")))?;
    py.detach(|| write_synthetic(&out, &motor, &truth, &settings))
        .map_err(|e| DataError::new_err(e.to_string()))?;
    Ok(())
}

/// Ranks the measurements that would shrink the bands of the fit `fit` (or its text
/// `fit_text`) most at the operating `pressures` (in `unit`) and optional `speeds_rpm`, as
/// `vanefit plan` (docs/plan.md): `candidates` the kinds weighed (None: all), `costs` rig
/// hours by kind, `fixed_spread` and `top` as the command's. Returns JSON: `plan` (what
/// `plan.json` holds), `ranking` (the printed table), `notes`, `report` (`plan.md`) and
/// `written` (the files, when `out` is given). A bad option is a ParameterError naming its
/// keyword.
#[pyfunction]
#[pyo3(signature = (fit, fit_text, pressures, unit, speeds_rpm, candidates, costs, fixed_spread, top, out))]
#[allow(clippy::too_many_arguments)]
pub fn plan(
    py: Python<'_>,
    fit: PathBuf,
    fit_text: Option<String>,
    pressures: Vec<f64>,
    unit: String,
    speeds_rpm: Option<Vec<f64>>,
    candidates: Option<Vec<String>>,
    costs: Option<Vec<(String, f64)>>,
    fixed_spread: Option<f64>,
    top: usize,
    out: Option<PathBuf>,
) -> PyResult<String> {
    use vanefit::plan::{CandidateKind, PlanError, PlanOptions};
    use vanefit::report::plan as report;
    use vanefit::report::predict::PressureDisplay;
    use vanefit::task;
    let file = load_fit(&fit, fit_text.as_deref())?;
    let u = task::pressure_unit(task::Opt::PredictUnit, &unit).map_err(|e| option_err(&e))?;
    let p_atm_pa = task::fit_atmosphere_pa(&file);
    let kind = |key: &str, n: &str| {
        CandidateKind::from_name(n).ok_or_else(|| param_err(format!("{key}: no candidate '{n}'")))
    };
    let mut o = PlanOptions::new(
        pressures.iter().map(|p| u.to_si(*p, p_atm_pa)).collect(),
        p_atm_pa,
    );
    o.speeds_rad_s = speeds_rpm.map(|s| {
        s.iter()
            .map(|w| vanefit::units::Unit::Rpm.to_si(*w, 0.0))
            .collect()
    });
    o.kinds = candidates
        .map(|c| {
            c.iter()
                .map(|n| kind("candidates", n))
                .collect::<PyResult<_>>()
        })
        .transpose()?;
    o.costs_h = costs
        .unwrap_or_default()
        .iter()
        .map(|(n, h)| Ok((kind("costs", n)?, *h)))
        .collect::<PyResult<_>>()?;
    o.fixed_spread = fixed_spread;
    o.top = top;
    let keyword = |e: PlanError| {
        let key = match e {
            PlanError::NoPressures | PlanError::BadPressure(_) => "pressures",
            PlanError::BadSpeed(_) => "speeds",
            PlanError::BadCost { .. } => "costs",
            PlanError::BadSpread(_) => "fixed_spread",
            PlanError::BadTop => "top",
            PlanError::NoKinds => "candidates",
            e => return VanefitError::new_err(e.to_string()),
        };
        param_err(format!("{key}: {e}"))
    };
    o.check().map_err(keyword)?;
    let p = py
        .detach(|| vanefit::plan::plan(&file, &o, &|_, _, _| {}))
        .map_err(keyword)?;
    let display = PressureDisplay { unit: u, p_atm_pa };
    let source = task::source_name(&fit, &file);
    let mut written = Vec::new();
    if let Some(dir) = &out {
        vanefit::io::check_dir(dir).map_err(|e| param_err(format!("out {e}")))?;
        std::fs::create_dir_all(dir).map_err(|e| VanefitError::new_err(e.to_string()))?;
        written = report::write(&p, &display, &source, dir)
            .map_err(|e| VanefitError::new_err(e.to_string()))?;
    }
    Ok(serde_json::json!({
        "plan": report::json(&p),
        "ranking": report::ranking_markdown(&p, &display),
        "notes": report::notes(&p),
        "report": report::markdown(&p, &display, &source),
        "unit": display.unit.suffix(),
        "written": written.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    })
    .to_string())
}
