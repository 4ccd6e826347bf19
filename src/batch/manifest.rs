//! The batch manifest (`manifest.toml`; docs/formats.md, "Manifest"): which datasets, which
//! tasks, and the shared options of each task. Every problem is refused at its place in the
//! file (line and column, from the TOML parser's spans), before any unit runs.
//!
//! ```toml
//! [batch]
//! datasets = ["measurements/*"]        # globs of dataset folders, relative to this file
//! tasks = ["fit", "diagnose", "predict"]
//!
//! [fit]                                # the options of `vanefit fit`, same names
//! starts = 32
//! seed = 1
//!
//! [diagnose]
//! starts = 4
//!
//! [predict]
//! pressures = [3, 4, 5, 6, 7]
//! ```

use crate::data::dataset::{locate_span, DataError};
use crate::estimate::fit::UncertaintyMethod;
use crate::model::effects::EffectSet;
use crate::task::diagnose::{DiagnoseOptions, Effort};
use crate::task::fit::{FitOptions, ParamRange};
use crate::task::predict::{pressure_unit, PredictOptions};
use crate::task::{Opt, OptionError};
use serde::{Deserialize, Serialize};
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// The work a unit does to its dataset.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum TaskKind {
    /// `vanefit fit`: the estimate, its intervals, the fit file.
    Fit,
    /// `vanefit diagnose`: missing physics.
    Diagnose,
    /// `vanefit predict` from the dataset's fit (needs `fit` among the tasks).
    Predict,
}

impl TaskKind {
    /// The name in manifests, folders and `summary.csv`.
    pub fn id(self) -> &'static str {
        match self {
            TaskKind::Fit => "fit",
            TaskKind::Diagnose => "diagnose",
            TaskKind::Predict => "predict",
        }
    }
}

/// A dataset of the batch: its name (the folder's, unique in the batch) and its folder.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DatasetEntry {
    /// Folder name: the dataset's name in unit folders and the summary.
    pub name: String,
    /// The folder (absolute: relative globs are resolved against the manifest's folder).
    pub path: PathBuf,
}

/// A checked manifest.
#[derive(Debug, Clone)]
pub struct Manifest {
    /// The manifest file (absolute).
    pub path: PathBuf,
    /// The datasets, sorted by name.
    pub datasets: Vec<DatasetEntry>,
    /// The tasks, in the order fit, diagnose, predict (predict reads the fit's file).
    pub tasks: Vec<TaskKind>,
    /// Options of every fit.
    pub fit: FitOptions,
    /// Whether a fit draws its plots.
    pub fit_plots: bool,
    /// Options of every diagnosis.
    pub diagnose: DiagnoseOptions,
    /// Options of every prediction.
    pub predict: PredictOptions,
    /// The task tables as written, so that a batch folder knows what made it.
    pub settings: serde_json::Value,
}

/// A manifest that cannot be used: `file:line:column: message` where the place is known.
#[derive(Debug, thiserror::Error)]
#[error(transparent)]
pub struct ManifestError(#[from] pub DataError);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawManifest {
    batch: RawBatch,
    fit: Option<Spanned<RawFit>>,
    diagnose: Option<RawDiagnose>,
    predict: Option<Spanned<RawPredict>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBatch {
    datasets: Spanned<Vec<Spanned<String>>>,
    tasks: Spanned<Vec<Spanned<TaskKind>>>,
}

#[derive(Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
struct RawFit {
    starts: Option<Spanned<usize>>,
    seed: Option<u64>,
    max_iters: Option<u64>,
    uncertainty: Option<Spanned<String>>,
    effects: Option<Spanned<Vec<String>>>,
    estimate: Option<Vec<String>>,
    bounds: Option<Spanned<String>>,
    start_range: Option<Spanned<String>>,
    start_spread: Option<Spanned<f64>>,
    plots: Option<bool>,
}

#[derive(Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
struct RawDiagnose {
    starts: Option<Spanned<usize>>,
    seed: Option<u64>,
    effort: Option<Spanned<String>>,
}

#[derive(Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields)]
struct RawPredict {
    pressures: Option<Vec<f64>>,
    unit: Option<String>,
    reference: Option<f64>,
    inlet_nozzle: Option<f64>,
    outlet_nozzle: Option<f64>,
    speed_grid_rpm: Option<f64>,
    curve_points: Option<usize>,
    fixed_spread: Option<f64>,
}

/// Where the manifest's text is, for located messages.
struct Source<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Source<'_> {
    fn at(&self, span: Range<usize>, message: impl AsRef<str>) -> ManifestError {
        ManifestError(locate_span(
            self.path,
            self.text,
            Some(span),
            message.as_ref(),
        ))
    }
}

