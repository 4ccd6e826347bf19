//! Predict the shipped fit at other supply pressures: catalogue figures with 95 % bands.
//!
//! `cargo run --release --example predict_fit`

use std::path::Path;
use vanefit::prelude::*;
use vanefit::task::fit_atmosphere_pa;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("fits/ar034-synthetic.json");
    let fit = FitFile::read(&path)?;

    // Pressures in the options' unit (bar gauge here); checked at the fit's atmosphere.
    let settings = PredictOptions {
        unit: Unit::BarG,
        pressures: Some(vec![4.0, 5.0, 6.3]),
        ..PredictOptions::default()
    }
    .check(fit_atmosphere_pa(&fit))?;
    let prediction = vanefit::predict(&fit, &settings)?;

    // The same tables `vanefit predict` prints.
    let display = settings.display();
    println!(
        "{}",
        vanefit::report::predict::tables_markdown(&prediction, display)
    );
    Ok(())
}
