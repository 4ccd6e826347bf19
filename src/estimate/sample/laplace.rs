//! The Laplace approximation of a posterior in the sampler's coordinates, and the
//! multivariate-t proposal made from it.
//!
//! Near its mode x̂ a posterior whose log-density is −½·Σ rᵢ(x)²/s² + ln π(x) is close to
//! the Gaussian N(x̂, H⁻¹) with the Gauss–Newton precision
//!
//! ```text
//!     H = JᵀJ/s² − ∇² ln π(x̂) + diag(1/wᵢ²),
//! ```
//!
//! J the residuals' Jacobian at x̂ (central differences), ∇² ln π the prior's Hessian (central
//! differences; exact for the motor prior, a Gaussian in ln θ) and wᵢ the width of
//! coordinate i's support: the last term keeps H positive definite in a direction neither
//! the data nor a prior pin (a flat prior on [lo, hi] has σ = w/√12, so the term is a
//! fraction of that precision and leaves the proposal wider than the posterior there).
//! Bates & Watts (1988, "Nonlinear Regression Analysis and Its Applications", §2.2.1) for
//! the Gauss–Newton Hessian.
//!
//! The proposal is a multivariate t with ν degrees of freedom about x̂, scale c·L (Σ = L·Lᵀ):
//! heavier tails than the posterior's where the Gaussian is close, so that the importance
//! ratio p/q stays bounded and an independence sampler is uniformly ergodic (Tierney 1994,
//! "Markov chains for exploring posterior distributions", Ann. Statist. 22(4), §2.3.2).

use super::SampleError;
use nalgebra::{DMatrix, DVector};
use rand::Rng;
use rand_distr::{ChiSquared, Distribution, StandardNormal};

/// A Gaussian N(mode, L·Lᵀ) in the sampler's coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Laplace {
    /// The mode x̂.
    pub mode: Vec<f64>,
    /// Lower Cholesky factor L of the covariance Σ = H⁻¹.
    pub chol: DMatrix<f64>,
}

impl Laplace {
    /// The Gaussian with precision `precision` + diag(1/wᵢ²) about `mode`, `widths` the
    /// supports' widths wᵢ (an infinite width adds nothing).
    pub fn from_precision(
        mode: Vec<f64>,
        precision: &DMatrix<f64>,
        widths: &[f64],
    ) -> Result<Self, SampleError> {
        let d = mode.len();
        if precision.nrows() != d || precision.ncols() != d || widths.len() != d {
            return Err(SampleError::Curvature("dimensions differ"));
        }
        let mut h = 0.5 * (precision + precision.transpose());
        for (i, w) in widths.iter().enumerate() {
            if w.is_finite() && *w > 0.0 {
                h[(i, i)] += 1.0 / (w * w);
            }
        }
        if h.iter().any(|v| !v.is_finite()) {
            return Err(SampleError::Curvature("the curvature is not finite"));
        }
        let cov = h
            .cholesky()
            .ok_or(SampleError::Curvature(
                "the curvature is not positive definite",
            ))?
            .inverse();
        let cov = 0.5 * (&cov + cov.transpose());
        let chol = cov
            .cholesky()
            .ok_or(SampleError::Curvature(
                "the covariance is not positive definite",
            ))?
            .l();
        Ok(Self { mode, chol })
    }

    /// Dimension d.
    pub fn dim(&self) -> usize {
        self.mode.len()
    }

    /// σ of each coordinate, √Σᵢᵢ.
    pub fn sd(&self) -> Vec<f64> {
        (0..self.dim()).map(|i| self.chol.row(i).norm()).collect()
    }

    /// x̂ + L·w: the point of whitened coordinates w.
    pub fn unwhiten(&self, w: &DVector<f64>) -> Vec<f64> {
        let y = &self.chol * w;
        self.mode.iter().zip(y.iter()).map(|(m, v)| m + v).collect()
    }

    /// L⁻¹·(x − x̂): the whitened coordinates of x.
    pub fn whiten(&self, x: &[f64]) -> DVector<f64> {
        let dx = DVector::from_iterator(x.len(), x.iter().zip(&self.mode).map(|(a, m)| a - m));
        self.chol
            .solve_lower_triangular(&dx)
            .unwrap_or_else(|| DVector::from_element(x.len(), f64::INFINITY))
    }
}

