//! The linearised design criteria: what a measurement is expected to do to the
//! parameters' covariance and to the bands at the operating points.
//!
//! The covariance of ln θ now is `predict`'s, C = A·C_c·Aᵀ (`ParamUncertainty::for_bands`):
//! C_c the fit's curvature covariance (the inverse of its Fisher information JᵀWJ + prior
//! precision at the estimate), A the stretch along each parameter's profile path to its
//! profile interval's width. A measurement z = G·δln θ + e, e ~ N(0, Σ) with Σ = diag σ²,
//! adds its information in the curvature's units and the stretch persists (what widens a
//! profile interval is the likelihood's shape, which more data of the same kind do not
//! remove at first order): C' = A·(C_c⁻¹ + GᵀΣ⁻¹G)⁻¹·Aᵀ, computed without inverting C_c
//! (which a parameter the data leave to its prior makes ill-conditioned) as
//! C' = A·(C_c − C_c·Gᵀ·S⁻¹·G·C_c)·Aᵀ with S = Σ + G·C_c·Gᵀ (Woodbury). A figure y
//! with gradient g has Var y = gᵀCg before and gᵀC'g after; its band's half-width shrinks
//! by 1 − √(gᵀC'g/gᵀCg). The criteria (Atkinson, Donev & Tobias, *Optimum Experimental
//! Designs*, 2007, ch. 10):
//!
//! * D: the information gained, ½·ln(det C/det C') = ½·ln det(S·Σ⁻¹) nats (the log of
//!   the parameters' confidence volume shrinking; A cancels);
//! * V: the reduction of the mean relative variance at the operating points,
//!   1 − Σ_i Var'(y_i)/y_i² / Σ_i Var(y_i)/y_i² (each figure counted alike whatever its
//!   unit).

use nalgebra::{DMatrix, DVector};

/// What one measurement is expected to do.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Expected {
    /// C' = A·(C_c⁻¹ + GᵀΣ⁻¹G)⁻¹·Aᵀ, the covariance of ln θ after it.
    pub cov_after: DMatrix<f64>,
    /// Var y_i after, per operating-point figure.
    pub var_after: Vec<f64>,
    /// D: ½·ln(det C/det C'), nats.
    pub d_gain_nats: f64,
}

/// The parameters' covariance now, C = A·C_c·Aᵀ.
pub(super) struct Prior<'a> {
    /// C_c, the curvature covariance.
    pub curvature: &'a DMatrix<f64>,
    /// A, the stretch along the profile paths.
    pub stretch: &'a DMatrix<f64>,
}

