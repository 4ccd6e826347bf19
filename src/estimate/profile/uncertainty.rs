//! Parameter uncertainty: 95% intervals by profile likelihood, with a curvature
//! (Gauss–Newton) estimate as the faster fallback, and a check of identifiability.
//!
//! Both use χ² = Σ (simulation − reference)²/σ² over the data points, which is −2·log L up
//! to a constant when the reference is the least-squares polynomial of the data (the data's
//! residuals about the polynomial are orthogonal to it, so differences of χ² against the
//! polynomial equal differences against the data). The 95% profile interval of parameter j
//! is where min over the others of χ² rises by χ²₁(0.95) = 3.841 above its minimum; when the
//! model misses the data by more than their noise (χ²/dof > 1) that threshold is scaled by
//! χ²/dof (Birge's ratio, as curve fitting does with `absolute_sigma = False`), so that the
//! interval of a model that misses is not narrower than its scatter warrants.
//!
//! A parameter is called identifiable only when its profile closes on both sides AND no
//! other local optimum the multi-start found fits as well (within the threshold) with the
//! parameter outside the interval: a profile explores one valley only.

use crate::estimate::engine::Engine;
use crate::estimate::optimize::least_squares::{levenberg_marquardt, LmSettings};
use crate::estimate::optimize::local::polish_residuals;
use crate::estimate::optimize::nelder_mead::{
    Layout, NelderMeadSettings, Restart, RestartedNelderMead,
};
use crate::estimate::problem::derivatives::{central_column, hessian};
use crate::estimate::problem::objective::{Coordinates, Problem, Profiled};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// χ²₁ quantile at 95%.
pub const CHI2_95: f64 = 3.841_458_820_694_124;
/// Step in θ of the curvature's central differences ([`curvature_covariance`]), for
/// `vanefit fit` and the diagnosis's extended model alike.
pub(crate) const CURVATURE_STEP: f64 = 1e-3;
/// Iteration cap of a profile point's Nelder–Mead refit (a likelihood's points are refitted
/// by Levenberg–Marquardt instead), for `vanefit fit` and the diagnosis alike.
pub(crate) const PROFILE_ITERS: u64 = 300;
/// Where, as fractions of the way from the estimate to an interval's end, a profile is
/// evaluated once more for its path.
const PATH_FRACTIONS: [f64; 3] = [0.3, 0.7, 1.4];
/// Beyond this |θ| the logistic map is at its bound to 1 part in 3e6.
const THETA_EDGE: f64 = 15.0;

/// How an interval was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Method {
    /// Profile likelihood.
    Profile,
    /// Curvature of χ² at the optimum.
    Curvature,
}

/// A 95% interval of one parameter, SI. A side is `None` where χ² never rose enough
/// before the search bound: the data do not pin the parameter down on that side.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Interval {
    /// Parameter name.
    pub name: String,
    /// Estimate, SI.
    pub value: f64,
    /// Lower end, SI (`None`: open).
    pub lo: Option<f64>,
    /// Upper end, SI (`None`: open).
    pub hi: Option<f64>,
    /// How it was obtained.
    pub method: Method,
    /// Another local optimum, as good within the threshold, puts the parameter here (SI),
    /// outside the interval.
    pub(crate) other_optimum: Option<f64>,
    /// The profile's points in increasing value, the estimate (Δχ² = 0) among them; empty
    /// for a curvature interval.
    pub path: Vec<ProfilePoint>,
}

/// One point of a likelihood profile: the parameter held at `value` (SI), every other
/// estimated parameter re-optimised, and the rise of χ² there above its minimum,
/// Δχ² = χ²(value) − χ²_min (the pyPESTO profile's `fval_path` less its minimum; its
/// likelihood ratio is exp(−Δχ²/2)).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ProfilePoint {
    /// The parameter's value, SI.
    pub value: f64,
    /// χ² − χ²_min with the others re-optimised.
    pub delta_chi2: f64,
}

impl Interval {
    /// Both sides are pinned down and no other optimum competes.
    pub fn identifiable(&self) -> bool {
        self.lo.is_some() && self.hi.is_some() && self.other_optimum.is_none()
    }

