//! The prior of a motor's parameters: what is known of a vane motor of a given size before
//! any of its data are seen (docs/estimation.md, "Priors").
//!
//! Each parameter with a prior is log-normal around its default scaled to the motor's
//! displacement (`ParamSpec::size_exponent`, geometric similarity):
//!
//! ```text
//!     ln v ~ N(ln v₀(V_disp), σ²),    σ = ln F / 1.96
//! ```
//!
//! with F the factor within which 95 % of real motors of that size lie
//! (`ParamSpec::prior_factor95` in the parameter registry; where each F comes from is in
//! docs/estimation.md). A fit minimises the likelihood's χ²
//! plus the prior's `χ²_prior = Σ ((ln v − ln v₀)/σ)²` (maximum a posteriori, the mode in
//! ln v), so its curvature (the Laplace covariance the fit file stores) holds the prior's
//! precision 1/σ² beside the data's. Where data pin a parameter to a few per cent, the
//! prior's pull moves it by a fraction (σ_data/σ)² of its distance from v₀: nothing; where
//! they do not (a catalogue page), the posterior is the prior and the bands carry it.
//!
//! A sampler of the estimator's coordinates θ (`estimate::problem::dimension`) adds [`Prior::ln_prior`]
//! to the log-likelihood −χ²/2: the log-density of θ, the Jacobian of θ → ln v included.

use crate::estimate::problem::dimension::Dimension;
use crate::model::params::{MotorParams, ParamId};

/// The normal quantile of a two-sided 95 % range.
const Z95: f64 = 1.959_963_984_540_054;

/// The residual of a prior term whose value (or size) has no logarithm: large and finite,
/// so that a cost built on it stays finite.
pub(crate) const NO_LOG_RESIDUAL: f64 = 1e6;

/// One parameter's log-normal prior.
#[derive(Debug, Clone, PartialEq)]
pub struct PriorTerm {
    /// The parameter (docs/model.md, "Parameters").
    pub id: ParamId,
    /// The median v₀, SI (the default scaled to the motor's displacement).
    pub median: f64,
    /// σ of ln v.
    pub sd_ln: f64,
    /// k of the size law the median follows when the displacement is estimated too:
    /// v₀(V) = `median`·(V/V_ref)^k with V_ref [`Prior::size_reference_m3`]
    /// (`ParamSpec::size_exponent`; 0 for a parameter that does not follow the size).
    pub size_exponent: f64,
}

impl PriorTerm {
    /// The parameter's name (fit files, reports).
    pub fn name(&self) -> &'static str {
        self.id.name()
    }

    /// The 95 % factor F = exp(1.96·σ).
    pub fn factor95(&self) -> f64 {
        (Z95 * self.sd_ln).exp()
    }

    /// (ln v − ln v₀)/σ; a value ≤ 0 or not finite (no logarithm) gives a large finite
    /// residual, so that a cost built on it stays finite.
    pub fn residual(&self, v: f64) -> f64 {
        self.residual_at_size(v, 1.0)
    }

    /// The median at a motor `size` times the reference displacement: v₀·size^k.
    pub fn median_at_size(&self, size: f64) -> f64 {
        self.median * size.powf(self.size_exponent)
    }

    /// (ln v − ln v₀(V))/σ for a motor `size` = V/V_ref times the displacement the median is
    /// stated at: the prior of a motor whose displacement is itself estimated (a page that
    /// does not print it) follows that displacement by geometric similarity. Large and finite
    /// where v or the size has no logarithm.
    pub fn residual_at_size(&self, v: f64, size: f64) -> f64 {
        if v > 0.0 && v.is_finite() && size > 0.0 && size.is_finite() {
            (v.ln() - self.median.ln() - self.size_exponent * size.ln()) / self.sd_ln
        } else {
            NO_LOG_RESIDUAL
        }
    }
}

/// The prior of the parameters of one motor (empty: no prior, the likelihood alone).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Prior {
    /// One term per parameter with a prior.
    pub terms: Vec<PriorTerm>,
    /// The displacement V_ref, m³, at which the terms' medians are stated (`None`: the
    /// medians are fixed). Where the displacement is estimated (`v_disp` in the space) the
    /// medians follow it as v₀·(V/V_ref)^k; where it is fixed, V = V_ref and nothing changes.
    pub size_reference_m3: Option<f64>,
}

impl Prior {
    /// No prior: the fit is the likelihood's alone (`--priors none`).
    pub fn none() -> Self {
        Self::default()
    }

