//! Bands from posterior samples, where the delta method fails: a curved valley, an
//! interval that is lopsided, a parameter the data do not pin (two optima that fit equally).
//!
//! A sampler ([`crate::estimate::sample`]; which one: [`Sampler`]) draws the fit's
//! estimated parameters from their posterior (the fit's likelihood, with a prior if one is
//! given, flat within the search bounds otherwise). `draws` of the
//! kept samples, spread evenly over walkers and steps, are each propagated through every
//! figure; a figure's 95 % band is the 2.5 and 97.5 percentiles of its values (linear
//! interpolation between order statistics). Parameters covered by a stated spread
//! (`--fixed-spread`) and not sampled are drawn independently for each propagated sample,
//! ln θ ~ N(ln θ̂, (ln F/1.96)²), as the delta method takes them.
//!
//! # When the bands come from samples (`auto`, the default)
//!
//! With the fit's dataset at hand (given, or found from the fit file: `data::locate`),
//! `auto` samples the posterior and makes the bands from the samples when they converged
//! ([`PosteriorSummary::converged`]: every R̂ < 1.01 and ESS ≥ 400); otherwise, or without
//! the dataset, from the delta method, and says why ([`BandsMade::statement`]).
//!
//! The delta method linearises each figure about the estimate with the fit's covariance;
//! the notes say it is not to be trusted where the fit file itself says the posterior is not
//! close to Gaussian ([`delta_unreliable`]):
//!
//! * an estimated parameter is not identifiable (its profile does not close, or another
//!   optimum fits as well), or has no 95 % interval;
//! * a profile interval is lopsided: its two sides in ln θ differ by more than a factor
//!   [`LOPSIDED`] (a Gaussian posterior in ln θ gives equal sides).

use super::uncertainty::ParamUncertainty;
use super::PredictError;
use crate::data::fitfile::FitFile;
use crate::estimate::fit::fit_likelihood::FitLikelihood;
use crate::estimate::sample::{
    run_chains, run_ensemble_resumable, run_ensemble_with, straightened, summarise, ChainSettings,
    Checkpoint, EnsembleSettings, FitPosterior, ImportanceCheck, LogDensity, LogPrior, Mapped,
    Moves, ParamDiagnostics, QuadraticMap, SampleError, TProposal, Unbounded, PROPOSAL_NU,
};
use crate::model::motor::Motor;
use crate::model::params::ParamSet;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

/// Share of the walkers' proposals that are differential-evolution moves, the rest stretch
/// moves ([`Moves::Mixed`]). A page's posterior is its prior in most directions, cut by a
/// few thin, curved constraints the printed figures make: there the stretch move alone
/// mixed so slowly that 4000 steps left R̂ at 1.3–2.0 and the bands at the pressures
/// farthest from the page too narrow (docs/validation.md, "Sampled bands on a page");
/// with this mixture the same steps give 2–3 times the effective sample size.
pub const DE_SHARE: f64 = 0.8;

/// Ratio of a profile interval's two sides in ln θ above which `auto` samples.
pub const LOPSIDED: f64 = 1.5;

/// Which method is asked to make the bands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BandChoice {
    /// The delta method always.
    Delta,
    /// Posterior samples always (needs the dataset).
    Samples,
    /// Posterior samples when the dataset is at hand and they converged, else the delta
    /// method (see the module documentation).
    Auto,
}

impl BandChoice {
    /// `delta`, `samples` or `auto`.
    pub fn name(self) -> &'static str {
        match self {
            BandChoice::Delta => "delta",
            BandChoice::Samples => "samples",
            BandChoice::Auto => "auto",
        }
    }
}

/// The method that made the bands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BandMethod {
    /// The delta method from the fit's covariance.
    Delta,
    /// Percentiles of the figures of posterior samples.
    Samples,
}

