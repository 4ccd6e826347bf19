//! Find the physics a model leaves out: diagnose a dataset, print the verdict.
//!
//! `cargo run --release --example diagnose_dataset [dataset] [out-folder]` (default the
//! shipped dataset, quick effort; with a folder, `vanefit diagnose`'s files are written).

use std::path::PathBuf;
use vanefit::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dataset = args.next().map(PathBuf::from).unwrap_or_else(|| {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("measurements/ar034-synthetic")
    });
    let settings = DiagnoseOptions {
        starts: 1,
        effort: Effort::Quick,
        ..DiagnoseOptions::default()
    }
    .check()?;
    let d = vanefit::diagnose(&dataset, &settings, &Silent)?;
    println!("{}", vanefit::diagnose::summary(&d));
    if let Some(out) = args.next().map(PathBuf::from) {
        vanefit::write_diagnosis(&d, &out)?;
        println!("wrote {}", out.join("report.md").display());
    }
    Ok(())
}
