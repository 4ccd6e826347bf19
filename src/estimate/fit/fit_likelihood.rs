//! The likelihood a fit's estimate and intervals were measured on, rebuilt from its fit file,
//! for tools outside vanefit (the Python package, pyPESTO, the PEtab export).
//!
//! A fit ([`crate::estimate::fit`]) maximises the likelihood of the recorded rows
//! ([`crate::objective::likelihood`]): the experiments driven by the smooth of each recorded
//! input, σ per channel from the data, the sensors' offsets and the supply-pressure sensor's
//! offset profiled out as Gaussian nuisances ([`crate::objective::nuisance`]),
//!
//! ```text
//!     χ²(θ) = min_β ‖u(θ) + A·β‖² + ‖Λ·β‖²,    u_i = (y_sim,i(θ) − y_i)/(k_c·σ_c)
//! ```
//!
//! where k_c ≥ 1 widens a channel whose residuals at the estimate scatter more than its
//! noise (the fit file's `statistics.widened_noise`), and the supply pressure's column of A
//! is the simulation's response to the recorded pressure, linearised at the motor the fit
//! file names in `statistics.linearised_at`. With both, the χ² of the fit file's parameters
//! is the fit's own `statistics.likelihood_chi2`, to rounding; the 95 % profile interval of
//! a parameter is where χ² rises by `statistics.profile_threshold` = χ²₁(0.95)·s² (s ≥ 1 the
//! widened likelihood's interval scale). (`statistics.chi2` is the goodness of fit: the
//! rows against the data's own σ, without the priors.)
//!
//! # The motor prior
//!
//! A fit made with the motor prior (docs/estimation.md, "Priors") minimised χ² + χ²_prior,
//! with the prior's log-normal terms as the fit file states them (`statistics.prior`):
//!
//! ```text
//!     χ²_prior(θ) = Σ_j ((ln θ_j − ln m_j − k_j·ln(V/V̂))/σ_j)²
//! ```
//!
//! over the estimated parameters with an entry (median m_j, σ_j = `sd_ln`; where the
//! displacement V was estimated too, the medians follow it with size exponent k_j about
//! the fit's V̂, else k_j = 0). [`FitLikelihood::prior_chi2`] and
//! [`FitLikelihood::prior_residuals`] give it; the χ² methods above stay the likelihood's
//! alone, so that a sampler adding its own prior does not count it twice. At the fit's
//! estimate, `likelihood_chi2` + `prior_chi2` of the fit file is the fit's objective.

use crate::data::dataset::Dataset;
use crate::data::fitfile::FitFile;
use crate::estimate::problem::fit_data::FitData;
use crate::estimate::problem::prior::{PriorTerm, NO_LOG_RESIDUAL};
use crate::estimate::problem::space::{Dimension, SpaceError};
use crate::estimate::profile::uncertainty::CHI2_95;
use crate::model::effects::EffectSet;
use crate::model::extra::ExtraTerm;
use crate::model::motor::Motor;
use crate::model::params::{MotorParams, ParamError, ParamId};
use crate::numerics::DefaultSolver;
use crate::objective::cost::{CostError, CostOptions, FAILURE_PENALTY};
use crate::objective::likelihood::Target;

