//! Recordings and experiments in memory: what a rig file and its CSV recordings describe,
//! converted to SI (the files themselves are read in `data`).

use crate::model::motor::Load;
use crate::units::{Quantity, Unit};
use std::path::PathBuf;

/// A channel that an experiment needs is not in its recording.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}:1: {}", .file.display(), missing_message(*.quantity))]
pub struct MissingColumn {
    /// The recording.
    pub file: PathBuf,
    /// The quantity without a column.
    pub quantity: Quantity,
}

impl MissingColumn {
    /// The message without the file: what is missing and an example column name.
    pub fn message(&self) -> String {
        missing_message(self.quantity)
    }
}

/// "missing column for q (e.g. 'q_unit')".
fn missing_message(q: Quantity) -> String {
    format!(
        "missing column for {} (e.g. '{}_{}')",
        q.prefix(),
        q.prefix(),
        q.si_unit().suffix()
    )
}

/// One column of a recording, converted to SI.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Name as written in the file's header.
    pub name: String,
    /// The quantity the name stands for.
    pub quantity: Quantity,
    /// The unit the values are written in.
    pub unit: Unit,
    /// Values in SI, one per data row.
    pub si: Vec<f64>,
    /// Values as written in the file (kept so exports can copy input columns verbatim).
    pub raw: Cells,
}

/// The cells of a column as written, in one buffer with the end of each cell: a recording
/// of a million rows would otherwise hold millions of small strings (each a 24-byte handle
/// and a heap block of 32 bytes for some ten bytes of text; 0.8 GB resident for `check` of
/// a 100 MB file). Indexing gives the cell's text (`raw[k]` is a `&str`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Cells {
    text: String,
    /// Where each cell ends in `text` (it starts where the one before ends). Four bytes
    /// each: a column's text is at most its file's, and readers refuse files from 4 GiB.
    ends: Vec<u32>,
}

impl Cells {
    /// The most text a column may hold (bytes), since cell ends are kept in 32 bits.
    pub(crate) const MAX_TEXT: usize = u32::MAX as usize;

    /// No cells yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// No cells yet, with room for `cells` cells of `bytes` bytes of text in all (the
    /// reader knows both from its file, so the buffers grow once).
    pub fn with_capacity(cells: usize, bytes: usize) -> Self {
        Self {
            text: String::with_capacity(bytes),
            ends: Vec::with_capacity(cells),
        }
    }

    /// Appends a cell. Panics if the column's text would pass `Cells::MAX_TEXT`: the
    /// readers refuse larger files first, with a message naming the file.
    pub fn push(&mut self, cell: &str) {
        self.text.push_str(cell);
        let end = u32::try_from(self.text.len()).expect("a column's text within 4 GiB");
        self.ends.push(end);
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// No cells.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// The k-th cell as written, if there is one.
    pub fn get(&self, k: usize) -> Option<&str> {
        let end = *self.ends.get(k)? as usize;
        let start = k.checked_sub(1).map_or(0, |j| self.ends[j] as usize);
        Some(&self.text[start..end])
    }

    /// The cells in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &str> + '_ {
        (0..self.len()).map(|k| &self[k])
    }

    /// The cells as owned strings (for callers that keep them apart from the recording).
    #[cfg(test)]
    pub(crate) fn to_strings(&self) -> Vec<String> {
        self.iter().map(str::to_owned).collect()
    }
}

impl std::ops::Index<usize> for Cells {
    type Output = str;
    /// The k-th cell; panics beyond the last, as a slice does.
    fn index(&self, k: usize) -> &str {
        match self.get(k) {
            Some(cell) => cell,
            None => panic!("cell {k} of a column of {} cells", self.len()),
        }
    }
}

impl<S: AsRef<str>> FromIterator<S> for Cells {
    fn from_iter<I: IntoIterator<Item = S>>(cells: I) -> Self {
        let mut out = Cells::new();
        for c in cells {
            out.push(c.as_ref());
        }
        out
    }
}

/// A CSV recording: columns in file order, all of equal length.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// The CSV file.
    pub file: PathBuf,
    /// Every column, in file order.
    pub columns: Vec<Column>,
    /// Line number of each data row (header is line 1).
    pub lines: Vec<u64>,
}

impl Recording {
    /// Number of data rows.
    pub fn rows(&self) -> usize {
        self.lines.len()
    }
    /// The column of a quantity, if recorded.
    pub fn column(&self, q: Quantity) -> Option<&Column> {
        self.columns.iter().find(|c| c.quantity == q)
    }
    /// The SI values of a column that must be present.
    pub fn values(&self, q: Quantity) -> Result<&[f64], MissingColumn> {
        self.column(q)
            .map(|c| c.si.as_slice())
            .ok_or_else(|| MissingColumn {
                file: self.file.clone(),
                quantity: q,
            })
    }
}

/// The experiment kinds (docs/model.md, "Reference experiments"; defined by the registry of
/// `sim::experiment`).
pub use crate::sim::experiment::Kind;

/// One experiment as the rig file describes it, with its recording.
#[derive(Debug, Clone)]
pub struct ExperimentData {
    /// The kind of experiment.
    pub kind: Kind,
    /// File name as given in rig.toml.
    pub file: String,
    /// Supply pressure from rig.toml (`p_supply_mpa` or `p_supply`), absolute Pa.
    pub p_supply_pa: Option<f64>,
    /// The supply pressure as written (`p_supply = "90 psi(g)"`), for people.
    pub p_supply_written: Option<String>,
    /// The rig.toml line of `p_supply`, for warnings about how it was read.
    pub p_supply_line: Option<u64>,
    /// Load on the shaft.
    pub load: Load,
    /// Weight of the whole experiment in the cost (default 1).
    pub weight: f64,
    /// Weight per channel prefix (e.g. "flow1"), default 1.
    pub(crate) channel_weights: std::collections::BTreeMap<String, f64>,
    /// The recording, converted to SI (a catalogue's rows may leave cells empty: NaN).
    pub recording: Recording,
    /// Relative reading tolerance of stated (not recorded) data: each channel's σ is this
    /// fraction of its full scale instead of a noise estimate (catalogues).
    pub tolerance: Option<f64>,
    /// Key figures of a catalogue as printed (they are also rows of the recording).
    pub figures: Vec<Figure>,
}

/// A catalogue's key figure as printed.
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    /// Its key in rig.toml (`free_speed`, `max_power`, …).
    pub key: String,
    /// Its quantity.
    pub quantity: Quantity,
    /// The unit it was printed in.
    pub unit: Unit,
    /// Its value, SI.
    pub si: f64,
    /// The number as written.
    pub written: f64,
    /// Its line in rig.toml, where known.
    pub line: Option<u64>,
}
