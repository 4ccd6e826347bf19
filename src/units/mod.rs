//! Column names and units at the file edge (docs/formats.md, "CSV recordings"). Every CSV
//! column name is a quantity followed by its unit (`flow1_g_s`, `p_port1_bar_g`); values
//! convert to SI on import and back on export. Nothing inside the crate sees any unit but
//! SI.

pub(crate) mod constants;
pub(crate) mod format;

pub use constants::{P_ATM_PA, T0_K};
pub use format::trim_zeros;

use crate::units::constants::RHO0_KG_M3;
use std::f64::consts::PI;

/// A measured or imposed quantity in a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Quantity {
    /// Time, s.
    Time,
    /// Shaft speed, rad/s.
    Speed,
    /// Shaft torque, N·m.
    Torque,
    /// Mass flow into port 1, kg/s.
    Flow1,
    /// Mass flow out of port 2, kg/s.
    Flow2,
    /// Absolute pressure at port 1, Pa.
    PPort1,
    /// Absolute pressure at port 2, Pa (recorded for information).
    PPort2,
    /// Sonic conductance of the nozzle behind port 2, m³/(s·Pa).
    CPort2,
    /// Shaft power T·ω, W (a catalogue's power curve).
    Power,
}

impl Quantity {
    /// Every quantity.
    pub const ALL: [Quantity; 9] = [
        Quantity::Time,
        Quantity::Speed,
        Quantity::Torque,
        Quantity::Flow1,
        Quantity::Flow2,
        Quantity::PPort1,
        Quantity::PPort2,
        Quantity::CPort2,
        Quantity::Power,
    ];

    /// The column-name prefix (before the unit).
    pub fn prefix(self) -> &'static str {
        match self {
            Quantity::Time => "t",
            Quantity::Speed => "speed",
            Quantity::Torque => "torque",
            Quantity::Flow1 => "flow1",
            Quantity::Flow2 => "flow2",
            Quantity::PPort1 => "p_port1",
            Quantity::PPort2 => "p_port2",
            Quantity::CPort2 => "c_port2",
            Quantity::Power => "power",
        }
    }

    /// The quantity in words, for axis titles ("port 1 pressure").
    pub fn words(self) -> &'static str {
        match self {
            Quantity::Time => "time",
            Quantity::Speed => "speed",
            Quantity::Torque => "torque",
            Quantity::Flow1 => "port 1 mass flow (air consumption)",
            Quantity::Flow2 => "port 2 mass flow",
            Quantity::PPort1 => "port 1 pressure",
            Quantity::PPort2 => "port 2 pressure",
            Quantity::CPort2 => "port 2 nozzle conductance",
            Quantity::Power => "shaft power",
        }
    }

    /// Other prefixes a column name may start with: catalogues call the port-1 flow `air`
    /// (air consumption) and the port-1 pressure `p_supply`.
    fn aliases(self) -> &'static [&'static str] {
        match self {
            Quantity::Flow1 => &["air"],
            Quantity::PPort1 => &["p_supply"],
            _ => &[],
        }
    }

    /// Units accepted for this quantity.
    pub fn units(self) -> &'static [Unit] {
        use Unit::*;
        match self {
            Quantity::Time => &[S],
            Quantity::Speed => &[Rpm, RadS],
            Quantity::Torque => &[Nm, LbfFt, LbfIn],
            Quantity::Flow1 | Quantity::Flow2 => {
                &[GS, KgS, LMinAnr, LSAnr, LS, LMin, M3Min, Cfm, Scfm, NlMin]
            }
            Quantity::PPort1 | Quantity::PPort2 => &[Mpa, BarAbs, BarG, Pa, Kpa, PsiG, PsiA],
            Quantity::CPort2 => &[M3SPa, Dm3SBar],
            Quantity::Power => &[W, Kw, Hp],
        }
    }

    /// SI unit, for messages.
    pub fn si_unit(self) -> Unit {
        match self {
            Quantity::Time => Unit::S,
            Quantity::Speed => Unit::RadS,
            Quantity::Torque => Unit::Nm,
            Quantity::Flow1 | Quantity::Flow2 => Unit::KgS,
            Quantity::PPort1 | Quantity::PPort2 => Unit::Pa,
            Quantity::CPort2 => Unit::M3SPa,
            Quantity::Power => Unit::W,
        }
    }
}

