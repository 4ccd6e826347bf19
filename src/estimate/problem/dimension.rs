//! One estimated parameter: its bounds and the map between its physical value and the
//! unconstrained coordinate that the optimizers move in.
//!
//! Positive parameters are placed on a log scale, u = (ln v − ln lo)/(ln hi − ln lo); others
//! linearly, u = (v − lo)/(hi − lo). The optimizer's coordinate is θ = logit(u) =
//! ln(u/(1 − u)), so any θ ∈ ℝ is a value strictly inside the bounds.

use crate::model::params::{Domain, ParamId};

/// One estimated parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Dimension {
    /// The parameter (docs/model.md, "Parameters").
    pub id: ParamId,
    /// Lower bound, SI.
    pub lo: f64,
    /// Upper bound, SI.
    pub hi: f64,
    /// Placed on a log scale (positive parameters).
    pub log_scale: bool,
    /// Where start points are drawn, inside [lo, hi] (default: all of it): lower end, SI.
    pub start_lo: f64,
    /// Upper end of the start range, SI.
    pub start_hi: f64,
}

/// An error in the estimation set-up (unknown name, bad bounds).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct SpaceError(pub String);

/// Share of a dimension's span (in its own scale: logarithmic or linear) within which an
/// estimate counts as sitting on a bound. 1e-3 of a ×/÷ 10 span is 0.5 % of the value: an
/// optimizer that stopped there was held by the bound, not by the data.
pub const ON_BOUND_SHARE: f64 = 1e-3;

/// Which end of its bounds an estimate reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundSide {
    /// The lower bound.
    Lower,
    /// The upper bound.
    Upper,
}

impl std::fmt::Display for BoundSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Lower => "lower",
            Self::Upper => "upper",
        })
    }
}

pub(crate) fn logit(u: f64) -> f64 {
    (u / (1.0 - u)).ln()
}

pub(crate) fn logistic(theta: f64) -> f64 {
    1.0 / (1.0 + (-theta).exp())
}

impl Dimension {
    /// The parameter of a name, or the error that names it.
    fn id_of(name: &str) -> Result<ParamId, SpaceError> {
        ParamId::from_name(name).ok_or_else(|| SpaceError(format!("unknown parameter '{name}'")))
    }

    /// A dimension with the default bounds of its parameter for a motor `size` times
    /// AR034-11's displacement (`ParamSpec::search_at`).
    pub fn for_param(name: &str, size: f64) -> Result<Self, SpaceError> {
        Self::for_id(Self::id_of(name)?, size)
    }

    /// A dimension with the default bounds of its parameter for a motor `size` times
    /// AR034-11's displacement (`ParamSpec::search_at`: the reference motor's range scaled by
    /// the parameter's size law, so that no motor of 0.3–500 cm³ starts against a bound).
    pub fn for_id(id: ParamId, size: f64) -> Result<Self, SpaceError> {
        let s = id.spec();
        if matches!(s.domain, Domain::Integer(..)) {
            return Err(SpaceError(format!(
                "parameter '{id}' is a whole number and cannot be estimated"
            )));
        }
        if !(size.is_finite() && size > 0.0) {
            return Err(SpaceError(format!(
                "bounds of '{id}': the motor's size {size:e} is not a positive number"
            )));
        }
        let (lo, hi) = s.search_at(size);
        Self::with_id_bounds(id, lo, hi)
    }

    /// A dimension with explicit bounds (SI).
    pub fn with_bounds(name: &str, lo: f64, hi: f64) -> Result<Self, SpaceError> {
        Self::with_id_bounds(Self::id_of(name)?, lo, hi)
    }

    /// A dimension of a parameter with explicit bounds (SI).
    pub fn with_id_bounds(id: ParamId, lo: f64, hi: f64) -> Result<Self, SpaceError> {
        let s = id.spec();
        let log_scale = matches!(s.domain, Domain::Positive | Domain::NonNegative);
        let ok = lo.is_finite() && hi.is_finite() && lo < hi && (!log_scale || lo > 0.0);
        if !ok {
            return Err(SpaceError(format!(
                "bounds of '{id}': need finite lo < hi{} (got {lo:e}..{hi:e})",
                if log_scale { " and lo > 0" } else { "" }
            )));
        }
        if let Domain::Interval(a, b) = s.domain {
            if lo < a || hi > b {
                return Err(SpaceError(format!(
                    "bounds of '{id}' must lie in [{a}, {b}]"
                )));
            }
        }
        Ok(Self {
            id,
            lo,
            hi,
            log_scale,
            start_lo: lo,
            start_hi: hi,
        })
    }

    /// The parameter's name (fit files, reports).
    pub fn name(&self) -> &'static str {
        self.id.name()
    }

    /// Draws start points from [lo, hi] ∩ the bounds (refused if empty or not finite).
    pub fn with_start_range(mut self, lo: f64, hi: f64) -> Result<Self, SpaceError> {
        let (lo, hi) = (lo.max(self.lo), hi.min(self.hi));
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(SpaceError(format!(
                "start range of '{}' must be a non-empty part of its bounds [{:e}, {:e}]",
                self.id, self.lo, self.hi
            )));
        }
        self.start_lo = lo;
        self.start_hi = hi;
        Ok(self)
    }

    /// Position u ∈ (0, 1) of a value within the bounds.
    pub fn unit(&self, v: f64) -> f64 {
        if self.log_scale {
            (v.ln() - self.lo.ln()) / (self.hi.ln() - self.lo.ln())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        }
    }

    /// Value at position u ∈ [0, 1] (never outside the bounds, whatever the rounding).
    pub fn from_unit(&self, u: f64) -> f64 {
        let v = if self.log_scale {
            (self.lo.ln() + u * (self.hi.ln() - self.lo.ln())).exp()
        } else {
            self.lo + u * (self.hi - self.lo)
        };
        v.clamp(self.lo, self.hi)
    }

    /// Optimizer coordinate θ of a value (clamped a hair inside the bounds).
    pub fn theta(&self, v: f64) -> f64 {
        logit(self.unit(v).clamp(1e-9, 1.0 - 1e-9))
    }

    /// The bound that a value `v` sits on (within `ON_BOUND_SHARE` of the span), and the
    /// bound's value, SI; `None` inside.
    pub fn bound_reached(&self, v: f64) -> Option<(BoundSide, f64)> {
        let u = self.unit(v);
        if u <= ON_BOUND_SHARE {
            Some((BoundSide::Lower, self.lo))
        } else if u >= 1.0 - ON_BOUND_SHARE {
            Some((BoundSide::Upper, self.hi))
        } else {
            None
        }
    }

    /// Value at optimizer coordinate θ.
    pub fn value(&self, theta: f64) -> f64 {
        self.from_unit(logistic(theta))
    }
}
