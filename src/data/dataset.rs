//! Datasets on disk (docs/formats.md, "Datasets", "rig.toml", "CSV recordings"): `rig.toml`
//! plus one CSV recording per experiment. Everything is validated here, at the edge, and
//! converted to SI; errors name the file, the line and the column.

pub use crate::data::motor::MotorSection;
use crate::model::motor::Load;
use crate::model::params::MotorParams;
use crate::sim::experiment::InputCheck;
pub use crate::sim::recording::{Cells, Column, ExperimentData, Kind, MissingColumn, Recording};

pub(crate) mod catalogue;
pub(crate) mod page_rules;
mod plausible;

use crate::units::constants::P_ATM_PA;
use crate::units::{parse_column, ColumnNameError, Quantity};
pub use catalogue::{parse_value, FIGURES};
pub use page_rules::page_warnings;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A located problem with input data (the data layer's error): shown as
/// `file:line:column (column 'name'): message` for a CSV file, `file:line:column (key
/// 'name'): message` for a TOML file, with whatever of the location is known.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}", located_text(.file, *.line, .column.as_ref(), .named, .message))]
pub struct DataError {
    /// The file at fault.
    pub file: PathBuf,
    /// 1-based line, where known.
    pub line: Option<u64>,
    /// 1-based column index (characters in the line) and the name found there, where known.
    pub column: Option<(usize, String)>,
    /// What the name in `column` is: a CSV column, or a TOML key, value or table.
    pub(crate) named: Named,
    /// What is wrong.
    pub message: String,
}

/// What the name beside a located error's column is, as its message says it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub(crate) enum Named {
    /// A CSV column's header.
    #[default]
    Column,
    /// A TOML key.
    Key,
    /// A TOML value.
    Value,
    /// A TOML table.
    Table,
}

impl Named {
    /// The word messages use.
    pub(crate) fn word(self) -> &'static str {
        match self {
            Named::Column => "column",
            Named::Key => "key",
            Named::Value => "value",
            Named::Table => "table",
        }
    }
}

fn located_text(
    file: &Path,
    line: Option<u64>,
    column: Option<&(usize, String)>,
    named: &Named,
    message: &str,
) -> String {
    let mut s = file.display().to_string();
    if let Some(line) = line {
        s += &format!(":{line}");
        if let Some((c, _)) = column {
            s += &format!(":{c}");
        }
    }
    if let Some((_, name)) = column {
        s += &format!(" ({} '{name}')", named.word());
    }
    s + ": " + message
}

/// Whether `text` has a comma between two digits (`0,1003551`, `6,3`): a number written with
/// a decimal comma (or a thousands separator), which neither a CSV field nor a value reads.
pub(crate) fn digit_comma_digit(text: &str) -> bool {
    let b = text.as_bytes();
    (1..b.len().saturating_sub(1))
        .any(|i| b[i] == b',' && b[i - 1].is_ascii_digit() && b[i + 1].is_ascii_digit())
}

impl DataError {
    /// An error about a whole file (no line known yet).
    pub fn new(file: &Path, message: impl Into<String>) -> Self {
        Self {
            file: file.to_path_buf(),
            line: None,
            column: None,
            named: Named::Column,
            message: message.into(),
        }
    }
    fn at(mut self, line: u64) -> Self {
        self.line = Some(line);
        self
    }
    fn col(mut self, index0: usize, name: &str) -> Self {
        self.column = Some((index0 + 1, name.to_string()));
        self
    }
}

impl From<MissingColumn> for DataError {
    fn from(e: MissingColumn) -> Self {
        DataError::new(&e.file, e.message()).at(1)
    }
}

/// The fewest rows a recording may have: a reference polynomial needs at least this many.
pub(crate) const MIN_ROWS: usize = 4;

/// The columns a CSV header names (quantity and unit of each), empty; a name that is not a
/// quantity and its unit, or a quantity given twice, is refused at its column.
fn header_columns(path: &Path, headers: &csv::StringRecord) -> Result<Vec<Column>, DataError> {
    let mut columns: Vec<Column> = Vec::with_capacity(headers.len());
    for (i, name) in headers.iter().enumerate() {
        let (quantity, unit) = parse_column(name).map_err(|e| {
            let msg = match e {
                ColumnNameError::UnknownUnit { quantity, unit } => {
                    let known: Vec<_> = quantity.units().iter().map(|u| u.suffix()).collect();
                    format!(
                        "unknown unit '{unit}' for {} (known: {})",
                        quantity.prefix(),
                        known.join(", ")
                    )
                }
                ColumnNameError::UnknownColumn => {
                    let known: Vec<_> = Quantity::ALL.iter().map(|q| q.prefix()).collect();
                    format!(
                        "unknown column (a name is a quantity and its unit; quantities: {})",
                        known.join(", ")
                    )
                }
            };
            DataError::new(path, msg).at(1).col(i, name)
        })?;
        if let Some(prev) = columns.iter().position(|c: &Column| c.quantity == quantity) {
            return Err(DataError::new(
                path,
                format!(
                    "{} given twice (also column {})",
                    quantity.prefix(),
                    prev + 1
                ),
            )
            .at(1)
            .col(i, name));
        }
        columns.push(Column {
            name: name.to_string(),
            quantity,
            unit,
            si: Vec::new(),
            raw: Cells::new(),
        });
    }
    Ok(columns)
}

