//! Fitted parameter sets as JSON, format `vanefit.fit/1` (docs/formats.md, "Fit files"):
//! written by `fit`, read back by `simulate` and by other tools. Partial files mean
//! defaults for the rest; unknown names, wrong units and non-physical values are refused
//! with the file and line.

use super::statistics::{EstimateMethod, FitStatistics, UncertaintyMethod};
use crate::model::effects::{Effect, EffectSet};
use crate::model::extra::{
    balance_name, coefficient_unit, describe, formula, pressure_id, speed_id, BalanceId, Chamber,
    ExtraTerm, LeakPath, PressureFactor as P, SpeedFactor as W,
};
use crate::model::gear::Gear;
use crate::model::params::{spec, MotorParams, ParamSet, PARAMS};
use crate::sim::recording::ExperimentData;
use crate::units::Quantity;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};

/// The format tag of fit files (docs/formats.md, "Fit files").
pub(crate) const FORMAT: &str = "vanefit.fit/1";

/// A problem with a fit file, shown as `file:line: message` (or `file: message`).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {}", .file.display(), .line.map(|l| format!(":{l}")).unwrap_or_default(), .message)]
pub struct FitFileError {
    /// The fit file.
    pub file: PathBuf,
    /// 1-based line, where known.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

/// One parameter's entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct ParamEntry {
    /// Value in SI.
    pub value: f64,
    /// SI unit (checked on reading; no conversion is done).
    pub unit: String,
    /// Whether the fit estimated it (otherwise it was fixed).
    pub estimated: bool,
    /// 95% interval, where computed.
    pub ci95: Option<[f64; 2]>,
}

/// What a fit could say of one estimated parameter's 95% interval. Exported in
/// the parameter's entry beside `ci95` (which is `[lo, hi]` only when identifiable), so
/// that "not identifiable" is distinct from "not computed": `"identifiable": false` with a
/// `"why"`, and `"bounds95"` holding the ends that closed (`null` for an open side).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamVerdict {
    /// Parameter name.
    pub name: String,
    /// Lower and upper end of the 95% interval, SI; `None` where the profile stays open.
    pub bounds95: [Option<f64>; 2],
    /// Both ends closed and no other optimum competes.
    pub identifiable: bool,
    /// Why not, in words.
    pub why: Option<String>,
}

/// Number of starts and how many converged.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct Starts {
    /// Starts run.
    pub total: usize,
    /// Starts that converged to the best minimum.
    pub converged: usize,
}

/// The work of the run that made the fit: its cost evaluations, which depend on the seed and
/// the data only. The run's wall time and worker threads (one per core by default) are
/// facts of the machine, not of the fit: they are printed, never written, so that a fit
/// file is reproducible byte for byte. Older files also carry `wall_s` and `threads`;
/// readers accept and ignore them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct RunInfo {
    /// Cost evaluations of the whole run.
    pub evaluations: u64,
}

/// The joint uncertainty of the estimated parameters (`covariance` in the file): the
/// covariance of ln θ from the curvature of the likelihood's χ² at the estimate,
/// Σ_log = D·Σ_θ·D with Σ_θ = 2·s²·H⁻¹ in the optimizer's coordinates
/// (`estimate::profile::uncertainty::curvature_covariance`, s² the intervals' scale) and
/// D = diag(d ln v/dθ). Written as
/// `{"space": "log", "parameters": [names], "matrix": [[...]]}`; `null` when a fit computed
/// no intervals or the curvature was not positive definite. A parameter on a bound of the
/// search (no variance) is not listed. The profile intervals (`ci95`)
/// are the better marginal widths; this matrix adds the correlations between parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct LogCovariance {
    /// The estimated parameters, in the matrix's order.
    pub parameters: Vec<String>,
    /// Cov(ln θ_i, ln θ_j), symmetric, positive diagonal.
    pub matrix: Vec<Vec<f64>>,
}

/// What is wrong with one field of a fit file (located by the reader).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub(crate) struct FieldError(pub String);

impl From<&str> for FieldError {
    fn from(message: &str) -> Self {
        FieldError(message.to_string())
    }
}

impl LogCovariance {
    /// The JSON object of the file.
    fn to_json(&self) -> Value {
        serde_json::json!({
            "space": "log",
            "parameters": self.parameters,
            "matrix": self.matrix,
        })
    }

    /// Reads and checks the file's object: log space, known and distinct names, a square
    /// symmetric matrix of finite numbers with a positive diagonal.
    fn from_json(v: &Value) -> Result<Self, FieldError> {
        if v.get("space").and_then(Value::as_str) != Some("log") {
            return Err("covariance.space must be \"log\"".into());
        }
        let parameters: Vec<String> = v
            .get("parameters")
            .and_then(|p| serde_json::from_value(p.clone()).ok())
            .ok_or("covariance.parameters must be a list of parameter names")?;
        for (i, n) in parameters.iter().enumerate() {
            if spec(n).is_none() {
                return Err(FieldError(format!("covariance: unknown parameter '{n}'")));
            }
            if parameters[..i].contains(n) {
                return Err(FieldError(format!(
                    "covariance: parameter '{n}' listed twice"
                )));
            }
        }
        let matrix: Vec<Vec<f64>> = v
            .get("matrix")
            .and_then(|m| serde_json::from_value(m.clone()).ok())
            .ok_or("covariance.matrix must be a list of rows of numbers")?;
        let k = parameters.len();
        if matrix.len() != k || matrix.iter().any(|r| r.len() != k) {
            return Err(FieldError(format!(
                "covariance.matrix must be {k}×{k}, one row per parameter"
            )));
        }
        for i in 0..k {
            if !(matrix[i][i].is_finite() && matrix[i][i] > 0.0) {
                return Err(FieldError(format!(
                    "covariance.matrix: the variance of '{}' must be a positive number",
                    parameters[i]
                )));
            }
            for j in 0..i {
                let (a, b) = (matrix[i][j], matrix[j][i]);
                let scale = (matrix[i][i] * matrix[j][j]).sqrt();
                if !(a.is_finite() && b.is_finite()) || (a - b).abs() > 1e-9 * scale {
                    return Err(FieldError(
                        "covariance.matrix must be symmetric and finite".into(),
                    ));
                }
            }
        }
        Ok(Self { parameters, matrix })
    }
}

