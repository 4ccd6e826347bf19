//! A fit as a PEtab v1 problem (`vanefit export-petab`): the parameter, observable,
//! measurement and condition tables, an SBML document that declares the model's symbols,
//! and the problem YAML.
//!
//! # What the tables say
//!
//! The problem is the likelihood the fit maximised (`estimate::fit::fit_likelihood`): the
//! compared rows of every recording, each channel with its σ (the data's noise, widened where
//! the fit widened it), and the rig's systematic errors as parameters with Gaussian priors.
//! Observable `<recording>_<quantity>` of channel c at row i is
//!
//! ```text
//!     y_obs,i = y_model,i + Σ_k β_k · a_k,i          noise σ_c, normal            [1]
//! ```
//!
//! where y_model is the simulated output (SI; the SBML symbol `speed_rad_s`, `torque_nm`,
//! `flow1_kg_s`, …), β_k the nuisances (a sensor's offset, the supply-pressure sensor's
//! offset; parameter `nuisance_…`, prior N(0, τ_k²) from the calibration tolerance) and
//! a_k,i their effect on the row: 1 for an offset on its own channel (written as a plain
//! `+ β_k`), the linearised response to the supply pressure's offset otherwise (a per-row
//! number in the measurement table's `observableParameters`). At the fit's parameters and
//! β̂, PEtab's χ² of the rows plus the priors' Σ(β̂_k/τ_k)² is the fit file's
//! `statistics.likelihood_chi2`; `vanefit_export.json` states both parts.
//!
//! # The motor prior
//!
//! A fit made with the motor prior (docs/estimation.md, "Priors") minimised χ² + χ²_prior,
//! each estimated parameter with an entry in the fit file's `statistics.prior` being
//! log-normal, ln v ~ N(ln m, σ²). vanefit estimates these parameters on a log scale
//! (`parameterScale` log10), and the fit is the posterior's mode in ln v, i.e. a normal
//! density on the parameter scale with no Jacobian term: PEtab's `parameterScaleNormal`
//! with
//!
//! ```text
//!     objectivePriorParameters = log10 m ; σ / ln 10                               [2]
//! ```
//!
//! (PEtab's `logNormal` is a density of the linear value, whose 1/v factor would move the
//! mode; it is used only for a parameter searched on a linear scale, with ln m ; σ). At the
//! fit, Σ((log10 v − log10 m)/(σ/ln 10))² = Σ((ln v − ln m)/σ)² is the fit file's
//! `statistics.prior_chi2`, so rows + nuisance priors + motor priors is the fit's objective
//! (`objective` in `vanefit_export.json`).
//!
//! # What PEtab cannot carry
//!
//! The model itself: the SBML document declares parameters, inputs and outputs only, and
//! says so; vanefit simulates (the Python package's `Likelihood.breakdown` gives the
//! simulated rows). The recorded inputs as time functions (supply-pressure ramp, outlet
//! throttle): a transient experiment is one condition whose inputs are the recording's.
//! The fitting cost J (per-channel means and reference polynomials), which is vanefit's
//! search criterion, not a likelihood. Where the fit estimated the displacement (a page
//! that does not print it), the motor priors' medians follow it (docs/estimation.md, "A
//! page without a displacement"); PEtab's priors have fixed parameters, so the table
//! states them at the fit's displacement: exact at the fit, not as the displacement moves.

