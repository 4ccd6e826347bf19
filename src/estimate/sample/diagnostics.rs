//! Convergence diagnostics of a set of chains, as Vehtari, Gelman, Simpson, Carpenter &
//! Bürkner (2021, "Rank-normalization, folding, and localization: an improved R̂ for
//! assessing convergence of MCMC", Bayesian Analysis 16(2)) define them and arviz computes
//! them:
//!
//! * split chains: each chain's first and last ⌊n/2⌋ draws as two chains;
//! * rank normalisation: z = Φ⁻¹((r − 3/8)/(S + 1/4)), r the draw's average rank among all
//!   S draws;
//! * R̂ = √((B/W + n − 1)/n) on the split chains (B = n·var of the chain means, W = mean
//!   within-chain variance); the rank R̂ is the larger of the bulk R̂ (rank-normalised draws)
//!   and the tail R̂ (rank-normalised |x − median|). Below 1.01 is converged (their advice);
//! * ESS = M·n/τ, τ = −1 + 2·Σ ρ̂_t summed by Geyer's initial monotone sequence over the
//!   split chains (ρ̂_t = 1 − (W − mean autocovariance at lag t)/var⁺); bulk ESS on the
//!   rank-normalised draws, tail ESS the smaller of those of the indicators x ≤ q₀.₀₅ and
//!   x ≤ q₀.₉₅. At least 100 per parameter (400 over all chains) is their advice for
//!   reliable 95 % intervals.
//!
//! For an ensemble sampler each walker is one chain (as arviz reads emcee's chains); the
//! walkers are not independent, so the ESS is a guide, not exact.

/// The diagnostics of one parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamDiagnostics {
    /// Rank-normalised split-R̂ (larger of bulk and tail).
    pub rhat: f64,
    /// Bulk effective sample size.
    pub ess_bulk: f64,
    /// Tail effective sample size (5 % and 95 % quantiles).
    pub ess_tail: f64,
}

/// R̂ below which chains count as converged (Vehtari et al. 2021).
pub const RHAT_LIMIT: f64 = 1.01;
/// Effective sample size per 95 % band end above which the band counts as reliable
/// (Vehtari et al. 2021: 100 per chain for 4 chains).
pub const ESS_LIMIT: f64 = 400.0;

/// The diagnostics of every parameter of `chains[walker][step][param]`.
pub fn summarise(chains: &[Vec<Vec<f64>>]) -> Vec<ParamDiagnostics> {
    let d = chains.first().and_then(|c| c.first()).map_or(0, Vec::len);
    (0..d)
        .map(|i| {
            let x: Vec<Vec<f64>> = chains
                .iter()
                .map(|c| c.iter().map(|v| v[i]).collect())
                .collect();
            ParamDiagnostics {
                rhat: rhat_rank(&x),
                ess_bulk: ess_bulk(&x),
                ess_tail: ess_tail(&x),
            }
        })
        .collect()
}

/// Each chain's first and last ⌊n/2⌋ draws as two chains (the middle draw of an odd n is
/// left out).
pub fn split_chains(x: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let mut out = Vec::with_capacity(2 * x.len());
    for c in x {
        let half = c.len() / 2;
        out.push(c[..half].to_vec());
    }
    for c in x {
        let half = c.len() / 2;
        out.push(c[c.len() - half..].to_vec());
    }
    out
}

/// Rank-normalised draws: Φ⁻¹((r − 3/8)/(S + 1/4)), r the average rank over all chains.
pub fn z_scale(x: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let flat: Vec<f64> = x.iter().flatten().copied().collect();
    let s = flat.len();
    let mut order: Vec<usize> = (0..s).collect();
    order.sort_by(|a, b| flat[*a].total_cmp(&flat[*b]));
    let mut rank = vec![0.0; s];
    let mut i = 0;
    while i < s {
        let mut j = i;
        while j + 1 < s && flat[order[j + 1]] == flat[order[i]] {
            j += 1;
        }
        let average = (i + j) as f64 / 2.0 + 1.0;
        for o in &order[i..=j] {
            rank[*o] = average;
        }
        i = j + 1;
    }
    let mut k = 0;
    x.iter()
        .map(|c| {
            c.iter()
                .map(|_| {
                    let r = rank[k];
                    k += 1;
                    normal_quantile((r - 0.375) / (s as f64 + 0.25))
                })
                .collect()
        })
        .collect()
}

/// Mean and unbiased variance (ddof 1).
fn mean_var(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, var)
}

/// Plain R̂ of equal-length chains, √((B/W + n − 1)/n).
pub fn rhat(x: &[Vec<f64>]) -> f64 {
    let n = x.first().map_or(0, Vec::len) as f64;
    let (means, vars): (Vec<f64>, Vec<f64>) = x.iter().map(|c| mean_var(c)).unzip();
    let b = n * mean_var(&means).1;
    let w = vars.iter().sum::<f64>() / vars.len() as f64;
    ((b / w + n - 1.0) / n).sqrt()
}