/// What the fitted data covered (`conditions` in the file): the rig's atmosphere and the
/// span of supply pressures in the recordings, so that a prediction can say when it
/// extrapolates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FitConditions {
    /// Atmospheric pressure of the rig, Pa absolute.
    pub p_atm_pa: f64,
    /// Lowest and highest supply pressure of the fitted experiments, Pa absolute (`None`:
    /// no experiment states one).
    pub p_supply_range_pa: Option<[f64; 2]>,
}

impl FitConditions {
    /// The conditions of a dataset's experiments: each contributes its `p_supply_pa` where
    /// rig.toml sets one, else the range of its recorded port-1 pressure (a datasheet's
    /// pressure column, a pressure ramp's rising supply); experiments with neither add
    /// nothing.
    pub fn of(p_atm_pa: f64, experiments: &[ExperimentData]) -> Self {
        let pressures = experiments.iter().flat_map(|ex| match ex.p_supply_pa {
            Some(p) => vec![p],
            None => ex
                .recording
                .column(Quantity::PPort1)
                .map(|c| c.si.clone())
                .unwrap_or_default(),
        });
        let (lo, hi) = pressures
            .filter(|p| p.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p), b.max(p))
            });
        Self {
            p_atm_pa,
            p_supply_range_pa: (lo <= hi).then_some([lo, hi]),
        }
    }

    /// Checks the file's values: a positive atmosphere, a range 0 < lo ≤ hi.
    fn check(self) -> Result<Self, FieldError> {
        if !(self.p_atm_pa.is_finite() && self.p_atm_pa > 0.0) {
            return Err(FieldError(
                "conditions.p_atm_pa must be a positive number of Pa".into(),
            ));
        }
        if let Some([lo, hi]) = self.p_supply_range_pa {
            if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
                return Err(FieldError(
                    "conditions.p_supply_range_pa must be [lo, hi] Pa with 0 < lo ≤ hi".into(),
                ));
            }
        }
        Ok(self)
    }
}

/// A complete fit file.
#[derive(Debug, Clone, PartialEq)]
pub struct FitFile {
    /// Name of the dataset that was fitted.
    pub dataset: String,
    /// Where that dataset's folder is, relative to the fit file's folder, `/`-separated
    /// (`dataset_path` in the file; `None`: not recorded, as in files written before it
    /// existed). `predict` samples the fit's posterior on it ([`crate::data::locate`]).
    pub dataset_path: Option<String>,
    /// Catalog effects switched on.
    pub effects: EffectSet,
    /// Every parameter's value (estimated or fixed), SI.
    pub params: MotorParams,
    /// Names of the estimated parameters.
    pub estimated: Vec<String>,
    /// 95% intervals by name (absent: not computed).
    pub ci95: Vec<(String, [f64; 2])>,
    /// Final cost, where a fit made the file.
    pub cost: Option<f64>,
    /// Start counts of the fit.
    pub starts: Option<Starts>,
    /// Seed of the start design.
    pub seed: Option<u64>,
    /// The fit's cost evaluations.
    pub run: Option<RunInfo>,
    /// Terms outside the catalog (`model.discovered`, written by `vanefit diagnose`).
    pub extra: Vec<ExtraTerm>,
    /// Identifiability of the estimated parameters (empty: not computed).
    pub verdicts: Vec<ParamVerdict>,
    /// The fit's statistics, where a fit made the file.
    pub statistics: Option<FitStatistics>,
    /// Covariance of the estimated parameters' logarithms, where the fit computed one.
    pub covariance: Option<LogCovariance>,
    /// What the fitted data covered (files written before it existed: `None`).
    pub conditions: Option<FitConditions>,
    /// The likelihood profiles the intervals were read from, one per estimated parameter
    /// (empty without profile intervals).
    pub profiles: Vec<ProfilePath>,
    /// The gearbox of a geared motor (`gear` in the file; docs/formats.md, "Geared
    /// motors"): the parameters are the motor shaft's, the pages were the output shaft's.
    /// `None`: no gearbox, and no `gear` in the file.
    pub gear: Option<Gear>,
}

/// A parameter's likelihood profile as a fit file keeps it: the parameter held at each
/// `value` (SI, increasing), the others re-optimised, and the rise of χ² there above its
/// minimum; the interval ends where it crosses `statistics.profile_threshold`. Written as
/// `"profiles": {"<name>": {"value": [...], "delta_chi2": [...]}}`, columns that pandas and
/// pyPESTO users read directly.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProfilePath {
    /// The parameter.
    #[serde(skip)]
    pub parameter: String,
    /// Its values along the profile, SI, increasing.
    pub value: Vec<f64>,
    /// χ² − χ²_min at each value.
    pub delta_chi2: Vec<f64>,
}