/// The update of the prior by a measurement of sensitivities `g_meas` (rows: observables)
/// and noise `sigma`; `g_targets` the operating-point figures' gradients (rows). `None`
/// when S is not positive definite (a zero or non-finite σ).
pub(super) fn expected(
    prior: &Prior,
    g_meas: &DMatrix<f64>,
    sigma: &[f64],
    g_targets: &DMatrix<f64>,
) -> Option<Expected> {
    let cov = prior.curvature;
    let cg = cov * g_meas.transpose();
    let mut s = g_meas * &cg;
    for (i, sd) in sigma.iter().enumerate() {
        s[(i, i)] += sd * sd;
    }
    let s = (&s + s.transpose()) * 0.5;
    let chol = s.clone().cholesky()?;
    let ln_det_s: f64 = chol.l().diagonal().iter().map(|d| 2.0 * d.ln()).sum();
    let ln_det_sigma: f64 = sigma.iter().map(|sd| 2.0 * sd.ln()).sum();
    let curv_after = cov - &cg * chol.solve(&cg.transpose());
    let cov_after = prior.stretch * curv_after * prior.stretch.transpose();
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
    use rand::{Rng, SeedableRng};

    /// One parameter, one figure y = ln θ, one observation z = ln θ + e: the posterior
    /// variance is the harmonic combination 1/(1/c + 1/σ²), the D gain ½·ln(1 + c/σ²).
    #[test]
    fn one_parameter_combines_as_a_harmonic_mean() {
        let (c, s) = (0.04, 0.1);
        let cov = DMatrix::from_element(1, 1, c);
        let g = DMatrix::from_element(1, 1, 1.0);
        let id = DMatrix::identity(1, 1);
        let prior = Prior {
            curvature: &cov,
            stretch: &id,
        };
        let e = expected(&prior, &g, &[s], &g).unwrap();
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
        let id = DMatrix::identity(2, 2);
        let prior = Prior {
            curvature: &cov,
            stretch: &id,
        };
        let e = expected(&prior, &g, &[s], &targets).unwrap();
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

    /// A random symmetric positive definite n × n matrix: B·Bᵀ + n·I·0.01, B uniform in ±1.
    fn random_spd(rng: &mut impl rand::Rng, n: usize) -> DMatrix<f64> {
        let b = DMatrix::from_fn(n, n, |_, _| rng.random_range(-1.0..1.0));
        &b * b.transpose() + DMatrix::identity(n, n) * (0.01 * n as f64)
    }

    /// The update of (C_c, A) by G, Σ against A·(C_c⁻¹ + GᵀΣ⁻¹G)⁻¹·Aᵀ by direct inversion:
    /// C' and each target row's gᵀC'g agree to 1e-10 of C'; returns the update and C'.
    fn against_direct_inverse(
        c_c: &DMatrix<f64>,
        a: &DMatrix<f64>,
        g: &DMatrix<f64>,
        sigma: &[f64],
        targets: &DMatrix<f64>,
    ) -> (Expected, DMatrix<f64>) {
        let prior = Prior {
            curvature: c_c,
            stretch: a,
        };
        let e = expected(&prior, g, sigma, targets).unwrap();
        let w = DMatrix::from_diagonal(&DVector::from_iterator(
            sigma.len(),
            sigma.iter().map(|s| 1.0 / (s * s)),
        ));
        let info = c_c.clone().try_inverse().unwrap() + g.transpose() * w * g;
        let want = a * info.try_inverse().unwrap() * a.transpose();
        let scale = want.abs().max();
        let diff = (&e.cov_after - &want).abs().max();
        assert!(diff < 1e-10 * scale, "{}\n{want}", e.cov_after);
        for (i, v) in variances(&want, targets).iter().enumerate() {
            assert!((e.var_after[i] - v).abs() < 1e-10 * scale, "{i}");
        }
        (e, want)
    }

    /// With A = D diagonal (each parameter stretched alone, as the former update took it),
    /// the update is the former closed form C' = D·(C_c⁻¹ + GᵀΣ⁻¹G)⁻¹·D, by direct inversion
    /// and as the former code made it (C = D·C_c·D updated by G·D⁻¹), and the D gain ½·ln(det C/det C') is the same as without the stretch.
    #[test]
    fn a_diagonal_stretch_gives_the_former_update() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let c_c = random_spd(&mut rng, 4) * 0.01;
        let d = DMatrix::from_diagonal(&DVector::from_vec(vec![2.0, 1.0, 1.5, 0.8]));
        let g = DMatrix::from_fn(2, 4, |_, _| rng.random_range(-1.0..1.0));
        let sigma = [0.05, 0.1];
        let (e, want) = against_direct_inverse(&c_c, &d, &g, &sigma, &DMatrix::identity(4, 4));
        let before = &d * &c_c * &d;
        // The former code's path: the plain update of C = D·C_c·D by the sensitivities G·D⁻¹.
        let g_scaled = &g * d.clone().try_inverse().unwrap();
        let id = DMatrix::identity(4, 4);
        let former = Prior {
            curvature: &before,
            stretch: &id,
        };
        let f = expected(&former, &g_scaled, &sigma, &id).unwrap();
        assert!((&f.cov_after - &e.cov_after).abs().max() < 1e-10 * want.abs().max());
        let gain = 0.5 * (before.determinant() / want.determinant()).ln();
        assert!(
            (e.d_gain_nats - gain).abs() < 1e-9,
            "{} vs {gain}",
            e.d_gain_nats
        );
    }

    /// On a random SPD C_c, a full stretch A and three observables, the Woodbury form
    /// equals A·(C_c⁻¹ + GᵀΣ⁻¹G)⁻¹·Aᵀ by direct inversion, and the targets' variances after
    /// are gᵀC'g.
    #[test]
    fn woodbury_equals_the_direct_inverse_on_a_random_case() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let n = 6;
        let c_c = random_spd(&mut rng, n) * 0.02;
        let a =
            DMatrix::identity(n, n) + DMatrix::from_fn(n, n, |_, _| rng.random_range(-0.3..0.3));
        let g = DMatrix::from_fn(3, n, |_, _| rng.random_range(-2.0..2.0));
        let sigma = [0.02, 0.07, 0.3];
        let targets = DMatrix::from_fn(2, n, |_, _| rng.random_range(-1.0..1.0));
        against_direct_inverse(&c_c, &a, &g, &sigma, &targets);
    }
}
