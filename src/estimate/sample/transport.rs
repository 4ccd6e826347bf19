//! A triangular quadratic transport map learnt from draws, which straightens a curved
//! posterior before it is sampled.
//!
//! Where a page's printed figures constrain a few combinations of the parameters that
//! the prior leaves wide, the posterior is a thin valley that bends: a thin coordinate
//! follows a wide one quadratically (its residual's own curvature, Σ rᵢ·∇²rᵢ, dwarfs the
//! Gauss–Newton JᵀJ there: docs/validation.md, "Sampled bands on a page"). The map takes
//! draws x to reference coordinates z in which that bend is gone (Marzouk, Moselhy, Parno
//! & Spantini 2016, "Sampling via measure transport", Handbook of UQ; Parno & Marzouk 2018,
//! "Transport map accelerated Markov chain Monte Carlo", SIAM/ASA JUQ 6(2)):
//!
//! ```text
//!     y = Vᵀ(x − m)                         (principal axes of the draws, widest first)
//!     z₁ = y₁
//!     z_k = y_k − g_k(y₁, …, y_{k−1})       (g_k: a quadratic polynomial)
//! ```
//!
//! each g_k fitted by least squares to the draws. The map is triangular with unit
//! diagonal, so its Jacobian determinant is 1 and its inverse is explicit (y_k =
//! z_k + g_k(y₁…y_{k−1}), in order): the density in z is p(T⁻¹(z)) exactly, whatever the
//! fit's quality. A poor fit makes the sampling in z no worse than in x.

use super::LogDensity;
use nalgebra::{DMatrix, DVector};

/// The map (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct QuadraticMap {
    /// Mean m of the draws.
    pub mean: Vec<f64>,
    /// Principal axes V (columns), widest first.
    pub axes: DMatrix<f64>,
    /// Coefficients of g_k over the features of y₁…y_{k−1}: 1, yᵢ, yᵢ·yⱼ (i ≤ j); 1 and yᵢ
    /// only where the draws were too few for a quadratic; empty for k = 1.
    pub coefs: Vec<Vec<f64>>,
}

/// The features of a quadratic polynomial in `y`: 1, yᵢ, yᵢ·yⱼ (i ≤ j).
fn features(y: &[f64]) -> Vec<f64> {
    let mut f = Vec::with_capacity(1 + y.len() + y.len() * (y.len() + 1) / 2);
    f.push(1.0);
    f.extend_from_slice(y);
    for i in 0..y.len() {
        for j in i..y.len() {
            f.push(y[i] * y[j]);
        }
    }
    f
}

impl QuadraticMap {
    /// The map fitted to `draws` (at least a few times more than the features of the last
    /// coordinate, (d + 1)(d + 2)/2; fewer leave the map linear). `ridge` is the relative
    /// Tikhonov weight of the least squares.
    pub fn fit(draws: &[Vec<f64>], ridge: f64) -> Option<Self> {
        let d = draws.first()?.len();
        let n = draws.len() as f64;
        let mean: Vec<f64> = (0..d)
            .map(|i| draws.iter().map(|x| x[i]).sum::<f64>() / n)
            .collect();
        let centred: Vec<DVector<f64>> = draws
            .iter()
            .map(|x| DVector::from_iterator(d, x.iter().zip(&mean).map(|(a, m)| a - m)))
            .collect();
        let mut cov = DMatrix::zeros(d, d);
        for c in &centred {
            cov += c * c.transpose() / n;
        }
        let eig = cov.symmetric_eigen();
        let mut order: Vec<usize> = (0..d).collect();
        order.sort_by(|a, b| eig.eigenvalues[*b].total_cmp(&eig.eigenvalues[*a]));
        let axes = DMatrix::from_fn(d, d, |r, c| eig.eigenvectors[(r, order[c])]);
        let ys: Vec<Vec<f64>> = centred
            .iter()
            .map(|c| (axes.transpose() * c).iter().copied().collect())
            .collect();
        let quadratic = draws.len() >= 3 * (d + 1) * (d + 2) / 2;
        let coefs = (0..d)
            .map(|k| {
                if k == 0 {
                    return Vec::new();
                }
                let rows: Vec<Vec<f64>> = ys
                    .iter()
                    .map(|y| {
                        if quadratic {
                            features(&y[..k])
                        } else {
                            std::iter::once(1.0).chain(y[..k].iter().copied()).collect()
                        }
                    })
                    .collect();
                let target: Vec<f64> = ys.iter().map(|y| y[k]).collect();
                least_squares(&rows, &target, ridge)
            })
            .collect();
        Some(Self { mean, axes, coefs })
    }

