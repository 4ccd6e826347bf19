//! The parameters' joint uncertainty as a prediction uses it, and its propagation to any
//! vector of predicted figures: the delta method (what `vanefit predict` reports) and a
//! Monte-Carlo check of it.
//!
//! # The parameters' distribution, as `predict`'s bands take it
//!
//! ln θ of the covered parameters is taken as normal, N(ln θ̂, C)
//! ([`ParamUncertainty::for_bands`]). C starts from the fit file's `covariance` C_c, the
//! curvature of the posterior's χ² at the estimate (prior included, in log space): the
//! Gaussian (Laplace) approximation of the posterior. It covers every estimated parameter
//! the covariance holds, those the profile found open (`"identifiable": false`, a page's
//! `b_crit`) too: their width is the curvature's, which their prior bounds, and a figure
//! that depends on them is traded against the parameters correlated with them (leaving one
//! out takes its marginal spread into the others' but drops that trade, and widened the
//! bands of the figures a page prints to several times their reading tolerance).
//!
//! Where a parameter's profile-likelihood `ci95` gives a marginal σ_j = (ln hi − ln lo)/(2·1.96)
//! other than the curvature's √C_jj (the likelihood is not quadratic along the profile),
//! the distribution is stretched along that parameter's profile path to it: the linear map
//! x ↦ x + (λ − 1)·x_j·C·e_j/C_jj, λ² = σ_j²/C_jj, which gives
//! C ← C + (λ² − 1)·C·e_j·e_jᵀ·C/C_jj. C·e_j/C_jj is how the others' optimum moves with θ_j
//! (the profile path of a Gaussian posterior), so the map moves every parameter along that
//! path and leaves the others' conditional distribution given θ_j as it was: what the data
//! pin stays pinned, and a figure's variance grows by (λ² − 1)·Cov(y, ln θ_j)²/C_jj, at most
//! λ² times. One such stretch changes the other diagonals a little, so they are repeated over
//! all parameters until every C_jj is σ_j² within 1e-9 (at most 200 sweeps; on the twin's
//! pages a few).
//!
//! Measured on 240 twin pages of six styles (docs/validation.md, "Bands as wide as the data
//! allow"): at the page's own pressure the printed figures' bands are about the page's
//! reading tolerance; the former C = S·R·S (the curvature's correlations R rescaled to the
//! profile widths S, non-identifiable parameters left out) made them 2–4 times that, since
//! rescaling each parameter alone breaks the cancellations along the directions the data
//! pin. [`ParamUncertainty::of`] keeps that construction for the posterior sampler's starts.
//!
//! Each stretch is a congruence C ← M·C·Mᵀ with M = I + (λ − 1)·C·e_j·e_jᵀ/C_jj, so the
//! result is C = A·C_c·Aᵀ, A the product of the M's ([`ParamUncertainty::stretch`]).
//! `vanefit plan` keeps A through its update (docs/plan.md): the inflation persists and a
//! measurement's information is added in the curvature's units,
//! C' = A·(C_c⁻¹ + GᵀΣ⁻¹G)⁻¹·Aᵀ.
//!
//! # S·R·S, and fits without a covariance
//!
//! [`ParamUncertainty::of`] takes C = S·R·S: R the correlation of the fit file's
//! `covariance`, and S = diag(σ_j) the marginal standard deviations, each from the
//! parameter's profile `ci95` where one exists, else from the covariance's own diagonal;
//! the parameters the profile found open are left out. A fit file without a covariance but
//! with intervals gives the parameters as independent (R = I), in both constructions;
//! without either there is no band.
//!
//! Not covered, and said so in every output: parameters held fixed in the fit, estimated
//! parameters that are not identifiable and not held by the covariance (all of them in
//! [`ParamUncertainty::of`]) or have no interval, and
//! the coefficients of discovered terms. With a stated spread F (`--fixed-spread`), the
//! parameters a fit could estimate (the six conductances, `t_coulomb`, `visc`) that were
//! held fixed or are not identifiable are covered too, independently, with
//! σ = ln F/1.96: a catalogue fit keeps them at defaults scaled to the displacement, which
//! are right to within such a factor at best.
//!
//! # Delta method
//!
//! For a figure y(ln θ), g_j = ∂y/∂ln θ_j by central differences of step h_j = σ_j (clamped
//! to [1e-4, 0.05]: one standard deviation probes the figure over the width the band is
//! about, and stays far above the steady solver's 1e-9 relative noise), Var y = gᵀ·C·g and
//! the band is y ± 1.96·√Var y (a 95 % band when y is close to linear over the parameters'
//! spread). A positive figure's band is propagated in log space, y·exp(∓1.96·√Var y/y): a
//! positive quantity has a positive band however wide, and for a narrow band the two agree
//! to second order.

