//! `export-petab` as a task: the dataset a fit was made from (`find_dataset`) and the
//! fit as a PEtab v1 problem ([`petab_problem`]), written by `export::petab::write`.

use crate::data::dataset::{DataError, Dataset};
use crate::data::fitfile::{FitFile, FitFileError};
use crate::export::petab::{self, PetabError, PetabSummary, PetabTables};
use std::path::{Path, PathBuf};

/// Why the export failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// No dataset given and none found where fits usually sit.
    #[error("{fit}: dataset '{name}' not found at {tried}; name it with {field}")]
    NoDataset {
        /// The fit file.
        fit: String,
        /// The dataset name the fit file gives.
        name: String,
        /// The folders looked in.
        tried: String,
        /// The option that names the dataset.
        field: &'static str,
    },
    /// The fit file cannot be read.
    #[error(transparent)]
    FitFile(#[from] FitFileError),
    /// The dataset cannot be read.
    #[error(transparent)]
    Data(#[from] DataError),
    /// The tables cannot be made or written.
    #[error(transparent)]
    Petab(#[from] PetabError),
}

/// `measurements/<name>` beside the fit file's folder (fits/x.json → measurements/name),
/// then in the current folder.
fn find_dataset(fit: &Path, name: &str) -> Result<PathBuf, ExportError> {
    let beside = fit
        .parent()
        .and_then(Path::parent)
        .map(|p| p.join("measurements").join(name));
    let here = Path::new("measurements").join(name);
    let candidates: Vec<PathBuf> = beside.into_iter().chain([here]).collect();
    candidates
        .iter()
        .find(|p| p.join("rig.toml").is_file())
        .cloned()
        .ok_or_else(|| ExportError::NoDataset {
            fit: fit.display().to_string(),
            name: name.to_string(),
            tried: candidates
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            field: "`dataset`",
        })
}

/// A fit as a PEtab problem, not yet written.
pub struct PetabProblem {
    /// The dataset folder the fit was evaluated on.
    pub dataset: PathBuf,
    /// The tables.
    pub tables: PetabTables,
    /// Counts and χ² at the fit.
    pub summary: PetabSummary,
}

/// Reads the fit file at `fit_path` and its dataset (`dataset`, or else found with
/// `find_dataset`) and makes the PEtab tables.
pub fn petab_problem(fit_path: &Path, dataset: Option<&Path>) -> Result<PetabProblem, ExportError> {
    let fit = FitFile::read(fit_path)?;
    let dir = match dataset {
        Some(d) => d.to_path_buf(),
        None => find_dataset(fit_path, &fit.dataset)?,
    };
    let ds = Dataset::load(&dir)?;
    let (tables, summary) = petab::tables(&ds, &fit, fit_path)?;
    Ok(PetabProblem {
        dataset: dir,
        tables,
        summary,
    })
}