    /// g_k(y₁…y_{k−1}).
    fn g(&self, k: usize, y: &[f64]) -> f64 {
        let c = &self.coefs[k];
        if c.is_empty() {
            return 0.0;
        }
        let f = if c.len() == 1 + k {
            std::iter::once(1.0).chain(y[..k].iter().copied()).collect()
        } else {
            features(&y[..k])
        };
        f.iter().zip(c).map(|(a, b)| a * b).sum()
    }

    /// z = T(x).
    pub fn forward(&self, x: &[f64]) -> Vec<f64> {
        let c = DVector::from_iterator(x.len(), x.iter().zip(&self.mean).map(|(a, m)| a - m));
        let y: Vec<f64> = (self.axes.transpose() * c).iter().copied().collect();
        (0..y.len()).map(|k| y[k] - self.g(k, &y)).collect()
    }

    /// x = T⁻¹(z).
    pub fn inverse(&self, z: &[f64]) -> Vec<f64> {
        let mut y = vec![0.0; z.len()];
        for k in 0..z.len() {
            y[k] = z[k] + self.g(k, &y);
        }
        let x = &self.axes * DVector::from_column_slice(&y);
        x.iter().zip(&self.mean).map(|(a, m)| a + m).collect()
    }
}

/// The map fitted to `draws` (ridge `ridge`) and the t proposal (ν `nu`, `scale` on its
/// Cholesky factor) of the mapped draws' Gaussian: what the chains propose from in the
/// map's coordinates.
pub fn straightened(
    draws: &[Vec<f64>],
    ridge: f64,
    nu: f64,
    scale: f64,
) -> Result<(QuadraticMap, super::TProposal), super::SampleError> {
    let map = QuadraticMap::fit(draws, ridge).ok_or(super::SampleError::Curvature(
        "no draws to fit the transport map to",
    ))?;
    let zs: Vec<Vec<f64>> = draws.iter().map(|x| map.forward(x)).collect();
    let laplace = gaussian_of(&zs).ok_or(super::SampleError::Curvature(
        "the mapped draws' covariance is not positive definite",
    ))?;
    Ok((map, super::TProposal { laplace, nu, scale }))
}

/// The Gaussian (mean, Cholesky factor of the covariance) of `draws`, its variances
/// raised by 10⁻⁹ of themselves so that the factor exists; `None` without draws or where
/// the covariance is singular.
pub fn gaussian_of(draws: &[Vec<f64>]) -> Option<super::Laplace> {
    let d = draws.first()?.len();
    let n = draws.len() as f64;
    let mean: Vec<f64> = (0..d)
        .map(|i| draws.iter().map(|x| x[i]).sum::<f64>() / n)
        .collect();
    let mut cov = DMatrix::zeros(d, d);
    for x in draws {
        let c = DVector::from_iterator(d, x.iter().zip(&mean).map(|(a, m)| a - m));
        cov += &c * c.transpose() / n;
    }
    for i in 0..d {
        cov[(i, i)] *= 1.0 + 1e-9;
    }
    let chol = cov.cholesky()?.l();
    Some(super::Laplace { mode: mean, chol })
}

/// Least squares min |A·c − b|² + ridge·tr(AᵀA)/p·|c|² by the normal equations.
fn least_squares(rows: &[Vec<f64>], b: &[f64], ridge: f64) -> Vec<f64> {
    let p = rows.first().map_or(0, Vec::len);
    let mut ata = DMatrix::zeros(p, p);
    let mut atb = DVector::zeros(p);
    for (r, bi) in rows.iter().zip(b) {
        let v = DVector::from_column_slice(r);
        ata += &v * v.transpose();
        atb += v * *bi;
    }
    let lambda = ridge * ata.trace() / p.max(1) as f64;
    for i in 0..p {
        ata[(i, i)] += lambda;
    }
    ata.cholesky()
        .map(|c| c.solve(&atb).iter().copied().collect())
        .unwrap_or_else(|| vec![0.0; p])
}

/// A density seen through a map: ln p(T⁻¹(z)) (the map's Jacobian is 1).
pub struct Mapped<'a> {
    /// The density in x.
    pub density: &'a dyn LogDensity,
    /// The map.
    pub map: &'a QuadraticMap,
}