    /// The prior of a motor whose nominal parameters (defaults scaled to its displacement,
    /// and whatever its rig file gives) are `nominal`: a term for every parameter of
    /// the registry with a prior (`ParamSpec::prior_factor95`) and a positive nominal value,
    /// in the registry's order.
    pub fn for_motor(nominal: &MotorParams) -> Self {
        let terms = ParamId::all()
            .filter_map(|id| {
                let spec = id.spec();
                let f = spec.prior_factor95?;
                let median = nominal.value(id);
                (median > 0.0 && median.is_finite()).then(|| PriorTerm {
                    id,
                    median,
                    sd_ln: f.ln() / Z95,
                    size_exponent: spec.size_exponent.unwrap_or(0.0),
                })
            })
            .collect();
        Self {
            terms,
            size_reference_m3: Some(nominal.v_disp()),
        }
    }

    /// V/V_ref of a motor (1 when the medians are fixed).
    pub fn size_of(&self, params: &MotorParams) -> f64 {
        self.size_reference_m3
            .map_or(1.0, |v_ref| params.v_disp() / v_ref)
    }

    /// Whether there is no prior.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    /// The term of a parameter.
    pub fn term(&self, id: ParamId) -> Option<&PriorTerm> {
        self.terms.iter().find(|t| t.id == id)
    }

    /// The prior's residuals of the space's estimated parameters that have a term, in θ
    /// order: their squares sum to χ²_prior. Parameters held fixed add nothing (they do not
    /// move).
    pub fn residuals(&self, dims: &[Dimension], params: &MotorParams) -> Vec<f64> {
        let size = self.size_of(params);
        dims.iter()
            .filter_map(|d| {
                let t = self.term(d.id)?;
                Some(t.residual_at_size(params.value(d.id), size))
            })
            .collect()
    }

    /// χ²_prior = Σ ((ln v − ln v₀)/σ)² over the space's estimated parameters with a term:
    /// −2 ln p(ln v) up to a constant.
    pub fn chi2(&self, dims: &[Dimension], params: &MotorParams) -> f64 {
        self.residuals(dims, params).iter().map(|r| r * r).sum()
    }

    /// ln p(θ), the log-density of the estimator's coordinates θ (normalised, up to the prior's mass that the search bounds cut off): for a
    /// parameter with a term, the normal density of ln v times |d ln v/dθ|; for one
    /// without, uniform over its bounds in the space's own scale (log for positive
    /// parameters), i.e. the logistic density of θ. −∞ where θ is not finite. A sampler
    /// adds this to the log-likelihood −χ²/2.
    pub fn ln_prior(&self, dims: &[Dimension], theta: &[f64]) -> f64 {
        if theta.len() != dims.len() || theta.iter().any(|t| !t.is_finite()) {
            return f64::NEG_INFINITY;
        }
        // The size the medians follow, where the displacement is estimated too.
        let size = dims
            .iter()
            .zip(theta)
            .find(|(d, _)| d.id == ParamId::V_DISP)
            .zip(self.size_reference_m3)
            .map_or(1.0, |((d, t), v_ref)| d.value(*t) / v_ref);
        let mut lp = 0.0;
        for (d, t) in dims.iter().zip(theta) {
            let u = 1.0 / (1.0 + (-t).exp());
            let du_dtheta = u * (1.0 - u);
            // ln of the logistic density; written via softplus to stay finite for large |θ|.
            let ln_logistic = -t.abs() - 2.0 * (-t.abs()).exp().ln_1p();
            match self.term(d.id) {
                None => lp += ln_logistic,
                Some(term) => {
                    let v = d.value(*t);
                    if v.is_nan() || v <= 0.0 {
                        return f64::NEG_INFINITY;
                    }
                    let dlnv_du = if d.log_scale {
                        d.hi.ln() - d.lo.ln()
                    } else {
                        (d.hi - d.lo) / v
                    };
                    let z = term.residual_at_size(v, size);
                    lp += -0.5 * z * z - (term.sd_ln * (2.0 * std::f64::consts::PI).sqrt()).ln()
                        + (dlnv_du * du_dtheta.max(f64::MIN_POSITIVE)).ln();
                }
            }
        }
        lp
    }