impl ProfilePath {
    /// Checks a path read from a file: equal lengths, finite numbers, values increasing.
    fn check(self) -> Result<Self, FieldError> {
        let name = &self.parameter;
        if self.value.len() != self.delta_chi2.len() {
            return Err(FieldError(format!(
                "profiles.{name}: {} values but {} delta_chi2",
                self.value.len(),
                self.delta_chi2.len()
            )));
        }
        if self
            .value
            .iter()
            .chain(&self.delta_chi2)
            .any(|v| !v.is_finite())
        {
            return Err(FieldError(format!(
                "profiles.{name}: numbers must be finite"
            )));
        }
        if self.value.windows(2).any(|w| w[1] < w[0]) {
            return Err(FieldError(format!(
                "profiles.{name}: values must be increasing"
            )));
        }
        Ok(self)
    }
}

impl FitFile {
    /// A fit file holding plain parameters (nothing estimated).
    pub fn from_params(dataset: &str, params: MotorParams, effects: EffectSet) -> Self {
        Self {
            dataset: dataset.to_string(),
            dataset_path: None,
            effects,
            params,
            estimated: Vec::new(),
            ci95: Vec::new(),
            cost: None,
            starts: None,
            seed: None,
            run: None,
            extra: Vec::new(),
            verdicts: Vec::new(),
            statistics: None,
            covariance: None,
            conditions: None,
            profiles: Vec::new(),
            gear: None,
        }
    }

    /// The JSON document (parameters in the fixed order of `params::PARAMS`; effect
    /// parameters only for the effects switched on).
    pub fn to_json(&self) -> Value {
        let mut doc = Map::new();
        doc.insert("format".into(), FORMAT.into());
        doc.insert("dataset".into(), self.dataset.clone().into());
        if let Some(p) = &self.dataset_path {
            doc.insert("dataset_path".into(), p.clone().into());
        }
        let mut model = serde_json::json!({ "effects": self.effects.ids() });
        if !self.extra.is_empty() {
            model["discovered"] = Value::Array(self.extra.iter().map(term_to_json).collect());
        }
        doc.insert("model".into(), model);
        doc.insert("parameters".into(), Value::Object(self.parameters_json()));
        doc.insert("cost".into(), self.cost.map_or(Value::Null, Value::from));
        doc.insert(
            "starts".into(),
            serde_json::to_value(self.starts).expect("plain data"),
        );
        doc.insert("seed".into(), self.seed.map_or(Value::Null, Value::from));
        doc.insert(
            "run".into(),
            serde_json::to_value(self.run).expect("plain data"),
        );
        if let Some(st) = &self.statistics {
            doc.insert(
                "statistics".into(),
                serde_json::to_value(st).expect("plain data"),
            );
        }
        // A fit says null when it computed no covariance; plain parameter files say nothing.
        match &self.covariance {
            Some(c) => {
                doc.insert("covariance".into(), c.to_json());
            }
            None if self.statistics.is_some() => {
                doc.insert("covariance".into(), Value::Null);
            }
            None => {}
        }
        if let Some(c) = &self.conditions {
            doc.insert(
                "conditions".into(),
                serde_json::to_value(c).expect("plain data"),
            );
        }
        if !self.profiles.is_empty() {
            doc.insert("profiles".into(), Value::Object(self.profiles_json()));
        }
        if let Some(g) = &self.gear {
            doc.insert("gear".into(), gear_to_json(g));
        }
        doc.insert("version".into(), env!("CARGO_PKG_VERSION").into());
        Value::Object(doc)
    }

    /// The `parameters` object: one entry per parameter of `params::PARAMS` in that order
    /// (effect parameters only for the effects switched on), with its interval and verdict.
    fn parameters_json(&self) -> Map<String, Value> {
        let mut parameters = Map::new();
        for s in PARAMS {
            if s.effect.is_some_and(|e| !self.effects.contains(e)) {
                continue;
            }
            let ci = self.ci95.iter().find(|(n, _)| n == s.name).map(|(_, c)| *c);
            let entry = ParamEntry {
                value: self.params.get(s.name).unwrap_or(s.default),
                unit: s.unit.to_string(),
                estimated: self.estimated.iter().any(|n| n == s.name),
                ci95: ci,
            };
            let mut value = serde_json::to_value(entry).expect("plain data");
            if let Some(v) = self.verdicts.iter().find(|v| v.name == s.name) {
                value["identifiable"] = v.identifiable.into();
                value["bounds95"] = serde_json::to_value(v.bounds95).expect("plain data");
                if let Some(why) = &v.why {
                    value["why"] = why.clone().into();
                }
            } else if self.statistics.is_some() && self.estimated.iter().any(|n| n == s.name) {
                // Estimated, but no interval asked for: not computed, said as null.
                value["identifiable"] = Value::Null;
            }
            parameters.insert(s.name.to_string(), value);
        }
        parameters
    }

    /// The `profiles` object: each likelihood profile under its parameter's name.
    fn profiles_json(&self) -> Map<String, Value> {
        self.profiles
            .iter()
            .map(|p| {
                let v = serde_json::to_value(p).expect("plain data");
                (p.parameter.clone(), v)
            })
            .collect()
    }