/// Refuses a header separated by semicolons or tabs (as spreadsheets write where the comma
/// is the decimal mark), naming what was found, instead of reading it as one unknown column.
fn refuse_other_separators(path: &Path, text: &str) -> Result<(), DataError> {
    let header = text.lines().next().unwrap_or("");
    if header.contains(',') {
        return Ok(());
    }
    let found = [(';', "semicolons"), ('\t', "tabs")]
        .into_iter()
        .map(|(c, name)| (header.matches(c).count(), name))
        .find(|(n, _)| *n > 0);
    match found {
        Some((n, name)) => Err(DataError::new(
            path,
            format!(
                "the header's columns are separated by {name} ({n} found, no comma): vanefit \
                 reads comma-separated files with '.' as the decimal mark; save the sheet as \
                 CSV with ',' between columns and '.' in numbers"
            ),
        )
        .at(1)),
        None => Ok(()),
    }
}

/// For a row with more fields than the header whose text has digits on both sides of a
/// comma (`0,1003551`): what was found, since numbers with a decimal comma cannot be told
/// from the columns of a comma-separated file. `None` for any other malformed row.
fn decimal_commas(e: &csv::Error, text: &str, line: u64) -> Option<String> {
    let csv::ErrorKind::UnequalLengths {
        expected_len, len, ..
    } = e.kind()
    else {
        return None;
    };
    let row = text
        .lines()
        .nth(usize::try_from(line).ok()?.checked_sub(1)?)?;
    (*len > *expected_len && digit_comma_digit(row)).then(|| {
        format!(
            "{len} fields where the header has {expected_len}: the numbers look written with a \
             decimal comma, which a comma-separated file cannot hold; save the sheet with '.' \
             as the decimal mark"
        )
    })
}

impl Recording {
    /// Reads and validates a CSV recording. `p_atm_pa` converts gauge pressures.
    pub fn read(path: &Path, p_atm_pa: f64) -> Result<Self, DataError> {
        let text = read_text(path)?;
        Self::parse(path, &text, p_atm_pa)
    }

    /// Parses CSV text (`path` is used in messages only).
    pub fn parse(path: &Path, text: &str, p_atm_pa: f64) -> Result<Self, DataError> {
        Self::parse_cells(path, text, p_atm_pa, false)
    }

    /// Parses CSV text whose cells may be empty (a catalogue's sparse points): an empty cell
    /// is NaN in SI and "" as written.
    pub fn parse_sparse(path: &Path, text: &str, p_atm_pa: f64) -> Result<Self, DataError> {
        Self::parse_cells(path, text, p_atm_pa, true)
    }

    fn parse_cells(
        path: &Path,
        text: &str,
        p_atm_pa: f64,
        sparse: bool,
    ) -> Result<Self, DataError> {
        let text = Self::unix_text(text);
        let text = text.as_ref();
        Self::check_text_size(path, text)?;
        refuse_other_separators(path, text)?;
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let headers = reader
            .headers()
            .map_err(|e| DataError::new(path, format!("unreadable header: {e}")).at(1))?
            .clone();
        let mut columns = header_columns(path, &headers)?;
        // Room for every row at once (a line per row, give or take the header and blank
        // lines): the buffers of a large recording then grow once instead of doubling.
        let rows = text.bytes().filter(|b| *b == b'\n').count() + 1;
        for c in &mut columns {
            c.si.reserve_exact(rows);
        }
        let mut lines: Vec<u64> = Vec::with_capacity(rows);
        for record in reader.records() {
            let record = record.map_err(|e| Self::malformed_row(path, text, &e, &lines))?;
            let line = record.position().map(|p| p.line()).unwrap_or(0);
            Self::push_row(path, &record, line, &mut columns, p_atm_pa, sparse)?;
            lines.push(line);
        }
        if lines.is_empty() {
            return Err(DataError::new(path, "no data rows after the header").at(1));
        }
        let rec = Recording {
            file: path.to_path_buf(),
            columns,
            lines,
        };
        rec.check_time()?;
        Ok(rec)
    }

