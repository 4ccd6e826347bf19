//! Posterior sampling: the affine-invariant ensemble sampler of Goodman & Weare (2010,
//! "Ensemble samplers with affine invariance", Commun. Appl. Math. Comput. Sci. 5(1)) with
//! the stretch move, as in emcee (Foreman-Mackey et al. 2013), its convergence diagnostics
//! ([`diagnostics`]: rank-normalised split-R̂ and bulk/tail effective sample sizes) and the
//! posterior of a fit ([`posterior`]: its likelihood plus a prior term).
//!
//! # The stretch move
//!
//! K walkers x_k ∈ ℝᵈ move in two halves, as emcee does, so that one half moves in parallel
//! against the other held fixed. Walker k of one half draws a partner x_j uniformly from the
//! other half and a stretch z from g(z) ∝ 1/√z on [1/a, a] (a = 2), proposes
//!
//! ```text
//!     y = x_j + z·(x_k − x_j)
//! ```
//!
//! and accepts it with probability min(1, z^(d−1)·p(y)/p(x_k)). The chain of each walker
//! leaves p invariant; the move is unchanged by any affine map of x, so that a narrow,
//! correlated posterior is sampled as easily as a round one.
//!
//! # The differential-evolution move
//!
//! [`run_ensemble_with`] can mix in ter Braak's differential-evolution move ([`Moves`]): a
//! walker steps along the difference of two walkers of the other half. `predict` samples
//! with 80 % of these: on a catalogue page's posterior (a prior cut by a few thin, curved
//! constraints) the stretch move alone needed about ten times the steps to mix.
//!
//! # Determinism
//!
//! Walker k's block b draws from its own Xoshiro256++ stream: the seed's stream advanced by
//! k long jumps of 2¹⁹² draws and b + 1 jumps of 2¹²⁸ (`long_jump`, `jump`), so that no two
//! walkers or blocks share draws and a run resumed from a checkpoint continues alike. Every random number a
//! walker uses comes from its own stream in a fixed order, and the log-densities are
//! evaluated per walker, so the chains for a seed do not depend on how many threads rayon
//! runs the walkers on.

pub(crate) mod chains;
pub(crate) mod checkpoint;
pub(crate) mod diagnostics;
pub(crate) mod importance;
pub(crate) mod laplace;
pub(crate) mod posterior;
pub(crate) mod proposal;
pub(crate) mod settings;
pub(crate) mod transport;

pub use chains::{run_chains, INDEPENDENCE_SHARE, PROPOSAL_NU, PROPOSAL_SCALE, RW_TARGET};
pub use checkpoint::{Checkpoint, CheckpointError};
pub use diagnostics::{ess, ess_bulk, ess_tail, rhat_rank, summarise, ParamDiagnostics};
pub use importance::{ImportanceCheck, K_HAT_LIMIT};
pub use laplace::{Laplace, TProposal};
pub use proposal::Proposal;
pub use settings::ChainSettings;
pub use transport::{gaussian_of, straightened, Mapped, QuadraticMap, Unbounded};

pub use posterior::{FitPosterior, LogPrior};

use checkpoint::{fingerprint, ChainState, Key, Saved};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

/// A log-density known up to a constant, ln p(x) (−∞ outside its support).
pub trait LogDensity: Sync {
    /// Dimension d of x.
    fn dim(&self) -> usize;
    /// ln p(x) + const; `f64::NEG_INFINITY` where p is zero (outside bounds, a failed
    /// simulation). Never NaN.
    fn log_density(&self, x: &[f64]) -> f64;
}

/// The stretch scale a of the proposal's z ∈ [1/a, a] (emcee's default, Goodman & Weare's
/// recommendation).
pub const STRETCH_A: f64 = 2.0;

/// How to run the ensemble.
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleSettings {
    /// Number of walkers K (even, ≥ 2·(d + 1)).
    pub walkers: usize,
    /// Steps kept per walker after the burn-in.
    pub steps: usize,
    /// Steps run first and discarded.
    pub burn_in: usize,
    /// Seed of the walkers' random streams.
    pub seed: u64,
}

