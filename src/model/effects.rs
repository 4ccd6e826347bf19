//! The missing-physics catalog (SPEC §5): effects the base model leaves out, each a model
//! extension with its own parameters, switched on by id.

use std::fmt;
use std::str::FromStr;

/// Where in the model an effect acts (SPEC §5 categories).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Category {
    TorqueLoss,
    InternalLeakage,
    InletFlow,
    OutletFlow,
    Measurement,
    Supply,
}

impl Category {
    pub fn id(self) -> &'static str {
        match self {
            Category::TorqueLoss => "torque_loss",
            Category::InternalLeakage => "internal_leakage",
            Category::InletFlow => "inlet_flow",
            Category::OutletFlow => "outlet_flow",
            Category::Measurement => "measurement",
            Category::Supply => "supply",
        }
    }
}

/// A catalogued effect. The ids are fixed once used (SPEC §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Effect {
    BreakawayFriction,
    VaneFrictionSpeedSquared,
    SpeedDependentLeakage,
    DeadVolumeCarryover,
    IncompleteFilling,
    PressureDependentFriction,
    SensorLag,
    ValveDynamics,
}

impl Effect {
    pub const ALL: [Effect; 8] = [
        Effect::BreakawayFriction,
        Effect::VaneFrictionSpeedSquared,
        Effect::SpeedDependentLeakage,
        Effect::DeadVolumeCarryover,
        Effect::IncompleteFilling,
        Effect::PressureDependentFriction,
        Effect::SensorLag,
        Effect::ValveDynamics,
    ];

    pub fn id(self) -> &'static str {
        match self {
            Effect::BreakawayFriction => "breakaway_friction",
            Effect::VaneFrictionSpeedSquared => "vane_friction_speed_squared",
            Effect::SpeedDependentLeakage => "speed_dependent_leakage",
            Effect::DeadVolumeCarryover => "dead_volume_carryover",
            Effect::IncompleteFilling => "incomplete_filling",
            Effect::PressureDependentFriction => "pressure_dependent_friction",
            Effect::SensorLag => "sensor_lag",
            Effect::ValveDynamics => "valve_dynamics",
        }
    }

    pub fn category(self) -> Category {
        match self {
            Effect::BreakawayFriction
            | Effect::VaneFrictionSpeedSquared
            | Effect::PressureDependentFriction => Category::TorqueLoss,
            Effect::SpeedDependentLeakage => Category::InternalLeakage,
            Effect::DeadVolumeCarryover | Effect::IncompleteFilling => Category::InletFlow,
            Effect::SensorLag => Category::Measurement,
            Effect::ValveDynamics => Category::Supply,
        }
    }

    /// Names of the parameters the effect adds (see `params::PARAMS`).
    pub fn parameters(self) -> &'static [&'static str] {
        match self {
            Effect::BreakawayFriction => &["t_static", "w_stribeck"],
            Effect::VaneFrictionSpeedSquared => &["c_w2"],
            Effect::SpeedDependentLeakage => &["g_seal", "w_seal"],
            Effect::DeadVolumeCarryover => &["v_carry"],
            Effect::IncompleteFilling => &["w_fill"],
            Effect::PressureDependentFriction => &["k_fric_p"],
            Effect::SensorLag => &["tau_sensor"],
            Effect::ValveDynamics => &["valve_tau", "valve_zeta"],
        }
    }

    /// One line of physics for reports.
    pub fn physics(self) -> &'static str {
        match self {
            Effect::BreakawayFriction => "static friction above Coulomb at standstill (Stribeck)",
            Effect::VaneFrictionSpeedSquared => "vane-tip friction from centrifugal force, windage",
            Effect::SpeedDependentLeakage => "vanes seal better as centrifugal force grows",
            Effect::DeadVolumeCarryover => {
                "air left in the dead volume at discharge pressure is carried back to the inlet side"
            }
            Effect::IncompleteFilling => {
                "the compartment does not reach port pressure before cut-off at speed"
            }
            Effect::PressureDependentFriction => "vanes are pressed out by supply pressure",
            Effect::SensorLag => "a sensor's first-order lag in transient recordings",
            Effect::ValveDynamics => "pressure control valve slower or higher-order than first order",
        }
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

impl FromStr for Effect {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Effect::ALL
            .into_iter()
            .find(|e| e.id() == s)
            .ok_or_else(|| {
                let known: Vec<_> = Effect::ALL.iter().map(|e| e.id()).collect();
                format!("unknown effect '{s}' (known: {})", known.join(", "))
            })
    }
}

/// The set of effects switched on in a model (small, ordered, no duplicates).
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub struct EffectSet(u16);

impl EffectSet {
    pub fn empty() -> Self {
        Self(0)
    }
    pub fn with(mut self, e: Effect) -> Self {
        self.0 |= 1 << (e as u16);
        self
    }
    pub fn contains(&self, e: Effect) -> bool {
        self.0 & (1 << (e as u16)) != 0
    }
    pub fn iter(&self) -> impl Iterator<Item = Effect> + '_ {
        Effect::ALL.into_iter().filter(|e| self.contains(*e))
    }
    pub fn is_empty(&self) -> bool {
        self.0 == 0
    }
    pub fn ids(&self) -> Vec<String> {
        self.iter().map(|e| e.id().to_string()).collect()
    }
    /// Parses a comma-separated list of ids ("" gives the empty set).
    pub fn parse_list(list: &str) -> Result<Self, String> {
        list.split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .try_fold(Self::empty(), |set, id| Ok(set.with(id.parse()?)))
    }
}

impl FromIterator<Effect> for EffectSet {
    fn from_iter<I: IntoIterator<Item = Effect>>(iter: I) -> Self {
        iter.into_iter().fold(Self::empty(), Self::with)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_and_unknown_is_refused() {
        for e in Effect::ALL {
            assert_eq!(e.id().parse::<Effect>().unwrap(), e);
        }
        assert!("magic_friction"
            .parse::<Effect>()
            .unwrap_err()
            .contains("unknown effect"));
        let set = EffectSet::parse_list("sensor_lag, breakaway_friction").unwrap();
        assert_eq!(set.ids(), vec!["breakaway_friction", "sensor_lag"]);
    }
}
