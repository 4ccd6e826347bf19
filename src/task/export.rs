//! `export-petab` as a task: the dataset a fit was made from (`find_dataset`) and the
//! fit as a PEtab v1 problem ([`petab_problem`]), written by `export::petab::write`; the
//! fit as an FMU ([`export_fmu`]).

use crate::data::dataset::{DataError, Dataset};
use crate::data::fitfile::{FitFile, FitFileError};
use crate::data::locate::{locate_dataset, Located};
use crate::export::petab::{self, PetabError, PetabSummary, PetabTables};
use crate::task::Opt;
use std::path::{Path, PathBuf};

/// Why the export failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// No dataset given and none found where fits usually sit.
    #[error("{}", no_dataset(.fit, .name, .tried, *.option, &Opt::field))]
    NoDataset {
        /// The fit file.
        fit: String,
        /// The dataset name the fit file gives.
        name: String,
        /// The folders looked in.
        tried: String,
        /// The option that names the dataset.
        option: Opt,
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

/// The message of [`ExportError::NoDataset`], its option called `name(option)`.
fn no_dataset(
    fit: &str,
    dataset: &str,
    tried: &str,
    option: Opt,
    name: &dyn Fn(Opt) -> &'static str,
) -> String {
    format!(
        "{fit}: dataset '{dataset}' not found at {tried}; name it with {}",
        name(option)
    )
}

impl ExportError {
    /// The message with the option it names called `name(option)` (e.g. the command line's
    /// flag); [`std::fmt::Display`] names it by the task's argument.
    pub fn message_with(&self, name: &dyn Fn(Opt) -> &'static str) -> String {
        match self {
            Self::NoDataset {
                fit,
                name: dataset,
                tried,
                option,
            } => no_dataset(fit, dataset, tried, *option, name),
            other => other.to_string(),
        }
    }
}

/// The dataset `fit` (read from `fit_path`) was made from, by the rule `predict` follows
/// ([`crate::data::locate`]): its recorded `dataset_path`, else `measurements/<name>` beside
/// the fit file's folder, then in the current folder.
fn find_dataset(fit_path: &Path, fit: &FitFile) -> Result<PathBuf, ExportError> {
    match locate_dataset(Some(fit_path), fit) {
        Located::Found(dir, _) => Ok(dir),
        Located::Missing { tried, recorded } => {
            let mut tried: Vec<String> = tried.iter().map(|p| p.display().to_string()).collect();
            if tried.is_empty() {
                tried.push("nothing (the fit file names no dataset)".into());
            }
            let mut tried = tried.join(", ");
            if let Some(why) = recorded {
                tried.push_str(&format!(" ({why})"));
            }
            Err(ExportError::NoDataset {
                fit: fit_path.display().to_string(),
                name: fit.dataset.clone(),
                tried,
                option: Opt::ExportDataset,
            })
        }
    }
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
        None => find_dataset(fit_path, &fit)?,
    };
    let ds = Dataset::load(&dir)?;
    let (tables, summary) = petab::tables(&ds, &fit, fit_path)?;
    Ok(PetabProblem {
        dataset: dir,
        tables,
        summary,
    })
}

/// Options of `export-fmu`: the fit file, the FMU to write, and where the FMU's shared
/// library is (`None`: `$VANEFIT_FMU_BINARY`, else beside the running executable).
#[derive(Debug, Clone)]
pub struct FmuOptions {
    /// The fit file (vanefit.fit/1).
    pub fit: PathBuf,
    /// The fit file's text when the fit is held in memory (the Python package's `Fit`):
    /// packed instead of the file's, `fit` then only names it in messages.
    pub fit_text: Option<String>,
    /// The FMU to write.
    pub out: PathBuf,
    /// The shared library built from the `fmu/` crate.
    pub binary: Option<PathBuf>,
}

/// What `export-fmu` wrote.
#[derive(Debug, Clone)]
pub struct FmuExport {
    /// The shared library packed.
    pub binary: PathBuf,
    /// Sizes, counts and GUID.
    pub summary: crate::export::fmu::package::FmuSummary,
}

/// Writes the FMU of a fit (docs/fmu.md): refuses an effect it cannot represent, finds the
/// shared library, packs description, library and fit (temporary file, then rename).
pub fn export_fmu(opts: &FmuOptions) -> Result<FmuExport, crate::export::fmu::FmuError> {
    use crate::export::fmu::package::{find_binary, write_fmu, write_fmu_of, BINARY_ENV};
    // The fit is read and checked before the library is looked for: a fit the FMU cannot
    // represent is the more useful message.
    let fit = match &opts.fit_text {
        Some(text) => FitFile::parse(&opts.fit, text)?,
        None => FitFile::read(&opts.fit)?,
    };
    crate::export::fmu::variables::model_parameters(&fit)?;
    let binary = match &opts.binary {
        Some(b) => find_binary(Some(b.clone()), None)?,
        None => {
            let env = std::env::var_os(BINARY_ENV).map(PathBuf::from);
            let exe = std::env::current_exe().ok();
            find_binary(env, exe.as_deref())?
        }
    };
    let summary = match &opts.fit_text {
        Some(text) => write_fmu_of(&opts.fit, text.as_bytes(), &binary, &opts.out)?,
        None => write_fmu(&opts.fit, &binary, &opts.out)?,
    };
    Ok(FmuExport { binary, summary })
}