/// How to sample.
#[derive(Debug, Clone, PartialEq)]
pub struct SamplingOptions {
    /// Walkers (`None`: max(16, 4·d) for d estimated parameters).
    pub walkers: Option<usize>,
    /// Kept steps per walker.
    pub steps: usize,
    /// Steps run first and discarded.
    pub burn_in: usize,
    /// Kept samples propagated through the figures.
    pub draws: usize,
    /// Seed of the walkers' streams and of the spread parameters' draws.
    pub seed: u64,
    /// Steps per walker between checkpoints.
    pub block: usize,
    /// Where the chains are checkpointed after every block and resumed from (`None`: not
    /// checkpointed). A checkpoint made with other settings is an error; the file is
    /// removed when the run ends.
    pub checkpoint: Option<std::path::PathBuf>,
}

/// Kept steps per walker unless others are asked.
pub const DEFAULT_STEPS: usize = 4000;
/// Burn-in steps unless others are asked.
pub const DEFAULT_BURN_IN: usize = 1000;
/// Steps per walker between checkpoints.
pub const DEFAULT_BLOCK: usize = 1000;
/// Samples propagated through the figures unless another number is asked.
pub const DEFAULT_DRAWS: usize = 400;

impl Default for SamplingOptions {
    fn default() -> Self {
        Self {
            walkers: None,
            steps: DEFAULT_STEPS,
            burn_in: DEFAULT_BURN_IN,
            draws: DEFAULT_DRAWS,
            seed: 1,
            block: DEFAULT_BLOCK,
            checkpoint: None,
        }
    }
}

impl SamplingOptions {
    /// The walkers for `d` parameters: as asked, else max(16, 4·d) rounded up to even.
    pub fn walkers_for(&self, d: usize) -> usize {
        self.walkers
            .unwrap_or_else(|| (4 * d).max(16).div_ceil(2) * 2)
    }
}

/// The posterior the samples are drawn from: the fit's likelihood and an optional prior.
#[derive(Clone, Copy)]
pub struct PosteriorSource<'a> {
    /// The fit's likelihood, rebuilt from its file and dataset.
    pub likelihood: &'a FitLikelihood,
    /// A log-prior of the estimated parameters (`None`: flat within the search bounds).
    pub prior: Option<&'a dyn LogPrior>,
}

/// Where the dataset the posterior stands on was found, or why there is none: said with
/// the bands.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PosteriorData {
    /// The dataset is at hand: where it was found, in words ("dataset x at y (...)").
    At(String),
    /// It is not: why, in words ("the dataset x was not found (looked at ...)").
    Missing(String),
}

/// What the bands of a prediction should stand on.
#[derive(Clone, Copy)]
pub struct BandRequest<'a> {
    /// The method asked.
    pub choice: BandChoice,
    /// The posterior, when the dataset is at hand.
    pub posterior: Option<PosteriorSource<'a>>,
    /// Where the dataset was found, or why it is not at hand (`None`: not said; without a
    /// posterior that reads "the fit's dataset was not given").
    pub data: Option<&'a PosteriorData>,
    /// How to sample.
    pub sampling: &'a SamplingOptions,
    /// Progress of long work: (what, done, total).
    pub progress: &'a (dyn Fn(&str, usize, usize) + Sync),
}

/// What the samples were and how well they converged.
#[derive(Debug, Clone, PartialEq)]
pub struct PosteriorSummary {
    /// The sampled parameters.
    pub names: Vec<String>,
    /// Each one's R̂ and effective sample sizes.
    pub diagnostics: Vec<ParamDiagnostics>,
    /// Each one's 2.5, 50 and 97.5 % posterior quantiles, SI.
    pub quantiles: Vec<[f64; 3]>,
    /// Walkers, kept steps, burn-in steps, seed.
    pub walkers: usize,
    /// Kept steps per walker.
    pub steps: usize,
    /// Burn-in steps per walker.
    pub burn_in: usize,
    /// Seed.
    pub seed: u64,
    /// Mean acceptance fraction.
    pub acceptance: f64,
    /// Samples propagated through the figures: 0 where `auto` found that they did not
    /// converge (decided before any was propagated).
    pub draws: usize,
    /// Of those, how many gave no figures (the motor failed at some pressure): left out.
    pub failed_draws: usize,
    /// Parameters drawn from the stated spread for each sample (not sampled).
    pub spread: Vec<String>,
    /// The kept samples themselves (for arviz: `vanefit.Prediction.to_arviz()`).
    pub kept: PosteriorDraws,
    /// The sampler that drew them, and why.
    pub sampler: Sampler,
}

