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
            Quantity::Torque => &[Nm, LbfFt, LbfIn, NCm, KgfM, KgfCm],
            Quantity::Flow1 | Quantity::Flow2 => &[
                GS, KgS, LMinAnr, LSAnr, LS, LMin, M3Min, Cfm, Scfm, NlMin, NlS,
            ],
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
    /// Normal litres per second (DIN 1343: 101.325 kPa, 0 °C, dry).
    NlS,
    /// Newton centimetre.
    NCm,
    /// Kilogram-force metre (kgf = 9.80665 N).
    KgfM,
    /// Kilogram-force centimetre.
    KgfCm,
}

/// How a unit converts to SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scale {
    /// SI = v·10^k exactly (g/s: −3, MPa: 6, SI units: 0): read with one rounding
    /// ([`Unit::parse_si`]).
    Decimal(i32),
    /// SI = v·k.
    Factor(f64),
    /// A gauge pressure: SI = v·k + p_atm (the rig's atmosphere).
    Gauge(f64),
}

/// Everything known of one unit, in one place: its column suffix, how people write it,
/// the other spellings makers print (normalised as [`unit_of`] compares them: lower case,
/// `_` for any run of other signs, `³` → `3`, `⁻¹` → `_1`), its factor to SI, where that
/// factor comes from, and for a volume flow the reference conditions it counts air at.
#[derive(Debug, Clone, Copy)]
pub struct UnitFacts {
    /// The unit.
    pub unit: Unit,
    /// The column-name suffix (`rpm`, `bar_g`).
    pub suffix: &'static str,
    /// The unit as people write it (`N·m`, `bar(g)`, `l/min ANR`).
    pub symbol: &'static str,
    /// Other spellings of the same unit (`u_min` for U/min, `barg`, `ft_lb`).
    pub spellings: &'static [&'static str],
    /// The conversion to SI.
    pub scale: Scale,
    /// Where the factor comes from.
    pub source: &'static str,
    /// For a volume flow: the reference conditions its volume is counted at.
    pub reference: Option<&'static str>,
}

/// Free air of ISO 1217, for the reference of its units.
const FREE_AIR: Option<&str> = Some("free air (ISO 1217): 100 kPa, 20 °C, dry, ρ = 1.1884 kg/m³");
/// ANR of ISO 8778, for the reference of its units.
const ANR: Option<&str> = Some("ANR (ISO 8778/6358): ρ0 = 1.185 kg/m³");
/// Normal conditions of DIN 1343, for the reference of its units.
const NORMAL: Option<&str> = Some("normal (DIN 1343): 101.325 kPa, 0 °C, dry, ρ = 1.2923 kg/m³");
/// The units' source: the SI Brochure.
const SI: &str = "SI Brochure (BIPM, 9th ed. 2019)";
/// The inch-pound units' source.
const NIST: &str = "NIST SP 811 (2008), appendix B: lb = 0.45359237 kg, ft = 0.3048 m, in = 0.0254 m, g_n = 9.80665 m/s² (exact)";

