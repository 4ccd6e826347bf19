//! `vanefit export-petab` (SPEC §7): a fit as a PEtab v1 problem.

use crate::cli::Failure;
use crate::data::dataset::Dataset;
use crate::data::fitfile::FitFile;
use crate::export::petab;
use crate::io::say;
use clap::Args;
use std::path::{Path, PathBuf};

/// Options of `vanefit export-petab`.
#[derive(Args, Debug)]
pub struct ExportPetabArgs {
    /// Fit file written by `vanefit fit` (vanefit.fit/1).
    pub fit: PathBuf,
    /// The dataset the fit was made from; omitted: `measurements/<its name>` beside the fit
    /// file's folder, or in the current folder.
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Output folder: parameters.tsv, observables.tsv, measurements.tsv, conditions.tsv,
    /// model.xml, problem.yaml and vanefit_export.json.
    #[arg(long)]
    pub out: PathBuf,
}

/// Why the export cannot start.
#[derive(Debug, thiserror::Error)]
pub enum ExportCommandError {
    /// No dataset given and none found where fits usually sit.
    #[error("{fit}: dataset '{name}' not found at {tried}; name it with --dataset")]
    NoDataset {
        /// The fit file.
        fit: String,
        /// The dataset name the fit file gives.
        name: String,
        /// The folders looked in.
        tried: String,
    },
    /// `--out` is a file.
    #[error("--out {0}: is a file, not a folder")]
    OutIsFile(String),
}

/// Runs `vanefit export-petab`.
pub fn run(args: &ExportPetabArgs) -> Result<(), Failure> {
    if args.out.is_file() {
        return Err(ExportCommandError::OutIsFile(args.out.display().to_string()).into());
    }
    // Checked now without writing (nothing is written when an input is bad), created and
    // locked once the tables are made.
    crate::io::out::check_dir(&args.out)?;
    let fit = FitFile::read(&args.fit)?;
    let dir = match &args.dataset {
        Some(d) => d.clone(),
        None => find_dataset(&args.fit, &fit.dataset)?,
    };
    let ds = Dataset::load(&dir)?;
    let (tables, summary) = petab::tables(&ds, &fit, &args.fit)?;
    let _lock = crate::io::out::prepare_dir(&args.out)?;
    petab::write(&args.out, &tables)?;
    say!(
        "PEtab problem of {} on {}: {} measurements, {} observables, {} conditions",
        args.fit.display(),
        dir.display(),
        summary.measurements,
        summary.observables,
        summary.conditions
    );
    say!(
        "likelihood chi2 at the fit: {:.6} (rows {:.6} + nuisance priors {:.6}; statistics.likelihood_chi2 of the fit file)",
        summary.chi2_rows + summary.chi2_priors,
        summary.chi2_rows,
        summary.chi2_priors
    );
    say!("wrote {}", args.out.join("problem.yaml").display());
    Ok(())
}

/// `measurements/<name>` beside the fit file's folder (fits/x.json → measurements/name),
/// then in the current folder.
fn find_dataset(fit: &Path, name: &str) -> Result<PathBuf, ExportCommandError> {
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
        .ok_or_else(|| ExportCommandError::NoDataset {
            fit: fit.display().to_string(),
            name: name.to_string(),
            tried: candidates
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        })
}