/// The kept samples of the walkers, SI.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PosteriorDraws {
    /// `values[walker][step][i]`: sampled parameter i (`PosteriorSummary::names`), SI.
    pub values: Vec<Vec<Vec<f64>>>,
    /// ln p of each sample (the sampler's log-density, 0 at the estimate), same layout.
    pub log_density: Vec<Vec<f64>>,
    /// Fraction of proposals accepted per walker over the kept steps.
    pub acceptance: Vec<f64>,
}

impl PosteriorDraws {
    /// The chains of `post`'s sampler in SI values.
    fn of(post: &FitPosterior, chains: &crate::estimate::sample::Chains) -> Self {
        Self {
            values: chains
                .draws
                .iter()
                .map(|w| w.iter().map(|x| post.to_values(x)).collect())
                .collect(),
            log_density: chains.log_density.clone(),
            acceptance: chains.acceptance.clone(),
        }
    }
}

/// Which sampler drew the posterior. The posterior's Laplace approximation is checked by
/// importance sampling from its t proposal (`IMPORTANCE_DRAWS` draws,
/// [`ImportanceCheck`]): where every draw has a positive density and the weights' Pareto
/// k̂ < 0.7 (a rig fit: k̂ 0.12) the Laplace-guided chains draw it
/// ([`crate::estimate::run_chains`]); otherwise (a catalogue page: k̂ 2–21, a fifth of the
/// draws outside the support, a valley that the residuals' own curvature bends) the same
/// chains run in the coordinates of a quadratic transport map learnt from a pilot ensemble,
/// and where that map does not straighten the posterior (its t's k̂ >
/// [`TRANSPORT_K_HAT_LIMIT`]) the affine-invariant ensemble draws it (docs/validation.md,
/// "Sampled bands on a page").
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Sampler {
    /// Metropolis–Hastings chains from the Laplace approximation (independence moves from
    /// its t proposal and whitened random walks).
    Laplace {
        /// The importance weights' k̂.
        k_hat: f64,
    },
    /// Metropolis–Hastings chains in the coordinates of a quadratic transport map learnt
    /// from a pilot ensemble ([`crate::estimate::QuadraticMap`]), which straightens the
    /// posterior's curved valley: independence moves from the t of the mapped draws'
    /// Gaussian and whitened random walks (`PredictSummary`'s chains are in the fit's
    /// coordinates).
    Transport {
        /// The Laplace approximation's importance weights' k̂ (∞ where a draw fell outside
        /// the support), `None` where it could not be made.
        laplace_k_hat: Option<f64>,
        /// The mapped t's importance weights' k̂, over its draws where p > 0.
        k_hat: f64,
    },
    /// The affine-invariant ensemble of differential-evolution and stretch moves.
    Ensemble {
        /// The importance weights' k̂ (∞ where a draw fell outside the support), `None`
        /// where the Laplace approximation could not be made.
        k_hat: Option<f64>,
        /// The transport map's t's k̂, above [`TRANSPORT_K_HAT_LIMIT`] (`None`: no map
        /// was tried).
        transport_k_hat: Option<f64>,
    },
}

/// Draws of the Laplace approximation's t proposal that decide the sampler.
pub const IMPORTANCE_DRAWS: usize = 400;
/// Chains of the Laplace-guided sampler unless `--walkers` asks for others.
pub const DEFAULT_CHAINS: usize = 8;

impl PosteriorSummary {
    /// Converged by Vehtari et al.'s rules: every R̂ < 1.01 and every ESS ≥ 400.
    pub fn converged(&self) -> bool {
        use crate::estimate::sample::diagnostics::{ESS_LIMIT, RHAT_LIMIT};
        self.diagnostics
            .iter()
            .all(|d| d.rhat < RHAT_LIMIT && d.ess_bulk >= ESS_LIMIT && d.ess_tail >= ESS_LIMIT)
    }
}

impl PosteriorSummary {
    /// The largest R̂ and the smallest effective sample size (bulk or tail) over the
    /// sampled parameters.
    pub fn worst(&self) -> (f64, f64) {
        let rhat = self.diagnostics.iter().map(|d| d.rhat).fold(0.0, f64::max);
        let ess = self
            .diagnostics
            .iter()
            .map(|d| d.ess_bulk.min(d.ess_tail))
            .fold(f64::INFINITY, f64::min);
        (rhat, ess)
    }
}