    /// Writes the file atomically (temporary file, then rename).
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let text = serde_json::to_string_pretty(&self.to_json()).expect("plain data") + "\n";
        crate::io::write_atomic(path, text.as_bytes())
    }

    /// Reads a fit file from disk.
    pub fn read(path: &Path) -> Result<Self, FitFileError> {
        Self::from_read(path, std::fs::read_to_string(path))
    }

    /// The fit file at `path` from the result of reading its text: [`FitFile::read`] for
    /// callers that read files their own way (`merge`'s summary, in memory when fuzzed).
    pub fn from_read(path: &Path, text: std::io::Result<String>) -> Result<Self, FitFileError> {
        let text = text.map_err(|e| FitFileError {
            file: path.to_path_buf(),
            line: None,
            message: format!("cannot read: {e}"),
        })?;
        Self::parse(path, &text)
    }

    /// Parses fit-file text (`path` is used in messages only).
    pub fn parse(path: &Path, text: &str) -> Result<Self, FitFileError> {
        let r = Reader { path, text };
        let doc: Value = serde_json::from_str(text)
            .map_err(|e| r.fail(Some(e.line()), format!("not valid JSON: {e}")))?;
        let obj = doc
            .as_object()
            .ok_or_else(|| r.fail(None, "expected a JSON object".into()))?;
        if let Some(f) = obj.get("format") {
            if f.as_str() != Some(FORMAT) {
                return Err(r.fail(
                    r.line_of("\"format\""),
                    format!("format {f} is not \"{FORMAT}\""),
                ));
            }
        }
        let effects = r.effects(obj)?;
        let extra = r.discovered(obj)?;
        let (params, estimated, ci95) = r.parameters(obj)?;
        let covariance = r.covariance(obj, &estimated)?;
        Ok(FitFile {
            dataset: obj
                .get("dataset")
                .and_then(Value::as_str)
                .unwrap_or_default()
                .to_string(),
            dataset_path: r.dataset_path(obj)?,
            effects,
            params,
            estimated,
            ci95,
            cost: obj.get("cost").and_then(Value::as_f64),
            starts: obj
                .get("starts")
                .and_then(|v| serde_json::from_value(v.clone()).ok()),
            seed: obj.get("seed").and_then(Value::as_u64),
            run: obj
                .get("run")
                .and_then(|v| serde_json::from_value(v.clone()).ok()),
            extra,
            verdicts: verdicts(obj),
            statistics: r.statistics(obj)?,
            covariance,
            conditions: r.conditions(obj)?,
            profiles: r.profiles(obj)?,
            gear: r.gear(obj)?,
        })
    }
}

/// The `gear` object: `{"ratio": G, "efficiency": η, "efficiency_printed": bool,
/// "efficiency_ln_sd": σ(ln η), "shaft": "motor"}`: the parameters are the motor shaft's.
fn gear_to_json(g: &Gear) -> Value {
    serde_json::json!({
        "ratio": g.ratio,
        "efficiency": g.efficiency,
        "efficiency_printed": g.efficiency_printed,
        "efficiency_ln_sd": g.efficiency_ln_sd,
        "parameters_at": "motor shaft",
    })
}

/// The identifiability verdicts written in the parameter entries (informative: a malformed
/// one is left out, not refused, since nothing computes with it).
fn verdicts(obj: &Map<String, Value>) -> Vec<ParamVerdict> {
    let Some(Value::Object(params)) = obj.get("parameters") else {
        return Vec::new();
    };
    params
        .iter()
        .filter_map(|(name, e)| {
            Some(ParamVerdict {
                name: name.clone(),
                identifiable: e.get("identifiable")?.as_bool()?,
                bounds95: serde_json::from_value(e.get("bounds95")?.clone()).ok()?,
                why: e.get("why").and_then(Value::as_str).map(str::to_string),
            })
        })
        .collect()
}

/// Reads the parts of one fit file's text, with errors located at their line.
struct Reader<'a> {
    path: &'a Path,
    text: &'a str,
}

/// What a fit file says of its parameters: the checked values, the estimated names and the
/// 95% intervals.
type ParsedParameters = (MotorParams, Vec<String>, Vec<(String, [f64; 2])>);