    /// The CSV text as the reader should see it: without a byte-order mark (as spreadsheet
    /// programs write; it is not part of the first name) and with CRLF line ends made LF
    /// (Windows exports: the csv reader places a record after CR on the line before, so
    /// located errors would name the line above the bad one).
    fn unix_text(text: &str) -> std::borrow::Cow<'_, str> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if text.contains('\r') {
            std::borrow::Cow::Owned(text.replace("\r\n", "\n"))
        } else {
            std::borrow::Cow::Borrowed(text)
        }
    }

    /// Refuses a text with nothing in it, or one too large for the cells' offsets.
    fn check_text_size(path: &Path, text: &str) -> Result<(), DataError> {
        if text.trim().is_empty() {
            return Err(DataError::new(
                path,
                "file is empty (expected a header row and data rows)",
            )
            .at(1));
        }
        if text.len() > Cells::MAX_TEXT {
            return Err(DataError::new(
                path,
                format!(
                    "file of {} bytes is larger than the 4 GiB vanefit reads; split the recording",
                    text.len()
                ),
            ));
        }
        Ok(())
    }

    /// A row the csv reader could not read, located at its line (the one after the last
    /// row read where the reader does not say), naming decimal commas where they are why.
    fn malformed_row(path: &Path, text: &str, e: &csv::Error, lines: &[u64]) -> DataError {
        let next = lines.last().map_or(2, |l| l + 1);
        let line = e.position().map_or(next, |p| p.line());
        let what = decimal_commas(e, text, line).unwrap_or_else(|| e.to_string());
        DataError::new(path, format!("malformed row: {what}")).at(line)
    }

    /// Appends one data row (at `line`) to the columns, in SI and as written; with `sparse`
    /// an empty cell is NaN. A row with another count of fields than the header is refused
    /// at its line, a field that is not a finite number at its cell.
    fn push_row(
        path: &Path,
        record: &csv::StringRecord,
        line: u64,
        columns: &mut [Column],
        p_atm_pa: f64,
        sparse: bool,
    ) -> Result<(), DataError> {
        if record.len() != columns.len() {
            return Err(DataError::new(
                path,
                format!(
                    "row has {} fields, header has {}",
                    record.len(),
                    columns.len()
                ),
            )
            .at(line));
        }
        for (i, (field, col)) in record.iter().zip(columns.iter_mut()).enumerate() {
            if sparse && field.is_empty() {
                col.si.push(f64::NAN);
                col.raw.push("");
                continue;
            }
            let v: f64 = field.parse().map_err(|_| {
                DataError::new(
                    path,
                    format!("'{field}' is not a number (use '.' as decimal mark)"),
                )
                .at(line)
                .col(i, &col.name)
            })?;
            let si = col.unit.parsed_si(field, v, p_atm_pa).unwrap_or(f64::NAN);
            if !(v.is_finite() && si.is_finite()) {
                return Err(
                    DataError::new(path, format!("'{field}' is not a finite number"))
                        .at(line)
                        .col(i, &col.name),
                );
            }
            col.si.push(si);
            col.raw.push(field);
        }
        Ok(())
    }

    fn check_time(&self) -> Result<(), DataError> {
        let Some((i, col)) = self
            .columns
            .iter()
            .enumerate()
            .find(|(_, c)| c.quantity == Quantity::Time)
        else {
            return Ok(());
        };
        for k in 1..col.si.len() {
            if col.si[k] <= col.si[k - 1] {
                return Err(DataError::new(
                    &self.file,
                    format!(
                        "time does not increase ({} after {})",
                        &col.raw[k],
                        &col.raw[k - 1]
                    ),
                )
                .at(self.lines[k])
                .col(i, &col.name));
            }
        }
        Ok(())
    }

    /// Refuses an abscissa that does not span a range (a ramp that does not ramp).
    fn check_spans(&self, q: Quantity, min_relative_span: f64) -> Result<(), DataError> {
        let v = self.values(q)?;
        if v.is_empty() {
            return Err(DataError::new(&self.file, "no data rows").at(1));
        }
        let (mut ilo, mut ihi) = (0, 0);
        for (k, x) in v.iter().enumerate() {
            if *x < v[ilo] {
                ilo = k;
            }
            if *x > v[ihi] {
                ihi = k;
            }
        }
        let (lo, hi) = (v[ilo], v[ihi]);
        let spread = (hi - lo).partial_cmp(&(min_relative_span * hi.abs().max(lo.abs())));
        if spread != Some(std::cmp::Ordering::Greater) {
            let i = self
                .columns
                .iter()
                .position(|c| c.quantity == q)
                .unwrap_or(0);
            let col = &self.columns[i];
            let first = self.lines.first().copied().unwrap_or(2);
            let last = self.lines.last().copied().unwrap_or(first);
            return Err(DataError::new(
                &self.file,
                format!(
                    "{} does not span a range: from line {first} to line {last} it stays between {} and {} (needs a spread of more than {}% of its magnitude)",
                    q.prefix(),
                    &col.raw[ilo],
                    &col.raw[ihi],
                    min_relative_span * 100.0
                ),
            )
            .at(last)
            .col(i, &col.name));
        }
        Ok(())
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RigFile {
    #[serde(default)]
    synthetic: bool,
    #[serde(default)]
    description: Option<String>,
    motor: MotorSection,
    #[serde(default)]
    conditions: ConditionsSection,
    experiment: Vec<ExperimentSection>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ConditionsSection {
    #[serde(default = "default_p_atm")]
    p_atm_pa: f64,
    #[serde(default = "default_temperature")]
    temperature_k: f64,
}

impl Default for ConditionsSection {
    fn default() -> Self {
        Self {
            p_atm_pa: default_p_atm(),
            temperature_k: default_temperature(),
        }
    }
}

fn default_p_atm() -> f64 {
    P_ATM_PA
}
fn default_temperature() -> f64 {
    crate::units::constants::T0_K
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExperimentSection {
    kind: Kind,
    /// The recording; a catalogue may give key figures only.
    #[serde(default)]
    file: Option<String>,
    #[serde(default)]
    p_supply_mpa: Option<f64>,
    /// Supply pressure as printed, e.g. "6.3 bar_g" or "90 psi(g)".
    #[serde(default)]
    p_supply: Option<String>,
    /// Relative reading tolerance of stated data (catalogues; default 0.02).
    #[serde(default)]
    tolerance: Option<f64>,
    /// A catalogue's key figures as printed, e.g. free_speed = "9000 rpm".
    #[serde(default)]
    figures: Option<std::collections::BTreeMap<String, String>>,
    #[serde(default)]
    load: Option<LoadSection>,
    #[serde(default)]
    weight: Option<f64>,
    #[serde(default)]
    weights: Option<std::collections::BTreeMap<String, f64>>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
enum LoadSection {
    None,
    ViscousBrake { c_nm_s_rad: f64 },
    Torque { t_nm: f64 },
}

/// A dataset: a motor and its recordings.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// The dataset folder.
    pub dir: PathBuf,
    /// The folder's name, used as the dataset's name.
    pub name: String,
    /// Written by `vanefit synth` (rig.toml `synthetic = true`).
    pub synthetic: bool,
    /// Free text from rig.toml.
    pub description: Option<String>,
    /// The `[motor]` table.
    pub motor: MotorSection,
    /// Atmospheric pressure of the rig, Pa (absolute).
    pub p_atm_pa: f64,
    /// Supply air temperature, K.
    pub temperature_k: f64,
    /// The experiments in rig.toml order.
    pub experiments: Vec<ExperimentData>,
}

#[cfg(test)]
impl Dataset {
    /// A dataset held in memory (no folder) of `experiments` under the default motor table
    /// and the standard atmosphere: for tests that synthesise their recordings.
    pub(crate) fn in_memory(experiments: Vec<ExperimentData>) -> Self {
        Self {
            dir: std::path::PathBuf::from("mem"),
            name: "mem".into(),
            synthetic: true,
            description: None,
            motor: MotorSection::default(),
            p_atm_pa: crate::units::constants::P_ATM_PA,
            temperature_k: crate::units::constants::T0_K,
            experiments,
        }
    }
}

impl Dataset {
    /// The rig's nominal motor: defaults, overridden by what `[motor]` gives (its volumes,
    /// or its geometry through paper eqs. 1–7).
    pub fn nominal_params(&self) -> Result<MotorParams, DataError> {
        self.motor
            .nominal_params()
            .map_err(|e| DataError::new(&self.dir.join("rig.toml"), e.to_string()))
    }

    /// Reads `<dir>/rig.toml` and every recording it names.
    pub fn load(dir: &Path) -> Result<Self, DataError> {
        let rig_path = dir.join("rig.toml");
        if !dir.is_dir() {
            return Err(DataError::new(dir, "dataset folder not found"));
        }
        let text = read_text(&rig_path)?;
        Self::from_rig_text(dir, &text)
    }

    /// The dataset whose `rig.toml` holds `text` (messages name `<dir>/rig.toml`), with the
    /// recordings it names read from `dir`: [`Dataset::load`] without reading rig.toml, for
    /// callers that have its text already (the fuzz target, which would otherwise write a
    /// file per input).
    pub fn from_rig_text(dir: &Path, text: &str) -> Result<Self, DataError> {
        let rig_path = dir.join("rig.toml");
        let mut rig: RigFile =
            toml::from_str(text).map_err(|e| locate_toml_error(&rig_path, text, &e))?;
        rig.motor
            .resolve_units()
            .map_err(|e| located(&rig_path, text, Table::Motor, e.key(), e.to_string()))?;
        check_rig(&rig_path, text, &rig)?;
        let p_atm_pa = rig.conditions.p_atm_pa;
        let gear = rig.motor.gear().ok().flatten();
        let mut experiments = Vec::with_capacity(rig.experiment.len());
        for (k, ex) in rig.experiment.iter().enumerate() {
            let mut data = experiment_data(dir, (&rig_path, text), k, ex, p_atm_pa)?;
            if let Some(g) = &gear {
                geared(&mut data, g, (&rig_path, text))?;
            }
            check_experiment(&data, &|key: &str, message: String| {
                located(&rig_path, text, Table::Experiment(k), key, message)
            })?;
            plausible::check_recording(&data.recording, p_atm_pa)?;
            experiments.push(data);
        }
        Ok(Dataset {
            dir: dir.to_path_buf(),
            name: dataset_name(dir),
            synthetic: rig.synthetic,
            description: rig.description,
            motor: rig.motor,
            p_atm_pa,
            temperature_k: rig.conditions.temperature_k,
            experiments,
        })
    }
}

/// The dataset's name: its folder's name, also where the folder is given as `.` or `..`
/// (the name of the folder it stands for).
pub(crate) fn dataset_name(dir: &Path) -> String {
    let named = |p: &Path| p.file_name().map(|n| n.to_string_lossy().into_owned());
    named(dir)
        .or_else(|| dir.canonicalize().ok().as_deref().and_then(named))
        .unwrap_or_default()
}

/// A geared motor's experiment moved to the motor shaft (a catalogue page's figures are
/// the output shaft's); a rig recording is refused at `gear_ratio`: a rig measures at the
/// motor shaft, where no gearbox sits between the motor and its sensors.
fn geared(
    data: &mut ExperimentData,
    gear: &crate::model::gear::Gear,
    rig: (&Path, &str),
) -> Result<(), DataError> {
    if data.kind != Kind::Catalogue {
        return Err(located(
            rig.0,
            rig.1,
            Table::Motor,
            "gear_ratio",
            format!(
                "gear_ratio is for catalogue pages (figures at a gearbox's output shaft); experiment '{}' is a {} recording, which a rig takes at the motor shaft: remove gear_ratio or fit the pages alone",
                data.file,
                data.kind.id()
            ),
        ));
    }
    catalogue::to_motor_shaft(&mut data.recording, &mut data.figures, gear);
    Ok(())
}

impl Dataset {
    /// The motor's gearbox, when `[motor]` gives `gear_ratio` (checked when read): the
    /// catalogue pages' figures were the output shaft's and are held at the motor shaft.
    pub fn gear(&self) -> Option<crate::model::gear::Gear> {
        self.motor.gear().ok().flatten()
    }
}

impl ExperimentSection {
    /// The experiment's name: its file, or for a catalogue of key figures only
    /// `catalogue_<k>.csv` (the name `simulate` writes its points under).
    fn name(&self, k: usize) -> String {
        self.file
            .clone()
            .unwrap_or_else(|| format!("{}_{}.csv", self.kind.id(), k + 1))
    }
}

/// One `[[experiment]]` (the k-th) with its recording, read and checked.
fn experiment_data(
    dir: &Path,
    rig: (&Path, &str),
    k: usize,
    ex: &ExperimentSection,
    p_atm_pa: f64,
) -> Result<ExperimentData, DataError> {
    let at = |key: &str, message: String| located(rig.0, rig.1, Table::Experiment(k), key, message);
    let catalogue = ex.kind == Kind::Catalogue;
    let p_supply_pa = supply_pressure_pa(ex, p_atm_pa, &at)?;
    let tolerance = reading_tolerance(ex, &at)?;
    let recording = read_recording(dir, ex, p_atm_pa, &at)?;
    let (recording, figures) = if catalogue {
        let src = catalogue::Source {
            rig,
            table: k,
            p_atm_pa,
            tolerance,
        };
        let figures = match &ex.figures {
            Some(t) => catalogue::read_figures(&src, t)?,
            None => Vec::new(),
        };
        (catalogue::recording(&src, recording, &figures)?, figures)
    } else {
        (recording.expect("checked above"), Vec::new())
    };
    Ok(ExperimentData {
        kind: ex.kind,
        file: ex.name(k),
        p_supply_pa,
        p_supply_written: ex.p_supply.clone(),
        p_supply_line: ex
            .p_supply
            .as_ref()
            .and_then(|_| key_location(rig.1, Table::Experiment(k), "p_supply"))
            .map(|l| l.0),
        load: experiment_load(ex),
        weight: ex.weight.unwrap_or(1.0),
        channel_weights: ex.weights.clone().unwrap_or_default(),
        recording,
        tolerance: catalogue.then_some(tolerance),
        figures,
    })
}

/// The experiment's supply pressure, Pa absolute, from `p_supply` as printed or from
/// `p_supply_mpa` (not both); `None` where neither is given. `at` locates a key's error.
fn supply_pressure_pa(
    ex: &ExperimentSection,
    p_atm_pa: f64,
    at: &impl Fn(&str, String) -> DataError,
) -> Result<Option<f64>, DataError> {
    Ok(match (&ex.p_supply, ex.p_supply_mpa) {
        (Some(_), Some(_)) => {
            return Err(at(
                "p_supply",
                "give p_supply or p_supply_mpa, not both".into(),
            ))
        }
        (Some(text), None) => {
            let (p, _, _) = catalogue::parse_value(text, Quantity::PPort1, p_atm_pa)
                .map_err(|m| at("p_supply", format!("p_supply: {m}")))?;
            if !(p > p_atm_pa && p < 5e6) {
                return Err(at(
                    "p_supply",
                    format!(
                        "p_supply = '{text}' must be above atmosphere and below 5 MPa absolute"
                    ),
                ));
            }
            Some(p)
        }
        (None, mpa) => mpa.map(|p| p * 1e6),
    })
}

/// The relative reading tolerance of the experiment's stated data (a catalogue's; other
/// kinds may give neither it nor figures), checked to lie in (0, 0.5).
fn reading_tolerance(
    ex: &ExperimentSection,
    at: &impl Fn(&str, String) -> DataError,
) -> Result<f64, DataError> {
    if ex.kind != Kind::Catalogue {
        for key in ["figures", "tolerance"] {
            let given = if key == "figures" {
                ex.figures.is_some()
            } else {
                ex.tolerance.is_some()
            };
            if given {
                return Err(at(key, format!("{key} is for kind = \"catalogue\" only")));
            }
        }
    }
    let tolerance = ex.tolerance.unwrap_or(catalogue::DEFAULT_TOLERANCE);
    if !(tolerance.is_finite() && tolerance > 0.0 && tolerance < 0.5) {
        return Err(at("tolerance", format!("tolerance = {tolerance} must be in (0, 0.5): the reading tolerance as a fraction of full scale")));
    }
    Ok(tolerance)
}

/// The experiment's CSV recording read from `dir` (a catalogue's with empty cells
/// allowed); `None` only for a catalogue of key figures alone, which needs no file.
fn read_recording(
    dir: &Path,
    ex: &ExperimentSection,
    p_atm_pa: f64,
    at: &impl Fn(&str, String) -> DataError,
) -> Result<Option<Recording>, DataError> {
    let catalogue = ex.kind == Kind::Catalogue;
    Ok(match &ex.file {
        None if !catalogue => {
            return Err(at(
                "kind",
                format!("{} needs a recording: file = \"…\"", ex.kind.id()),
            ))
        }
        None => None,
        Some(file) => {
            let csv = dir.join(file);
            if !csv.is_file() {
                return Err(at(
                    "file",
                    format!(
                        "recording '{file}' not found (looked for {})",
                        csv.display()
                    ),
                ));
            }
            let text = read_text(&csv)?;
            Some(if catalogue {
                Recording::parse_sparse(&csv, &text, p_atm_pa)?
            } else {
                Recording::parse(&csv, &text, p_atm_pa)?
            })
        }
    })
}

/// The experiment's load on the shaft (none where rig.toml gives none).
fn experiment_load(ex: &ExperimentSection) -> Load {
    match ex.load {
        None | Some(LoadSection::None) => Load::None,
        Some(LoadSection::ViscousBrake { c_nm_s_rad }) => Load::ViscousBrake { c_nm_s_rad },
        Some(LoadSection::Torque { t_nm }) => Load::Torque { t_nm },
    }
}

fn locate_toml_error(path: &Path, text: &str, e: &toml::de::Error) -> DataError {
    locate_span(path, text, e.span(), e.message())
}

/// A problem with the TOML text `text` of `path` at the byte range `span` (a parser's or a
/// `toml::Spanned` value's), as a located error: line, column and the offending token.
pub(crate) fn locate_span(
    path: &Path,
    text: &str,
    span: Option<std::ops::Range<usize>>,
    message: &str,
) -> DataError {
    let mut err = DataError::new(path, message.to_string());
    if let Some(span) = span {
        // Spans are byte offsets; never slice inside a character.
        let mut start = span.start.min(text.len());
        while !text.is_char_boundary(start) {
            start -= 1;
        }
        let mut end = span.end.clamp(start, text.len());
        while !text.is_char_boundary(end) {
            end += 1;
        }
        // A span that covers only the start of a bare key (the parser's "duplicate key"
        // points at its first letter) names the whole key.
        let bare = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
        if text[start..end].chars().all(bare) {
            end += text[end..]
                .find(|c: char| !bare(c))
                .unwrap_or(text.len() - end);
        }
        let before = &text[..start];
        let line = before.matches('\n').count() as u64 + 1;
        let col = before[before.rfind('\n').map_or(0, |i| i + 1)..]
            .chars()
            .count();
        err = err.at(line);
        let token: String = text[start..end].trim().chars().take(40).collect();
        err.named = if token.starts_with('[') {
            Named::Table
        } else if text[end..].trim_start().starts_with('=') {
            Named::Key
        } else {
            Named::Value
        };
        err.column = Some((col + 1, token));
    }
    err
}

/// Reads a text file; bytes that are not UTF-8 are refused with their line.
fn read_text(path: &Path) -> Result<String, DataError> {
    let bytes =
        std::fs::read(path).map_err(|e| DataError::new(path, format!("cannot read: {e}")))?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = e.utf8_error().valid_up_to();
        let prefix = &e.as_bytes()[..valid];
        let line = prefix.iter().filter(|b| **b == b'\n').count() as u64 + 1;
        let byte = valid
            - prefix
                .iter()
                .rposition(|b| *b == b'\n')
                .map_or(0, |i| i + 1)
            + 1;
        DataError::new(
            path,
            format!("not UTF-8 text (byte {byte} of the line); save the file as UTF-8"),
        )
        .at(line)
    })
}

/// A table of rig.toml.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Table {
    /// Keys before any table header.
    Top,
    Motor,
    Conditions,
    /// The k-th `[[experiment]]` (0-based).
    Experiment(usize),
}

