//! Independent Metropolis–Hastings chains guided by the posterior's Laplace approximation
//! ([`super::laplace`]), run in blocks that can be checkpointed and resumed
//! ([`super::checkpoint`]).
//!
//! # The moves
//!
//! Each chain proposes, with probability [`INDEPENDENCE_SHARE`], an independence move: a
//! draw y from the multivariate-t proposal q = t_ν(x̂, c²Σ) ([`TProposal`]), accepted with
//! probability min(1, p(y)·q(x) / (p(x)·q(y))) (Tierney 1994, §2.3.2). Where the posterior
//! is close to its Laplace approximation these are near-independent draws. Otherwise it
//! proposes a random-walk move in the whitened coordinates, y = x + ε·L·z with z ~ N(0, I),
//! accepted with probability min(1, p(y)/p(x)): it follows a thin, curved valley that the
//! Gaussian misses, along the directions L gives. ε starts at 2.38/√d (Roberts, Gelman &
//! Gilks 1997, "Weak convergence and optimal scaling of random walk Metropolis
//! algorithms", Ann. Appl. Probab. 7(1)) and is tuned during the burn-in towards an
//! acceptance of [`RW_TARGET`] (Robbins–Monro on ln ε with gain n^−0.6, Andrieu & Thoms
//! 2008, "A tutorial on adaptive MCMC", Stat. Comput. 18, §4); it is fixed after the
//! burn-in, so the kept draws come from a time-homogeneous chain.
//!
//! Both moves leave p invariant, so their mixture does.
//!
//! # Starts
//!
//! Chain c starts from a draw of the t proposal (redrawn until p > 0, at most 100 times;
//! the mode otherwise): over-dispersed against the posterior where the Gaussian is close,
//! which split-R̂ needs to mean something (Vehtari et al. 2021).
//!
//! # Determinism
//!
//! Chain c's start draws from its own Xoshiro256++ stream, the seed's stream advanced by c
//! long jumps (2¹⁹² draws), and its block b from that stream advanced by b + 1 jumps (2¹²⁸
//! draws each): every random number of a chain comes
//! from streams fixed by (seed, chain, block), so the chains for a seed depend neither on
//! how many threads rayon runs them on nor on where a run was stopped and resumed.

use super::checkpoint::{chains_key, ChainState, Checkpoint, Saved};
use super::proposal::Proposal;
use super::settings::ChainSettings;
use super::{Chains, LogDensity, SampleError};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;

/// Probability of an independence move (else a whitened random-walk move).
pub const INDEPENDENCE_SHARE: f64 = 0.5;
/// Degrees of freedom ν of the t proposal.
pub const PROPOSAL_NU: f64 = 5.0;
/// Scale c of the t proposal on the Laplace approximation's L.
pub const PROPOSAL_SCALE: f64 = 1.3;
/// Acceptance of the random-walk moves that the burn-in tunes ε towards.
pub const RW_TARGET: f64 = 0.25;

/// The stream of block `block` of chain `chain` (see the module documentation).
pub(crate) fn stream(seed: u64, chain: usize, block: usize) -> Xoshiro256PlusPlus {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    for _ in 0..chain {
        rng.long_jump();
    }
    for _ in 0..block {
        rng.jump();
    }
    rng
}

/// Chain `c`'s start: a draw of `q` where p > 0 (module documentation).
fn start<P: Proposal>(density: &dyn LogDensity, q: &P, seed: u64, c: usize) -> ChainState {
    // A stream of its own: block 0's stream, which the start's draws precede.
    let mut rng = stream(seed, c, 0);
    let first = (0..100)
        .map(|_| q.draw_with(&mut rng))
        .map(|x| {
            let lp = density.log_density(&x);
            (x, lp)
        })
        .find(|(_, lp)| lp.is_finite());
    let (x, lp) = first.unwrap_or_else(|| {
        let m = q.walk().mode.clone();
        let lp = density.log_density(&m);
        (m, lp)
    });
    ChainState::new(x, lp, (2.38 / (q.dim() as f64).sqrt()).ln())
}

/// Robbins–Monro update of ln ε after the `n`-th tuned proposal (gain n^−0.6) towards the
/// acceptance `target`.
fn tune(log_eps: &mut f64, n: u64, accepted: bool, target: f64) {
    let gain = (n as f64).powf(-0.6);
    *log_eps += gain * (f64::from(u8::from(accepted)) - target);
}