use crate::data::dataset::{Dataset, Kind};
use crate::data::fitfile::FitFile;
use crate::estimate::fit::fit_likelihood::{
    Breakdown, ChannelRows, FitLikelihood, FitLikelihoodError, MotorPriorTerm,
};
use crate::model::params::{ParamId, PARAMS};
use crate::sim::recording::ExperimentData;
use crate::units::Quantity;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Why a fit cannot be exported.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PetabError {
    /// The fit's likelihood cannot be rebuilt or evaluated on the dataset.
    #[error("{0}")]
    Likelihood(#[from] FitLikelihoodError),
    /// A compared channel names a recording or column the dataset does not have.
    #[error("the fit compares '{file}' column '{column}', which the dataset does not have")]
    Channel {
        /// The recording.
        file: String,
        /// The column.
        column: String,
    },
    /// A steady-state row without the recorded speed that sets its operating point.
    #[error("{file}: steady-state row {row} has no speed (needed for its PEtab condition)")]
    NoSpeed {
        /// The recording.
        file: String,
        /// The 0-based data row.
        row: usize,
    },
    /// A file could not be written.
    #[error("{}: {source}", .path.display())]
    Write {
        /// The file or folder.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
}

/// The problem's files as text, built before anything is written.
#[derive(Debug, Clone, PartialEq)]
pub struct PetabTables {
    /// `parameters.tsv`.
    pub parameters: String,
    /// `observables.tsv`.
    pub observables: String,
    /// `measurements.tsv`.
    pub measurements: String,
    /// `conditions.tsv`.
    pub conditions: String,
    /// `model.xml` (SBML Level 3 declaring the symbols).
    pub model: String,
    /// `problem.yaml`.
    pub problem: String,
    /// `vanefit_export.json`: what vanefit computes for the tables at the fit.
    pub summary: String,
}

/// What the export holds, in numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct PetabSummary {
    /// Measurement rows.
    pub measurements: usize,
    /// Observables (one per compared channel).
    pub observables: usize,
    /// Conditions.
    pub conditions: usize,
    /// χ² of the measurement rows at the fit (what `petab.calculate_chi2` gives with
    /// vanefit's simulation and the nuisances at their nominal values).
    pub chi2_rows: f64,
    /// Σ(β̂/τ)² of the nuisances' priors at their nominal values.
    pub chi2_priors: f64,
    /// Σ r² of the pages' power-peak terms at the fit (docs/model.md, "Cost J"): part of
    /// the fit's likelihood that no PEtab table carries (it compares the vertex of the
    /// power at three speeds, not an observable at a condition).
    pub chi2_power_peaks: f64,
    /// χ²_prior of the motor prior at the fit (the parameter table's `parameterScaleNormal`
    /// priors at the nominal values; 0 for a fit made without priors).
    pub chi2_motor_priors: f64,
}

impl PetabSummary {
    /// The fit's objective at its estimate: rows + nuisance priors + power peaks + motor
    /// priors.
    pub fn objective(&self) -> f64 {
        self.chi2_rows + self.chi2_priors + self.chi2_power_peaks + self.chi2_motor_priors
    }
}

/// The file names, in the order they are written (the YAML last, so that a problem that
/// names its tables only appears once they exist).
const FILES: [&str; 7] = [
    "parameters.tsv",
    "observables.tsv",
    "measurements.tsv",
    "conditions.tsv",
    "model.xml",
    "vanefit_export.json",
    "problem.yaml",
];

/// One observable: a compared channel and how the nuisances enter it.
struct Observable {
    id: String,
    name: String,
    formula: String,
    sigma: f64,
    /// Nuisances entering through a per-row number (index into the breakdown's nuisances).
    per_row: Vec<usize>,
}

/// The PEtab tables of a fit on its dataset (`fit_path` and the dataset's folder are named in
/// the summary only).
pub fn tables(
    ds: &Dataset,
    fit: &FitFile,
    fit_path: &Path,
) -> Result<(PetabTables, PetabSummary), PetabError> {
    let likelihood = FitLikelihood::from_fit(ds, fit)?;
    let b = likelihood.breakdown(&likelihood.estimate())?;
    let chi2_motor_priors = likelihood.prior_chi2(&likelihood.estimate());
    let nuisance_ids: Vec<String> = b.nuisances.iter().map(|(l, _, _)| nuisance_id(l)).collect();
    let mut observables = Vec::new();
    let mut measurements = String::from(
        "observableId\tsimulationConditionId\tmeasurement\ttime\tobservableParameters\tdatasetId\n",
    );
    let mut conditions: Vec<Condition> = Vec::new();
    let mut outputs: Vec<String> = Vec::new();
    for c in &b.channels {
        let exp = experiment(ds, c)?;
        let quantity = quantity(exp, c)?;
        let symbol = output_symbol(quantity);
        if !outputs.contains(&symbol) {
            outputs.push(symbol.clone());
        }
        let obs = observable(c, exp, quantity, &symbol, &nuisance_ids);
        rows(c, exp, &obs, &mut measurements, &mut conditions)?;
        observables.push(obs);
    }
    let summary = PetabSummary {
        measurements: b.channels.iter().map(|c| c.rows.len()).sum(),
        observables: observables.len(),
        conditions: conditions.len(),
        chi2_rows: b.chi2_data,
        chi2_priors: b.chi2_prior,
        chi2_power_peaks: b.chi2_power_peaks,
        chi2_motor_priors,
    };
    let t = PetabTables {
        parameters: parameter_table(&likelihood, fit, &b, &nuisance_ids),
        observables: observable_table(&observables),
        measurements,
        conditions: condition_table(&conditions),
        model: sbml(fit, &outputs),
        problem: PROBLEM_YAML.to_string(),
        summary: summary_json(ds, fit, fit_path, &summary, &likelihood),
    };
    Ok((t, summary))
}

/// Writes the tables into `dir` (created if missing), each atomically; the files written.
pub fn write(dir: &Path, t: &PetabTables) -> Result<Vec<PathBuf>, PetabError> {
    std::fs::create_dir_all(dir).map_err(|source| PetabError::Write {
        path: dir.to_path_buf(),
        source,
    })?;
    let texts = [
        &t.parameters,
        &t.observables,
        &t.measurements,
        &t.conditions,
        &t.model,
        &t.summary,
        &t.problem,
    ];
    FILES
        .iter()
        .zip(texts)
        .map(|(name, text)| {
            let path = dir.join(name);
            crate::io::write_atomic(&path, text.as_bytes())
                .map(|()| path.clone())
                .map_err(|source| PetabError::Write { path, source })
        })
        .collect()
}

const PROBLEM_YAML: &str = "format_version: 1
parameter_file: parameters.tsv
problems:
- sbml_files:
  - model.xml
  condition_files:
  - conditions.tsv
  measurement_files:
  - measurements.tsv
  observable_files:
  - observables.tsv
";

/// The experiment a compared channel belongs to.
fn experiment<'a>(ds: &'a Dataset, c: &ChannelRows) -> Result<&'a ExperimentData, PetabError> {
    ds.experiments
        .iter()
        .find(|e| e.file == c.file)
        .ok_or_else(|| PetabError::Channel {
            file: c.file.clone(),
            column: c.column.clone(),
        })
}