/// 1-based line and character column of `key = ...` (also inside an inline table) in a
/// table of rig.toml text.
fn key_location(text: &str, table: Table, key: &str) -> Option<(u64, usize)> {
    let mut current = Some(Table::Top);
    let mut experiments = 0;
    let mut header = None;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if t.starts_with("[[") && t[2..].trim_start().starts_with("experiment") {
            current = Some(Table::Experiment(experiments));
            experiments += 1;
        } else if t.starts_with("[experiment.") {
            // A sub-table of the current experiment (its figures).
            current = Some(Table::Experiment(experiments.max(1) - 1));
        } else if t.starts_with("[conditions") {
            current = Some(Table::Conditions);
        } else if t.starts_with("[motor") {
            current = Some(Table::Motor);
        } else if t.starts_with('[') {
            current = None;
        } else if current == Some(table) {
            for (at, _) in line.match_indices(key) {
                let before_ok = line[..at]
                    .chars()
                    .next_back()
                    .is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
                let after_ok = line[at + key.len()..].trim_start().starts_with('=');
                if before_ok && after_ok {
                    return Some((i as u64 + 1, line[..at].chars().count() + 1));
                }
            }
            continue;
        } else {
            continue;
        }
        if current == Some(table) {
            header = Some((i as u64 + 1, 1));
        }
    }
    header
}

