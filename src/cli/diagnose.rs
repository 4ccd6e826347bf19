//! `vanefit diagnose` (docs/cli.md, "diagnose"): the options and what is printed; the work is
//! `vanefit::task::diagnose`.

use crate::cli::Failure;
use std::path::PathBuf;
use vanefit::data::Dataset;
use vanefit::diagnose::{summary, DiagnoseObserver, Progress};
use vanefit::estimate::Engine;
use vanefit::task::{diagnose_dataset, write_diagnosis, DiagnoseOptions};

/// `vanefit diagnose` options.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct DiagnoseArgs {
    /// Dataset folder (rig.toml and recordings).
    pub(crate) dataset: PathBuf,
    /// Start points of the baseline fit: the rig's nominal motor plus Latin-hypercube starts.
    #[arg(long, default_value_t = 4, value_parser = crate::cli::at_least_one)]
    pub(crate) starts: usize,
    #[command(flatten)]
    pub(crate) run: crate::cli::RunArgs,
    /// Output folder: diagnosis.json, report.md and its SVG plots.
    #[arg(long)]
    pub(crate) out: PathBuf,
}

/// Prints a diagnosis's progress on stderr, one line per event with the time since the
/// start: `[  21.5 s] concealment: ...`.
struct StderrProgress;

impl DiagnoseObserver for StderrProgress {
    fn progress(&self, elapsed_s: f64, event: &Progress<'_>) {
        eprintln!("[{elapsed_s:6.1} s] {event}");
    }
}

/// `vanefit diagnose`.
pub(crate) fn run(args: &DiagnoseArgs) -> Result<(), Failure> {
    let settings = DiagnoseOptions {
        starts: args.starts,
        seed: args.run.seed,
        threads: args.run.threads,
        ..DiagnoseOptions::default()
    }
    .check()
    .map_err(Failure::option)?;
    // The output is checked, then the data (so bad data leaves no folder behind), then the
    // output is created and locked: all before the diagnosis, which takes tens of seconds.
    vanefit::io::check_dir(&args.out)?;
    let ds = Dataset::load(&args.dataset)?;
    let _lock = vanefit::io::prepare_dir(&args.out)?;
    let engine = Engine::with_threads(settings.threads())?;
    let d = diagnose_dataset(&engine, &ds, &settings, &StderrProgress)?;
    write_diagnosis(&d, &args.out)?;
    say!("{}", summary(&d));
    say!(
        "wrote {} and {} ({:.1} s on {} thread(s))",
        args.out.join("diagnosis.json").display(),
        args.out.join("report.md").display(),
        d.wall_s,
        d.threads
    );
    Ok(())
}
