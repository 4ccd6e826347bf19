//! Motor parameters: names, units, defaults and bounds (docs/model.md, "Parameters"), and
//! the one place where unchecked values become checked parameters (as linfa's
//! `ParamGuard`).
//!
//! Every parameter is SI. The names are the contract used in fit files and on the command
//! line; they must not change.

use crate::model::effects::{Effect, EffectSet, N_EFFECTS, PARAM_LISTS};
use std::fmt;

/// What values a parameter may take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Domain {
    /// Strictly positive (searched in log space).
    Positive,
    /// Zero or positive (searched in log space between its bounds).
    NonNegative,
    /// Closed interval [lo, hi] (searched through a logistic map).
    Interval(f64, f64),
    /// Whole number in [lo, hi] (never estimated).
    Integer(u32, u32),
}

/// Which value switches an effect's parameter off: the nested base model, or as near as
/// the search range allows (the diagnosis starts each candidate there).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OffValue {
    /// A base-model parameter: never switched off (its default stands in).
    NotAnEffect,
    /// The lower end of the search range.
    SearchLower,
    /// The upper end of the search range.
    SearchUpper,
    /// The default (the parameter does not matter once the others are off).
    Default,
    /// The base model's value of the parameter, clamped into the search range.
    BaseClamped(ParamId),
}

/// When a fit estimates a parameter without being told which to estimate
/// (docs/model.md, "What is estimated").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Estimated {
    /// Always (the six conductances and the two friction terms).
    ByDefault,
    /// Also in a fit of catalogue pages alone with the motor prior: the parameters that
    /// shape how torque and flow change with the supply pressure, resting on their priors
    /// where the page is silent. `rank` orders them after the default ones (θ order).
    OnPagesWithPrior {
        /// Position among these parameters in θ.
        rank: u8,
    },
    /// Only when named (`--estimate`), or with its effect switched on.
    OnRequest,
}

/// A parameter's identity: its position in [`PARAMS`]. Strings appear only at the file
/// edges ([`ParamId::from_name`], [`ParamId::name`]); inside, a parameter travels as this.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ParamId(u8);

impl ParamId {
    /// The parameter `j` of effect `e` (its `j`-th spec).
    pub const fn of_effect(e: Effect, j: usize) -> Self {
        Self((EFFECT_OFFSETS[e.index()] + j) as u8)
    }

    /// Position in [`PARAMS`] (and in a [`MotorParams`]'s values).
    pub const fn index(self) -> usize {
        self.0 as usize
    }

    /// Everything the registry knows of the parameter.
    pub fn spec(self) -> &'static ParamSpec {
        &PARAMS[self.index()]
    }

    /// The name in fit files and on the command line.
    pub fn name(self) -> &'static str {
        self.spec().name
    }

    /// The parameter of that name (`None` for an unknown name).
    pub fn from_name(name: &str) -> Option<Self> {
        position(name).map(|i| Self(i as u8))
    }

    /// Every parameter, in the order of [`PARAMS`].
    pub fn all() -> impl Iterator<Item = Self> {
        (0..N_PARAMS).map(|i| Self(i as u8))
    }
}

