//! Catalogue pages as experiments: one `[[experiment]] kind = "catalogue"` per supply
//! pressure, with the curves read off the page (`file`, optional: speed and any of torque,
//! power and air consumption, empty cells allowed) and the key figures
//! (`[experiment.figures]`, optional: `free_speed = "9000 rpm"`, `max_power = "0.12 kW"`,
//! …, each a number and the unit the catalogue prints). The figures become points of the
//! same curves, so one experiment describes the page: the stall torque is the torque at ω =
//! 0 (the datasheet's stall convention), the free speed is where the torque is 0, the
//! max-power figures are the torque, power and air at the speed at max power. The minimum
//! start torque is read and shown but not compared: the model averages the torque over the
//! rotor angle (docs/model.md, "Cycle work and torque") and has no position-dependent
//! starting torque.

use super::{key_location, located, DataError, Table};
use crate::sim::recording::{Column, ExperimentData, Figure, Recording};
use crate::units::{unit_of, Quantity, Unit};
use std::collections::BTreeMap;
use std::path::Path;

/// The key figures a catalogue prints: rig.toml key, quantity, words.
pub const FIGURES: [(&str, Quantity, &str); 8] = [
    ("free_speed", Quantity::Speed, "free speed"),
    ("max_power", Quantity::Power, "max power"),
    ("speed_at_max_power", Quantity::Speed, "speed at max power"),
    (
        "torque_at_max_power",
        Quantity::Torque,
        "torque at max power",
    ),
    ("stall_torque", Quantity::Torque, "stall torque"),
    ("min_start_torque", Quantity::Torque, "minimum start torque"),
    (
        "air_at_max_power",
        Quantity::Flow1,
        "air consumption at max power",
    ),
    (
        "air_at_free_speed",
        Quantity::Flow1,
        "air consumption at free speed",
    ),
];

/// Default reading tolerance of a catalogue point: 1σ = 2 % of its curve's full scale
/// (points read off a printed curve, figures rounded to two or three digits).
pub(crate) const DEFAULT_TOLERANCE: f64 = 0.02;

/// Where a catalogue experiment's text lives, for located errors.
pub(super) struct Source<'a> {
    /// rig.toml's path and text.
    pub rig: (&'a Path, &'a str),
    /// Index of the `[[experiment]]` table.
    pub table: usize,
    /// Atmosphere, Pa (gauge units).
    pub p_atm_pa: f64,
    /// Relative reading tolerance (1σ of the full scale).
    pub tolerance: f64,
}

impl Source<'_> {
    fn at(&self, key: &str, message: String) -> DataError {
        located(
            self.rig.0,
            self.rig.1,
            Table::Experiment(self.table),
            key,
            message,
        )
    }
}

/// Why a printed value ("0.12 kW") was not understood.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ValueError {
    /// No number first.
    #[error("'{0}' is not a number followed by a unit (e.g. '6.3 bar_g')")]
    NotANumber(String),
    /// A number without a unit.
    #[error("'{text}' has no unit (e.g. '{example}')")]
    NoUnit {
        /// The text.
        text: String,
        /// The number with the quantity's SI unit.
        example: String,
    },
    /// A unit that is not one of the quantity's.
    #[error("'{unit}' is not a unit of {what} (known: {known})")]
    WrongUnit {
        /// The unit as printed.
        unit: String,
        /// The quantity in words.
        what: &'static str,
        /// The quantity's units.
        known: String,
    },
    /// The value overflows.
    #[error("'{0}' is not a finite number")]
    NotFinite(String),
    /// A number with a comma in it ("6,3 bar(g)", "1,450 rpm").
    #[error("'{text}' is written with a decimal comma: write the decimal mark as a point ({suggestion})")]
    DecimalComma {
        /// The text.
        text: String,
        /// The text with its decimal comma written as a point.
        suggestion: String,
    },
}

/// Reads "6.3 bar(g)", "0.12 kW", "12 lbf·ft", "7.4 cfm": a number and a unit of `q`,
/// converted to SI. Returns (SI value, unit, the number as written).
pub fn parse_value(text: &str, q: Quantity, p_atm_pa: f64) -> Result<(f64, Unit, f64), ValueError> {
    let plain = without_thousands(without_approx(text.trim()));
    let text = plain.as_str();
    let split = text
        .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
        .unwrap_or(text.len());
    // An exponent's 'e' must not eat the unit's first letter ("5e" of "5 eV" is no number).
    let (number, unit) = text.split_at(split);
    let (number, unit) = match number.parse::<f64>() {
        Ok(_) => (number, unit),
        Err(_) => {
            let k = number.rfind(['e', 'E']).unwrap_or(number.len());
            (&text[..k], &text[k..])
        }
    };
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| ValueError::NotANumber(text.to_string()))?;
    // "6,3 bar(g)" reads as 6 in the unit ",3 bar(g)": name the comma instead, as the CSV
    // reader does for a row of decimal commas.
    if super::digit_comma_digit(text) {
        let point = text.replacen(',', ".", 1);
        let after = text.split_once(',').map_or("", |(_, a)| a);
        let digits = after.chars().take_while(char::is_ascii_digit).count();
        // Three digits after the comma may be thousands ("1,450 rpm"): offer both readings.
        let suggestion = if digits == 3 {
            format!(
                "'{point}'; or, if the comma separates thousands, without it: '{}'",
                text.replacen(',', "", 1)
            )
        } else {
            format!("'{point}'")
        };
        return Err(ValueError::DecimalComma {
            text: text.to_string(),
            suggestion,
        });
    }
    if unit.trim().is_empty() {
        return Err(ValueError::NoUnit {
            text: text.to_string(),
            example: format!("{value} {}", q.si_unit().suffix()),
        });
    }
    let unit = unit_of(q, bare_pressure_as_gauge(q, &normalise_unit(unit))).map_err(|_| {
        ValueError::WrongUnit {
            unit: unit.trim().to_string(),
            what: words(q),
            known: q
                .units()
                .iter()
                .map(|u| u.suffix())
                .collect::<Vec<_>>()
                .join(", "),
        }
    })?;
    let si = unit.to_si(value, p_atm_pa);
    if !si.is_finite() {
        return Err(ValueError::NotFinite(text.to_string()));
    }
    Ok((si, unit, value))
}