    /// The prior's precision in θ (diagonal): 1/σ² · (d ln v/dθ)² for each estimated
    /// parameter with a term, 0 for the others; the Gauss–Newton curvature of χ²_prior/2
    /// where the displacement is fixed (where it is estimated, the medians' dependence on it
    /// adds off-diagonal terms, which the fit's curvature takes from the residuals instead).
    pub fn precision_theta(&self, dims: &[Dimension], theta: &[f64]) -> Vec<f64> {
        dims.iter()
            .zip(theta)
            .map(|(d, t)| {
                let Some(term) = self.term(d.id) else {
                    return 0.0;
                };
                let u = 1.0 / (1.0 + (-t).exp());
                let v = d.value(*t);
                let slope = if d.log_scale {
                    (d.hi.ln() - d.lo.ln()) * u * (1.0 - u)
                } else {
                    (d.hi - d.lo) * u * (1.0 - u) / v
                };
                (slope / term.sd_ln).powi(2)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::problem::space::ParamSpace;
    use crate::model::effects::EffectSet;

    fn space() -> ParamSpace {
        ParamSpace::new(
            &["c_in1", "b_crit", "n_poly"],
            MotorParams::default(),
            EffectSet::empty(),
        )
        .unwrap()
    }

    #[test]
    fn the_prior_is_centred_on_the_nominal_motor_with_its_stated_spread() {
        let p = MotorParams::default().with("c_in1", 2e-8).unwrap();
        let prior = Prior::for_motor(&p);
        let t = prior.term(ParamId::C_IN1).unwrap();
        assert_eq!(t.median, 2e-8);
        assert!((t.factor95() - 2.0).abs() < 1e-12);
        // One F above the median is 1.96 σ: χ² = 1.96².
        let s = space();
        let at = MotorParams::default().with("c_in1", 4e-8).unwrap();
        let chi2 = prior.chi2(&s.dims, &at);
        // b_crit sits at its median; n_poly has no term.
        assert!((chi2 - Z95 * Z95).abs() < 1e-9, "{chi2}");
        assert_eq!(prior.residuals(&s.dims, &at).len(), 2);
        assert!(Prior::none().chi2(&s.dims, &at) == 0.0);
    }

    /// ln p(θ) is a density of θ: its integral is 1 for a parameter whose bounds hold the
    /// whole prior (c_in1: ±7σ) and for one without a term (n_poly, uniform in its bounds).
    #[test]
    fn ln_prior_is_a_normalised_density_of_theta() {
        let prior = Prior::for_motor(&MotorParams::default());
        for name in ["c_in1", "n_poly"] {
            let single =
                ParamSpace::new(&[name], MotorParams::default(), EffectSet::empty()).unwrap();
            let (a, b, n) = (-40.0, 40.0, 80_000);
            let h = (b - a) / n as f64;
            let integral: f64 = (0..=n)
                .map(|i| {
                    let w = if i == 0 || i == n { 0.5 } else { 1.0 };
                    w * prior.ln_prior(&single.dims, &[a + h * i as f64]).exp()
                })
                .sum::<f64>()
                * h;
            assert!((integral - 1.0).abs() < 1e-4, "{name}: {integral}");
        }
        let s = space();
        assert_eq!(
            prior.ln_prior(&s.dims, &[f64::NAN, 0.0, 0.0]),
            f64::NEG_INFINITY
        );
    }

    /// Where the displacement is estimated, each median follows it by its size law: a motor
    /// twice AR034-11's size with its ports at the scaled default costs nothing, the same
    /// ports at the reference size cost (⅔·ln 2/σ)², and b_crit does not move.
    #[test]
    fn the_medians_follow_an_estimated_displacement() {
        let nominal = MotorParams::default();
        let prior = Prior::for_motor(&nominal);
        let space = ParamSpace::new(
            &["c_in1", "v_disp", "b_crit"],
            nominal.clone(),
            EffectSet::empty(),
        )
        .unwrap();
        let scaled_c = nominal.c_in1() * 2f64.powf(2.0 / 3.0);
        let twice = nominal
            .with("v_disp", 7.6e-6)
            .unwrap()
            .with("c_in1", scaled_c)
            .unwrap();
        let r = prior.residuals(&space.dims, &twice);
        assert_eq!(r.len(), 2, "{r:?}");
        assert!(r.iter().all(|x| x.abs() < 1e-9), "{r:?}");
        let same_size = nominal.with("c_in1", scaled_c).unwrap();
        let r = prior.residuals(&space.dims, &same_size);
        let sd = prior.term(ParamId::C_IN1).unwrap().sd_ln;
        assert!((r[0] - 2.0 / 3.0 * 2f64.ln() / sd).abs() < 1e-9, "{r:?}");
        // ln p(θ) follows the same medians: at the scaled point it beats the unscaled one.
        let (a, b) = (
            space.theta(&twice),
            space.theta(&nominal.with("v_disp", 7.6e-6).unwrap()),
        );
        assert!(prior.ln_prior(&space.dims, &a) > prior.ln_prior(&space.dims, &b));
    }

    #[test]
    fn precision_is_the_curvature_of_half_the_prior_chi2() {
        let s = space();
        let prior = Prior::for_motor(&MotorParams::default());
        let th = vec![0.3, -0.2, 0.1];
        let prec = prior.precision_theta(&s.dims, &th);
        let h = 1e-4;
        for j in 0..2 {
            let f = |d: f64| {
                let mut t = th.clone();
                t[j] += d;
                prior.residuals(&s.dims, &s.params(&t).unwrap())[j]
            };
            let slope = (f(h) - f(-h)) / (2.0 * h);
            assert!((prec[j] - slope * slope).abs() < 1e-6 * prec[j], "{j}");
        }
        assert_eq!(prec[2], 0.0);
    }
}