impl fmt::Debug for ParamId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl fmt::Display for ParamId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Everything known of one parameter, in one place: its name, unit, default, domain and
/// search range, the effect that adds it, how it follows the motor's size, its prior, when
/// it is estimated, and what would pin it.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    /// The name in fit files and on the command line.
    pub name: &'static str,
    /// The SI unit, as fit files write it.
    pub unit: &'static str,
    /// Default value (motor AR034-11), SI.
    pub default: f64,
    /// Values the parameter may take.
    pub(crate) domain: Domain,
    /// Search range for estimation (lo, hi) in SI; log-spaced for positive parameters.
    pub search: (f64, f64),
    /// The effect that adds this parameter, or `None` for the base model.
    pub effect: Option<Effect>,
    /// The value that switches the effect off.
    pub off: OffValue,
    /// What the parameter is, in a few words for people (see [`ParamSpec::description`]).
    pub(crate) meaning: &'static str,
    /// k of its size law: the default of a motor of displacement V is the AR034-11 default
    /// × (V/V_AR034)^k, by geometric similarity (docs/model.md, "Defaults that follow the
    /// motor's size"). `None`: it does not follow the size.
    pub size_exponent: Option<f64>,
    /// F, the factor (95 %, either way) within which real vane motors of the same
    /// displacement lie around the size-scaled default: the log-normal motor prior
    /// σ = ln F/1.96 (docs/estimation.md, "Priors"). `None`: no prior.
    pub prior_factor95: Option<f64>,
    /// When a fit estimates it unasked.
    pub estimated: Estimated,
    /// The one extra measurement a catalogue's reader can most easily get that pins it, in
    /// words (docs/estimation.md, "What a page cannot pin").
    pub pinned_by: &'static str,
    /// The `[motor]` key of rig.toml that gives it, where that is not its name.
    pub rig_key: Option<&'static str>,
}

/// The measurement that pins a parameter for which no easier one is known.
const PINNED_BY_RIG: &str = "a rig experiment (docs/estimation.md, \"Catalogue pages\")";

/// The friction and the pressure-shaping parameters separate from the air's torque only
/// across supply pressures: the Coulomb friction is a constant, the air torque ∝ the
/// pressure.
const PINNED_BY_SECOND_PRESSURE: &str =
    "the torque curve (or stall torque) at a second supply pressure";

/// The leaks carry all the air at stall, where no air passes through the displacement.
const PINNED_BY_STALL_AIR: &str = "the air flow at stall (the internal leakage)";

/// The outlet and exhaust ports set the air at free speed, where the flow through them
/// peaks.
const PINNED_BY_FREE_AIR: &str = "the air consumption at free speed";

impl ParamSpec {
    /// The registry's facts that an effect's parameter does not set: no size law, no prior,
    /// estimated only with its effect, pinned by a rig experiment. An effect's spec is its
    /// own fields followed by `..ParamSpec::EFFECT`.
    pub const EFFECT: ParamSpec = ParamSpec {
        name: "",
        unit: "1",
        default: 0.0,
        domain: Domain::NonNegative,
        search: (0.0, 1.0),
        effect: None,
        off: OffValue::Default,
        meaning: "",
        size_exponent: None,
        prior_factor95: None,
        estimated: Estimated::OnRequest,
        pinned_by: PINNED_BY_RIG,
        rig_key: None,
    };

    /// What the parameter is, in words, for every table and report that prints its id:
    /// `c_1e` is "leak, inlet side → exhaust", `t_coulomb` "Coulomb friction torque". The
    /// base model's descriptions are the table in this file; each effect's are in its file
    /// under `model/effects/`.
    pub fn description(&self) -> &'static str {
        self.meaning
    }

    /// The id followed by its description, e.g. `c_in1 (inlet port, supply → chamber 1)`.
    pub fn label(&self) -> String {
        format!("{} ({})", self.name, self.meaning)
    }

    /// Whether the parameter is a sonic conductance (unit [`CONDUCTANCE_UNIT`]), which
    /// reports give in [`CATALOGUE_CONDUCTANCE_UNIT`] too.
    pub(crate) fn is_conductance(&self) -> bool {
        self.unit == CONDUCTANCE_UNIT
    }

    /// The value that switches this parameter's effect off, given the base parameters.
    pub(crate) fn off_value(&self, base: &MotorParams) -> f64 {
        let (lo, hi) = self.search;
        match self.off {
            OffValue::NotAnEffect | OffValue::Default => self.default,
            OffValue::SearchLower => lo,
            OffValue::SearchUpper => hi,
            OffValue::BaseClamped(id) => base.value(id).clamp(lo, hi),
        }
    }

    /// Its default scaled to a motor `size` times AR034-11's displacement by its size law
    /// (the default itself for a parameter that does not follow the size).
    pub fn scaled_default(&self, size: f64) -> f64 {
        match self.size_exponent {
            Some(k) => self.default * size.powf(k),
            None => self.default,
        }
    }
}