/// An error about a key of rig.toml, located at that key (or its table).
fn located(path: &Path, text: &str, table: Table, key: &str, message: String) -> DataError {
    let mut err = DataError::new(path, message);
    if let Some((line, col)) = key_location(text, table, key) {
        err.line = Some(line);
        err.column = Some((col, key.to_string()));
        err.named = Named::Key;
    }
    err
}

fn check_rig(path: &Path, text: &str, rig: &RigFile) -> Result<(), DataError> {
    // The motor is checked here, where its keys can be located, not first by `fit`.
    if let Err(e) = rig.motor.nominal_params().and(rig.motor.gear()) {
        return Err(located(path, text, Table::Motor, e.key(), e.to_string()));
    }
    check_conditions(path, text, &rig.conditions)?;
    if rig.experiment.is_empty() {
        return Err(located(
            path,
            text,
            Table::Top,
            "experiment",
            "no [[experiment]] tables".into(),
        ));
    }
    for (k, ex) in rig.experiment.iter().enumerate() {
        let label = ex.name(k);
        let at =
            |key: &str, message: String| located(path, text, Table::Experiment(k), key, message);
        if let Some(p) = ex.p_supply_mpa {
            if !(p.is_finite() && p * 1e6 > rig.conditions.p_atm_pa && p < 5.0) {
                return Err(at("p_supply_mpa", format!("experiment '{}': p_supply_mpa = {p} must be an absolute pressure above atmosphere and below 5 MPa", label)));
            }
        }
        check_weights(ex, &label, &at)?;
        check_load(ex, &label, &at)?;
    }
    Ok(())
}

