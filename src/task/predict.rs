//! `predict` as a task: [`PredictOptions`] → [`PredictOptions::check`] (at the fit's
//! atmosphere) → [`PredictSettings`]; the prediction of a fit ([`predict`]) and the files it
//! leaves ([`write_prediction`]: `catalogue.csv`, `factors.csv`, `curves.csv`, `predict.md`,
//! SVG figures), called by the command line and by `batch` alike.
//!
//! Every bad input (fit file, pressure list, unit, nozzle) is refused with a message that
//! names the file or field, before anything is written.

use super::{Opt, OptionError};
use crate::data::dataset::{DataError, Dataset};
use crate::data::fitfile::{FitFile, FitFileError};
use crate::data::locate::{locate_dataset, Located};
use crate::estimate::fit::fit_likelihood::{FitLikelihood, FitLikelihoodError};
use crate::estimate::sample::posterior::LogPrior;
use crate::model::params::ParamId;
use crate::predict::Prediction;
use crate::predict::{
    BandChoice, BandRequest, Nozzle, NozzlePort, PosteriorData, PosteriorSource, PredictError,
    SamplingOptions,
};
use crate::report::predict::{write, PredictReportError, PressureDisplay};
use crate::sim::operating_point::OperatingPointError;
use crate::units::constants::P_ATM_PA;
use crate::units::{Quantity, Unit};
use std::path::{Path, PathBuf};

/// Options of a prediction as given (unchecked), pressures in `unit`;
/// [`PredictOptions::check`] makes them [`PredictSettings`].
#[derive(Debug, Clone, PartialEq)]
pub struct PredictOptions {
    /// Unit of `pressures`, `reference` and the outputs: a unit of `p_port1` columns
    /// ([`pressure_units`]).
    pub unit: Unit,
    /// Supply pressures in `unit` (`None`: 3, 4, 5, 6, 7 bar g).
    pub pressures: Option<Vec<f64>>,
    /// Reference pressure of the correction factors in `unit` (`None`: 6.3 bar g).
    pub reference: Option<f64>,
    /// Extra nozzle in series in front of port 1: its sonic conductance C, m3/(s*Pa).
    pub inlet_nozzle_m3_s_pa: Option<f64>,
    /// Extra nozzle in series behind port 2: its sonic conductance C, m3/(s*Pa).
    pub outlet_nozzle_m3_s_pa: Option<f64>,
    /// Speed grid on which the maximum power is exact, rpm (> 0).
    pub speed_grid_rpm: f64,
    /// Points of each curve from standstill to the free speed (≥ 2).
    pub curve_points: usize,
    /// Parameters a fit could estimate but held fixed or could not identify are taken as
    /// uncertain within this factor (> 1, 95 %), so that the bands include them.
    pub fixed_spread: Option<f64>,
    /// Which method makes the bands: the delta method, posterior samples, or `auto`
    /// (samples where the fit says the delta method fails and `data` is given;
    /// `predict::samples`).
    pub bands: BandChoice,
    /// The dataset folder the fit was made from (needed to sample the posterior).
    pub data: Option<PathBuf>,
    /// Walkers, steps, burn-in, propagated draws and seed of the posterior samples.
    pub sampling: SamplingOptions,
}

impl Default for PredictOptions {
    /// The command line's defaults: bar g, 3 to 7 bar g, reference 6.3 bar g, no nozzle,
    /// a 1 rpm grid, 41 curve points, `auto` bands without a dataset, the default sampling.
    fn default() -> Self {
        Self {
            unit: Unit::BarG,
            pressures: None,
            reference: None,
            inlet_nozzle_m3_s_pa: None,
            outlet_nozzle_m3_s_pa: None,
            speed_grid_rpm: 1.0,
            curve_points: crate::predict::options::DEFAULT_CURVE_POINTS,
            fixed_spread: None,
            bands: BandChoice::Auto,
            data: None,
            sampling: SamplingOptions::default(),
        }
    }
}

/// The pressure units (those of `p_port1` columns), by column suffix.
pub fn pressure_units() -> &'static [Unit] {
    Quantity::PPort1.units()
}