impl Reader<'_> {
    fn fail(&self, line: Option<usize>, message: String) -> FitFileError {
        FitFileError {
            file: self.path.to_path_buf(),
            line,
            message,
        }
    }

    /// The first line that contains `needle` (where a key's error is reported).
    fn line_of(&self, needle: &str) -> Option<usize> {
        self.text
            .lines()
            .position(|l| l.contains(needle))
            .map(|i| i + 1)
    }

    /// `model.effects`: a list of catalog ids.
    fn effects(&self, obj: &Map<String, Value>) -> Result<EffectSet, FitFileError> {
        match obj.get("model").and_then(|m| m.get("effects")) {
            None | Some(Value::Null) => Ok(EffectSet::empty()),
            Some(Value::Array(ids)) => ids
                .iter()
                .map(|v| {
                    v.as_str()
                        .ok_or_else(|| "effect ids must be strings".to_string())
                        .and_then(|s| s.parse::<Effect>().map_err(|e| e.to_string()))
                })
                .collect::<Result<EffectSet, _>>()
                .map_err(|m| self.fail(self.line_of("\"effects\""), m)),
            Some(_) => Err(self.fail(
                self.line_of("\"effects\""),
                "model.effects must be a list of ids".into(),
            )),
        }
    }

    /// `model.discovered`: the terms outside the catalog.
    fn discovered(&self, obj: &Map<String, Value>) -> Result<Vec<ExtraTerm>, FitFileError> {
        match obj.get("model").and_then(|m| m.get("discovered")) {
            None | Some(Value::Null) => Ok(Vec::new()),
            Some(Value::Array(items)) => items
                .iter()
                .map(term_from_json)
                .collect::<Result<Vec<_>, _>>()
                .map_err(|e| self.fail(self.line_of("\"discovered\""), e.to_string())),
            Some(_) => Err(self.fail(
                self.line_of("\"discovered\""),
                "model.discovered must be a list".into(),
            )),
        }
    }

    /// The first line from line `from` on (1-based) that contains `needle`: a key inside an
    /// object whose name also appears before it.
    fn line_after(&self, from: Option<usize>, needle: &str) -> Option<usize> {
        let skip = from?.saturating_sub(1);
        self.text
            .lines()
            .enumerate()
            .skip(skip)
            .find(|(_, l)| l.contains(needle))
            .map(|(i, _)| i + 1)
    }

    /// `covariance` (absent or null: none). Predictions compute with it, so a malformed one
    /// is refused rather than left out.
    /// Its parameters must be estimated ones (`estimated`).
    fn covariance(
        &self,
        obj: &Map<String, Value>,
        estimated: &[String],
    ) -> Result<Option<LogCovariance>, FitFileError> {
        let here = || self.line_of("\"covariance\"");
        let c = match obj.get("covariance") {
            None | Some(Value::Null) => return Ok(None),
            Some(v) => LogCovariance::from_json(v).map_err(|m| self.fail(here(), m.0))?,
        };
        match c.parameters.iter().find(|n| !estimated.contains(n)) {
            Some(n) => Err(self.fail(
                here(),
                format!("covariance: parameter '{n}' is not marked as estimated"),
            )),
            None => Ok(Some(c)),
        }
    }

    /// `statistics` (absent or null: none). Its methods are refused at their line when
    /// unknown (a file that names another estimate or interval must not pass for one of
    /// ours); an object that does not read otherwise is left out, as it always was.
    fn statistics(&self, obj: &Map<String, Value>) -> Result<Option<FitStatistics>, FitFileError> {
        let v = match obj.get("statistics") {
            None | Some(Value::Null) => return Ok(None),
            Some(v) => v,
        };
        let here = self.line_of("\"statistics\"");
        let method = |key: &str, read: fn(Value) -> Result<(), serde_json::Error>| {
            let Some(id) = v.get(key) else {
                return Ok(());
            };
            read(id.clone()).map_err(|e| {
                let at = self.line_after(here, &format!("\"{key}\"")).or(here);
                self.fail(at, format!("statistics.{key} {e}"))
            })
        };
        method("estimate", |id| {
            serde_json::from_value::<EstimateMethod>(id).map(drop)
        })?;
        method("uncertainty", |id| {
            serde_json::from_value::<UncertaintyMethod>(id).map(drop)
        })?;
        Ok(serde_json::from_value(v.clone()).ok())
    }

    /// `dataset_path` (absent or null: not recorded): a non-empty string.
    fn dataset_path(&self, obj: &Map<String, Value>) -> Result<Option<String>, FitFileError> {
        match obj.get("dataset_path") {
            None | Some(Value::Null) => Ok(None),
            Some(Value::String(p)) if !p.trim().is_empty() => Ok(Some(p.clone())),
            Some(v) => Err(self.fail(
                self.line_of("\"dataset_path\""),
                format!("dataset_path {v} is not a folder's path (a non-empty string)"),
            )),
        }
    }

    /// `conditions` (absent or null: unknown).
    fn conditions(&self, obj: &Map<String, Value>) -> Result<Option<FitConditions>, FitFileError> {
        let here = || self.line_of("\"conditions\"");
        match obj.get("conditions") {
            None | Some(Value::Null) => Ok(None),
            Some(v) => serde_json::from_value::<FitConditions>(v.clone())
                .map_err(|e| FieldError(format!("conditions: {e}")))
                .and_then(FitConditions::check)
                .map(Some)
                .map_err(|m| self.fail(here(), m.0)),
        }
    }

    /// `gear` (absent or null: no gearbox): ratio finite and > 0, efficiency in (0, 1],
    /// σ(ln η) finite and ≥ 0.
    fn gear(&self, obj: &Map<String, Value>) -> Result<Option<Gear>, FitFileError> {
        let here = || self.line_of("\"gear\"");
        let g = match obj.get("gear") {
            None | Some(Value::Null) => return Ok(None),
            Some(Value::Object(g)) => g,
            Some(_) => return Err(self.fail(here(), "gear must be an object".into())),
        };
        let num = |k: &str| g.get(k).and_then(Value::as_f64);
        let (Some(ratio), Some(efficiency)) = (num("ratio"), num("efficiency")) else {
            return Err(self.fail(here(), "gear needs ratio and efficiency (numbers)".into()));
        };
        let ln_sd = num("efficiency_ln_sd").unwrap_or(0.0);
        if !(ratio.is_finite() && ratio > 0.0) {
            return Err(self.fail(
                here(),
                format!("gear.ratio = {ratio} must be finite and > 0"),
            ));
        }
        if !(efficiency > 0.0 && efficiency <= 1.0) {
            return Err(self.fail(
                here(),
                format!("gear.efficiency = {efficiency} must be in (0, 1]"),
            ));
        }
        if !(ln_sd.is_finite() && ln_sd >= 0.0) {
            return Err(self.fail(
                here(),
                format!("gear.efficiency_ln_sd = {ln_sd} must be finite and >= 0"),
            ));
        }
        Ok(Some(Gear {
            ratio,
            efficiency,
            efficiency_ln_sd: ln_sd,
            efficiency_printed: g
                .get("efficiency_printed")
                .and_then(Value::as_bool)
                .unwrap_or(ln_sd == 0.0),
        }))
    }

    /// `profiles` (absent or null: none): each entry an object of two equal-length columns.
    fn profiles(&self, obj: &Map<String, Value>) -> Result<Vec<ProfilePath>, FitFileError> {
        let here = || self.line_of("\"profiles\"");
        let entries = match obj.get("profiles") {
            None | Some(Value::Null) => return Ok(Vec::new()),
            Some(Value::Object(m)) => m,
            Some(_) => return Err(self.fail(here(), "profiles must be an object".into())),
        };
        entries
            .iter()
            .map(|(name, v)| {
                let at = self
                    .line_after(here(), &format!("\"{name}\""))
                    .or_else(here);
                serde_json::from_value::<ProfilePath>(v.clone())
                    .map_err(|e| FieldError(format!("profiles.{name}: {e}")))
                    .and_then(|p| {
                        ProfilePath {
                            parameter: name.clone(),
                            ..p
                        }
                        .check()
                    })
                    .map_err(|m| self.fail(at, m.0))
            })
            .collect()
    }

    /// `parameters`: defaults overridden by each entry (a number or an object with value,
    /// unit, estimated and ci95), checked as a whole.
    fn parameters(&self, obj: &Map<String, Value>) -> Result<ParsedParameters, FitFileError> {
        let mut set = ParamSet::default();
        let mut estimated = Vec::new();
        let mut ci95 = Vec::new();
        let params = match obj.get("parameters") {
            None => Map::new(),
            Some(Value::Object(m)) => m.clone(),
            Some(_) => {
                return Err(self.fail(
                    self.line_of("\"parameters\""),
                    "parameters must be an object".into(),
                ))
            }
        };
        for (name, entry) in &params {
            let (value, est, ci) = self.entry(name, entry)?;
            let here = self.line_of(&format!("\"{name}\""));
            set.set(name, value)
                .map_err(|e| self.fail(here, e.to_string()))?;
            if est {
                estimated.push(name.clone());
            }
            if let Some(c) = ci {
                ci95.push((name.clone(), c));
            }
        }
        let params = set
            .check()
            .map_err(|e| self.fail(self.line_of(&format!("\"{}\"", e.name)), e.to_string()))?;
        Ok((params, estimated, ci95))
    }

    /// One parameter entry: its value, whether it was estimated, its interval; the name must
    /// be known and a unit, if given, must be the parameter's SI unit.
    fn entry(
        &self,
        name: &str,
        entry: &Value,
    ) -> Result<(f64, bool, Option<[f64; 2]>), FitFileError> {
        let here = self.line_of(&format!("\"{name}\""));
        let s = spec(name).ok_or_else(|| self.fail(here, format!("unknown parameter '{name}'")))?;
        let (value, unit, est, ci) = match entry {
            Value::Number(n) => (n.as_f64(), None, false, None),
            Value::Object(o) => (
                o.get("value").and_then(Value::as_f64),
                o.get("unit").and_then(Value::as_str),
                o.get("estimated").and_then(Value::as_bool).unwrap_or(false),
                o.get("ci95")
                    .and_then(|c| serde_json::from_value::<[f64; 2]>(c.clone()).ok()),
            ),
            _ => (None, None, false, None),
        };
        let value = value.ok_or_else(|| {
            self.fail(
                here,
                format!("parameter '{name}' needs a numeric \"value\""),
            )
        })?;
        if let Some(u) = unit {
            if u != s.unit {
                return Err(self.fail(
                    here,
                    format!(
                        "parameter '{name}' has unit '{u}', expected '{}' (no conversion is done)",
                        s.unit
                    ),
                ));
            }
        }
        Ok((value, est, ci))
    }
}

