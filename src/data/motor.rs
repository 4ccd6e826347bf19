//! The `[motor]` table of rig.toml: the motor either by its volumes (`displacement_m3`,
//! `expansion_ratio`, `dead_volume_m3`) or by its geometry (rotor length L, stator and rotor
//! radii R_S and R_R, vanes z and the port timing angles), from which paper eqs. 1–7
//! (`VaneGeometry::derived_volumes`) give V_disp,nom = z·V_fill, ε = V_exp/V_fill and V_d.

use crate::model::geometry::{PortTiming, VaneGeometry};
use crate::model::params::{MotorParams, ParamError, ParamId, ParamSet};
use serde::Deserialize;

/// The `[motor]` table of rig.toml (every key optional: defaults are motor AR034-11's).
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields)]
pub struct MotorSection {
    /// Catalogue name of the motor.
    #[serde(default)]
    pub name: Option<String>,
    /// Number of vanes z.
    pub vanes: Option<u32>,
    /// Nominal displacement z·V_fill, m³ (paper eq. 7).
    pub displacement_m3: Option<f64>,
    /// The same in cm³, as catalogues print it (`displacement_cm3 = 3.8`); moved into
    /// `displacement_m3` by [`MotorSection::resolve_units`] when rig.toml is read.
    #[serde(default)]
    displacement_cm3: Option<f64>,
    /// Expansion ratio ε = V_exp/V_fill (paper eq. 6).
    pub expansion_ratio: Option<f64>,
    /// Dead volume per compartment V_d, m³.
    #[serde(default)]
    dead_volume_m3: Option<f64>,
    /// Rotor length L, m.
    #[serde(default)]
    pub(crate) length_m: Option<f64>,
    /// Stator radius R_S, m.
    #[serde(default)]
    pub r_stator_m: Option<f64>,
    /// Rotor radius R_R, m.
    #[serde(default)]
    pub(crate) r_rotor_m: Option<f64>,
    /// Angle of the leading vane when a compartment opens to the inlet (its dead volume), °.
    #[serde(default)]
    alpha_dead_deg: Option<f64>,
    /// Angle of the leading vane at inlet cut-off (the filling volume), °.
    #[serde(default)]
    pub alpha_fill_deg: Option<f64>,
    /// Angle of the leading vane when the exhaust opens (the expanded volume), °.
    #[serde(default)]
    alpha_exp_deg: Option<f64>,
    /// Gearbox ratio G = motor speed / output speed: the page's figures are the output
    /// shaft's (docs/formats.md, "Geared motors").
    #[serde(default)]
    pub gear_ratio: Option<f64>,
    /// Gearbox efficiency η in (0, 1], where the page prints it (otherwise a prior,
    /// [`crate::model::gear::Gear::prior`]).
    #[serde(default)]
    pub gear_efficiency: Option<f64>,
}

/// A `[motor]` table that does not describe a motor; each names the key to blame.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum MotorSpecError {
    /// Part of the geometry is given, but not all of it.
    #[error("[motor] gives part of the geometry; '{missing}' is missing (a geometry needs vanes, length_m, r_stator_m, r_rotor_m, alpha_dead_deg, alpha_fill_deg and alpha_exp_deg)")]
    IncompleteGeometry {
        /// The first key that is missing.
        missing: &'static str,
    },
    /// Both the geometry and a volume it determines are given.
    #[error("[motor] gives both the geometry and '{key}'; give one or the other (the geometry determines displacement_m3, expansion_ratio and dead_volume_m3)")]
    GeometryAndVolume {
        /// The volume key given besides the geometry.
        key: &'static str,
    },
    /// A length or an angle that cannot be.
    #[error("[motor] {key} = {value} {reason}")]
    BadGeometry {
        /// The key.
        key: &'static str,
        /// Its value as given.
        value: f64,
        /// What is wrong.
        reason: &'static str,
    },
    /// The resulting parameters fail their check.
    #[error("[motor] gives {0}")]
    Param(#[from] ParamError),
    /// The displacement is given twice, in m³ and in cm³.
    #[error("[motor] gives both displacement_cm3 and displacement_m3; give one")]
    DisplacementTwice,
    /// A gearbox key with a value that cannot be, or an efficiency without a ratio.
    #[error("[motor] {key} = {value} {reason}")]
    BadGear {
        /// `gear_ratio` or `gear_efficiency`.
        key: &'static str,
        /// Its value as given (NaN where it is missing).
        value: f64,
        /// What is wrong.
        reason: &'static str,
    },
}

