//! How far a posterior is from a proposal q ([`ImportanceCheck`]): importance sampling from
//! q with Pareto-smoothed diagnostics, which decides whether proposal-guided chains can be
//! trusted on a posterior.

use super::proposal::Proposal;
use super::LogDensity;

/// How close a posterior is to a proposal q: importance sampling from q.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImportanceCheck {
    /// Draws of q.
    pub draws: usize,
    /// Of those, where the posterior is positive.
    pub inside: usize,
    /// Effective sample size of the weights p/q, (Σw)²/Σw².
    pub ess: f64,
    /// Hill's estimate of the weights' Pareto tail index k̂ over the largest 20 % (∞ when a
    /// draw fell where p = 0).
    pub k_hat: f64,
}

/// Largest k̂ at which importance weights are usable (Vehtari, Simpson, Gelman, Yao & Gabry
/// 2024, "Pareto smoothed importance sampling", JMLR 25, §3.2: above 0.7 the estimate's error
/// falls too slowly with the draws to be of use).
pub const K_HAT_LIMIT: f64 = 0.7;

impl ImportanceCheck {
    /// `n` draws of `q` from the stream of `seed`, weighed by the density; the draws are made
    /// in one stream and evaluated in parallel, so the result does not depend on the threads.
    pub fn of(density: &dyn LogDensity, q: &dyn Proposal, n: usize, seed: u64) -> Self {
        let (_, log_w) = Self::weighed(density, q, n, seed);
        Self::of_log_weights(log_w)
    }

    /// `n` draws of `q` from the stream of `seed` and their log-weights ln p − ln q (−∞
    /// where p = 0), evaluated in parallel.
    pub fn weighed(
        density: &dyn LogDensity,
        q: &dyn Proposal,
        n: usize,
        seed: u64,
    ) -> (Vec<Vec<f64>>, Vec<f64>) {
        use rand::SeedableRng;
        use rayon::prelude::*;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let xs: Vec<Vec<f64>> = (0..n).map(|_| q.draw_with(&mut rng)).collect();
        let log_w: Vec<f64> = xs
            .par_iter()
            .map(|x| density.log_density(x) - q.log_q(x))
            .collect();
        (xs, log_w)
    }

    /// The check of log-weights `log_w` (−∞ where p = 0).
    pub fn of_log_weights(mut log_w: Vec<f64>) -> Self {
        let draws = log_w.len();
        log_w.retain(|v| v.is_finite());
        let inside = log_w.len();
        log_w.sort_by(|a, b| b.total_cmp(a));
        let top = log_w.first().copied().unwrap_or(0.0);
        let w: Vec<f64> = log_w.iter().map(|v| (v - top).exp()).collect();
        let ess = w.iter().sum::<f64>().powi(2)
            / w.iter().map(|v| v * v).sum::<f64>().max(f64::MIN_POSITIVE);
        let m = inside / 5;
        let k_hat = if inside < draws || m < 2 {
            f64::INFINITY
        } else {
            log_w[..m].iter().map(|v| v - log_w[m]).sum::<f64>() / m as f64
        };
        Self {
            draws,
            inside,
            ess,
            k_hat,
        }
    }

    /// The check of log-weights `log_w` with k̂ over the draws inside the support only: a
    /// draw where p = 0 has weight 0, it costs an evaluation and biases nothing.
    pub fn of_inside(log_w: Vec<f64>) -> Self {
        let draws = log_w.len();
        let inside: Vec<f64> = log_w.into_iter().filter(|v| v.is_finite()).collect();
        Self {
            draws,
            ..Self::of_log_weights(inside)
        }
    }

    /// Whether q is close enough to the posterior for the Laplace-guided chains: every draw
    /// inside and k̂ below [`K_HAT_LIMIT`].
    pub fn close(&self) -> bool {
        self.inside == self.draws && self.k_hat < K_HAT_LIMIT
    }
}

#[cfg(test)]
mod tests {
    use super::ImportanceCheck;

    #[test]
    fn hill_s_k_hat_finds_the_tail_index_of_pareto_weights() {
        // Weights w = u^(−k) with u uniform are Pareto with tail index k; with w ≡ 1 k̂ = 0.
        let n = 20_000;
        for k in [0.3, 1.0] {
            let log_w = (0..n)
                .map(|i| -k * ((i as f64 + 0.5) / n as f64).ln())
                .collect();
            let c = ImportanceCheck::of_log_weights(log_w);
            assert!((c.k_hat - k).abs() < 0.02 * k.max(1.0), "{k}: {c:?}");
        }
        let flat = ImportanceCheck::of_log_weights(vec![0.0; 100]);
        assert_eq!((flat.k_hat, flat.ess), (0.0, 100.0));
        assert!(flat.close());
        let outside = ImportanceCheck::of_log_weights(vec![0.0, f64::NEG_INFINITY, 0.0]);
        assert!(!outside.close());
    }
}
