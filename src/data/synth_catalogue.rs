//! Synthetic catalogue pages: what a manufacturer would print for a motor, made by the
//! simulator — at each supply pressure the curves of torque, power and air consumption
//! against speed as sparse points read off a printed curve (three significant digits, not
//! every quantity at every speed) and the key figures, in the units catalogues use (rpm,
//! N·m, kW, l/s of free air, bar(g)). Written as a dataset folder marked synthetic.

use crate::data::dataset::DataError;
use crate::model::motor::Motor;
use crate::sim::operating_point::{
    at_speeds, catalogue_row, CatalogueRow, Conditions, OperatingPointError,
};
use crate::units::Unit;
use std::fmt::Write as _;
use std::path::Path;

/// What the synthetic catalogue prints.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CataloguePlan {
    /// Supply pressures, bar(g) (one page each).
    pub pressures_bar_g: Vec<f64>,
    /// Atmosphere, Pa.
    pub p_atm_pa: f64,
    /// Significant digits of every printed number.
    pub digits: usize,
}

impl Default for CataloguePlan {
    /// One page at 6.3 bar(g), the pressure catalogues quote, three digits.
    fn default() -> Self {
        Self {
            pressures_bar_g: vec![6.3],
            p_atm_pa: crate::units::constants::P_ATM_PA,
            digits: 3,
        }
    }
}

/// `v` printed with `digits` significant digits, as a catalogue would.
pub fn printed(v: f64, digits: usize) -> String {
    let rounded: f64 = format!("{:.*e}", digits.max(1) - 1, v).parse().unwrap_or(v);
    format!("{rounded}")
}

/// Speed grid of the max-power figure: 1 rpm.
const GRID_RAD_S: f64 = std::f64::consts::PI / 30.0;

/// Fractions of the free speed where the curves have points, and which of torque, power and
/// air a reader took at each (a printed page rarely lines them up).
const POINTS: [(f64, [bool; 3]); 9] = [
    (0.1, [true, false, true]),
    (0.2, [true, true, false]),
    (0.3, [true, false, true]),
    (0.4, [false, true, false]),
    (0.5, [true, true, true]),
    (0.6, [false, true, false]),
    (0.7, [true, false, true]),
    (0.8, [false, true, false]),
    (0.9, [true, true, true]),
];

/// One page: the curve file's text and the figures table of rig.toml, with the row.
fn page(
    motor: &Motor,
    p_supply_pa: f64,
    plan: &CataloguePlan,
) -> Result<(String, String, CatalogueRow), OperatingPointError> {
    let conditions = Conditions::supplied(p_supply_pa, plan.p_atm_pa);
    let row = catalogue_row(motor, &conditions, GRID_RAD_S)?;
    // Speeds as read off the axis: multiples of 100 rpm.
    let speeds: Vec<f64> = POINTS
        .iter()
        .map(|(f, _)| (f * Unit::Rpm.from_si(row.free_speed_rad_s, 0.0) / 100.0).round() * 100.0)
        .collect();
    let si: Vec<f64> = speeds.iter().map(|v| Unit::Rpm.to_si(*v, 0.0)).collect();
    let points = at_speeds(motor, &conditions, &si)?;
    let p = |v: f64| printed(v, plan.digits);
    let mut csv = String::from("speed_rpm,torque_nm,power_kw,air_l_s\n");
    for ((rpm, (_, taken)), pt) in speeds.iter().zip(&POINTS).zip(&points) {
        let cell = |take: bool, v: f64| if take { p(v) } else { String::new() };
        let _ = writeln!(
            csv,
            "{rpm},{},{},{}",
            cell(taken[0], pt.torque_nm),
            cell(taken[1], Unit::Kw.from_si(pt.power_w, 0.0)),
            cell(taken[2], Unit::LS.from_si(pt.flow1_kg_s, 0.0)),
        );
    }
    let rpm = |w: f64| format!("{} rpm", p(Unit::Rpm.from_si(w, 0.0)));
    let l_s = |m: f64| format!("{} l/s", p(Unit::LS.from_si(m, 0.0)));
    let figures = [
        ("free_speed", rpm(row.free_speed_rad_s)),
        ("max_power", format!("{} kW", p(row.max_power_w / 1e3))),
        ("speed_at_max_power", rpm(row.speed_at_max_power_rad_s)),
        (
            "torque_at_max_power",
            format!("{} N·m", p(row.torque_at_max_power_nm)),
        ),
        ("stall_torque", format!("{} N·m", p(row.stall_torque_nm))),
        ("air_at_max_power", l_s(row.air_at_max_power_kg_s)),
        ("air_at_free_speed", l_s(row.air_at_free_speed_kg_s)),
    ];
    let mut table = String::new();
    for (k, v) in figures {
        let _ = writeln!(table, "{k} = \"{v}\"");
    }
    Ok((csv, table, row))
}

/// Writes the catalogue dataset to `dir` (rig.toml marked synthetic and one curve file per
/// pressure) and returns the generator's catalogue rows.
pub(crate) fn write_catalogue(
    dir: &Path,
    motor: &Motor,
    plan: &CataloguePlan,
    description: &str,
) -> Result<Vec<CatalogueRow>, DataError> {
    let fail = |m: String| DataError::new(dir, m);
    std::fs::create_dir_all(dir).map_err(|e| fail(format!("cannot create: {e}")))?;
    let p = motor.params();
    let mut rig = format!(
        "synthetic = true\ndescription = \"Catalogue pages made by vanefit synth --catalogue from the simulator ({description}); numbers printed to {} digits.\"\n\n[motor]\nname = \"AR034-11 (synthetic catalogue)\"\nvanes = {}\ndisplacement_m3 = {:e}\nexpansion_ratio = {}\n\n[conditions]\np_atm_pa = {}\n",
        plan.digits,
        p.vanes(),
        p.v_disp(),
        p.eps(),
        plan.p_atm_pa
    );
    let mut rows = Vec::new();
    for &bar_g in &plan.pressures_bar_g {
        let p_supply_pa = Unit::BarG.to_si(bar_g, plan.p_atm_pa);
        let (csv, figures, row) =
            page(motor, p_supply_pa, plan).map_err(|e| fail(format!("at {bar_g} bar(g): {e}")))?;
        let file = format!("curves-{bar_g}bar.csv");
        crate::io::write_atomic(&dir.join(&file), csv.as_bytes())
            .map_err(|e| fail(format!("{file}: {e}")))?;
        let _ = write!(
            rig,
            "\n[[experiment]]\nkind = \"catalogue\"\nfile = \"{file}\"\np_supply = \"{bar_g} bar(g)\"\n\n[experiment.figures]\n{figures}"
        );
        rows.push(row);
    }
    crate::io::write_atomic(&dir.join("rig.toml"), rig.as_bytes())
        .map_err(|e| fail(format!("rig.toml: {e}")))?;
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_printed_to_their_digits() {
        assert_eq!(printed(0.293967, 3), "0.294");
        assert_eq!(printed(12345.0, 3), "12300");
        assert_eq!(printed(0.0999, 2), "0.1");
    }
}
