//! Motor parameters: names, units, defaults and bounds (SPEC §1.6, §5), and the one place
//! where unchecked values become checked parameters (as linfa's `ParamGuard`).
//!
//! Every parameter is SI. The names are the contract used in fit files and on the command
//! line; they must not change.

use crate::model::effects::Effect;
use std::fmt;

/// What values a parameter may take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Domain {
    /// Strictly positive (searched in log space).
    Positive,
    /// Zero or positive (searched in log space between its bounds).
    NonNegative,
    /// Closed interval [lo, hi] (searched through a logistic map).
    Interval(f64, f64),
    /// Whole number in [lo, hi] (never estimated).
    Integer(u32, u32),
}

/// Static description of one named parameter.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    pub name: &'static str,
    pub unit: &'static str,
    pub default: f64,
    pub domain: Domain,
    /// Search range for estimation (lo, hi) in SI; log-spaced for positive parameters.
    pub search: (f64, f64),
    /// The effect that adds this parameter, or `None` for the base model.
    pub effect: Option<Effect>,
    pub meaning: &'static str,
}

macro_rules! params {
    ($( $field:ident : $unit:literal = $default:expr, $domain:expr, ($lo:expr, $hi:expr), $effect:expr, $meaning:literal; )*) => {
        /// Checked motor parameters, SI units. The only way to build them is
        /// [`ParamSet::check`] (or a default), so every value has passed its check; read them
        /// through the accessor of the same name.
        #[derive(Debug, Clone, PartialEq)]
        pub struct MotorParams { $( $field: f64, )* }

        /// Every parameter, in a fixed order (the order of fit files and reports).
        pub const PARAMS: &[ParamSpec] = &[
            $( ParamSpec { name: stringify!($field), unit: $unit, default: $default, domain: $domain,
                           search: ($lo, $hi), effect: $effect, meaning: $meaning }, )*
        ];

        impl MotorParams {
            $(
                #[doc = concat!($meaning, ", ", $unit, ".")]
                pub fn $field(&self) -> f64 { self.$field }
            )*
            /// Value of a named parameter (`None` for an unknown name).
            pub fn get(&self, name: &str) -> Option<f64> {
                match name { $( stringify!($field) => Some(self.$field), )* _ => None }
            }
            fn set_unchecked(&mut self, name: &str, value: f64) -> bool {
                match name { $( stringify!($field) => { self.$field = value; true } )* _ => false }
            }
            fn defaults() -> Self {
                Self { $( $field: $default, )* }
            }
        }
    };
}

use Domain::{Integer, Interval, NonNegative, Positive};
params! {
    c_in1: "m3/(s*Pa)" = 6.758282e-9, Positive, (5e-10, 5e-8), None, "sonic conductance of the inlet duct (port 1 to volume 1)";
    c_out2: "m3/(s*Pa)" = 6.758282e-9, Positive, (5e-10, 5e-8), None, "sonic conductance of the outlet duct (volume 2 to port 2)";
    c_ext: "m3/(s*Pa)" = 1.170707e-8, Positive, (1e-9, 1e-7), None, "sonic conductance of the exhaust path (volume e to atmosphere)";
    c_1e: "m3/(s*Pa)" = 2.077886e-9, NonNegative, (1e-11, 2e-8), None, "leakage conductance volume 1 to volume e";
    c_2e: "m3/(s*Pa)" = 2.077886e-9, NonNegative, (1e-11, 2e-8), None, "leakage conductance volume 2 to volume e";
    c_12: "m3/(s*Pa)" = 7.616275e-10, NonNegative, (1e-12, 1e-8), None, "leakage conductance volume 1 to volume 2";
    b_crit: "1" = 0.5, Interval(0.05, 0.95), (0.2, 0.6), None, "critical pressure ratio of every nozzle";
    z: "1" = 5.0, Integer(2, 16), (5.0, 5.0), None, "number of vanes";
    v_disp: "m3" = 3.8e-6, Positive, (1e-7, 1e-3), None, "nominal displacement z*V_fill";
    eps: "1" = 1.071, Interval(1.0, 2.0), (1.0, 1.5), None, "expansion ratio V_exp/V_fill";
    v_dead: "m3" = 0.10e-6, NonNegative, (0.0, 1e-6), None, "dead volume per compartment";
    n_poly: "1" = 1.3, Interval(1.0, 1.4), (1.0, 1.4), None, "polytropic index";
    vol1: "m3" = 2e-6, Positive, (1e-7, 1e-4), None, "lumped volume at the port-1 inlet of the stator";
    vol2: "m3" = 2e-6, Positive, (1e-7, 1e-4), None, "lumped volume at the port-2 inlet of the stator";
    vole: "m3" = 2e-6, Positive, (1e-7, 1e-4), None, "lumped volume at the exhaust inlet of the stator";
    inertia: "kg*m2" = 2e-4, Positive, (1e-6, 1e-2), None, "inertia of rotor, coupling and brake";
    t_coulomb: "N*m" = 0.02, NonNegative, (1e-3, 0.2), None, "Coulomb friction torque";
    visc: "N*m*s/rad" = 6e-5, NonNegative, (1e-6, 1e-3), None, "viscous friction coefficient";
    w_reg: "rad/s" = 0.2, Positive, (0.01, 5.0), None, "friction regularisation speed";
    t_static: "N*m" = 0.06, NonNegative, (1e-3, 0.5), Some(Effect::BreakawayFriction), "static (breakaway) friction torque";
    w_stribeck: "rad/s" = 30.0, Positive, (1.0, 500.0), Some(Effect::BreakawayFriction), "Stribeck speed";
    c_w2: "N*m*s2/rad2" = 1e-8, NonNegative, (1e-10, 1e-6), Some(Effect::VaneFrictionSpeedSquared), "speed-squared friction coefficient";
    g_seal: "1" = 1.0, NonNegative, (0.01, 10.0), Some(Effect::SpeedDependentLeakage), "extra leakage at standstill, relative";
    w_seal: "rad/s" = 300.0, Positive, (10.0, 5000.0), Some(Effect::SpeedDependentLeakage), "speed at which vane sealing halves the extra leakage";
    v_carry: "m3" = 0.05e-6, NonNegative, (1e-9, 1e-6), Some(Effect::DeadVolumeCarryover), "volume carried back at discharge pressure per compartment";
    w_fill: "rad/s" = 3000.0, Positive, (100.0, 1e5), Some(Effect::IncompleteFilling), "speed at which filling reaches half the pressure difference";
    k_fric_p: "N*m/Pa" = 3e-8, NonNegative, (1e-10, 1e-6), Some(Effect::PressureDependentFriction), "Coulomb friction per Pa of p_1 - p_e";
    tau_sensor: "s" = 0.5, Positive, (1e-3, 10.0), Some(Effect::SensorLag), "first-order lag of the flow and speed sensors";
    valve_tau: "s" = 0.05, Positive, (1e-3, 1.0), Some(Effect::ValveDynamics), "time constant of the pressure control valve";
    valve_zeta: "1" = 0.7, Positive, (0.1, 3.0), Some(Effect::ValveDynamics), "damping ratio of the second-order valve";
}

