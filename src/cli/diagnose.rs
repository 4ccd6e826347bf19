//! `vanefit diagnose` (SPEC §6).

use crate::data::dataset::Dataset;
use crate::diagnose::{diagnose, summary, DiagnoseOptions};
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

/// `vanefit diagnose`.
pub fn run(args: &DiagnoseArgs) -> Result<(), String> {
    if args.starts == 0 {
        return Err("--starts must be at least 1".into());
    }
    let ds = Dataset::load(&args.dataset).map_err(|e| e.to_string())?;
    let d = diagnose(&ds, &DiagnoseOptions::full(args.starts, args.seed))?;
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