/// The quantity of a compared channel's column.
fn quantity(exp: &ExperimentData, c: &ChannelRows) -> Result<Quantity, PetabError> {
    exp.recording
        .columns
        .iter()
        .find(|col| col.name == c.column)
        .map(|col| col.quantity)
        .ok_or_else(|| PetabError::Channel {
            file: c.file.clone(),
            column: c.column.clone(),
        })
}

/// The model's output symbol of a quantity, named with its SI unit (`torque_nm`).
fn output_symbol(q: Quantity) -> String {
    format!("{}_{}", q.prefix(), q.si_unit().suffix())
}

/// A PEtab identifier from free text: letters, digits and `_`, not starting with a digit.
fn petab_id(text: &str) -> String {
    let mut id: String = text
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    while id.contains("__") {
        id = id.replace("__", "_");
    }
    let id = id.trim_matches('_').to_string();
    if id.starts_with(|c: char| c.is_ascii_digit()) || id.is_empty() {
        format!("x_{id}")
    } else {
        id
    }
}

/// The parameter id of a nuisance (`ramp.csv flow1_g_s offset` → `nuisance_ramp_csv_flow1_g_s_offset`).
fn nuisance_id(label: &str) -> String {
    format!("nuisance_{}", petab_id(label))
}

/// A recording's stem as an id part (`ramp.csv` → `ramp`).
fn stem_id(file: &str) -> String {
    let stem = Path::new(file)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or(file);
    petab_id(stem)
}

