//! `vanefit diagnose` (SPEC §6).

use crate::cli::Failure;
use crate::data::dataset::Dataset;
use crate::diagnose::{summary, DiagnoseObserver, DiagnoseOptions, Progress};
use crate::estimate::Engine;
use crate::io::say;
use crate::task::diagnose::diagnose_dataset_to;
pub use crate::task::diagnose::DiagnoseArgs;

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
    // The output is checked, then the data (so bad data leaves no folder behind), then the
    // output is created and locked: all before the diagnosis, which takes tens of seconds.
    crate::io::out::check_dir(&args.out)?;
    let ds = Dataset::load(&args.dataset)?;
    let _lock = crate::io::out::prepare_dir(&args.out)?;
    let opts = DiagnoseOptions::full(args.starts, args.seed);
    let engine = Engine::with_threads(opts.threads)?;
    let d = diagnose_dataset_to(&engine, &ds, &opts, &StderrProgress, &args.out)?;
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
