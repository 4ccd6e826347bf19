//! Fits the shipped dataset through the library and prints the parameter table.
//!
//! `cargo run --release --example fit_shipped [starts]` (default 8 starts; the command line's
//! `vanefit fit` does the same with 32 starts, results files and plots).

use std::path::Path;
use vanefit::data::Dataset;
use vanefit::estimate::multistart::Silent;
use vanefit::estimate::{fit, FitData, FitSetup, UncertaintyMethod};
use vanefit::estimate::{Engine, MultiStartConfig, ParamSpace, DEFAULT_ESTIMATED};
use vanefit::model::EffectSet;
use vanefit::objective::CostOptions;
use vanefit::report::fit::{parameter_rows, terminal_table};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let starts = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 8,
    };
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("measurements/ar034-synthetic");
    let ds = Dataset::load(&dir)?;
    let data = FitData::new(&ds, CostOptions::default())?;
    let space = ParamSpace::new(&DEFAULT_ESTIMATED, ds.nominal_params()?, EffectSet::empty())?;
    let setup = FitSetup {
        space,
        multistart: MultiStartConfig {
            starts,
            seed: 1,
            ..MultiStartConfig::default()
        },
        uncertainty: UncertaintyMethod::Curvature,
        results_file: None,
        resume: false,
    };
    let engine = Engine::with_threads(None)?;
    let out = fit(&engine, &data, &setup, &Silent)?;
    println!(
        "{}: cost {:.4} after {} evaluations",
        ds.name, out.cost, out.evaluations
    );
    // Each parameter with its meaning; conductances in m3/(s*Pa) and dm3/(s*bar).
    for line in terminal_table(&parameter_rows(&ds, &setup, &out)) {
        println!("{line}");
    }
    Ok(())
}