/// Why a fit's likelihood cannot be rebuilt or evaluated.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FitLikelihoodError {
    /// The fit file has no statistics (not written by `vanefit fit`).
    #[error("the fit file of '{0}' holds no fit statistics: it was not written by `vanefit fit`")]
    NoStatistics(String),
    /// The fit file estimated nothing.
    #[error("the fit file of '{0}' estimated no parameters")]
    NothingEstimated(String),
    /// The fit file was made from another dataset.
    #[error("the fit file was made from dataset '{fit}', not '{dataset}'")]
    OtherDataset {
        /// The fit file's dataset.
        fit: String,
        /// The dataset given.
        dataset: String,
    },
    /// An estimated parameter has no search dimension.
    #[error("{0}")]
    Space(#[from] SpaceError),
    /// The dataset's cost could not be set up.
    #[error("{0}")]
    Cost(#[from] CostError),
    /// A parameter value is not valid for the motor.
    #[error("{0}")]
    Param(#[from] ParamError),
    /// A parameter vector of the wrong length.
    #[error("{got} parameter values given, the fit estimated {want} ({names})")]
    Length {
        /// Values given.
        got: usize,
        /// Parameters estimated.
        want: usize,
        /// Their names.
        names: String,
    },
    /// The simulation failed or gave a value that is not finite.
    #[error("the simulation failed at these parameters")]
    Simulation,
}

/// One compared channel at a parameter vector: what a tool needs to recompute χ².
#[derive(Debug, Clone)]
pub struct ChannelRows {
    /// The recording.
    pub file: String,
    /// The recording's column (name with unit).
    pub column: String,
    /// Recording rows compared (0-based data rows).
    pub rows: Vec<usize>,
    /// Recorded values at those rows, SI.
    pub data: Vec<f64>,
    /// σ of the channel in the likelihood (the data's noise, widened where the fit widened it), SI.
    pub sigma: f64,
    /// Simulated values at those rows, SI (inputs smoothed as in the fit).
    pub simulated: Vec<f64>,
    /// Normalised residuals after the nuisances' correction, (y_sim − y + (A·β̂)_i·σ)/σ: their
    /// squares summed over every channel are `chi2_data`.
    pub residuals: Vec<f64>,
    /// Per nuisance (in [`Breakdown::nuisances`]' order), how one unit of it moves each of
    /// these rows, SI (a_k restricted to the channel: 1 on the rows of an offset sensor's
    /// own channel, the linearised response to the supply pressure's offset, 0 elsewhere).
    pub(crate) nuisance_shapes: Vec<Vec<f64>>,
}

/// χ² at a parameter vector, split into its parts.
#[derive(Debug, Clone)]
pub struct Breakdown {
    /// Every compared channel.
    pub channels: Vec<ChannelRows>,
    /// The profiled nuisances: label, β̂ (SI of the nuisance), prior σ τ.
    pub nuisances: Vec<(String, f64, f64)>,
    /// Σ residuals² over the compared rows.
    pub chi2_data: f64,
    /// Σ (β̂/τ)² over the nuisances.
    pub chi2_prior: f64,
    /// Σ r² of the pages' power-peak terms (`objective::peak`): a condition on the power
    /// curve's shape, in no channel's rows.
    pub chi2_power_peaks: f64,
}

impl Breakdown {
    /// χ² = `chi2_data` + `chi2_prior` + `chi2_power_peaks`.
    pub fn chi2(&self) -> f64 {
        self.chi2_data + self.chi2_prior + self.chi2_power_peaks
    }
}

/// One estimated parameter's motor prior, as the fit file states it.
#[derive(Debug, Clone, PartialEq)]
pub struct MotorPriorTerm {
    /// Index of the parameter among the estimated ones.
    pub index: usize,
    /// The prior: its median stated at the fit's displacement V̂ (SI), σ of ln v, and the
    /// size exponent k the median follows where the displacement is estimated (0 where it
    /// is not).
    pub term: PriorTerm,
}

/// The likelihood of a fit, as a function of its estimated parameters (SI values).
pub struct FitLikelihood {
    data: FitData,
    target: Target,
    params: MotorParams,
    effects: EffectSet,
    extra: Vec<ExtraTerm>,
    dims: Vec<Dimension>,
    estimate: Vec<f64>,
    chi2_min: f64,
    threshold: f64,
    solver: DefaultSolver,
    prior: Vec<MotorPriorTerm>,
    /// Index of `v_disp` among the estimated parameters, where the priors' medians follow it.
    size_index: Option<usize>,
    /// V̂, the fit's displacement, m³.
    v_disp_hat: f64,
    prior_chi2_min: f64,
}

impl FitLikelihood {
    /// Rebuilds the likelihood of `fit` on `ds` (the dataset it was made from).
    pub fn from_fit(ds: &Dataset, fit: &FitFile) -> Result<Self, FitLikelihoodError> {
        let stats = fit
            .statistics
            .as_ref()
            .ok_or_else(|| FitLikelihoodError::NoStatistics(fit.dataset.clone()))?;
        if fit.estimated.is_empty() {
            return Err(FitLikelihoodError::NothingEstimated(fit.dataset.clone()));
        }
        if fit.dataset != ds.name {
            return Err(FitLikelihoodError::OtherDataset {
                fit: fit.dataset.clone(),
                dataset: ds.name.clone(),
            });
        }
        let data = FitData::new(ds, CostOptions::default())?;
        let number = |m: &serde_json::Map<String, serde_json::Value>, k: &str| {
            m.get(k).and_then(serde_json::Value::as_f64)
        };
        // Files written before `linearised_at` existed: linearise at the estimate.
        let mut at = fit.params.clone();
        for name in &fit.estimated {
            if let Some(v) = number(&stats.linearised_at, name) {
                at = at.with(name, v)?;
            }
        }
        let motor = Motor::new(at, fit.effects.clone()).with_extra(&fit.extra);
        let older = stats.likelihood_chi2.is_none();
        let target = data.target_at(&motor);
        let factors: Vec<f64> = data
            .labels()
            .iter()
            .map(|label| number(&stats.widened_noise, label).unwrap_or(1.0))
            .collect();
        let target = target.widened(&factors);
        let dims = fit
            .estimated
            .iter()
            .map(|n| {
                Dimension::for_param(n, fit.params.size()).or_else(|e| {
                    // A parameter whose default search range starts at 0 (the dead volume, which
                    // page fits estimate): ×/÷ 10 about the fitted value.
                    match fit.params.get(n).filter(|v| *v > 0.0) {
                        Some(v) => Dimension::with_bounds(n, v / 10.0, v * 10.0),
                        None => Err(e),
                    }
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let estimate = fit
            .estimated
            .iter()
            .map(|n| fit.params.get(n).unwrap_or(f64::NAN))
            .collect();
        let prior: Vec<MotorPriorTerm> = fit
            .estimated
            .iter()
            .enumerate()
            .filter_map(|(index, n)| {
                let e = stats.prior.iter().find(|e| e.parameter == *n)?;
                let id = ParamId::from_name(n)?;
                (e.median > 0.0 && e.sd_ln > 0.0).then(|| MotorPriorTerm {
                    index,
                    term: PriorTerm {
                        id,
                        median: e.median,
                        sd_ln: e.sd_ln,
                        size_exponent: e.size_exponent.unwrap_or(0.0),
                    },
                })
            })
            .collect();
        let size_index = fit
            .estimated
            .iter()
            .position(|n| ParamId::from_name(n) == Some(ParamId::V_DISP));
        let mut out = Self {
            data,
            target,
            params: fit.params.clone(),
            effects: fit.effects.clone(),
            extra: fit.extra.clone(),
            dims,
            estimate,
            chi2_min: stats.likelihood_chi2.unwrap_or(f64::NAN),
            threshold: stats
                .profile_threshold
                .unwrap_or(CHI2_95 * stats.goodness.interval_scale.powi(2)),
            solver: DefaultSolver::default(),
            prior,
            size_index,
            v_disp_hat: fit.params.v_disp(),
            prior_chi2_min: 0.0,
        };
        out.prior_chi2_min = stats
            .prior_chi2
            .unwrap_or_else(|| out.prior_chi2(&out.estimate));
        if older {
            // Files written before `likelihood_chi2` existed: the minimum is taken where it
            // is evaluated now.
            out.chi2_min = out.chi2(&out.estimate);
        }
        Ok(out)
    }

    /// Names of the estimated parameters, in the fit file's order.
    pub fn names(&self) -> Vec<String> {
        self.dims.iter().map(|d| d.name().to_string()).collect()
    }

    /// Each estimated parameter's default search bounds (lower, upper), SI.
    pub fn bounds(&self) -> Vec<(f64, f64)> {
        self.dims.iter().map(|d| (d.lo, d.hi)).collect()
    }

    /// Whether each parameter is searched on a log scale.
    pub fn log_scale(&self) -> Vec<bool> {
        self.dims.iter().map(|d| d.log_scale).collect()
    }

    /// The fit's estimate of each parameter, SI.
    pub fn estimate(&self) -> Vec<f64> {
        self.estimate.clone()
    }

    /// χ² at the estimate, as the fit file states it.
    pub fn chi2_min(&self) -> f64 {
        self.chi2_min
    }

    /// Rise of χ² over its minimum that bounds a 95 % profile interval, χ²₁(0.95)·s².
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// The motor at `values` (SI, one per estimated parameter; the rest as fitted).
    pub fn motor(&self, values: &[f64]) -> Result<Motor, FitLikelihoodError> {
        if values.len() != self.dims.len() {
            return Err(FitLikelihoodError::Length {
                got: values.len(),
                want: self.dims.len(),
                names: self.names().join(", "),
            });
        }
        let mut p = self.params.clone();
        for (d, v) in self.dims.iter().zip(values) {
            p = p.with_value(d.id, *v)?;
        }
        Ok(Motor::new(p, self.effects.clone()).with_extra(&self.extra))
    }

    /// χ² at `values`, or why it cannot be computed.
    pub fn try_chi2(&self, values: &[f64]) -> Result<f64, FitLikelihoodError> {
        let motor = self.motor(values)?;
        self.target
            .chi2(&self.data.smoothed, &motor, &self.solver)
            .ok_or(FitLikelihoodError::Simulation)
    }

    /// The residual vector at `values` (the compared rows after the nuisances' correction,
    /// then one row per nuisance's prior): its squares sum to χ², so least-squares optimizers
    /// (Levenberg–Marquardt, pyPESTO's `res`) can use it directly.
    pub fn residuals(&self, values: &[f64]) -> Result<Vec<f64>, FitLikelihoodError> {
        let motor = self.motor(values)?;
        self.target
            .residuals(&self.data.smoothed, &motor, &self.solver)
            .ok_or(FitLikelihoodError::Simulation)
    }

    /// The motor prior's terms of the estimated parameters (empty for a fit made without
    /// priors), in the fit file's order.
    pub fn prior_terms(&self) -> &[MotorPriorTerm] {
        &self.prior
    }

    /// The motor prior's residuals (ln θ_j − ln m_j − k_j·ln(V/V̂))/σ_j at `values`, one per
    /// [`Self::prior_terms`] entry: their squares sum to χ²_prior (module documentation). A
    /// value without a logarithm gives a large finite residual.
    pub fn prior_residuals(&self, values: &[f64]) -> Result<Vec<f64>, FitLikelihoodError> {
        if values.len() != self.dims.len() {
            return Err(FitLikelihoodError::Length {
                got: values.len(),
                want: self.dims.len(),
                names: self.names().join(", "),
            });
        }
        // V/V̂: the medians are stated at the fit's displacement V̂.
        let size = self.size_index.map_or(1.0, |j| values[j] / self.v_disp_hat);
        Ok(self
            .prior
            .iter()
            .map(|t| t.term.residual_at_size(values[t.index], size))
            .collect())
    }

    /// χ²_prior at `values` (module documentation); 0 for a fit made without priors, the
    /// square of the large residual for a bad vector.
    pub fn prior_chi2(&self, values: &[f64]) -> f64 {
        self.prior_residuals(values)
            .map_or(NO_LOG_RESIDUAL * NO_LOG_RESIDUAL, |r| {
                r.iter().map(|x| x * x).sum()
            })
    }

    /// χ²_prior at the estimate, as the fit file states it (`statistics.prior_chi2`).
    pub fn prior_chi2_min(&self) -> f64 {
        self.prior_chi2_min
    }

    /// The motor prior as a log-density of the values in the sampler's coordinates (ln θ,
    /// where the log-normal is a Gaussian with no Jacobian): −½·(χ²_prior − χ²_prior,min),
    /// 0 at the estimate, −∞ where a value has no logarithm.
    pub fn log_prior(&self, values: &[f64]) -> f64 {
        match self.prior_residuals(values) {
            Ok(r) if r.iter().all(|x| x.abs() < NO_LOG_RESIDUAL) => {
                -0.5 * (r.iter().map(|x| x * x).sum::<f64>() - self.prior_chi2_min)
            }
            _ => f64::NEG_INFINITY,
        }
    }

    /// The estimated parameters' search dimensions (bounds, scales), in the fit file's order.
    pub(crate) fn dimensions(&self) -> &[Dimension] {
        &self.dims
    }

    /// χ² at `values` for an optimizer: finite always, the cost module's
    /// `FAILURE_PENALTY` where the values are invalid or the simulation fails.
    pub fn chi2(&self, values: &[f64]) -> f64 {
        self.try_chi2(values).unwrap_or(FAILURE_PENALTY)
    }

    /// χ² at `values` split into the rows' and the nuisances' parts, with every compared row.
    pub fn breakdown(&self, values: &[f64]) -> Result<Breakdown, FitLikelihoodError> {
        let motor = self.motor(values)?;
        let simulated = self
            .data
            .smoothed
            .simulated_rows(&motor, &self.solver)
            .map_err(|_| FitLikelihoodError::Simulation)?;
        let r = self.target.residual_vector(&simulated);
        if r.iter().any(|v| !v.is_finite()) {
            return Err(FitLikelihoodError::Simulation);
        }
        // The channels' rows, then the pages' power peaks (which have no reference).
        let beta = self.target.nuisance_estimates(&simulated);
        let n_points = self.target.n_points();
        let shapes: Vec<&[f64]> = self
            .target
            .nuisances()
            .map(|n| n.items().iter().map(|it| it.shape.as_slice()).collect())
            .unwrap_or_default();
        let mut start = 0;
        let channels: Vec<ChannelRows> = self
            .target
            .channels
            .iter()
            .zip(self.data.smoothed.references())
            .zip(simulated)
            .map(|((c, reference), sim)| {
                let span = start..start + c.rows.len();
                let part = r[span.clone()].to_vec();
                let nuisance_shapes = shapes.iter().map(|a| a[span.clone()].to_vec()).collect();
                start += c.rows.len();
                ChannelRows {
                    file: c.file.clone(),
                    column: reference.column.clone(),
                    rows: c.rows.clone(),
                    data: c.data.clone(),
                    sigma: c.sigma,
                    simulated: sim,
                    residuals: part,
                    nuisance_shapes,
                }
            })
            .collect();
        let chi2_data = r[..start].iter().map(|v| v * v).sum();
        let chi2_power_peaks = r[start..n_points].iter().map(|v| v * v).sum();
        let chi2_prior = r[n_points..].iter().map(|v| v * v).sum();
        let nuisances = match self.target.nuisances() {
            Some(n) => n
                .items()
                .iter()
                .zip(beta)
                .map(|(it, (label, b))| (label, b, it.prior_sd))
                .collect(),
            None => Vec::new(),
        };
        Ok(Breakdown {
            channels,
            nuisances,
            chi2_data,
            chi2_prior,
            chi2_power_peaks,
        })
    }
}