/// The SI unit of a sonic conductance, as fit files write it.
pub(crate) const CONDUCTANCE_UNIT: &str = "m3/(s*Pa)";

/// The unit in which catalogues and ISO 6358 give sonic conductances.
pub(crate) const CATALOGUE_CONDUCTANCE_UNIT: &str = "dm3/(s*bar)";

macro_rules! base_params {
    ($( $id:ident $field:ident : $unit:literal = $default:expr, $domain:expr, ($lo:expr, $hi:expr),
        $meaning:literal, size $k:expr, prior $f:expr, $est:expr, $pins:expr, key $key:expr; )*) => {
        #[allow(non_camel_case_types)]
        enum Base { $( $field, )* }

        /// The base model's parameters (docs/model.md, "Parameters"), first in [`PARAMS`].
        pub const BASE_PARAMS: &[ParamSpec] = &[
            $( ParamSpec { name: stringify!($field), unit: $unit, default: $default, domain: $domain,
                           search: ($lo, $hi), effect: None, off: OffValue::NotAnEffect,
                           meaning: $meaning, size_exponent: $k, prior_factor95: $f,
                           estimated: $est, pinned_by: $pins, rig_key: $key }, )*
        ];

        impl ParamId {
            $(
                #[doc = concat!("`", stringify!($field), "`: ", $meaning, " (", $unit, ").")]
                pub const $id: ParamId = ParamId(Base::$field as u8);
            )*
        }

        impl MotorParams {
            $(
                #[doc = concat!("`", stringify!($field), "`: ", $meaning, " (", $unit, ").")]
                pub fn $field(&self) -> f64 { self.values[Base::$field as usize] }
            )*
        }
    };
}