/// Why the ensemble cannot run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SampleError {
    /// Too few walkers, or an odd number.
    #[error("the ensemble needs an even number of walkers ≥ 2·(d + 1) = {need}, not {walkers}")]
    Walkers {
        /// Walkers asked.
        walkers: usize,
        /// The least number for this dimension.
        need: usize,
    },
    /// No steps to keep.
    #[error("the sampler needs at least 4 kept steps, not {0}")]
    Steps(usize),
    /// Fewer than two chains (R̂ compares chains).
    #[error("the sampler needs at least 2 chains, not {0}")]
    Chains(usize),
    /// Blocks of no steps.
    #[error("the sampler's blocks need at least one step")]
    Block,
    /// The Laplace approximation cannot be made.
    #[error("the posterior's curvature at the estimate: {0}")]
    Curvature(&'static str),
    /// A checkpoint cannot be read, written or used.
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    /// The run stopped after this many blocks, as its checkpoint's hook asked.
    #[error("stopped after block {0}, as asked")]
    Halted(usize),
    /// A start is not where the density is positive.
    #[error(
        "walker {0} starts where the density is zero (outside the bounds or a failed simulation)"
    )]
    BadStart(usize),
    /// The starts are not one per walker, or not of dimension d.
    #[error(
        "{got} starts given of dimension {dim_got}, the ensemble needs {want} of dimension {dim}"
    )]
    Starts {
        /// Starts given.
        got: usize,
        /// Walkers.
        want: usize,
        /// Dimension of the first start.
        dim_got: usize,
        /// Dimension of the density.
        dim: usize,
    },
}

/// The kept chains of an ensemble run.
#[derive(Debug, Clone, PartialEq)]
pub struct Chains {
    /// Dimension d.
    pub dim: usize,
    /// `draws[k][t]` is walker k's position after kept step t.
    pub draws: Vec<Vec<Vec<f64>>>,
    /// ln p of each draw, same layout.
    pub log_density: Vec<Vec<f64>>,
    /// Fraction of proposals accepted per walker over the kept steps.
    pub acceptance: Vec<f64>,
}

impl Chains {
    /// Number of walkers.
    pub fn walkers(&self) -> usize {
        self.draws.len()
    }

    /// Kept steps per walker.
    pub fn steps(&self) -> usize {
        self.draws.first().map_or(0, Vec::len)
    }

    /// Parameter `i` as one chain per walker: `[walker][step]`.
    pub fn parameter(&self, i: usize) -> Vec<Vec<f64>> {
        self.draws
            .iter()
            .map(|w| w.iter().map(|x| x[i]).collect())
            .collect()
    }

    /// Every draw, walker after walker.
    pub fn flat(&self) -> Vec<Vec<f64>> {
        self.draws.iter().flatten().cloned().collect()
    }

    /// `n` draws spread evenly over the kept steps of every walker (all when n ≥ K·T), in
    /// step-major order so that every walker contributes alike.
    pub fn thinned(&self, n: usize) -> Vec<Vec<f64>> {
        let (k, t) = (self.walkers(), self.steps());
        let total = k * t;
        let n = n.min(total).max(1);
        (0..n)
            .map(|i| {
                let flat = i * total / n;
                let (step, walker) = (flat / k, flat % k);
                self.draws[walker][step].clone()
            })
            .collect()
    }

    /// Mean acceptance fraction over the walkers.
    pub fn mean_acceptance(&self) -> f64 {
        self.acceptance.iter().sum::<f64>() / self.acceptance.len().max(1) as f64
    }
}

/// One walker's state (its `tried` counts its DE proposals: every 10th takes γ = 1) and
/// its random stream.
struct Walker {
    s: ChainState,
    rng: Xoshiro256PlusPlus,
}

/// z from g(z) ∝ 1/√z on [1/a, a], by inversion: z = ((a − 1)·u + 1)²/a.
fn stretch(u: f64) -> f64 {
    ((STRETCH_A - 1.0) * u + 1.0).powi(2) / STRETCH_A
}

