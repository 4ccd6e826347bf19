//! Predictions from a fit (docs/formats.md, "Contracts added later"; docs/model.md,
//! "Catalogue figures and predictions"): what the fitted motor does at other supply
//! pressures, or with an extra nozzle at its inlet or outlet, and how sure that is.
//!
//! For each asked supply pressure: the catalogue row of `sim::operating_point`
//! (free speed, maximum power on a speed grid with the speed, torque and air there, stall
//! torque, air at free speed), the correction factors relative to a reference pressure
//! (6.3 bar g unless asked otherwise), and curves of shaft torque, power and air
//! consumption against speed from standstill to the free speed. The factors are
//!
//! * `power`: maximum power P_max(p)/P_max(p_ref),
//! * `speed`: free speed ω_0(p)/ω_0(p_ref),
//! * `torque`: stall torque T_stall(p)/T_stall(p_ref),
//! * `air`: air consumption at maximum power ṁ_1(p)/ṁ_1(p_ref),
//!
//! each 1 at the reference pressure. Every figure carries a 95 % band propagated from the
//! fit's parameter uncertainty (`uncertainty`); a pressure outside the supply pressures
//! the fitted data covered is flagged as an extrapolation.

mod figures;
pub(crate) mod options;
pub(crate) mod samples;
pub(crate) mod uncertainty;

pub use options::{Nozzle, NozzlePort, PredictOptions, DEFAULT_CURVE_POINTS};
pub use samples::{
    delta_unreliable, BandChoice, BandMethod, BandReason, BandRequest, BandsMade, PosteriorData,
    PosteriorDraws, PosteriorSource, PosteriorSummary, Sampler, SamplingOptions, DEFAULT_BURN_IN,
    DEFAULT_DRAWS, DEFAULT_STEPS, MAP_ROUNDS, PILOT_STEPS, TRANSPORT_K_HAT_LIMIT,
};

pub use uncertainty::{log_band, BandBasis, ParamUncertainty, Z95};

use crate::data::fitfile::FitFile;
use crate::model::motor::Motor;
use crate::model::params::{spec, ParamError, ParamId, ParamSpec, PARAMS};
use crate::objective::likelihood::calibration_tolerance;
use crate::sim::operating_point::{CatalogueRow, OperatingPointError};
use crate::units::Quantity;
use figures::{Outcome, N_CURVE, N_FACTORS, N_ROW};

/// The catalogue figures of a row, in the order of [`PressurePrediction::figures`].
pub const ROW_FIGURES: [&str; 7] = [
    "free_speed",
    "max_power",
    "speed_at_max_power",
    "torque_at_max_power",
    "stall_torque",
    "air_at_max_power",
    "air_at_free_speed",
];
/// The correction factors, in the order of [`PressurePrediction::factors`].
pub(crate) const FACTORS: [&str; 4] = ["power", "speed", "torque", "air"];

/// Why a prediction failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PredictError {
    /// No supply pressure was asked for.
    #[error("no supply pressure to predict at")]
    NoPressures,
    /// A pressure is not a positive absolute pressure.
    #[error("pressure {0} Pa is not a positive absolute pressure")]
    BadPressure(f64),
    /// The nozzle's conductance is not a positive number.
    #[error("the nozzle's conductance {0:e} m3/(s*Pa) is not a positive number")]
    BadNozzle(f64),
    /// The speed grid is not a positive number.
    #[error("the speed grid {0} rad/s is not a positive number")]
    BadGrid(f64),
    /// The fixed parameters' spread is not a factor above 1.
    #[error("the fixed parameters' spread {0} is not a factor > 1")]
    BadSpread(f64),
    /// Fewer than two curve points.
    #[error("a curve needs at least 2 points, not {0}")]
    BadCurvePoints(usize),
    /// The motor's figures at one supply pressure could not be found.
    #[error("at {p_supply_pa:.0} Pa abs.: {source}")]
    AtPressure {
        /// Supply pressure, Pa absolute.
        p_supply_pa: f64,
        /// Why.
        source: OperatingPointError,
    },
    /// A parameter set moved within the uncertainty is not a valid motor.
    #[error("perturbing the parameters: {0}")]
    Params(#[from] ParamError),
    /// Bands from samples were asked without the fit's dataset.
    #[error("bands from posterior samples need the dataset the fit was made from")]
    NoPosterior,
    /// The posterior sampler could not run.
    #[error("sampling the posterior: {0}")]
    Sampling(#[from] crate::estimate::sample::SampleError),
    /// Too many posterior samples gave no figures.
    #[error(
        "{failed} of {total} posterior samples gave no figures (the motor fails at some pressure)"
    )]
    SampleFigures {
        /// Samples without figures.
        failed: usize,
        /// Samples propagated.
        total: usize,
    },
}

