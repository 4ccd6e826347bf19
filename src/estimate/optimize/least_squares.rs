//! Levenberg–Marquardt for χ² = ‖r(θ)‖² (Marquardt 1963, with Nielsen's damping update):
//! the polish of a maximum-likelihood point and the inner fits of a profile, where the
//! objective is a sum of squared normalised residuals and its valley can be a thousand times
//! narrower than a Nelder–Mead simplex starts.
//!
//! Each iteration solves (JᵀJ + μ·diag(JᵀJ))·δ = −Jᵀr (Marquardt's scaling, μ starting at
//! 1e-3) with J by forward differences of step `H` = 1e-3 in each coordinate (θ is logarithmic or
//! logistic, so that is a relative change), accepts δ when χ² falls, and adapts μ by the
//! gain ratio ρ = (χ²_old − χ²_new)/(predicted fall): μ·max(1/3, 1 − (2ρ − 1)³) on success,
//! μ·ν (ν doubling) on failure. It stops when a step lowers χ², or the linear model predicts
//! that it would, by less than `tol` (absolute, in χ² units: far below the 3.84 of a 95%
//! interval), or after `max_iters` iterations. A residual vector that cannot be computed
//! (a failed simulation) counts as an infinite χ²: the step is refused.

use nalgebra::{DMatrix, DVector};

/// Finite-difference step in θ: a relative change of 1e-3, a secant rather than a tangent
/// where a residual is steep (a row at the ramp's breakaway), and far above the solver's
/// jitter (χ² moves by a few hundredths between neighbouring points of an adaptive-step
/// simulation at rtol 3e-7).
const H: f64 = 1e-3;

/// When Levenberg–Marquardt stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct LmSettings {
    /// Most iterations (each costs the residual evaluation of its trial step, plus k for the
    /// Jacobian at a new point after an accepted one).
    pub max_iters: usize,
    /// Stop when an accepted step lowers χ² by less than this plus `rel_tol`·χ².
    pub tol: f64,
    /// See `tol` (0: an absolute tolerance).
    pub rel_tol: f64,
    /// Largest change of any coordinate in one step: a longer step is shortened along its
    /// direction (∞: never). θ is logistic at the bounds, where a step of hundreds lands on
    /// a plateau whose zero gradient looks like convergence.
    pub max_step: f64,
}

impl Default for LmSettings {
    fn default() -> Self {
        Self {
            max_iters: 30,
            tol: 0.02,
            rel_tol: 0.0,
            max_step: f64::INFINITY,
        }
    }
}

pub(crate) fn chi2(r: &[f64]) -> f64 {
    r.iter().map(|v| v * v).sum()
}

/// Forward-difference Jacobian of `f` at `x` (rows: residuals), `None` if any column fails.
fn jacobian(f: &dyn Fn(&[f64]) -> Option<Vec<f64>>, x: &[f64], r0: &[f64]) -> Option<DMatrix<f64>> {
    let mut j = DMatrix::zeros(r0.len(), x.len());
    let mut xp = x.to_vec();
    for c in 0..x.len() {
        xp[c] = x[c] + H;
        let r = f(&xp)?;
        xp[c] = x[c];
        if r.len() != r0.len() {
            return None;
        }
        for (i, (a, b)) in r.iter().zip(r0).enumerate() {
            j[(i, c)] = (a - b) / H;
        }
    }
    Some(j)
}

/// Minimises ‖f(x)‖² from `x0`; returns the best point and its χ² (`x0` and its χ², or ∞,
/// when no step helps).
pub(crate) fn levenberg_marquardt(
    f: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    x0: &[f64],
    settings: LmSettings,
) -> (Vec<f64>, f64) {
    let out = levenberg_marquardt_run(f, x0, settings);
    (out.x, out.chi2)
}

/// Where a Levenberg–Marquardt run ended.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LmOutcome {
    /// The best point.
    pub x: Vec<f64>,
    /// Its χ² (∞ when `f` fails at the start).
    pub chi2: f64,
    /// It stopped by its tolerance (an accepted step, or the linear model's prediction,
    /// below `tol`), not by the iteration budget, a failed Jacobian or a singular system.
    pub converged: bool,
}

/// [`levenberg_marquardt`], telling also whether it converged.
pub(crate) fn levenberg_marquardt_run(
    f: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    x0: &[f64],
    settings: LmSettings,
) -> LmOutcome {
    let Some(r0) = f(x0) else {
        return LmOutcome {
            x: x0.to_vec(),
            chi2: f64::INFINITY,
            converged: false,
        };
    };
    levenberg_marquardt_from(f, x0, r0, settings)
}