/// Why the bands were made by the method that made them.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum BandReason {
    /// The method was asked for (`--bands delta` or `--bands samples`).
    Asked,
    /// `auto`: the samples converged.
    Converged,
    /// `auto`: the samples did not converge (their summary is in `sampling`).
    NotConverged,
    /// `auto`: the dataset is not at hand (why, in words).
    NoData(String),
    /// `auto`: the sampler or the samples' figures failed (why, in words).
    SamplingFailed(String),
}

/// Which method made a prediction's bands, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct BandsMade {
    /// The method.
    pub method: BandMethod,
    /// The method asked.
    pub choice: BandChoice,
    /// Why this method.
    pub reason: BandReason,
    /// Why the delta method is not to be trusted for this fit (`None`: nothing says so).
    pub delta_unreliable: Option<String>,
    /// The samples, when any were drawn: they made the bands, or `auto` found that they
    /// did not converge (`reason`).
    pub sampling: Option<PosteriorSummary>,
    /// Where the dataset the samples stand on was found, or why it was not.
    pub data: Option<PosteriorData>,
}

impl BandsMade {
    /// The samples, when they made the bands.
    pub fn used_samples(&self) -> Option<&PosteriorSummary> {
        self.sampling
            .as_ref()
            .filter(|_| self.method == BandMethod::Samples)
    }

    /// Which method made the bands and why, in one sentence without a full stop: "bands
    /// from 400 posterior samples (R̂ ≤ 1.004, ESS ≥ 612)", "delta-method bands: the samples
    /// did not converge (largest R̂ 1.69, smallest ESS 63)", "delta-method bands: the
    /// dataset x was not found (looked at ...)".
    pub fn statement(&self) -> String {
        let asked = self.choice.name();
        match (&self.reason, self.sampling.as_ref()) {
            (BandReason::NotConverged, Some(s)) => {
                let (rhat, ess) = s.worst();
                format!(
                    "delta-method bands: the samples did not converge (largest R̂ {rhat:.3}, smallest ESS {ess:.0}; converged means R̂ < 1.01 and ESS ≥ 400)"
                )
            }
            (BandReason::NoData(why), _) => format!("delta-method bands: {why}"),
            (BandReason::SamplingFailed(why), _) => {
                format!("delta-method bands: sampling the posterior failed ({why})")
            }
            (_, Some(s)) if self.method == BandMethod::Samples => {
                let (rhat, ess) = s.worst();
                let verdict = if s.converged() {
                    "converged"
                } else {
                    "NOT converged"
                };
                format!(
                    "bands from {} posterior samples (R̂ ≤ {rhat:.3}, ESS ≥ {ess:.0}: {verdict}; --bands {asked})",
                    s.draws - s.failed_draws
                )
            }
            _ => format!("delta-method bands (--bands {asked})"),
        }
    }
}

/// Why the delta method is not to be trusted for `fit` (see the module documentation), or
/// `None`.
pub fn delta_unreliable(fit: &FitFile) -> Option<String> {
    let mut why = Vec::new();
    for n in &fit.estimated {
        if fit.verdicts.iter().any(|v| &v.name == n && !v.identifiable) {
            why.push(format!("{n} is not identifiable"));
            continue;
        }
        let ci = fit.ci95.iter().find(|(m, _)| m == n).map(|(_, c)| *c);
        let value = fit.params.get(n).unwrap_or(f64::NAN);
        match ci {
            Some([lo, hi]) if lo > 0.0 && value > lo && hi > value => {
                let (down, up) = ((value / lo).ln(), (hi / value).ln());
                let ratio = down.max(up) / down.min(up);
                if ratio > LOPSIDED {
                    why.push(format!(
                        "the interval of {n} is lopsided ({ratio:.1}:1 in ln {n})"
                    ));
                }
            }
            _ => why.push(format!("{n} has no two-sided 95 % interval")),
        }
    }
    (!why.is_empty()).then(|| why.join("; "))
}

