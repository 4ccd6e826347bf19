//! What a parameter and an effect are, below both the parameter registry (`params`) and
//! the missing-physics catalog (`effects/`): the effect handle [`Effect`], a parameter's
//! identity [`ParamId`] and everything known of it ([`ParamSpec`], with [`Domain`],
//! [`OffValue`] and [`Estimated`]), a motor's parameter values as the catalog's hooks read
//! them ([`ParamValues`]), and the base model's parameters ([`BASE_PARAMS`], with a
//! `ParamId` constant for each).
//!
//! Each effect declares its own parameters in its file under `model/effects/`, through this
//! file's `effect_params!` (the base model's rows are `base_table!`'s); `params`
//! assembles the base model's and theirs into `PARAMS` and holds a motor's values
//! (`MotorParams`). This file imports neither, so the imports run one way: `params`
//! imports `effects` and `spec`, `effects` imports `spec`.
//!
//! Every parameter is SI. The names are the contract used in fit files and on the command
//! line; they must not change.

/// A catalogued effect: a handle to its entry in the registry of `model/effects/mod.rs`,
/// which defines the handles (`Effect::BreakawayFriction`, …) and everything else about
/// them. It sits here, below the catalog, because a parameter's spec names the effect that
/// adds it. The ids are fixed once used (docs/model.md, "Missing-physics catalog"); the
/// order is the registry's.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Effect(pub(crate) u8);

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

/// A parameter's identity: its position in [`PARAMS`](crate::model::PARAMS) (the base
/// model's parameters, then each effect's, as `params` assembles them). Strings appear only
/// at the file edges (`ParamId::from_name`, `ParamId::name`, in `params`); inside, a
/// parameter travels as this. The base model's constants (`ParamId::C_IN1`, …) come with
/// its table below; `params` makes those of the effects' parameters that code names.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ParamId(pub(crate) u8);

impl ParamId {
    /// Position in [`PARAMS`](crate::model::PARAMS) (and in a motor's parameter values).
    pub const fn index(self) -> usize {
        self.0 as usize
    }
}

/// A motor's parameter values as the catalog's hooks read them
/// ([`Term::add_to_balances`](crate::model::Term::add_to_balances)): one per entry of
/// [`PARAMS`](crate::model::PARAMS), in its order, read by [`ParamId`]. A
/// [`MotorParams`](crate::model::MotorParams) gives them (`MotorParams::values`); it cannot
/// be named below the catalog, whose parameters it holds.
#[derive(Debug, Clone, Copy)]
pub struct ParamValues<'a>(&'a [f64]);

impl<'a> ParamValues<'a> {
    /// The values `values`, one per entry of `PARAMS` in its order.
    pub(crate) const fn new(values: &'a [f64]) -> Self {
        Self(values)
    }