    /// Why the parameter is not identifiable, in words (`None` when it is).
    pub(crate) fn why_not(&self) -> Option<String> {
        match (self.lo, self.hi, self.other_optimum) {
            (None, None, _) => Some("the data bound it on neither side".into()),
            (None, Some(_), _) => Some("the data do not bound it from below".into()),
            (Some(_), None, _) => Some("the data do not bound it from above".into()),
            (_, _, Some(v)) => Some(format!(
                "another optimum fits as well with {} = {v:.4e}",
                self.name
            )),
            _ => None,
        }
    }
    /// `[lo, hi]` when identifiable.
    pub fn ci95(&self) -> Option<[f64; 2]> {
        Some([self.lo?, self.hi?])
    }
}

/// The profile polish: one Nelder–Mead simplex (argmin's coefficients) on a forward axis
/// simplex of edge 0.05, converged when the costs' spread is below 1e-9.
const POLISH: NelderMeadSettings = NelderMeadSettings {
    sd_tolerance: 1e-9,
    step: 0.05,
    layout: Layout::Forward,
    adaptive: false,
    restart: Restart::Never,
};

/// Minimises the profiled χ² from `start`: by Levenberg–Marquardt where the objective has
/// residuals (a likelihood), otherwise by Nelder–Mead in at most `max_iters` iterations;
/// (start, ∞) if the optimizer fails.
fn polish<C: Coordinates + ?Sized>(
    problem: Profiled<'_, C>,
    start: Vec<f64>,
    max_iters: u64,
) -> (Vec<f64>, f64) {
    let residuals = |free: &[f64]| problem.inner.residuals(&problem.full(free));
    if problem.use_chi2 && residuals(&start).is_some() {
        return levenberg_marquardt(&residuals, &start, LmSettings::default());
    }
    if start.is_empty() {
        let c = argmin::core::CostFunction::cost(&problem, &start).unwrap_or(f64::INFINITY);
        return (start, c);
    }
    let mut search = RestartedNelderMead::new(start, f64::INFINITY, POLISH);
    search.advance(&problem, max_iters);
    (search.x().to_vec(), search.cost())
}

/// Minimises χ² from θ (a short polish after a cost fit whose weights differ from χ²'s).
pub fn polish_chi2(problem: &Problem<'_>, theta: &[f64], max_iters: u64) -> (Vec<f64>, f64) {
    if let Some(polished) = polish_residuals(problem, theta) {
        return polished;
    }
    let all: Vec<usize> = (0..theta.len()).collect();
    let p = Profiled {
        inner: problem,
        template: theta.to_vec(),
        free: all.clone(),
        use_chi2: true,
    };
    let start0 = problem.evaluate(theta).chi2;
    let (t, c) = polish(p, theta.to_vec(), max_iters);
    if c <= start0 {
        (t, c)
    } else {
        (theta.to_vec(), start0)
    }
}

/// Covariance of θ from the curvature of χ²: Σ = 2·s²·H⁻¹ with s² the threshold's scale (1,
/// or χ²/dof when the model misses). H is the Gauss–Newton curvature 2·JᵀJ of χ² = Σ r²,
/// J = ∂r/∂θ by central differences of the residual vector (step `h`), so Σ = s²·(JᵀJ)⁻¹.
/// The full second differences of χ² (the fallback, for an objective without residuals or
/// a residual vector that cannot be computed at a step) divide the solver's jitter by h²
/// and, at the estimate, by the tiny rise of χ² over one step: on twin data their
/// correlations moved from run to run with rounding-level changes of the ODE solver, and one
/// fit's H came out indefinite (twin seed 2 of the coverage test); first differences of the
/// residuals divide the jitter by h only, and JᵀJ is positive semi-definite by
/// construction. The term the Gauss–Newton form drops, Σ r·∇²r, averages out where the
/// residuals are the data's noise. A coordinate the residuals do not move at all (JᵀJ's
/// diagonal 0 to rounding: a parameter pinned to a bound of the search, where the logistic
/// coordinate's slope vanishes) has no variance and leaves the others' covariance to the
/// rest (`inverse_over_informed`). `None` when the curvature is otherwise not positive
/// definite (a flat or ill-posed direction).
pub fn curvature_covariance<C: Coordinates + ?Sized>(
    problem: &Problem<'_, C>,
    theta: &[f64],
    h: f64,
    scale2: f64,
) -> Option<DMatrix<f64>> {
    if let Some(jtj) = gauss_newton_curvature(problem, theta, h) {
        return inverse_over_informed(&jtj).map(|c| c * scale2);
    }
    let chi2 = |t: &[f64]| problem.evaluate(t).chi2;
    let hess = hessian(&chi2, theta, chi2(theta), h);
    let chol = hess.cholesky()?;
    Some(chol.inverse() * (2.0 * scale2))
}