/// A predicted figure, SI, with its 95 % band (`None`: no band, see
/// [`Prediction::uncertainty`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Banded {
    /// The figure at the estimate.
    pub value: f64,
    /// Lower and upper end of its 95 % band.
    pub band95: Option<[f64; 2]>,
}

/// One point of the curves against speed, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// Imposed speed, rad/s.
    pub speed_rad_s: f64,
    /// Shaft torque, N·m.
    pub torque_nm: Banded,
    /// Shaft power, W.
    pub power_w: Banded,
    /// Air consumption (mass flow into port 1), kg/s.
    pub air_kg_s: Banded,
}

/// Everything predicted at one supply pressure.
#[derive(Debug, Clone, PartialEq)]
pub struct PressurePrediction {
    /// Supply pressure, Pa absolute.
    pub p_supply_pa: f64,
    /// Outside the supply pressures the fitted data covered (`None`: the fit does not say).
    pub extrapolated: Option<bool>,
    /// The catalogue row at the estimate.
    pub row: CatalogueRow,
    /// The figures of [`ROW_FIGURES`], SI, with bands.
    pub figures: [Banded; 7],
    /// The factors of `FACTORS` relative to the reference pressure, with bands.
    pub factors: [Banded; 4],
    /// Torque, power and air against speed, from 0 to the free speed.
    pub curve: Vec<CurvePoint>,
}

/// A prediction from a fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// What was asked.
    pub options: PredictOptions,
    /// The catalogue row at the reference pressure.
    pub reference: CatalogueRow,
    /// One per asked pressure, in the asked order.
    pub pressures: Vec<PressurePrediction>,
    /// The parameters' uncertainty the bands stand on, and what it leaves out.
    pub uncertainty: ParamUncertainty,
    /// Parameters the fit held fixed (taken as exact).
    pub fixed: Vec<String>,
    /// Supply pressures the fitted data covered, Pa absolute (`None`: not stated).
    pub supply_range_pa: Option<[f64; 2]>,
    /// How far outside that range a pressure may lie before it counts as extrapolated, Pa:
    /// the supply-pressure sensor's calibration tolerance.
    pub range_tolerance_pa: f64,
    /// Discovered terms of the fit's model (their coefficients are taken as exact).
    pub discovered_terms: usize,
    /// Which method made the bands, and why.
    pub bands: BandsMade,
    /// What the fit itself warned of, repeated with every prediction made from it
    /// ([`fit_warnings`]).
    pub fit_warnings: Vec<String>,
    /// The catalogue figures whose band rests on the motor prior rather than on the data
    /// ([`RestsOnPrior`]); empty for a fit without a prior or without delta-method bands.
    pub resting: Vec<RestsOnPrior>,
    /// The fit's gearbox: every figure, curve and band is its output shaft's (`None`: the
    /// motor's own shaft, there being no gearbox).
    pub gear: Option<crate::model::gear::Gear>,
}

/// A predicted figure whose band rests on the prior: knowing the parameters that rest on
/// their prior (posterior σ of ln v at least half the prior's, [`prior_shares`]) would
/// remove more than half of its delta-method variance
/// ([`ParamUncertainty::variance_shares`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RestsOnPrior {
    /// Supply pressure, Pa absolute.
    pub p_supply_pa: f64,
    /// The figure, one of [`ROW_FIGURES`].
    pub figure: &'static str,
    /// The share of its variance that knowing those parameters would remove.
    pub prior_share: f64,
    /// Those of them that alone would remove more than 5 %, with that share, largest first.
    pub parameters: Vec<(String, f64)>,
}