/// Words and signs a page prints before an approximate figure ("~9000 rpm", "approx. 0.3
/// N·m", "ca. 180 l/min"): the figure is read as printed, within its reading tolerance.
const APPROX: [&str; 6] = ["approximately", "approx.", "approx", "ca.", "~", "≈"];

/// `text` without a leading sign or word of [`APPROX`] (case-insensitive).
fn without_approx(text: &str) -> &str {
    for word in APPROX {
        if text.len() >= word.len()
            && text.is_char_boundary(word.len())
            && text[..word.len()].eq_ignore_ascii_case(word)
        {
            return text[word.len()..].trim_start();
        }
    }
    text
}

/// Separators a page puts between groups of three digits: the comma, and spaces (plain,
/// thin, narrow no-break, no-break) as ISO 80000 writes "12 200".
const THOUSANDS: [char; 5] = [',', ' ', '\u{2009}', '\u{202f}', '\u{a0}'];

/// `text` with its thousands separators removed where they cannot be a decimal comma:
/// "1,200,000 rpm" (more than one group), "1,200.5 rpm" (a decimal point after the group),
/// "12 200 rpm" (a space; never a decimal mark). A single comma group without a point
/// ("1,200 rpm": 1.2 or 1200?) is left as it is, for [`parse_value`] to refuse as
/// ambiguous with both readings, at the figure's line and column.
fn without_thousands(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let digits_at = |i: usize| chars[i..].iter().take_while(|c| c.is_ascii_digit()).count();
    let sign = usize::from(matches!(chars.first(), Some('-' | '+')));
    let lead = digits_at(sign);
    if !(1..=3).contains(&lead) {
        return text.to_string();
    }
    let mut i = sign + lead;
    let (mut groups, mut sep) = (0, None);
    while i < chars.len() && THOUSANDS.contains(&chars[i]) && sep.is_none_or(|s| s == chars[i]) {
        if digits_at(i + 1) != 3 {
            break;
        }
        sep = Some(chars[i]);
        groups += 1;
        i += 4;
    }
    let point_follows =
        chars.get(i) == Some(&'.') && chars.get(i + 1).is_some_and(char::is_ascii_digit);
    let unambiguous = match sep {
        None => false,
        Some(',') => groups >= 2 || point_follows,
        Some(_) => true,
    };
    if !unambiguous {
        return text.to_string();
    }
    let number: String = chars[..i]
        .iter()
        .filter(|c| !THOUSANDS.contains(c))
        .collect();
    number + &chars[i..].iter().collect::<String>()
}

/// A supply pressure printed in bare `bar` or `psi` (neither gauge nor absolute said): read
/// as gauge, as makers print supply pressures (docs/formats.md, "Catalogue data"); a
/// warning names the line (`supply_notation`).
fn bare_pressure_as_gauge(q: Quantity, unit: &str) -> &str {
    match (q, unit) {
        (Quantity::PPort1 | Quantity::PPort2, "bar") => "bar_g",
        (Quantity::PPort1 | Quantity::PPort2, "psi") => "psi_g",
        _ => unit,
    }
}

/// How a printed supply pressure was read where the page leaves it open: bare `bar`/`psi`
/// as gauge, `MPa`/`kPa`/`Pa` as absolute (vanefit's convention for those units), in words
/// for a warning; `None` where the unit says which (`bar(g)`, `psi(a)`, …).
pub fn supply_notation(text: &str, p_atm_pa: f64) -> Option<String> {
    let (si, unit, written) = parse_value(text, Quantity::PPort1, p_atm_pa).ok()?;
    let plain = without_thousands(without_approx(text.trim()));
    let printed = normalise_unit(plain.trim_start_matches(|c: char| {
        c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E') || c.is_whitespace()
    }));
    let gauge_bar = Unit::BarG.from_si(si, p_atm_pa);
    match printed.as_str() {
        "bar" | "psi" => Some(format!(
            "supply pressure '{}' says neither gauge nor absolute: read as GAUGE, {written} {} = {:.3} bar absolute, as makers print supply pressures; write '{written} {}(a)' if absolute is meant",
            text.trim(),
            unit.suffix(),
            Unit::BarAbs.from_si(si, p_atm_pa),
            printed
        )),
        "mpa" | "kpa" | "pa" => Some(format!(
            "supply pressure '{}' is read as ABSOLUTE ({gauge_bar:.3} bar g), as vanefit reads {printed} everywhere; makers usually print gauge: if gauge is meant, write it as '{:.4} bar(g)'",
            text.trim(),
            Unit::BarG.from_si(si + p_atm_pa, p_atm_pa)
        )),
        _ => None,
    }
}