/// A unit that a column may carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Unit {
    /// Seconds.
    S,
    /// Revolutions per minute.
    Rpm,
    /// Radians per second.
    RadS,
    /// Newton metres.
    Nm,
    /// Grams per second.
    GS,
    /// Kilograms per second.
    KgS,
    /// Free-air (ANR) volume flow in l/min, converted with ρ0.
    LMinAnr,
    /// Free-air (ANR) volume flow in l/s, converted with ρ0.
    LSAnr,
    /// Megapascal, absolute.
    Mpa,
    /// Bar, absolute.
    BarAbs,
    /// Gauge pressure in bar, relative to the rig's p_atm.
    BarG,
    /// Pascal, absolute.
    Pa,
    /// Kilopascal, absolute.
    Kpa,
    /// Sonic conductance, m³/(s·Pa).
    M3SPa,
    /// Sonic conductance, dm³/(s·bar) (ISO 6358 catalogues).
    Dm3SBar,
    /// Pound-force foot.
    LbfFt,
    /// Pound-force inch.
    LbfIn,
    /// Free-air volume flow in l/s (100 kPa, 20 °C, dry; ISO 1217).
    LS,
    /// Free-air volume flow in l/min (100 kPa, 20 °C, dry; ISO 1217).
    LMin,
    /// Free-air volume flow in m³/min (100 kPa, 20 °C, dry; ISO 1217).
    M3Min,
    /// Free-air volume flow in ft³/min (100 kPa, 20 °C, dry; ISO 1217).
    Cfm,
    /// Standard cubic feet per minute: US standard air, 0.075 lb/ft³.
    Scfm,
    /// Normal litres per minute (DIN 1343: 101.325 kPa, 0 °C, dry).
    NlMin,
    /// Gauge pressure in psi, relative to the rig's p_atm.
    PsiG,
    /// Absolute pressure in psi.
    PsiA,
    /// Watts.
    W,
    /// Kilowatts.
    Kw,
    /// Mechanical horsepower (550 ft·lbf/s).
    Hp,
}