/// The multivariate-t proposal t_ν(x̂, c²·Σ) of a [`Laplace`] approximation.
#[derive(Debug, Clone, PartialEq)]
pub struct TProposal {
    /// The approximation.
    pub laplace: Laplace,
    /// Degrees of freedom ν.
    pub nu: f64,
    /// Scale factor c on L.
    pub scale: f64,
}

impl TProposal {
    /// ln q(x) up to a constant: −(ν + d)/2 · ln(1 + |L⁻¹(x − x̂)|²/(c²ν)).
    pub fn log_q(&self, x: &[f64]) -> f64 {
        let w = self.laplace.whiten(x);
        let m2 = w.norm_squared() / (self.scale * self.scale);
        -0.5 * (self.nu + self.laplace.dim() as f64) * (m2 / self.nu).ln_1p()
    }

    /// A draw x̂ + c·L·z·√(ν/g), z ~ N(0, I), g ~ χ²_ν.
    pub fn draw<R: Rng>(&self, rng: &mut R) -> Vec<f64> {
        let d = self.laplace.dim();
        let z = DVector::from_fn(d, |_, _| StandardNormal.sample(rng));
        let g: f64 = ChiSquared::new(self.nu).map_or(self.nu, |c| c.sample(rng));
        let f = self.scale * (self.nu / g.max(f64::MIN_POSITIVE)).sqrt();
        self.laplace.unwhiten(&(z * f))
    }
}

/// The central-difference step in coordinate i: 10⁻⁴ of the coordinate's scale (1 for
/// ln θ, where it is a relative step of 10⁻⁴), kept inside (lo, hi).
pub(crate) fn fd_step(x: f64, log_scale: bool, (lo, hi): (f64, f64)) -> f64 {
    let scale = if log_scale { 1.0 } else { x.abs().max(1e-12) };
    let h = 1e-4 * scale;
    let room = (x - lo).min(hi - x);
    if room.is_finite() && room > 0.0 {
        h.min(0.5 * room)
    } else {
        h
    }
}

/// The Gauss–Newton precision JᵀJ/s² of residuals r(x) at `x` (columns by central
/// differences with steps `steps`).
pub(crate) fn gauss_newton(
    residuals: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    x: &[f64],
    steps: &[f64],
    scale2: f64,
) -> Result<DMatrix<f64>, SampleError> {
    let d = x.len();
    let at = |i: usize, s: f64| {
        let mut y = x.to_vec();
        y[i] += s;
        residuals(&y)
    };
    let mut cols: Vec<Vec<f64>> = Vec::with_capacity(d);
    for (i, h) in steps.iter().enumerate() {
        let (up, down) = (
            at(i, *h).ok_or(SampleError::Curvature(
                "a simulation beside the estimate failed",
            ))?,
            at(i, -*h).ok_or(SampleError::Curvature(
                "a simulation beside the estimate failed",
            ))?,
        );
        if up.len() != down.len() {
            return Err(SampleError::Curvature("the residuals changed length"));
        }
        cols.push(
            up.iter()
                .zip(&down)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect(),
        );
    }
    let n = cols.first().map_or(0, Vec::len);
    let j = DMatrix::from_fn(n, d, |r, c| cols[c][r]);
    Ok(j.transpose() * j / scale2)
}