/// A printed unit as a column suffix: "N·m" → "n_m", "m³/min" → "m3_min", "bar(g)" →
/// "bar_g", "l/min ANR" → "l_min_anr", "r/min" → "r_min".
fn normalise_unit(unit: &str) -> String {
    let mut s = String::new();
    for c in unit.trim().to_lowercase().chars() {
        match c {
            '³' => s.push('3'),
            // "min⁻¹": the superscript minus separates, the superscript one is a 1.
            '¹' => s.push('1'),
            '(' | ')' => {}
            c if c.is_alphanumeric() => s.push(c),
            _ => {
                if !s.ends_with('_') && !s.is_empty() {
                    s.push('_');
                }
            }
        }
        if c == '(' && !s.ends_with('_') {
            s.push('_');
        }
    }
    s.trim_end_matches('_').to_string()
}

/// A quantity in words, for messages.
fn words(q: Quantity) -> &'static str {
    match q {
        Quantity::Speed => "speed",
        Quantity::Torque => "torque",
        Quantity::Power => "power",
        Quantity::Flow1 | Quantity::Flow2 => "air consumption (a flow)",
        Quantity::PPort1 | Quantity::PPort2 => "pressure",
        Quantity::Time => "time",
        Quantity::CPort2 => "conductance",
    }
}

/// Reads the `[experiment.figures]` table: every key known, every value a number and a unit
/// of its quantity, > 0, and consistent with one another.
pub(super) fn read_figures(
    src: &Source<'_>,
    table: &BTreeMap<String, String>,
) -> Result<Vec<Figure>, DataError> {
    let mut out = Vec::new();
    for (key, text) in table {
        let Some((_, q, what)) = FIGURES.iter().find(|(k, _, _)| k == key) else {
            let known: Vec<_> = FIGURES.iter().map(|f| f.0).collect();
            return Err(src.at(
                key,
                format!("unknown key figure '{key}' (known: {})", known.join(", ")),
            ));
        };
        let (si, unit, written) =
            parse_value(text, *q, src.p_atm_pa).map_err(|m| src.at(key, format!("{key}: {m}")))?;
        if si <= 0.0 {
            return Err(src.at(key, format!("{key}: the {what} must be > 0 (got '{text}')")));
        }
        out.push(Figure {
            key: key.clone(),
            quantity: *q,
            unit,
            si,
            written,
            line: key_location(src.rig.1, Table::Experiment(src.table), key).map(|l| l.0),
        });
    }
    check_figures(src, &out)?;
    Ok(out)
}

fn figure(figures: &[Figure], key: &str) -> Option<f64> {
    figures.iter().find(|f| f.key == key).map(|f| f.si)
}

/// The figures against one another: the free speed above the speed at max power, max power
/// placed at a speed, max power = torque·speed there (within three reading tolerances).
fn check_figures(src: &Source<'_>, figures: &[Figure]) -> Result<(), DataError> {
    let get = |k: &str| figure(figures, k);
    let rpm = |w: f64| Unit::Rpm.from_si(w, 0.0);
    if let (Some(free), Some(at_max)) = (get("free_speed"), get("speed_at_max_power")) {
        if free <= at_max {
            return Err(src.at(
                "free_speed",
                format!(
                    "free speed {:.0} rpm is not above the speed at max power {:.0} rpm (the torque is 0 at free speed, so the power is too)",
                    rpm(free),
                    rpm(at_max)
                ),
            ));
        }
    }
    let at_max_keys = ["max_power", "torque_at_max_power", "air_at_max_power"];
    if get("speed_at_max_power").is_none() {
        if let Some(k) = at_max_keys.iter().find(|k| get(k).is_some()) {
            return Err(src.at(
                k,
                format!("{k} needs speed_at_max_power: the model is compared at that speed"),
            ));
        }
    }
    if get("air_at_free_speed").is_some() && get("free_speed").is_none() {
        return Err(src.at(
            "air_at_free_speed",
            "air_at_free_speed needs free_speed: the model is compared at that speed".into(),
        ));
    }
    if let (Some(p), Some(t), Some(w)) = (
        get("max_power"),
        get("torque_at_max_power"),
        get("speed_at_max_power"),
    ) {
        let tw = t * w;
        if (p - tw).abs() > 3.0 * src.tolerance * p.max(tw) {
            let side = if p > tw { "above" } else { "below" };
            return Err(src.at(
                "max_power",
                format!(
                    "max power {p:.1} W is {side} torque·speed at max power = {t:.4} N·m × {:.0} rpm = {tw:.1} W (they must agree within 3 reading tolerances, {:.0} %)",
                    rpm(w),
                    300.0 * src.tolerance
                ),
            ));
        }
    }
    if let (Some(stall), Some(t)) = (get("stall_torque"), get("torque_at_max_power")) {
        if t >= stall {
            return Err(src.at(
                "torque_at_max_power",
                format!(
                    "torque at max power {t:.4} N·m is not below the stall torque {stall:.4} N·m"
                ),
            ));
        }
    }
    Ok(())
}

/// One cell of a figure row: the SI value and, where a figure gave it, that figure.
type Cell<'a> = Option<(f64, Option<&'a Figure>)>;