/// Starts of the walkers: a ball about the estimate, half the delta method's σ wide where
/// known (2 % in ln θ otherwise), each redrawn (narrower each time) until its density is
/// positive.
fn starts(
    post: &FitPosterior,
    unc: &ParamUncertainty,
    estimate: &[f64],
    walkers: usize,
    seed: u64,
) -> Vec<Vec<f64>> {
    let centre = post.to_coords(estimate);
    let width: Vec<f64> = post
        .names()
        .iter()
        .map(|n| {
            let sd = unc.names.iter().position(|m| m == n).map(|j| unc.sd[j]);
            sd.filter(|s| *s > 0.0).map_or(0.02, |s| 0.5 * s)
        })
        .collect();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5157_4152_5453);
    (0..walkers)
        .map(|_| {
            for attempt in 0..60 {
                let shrink = 0.5_f64.powi(attempt / 10);
                let x: Vec<f64> = centre
                    .iter()
                    .zip(&width)
                    .map(|(c, w)| {
                        let z: f64 = StandardNormal.sample(&mut rng);
                        c + shrink * w * z
                    })
                    .collect();
                if post.log_density(&x).is_finite() {
                    return x;
                }
            }
            centre.clone()
        })
        .collect()
}

/// The fit's motor with the parameters `names` at SI `values`.
fn motor_with(fit: &FitFile, names: &[String], values: &[f64]) -> Result<Motor, PredictError> {
    let mut set = ParamSet::from(fit.params.clone());
    for (n, v) in names.iter().zip(values) {
        set.set(n, *v)?;
    }
    Ok(Motor::new(set.check()?, fit.effects.clone()).with_extra(&fit.extra))
}

/// The q-quantile of sorted values, interpolating linearly between order statistics.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    let x = q * (sorted.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x - x.floor());
    let next = sorted[(i + 1).min(sorted.len() - 1)];
    sorted[i] + f * (next - sorted[i])
}

/// Posterior samples of a fit, drawn but not yet propagated through any figure: `auto`
/// decides on their convergence first, so that samples it would throw away cost no
/// simulations of the figures.
pub(super) struct Drawn {
    chains: crate::estimate::sample::Chains,
    /// Their summary, with no draws propagated yet (`draws` 0).
    pub(super) summary: PosteriorSummary,
}

/// Draws the posterior of `source` (see [`Sampler`]) and summarises the draws: R̂, ESS,
/// quantiles; nothing is propagated through the figures ([`propagate_bands`] does that).
pub(super) fn sample_posterior(
    unc: &ParamUncertainty,
    source: PosteriorSource,
    sampling: &SamplingOptions,
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Result<Drawn, PredictError> {
    let post = posterior_of(&source);
    let names = post.names();
    let (chains, sampler) = draw(&post, unc, &source, sampling, progress)?;
    let diagnostics = summarise(&chains.draws);
    let quantiles = posterior_quantiles(&post, &chains, names.len());
    let spread = spread_not_sampled(unc, &names);
    let summary = PosteriorSummary {
        names,
        diagnostics,
        quantiles,
        walkers: chains.walkers(),
        steps: sampling.steps,
        burn_in: sampling.burn_in,
        seed: sampling.seed,
        acceptance: chains.mean_acceptance(),
        draws: 0,
        failed_draws: 0,
        spread: spread.into_iter().map(|(_, n)| n).collect(),
        kept: PosteriorDraws::of(&post, &chains),
        sampler,
    };
    Ok(Drawn { chains, summary })
}

/// The posterior of `source`: its likelihood and its prior, if any.
fn posterior_of<'a>(source: &PosteriorSource<'a>) -> FitPosterior<'a> {
    let post = FitPosterior::new(source.likelihood);
    match source.prior {
        Some(p) => post.with_prior(p),
        None => post,
    }
}

