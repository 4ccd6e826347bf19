//! `speed_dependent_leakage` (docs/model.md, "Missing-physics catalog"; internal leakage):
//! the vanes seal better as the centrifugal force grows, so every leakage conductance is
//! multiplied by 1 + g/(1 + (ω/ω_seal)²).

use super::{Category, CatalogEffect, Effect, Term};
use crate::model::spec::{effect_params, Domain, OffValue, ParamSpec, SizeLaw};

/// The effect (see the module documentation).
pub struct SpeedDependentLeakage;

effect_params! {
    /// Its parameters g and ω_seal; off: g at the bottom of its search range, ω_seal at its
    /// default (it does not matter when g ≈ 0).
    Effect::SpeedDependentLeakage {
        G_SEAL g_seal: "1" = 1.0, Domain::NonNegative, (0.01, 10.0),
            "extra leakage at standstill, relative",
            size None, off OffValue::SearchLower;
        W_SEAL w_seal: "rad/s" = 300.0, Domain::Positive, (10.0, 5000.0),
            "speed at which vane sealing halves the extra leakage",
            size Some(SizeLaw::SPEED), off OffValue::Default;
    }
}

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
