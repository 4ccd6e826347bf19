//! The search space: which parameters are estimated (each a [`Dimension`] with its bounds
//! and coordinate map), what is held fixed, the effects switched on and the motor prior.

use crate::estimate::problem::dimension::{logistic, logit, BoundSide};
pub use crate::estimate::problem::dimension::{Dimension, SpaceError};
use crate::estimate::problem::prior::Prior;
use crate::model::effects::EffectSet;
pub use crate::model::params::DEFAULT_ESTIMATED;
use crate::model::params::{MotorParams, ParamId, ParamSet};

/// Parameters that are estimated, on top of fixed values.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamSpace {
    /// The estimated parameters, in θ order.
    pub dims: Vec<Dimension>,
    /// Values of everything not estimated (and the template for the estimated ones).
    pub fixed: MotorParams,
    /// Effects switched on.
    pub effects: EffectSet,
    /// The prior of the estimated parameters (empty: none), added to every cost the space
    /// is searched on (`estimate::problem::prior`).
    pub prior: Prior,
    /// The displacement, m³, that `fixed` was scaled to, when the fixed size-dependent
    /// parameters follow an estimated displacement (a page that does not print it): with
    /// `v_disp` estimated at V, each fixed parameter with a size law
    /// (`ParamSpec::size_exponent`) is its `fixed` value × (V/V_ref)^k (geometric
    /// similarity). `None`: they stay as fixed.
    pub size_reference_m3: Option<f64>,
}

/// An estimate that ended on a bound of its dimension ([`ParamSpace::bounds_reached`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundHit {
    /// The parameter.
    pub id: ParamId,
    /// Which bound.
    pub side: BoundSide,
    /// The bound, SI.
    pub bound: f64,
}

impl ParamSpace {
    /// Estimates `names` (default bounds at `fixed`'s size) over `fixed`, with the effects
    /// switched on.
    pub fn new(names: &[&str], fixed: MotorParams, effects: EffectSet) -> Result<Self, SpaceError> {
        let size = fixed.size();
        let dims = names
            .iter()
            .map(|n| Dimension::for_param(n, size))
            .collect::<Result<Vec<_>, _>>()?;
        Self::from_dims(dims, fixed, effects)
    }

    /// Estimates `dims` over `fixed`; every parameter once, effects' parameters only with
    /// their effect switched on, at least one.
    pub(crate) fn from_dims(
        dims: Vec<Dimension>,
        fixed: MotorParams,
        effects: EffectSet,
    ) -> Result<Self, SpaceError> {
        for (i, d) in dims.iter().enumerate() {
            if dims[..i].iter().any(|e| e.id == d.id) {
                return Err(SpaceError(format!("parameter '{}' listed twice", d.id)));
            }
            if let Some(e) = d.id.spec().effect {
                if !effects.contains(e) {
                    return Err(SpaceError(format!(
                        "parameter '{}' belongs to effect '{e}', which is not switched on",
                        d.id
                    )));
                }
            }
        }
        if dims.is_empty() {
            return Err(SpaceError("nothing to estimate".into()));
        }
        Ok(Self {
            dims,
            fixed,
            effects,
            prior: Prior::none(),
            size_reference_m3: None,
        })
    }

    /// The same space with the fixed size-dependent parameters following an estimated
    /// displacement from `v_ref_m3`, the displacement `fixed` was scaled to (see
    /// [`ParamSpace::size_reference_m3`]).
    pub fn with_size_following(mut self, v_ref_m3: f64) -> Self {
        self.size_reference_m3 = Some(v_ref_m3);
        self
    }

    /// The same space with a prior on its parameters (MAP instead of maximum likelihood).
    pub fn with_prior(mut self, prior: Prior) -> Self {
        self.prior = prior;
        self
    }

    /// Number of estimated parameters.
    pub fn len(&self) -> usize {
        self.dims.len()
    }

    /// Nothing estimated (never, for a checked space).
    pub fn is_empty(&self) -> bool {
        self.dims.is_empty()
    }

    /// Names of the estimated parameters, in θ order.
    pub fn names(&self) -> Vec<String> {
        self.dims.iter().map(|d| d.name().to_string()).collect()
    }

