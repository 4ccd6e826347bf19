//! The ensemble sampler and its diagnostics against posteriors whose answer is known in
//! closed form: a correlated Gaussian (mean and covariance), a banana (a curved valley: the
//! marginal moments of x₂ = b·x₁² + noise), a two-mode mixture (both modes' weights),
//! determinism across thread counts, and the diagnostics on chains of known autocorrelation.

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use vanefit::estimate::{ess_bulk, ess_tail, rhat_rank};
use vanefit::estimate::{run_ensemble, summarise, Chains, EnsembleSettings, LogDensity};

/// A density from a closure.
struct Density<F: Fn(&[f64]) -> f64 + Sync>(usize, F);

impl<F: Fn(&[f64]) -> f64 + Sync> LogDensity for Density<F> {
    fn dim(&self) -> usize {
        self.0
    }
    fn log_density(&self, x: &[f64]) -> f64 {
        (self.1)(x)
    }
}

/// Starts in a small ball around `centre`.
fn ball(centre: &[f64], walkers: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..walkers)
        .map(|_| {
            centre
                .iter()
                .map(|c| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    c + 0.1 * z
                })
                .collect()
        })
        .collect()
}

fn run(d: &dyn LogDensity, centre: &[f64], walkers: usize, steps: usize, seed: u64) -> Chains {
    let settings = EnsembleSettings {
        walkers,
        steps,
        burn_in: steps / 2,
        seed,
    };
    run_ensemble(d, &ball(centre, walkers, seed + 1), &settings, &|_, _| {}).unwrap()
}

fn mean_of(chains: &Chains, f: &dyn Fn(&[f64]) -> f64) -> f64 {
    let all = chains.flat();
    all.iter().map(|x| f(x)).sum::<f64>() / all.len() as f64
}

/// Mean, covariance and log-density of a test Gaussian.
type Gaussian<F> = (Vec<f64>, [[f64; 2]; 2], F);

/// A correlated Gaussian: N(μ, Σ) with correlation 0.9 and unequal scales.
fn gaussian() -> Gaussian<impl Fn(&[f64]) -> f64 + Sync> {
    let mu = vec![1.0, -2.0];
    let (s1, s2, rho) = (1.0, 0.1, 0.9);
    let cov = [[s1 * s1, rho * s1 * s2], [rho * s1 * s2, s2 * s2]];
    let det = cov[0][0] * cov[1][1] - cov[0][1] * cov[1][0];
    let inv = [
        [cov[1][1] / det, -cov[0][1] / det],
        [-cov[1][0] / det, cov[0][0] / det],
    ];
    let m = mu.clone();
    let f = move |x: &[f64]| {
        let d = [x[0] - m[0], x[1] - m[1]];
        -0.5 * (d[0] * (inv[0][0] * d[0] + inv[0][1] * d[1])
            + d[1] * (inv[1][0] * d[0] + inv[1][1] * d[1]))
    };
    (mu, cov, f)
}

#[test]
fn a_correlated_gaussian_s_mean_and_covariance_are_recovered_over_seeds() {
    let (mu, cov, f) = gaussian();
    let d = Density(2, f);
    for seed in [1, 2, 3] {
        let c = run(&d, &[0.0, 0.0], 32, 8000, seed);
        let diag = summarise(&c.draws);
        for (i, g) in diag.iter().enumerate() {
            assert!(g.rhat < 1.02, "seed {seed} param {i}: R-hat {}", g.rhat);
            let sd = cov[i][i].sqrt();
            let m = mean_of(&c, &|x| x[i]);
            let tol = 4.0 * sd / g.ess_bulk.sqrt();
            assert!(
                (m - mu[i]).abs() < tol,
                "seed {seed} mean {i}: {m} vs {}",
                mu[i]
            );
        }
        let m0 = mean_of(&c, &|x| x[0]);
        let m1 = mean_of(&c, &|x| x[1]);
        let v0 = mean_of(&c, &|x| (x[0] - m0).powi(2));
        let v1 = mean_of(&c, &|x| (x[1] - m1).powi(2));
        let c01 = mean_of(&c, &|x| (x[0] - m0) * (x[1] - m1));
        assert!(
            (v0 / cov[0][0] - 1.0).abs() < 0.15,
            "seed {seed}: var0 {v0}"
        );
        assert!(
            (v1 / cov[1][1] - 1.0).abs() < 0.15,
            "seed {seed}: var1 {v1}"
        );
        let r = c01 / (v0 * v1).sqrt();
        assert!((r - 0.9).abs() < 0.03, "seed {seed}: correlation {r}");
        let acc = c.mean_acceptance();
        assert!((0.2..0.9).contains(&acc), "seed {seed}: acceptance {acc}");
    }
}