/// The observable of a channel, eq. \[1\]: an offset on its own channel is a plain `+ β`,
/// any other nuisance that moves its rows enters through a per-row observable parameter.
fn observable(
    c: &ChannelRows,
    exp: &ExperimentData,
    q: Quantity,
    symbol: &str,
    nuisance_ids: &[String],
) -> Observable {
    let id = format!("{}_{}", stem_id(&exp.file), q.prefix());
    let mut formula = symbol.to_string();
    let mut per_row = Vec::new();
    for (k, shape) in c.nuisance_shapes.iter().enumerate() {
        if shape.iter().all(|a| *a == 0.0) {
            continue;
        }
        if shape.iter().all(|a| *a == 1.0) {
            let _ = write!(formula, " + {}", nuisance_ids[k]);
        } else {
            per_row.push(k);
            let _ = write!(
                formula,
                " + {} * observableParameter{}_{id}",
                nuisance_ids[k],
                per_row.len()
            );
        }
    }
    Observable {
        name: format!("{} {}", c.file, c.column),
        id,
        formula,
        sigma: c.sigma,
        per_row,
    }
}

/// One condition of the condition table: a transient recording (inputs empty: the
/// recording drives it) or one steady-state row with its speed and supply pressure.
struct Condition {
    id: String,
    name: String,
    omega_rad_s: Option<f64>,
    p_supply_pa: Option<f64>,
}

/// Adds a condition unless one with its id is there already (several channels of a
/// recording share its conditions).
fn add_condition(conditions: &mut Vec<Condition>, c: Condition) {
    if !conditions.iter().any(|k| k.id == c.id) {
        conditions.push(c);
    }
}

/// The measurement rows of a channel (appended to `out`) and the conditions they need.
/// A recording with time is one condition measured at its times; a steady-state recording
/// (datasheet, catalogue) is one condition per row, at steady state (`time` = inf), set by
/// the row's speed and supply pressure.
fn rows(
    c: &ChannelRows,
    exp: &ExperimentData,
    obs: &Observable,
    out: &mut String,
    conditions: &mut Vec<Condition>,
) -> Result<(), PetabError> {
    let stem = stem_id(&exp.file);
    // A datasheet or catalogue row is a steady state, even where the rig logged a time.
    let steady = matches!(exp.kind, Kind::Datasheet | Kind::Catalogue);
    let time = exp.recording.column(Quantity::Time).filter(|_| !steady);
    let speed = exp.recording.column(Quantity::Speed);
    let p1 = exp.recording.column(Quantity::PPort1);
    if time.is_some() {
        add_condition(
            conditions,
            Condition {
                id: stem.clone(),
                name: format!("{} as recorded", exp.file),
                omega_rad_s: None,
                p_supply_pa: None,
            },
        );
    }
    for (i, (&row, value)) in c.rows.iter().zip(&c.data).enumerate() {
        let (condition, t) = match time {
            Some(tc) => (stem.clone(), tc.si[row]),
            None => {
                let omega = speed
                    .map(|s| s.si[row])
                    .filter(|w| w.is_finite())
                    .ok_or_else(|| PetabError::NoSpeed {
                        file: exp.file.clone(),
                        row,
                    })?;
                let p = p1
                    .map(|p| p.si[row])
                    .filter(|p| p.is_finite())
                    .or(exp.p_supply_pa);
                let id = format!("{stem}_r{row:04}");
                add_condition(
                    conditions,
                    Condition {
                        id: id.clone(),
                        name: format!("{} row {}", exp.file, row + 1),
                        omega_rad_s: Some(omega),
                        p_supply_pa: p,
                    },
                );
                (id, f64::INFINITY)
            }
        };
        let parameters: Vec<String> = obs
            .per_row
            .iter()
            .map(|k| c.nuisance_shapes[*k][i].to_string())
            .collect();
        let _ = writeln!(
            out,
            "{}\t{condition}\t{value}\t{t}\t{}\t{stem}",
            obs.id,
            parameters.join(";")
        );
    }
    Ok(())
}

fn cell(v: Option<f64>) -> String {
    v.map_or_else(String::new, |v| v.to_string())
}