use Domain::{Integer, Interval, NonNegative, Positive};
use Estimated::{ByDefault, OnPagesWithPrior, OnRequest};
// Size laws (geometric similarity, lengths ∝ s^⅓ with s = V_disp/V_disp,AR034): sonic
// conductances are areas (∝ s^⅔); lumped volumes and the dead volume per compartment ∝ s;
// Coulomb friction is a force from the pressure on vane and seal areas times a radius (∝ s);
// viscous friction is a sheared area times a radius squared over an unchanged clearance
// (∝ s^{4/3}); inertia is a mass times a radius squared (∝ s^{5/3}). Dimensionless
// parameters (z, ε, b_crit, n_poly) do not change with size; `w_reg` is a numerical
// regularisation speed and is kept. Where the priors' factors come from: docs/estimation.md,
// "Priors".
base_params! {
    C_IN1 c_in1: "m3/(s*Pa)" = 6.758282e-9, Positive, (5e-10, 5e-8), "inlet port, supply → chamber 1",
        size Some(2.0 / 3.0), prior Some(2.0), ByDefault, "the air consumption at max power", key None;
    C_OUT2 c_out2: "m3/(s*Pa)" = 6.758282e-9, Positive, (5e-10, 5e-8), "outlet port, chamber 2 → port 2",
        size Some(2.0 / 3.0), prior Some(2.0), ByDefault, PINNED_BY_FREE_AIR, key None;
    C_EXT c_ext: "m3/(s*Pa)" = 1.170707e-8, Positive, (1e-9, 1e-7), "exhaust port, exhaust chamber → atmosphere",
        size Some(2.0 / 3.0), prior Some(2.0), ByDefault, PINNED_BY_FREE_AIR, key None;
    C_1E c_1e: "m3/(s*Pa)" = 2.077886e-9, NonNegative, (1e-11, 2e-8), "leak, inlet side → exhaust",
        size Some(2.0 / 3.0), prior Some(4.0), ByDefault, PINNED_BY_STALL_AIR, key None;
    C_2E c_2e: "m3/(s*Pa)" = 2.077886e-9, NonNegative, (1e-11, 2e-8), "leak, outlet side → exhaust",
        size Some(2.0 / 3.0), prior Some(4.0), ByDefault, PINNED_BY_STALL_AIR, key None;
    C_12 c_12: "m3/(s*Pa)" = 7.616275e-10, NonNegative, (1e-12, 1e-8), "leak, inlet side → outlet side",
        size Some(2.0 / 3.0), prior Some(4.0), ByDefault, PINNED_BY_STALL_AIR, key None;
    B_CRIT b_crit: "1" = 0.5, Interval(0.05, 0.95), (0.2, 0.6), "critical pressure ratio of every nozzle",
        size None, prior Some(1.6), OnPagesWithPrior { rank: 1 }, PINNED_BY_SECOND_PRESSURE, key None;
    Z z: "1" = 5.0, Integer(2, 16), (5.0, 5.0), "number of vanes",
        size None, prior None, OnRequest, PINNED_BY_RIG, key Some("vanes");
    // 0.01–10 000 cm³ per revolution: beyond either end no vane motor exists, and the
    // steady-state search fails (1 m³ has no steady state), so the gate refuses it first.
    V_DISP v_disp: "m3" = 3.8e-6, Interval(1e-8, 1e-2), (1e-7, 1e-3), "nominal displacement z·V_fill",
        size None, prior None, OnRequest, "the displacement (a datasheet row)", key Some("displacement_m3");
    EPS eps: "1" = 1.071, Interval(1.0, 2.0), (1.0, 1.5), "expansion ratio V_exp/V_fill",
        size None, prior None, OnRequest, PINNED_BY_RIG, key Some("expansion_ratio");
    V_DEAD v_dead: "m3" = 0.10e-6, NonNegative, (0.0, 1e-6), "dead volume per compartment",
        size Some(1.0), prior Some(2.0), OnPagesWithPrior { rank: 0 }, PINNED_BY_SECOND_PRESSURE, key Some("dead_volume_m3");
    N_POLY n_poly: "1" = 1.3, Interval(1.0, 1.4), (1.0, 1.4), "polytropic index of expansion and compression",
        size None, prior None, OnRequest, PINNED_BY_RIG, key None;
    VOL1 vol1: "m3" = 2e-6, Positive, (1e-7, 1e-4), "lumped volume of chamber 1 (inlet side)",
        size Some(1.0), prior Some(3.0), OnRequest, PINNED_BY_RIG, key None;
    VOL2 vol2: "m3" = 2e-6, Positive, (1e-7, 1e-4), "lumped volume of chamber 2 (outlet side)",
        size Some(1.0), prior Some(3.0), OnRequest, PINNED_BY_RIG, key None;
    VOLE vole: "m3" = 2e-6, Positive, (1e-7, 1e-4), "lumped volume of the exhaust chamber",
        size Some(1.0), prior Some(3.0), OnRequest, PINNED_BY_RIG, key None;
    INERTIA inertia: "kg*m2" = 2e-4, Positive, (1e-6, 1e-2), "inertia of rotor, coupling and brake",
        size Some(5.0 / 3.0), prior Some(2.0), OnRequest, PINNED_BY_RIG, key None;
    T_COULOMB t_coulomb: "N*m" = 0.02, NonNegative, (1e-3, 0.2), "Coulomb friction torque",
        size Some(1.0), prior Some(3.0), ByDefault, PINNED_BY_SECOND_PRESSURE, key None;
    VISC visc: "N*m*s/rad" = 6e-5, NonNegative, (1e-6, 1e-3), "viscous friction",
        size Some(4.0 / 3.0), prior Some(3.0), ByDefault, PINNED_BY_SECOND_PRESSURE, key None;
    W_REG w_reg: "rad/s" = 0.2, Positive, (0.01, 5.0), "speed that regularises the Coulomb friction",
        size None, prior None, OnRequest, PINNED_BY_RIG, key None;
}