impl Manifest {
    /// Reads and checks the manifest at `path`: TOML syntax, known keys, task names, dataset
    /// globs that match at least one folder, unique dataset names and valid task options.
    pub fn load(path: &Path) -> Result<Self, ManifestError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| ManifestError(DataError::new(path, format!("cannot read: {e}"))))?;
        let abs = std::fs::canonicalize(path)
            .map_err(|e| ManifestError(DataError::new(path, format!("cannot read: {e}"))))?;
        Self::parse(&abs, path, &text)
    }

    /// Checks manifest text; `abs` is the file's absolute path (globs resolve against its
    /// folder), `shown` the path messages name. [`Manifest::load`] without reading the file,
    /// for callers that have its text (the fuzz target, which would otherwise write a file
    /// per input).
    pub fn parse(abs: &Path, shown: &Path, text: &str) -> Result<Self, ManifestError> {
        let src = Source { path: shown, text };
        let raw: RawManifest = toml::from_str(text)
            .map_err(|e| ManifestError(locate_span(shown, text, e.span(), e.message())))?;
        let base = abs.parent().unwrap_or(Path::new("/"));
        let datasets = datasets(&src, base, &raw.batch.datasets)?;
        let tasks = tasks(&src, &raw.batch.tasks)?;
        let fit_raw = raw
            .fit
            .unwrap_or_else(|| Spanned::new(0..0, RawFit::default()));
        let (fit, fit_plots) = fit_args(&src, fit_raw.get_ref())?;
        let diag_raw = raw.diagnose.unwrap_or_default();
        let diagnose = diagnose_args(&src, &diag_raw)?;
        let pred_raw = raw
            .predict
            .unwrap_or_else(|| Spanned::new(0..0, RawPredict::default()));
        let predict = predict_args(&src, &pred_raw)?;
        let settings = serde_json::json!({
            "fit": settings_json(fit_raw.get_ref()),
            "diagnose": settings_json(&diag_raw),
            "predict": settings_json(pred_raw.get_ref()),
        });
        Ok(Self {
            path: abs.to_path_buf(),
            datasets,
            tasks,
            fit,
            fit_plots,
            diagnose,
            predict,
            settings,
        })
    }
}

/// A task table as plain JSON (spans dropped), for the batch folder's record.
fn settings_json<T: Serialize>(t: &T) -> serde_json::Value {
    let v = toml::Value::try_from(t).unwrap_or(toml::Value::Table(Default::default()));
    serde_json::to_value(v).unwrap_or_default()
}

/// The dataset folders the globs match, sorted by name; a glob that matches no folder, a bad
/// pattern and two folders of one name are refused at the glob.
fn datasets(
    src: &Source<'_>,
    base: &Path,
    globs: &Spanned<Vec<Spanned<String>>>,
) -> Result<Vec<DatasetEntry>, ManifestError> {
    if globs.get_ref().is_empty() {
        return Err(src.at(globs.span(), "give at least one dataset folder or glob"));
    }
    // Every glob is judged before any is walked: one that could leave the folder would walk
    // the machine's file system (`/*/*/*`, or `.?/`, which glob lets match `..`).
    for g in globs.get_ref() {
        if let Some(why) = leaves_folder(g.get_ref()) {
            return Err(src.at(
                g.span(),
                format!(
                    "'{}' {why}: dataset globs stay inside the manifest's folder; put the manifest in a folder that holds its datasets",
                    g.get_ref()
                ),
            ));
        }
    }
    let mut out: Vec<DatasetEntry> = Vec::new();
    for g in globs.get_ref() {
        let pattern = base.join(g.get_ref());
        let entries = glob::glob(&pattern.to_string_lossy())
            .map_err(|e| src.at(g.span(), format!("not a glob pattern: {e}")))?;
        let mut found = 0;
        for entry in entries {
            let path = entry.map_err(|e| src.at(g.span(), format!("cannot read: {e}")))?;
            if !path.is_dir() {
                continue; // a README next to the datasets is no dataset
            }
            found += 1;
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            match out.iter().find(|d| d.name == name) {
                Some(d) if d.path == path => {}
                Some(d) => {
                    return Err(src.at(
                        g.span(),
                        format!(
                            "two datasets are named '{name}' ({} and {}): unit folders and the summary go by folder name",
                            d.path.display(),
                            path.display()
                        ),
                    ))
                }
                None => out.push(DatasetEntry { name, path }),
            }
        }
        if found == 0 {
            return Err(src.at(
                g.span(),
                format!("'{}' matches no dataset folder", g.get_ref()),
            ));
        }
    }
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

/// Why the dataset glob `glob` could match a path outside the manifest's folder, if it
/// could: an absolute path, a `..` component, or a wildcard component that glob lets match
/// `..` (one that begins with a literal dot, such as `.?` or `.*`: glob offers `.` and `..`
/// to those). Judged on the components alone, before any walking; a symbolic link inside
/// the folder is followed, as the user made it.
fn leaves_folder(glob: &str) -> Option<&'static str> {
    use std::path::Component;
    let path = Path::new(glob);
    if path
        .components()
        .any(|c| matches!(c, Component::RootDir | Component::Prefix(_)))
    {
        return Some("is an absolute path");
    }
    for component in glob.split(std::path::is_separator) {
        if component == ".." {
            return Some("climbs out with '..'");
        }
        // glob offers `.` and `..` only to a component that begins with a literal dot.
        let wild = component.contains(['*', '?', '[']);
        if component.starts_with('.')
            && wild
            && glob::Pattern::new(component).is_ok_and(|p| p.matches(".."))
        {
            return Some("has a component that matches '..' (a wildcard after a leading dot)");
        }
    }
    None
}