use super::PredictError;
use crate::data::fitfile::FitFile;
use crate::estimate::problem::space::DEFAULT_ESTIMATED;
use crate::model::motor::Motor;
use crate::model::params::{MotorParams, ParamId, ParamSet};
use nalgebra::{DMatrix, DVector};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

/// The normal quantile of a two-sided 95 % band.
pub const Z95: f64 = 1.959_963_984_540_054;

/// Of one figure's variance: the share a set of parameters carries, and each parameter's
/// own share ([`ParamUncertainty::variance_shares`]).
pub type VarianceShares = (f64, Vec<f64>);

/// What the bands stand on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum BandBasis {
    /// The fit's covariance (correlations) with profile-interval widths.
    Covariance,
    /// The fit's curvature covariance, every parameter it holds, stretched along the
    /// profile paths to the profile intervals' widths ([`ParamUncertainty::for_bands`]).
    Stretched,
    /// The parameters' intervals taken as independent: the fit file has no covariance.
    Independent,
    /// Only the stated spread of the fixed parameters: the fit gives no usable uncertainty.
    SpreadOnly,
    /// No band: the fit file has neither covariance nor intervals.
    None,
}

impl BandBasis {
    /// The basis in words, for notes.
    pub fn describe(self) -> &'static str {
        match self {
            BandBasis::Covariance => {
                "95 % bands by the delta method from the fit's covariance of the log-parameters \
                 (correlations of the curvature, widths of the profile intervals)"
            }
            BandBasis::Stretched => {
                "95 % bands by the delta method from the fit's covariance of the log-parameters \
                 (the curvature of the posterior, stretched along each parameter's profile to \
                 its profile interval)"
            }
            BandBasis::Independent => {
                "95 % bands by the delta method with the parameters taken as INDEPENDENT: the \
                 fit file has intervals but no covariance, so correlations are ignored"
            }
            BandBasis::SpreadOnly => {
                "95 % bands by the delta method from the stated spread of the fixed parameters \
                 only: the fit file gives no usable covariance or intervals"
            }
            BandBasis::None => "no bands: the fit file has neither a covariance nor intervals",
        }
    }
}

/// The covered parameters' distribution, and what it leaves out.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamUncertainty {
    /// What the bands stand on.
    pub basis: BandBasis,
    /// The covered parameters, in the matrix's order.
    pub names: Vec<String>,
    /// ln θ̂ of each covered parameter.
    pub log_values: Vec<f64>,
    /// Marginal standard deviation σ_j of ln θ_j.
    pub sd: Vec<f64>,
    /// C, the covariance of ln θ the bands use: A·C_c·Aᵀ ([`Self::for_bands`]) or S·R·S
    /// ([`Self::of`]).
    pub cov: DMatrix<f64>,
    /// C_c: C before the stretch along the profile paths (the fit's curvature covariance,
    /// with the stated spread's variances on the diagonal); C itself for [`Self::of`].
    pub curvature: DMatrix<f64>,
    /// A, the product of the stretches (C = A·C_c·Aᵀ); the identity for [`Self::of`].
    /// `vanefit plan` keeps it through its update: C' = A·(C_c⁻¹ + GᵀΣ⁻¹G)⁻¹·Aᵀ.
    pub stretch: DMatrix<f64>,
    /// Estimated parameters the band does not cover, each with the reason.
    pub uncovered: Vec<(String, String)>,
    /// Parameters covered by the stated spread (held fixed or not identifiable).
    pub spread: Vec<String>,
    /// The spread factor F, when given.
    pub spread_factor: Option<f64>,
}

impl ParamUncertainty {
    /// The distribution `predict`'s delta bands stand on (the module documentation): the
    /// fit's curvature covariance over every estimated parameter it holds, stretched along
    /// each parameter's profile path to its profile interval's width; without a covariance,
    /// as [`Self::of`].
    pub fn for_bands(fit: &FitFile, spread: Option<f64>) -> Self {
        let mut u = Self::select(fit, spread, true);
        let Some(file) = &fit.covariance else {
            return u;
        };
        let at = |n: &str| file.parameters.iter().position(|m| m == n);
        let k = u.len();
        let fitted: Vec<Option<usize>> = u
            .names
            .iter()
            .map(|n| at(n).filter(|_| !u.spread.contains(n)))
            .collect();
        if fitted.iter().all(Option::is_none) {
            return u;
        }
        u.cov = DMatrix::from_fn(k, k, |a, b| match (fitted[a], fitted[b]) {
            (Some(i), Some(j)) => file.matrix[i][j],
            _ if a == b => u.sd[a] * u.sd[a],
            _ => 0.0,
        });
        let target: Vec<Option<f64>> = (0..k)
            .map(|a| {
                fitted[a]?;
                profile_sd(fit, &u.names[a]).map(|s| s * s)
            })
            .collect();
        u.curvature = u.cov.clone();
        u.stretch = stretch_to(&mut u.cov, &target);
        u.sd = (0..k).map(|a| u.cov[(a, a)].max(0.0).sqrt()).collect();
        u.basis = BandBasis::Stretched;
        u
    }

