//! `vanefit export-petab` (docs/cli.md, "export-petab"): a fit as a PEtab v1 problem.

use crate::cli::Failure;
use clap::Args;
use std::path::PathBuf;
use vanefit::export::petab;
use vanefit::task::petab_problem;

/// Options of `vanefit export-petab`.
#[derive(Args, Debug)]
pub(crate) struct ExportPetabArgs {
    /// Fit file written by `vanefit fit` (vanefit.fit/1).
    pub(crate) fit: PathBuf,
    /// The dataset the fit was made from; omitted: the one the fit file records
    /// (`dataset_path`), else `measurements/<its name>` beside the fit file's folder, or in
    /// the current folder (as predict finds it).
    #[arg(long)]
    pub(crate) dataset: Option<PathBuf>,
    /// Output folder: parameters.tsv, observables.tsv, measurements.tsv, conditions.tsv,
    /// model.xml, problem.yaml and vanefit_export.json.
    #[arg(long)]
    pub(crate) out: PathBuf,
}

/// Runs `vanefit export-petab`.
pub(crate) fn run(args: &ExportPetabArgs) -> Result<(), Failure> {
    if args.out.is_file() {
        return Err(Failure(format!(
            "--out {}: is a file, not a folder",
            args.out.display()
        )));
    }
    // Checked now without writing (nothing is written when an input is bad), created and
    // locked once the tables are made.
    vanefit::io::check_dir(&args.out)?;
    let problem = petab_problem(&args.fit, args.dataset.as_deref()).map_err(Failure::export)?;
    let _lock = vanefit::io::prepare_dir(&args.out)?;
    petab::write(&args.out, &problem.tables)?;
    let summary = &problem.summary;
    say!(
        "PEtab problem of {} on {}: {} measurements, {} observables, {} conditions",
        args.fit.display(),
        problem.dataset.display(),
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
    say!(
        "objective at the fit: {:.6} (+ motor priors {:.6}; statistics.likelihood_chi2 + statistics.prior_chi2)",
        summary.objective(),
        summary.chi2_motor_priors
    );
    say!("wrote {}", args.out.join("problem.yaml").display());
    Ok(())
}

/// Options of `vanefit export-fmu`.
#[derive(Args, Debug)]
pub(crate) struct ExportFmuArgs {
    /// Fit file written by `vanefit fit` or `vanefit diagnose` (vanefit.fit/1).
    pub(crate) fit: PathBuf,
    /// The FMU to write (FMI 2.0, model exchange and co-simulation, linux64).
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// The FMU's shared library (libvanefit_fmu.so); omitted: $VANEFIT_FMU_BINARY, else
    /// beside the vanefit executable.
    #[arg(long)]
    pub(crate) binary: Option<PathBuf>,
}

/// Runs `vanefit export-fmu`.
pub(crate) fn run_fmu(args: &ExportFmuArgs) -> Result<(), Failure> {
    if args.out.is_dir() {
        return Err(Failure(format!(
            "--out {}: is a folder, not a file",
            args.out.display()
        )));
    }
    let done = vanefit::task::export_fmu(&vanefit::task::FmuOptions {
        fit: args.fit.clone(),
        fit_text: None,
        out: args.out.clone(),
        binary: args.binary.clone(),
    })?;
    let s = &done.summary;
    say!(
        "FMU (FMI 2.0, model exchange and co-simulation) of {}: {} variables, {} tunable model parameters, {} bytes, GUID {}",
        args.fit.display(),
        s.variables,
        s.model_parameters,
        s.bytes,
        s.guid
    );
    say!("binary {}", done.binary.display());
    say!("wrote {}", args.out.display());
    Ok(())
}