/// The figures as rows of the curves: cells (speed, torque, power, air), `None` where not
/// given, with the rig.toml line of the row's first figure. Torque at max power is compared
/// only when no max power is given: the model's torque there is its power over the speed,
/// so a second residual would count the one reading of the max-power point twice (it
/// narrowed the posterior's bands on the twin's pages until 94 of 105 held the truth,
/// against 95 % asked); [`check_figures`] holds the two within three reading tolerances of
/// each other, and a torque channel left with the 0 at free speed alone takes its full
/// scale from them (`objective::reference`).
pub(super) fn figure_rows(figures: &[Figure]) -> Vec<([Cell<'_>; 4], u64)> {
    let get = |k: &str| figures.iter().find(|f| f.key == k).map(|f| (f.si, Some(f)));
    let line = |k: &str| figures.iter().find(|f| f.key == k).and_then(|f| f.line);
    let mut rows = Vec::new();
    if let Some(t) = get("stall_torque") {
        rows.push((
            [Some((0.0, None)), Some(t), None, None],
            line("stall_torque"),
        ));
    }
    if let Some(w) = get("speed_at_max_power") {
        let p = get("max_power");
        let t = if p.is_some() {
            None
        } else {
            get("torque_at_max_power")
        };
        let a = get("air_at_max_power");
        if p.is_some() || t.is_some() || a.is_some() {
            rows.push(([Some(w), t, p, a], line("speed_at_max_power")));
        }
    }
    if let Some(w) = get("free_speed") {
        let a = get("air_at_free_speed");
        rows.push(([Some(w), Some((0.0, None)), None, a], line("free_speed")));
    }
    rows.into_iter().map(|(r, l)| (r, l.unwrap_or(1))).collect()
}

/// The recording row where the page says the model's power peaks: its max-power row, on a
/// page whose power peak the catalogue sweep places (`sim::experiment::catalogue::
/// power_peak_speed`: `max_power` printed at `speed_at_max_power`). `None` on any other
/// page. The figure rows follow the curve rows ([`figure_rows`], [`recording`]), so the row
/// is counted from the recording's end.
pub(crate) fn power_peak_row(ex: &ExperimentData) -> Option<usize> {
    crate::sim::experiment::catalogue::power_peak_speed(&ex.figures)?;
    let rows = figure_rows(&ex.figures);
    let at = rows.iter().position(|(cells, _)| {
        cells[0].is_some_and(|(_, f)| f.is_some_and(|f| f.key == "speed_at_max_power"))
    })?;
    let n_curve_rows = ex.recording.rows().checked_sub(rows.len())?;
    Some(n_curve_rows + at)
}

/// The catalogue's recording: the curve rows (if a file is given) followed by the figure
/// rows, columns speed, torque, power and air (those with any value), NaN where a row
/// gives no value.
pub(super) fn recording(
    src: &Source<'_>,
    curves: Option<Recording>,
    figures: &[Figure],
) -> Result<Recording, DataError> {
    if curves.is_none() && figures.is_empty() {
        return Err(src.at(
            "kind",
            "this catalogue experiment gives neither curves nor key figures: give a curve file (file = \"curves.csv\": speed_rpm and any of torque, power and air columns) or an [experiment.figures] table (free_speed = \"9000 rpm\", …), or both".into(),
        ));
    }
    let mut rec = curves.unwrap_or_else(|| Recording {
        file: src.rig.0.to_path_buf(),
        columns: Vec::new(),
        lines: Vec::new(),
    });
    refuse_other_columns(&rec)?;
    let rows = figure_rows(figures);
    // Rows from here on are the figures of rig.toml: their errors name the key.
    let keys = FigureKeys::new(rec.rows(), &rows);
    add_figure_columns(&mut rec, &rows, figures);
    append_figure_rows(&mut rec, rows, src.p_atm_pa);
    let locate = |q, row, message| keys.locate(src, &rec, q, row, message);
    check_curves(&rec, src.tolerance, locate)?;
    check_beyond_free_speed(&rec, keys.n_curve_rows, figures, src.tolerance, locate)?;
    Ok(rec)
}

/// Refuses a curve point beyond the printed free speed whose torque or power is above zero
/// by more than three reading tolerances of its curve's full scale: the torque is 0 at the
/// free speed and falls with speed, so no point beyond it has a torque (a misread speed, or
/// a point of another pressure). Only the curve rows (the first `n_curve_rows`) are looked
/// at; `locate` places the message at the cell.
fn check_beyond_free_speed(
    rec: &Recording,
    n_curve_rows: usize,
    figures: &[Figure],
    tolerance: f64,
    locate: impl Fn(Quantity, usize, String) -> DataError,
) -> Result<(), DataError> {
    let Some(free) = figures.iter().find(|f| f.key == "free_speed") else {
        return Ok(());
    };
    let speed = rec.values(Quantity::Speed)?;
    for q in [Quantity::Torque, Quantity::Power] {
        let Some(col) = rec.column(q) else { continue };
        let full_scale = col
            .si
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max);
        let curve_rows = speed.iter().zip(&col.si).take(n_curve_rows).enumerate();
        for (i, (&w, &v)) in curve_rows {
            if w > free.si && v.is_finite() && v > 3.0 * tolerance * full_scale {
                let at = free
                    .line
                    .map_or(String::new(), |l| format!(" (rig.toml line {l})"));
                return Err(locate(
                    q,
                    i,
                    format!(
                        "{} {} {} at {:.0} rpm, beyond the printed free speed {} {}{at}: the torque is 0 at free speed and falls with speed, so no point beyond it has a torque or power (a misread speed, or a point of another pressure?)",
                        q.words(),
                        &col.raw[i],
                        col.unit.symbol(),
                        Unit::Rpm.from_si(w, 0.0),
                        free.written,
                        free.unit.symbol()
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The quantities of a catalogue's curves, in the order of a figure row's cells.
const CURVE_QUANTITIES: [Quantity; 4] = [
    Quantity::Speed,
    Quantity::Torque,
    Quantity::Power,
    Quantity::Flow1,
];

/// The index of `q` among [`CURVE_QUANTITIES`] (0 for any other).
fn curve_index(q: Quantity) -> usize {
    CURVE_QUANTITIES.iter().position(|x| *x == q).unwrap_or(0)
}

/// Refuses a curve file with a column other than speed, torque, power and air, at that
/// column.
fn refuse_other_columns(rec: &Recording) -> Result<(), DataError> {
    if let Some(c) = rec
        .columns
        .iter()
        .position(|c| !CURVE_QUANTITIES.contains(&c.quantity))
    {
        let name = rec.columns[c].name.clone();
        return Err(DataError::new(
            &rec.file,
            "a catalogue curve file has speed, torque, power and air columns only (give the supply pressure as p_supply in rig.toml, one [[experiment]] per pressure)",
        )
        .at(1)
        .col(c, &name));
    }
    Ok(())
}

/// Adds a column, empty in the rows so far, for each quantity the figure rows give and
/// the curves do not; its unit is that of the first figure of the quantity, as printed.
fn add_figure_columns(rec: &mut Recording, rows: &[([Cell<'_>; 4], u64)], figures: &[Figure]) {
    for (k, &q) in CURVE_QUANTITIES.iter().enumerate() {
        let n_before = rec.rows();
        if rec.column(q).is_none() && rows.iter().any(|(r, _)| r[k].is_some()) {
            // The column's unit: the first figure of that quantity, as printed.
            let unit = figures
                .iter()
                .find(|f| f.quantity == q)
                .map_or(q.si_unit(), |f| f.unit);
            rec.columns.push(Column {
                name: crate::units::column_name(q, unit),
                quantity: q,
                unit,
                si: vec![f64::NAN; n_before],
                raw: std::iter::repeat_n("", n_before).collect(),
            });
        }
    }
}

/// Appends the figure rows to every column: the SI value and the text as printed (with
/// the figure's unit where it is not the column's), NaN and empty where a row gives none.
fn append_figure_rows(rec: &mut Recording, rows: Vec<([Cell<'_>; 4], u64)>, p_atm_pa: f64) {
    for (row, line) in rows {
        for col in &mut rec.columns {
            let k = curve_index(col.quantity);
            let (si, raw) = match row[k] {
                None => (f64::NAN, String::new()),
                // As printed where the figure's unit is the column's, else with its unit.
                Some((v, Some(f))) if f.unit == col.unit => (v, format!("{}", f.written)),
                Some((v, Some(f))) if k > 0 => (v, format!("{} {}", f.written, f.unit.suffix())),
                Some((v, _)) => (v, format!("{}", col.unit.from_si(v, p_atm_pa))),
            };
            col.si.push(si);
            col.raw.push(&raw);
        }
        rec.lines.push(line);
    }
}

/// Where a catalogue recording's figure rows begin and the rig.toml key of each of their
/// cells, so that an error about a cell is placed at the figure that gave it.
struct FigureKeys {
    /// Rows read from the curve file, before the first figure row.
    n_curve_rows: usize,
    /// Each figure row's keys, one per quantity of [`CURVE_QUANTITIES`] (`None` where the
    /// cell was not a figure).
    keys: Vec<[Option<String>; 4]>,
}

impl FigureKeys {
    /// The keys of `rows`, which follow `n_curve_rows` curve rows.
    fn new(n_curve_rows: usize, rows: &[([Cell<'_>; 4], u64)]) -> Self {
        let keys = rows
            .iter()
            .map(|(r, _)| r.map(|c| c.and_then(|(_, f)| f.map(|f| f.key.clone()))))
            .collect();
        Self { n_curve_rows, keys }
    }

    /// An error about the cell of quantity `q` in row `row` of `rec`: in a figure row at
    /// the figure's key of rig.toml (the first of the row if the quantity was not a
    /// figure), in a curve row at the file's line and column.
    fn locate(
        &self,
        src: &Source<'_>,
        rec: &Recording,
        q: Quantity,
        row: usize,
        message: String,
    ) -> DataError {
        let k = curve_index(q);
        match row
            .checked_sub(self.n_curve_rows)
            .and_then(|f| self.keys.get(f))
        {
            Some(keys) => match keys[k].as_ref().or(keys.iter().flatten().next()) {
                Some(key) => src.at(key, message),
                None => DataError::new(src.rig.0, message),
            },
            None => {
                let c = rec
                    .columns
                    .iter()
                    .position(|c| c.quantity == q)
                    .unwrap_or(0);
                DataError::new(&rec.file, message)
                    .at(rec.lines[row])
                    .col(c, &rec.columns[c].name)
            }
        }
    }
}

/// Every row has a speed ≥ 0; torque, power and air are ≥ 0; power is not above
/// torque·speed by more than three reading tolerances of the power's full scale, with the
/// torque taken from the same row or, where the row prints none, bounded by the torque
/// printed at the nearest lower speed. Why not interpolated: at a fixed supply the torque
/// falls with speed, so the torque printed at a lower speed bounds it from above, while a
/// straight line between two sparse points (or between the stall torque and the free speed)
/// lies below a real curve, which bows 8–15 % above it (docs/formats.md, "Catalogue data"),
/// and refused true pages. `locate` places a message at a row's cell of a quantity.
fn check_curves(
    rec: &Recording,
    tolerance: f64,
    locate: impl Fn(Quantity, usize, String) -> DataError,
) -> Result<(), DataError> {
    let speed = rec.values(Quantity::Speed)?;
    for q in [
        Quantity::Speed,
        Quantity::Torque,
        Quantity::Power,
        Quantity::Flow1,
    ] {
        let Some(col) = rec.column(q) else { continue };
        for (i, v) in col.si.iter().enumerate() {
            if q == Quantity::Speed && !v.is_finite() {
                return Err(locate(q, i, "every catalogue point needs its speed".into()));
            }
            if *v < 0.0 {
                return Err(locate(q, i, format!("'{}' must be >= 0", &col.raw[i])));
            }
        }
    }
    if !rec
        .columns
        .iter()
        .any(|c| c.quantity != Quantity::Speed && c.si.iter().any(|v| v.is_finite()))
    {
        return Err(DataError::new(
            &rec.file,
            "the catalogue gives no torque, power or air consumption (a curve file or key figures)",
        ));
    }
    let (Some(power), Some(torque)) = (rec.column(Quantity::Power), rec.column(Quantity::Torque))
    else {
        return Ok(());
    };
    let p_max = power
        .si
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let mut torque_points: Vec<(f64, f64)> = speed
        .iter()
        .zip(&torque.si)
        .filter(|(_, t)| t.is_finite())
        .map(|(w, t)| (*w, *t))
        .collect();
    torque_points.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (i, (&w, &p)) in speed.iter().zip(&power.si).enumerate() {
        let (t, at) = if torque.si[i].is_finite() {
            (torque.si[i], w)
        } else {
            match torque_below(&torque_points, w) {
                Some(p) => (p.1, p.0),
                None => continue,
            }
        };
        if p.is_finite() && p > t * w + 3.0 * tolerance * p_max {
            let rpm = Unit::Rpm.from_si(w, 0.0);
            let bound = if at == w {
                format!("torque·speed = {t:.4} N·m × {rpm:.0} rpm = {:.1} W", t * w)
            } else {
                format!(
                    "torque·speed = {:.1} W with the torque {t:.4} N·m printed at {:.0} rpm, which bounds it above as the torque falls with speed",
                    t * w,
                    Unit::Rpm.from_si(at, 0.0)
                )
            };
            let message = format!(
                "power {p:.1} W at {rpm:.0} rpm is above {bound} (shaft power is torque times speed)"
            );
            return Err(locate(Quantity::Power, i, message));
        }
    }
    Ok(())
}

/// Linear interpolation on points sorted by x; `None` outside their range.
pub(super) fn interpolate(points: &[(f64, f64)], x: f64) -> Option<f64> {
    let k = points.iter().position(|p| p.0 >= x)?;
    let (x1, y1) = points[k];
    if x1 == x {
        return Some(y1);
    }
    let (x0, y0) = *points.get(k.checked_sub(1)?)?;
    Some(y0 + (y1 - y0) * (x - x0) / (x1 - x0))
}

/// The point of the largest x ≤ `x` of points sorted by x; `None` if all lie above `x`.
fn torque_below(points: &[(f64, f64)], x: f64) -> Option<(f64, f64)> {
    points.iter().rev().find(|p| p.0 <= x).copied()
}

/// A geared motor's page moved to the motor shaft, which the model describes: each speed
/// × G, each torque ÷ (η·G), each power ÷ η, air as printed (`Gear`'s law; docs/formats.md,
/// "Geared motors"), in the recording's SI values and in its figures'. The text as printed
/// (`raw`, `written`) stays the output shaft's, for messages and reports.
pub(super) fn to_motor_shaft(
    rec: &mut Recording,
    figures: &mut [Figure],
    gear: &crate::model::gear::Gear,
) {
    for col in &mut rec.columns {
        let q = col.quantity;
        col.si
            .iter_mut()
            .for_each(|v| *v = gear.to_motor_shaft(q, *v));
    }
    for f in figures {
        f.si = gear.to_motor_shaft(f.quantity, f.si);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A decimal comma is named, with the value written with a point; three digits after it
    /// may be thousands, and both readings are offered.
    #[test]
    fn a_decimal_comma_is_named() {
        let e = parse_value("6,3 bar(g)", Quantity::PPort1, 101_325.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "'6,3 bar(g)' is written with a decimal comma: write the decimal mark as a point ('6.3 bar(g)')"
        );
        let e = parse_value("1,450 rpm", Quantity::Speed, 101_325.0).unwrap_err();
        assert!(
            e.to_string().contains(
                "'1.450 rpm'; or, if the comma separates thousands, without it: '1450 rpm'"
            ),
            "{e}"
        );
        assert!(parse_value("6.3 bar(g)", Quantity::PPort1, 101_325.0).is_ok());
    }

    #[test]
    fn printed_units_are_read() {
        let p = 101_325.0;
        let (si, u, v) = parse_value("6.3 bar(g)", Quantity::PPort1, p).unwrap();
        assert_eq!((u, v), (Unit::BarG, 6.3));
        assert!((si - 731_325.0).abs() < 1e-6);
        assert_eq!(
            parse_value("0.12 kW", Quantity::Power, p).unwrap().1,
            Unit::Kw
        );
        assert_eq!(
            parse_value("12 lbf·ft", Quantity::Torque, p).unwrap().1,
            Unit::LbfFt
        );
        assert_eq!(
            parse_value("0.31 N·m", Quantity::Torque, p).unwrap().1,
            Unit::Nm
        );
        assert_eq!(
            parse_value("7.4cfm", Quantity::Flow1, p).unwrap().1,
            Unit::Cfm
        );
        assert_eq!(
            parse_value("3 m³/min", Quantity::Flow1, p).unwrap().1,
            Unit::M3Min
        );
        assert_eq!(
            parse_value("180 l/min ANR", Quantity::Flow1, p).unwrap().1,
            Unit::LMinAnr
        );
        assert_eq!(
            parse_value("180 Nl/min", Quantity::Flow1, p).unwrap().1,
            Unit::NlMin
        );
        assert_eq!(
            parse_value("9000 r/min", Quantity::Speed, p).unwrap().1,
            Unit::Rpm
        );
        assert_eq!(
            parse_value("90 psi(g)", Quantity::PPort1, p).unwrap().1,
            Unit::PsiG
        );
        assert_eq!(parse_value("1e3 rpm", Quantity::Speed, p).unwrap().2, 1e3);
        for (text, q, u) in [
            ("9000 min-1", Quantity::Speed, Unit::Rpm),
            ("9000 min⁻¹", Quantity::Speed, Unit::Rpm),
            ("9000 1/min", Quantity::Speed, Unit::Rpm),
            ("9000 r.p.m.", Quantity::Speed, Unit::Rpm),
            ("12 in·lbf", Quantity::Torque, Unit::LbfIn),
            ("12 in-lb", Quantity::Torque, Unit::LbfIn),
            ("12 lb-in", Quantity::Torque, Unit::LbfIn),
            ("12 in.lbs", Quantity::Torque, Unit::LbfIn),
            ("120 watts", Quantity::Power, Unit::W),
            ("7.4 ft³/min", Quantity::Flow1, Unit::Cfm),
            ("180 Nl/min ANR", Quantity::Flow1, Unit::LMinAnr),
            // Issue 44's spellings.
            ("12200 U/min", Quantity::Speed, Unit::Rpm),
            ("12200 UpM", Quantity::Speed, Unit::Rpm),
            ("3.9 Nl/s", Quantity::Flow1, Unit::NlS),
            ("230 Nl/min", Quantity::Flow1, Unit::NlMin),
            ("0.12 ft-lb", Quantity::Torque, Unit::LbfFt),
            ("0.12 lb-ft", Quantity::Torque, Unit::LbfFt),
            ("0.12 ft·lbf", Quantity::Torque, Unit::LbfFt),
            ("0.12 ft.lbf", Quantity::Torque, Unit::LbfFt),
            ("0.12 ft lbf", Quantity::Torque, Unit::LbfFt),
            ("0.12 ft.lbs", Quantity::Torque, Unit::LbfFt),
            ("6.3 barg", Quantity::PPort1, Unit::BarG),
            ("6.3 bar(ü)", Quantity::PPort1, Unit::BarG),
            ("6.3 bar ü", Quantity::PPort1, Unit::BarG),
            ("6.3 BAR(Ü)", Quantity::PPort1, Unit::BarG),
            ("90 psig", Quantity::PPort1, Unit::PsiG),
            ("0.03 kgf·m", Quantity::Torque, Unit::KgfM),
            ("0.03 kgf m", Quantity::Torque, Unit::KgfM),
            ("0.03 kgfm", Quantity::Torque, Unit::KgfM),
            ("3 kgf·cm", Quantity::Torque, Unit::KgfCm),
            ("29 N·cm", Quantity::Torque, Unit::NCm),
        ] {
            assert_eq!(parse_value(text, q, p).map(|r| r.1), Ok(u), "{text}");
        }
        let e = parse_value("0.12 N·m", Quantity::Power, p).unwrap_err();
        let e = e.to_string();
        assert!(e.contains("not a unit of power") && e.contains("kw"), "{e}");
        assert!(parse_value("kW", Quantity::Power, p).is_err());
        assert!(matches!(
            parse_value("0.12", Quantity::Power, p),
            Err(ValueError::NoUnit { .. })
        ));
    }

    /// Makers' spellings read as printed give the SI value of a closed form written out
    /// here: 12200 U/min = 12200·2π/60 rad/s, 6.3 barg = 6.3e5 Pa + p_atm, 0.12 ft-lb =
    /// 0.12·0.3048·0.45359237·9.80665 N·m, 3.9 Nl/s = 3.9e-3 m³/s · 101325/(287.05287·273.15)
    /// kg/m³, 0.03 kgf·m = 0.03·9.80665 N·m.
    #[test]
    fn makers_spellings_give_closed_form_si_values() {
        let p = 101_325.0;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs();
        for (text, q, want) in [
            (
                "12200 U/min",
                Quantity::Speed,
                12_200.0 * std::f64::consts::PI / 30.0,
            ),
            (
                "12200 min⁻¹",
                Quantity::Speed,
                12_200.0 * std::f64::consts::PI / 30.0,
            ),
            ("6.3 barg", Quantity::PPort1, 6.3e5 + p),
            ("6.3 bar(ü)", Quantity::PPort1, 6.3e5 + p),
            (
                "90 psig",
                Quantity::PPort1,
                90.0 * 0.453_592_37 * 9.806_65 / 0.0254_f64.powi(2) + p,
            ),
            (
                "0.12 ft-lb",
                Quantity::Torque,
                0.12 * 0.3048 * 0.453_592_37 * 9.806_65,
            ),
            (
                "0.12 lb-ft",
                Quantity::Torque,
                0.12 * 0.3048 * 0.453_592_37 * 9.806_65,
            ),
            ("0.03 kgf·m", Quantity::Torque, 0.03 * 9.806_65),
            (
                "3.9 Nl/s",
                Quantity::Flow1,
                3.9e-3 * 101_325.0 / (287.052_87 * 273.15),
            ),
            (
                "234 Nl/min",
                Quantity::Flow1,
                234e-3 / 60.0 * 101_325.0 / (287.052_87 * 273.15),
            ),
        ] {
            let (si, _, _) = parse_value(text, q, p).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert!(close(si, want), "{text}: {si} vs {want}");
        }
        // Stated gauge: no warning about how it was read.
        for stated in ["6.3 barg", "6.3 bar(ü)", "90 psig"] {
            assert_eq!(supply_notation(stated, p), None, "{stated}");
        }
    }

    /// "~9000 rpm", "approx. 0.3 N·m", "ca. 180 l/min": read as printed.
    #[test]
    fn approximate_figures_are_read() {
        let p = 101_325.0;
        for (text, q, want) in [
            ("~9000 rpm", Quantity::Speed, 9000.0),
            ("≈ 9000 rpm", Quantity::Speed, 9000.0),
            ("approx. 0.3 N·m", Quantity::Torque, 0.3),
            ("Approx 0.3 N·m", Quantity::Torque, 0.3),
            ("ca. 180 l/min", Quantity::Flow1, 180.0),
        ] {
            let (_, _, written) = parse_value(text, q, p).unwrap();
            assert_eq!(written, want, "{text}");
        }
        assert!(parse_value("~ rpm", Quantity::Speed, p).is_err());
    }

    /// Thousands separators where they cannot be a decimal comma are read; "1,200 rpm" (1.2
    /// or 1200?) is refused with both readings.
    #[test]
    fn thousands_separators_are_read_where_unambiguous() {
        let p = 101_325.0;
        for (text, want) in [
            ("1,200,000 rpm", 1_200_000.0),
            ("1,200.5 rpm", 1200.5),
            ("12 200 rpm", 12_200.0),
            ("12\u{202f}200 rpm", 12_200.0),
            ("12\u{a0}200 r/min", 12_200.0),
            ("9000 1/min", 9000.0),
            ("12200 rpm", 12_200.0),
        ] {
            let (_, _, written) = parse_value(text, Quantity::Speed, p).unwrap();
            assert_eq!(written, want, "{text}");
        }
        let e = parse_value("1,200 rpm", Quantity::Speed, p).unwrap_err();
        assert!(matches!(e, ValueError::DecimalComma { .. }), "{e}");
        assert!(e.to_string().contains("'1200 rpm'"), "{e}");
        // Mixed separators are not a grouping.
        assert!(parse_value("1,200 000 rpm", Quantity::Speed, p).is_err());
    }

    /// Bare bar and psi are gauge; MPa is absolute; each is said, a stated reference is not.
    #[test]
    fn supply_pressures_without_gauge_or_absolute_are_read_and_said() {
        let p = 101_325.0;
        let (si, u, _) = parse_value("6.3 bar", Quantity::PPort1, p).unwrap();
        assert_eq!(u, Unit::BarG);
        assert!((si - 731_325.0).abs() < 1e-6);
        assert_eq!(
            parse_value("90 psi", Quantity::PPort1, p).unwrap().1,
            Unit::PsiG
        );
        let note = supply_notation("6.3 bar", p).unwrap();
        assert!(
            note.contains("GAUGE") && note.contains("7.313 bar absolute"),
            "{note}"
        );
        let note = supply_notation("0.73 MPa", p).unwrap();
        assert!(
            note.contains("ABSOLUTE") && note.contains("6.287 bar g"),
            "{note}"
        );
        assert!(note.contains("'7.3000 bar(g)'"), "{note}");
        for stated in ["6.3 bar(g)", "6.3 bar_abs", "90 psi(g)", "90 psig"] {
            assert_eq!(supply_notation(stated, p), None, "{stated}");
        }
    }

    proptest::proptest! {
        #[test]
        fn any_printed_value_is_read_or_refused_without_panic(text in "\\PC{0,24}") {
            for q in [Quantity::Speed, Quantity::Torque, Quantity::Power, Quantity::Flow1, Quantity::PPort1] {
                if let Ok((si, _, _)) = parse_value(&text, q, 101_325.0) {
                    proptest::prop_assert!(si.is_finite());
                }
            }
        }
    }

    #[test]
    fn the_torque_bound_is_the_point_at_or_below_the_speed() {
        let pts = [(0.0, 1.0), (10.0, 0.0)];
        assert_eq!(torque_below(&pts, 5.0), Some((0.0, 1.0)));
        assert_eq!(torque_below(&pts, 10.0), Some((10.0, 0.0)));
        assert_eq!(torque_below(&[(2.0, 1.0)], 1.0), None);
    }
}
