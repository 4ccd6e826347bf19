//! `valve_dynamics` (docs/model.md, "Missing-physics catalog"; supply): the pressure
//! control valve is slower or of higher order than first order: τ²·p̈ + 2ζτ·ṗ + p = p_cmd
//! instead of τ·ṗ + p = p_cmd. The valve exists in the control studies without the effect
//! too (first order with τ); the reference experiments are driven by the recorded valve
//! output, so it never shows in them.

use super::{Category, CatalogEffect, Effect, ShowsIn, SupplyValve, Term};
use crate::model::spec::{effect_params, Domain, OffValue, ParamSpec};

/// The effect (see the module documentation).
pub(crate) struct ValveDynamics;

effect_params! {
    /// Its parameters τ and ζ; off at the bottom of their search ranges.
    Effect::ValveDynamics {
        VALVE_TAU valve_tau: "s" = 0.05, Domain::Positive, (1e-3, 1.0),
            "time constant of the pressure control valve",
            size None, off OffValue::SearchLower;
        VALVE_ZETA valve_zeta: "1" = 0.7, Domain::Positive, (0.1, 3.0),
            "damping ratio of the second-order valve",
            size None, off OffValue::SearchLower;
    }
}

impl Term for ValveDynamics {
    /// Second order with τ and ζ when switched on, otherwise first order with τ.
    fn supply_valve(&self, own: &[f64], switched_on: bool) -> Option<SupplyValve> {
        Some(SupplyValve {
            tau_s: own[VALVE_TAU],
            zeta: switched_on.then(|| own[VALVE_ZETA]),
        })
    }
}

impl CatalogEffect for ValveDynamics {
    fn id(&self) -> &'static str {
        "valve_dynamics"
    }
    fn category(&self) -> Category {
        Category::Supply
    }
    fn physics(&self) -> &'static str {
        "pressure control valve slower or higher-order than first order"
    }
    fn specs(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn shows_in(&self) -> ShowsIn {
        ShowsIn::Never {
            reason: "the recorded port-1 pressure is the valve's output and drives the \
                     simulation; the datasheet and outlet-throttle supplies are constant \
                     and the pressure ramp is ~10^3 times slower than a valve, so valve \
                     dynamics cannot show in these experiments (and the model has no \
                     valve)",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::effects::EffectSet;
    use crate::model::testing::{reproduces_base, supply_valve};

    #[test]
    fn off_is_the_base_model_and_the_valve_follows_the_switch() {
        reproduces_base(Effect::ValveDynamics, &[], 0.0);
        let off = supply_valve(EffectSet::empty());
        assert_eq!(off, SupplyValve { tau_s: 0.05, zeta: None });
        let on = supply_valve(EffectSet::empty().with(Effect::ValveDynamics));
        assert_eq!(on.zeta, Some(0.7));
    }
}