    /// The distribution with C = S·R·S (the module documentation's last section): the
    /// curvature's correlations with the profile intervals' widths, parameters the profile
    /// found open left out. `vanefit plan`'s update and the posterior sampler's starts stand
    /// on it.
    pub fn of(fit: &FitFile, spread: Option<f64>) -> Self {
        Self::select(fit, spread, false)
    }

    /// The covered parameters and C = S·R·S over them; with `open_too`, an estimated
    /// parameter the profile found open is covered where the covariance holds it.
    fn select(fit: &FitFile, spread: Option<f64>, open_too: bool) -> Self {
        let ci_sd = |n: &str| profile_sd(fit, n);
        let value = |n: &str| fit.params.get(n).filter(|v| *v > 0.0);
        let not_identifiable =
            |n: &str| fit.verdicts.iter().any(|v| v.name == n && !v.identifiable);
        let mut uncovered = Vec::new();
        let mut names = Vec::new();
        let mut sd = Vec::new();
        let mut source = Vec::new(); // index into the file's covariance, if any
        for n in &fit.estimated {
            let in_cov = fit
                .covariance
                .as_ref()
                .and_then(|c| c.parameters.iter().position(|m| m == n));
            let why = if not_identifiable(n) && !(open_too && in_cov.is_some()) {
                Some("not identifiable")
            } else if value(n).is_none() {
                Some("not positive (no logarithm)")
            } else if fit.covariance.is_some() && in_cov.is_none() {
                Some("not in the covariance")
            } else if in_cov.is_none() && ci_sd(n).is_none() {
                Some("no 95 % interval")
            } else {
                None
            };
            if let Some(why) = why {
                uncovered.push((n.clone(), why.to_string()));
                continue;
            }
            let m = fit.covariance.as_ref();
            let own = in_cov.and_then(|i| m.map(|c| c.matrix[i][i].sqrt()));
            names.push(n.clone());
            sd.push(ci_sd(n).or(own).unwrap_or(0.0));
            source.push(in_cov);
        }
        let covered_by_fit = names.len();
        let mut spread_names = Vec::new();
        if let Some(f) = spread {
            for n in DEFAULT_ESTIMATED {
                let held = !fit.estimated.iter().any(|m| m == n);
                let flat = uncovered.iter().any(|(m, _)| m == n);
                if (held || flat) && value(n).is_some() {
                    uncovered.retain(|(m, _)| m != n);
                    names.push(n.to_string());
                    sd.push(f.ln() / Z95);
                    source.push(None);
                    spread_names.push(n.to_string());
                }
            }
        }
        let k = names.len();
        let corr = |a: usize, b: usize| -> f64 {
            if a == b {
                return 1.0;
            }
            match (&fit.covariance, source[a], source[b]) {
                (Some(c), Some(i), Some(j)) => {
                    c.matrix[i][j] / (c.matrix[i][i] * c.matrix[j][j]).sqrt()
                }
                _ => 0.0,
            }
        };
        let cov = DMatrix::from_fn(k, k, |a, b| sd[a] * corr(a, b) * sd[b]);
        let curvature = cov.clone();
        let basis = match (k, covered_by_fit, &fit.covariance) {
            (0, _, _) => BandBasis::None,
            (_, 0, _) => BandBasis::SpreadOnly,
            (_, _, Some(_)) => BandBasis::Covariance,
            (_, _, None) => BandBasis::Independent,
        };
        Self {
            basis,
            log_values: names.iter().map(|n| value(n).unwrap_or(1.0).ln()).collect(),
            names,
            sd,
            cov,
            curvature,
            stretch: DMatrix::identity(k, k),
            uncovered,
            spread: spread_names,
            spread_factor: spread,
        }
    }

    /// Number of covered parameters.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Nothing covered (no band).
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// The fit's motor with the covered parameters at ln θ = `log_values` (the rest as
    /// fitted, discovered terms included).
    pub fn motor_at(&self, fit: &FitFile, log_values: &[f64]) -> Result<Motor, PredictError> {
        let mut set = ParamSet::from(fit.params.clone());
        for (n, v) in self.names.iter().zip(log_values) {
            set.set(n, v.exp())?;
        }
        // An estimated displacement (a page that did not print it): what the fit held fixed
        // and scales with the size follows it, as in the fit (geometric similarity).
        let v_disp = ParamId::V_DISP.name();
        if let Some(j) = self.names.iter().position(|n| n == v_disp) {
            let size = log_values[j].exp() / fit.params.v_disp();
            for id in ParamId::all() {
                let Some(k) = id.spec().size_exponent else {
                    continue;
                };
                if !fit.estimated.iter().any(|n| n == id.name()) {
                    set.set_value(id, fit.params.value(id) * size.powf(k));
                }
            }
        }
        let params: MotorParams = set.check()?;
        Ok(Motor::new(params, fit.effects.clone()).with_extra(&fit.extra))
    }

