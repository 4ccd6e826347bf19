//! The missing-physics catalog (docs/model.md, "Missing-physics catalog"): effects the base
//! model leaves out, each a model extension with its own parameters, switched on by id.
//!
//! Every effect lives in its own file, which declares everything about it: its id,
//! category and one line of physics, its parameters ([`ParamSpec`], with the value that
//! switches each off), the experiments it can show in ([`ShowsIn`]), and where it acts in
//! the motor (the hooks of [`Term`]). Adding an effect is its file plus one line in the
//! `registry!` below; `params` assembles its parameters into
//! [`PARAMS`](crate::model::PARAMS) after those of the effects before it (the order of fit
//! files).
//!
//! The catalog stands on `spec` (the [`Effect`] handle and what a parameter is) and never
//! on `params`, which stands on the catalog: a hook reads its own parameter values (`own`),
//! and [`Term::add_to_balances`] every parameter of the motor as [`ParamValues`].
//!
//! Discovered terms ([`crate::model::extra::ExtraTerm`]) act through the same [`Term`]
//! hooks.

pub use crate::model::spec::Effect;
use crate::model::spec::{ParamSpec, ParamValues};
use crate::numerics::ode::State;
use std::fmt;
use std::str::FromStr;

/// Where in the model an effect acts (the categories of docs/model.md, "Missing-physics
/// catalog").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Category {
    /// A torque lost to friction or drag.
    TorqueLoss,
    /// Leakage between the motor's chambers.
    InternalLeakage,
    /// The filling of the compartments from the inlet side.
    InletFlow,
    /// The discharge of the compartments to the outlet side.
    OutletFlow,
    /// The sensors between the motor and the recording.
    Measurement,
    /// The supply in front of the motor.
    Supply,
}

impl Category {
    /// The category's id in files and reports.
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

/// In which experiments an effect can show (the model knows no experiment kinds; the
/// diagnosis maps "transient" to the kinds that are).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ShowsIn {
    /// In steady and in transient experiments.
    Any,
    /// Only in transient recordings; `reason` says why when a dataset has none.
    TransientOnly {
        /// Why steady experiments cannot show it (a sentence for reports).
        reason: &'static str,
    },
    /// In none of the reference experiments.
    Never {
        /// Why (a sentence for reports).
        reason: &'static str,
    },
}

/// The pressure control valve in front of the motor, as the model's parameters describe
/// it: τ·ṗ + p = p_cmd, or τ²·p̈ + 2ζτ·ṗ + p = p_cmd when ζ is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SupplyValve {
    /// Time constant τ, s.
    pub tau_s: f64,
    /// Damping ratio ζ of a second-order valve (`None`: first order).
    pub(crate) zeta: Option<f64>,
}

/// Where a term acts in the motor: hooks that the motor calls, for every effect switched
/// on, in registry order (and for every discovered term), at fixed points of its
/// arithmetic. Each default leaves the base model unchanged. `own` holds the term's own
/// parameter values, in the order of its [`CatalogEffect::specs`] (empty for a discovered
/// term).
pub trait Term: Sync {
    /// Factor on every leakage conductance (c_1e, c_2e, c_12), 1; `None` leaves them
    /// unchanged. Several factors multiply.
    fn leak_factor(&self, own: &[f64], omega: f64) -> Option<f64> {
        let _ = (own, omega);
        None
    }

    /// The pressure a compartment is filled to, Pa, given the pressure `p_fill` that the
    /// hooks before left (the inlet pressure in the base model) and p_e.
    fn filling_pressure(&self, own: &[f64], p_fill: f64, p_e: f64, omega: f64) -> f64 {
        let _ = (own, p_e, omega);
        p_fill
    }

    /// Mass carried back from the discharge to the inlet side, kg/s (`None`: none);
    /// `vanes` is the number of vanes z. Several carry-overs add.
    fn carryover_kg_s(&self, own: &[f64], p_discharge: f64, omega: f64, vanes: f64) -> Option<f64> {
        let _ = (own, p_discharge, omega, vanes);
        None
    }

    /// The Coulomb friction torque, N·m, given `t_coulomb` as the hooks before left it (the
    /// base T_c first), the inlet pressure and p_e, Pa.
    fn coulomb_nm(&self, own: &[f64], t_coulomb: f64, p_inlet: f64, p_e: f64) -> f64 {
        let _ = (own, p_inlet, p_e);
        t_coulomb
    }

