//! `speed_dependent_leakage` (docs/model.md, "Missing-physics catalog"; internal leakage):
//! the vanes seal better as the centrifugal force grows, so every leakage conductance is
//! multiplied by 1 + g/(1 + (ω/ω_seal)²).

use super::{Category, CatalogEffect, Effect, Term};
use crate::model::spec::{Domain, OffValue, ParamSpec, SizeLaw};

/// The effect (see the module documentation).
pub struct SpeedDependentLeakage;

const G_SEAL: usize = 0;
const W_SEAL: usize = 1;

/// Its parameters g and ω_seal; off: g at the bottom of its search range, ω_seal at its
/// default (it does not matter when g ≈ 0).
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "g_seal",
        unit: "1",
        default: 1.0,
        domain: Domain::NonNegative,
        search: (0.01, 10.0),
        effect: Some(Effect::SpeedDependentLeakage),
        off: OffValue::SearchLower,
        meaning: "extra leakage at standstill, relative",
        ..ParamSpec::EFFECT
    },
    ParamSpec {
        name: "w_seal",
        unit: "rad/s",
        default: 300.0,
        domain: Domain::Positive,
        search: (10.0, 5000.0),
        effect: Some(Effect::SpeedDependentLeakage),
        off: OffValue::Default,
        meaning: "speed at which vane sealing halves the extra leakage",
        size_exponent: Some(SizeLaw::SPEED),
        ..ParamSpec::EFFECT
    },
];

impl Term for SpeedDependentLeakage {
    /// 1 + g/(1 + (ω/ω_seal)²).
    fn leak_factor(&self, own: &[f64], omega: f64) -> Option<f64> {
        Some(1.0 + own[G_SEAL] / (1.0 + (omega / own[W_SEAL]).powi(2)))
    }
}

impl CatalogEffect for SpeedDependentLeakage {
    fn id(&self) -> &'static str {
        "speed_dependent_leakage"
    }
    fn category(&self) -> Category {
        Category::InternalLeakage
    }
    fn physics(&self) -> &'static str {
        "vanes seal better as centrifugal force grows"
    }
    fn specs(&self) -> &'static [ParamSpec] {
        PARAMS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_is_the_base_model_and_hook_halves_at_w_seal() {
        crate::model::testing::reproduces_base(Effect::SpeedDependentLeakage, &[("g_seal", 0.0)], 0.0);
        let own = [1.0, 300.0];
        assert_eq!(SpeedDependentLeakage.leak_factor(&own, 0.0), Some(2.0));
        assert_eq!(SpeedDependentLeakage.leak_factor(&own, 300.0), Some(1.5));
    }
}