    /// The delta-method 95 % bands of the figures `figures(motor)` about their values
    /// `center` at the estimate (see the module documentation); `None` without covered
    /// parameters. `figures` must give the same number of values for every motor.
    pub fn delta_bands(
        &self,
        fit: &FitFile,
        center: &[f64],
        figures: &dyn Fn(&Motor) -> Result<Vec<f64>, PredictError>,
    ) -> Result<Option<Vec<[f64; 2]>>, PredictError> {
        if self.is_empty() {
            return Ok(None);
        }
        let jac = self.jacobian(fit, center.len(), figures)?;
        let bands = (0..center.len())
            .map(|i| {
                let g = DVector::from_fn(self.len(), |j, _| jac[(i, j)]);
                let var = (g.transpose() * &self.cov * &g)[(0, 0)].max(0.0);
                log_band(center[i], Z95 * var.sqrt())
            })
            .collect();
        Ok(Some(bands))
    }

    /// For each figure of `which` (indices into `figures(motor)`, `n` values in all): how
    /// much of its delta-method variance Var y = gᵀ·C·g knowing parameters exactly would
    /// remove. For the set P of parameters marked in `set` it is 1 − Var(y | θ_P)/Var y =
    /// c_Pᵀ·C_PP⁻¹·c_P / Var y with c = C·g (the covariances of y with each ln θ_j); for each
    /// parameter alone, c_j²/(C_jj·Var y), its squared correlation with the figure. Both lie
    /// in [0, 1]. Returns (the set's share, each parameter's share) per figure; `None`
    /// without covered parameters. A figure of zero variance gets shares 0.
    pub fn variance_shares(
        &self,
        fit: &FitFile,
        n: usize,
        which: &[usize],
        set: &[bool],
        figures: &dyn Fn(&Motor) -> Result<Vec<f64>, PredictError>,
    ) -> Result<Option<Vec<VarianceShares>>, PredictError> {
        if self.is_empty() {
            return Ok(None);
        }
        let jac = self.jacobian(fit, n, figures)?;
        let in_set: Vec<usize> = (0..self.len())
            .filter(|j| set.get(*j) == Some(&true))
            .collect();
        let c_pp = DMatrix::from_fn(in_set.len(), in_set.len(), |a, b| {
            self.cov[(in_set[a], in_set[b])]
        });
        // An empty set removes nothing (and nalgebra's SVD panics on a 0×0 matrix).
        let c_pp_inv = if in_set.is_empty() {
            c_pp
        } else {
            c_pp.clone().pseudo_inverse(1e-300).unwrap_or(c_pp * 0.0)
        };
        let shares = which
            .iter()
            .map(|&i| {
                let g = DVector::from_fn(self.len(), |j, _| jac[(i, j)]);
                let c = &self.cov * &g;
                let var = g.dot(&c);
                if var.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                    return (0.0, vec![0.0; self.len()]);
                }
                let c_p = DVector::from_fn(in_set.len(), |a, _| c[in_set[a]]);
                let set_share = (c_p.dot(&(&c_pp_inv * &c_p)) / var).clamp(0.0, 1.0);
                let each = (0..self.len())
                    .map(|j| {
                        let cjj = self.cov[(j, j)];
                        if cjj > 0.0 {
                            (c[j] * c[j] / (cjj * var)).clamp(0.0, 1.0)
                        } else {
                            0.0
                        }
                    })
                    .collect();
                (set_share, each)
            })
            .collect();
        Ok(Some(shares))
    }

    /// ∂y_i/∂ln θ_j of the `n` figures by central differences (module documentation); an
    /// `n` × [`Self::len`] matrix, columns in the order of [`Self::names`].
    pub fn jacobian(
        &self,
        fit: &FitFile,
        n: usize,
        figures: &dyn Fn(&Motor) -> Result<Vec<f64>, PredictError>,
    ) -> Result<DMatrix<f64>, PredictError> {
        let k = self.len();
        let mut jac = DMatrix::<f64>::zeros(n, k);
        for j in 0..k {
            let h = self.sd[j].clamp(1e-4, 0.05);
            let mut at = self.log_values.clone();
            at[j] = self.log_values[j] + h;
            let plus = figures(&self.motor_at(fit, &at)?)?;
            at[j] = self.log_values[j] - h;
            let minus = figures(&self.motor_at(fit, &at)?)?;
            for (i, (a, b)) in plus.iter().zip(&minus).enumerate().take(n) {
                jac[(i, j)] = (a - b) / (2.0 * h);
            }
        }
        Ok(jac)
    }

    /// Monte-Carlo 95 % bands of the same figures: `samples` draws of ln θ ~ N(ln θ̂, C)
    /// (seeded Xoshiro256++), each figure's 2.5 and 97.5 percentiles (linear interpolation
    /// between order statistics). A check of [`Self::delta_bands`], slower by
    /// samples/(2k); `None` without covered parameters or when C is not positive definite.
    pub fn monte_carlo_bands(
        &self,
        fit: &FitFile,
        samples: usize,
        seed: u64,
        figures: &dyn Fn(&Motor) -> Result<Vec<f64>, PredictError>,
    ) -> Result<Option<Vec<[f64; 2]>>, PredictError> {
        if self.is_empty() || samples < 2 {
            return Ok(None);
        }
        let Some(chol) = self.cov.clone().cholesky() else {
            return Ok(None);
        };
        let l = chol.l();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let k = self.len();
        let mut draws: Vec<Vec<f64>> = Vec::with_capacity(samples);
        for _ in 0..samples {
            let z = DVector::from_fn(k, |_, _| StandardNormal.sample(&mut rng));
            let step = &l * z;
            let at: Vec<f64> = (0..k).map(|j| self.log_values[j] + step[j]).collect();
            draws.push(figures(&self.motor_at(fit, &at)?)?);
        }
        let n_fig = draws[0].len();
        let bands = (0..n_fig)
            .map(|i| {
                let mut v: Vec<f64> = draws.iter().map(|d| d[i]).collect();
                v.sort_by(f64::total_cmp);
                [percentile(&v, 0.025), percentile(&v, 0.975)]
            })
            .collect();
        Ok(Some(bands))
    }
}