/// The rank-normalised split-R̂: the larger of the bulk and the tail (folded) R̂.
pub fn rhat_rank(x: &[Vec<f64>]) -> f64 {
    let split = split_chains(x);
    let bulk = rhat(&z_scale(&split));
    let mut all: Vec<f64> = split.iter().flatten().copied().collect();
    let med = quantile(&mut all, 0.5);
    let folded: Vec<Vec<f64>> = split
        .iter()
        .map(|c| c.iter().map(|v| (v - med).abs()).collect())
        .collect();
    let tail = rhat(&z_scale(&folded));
    bulk.max(tail)
}

/// Bulk effective sample size: ESS of the rank-normalised split chains.
pub fn ess_bulk(x: &[Vec<f64>]) -> f64 {
    ess(&z_scale(&split_chains(x)))
}

/// Tail effective sample size: the smaller ESS of the indicators x ≤ q₀.₀₅, x ≤ q₀.₉₅ on the
/// split chains.
pub fn ess_tail(x: &[Vec<f64>]) -> f64 {
    let mut all: Vec<f64> = x.iter().flatten().copied().collect();
    let q05 = quantile(&mut all, 0.05);
    let q95 = quantile(&mut all, 0.95);
    let indicator = |q: f64| -> Vec<Vec<f64>> {
        x.iter()
            .map(|c| c.iter().map(|v| f64::from(u8::from(*v <= q))).collect())
            .collect()
    };
    ess(&split_chains(&indicator(q05))).min(ess(&split_chains(&indicator(q95))))
}

/// The q-quantile with linear interpolation between order statistics (numpy's default).
pub fn quantile(values: &mut [f64], q: f64) -> f64 {
    values.sort_by(f64::total_cmp);
    let x = q * (values.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x - x.floor());
    let next = values[(i + 1).min(values.len() - 1)];
    values[i] + f * (next - values[i])
}

/// Lags whose autocovariances [`autocovs`] forms in one pass over a chain.
const LAGS: usize = 8;

/// Biased autocovariances of a chain at lags t, t + 1, …, t + [`LAGS`] − 1,
/// (1/n)·Σ_i d_i·d_{i+s} for each lag s (0 where s ≥ n), from the chain's deviations
/// d_i = x_i − x̄.
///
/// One pass over the chain for the [`LAGS`] lags: each lag's sum runs over i in ascending
/// order in an accumulator of its own, so every value is the one a separate sum per lag
/// gives, bit for bit, while the [`LAGS`] independent additions overlap (a single sum is
/// bound by the latency of one floating-point addition per term; Geyer's sequence needs
/// hundreds of lags on slowly mixing chains, where this sum was three quarters of the
/// sampler tests' time).
fn autocovs(d: &[f64], t: usize) -> [f64; LAGS] {
    let n = d.len();
    let mut sums = [-0.0; LAGS];
    // i < n − t − (LAGS − 1): every lag's partner d_{i+s} exists.
    let common = n.saturating_sub(t + LAGS - 1);
    for i in 0..common {
        let a = d[i];
        let ahead = &d[i + t..i + t + LAGS];
        for (s, b) in sums.iter_mut().zip(ahead) {
            *s += a * b;
        }
    }
    for (k, s) in sums.iter_mut().enumerate() {
        for i in common..n.saturating_sub(t + k) {
            *s += d[i] * d[i + t + k];
        }
    }
    sums.map(|s| s / n as f64)
}

/// The mean over the chains of [`autocovs`] at lags t, …, t + [`LAGS`] − 1, from each
/// chain's deviations from its mean: (1/m)·Σ_chains, the chains added in order.
fn mean_autocovs(deviations: &[Vec<f64>], t: usize) -> [f64; LAGS] {
    let mut block = [-0.0; LAGS];
    for d in deviations {
        for (b, a) in block.iter_mut().zip(autocovs(d, t)) {
            *b += a;
        }
    }
    block.map(|b| b / deviations.len() as f64)
}