    /// The magnitude of the dry friction, N·m, given `dry` as the hooks before left it (the
    /// Coulomb torque of [`Term::coulomb_nm`] first) and the base model's T_c.
    fn dry_nm(&self, own: &[f64], dry: f64, t_coulomb_base: f64, omega: f64) -> f64 {
        let _ = (own, t_coulomb_base, omega);
        dry
    }

    /// The odd, smooth part of the friction, N·m, given `wet` as the hooks before left it
    /// (the viscous d·ω first).
    fn wet_nm(&self, own: &[f64], wet: f64, omega: f64) -> f64 {
        let _ = (own, omega);
        wet
    }

    /// Adds this term's contributions to the balances, indexed by
    /// [`crate::model::extra::BalanceId`]: a loss torque (N·m) and mass flows into V_1,
    /// V_2, V_e (kg/s), at state `x`; `params` holds every parameter of the motor.
    fn add_to_balances(
        &self,
        own: &[f64],
        params: ParamValues<'_>,
        x: &State,
        p_atm_pa: f64,
        acc: &mut [f64; 4],
    ) {
        let _ = (own, params, x, p_atm_pa, acc);
    }

    /// What a sensor records of a channel y sampled at `times` (the channel itself when the
    /// term does not act on measurement).
    fn measure(&self, own: &[f64], times: &[f64], y: Vec<f64>) -> Vec<f64> {
        let _ = (own, times);
        y
    }

    /// The supply valve this term describes, switched on or not (`None`: it describes no
    /// valve). Asked of every catalog entry, because the valve exists without the effect.
    fn supply_valve(&self, own: &[f64], switched_on: bool) -> Option<SupplyValve> {
        let _ = (own, switched_on);
        None
    }
}

/// A catalog effect: what it is, its parameters, where it can show, and (through [`Term`])
/// where it acts.
pub trait CatalogEffect: Term {
    /// The id in files and on the command line (fixed once used; docs/model.md,
    /// "Missing-physics catalog").
    fn id(&self) -> &'static str;
    /// Where it acts (its category in docs/model.md, "Missing-physics catalog").
    fn category(&self) -> Category;
    /// One line of physics for reports.
    fn physics(&self) -> &'static str;
    /// Its parameters, with units, defaults, domains, search bounds and off values.
    fn specs(&self) -> &'static [ParamSpec];
    /// The experiments it can show in.
    fn shows_in(&self) -> ShowsIn {
        ShowsIn::Any
    }
}

/// One line per effect: `file::Type;` declares the module `file` (which must define the
/// unit struct `Type` implementing [`CatalogEffect`] and its parameters `PARAMS` through
/// `spec`'s `effect_params!`) and the constant `Effect::Type`.
macro_rules! registry {
    ($( $file:ident :: $ty:ident ; )*) => {
        $( pub mod $file; )*

        #[allow(non_camel_case_types, clippy::enum_variant_names)]
        enum Index { $( $ty, )* }

        /// Number of catalog effects.
        pub const N_EFFECTS: usize = [$( stringify!($ty), )*].len();

        #[allow(non_upper_case_globals)]
        impl Effect {
            $(
                #[doc = concat!("The `", stringify!($file), "` effect.")]
                pub const $ty: Effect = Effect(Index::$ty as u8);
            )*
            /// Every catalog effect, in registry order.
            pub const ALL: [Effect; N_EFFECTS] = [$( Effect::$ty, )*];
        }

        static MODELS: [&dyn CatalogEffect; N_EFFECTS] = [$( &$file::$ty, )*];

        /// Each effect's parameters, in registry order (the order of fit files).
        pub(crate) const PARAM_LISTS: [&[ParamSpec]; N_EFFECTS] = [$( $file::PARAMS, )*];

        const NAMES: [&[&str]; N_EFFECTS] =
            [$( &names::<{ $file::PARAMS.len() }>($file::PARAMS), )*];

        const TYPE_NAMES: [&str; N_EFFECTS] = [$( stringify!($ty), )*];
    };
}

registry! {
    breakaway_friction::BreakawayFriction;
    vane_friction_speed_squared::VaneFrictionSpeedSquared;
    speed_dependent_leakage::SpeedDependentLeakage;
    dead_volume_carryover::DeadVolumeCarryover;
    incomplete_filling::IncompleteFilling;
    pressure_dependent_friction::PressureDependentFriction;
    sensor_lag::SensorLag;
    valve_dynamics::ValveDynamics;
}

