//! A catalogue page against what makers state as rules and against itself: warnings, not
//! refusals (a real motor may break a rule of thumb), each at the figure's rig.toml line.
//!
//! Rules of thumb of vane-motor makers (Atlas Copco's and Chicago Pneumatic's technical
//! guides to air motors): the stall torque is about twice the torque at max power, and
//! max power lies near half the free speed (both follow from a torque that falls about
//! linearly with speed). A page far from them more likely holds a reading error (a unit
//! slip, a digit, a figure of another pressure) than an unusual motor. And a key figure
//! that disagrees with the page's own curve at the same speed is a reading error of one of
//! the two; where the ratio is close to a unit conversion, the warning names it.

use super::catalogue::{figure_rows, interpolate};
use crate::sim::recording::{ExperimentData, Figure};
use crate::units::{Quantity, Unit};

/// Stall torque over torque at max power outside this range breaks the makers' "about 2".
pub const STALL_OVER_MAX_POWER_TORQUE: (f64, f64) = (1.4, 3.0);
/// Speed at max power over free speed outside this range breaks the makers' "about ½".
pub const MAX_POWER_SPEED_OVER_FREE: (f64, f64) = (0.35, 0.65);
/// A figure and the page's curve at its speed disagree when they differ by more than this
/// fraction (or five reading tolerances, whichever is larger).
pub const FIGURE_VS_CURVE: f64 = 0.25;

/// One warning about a page: the figure's key and rig.toml line, and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct PageWarning {
    /// The figure's key (`stall_torque`, …).
    pub key: String,
    /// Its line in rig.toml, where known.
    pub line: Option<u64>,
    /// What is wrong, in words.
    pub message: String,
}

/// Pairs of units a page confuses: (smaller unit, larger unit) of one quantity. A value
/// in the smaller unit printed as the larger one reads `factor` times too large, where the
/// factor is their ratio in the unit table ([`crate::units::UNITS`]).
const SLIPS: [(Unit, Unit); 10] = [
    (Unit::LbfIn, Unit::Nm),
    (Unit::Nm, Unit::LbfFt),
    (Unit::LbfIn, Unit::LbfFt),
    (Unit::NCm, Unit::Nm),
    (Unit::Nm, Unit::KgfM),
    (Unit::W, Unit::Kw),
    (Unit::Hp, Unit::Kw),
    (Unit::LMin, Unit::LS),
    (Unit::Cfm, Unit::LS),
    (Unit::NlMin, Unit::NlS),
];

/// How many of `small` make one `large` (both without an offset).
fn slip_factor(small: Unit, large: Unit) -> f64 {
    large.si_factor().unwrap_or(1.0) / small.si_factor().unwrap_or(1.0)
}

/// The slip a value that reads `ratio` times what it should names: "N·cm printed as N·m"
/// where it reads about 100 times too large, "N·m printed as N·cm" where 100 times too
/// small (within 5 %).
fn slip(ratio: f64) -> Option<String> {
    SLIPS.iter().find_map(|&(small, large)| {
        let f = slip_factor(small, large);
        if (ratio / f - 1.0).abs() < 0.05 {
            Some(format!("{} printed as {}", small.symbol(), large.symbol()))
        } else if (ratio * f - 1.0).abs() < 0.05 {
            Some(format!("{} printed as {}", large.symbol(), small.symbol()))
        } else {
            None
        }
    })
}

/// The slip of quantity `q` that would bring `ratio`, a ratio makers state as about
/// `typical` (expected within `range`), back inside its range, the one that brings it
/// nearest `typical`: a stall torque 210 times the torque at max power is a stall torque
/// in N·cm printed as N·m (210/100 = 2.1).
fn rule_slip(ratio: f64, typical: f64, range: (f64, f64), q: Quantity) -> Option<String> {
    let mut best: Option<(f64, String)> = None;
    for &(small, large) in SLIPS.iter() {
        if !q.units().contains(&small) {
            continue;
        }
        let f = slip_factor(small, large);
        // A factor within the rule's own width cannot be told from an unusual motor.
        if f < range.1 / range.0 {
            continue;
        }
        for (corrected, what) in [
            (
                ratio / f,
                format!("{} printed as {}", small.symbol(), large.symbol()),
            ),
            (
                ratio * f,
                format!("{} printed as {}", large.symbol(), small.symbol()),
            ),
        ] {
            let off = (corrected / typical).ln().abs();
            let inside = (range.0..=range.1).contains(&corrected);
            if inside && best.as_ref().is_none_or(|b| off < b.0) {
                best = Some((off, what));
            }
        }
    }
    best.map(|b| b.1)
}