/// Every unit, in the order of [`Unit`]'s variants (a test checks the order).
pub const UNITS: [UnitFacts; 32] = {
    use constants::*;
    use Scale::*;
    const fn u(
        unit: Unit,
        suffix: &'static str,
        symbol: &'static str,
        spellings: &'static [&'static str],
        scale: Scale,
        source: &'static str,
    ) -> UnitFacts {
        UnitFacts {
            unit,
            suffix,
            symbol,
            spellings,
            scale,
            source,
            reference: None,
        }
    }
    const fn flow(mut f: UnitFacts, reference: Option<&'static str>) -> UnitFacts {
        f.reference = reference;
        f
    }
    [
        u(Unit::S, "s", "s", &[], Decimal(0), SI),
        // Makers' spellings: "r/min", "min-1", "min⁻¹", "1/min", "r.p.m.", German "U/min"
        // and "UpM" (Umdrehungen pro Minute).
        u(Unit::Rpm, "rpm", "rpm",
            &["r_min", "min_1", "min-1", "1_min", "r_p_m", "rev_min", "u_min", "upm"],
            Factor(PI / 30.0), "one revolution is 2π rad (SI Brochure, 9th ed., table 4)"),
        u(Unit::RadS, "rad_s", "rad/s", &[], Decimal(0), SI),
        u(Unit::Nm, "nm", "N·m", &["n_m"], Decimal(0), SI),
        u(Unit::GS, "g_s", "g/s", &[], Decimal(-3), SI),
        u(Unit::KgS, "kg_s", "kg/s", &[], Decimal(0), SI),
        // "Nl/min ANR": litres counted at ANR, whatever the N says.
        flow(u(Unit::LMinAnr, "l_min_anr", "l/min ANR", &["anr_l_min", "nl_min_anr"],
            Factor(1e-3 * RHO0_KG_M3 / 60.0), "ISO 8778 (ANR: 20 °C, 100 kPa, 65 % RH), ρ0 = 1.185 kg/m³ of ISO 6358"), ANR),
        flow(u(Unit::LSAnr, "l_s_anr", "l/s ANR", &["anr_l_s", "nl_s_anr"],
            Factor(1e-3 * RHO0_KG_M3), "ISO 8778 (ANR: 20 °C, 100 kPa, 65 % RH), ρ0 = 1.185 kg/m³ of ISO 6358"), ANR),
        u(Unit::Mpa, "mpa", "MPa abs", &[], Decimal(6), SI),
        u(Unit::BarAbs, "bar_abs", "bar(a)", &["bar_a", "bara"], Decimal(5),
            "1 bar = 100 kPa (SI Brochure, 9th ed., table 8)"),
        // "barg", and German "bar(ü)" (Überdruck, DIN 1314).
        u(Unit::BarG, "bar_g", "bar(g)", &["barg", "bar_ü", "barü", "bar_ue"], Gauge(1e5),
            "1 bar = 100 kPa (SI Brochure, table 8); gauge: above the rig's atmosphere (DIN 1314: Überdruck)"),
        u(Unit::Pa, "pa", "Pa abs", &[], Decimal(0), SI),
        u(Unit::Kpa, "kpa", "kPa abs", &[], Decimal(3), SI),
        u(Unit::M3SPa, "m3_s_pa", "m³/(s·Pa)", &[], Decimal(0), SI),
        // 1 dm³/(s·bar) = 1e-3 m³/s per 1e5 Pa.
        u(Unit::Dm3SBar, "dm3_s_bar", "dm³/(s·bar)", &[], Decimal(-8),
            "ISO 6358-1 (sonic conductance in dm³/(s·bar)); 1 bar = 100 kPa"),
        // "ft·lbf", "ft.lbf", "ft lbf", "ft-lb", "lb-ft", "ft.lbs": a torque on a motor
        // page (the same product is an energy elsewhere; a torque column reads it as one).
        u(Unit::LbfFt, "lbf_ft", "lbf·ft",
            &["ft_lbf", "ft_lb", "lb_ft", "ft_lbs", "lbs_ft"],
            Factor(LBF_N * FT_M), NIST),
        // "in·lbf", "in-lb", "lb-in", "in.lbs": all the inch-pound.
        u(Unit::LbfIn, "lbf_in", "lbf·in", &["in_lbf", "in_lb", "lb_in", "in_lbs", "lbs_in"],
            Factor(LBF_N * IN_M), NIST),
        flow(u(Unit::LS, "l_s", "l/s", &[], Factor(1e-3 * RHO_FREE_AIR_KG_M3),
            "ISO 1217 free air: ρ = 100 kPa / (287.05287 J/(kg·K) · 293.15 K)"), FREE_AIR),
        flow(u(Unit::LMin, "l_min", "l/min", &[], Factor(1e-3 * RHO_FREE_AIR_KG_M3 / 60.0),
            "ISO 1217 free air: ρ = 100 kPa / (287.05287 J/(kg·K) · 293.15 K)"), FREE_AIR),
        flow(u(Unit::M3Min, "m3_min", "m³/min", &[], Factor(RHO_FREE_AIR_KG_M3 / 60.0),
            "ISO 1217 free air: ρ = 100 kPa / (287.05287 J/(kg·K) · 293.15 K)"), FREE_AIR),
        // "ft³/min" is cfm.
        flow(u(Unit::Cfm, "cfm", "cfm", &["ft3_min"], Factor(FT3_M3 * RHO_FREE_AIR_KG_M3 / 60.0),
            "ft³ = 0.3048³ m³ (NIST SP 811); ISO 1217 free air"), FREE_AIR),
        flow(u(Unit::Scfm, "scfm", "scfm", &[], Factor(FT3_M3 * RHO_SCFM_KG_M3 / 60.0),
            "US standard air, 0.075 lb/ft³ (ASME/ANSI; 14.7 psia, 68 °F, 36 % RH)"),
            Some("US standard air: 0.075 lb/ft³ = 1.2014 kg/m³")),
        flow(u(Unit::NlMin, "nl_min", "Nl/min", &[], Factor(1e-3 * RHO_NORMAL_KG_M3 / 60.0),
            "DIN 1343 normal conditions: ρn = 101.325 kPa / (287.05287 J/(kg·K) · 273.15 K)"), NORMAL),
        u(Unit::PsiG, "psi_g", "psi(g)", &["psig"], Gauge(PSI_PA),
            "psi = lbf/in² (NIST SP 811); gauge: above the rig's atmosphere"),
        u(Unit::PsiA, "psi_a", "psi(a)", &["psia", "psi_abs"], Factor(PSI_PA),
            "psi = lbf/in² (NIST SP 811)"),
        u(Unit::W, "w", "W", &["watt", "watts"], Decimal(0), SI),
        u(Unit::Kw, "kw", "kW", &[], Decimal(3), SI),
        u(Unit::Hp, "hp", "hp", &[], Factor(HP_W), "mechanical horsepower, 550 ft·lbf/s (NIST SP 811)"),
        flow(u(Unit::NlS, "nl_s", "Nl/s", &[], Factor(1e-3 * RHO_NORMAL_KG_M3),
            "DIN 1343 normal conditions: ρn = 101.325 kPa / (287.05287 J/(kg·K) · 273.15 K)"), NORMAL),
        u(Unit::NCm, "n_cm", "N·cm", &["ncm"], Decimal(-2), SI),
        // "kgf·m", "kgf m", "kgfm"; the kilopond-metre "kp·m" of older German pages.
        u(Unit::KgfM, "kgf_m", "kgf·m", &["kgfm", "kp_m", "kpm"], Factor(G_N),
            "kgf = 9.80665 N (3rd CGPM 1901; NIST SP 811)"),
        u(Unit::KgfCm, "kgf_cm", "kgf·cm", &["kgfcm", "kp_cm", "kpcm"], Factor(G_N * 1e-2),
            "kgf = 9.80665 N (3rd CGPM 1901; NIST SP 811)"),
    ]
};