impl RestsOnPrior {
    /// The one extra measurement that would pin the figure's largest prior-resting
    /// parameter, in words.
    pub fn pinned_by(&self) -> &'static str {
        self.parameters
            .first()
            .map_or("a rig experiment", |(name, _)| measurement_that_pins(name))
    }
}

/// The one extra measurement a catalogue's reader can most easily get that pins a
/// parameter (`ParamSpec::pinned_by`; a rig experiment for a name the registry does not
/// know).
pub fn measurement_that_pins(name: &str) -> &'static str {
    match spec(name) {
        Some(s) => s.pinned_by,
        None => ParamSpec::EFFECT.pinned_by,
    }
}

/// The fit's own warnings that a prediction from it inherits: a fit that does not reach
/// the noise (its model misses the data, so bands from its curvature are too narrow where
/// it misses), parameters it could not identify, and parameters that rest on the motor
/// prior rather than on the data ([`prior_shares`]).
pub fn fit_warnings(fit: &FitFile) -> Vec<String> {
    let mut out = Vec::new();
    if let Some(line) = displacement_from_page(fit) {
        out.push(line);
    }
    if let Some(g) = fit.statistics.as_ref().map(|st| &st.goodness) {
        if !g.noise_reached {
            out.push(format!(
                "WARNING: the fit does NOT reach the noise (noise ratio {:.2} > limit {:.2}): its model misses the data, the bands are widened by {:.2} but may still not hold where the model misses.",
                g.noise_ratio, g.noise_ratio_limit, g.interval_scale
            ));
        }
    }
    let open: Vec<&str> = fit
        .verdicts
        .iter()
        .filter(|v| !v.identifiable)
        .map(|v| v.name.as_str())
        .collect();
    if !open.is_empty() {
        out.push(format!(
            "WARNING: the fit could not identify {}: predictions that depend on them rest on one of several equally good fits.",
            open.join(", ")
        ));
    }
    let on_prior: Vec<String> = prior_shares(fit)
        .into_iter()
        .filter(|(_, r)| *r >= 0.5)
        .map(|(n, r)| format!("{n} ({:.0} %)", 100.0 * r))
        .collect();
    if !on_prior.is_empty() {
        out.push(format!(
            "Resting on the motor prior, not on the data (posterior σ of ln v as a share of the prior's): {}. Figures that depend on them carry the prior's spread; a second supply pressure, the air flow at stall or a rig experiment would pin them.",
            on_prior.join(", ")
        ));
    }
    out
}

/// For a fit that estimated the displacement with the rest (a page that does not print it;
/// its prior entries follow the size): "displacement estimated from the page: 4.1 cm³
/// [3.8, 4.5] (95 %)", with what that means for the figures.
pub fn displacement_from_page(fit: &FitFile) -> Option<String> {
    let st = fit.statistics.as_ref()?;
    let follows = st.prior.iter().any(|p| p.size_exponent.is_some());
    let v_disp = ParamId::V_DISP.name();
    if !(follows && fit.estimated.iter().any(|n| n == v_disp)) {
        return None;
    }
    let text = crate::estimate::fit::displacement::describe_fitted(fit);
    Some(format!(
        "The {text} (the page does not print it): the bands carry its uncertainty, and every size-scaled default and prior follows it."
    ))
}

/// For each estimated parameter with a prior (`statistics.prior`) and in the covariance:
/// its posterior standard deviation of ln v over the prior's, √C_jj/σ_prior. Near 1 the
/// parameter rests on the prior (the data add nothing); near 0 on the data.
pub fn prior_shares(fit: &FitFile) -> Vec<(String, f64)> {
    let (Some(st), Some(cov)) = (&fit.statistics, &fit.covariance) else {
        return Vec::new();
    };
    st.prior
        .iter()
        .filter_map(|p| {
            let j = cov.parameters.iter().position(|n| *n == p.parameter)?;
            let sd = cov.matrix[j][j].max(0.0).sqrt();
            (p.sd_ln > 0.0).then(|| (p.parameter.clone(), sd / p.sd_ln))
        })
        .collect()
}