fn condition_table(conditions: &[Condition]) -> String {
    let mut s = String::from("conditionId\tconditionName\tomega_rad_s\tp_supply_pa\n");
    for c in conditions {
        let (omega, p) = (cell(c.omega_rad_s), cell(c.p_supply_pa));
        let _ = writeln!(s, "{}\t{}\t{omega}\t{p}", c.id, c.name);
    }
    s
}

fn observable_table(observables: &[Observable]) -> String {
    let mut s = String::from(
        "observableId\tobservableName\tobservableFormula\tobservableTransformation\tnoiseFormula\tnoiseDistribution\n",
    );
    for o in observables {
        let _ = writeln!(
            s,
            "{}\t{}\t{}\tlin\t{}\tnormal",
            o.id, o.name, o.formula, o.sigma
        );
    }
    s
}

/// The estimated parameters (bounds and scale of vanefit's search, nominal value the fit's
/// estimate, the motor prior where the fit has one, eq. \[2\]) and the nuisances (nominal
/// value β̂, prior N(0, τ²), bounds ±10τ around 0 or wider to hold β̂).
fn parameter_table(
    likelihood: &FitLikelihood,
    fit: &FitFile,
    b: &Breakdown,
    nuisance_ids: &[String],
) -> String {
    let mut s = String::from(
        "parameterId\tparameterName\tparameterScale\tlowerBound\tupperBound\tnominalValue\testimate\tobjectivePriorType\tobjectivePriorParameters\n",
    );
    for (i, d) in likelihood.dimensions().iter().enumerate() {
        let value = fit.params.value(d.id);
        let meaning = d.id.spec().meaning;
        let scale = if d.log_scale { "log10" } else { "lin" };
        let prior = likelihood
            .prior_terms()
            .iter()
            .find(|t| t.index == i)
            .map_or_else(|| "\t".to_string(), |t| motor_prior_cells(t, d.log_scale));
        let _ = writeln!(
            s,
            "{}\t{meaning}\t{scale}\t{}\t{}\t{value}\t1\t{prior}",
            d.id, d.lo, d.hi
        );
    }
    for ((label, beta, tau), id) in b.nuisances.iter().zip(nuisance_ids) {
        let half = (10.0 * tau).max(2.0 * beta.abs());
        let _ = writeln!(
            s,
            "{id}\t{label}\tlin\t{}\t{half}\t{beta}\t1\tnormal\t0;{tau}",
            -half
        );
    }
    s
}

/// The `objectivePriorType` and `objectivePriorParameters` cells of a motor prior term,
/// eq. \[2\]: `parameterScaleNormal` (log10 m; σ/ln 10) on a log10 scale, `logNormal`
/// (ln m; σ) on a linear one.
fn motor_prior_cells(t: &MotorPriorTerm, log_scale: bool) -> String {
    let t = &t.term;
    if log_scale {
        format!(
            "parameterScaleNormal\t{};{}",
            t.median.log10(),
            t.sd_ln / std::f64::consts::LN_10
        )
    } else {
        format!("logNormal\t{};{}", t.median.ln(), t.sd_ln)
    }
}