/// σ of ln θ of parameter `n` from its profile-likelihood `ci95`: (ln hi − ln lo)/(2·1.96),
/// the two sides' half-widths in log space averaged; `None` without a positive interval.
fn profile_sd(fit: &FitFile, n: &str) -> Option<f64> {
    fit.ci95
        .iter()
        .find(|(m, _)| m == n)
        .map(|(_, c)| *c)
        .filter(|[lo, hi]| *lo > 0.0 && hi > lo)
        .map(|[lo, hi]| (hi.ln() - lo.ln()) / (2.0 * Z95))
}

/// Sweeps over the parameters with a `target` variance; each stretches (or shrinks) `c`
/// along its profile path, C ← C + (λ² − 1)·C·e_j·e_jᵀ·C/C_jj with λ² = target/C_jj (the
/// module documentation), until every C_jj is its target within 1e-9 relative or after
/// 200 sweeps. Each step is a congruence C ← M·C·Mᵀ, M = I + (λ − 1)·C·e_j·e_jᵀ/C_jj with
/// det M = λ > 0, so C stays positive definite; returns A, the product of the M's (latest
/// on the left), with C_after = A·C_before·Aᵀ.
fn stretch_to(c: &mut DMatrix<f64>, target: &[Option<f64>]) -> DMatrix<f64> {
    let mut a = DMatrix::identity(c.nrows(), c.ncols());
    for _ in 0..200 {
        let mut worst = 0.0_f64;
        for (j, t) in target.iter().enumerate() {
            let (Some(t), cjj) = (t, c[(j, j)]) else {
                continue;
            };
            if cjj <= 0.0 {
                continue;
            }
            let l2 = t / cjj;
            worst = worst.max((l2 - 1.0).abs());
            let v = c.column(j).clone_owned();
            *c += (&v * v.transpose()) * ((l2 - 1.0) / cjj);
            let row_j = a.row(j).clone_owned();
            a += (&v * row_j) * ((l2.sqrt() - 1.0) / cjj);
        }
        if worst < 1e-9 {
            break;
        }
    }
    a
}

/// Largest half-width of a linear band, relative to the figure, that is still propagated in
/// log space (a factor e² ≈ 7.4 either side): beyond it the figure is not resolved from 0.
const LOG_BAND_MAX_RELATIVE: f64 = 2.0;

/// The 95 % band of a figure y with delta-method half-width `half` (1.96·√Var y): for a
/// positive figure propagated in log space, y·exp(∓half/y) (Var ln y = Var y/y² to first
/// order), so that a positive quantity keeps a positive band and the band's ends are the
/// same factor either side of y, as the parameters' log-normal spread makes them; a
/// figure ≤ 0 (a torque past free speed) keeps the linear y ∓ half, and so does one whose
/// band reaches more than `LOG_BAND_MAX_RELATIVE` (2) times itself: the fit does not tell it
/// from zero (a curve's torque next to the free speed, whose sign the parameters' spread
/// can change), and its log-space factor e^(half/y) would grow without bound as y → 0.
pub fn log_band(y: f64, half: f64) -> [f64; 2] {
    if y > 0.0 && half <= LOG_BAND_MAX_RELATIVE * y {
        let f = (half / y).exp();
        [y / f, y * f]
    } else {
        [y - half, y + half]
    }
}