/// One step of chain `s` at step `t` (burn-in while t < `burn_in`).
fn step<P: Proposal>(
    density: &dyn LogDensity,
    q: &P,
    s: &mut ChainState,
    rng: &mut Xoshiro256PlusPlus,
    t: usize,
    burn_in: usize,
) {
    let independent = rng.random::<f64>() < INDEPENDENCE_SHARE;
    let (y, log_q_ratio) = if independent {
        let y = q.draw_with(rng);
        let r = q.log_q(&s.x) - q.log_q(&y);
        (y, r)
    } else {
        let z = DVector::from_fn(s.x.len(), |_, _| StandardNormal.sample(rng));
        let dx = &q.walk().chol * z * s.log_eps.exp();
        (s.x.iter().zip(dx.iter()).map(|(a, b)| a + b).collect(), 0.0)
    };
    let u: f64 = rng.random();
    let lp = density.log_density(&y);
    let accept = lp.is_finite() && u.ln() < lp - s.lp + log_q_ratio;
    if accept {
        s.x = y;
        s.lp = lp;
    }
    if t < burn_in {
        if !independent {
            s.tried += 1;
            tune(&mut s.log_eps, s.tried, accept, RW_TARGET);
        }
    } else {
        s.accepted += u64::from(accept);
        s.draws.push(s.x.clone());
        s.lps.push(s.lp);
    }
}

/// Runs chain `s` through block `b` of `settings`.
fn run_block<P: Proposal>(
    density: &dyn LogDensity,
    q: &P,
    s: &mut ChainState,
    settings: &ChainSettings,
    c: usize,
    b: usize,
) {
    let mut rng = stream(settings.seed, c, b + 1);
    let from = b * settings.block;
    let to = ((b + 1) * settings.block).min(settings.total());
    for t in from..to {
        step(density, q, s, &mut rng, t, settings.burn_in);
    }
}

