//! Systematic errors of a rig as linear nuisance parameters, profiled out in closed form
//! (sensor offsets and the supply-pressure sensor's offset).
//!
//! A nuisance β_k (a sensor's zero offset, SI of that sensor; the recorded supply pressure's
//! offset, Pa) moves the compared rows by β_k·a_k, with a_k its effect on every row (SI per
//! unit of β_k: 1 on the rows of the offset sensor's channel; for an input, the simulation's
//! sensitivity to it). With a Gaussian prior β_k ~ N(0, τ_k²) (the calibration tolerance) and
//! in noise units (u_i = (y_sim,i − y_data,i)/σ_i, A_ik = a_ik/σ_i, Λ = diag(1/τ_k)):
//!
//! ```text
//!     χ²(β) = ‖u + A·β‖² + ‖Λ·β‖²
//!     β̂ = −(AᵀA + Λ²)⁻¹ Aᵀ u                                           [1]
//!     χ²(β̂) = ‖u‖² − uᵀ A (AᵀA + Λ²)⁻¹ Aᵀ u                            [2]
//! ```
//!
//! Since β enters linearly, \[2\] is the Gaussian marginal likelihood up to a constant: an
//! offset the data cannot tell from a parameter change widens that parameter's interval
//! instead of biasing it. The residual vector whose squares sum to \[2\] is u + A·β̂ followed
//! by Λ·β̂ (one row per nuisance), which is what Levenberg–Marquardt sees.

use nalgebra::{DMatrix, DVector};

/// One nuisance: its name, prior σ and effect on the compared rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Nuisance {
    /// What it is (e.g. "ramp.csv flow1_g_s offset").
    pub label: String,
    /// Prior standard deviation τ, in the nuisance's unit (> 0).
    pub prior_sd: f64,
    /// a: the change of each compared row (all channels, concatenated) per unit nuisance, SI.
    pub(crate) shape: Vec<f64>,
}

/// The nuisances of a target, ready to profile out.
#[derive(Debug, Clone)]
pub struct Nuisances {
    items: Vec<Nuisance>,
    /// A, rows in noise units.
    a: DMatrix<f64>,
    /// (AᵀA + Λ²)⁻¹Aᵀ, so that β̂ = −gain·u.
    gain: DMatrix<f64>,
    /// The diagonal of Λ, 1/τ_k.
    precision_sqrt: DVector<f64>,
}

impl Nuisances {
    /// The nuisances over rows of noise `sigma` (one per row); `None` when there are none, or
    /// when a shape's length is not the number of rows, or a prior σ is not positive.
    pub fn new(items: Vec<Nuisance>, sigma: &[f64]) -> Option<Self> {
        let (n, m) = (sigma.len(), items.len());
        if m == 0
            || items
                .iter()
                .any(|it| it.shape.len() != n || it.prior_sd.is_nan() || it.prior_sd <= 0.0)
        {
            return None;
        }
        let a = DMatrix::from_fn(n, m, |i, k| items[k].shape[i] / sigma[i]);
        let precision_sqrt = DVector::from_iterator(m, items.iter().map(|it| 1.0 / it.prior_sd));
        let mut normal = a.transpose() * &a;
        for k in 0..m {
            normal[(k, k)] += precision_sqrt[k].powi(2);
        }
        let gain = normal.cholesky()?.inverse() * a.transpose();
        Some(Self {
            items,
            a,
            gain,
            precision_sqrt,
        })
    }

    /// The nuisances.
    pub fn items(&self) -> &[Nuisance] {
        &self.items
    }

    /// β̂ of eq. \[1\] for normalised residuals `u`, in each nuisance's unit.
    pub fn estimate(&self, u: &[f64]) -> Vec<f64> {
        let beta = -(&self.gain * DVector::from_column_slice(u));
        beta.iter().copied().collect()
    }

    /// Turns `u` into the residual vector of eq. \[2\]: u + A·β̂, then Λ·β̂ appended.
    pub(crate) fn apply(&self, u: &mut Vec<f64>) {
        let beta = -(&self.gain * DVector::from_column_slice(u));
        let shift = &self.a * &beta;
        for (v, s) in u.iter_mut().zip(shift.iter()) {
            *v += s;
        }
        u.extend(
            beta.iter()
                .zip(self.precision_sqrt.iter())
                .map(|(b, l)| b * l),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One constant offset: eq. [2] is Σu² − (Σu)²/(N + σ²/τ²), the closed form of a mean
    /// shrunk by its prior; and β̂ minimises χ²(β) (any other β does worse).
    #[test]
    fn one_offset_matches_the_closed_form() {
        let sigma = [0.5; 5];
        let data = [1.0, 2.0, 3.5, 4.0, 5.5];
        let sim = [1.2, 2.3, 3.6, 4.4, 5.6];
        let u: Vec<f64> = sim.iter().zip(&data).map(|(s, d)| (s - d) / 0.5).collect();
        let tau = 0.3;
        let nz = Nuisances::new(
            vec![Nuisance {
                label: "offset".into(),
                prior_sd: tau,
                shape: vec![1.0; 5],
            }],
            &sigma,
        )
        .unwrap();
        let mut r = u.clone();
        nz.apply(&mut r);
        let chi2: f64 = r.iter().map(|v| v * v).sum();
        let s1: f64 = u.iter().sum();
        let s2: f64 = u.iter().map(|v| v * v).sum();
        let closed = s2 - s1 * s1 / (5.0 + (0.5f64 / tau).powi(2));
        assert!((chi2 - closed).abs() < 1e-12, "{chi2} {closed}");
        let beta = nz.estimate(&u)[0];
        let at = |b: f64| -> f64 {
            sim.iter()
                .zip(&data)
                .map(|(s, d)| ((s + b - d) / 0.5).powi(2))
                .sum::<f64>()
                + (b / tau).powi(2)
        };
        assert!((at(beta) - chi2).abs() < 1e-12);
        assert!(at(beta + 0.01) > chi2 && at(beta - 0.01) > chi2);
    }

    /// A nuisance whose shape the residuals follow exactly is absorbed up to its prior: a
    /// line a·x with a far inside the prior leaves almost nothing.
    #[test]
    fn a_shaped_nuisance_absorbs_its_own_shape() {
        let x: Vec<f64> = (0..50).map(|i| i as f64 / 49.0).collect();
        let sigma = vec![0.1; 50];
        let u: Vec<f64> = x.iter().map(|x| 3.0 * x / 0.1).collect();
        let nz = Nuisances::new(
            vec![Nuisance {
                label: "slope".into(),
                prior_sd: 100.0,
                shape: x.clone(),
            }],
            &sigma,
        )
        .unwrap();
        assert!((nz.estimate(&u)[0] + 3.0).abs() < 1e-3);
        let mut r = u.clone();
        nz.apply(&mut r);
        let chi2: f64 = r.iter().map(|v| v * v).sum();
        assert!(chi2 < 1e-2, "{chi2}");
    }

    #[test]
    fn bad_shapes_give_no_nuisances() {
        let one = |shape: Vec<f64>, prior_sd: f64| Nuisance {
            label: "x".into(),
            prior_sd,
            shape,
        };
        assert!(Nuisances::new(vec![], &[1.0]).is_none());
        assert!(Nuisances::new(vec![one(vec![1.0, 1.0], 1.0)], &[1.0]).is_none());
        assert!(Nuisances::new(vec![one(vec![1.0], 0.0)], &[1.0]).is_none());
    }
}
