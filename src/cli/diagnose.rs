//! `vanefit diagnose` (SPEC §6).

use crate::cli::Failure;
use crate::data::dataset::Dataset;
use crate::diagnose::{diagnose_observed, summary, DiagnoseObserver, DiagnoseOptions, Progress};
use crate::estimate::Engine;
use std::path::PathBuf;

/// `vanefit diagnose` options (SPEC §6).
#[derive(clap::Args, Debug, Clone)]
pub struct DiagnoseArgs {
    /// Dataset folder (rig.toml and recordings).
    pub dataset: PathBuf,
    /// Start points of the baseline fit: the rig's nominal motor plus Latin-hypercube starts.
    #[arg(long, default_value_t = 4)]
    pub starts: usize,
    /// Seed of the start designs; a seed gives the same result whatever the thread count.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder: diagnosis.json, report.md and its SVG plots.
    #[arg(long)]
    pub out: PathBuf,
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
pub fn run(args: &DiagnoseArgs) -> Result<(), Failure> {
    if args.starts == 0 {
        return Err(Failure("--starts must be at least 1".into()));
    }
    let ds = Dataset::load(&args.dataset)?;
    let opts = DiagnoseOptions::full(args.starts, args.seed);
    let engine = Engine::with_threads(opts.threads)?;
    let d = diagnose_observed(&ds, &opts, &engine, &StderrProgress)?;
    crate::report::diagnose::write_all(&d, &args.out)?;
    println!("{}", summary(&d));
    println!(
        "wrote {} and {} ({:.1} s on {} thread(s))",
        args.out.join("diagnosis.json").display(),
        args.out.join("report.md").display(),
        d.wall_s,
        d.threads
    );
    Ok(())
}
