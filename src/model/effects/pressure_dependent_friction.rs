//! `pressure_dependent_friction` (docs/model.md, "Missing-physics catalog"; torque loss):
//! the supply pressure presses the vanes out, so the Coulomb friction grows by
//! k·max(p_inlet − p_e, 0), N·m.

use super::{Category, CatalogEffect, Effect, Term};
use crate::model::spec::{effect_params, Domain, OffValue, ParamSpec, SizeLaw};

/// The effect (see the module documentation).
pub struct PressureDependentFriction;

effect_params! {
    /// Its parameter k; off at the bottom of its search range.
    Effect::PressureDependentFriction {
        K_FRIC_P k_fric_p: "N*m/Pa" = 3e-8, Domain::NonNegative, (1e-10, 1e-6),
            "Coulomb friction per Pa of p_1 - p_e",
            size Some(SizeLaw::TORQUE), off OffValue::SearchLower;
    }
}

impl Term for PressureDependentFriction {
    /// T_c + k·max(p_inlet − p_e, 0).
    fn coulomb_nm(&self, own: &[f64], t_coulomb: f64, p_inlet: f64, p_e: f64) -> f64 {
        t_coulomb + own[K_FRIC_P] * (p_inlet - p_e).max(0.0)
    }
}

impl CatalogEffect for PressureDependentFriction {
    fn id(&self) -> &'static str {
        "pressure_dependent_friction"
    }
    fn category(&self) -> Category {
        Category::TorqueLoss
    }
    fn physics(&self) -> &'static str {
        "vanes are pressed out by supply pressure"
    }
    fn specs(&self) -> &'static [ParamSpec] {
        PARAMS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_is_the_base_model_and_hook_is_the_formula() {
        crate::model::testing::reproduces_base(Effect::PressureDependentFriction, &[("k_fric_p", 0.0)], 0.0);
        let h = PressureDependentFriction;
        assert_eq!(h.coulomb_nm(&[1e-8], 0.02, 6e5, 1e5), 0.02 + 1e-8 * 5e5);
        assert_eq!(h.coulomb_nm(&[1e-8], 0.02, 1e5, 2e5), 0.02);
    }
}