/// The tasks in their run order; `predict` needs `fit`, since it predicts from its file.
fn tasks(
    src: &Source<'_>,
    list: &Spanned<Vec<Spanned<TaskKind>>>,
) -> Result<Vec<TaskKind>, ManifestError> {
    let mut tasks: Vec<TaskKind> = list.get_ref().iter().map(|t| *t.get_ref()).collect();
    if tasks.is_empty() {
        return Err(src.at(
            list.span(),
            "give at least one task: fit, diagnose, predict",
        ));
    }
    tasks.sort();
    tasks.dedup();
    if tasks.contains(&TaskKind::Predict) && !tasks.contains(&TaskKind::Fit) {
        let at = list
            .get_ref()
            .iter()
            .find(|t| *t.get_ref() == TaskKind::Predict)
            .map_or(list.span(), |t| t.span());
        return Err(src.at(
            at,
            "predict needs fit among the tasks: it predicts from the dataset's fit",
        ));
    }
    Ok(tasks)
}

/// `[fit]` as the options of a fit (the library's defaults for what it leaves out), and
/// whether it draws plots.
fn fit_args(src: &Source<'_>, raw: &RawFit) -> Result<(FitOptions, bool), ManifestError> {
    let mut a = FitOptions::default();
    if let Some(s) = &raw.starts {
        if *s.get_ref() == 0 {
            return Err(src.at(s.span(), "starts must be at least 1"));
        }
        a.starts = *s.get_ref();
    }
    a.seed = raw.seed.unwrap_or(a.seed);
    a.max_iters = raw.max_iters.unwrap_or(a.max_iters);
    if let Some(u) = &raw.uncertainty {
        a.uncertainty = UncertaintyMethod::from_id(u.get_ref()).ok_or_else(|| {
            src.at(
                u.span(),
                "uncertainty must be \"profile\", \"curvature\" or \"none\"",
            )
        })?;
    }
    if let Some(e) = &raw.effects {
        a.effects = EffectSet::parse_list(&e.get_ref().join(","))
            .map_err(|m| src.at(e.span(), m.to_string()))?;
    }
    a.estimate = raw
        .estimate
        .as_ref()
        .map(|v| v.join(",").split(',').map(str::to_string).collect());
    for (value, field, option) in [
        (&raw.bounds, &mut a.bounds, "bounds"),
        (&raw.start_range, &mut a.start_ranges, "start_range"),
    ] {
        if let Some(v) = value {
            *field = ParamRange::parse_list(v.get_ref())
                .map_err(|_| src.at(v.span(), format!("{option}: give name=lo:hi,...")))?;
        }
    }
    if let Some(s) = &raw.start_spread {
        if !(s.get_ref().is_finite() && *s.get_ref() > 1.0) {
            return Err(src.at(s.span(), "start_spread must be a number > 1"));
        }
        a.start_spread = *s.get_ref();
    }
    Ok((a, raw.plots.unwrap_or(true)))
}

/// `[diagnose]` as the options of a diagnosis, its effort included.
fn diagnose_args(src: &Source<'_>, raw: &RawDiagnose) -> Result<DiagnoseOptions, ManifestError> {
    let mut a = DiagnoseOptions::default();
    if let Some(s) = &raw.starts {
        if *s.get_ref() == 0 {
            return Err(src.at(s.span(), "starts must be at least 1"));
        }
        a.starts = *s.get_ref();
    }
    a.seed = raw.seed.unwrap_or(a.seed);
    a.effort = match raw
        .effort
        .as_ref()
        .map(|e| (e.get_ref().as_str(), e.span()))
    {
        None | Some(("full", _)) => Effort::Full,
        Some(("quick", _)) => Effort::Quick,
        Some((_, span)) => return Err(src.at(span, "effort must be \"full\" or \"quick\"")),
    };
    Ok(a)
}