/// The 95 % bands of `figures` from the samples `drawn` ([`SamplingOptions::draws`] of
/// them, spread evenly over the chains), and their summary with the draws propagated.
pub(super) fn propagate_bands(
    fit: &FitFile,
    unc: &ParamUncertainty,
    source: PosteriorSource,
    sampling: &SamplingOptions,
    drawn: Drawn,
    figures: &(dyn Fn(&Motor) -> Result<Vec<f64>, PredictError> + Sync),
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Result<(Vec<[f64; 2]>, PosteriorSummary), PredictError> {
    let post = posterior_of(&source);
    let Drawn { chains, summary } = drawn;
    let values: Vec<Vec<f64>> = chains
        .thinned(sampling.draws)
        .iter()
        .map(|x| post.to_values(x))
        .collect();
    let spread = spread_not_sampled(unc, &summary.names);
    let jobs = with_spread_draws(values, &summary.names, unc, &spread, sampling.seed);
    let total = jobs.len();
    let results = propagate(fit, &jobs, figures, progress);
    let ok: Vec<&Vec<f64>> = results.iter().flatten().collect();
    let failed = total - ok.len();
    if ok.len() < 2 || failed * 10 > total {
        return Err(PredictError::SampleFigures { failed, total });
    }
    Ok((
        percentile_bands(&ok),
        PosteriorSummary {
            draws: total,
            failed_draws: failed,
            ..summary
        },
    ))
}

/// Draws from the posterior `post` with the sampler its shape calls for (see
/// [`Sampler`]), resuming from the checkpoint when one is asked and there.
fn draw(
    post: &FitPosterior,
    unc: &ParamUncertainty,
    source: &PosteriorSource,
    sampling: &SamplingOptions,
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Result<(crate::estimate::sample::Chains, Sampler), PredictError> {
    let step_progress = |done: usize, total: usize| progress("sampling", done, total);
    let checkpoint = sampling.checkpoint.as_ref().map(Checkpoint::at);
    // The Laplace approximation and how far the posterior is from it (400 simulations).
    let proposal = post.proposal().ok();
    let check = proposal
        .as_ref()
        .map(|q| ImportanceCheck::of(post, q, IMPORTANCE_DRAWS, sampling.seed ^ 0x1a91_ace0));
    if let (Some(q), Some(c)) = (&proposal, check.filter(ImportanceCheck::close)) {
        let settings = ChainSettings {
            chains: sampling.walkers.unwrap_or(DEFAULT_CHAINS),
            steps: sampling.steps,
            burn_in: sampling.burn_in,
            block: sampling.block,
            seed: sampling.seed,
        };
        let chains = run_chains(post, q, &settings, checkpoint.as_ref(), &step_progress)?;
        return Ok((chains, Sampler::Laplace { k_hat: c.k_hat }));
    }
    let far = Far {
        post,
        x0: starts(
            post,
            unc,
            &source.likelihood.estimate(),
            sampling.walkers_for(post.dim()),
            sampling.seed,
        ),
        sampling,
        laplace_k_hat: check.map(|c| c.k_hat),
        checkpoint: checkpoint.as_ref(),
    };
    Ok(far.draw(progress)?)
}

/// A posterior far from its Laplace approximation, and how to sample it: the transport
/// chains, or the ensemble where the map does not straighten it ([`Sampler`]).
struct Far<'a> {
    post: &'a FitPosterior<'a>,
    /// The walkers' starts about the estimate (the pilot's and the ensemble's).
    x0: Vec<Vec<f64>>,
    sampling: &'a SamplingOptions,
    laplace_k_hat: Option<f64>,
    checkpoint: Option<&'a Checkpoint>,
}

impl Far<'_> {
    /// The chains of `sampling` with `steps` kept steps from the streams of `seed`.
    fn chains(&self, steps: usize, seed: u64) -> ChainSettings {
        ChainSettings {
            chains: self.sampling.walkers.unwrap_or(DEFAULT_CHAINS),
            steps,
            burn_in: self.sampling.burn_in,
            block: self.sampling.block,
            seed,
        }
    }

    /// Draws the posterior (see [`Sampler`]), in the coordinates of [`FitPosterior`].
    fn draw(
        &self,
        progress: &(dyn Fn(&str, usize, usize) + Sync),
    ) -> Result<(crate::estimate::sample::Chains, Sampler), SampleError> {
        let step_progress = |done: usize, total: usize| progress("sampling", done, total);
        // Sampled in unbounded coordinates u: a t proposal there has the posterior's support.
        let ub = Unbounded {
            density: self.post,
            bounds: self.post.coord_bounds(),
        };
        let (map, q, k_hat) = self.straighten(&ub, progress)?;
        let seed = self.sampling.seed;
        if k_hat > TRANSPORT_K_HAT_LIMIT {
            // The map did not straighten the posterior: the ensemble mixes better there.
            let settings = EnsembleSettings {
                walkers: self.x0.len(),
                steps: self.sampling.steps,
                burn_in: self.sampling.burn_in,
                seed,
            };
            let chains = run_ensemble_resumable(
                self.post,
                &self.x0,
                &settings,
                Moves::Mixed { de: DE_SHARE },
                self.sampling.block,
                self.checkpoint,
                &step_progress,
            )?;
            let sampler = Sampler::Ensemble {
                k_hat: self.laplace_k_hat,
                transport_k_hat: Some(k_hat),
            };
            return Ok((chains, sampler));
        }
        let mapped = Mapped {
            density: &ub,
            map: &map,
        };
        let settings = self.chains(self.sampling.steps, seed);
        let zc = run_chains(&mapped, &q, &settings, self.checkpoint, &step_progress)?;
        let chains = crate::estimate::sample::Chains {
            draws: zc
                .draws
                .iter()
                .map(|c| c.iter().map(|z| ub.to_x(&map.inverse(z))).collect())
                .collect(),
            ..zc
        };
        let sampler = Sampler::Transport {
            laplace_k_hat: self.laplace_k_hat,
            k_hat,
        };
        Ok((chains, sampler))
    }

    /// The last of [`MAP_ROUNDS`] maps in the coordinates of `ub` (the first fitted to a
    /// pilot ensemble's draws, each next to those of chains run in the one before's
    /// coordinates with half the steps), its t proposal and that t's k̂ ([`fit_map`]).
    fn straighten(
        &self,
        ub: &Unbounded,
        progress: &(dyn Fn(&str, usize, usize) + Sync),
    ) -> Result<(QuadraticMap, TProposal, f64), SampleError> {
        let seed = self.sampling.seed;
        let u0: Vec<Vec<f64>> = self.x0.iter().map(|x| ub.to_u(x)).collect();
        let pilot = EnsembleSettings {
            walkers: u0.len(),
            steps: PILOT_STEPS,
            burn_in: PILOT_STEPS,
            seed,
        };
        let pilot_progress = |done: usize, total: usize| progress("pilot", done, total);
        let moves = Moves::Mixed { de: DE_SHARE };
        let mut draws = run_ensemble_with(ub, &u0, &pilot, moves, &pilot_progress)?.flat();
        let step_progress = |done: usize, total: usize| progress("sampling", done, total);
        for round in 0..MAP_ROUNDS - 1 {
            let (map, q, _) = fit_map(ub, &draws, seed)?;
            let mapped = Mapped {
                density: ub,
                map: &map,
            };
            let steps = self.sampling.steps.div_ceil(2).max(4);
            let settings = self.chains(steps, seed ^ (0x6d61_7030 + round as u64));
            let zc = run_chains(&mapped, &q, &settings, None, &step_progress)?;
            draws = zc
                .thinned(MAP_DRAWS)
                .iter()
                .map(|z| map.inverse(z))
                .collect();
        }
        fit_map(ub, &draws, seed)
    }
}

