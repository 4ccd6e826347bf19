//! χ² of the likelihood at a dataset's truth.json against the fit's estimate (a probe of
//! calibration: do the 95 % intervals hold the truth 95 % of the time?): `cargo run
//! --release --example chi2_at_truth -- DATASET FIT.json`. Under a correct likelihood
//! χ²(truth) − χ²(estimate) follows χ²(k), k estimated parameters.

use std::path::Path;
use vanefit::data::Dataset;
use vanefit::data::FitFile;
use vanefit::estimate::FitData;
use vanefit::model::Motor;
use vanefit::numerics::DefaultSolver;
use vanefit::objective::CostOptions;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dataset, fit] = &args[..] else {
        eprintln!("usage: chi2_at_truth DATASET FIT.json");
        std::process::exit(2);
    };
    let ds = Dataset::load(Path::new(dataset))?;
    let data = FitData::new(&ds, CostOptions::default())?;
    let truth = FitFile::read(&Path::new(dataset).join("truth.json"))?;
    let est = FitFile::read(Path::new(fit))?;
    let at = |f: &FitFile| Motor::new(f.params.clone(), f.effects.clone());
    let target = data.target_at(&at(&est));
    let solver = DefaultSolver::default();
    let chi2 = |m: &Motor| target.chi2(&data.smoothed, m, &solver).unwrap_or(f64::NAN);
    let (ct, ce) = (chi2(&at(&truth)), chi2(&at(&est)));
    println!(
        "chi2 truth {ct:.2} estimate {ce:.2} difference {:.2}",
        ct - ce
    );
    Ok(())
}
