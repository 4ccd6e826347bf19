//! Motor parameters: the registry of every parameter ([`PARAMS`], docs/model.md,
//! "Parameters"), a motor's values ([`MotorParams`]), and the one place where unchecked
//! values become checked parameters (as linfa's `ParamGuard`).
//!
//! What a parameter is ([`ParamSpec`], [`ParamId`], …) and the base model's table of them
//! are in `spec`; each effect's parameters are in its file under `model/effects/`. This file
//! assembles them, base model first and then each effect in registry order, and re-exports
//! `spec`'s parameter types, so that `params::ParamSpec` and the like still name them.
//!
//! Every parameter is SI. The names are the contract used in fit files and on the command
//! line; they must not change.

use crate::model::effects::{breakaway_friction, Effect, EffectSet, N_EFFECTS, PARAM_LISTS};
use crate::model::spec::base_table;
pub(crate) use crate::model::spec::{Domain, CATALOGUE_CONDUCTANCE_UNIT, CONDUCTANCE_UNIT};
pub use crate::model::spec::{Estimated, OffValue, ParamId, ParamSpec, ParamValues, BASE_PARAMS};
use std::fmt;

impl ParamId {
    /// The parameter `j` of effect `e` (its `j`-th spec).
    pub const fn of_effect(e: Effect, j: usize) -> Self {
        Self((EFFECT_OFFSETS[e.index()] + j) as u8)
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

/// The effects' parameters that code names (the base model's constants come with its table
/// in `spec`), each from its position in its effect's file.
impl ParamId {
    /// `t_static`: static (breakaway) friction torque T_s, N·m (`breakaway_friction`).
    pub const T_STATIC: ParamId =
        ParamId::of_effect(Effect::BreakawayFriction, breakaway_friction::T_STATIC);
    /// `w_stribeck`: Stribeck speed ω_s, rad/s (`breakaway_friction`).
    pub const W_STRIBECK: ParamId =
        ParamId::of_effect(Effect::BreakawayFriction, breakaway_friction::W_STRIBECK);
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

impl ParamSpec {
    /// The value that switches this parameter's effect off, given the base parameters.
    /// (Here rather than with the rest of `ParamSpec` in `spec`, because it reads a
    /// [`MotorParams`].)
    pub(crate) fn off_value(&self, base: &MotorParams) -> f64 {
        let (lo, hi) = self.search_at(base.size());
        match self.off {
            OffValue::NotAnEffect | OffValue::Default => self.default,
            OffValue::SearchLower => lo,
            OffValue::SearchUpper => hi,
            OffValue::BaseClamped(id) => base.value(id).clamp(lo, hi),
        }
    }
}

/// The base model's accessors on [`MotorParams`], one per row of `spec`'s `base_table!`.
macro_rules! base_accessors {
    ($( $id:ident $field:ident : $unit:literal = $default:expr, $domain:expr, $search:expr,
        $meaning:literal, size $k:expr, prior $f:expr, $est:expr, $pins:expr, key $key:expr; )*) => {
        impl MotorParams {
            $(
                #[doc = concat!("`", stringify!($field), "`: ", $meaning, " (", $unit, ").")]
                pub fn $field(&self) -> f64 { self.values[ParamId::$id.index()] }
            )*
        }
    };
}

base_table!(base_accessors);

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
/// (or a default), so every value has passed its check; read a base parameter through the
/// accessor of the same name (made from `spec`'s table), any through [`MotorParams::value`]
/// with its [`ParamId`] or [`MotorParams::get`] with its name, and an effect's own through
/// [`MotorParams::effect_values`].
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

    /// The motor's size s = V_disp/V_disp,AR034 that its size laws scale with
    /// ([`ParamSpec::size_exponent`]; exactly 1 for the reference motor).
    pub fn size(&self) -> f64 {
        self.v_disp() / crate::model::spec::REFERENCE_DISPLACEMENT_M3
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

    /// Every value, as the catalog's hooks read them ([`ParamValues`]).
    pub fn values(&self) -> ParamValues<'_> {
        ParamValues::new(&self.values)
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
use Domain::{Integer, Interval, NonNegative, Positive};

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
    use crate::model::spec::SizeLaw;

    /// The reference motor keeps its exact search ranges (so its fits do not change), and a
    /// motor of any size from 0.3 to 500 cm³ gets the same factors around its size-scaled
    /// default: the range × s^k, k the parameter's size law.
    #[test]
    fn search_ranges_follow_the_size_law_and_keep_the_reference_motors() {
        for s in PARAMS {
            assert_eq!(s.search_at(1.0), s.search, "{}", s.name);
        }
        for cm3 in [0.3, 1.0, 3.8, 25.0, 150.0, 500.0] {
            let size = cm3 / 3.8;
            for s in PARAMS.iter().filter(|s| s.size_exponent.is_some()) {
                let k = s.size_exponent.unwrap();
                let (lo, hi) = s.search_at(size);
                let d = s.scaled_default(size);
                // Independent: the default's position between the bounds in log space is
                // the reference motor's at every size.
                let f = size.powf(k);
                assert!(
                    (lo - s.search.0 * f).abs() <= 1e-12 * lo,
                    "{} {cm3}",
                    s.name
                );
                assert!(
                    (hi / (s.search.1 * f) - 1.0).abs() < 1e-12,
                    "{} {cm3}",
                    s.name
                );
                assert!(
                    (d / (s.default * f) - 1.0).abs() < 1e-12,
                    "{} {cm3}",
                    s.name
                );
                if lo > 0.0 {
                    assert!(
                        d / lo >= 5.0 && hi / d >= 5.0,
                        "{} at {cm3} cm³: [{lo:e}, {hi:e}] around {d:e}",
                        s.name
                    );
                }
            }
        }
        // A Coulomb friction torque scales as a torque (∝ s), a conductance as an area.
        assert_eq!(
            ParamId::T_COULOMB.spec().size_exponent,
            Some(SizeLaw::TORQUE)
        );
        assert_eq!(ParamId::C_IN1.spec().size_exponent, Some(SizeLaw::AREA));
        let big = MotorParams::default().with("v_disp", 100e-6).unwrap();
        assert!((big.size() - 100.0 / 3.8).abs() < 1e-12);
        assert_eq!(MotorParams::default().size(), 1.0);
    }

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