    /// The estimated parameters, in θ order.
    pub fn ids(&self) -> Vec<ParamId> {
        self.dims.iter().map(|d| d.id).collect()
    }

    /// Whether a parameter is estimated.
    pub fn estimates(&self, id: ParamId) -> bool {
        self.dims.iter().any(|d| d.id == id)
    }

    /// Checked parameters at optimizer coordinates θ. Values strictly inside the bounds can
    /// still break a cross-constraint (e.g. v_dead ≥ V_fill): that is an error to penalise.
    pub fn params(&self, theta: &[f64]) -> Result<MotorParams, crate::model::params::ParamError> {
        let mut set = ParamSet::from(self.fixed.clone());
        let mut v_disp = None;
        for (d, t) in self.dims.iter().zip(theta) {
            let v = d.value(*t);
            set.set_value(d.id, v);
            if d.id == ParamId::V_DISP {
                v_disp = Some(v);
            }
        }
        if let (Some(v), Some(v_ref)) = (v_disp, self.size_reference_m3) {
            let size = v / v_ref;
            for id in ParamId::all() {
                let Some(k) = id.spec().size_exponent else {
                    continue;
                };
                if !self.estimates(id) {
                    set.set_value(id, self.fixed.value(id) * size.powf(k));
                }
            }
        }
        set.check()
    }

    /// The estimated parameters of `p` that sit on one of their bounds: an optimizer that
    /// stopped there was held by the bound, and what depends on that parameter is
    /// unreliable (the fit says so).
    pub fn bounds_reached(&self, p: &MotorParams) -> Vec<BoundHit> {
        self.dims
            .iter()
            .filter_map(|d| {
                d.bound_reached(p.value(d.id))
                    .map(|(side, bound)| BoundHit {
                        id: d.id,
                        side,
                        bound,
                    })
            })
            .collect()
    }

    /// Optimizer coordinates of a parameter set.
    pub fn theta(&self, p: &MotorParams) -> Vec<f64> {
        self.dims.iter().map(|d| d.theta(p.value(d.id))).collect()
    }

    /// Optimizer coordinates of a point of the unit cube of start ranges (for start designs).
    pub(crate) fn theta_of_unit(&self, u: &[f64]) -> Vec<f64> {
        self.dims
            .iter()
            .zip(u)
            .map(|(d, x)| {
                let (a, b) = (d.unit(d.start_lo), d.unit(d.start_hi));
                logit((a + x * (b - a)).clamp(1e-9, 1.0 - 1e-9))
            })
            .collect()
    }