impl LogDensity for Mapped<'_> {
    fn dim(&self) -> usize {
        self.density.dim()
    }
    fn log_density(&self, z: &[f64]) -> f64 {
        self.density.log_density(&self.map.inverse(z))
    }
}

/// A density on a box seen in unbounded coordinates: coordinate i with finite bounds
/// (lo, hi) is u = logit((x − lo)/(hi − lo)), and the density of u carries the Jacobian,
///
/// ```text
///     ln p_u(u) = ln p(x(u)) + Σᵢ ln((hi − lo)·σ(uᵢ)·(1 − σ(uᵢ))),    σ the logistic function,
/// ```
///
/// so that a Gaussian or t proposal in u has the posterior's support (none of its draws
/// falls outside), and a flat prior on (lo, hi) becomes the smooth logistic density.
pub struct Unbounded<'a> {
    /// The density in x.
    pub density: &'a dyn LogDensity,
    /// Each coordinate's support (infinite ends: left as it is).
    pub bounds: Vec<(f64, f64)>,
}

/// ln σ(u) = −ln(1 + e^(−u)), without overflow.
fn ln_logistic(u: f64) -> f64 {
    if u > 0.0 {
        -(-u).exp().ln_1p()
    } else {
        u - u.exp().ln_1p()
    }
}

impl Unbounded<'_> {
    fn boxed(&self, i: usize) -> Option<(f64, f64)> {
        self.bounds
            .get(i)
            .copied()
            .filter(|(lo, hi)| lo.is_finite() && hi.is_finite() && hi > lo)
    }

    /// u of x (a point on a bound is taken 10⁻¹² of the width inside it).
    pub fn to_u(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .enumerate()
            .map(|(i, v)| match self.boxed(i) {
                Some((lo, hi)) => {
                    // A point on a bound is taken a hair inside it.
                    let f = ((v - lo) / (hi - lo)).clamp(1e-12, 1.0 - 1e-12);
                    (f / (1.0 - f)).ln()
                }
                None => *v,
            })
            .collect()
    }

    /// x of u.
    pub fn to_x(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .enumerate()
            .map(|(i, v)| match self.boxed(i) {
                Some((lo, hi)) => lo + (hi - lo) * ln_logistic(*v).exp(),
                None => *v,
            })
            .collect()
    }
}