/// Below this fraction of JᵀJ's largest diagonal entry a coordinate counts as one the
/// residuals do not move (a saturated logistic coordinate gives exactly 0).
const UNINFORMED: f64 = 1e-12;

/// (JᵀJ)⁻¹, or where JᵀJ is singular because coordinates have a zero diagonal (the
/// residuals do not depend on them), the inverse over the others with zero rows and columns
/// for those: their variance is unknown, and the others' covariance is that of the fit with
/// them held where they are. Without it, one parameter on a bound (a page's `b_crit` at 0.6)
/// took the whole covariance away, and `predict` fell back to independent parameters with
/// bands several times wider (docs/plan.md). `None` when what remains is not positive
/// definite.
fn inverse_over_informed(jtj: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if let Some(c) = jtj.clone().cholesky() {
        return Some(c.inverse());
    }
    let top = jtj.diagonal().max();
    let keep: Vec<usize> = (0..jtj.nrows())
        .filter(|&i| jtj[(i, i)] > UNINFORMED * top)
        .collect();
    if keep.len() == jtj.nrows() || keep.is_empty() {
        return None;
    }
    let sub = DMatrix::from_fn(keep.len(), keep.len(), |a, b| jtj[(keep[a], keep[b])]);
    let inv = sub.cholesky()?.inverse();
    let mut out = DMatrix::zeros(jtj.nrows(), jtj.ncols());
    for (a, &i) in keep.iter().enumerate() {
        for (b, &j) in keep.iter().enumerate() {
            out[(i, j)] = inv[(a, b)];
        }
    }
    Some(out)
}

/// JᵀJ of the residual vector at θ, J by central differences of step `h`; `None` when the
/// objective has no residuals or one of them cannot be computed.
fn gauss_newton_curvature<C: Coordinates + ?Sized>(
    problem: &Problem<'_, C>,
    theta: &[f64],
    h: f64,
) -> Option<DMatrix<f64>> {
    let n = problem.residuals(theta)?.len();
    let k = theta.len();
    let mut jac = DMatrix::<f64>::zeros(n, k);
    for j in 0..k {
        let at = |d: f64| {
            let mut t = theta.to_vec();
            t[j] += d;
            problem.residuals(&t).filter(|r| r.len() == n)
        };
        let column = central_column(&at(h)?, &at(-h)?, 2.0 * h);
        jac.set_column(j, &DVector::from_vec(column));
    }
    Some(jac.tr_mul(&jac))
}

/// Intervals from the curvature: θ̂ ± 1.96·σ_θ, mapped back through the transforms
/// (so positive parameters get intervals that are symmetric on a log scale).
pub fn curvature_intervals<C: Coordinates + ?Sized>(
    problem: &Problem<'_, C>,
    theta: &[f64],
    cov: Option<&DMatrix<f64>>,
) -> Vec<Interval> {
    let space = problem.space;
    (0..theta.len())
        .map(|j| {
            let sd = cov
                .map(|c| c[(j, j)])
                .filter(|v| v.is_finite() && *v > 0.0)
                .map(f64::sqrt);
            let within = |t: f64| (t.abs() < THETA_EDGE).then(|| space.coordinate_value(j, t));
            Interval {
                name: space.coordinate_name(j),
                value: space.coordinate_value(j, theta[j]),
                lo: sd.and_then(|s| within(theta[j] - 1.96 * s)),
                hi: sd.and_then(|s| within(theta[j] + 1.96 * s)),
                method: Method::Curvature,
                other_optimum: None,
                path: Vec::new(),
            }
        })
        .collect()
}

/// Profile of χ² along coordinate j: re-optimises the others at θ_j = t.
struct Profile<'a, C: Coordinates + ?Sized> {
    problem: &'a Problem<'a, C>,
    j: usize,
    others: Vec<usize>,
    max_iters: u64,
    /// Rise of χ² that ends the interval.
    threshold: f64,
    /// Σ_ij/Σ_jj for every coordinate i (from the curvature covariance): how the others'
    /// optimum moves with θ_j near the optimum, so each profile point starts on the valley.
    slope: Option<Vec<f64>>,
}

