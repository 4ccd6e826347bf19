//! The posterior of a fit's estimated parameters, as the ensemble sampler sees it.
//!
//! Coordinates x: ln θ for a parameter searched on a log scale (every positive one), θ
//! itself otherwise, in the fit file's order. The density is
//!
//! ```text
//!     ln p(x) = −½·(χ²(θ) − χ²_min)/s² + ln π(θ),     θ inside the search bounds
//! ```
//!
//! with χ² the fit's likelihood rebuilt from its file ([`FitLikelihood`]), χ²_min its value
//! at the estimate and s² = `profile_threshold`/χ²₁(0.95) the widened likelihood's interval
//! scale, so that the posterior's 95 % marginals agree with the fit's profile intervals
//! where the likelihood is Gaussian. The prior π is flat in x within the search bounds
//! unless a [`LogPrior`] is given ([`FitPosterior::with_prior`]); a failed simulation has
//! zero density. A parameter that the fit's motor prior bounds is sampled within its search
//! range widened ×/÷ [`PRIOR_SUPPORT_WIDENING`]: the search range is the optimizer's, and
//! cutting the posterior off there truncated the tails of what a page leaves to the prior
//! (three twin pages' sampled bands held 92 of 105 figures so, 105 with the wider range).

use super::laplace::{fd_step, gauss_newton, neg_hessian, Laplace, TProposal};
use super::{LogDensity, SampleError};
use crate::estimate::fit::fit_likelihood::FitLikelihood;
use crate::estimate::profile::uncertainty::CHI2_95;

/// A log-prior density of the estimated parameters' values (SI, the fit file's order), up
/// to a constant; −∞ where the prior is zero.
pub trait LogPrior: Sync {
    /// ln π(θ) + const.
    fn log_prior(&self, values: &[f64]) -> f64;
}

impl<F: Fn(&[f64]) -> f64 + Sync> LogPrior for F {
    fn log_prior(&self, values: &[f64]) -> f64 {
        self(values)
    }
}

/// Factor by which the sampling range of a parameter with a motor prior reaches beyond its
/// search range either way (the prior's σ of ln v is at most ln 4/1.96 = 0.71, so ×/÷ 10 more
/// is over 3 σ of room beyond any search bound).
pub const PRIOR_SUPPORT_WIDENING: f64 = 10.0;

/// The posterior of a fit (see the module documentation).
pub struct FitPosterior<'a> {
    likelihood: &'a FitLikelihood,
    prior: Option<&'a dyn LogPrior>,
    log_scale: Vec<bool>,
    bounds: Vec<(f64, f64)>,
    scale2: f64,
}

impl<'a> FitPosterior<'a> {
    /// The posterior with the likelihood of `likelihood` and a prior flat in the sampling
    /// coordinates within the search bounds.
    pub fn new(likelihood: &'a FitLikelihood) -> Self {
        let scale2 = (likelihood.threshold() / CHI2_95).max(1.0);
        let log_scale = likelihood.log_scale();
        let mut bounds = likelihood.bounds();
        // Where the motor prior bounds a parameter, the prior (not the optimizer's search
        // range) decides its tails: the search range is widened ×/÷ PRIOR_SUPPORT_WIDENING
        // so that it does not cut the posterior off at a few prior σ.
        for t in likelihood.prior_terms() {
            if let (Some(b), Some(true)) = (bounds.get_mut(t.index), log_scale.get(t.index)) {
                *b = (b.0 / PRIOR_SUPPORT_WIDENING, b.1 * PRIOR_SUPPORT_WIDENING);
            }
        }
        Self {
            likelihood,
            prior: None,
            log_scale,
            bounds,
            scale2,
        }
    }

    /// The same with the prior `prior` added to the flat one.
    pub fn with_prior(mut self, prior: &'a dyn LogPrior) -> Self {
        self.prior = Some(prior);
        self
    }

    /// The sampling coordinates of SI values.
    pub fn to_coords(&self, values: &[f64]) -> Vec<f64> {
        values
            .iter()
            .zip(&self.log_scale)
            .map(|(v, log)| if *log { v.ln() } else { *v })
            .collect()
    }

    /// The SI values at sampling coordinates.
    pub fn to_values(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(&self.log_scale)
            .map(|(v, log)| if *log { v.exp() } else { *v })
            .collect()
    }

    /// The search bounds in sampling coordinates.
    pub fn coord_bounds(&self) -> Vec<(f64, f64)> {
        self.bounds
            .iter()
            .zip(&self.log_scale)
            .map(|((lo, hi), log)| if *log { (lo.ln(), hi.ln()) } else { (*lo, *hi) })
            .collect()
    }