    /// Position in the unit cube of optimizer coordinates.
    pub(crate) fn unit_of_theta(&self, theta: &[f64]) -> Vec<f64> {
        theta.iter().map(|t| logistic(*t)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An estimate at a bound (or within 1e-3 of the span of it, in the dimension's own
    /// scale) is reported with its side and bound; one inside is not.
    #[test]
    fn estimates_on_a_bound_are_found_with_their_side() {
        let s = ParamSpace::new(
            &["c_in1", "b_crit", "t_coulomb"],
            MotorParams::default(),
            EffectSet::empty(),
        )
        .unwrap();
        assert!(s.bounds_reached(&MotorParams::default()).is_empty());
        let (lo, hi) = (s.dims[2].lo, s.dims[2].hi);
        let p = MotorParams::default()
            .with("t_coulomb", hi)
            .unwrap()
            .with(
                "b_crit",
                s.dims[1].lo + 1e-4 * (s.dims[1].hi - s.dims[1].lo),
            )
            .unwrap();
        let hits = s.bounds_reached(&p);
        assert_eq!(hits.len(), 2, "{hits:?}");
        assert_eq!(
            (hits[0].id, hits[0].side, hits[0].bound),
            (ParamId::B_CRIT, BoundSide::Lower, s.dims[1].lo)
        );
        assert_eq!(
            (hits[1].id, hits[1].side, hits[1].bound),
            (ParamId::T_COULOMB, BoundSide::Upper, hi)
        );
        // 1 % above the lower bound of a ×/÷ 10 log span is 4e-3 of it: inside.
        let p = MotorParams::default().with("t_coulomb", lo * 1.01).unwrap();
        assert!(s.bounds_reached(&p).is_empty());
    }

    /// A space over a motor of another size is bounded around that motor's size-scaled
    /// values: a 100 cm³ motor's Coulomb friction (26 × the reference's) is inside.
    #[test]
    fn a_large_motors_space_is_bounded_around_its_own_size() {
        let size = 100.0 / 3.8;
        let mut set = ParamSet::default();
        set.set_value(ParamId::V_DISP, 100e-6);
        for id in ParamId::all() {
            if id.spec().size_exponent.is_some() {
                set.set_value(id, id.spec().scaled_default(size));
            }
        }
        let p = set.check().unwrap();
        let s = ParamSpace::new(
            &["t_coulomb", "visc", "c_in1"],
            p.clone(),
            EffectSet::empty(),
        )
        .unwrap();
        assert!(s.bounds_reached(&p).is_empty());
        let reference = ParamId::T_COULOMB.spec().search;
        assert!(
            p.t_coulomb() > reference.1,
            "outside the reference motor's range"
        );
        assert!(s.dims[0].lo < p.t_coulomb() && p.t_coulomb() < s.dims[0].hi);
    }

    #[test]
    fn theta_round_trips_inside_bounds() {
        let s = ParamSpace::new(
            &["c_in1", "b_crit", "t_coulomb"],
            MotorParams::default(),
            EffectSet::empty(),
        )
        .unwrap();
        let p = MotorParams::default();
        let th = s.theta(&p);
        let back = s.params(&th).unwrap();
        for d in &s.dims {
            let (a, b) = (p.value(d.id), back.value(d.id));
            assert!((a - b).abs() < 1e-12 * a.abs(), "{}: {a} vs {b}", d.id);
        }
        for t in [-40.0, -3.0, 0.0, 5.0, 40.0] {
            for d in &s.dims {
                let v = d.value(t);
                assert!(v >= d.lo && v <= d.hi);
            }
        }
    }

    /// With the displacement estimated and size following on, the fixed size-dependent
    /// parameters scale with it by their similarity exponents; the estimated ones and the
    /// dimensionless ones do not; without size following nothing else moves.
    #[test]
    fn fixed_parameters_follow_an_estimated_displacement() {
        let base = MotorParams::default();
        let s = ParamSpace::new(&["c_in1", "v_disp"], base.clone(), EffectSet::empty())
            .unwrap()
            .with_size_following(base.v_disp());
        let at = base.with("v_disp", 2.0 * base.v_disp()).unwrap();
        let p = s.params(&s.theta(&at)).unwrap();
        let ratio = |n: &str| p.get(n).unwrap() / base.get(n).unwrap();
        assert!((ratio("v_disp") - 2.0).abs() < 1e-9);
        for (name, k) in [
            ("v_dead", 1.0),
            ("vol1", 1.0),
            ("t_coulomb", 1.0),
            ("c_ext", 2.0 / 3.0),
            ("visc", 4.0 / 3.0),
            ("inertia", 5.0 / 3.0),
        ] {
            assert!(
                (ratio(name) - 2f64.powf(k)).abs() < 1e-9,
                "{name}: {}",
                ratio(name)
            );
        }
        assert!((ratio("c_in1") - 1.0).abs() < 1e-9, "estimated: not scaled");
        assert_eq!(ratio("eps"), 1.0);
        let plain =
            ParamSpace::new(&["c_in1", "v_disp"], base.clone(), EffectSet::empty()).unwrap();
        let q = plain.params(&plain.theta(&at)).unwrap();
        assert_eq!(q.v_dead(), base.v_dead());
    }

    #[test]
    fn set_up_errors_are_named() {
        let e =
            ParamSpace::new(&["c_nope"], MotorParams::default(), EffectSet::empty()).unwrap_err();
        assert!(e.0.contains("c_nope"));
        let e =
            ParamSpace::new(&["v_carry"], MotorParams::default(), EffectSet::empty()).unwrap_err();
        assert!(e.0.contains("dead_volume_carryover"));
        assert!(Dimension::with_bounds("c_in1", 1e-8, 1e-9).is_err());
        assert!(ParamSpace::new(&["z"], MotorParams::default(), EffectSet::empty()).is_err());
    }
}