impl<C: Coordinates + ?Sized> Profile<'_, C> {
    /// The profile at θ_j = t: the others re-optimised from the valley predicted from the
    /// last profile point `base`.
    fn at(&self, base: &[f64], t: f64) -> (Vec<f64>, f64) {
        let mut template = base.to_vec();
        template[self.j] = t;
        let dt = t - base[self.j];
        let start: Vec<f64> = self
            .others
            .iter()
            .map(|i| base[*i] + self.slope.as_ref().map_or(0.0, |s| s[*i] * dt))
            .collect();
        let p = Profiled {
            inner: self.problem,
            template: template.clone(),
            free: self.others.clone(),
            use_chi2: true,
        };
        let (free, c) = polish(p, start, self.max_iters);
        for (i, v) in self.others.iter().zip(&free) {
            template[*i] = *v;
        }
        (template, c)
    }

    /// Where the profile crosses χ²_min + threshold on one side (`dir` = ±1), in θ_j, and
    /// every point it evaluated on the way as (θ_j, Δχ²).
    fn crossing(
        &self,
        theta_hat: &[f64],
        chi2_min: f64,
        dir: f64,
        step0: f64,
    ) -> (Option<f64>, Vec<(f64, f64)>) {
        let mut path = Vec::new();
        let end = self.walk(theta_hat, chi2_min, dir, step0, &mut path);
        if let Some(e) = end {
            // The search itself evaluates few points, most near the crossing or far beyond
            // it: a few more draw the profile's shape (√Δχ² is near linear in θ, so these
            // fall near Δχ² = 0.1, 0.5 and 2 thresholds).
            let t0 = theta_hat[self.j];
            for f in PATH_FRACTIONS {
                let t = t0 + f * (e - t0);
                let (_, c) = self.at(theta_hat, t);
                path.push((t, c - chi2_min));
            }
        }
        (end, path)
    }

    /// [`Profile::crossing`]'s search, pushing each evaluated point onto `path`.
    fn walk(
        &self,
        theta_hat: &[f64],
        chi2_min: f64,
        dir: f64,
        step0: f64,
        path: &mut Vec<(f64, f64)>,
    ) -> Option<f64> {
        let t0 = theta_hat[self.j];
        let (mut t_in, mut d_in): (f64, f64) = (t0, 0.0);
        let mut base = theta_hat.to_vec();
        let mut step = step0;
        loop {
            let t = t0 + dir * step;
            if t.abs() > THETA_EDGE {
                return None;
            }
            let (b, c) = self.at(&base, t);
            let delta = c - chi2_min;
            path.push((t, delta));
            if delta >= self.threshold {
                // √Δ is close to linear in θ near the optimum: interpolate it, then refine once.
                let mut t_out = t;
                let mut d_out = delta;
                for _ in 0..2 {
                    let (a, z) = (d_in.max(0.0).sqrt(), d_out.sqrt());
                    let tc = t_in + (self.threshold.sqrt() - a) / (z - a) * (t_out - t_in);
                    let (_, cc) = self.at(&b, tc);
                    let dc = cc - chi2_min;
                    path.push((tc, dc));
                    if (dc - self.threshold).abs() < 0.05 {
                        return Some(tc);
                    }
                    if dc < self.threshold {
                        t_in = tc;
                        d_in = dc;
                    } else {
                        t_out = tc;
                        d_out = dc;
                    }
                }
                let (a, z) = (d_in.max(0.0).sqrt(), d_out.sqrt());
                return Some(t_in + (self.threshold.sqrt() - a) / (z - a) * (t_out - t_in));
            }
            t_in = t;
            d_in = delta;
            base = b;
            step *= 2.0;
        }
    }
}

/// Profile-likelihood intervals for every estimated parameter (in parallel), starting from
/// the χ² optimum `theta_hat`, ending where χ² rises by `threshold`, and using the curvature
/// covariance (if any) to size steps.
pub fn profile_intervals<C: Coordinates + ?Sized>(
    engine: &Engine,
    problem: &Problem<'_, C>,
    theta_hat: &[f64],
    chi2_min: f64,
    threshold: f64,
    cov: Option<&DMatrix<f64>>,
    max_iters: u64,
) -> Vec<Interval> {
    let sides = ProfileSides {
        max_iters,
        on_side: &|_| {},
    };
    profile_intervals_observed(engine, problem, theta_hat, chi2_min, threshold, cov, &sides)
}

/// How [`profile_intervals_observed`] runs: the iteration cap of each side and a callback
/// told how many of the 2k sides are done (progress of a long fit).
pub(crate) struct ProfileSides<'a> {
    /// Iteration cap of each profile's inner fits.
    pub max_iters: u64,
    /// Called with the number of finished sides after each side.
    pub(crate) on_side: &'a (dyn Fn(usize) + Sync),
}

