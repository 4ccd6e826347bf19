//! Column names and units at the file edge (SPEC §3). Every CSV column name is a quantity
//! followed by its unit (`flow1_g_s`, `p_port1_bar_g`); values convert to SI on import and
//! back on export. Nothing inside the crate sees any unit but SI.

pub mod constants;

use crate::units::constants::RHO0_KG_M3;
use std::f64::consts::PI;

/// A measured or imposed quantity in a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
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
}

impl Quantity {
    /// Every quantity.
    pub const ALL: [Quantity; 8] = [
        Quantity::Time,
        Quantity::Speed,
        Quantity::Torque,
        Quantity::Flow1,
        Quantity::Flow2,
        Quantity::PPort1,
        Quantity::PPort2,
        Quantity::CPort2,
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
        }
    }

    /// Units accepted for this quantity.
    pub fn units(self) -> &'static [Unit] {
        use Unit::*;
        match self {
            Quantity::Time => &[S],
            Quantity::Speed => &[Rpm, RadS],
            Quantity::Torque => &[Nm],
            Quantity::Flow1 | Quantity::Flow2 => &[GS, KgS, LMinAnr, LSAnr],
            Quantity::PPort1 | Quantity::PPort2 => &[Mpa, BarAbs, BarG, Pa, Kpa],
            Quantity::CPort2 => &[M3SPa, Dm3SBar],
        }
    }

    /// SI unit, for messages.
    pub fn si_unit(self) -> Unit {
        self.units()[match self {
            Quantity::Flow1 | Quantity::Flow2 => 1,
            Quantity::PPort1 | Quantity::PPort2 => 3,
            Quantity::Speed => 1,
            _ => 0,
        }]
    }
}

/// A unit that a column may carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
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
        }
    }

    /// Converts a value in this unit to SI. `p_atm_pa` is needed for gauge pressure.
    pub fn to_si(self, v: f64, p_atm_pa: f64) -> f64 {
        match self {
            Unit::S | Unit::RadS | Unit::Nm | Unit::KgS | Unit::Pa | Unit::M3SPa => v,
            Unit::Rpm => v * PI / 30.0,
            Unit::GS => v * 1e-3,
            Unit::LMinAnr => v * 1e-3 * RHO0_KG_M3 / 60.0,
            Unit::LSAnr => v * 1e-3 * RHO0_KG_M3,
            Unit::Mpa => v * 1e6,
            Unit::BarAbs => v * 1e5,
            // One rounding (fused multiply-add), so that every absolute pressure has a
            // gauge value that converts back to it exactly.
            Unit::BarG => v.mul_add(1e5, p_atm_pa),
            Unit::Kpa => v * 1e3,
            // 1 dm³/(s·bar) = 1e-3 m³/s per 1e5 Pa.
            Unit::Dm3SBar => v * 1e-8,
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
            Unit::Rpm | Unit::LMinAnr | Unit::LSAnr | Unit::BarG => None,
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
            .and_then(|e| format!("{mantissa}e{e}").parse().ok())
            .or_else(|| Some(self.to_si(v, p_atm_pa)))
    }

    /// Converts an SI value back to this unit (inverse of [`Unit::to_si`]).
    pub fn from_si(self, v: f64, p_atm_pa: f64) -> f64 {
        match self {
            Unit::S | Unit::RadS | Unit::Nm | Unit::KgS | Unit::Pa | Unit::M3SPa => v,
            Unit::Rpm => v * 30.0 / PI,
            Unit::GS => v * 1e3,
            Unit::LMinAnr => v * 60.0 / (1e-3 * RHO0_KG_M3),
            Unit::LSAnr => v / (1e-3 * RHO0_KG_M3),
            Unit::Mpa => v * 1e-6,
            Unit::BarAbs => v * 1e-5,
            Unit::BarG => (v - p_atm_pa) * 1e-5,
            Unit::Kpa => v * 1e-3,
            Unit::Dm3SBar => v * 1e8,
        }
    }
}

/// Why a column name was not understood (the units layer's error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ColumnNameError {
    /// The quantity is known but the unit is not.
    #[error("unknown unit '{unit}' for {}", quantity.prefix())]
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

/// Splits a column name into quantity and unit, e.g. `flow1_l_min_anr` → (Flow1, LMinAnr).
pub fn parse_column(name: &str) -> Result<(Quantity, Unit), ColumnNameError> {
    let name = name.trim().to_ascii_lowercase();
    // Longest prefix first, so that "p_port1" wins over a shorter one.
    let mut quantities = Quantity::ALL;
    quantities.sort_by_key(|q| std::cmp::Reverse(q.prefix().len()));
    for q in quantities {
        if let Some(rest) = name
            .strip_prefix(q.prefix())
            .and_then(|r| r.strip_prefix('_'))
        {
            return q
                .units()
                .iter()
                .find(|u| u.suffix() == rest)
                .map(|u| (q, *u))
                .ok_or(ColumnNameError::UnknownUnit {
                    quantity: q,
                    unit: rest.to_string(),
                });
        }
    }
    Err(ColumnNameError::UnknownColumn)
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
    fn conversions_agree_with_hand_calculation() {
        assert!((Unit::Rpm.to_si(60.0, 0.0) - 2.0 * PI).abs() < 1e-12);
        assert!((Unit::BarG.to_si(6.0, 101_325.0) - 701_325.0).abs() < 1e-9);
        assert!((Unit::LMinAnr.to_si(60.0, 0.0) - 1.185e-3).abs() < 1e-15);
        assert!((Unit::Dm3SBar.to_si(0.68, 0.0) - 6.8e-9).abs() < 1e-20);
        assert!(matches!(
            parse_column("flow1_cfm"),
            Err(ColumnNameError::UnknownUnit { .. })
        ));
        assert_eq!(
            parse_column("temperature_k"),
            Err(ColumnNameError::UnknownColumn)
        );
    }
}