/// The pressure unit with column suffix `suffix` (`bar_g`, `mpa`, ...); a bad one is an
/// error naming the option `opt` and the known suffixes.
pub fn pressure_unit(opt: Opt, suffix: &str) -> Result<Unit, OptionError> {
    let units = pressure_units();
    units
        .iter()
        .find(|u| u.suffix() == suffix.trim())
        .copied()
        .ok_or_else(|| {
            let known: Vec<&str> = units.iter().map(|u| u.suffix()).collect();
            OptionError::of(
                opt,
                format!(
                    " '{suffix}': not a pressure unit; use one of {}",
                    known.join(", ")
                ),
            )
        })
}

/// A pressure in `unit` as an absolute pressure, Pa, that must be positive.
fn absolute(opt: Opt, given: &str, v: f64, unit: Unit, p_atm_pa: f64) -> Result<f64, OptionError> {
    let p = unit.to_si(v, p_atm_pa);
    if p.is_finite() && p > 0.0 {
        return Ok(p);
    }
    Err(OptionError::of(
        opt,
        format!(
            " '{given}': {} {} is not a positive absolute pressure ({p} Pa)",
            v,
            unit.suffix()
        ),
    ))
}

/// A list of numbers as written in messages: comma-separated.
fn list_text(values: &[f64]) -> String {
    values
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

impl PredictOptions {
    /// Checks every value at the atmosphere `p_atm_pa` (the fit's): the unit is a pressure
    /// unit, every pressure a positive absolute pressure, at most one nozzle with a
    /// positive conductance, a positive grid, at least 2 curve points, a spread > 1.
    pub fn check(&self, p_atm_pa: f64) -> Result<PredictSettings, OptionError> {
        let unit = pressure_unit(Opt::PredictUnit, self.unit.suffix())?;
        let mut o = crate::predict::PredictOptions::new(p_atm_pa);
        if let Some(list) = &self.pressures {
            let given = list_text(list);
            if list.is_empty() {
                return Err(OptionError::of(
                    Opt::PredictPressures,
                    " '': give at least one pressure, e.g. 3,4,5",
                ));
            }
            o.pressures_pa = list
                .iter()
                .map(|v| absolute(Opt::PredictPressures, &given, *v, unit, p_atm_pa))
                .collect::<Result<_, _>>()?;
        }
        if let Some(r) = self.reference {
            o.reference_pa = absolute(Opt::PredictReference, &r.to_string(), r, unit, p_atm_pa)?;
        }
        o.nozzle = self.nozzle()?;
        let grid = self.speed_grid_rpm;
        if !(grid.is_finite() && grid > 0.0) {
            return Err(OptionError::of(
                Opt::PredictSpeedGrid,
                format!(" {grid}: must be a positive number of rpm"),
            ));
        }
        o.speed_grid_rad_s = Unit::Rpm.to_si(grid, p_atm_pa);
        if self.curve_points < 2 {
            return Err(OptionError::of(
                Opt::PredictCurvePoints,
                format!(" {}: a curve needs at least 2 points", self.curve_points),
            ));
        }
        o.curve_points = self.curve_points;
        if let Some(f) = self.fixed_spread {
            if !(f.is_finite() && f > 1.0) {
                return Err(OptionError::of(
                    Opt::PredictFixedSpread,
                    format!(" {f}: must be a factor > 1"),
                ));
            }
        }
        o.fixed_spread = self.fixed_spread;
        self.check_sampling()?;
        Ok(PredictSettings {
            options: o,
            display: PressureDisplay { unit, p_atm_pa },
            bands: self.bands,
            data: self.data.clone(),
            sampling: self.sampling.clone(),
        })
    }

    /// Samples asked need the dataset; the sampler's counts must be usable.
    fn check_sampling(&self) -> Result<(), OptionError> {
        let s = &self.sampling;
        // Which sampler runs is known only once the posterior is: the Laplace-guided
        // chains take any number ≥ 2, the ensemble checks its own need when it runs.
        if let Some(w) = s.walkers.filter(|w| *w < 2) {
            return Err(OptionError::of(
                Opt::PredictWalkers,
                format!(
                    " {w}: give at least 2 (chains of the Laplace-guided sampler: any number \
                     ≥ 2; walkers of the ensemble, which a posterior far from Gaussian gets: \
                     an even number ≥ 2·(estimated parameters + 1))"
                ),
            ));
        }
        if s.steps < 20 {
            return Err(OptionError::of(
                Opt::PredictSteps,
                format!(" {}: give at least 20 kept steps", s.steps),
            ));
        }
        if s.draws < 40 {
            return Err(OptionError::of(
                Opt::PredictDraws,
                format!(
                    " {}: give at least 40 draws for a 95 % band's percentiles",
                    s.draws
                ),
            ));
        }
        Ok(())
    }

    /// The extra nozzle: at most one, with a positive conductance.
    fn nozzle(&self) -> Result<Option<Nozzle>, OptionError> {
        let nozzle = |opt: Opt, port: NozzlePort, c: Option<f64>| match c {
            Some(v) if !(v.is_finite() && v > 0.0) => Err(OptionError::of(
                opt,
                format!(" {v}: the conductance must be a positive number of m3/(s*Pa)"),
            )),
            Some(v) => Ok(Some(Nozzle { port, c_m3_s_pa: v })),
            None => Ok(None),
        };
        let inlet = nozzle(
            Opt::PredictInletNozzle,
            NozzlePort::Inlet,
            self.inlet_nozzle_m3_s_pa,
        )?;
        let outlet = nozzle(
            Opt::PredictOutletNozzle,
            NozzlePort::Outlet,
            self.outlet_nozzle_m3_s_pa,
        )?;
        if inlet.is_some() && outlet.is_some() {
            return Err(OptionError::pair(
                Opt::PredictInletNozzle,
                Opt::PredictOutletNozzle,
                ": give one extra nozzle, not both",
            ));
        }
        Ok(inlet.or(outlet))
    }
}

/// Checked [`PredictOptions`]: the prediction layer's options in SI and the unit of the
/// tables (private fields, read through the getters).
#[derive(Debug, Clone, PartialEq)]
pub struct PredictSettings {
    options: crate::predict::PredictOptions,
    display: PressureDisplay,
    bands: BandChoice,
    data: Option<PathBuf>,
    sampling: SamplingOptions,
}

/// How far beyond the supply pressures a fit covered a prediction is still an
/// extrapolation worth reading: a factor of 2 on the absolute supply pressure either way. The
/// model's flows scale with the absolute upstream pressure (choked ISO 6358 nozzles) and its
/// torque with the chamber pressures, so at twice the highest fitted absolute pressure the
/// forces on vanes and seals, the flows through the leak gaps and the friction load are
/// twice what the fit ever saw: its leakage and friction laws are then a guess, and the 95 %
/// bands (the parameters' uncertainty only) say nothing of that. The factor also keeps a
/// catalogue page at 6.3 bar g predicting over the makers' own range of correction factors
/// (3 to 7 bar g, ≈ 0.55 to 1.1 of 7.3 bar a) without the warning.
pub const FAR_EXTRAPOLATION_FACTOR: f64 = 2.0;

/// A pressure for a warning: two decimals, no trailing zeros.
fn round2(v: f64) -> String {
    let t = format!("{v:.2}");
    t.trim_end_matches('0').trim_end_matches('.').to_string()
}

impl PredictSettings {
    /// Warnings, one per asked supply pressure (Pa absolute) that lies more than
    /// `FAR_EXTRAPOLATION_FACTOR` beyond the absolute supply pressures `fit` covered
    /// (`conditions.p_supply_range_pa`; none when the fit file does not say), in the unit of
    /// the tables. The usual `*` marks every pressure outside the range; these are far
    /// outside it.
    pub fn far_extrapolations(&self, fit: &FitFile) -> Vec<String> {
        let Some([lo, hi]) = fit.conditions.and_then(|c| c.p_supply_range_pa) else {
            return Vec::new();
        };
        let f = FAR_EXTRAPOLATION_FACTOR;
        let (lo_far, hi_far) = (lo / f, hi * f);
        let d = &self.display;
        let unit = d.label();
        self.options
            .pressures_pa
            .iter()
            .filter(|p| **p < lo_far || **p > hi_far)
            .map(|p| {
                format!(
                    "--pressures {} {unit} ({:.3} MPa absolute) is far outside the supply pressures the fit covered ({} to {} {unit}): the prediction holds to within a factor of {f} on the absolute supply pressure ({} to {} {unit}), because beyond it the leakage and friction laws work at forces and flows the fit never saw and the 95 % bands do not include that; do not use these rows",
                    d.text(*p),
                    p * 1e-6,
                    round2(d.value(lo)),
                    round2(d.value(hi)),
                    round2(d.value(lo_far)),
                    round2(d.value(hi_far)),
                )
            })
            .collect()
    }

    /// The prediction layer's options (pressures in Pa absolute).
    pub fn engine_options(&self) -> &crate::predict::PredictOptions {
        &self.options
    }
    /// The pressure unit of the tables and the atmosphere.
    pub fn display(&self) -> &PressureDisplay {
        &self.display
    }
}

/// Why a prediction failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PredictTaskError {
    /// An option is bad (named by its field).
    #[error(transparent)]
    Option(#[from] OptionError),
    /// The fit file cannot be read.
    #[error(transparent)]
    FitFile(#[from] FitFileError),
    /// The motor's figures at one supply pressure could not be found.
    #[error("{}", at_pressure(.pressure, *.p_supply_pa, *.reference, .source, &Opt::field))]
    AtPressure {
        /// The supply pressure in the tables' unit, with the unit's label.
        pressure: String,
        /// Supply pressure, Pa absolute.
        p_supply_pa: f64,
        /// Whether it is the reference pressure of the factors (`PredictOptions.reference`).
        reference: bool,
        /// Why.
        source: OperatingPointError,
    },
    /// The prediction failed.
    #[error(transparent)]
    Predict(PredictError),
    /// The fit's dataset cannot be read.
    #[error("{opt}: {0}", opt = Opt::PredictData)]
    Data(#[from] DataError),
    /// The fit's likelihood cannot be rebuilt on the dataset.
    #[error("{opt}: {0}", opt = Opt::PredictData)]
    Likelihood(#[from] FitLikelihoodError),
    /// The output folder cannot be made.
    #[error("{}: cannot create: {source}", path.display())]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The results cannot be written.
    #[error(transparent)]
    Report(#[from] PredictReportError),
}

/// The message of [`PredictTaskError::AtPressure`], the option `PredictOptions.reference`
/// called `name(option)` when the pressure is the reference.
fn at_pressure(
    pressure: &str,
    p_supply_pa: f64,
    reference: bool,
    source: &OperatingPointError,
    name: &dyn Fn(Opt) -> &'static str,
) -> String {
    let note = if reference {
        format!(
            ", the {} pressure of the factors",
            name(Opt::PredictReference)
        )
    } else {
        String::new()
    };
    format!("at {pressure} ({p_supply_pa:.0} Pa abs.{note}): {source}")
}

impl PredictTaskError {
    /// The message with every option it names called `name(option)` (e.g. the command
    /// line's flag); [`std::fmt::Display`] names them by their fields.
    pub fn message_with(&self, name: &dyn Fn(Opt) -> &'static str) -> String {
        match self {
            Self::Option(e) => e.message_with(name),
            Self::Data(e) => format!("{}: {e}", name(Opt::PredictData)),
            Self::Likelihood(e) => format!("{}: {e}", name(Opt::PredictData)),
            Self::AtPressure {
                pressure,
                p_supply_pa,
                reference,
                source,
            } => at_pressure(pressure, *p_supply_pa, *reference, source, name),
            other => other.to_string(),
        }
    }
}

/// The atmosphere of a fit (its recordings'), Pa; the standard one when it has none.
pub fn fit_atmosphere_pa(fit: &FitFile) -> f64 {
    fit.conditions.map_or(P_ATM_PA, |c| c.p_atm_pa)
}

/// The prediction of the fitted motor `fit` under `settings` (a failure at a pressure is
/// reported in the table's unit, naming the reference when it is the one that failed).
pub fn predict(fit: &FitFile, settings: &PredictSettings) -> Result<Prediction, PredictTaskError> {
    predict_observed(fit, settings, &|_, _, _| {})
}

/// [`predict`], telling `progress` (what, done, total) how long work goes (sampling the
/// posterior and propagating its samples). The dataset is the one the settings name
/// (`--data`), else none: [`predict_located`] also finds it from the fit file.
pub fn predict_observed(
    fit: &FitFile,
    settings: &PredictSettings,
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Result<Prediction, PredictTaskError> {
    let data = match (&settings.data, settings.bands) {
        (Some(dir), BandChoice::Samples | BandChoice::Auto) => Some(given_dataset(dir)?),
        (None, BandChoice::Samples) => {
            return Err(OptionError::of(
                Opt::PredictData,
                ": bands from posterior samples need the dataset the fit was made from",
            )
            .into())
        }
        _ => None,
    };
    predict_on(fit, settings, data, progress)
}

/// [`predict_observed`], the dataset found from the fit file (`fit_path`: where it was
/// read from; `None` for a fit held in memory) by `data::locate` when the settings name
/// none and the bands may come from samples. A dataset that is not found or cannot be
/// read is no error: `auto` then makes delta-method bands and says why
/// (`Prediction::bands`), `samples` is refused naming `data`.
pub fn predict_located(
    fit_path: Option<&Path>,
    fit: &FitFile,
    settings: &PredictSettings,
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Result<Prediction, PredictTaskError> {
    let data = match (&settings.data, settings.bands) {
        (_, BandChoice::Delta) => None,
        (Some(dir), _) => Some(given_dataset(dir)?),
        (None, choice) => {
            let found = if fit.estimated.is_empty() {
                Err(PosteriorData::Missing(
                    "the fit estimated no parameter: there is no posterior to sample".into(),
                ))
            } else {
                located_dataset(fit_path, fit)
            };
            if let (BandChoice::Samples, Err(PosteriorData::Missing(why))) = (choice, &found) {
                return Err(OptionError::of(Opt::PredictData, format!(": {why}")).into());
            }
            Some(found)
        }
    };
    predict_on(fit, settings, data, progress)
}

/// A dataset read for the posterior and where it was found, or why there is none.
type DatasetAtHand = Result<(Dataset, PosteriorData), PosteriorData>;

/// The dataset at `dir`, named by the settings: read (an error if it cannot be).
fn given_dataset(dir: &Path) -> Result<DatasetAtHand, DataError> {
    let ds = Dataset::load(dir)?;
    let at = PosteriorData::At(format!("dataset {} at {} (given)", ds.name, dir.display()));
    Ok(Ok((ds, at)))
}

/// The dataset of `fit` found by `data::locate` and read, or why not.
fn located_dataset(fit_path: Option<&Path>, fit: &FitFile) -> DatasetAtHand {
    let located = locate_dataset(fit_path, fit);
    let name = &fit.dataset;
    match &located {
        Located::Found(dir, _) => Dataset::load(dir)
            .map(|ds| (ds, PosteriorData::At(located.describe(name))))
            .map_err(|e| {
                PosteriorData::Missing(format!(
                    "the dataset {name} at {} could not be read: {e}",
                    dir.display()
                ))
            }),
        _ => Err(PosteriorData::Missing(located.describe(name))),
    }
}

/// The prediction with the dataset `data` (read, or why it is not at hand; `None`: none
/// was asked for).
fn predict_on(
    fit: &FitFile,
    settings: &PredictSettings,
    data: Option<DatasetAtHand>,
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Result<Prediction, PredictTaskError> {
    let o = &settings.options;
    // A dataset found from the fit file that the fit's likelihood cannot be rebuilt on is
    // as good as not found for `auto`; one given (`data`) is an error.
    let lenient = settings.data.is_none() && settings.bands == BandChoice::Auto;
    let (likelihood, said) = match data {
        Some(Ok((ds, at))) => match FitLikelihood::from_fit(&ds, fit) {
            Ok(l) => (Some(l), Some(at)),
            Err(e) if lenient => {
                let PosteriorData::At(at) = at else {
                    return Err(e.into());
                };
                let why = format!("the fit's likelihood cannot be rebuilt on the {at}: {e}");
                (None, Some(PosteriorData::Missing(why)))
            }
            Err(e) => return Err(e.into()),
        },
        Some(Err(missing)) => (None, Some(missing)),
        None => (None, None),
    };
    // The fit's motor prior (fit files of fits made with priors list it per parameter): the
    // posterior the samples come from is the one the fit's estimate is the mode of.
    let prior = likelihood
        .as_ref()
        .and_then(|l| motor_log_prior(fit, &l.names()));
    let request = BandRequest {
        choice: settings.bands,
        posterior: likelihood.as_ref().map(|l| PosteriorSource {
            likelihood: l,
            prior: prior.as_ref().map(|p| p as &dyn LogPrior),
        }),
        data: said.as_ref(),
        sampling: &settings.sampling,
        progress,
    };
    crate::predict::predict_with(fit, o, &request)
        .map_err(|e| failed(e, &settings.display, o.reference_pa))
}

/// The motor prior of a fit file as a log-density of the estimated parameters' values (in
/// `names`' order): Σ −½ ((ln v − ln v₀)/σ)² over the parameters the file has a prior for
/// (docs/estimation.md, "Priors"). The sampler works in ln v, where this log-normal prior is
/// a Gaussian with no Jacobian term. `None` for a fit made without priors.
fn motor_log_prior(fit: &FitFile, names: &[String]) -> Option<impl Fn(&[f64]) -> f64 + Sync> {
    let entries = &fit.statistics.as_ref()?.prior;
    let terms: Vec<(usize, f64, f64, f64)> = names
        .iter()
        .enumerate()
        .filter_map(|(i, n)| {
            let e = entries.iter().find(|e| e.parameter == *n)?;
            let k = e.size_exponent.unwrap_or(0.0);
            (e.median > 0.0 && e.sd_ln > 0.0).then(|| (i, e.median.ln(), e.sd_ln, k))
        })
        .collect();
    // Where the displacement was estimated too, the medians follow it (size exponent k):
    // ln v₀ = ln median + k·ln(V/V̂).
    let size_index = names.iter().position(|n| n == ParamId::V_DISP.name());
    let ln_v_hat = fit.params.v_disp().ln();
    (!terms.is_empty()).then_some(move |values: &[f64]| {
        let ln_size = size_index.map_or(0.0, |j| {
            if values[j] > 0.0 {
                values[j].ln() - ln_v_hat
            } else {
                f64::NAN
            }
        });
        terms
            .iter()
            .map(|&(i, mu, sd, k)| {
                let v = values[i];
                let z = (v.ln() - mu - k * ln_size) / sd;
                if v > 0.0 && z.is_finite() {
                    -0.5 * z * z
                } else {
                    f64::NEG_INFINITY
                }
            })
            .sum()
    })
}

/// A prediction's failure in the asked unit (marking the reference when the reference
/// pressure is the one that failed, since every factor needs it).
fn failed(e: PredictError, display: &PressureDisplay, reference_pa: f64) -> PredictTaskError {
    match e {
        PredictError::AtPressure {
            p_supply_pa,
            source,
        } => PredictTaskError::AtPressure {
            pressure: format!("{} {}", display.text(p_supply_pa), display.label()),
            p_supply_pa,
            reference: p_supply_pa == reference_pa,
            source,
        },
        other => PredictTaskError::Predict(other),
    }
}

/// Writes a prediction into the folder `out` (created): tables, report and figures, titled
/// with `source` (the fit file and its dataset). Returns the files written.
pub fn write_prediction(
    prediction: &Prediction,
    settings: &PredictSettings,
    source: &str,
    out: &Path,
) -> Result<Vec<PathBuf>, PredictTaskError> {
    std::fs::create_dir_all(out).map_err(|source| PredictTaskError::CreateDir {
        path: out.to_path_buf(),
        source,
    })?;
    let mut written = Vec::new();
    write(
        prediction,
        &settings.display,
        source,
        out,
        &mut |p: &Path| written.push(p.to_path_buf()),
    )?;
    Ok(written)
}

/// A finished prediction and what it wrote.
pub struct Predicted {
    /// The prediction.
    pub prediction: Prediction,
    /// The files written.
    pub written: Vec<PathBuf>,
}

/// Reads the fit file at `fit_path`, checks the options at its atmosphere, predicts and
/// writes the results into `out`; nothing is written when an input is bad.
pub(crate) fn predict_to(
    fit_path: &Path,
    options: &PredictOptions,
    out: &Path,
) -> Result<Predicted, PredictTaskError> {
    let fit = FitFile::read(fit_path)?;
    let settings = options.check(fit_atmosphere_pa(&fit))?;
    let prediction = predict(&fit, &settings)?;
    let source = source_name(fit_path, &fit);
    let written = write_prediction(&prediction, &settings, &source, out)?;
    Ok(Predicted {
        prediction,
        written,
    })
}

/// The fit file and its dataset, for titles.
pub fn source_name(path: &Path, fit: &FitFile) -> String {
    if fit.dataset.is_empty() {
        path.display().to_string()
    } else {
        format!("{} (fit of dataset {})", path.display(), fit.dataset)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Laplace-guided chains run with any number ≥ 2 of chains (R̂ compares two or
    /// more), so `--walkers` takes 2 or 3; 1 and 0 are refused, naming the option.
    #[test]
    fn walkers_take_any_number_of_chains_from_two() {
        let with = |w: usize| {
            let mut o = PredictOptions::default();
            o.sampling.walkers = Some(w);
            o.check(101_325.0)
        };
        assert!(with(2).is_ok() && with(3).is_ok() && with(40).is_ok());
        for w in [0, 1] {
            let e = with(w).unwrap_err();
            let m = e.to_string();
            assert!(
                m.contains("sampling.walkers") && m.contains("at least 2"),
                "{m}"
            );
        }
    }
}