/// The proposals the walkers make.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Moves {
    /// The stretch move alone (emcee's default; the module documentation).
    Stretch,
    /// The differential-evolution move (ter Braak 2006, "A Markov chain Monte Carlo version
    /// of the genetic algorithm Differential Evolution", Stat. Comput. 16; emcee's
    /// `DEMove`) with probability `de`, the stretch move otherwise. Walker k proposes
    ///
    /// ```text
    ///     y = x_k + γ·(x_a − x_b),    γ = (2.38/√(2d))·(1 + 0.1·N(0,1)),
    /// ```
    ///
    /// with x_a ≠ x_b two walkers of the other half, and accepts with probability
    /// min(1, p(y)/p(x_k)) (a symmetric proposal). Every 10th DE proposal of a walker takes
    /// γ = 1 (a jump between modes, as ter Braak advises). The move is affine invariant as
    /// the stretch move is, and in ten or more dimensions its steps follow a thin, curved
    /// posterior far better: on catalogue-page posteriors its autocorrelation time is a
    /// fraction of the stretch move's (docs/validation.md, "Catalogue predictions").
    Mixed {
        /// Probability of a DE proposal, in [0, 1].
        de: f64,
    },
}

/// Walker `w`'s differential-evolution proposal y = x + γ·(x_a − x_b) from two distinct
/// walkers of `fixed` (at least two), in `d` dimensions ([`Moves::Mixed`]); symmetric, so
/// its log-Jacobian is 0.
fn de_proposal(w: &mut Walker, fixed: &[Walker], d: usize) -> Vec<f64> {
    let a = w.rng.random_range(0..fixed.len());
    let b = (a + w.rng.random_range(1..fixed.len())) % fixed.len();
    w.s.tried += 1;
    let gamma = if w.s.tried % 10 == 0 {
        1.0
    } else {
        let z: f64 = rand_distr::Distribution::sample(&rand_distr::StandardNormal, &mut w.rng);
        2.38 / (2.0 * d as f64).sqrt() * (1.0 + 0.1 * z)
    };
    w.s.x
        .iter()
        .zip(fixed[a].s.x.iter().zip(&fixed[b].s.x))
        .map(|(x, (p, q))| x + gamma * (p - q))
        .collect()
}

/// Walker `w`'s stretch proposal y = x_j + z·(x − x_j) towards a walker j of `fixed`, and
/// its log-Jacobian (d − 1)·ln z (Goodman & Weare; the module documentation).
fn stretch_proposal(w: &mut Walker, fixed: &[Walker], d: usize) -> (Vec<f64>, f64) {
    let j = w.rng.random_range(0..fixed.len());
    let z = stretch(w.rng.random::<f64>());
    let partner = &fixed[j].s.x;
    let y = partner
        .iter()
        .zip(&w.s.x)
        .map(|(p, x)| p + z * (x - p))
        .collect();
    (y, (d as f64 - 1.0) * z.ln())
}

/// Moves one half of the walkers (the first or the second) against the other half held
/// fixed, in parallel; `count` tallies the accepted proposals.
fn half_step(
    density: &dyn LogDensity,
    walkers: &mut [Walker],
    first_half: bool,
    count: bool,
    moves: Moves,
) {
    let k = walkers.len();
    let half = k / 2;
    let (a, b) = walkers.split_at_mut(half);
    let (moving, fixed) = if first_half { (a, &*b) } else { (b, &*a) };
    let d = density.dim();
    moving.par_iter_mut().for_each(|w| {
        let de = match moves {
            Moves::Stretch => false,
            Moves::Mixed { de } => w.rng.random::<f64>() < de,
        };
        let (y, log_jacobian) = if de && fixed.len() >= 2 {
            (de_proposal(w, fixed, d), 0.0)
        } else {
            stretch_proposal(w, fixed, d)
        };
        let u: f64 = w.rng.random();
        let lp = density.log_density(&y);
        let log_ratio = log_jacobian + lp - w.s.lp;
        if lp.is_finite() && u.ln() < log_ratio {
            w.s.x = y;
            w.s.lp = lp;
            if count {
                w.s.accepted += 1;
            }
        }
    });
}

