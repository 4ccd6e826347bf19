//! What a fit says of its estimate (`statistics` in a fit file, docs/formats.md, "Fit
//! files"): how the values and their intervals were obtained ([`EstimateMethod`],
//! [`UncertaintyMethod`], named in the file by their ids) and how well the estimate
//! reproduces the data ([`GoodnessOfFit`]). The record lives here, below `estimate`, so that
//! the fit's outcome (`estimate::FitOutcome::goodness`, which computes it in
//! `estimate::fit::goodness`) and the file's [`FitStatistics`] hold the same one.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::Value;

/// What a fit's exported values are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum EstimateMethod {
    /// The maximum of the likelihood of the recorded rows (`estimate::fit`).
    MaximumLikelihood,
}

impl EstimateMethod {
    /// Every method, in the order messages list them.
    pub const ALL: [EstimateMethod; 1] = [EstimateMethod::MaximumLikelihood];

    /// The method's name in files.
    pub fn id(self) -> &'static str {
        match self {
            EstimateMethod::MaximumLikelihood => "maximum_likelihood",
        }
    }

    /// The method of an id ([`EstimateMethod::id`]).
    pub fn from_id(id: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.id() == id)
    }
}

/// How intervals are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum UncertaintyMethod {
    /// Profile likelihood (curvature sizes the steps and fills in if it fails).
    Profile,
    /// Curvature of χ² only (fast).
    Curvature,
    /// No intervals.
    None,
}

impl UncertaintyMethod {
    /// Every method, in the order messages list them.
    pub const ALL: [UncertaintyMethod; 3] = [
        UncertaintyMethod::Profile,
        UncertaintyMethod::Curvature,
        UncertaintyMethod::None,
    ];

    /// The method's name in files and on the command line.
    pub fn id(self) -> &'static str {
        match self {
            UncertaintyMethod::Profile => "profile",
            UncertaintyMethod::Curvature => "curvature",
            UncertaintyMethod::None => "none",
        }
    }

    /// The method of an id ([`UncertaintyMethod::id`]).
    pub fn from_id(id: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.id() == id)
    }
}

/// What a field that takes one of `ids` says of anything else: `must be "a", "b" or "c",
/// not <found>` (`found` as JSON).
pub(crate) fn must_be(ids: &[&str], found: &Value) -> String {
    let quoted: Vec<String> = ids.iter().map(|id| format!("\"{id}\"")).collect();
    let list = match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => quoted.join(""),
    };
    format!("must be {list}, not {found}")
}

/// A method written as its id and read back from it; anything else is refused with
/// [`must_be`].
macro_rules! by_id {
    ($method:ident) => {
        impl Serialize for $method {
            fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.id())
            }
        }

        impl<'de> Deserialize<'de> for $method {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                let v = Value::deserialize(d)?;
                v.as_str().and_then($method::from_id).ok_or_else(|| {
                    let ids = $method::ALL.map($method::id);
                    serde::de::Error::custom(must_be(&ids, &v))
                })
            }
        }
    };
}

by_id!(EstimateMethod);
by_id!(UncertaintyMethod);

/// How well the estimate reproduces the data, against the data's own noise (computed in
/// `estimate::fit::goodness`, eqs. \[1\]–\[2\]; written in the fit file's `statistics` in
/// this order).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GoodnessOfFit {
    /// χ² of the likelihood at the estimate (offsets profiled out; the rows against the
    /// data's own σ).
    pub chi2: f64,
    /// Compared points.
    pub n_points: usize,
    /// Degrees of freedom, n − k: zero or negative when the fit estimates as many
    /// parameters as it has rows or more (files written before this clamped it to ≥ 1).
    pub dof: i64,
    /// χ²/dof; `None` (`null` in the file) when dof ≤ 0, where it is undefined.
    pub(crate) chi2_per_dof: Option<f64>,
    /// r: RMS residual over noise, channels averaged alike (eq. \[1\]).
    pub noise_ratio: f64,
    /// The largest r of a model that reaches the noise (eq. \[2\]).
    pub noise_ratio_limit: f64,
    /// r ≤ the limit: the model reaches the noise.
    pub noise_reached: bool,
    /// s = max(1, r): the factor by which intervals are widened (1 when the noise is
    /// reached).
    pub interval_scale: f64,
}