impl LogDensity for Unbounded<'_> {
    fn dim(&self) -> usize {
        self.density.dim()
    }
    fn log_density(&self, u: &[f64]) -> f64 {
        if u.iter().any(|v| !v.is_finite()) {
            return f64::NEG_INFINITY;
        }
        let jacobian: f64 = u
            .iter()
            .enumerate()
            .filter_map(|(i, v)| {
                self.boxed(i)
                    .map(|(lo, hi)| (hi - lo).ln() + ln_logistic(*v) + ln_logistic(-*v))
            })
            .sum();
        let lp = self.density.log_density(&self.to_x(u)) + jacobian;
        if lp.is_nan() {
            f64::NEG_INFINITY
        } else {
            lp
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// Draws of a banana x₂ = 0.5·x₁² + 0.05·e: the map takes them to coordinates with no
    /// bend (z₂'s spread is e's), and T⁻¹(T(x)) = x.
    #[test]
    fn a_banana_is_straightened_and_the_map_inverts() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        // Antithetic in a, so that the draws' x₁ and x₂ are uncorrelated exactly and their
        // principal axes are x's own (a rotation would mix x₂'s bend into x₁).
        let mut draws: Vec<Vec<f64>> = Vec::new();
        for _ in 0..2000 {
            let a: f64 = StandardNormal.sample(&mut rng);
            for sign in [1.0, -1.0] {
                let e: f64 = StandardNormal.sample(&mut rng);
                let c: f64 = StandardNormal.sample(&mut rng);
                draws.push(vec![sign * a, 0.5 * a * a + 0.05 * e, 0.3 * c]);
            }
        }
        let map = QuadraticMap::fit(&draws, 1e-9).unwrap();
        let zs: Vec<Vec<f64>> = draws.iter().map(|x| map.forward(x)).collect();
        // The smallest spread among z's coordinates is e's (0.05), where x's is 0.3.
        let sd = |i: usize| {
            let m = zs.iter().map(|z| z[i]).sum::<f64>() / zs.len() as f64;
            (zs.iter().map(|z| (z[i] - m).powi(2)).sum::<f64>() / zs.len() as f64).sqrt()
        };
        let least = (0..3).map(sd).fold(f64::INFINITY, f64::min);
        assert!((least - 0.05).abs() < 0.005, "{least}");
        for x in draws.iter().take(50) {
            let back = map.inverse(&map.forward(x));
            assert!(x.iter().zip(&back).all(|(a, b)| (a - b).abs() < 1e-9));
        }
    }

    /// A flat density on (2, 6) seen in u is the logistic density times 4: its integral over
    /// u is the box's width (trapezoids), and x(u(x)) = x.
    #[test]
    fn a_flat_box_becomes_the_logistic_density() {
        struct Flat;
        impl LogDensity for Flat {
            fn dim(&self) -> usize {
                1
            }
            fn log_density(&self, x: &[f64]) -> f64 {
                if x[0] > 2.0 && x[0] < 6.0 {
                    0.0
                } else {
                    f64::NEG_INFINITY
                }
            }
        }
        let u = Unbounded {
            density: &Flat,
            bounds: vec![(2.0, 6.0)],
        };
        let h = 0.01;
        let total: f64 = (-4000..4000)
            .map(|k| u.log_density(&[k as f64 * h]).exp() * h)
            .sum();
        assert!((total - 4.0).abs() < 1e-6, "{total}");
        for x in [2.001, 3.0, 5.999] {
            assert!((u.to_x(&u.to_u(&[x]))[0] - x).abs() < 1e-9);
        }
        assert_eq!(u.log_density(&[f64::INFINITY]), f64::NEG_INFINITY);
    }

    /// The banana p(x) = N(x₁; 0, 1)·N(x₂; ½x₁², 0.05²): chains in the coordinates of a map
    /// fitted to 2000 draws of it (a pilot), with the t of the mapped draws for their
    /// independence moves, draw it: E x₂ = ½·E x₁² = ½, Var x₁ = 1 (closed forms), within
    /// 4 Monte-Carlo standard errors, and R̂ < 1.01.
    #[test]
    fn chains_in_the_map_s_coordinates_draw_a_banana() {
        use crate::estimate::sample::{run_chains, summarise, ChainSettings};
        struct Banana;
        impl LogDensity for Banana {
            fn dim(&self) -> usize {
                2
            }
            fn log_density(&self, x: &[f64]) -> f64 {
                let u = (x[1] - 0.5 * x[0] * x[0]) / 0.05;
                -0.5 * (x[0] * x[0] + u * u)
            }
        }
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(8);
        let pilot: Vec<Vec<f64>> = (0..2000)
            .map(|_| {
                let a: f64 = StandardNormal.sample(&mut rng);
                let e: f64 = StandardNormal.sample(&mut rng);
                vec![a, 0.5 * a * a + 0.05 * e]
            })
            .collect();
        let (map, q) = super::straightened(&pilot, 1e-6, 5.0, 1.2).unwrap();
        let mapped = Mapped {
            density: &Banana,
            map: &map,
        };
        let settings = ChainSettings {
            chains: 4,
            steps: 4000,
            burn_in: 500,
            block: 4500,
            seed: 2,
        };
        let zc = run_chains(&mapped, &q, &settings, None, &|_, _| {}).unwrap();
        let xs: Vec<Vec<Vec<f64>>> = zc
            .draws
            .iter()
            .map(|c| c.iter().map(|z| map.inverse(z)).collect())
            .collect();
        let diag = summarise(&xs);
        let flat: Vec<&Vec<f64>> = xs.iter().flatten().collect();
        let n = flat.len() as f64;
        let mean = |i: usize| flat.iter().map(|x| x[i]).sum::<f64>() / n;
        let (m0, m1) = (mean(0), mean(1));
        let v0 = flat.iter().map(|x| (x[0] - m0).powi(2)).sum::<f64>() / n;
        // Var x₂ = ¼·Var x₁² + 0.05² = ½ + 0.0025.
        let mcse1 = (0.5025 / diag[1].ess_bulk).sqrt();
        let mcse0 = (1.0 / diag[0].ess_bulk).sqrt();
        assert!((m1 - 0.5).abs() < 4.0 * mcse1, "E x₂ {m1} ± {mcse1}");
        assert!(m0.abs() < 4.0 * mcse0, "E x₁ {m0} ± {mcse0}");
        assert!((v0 - 1.0).abs() < 0.1, "Var x₁ {v0}");
        assert!(diag.iter().all(|d| d.rhat < 1.01), "{diag:?}");
    }
}