/// Steps per walker of the pilot ensemble whose draws the first transport map is fitted
/// to, after as many burn-in steps.
pub const PILOT_STEPS: usize = 500;
/// Maps fitted in turn: the first to the pilot's draws, each next to the draws of chains
/// that ran (half the steps) in the coordinates of the one before; the chains of the last
/// run all the steps.
pub const MAP_ROUNDS: usize = 2;
/// Draws a map is fitted to (spread evenly over the chains).
pub const MAP_DRAWS: usize = 8000;
/// Relative ridge of the map's least squares.
pub const MAP_RIDGE: f64 = 1e-6;
/// Scale c of the mapped draws' t proposal on their Cholesky factor.
pub const MAP_SCALE: f64 = 1.2;
/// Largest k̂ of the last map's t at which its chains draw the posterior; above it the
/// ensemble does. On the 30 twin pages of every size and style the transport chains
/// reached a lower R̂ than the ensemble on every page up to k̂ 1.83, a higher one on the
/// three from 2.51 (docs/validation.md, "Sampled bands on a page").
pub const TRANSPORT_K_HAT_LIMIT: f64 = 2.0;

/// The quadratic map fitted to `draws` (coordinates of `density`), the t proposal of the
/// mapped draws' Gaussian, and its importance weights' k̂ over `IMPORTANCE_DRAWS` draws
/// where p > 0.
fn fit_map(
    density: &dyn LogDensity,
    draws: &[Vec<f64>],
    seed: u64,
) -> Result<(QuadraticMap, TProposal, f64), SampleError> {
    let (map, q) = straightened(draws, MAP_RIDGE, PROPOSAL_NU, MAP_SCALE)?;
    let mapped = Mapped { density, map: &map };
    let (_, log_w) = ImportanceCheck::weighed(&mapped, &q, IMPORTANCE_DRAWS, seed ^ 0x1a91);
    let k_hat = ImportanceCheck::of_inside(log_w).k_hat;
    Ok((map, q, k_hat))
}