/// `[predict]` as the options of a prediction, checked as the command checks them (at the
/// standard atmosphere; the fit's own is used when the unit runs).
fn predict_args(
    src: &Source<'_>,
    raw: &Spanned<RawPredict>,
) -> Result<PredictOptions, ManifestError> {
    let mut a = PredictOptions::default();
    let r = raw.get_ref();
    let fail = |e: OptionError| src.at(raw.span(), format!("[predict]: {}", predict_key(&e)));
    if let Some(u) = &r.unit {
        a.unit = pressure_unit(Opt::PredictUnit, u).map_err(fail)?;
    }
    a.pressures = r.pressures.clone();
    a.reference = r.reference.or(a.reference);
    a.inlet_nozzle_m3_s_pa = r.inlet_nozzle;
    a.outlet_nozzle_m3_s_pa = r.outlet_nozzle;
    a.speed_grid_rpm = r.speed_grid_rpm.unwrap_or(a.speed_grid_rpm);
    a.curve_points = r.curve_points.unwrap_or(a.curve_points);
    a.fixed_spread = r.fixed_spread;
    a.check(crate::units::constants::P_ATM_PA).map_err(fail)?;
    Ok(a)
}

/// A bad `[predict]` value's message, named as the command line names it (the manifest's
/// keys are the command's options).
fn predict_key(e: &OptionError) -> String {
    e.message_with(&|o| match o {
        Opt::PredictUnit
        | Opt::PredictPressures
        | Opt::PredictReference
        | Opt::PredictInletNozzle
        | Opt::PredictOutletNozzle
        | Opt::PredictSpeedGrid
        | Opt::PredictCurvePoints
        | Opt::PredictFixedSpread => o.flag(),
        other => other.field(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Manifest, ManifestError> {
        let dir = std::env::temp_dir();
        Manifest::parse(&dir.join("m.toml"), Path::new("m.toml"), text)
    }

    /// Syntax errors, unknown keys and bad values name line and column.
    #[test]
    fn errors_are_located() {
        let e = parse("[batch]\ndatasets = [\"x\"]\ntasks = [\"fitt\"]\n").unwrap_err();
        assert!(e.to_string().starts_with("m.toml:3:10"), "{e}");
        let e = parse("[batch]\ndatasets = [\".\"]\ntasks = [\"fit\"]\n[fit]\nstart = 3\n")
            .unwrap_err();
        assert!(e.to_string().starts_with("m.toml:5:1 (key 'start')"), "{e}");
        let e = parse(
            "[batch]\ndatasets = [\".\"]\ntasks = [\"fit\"]\n[fit]\nuncertainty = \"exact\"\n",
        )
        .unwrap_err();
        assert!(
            e.to_string().starts_with("m.toml:5:15 (value '\"exact\"')"),
            "{e}"
        );
        let e = parse("[batch]\ndatasets = [\".\"]\ntasks = [\"predict\"]\n").unwrap_err();
        assert!(e.to_string().contains("predict needs fit"), "{e}");
    }

    /// A glob that could leave the manifest's folder is refused at its place before any
    /// walking (a walk of `/*/*/*` takes minutes); globs inside it are read.
    #[test]
    fn globs_stay_inside_the_manifest_folder() {
        let dir = tempfile::tempdir().unwrap();
        for d in ["measurements/a", "measurements/b", ".hidden/c"] {
            std::fs::create_dir_all(dir.path().join(d)).unwrap();
        }
        let at = |glob: &str| {
            let text =
                format!("[batch]\ntasks = [\"fit\"]\ndatasets = [\"measurements/*\", {glob:?}]\n");
            Manifest::parse(&dir.path().join("m.toml"), Path::new("m.toml"), &text)
        };
        for bad in [
            "/*/*/*",
            "/",
            "../x/*",
            "measurements/../../*",
            ".?/*",
            ".*",
            "measurements/.?/.?/*",
            "./.[.]/*",
        ] {
            let e = at(bad).map(|_| ()).unwrap_err().to_string();
            assert!(e.starts_with("m.toml:3:31"), "{bad}: {e}");
            assert!(
                e.contains("stay inside the manifest's folder"),
                "{bad}: {e}"
            );
        }
        for good in [
            "measurements/a",
            "./measurements/?",
            ".hidden/*",
            "**/b",
            ".",
        ] {
            assert!(at(good).is_ok(), "{good}: {:?}", at(good).map(|_| ()));
        }
        let names: Vec<String> = at("measurements/[ab]")
            .unwrap()
            .datasets
            .iter()
            .map(|d| d.name.clone())
            .collect();
        assert_eq!(names, ["a", "b"]);
    }
}