    /// The names of the parameters, in the coordinates' order.
    pub fn names(&self) -> Vec<String> {
        self.likelihood.names()
    }

    /// ln L at SI `values`: −½·(χ² − χ²_min)/s² (−∞ where the simulation fails).
    pub fn log_likelihood(&self, values: &[f64]) -> f64 {
        match self.likelihood.try_chi2(values) {
            Ok(c) if c.is_finite() => -0.5 * (c - self.likelihood.chi2_min()) / self.scale2,
            _ => f64::NEG_INFINITY,
        }
    }
}

impl FitPosterior<'_> {
    /// The Laplace approximation about the fit's estimate in the sampling coordinates
    /// (`estimate::sample::laplace`): the Gauss–Newton precision of the likelihood's residuals
    /// (JᵀJ/s²) plus the prior's (−∇² ln π, central differences), regularised by the
    /// supports' widths.
    pub fn laplace(&self) -> Result<Laplace, SampleError> {
        let x = self.to_coords(&self.likelihood.estimate());
        if !self.log_density(&x).is_finite() {
            return Err(SampleError::Curvature(
                "the density is zero at the estimate",
            ));
        }
        let bounds = self.coord_bounds();
        let steps: Vec<f64> = x
            .iter()
            .zip(&self.log_scale)
            .zip(&bounds)
            .map(|((v, log), b)| fd_step(*v, *log, *b))
            .collect();
        let residuals = |y: &[f64]| self.likelihood.residuals(&self.to_values(y)).ok();
        let mut h = gauss_newton(&residuals, &x, &steps, self.scale2)?;
        if let Some(p) = self.prior {
            let f = |y: &[f64]| p.log_prior(&self.to_values(y));
            let hp = neg_hessian(&f, &x, &steps);
            if hp.iter().any(|v| !v.is_finite()) {
                return Err(SampleError::Curvature(
                    "the prior is not smooth at the estimate",
                ));
            }
            h += hp;
        }
        let widths: Vec<f64> = bounds.iter().map(|(lo, hi)| hi - lo).collect();
        Laplace::from_precision(x, &h, &widths)
    }

    /// The Laplace approximation with the full Hessian of ln p at the estimate (central
    /// differences of the log-density, steps `step` in each coordinate), where the
    /// Gauss–Newton one leaves out the residuals' own curvature Σ rᵢ∇²rᵢ.
    pub fn laplace_full(&self, step: f64) -> Result<Laplace, SampleError> {
        let x = self.to_coords(&self.likelihood.estimate());
        let bounds = self.coord_bounds();
        let steps: Vec<f64> = x
            .iter()
            .zip(&bounds)
            .map(|(v, (lo, hi))| step.min(0.5 * (v - lo)).min(0.5 * (hi - v)).max(1e-9))
            .collect();
        let f = |y: &[f64]| self.log_density(y);
        let h = neg_hessian(&f, &x, &steps);
        if h.iter().any(|v| !v.is_finite()) {
            return Err(SampleError::Curvature(
                "the density is not finite beside the estimate",
            ));
        }
        let widths: Vec<f64> = bounds.iter().map(|(lo, hi)| hi - lo).collect();
        Laplace::from_precision(x, &h, &widths)
    }

    /// The t proposal of [`Self::laplace`] with the sampler's ν and scale
    /// ([`super::PROPOSAL_NU`], [`super::PROPOSAL_SCALE`]).
    pub fn proposal(&self) -> Result<TProposal, SampleError> {
        Ok(TProposal {
            laplace: self.laplace()?,
            nu: super::PROPOSAL_NU,
            scale: super::PROPOSAL_SCALE,
        })
    }
}

impl LogDensity for FitPosterior<'_> {
    fn dim(&self) -> usize {
        self.log_scale.len()
    }

    fn log_density(&self, x: &[f64]) -> f64 {
        let inside = x
            .iter()
            .zip(self.coord_bounds())
            .all(|(v, (lo, hi))| v.is_finite() && *v >= lo && *v <= hi);
        if !inside {
            return f64::NEG_INFINITY;
        }
        let values = self.to_values(x);
        let prior = self.prior.map_or(0.0, |p| p.log_prior(&values));
        if !prior.is_finite() {
            return f64::NEG_INFINITY;
        }
        let lp = self.log_likelihood(&values) + prior;
        if lp.is_nan() {
            f64::NEG_INFINITY
        } else {
            lp
        }
    }
}