/// A discovered term in a fit file that cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct TermError(pub String);

/// A discovered term as JSON: `{"balance", "pressure", "speed", "coefficient", "unit",
/// "formula", "description"}` (ids of [`balance_name`], [`pressure_id`], [`speed_id`]; SI
/// coefficient). A leak path has `"balance": "leak_path"`, its ends in `"from"` and `"to"`
/// (`v1`, `v2`, `ve`, `atm`) and its flow law as `"pressure"` (`laminar`, `quadratic`,
/// `orifice`, `iso6358`). Files written before paths existed read unchanged.
pub fn term_to_json(t: &ExtraTerm) -> serde_json::Value {
    let mut v = serde_json::json!({
        "balance": balance_name(t.balance),
        "pressure": pressure_id(t.pressure),
        "speed": speed_id(t.speed),
        "coefficient": t.coefficient,
        "unit": coefficient_unit(t),
        "formula": formula(t),
        "description": describe(t),
    });
    if let BalanceId::Path(path) = t.balance {
        v["from"] = path.from.id().0.into();
        v["to"] = path.to.id().0.into();
    }
    v
}

/// The leak path of a term read from JSON (`from`, `to`).
fn path_from_json(v: &serde_json::Value) -> Result<LeakPath, TermError> {
    let end = |k: &str| {
        let id = v
            .get(k)
            .and_then(serde_json::Value::as_str)
            .ok_or_else(|| {
                TermError(format!(
                    "a leak path needs a string \"{k}\" (v1, v2, ve, atm)"
                ))
            })?;
        Chamber::ALL
            .into_iter()
            .find(|c| c.id().0 == id)
            .ok_or_else(|| TermError(format!("unknown chamber '{id}' (v1, v2, ve, atm)")))
    };
    let (from, to) = (end("from")?, end("to")?);
    if from == to {
        return Err(TermError(format!(
            "a leak path from '{}' to itself",
            from.id().0
        )));
    }
    Ok(LeakPath::new(from, to))
}