impl MotorSpecError {
    /// The rig.toml key the error is about (to locate it in the file).
    pub fn key(&self) -> &str {
        match self {
            MotorSpecError::IncompleteGeometry { .. } => "length_m",
            MotorSpecError::GeometryAndVolume { key } => key,
            MotorSpecError::BadGeometry { key, .. } => key,
            MotorSpecError::DisplacementTwice => "displacement_cm3",
            MotorSpecError::BadGear { key, .. } => key,
            MotorSpecError::Param(e) => crate::model::params::spec(&e.name)
                .and_then(|s| s.rig_key)
                .unwrap_or(&e.name),
        }
    }
}

/// The geometry keys, in the order they are asked for.
const GEOMETRY_KEYS: [&str; 6] = [
    "length_m",
    "r_stator_m",
    "r_rotor_m",
    "alpha_dead_deg",
    "alpha_fill_deg",
    "alpha_exp_deg",
];

impl MotorSection {
    /// Moves a displacement given in cm³ (`displacement_cm3`) into `displacement_m3`
    /// (× 1e-6); both given is an error. rig.toml's reader calls this before anything else
    /// looks at the table, so the rest of vanefit sees the displacement in m³ only.
    pub fn resolve_units(&mut self) -> Result<(), MotorSpecError> {
        if let Some(cm3) = self.displacement_cm3.take() {
            if self.displacement_m3.is_some() {
                return Err(MotorSpecError::DisplacementTwice);
            }
            self.displacement_m3 = Some(cm3 * 1e-6);
        }
        Ok(())
    }

    /// The gearbox, when the table gives `gear_ratio` (finite, > 0) and perhaps
    /// `gear_efficiency` (in (0, 1]); `None` for a motor without one.
    pub fn gear(&self) -> Result<Option<crate::model::gear::Gear>, MotorSpecError> {
        let bad = |key, value, reason| Err(MotorSpecError::BadGear { key, value, reason });
        let Some(ratio) = self.gear_ratio else {
            return match self.gear_efficiency {
                Some(eta) => bad(
                    "gear_efficiency",
                    eta,
                    "needs gear_ratio (motor speed / output speed)",
                ),
                None => Ok(None),
            };
        };
        if !(ratio.is_finite() && ratio > 0.0) {
            return bad(
                "gear_ratio",
                ratio,
                "must be a finite ratio > 0 (motor speed / output speed)",
            );
        }
        if let Some(eta) = self.gear_efficiency {
            if !(eta > 0.0 && eta <= 1.0) {
                return bad(
                    "gear_efficiency",
                    eta,
                    "must be in (0, 1] (output power / motor power)",
                );
            }
        }
        Ok(Some(crate::model::gear::Gear::new(
            ratio,
            self.gear_efficiency,
        )))
    }

    fn geometry_values(&self) -> [Option<f64>; 6] {
        [
            self.length_m,
            self.r_stator_m,
            self.r_rotor_m,
            self.alpha_dead_deg,
            self.alpha_fill_deg,
            self.alpha_exp_deg,
        ]
    }

    /// The geometry and port timing, when the table gives them (`None` when it gives no
    /// geometry key at all).
    pub fn geometry(&self) -> Result<Option<(VaneGeometry, PortTiming)>, MotorSpecError> {
        let values = self.geometry_values();
        if values.iter().all(Option::is_none) {
            return Ok(None);
        }
        let mut got = [0.0; 6];
        for (k, v) in values.iter().enumerate() {
            got[k] = v.ok_or(MotorSpecError::IncompleteGeometry {
                missing: GEOMETRY_KEYS[k],
            })?;
        }
        let vanes = self
            .vanes
            .ok_or(MotorSpecError::IncompleteGeometry { missing: "vanes" })?;
        for key in ["displacement_m3", "expansion_ratio", "dead_volume_m3"] {
            let given = match key {
                "displacement_m3" => self.displacement_m3,
                "expansion_ratio" => self.expansion_ratio,
                _ => self.dead_volume_m3,
            };
            if given.is_some() {
                return Err(MotorSpecError::GeometryAndVolume { key });
            }
        }
        let [length_m, r_stator_m, r_rotor_m, dead, fill, exp] = got;
        check_geometry(length_m, r_stator_m, r_rotor_m, [dead, fill, exp])?;
        let geometry = VaneGeometry {
            length_m,
            r_stator_m,
            r_rotor_m,
            vanes,
        };
        let timing = PortTiming {
            alpha_dead_rad: dead.to_radians(),
            alpha_fill_rad: fill.to_radians(),
            alpha_exp_rad: exp.to_radians(),
        };
        Ok(Some((geometry, timing)))
    }