    /// Value of a parameter.
    pub fn value(self, id: ParamId) -> f64 {
        self.0[id.index()]
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

/// The inlet port sets the air at max power, where the supply fills the compartments.
const PINNED_BY_MAX_POWER_AIR: &str = "the air consumption at max power";

impl ParamSpec {
    /// The registry's facts that an effect's parameter does not set: no size law, no prior,
    /// estimated only with its effect, pinned by a rig experiment. An effect's rows in
    /// `effect_params!` set the rest.
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

    /// The factor s^k by which its size law scales it for a motor `size` = s times
    /// AR034-11's displacement (1 for a parameter that does not follow the size, and exactly
    /// 1 at s = 1, so the reference motor keeps its exact values).
    pub fn size_factor(&self, size: f64) -> f64 {
        match self.size_exponent {
            Some(k) => size.powf(k),
            None => 1.0,
        }
    }

    /// Its default scaled to a motor `size` times AR034-11's displacement by its size law
    /// (the default itself for a parameter that does not follow the size).
    pub fn scaled_default(&self, size: f64) -> f64 {
        self.default * self.size_factor(size)
    }

    /// Its search range for a motor `size` times AR034-11's displacement: the reference
    /// motor's range [`ParamSpec::search`] × s^k, so that the bounds are the same wide
    /// factors around the size-scaled default at every size (a 100 cm³ motor's Coulomb
    /// friction is 26 × the 3.8 cm³ motor's, and so are its bounds).
    pub fn search_at(&self, size: f64) -> (f64, f64) {
        let f = self.size_factor(size);
        (self.search.0 * f, self.search.1 * f)
    }
}

/// Size laws of geometric similarity: the exponent k with which a quantity follows a motor's
/// size s = V_disp/V_disp,AR034 (lengths ∝ s^⅓; docs/model.md, "Defaults that follow the
/// motor's size"). The registry's rows, the diagnosis's scales and `synth`'s rig name them.
pub struct SizeLaw;

impl SizeLaw {
    /// Areas: sonic conductances, port and leak gaps (∝ s^⅔).
    pub const AREA: f64 = 2.0 / 3.0;
    /// Volumes: lumped, dead and carried-over volumes (∝ s).
    pub const VOLUME: f64 = 1.0;
    /// Torques: a pressure on an area times a radius (s^⅔·s^⅓ = s).
    pub const TORQUE: f64 = 1.0;
    /// Viscous friction: a sheared area times a radius squared over an unchanged clearance
    /// (s^⅔·s^⅔ = s^{4/3}).
    pub const VISCOUS: f64 = 4.0 / 3.0;
    /// Inertia: a mass times a radius squared (s·s^⅔ = s^{5/3}).
    pub const INERTIA: f64 = 5.0 / 3.0;
    /// Speeds at equal vane-tip (sliding) speed: ω = v/r ∝ s^{-⅓}. The free speed of vane
    /// motors falls so with size (makers' ranges: ≈ 20 000 rpm at 1 cm³, 3 000 rpm at 500 cm³).
    pub const SPEED: f64 = -1.0 / 3.0;
    /// Mass flows: a displacement times a speed (s·s^{-⅓} = s^⅔), as the port areas pass them.
    pub const MASS_FLOW: f64 = 2.0 / 3.0;
    /// Torque per speed squared (vane friction ∝ ω²: centrifugal force m·ω²·r times a
    /// radius; s·s^⅔ = s^{5/3}).
    pub const TORQUE_PER_SPEED2: f64 = 5.0 / 3.0;

    /// s^k for a motor of displacement `v_disp_m3`, with s relative to AR034-11's.
    pub fn factor(v_disp_m3: f64, k: f64) -> f64 {
        (v_disp_m3 / REFERENCE_DISPLACEMENT_M3).powf(k)
    }
}

/// AR034-11's displacement, m³: the motor of size 1 whose values are the registry's defaults.
pub const REFERENCE_DISPLACEMENT_M3: f64 = 3.8e-6;

/// The SI unit of a sonic conductance, as fit files write it.
pub(crate) const CONDUCTANCE_UNIT: &str = "m3/(s*Pa)";

/// The unit in which catalogues and ISO 6358 give sonic conductances.
pub(crate) const CATALOGUE_CONDUCTANCE_UNIT: &str = "dm3/(s*bar)";

/// The base model's parameter table, handed to the macro `$then`: one table gives
/// [`BASE_PARAMS`] and the base `ParamId` constants here (`base_params!`) and
/// `MotorParams`'s accessors of the same names in `params`. A row is: the constant,
/// `name: unit = default`, domain, search range, meaning, size law, prior factor, when it
/// is estimated, what pins it, rig.toml key.
///
/// Size laws (geometric similarity, lengths ∝ s^⅓ with s = V_disp/V_disp,AR034): sonic
/// conductances are areas (∝ s^⅔); lumped volumes and the dead volume per compartment ∝ s;
/// Coulomb friction is a force from the pressure on vane and seal areas times a radius
/// (∝ s); viscous friction is a sheared area times a radius squared over an unchanged
/// clearance (∝ s^{4/3}); inertia is a mass times a radius squared (∝ s^{5/3}).
/// Dimensionless parameters (z, ε, b_crit, n_poly) do not change with size; `w_reg` is a
/// numerical regularisation speed and is kept. Where the priors' factors come from:
/// docs/estimation.md, "Priors".
macro_rules! base_table {
    ($then:ident) => {
        $then! {
            C_IN1 c_in1: "m3/(s*Pa)" = 6.758282e-9, Positive, (5e-10, 5e-8), "inlet port, supply → chamber 1",
                size Some(SizeLaw::AREA), prior Some(2.0), ByDefault, PINNED_BY_MAX_POWER_AIR, key None;
            C_OUT2 c_out2: "m3/(s*Pa)" = 6.758282e-9, Positive, (5e-10, 5e-8), "outlet port, chamber 2 → port 2",
                size Some(SizeLaw::AREA), prior Some(2.0), ByDefault, PINNED_BY_FREE_AIR, key None;
            C_EXT c_ext: "m3/(s*Pa)" = 1.170707e-8, Positive, (1e-9, 1e-7), "exhaust port, exhaust chamber → atmosphere",
                size Some(SizeLaw::AREA), prior Some(2.0), ByDefault, PINNED_BY_FREE_AIR, key None;
            C_1E c_1e: "m3/(s*Pa)" = 2.077886e-9, NonNegative, (1e-11, 2e-8), "leak, inlet side → exhaust",
                size Some(SizeLaw::AREA), prior Some(4.0), ByDefault, PINNED_BY_STALL_AIR, key None;
            C_2E c_2e: "m3/(s*Pa)" = 2.077886e-9, NonNegative, (1e-11, 2e-8), "leak, outlet side → exhaust",
                size Some(SizeLaw::AREA), prior Some(4.0), ByDefault, PINNED_BY_STALL_AIR, key None;
            C_12 c_12: "m3/(s*Pa)" = 7.616275e-10, NonNegative, (1e-12, 1e-8), "leak, inlet side → outlet side",
                size Some(SizeLaw::AREA), prior Some(4.0), ByDefault, PINNED_BY_STALL_AIR, key None;
            B_CRIT b_crit: "1" = 0.5, Interval(0.05, 0.95), (0.2, 0.6), "critical pressure ratio of every nozzle",
                size None, prior Some(1.6), OnPagesWithPrior { rank: 1 }, PINNED_BY_SECOND_PRESSURE, key None;
            Z z: "1" = 5.0, Integer(2, 16), (5.0, 5.0), "number of vanes",
                size None, prior None, OnRequest, PINNED_BY_RIG, key Some("vanes");
            // 0.01–10 000 cm³ per revolution: beyond either end no vane motor exists, and the
            // steady-state search fails (1 m³ has no steady state), so the gate refuses it first.
            V_DISP v_disp: "m3" = REFERENCE_DISPLACEMENT_M3, Interval(1e-8, 1e-2), (1e-7, 1e-3), "nominal displacement z·V_fill",
                size None, prior None, OnRequest, "the displacement (a datasheet row)", key Some("displacement_m3");
            EPS eps: "1" = 1.071, Interval(1.0, 2.0), (1.0, 1.5), "expansion ratio V_exp/V_fill",
                size None, prior None, OnRequest, PINNED_BY_RIG, key Some("expansion_ratio");
            V_DEAD v_dead: "m3" = 0.10e-6, NonNegative, (0.0, 1e-6), "dead volume per compartment",
                size Some(SizeLaw::VOLUME), prior Some(2.0), OnPagesWithPrior { rank: 0 }, PINNED_BY_SECOND_PRESSURE, key Some("dead_volume_m3");
            N_POLY n_poly: "1" = 1.3, Interval(1.0, 1.4), (1.0, 1.4), "polytropic index of expansion and compression",
                size None, prior None, OnRequest, PINNED_BY_RIG, key None;
            VOL1 vol1: "m3" = 2e-6, Positive, (1e-7, 1e-4), "lumped volume of chamber 1 (inlet side)",
                size Some(SizeLaw::VOLUME), prior Some(3.0), OnRequest, PINNED_BY_RIG, key None;
            VOL2 vol2: "m3" = 2e-6, Positive, (1e-7, 1e-4), "lumped volume of chamber 2 (outlet side)",
                size Some(SizeLaw::VOLUME), prior Some(3.0), OnRequest, PINNED_BY_RIG, key None;
            VOLE vole: "m3" = 2e-6, Positive, (1e-7, 1e-4), "lumped volume of the exhaust chamber",
                size Some(SizeLaw::VOLUME), prior Some(3.0), OnRequest, PINNED_BY_RIG, key None;
            INERTIA inertia: "kg*m2" = 2e-4, Positive, (1e-6, 1e-2), "inertia of rotor, coupling and brake",
                size Some(SizeLaw::INERTIA), prior Some(2.0), OnRequest, PINNED_BY_RIG, key None;
            T_COULOMB t_coulomb: "N*m" = 0.02, NonNegative, (1e-3, 0.2), "Coulomb friction torque",
                size Some(SizeLaw::TORQUE), prior Some(3.0), ByDefault, PINNED_BY_SECOND_PRESSURE, key None;
            VISC visc: "N*m*s/rad" = 6e-5, NonNegative, (1e-6, 1e-3), "viscous friction",
                size Some(SizeLaw::VISCOUS), prior Some(3.0), ByDefault, PINNED_BY_SECOND_PRESSURE, key None;
            W_REG w_reg: "rad/s" = 0.2, Positive, (0.01, 5.0), "speed that regularises the Coulomb friction",
                size None, prior None, OnRequest, PINNED_BY_RIG, key None;
        }
    };
}
pub(crate) use base_table;

/// [`BASE_PARAMS`] and the base `ParamId` constants from the rows of `base_table!`.
macro_rules! base_params {
    ($( $id:ident $field:ident : $unit:literal = $default:expr, $domain:expr, ($lo:expr, $hi:expr),
        $meaning:literal, size $k:expr, prior $f:expr, $est:expr, $pins:expr, key $key:expr; )*) => {
        #[allow(non_camel_case_types)]
        enum Base { $( $field, )* }

        /// The base model's parameters (docs/model.md, "Parameters"), first in
        /// [`PARAMS`](crate::model::PARAMS).
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
    };
}

/// An effect's parameter table, in the effect's file under `model/effects/`: rows like
/// `base_table!`'s (the constant, `name: unit = default`, domain, search range, meaning, size
/// law), each with the value that switches the effect off; what a row does not set is
/// [`ParamSpec::EFFECT`]'s. It makes the effect's `PARAMS` and, per row, the constant that
/// is the parameter's position among the effect's own values (`own[VALVE_TAU]` in its
/// hooks), so that each name is written once, as an identifier, as the base model's are.
macro_rules! effect_params {
    ($(#[$doc:meta])* $effect:path {
        $( $(#[$row_doc:meta])* $id:ident $field:ident : $unit:literal = $default:expr,
           $domain:expr, ($lo:expr, $hi:expr), $meaning:literal, size $k:expr, off $off:expr; )*
    }) => {
        #[allow(non_camel_case_types)]
        enum Own { $( $field, )* }

        $( $(#[$row_doc])* pub(crate) const $id: usize = Own::$field as usize; )*

        $(#[$doc])*
        pub const PARAMS: &[$crate::model::spec::ParamSpec] = &[
            $( $crate::model::spec::ParamSpec {
                name: stringify!($field), unit: $unit, default: $default, domain: $domain,
                search: ($lo, $hi), effect: Some($effect),
                off: $off, meaning: $meaning, size_exponent: $k,
                ..$crate::model::spec::ParamSpec::EFFECT
            }, )*
        ];
    };
}
pub(crate) use effect_params;

use Domain::{Integer, Interval, NonNegative, Positive};
use Estimated::{ByDefault, OnPagesWithPrior, OnRequest};

base_table!(base_params);