/// Runs the chains from draws of `q` (see the module documentation) and returns the kept
/// draws; with a `checkpoint`, resumes from its file when there is one and writes it after
/// every block (removed when the run ends). `progress(done, total)` after every block, in
/// steps per chain.
pub fn run_chains<P: Proposal>(
    density: &dyn LogDensity,
    q: &P,
    settings: &ChainSettings,
    checkpoint: Option<&Checkpoint>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Chains, SampleError> {
    if settings.chains < 2 {
        return Err(SampleError::Chains(settings.chains));
    }
    if settings.steps < 4 {
        return Err(SampleError::Steps(settings.steps));
    }
    if settings.block == 0 {
        return Err(SampleError::Block);
    }
    let d = density.dim();
    if q.dim() != d {
        return Err(SampleError::Starts {
            got: 1,
            want: 1,
            dim_got: q.dim(),
            dim: d,
        });
    }
    let key = chains_key(settings, q);
    let saved = match checkpoint {
        Some(c) => c.load(&key)?,
        None => None,
    };
    let (mut states, first_block) = match saved {
        Some(Saved {
            states,
            blocks_done,
        }) => (states, blocks_done),
        None => {
            let states = (0..settings.chains)
                .into_par_iter()
                .map(|c| start(density, q, settings.seed, c))
                .collect();
            (states, 0)
        }
    };
    for b in first_block..settings.blocks() {
        states
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, s)| run_block(density, q, s, settings, c, b));
        if let Some(c) = checkpoint {
            c.save(&key, &states, b + 1)?;
        }
        progress(
            ((b + 1) * settings.block).min(settings.total()),
            settings.total(),
        );
    }
    if let Some(c) = checkpoint {
        c.remove()?;
    }
    let acceptance = states
        .iter()
        .map(|s| s.accepted as f64 / settings.steps as f64)
        .collect();
    let (draws, log_density) = states.into_iter().map(|s| (s.draws, s.lps)).unzip();
    Ok(Chains {
        dim: d,
        draws,
        log_density,
        acceptance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::sample::checkpoint::CheckpointError;
    use crate::estimate::sample::laplace::{Laplace, TProposal};
    use nalgebra::DMatrix;

    /// A correlated Gaussian N(μ, A⁻¹) in 3 dimensions.
    struct Gauss {
        mu: [f64; 3],
        a: DMatrix<f64>,
    }

    impl LogDensity for Gauss {
        fn dim(&self) -> usize {
            3
        }
        fn log_density(&self, x: &[f64]) -> f64 {
            let d = DVector::from_iterator(3, x.iter().zip(&self.mu).map(|(a, b)| a - b));
            -0.5 * (d.transpose() * &self.a * d)[(0, 0)]
        }
    }

    fn target() -> Gauss {
        Gauss {
            mu: [1.0, -2.0, 0.5],
            a: DMatrix::from_row_slice(3, 3, &[4.0, 1.5, 0.0, 1.5, 2.0, 0.3, 0.0, 0.3, 1.0]),
        }
    }

    /// A proposal off the target on purpose: mode shifted, precision halved in one
    /// direction, as a Laplace approximation of a curved posterior would be.
    fn proposal(g: &Gauss) -> TProposal {
        let mut p = g.a.clone();
        p[(0, 0)] *= 0.5;
        let mode = vec![g.mu[0] + 0.2, g.mu[1], g.mu[2] - 0.1];
        TProposal {
            laplace: Laplace::from_precision(mode, &p, &[f64::INFINITY; 3]).unwrap(),
            nu: PROPOSAL_NU,
            scale: PROPOSAL_SCALE,
        }
    }

    fn settings(seed: u64) -> ChainSettings {
        ChainSettings {
            chains: 4,
            steps: 3000,
            burn_in: 500,
            block: 700,
            seed,
        }
    }

    #[test]
    fn the_chains_draw_the_target_s_mean_and_covariance() {
        let g = target();
        let c = run_chains(&g, &proposal(&g), &settings(3), None, &|_, _| {}).unwrap();
        let cov = g.a.clone().try_inverse().unwrap();
        let flat = c.flat();
        let n = flat.len() as f64;
        let diag = crate::estimate::sample::summarise(&c.draws);
        for i in 0..3 {
            let m = flat.iter().map(|x| x[i]).sum::<f64>() / n;
            let v = flat.iter().map(|x| (x[i] - m).powi(2)).sum::<f64>() / n;
            let mcse = (cov[(i, i)] / diag[i].ess_bulk).sqrt();
            assert!((m - g.mu[i]).abs() < 4.0 * mcse, "mean {i}: {m} ± {mcse}");
            assert!(
                (v / cov[(i, i)] - 1.0).abs() < 0.1,
                "variance {i}: {v} vs {}",
                cov[(i, i)]
            );
            assert!(
                diag[i].rhat < 1.01 && diag[i].ess_bulk > 1000.0,
                "{:?}",
                diag[i]
            );
        }
    }

    #[test]
    fn the_chains_for_a_seed_do_not_depend_on_the_thread_count() {
        let g = target();
        let q = proposal(&g);
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| run_chains(&g, &q, &settings(5), None, &|_, _| {}).unwrap())
        };
        let one = run(1);
        assert_eq!(one, run(2));
        let other = run_chains(&g, &q, &settings(6), None, &|_, _| {}).unwrap();
        assert_ne!(one.draws, other.draws);
    }

    #[test]
    fn a_run_stopped_after_a_block_resumes_to_the_same_chains() {
        let g = target();
        let q = proposal(&g);
        let whole = run_chains(&g, &q, &settings(7), None, &|_, _| {}).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("samples.checkpoint");
        // Stopped after the first block (burn-in only) and after a block with kept draws.
        for k in [1, 3] {
            let halted = Checkpoint {
                path: path.clone(),
                halt_after: Some(k),
            };
            let stopped = run_chains(&g, &q, &settings(7), Some(&halted), &|_, _| {});
            assert_eq!(stopped, Err(SampleError::Halted(k)));
            assert!(path.exists());
            let resumed = run_chains(
                &g,
                &q,
                &settings(7),
                Some(&Checkpoint::at(&path)),
                &|_, _| {},
            )
            .unwrap();
            assert_eq!(resumed, whole, "stopped after block {k}");
            assert!(
                !path.exists(),
                "the checkpoint is removed when the run ends"
            );
        }
    }

    #[test]
    fn a_checkpoint_of_other_settings_is_an_error_naming_the_file() {
        let g = target();
        let q = proposal(&g);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("samples.checkpoint");
        let halted = Checkpoint {
            path: path.clone(),
            halt_after: Some(1),
        };
        let _ = run_chains(&g, &q, &settings(7), Some(&halted), &|_, _| {});
        let at = Checkpoint::at(&path);
        let e = run_chains(&g, &q, &settings(8), Some(&at), &|_, _| {}).unwrap_err();
        let SampleError::Checkpoint(CheckpointError::Settings {
            what, saved, now, ..
        }) = &e
        else {
            panic!("{e:?}")
        };
        assert_eq!((*what, saved.as_str(), now.as_str()), ("seed", "7", "8"));
        assert!(e.to_string().contains(&path.display().to_string()), "{e}");
        // Another posterior (the proposal of another fit).
        let mut other = q.clone();
        other.laplace.mode[0] += 1e-9;
        let e = run_chains(&g, &other, &settings(7), Some(&at), &|_, _| {}).unwrap_err();
        assert!(e.to_string().contains("the posterior"), "{e}");
        // Not a checkpoint at all, or one cut short.
        let bytes = std::fs::read(&path).unwrap();
        std::fs::write(&path, &bytes[..bytes.len() - 3]).unwrap();
        let e = run_chains(&g, &q, &settings(7), Some(&at), &|_, _| {}).unwrap_err();
        assert!(
            matches!(e, SampleError::Checkpoint(CheckpointError::Format { .. })),
            "{e}"
        );
        std::fs::write(&path, "a,b\n1,2\n").unwrap();
        let e = run_chains(&g, &q, &settings(7), Some(&at), &|_, _| {}).unwrap_err();
        assert!(e.to_string().contains(&path.display().to_string()), "{e}");
        assert!(
            path.exists(),
            "a checkpoint that does not fit is never overwritten"
        );
    }
}
