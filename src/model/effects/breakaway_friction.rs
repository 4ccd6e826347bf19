//! `breakaway_friction` (docs/model.md, "Missing-physics catalog"; torque loss): static
//! friction above Coulomb at standstill, decaying to Coulomb with speed (Stribeck). The dry
//! friction becomes T_c + (T_s − T_c)·exp(−(ω/ω_s)²), N·m, where T_s keeps its excess over
//! the base T_c when other hooks raise T_c (e.g. `pressure_dependent_friction`).

use super::{Category, CatalogEffect, Effect, Term};
use crate::model::friction;
use crate::model::spec::{effect_params, Domain, OffValue, ParamId, ParamSpec, SizeLaw};

/// The effect (see the module documentation).
pub struct BreakawayFriction;

effect_params! {
    /// Its parameters: T_s and ω_s. Off: T_s = T_c (clamped into its search range) leaves the
    /// base model's friction; ω_s then does not matter and stays at its default.
    Effect::BreakawayFriction {
        /// Position of T_s among its parameters (`ParamId::T_STATIC` in `params` names it).
        T_STATIC t_static: "N*m" = 0.06, Domain::NonNegative, (1e-3, 0.5),
            "static (breakaway) friction torque",
            size Some(SizeLaw::TORQUE), off OffValue::BaseClamped(ParamId::T_COULOMB);
        /// Position of ω_s among its parameters (`ParamId::W_STRIBECK` in `params` names it).
        W_STRIBECK w_stribeck: "rad/s" = 30.0, Domain::Positive, (1.0, 500.0),
            "Stribeck speed (the excess over Coulomb falls to 1/e)",
            size Some(SizeLaw::SPEED), off OffValue::Default;
    }
}

impl Term for BreakawayFriction {
    /// T_c + (T_s + (T_c − T_c,base) − T_c)·exp(−(ω/ω_s)²), with T_c = `dry`.
    fn dry_nm(&self, own: &[f64], dry: f64, t_coulomb_base: f64, omega: f64) -> f64 {
        let t_static = own[T_STATIC] + (dry - t_coulomb_base);
        friction::stribeck_dry(omega, dry, t_static, own[W_STRIBECK])
    }
}

impl CatalogEffect for BreakawayFriction {
    fn id(&self) -> &'static str {
        "breakaway_friction"
    }
    fn category(&self) -> Category {
        Category::TorqueLoss
    }
    fn physics(&self) -> &'static str {
        "static friction above Coulomb at standstill (Stribeck)"
    }
    fn specs(&self) -> &'static [ParamSpec] {
        PARAMS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_is_the_base_model() {
        crate::model::testing::reproduces_base(Effect::BreakawayFriction, &[], 0.0);
    }

    #[test]
    fn hook_is_the_stribeck_curve() {
        let own = [0.05, 5.0];
        let d = BreakawayFriction.dry_nm(&own, 0.02, 0.02, 3.0);
        assert_eq!(d, 0.02 + (0.05 - 0.02) * (-(3.0f64 / 5.0).powi(2)).exp());
        assert_eq!(BreakawayFriction.dry_nm(&own, 0.02, 0.02, 0.0), 0.05);
    }
}
