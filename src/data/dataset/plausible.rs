//! The range a recorded value can physically have on a pneumatic vane-motor rig.
//!
//! A recording is validated once, here, for every command: `check`, `fit`, `simulate`,
//! `diagnose` and `predict` all load a dataset through [`super::Dataset::load`], so a value
//! one of them refuses is refused by all of them with the same located message ("one
//! gate for values"). Without this gate a speed of 1e30 rpm or a port pressure of
//! 1e30 MPa in one row was simulated into flows of 1e29 g/s by `simulate`, passed `check`
//! when the reference polynomial happened to absorb it, and was refused by `fit` only with
//! an unlocated "no degree can be cross-validated".
//!
//! The limits are deliberately generous, orders of magnitude beyond any catalogue motor, so
//! that they only catch values that cannot be measurements (a unit slip, a sentinel such as
//! 9.9e37 from a data logger, a pasted cell): they are not a model-validity range.

use super::DataError;
use crate::sim::recording::Recording;
use crate::units::format::short;
use crate::units::Quantity;

/// Absolute port pressure, Pa: the same ceiling as a rig's supply pressure (5 MPa, the
/// `p_supply` check of `rig.toml`); a pneumatic motor runs at 0.4–1 MPa.
const P_MAX_PA: f64 = 5e6;
/// Shaft speed, rad/s (1e6 rpm; the fastest air turbines run near 4e5 rpm).
const SPEED_MAX_RAD_S: f64 = 1e6 * std::f64::consts::PI / 30.0;
/// Shaft torque, N·m (a geared vane motor's output stays below a few kN·m).
const TORQUE_MAX_NM: f64 = 1e5;
/// Mass flow, kg/s (the largest vane motors use about 0.2 kg/s of air).
const FLOW_MAX_KG_S: f64 = 10.0;
/// Shaft power, W (the largest vane motors give about 20 kW).
const POWER_MAX_W: f64 = 1e7;
/// Sonic conductance of the outlet nozzle, m³/(s·Pa) (a DN50 valve is about 1e-6).
const C_MAX_M3_S_PA: f64 = 1e-4;
/// Time since the recording's start, s (one year: a rig log, not a sentinel).
const T_MAX_S: f64 = 3.2e7;

/// The closed range `[lo, hi]` in SI a quantity's values must lie in, and what it is.
fn range(q: Quantity) -> (f64, f64, &'static str) {
    match q {
        Quantity::Time => (-T_MAX_S, T_MAX_S, "a time"),
        Quantity::Speed => (-SPEED_MAX_RAD_S, SPEED_MAX_RAD_S, "a shaft speed"),
        Quantity::Torque => (-TORQUE_MAX_NM, TORQUE_MAX_NM, "a shaft torque"),
        Quantity::Flow1 | Quantity::Flow2 => (-FLOW_MAX_KG_S, FLOW_MAX_KG_S, "a mass flow"),
        // An absolute pressure of zero or below is no pressure at all.
        Quantity::PPort1 | Quantity::PPort2 => (f64::MIN_POSITIVE, P_MAX_PA, "a pressure"),
        Quantity::CPort2 => (0.0, C_MAX_M3_S_PA, "a nozzle conductance"),
        Quantity::Power => (-POWER_MAX_W, POWER_MAX_W, "a motor's shaft power"),
    }
}

/// Refuses the first value of any column outside its quantity's range, naming its line,
/// column, the value in the column's own unit and the range in that unit.
pub(super) fn check_recording(rec: &Recording, p_atm_pa: f64) -> Result<(), DataError> {
    // No pressure at all is said in the user's own text before any range is.
    for q in [Quantity::PPort1, Quantity::PPort2] {
        if let Some(i) = rec.columns.iter().position(|c| c.quantity == q) {
            let col = &rec.columns[i];
            if let Some(k) = col.si.iter().position(|v| *v <= 0.0) {
                return Err(DataError::new(
                    &rec.file,
                    format!(
                        "'{}' is not a possible pressure (absolute pressure must be > 0)",
                        &col.raw[k]
                    ),
                )
                .at(rec.lines[k])
                .col(i, &col.name));
            }
        }
    }
    for (i, col) in rec.columns.iter().enumerate() {
        let (lo, hi, what) = range(col.quantity);
        // NaN is an empty cell of a catalogue page (dense recordings refuse it earlier).
        let outside = |v: &f64| !v.is_nan() && !(lo..=hi).contains(v);
        let Some(k) = col.si.iter().position(outside) else {
            continue;
        };
        let shown = |v: f64| short(col.unit.from_si(v, p_atm_pa));
        let (a, b) = (shown(lo), shown(hi));
        // Gauge units turn the absolute floor into "above -p_atm": say it in words.
        let range = if matches!(col.quantity, Quantity::PPort1 | Quantity::PPort2) {
            format!("above 0 absolute and at most {b}")
        } else {
            format!("from {a} to {b}")
        };
        return Err(DataError::new(
            &rec.file,
            format!(
                "{} {} is not possible as {what} (the range is {range} {})",
                shown(col.si[k]),
                col.unit.symbol(),
                col.unit.symbol()
            ),
        )
        .at(rec.lines[k])
        .col(i, &col.name));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_quantity_has_a_range_that_holds_its_everyday_values() {
        // The shipped motor's operating point must pass with room to spare (a supply of
        // 7.3 bar abs., within a factor of 6 of the ceiling; the rest by 100).
        for (q, v) in [
            (Quantity::Time, 65.0),
            (Quantity::Speed, 1000.0),
            (Quantity::Torque, 0.3),
            (Quantity::Flow1, 5e-3),
            (Quantity::PPort1, 7.3e5),
            (Quantity::CPort2, 3e-8),
            (Quantity::Power, 300.0),
        ] {
            let (lo, hi, _) = range(q);
            let margin = if q == Quantity::PPort1 { 6.0 } else { 100.0 };
            assert!(lo < v && margin * v < hi, "{q:?}");
        }
    }
}
