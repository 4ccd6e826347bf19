//! The linearised design criteria: what a measurement is expected to do to the
//! parameters' covariance and to the bands at the operating points.
//!
//! With C the covariance of ln θ now (the inverse of the fit's Fisher information
//! JᵀWJ + prior precision at the estimate) and a measurement z = G·δln θ + e,
//! e ~ N(0, Σ) with Σ = diag σ², the information adds: C' = (C⁻¹ + GᵀΣ⁻¹G)⁻¹, computed
//! without inverting C (which a parameter the data leave to its prior makes
//! ill-conditioned) as C' = C − C·Gᵀ·S⁻¹·G·C with S = Σ + G·C·Gᵀ (Woodbury). A figure y
//! with gradient g has Var y = gᵀCg before and gᵀC'g after; its band's half-width shrinks
//! by 1 − √(gᵀC'g/gᵀCg). The criteria (Atkinson, Donev & Tobias, *Optimum Experimental
//! Designs*, 2007, ch. 10):
//!
//! * D: the information gained, ½·ln(det C/det C') = ½·ln det(S·Σ⁻¹) nats (the log of
//!   the parameters' confidence volume shrinking);
//! * V: the reduction of the mean relative variance at the operating points,
//!   1 − Σ_i Var'(y_i)/y_i² / Σ_i Var(y_i)/y_i² (each figure counted alike whatever its
//!   unit).

use nalgebra::{DMatrix, DVector};

/// What one measurement is expected to do.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Expected {
    /// C' (the covariance of ln θ after it).
    pub cov_after: DMatrix<f64>,
    /// Var y_i after, per operating-point figure.
    pub var_after: Vec<f64>,
    /// D: ½·ln(det C/det C'), nats.
    pub d_gain_nats: f64,
}

/// The update of `cov` by a measurement of sensitivities `g_meas` (rows: observables) and
/// noise `sigma`; `g_targets` the operating-point figures' gradients (rows). `None` when
/// S is not positive definite (a zero or non-finite σ).
pub(super) fn expected(
    cov: &DMatrix<f64>,
    g_meas: &DMatrix<f64>,
    sigma: &[f64],
    g_targets: &DMatrix<f64>,
) -> Option<Expected> {
    let cg = cov * g_meas.transpose();
    let mut s = g_meas * &cg;
    for (i, sd) in sigma.iter().enumerate() {
        s[(i, i)] += sd * sd;
    }
    let s = (&s + s.transpose()) * 0.5;
    let chol = s.clone().cholesky()?;
    let ln_det_s: f64 = chol.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum();
    let ln_det_sigma: f64 = sigma.iter().map(|sd| 2.0 * sd.ln()).sum();
    let cov_after = cov - &cg * chol.solve(&cg.transpose());
    let cov_after = (&cov_after + cov_after.transpose()) * 0.5;
    Some(Expected {
        var_after: variances(&cov_after, g_targets),
        cov_after,
        d_gain_nats: 0.5 * (ln_det_s - ln_det_sigma),
    })
}

/// gᵢᵀ·C·gᵢ for each row gᵢ of `g` (≥ 0).
pub(super) fn variances(cov: &DMatrix<f64>, g: &DMatrix<f64>) -> Vec<f64> {
    (0..g.nrows())
        .map(|i| {
            let gi = DVector::from_fn(g.ncols(), |j, _| g[(i, j)]);
            gi.dot(&(cov * &gi)).max(0.0)
        })
        .collect()
}

/// V: 1 − Σ Var'(yᵢ)/yᵢ² / Σ Var(yᵢ)/yᵢ² over the figures with y ≠ 0 (0 when nothing
/// has variance).
pub(super) fn v_reduction(values: &[f64], before: &[f64], after: &[f64]) -> f64 {
    let rel = |v: &[f64]| -> f64 {
        values
            .iter()
            .zip(v)
            .filter(|(y, _)| **y != 0.0)
            .map(|(y, var)| var / (y * y))
            .sum()
    };
    let b = rel(before);
    if b > 0.0 {
        1.0 - rel(after) / b
    } else {
        0.0
    }
}

/// 1 − √(after/before): how much a band's half-width shrinks (0 without variance).
pub(super) fn shrinkage(before: f64, after: f64) -> f64 {
    if before > 0.0 {
        1.0 - (after / before).clamp(0.0, 1.0).sqrt()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One parameter, one figure y = ln θ, one observation z = ln θ + e: the posterior
    /// variance is the harmonic combination 1/(1/c + 1/σ²), the D gain ½·ln(1 + c/σ²).
    #[test]
    fn one_parameter_combines_as_a_harmonic_mean() {
        let (c, s) = (0.04, 0.1);
        let cov = DMatrix::from_element(1, 1, c);
        let g = DMatrix::from_element(1, 1, 1.0);
        let e = expected(&cov, &g, &[s], &g).unwrap();
        let want = 1.0 / (1.0 / c + 1.0 / (s * s));
        assert!((e.var_after[0] - want).abs() < 1e-15);
        assert!((e.d_gain_nats - 0.5 * (1.0 + c / (s * s)).ln()).abs() < 1e-12);
        assert!((shrinkage(c, want) - (1.0 - (want / c).sqrt())).abs() < 1e-15);
    }

    /// Two correlated parameters, a measurement of the first: the Woodbury update equals
    /// the inverse of the summed information, and a figure of the second alone shrinks
    /// through the correlation only.
    #[test]
    fn woodbury_equals_the_summed_information() {
        let cov = DMatrix::from_row_slice(2, 2, &[0.09, 0.06, 0.06, 0.16]);
        let g = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let s = 0.05;
        let targets = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1.0]);
        let e = expected(&cov, &g, &[s], &targets).unwrap();
        let info = cov.clone().try_inverse().unwrap() + g.transpose() * &g / (s * s);
        let want = info.try_inverse().unwrap();
        assert!(
            (&e.cov_after - &want).abs().max() < 1e-12,
            "{}",
            e.cov_after
        );
        // ρ² = 0.06²/(0.09·0.16) = 0.25 of the second's variance is what θ₁ can explain.
        let gone = 1.0 - e.var_after[1] / 0.16;
        assert!(gone > 0.0 && gone < 0.25, "{gone}");
        let v = v_reduction(&[1.0, 1.0], &[0.09, 0.16], &e.var_after);
        assert!((v - (1.0 - (e.var_after[0] + e.var_after[1]) / 0.25)).abs() < 1e-15);
    }
}
