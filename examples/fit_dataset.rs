//! Fit a dataset through the front door: options, check, fit, files.
//!
//! `cargo run --release --example fit_dataset [starts] [out.json]` (default 8 starts; with
//! an output path the fit file, report and plots are written as `vanefit fit` writes them).

use std::path::{Path, PathBuf};
use vanefit::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let starts = args.next().map_or(Ok(8), |s| s.parse())?;
    let dataset = Path::new(env!("CARGO_MANIFEST_DIR")).join("measurements/ar034-synthetic");

    // Options are plain data; check() refuses a bad value, naming the field.
    let settings = FitOptions {
        starts,
        uncertainty: UncertaintyMethod::Curvature,
        ..FitOptions::default()
    }
    .check()?;
    let fit = vanefit::fit(&dataset, &settings, None, &Silent)?;

    let o = &fit.outcome;
    println!(
        "chi2 {:.1} over {} points, cost J {:.4}",
        o.chi2, o.n_points, o.cost
    );
    for i in &o.intervals {
        let end = |v: Option<f64>| v.map_or("open".to_string(), |v| format!("{v:.4e}"));
        println!(
            "  {:<10} {:.4e}  [{}, {}]",
            i.name,
            i.value,
            end(i.lo),
            end(i.hi)
        );
    }
    if let Some(out) = args.next().map(PathBuf::from) {
        let written = vanefit::write_fit(&fit, &out, true)?;
        println!("wrote {} and {}", out.display(), written.report.display());
    }
    Ok(())
}