/// The warnings of one catalogue experiment (none for other kinds).
pub fn page_warnings(ex: &ExperimentData) -> Vec<PageWarning> {
    let mut out = Vec::new();
    // How the supply pressure was read where its unit leaves gauge or absolute open. The
    // gauge's zero is the standard atmosphere here (the rig's is not at hand; the wording
    // only rounds the other reading).
    let p_atm = crate::units::constants::P_ATM_PA;
    if let Some(note) = ex
        .p_supply_written
        .as_deref()
        .and_then(|t| super::catalogue::supply_notation(t, p_atm))
    {
        out.push(PageWarning {
            key: "p_supply".into(),
            line: ex.p_supply_line,
            message: note,
        });
    }
    let fig = |k: &str| ex.figures.iter().find(|f| f.key == k);
    let warn = |f: &Figure, message: String| PageWarning {
        key: f.key.clone(),
        line: f.line,
        message,
    };
    if let (Some(stall), Some(t)) = (fig("stall_torque"), fig("torque_at_max_power")) {
        let r = stall.si / t.si;
        let (lo, hi) = STALL_OVER_MAX_POWER_TORQUE;
        if !(lo..=hi).contains(&r) {
            out.push(warn(
                stall,
                format!(
                    "stall torque is {r:.2} × the torque at max power; makers state about 2 (expected {lo}–{hi}){}",
                    rule_slip(r, 2.0, (lo, hi), Quantity::Torque)
                        .map_or(String::new(), |s| format!(": likely a unit slip ({s}?)"))
                ),
            ));
        }
    }
    if let (Some(w), Some(free)) = (fig("speed_at_max_power"), fig("free_speed")) {
        let r = w.si / free.si;
        let (lo, hi) = MAX_POWER_SPEED_OVER_FREE;
        if !(lo..=hi).contains(&r) {
            out.push(warn(
                w,
                format!(
                    "max power at {:.0} % of the free speed; makers state about half (expected {:.0}–{:.0} %)",
                    100.0 * r,
                    100.0 * lo,
                    100.0 * hi
                ),
            ));
        }
    }
    out.extend(figures_against_curves(ex));
    out
}