/// [`levenberg_marquardt_run`] from `x0` whose residuals `r0 = f(x0)` the caller has.
pub(crate) fn levenberg_marquardt_from(
    f: &dyn Fn(&[f64]) -> Option<Vec<f64>>,
    x0: &[f64],
    mut r: Vec<f64>,
    settings: LmSettings,
) -> LmOutcome {
    let mut x = x0.to_vec();
    let mut c = chi2(&r);
    if x.is_empty() {
        return LmOutcome {
            x,
            chi2: c,
            converged: true,
        };
    }
    let mut converged = false;
    let (mut mu, mut nu): (Option<f64>, f64) = (None, 2.0);
    // J, JᵀJ and Jᵀr at x. A refused step leaves x, so they are kept and only μ grows: a
    // refusal costs one simulation instead of k + 1 (the same J, formed again from the same
    // points, would be the same bit for bit).
    let mut at_x: Option<(DMatrix<f64>, DMatrix<f64>, DVector<f64>)> = None;
    for _ in 0..settings.max_iters {
        let (j, jtj, g) = match at_x {
            Some(ref kept) => kept,
            None => {
                let Some(j) = jacobian(f, &x, &r) else { break };
                let jtj = j.transpose() * &j;
                let g = j.transpose() * DVector::from_column_slice(&r);
                &*at_x.insert((j, jtj, g))
            }
        };
        let m = *mu.get_or_insert(1e-3);
        let mut a = jtj.clone();
        for i in 0..x.len() {
            a[(i, i)] += m * jtj[(i, i)].max(1e-12);
        }
        let Some(mut delta) = a.lu().solve(&(-g)) else {
            break;
        };
        let longest = delta.amax();
        if longest > settings.max_step {
            delta *= settings.max_step / longest;
        }
        let trial: Vec<f64> = x.iter().zip(delta.iter()).map(|(a, b)| a + b).collect();
        let predicted = -(delta.dot(g) * 2.0 + (j * &delta).norm_squared());
        let tol = settings.tol + settings.rel_tol * c;
        if predicted < tol {
            // The linear model sees no gain worth a simulation: converged.
            converged = true;
            break;
        }
        match f(&trial).map(|rt| (chi2(&rt), rt)) {
            Some((ct, rt)) if ct < c => {
                let rho = (c - ct) / predicted.max(f64::MIN_POSITIVE);
                mu = Some(m * (1.0f64 / 3.0).max(1.0 - (2.0 * rho - 1.0).powi(3)));
                nu = 2.0;
                let gain = c - ct;
                (x, r, c) = (trial, rt, ct);
                at_x = None;
                if gain < tol {
                    converged = true;
                    break;
                }
            }
            _ => {
                mu = Some(m * nu);
                nu *= 2.0;
            }
        }
    }
    LmOutcome {
        x,
        chi2: c,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock as residuals (10(y − x²), 1 − x): the minimum 0 at (1, 1) from (−1.2, 1).
    #[test]
    fn rosenbrock_residuals_reach_the_minimum() {
        let f = |p: &[f64]| Some(vec![10.0 * (p[1] - p[0] * p[0]), 1.0 - p[0]]);
        let (x, c) = levenberg_marquardt(
            &f,
            &[-1.2, 1.0],
            LmSettings {
                max_iters: 200,
                tol: 0.0,
                rel_tol: 0.0,
                max_step: f64::INFINITY,
            },
        );
        assert!(c < 1e-12, "{c} at {x:?}");
        assert!(
            (x[0] - 1.0).abs() < 1e-5 && (x[1] - 1.0).abs() < 1e-5,
            "{x:?}"
        );
    }

    /// A refused step leaves x, so its Jacobian is not formed again: no point is simulated
    /// twice. The residuals fail (a failed simulation) beyond x₀ = 0.5, where the nearly
    /// Gauss–Newton steps towards the minimum at (2, 2) land, so steps are refused until μ
    /// has grown enough.
    #[test]
    fn a_refused_step_costs_only_its_trial() {
        let seen = std::cell::RefCell::new(Vec::<Vec<f64>>::new());
        let refused = std::cell::Cell::new(0);
        let f = |p: &[f64]| {
            seen.borrow_mut().push(p.to_vec());
            if p[0] > 0.5 {
                refused.set(refused.get() + 1);
                return None;
            }
            Some(vec![p[0] - 2.0, 3.0 * (p[1] - 2.0)])
        };
        let out = levenberg_marquardt_run(&f, &[0.0, 0.0], LmSettings::default());
        assert!(refused.get() >= 2, "{} refusals", refused.get());
        // It went down towards the minimum from χ² = 40, never into the failing region.
        assert!(out.x[0] <= 0.5 && out.chi2 < 40.0, "{out:?}");
        let points = seen.into_inner();
        for (i, p) in points.iter().enumerate() {
            assert!(
                !points[..i].contains(p),
                "{p:?} simulated again (call {i} of {})",
                points.len()
            );
        }
    }

    /// A linear least-squares problem is solved in one or two steps to its closed form.
    #[test]
    fn linear_fit_matches_the_normal_equations() {
        let t = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y = [1.1, 2.9, 5.2, 7.1, 8.8];
        let f = |p: &[f64]| Some(t.iter().zip(&y).map(|(t, y)| p[0] + p[1] * t - y).collect());
        let tight = LmSettings {
            max_iters: 50,
            tol: 1e-14,
            rel_tol: 0.0,
            max_step: f64::INFINITY,
        };
        let (x, _) = levenberg_marquardt(&f, &[0.0, 0.0], tight);
        // Closed form: slope = Sxy/Sxx, intercept = ȳ − slope·t̄.
        let (tm, ym) = (2.0, (1.1 + 2.9 + 5.2 + 7.1 + 8.8) / 5.0);
        let sxy: f64 = t.iter().zip(&y).map(|(t, y)| (t - tm) * (y - ym)).sum();
        let slope = sxy / 10.0;
        assert!((x[1] - slope).abs() < 1e-6, "{x:?}");
        assert!((x[0] - (ym - slope * tm)).abs() < 1e-6, "{x:?}");
    }

    /// Where the residuals cannot be computed the point is kept.
    #[test]
    fn failing_residuals_leave_the_start() {
        let f = |p: &[f64]| (p[0] < 0.5).then(|| vec![p[0] - 1.0]);
        let (x, c) = levenberg_marquardt(&f, &[0.0], LmSettings::default());
        assert!(x[0] < 0.5 && c.is_finite());
    }
}