/// An SBML Level 3 document that declares the model's symbols: every parameter of the fitted
/// motor (its value), the steady-state conditions' inputs, and the outputs the observables
/// read. It holds no dynamics and says so.
fn sbml(fit: &FitFile, outputs: &[String]) -> String {
    let mut s = String::from(
        r#"<?xml version="1.0" encoding="UTF-8"?>
<sbml xmlns="http://www.sbml.org/sbml/level3/version2/core" level="3" version="2">
  <model id="vanefit_vane_motor" name="reversible pneumatic vane motor (vanefit)">
    <notes>
      <body xmlns="http://www.w3.org/1999/xhtml">
        <p>Declarations only: the motor's parameters, the steady-state inputs and the
        simulated outputs of the vanefit model (Beater's reversible vane motor). The
        dynamics are not SBML; vanefit simulates them (command line or Python package).</p>
      </body>
    </notes>
    <listOfParameters>
"#,
    );
    for p in PARAMS {
        if p.effect.is_some_and(|e| !fit.effects.contains(e)) {
            continue;
        }
        let v = fit.params.get(p.name).unwrap_or(p.default);
        let _ = writeln!(
            s,
            r#"      <parameter id="{}" name="{}" value="{v}" constant="true"/>"#,
            p.name,
            xml_escape(p.meaning)
        );
    }
    s.push_str(
        r#"      <parameter id="omega_rad_s" name="shaft speed held by the brake (steady-state conditions), rad/s" value="0" constant="true"/>
      <parameter id="p_supply_pa" name="supply pressure, absolute (steady-state conditions), Pa" value="0" constant="true"/>
"#,
    );
    for o in outputs {
        let _ = writeln!(
            s,
            r#"      <parameter id="{o}" name="simulated output {o} (computed by vanefit)" value="0" constant="false"/>"#
        );
    }
    s.push_str("    </listOfParameters>\n  </model>\n</sbml>\n");
    s
}

fn xml_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// `vanefit_export.json`: where the problem came from and vanefit's χ² of it at the fit.
fn summary_json(
    ds: &Dataset,
    fit: &FitFile,
    fit_path: &Path,
    s: &PetabSummary,
    likelihood: &FitLikelihood,
) -> String {
    // Absolute paths: tools read this file from wherever they run.
    let absolute = |p: &Path| {
        std::fs::canonicalize(p)
            .unwrap_or_else(|_| p.to_path_buf())
            .display()
            .to_string()
    };
    let mut not_carried = vec![
        "the model's dynamics (model.xml declares symbols only; vanefit simulates)",
        "recorded inputs as time functions (a transient experiment is one condition driven by its recording)",
        "the fitting cost J (per-channel means and reference polynomials)",
    ];
    let peak = |(i, e)| crate::objective::peak::PowerPeak::of(e, i).is_some();
    let has_peaks = ds.experiments.iter().enumerate().any(peak);
    if has_peaks {
        not_carried.push(
            "the power-peak term of a page that prints max power at a speed (chi2_power_peaks: the vertex of the power at three speeds against the printed speed, not an observable at a condition)",
        );
    }
    let v_disp = ParamId::V_DISP.name();
    if likelihood.names().iter().any(|n| n == v_disp) && !likelihood.prior_terms().is_empty() {
        not_carried.push(
            "the motor priors' medians following the estimated displacement (parameters.tsv states them at the fit's displacement)",
        );
    }
    let stats = fit.statistics.as_ref();
    let doc = serde_json::json!({
        "format": "vanefit.petab_export/1",
        "fit": absolute(fit_path),
        "dataset": absolute(&ds.dir),
        "measurements": s.measurements,
        "observables": s.observables,
        "conditions": s.conditions,
        "chi2_rows": s.chi2_rows,
        "chi2_priors": s.chi2_priors,
        "chi2": s.chi2_rows + s.chi2_priors + s.chi2_power_peaks,
        "likelihood_chi2": stats.and_then(|st| st.likelihood_chi2),
        "chi2_motor_priors": s.chi2_motor_priors,
        "objective": s.objective(),
        "prior_chi2": stats.and_then(|st| st.prior_chi2),
        "not_carried": not_carried,
    });
    let mut doc = doc;
    if has_peaks {
        // Stated only where a page has the term, so that other exports read as before.
        doc["chi2_power_peaks"] = s.chi2_power_peaks.into();
    }
    serde_json::to_string_pretty(&doc).expect("plain data") + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_petab_identifiers() {
        assert_eq!(
            petab_id("ramp.csv flow1_g_s offset"),
            "ramp_csv_flow1_g_s_offset"
        );
        assert_eq!(petab_id("2nd run"), "x_2nd_run");
        assert_eq!(petab_id("--"), "x_");
        assert_eq!(stem_id("data/ramp.csv"), "ramp");
        assert_eq!(output_symbol(Quantity::Torque), "torque_nm");
        assert_eq!(output_symbol(Quantity::PPort1), "p_port1_pa");
    }

    #[test]
    fn sbml_escapes_names() {
        assert_eq!(
            xml_escape(r#"a<b & "c">"#),
            "a&lt;b &amp; &quot;c&quot;&gt;"
        );
    }
}