/// 10^k, exact where 10^|k| is (|k| ≤ 22) and correctly rounded otherwise: the factor of a
/// [`Scale::Decimal`] unit, equal to the literal (`pow10(-3) == 1e-3`).
fn pow10(k: i32) -> f64 {
    if k >= 0 {
        10f64.powi(k)
    } else {
        1.0 / 10f64.powi(-k)
    }
}

impl Unit {
    /// Everything known of the unit (its row of [`UNITS`]).
    pub fn facts(self) -> &'static UnitFacts {
        &UNITS[self as usize]
    }

    /// The column-name suffix of the unit, e.g. `rpm`.
    pub fn suffix(self) -> &'static str {
        self.facts().suffix
    }

    /// The unit as people write it, for axis titles and messages (`N·m`, `bar(g)`,
    /// `l/min ANR`); a pressure unit says whether it is absolute or gauge (`MPa abs`,
    /// `bar(g)`).
    pub fn symbol(self) -> &'static str {
        self.facts().symbol
    }

    /// Other suffixes that name the same unit (`bar_a` for `bar_abs`, `psig`, `u_min`…).
    pub fn aliases(self) -> &'static [&'static str] {
        self.facts().spellings
    }

    /// The reference conditions a volume-flow unit is counted at, for people (`None` for
    /// other units).
    pub fn reference_conditions(self) -> Option<&'static str> {
        self.facts().reference
    }

    /// The factor k with SI = k·v for units without an offset (`None` for gauge units).
    pub fn si_factor(self) -> Option<f64> {
        match self.facts().scale {
            Scale::Decimal(k) => Some(pow10(k)),
            Scale::Factor(k) => Some(k),
            Scale::Gauge(_) => None,
        }
    }

    /// Converts a value in this unit to SI. `p_atm_pa` is needed for gauge pressure.
    pub fn to_si(self, v: f64, p_atm_pa: f64) -> f64 {
        match (self, self.facts().scale) {
            // One rounding (fused multiply-add), so that every absolute pressure has a
            // gauge value that converts back to it exactly.
            (_, Scale::Gauge(k)) => v.mul_add(k, p_atm_pa),
            (_, Scale::Decimal(0)) => v,
            (_, Scale::Decimal(k)) => v * pow10(k),
            // These three keep the arithmetic they had before the table (bit-identical
            // imports); a test checks each against its factor.
            (Unit::Rpm, _) => v * PI / 30.0,
            (Unit::LMinAnr, _) => v * 1e-3 * RHO0_KG_M3 / 60.0,
            (Unit::LSAnr, _) => v * 1e-3 * RHO0_KG_M3,
            (_, Scale::Factor(k)) => v * k,
        }
    }

    /// The power of ten k when the unit is exactly 10^k SI units (g/s: −3, MPa: 6,
    /// dm³/(s·bar): −8, SI units: 0), else `None`.
    pub fn decimal_exponent(self) -> Option<i32> {
        match self.facts().scale {
            Scale::Decimal(k) => Some(k),
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
        match (self, self.facts().scale) {
            (Unit::BarG, _) => (v - p_atm_pa) * 1e-5,
            (_, Scale::Gauge(k)) => (v - p_atm_pa) / k,
            // Exact where SI is the unit (no division by one).
            (_, Scale::Decimal(0)) => v,
            (_, Scale::Decimal(k)) => v * pow10(-k),
            // The arithmetic these had before the table (bit-identical exports).
            (Unit::Rpm, _) => v * 30.0 / PI,
            (Unit::LMinAnr, _) => v * 60.0 / (1e-3 * RHO0_KG_M3),
            (_, Scale::Factor(k)) => v / k,
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

    /// The table lists every unit once, in the order of the variants, with a factor, a
    /// source, and spellings that name no other unit of its quantities.
    #[test]
    fn the_unit_table_is_in_variant_order_and_complete() {
        for (i, f) in UNITS.iter().enumerate() {
            assert_eq!(f.unit as usize, i, "{}", f.suffix);
            assert!(!f.source.is_empty(), "{}", f.suffix);
            assert!(!f.spellings.contains(&f.suffix), "{}", f.suffix);
        }
        for q in Quantity::ALL {
            let mut names: Vec<&str> = q
                .units()
                .iter()
                .flat_map(|u| std::iter::once(u.suffix()).chain(u.aliases().iter().copied()))
                .collect();
            let n = names.len();
            names.sort_unstable();
            names.dedup();
            assert_eq!(names.len(), n, "{q:?}: a spelling names two units");
        }
        // Every unit is a unit of some quantity.
        for f in &UNITS {
            assert!(
                Quantity::ALL.iter().any(|q| q.units().contains(&f.unit)),
                "{}",
                f.suffix
            );
        }
    }

    /// docs/formats.md lists every unit of the table and every spelling of it.
    #[test]
    fn the_docs_list_every_unit_and_spelling() {
        let docs = include_str!("../../docs/formats.md");
        let at = docs.find("### Units and their spellings").unwrap();
        let section = &docs[at..];
        for f in &UNITS {
            for name in std::iter::once(&f.suffix).chain(f.spellings) {
                assert!(section.contains(&format!("`{name}`")), "{name}");
            }
        }
    }

    /// The units that keep their former arithmetic agree with their factor in the table,
    /// and a decimal factor is its literal.
    #[test]
    fn kept_arithmetic_agrees_with_the_table() {
        for u in [Unit::Rpm, Unit::LMinAnr, Unit::LSAnr] {
            let k = u.si_factor().unwrap();
            for v in [1.0, 3.7, 12_200.0] {
                let si = u.to_si(v, 0.0);
                assert!((si - v * k).abs() <= 4.0 * f64::EPSILON * si, "{u:?}");
                assert!(
                    (u.from_si(si, 0.0) - v).abs() <= 4.0 * f64::EPSILON * v,
                    "{u:?}"
                );
            }
        }
        assert_eq!(pow10(-3), 1e-3);
        assert_eq!(pow10(-6), 1e-6);
        assert_eq!(pow10(-8), 1e-8);
        assert_eq!(pow10(-2), 1e-2);
        assert_eq!(pow10(6), 1e6);
    }

    /// Makers' spellings of issue 44, each to its SI value by a closed form written out
    /// here (not read from the table).
    #[test]
    fn makers_spellings_convert_by_closed_forms() {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        let lbf_ft = 0.453_592_37 * 9.806_65 * 0.3048;
        let rho_n = 101_325.0 / (287.052_87 * 273.15);
        for (q, text, v, want) in [
            (
                Quantity::Speed,
                "u_min",
                12_200.0,
                12_200.0 * 2.0 * PI / 60.0,
            ),
            (Quantity::Speed, "upm", 60.0, 2.0 * PI),
            (Quantity::Speed, "min_1", 60.0, 2.0 * PI),
            (Quantity::Speed, "1_min", 60.0, 2.0 * PI),
            (Quantity::Flow1, "nl_s", 1.0, 1e-3 * rho_n),
            (Quantity::Flow1, "nl_min", 60.0, 1e-3 * rho_n),
            (Quantity::Torque, "ft_lb", 1.0, lbf_ft),
            (Quantity::Torque, "lb_ft", 2.0, 2.0 * lbf_ft),
            (Quantity::Torque, "ft_lbf", 1.0, lbf_ft),
            (Quantity::Torque, "kgf_m", 1.0, 9.806_65),
            (Quantity::Torque, "kgfm", 1.0, 9.806_65),
            (Quantity::Torque, "kgf_cm", 100.0, 9.806_65),
            (Quantity::Torque, "n_cm", 29.4, 0.294),
            (Quantity::PPort1, "barg", 6.3, 731_325.0),
            (Quantity::PPort1, "bar_ü", 6.3, 731_325.0),
            (
                Quantity::PPort1,
                "psig",
                90.0,
                90.0 * 6_894.757_293_168_361 + 101_325.0,
            ),
        ] {
            let u = unit_of(q, text).unwrap_or_else(|e| panic!("{text}: {e}"));
            let si = u.to_si(v, 101_325.0);
            assert!(close(si, want), "{text}: {si} vs {want}");
            assert!((u.from_si(si, 101_325.0) - v).abs() <= 1e-12 * v, "{text}");
        }
        // Normal litres and ANR litres are different air: 1 Nl is 1.2923/1.185 ANR litres.
        let ratio = Unit::NlS.to_si(1.0, 0.0) / Unit::LSAnr.to_si(1.0, 0.0);
        assert!((ratio - rho_n / 1.185).abs() < 1e-12, "{ratio}");
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