/// Refuses an atmosphere outside 50 to 150 kPa or an implausible supply temperature.
fn check_conditions(path: &Path, text: &str, c: &ConditionsSection) -> Result<(), DataError> {
    if !(c.p_atm_pa.is_finite() && (50e3..=150e3).contains(&c.p_atm_pa)) {
        return Err(located(
            path,
            text,
            Table::Conditions,
            "p_atm_pa",
            format!(
                "conditions.p_atm_pa = {} Pa is not a plausible atmosphere (50 to 150 kPa)",
                c.p_atm_pa
            ),
        ));
    }
    if !(c.temperature_k.is_finite() && c.temperature_k > 150.0 && c.temperature_k < 500.0) {
        return Err(located(
            path,
            text,
            Table::Conditions,
            "temperature_k",
            format!(
                "conditions.temperature_k = {} K is not plausible",
                c.temperature_k
            ),
        ));
    }
    Ok(())
}

/// Refuses an experiment's `weight` or channel `weights` that is negative or not finite,
/// and a channel weight naming no channel of the experiment's kind. `label` names the
/// experiment, `at` locates a key's error.
fn check_weights(
    ex: &ExperimentSection,
    label: &str,
    at: &impl Fn(&str, String) -> DataError,
) -> Result<(), DataError> {
    let bad_weight = |w: f64| !(w.is_finite() && w >= 0.0);
    if ex.weight.is_some_and(bad_weight) {
        return Err(at(
            "weight",
            format!("experiment '{}': weight must be finite and >= 0", label),
        ));
    }
    if let Some(weights) = &ex.weights {
        let channels = ex.kind.channels();
        for (name, w) in weights {
            if !channels.iter().any(|q| q.prefix() == name) {
                let known: Vec<_> = channels.iter().map(|q| q.prefix()).collect();
                return Err(at(
                    name,
                    format!(
                        "experiment '{}': weights names '{name}', which is not a channel of {} (channels: {})",
                        label,
                        ex.kind.id(),
                        known.join(", ")
                    ),
                ));
            }
            if bad_weight(*w) {
                return Err(at(
                    name,
                    format!(
                        "experiment '{}': weight of {name} must be finite and >= 0",
                        label
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// Refuses a negative viscous brake or a torque load that is not finite.
fn check_load(
    ex: &ExperimentSection,
    label: &str,
    at: &impl Fn(&str, String) -> DataError,
) -> Result<(), DataError> {
    match ex.load {
        Some(LoadSection::ViscousBrake { c_nm_s_rad })
            if !(c_nm_s_rad.is_finite() && c_nm_s_rad >= 0.0) =>
        {
            Err(at(
                "c_nm_s_rad",
                format!("experiment '{}': load c_nm_s_rad must be >= 0", label),
            ))
        }
        Some(LoadSection::Torque { t_nm }) if !t_nm.is_finite() => Err(at(
            "t_nm",
            format!("experiment '{}': load t_nm must be finite", label),
        )),
        _ => Ok(()),
    }
}

/// Runs one of the input checks of an experiment's kind; `at` locates an error at a key of
/// the experiment's table in rig.toml.
fn check_input(
    ex: &ExperimentData,
    check: InputCheck,
    at: &impl Fn(&str, String) -> DataError,
) -> Result<(), DataError> {
    let rec = &ex.recording;
    match check {
        InputCheck::Column(q) => rec.values(q).map(|_| ()).map_err(DataError::from),
        InputCheck::Spans(q, min_relative_span) => rec.check_spans(q, min_relative_span),
        InputCheck::Supply => {
            if ex.p_supply_pa.is_none() && rec.column(Quantity::PPort1).is_none() {
                // At the experiment's table, where the key belongs (no line of its own).
                return Err(at(
                    "kind",
                    format!(
                        "this {} experiment needs its supply pressure: add p_supply = \"6.3 bar(g)\" (as printed) or p_supply_mpa to its [[experiment]] table, or a p_port1 column to its recording",
                        ex.kind.id()
                    ),
                ));
            }
            Ok(())
        }
        InputCheck::Positive(q, what) => {
            let v = rec.values(q)?;
            if let Some(k) = v.iter().position(|v| *v <= 0.0) {
                let i = rec
                    .columns
                    .iter()
                    .position(|c| c.quantity == q)
                    .unwrap_or(0);
                return Err(DataError::new(&rec.file, format!("{what} must be > 0"))
                    .at(rec.lines[k])
                    .col(i, &rec.columns[i].name));
            }
            Ok(())
        }
    }
}

/// Checks that an experiment has the columns its kind needs; `at` locates an error at a
/// key of its table in rig.toml.
fn check_experiment(
    ex: &ExperimentData,
    at: &impl Fn(&str, String) -> DataError,
) -> Result<(), DataError> {
    let rec = &ex.recording;
    // A catalogue's points are few by nature; its reader checks that it has some.
    if rec.rows() < MIN_ROWS && ex.kind != Kind::Catalogue {
        return Err(DataError::new(
            &rec.file,
            format!(
                "{} data rows are too few for a reference response (need at least {})",
                rec.rows(),
                MIN_ROWS
            ),
        )
        .at(rec.lines.last().copied().unwrap_or(1)));
    }
    let kind = ex.kind.model();
    for check in kind.inputs() {
        check_input(ex, *check, at)?;
    }
    let outputs = kind.channels();
    if !outputs.iter().any(|q| rec.column(*q).is_some()) {
        let names: Vec<_> = outputs.iter().map(|q| q.prefix()).collect();
        return Err(DataError::new(
            &rec.file,
            format!(
                "{} has no measured channel (expected one of: {})",
                ex.kind.id(),
                names.join(", ")
            ),
        )
        .at(1));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Recording, DataError> {
        Recording::parse(Path::new("x.csv"), text, 101_325.0)
    }

    #[test]
    fn decimal_commas_with_comma_separators_are_named_at_their_line() {
        let text = "t_s,p_port1_mpa\n0.0,0.1\n0,1,0,2\n";
        let e = Recording::parse(Path::new("r.csv"), text, 101325.0).unwrap_err();
        let m = e.to_string();
        assert!(m.starts_with("r.csv:3"), "{m}");
        assert!(m.contains("4 fields where the header has 2"), "{m}");
        assert!(m.contains("decimal comma"), "{m}");
    }

    #[test]
    fn other_separators_are_named_not_read_as_one_column() {
        let e = parse("t_s;speed_rpm;torque_nm\n0;1,5;0,2\n").unwrap_err();
        assert_eq!(e.line, Some(1));
        assert!(
            e.to_string().contains("separated by semicolons (2 found"),
            "{e}"
        );
        let e = parse("t_s\tspeed_rpm\n0\t1.5\n").unwrap_err();
        assert!(e.to_string().contains("separated by tabs"), "{e}");
        // One column needs no separator.
        assert!(parse("t_s\n0\n0.1\n0.2\n").is_ok());
    }

    #[test]
    fn crlf_errors_name_the_bad_line() {
        let e = parse("t_s,flow1_g_s\r\n0,1.0\r\n0.1,abc\r\n0.2,1.0\r\n").unwrap_err();
        assert_eq!(e.line, Some(3), "{e}");
        let e = parse("t_s,flow1_g_s\r\n0,1.0\r\n0.1,1.0\r\n0.1,1.0\r\n").unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse("t_s,flow1_g_s\n0,1.0\n0.1,abc\n").unwrap_err();
        assert_eq!(
            (e.line, e.column.clone()),
            (Some(3), Some((2, "flow1_g_s".into())))
        );
        assert_eq!(
            e.to_string(),
            "x.csv:3:2 (column 'flow1_g_s'): 'abc' is not a number (use '.' as decimal mark)"
        );
        let e = parse("t_s,flow1_g_s\n0,1.0\n0,2\n").unwrap_err();
        assert_eq!(e.line, Some(3));
        assert!(e.message.contains("time does not increase"));
        let e = parse("t_s,flow1_furlongs\n0,1\n").unwrap_err();
        assert!(e.message.contains("unknown unit 'furlongs'"), "{e}");
        assert!(parse("").unwrap_err().message.contains("empty"));
        assert!(parse("t_s,flow1_g_s\n")
            .unwrap_err()
            .message
            .contains("no data rows"));
        assert!(parse("t_s,flow1_g_s\n0,NaN\n")
            .unwrap_err()
            .message
            .contains("finite"));
    }

    #[test]
    fn cells_are_kept_as_written() {
        let text = "speed_rpm,torque_nm\n 1.50 ,\n2e3,0.25\n";
        let r = Recording::parse_sparse(Path::new("x.csv"), text, 101_325.0).unwrap();
        let speed = &r.columns[0].raw;
        assert_eq!(
            (speed.len(), &speed[0], speed.get(1)),
            (2, "1.50", Some("2e3"))
        );
        assert_eq!(speed.get(2), None);
        let torque: Vec<&str> = r.columns[1].raw.iter().collect();
        assert_eq!(torque, ["", "0.25"]);
        let cells: Cells = ["a", "", "bc"].into_iter().collect();
        assert_eq!(cells.to_strings(), ["a", "", "bc"]);
        assert_eq!(cells, ["a", "", "bc"].into_iter().collect::<Cells>());
    }

    /// A rig.toml value with a decimal comma is refused at its key, naming the comma.
    #[test]
    fn a_decimal_comma_in_rig_toml_is_named_at_its_key() {
        let dir = tempfile::tempdir().unwrap();
        let from = Path::new("measurements/ar034-synthetic-catalogue");
        for e in std::fs::read_dir(from).unwrap().flatten() {
            std::fs::copy(e.path(), dir.path().join(e.file_name())).unwrap();
        }
        let rig = dir.path().join("rig.toml");
        let text = std::fs::read_to_string(&rig).unwrap();
        let line = text
            .lines()
            .position(|l| l.starts_with("p_supply"))
            .unwrap()
            + 1;
        std::fs::write(&rig, text.replacen("\"6.3 bar(g)\"", "\"6,3 bar(g)\"", 1)).unwrap();
        let e = Dataset::load(dir.path()).unwrap_err().to_string();
        let want = format!(
            "rig.toml:{line}:1 (key 'p_supply'): p_supply: '6,3 bar(g)' is written with a \
             decimal comma: write the decimal mark as a point ('6.3 bar(g)')"
        );
        assert!(e.ends_with(&want), "{e}");
    }

    #[test]
    fn gauge_pressure_uses_rig_atmosphere() {
        let r =
            Recording::parse(Path::new("x.csv"), "t_s,p_port1_bar_g\n0,6.0\n", 95_000.0).unwrap();
        assert!((r.values(Quantity::PPort1).unwrap()[0] - 695_000.0).abs() < 1e-9);
    }
}