impl Unit {
    /// The column-name suffix of the unit, e.g. `rpm`.
    pub fn suffix(self) -> &'static str {
        match self {
            Unit::S => "s",
            Unit::Rpm => "rpm",
            Unit::RadS => "rad_s",
            Unit::Nm => "nm",
            Unit::GS => "g_s",
            Unit::KgS => "kg_s",
            Unit::LMinAnr => "l_min_anr",
            Unit::LSAnr => "l_s_anr",
            Unit::Mpa => "mpa",
            Unit::BarAbs => "bar_abs",
            Unit::BarG => "bar_g",
            Unit::Pa => "pa",
            Unit::Kpa => "kpa",
            Unit::M3SPa => "m3_s_pa",
            Unit::Dm3SBar => "dm3_s_bar",
            Unit::LbfFt => "lbf_ft",
            Unit::LbfIn => "lbf_in",
            Unit::LS => "l_s",
            Unit::LMin => "l_min",
            Unit::M3Min => "m3_min",
            Unit::Cfm => "cfm",
            Unit::Scfm => "scfm",
            Unit::NlMin => "nl_min",
            Unit::PsiG => "psi_g",
            Unit::PsiA => "psi_a",
            Unit::W => "w",
            Unit::Kw => "kw",
            Unit::Hp => "hp",
        }
    }

    /// The unit as people write it, for axis titles (`N·m`, `bar(g)`, `l/min ANR`); a
    /// pressure unit says whether it is absolute or gauge (`MPa abs`, `bar(g)`).
    pub fn symbol(self) -> &'static str {
        match self {
            Unit::S => "s",
            Unit::Rpm => "rpm",
            Unit::RadS => "rad/s",
            Unit::Nm => "N·m",
            Unit::GS => "g/s",
            Unit::KgS => "kg/s",
            Unit::LMinAnr => "l/min ANR",
            Unit::LSAnr => "l/s ANR",
            Unit::Mpa => "MPa abs",
            Unit::BarAbs => "bar(a)",
            Unit::BarG => "bar(g)",
            Unit::Pa => "Pa abs",
            Unit::Kpa => "kPa abs",
            Unit::M3SPa => "m³/(s·Pa)",
            Unit::Dm3SBar => "dm³/(s·bar)",
            Unit::LbfFt => "lbf·ft",
            Unit::LbfIn => "lbf·in",
            Unit::LS => "l/s",
            Unit::LMin => "l/min",
            Unit::M3Min => "m³/min",
            Unit::Cfm => "cfm",
            Unit::Scfm => "scfm",
            Unit::NlMin => "Nl/min",
            Unit::PsiG => "psi(g)",
            Unit::PsiA => "psi(a)",
            Unit::W => "W",
            Unit::Kw => "kW",
            Unit::Hp => "hp",
        }
    }

    /// Other suffixes that name the same unit (`bar_a` for `bar_abs`, `psig`, `nm3_min`…).
    pub fn aliases(self) -> &'static [&'static str] {
        match self {
            Unit::BarAbs => &["bar_a"],
            // Makers' spellings of a page: "min-1", "min⁻¹", "1/min", "r.p.m.".
            Unit::Rpm => &["r_min", "min_1", "min-1", "1_min", "r_p_m", "rev_min"],
            Unit::PsiG => &["psig"],
            Unit::PsiA => &["psia", "psi_abs"],
            // "Nl/min ANR": litres counted at ANR, whatever the N says.
            Unit::LMinAnr => &["anr_l_min", "nl_min_anr"],
            Unit::Nm => &["n_m"],
            // "in·lbf", "in-lb", "lb-in", "in.lbs": all the inch-pound.
            Unit::LbfIn => &["in_lbf", "in_lb", "lb_in", "in_lbs", "lbs_in"],
            Unit::W => &["watt", "watts"],
            // "ft³/min" is cfm.
            Unit::Cfm => &["ft3_min"],
            _ => &[],
        }
    }

    /// The reference conditions a volume-flow unit is counted at, for people (`None` for
    /// other units).
    pub fn reference_conditions(self) -> Option<&'static str> {
        match self {
            Unit::LMinAnr | Unit::LSAnr => Some("ANR (ISO 8778/6358): ρ0 = 1.185 kg/m³"),
            Unit::LS | Unit::LMin | Unit::M3Min | Unit::Cfm => {
                Some("free air (ISO 1217): 100 kPa, 20 °C, dry, ρ = 1.1884 kg/m³")
            }
            Unit::Scfm => Some("US standard air: 0.075 lb/ft³ = 1.2014 kg/m³"),
            Unit::NlMin => Some("normal (DIN 1343): 101.325 kPa, 0 °C, dry, ρ = 1.2923 kg/m³"),
            _ => None,
        }
    }

    /// The factor k with SI = k·v for units without an offset (`None` for gauge units).
    fn si_factor(self) -> Option<f64> {
        use constants::*;
        Some(match self {
            Unit::S | Unit::RadS | Unit::Nm | Unit::KgS | Unit::Pa | Unit::M3SPa | Unit::W => 1.0,
            Unit::Rpm => PI / 30.0,
            Unit::GS => 1e-3,
            Unit::LMinAnr => 1e-3 * RHO0_KG_M3 / 60.0,
            Unit::LSAnr => 1e-3 * RHO0_KG_M3,
            Unit::LS => 1e-3 * RHO_FREE_AIR_KG_M3,
            Unit::LMin => 1e-3 * RHO_FREE_AIR_KG_M3 / 60.0,
            Unit::M3Min => RHO_FREE_AIR_KG_M3 / 60.0,
            Unit::Cfm => FT3_M3 * RHO_FREE_AIR_KG_M3 / 60.0,
            Unit::Scfm => FT3_M3 * RHO_SCFM_KG_M3 / 60.0,
            Unit::NlMin => 1e-3 * RHO_NORMAL_KG_M3 / 60.0,
            Unit::Mpa => 1e6,
            Unit::BarAbs => 1e5,
            Unit::Kpa => 1e3,
            Unit::PsiA => PSI_PA,
            // 1 dm³/(s·bar) = 1e-3 m³/s per 1e5 Pa.
            Unit::Dm3SBar => 1e-8,
            Unit::LbfFt => LBF_N * FT_M,
            Unit::LbfIn => LBF_N * IN_M,
            Unit::Kw => 1e3,
            Unit::Hp => HP_W,
            Unit::BarG | Unit::PsiG => return None,
        })
    }

    /// Converts a value in this unit to SI. `p_atm_pa` is needed for gauge pressure.
    pub fn to_si(self, v: f64, p_atm_pa: f64) -> f64 {
        match self {
            // One rounding (fused multiply-add), so that every absolute pressure has a
            // gauge value that converts back to it exactly.
            Unit::BarG => v.mul_add(1e5, p_atm_pa),
            Unit::PsiG => v.mul_add(constants::PSI_PA, p_atm_pa),
            // The original units keep their original arithmetic (bit-identical imports).
            Unit::S | Unit::RadS | Unit::Nm | Unit::KgS | Unit::Pa | Unit::M3SPa | Unit::W => v,
            Unit::Rpm => v * PI / 30.0,
            Unit::GS => v * 1e-3,
            Unit::LMinAnr => v * 1e-3 * RHO0_KG_M3 / 60.0,
            Unit::LSAnr => v * 1e-3 * RHO0_KG_M3,
            Unit::Mpa => v * 1e6,
            Unit::BarAbs => v * 1e5,
            Unit::Kpa => v * 1e3,
            Unit::Dm3SBar => v * 1e-8,
            u => v * u.si_factor().unwrap_or(1.0),
        }
    }

    /// The power of ten k when the unit is exactly 10^k SI units (g/s: −3, MPa: 6,
    /// dm³/(s·bar): −8, SI units: 0), else `None`.
    pub fn decimal_exponent(self) -> Option<i32> {
        match self {
            Unit::S | Unit::RadS | Unit::Nm | Unit::KgS | Unit::Pa | Unit::M3SPa => Some(0),
            Unit::GS => Some(-3),
            Unit::Mpa => Some(6),
            Unit::BarAbs => Some(5),
            Unit::Kpa => Some(3),
            Unit::Dm3SBar => Some(-8),
            Unit::Kw => Some(3),
            Unit::W => Some(0),
            _ => None,
        }
    }

    /// Reads a number written in this unit and converts it to SI. Where the unit is a power
    /// of ten of the SI unit, the conversion shifts the decimal exponent of the text before
    /// it is rounded to binary, so that the SI value is the one nearest the written decimal
    /// (one rounding, where `to_si(text.parse())` would round twice): the same quantity
    /// written in g/s or kg/s, in MPa or Pa, gives the same bits. Other units convert with
    /// [`Unit::to_si`]. `None` when the text is not a number.
    pub fn parse_si(self, text: &str, p_atm_pa: f64) -> Option<f64> {
        let v: f64 = text.parse().ok()?;
        self.parsed_si(text, v, p_atm_pa)
    }

    /// [`Unit::parse_si`] of `text` whose number `v` the caller has read already (a
    /// recording's reader checks each cell's number first, and reading it again was a
    /// seventh of reading a large recording).
    pub fn parsed_si(self, text: &str, v: f64, p_atm_pa: f64) -> Option<f64> {
        let Some(k) = self.decimal_exponent() else {
            return Some(self.to_si(v, p_atm_pa));
        };
        if k == 0 || v == 0.0 || !v.is_finite() {
            return Some(self.to_si(v, p_atm_pa));
        }
        let (mantissa, exponent) = match text.find(['e', 'E']) {
            Some(i) => (&text[..i], text[i + 1..].parse::<i32>().ok()?),
            None => (text, 0),
        };
        exponent
            .checked_add(k)
            .and_then(|e| shifted(mantissa, e))
            .or_else(|| Some(self.to_si(v, p_atm_pa)))
    }

    /// Converts an SI value back to this unit (inverse of [`Unit::to_si`]).
    pub fn from_si(self, v: f64, p_atm_pa: f64) -> f64 {
        match self {
            Unit::BarG => (v - p_atm_pa) * 1e-5,
            Unit::PsiG => (v - p_atm_pa) / constants::PSI_PA,
            // Exact where SI is the unit (no division by one).
            Unit::S | Unit::RadS | Unit::Nm | Unit::KgS | Unit::Pa | Unit::M3SPa | Unit::W => v,
            Unit::GS => v * 1e3,
            Unit::Mpa => v * 1e-6,
            Unit::BarAbs => v * 1e-5,
            Unit::Kpa => v * 1e-3,
            Unit::Kw => v * 1e-3,
            Unit::Dm3SBar => v * 1e8,
            Unit::Rpm => v * 30.0 / PI,
            Unit::LMinAnr => v * 60.0 / (1e-3 * RHO0_KG_M3),
            Unit::LSAnr => v / (1e-3 * RHO0_KG_M3),
            u => v / u.si_factor().unwrap_or(1.0),
        }
    }
}

