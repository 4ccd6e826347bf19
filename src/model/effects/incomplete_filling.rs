//! `incomplete_filling` (docs/model.md, "Missing-physics catalog"; inlet flow): at speed a
//! compartment does not reach the port pressure before cut-off; it is filled to p_e +
//! (p_inlet − p_e)·η(ω), η = 1/(1 + (ω/ω_f)²).

use super::{Category, CatalogEffect, Effect, Term};
use crate::model::spec::{effect_params, Domain, OffValue, ParamSpec, SizeLaw};

/// The effect (see the module documentation).
pub struct IncompleteFilling;

effect_params! {
    /// Its parameter ω_f; off at the top of its search range (filling complete at every speed
    /// reached).
    Effect::IncompleteFilling {
        W_FILL w_fill: "rad/s" = 3000.0, Domain::Positive, (100.0, 1e5),
            "speed at which filling reaches half the pressure difference",
            size Some(SizeLaw::SPEED), off OffValue::SearchUpper;
    }
}

impl Term for IncompleteFilling {
    /// p_e + (p_fill − p_e)·η(ω), η = 1/(1 + (ω/ω_f)²).
    fn filling_pressure(&self, own: &[f64], p_fill: f64, p_e: f64, omega: f64) -> f64 {
        let eta = 1.0 / (1.0 + (omega / own[W_FILL]).powi(2));
        p_e + (p_fill - p_e) * eta
    }
}

impl CatalogEffect for IncompleteFilling {
    fn id(&self) -> &'static str {
        "incomplete_filling"
    }
    fn category(&self) -> Category {
        Category::InletFlow
    }
    fn physics(&self) -> &'static str {
        "the compartment does not reach port pressure before cut-off at speed"
    }
    fn specs(&self) -> &'static [ParamSpec] {
        PARAMS
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn far_off_is_the_base_model_and_hook_is_half_at_w_fill() {
        crate::model::testing::reproduces_base(Effect::IncompleteFilling, &[("w_fill", 1e150)], 1e-12);
        let p = IncompleteFilling.filling_pressure(&[1000.0], 6e5, 1e5, 1000.0);
        assert_eq!(p, 1e5 + 5e5 * 0.5);
    }
}