/// Looks up a parameter's description by name.
pub fn spec(name: &str) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|p| p.name == name)
}

impl Default for MotorParams {
    /// Motor AR034-11 with the appendix conductances (SPEC §1.6).
    fn default() -> Self {
        Self::defaults()
    }
}

impl MotorParams {
    /// Number of vanes as a count.
    pub fn vanes(&self) -> u32 {
        self.z.round() as u32
    }

    /// Returns a copy with one parameter changed, checked.
    pub fn with(&self, name: &str, value: f64) -> Result<Self, ParamError> {
        let mut set = ParamSet::from(self.clone());
        set.set(name, value)?;
        set.check()
    }
}

/// An error in a parameter value or name.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamError {
    pub name: String,
    pub message: String,
}

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "parameter '{}': {}", self.name, self.message)
    }
}

impl std::error::Error for ParamError {}

/// Unchecked parameters: defaults overridden by whatever a file or the user gave.
#[derive(Debug, Clone, Default)]
pub struct ParamSet {
    values: MotorParams,
}

impl From<MotorParams> for ParamSet {
    fn from(values: MotorParams) -> Self {
        Self { values }
    }
}

impl ParamSet {
    /// Sets a named parameter; unknown names are an error (never silently ignored).
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), ParamError> {
        if self.values.set_unchecked(name, value) {
            Ok(())
        } else {
            Err(ParamError {
                name: name.to_string(),
                message: "unknown parameter name".into(),
            })
        }
    }

    /// Checks every value against its domain and the cross-constraints of the model.
    pub fn check(self) -> Result<MotorParams, ParamError> {
        let p = self.values;
        for spec in PARAMS {
            let v = p.get(spec.name).expect("every spec names a field");
            check_domain(spec, v)?;
        }
        let v_fill = p.v_disp / p.z.round();
        if p.v_dead >= v_fill {
            return Err(ParamError {
                name: "v_dead".into(),
                message: format!(
                    "dead volume {:.3e} m3 must be smaller than the filling volume v_disp/z = {v_fill:.3e} m3",
                    p.v_dead
                ),
            });
        }
        Ok(p)
    }
}

fn check_domain(spec: &ParamSpec, v: f64) -> Result<(), ParamError> {
    let fail = |message: String| {
        Err(ParamError {
            name: spec.name.to_string(),
            message,
        })
    };
    if !v.is_finite() {
        return fail(format!("value {v} is not a finite number"));
    }
    match spec.domain {
        Positive if v <= 0.0 => fail(format!("must be > 0 {}, got {v:e}", spec.unit)),
        NonNegative if v < 0.0 => fail(format!("must be >= 0 {}, got {v:e}", spec.unit)),
        Interval(lo, hi) if !(lo..=hi).contains(&v) => {
            fail(format!("must lie in [{lo}, {hi}] {}, got {v}", spec.unit))
        }
        Integer(lo, hi) if v.fract() != 0.0 || v < f64::from(lo) || v > f64::from(hi) => {
            fail(format!("must be a whole number in [{lo}, {hi}], got {v}"))
        }
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_pass_their_own_check_and_names_are_unique() {
        assert!(ParamSet::default().check().is_ok());
        let mut names: Vec<_> = PARAMS.iter().map(|p| p.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), PARAMS.len());
    }

    #[test]
    fn non_physical_values_are_refused_with_their_name() {
        let p = MotorParams::default();
        assert_eq!(p.with("vol1", -1e-6).unwrap_err().name, "vol1");
        assert_eq!(p.with("c_in1", 0.0).unwrap_err().name, "c_in1");
        assert_eq!(p.with("n_poly", 1.5).unwrap_err().name, "n_poly");
        assert_eq!(p.with("z", 4.5).unwrap_err().name, "z");
        assert_eq!(p.with("v_dead", 1e-6).unwrap_err().name, "v_dead");
        assert_eq!(p.with("visc", f64::NAN).unwrap_err().name, "visc");
        assert!(p
            .with("no_such", 1.0)
            .unwrap_err()
            .message
            .contains("unknown"));
    }

    #[test]
    fn every_effect_parameter_is_declared() {
        for e in Effect::ALL {
            for name in e.parameters() {
                assert_eq!(spec(name).unwrap().effect, Some(e), "{name}");
            }
        }
    }
}