/// Runs the ensemble from `starts` (one per walker, each where the density is positive) and
/// returns the kept chains; `progress(done, total)` is called after each step. The stretch
/// move alone ([`run_ensemble_with`] chooses the moves).
pub fn run_ensemble(
    density: &dyn LogDensity,
    starts: &[Vec<f64>],
    settings: &EnsembleSettings,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Chains, SampleError> {
    run_ensemble_with(density, starts, settings, Moves::Stretch, progress)
}

/// [`run_ensemble`] with the proposals `moves`.
pub fn run_ensemble_with(
    density: &dyn LogDensity,
    starts: &[Vec<f64>],
    settings: &EnsembleSettings,
    moves: Moves,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Chains, SampleError> {
    let whole = settings.burn_in + settings.steps;
    run_ensemble_resumable(density, starts, settings, moves, whole, None, progress)
}

/// Checks the walkers, the steps and the starts of an ensemble run.
fn check_ensemble(
    d: usize,
    starts: &[Vec<f64>],
    settings: &EnsembleSettings,
) -> Result<(), SampleError> {
    let k = settings.walkers;
    let need = 2 * (d + 1);
    if k < need || k % 2 == 1 {
        return Err(SampleError::Walkers { walkers: k, need });
    }
    if settings.steps < 4 {
        return Err(SampleError::Steps(settings.steps));
    }
    if starts.len() != k || starts.iter().any(|s| s.len() != d) {
        return Err(SampleError::Starts {
            got: starts.len(),
            want: k,
            dim_got: starts.first().map_or(0, Vec::len),
            dim: d,
        });
    }
    Ok(())
}

/// [`run_ensemble_with`] in blocks of `block` steps; with a `checkpoint`, resumed from its
/// file when there is one and written after every block (removed when the run ends). Walker
/// k's block b draws from the stream of (seed, k, b) (the determinism of `estimate::sample::chains`), so a
/// resumed run ends with the same chains as one that was not stopped, whatever the threads.
pub fn run_ensemble_resumable(
    density: &dyn LogDensity,
    starts: &[Vec<f64>],
    settings: &EnsembleSettings,
    moves: Moves,
    block: usize,
    checkpoint: Option<&Checkpoint>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Chains, SampleError> {
    let d = density.dim();
    check_ensemble(d, starts, settings)?;
    let blocks = ChainSettings {
        chains: settings.walkers,
        steps: settings.steps,
        burn_in: settings.burn_in,
        block: block.max(1),
        seed: settings.seed,
    };
    let de = match moves {
        Moves::Stretch => 0.0,
        Moves::Mixed { de } => de,
    };
    let key = Key {
        sampler: "ensemble",
        settings: blocks.clone(),
        fingerprint: fingerprint(starts.iter().flatten().chain(std::iter::once(&de))),
        dim: d,
    };
    let saved = match checkpoint {
        Some(c) => c.load(&key)?,
        None => None,
    };
    let (states, first) = match saved {
        Some(Saved {
            states,
            blocks_done,
        }) => (states, blocks_done),
        None => (ensemble_starts(density, starts)?, 0),
    };
    let mut walkers: Vec<Walker> = states
        .into_iter()
        .map(|s| Walker {
            s,
            rng: Xoshiro256PlusPlus::seed_from_u64(0),
        })
        .collect();
    let total = blocks.total();
    for b in first..blocks.blocks() {
        for (k, w) in walkers.iter_mut().enumerate() {
            w.rng = chains::stream(settings.seed, k, b + 1);
        }
        for step in b * blocks.block..((b + 1) * blocks.block).min(total) {
            let keep = step >= settings.burn_in;
            half_step(density, &mut walkers, true, keep, moves);
            half_step(density, &mut walkers, false, keep, moves);
            if keep {
                for w in &mut walkers {
                    w.s.draws.push(w.s.x.clone());
                    w.s.lps.push(w.s.lp);
                }
            }
            progress(step + 1, total);
        }
        if let Some(c) = checkpoint {
            let states: Vec<ChainState> = walkers.iter().map(|w| w.s.clone()).collect();
            c.save(&key, &states, b + 1)?;
        }
    }
    if let Some(c) = checkpoint {
        c.remove()?;
    }
    let acceptance = walkers
        .iter()
        .map(|w| w.s.accepted as f64 / settings.steps as f64)
        .collect();
    let (draws, log_density) = walkers.into_iter().map(|w| (w.s.draws, w.s.lps)).unzip();
    Ok(Chains {
        dim: d,
        draws,
        log_density,
        acceptance,
    })
}

/// The walkers at `starts`, each where the density is positive.
fn ensemble_starts(
    density: &dyn LogDensity,
    starts: &[Vec<f64>],
) -> Result<Vec<ChainState>, SampleError> {
    let lps: Vec<f64> = starts.par_iter().map(|x| density.log_density(x)).collect();
    if let Some(i) = lps.iter().position(|lp| !lp.is_finite()) {
        return Err(SampleError::BadStart(i));
    }
    Ok(starts
        .iter()
        .zip(lps)
        .map(|(x, lp)| ChainState::new(x.clone(), lp, 0.0))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A thin, tilted Gaussian in 3 dimensions.
    struct Thin;

    impl LogDensity for Thin {
        fn dim(&self) -> usize {
            3
        }
        fn log_density(&self, x: &[f64]) -> f64 {
            let u = (x[0] + x[1]) / 0.05;
            -0.5 * (u * u + x[0] * x[0] + x[2] * x[2])
        }
    }

    fn starts() -> Vec<Vec<f64>> {
        (0..8)
            .map(|k| {
                let t = k as f64 / 8.0 - 0.5;
                vec![t * 0.1, -t * 0.1 + 0.001 * t * t, 0.3 * t]
            })
            .collect()
    }

    fn settings() -> EnsembleSettings {
        EnsembleSettings {
            walkers: 8,
            steps: 400,
            burn_in: 100,
            seed: 11,
        }
    }

    #[test]
    fn an_ensemble_stopped_after_a_block_resumes_to_the_same_chains() {
        let moves = Moves::Mixed { de: 0.8 };
        let whole = run_ensemble_with(&Thin, &starts(), &settings(), moves, &|_, _| {}).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("samples.checkpoint");
        let in_blocks = |c: Option<&Checkpoint>| {
            run_ensemble_resumable(&Thin, &starts(), &settings(), moves, 120, c, &|_, _| {})
        };
        // Blocks change nothing by themselves (each starts its own streams; the whole run
        // is one block).
        let blocked = in_blocks(None).unwrap();
        assert_eq!(blocked.draws.len(), whole.draws.len());
        for k in [1, 3] {
            let halted = Checkpoint {
                path: path.clone(),
                halt_after: Some(k),
            };
            assert_eq!(in_blocks(Some(&halted)), Err(SampleError::Halted(k)));
            let resumed = rayon::ThreadPoolBuilder::new()
                .num_threads(1)
                .build()
                .unwrap()
                .install(|| in_blocks(Some(&Checkpoint::at(&path))).unwrap());
            assert_eq!(resumed, blocked, "stopped after block {k}");
            assert!(!path.exists());
        }
        // A chains run's checkpoint is not an ensemble's.
        let halted = Checkpoint {
            path: path.clone(),
            halt_after: Some(1),
        };
        let _ = in_blocks(Some(&halted));
        let other = EnsembleSettings {
            steps: 401,
            ..settings()
        };
        let e = run_ensemble_resumable(
            &Thin,
            &starts(),
            &other,
            moves,
            120,
            Some(&Checkpoint::at(&path)),
            &|_, _| {},
        )
        .unwrap_err();
        assert!(e.to_string().contains("steps 400"), "{e}");
    }
}