/// The fit's motor, discovered terms included.
fn fitted_motor(fit: &FitFile) -> Motor {
    Motor::new(fit.params.clone(), fit.effects.clone()).with_extra(&fit.extra)
}

/// The figures at the estimate, and those of any motor at the same curve speeds (smooth).
fn centre_and_figures(
    fit: &FitFile,
    options: &PredictOptions,
) -> Result<(Outcome, Vec<Vec<f64>>), PredictError> {
    options.check()?;
    let centre = Outcome::of(&fitted_motor(fit), options, None, fit.gear.as_ref())?;
    let speeds = centre
        .curves
        .iter()
        .map(|c| c.iter().map(|p| p.speed_rad_s).collect())
        .collect();
    Ok((centre, speeds))
}

/// Predicts the fitted motor under `options` with 95 % delta-method bands (see the module
/// documentation and `uncertainty`).
pub fn predict(fit: &FitFile, options: &PredictOptions) -> Result<Prediction, PredictError> {
    let sampling = SamplingOptions::default();
    let request = BandRequest {
        choice: BandChoice::Delta,
        posterior: None,
        data: None,
        sampling: &sampling,
        progress: &|_, _, _| {},
    };
    predict_with(fit, options, &request)
}

/// Predicts the fitted motor under `options` with 95 % bands made as `request` asks: the
/// delta method, or percentiles of posterior samples (`samples`).
pub fn predict_with(
    fit: &FitFile,
    options: &PredictOptions,
    request: &BandRequest,
) -> Result<Prediction, PredictError> {
    let (centre, speeds) = centre_and_figures(fit, options)?;
    // The delta bands' distribution, and the one the sampler starts from (and that sampled
    // bands report): `uncertainty`'s module documentation.
    let unc = ParamUncertainty::for_bands(fit, options.fixed_spread);
    let sampler = ParamUncertainty::of(fit, options.fixed_spread);
    let shown = centre.flat(false);
    let figures =
        |m: &Motor| Outcome::of(m, options, Some(&speeds), fit.gear.as_ref()).map(|o| o.flat(true));
    let figures_sync = &figures as &(dyn Fn(&Motor) -> Result<Vec<f64>, PredictError> + Sync);
    let (bands, made) = choose_bands(fit, [&unc, &sampler], &shown, figures_sync, request)?;
    let unc = if made.method == BandMethod::Delta {
        unc
    } else {
        sampler
    };
    let resting = if made.method == BandMethod::Delta {
        resting_on_prior(fit, &unc, &centre, options, &figures)?
    } else {
        Vec::new()
    };
    let band = |i: usize| Banded {
        value: shown[i],
        band95: bands.as_ref().map(|b| b[i]),
    };
    let tolerance = calibration_tolerance(Quantity::PPort1, 1.0).unwrap_or(0.0);
    let range = fit.conditions.and_then(|c| c.p_supply_range_pa);
    let stride = N_ROW + N_FACTORS + N_CURVE * options.curve_points;
    let pressures = centre
        .rows
        .iter()
        .zip(&centre.curves)
        .enumerate()
        .map(|(i, (row, curve))| {
            let at = i * stride;
            let c0 = at + N_ROW + N_FACTORS;
            PressurePrediction {
                p_supply_pa: row.p_supply_pa,
                extrapolated: range.map(|[lo, hi]| {
                    row.p_supply_pa < lo - tolerance || row.p_supply_pa > hi + tolerance
                }),
                row: *row,
                figures: std::array::from_fn(|k| band(at + k)),
                factors: std::array::from_fn(|k| band(at + N_ROW + k)),
                curve: curve
                    .iter()
                    .enumerate()
                    .map(|(k, p)| CurvePoint {
                        speed_rad_s: p.speed_rad_s,
                        torque_nm: band(c0 + N_CURVE * k),
                        power_w: band(c0 + N_CURVE * k + 1),
                        air_kg_s: band(c0 + N_CURVE * k + 2),
                    })
                    .collect(),
            }
        })
        .collect();
    Ok(Prediction {
        options: options.clone(),
        reference: centre.reference,
        pressures,
        fixed: fixed_parameters(fit)
            .into_iter()
            .filter(|n| !unc.spread.iter().any(|m| m == n))
            .collect(),
        supply_range_pa: range,
        uncertainty: unc,
        range_tolerance_pa: tolerance,
        discovered_terms: fit.extra.len(),
        bands: made,
        fit_warnings: fit_warnings(fit),
        resting,
        gear: fit.gear,
    })
}