/// Reads a term written by [`term_to_json`] (`unit` and `formula` are informative only).
pub fn term_from_json(v: &serde_json::Value) -> Result<ExtraTerm, TermError> {
    let field = |k: &str| {
        v.get(k)
            .and_then(serde_json::Value::as_str)
            .ok_or_else(|| TermError(format!("discovered term needs a string \"{k}\"")))
    };
    let balance = match field("balance")? {
        "torque" => BalanceId::Torque,
        "mass_v1" => BalanceId::Mass1,
        "mass_v2" => BalanceId::Mass2,
        "mass_ve" => BalanceId::MassE,
        "leak_path" => BalanceId::Path(path_from_json(v)?),
        other => return Err(TermError(format!("unknown balance '{other}'"))),
    };
    let p = field("pressure")?;
    let pressure = P::ALL
        .into_iter()
        .find(|x| pressure_id(*x) == p)
        .ok_or_else(|| TermError(format!("unknown pressure factor '{p}'")))?;
    if pressure.is_law() && !matches!(balance, BalanceId::Path(_)) {
        return Err(TermError(format!(
            "the flow law '{p}' needs a leak path (\"balance\": \"leak_path\")"
        )));
    }
    if pressure == P::AirTorque && balance != BalanceId::Torque {
        return Err(TermError(format!(
            "the pressure factor '{p}' is a torque: it enters only \"balance\": \"torque\""
        )));
    }
    let w = field("speed")?;
    let speed = W::ALL
        .into_iter()
        .find(|x| speed_id(*x) == w)
        .ok_or_else(|| TermError(format!("unknown speed factor '{w}'")))?;
    let coefficient = v
        .get("coefficient")
        .and_then(serde_json::Value::as_f64)
        .filter(|c| c.is_finite())
        .ok_or_else(|| {
            TermError("discovered term needs a finite numeric \"coefficient\"".into())
        })?;
    Ok(ExtraTerm {
        balance,
        pressure,
        speed,
        coefficient,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_every_value() {
        let p = MotorParams::default()
            .with("c_1e", 1.234567890123e-9)
            .unwrap();
        let mut f = FitFile::from_params("demo", p, EffectSet::empty().with(Effect::SensorLag));
        f.estimated = vec!["c_1e".into()];
        f.ci95 = vec![("c_1e".into(), [1e-9, 1.5e-9])];
        f.cost = Some(3.5);
        let text = serde_json::to_string_pretty(&f.to_json()).unwrap();
        let back = FitFile::parse(Path::new("f.json"), &text).unwrap();
        assert_eq!(back.params, f.params);
        assert_eq!(back.effects, f.effects);
        assert_eq!(back.estimated, f.estimated);
        assert_eq!(back.ci95, f.ci95);
        assert_eq!(back.cost, Some(3.5));
    }

    /// The statistics' keys as the file has always had them, the goodness of fit inline.
    #[test]
    fn statistics_round_trip_in_their_order_and_unknown_methods_are_refused_at_their_line() {
        use crate::data::statistics::GoodnessOfFit;
        let mut f = FitFile::from_params("demo", MotorParams::default(), EffectSet::empty());
        f.statistics = Some(FitStatistics {
            estimate: EstimateMethod::MaximumLikelihood,
            uncertainty: UncertaintyMethod::Curvature,
            goodness: GoodnessOfFit {
                chi2: 12.5,
                n_points: 10,
                dof: 8,
                chi2_per_dof: Some(12.5 / 8.0),
                noise_ratio: 1.1,
                noise_ratio_limit: 1.3,
                noise_reached: true,
                interval_scale: 1.1,
            },
            best_start_cost: 0.25,
            nuisances: Map::new(),
            widened_noise: Map::new(),
            likelihood_chi2: Some(12.0),
            profile_threshold: None,
            linearised_at: Map::new(),
            prior: Vec::new(),
            prior_chi2: None,
            on_bound: Vec::new(),
        });
        let text = serde_json::to_string_pretty(&f.to_json()).unwrap();
        let doc: Value = serde_json::from_str(&text).unwrap();
        let keys: Vec<&str> = doc["statistics"]
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        assert_eq!(
            keys,
            [
                "estimate",
                "uncertainty",
                "chi2",
                "n_points",
                "dof",
                "chi2_per_dof",
                "noise_ratio",
                "noise_ratio_limit",
                "noise_reached",
                "interval_scale",
                "best_start_cost",
                "nuisances",
                "widened_noise",
                "likelihood_chi2",
                "profile_threshold",
                "linearised_at",
            ]
        );
        assert_eq!(doc["statistics"]["estimate"], "maximum_likelihood");
        assert_eq!(doc["statistics"]["uncertainty"], "curvature");
        let back = FitFile::parse(Path::new("f.json"), &text).unwrap();
        assert_eq!(back.statistics, f.statistics);
        for (from, to, says) in [
            (
                "\"uncertainty\": \"curvature\"",
                "\"uncertainty\": \"bogus\"",
                r#"statistics.uncertainty must be "profile", "curvature" or "none", not "bogus""#,
            ),
            (
                "\"estimate\": \"maximum_likelihood\"",
                "\"estimate\": 3",
                r#"statistics.estimate must be "maximum_likelihood", not 3"#,
            ),
        ] {
            let line = text.lines().position(|l| l.contains(from)).unwrap() + 1;
            let e = FitFile::parse(Path::new("f.json"), &text.replace(from, to)).unwrap_err();
            assert_eq!((e.line, e.message.as_str()), (Some(line), says), "{e}");
        }
    }

    #[test]
    fn covariance_and_conditions_round_trip_and_old_files_read_without_them() {
        let mut f = FitFile::from_params("demo", MotorParams::default(), EffectSet::empty());
        f.estimated = vec!["c_in1".into(), "visc".into()];
        f.covariance = Some(LogCovariance {
            parameters: f.estimated.clone(),
            matrix: vec![vec![4e-6, -1e-6], vec![-1e-6, 9e-6]],
        });
        f.conditions = Some(FitConditions {
            p_atm_pa: 101_325.0,
            p_supply_range_pa: Some([1.2e5, 7.3e5]),
        });
        let text = serde_json::to_string_pretty(&f.to_json()).unwrap();
        assert!(text.contains("\"space\": \"log\""), "{text}");
        let back = FitFile::parse(Path::new("f.json"), &text).unwrap();
        assert_eq!(back.covariance, f.covariance);
        assert_eq!(back.conditions, f.conditions);
        // A file written before these fields existed.
        let old = FitFile::parse(Path::new("f.json"), r#"{"parameters": {}}"#).unwrap();
        assert_eq!((old.covariance, old.conditions), (None, None));
        let with_null = r#"{"parameters": {}, "covariance": null, "conditions": null}"#;
        assert!(FitFile::parse(Path::new("f.json"), with_null).is_ok());
    }

    #[test]
    fn a_malformed_covariance_or_condition_is_refused_at_its_line() {
        let base = |cov: &str| {
            format!(
                "{{\n \"parameters\": {{\"c_in1\": {{\"value\": 7e-9, \"estimated\": true}}}},\n                  \"covariance\": {cov}\n}}"
            )
        };
        for (cov, says) in [
            (
                r#"{"space": "theta", "parameters": ["c_in1"], "matrix": [[1e-6]]}"#,
                "log",
            ),
            (
                r#"{"space": "log", "parameters": ["c_in1"], "matrix": [[-1e-6]]}"#,
                "positive",
            ),
            (
                r#"{"space": "log", "parameters": ["c_in1"], "matrix": [[1, 2]]}"#,
                "1×1",
            ),
            (
                r#"{"space": "log", "parameters": ["visc"], "matrix": [[1e-6]]}"#,
                "not marked",
            ),
            (
                r#"{"space": "log", "parameters": ["c_nope"], "matrix": [[1e-6]]}"#,
                "unknown",
            ),
        ] {
            let e = FitFile::parse(Path::new("f.json"), &base(cov)).unwrap_err();
            assert_eq!(e.line, Some(3), "{e}");
            assert!(e.message.contains(says), "{e}");
        }
        let e = FitFile::parse(
            Path::new("f.json"),
            r#"{"conditions": {"p_atm_pa": 101325, "p_supply_range_pa": [7e5, 2e5]}}"#,
        )
        .unwrap_err();
        assert!(e.message.contains("p_supply_range_pa"), "{e}");
    }

    #[test]
    fn conditions_take_the_stated_supply_or_the_recorded_pressure() {
        use crate::model::motor::Load;
        use crate::sim::recording::{Column, Kind, Recording};
        use crate::units::Unit;
        let ex = |p_supply: Option<f64>, p_column: Option<Vec<f64>>| ExperimentData {
            kind: Kind::PressureRamp,
            file: "x.csv".into(),
            p_supply_pa: p_supply,
            load: Load::None,
            weight: 1.0,
            channel_weights: Default::default(),
            p_supply_written: None,
            p_supply_line: None,
            tolerance: None,
            figures: Vec::new(),
            recording: Recording {
                file: "x.csv".into(),
                columns: p_column
                    .into_iter()
                    .map(|si| Column {
                        name: "p_port1_pa".into(),
                        quantity: Quantity::PPort1,
                        unit: Unit::Pa,
                        raw: si.iter().map(|v| v.to_string()).collect(),
                        si,
                    })
                    .collect(),
                lines: vec![2, 3, 4],
            },
        };
        let c = FitConditions::of(
            1e5,
            &[
                ex(Some(7.3e5), None),
                ex(None, Some(vec![1.1e5, 4e5, 7.5e5])),
                ex(Some(5e5), Some(vec![9e5])),
            ],
        );
        assert_eq!(c.p_supply_range_pa, Some([1.1e5, 7.5e5]));
        assert_eq!(
            FitConditions::of(1e5, &[ex(None, None)]).p_supply_range_pa,
            None
        );
    }

    /// A geared fit's gearbox is written and read back; an ungeared file has no `gear`;
    /// a gearbox that cannot be is refused at its line.
    #[test]
    fn the_gearbox_round_trips_and_bad_ones_are_refused() {
        let mut f = FitFile::from_params("g", MotorParams::default(), EffectSet::empty());
        assert!(f.to_json().get("gear").is_none());
        f.gear = Some(Gear::new(29.0, None));
        let text = serde_json::to_string_pretty(&f.to_json()).unwrap();
        let back = FitFile::parse(Path::new("f.json"), &text).unwrap();
        assert_eq!(back.gear, f.gear);
        for bad in [
            r#"{"parameters": {},
 "gear": {"ratio": 0, "efficiency": 0.9}}"#,
            r#"{"parameters": {},
 "gear": {"ratio": 4, "efficiency": 1.5}}"#,
            r#"{"parameters": {},
 "gear": {"ratio": 4}}"#,
            r#"{"parameters": {},
 "gear": {"ratio": 4, "efficiency": 0.9, "efficiency_ln_sd": -1}}"#,
            r#"{"parameters": {},
 "gear": 4}"#,
        ] {
            let e = FitFile::parse(Path::new("f.json"), bad).unwrap_err();
            assert_eq!(e.line, Some(2), "{bad}: {e}");
            assert!(e.message.contains("gear"), "{e}");
        }
    }

    #[test]
    fn partial_file_means_defaults_and_unknown_names_fail_with_line() {
        let f = FitFile::parse(
            Path::new("f.json"),
            r#"{"parameters": {"visc": {"value": 1e-4}}}"#,
        )
        .unwrap();
        assert_eq!(f.params.visc(), 1e-4);
        assert_eq!(f.params.c_in1(), MotorParams::default().c_in1());
        let text = "{\n \"parameters\": {\n  \"c_in1\": 7e-9,\n  \"c_magic\": 1\n }\n}";
        let e = FitFile::parse(Path::new("f.json"), text).unwrap_err();
        assert_eq!(e.line, Some(4));
        assert!(e.message.contains("unknown parameter 'c_magic'"));
        let e =
            FitFile::parse(Path::new("f.json"), r#"{"parameters": {"vol1": -2e-6}}"#).unwrap_err();
        assert!(e.message.contains("vol1"));
        let e = FitFile::parse(
            Path::new("f.json"),
            r#"{"parameters": {"vol1": {"value": 2e-6, "unit": "l"}}}"#,
        )
        .unwrap_err();
        assert!(e.message.contains("unit 'l'"));
    }
}