/// How the fit's estimate and intervals were obtained and how well it reproduces the data
/// (`statistics` in the file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitStatistics {
    /// What the exported values are.
    pub estimate: EstimateMethod,
    /// How intervals were computed.
    pub uncertainty: UncertaintyMethod,
    /// The goodness of fit (its keys inline, after `uncertainty`).
    #[serde(flatten)]
    pub goodness: GoodnessOfFit,
    /// Cost J of the multi-start's best start (`cost` is J at the estimate).
    pub best_start_cost: f64,
    /// The systematic errors profiled out at the estimate, SI (sensor offsets in the
    /// sensor's unit, the supply-pressure sensor's offset in Pa), by label.
    #[serde(default)]
    pub nuisances: serde_json::Map<String, Value>,
    /// Channels whose noise estimate was widened to their residual scatter for the
    /// intervals, by "file column": the factor (> 1).
    #[serde(default)]
    pub widened_noise: serde_json::Map<String, Value>,
    /// χ² of the likelihood that the estimate minimises and the intervals are profiled on:
    /// each channel's σ widened per `widened_noise`, the nuisances' prior terms
    /// (β̂/τ)² included. (`goodness.chi2` is the goodness of fit: the rows against the
    /// data's own σ, without the priors.) `None` in files written before it existed.
    #[serde(default)]
    pub likelihood_chi2: Option<f64>,
    /// Rise of `likelihood_chi2` that bounds a 95 % profile interval, χ²₁(0.95)·s² with s
    /// the widened likelihood's own interval scale. `None` in files written before it
    /// existed or when no interval could be computed.
    #[serde(default)]
    pub profile_threshold: Option<f64>,
    /// The estimated parameters' values (SI) at which the supply-pressure sensor offset's
    /// effect on the rows was linearised; with `widened_noise` it rebuilds the likelihood
    /// exactly (`estimate::fit::fit_likelihood`). Empty in files written before it existed.
    #[serde(default)]
    pub linearised_at: serde_json::Map<String, Value>,
    /// The motor prior of the estimated parameters (docs/estimation.md, "Priors"): the
    /// estimate minimises `likelihood_chi2` + `prior_chi2`, and the covariance and the
    /// profiles hold the prior's precision. Empty without a prior (`--priors none`, and
    /// files written before priors existed).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub prior: Vec<PriorEntry>,
    /// χ²_prior = Σ ((ln v − ln median)/sd_ln)² at the estimate (`None` without a prior).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prior_chi2: Option<f64>,
    /// The estimated parameters that ended on a bound of their search range: what depends
    /// on them is unreliable (docs/estimation.md, "Bounds"). Absent when none did.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub on_bound: Vec<BoundEntry>,
}

/// An estimate that ended on a bound of its search range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoundEntry {
    /// The parameter.
    pub parameter: String,
    /// `lower` or `upper`.
    pub side: String,
    /// The bound, SI.
    pub bound: f64,
}

/// One estimated parameter's log-normal prior as the fit file states it:
/// ln v ~ N(ln median, sd_ln²).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PriorEntry {
    /// The parameter.
    pub parameter: String,
    /// The median, SI (its default scaled to the motor's displacement).
    pub median: f64,
    /// Standard deviation of ln v.
    pub sd_ln: f64,
    /// Where the displacement was estimated with the other parameters (a page that does not
    /// print it): k of the size law the median follows, median·(v_disp/v̂_disp)^k with
    /// v̂_disp the fit's displacement (`ParamSpec::size_exponent`). Absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size_exponent: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The methods read and write their ids, and refuse anything else by listing them.
    #[test]
    fn methods_are_their_ids() {
        for m in UncertaintyMethod::ALL {
            let v = serde_json::to_value(m).unwrap();
            assert_eq!(v, Value::from(m.id()));
            assert_eq!(serde_json::from_value::<UncertaintyMethod>(v).unwrap(), m);
        }
        let m = EstimateMethod::MaximumLikelihood;
        assert_eq!(serde_json::to_value(m).unwrap(), "maximum_likelihood");
        let e = serde_json::from_value::<UncertaintyMethod>("bogus".into()).unwrap_err();
        assert_eq!(
            e.to_string(),
            r#"must be "profile", "curvature" or "none", not "bogus""#
        );
        let e = serde_json::from_value::<EstimateMethod>(3.into()).unwrap_err();
        assert_eq!(e.to_string(), r#"must be "maximum_likelihood", not 3"#);
    }
}