#[test]
fn a_banana_s_curved_valley_is_followed() {
    // x1 ~ N(0, 1), x2 | x1 ~ N(b·x1², 0.2²): E x2 = b, Var x2 = 2b² + 0.04, and the
    // 97.5 % quantile of x2 lies far from the Gaussian one.
    let b = 1.0;
    let d = Density(2, move |x: &[f64]| {
        -0.5 * x[0] * x[0] - 0.5 * ((x[1] - b * x[0] * x[0]) / 0.2).powi(2)
    });
    let mut errors = Vec::new();
    for seed in [11, 12, 13] {
        let c = run(&d, &[0.0, 0.0], 40, 20000, seed);
        let diag = summarise(&c.draws);
        assert!(diag.iter().all(|g| g.rhat < 1.03), "seed {seed}: {diag:?}");
        let m2 = mean_of(&c, &|x| x[1]);
        let v2 = mean_of(&c, &|x| (x[1] - m2).powi(2));
        let tol = 4.0 * (2.0_f64 * b * b).sqrt() / diag[1].ess_bulk.sqrt();
        assert!((m2 - b).abs() < tol, "seed {seed}: E x2 {m2} ± {tol}");
        errors.push(v2 / (2.0 * b * b + 0.04) - 1.0);
        // x1² ~ χ²₁: P(x2 > 5.024·b) ≈ 0.025 (the noise moves it little), far in the tail
        // of the valley's curved arm.
        let tail: Vec<Vec<f64>> = c
            .draws
            .iter()
            .map(|w| {
                w.iter()
                    .map(|x| f64::from(u8::from(x[1] > 5.024 * b)))
                    .collect()
            })
            .collect();
        let p = mean_of(&c, &|x| f64::from(u8::from(x[1] > 5.024 * b)));
        let ess = vanefit::estimate::ess(&tail);
        let tol = 4.0 * (0.025 * 0.975 / ess).sqrt();
        assert!(
            (p - 0.025).abs() < tol,
            "seed {seed}: P(x2 > 5.02) {p} ± {tol}"
        );
    }
    let mean_err = errors.iter().sum::<f64>() / errors.len() as f64;
    assert!(mean_err.abs() < 0.15, "variance of x2 off by {errors:?}");
}

#[test]
fn both_modes_of_a_mixture_get_their_weights() {
    // 0.3·N((−2, 0), I) + 0.7·N((2, 0), I): P(x1 > 0) = 0.3·Φ(−2) + 0.7·Φ(2).
    let d = Density(2, |x: &[f64]| {
        let a = -0.5 * ((x[0] + 2.0).powi(2) + x[1] * x[1]);
        let b = -0.5 * ((x[0] - 2.0).powi(2) + x[1] * x[1]);
        let m = a.max(b);
        m + (0.3 * (a - m).exp() + 0.7 * (b - m).exp()).ln()
    });
    let phi2 = 0.977_249_868_051_820_8;
    let want = 0.3 * (1.0 - phi2) + 0.7 * phi2;
    for seed in [21, 22, 23] {
        let c = run(&d, &[0.0, 0.0], 40, 8000, seed);
        let right: Vec<Vec<f64>> = c
            .draws
            .iter()
            .map(|w| w.iter().map(|x| f64::from(u8::from(x[0] > 0.0))).collect())
            .collect();
        let p = mean_of(&c, &|x| f64::from(u8::from(x[0] > 0.0)));
        let ess = vanefit::estimate::ess(&right);
        let tol = 4.0 * (want * (1.0 - want) / ess).sqrt();
        assert!(
            (p - want).abs() < tol.max(0.02),
            "seed {seed}: P(right mode) {p} vs {want} ± {tol}"
        );
    }
}

#[test]
fn chains_for_a_seed_do_not_depend_on_the_thread_count() {
    let (_, _, f) = gaussian();
    let d = Density(2, f);
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run(&d, &[0.0, 0.0], 16, 200, 7))
    };
    let one = with(1);
    assert_eq!(one, with(3));
    assert_eq!(one, with(1));
    assert_ne!(one.draws, run(&d, &[0.0, 0.0], 16, 200, 8).draws);
}

#[test]
fn bad_settings_are_refused() {
    let (_, _, f) = gaussian();
    let d = Density(2, f);
    let s = |walkers, steps| EnsembleSettings {
        walkers,
        steps,
        burn_in: 0,
        seed: 1,
    };
    let starts = ball(&[0.0, 0.0], 8, 1);
    assert!(run_ensemble(&d, &starts, &s(5, 10), &|_, _| {}).is_err());
    assert!(run_ensemble(&d, &starts, &s(8, 2), &|_, _| {}).is_err());
    assert!(run_ensemble(&d, &starts[..6], &s(8, 10), &|_, _| {}).is_err());
    let outside = Density(
        2,
        |x: &[f64]| if x[0] > 5.0 { 0.0 } else { f64::NEG_INFINITY },
    );
    assert!(run_ensemble(&outside, &starts, &s(8, 10), &|_, _| {}).is_err());
}

/// `m` AR(1) chains x_t = ρ·x_{t−1} + √(1−ρ²)·ε_t of length n, chain j shifted by shift·j.
fn ar1(m: usize, n: usize, rho: f64, shift: f64, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    (0..m)
        .map(|j| {
            let mut x: f64 = StandardNormal.sample(&mut rng);
            (0..n)
                .map(|_| {
                    let e: f64 = StandardNormal.sample(&mut rng);
                    x = rho * x + (1.0 - rho * rho).sqrt() * e;
                    x + shift * j as f64
                })
                .collect()
        })
        .collect()
}

