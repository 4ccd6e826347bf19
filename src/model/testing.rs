//! Test helpers shared by the effect files of `model/effects/`: they build a motor, so they
//! sit above the catalog, the parameter registry and the motor (the catalog itself stands
//! below the registry).

use crate::model::effects::{Effect, EffectSet, SupplyValve};
use crate::model::motor::{Boundary, Load, Motor};
use crate::model::params::MotorParams;
use crate::numerics::ode::State;

/// States forward, reverse and at standstill.
const STATES: [State; 4] = [
    [6e5, 1.5e5, 1.3e5, 800.0],
    [3e5, 4e5, 2e5, -300.0],
    [2e5, 1e5, 1e5, 0.0],
    [5e5, 2e5, 1.2e5, 3.0],
];

/// The boundary of the checks.
fn boundary() -> Boundary {
    Boundary::supplied(7.3e5, 1.01325e5, Load::ViscousBrake { c_nm_s_rad: 2e-4 })
}

/// `effect` switched on with its parameters at their off values, then at `values`,
/// gives the base model's derivatives to within `tol` relative (0: bit for bit).
pub(crate) fn reproduces_base(effect: Effect, values: &[(&str, f64)], tol: f64) {
    let base = MotorParams::default();
    let mut p = base.clone();
    for s in effect.specs() {
        p = p.with(s.name, s.off_value(&base)).unwrap();
    }
    for (name, v) in values {
        p = p.with(name, *v).unwrap();
    }
    let on = Motor::new(p, EffectSet::empty().with(effect));
    let off = Motor::new(base, EffectSet::empty());
    for x in STATES {
        let (a, b) = (
            on.derivatives(&x, &boundary()),
            off.derivatives(&x, &boundary()),
        );
        for i in 0..4 {
            let d = (a[i] - b[i]).abs();
            assert!(
                d <= tol * b[i].abs(),
                "{effect} {x:?} [{i}]: {} vs {}",
                a[i],
                b[i]
            );
        }
    }
}

/// The supply valve of the default motor with `effects` switched on.
pub(crate) fn supply_valve(effects: EffectSet) -> SupplyValve {
    Motor::new(MotorParams::default(), effects).supply_valve()
}
