//! What `vanefit check` prints for a catalogue experiment: the supply pressure, the key
//! figures and every point, as printed and in SI, with the reference conditions of the
//! air-consumption unit (free air, ANR, normal or standard air).

use vanefit::data::FIGURES;
use vanefit::data::{ExperimentData, Kind};
use vanefit::units::trim_zeros;
use vanefit::units::{Quantity, Unit};

/// A number for people: 5 significant digits.
fn num(v: f64) -> String {
    if v == 0.0 || (1e-3..1e6).contains(&v.abs()) {
        trim_zeros(&format!("{v:.5}"))
    } else {
        format!("{v:.4e}")
    }
}

/// The catalogue part of `check` (nothing for other kinds).
pub(crate) fn print(ex: &ExperimentData, p_atm_pa: f64) {
    if ex.kind != Kind::Catalogue {
        return;
    }
    if let Some(p) = ex.p_supply_pa {
        let gauge = format!("{} bar(g)", num(Unit::BarG.from_si(p, p_atm_pa)));
        say!(
            "    supply pressure {} = {} Pa absolute; reading tolerance {} % of each curve's full scale",
            match ex.p_supply_written.as_deref() {
                Some(w) if w.trim() != gauge => format!("{w} = {gauge}"),
                _ => gauge,
            },
            num(p),
            num(100.0 * ex.tolerance.unwrap_or(0.0))
        );
    }
    for f in &ex.figures {
        let what = FIGURES.iter().find(|x| x.0 == f.key).map_or("", |x| x.2);
        let si = f.quantity.si_unit();
        let note = if f.key == "min_start_torque" {
            "  (shown, not compared: the model averages torque over the rotor angle)"
        } else {
            ""
        };
        say!(
            "    {:<28} {:>10} {:<10} = {:>12} {}{note}",
            what,
            num(f.written),
            f.unit.symbol(),
            num(f.si),
            si.symbol()
        );
    }
    let rec = &ex.recording;
    let cols: Vec<_> = [
        Quantity::Speed,
        Quantity::Torque,
        Quantity::Power,
        Quantity::Flow1,
    ]
    .iter()
    .filter_map(|q| rec.column(*q))
    .collect();
    let header: Vec<String> = cols
        .iter()
        .map(|c| format!("{} = {}", c.name, c.quantity.si_unit().symbol()))
        .collect();
    say!("    points (as written → SI): {}", header.join(" | "));
    for r in 0..rec.rows() {
        let cells: Vec<String> = cols
            .iter()
            .map(|c| match c.si[r].is_finite() {
                true => format!("{:>9} → {:<11}", &c.raw[r], num(c.si[r])),
                false => format!("{:>9}   {:<11}", "-", ""),
            })
            .collect();
        say!("      line {:>3}: {}", rec.lines[r], cells.join(" "));
    }
    let mut units: Vec<Unit> = cols.iter().map(|c| c.unit).collect();
    units.extend(ex.figures.iter().map(|f| f.unit));
    units.dedup();
    let mut shown = Vec::new();
    for u in units {
        if let Some(conditions) = u.reference_conditions() {
            if !shown.contains(&conditions) {
                say!(
                    "    air consumption in {} counts air at {conditions}",
                    u.symbol()
                );
                shown.push(conditions);
            }
        }
    }
}