/// The q-quantile of sorted values, interpolating linearly between order statistics.
fn percentile(sorted: &[f64], q: f64) -> f64 {
    let x = q * (sorted.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x - x.floor());
    let next = sorted[(i + 1).min(sorted.len() - 1)];
    sorted[i] + f * (next - sorted[i])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::fitfile::{LogCovariance, ParamVerdict};
    use crate::model::effects::EffectSet;

    fn fit_file() -> FitFile {
        let mut f = FitFile::from_params("t", MotorParams::default(), EffectSet::empty());
        f.estimated = vec!["c_in1".into(), "c_ext".into(), "visc".into()];
        let v = MotorParams::default();
        let around = |n: &str, r: f64| {
            let x = v.get(n).unwrap();
            [x * (-r).exp(), x * r.exp()]
        };
        f.ci95 = vec![
            ("c_in1".into(), around("c_in1", 0.02)),
            ("c_ext".into(), around("c_ext", 0.04)),
        ];
        f.verdicts = vec![ParamVerdict {
            name: "visc".into(),
            bounds95: [None, Some(1e-4)],
            identifiable: false,
            why: Some("open below".into()),
        }];
        f
    }

    #[test]
    fn widths_come_from_the_intervals_and_correlations_from_the_covariance() {
        let mut f = fit_file();
        let u = ParamUncertainty::of(&f, None);
        assert_eq!(u.basis, BandBasis::Independent);
        assert_eq!(u.names, vec!["c_in1", "c_ext"]);
        assert!((u.sd[0] - 0.02 / Z95).abs() < 1e-12);
        assert_eq!(u.cov[(0, 1)], 0.0);
        assert_eq!(
            u.uncovered,
            vec![("visc".into(), "not identifiable".into())]
        );
        f.covariance = Some(LogCovariance {
            parameters: vec!["c_in1".into(), "c_ext".into(), "visc".into()],
            matrix: vec![
                vec![1e-4, 1e-4, 0.0],
                vec![1e-4, 4e-4, 0.0],
                vec![0.0, 0.0, 1.0],
            ],
        });
        let u = ParamUncertainty::of(&f, None);
        assert_eq!(u.basis, BandBasis::Covariance);
        // Correlation 0.5, rescaled to the intervals' widths.
        let want = 0.5 * (0.02 / Z95) * (0.04 / Z95);
        assert!((u.cov[(0, 1)] - want).abs() < 1e-15, "{}", u.cov);
        f.ci95.clear();
        f.covariance = None;
        assert_eq!(ParamUncertainty::of(&f, None).basis, BandBasis::None);
    }

    /// Two parameters the curvature ties (correlation 0.99, σ 0.1 each): the data pin
    /// d = ln c_in1 − ln c_ext to σ_d = 0.1·√(2·0.01). c_in1's profile is twice as wide as
    /// its curvature (σ 0.2), c_ext is open (not identifiable, no interval). `for_bands`
    /// covers c_ext with its curvature width and stretches along c_in1's profile path, one
    /// stretch of λ² = 4: C' = C + 3·C·e₁·e₁ᵀ·C/C₁₁, so C'₁₁ = 4·C₁₁, C'₁₂ = 4·C₁₂ and
    /// C'₂₂ = C₂₂ + 3·C₁₂²/C₁₁, which keeps Var(c_ext | c_in1) = C₂₂ − C₁₂²/C₁₁; d's
    /// variance becomes Var d + 3·Cov(d, ln c_in1)²/C₁₁.
    /// S·R·S (`of`) drops c_ext and gives d the band of c_in1 alone.
    #[test]
    fn stretched_bands_keep_what_the_data_pin() {
        let mut f = fit_file();
        let v = MotorParams::default();
        let c_in1 = v.get("c_in1").unwrap();
        f.estimated = vec!["c_in1".into(), "c_ext".into()];
        f.ci95 = vec![(
            "c_in1".into(),
            [c_in1 * (-Z95 * 0.2f64).exp(), c_in1 * (Z95 * 0.2f64).exp()],
        )];
        f.verdicts = vec![ParamVerdict {
            name: "c_ext".into(),
            bounds95: [None, None],
            identifiable: false,
            why: Some("open".into()),
        }];
        let (s, rho) = (0.1f64, 0.99f64);
        f.covariance = Some(LogCovariance {
            parameters: vec!["c_in1".into(), "c_ext".into()],
            matrix: vec![vec![s * s, rho * s * s], vec![rho * s * s, s * s]],
        });
        let u = ParamUncertainty::for_bands(&f, None);
        assert_eq!(u.basis, BandBasis::Stretched);
        assert_eq!(u.names, vec!["c_in1", "c_ext"]);
        assert!(u.uncovered.is_empty(), "{:?}", u.uncovered);
        let (c11, c12, c22) = (s * s, rho * s * s, s * s);
        let want = [
            [4.0 * c11, 4.0 * c12],
            [4.0 * c12, c22 + 3.0 * c12 * c12 / c11],
        ];
        for (a, row) in want.iter().enumerate() {
            for (b, w) in row.iter().enumerate() {
                assert!((u.cov[(a, b)] - w).abs() < 1e-12, "{} vs {want:?}", u.cov);
            }
        }
        let cond = |c: &DMatrix<f64>| c[(1, 1)] - c[(0, 1)].powi(2) / c[(0, 0)];
        assert!((cond(&u.cov) - (c22 - c12 * c12 / c11)).abs() < 1e-15);
        assert!((u.sd[0] - 0.2).abs() < 1e-12);
        // The pinned difference: its delta band against the closed form, and against S·R·S.
        let d = |m: &Motor| Ok(vec![m.params().c_in1().ln() - m.params().c_ext().ln()]);
        let half = |u: &ParamUncertainty| {
            let centre = d(&u.motor_at(&f, &u.log_values).unwrap()).unwrap();
            let [lo, hi] = u.delta_bands(&f, &centre, &d).unwrap().unwrap()[0];
            (hi - lo) / 2.0
        };
        let var_d = c11 + c22 - 2.0 * c12;
        let cov_d1 = c11 - c12;
        let want_sd = (var_d + 3.0 * cov_d1 * cov_d1 / c11).sqrt();
        assert!(
            (half(&u) - Z95 * want_sd).abs() < 1e-9,
            "{} vs {}",
            half(&u),
            Z95 * want_sd
        );
        let srs = ParamUncertainty::of(&f, None);
        assert_eq!(srs.names, vec!["c_in1"]);
        assert!((half(&srs) - Z95 * 0.2).abs() < 1e-9);
        assert!(
            half(&u) < 0.3 * half(&srs),
            "{} vs {}",
            half(&u),
            half(&srs)
        );
    }

    /// With several profile widths the sweeps bring every variance to its profile's and C
    /// stays positive definite.
    #[test]
    fn stretching_reaches_every_profile_width() {
        let mut c =
            DMatrix::from_row_slice(3, 3, &[1.0, 0.9, -0.5, 0.9, 1.0, -0.3, -0.5, -0.3, 1.0]);
        let target = [Some(4.0), Some(0.5), None];
        let c0 = c.clone();
        let a = stretch_to(&mut c, &target);
        // C = A·C₀·Aᵀ: what `vanefit plan`'s update keeps.
        assert!((&a * &c0 * a.transpose() - &c).abs().max() < 1e-12, "{a}");
        assert!(
            (c[(0, 0)] - 4.0).abs() < 1e-8 && (c[(1, 1)] - 0.5).abs() < 1e-8,
            "{c}"
        );
        assert!(c.clone().cholesky().is_some(), "{c}");
    }

    #[test]
    fn a_stated_spread_covers_the_fixed_and_the_flat_estimable_parameters() {
        let mut f = fit_file();
        f.ci95.clear();
        f.covariance = None;
        // Nothing from the fit: the spread alone gives the band.
        let u = ParamUncertainty::of(&f, Some(1.5));
        assert_eq!(u.basis, BandBasis::SpreadOnly);
        // visc is estimated but not identifiable, c_in1 and c_ext have no interval left,
        // the other five were never estimated: all eight take the spread, nothing else.
        assert_eq!(u.spread.len(), 8);
        assert!(u.spread.contains(&"visc".to_string()));
        assert!(u.uncovered.is_empty());
        assert!(u.spread.contains(&"t_coulomb".to_string()));
        assert!(!u.spread.iter().any(|n| n == "b_crit" || n == "inertia"));
        let j = u.names.iter().position(|n| n == "t_coulomb").unwrap();
        assert!((u.sd[j] - 1.5f64.ln() / Z95).abs() < 1e-15);
        assert!(!u.uncovered.iter().any(|(n, _)| n == "visc"));
        // With the fit's intervals the fitted ones keep their widths, the spread adds the rest.
        let g = fit_file();
        let u = ParamUncertainty::of(&g, Some(2.0));
        assert_eq!(u.basis, BandBasis::Independent);
        assert_eq!(&u.names[..2], &["c_in1", "c_ext"]);
        assert!((u.sd[0] - 0.02 / Z95).abs() < 1e-12);
        assert_eq!(u.names.len(), 2 + u.spread.len());
        assert!(!u.spread.iter().any(|n| n == "c_in1" || n == "c_ext"));
    }

    /// On y = ln c_in1 + 2 ln c_ext with independent parameters, knowing c_ext removes its
    /// share 4σ₂²/(σ₁² + 4σ₂²) of the variance, alone or as the set; a set of both removes
    /// all of it.
    #[test]
    fn variance_shares_are_what_knowing_a_parameter_removes() {
        let f = fit_file();
        let u = ParamUncertainty::of(&f, None);
        let y = |m: &Motor| {
            Ok(vec![
                m.params().c_in1().ln() + 2.0 * m.params().c_ext().ln(),
            ])
        };
        let (s1, s2) = (0.02 / Z95, 0.04 / Z95);
        let want = 4.0 * s2 * s2 / (s1 * s1 + 4.0 * s2 * s2);
        let shares = u
            .variance_shares(&f, 1, &[0], &[false, true], &y)
            .unwrap()
            .unwrap();
        let (set, each) = &shares[0];
        assert!((set - want).abs() < 1e-6, "{set} vs {want}");
        assert!((each[1] - want).abs() < 1e-6 && (each[0] - (1.0 - want)).abs() < 1e-6);
        let all = u
            .variance_shares(&f, 1, &[0], &[true, true], &y)
            .unwrap()
            .unwrap();
        assert!((all[0].0 - 1.0).abs() < 1e-6, "{:?}", all[0]);
        // An empty set removes nothing: share 0, each parameter's own share as before (a
        // page whose figures rest on no prior parameter made `fit` panic here).
        let none = u
            .variance_shares(&f, 1, &[0], &[false, false], &y)
            .unwrap()
            .unwrap();
        assert_eq!(none[0].0, 0.0);
        assert!((none[0].1[1] - want).abs() < 1e-6, "{:?}", none[0]);
    }

    /// A positive figure with a spread wider than itself (a linear band would reach below
    /// 0) keeps a positive band, the same factor either side of it, the factor of the
    /// log-space delta method.
    #[test]
    fn a_positive_figure_has_a_positive_band() {
        let f = fit_file();
        let u = ParamUncertainty::of(&f, None);
        let k = 60.0;
        let y = |m: &Motor| Ok(vec![(m.params().c_in1() / 1e-9).powf(k)]);
        let center = y(&u.motor_at(&f, &u.log_values).unwrap()).unwrap();
        let [lo, hi] = u.delta_bands(&f, &center, &y).unwrap().unwrap()[0];
        assert!(lo > 0.0 && lo < center[0] && center[0] < hi, "{lo} {hi}");
        assert!(((hi / center[0]) * (lo / center[0]) - 1.0).abs() < 1e-9);
        // σ of ln c_in1 is s = 0.02/1.96 and the step h = s: the central difference of
        // y = e^(k·ln c) is y·sinh(k·h)/h, so the band's factor is exp(1.96·s·sinh(k·h)/h).
        let s = 0.02 / Z95;
        let want = (Z95 * s * (k * s).sinh() / s).exp();
        assert!(
            (hi / center[0] / want - 1.0).abs() < 1e-6,
            "{} vs {want}",
            hi / center[0]
        );
        // A figure ≤ 0 keeps the linear band.
        assert_eq!(log_band(-1.0, 0.5), [-1.5, -0.5]);
        // So does a positive one that the band does not tell from zero (a torque next to
        // the free speed): no factor e^(half/y) that overflows as y → 0.
        assert_eq!(log_band(1e-6, 0.5), [1e-6 - 0.5, 1e-6 + 0.5]);
        let [lo, hi] = log_band(1.0, 1.9);
        assert!(lo > 0.0 && (hi * lo - 1.0).abs() < 1e-12, "{lo} {hi}");
    }

    #[test]
    fn delta_and_monte_carlo_agree_on_a_linear_figure() {
        let f = fit_file();
        let u = ParamUncertainty::of(&f, None);
        // y = ln c_in1 + 2 ln c_ext: exactly linear in the log-parameters.
        let y = |m: &Motor| {
            Ok(vec![
                m.params().c_in1().ln() + 2.0 * m.params().c_ext().ln(),
            ])
        };
        let center = y(&u.motor_at(&f, &u.log_values).unwrap()).unwrap();
        let delta = u.delta_bands(&f, &center, &y).unwrap().unwrap()[0];
        let sd = ((0.02f64 / Z95).powi(2) + (2.0 * 0.04 / Z95).powi(2)).sqrt();
        assert!(((delta[1] - delta[0]) / 2.0 - Z95 * sd).abs() < 1e-9);
        let mc = u.monte_carlo_bands(&f, 4000, 7, &y).unwrap().unwrap()[0];
        let ratio = (mc[1] - mc[0]) / (delta[1] - delta[0]);
        assert!((ratio - 1.0).abs() < 0.06, "{ratio}");
    }
}
