//! The posterior of a fit and vanefit's ensemble sampler and diagnostics, for checks
//! against emcee and arviz: the log-posterior in the sampler's coordinates (ln θ of a
//! log-scale parameter), a run of the sampler from given starts, and the R̂ / ESS of any
//! chains. The GIL is released while the sampler runs.

use crate::errors::ParameterError;
use pyo3::prelude::*;
use vanefit::estimate::summarise;
use vanefit::estimate::FitLikelihood;
use vanefit::estimate::{run_ensemble, EnsembleSettings, FitPosterior, LogDensity, LogPrior};

/// Chains, ln p and acceptance of a run, as plain lists.
pub(crate) type Run = (Vec<Vec<Vec<f64>>>, Vec<Vec<f64>>, Vec<f64>);

/// The fit's motor prior as the sampler's log-prior (`FitLikelihood::log_prior`: a
/// Gaussian in ln v, 0 at the estimate), as `vanefit predict --bands samples` adds it.
fn motor_prior(inner: &FitLikelihood) -> impl Fn(&[f64]) -> f64 + Sync + '_ {
    move |values: &[f64]| inner.log_prior(values)
}

/// The fit's posterior, with `prior` when `priors` (else flat in the sampling coordinates).
fn posterior<'a>(
    inner: &'a FitLikelihood,
    priors: bool,
    prior: &'a dyn LogPrior,
) -> FitPosterior<'a> {
    let post = FitPosterior::new(inner);
    if priors {
        post.with_prior(prior)
    } else {
        post
    }
}

/// ln p at sampling coordinates `x` (ln θ for a log-scale parameter, θ otherwise):
/// −½·(χ² − χ²_min)/s², plus the motor prior when `priors`, with a prior flat in `x`
/// within the search bounds; −inf outside them or where the simulation fails.
pub(crate) fn log_posterior(
    inner: &FitLikelihood,
    priors: bool,
    py: Python<'_>,
    x: Vec<f64>,
) -> PyResult<f64> {
    let prior = motor_prior(inner);
    let post = posterior(inner, priors, &prior);
    if x.len() != post.dim() {
        return Err(ParameterError::new_err(format!(
            "{} coordinates given, the fit estimated {} ({})",
            x.len(),
            post.dim(),
            post.names().join(", ")
        )));
    }
    Ok(py.detach(|| post.log_density(&x)))
}

/// Runs vanefit's ensemble sampler on the log-posterior (with the motor prior when
/// `priors`) from `starts` (one list of coordinates per walker): returns (chains[walker][step][param], ln p[walker][step],
/// acceptance per walker).
pub(crate) fn sample(
    inner: &FitLikelihood,
    priors: bool,
    py: Python<'_>,
    starts: Vec<Vec<f64>>,
    steps: usize,
    burn_in: usize,
    seed: u64,
) -> PyResult<Run> {
    let prior = motor_prior(inner);
    let post = posterior(inner, priors, &prior);
    let settings = EnsembleSettings {
        walkers: starts.len(),
        steps,
        burn_in,
        seed,
    };
    let chains = py
        .detach(|| run_ensemble(&post, &starts, &settings, &|_, _| {}))
        .map_err(|e| ParameterError::new_err(e.to_string()))?;
    Ok((chains.draws, chains.log_density, chains.acceptance))
}

/// Rank-normalised split-R̂, bulk ESS and tail ESS (Vehtari et al. 2021) of every parameter
/// of `chains[chain][draw][param]`.
#[pyfunction]
pub(crate) fn chain_diagnostics(chains: Vec<Vec<Vec<f64>>>) -> PyResult<Vec<(f64, f64, f64)>> {
    let n = chains.first().map_or(0, Vec::len);
    if n < 4 || chains.iter().any(|c| c.len() != n) {
        return Err(ParameterError::new_err(
            "give chains of equal length, at least 4 draws each",
        ));
    }
    Ok(summarise(&chains)
        .into_iter()
        .map(|d| (d.rhat, d.ess_bulk, d.ess_tail))
        .collect())
}