/// Effective sample size of equal-length chains by Geyer's initial monotone sequence.
pub fn ess(x: &[Vec<f64>]) -> f64 {
    let m = x.len();
    let n = x.first().map_or(0, Vec::len);
    let flat = x.iter().flatten();
    let (lo, hi) = flat.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(*v), b.max(*v))
    });
    if n < 4 || !(lo.is_finite() && hi.is_finite()) {
        return f64::NAN;
    }
    if hi - lo < 1e-15 {
        return (m * n) as f64;
    }
    let nf = n as f64;
    let means: Vec<f64> = x.iter().map(|c| c.iter().sum::<f64>() / nf).collect();
    // The mean autocovariance over the chains at each lag, formed [`LAGS`] lags at a time
    // as Geyer's sequence asks for them (it stops at the first pair whose sum is negative).
    let deviations: Vec<Vec<f64>> = x
        .iter()
        .zip(&means)
        .map(|(c, mu)| c.iter().map(|v| v - mu).collect())
        .collect();
    let mut acov: Vec<f64> = Vec::new();
    let mut mean_acov = |t: usize| -> f64 {
        while acov.len() <= t {
            acov.extend(mean_autocovs(&deviations, acov.len()));
        }
        acov[t]
    };
    let mean_var = mean_acov(0) * nf / (nf - 1.0);
    let mut var_plus = mean_var * (nf - 1.0) / nf;
    if m > 1 {
        var_plus += mean_var_of(&means);
    }
    let mut rho = |t: usize| 1.0 - (mean_var - mean_acov(t)) / var_plus;
    let mut rho_hat = vec![0.0; n];
    rho_hat[0] = 1.0;
    let mut even = 1.0;
    let mut odd = rho(1);
    rho_hat[1] = odd;
    let mut t = 1;
    while t < n - 3 && even + odd > 0.0 {
        even = rho(t + 1);
        odd = rho(t + 2);
        if even + odd >= 0.0 {
            rho_hat[t + 1] = even;
            rho_hat[t + 2] = odd;
        }
        t += 2;
    }
    let max_t = t.saturating_sub(2);
    if even > 0.0 {
        rho_hat[max_t + 1] = even;
    }
    let mut t = 1;
    while t + 2 <= max_t {
        if rho_hat[t + 1] + rho_hat[t + 2] > rho_hat[t - 1] + rho_hat[t] {
            rho_hat[t + 1] = (rho_hat[t - 1] + rho_hat[t]) / 2.0;
            rho_hat[t + 2] = rho_hat[t + 1];
        }
        t += 2;
    }
    let total = (m * n) as f64;
    let tau = -1.0 + 2.0 * rho_hat[..=max_t].iter().sum::<f64>() + rho_hat[max_t + 1];
    total / tau.max(1.0 / total.log10())
}

/// Unbiased variance of values (ddof 1).
fn mean_var_of(v: &[f64]) -> f64 {
    mean_var(v).1
}

pub use crate::numerics::normal::normal_quantile;

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean autocovariance at lag t as it was formed before several lags shared a
    /// pass: one sum per lag and chain over i in ascending order, (1/n)·Σ (x_i − x̄)(x_{i+t}
    /// − x̄), then the chains' mean.
    fn one_lag_at_a_time(x: &[Vec<f64>], t: usize) -> f64 {
        let n = x[0].len();
        let acov = |c: &[f64]| {
            let mu = c.iter().sum::<f64>() / n as f64;
            (0..n.saturating_sub(t))
                .map(|i| (c[i] - mu) * (c[i + t] - mu))
                .sum::<f64>()
                / n as f64
        };
        x.iter().map(|c| acov(c)).sum::<f64>() / x.len() as f64
    }

    /// m chains of n draws of an AR(1) process with coefficient rho (a fixed linear
    /// congruential sequence as its innovations), shifted by `shift`.
    fn ar1(m: usize, n: usize, rho: f64, shift: f64, seed: u64) -> Vec<Vec<f64>> {
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
        let mut uniform = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        (0..m)
            .map(|_| {
                let mut v = 0.0;
                (0..n)
                    .map(|_| {
                        v = rho * v + uniform();
                        v + shift
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn several_lags_per_pass_equal_the_one_lag_sums_bit_for_bit() {
        // Lengths around the multiples of the lags formed together, one chain and several,
        // chains that mix fast and slowly, and a rare indicator (long runs of zeros, as the
        // banana's tail probability has); every lag up to the chain's length and past it.
        let mut cases = Vec::new();
        for (i, n) in [4, 5, 7, 8, 9, 11, 16, 17, 33, 1000, 1003]
            .into_iter()
            .enumerate()
        {
            for (m, rho) in [(1, 0.0), (3, 0.5), (4, 0.99)] {
                cases.push(ar1(m, n, rho, 0.1, 300 + i as u64));
            }
        }
        let rare = ar1(8, 2000, 0.995, 0.0, 7)
            .into_iter()
            .map(|c| c.iter().map(|v| f64::from(u8::from(*v > 2.0))).collect())
            .collect();
        cases.push(rare);
        for x in &cases {
            let n = x[0].len();
            let deviations: Vec<Vec<f64>> = x
                .iter()
                .map(|c| {
                    let mu = c.iter().sum::<f64>() / n as f64;
                    c.iter().map(|v| v - mu).collect()
                })
                .collect();
            for t0 in (0..n + LAGS).step_by(LAGS) {
                for (k, got) in mean_autocovs(&deviations, t0).into_iter().enumerate() {
                    let want = one_lag_at_a_time(x, t0 + k);
                    assert_eq!(
                        got.to_bits(),
                        want.to_bits(),
                        "{} chains of {n}, lag {}: {got} against {want}",
                        x.len(),
                        t0 + k
                    );
                }
            }
        }
    }
}