const _: () = assert!(N_EFFECTS <= 16, "EffectSet holds at most 16 effects");

/// The names of a list of parameters (for [`Effect::parameters`]).
const fn names<const N: usize>(specs: &[ParamSpec]) -> [&'static str; N] {
    let mut out = [""; N];
    let mut i = 0;
    while i < N {
        out[i] = specs[i].name;
        i += 1;
    }
    out
}

/// The handle [`Effect`] (defined in `spec`, below the parameters that name it): its
/// constants come from the `registry!` above, the rest from its entry.
impl Effect {
    /// Position in the registry.
    pub const fn index(self) -> usize {
        self.0 as usize
    }

    /// The effect's definition.
    pub fn model(self) -> &'static dyn CatalogEffect {
        MODELS[self.index()]
    }

    /// The id in files and on the command line.
    pub fn id(self) -> &'static str {
        self.model().id()
    }

    /// Where it acts (its category in docs/model.md, "Missing-physics catalog").
    pub fn category(self) -> Category {
        self.model().category()
    }

    /// Names of the parameters the effect adds (see `params::PARAMS`).
    pub fn parameters(self) -> &'static [&'static str] {
        NAMES[self.index()]
    }

    /// The parameters the effect adds, described.
    pub fn specs(self) -> &'static [ParamSpec] {
        self.model().specs()
    }

    /// One line of physics for reports.
    pub fn physics(self) -> &'static str {
        self.model().physics()
    }

    /// The experiments the effect can show in.
    pub fn shows_in(self) -> ShowsIn {
        self.model().shows_in()
    }
}

impl fmt::Debug for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(TYPE_NAMES[self.index()])
    }
}

impl fmt::Display for Effect {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.id())
    }
}

/// An effect id that is not in the catalog.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown effect '{id}' (known: {known})", id = .0, known = known_ids())]
pub struct UnknownEffect(pub String);

fn known_ids() -> String {
    Effect::ALL.map(|e| e.id()).join(", ")
}

impl FromStr for Effect {
    type Err = UnknownEffect;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Effect::ALL
            .into_iter()
            .find(|e| e.id() == s)
            .ok_or_else(|| UnknownEffect(s.to_string()))
    }
}

/// The set of effects switched on in a model (small, ordered, no duplicates).
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub struct EffectSet(u16);

impl EffectSet {
    /// No effect: the base model.
    pub fn empty() -> Self {
        Self(0)
    }
    /// The set with `e` added.
    pub fn with(mut self, e: Effect) -> Self {
        self.0 |= 1 << e.0;
        self
    }
    /// Whether `e` is switched on.
    pub fn contains(&self, e: Effect) -> bool {
        self.0 & (1 << e.0) != 0
    }
    /// The effects switched on, in registry order. Walks the set bits only, so that the
    /// base model (the empty set) costs nothing on the motor's hot path.
    pub fn iter(&self) -> impl Iterator<Item = Effect> + '_ {
        let mut bits = self.0;
        std::iter::from_fn(move || {
            if bits == 0 {
                return None;
            }
            let i = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            Some(Effect(i))
        })
    }
    /// Whether no effect is switched on.
    pub fn is_empty(&self) -> bool {
        self.0 == 0
    }
    /// The ids of the effects switched on, in registry order.
    pub fn ids(&self) -> Vec<String> {
        self.iter().map(|e| e.id().to_string()).collect()
    }
    /// Parses a comma-separated list of ids ("" gives the empty set).
    pub fn parse_list(list: &str) -> Result<Self, UnknownEffect> {
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
            .to_string()
            .contains("unknown effect"));
        let set = EffectSet::parse_list("sensor_lag, breakaway_friction").unwrap();
        assert_eq!(set.ids(), vec!["breakaway_friction", "sensor_lag"]);
    }

    #[test]
    fn every_effect_declares_its_own_parameters() {
        for e in Effect::ALL {
            assert_eq!(e.parameters().len(), e.specs().len());
            for (name, s) in e.parameters().iter().zip(e.specs()) {
                assert_eq!(*name, s.name);
                assert_eq!(s.effect, Some(e), "{name}");
            }
        }
        assert_eq!(format!("{:?}", Effect::SensorLag), "SensorLag");
    }
}