/// Number of parameters: the base model's and every catalog effect's.
const N_PARAMS: usize = count_params();

const fn count_params() -> usize {
    let mut n = BASE_PARAMS.len();
    let mut e = 0;
    while e < N_EFFECTS {
        n += PARAM_LISTS[e].len();
        e += 1;
    }
    n
}

/// The base parameters, then each effect's in registry order.
const fn assemble() -> [ParamSpec; N_PARAMS] {
    let mut out = [BASE_PARAMS[0]; N_PARAMS];
    let mut k = 0;
    while k < BASE_PARAMS.len() {
        out[k] = BASE_PARAMS[k];
        k += 1;
    }
    let mut e = 0;
    while e < N_EFFECTS {
        let list = PARAM_LISTS[e];
        let mut j = 0;
        while j < list.len() {
            out[k] = list[j];
            k += 1;
            j += 1;
        }
        e += 1;
    }
    out
}

/// Where each effect's parameters start in [`PARAMS`].
const fn offsets() -> [usize; N_EFFECTS] {
    let mut out = [0; N_EFFECTS];
    let mut k = BASE_PARAMS.len();
    let mut e = 0;
    while e < N_EFFECTS {
        out[e] = k;
        k += PARAM_LISTS[e].len();
        e += 1;
    }
    out
}

const ALL_PARAMS: [ParamSpec; N_PARAMS] = assemble();
const EFFECT_OFFSETS: [usize; N_EFFECTS] = offsets();

/// Every parameter, in a fixed order (the order of fit files and reports): the base
/// model's, then each catalog effect's in registry order.
pub const PARAMS: &[ParamSpec] = &ALL_PARAMS;

const fn count_default_estimated() -> usize {
    let mut n = 0;
    let mut k = 0;
    while k < N_PARAMS {
        if matches!(ALL_PARAMS[k].estimated, Estimated::ByDefault) {
            n += 1;
        }
        k += 1;
    }
    n
}

const N_DEFAULT_ESTIMATED: usize = count_default_estimated();

const fn default_estimated() -> [ParamId; N_DEFAULT_ESTIMATED] {
    let mut out = [ParamId(0); N_DEFAULT_ESTIMATED];
    let (mut n, mut k) = (0, 0);
    while k < N_PARAMS {
        if matches!(ALL_PARAMS[k].estimated, Estimated::ByDefault) {
            out[n] = ParamId(k as u8);
            n += 1;
        }
        k += 1;
    }
    out
}

const fn names_of<const N: usize>(ids: [ParamId; N]) -> [&'static str; N] {
    let mut out = [""; N];
    let mut k = 0;
    while k < N {
        out[k] = ALL_PARAMS[ids[k].index()].name;
        k += 1;
    }
    out
}

/// The parameters a fit estimates when not told which ([`Estimated::ByDefault`]), in the
/// order of [`PARAMS`]: six conductances and the two friction terms.
pub const DEFAULT_ESTIMATED_IDS: [ParamId; N_DEFAULT_ESTIMATED] = default_estimated();

/// The names of [`DEFAULT_ESTIMATED_IDS`], for code that names parameters by string.
pub const DEFAULT_ESTIMATED: [&str; N_DEFAULT_ESTIMATED] = names_of(DEFAULT_ESTIMATED_IDS);

/// The names a model with `effects` switched on estimates unasked: the default ones
/// ([`DEFAULT_ESTIMATED`]), then each effect's parameters in registry order.
pub fn estimated_names(effects: &EffectSet) -> Vec<String> {
    let mut names: Vec<String> = DEFAULT_ESTIMATED.iter().map(|s| s.to_string()).collect();
    for e in effects.iter() {
        names.extend(e.parameters().iter().map(|s| s.to_string()));
    }
    names
}