/// −∇² f at `x` by central differences with steps `steps` (f a log-density).
pub(crate) fn neg_hessian(f: &dyn Fn(&[f64]) -> f64, x: &[f64], steps: &[f64]) -> DMatrix<f64> {
    let d = x.len();
    let at = |i: usize, si: f64, j: usize, sj: f64| {
        let mut y = x.to_vec();
        y[i] += si;
        y[j] += sj;
        f(&y)
    };
    let mut h = DMatrix::zeros(d, d);
    for i in 0..d {
        for j in i..d {
            let (a, b) = (steps[i], steps[j]);
            let v = if i == j {
                let f0 = f(x);
                (at(i, a, i, 0.0) - 2.0 * f0 + at(i, -a, i, 0.0)) / (a * a)
            } else {
                (at(i, a, j, b) - at(i, a, j, -b) - at(i, -a, j, b) + at(i, -a, j, -b))
                    / (4.0 * a * b)
            };
            h[(i, j)] = -v;
            h[(j, i)] = -v;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn the_laplace_covariance_inverts_the_precision() {
        let p = DMatrix::from_row_slice(2, 2, &[4.0, 1.0, 1.0, 2.0]);
        let l = Laplace::from_precision(vec![1.0, 2.0], &p, &[f64::INFINITY; 2]).unwrap();
        let cov = &l.chol * l.chol.transpose();
        let id = cov * p;
        assert!((id - DMatrix::identity(2, 2)).norm() < 1e-12);
        let x = l.unwhiten(&DVector::from_vec(vec![0.3, -0.7]));
        let w = l.whiten(&x);
        assert!((w[0] - 0.3).abs() < 1e-12 && (w[1] + 0.7).abs() < 1e-12);
    }

    #[test]
    fn a_direction_nothing_pins_gets_the_support_s_width() {
        let p = DMatrix::from_row_slice(2, 2, &[4.0, 0.0, 0.0, 0.0]);
        let l = Laplace::from_precision(vec![0.0; 2], &p, &[10.0, 3.0]).unwrap();
        let sd = l.sd();
        assert!((sd[0] - 1.0 / (4.0_f64 + 0.01).sqrt()).abs() < 1e-12);
        assert!((sd[1] - 3.0).abs() < 1e-12);
    }

    #[test]
    fn the_curvature_of_a_quadratic_is_found_exactly() {
        // f = −½ xᵀAx: −∇²f = A; residuals r = Bx with BᵀB = A give the same.
        let a = [[3.0, 0.5], [0.5, 1.0]];
        let f = |x: &[f64]| {
            -0.5 * (0..2)
                .map(|i| (0..2).map(|j| x[i] * a[i][j] * x[j]).sum::<f64>())
                .sum::<f64>()
        };
        let h = neg_hessian(&f, &[0.2, -0.1], &[1e-3, 1e-3]);
        for i in 0..2 {
            for j in 0..2 {
                assert!((h[(i, j)] - a[i][j]).abs() < 1e-6, "{h}");
            }
        }
        let b = DMatrix::from_row_slice(
            2,
            2,
            &[
                3.0_f64.sqrt(),
                0.5 / 3.0_f64.sqrt(),
                0.0,
                (1.0 - 0.25 / 3.0_f64).sqrt(),
            ],
        );
        let r = |x: &[f64]| {
            Some(
                (&b * DVector::from_column_slice(x))
                    .iter()
                    .copied()
                    .collect(),
            )
        };
        let g = gauss_newton(&r, &[0.2, -0.1], &[1e-4, 1e-4], 2.0).unwrap();
        for i in 0..2 {
            for j in 0..2 {
                assert!((g[(i, j)] - a[i][j] / 2.0).abs() < 1e-8, "{g}");
            }
        }
    }

    #[test]
    fn t_draws_have_the_t_covariance() {
        // Var of a multivariate t: c²·ν/(ν − 2)·Σ.
        let p = DMatrix::from_row_slice(2, 2, &[2.0, 0.6, 0.6, 1.0]);
        let l = Laplace::from_precision(vec![1.0, -1.0], &p, &[f64::INFINITY; 2]).unwrap();
        let q = TProposal {
            laplace: l.clone(),
            nu: 8.0,
            scale: 1.5,
        };
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(4);
        let n = 200_000;
        let draws: Vec<Vec<f64>> = (0..n).map(|_| q.draw(&mut rng)).collect();
        let cov = &l.chol * l.chol.transpose() * (1.5 * 1.5 * 8.0 / 6.0);
        for i in 0..2 {
            let mean = draws.iter().map(|x| x[i]).sum::<f64>() / n as f64;
            assert!((mean - l.mode[i]).abs() < 0.02);
            for j in 0..2 {
                let c = draws
                    .iter()
                    .map(|x| (x[i] - l.mode[i]) * (x[j] - l.mode[j]))
                    .sum::<f64>()
                    / n as f64;
                assert!(
                    (c - cov[(i, j)]).abs() < 0.05 * cov[(i, i)].max(cov[(j, j)]),
                    "{c} {}",
                    cov[(i, j)]
                );
            }
        }
        // ln q falls with the Mahalanobis distance as the t density does.
        let far = l.unwhiten(&DVector::from_vec(vec![3.0, 0.0]));
        let expect = -0.5 * 10.0 * (9.0_f64 / (1.5 * 1.5 * 8.0)).ln_1p();
        assert!((q.log_q(&far) - expect).abs() < 1e-9);
        assert_eq!(q.log_q(&l.mode), 0.0);
    }
}