    /// The nominal motor: defaults, overridden by the table's vanes and volumes (given
    /// directly, or derived from the geometry by paper eqs. 5–7), checked.
    pub fn nominal_params(&self) -> Result<MotorParams, MotorSpecError> {
        let mut set = ParamSet::default();
        let volumes = match self.geometry()? {
            Some((g, timing)) => {
                let d = g.derived_volumes(&timing);
                [Some(d.v_disp_m3), Some(d.eps), Some(d.v_dead_m3)]
            }
            None => [
                self.displacement_m3,
                self.expansion_ratio,
                self.dead_volume_m3,
            ],
        };
        // The size-scaled defaults first, so that a value the table gives (the dead volume)
        // overrides its default.
        if let Some(v_disp) = volumes[0] {
            let size = v_disp / crate::model::params::MotorParams::default().v_disp();
            for (id, value) in scaled_defaults(size) {
                set.set_value(id, value);
            }
        }
        let given = [
            (ParamId::Z, self.vanes.map(f64::from)),
            (ParamId::V_DISP, volumes[0]),
            (ParamId::EPS, volumes[1]),
            (ParamId::V_DEAD, volumes[2]),
        ];
        for (id, value) in given {
            if let Some(v) = value {
                set.set_value(id, v);
            }
        }
        Ok(set.check()?)
    }
}

/// Where the value a fit assumes for a `[motor]` key that pages rarely print comes from:
/// (rig.toml key, source). The values themselves are the registry's defaults
/// (`model::spec`), the dead volume's scaled to the displacement.
pub const ASSUMED_SOURCES: [(&str, &str); 4] = [
    (
        "displacement_m3",
        "the paper's motor AR034-11 (W. Beater; docs/model.md); a fit of catalogue pages alone estimates it from the pages (docs/estimation.md, \"A page without a displacement\")",
    ),
    (
        "vanes",
        "the paper's motor AR034-11 (W. Beater; docs/model.md); vane air motors have 3 to 10 vanes (Hydraulics & Pneumatics, Fluid Power Basics, \"Air motors\")",
    ),
    (
        "expansion_ratio",
        "the paper's motor AR034-11 (W. Beater; docs/model.md)",
    ),
    (
        "dead_volume_m3",
        "AR034-11's 0.1 cm³ scaled with the displacement (geometric similarity; docs/model.md, \"Defaults that follow the motor's size\")",
    ),
];

/// The source of the value assumed for `key` (one of [`ASSUMED_SOURCES`]).
fn assumed_source(key: &str) -> &'static str {
    ASSUMED_SOURCES
        .iter()
        .find(|(k, _)| *k == key)
        .map_or("", |(_, s)| s)
}

impl MotorSection {
    /// The motor a fit of this table will use, one line per key a page or rig file should
    /// give (displacement, vanes, expansion ratio, dead volume): its value and where it came
    /// from (given, derived from the geometry, or assumed, not printed, with the source of
    /// the assumed value), for `vanefit check`.
    pub fn assumed(&self) -> Result<Vec<String>, MotorSpecError> {
        let p = self.nominal_params()?;
        let geometry = self.geometry()?.is_some();
        let reference = MotorParams::default();
        let size = p.v_disp() / reference.v_disp();
        let from = |given: bool, key: &str, note: &str| -> String {
            if geometry && key != "vanes" {
                "derived from the geometry (paper eqs. 5–7)".to_string()
            } else if given {
                "given".to_string()
            } else {
                format!(
                    "(assumed, not printed; source: {}{note})",
                    assumed_source(key)
                )
            }
        };
        let mut lines = vec![
            format!(
                "displacement    {:.4} cm³  {}",
                p.v_disp() * 1e6,
                from(
                    self.displacement_m3.is_some(),
                    "displacement_m3",
                    "; give displacement_m3 or displacement_cm3"
                )
            ),
            format!(
                "vanes           {}  {}",
                p.z(),
                from(self.vanes.is_some(), "vanes", "")
            ),
            format!(
                "expansion ratio {:.4}  {}",
                p.eps(),
                from(self.expansion_ratio.is_some(), "expansion_ratio", "")
            ),
            format!(
                "dead volume     {:.4} cm³  {}",
                p.v_dead() * 1e6,
                from(
                    self.dead_volume_m3.is_some(),
                    "dead_volume_m3",
                    &format!(", here × {size:.3}")
                )
            ),
        ];
        if size != 1.0 {
            lines.push(format!(
                "conductances, friction, volumes and inertia: AR034-11's scaled to {size:.3}× its displacement (geometric similarity)"
            ));
        }
        Ok(lines)
    }
}