/// The parameters a fit of catalogue pages alone with the motor prior estimates besides
/// the default ones ([`Estimated::OnPagesWithPrior`]), in their θ order.
pub fn page_prior_extra() -> Vec<ParamId> {
    let rank = |id: &ParamId| match id.spec().estimated {
        Estimated::OnPagesWithPrior { rank } => Some(rank),
        _ => None,
    };
    let mut ids: Vec<ParamId> = ParamId::all().filter(|id| rank(id).is_some()).collect();
    ids.sort_by_key(rank);
    ids
}

const fn default_values() -> [f64; N_PARAMS] {
    let mut out = [0.0; N_PARAMS];
    let mut k = 0;
    while k < N_PARAMS {
        out[k] = ALL_PARAMS[k].default;
        k += 1;
    }
    out
}

/// Checked motor parameters, SI units. The only way to build them is `ParamSet::check`
/// (or a default), so every value has passed its check; read them through the accessor of
/// the same name (base parameters here, each effect's in its file) or [`MotorParams::get`].
#[derive(Clone, PartialEq)]
pub struct MotorParams {
    /// One value per entry of [`PARAMS`], in its order.
    values: [f64; N_PARAMS],
}

impl fmt::Debug for MotorParams {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut s = f.debug_struct("MotorParams");
        for (spec, v) in PARAMS.iter().zip(&self.values) {
            s.field(spec.name, v);
        }
        s.finish()
    }
}

impl MotorParams {
    /// Value of a parameter.
    pub fn value(&self, id: ParamId) -> f64 {
        self.values[id.index()]
    }

    /// Value of a named parameter (`None` for an unknown name).
    pub fn get(&self, name: &str) -> Option<f64> {
        position(name).map(|i| self.values[i])
    }

    /// The values of an effect's own parameters, in the order of its specs.
    pub fn effect_values(&self, e: Effect) -> &[f64] {
        let start = EFFECT_OFFSETS[e.index()];
        &self.values[start..start + e.specs().len()]
    }

    fn set_unchecked(&mut self, name: &str, value: f64) -> bool {
        match position(name) {
            Some(i) => {
                self.values[i] = value;
                true
            }
            None => false,
        }
    }

    fn defaults() -> Self {
        Self {
            values: default_values(),
        }
    }
}

fn position(name: &str) -> Option<usize> {
    PARAMS.iter().position(|p| p.name == name)
}

/// Looks up a parameter's description by name.
pub fn spec(name: &str) -> Option<&'static ParamSpec> {
    PARAMS.iter().find(|p| p.name == name)
}

/// A parameter's description in words by name (`None` for an unknown name); see
/// [`ParamSpec::description`].
pub fn description(name: &str) -> Option<&'static str> {
    spec(name).map(ParamSpec::description)
}

/// Whether the named parameter is a sonic conductance (false for an unknown name).
pub(crate) fn is_conductance(name: &str) -> bool {
    spec(name).is_some_and(ParamSpec::is_conductance)
}

/// A sonic conductance in dm³/(s·bar) (ISO 6358 catalogues) from m³/(s·Pa):
/// 1 dm³/(s·bar) = 1e-3 m³/s per 1e5 Pa = 1e-8 m³/(s·Pa), so 6.76e-9 m³/(s·Pa) is
/// 0.676 dm³/(s·bar).
pub(crate) fn conductance_dm3_s_bar(c_m3_s_pa: f64) -> f64 {
    crate::units::Unit::Dm3SBar.from_si(c_m3_s_pa, 0.0)
}

impl Default for MotorParams {
    /// Motor AR034-11 with the appendix conductances (docs/model.md, "Parameters").
    fn default() -> Self {
        Self::defaults()
    }
}

impl MotorParams {
    /// Number of vanes as a count.
    pub fn vanes(&self) -> u32 {
        self.z().round() as u32
    }

    /// Returns a copy with one parameter changed, checked.
    pub fn with_value(&self, id: ParamId, value: f64) -> Result<Self, ParamError> {
        let mut set = ParamSet::from(self.clone());
        set.set_value(id, value);
        set.check()
    }