#[test]
fn diagnostics_match_chains_of_known_autocorrelation() {
    let mut ratios = Vec::new();
    for seed in 0..20 {
        let iid = ar1(4, 1000, 0.0, 0.0, seed);
        assert!(rhat_rank(&iid) < 1.01, "iid R-hat {}", rhat_rank(&iid));
        let e = ess_bulk(&iid);
        assert!((3000.0..5200.0).contains(&e), "iid bulk ESS {e}");
        assert!(ess_tail(&iid) > 2500.0);
        // ESS of AR(1) ≈ S·(1 − ρ)/(1 + ρ).
        let rho = 0.8;
        let c = ar1(4, 4000, rho, 0.0, 100 + seed);
        ratios.push(ess_bulk(&c) / (16000.0 * (1.0 - rho) / (1.0 + rho)));
        let apart = ar1(4, 1000, 0.0, 1.0, 200 + seed);
        assert!(
            rhat_rank(&apart) > 1.2,
            "separated chains R-hat {}",
            rhat_rank(&apart)
        );
    }
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!((mean - 1.0).abs() < 0.1, "AR(1) ESS / theory: {ratios:?}");
}

/// An eight-dimensional Gaussian, thin and correlated: x₀ ~ N(0, s₀²), x_i | x_{i−1} ~
/// N(ρ·(s_i/s_{i−1})·x_{i−1}, s_i²·(1 − ρ²)), so that Var x_i = s_i² and
/// corr(x_i, x_{i+1}) = ρ, with scales s_i = 10^(−i/4) (a factor 56 apart) and ρ = 0.95.
fn thin_gaussian(d: usize, rho: f64) -> impl Fn(&[f64]) -> f64 + Sync {
    move |x: &[f64]| {
        let s = |i: usize| 10f64.powf(-(i as f64) / 4.0);
        let mut lp = -0.5 * (x[0] / s(0)).powi(2);
        for i in 1..d {
            let m = rho * s(i) / s(i - 1) * x[i - 1];
            lp -= 0.5 * ((x[i] - m) / (s(i) * (1.0 - rho * rho).sqrt())).powi(2);
        }
        lp
    }
}

/// The mixture of differential-evolution and stretch moves that `predict` samples with
/// recovers the variances and neighbour correlations of a thin, correlated Gaussian in
/// eight dimensions over seeds, and its chains depend on the seed only, not on the thread
/// count.
#[test]
fn mixed_moves_recover_a_thin_gaussian_in_eight_dimensions() {
    use vanefit::estimate::{run_ensemble_with, Moves};
    let (d, rho) = (8, 0.95);
    let density = Density(d, thin_gaussian(d, rho));
    let moves = Moves::Mixed { de: 0.8 };
    let settings = |seed| EnsembleSettings {
        walkers: 32,
        steps: 6000,
        burn_in: 2000,
        seed,
    };
    let s = |i: usize| 10f64.powf(-(i as f64) / 4.0);
    let centre = vec![0.0; d];
    for seed in [1, 2] {
        let starts: Vec<Vec<f64>> = ball(&centre, 32, seed + 100)
            .into_iter()
            .map(|x| x.iter().enumerate().map(|(i, v)| v * s(i)).collect())
            .collect();
        let c = run_ensemble_with(&density, &starts, &settings(seed), moves, &|_, _| {}).unwrap();
        let diag = summarise(&c.draws);
        assert!(diag.iter().all(|g| g.rhat < 1.05), "seed {seed}: {diag:?}");
        let m: Vec<f64> = (0..d).map(|i| mean_of(&c, &|x| x[i])).collect();
        for i in 0..d {
            let tol = 4.0 * s(i) / diag[i].ess_bulk.sqrt();
            assert!(m[i].abs() < tol, "seed {seed} mean {i}: {} ± {tol}", m[i]);
            let v = mean_of(&c, &|x| (x[i] - m[i]).powi(2));
            assert!(
                (v / (s(i) * s(i)) - 1.0).abs() < 0.2,
                "seed {seed} var {i}: {v}"
            );
            if i + 1 < d {
                let cov = mean_of(&c, &|x| (x[i] - m[i]) * (x[i + 1] - m[i + 1]));
                let vn = mean_of(&c, &|x| (x[i + 1] - m[i + 1]).powi(2));
                let r = cov / (v * vn).sqrt();
                assert!((r - rho).abs() < 0.03, "seed {seed} corr {i}: {r}");
            }
        }
    }
    let starts = ball(&centre, 32, 5);
    let short = EnsembleSettings {
        steps: 100,
        burn_in: 10,
        ..settings(3)
    };
    let with = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run_ensemble_with(&density, &starts, &short, moves, &|_, _| {}).unwrap())
    };
    assert_eq!(with(1), with(3));
}