/// [`profile_intervals`], reporting each finished side to `sides.on_side`.
pub(crate) fn profile_intervals_observed<C: Coordinates + ?Sized>(
    engine: &Engine,
    problem: &Problem<'_, C>,
    theta_hat: &[f64],
    chi2_min: f64,
    threshold: f64,
    cov: Option<&DMatrix<f64>>,
    run: &ProfileSides<'_>,
) -> Vec<Interval> {
    let max_iters = run.max_iters;
    let done = std::sync::atomic::AtomicUsize::new(0);
    let k = theta_hat.len();
    // One task per side of each profile: sixteen tasks balance two threads better than
    // eight whole profiles, whose costs differ.
    let sides: Vec<(usize, f64)> = (0..k).flat_map(|j| [(j, -1.0), (j, 1.0)]).collect();
    let ends = engine.map(&sides, |&(j, dir)| {
        let step = cov
            .map(|c| c[(j, j)])
            .filter(|v| v.is_finite() && *v > 0.0)
            .map_or(0.3, |v| v.sqrt().clamp(0.02, 2.0));
        let slope = cov
            .filter(|c| c[(j, j)].is_finite() && c[(j, j)] > 0.0)
            .map(|c| (0..k).map(|i| c[(i, j)] / c[(j, j)]).collect());
        let profile = Profile {
            problem,
            j,
            others: (0..k).filter(|i| *i != j).collect(),
            max_iters,
            threshold,
            slope,
        };
        let value = |t: f64| problem.space.coordinate_value(j, t);
        let (end, path) = profile.crossing(theta_hat, chi2_min, dir, step);
        let points: Vec<ProfilePoint> = path
            .into_iter()
            .filter(|(_, delta)| delta.is_finite())
            .map(|(t, delta)| ProfilePoint {
                value: value(t),
                delta_chi2: delta,
            })
            .collect();
        (run.on_side)(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
        (end.map(value), points)
    });
    (0..k)
        .map(|j| {
            let value = problem.space.coordinate_value(j, theta_hat[j]);
            let (lo, below) = &ends[2 * j];
            let (hi, above) = &ends[2 * j + 1];
            Interval {
                name: problem.space.coordinate_name(j),
                value,
                lo: *lo,
                hi: *hi,
                method: Method::Profile,
                other_optimum: None,
                path: profile_path(value, below, above),
            }
        })
        .collect()
}

/// The two sides' points and the estimate (Δχ² = 0) in increasing value. A side lists its
/// points in the order they were evaluated (the doubling search, its refinements, then the
/// path's extra points), so the whole is sorted once here.
fn profile_path(value: f64, below: &[ProfilePoint], above: &[ProfilePoint]) -> Vec<ProfilePoint> {
    let mut path: Vec<ProfilePoint> = below.to_vec();
    path.push(ProfilePoint {
        value,
        delta_chi2: 0.0,
    });
    path.extend_from_slice(above);
    path.sort_by(|a, b| a.value.total_cmp(&b.value));
    path
}

#[cfg(test)]
mod tests {
    use super::*;

    /// JᵀJ of two informed coordinates and a third the residuals do not move: the
    /// covariance of the first two is the inverse of their 2×2 block (the fit with the third
    /// held), the third has none; a regular JᵀJ is simply inverted.
    #[test]
    fn a_coordinate_the_residuals_ignore_leaves_the_others_covariance() {
        let jtj = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0]);
        let c = inverse_over_informed(&jtj).unwrap();
        let det = 4.0 * 2.0 - 1.0;
        let want = [[2.0 / det, -1.0 / det], [-1.0 / det, 4.0 / det]];
        for a in 0..2 {
            for b in 0..2 {
                assert!((c[(a, b)] - want[a][b]).abs() < 1e-15, "{c}");
            }
            assert_eq!(c[(a, 2)], 0.0);
            assert_eq!(c[(2, a)], 0.0);
        }
        assert_eq!(c[(2, 2)], 0.0);
        let regular = DMatrix::from_row_slice(2, 2, &[4.0, 1.0, 1.0, 2.0]);
        let inv = inverse_over_informed(&regular).unwrap();
        assert!((&inv * &regular - DMatrix::identity(2, 2)).abs().max() < 1e-15);
        // Singular among the informed ones: no covariance.
        let flat = DMatrix::from_row_slice(2, 2, &[1.0, 1.0, 1.0, 1.0]);
        assert!(inverse_over_informed(&flat).is_none());
    }
}