    /// Returns a copy with one named parameter changed, checked.
    pub fn with(&self, name: &str, value: f64) -> Result<Self, ParamError> {
        let mut set = ParamSet::from(self.clone());
        set.set(name, value)?;
        set.check()
    }
}

/// An error in a parameter value or name.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("parameter '{name}': {message}")]
pub struct ParamError {
    /// The parameter's name as given.
    pub name: String,
    /// What is wrong with it.
    pub message: String,
}

/// Unchecked parameters: defaults overridden by whatever a file or the user gave.
#[derive(Debug, Clone, Default)]
pub(crate) struct ParamSet {
    values: MotorParams,
}

impl From<MotorParams> for ParamSet {
    fn from(values: MotorParams) -> Self {
        Self { values }
    }
}

impl ParamSet {
    /// Sets a parameter (checked by [`ParamSet::check`]).
    pub fn set_value(&mut self, id: ParamId, value: f64) {
        self.values.values[id.index()] = value;
    }

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
        for (spec, v) in PARAMS.iter().zip(&p.values) {
            check_domain(spec, *v)?;
        }
        let v_fill = p.v_disp() / p.z().round();
        if p.v_dead() >= v_fill {
            return Err(ParamError {
                name: "v_dead".into(),
                message: format!(
                    "dead volume {:.3e} m3 must be smaller than the filling volume v_disp/z = {v_fill:.3e} m3",
                    p.v_dead()
                ),
            });
        }
        Ok(p)
    }
}

use crate::units::format::short;

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
        Interval(lo, hi) if !(lo..=hi).contains(&v) => fail(format!(
            "must lie in [{}, {}] {}, got {}",
            short(lo),
            short(hi),
            spec.unit,
            short(v)
        )),
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
    fn the_fit_file_order_is_fixed() {
        let names: Vec<_> = PARAMS.iter().map(|p| p.name).collect();
        let expected = "c_in1 c_out2 c_ext c_1e c_2e c_12 b_crit z v_disp eps v_dead n_poly \
                        vol1 vol2 vole inertia t_coulomb visc w_reg t_static w_stribeck c_w2 \
                        g_seal w_seal v_carry w_fill k_fric_p tau_sensor valve_tau valve_zeta";
        assert_eq!(names.join(" "), expected);
        let p = MotorParams::default().with("g_seal", 2.5).unwrap();
        assert_eq!(p.g_seal(), 2.5);
        assert_eq!(
            p.effect_values(Effect::SpeedDependentLeakage),
            &[2.5, 300.0]
        );
    }

    #[test]
    fn every_parameter_is_described_and_conductances_convert_to_catalogue_units() {
        for p in PARAMS {
            let d = p.description();
            assert!(d.len() >= 6 && d != p.name, "{}: '{d}'", p.name);
            assert_eq!(description(p.name), Some(d));
            assert_eq!(p.label(), format!("{} ({d})", p.name));
        }
        assert_eq!(description("c_1e"), Some("leak, inlet side → exhaust"));
        assert_eq!(description("c_in1"), Some("inlet port, supply → chamber 1"));
        assert_eq!(description("t_coulomb"), Some("Coulomb friction torque"));
        assert_eq!(description("visc"), Some("viscous friction"));
        assert_eq!(description("no_such"), None);
        let conductances: Vec<_> = PARAMS
            .iter()
            .filter(|p| p.is_conductance())
            .map(|p| p.name)
            .collect();
        assert_eq!(
            conductances,
            ["c_in1", "c_out2", "c_ext", "c_1e", "c_2e", "c_12"]
        );
        assert!(is_conductance("c_12") && !is_conductance("visc") && !is_conductance("x"));
        // 1 dm³/(s·bar) = 1e-3 m³/s / 1e5 Pa.
        assert!((conductance_dm3_s_bar(6.76e-9) - 0.676).abs() < 1e-12);
        assert!((conductance_dm3_s_bar(1e-8) - 1.0).abs() < 1e-15);
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