/// Each figure against the page's own curve at its speed (the curve rows are the
/// recording's rows before the figures' rows).
fn figures_against_curves(ex: &ExperimentData) -> Vec<PageWarning> {
    let rec = &ex.recording;
    let n_curve = rec.rows().saturating_sub(figure_rows(&ex.figures).len());
    let Some(speed) = rec.column(Quantity::Speed) else {
        return Vec::new();
    };
    let curve = |q: Quantity| -> Vec<(f64, f64)> {
        let Some(col) = rec.column(q) else {
            return Vec::new();
        };
        let mut pts: Vec<(f64, f64)> = (0..n_curve)
            .map(|i| (speed.si[i], col.si[i]))
            .filter(|(w, y)| w.is_finite() && y.is_finite())
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        pts
    };
    let tolerance = ex.tolerance.unwrap_or(0.02);
    let limit = FIGURE_VS_CURVE.max(5.0 * tolerance);
    let fig = |k: &str| ex.figures.iter().find(|f| f.key == k);
    let w_max = fig("speed_at_max_power").map(|f| f.si);
    let checks: [(&str, Quantity, Option<f64>); 4] = [
        ("stall_torque", Quantity::Torque, Some(0.0)),
        ("torque_at_max_power", Quantity::Torque, w_max),
        ("max_power", Quantity::Power, w_max),
        ("air_at_max_power", Quantity::Flow1, w_max),
    ];
    let mut out = Vec::new();
    for (key, q, at) in checks {
        let (Some(f), Some(w)) = (fig(key), at) else {
            continue;
        };
        let Some(on_curve) = interpolate(&curve(q), w) else {
            continue;
        };
        if on_curve.is_nan() || on_curve <= 0.0 {
            continue;
        }
        let ratio = f.si / on_curve;
        if (ratio - 1.0).abs() > limit {
            let unit = rec.column(q).map(|c| c.unit).unwrap_or(f.unit);
            out.push(PageWarning {
                key: f.key.clone(),
                line: f.line,
                message: format!(
                    "{key} = {} {} is {ratio:.3} × the page's own curve at {:.0} rpm ({:.4} {}){}",
                    f.written,
                    f.unit.symbol(),
                    w * 30.0 / std::f64::consts::PI,
                    unit.from_si(on_curve, 0.0),
                    unit.symbol(),
                    slip(ratio).map_or(String::new(), |s| format!(": likely a unit slip ({s}?)"))
                ),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use crate::data::dataset::Dataset;

    /// A page as a user typed it: its warnings by key.
    fn warnings(figures: &str, curve: &str) -> Vec<(String, String)> {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("curves.csv"), curve).unwrap();
        let rig = format!(
            "[motor]\ndisplacement_m3 = 3.8e-6\n\n[[experiment]]\nkind = \"catalogue\"\nfile = \"curves.csv\"\np_supply = \"6.3 bar(g)\"\n\n[experiment.figures]\n{figures}"
        );
        std::fs::write(dir.path().join("rig.toml"), rig).unwrap();
        let ds = Dataset::load(dir.path()).unwrap();
        ds.experiments
            .iter()
            .flat_map(super::page_warnings)
            .map(|w| (w.key, w.message))
            .collect()
    }

    /// A supply pressure in bare bar is read as gauge and said at its line; an ambiguous
    /// thousands comma is refused at the figure's line and column.
    #[test]
    fn supply_notation_is_warned_at_its_line_and_ambiguity_refused_at_its_column() {
        let dir = tempfile::tempdir().unwrap();
        let rig = "[motor]\ndisplacement_cm3 = 3.8\n\n[[experiment]]\nkind = \"catalogue\"\np_supply = \"6.3 bar\"\n\n[experiment.figures]\nfree_speed = \"12 200 rpm\"\nstall_torque = \"~0.29 N·m\"\n";
        std::fs::write(dir.path().join("rig.toml"), rig).unwrap();
        let ds = Dataset::load(dir.path()).unwrap();
        assert!((ds.nominal_params().unwrap().v_disp() - 3.8e-6).abs() < 1e-18);
        let ex = &ds.experiments[0];
        assert!((ex.p_supply_pa.unwrap() - 731_325.0).abs() < 1e-6);
        assert_eq!(ex.figures[0].written, 12_200.0);
        let w = super::page_warnings(ex);
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!((w[0].key.as_str(), w[0].line), ("p_supply", Some(6)));
        assert!(w[0].message.contains("GAUGE"), "{}", w[0].message);
        std::fs::write(
            dir.path().join("rig.toml"),
            rig.replace("12 200 rpm", "12,200 rpm"),
        )
        .unwrap();
        let e = Dataset::load(dir.path()).unwrap_err().to_string();
        assert!(e.contains("rig.toml:9:"), "{e}");
        assert!(
            e.contains("'12.200 rpm'") && e.contains("'12200 rpm'"),
            "{e}"
        );
    }

    const CURVE: &str = "speed_rpm,torque_lbf_in\n0,13.1\n3000,9.8\n6000,6.5\n9000,3.3\n";

    #[test]
    fn a_figure_in_the_wrong_unit_is_named_at_its_key() {
        let w = warnings("stall_torque = \"13.1 N·m\"\n", CURVE);
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].0, "stall_torque");
        assert!(w[0].1.contains("lbf·in"), "{}", w[0].1);
        // The same figure in the curve's unit agrees with it.
        assert!(warnings("stall_torque = \"13.1 lbf·in\"\n", CURVE).is_empty());
    }

    /// A stall torque slipped to N·cm but labelled N·m (issue 45: 209.79 × the torque at
    /// max power) is named as the likely slip; a ratio merely off the rule of thumb names
    /// none, and no slip whose factor the rule's own width (1.4–3) cannot tell apart.
    #[test]
    fn a_stall_torque_in_n_cm_printed_as_n_m_is_named_a_unit_slip() {
        let air = "speed_rpm,air_l_s\n0,2\n6000,3\n12000,4\n";
        let figures = |stall: &str| {
            format!("free_speed = \"12000 rpm\"\nspeed_at_max_power = \"6000 rpm\"\ntorque_at_max_power = \"0.14 N·m\"\nstall_torque = \"{stall}\"\n")
        };
        let w = warnings(&figures("29.37 N·m"), air);
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].0, "stall_torque");
        assert!(
            w[0].1.contains("209.79 × the torque at max power")
                && w[0].1.contains("likely a unit slip (N·cm printed as N·m?)"),
            "{}",
            w[0].1
        );
        // 4.5 × is off the rule, but no slip brings it back by a factor the rule can tell.
        let w = warnings(&figures("0.63 N·m"), air);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(!w[0].1.contains("slip"), "{}", w[0].1);
        assert_eq!(
            super::rule_slip(0.02, 2.0, (1.4, 3.0), crate::units::Quantity::Torque).as_deref(),
            Some("N·m printed as N·cm")
        );
    }

    #[test]
    fn the_makers_rules_of_thumb_are_checked() {
        let ok = "free_speed = \"12000 rpm\"\nspeed_at_max_power = \"6000 rpm\"\ntorque_at_max_power = \"6.5 lbf·in\"\nstall_torque = \"13.1 lbf·in\"\n";
        assert!(warnings(ok, CURVE).is_empty(), "{:?}", warnings(ok, CURVE));
        let bad = "free_speed = \"20000 rpm\"\nspeed_at_max_power = \"6000 rpm\"\ntorque_at_max_power = \"6.5 lbf·in\"\nstall_torque = \"13.1 lbf·in\"\n";
        let w = warnings(bad, CURVE);
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0].0, "speed_at_max_power");
        assert!(w[0].1.contains("30 %"), "{}", w[0].1);
    }
}
