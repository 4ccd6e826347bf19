//! `vane_friction_speed_squared` (docs/model.md, "Missing-physics catalog"; torque loss):
//! vane-tip friction from the centrifugal force, and windage: c₂·ω·|ω|, N·m, added to the
//! smooth part of the friction.

use super::{Category, CatalogEffect, Effect, Term};
use crate::model::spec::{effect_params, Domain, OffValue, ParamSpec, SizeLaw};

/// The effect (see the module documentation).
pub struct VaneFrictionSpeedSquared;

effect_params! {
    /// Its parameter c₂; off at the bottom of its search range (c₂ = 0 is outside the log-space
    /// search).
    Effect::VaneFrictionSpeedSquared {
        C_W2 c_w2: "N*m*s2/rad2" = 1e-8, Domain::NonNegative, (1e-10, 1e-6),
            "friction torque per (rad/s)² (vane tips, windage)",
            size Some(SizeLaw::TORQUE_PER_SPEED2), off OffValue::SearchLower;
    }
}

impl Term for VaneFrictionSpeedSquared {
    /// wet + c₂·ω·|ω|.
    fn wet_nm(&self, own: &[f64], wet: f64, omega: f64) -> f64 {
        wet + own[C_W2] * omega * omega.abs()
    }
}

impl CatalogEffect for VaneFrictionSpeedSquared {
    fn id(&self) -> &'static str {
        "vane_friction_speed_squared"
    }
    fn category(&self) -> Category {
        Category::TorqueLoss
    }
    fn physics(&self) -> &'static str {
        "vane-tip friction from centrifugal force, windage"
    }
    fn specs(&self) -> &'static [ParamSpec] {
        PARAMS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_is_the_base_model_and_hook_is_odd() {
        crate::model::testing::reproduces_base(Effect::VaneFrictionSpeedSquared, &[("c_w2", 0.0)], 0.0);
        let t = VaneFrictionSpeedSquared.wet_nm(&[2e-8], 0.0, 100.0);
        assert_eq!(t, 2e-8 * 100.0 * 100.0);
        assert_eq!(VaneFrictionSpeedSquared.wet_nm(&[2e-8], 0.0, -100.0), -t);
    }
}