/// The 2.5, 50 and 97.5 % quantiles of each of the `n` sampled parameters over every kept
/// sample of `chains`, SI.
fn posterior_quantiles(
    post: &FitPosterior,
    chains: &crate::estimate::sample::Chains,
    n: usize,
) -> Vec<[f64; 3]> {
    (0..n)
        .map(|i| {
            let mut v: Vec<f64> = chains.flat().iter().map(|x| post.to_values(x)[i]).collect();
            v.sort_by(f64::total_cmp);
            [0.025, 0.5, 0.975].map(|q| percentile(&v, q))
        })
        .collect()
}

/// The parameters of the stated spread that are not sampled (`names`), with their index
/// in `unc`.
fn spread_not_sampled(unc: &ParamUncertainty, names: &[String]) -> Vec<(usize, String)> {
    unc.names
        .iter()
        .enumerate()
        .filter(|(_, n)| unc.spread.contains(n) && !names.contains(n))
        .map(|(j, n)| (j, n.clone()))
        .collect()
}

/// The parameter names and SI values to propagate for each sample: its sampled `values`
/// followed by the `spread` parameters, drawn per sample from one stream seeded by `seed`.
fn with_spread_draws(
    values: Vec<Vec<f64>>,
    names: &[String],
    unc: &ParamUncertainty,
    spread: &[(usize, String)],
    seed: u64,
) -> Vec<(Vec<String>, Vec<f64>)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed.wrapping_add(0x9e37_79b9));
    values
        .into_iter()
        .map(|v| {
            let mut n = names.to_vec();
            let mut v = v;
            for (j, name) in spread {
                let z: f64 = StandardNormal.sample(&mut rng);
                n.push(name.clone());
                v.push((unc.log_values[*j] + unc.sd[*j] * z).exp());
            }
            (n, v)
        })
        .collect()
}

/// Each sample's figures, in parallel, reporting progress; `None` where the motor fails or
/// a figure is not finite.
fn propagate(
    fit: &FitFile,
    jobs: &[(Vec<String>, Vec<f64>)],
    figures: &(dyn Fn(&Motor) -> Result<Vec<f64>, PredictError> + Sync),
    progress: &(dyn Fn(&str, usize, usize) + Sync),
) -> Vec<Option<Vec<f64>>> {
    let total = jobs.len();
    let done = std::sync::atomic::AtomicUsize::new(0);
    jobs.par_iter()
        .map(|(n, v)| {
            let r = motor_with(fit, n, v).and_then(|m| figures(&m)).ok();
            let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress("propagating", k, total);
            r.filter(|f| f.iter().all(|y| y.is_finite()))
        })
        .collect()
}

/// Each figure's 95 % band: the 2.5 and 97.5 percentiles of its values over the samples.
fn percentile_bands(samples: &[&Vec<f64>]) -> Vec<[f64; 2]> {
    (0..samples[0].len())
        .map(|i| {
            let mut v: Vec<f64> = samples.iter().map(|d| d[i]).collect();
            v.sort_by(f64::total_cmp);
            [percentile(&v, 0.025), percentile(&v, 0.975)]
        })
        .collect()
}
