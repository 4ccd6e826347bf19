//! `dead_volume_carryover` (docs/model.md, "Missing-physics catalog"; inlet flow): air left
//! in the dead volume at discharge pressure is carried back to the inlet side,
//! p_discharge·V_carry·z·|ω|/(2π·R·T0), kg/s.

use super::{Category, CatalogEffect, Effect, Term};
use crate::model::spec::{effect_params, Domain, OffValue, ParamSpec, SizeLaw};
use crate::units::constants::RT0;
use std::f64::consts::PI;

/// The effect (see the module documentation).
pub struct DeadVolumeCarryover;

effect_params! {
    /// Its parameter V_carry; off at the bottom of its search range.
    Effect::DeadVolumeCarryover {
        V_CARRY v_carry: "m3" = 0.05e-6, Domain::NonNegative, (1e-9, 1e-6),
            "volume carried back at discharge pressure per compartment",
            size Some(SizeLaw::VOLUME), off OffValue::SearchLower;
    }
}

impl Term for DeadVolumeCarryover {
    /// p_discharge·V_carry·z·|ω|/(2π·R·T0).
    fn carryover_kg_s(&self, own: &[f64], p_discharge: f64, omega: f64, vanes: f64) -> Option<f64> {
        Some(p_discharge * own[V_CARRY] * vanes * omega.abs() / (2.0 * PI * RT0))
    }
}

impl CatalogEffect for DeadVolumeCarryover {
    fn id(&self) -> &'static str {
        "dead_volume_carryover"
    }
    fn category(&self) -> Category {
        Category::InletFlow
    }
    fn physics(&self) -> &'static str {
        "air left in the dead volume at discharge pressure is carried back to the inlet side"
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
        crate::model::testing::reproduces_base(Effect::DeadVolumeCarryover, &[("v_carry", 0.0)], 0.0);
        let m = DeadVolumeCarryover.carryover_kg_s(&[1e-7], 2e5, -100.0, 5.0);
        assert_eq!(m, Some(2e5 * 1e-7 * 5.0 * 100.0 / (2.0 * PI * RT0)));
    }
}