/// Each figure's 95 % band, [lo, hi], in the order of the flattened figures.
type Bands = Vec<[f64; 2]>;

/// The bands of the figures (`shown`: their values at the estimate) as `request` asks,
/// and which method made them and why (`predict::samples`, "When the bands come from
/// samples"): `delta` always by the delta method; `samples` always from samples (an error
/// without the posterior); `auto` from samples when the posterior is at hand and they
/// converged, else by the delta method, whatever went wrong with the samples. `unc` is the
/// delta method's distribution and the sampler's starts' ([`ParamUncertainty::for_bands`],
/// [`ParamUncertainty::of`]).
fn choose_bands(
    fit: &FitFile,
    [unc, sampler]: [&ParamUncertainty; 2],
    shown: &[f64],
    figures: &(dyn Fn(&Motor) -> Result<Vec<f64>, PredictError> + Sync),
    request: &BandRequest,
) -> Result<(Option<Bands>, BandsMade), PredictError> {
    let mut made = BandsMade {
        method: BandMethod::Delta,
        choice: request.choice,
        reason: BandReason::Asked,
        delta_unreliable: samples::delta_unreliable(fit),
        sampling: None,
        data: request.data.cloned(),
    };
    let sample = |source: PosteriorSource| {
        samples::sample_posterior(unc, source, request.sampling, request.progress)
    };
    let bands = |source: PosteriorSource, drawn: samples::Drawn| {
        samples::propagate_bands(
            fit,
            sampler,
            source,
            request.sampling,
            drawn,
            figures,
            request.progress,
        )
    };
    match (request.choice, request.posterior) {
        (BandChoice::Samples, None) => return Err(PredictError::NoPosterior),
        (BandChoice::Samples, Some(source)) => {
            let (b, summary) = bands(source, sample(source)?)?;
            made.method = BandMethod::Samples;
            made.sampling = Some(summary);
            return Ok((Some(b), made));
        }
        (BandChoice::Auto, None) => {
            made.reason = BandReason::NoData(match &request.data {
                Some(PosteriorData::Missing(why)) => why.clone(),
                _ => "the fit's dataset was not given".into(),
            });
        }
        // Convergence is decided before any sample is propagated: samples that did not
        // converge are summarised, never run through the figures.
        (BandChoice::Auto, Some(source)) => match sample(source) {
            Ok(drawn) if drawn.summary.converged() => match bands(source, drawn) {
                Ok((b, summary)) => {
                    made.method = BandMethod::Samples;
                    made.reason = BandReason::Converged;
                    made.sampling = Some(summary);
                    return Ok((Some(b), made));
                }
                Err(e) => made.reason = BandReason::SamplingFailed(e.to_string()),
            },
            Ok(drawn) => {
                made.reason = BandReason::NotConverged;
                made.sampling = Some(drawn.summary);
            }
            Err(e) => made.reason = BandReason::SamplingFailed(e.to_string()),
        },
        _ => {}
    }
    Ok((unc.delta_bands(fit, shown, figures)?, made))
}