/// `mantissa`e`exponent` read as a number, composed on the stack when it is short (as every
/// number of a recording is): `parse_si` runs once per cell, and a heap string per cell
/// was a tenth of reading a 100 MB recording.
fn shifted(mantissa: &str, exponent: i32) -> Option<f64> {
    use std::io::Write as _;
    let mut buf = [0u8; 64];
    let mut rest = &mut buf[..];
    if write!(rest, "{mantissa}e{exponent}").is_err() {
        return format!("{mantissa}e{exponent}").parse().ok();
    }
    let len = 64 - rest.len();
    std::str::from_utf8(&buf[..len]).ok()?.parse().ok()
}

/// Why a column name was not understood (the units layer's error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ColumnNameError {
    /// The quantity is known but the unit is not.
    #[error(
        "unknown unit '{unit}' for {} (known: {})",
        quantity.prefix(),
        known_units(*quantity)
    )]
    UnknownUnit {
        /// The quantity the name starts with.
        quantity: Quantity,
        /// The unit suffix that is not known.
        unit: String,
    },
    /// No known quantity.
    #[error("unknown column (expected a quantity and its unit, e.g. 'speed_rpm')")]
    UnknownColumn,
}

/// The suffixes of a quantity's units, for messages.
fn known_units(q: Quantity) -> String {
    q.units()
        .iter()
        .map(|u| u.suffix())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Splits a column name into quantity and unit, e.g. `flow1_l_min_anr` → (Flow1, LMinAnr).
pub fn parse_column(name: &str) -> Result<(Quantity, Unit), ColumnNameError> {
    let name = name.trim().to_ascii_lowercase();
    // Longest prefix first, so that "p_port1" wins over a shorter one.
    let mut prefixes: Vec<(Quantity, &str)> = Quantity::ALL
        .iter()
        .flat_map(|q| {
            std::iter::once(q.prefix())
                .chain(q.aliases().iter().copied())
                .map(|p| (*q, p))
        })
        .collect();
    prefixes.sort_by_key(|(_, p)| std::cmp::Reverse(p.len()));
    for (q, prefix) in prefixes {
        if let Some(rest) = name.strip_prefix(prefix).and_then(|r| r.strip_prefix('_')) {
            return unit_of(q, rest).map(|u| (q, u));
        }
    }
    Err(ColumnNameError::UnknownColumn)
}

/// The unit of quantity `q` that the suffix `text` names (its own suffix or an alias).
pub fn unit_of(q: Quantity, text: &str) -> Result<Unit, ColumnNameError> {
    let text = text.trim().to_ascii_lowercase();
    q.units()
        .iter()
        .find(|u| u.suffix() == text || u.aliases().contains(&text.as_str()))
        .copied()
        .ok_or(ColumnNameError::UnknownUnit {
            quantity: q,
            unit: text,
        })
}

/// Canonical column name for a quantity in a unit.
pub fn column_name(q: Quantity, u: Unit) -> String {
    format!("{}_{}", q.prefix(), u.suffix())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_unit_round_trips() {
        for q in Quantity::ALL {
            for u in q.units() {
                let (q2, u2) = parse_column(&column_name(q, *u)).unwrap();
                assert_eq!((q2, *u), (q, u2));
                let si = u.to_si(3.7, 101_325.0);
                assert!((u.from_si(si, 101_325.0) - 3.7).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn makers_spellings_are_aliases() {
        for (q, text, u) in [
            (Quantity::Speed, "min-1", Unit::Rpm),
            (Quantity::Speed, "min_1", Unit::Rpm),
            (Quantity::Speed, "1_min", Unit::Rpm),
            (Quantity::Speed, "r_p_m", Unit::Rpm),
            (Quantity::Torque, "in_lbf", Unit::LbfIn),
            (Quantity::Torque, "lb_in", Unit::LbfIn),
            (Quantity::Torque, "in_lbs", Unit::LbfIn),
            (Quantity::Power, "watts", Unit::W),
            (Quantity::Flow1, "ft3_min", Unit::Cfm),
            (Quantity::Flow1, "nl_min_anr", Unit::LMinAnr),
        ] {
            assert_eq!(unit_of(q, text), Ok(u), "{text}");
        }
        // A curve file's header with a maker's unit.
        assert_eq!(
            parse_column("speed_min-1"),
            Ok((Quantity::Speed, Unit::Rpm))
        );
    }

    #[test]
    fn decimal_units_convert_with_one_rounding() {
        // 0.1003551 MPa is 100355.1 Pa: the same bits whichever way it is written.
        let pa: f64 = "100355.1".parse().unwrap();
        assert_eq!(Unit::Mpa.parse_si("1.003551e-1", 0.0), Some(pa));
        assert_eq!(Unit::Mpa.parse_si("0.1003551", 0.0), Some(pa));
        assert_eq!(Unit::Kpa.parse_si("100.3551", 0.0), Some(pa));
        assert_eq!(Unit::BarAbs.parse_si("+1.003551E0", 0.0), Some(pa));
        let c: f64 = "3.005567e-8".parse().unwrap();
        assert_eq!(Unit::Dm3SBar.parse_si("3.005567", 0.0), Some(c));
        assert_eq!(Unit::GS.parse_si("-2.5", 0.0), Some(-2.5e-3));
        assert_eq!(Unit::GS.parse_si("abc", 0.0), None);
        assert_eq!(Unit::GS.parse_si("1e", 0.0), None);
        assert_eq!(Unit::Mpa.parse_si("inf", 0.0), Some(f64::INFINITY));
        assert!(Unit::Mpa.parse_si("1e308", 0.0).unwrap().is_infinite());
        assert_eq!(
            Unit::Rpm.parse_si("60", 0.0),
            Some(Unit::Rpm.to_si(60.0, 0.0))
        );
        // Gauge pressure rounds once too.
        assert_eq!(Unit::BarG.to_si(6.0, 101_325.0), 701_325.0);
    }

    #[test]
    fn catalogue_units_agree_with_hand_calculation() {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-300);
        // psi: 1 lbf/in² = 0.45359237·9.80665 N / 0.0254² m² = 6894.757293168361 Pa.
        assert!(close(Unit::PsiA.to_si(1.0, 0.0), 6_894.757_293_168_361));
        // 90 psi(g) at 101325 Pa: 90·6894.757293168361 + 101325 = 721853.1563851525 Pa.
        assert!(close(
            Unit::PsiG.to_si(90.0, 101_325.0),
            721_853.156_385_152_5
        ));
        // cfm (free air): 1 ft³/min = 0.028316846592/60 m³/s × 100000/(287.05287·293.15) kg/m³.
        let rho_free: f64 = 100_000.0 / (287.052_87 * 293.15);
        assert!((rho_free - 1.188_360_5).abs() < 1e-7, "{rho_free}");
        assert!(close(
            Unit::Cfm.to_si(1.0, 0.0),
            0.028_316_846_592 / 60.0 * rho_free
        ));
        // scfm: 0.075 lb/ft³ · 1 ft³/min = 0.075·0.45359237/60 kg/s = 5.669904625e-4 kg/s.
        assert!(close(Unit::Scfm.to_si(1.0, 0.0), 5.669_904_625e-4));
        // hp: 550 ft·lbf/s = 550·0.3048·4.4482216152605 W = 745.6998715822702 W.
        assert!(close(Unit::Hp.to_si(1.0, 0.0), 745.699_871_582_270_2));
        assert!(close(Unit::Kw.to_si(0.12, 0.0), 120.0));
        // lbf·ft = 4.4482216152605·0.3048 = 1.3558179483314004 N·m; lbf·in = ÷12.
        assert!(close(Unit::LbfFt.to_si(1.0, 0.0), 1.355_817_948_331_400_4));
        assert!(close(Unit::LbfIn.to_si(12.0, 0.0), 1.355_817_948_331_400_4));
        // Nl/min (DIN 1343, 101325 Pa, 273.15 K): ρn = 101325/(287.05287·273.15) = 1.2922...
        let rho_n: f64 = 101_325.0 / (287.052_87 * 273.15);
        assert!((rho_n - 1.2923).abs() < 1e-4, "{rho_n}");
        assert!(close(Unit::NlMin.to_si(60.0, 0.0), 1e-3 * rho_n));
        // m³/min and l/s of free air: 0.06 m³/min = 1 l/s.
        assert!(close(
            Unit::M3Min.to_si(0.06, 0.0),
            Unit::LS.to_si(1.0, 0.0)
        ));
        assert!(close(Unit::LMin.to_si(60.0, 0.0), Unit::LS.to_si(1.0, 0.0)));
        // r/min is rpm; bar(a) is bar_abs.
        assert_eq!(
            parse_column("speed_r_min").unwrap(),
            (Quantity::Speed, Unit::Rpm)
        );
        assert_eq!(
            parse_column("p_supply_bar_a").unwrap(),
            (Quantity::PPort1, Unit::BarAbs)
        );
        assert_eq!(
            parse_column("air_cfm").unwrap(),
            (Quantity::Flow1, Unit::Cfm)
        );
        assert_eq!(
            parse_column("power_kw").unwrap(),
            (Quantity::Power, Unit::Kw)
        );
        // A unit that does not fit the quantity is refused with the known ones listed.
        let e = parse_column("torque_kw").unwrap_err().to_string();
        assert!(e.contains("'kw'") && e.contains("lbf_ft"), "{e}");
        // Every new unit round-trips through SI.
        for u in [
            Unit::PsiG,
            Unit::PsiA,
            Unit::Cfm,
            Unit::Scfm,
            Unit::NlMin,
            Unit::Hp,
        ] {
            assert!((u.from_si(u.to_si(7.3, 101_325.0), 101_325.0) - 7.3).abs() < 1e-12);
        }
    }

    #[test]
    fn conversions_agree_with_hand_calculation() {
        assert!((Unit::Rpm.to_si(60.0, 0.0) - 2.0 * PI).abs() < 1e-12);
        assert!((Unit::BarG.to_si(6.0, 101_325.0) - 701_325.0).abs() < 1e-9);
        assert!((Unit::LMinAnr.to_si(60.0, 0.0) - 1.185e-3).abs() < 1e-15);
        assert!((Unit::Dm3SBar.to_si(0.68, 0.0) - 6.8e-9).abs() < 1e-20);
        assert!(matches!(
            parse_column("flow1_furlongs"),
            Err(ColumnNameError::UnknownUnit { .. })
        ));
        assert_eq!(
            parse_column("temperature_k"),
            Err(ColumnNameError::UnknownColumn)
        );
    }
}