/// The defaults that follow the motor's size (`ParamSpec::size_exponent`: geometric
/// similarity with s = V_disp/V_disp,AR034; docs/model.md, "Defaults that follow the
/// motor's size"), scaled to a motor `size` times AR034-11's displacement (nothing when the
/// size is 1, so the default motor keeps its exact values).
fn scaled_defaults(size: f64) -> Vec<(ParamId, f64)> {
    if size == 1.0 || !(size.is_finite() && size > 0.0) {
        return Vec::new();
    }
    ParamId::all()
        .filter(|id| id.spec().size_exponent.is_some())
        .map(|id| (id, id.spec().scaled_default(size)))
        .collect()
}

/// Lengths positive, the rotor inside the stator, the ports in the order dead < fill < exp
/// within one turn.
fn check_geometry(
    length_m: f64,
    r_stator_m: f64,
    r_rotor_m: f64,
    angles_deg: [f64; 3],
) -> Result<(), MotorSpecError> {
    let bad = |key, value, reason| Err(MotorSpecError::BadGeometry { key, value, reason });
    for (key, value) in [
        ("length_m", length_m),
        ("r_stator_m", r_stator_m),
        ("r_rotor_m", r_rotor_m),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return bad(key, value, "must be a length > 0 m");
        }
    }
    if r_rotor_m >= r_stator_m {
        return bad("r_rotor_m", r_rotor_m, "must be smaller than r_stator_m");
    }
    let [dead, fill, exp] = angles_deg;
    for (key, value) in [
        ("alpha_dead_deg", dead),
        ("alpha_fill_deg", fill),
        ("alpha_exp_deg", exp),
    ] {
        if !(value.is_finite() && (0.0..=360.0).contains(&value)) {
            return bad(key, value, "must be an angle from 0 to 360 degrees");
        }
    }
    if fill <= dead {
        return bad("alpha_fill_deg", fill, "must be larger than alpha_dead_deg");
    }
    if exp < fill {
        return bad(
            "alpha_exp_deg",
            exp,
            "must not be smaller than alpha_fill_deg",
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The appendix motor by its geometry, with port angles that give its volumes.
    fn ar034_by_geometry() -> MotorSection {
        let g = VaneGeometry::ar034_11();
        let v_fill = 3.8e-6 / 5.0;
        MotorSection {
            vanes: Some(5),
            length_m: Some(g.length_m),
            r_stator_m: Some(g.r_stator_m),
            r_rotor_m: Some(g.r_rotor_m),
            alpha_dead_deg: Some((0.5 * g.gamma()).to_degrees()),
            alpha_fill_deg: Some(g.alpha_at_volume(v_fill).unwrap().to_degrees()),
            alpha_exp_deg: Some(g.alpha_at_volume(1.071 * v_fill).unwrap().to_degrees()),
            ..MotorSection::default()
        }
    }

    #[test]
    fn geometry_gives_the_appendix_volumes() {
        let p = ar034_by_geometry().nominal_params().unwrap();
        assert!((p.v_disp() - 3.8e-6).abs() < 1e-12, "{}", p.v_disp());
        assert!((p.eps() - 1.071).abs() < 1e-9, "{}", p.eps());
        // Recomputed independently: the dead volume is the working volume at α_dead (eq. 5).
        let g = VaneGeometry::ar034_11();
        assert!((p.v_dead() - g.v_working(0.5 * g.gamma())).abs() < 1e-18);
    }

    #[test]
    fn volumes_given_directly_are_used_as_given() {
        let m = MotorSection {
            vanes: Some(7),
            displacement_m3: Some(5e-6),
            expansion_ratio: Some(1.2),
            ..MotorSection::default()
        };
        let p = m.nominal_params().unwrap();
        assert_eq!((p.z(), p.v_disp(), p.eps()), (7.0, 5e-6, 1.2));
        assert_eq!(
            MotorSection::default().nominal_params().unwrap(),
            MotorParams::default()
        );
    }

    /// The motor of a `[motor]` table that gives only a displacement `size` times AR034's.
    fn scaled_motor(size: f64) -> MotorParams {
        MotorSection {
            displacement_m3: Some(3.8e-6 * size),
            ..MotorSection::default()
        }
        .nominal_params()
        .unwrap()
    }

    /// Each default with a physical size, by name, against the exponent geometric similarity
    /// gives it (written out here, not read from the registry's size exponents): a default that stays at
    /// AR034's value whatever the displacement fails its own line.
    #[test]
    fn every_dimensional_default_follows_the_displacement() {
        let expected: [(&str, f64); 13] = [
            ("v_dead", 1.0),
            ("vol1", 1.0),
            ("vol2", 1.0),
            ("vole", 1.0),
            ("c_in1", 2.0 / 3.0),
            ("c_out2", 2.0 / 3.0),
            ("c_ext", 2.0 / 3.0),
            ("c_1e", 2.0 / 3.0),
            ("c_2e", 2.0 / 3.0),
            ("c_12", 2.0 / 3.0),
            ("t_coulomb", 1.0),
            ("visc", 4.0 / 3.0),
            ("inertia", 5.0 / 3.0),
        ];
        let base = MotorParams::default();
        for size in [0.4, 2.5] {
            let p = scaled_motor(size);
            for (name, k) in expected {
                let (b, v) = (base.get(name).unwrap(), p.get(name).unwrap());
                let want = b * size.powf(k);
                assert!(
                    (v - want).abs() <= 1e-12 * want,
                    "{name} at {size}× the displacement: {v:e}, want {want:e} (∝ s^{k:.3})"
                );
            }
            for name in ["z", "eps", "b_crit", "n_poly"] {
                assert_eq!(p.get(name), base.get(name), "{name} is dimensionless");
            }
        }
    }

    /// No default with a unit of length, area, volume, mass or force is left unscaled: a
    /// parameter added later with such a unit needs a size exponent in the registry.
    #[test]
    fn no_dimensional_base_default_is_left_out() {
        let kept = ["v_disp", "w_reg"];
        for s in crate::model::params::BASE_PARAMS {
            let dimensional = ["m3", "kg", "N*m"].iter().any(|u| s.unit.contains(u));
            if dimensional && !kept.contains(&s.name) {
                assert!(
                    s.size_exponent.is_some(),
                    "{} ({}) does not follow the motor's size",
                    s.name,
                    s.unit
                );
            }
        }
    }

    #[test]
    fn a_given_dead_volume_is_kept_and_a_missing_one_scales() {
        let m = MotorSection {
            displacement_m3: Some(2.1e-6),
            dead_volume_m3: Some(0.03e-6),
            ..MotorSection::default()
        };
        assert_eq!(m.nominal_params().unwrap().v_dead(), 0.03e-6);
        let p = scaled_motor(2.1 / 3.8);
        assert!(
            (p.v_dead() - 0.1e-6 * 2.1 / 3.8).abs() < 1e-18,
            "{}",
            p.v_dead()
        );
    }

    #[test]
    fn the_assumed_motor_marks_every_default() {
        let lines = MotorSection::default().assumed().unwrap();
        assert_eq!(lines.len(), 4, "{lines:?}");
        assert!(
            lines
                .iter()
                .all(|l| l.contains("(assumed, not printed") && l.contains("; source: ")),
            "{lines:?}"
        );
        // The vane count: the registry's default, with where it comes from.
        assert!(
            lines[1].starts_with("vanes           5  (assumed, not printed; source: ")
                && lines[1].contains("3 to 10 vanes"),
            "{}",
            lines[1]
        );
        let m = MotorSection {
            displacement_m3: Some(7.6e-6),
            vanes: Some(4),
            ..MotorSection::default()
        };
        let lines = m.assumed().unwrap();
        assert!(lines[0].contains("7.6000 cm³  given"), "{}", lines[0]);
        assert!(lines[1].contains("given"), "{}", lines[1]);
        assert!(lines[2].contains("(assumed, not printed"), "{}", lines[2]);
        assert!(
            lines[3].contains("0.2000 cm³  (assumed, not printed") && lines[3].contains("2.000"),
            "{}",
            lines[3]
        );
        assert!(lines[4].contains("2.000×"), "{}", lines[4]);
        let lines = ar034_by_geometry().assumed().unwrap();
        assert!(lines[0].contains("geometry"), "{}", lines[0]);
    }

    #[test]
    fn a_displacement_in_cm3_is_read_as_m3_and_not_twice() {
        let mut m: MotorSection = toml::from_str("displacement_cm3 = 4.1").unwrap();
        m.resolve_units().unwrap();
        assert_eq!(m.displacement_m3, Some(4.1e-6));
        assert!((m.nominal_params().unwrap().v_disp() - 4.1e-6).abs() < 1e-18);
        let mut both: MotorSection =
            toml::from_str("displacement_cm3 = 4.1\ndisplacement_m3 = 4.1e-6").unwrap();
        let e = both.resolve_units().unwrap_err();
        assert_eq!(e.key(), "displacement_cm3");
    }

    /// A gearbox: the ratio finite and > 0, the efficiency in (0, 1] and only with a
    /// ratio; without an efficiency, the prior's.
    #[test]
    fn gearbox_keys_are_checked_and_named() {
        let table = |ratio: Option<f64>, eta: Option<f64>| MotorSection {
            gear_ratio: ratio,
            gear_efficiency: eta,
            ..MotorSection::default()
        };
        assert_eq!(table(None, None).gear(), Ok(None));
        let g = table(Some(4.0), Some(0.9)).gear().unwrap().unwrap();
        assert_eq!(
            (g.ratio, g.efficiency, g.efficiency_printed),
            (4.0, 0.9, true)
        );
        let g = table(Some(4.0), None).gear().unwrap().unwrap();
        assert!(!g.efficiency_printed && g.efficiency_ln_sd > 0.0);
        for (ratio, eta, key) in [
            (Some(0.0), None, "gear_ratio"),
            (Some(-2.0), None, "gear_ratio"),
            (Some(f64::NAN), None, "gear_ratio"),
            (Some(f64::INFINITY), None, "gear_ratio"),
            (Some(4.0), Some(0.0), "gear_efficiency"),
            (Some(4.0), Some(1.01), "gear_efficiency"),
            (Some(4.0), Some(f64::NAN), "gear_efficiency"),
            (None, Some(0.9), "gear_efficiency"),
        ] {
            let e = table(ratio, eta).gear().unwrap_err();
            assert_eq!(e.key(), key, "{ratio:?} {eta:?}: {e}");
            assert!(e.to_string().contains(key), "{e}");
        }
    }

    #[test]
    fn bad_tables_name_their_key() {
        let mut m = ar034_by_geometry();
        m.alpha_exp_deg = None;
        let e = m.nominal_params().unwrap_err();
        assert_eq!(
            e,
            MotorSpecError::IncompleteGeometry {
                missing: "alpha_exp_deg"
            }
        );
        let mut m = ar034_by_geometry();
        m.displacement_m3 = Some(3.8e-6);
        assert_eq!(m.nominal_params().unwrap_err().key(), "displacement_m3");
        let mut m = ar034_by_geometry();
        m.r_rotor_m = Some(0.01);
        assert_eq!(m.nominal_params().unwrap_err().key(), "r_rotor_m");
        let m = MotorSection {
            displacement_m3: Some(-1e-6),
            ..MotorSection::default()
        };
        let e = m.nominal_params().unwrap_err();
        assert_eq!(e.key(), "displacement_m3");
        assert!(e
            .to_string()
            .starts_with("[motor] gives parameter 'v_disp'"));
        let m = MotorSection {
            expansion_ratio: Some(0.5),
            ..MotorSection::default()
        };
        assert_eq!(m.nominal_params().unwrap_err().key(), "expansion_ratio");
    }
}