/// The catalogue figures (each pressure's [`ROW_FIGURES`]) whose delta-method variance
/// comes for more than half from parameters resting on their prior ([`RestsOnPrior`]).
fn resting_on_prior(
    fit: &FitFile,
    unc: &ParamUncertainty,
    centre: &Outcome,
    options: &PredictOptions,
    figures: &dyn Fn(&Motor) -> Result<Vec<f64>, PredictError>,
) -> Result<Vec<RestsOnPrior>, PredictError> {
    let on_prior: Vec<String> = prior_shares(fit)
        .into_iter()
        .filter(|(_, r)| *r >= 0.5)
        .map(|(n, _)| n)
        .collect();
    if on_prior.is_empty() {
        return Ok(Vec::new());
    }
    let stride = N_ROW + N_FACTORS + N_CURVE * options.curve_points;
    let n = stride * centre.rows.len();
    let which: Vec<usize> = (0..centre.rows.len())
        .flat_map(|p| (0..N_ROW).map(move |k| p * stride + k))
        .collect();
    let set: Vec<bool> = unc.names.iter().map(|n| on_prior.contains(n)).collect();
    let Some(shares) = unc.variance_shares(fit, n, &which, &set, figures)? else {
        return Ok(Vec::new());
    };
    let mut out = Vec::new();
    for (w, (prior_share, each)) in which.iter().zip(&shares) {
        let prior_share = *prior_share;
        if prior_share <= 0.5 {
            continue;
        }
        let mut parameters: Vec<(String, f64)> = unc
            .names
            .iter()
            .zip(each)
            .zip(&set)
            .filter(|((_, share), on)| **on && **share > 0.05)
            .map(|((name, share), _)| (name.clone(), *share))
            .collect();
        parameters.sort_by(|a, b| b.1.total_cmp(&a.1));
        out.push(RestsOnPrior {
            p_supply_pa: centre.rows[w / stride].p_supply_pa,
            figure: ROW_FIGURES[w % stride],
            prior_share,
            parameters,
        });
    }
    Ok(out)
}

/// The parameters of the fit's model (base and switched-on effects) that were not
/// estimated.
fn fixed_parameters(fit: &FitFile) -> Vec<String> {
    PARAMS
        .iter()
        .filter(|s| s.effect.is_none_or(|e| fit.effects.contains(e)))
        .filter(|s| !fit.estimated.iter().any(|n| n == s.name))
        .map(|s| s.name.to_string())
        .collect()
}

/// One figure's delta-method band beside its Monte-Carlo band.
#[derive(Debug, Clone, PartialEq)]
pub struct BandCheck {
    /// Which figure: `<pressure Pa> <figure>` (curves: `<pressure Pa> <quantity>@<rad/s>`).
    pub label: String,
    /// The smooth figure at the estimate.
    pub value: f64,
    /// Its delta-method 95 % band.
    pub delta: [f64; 2],
    /// Its Monte-Carlo 95 % band.
    pub monte_carlo: [f64; 2],
}

/// The delta-method bands of every figure beside Monte-Carlo bands from `samples` draws
/// of the parameters (seed `seed`): the check of [`predict`]'s bands (slow: each draw is a
/// whole prediction). Empty when the fit gives no band.
pub fn check_bands(
    fit: &FitFile,
    options: &PredictOptions,
    samples: usize,
    seed: u64,
) -> Result<Vec<BandCheck>, PredictError> {
    let (centre, speeds) = centre_and_figures(fit, options)?;
    let unc = ParamUncertainty::for_bands(fit, options.fixed_spread);
    let smooth = centre.flat(true);
    let figures =
        |m: &Motor| Outcome::of(m, options, Some(&speeds), fit.gear.as_ref()).map(|o| o.flat(true));
    let delta = unc.delta_bands(fit, &smooth, &figures)?;
    let mc = unc.monte_carlo_bands(fit, samples, seed, &figures)?;
    let (Some(delta), Some(mc)) = (delta, mc) else {
        return Ok(Vec::new());
    };
    let mut labels = Vec::new();
    for (row, speeds) in centre.rows.iter().zip(&speeds) {
        let p = row.p_supply_pa;
        labels.extend(ROW_FIGURES.iter().map(|f| format!("{p:.0} {f}")));
        labels.extend(FACTORS.iter().map(|f| format!("{p:.0} factor {f}")));
        for w in speeds {
            labels.extend(["torque", "power", "air"].map(|q| format!("{p:.0} {q}@{w:.2}")));
        }
    }
    Ok(labels
        .into_iter()
        .enumerate()
        .map(|(i, label)| BandCheck {
            label,
            value: smooth[i],
            delta: delta[i],
            monte_carlo: mc[i],
        })
        .collect())
}
