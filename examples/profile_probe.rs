//! Probe of a profile point: χ² minimised over the other parameters with one held fixed,
//! by Levenberg–Marquardt from the estimate and then Nelder–Mead, against the estimate's χ².
//! `cargo run --release --example profile_probe -- DATASET FIT.json NAME VALUE`

use std::path::Path;
use vanefit::data::Dataset;
use vanefit::data::FitFile;
use vanefit::estimate::polish_chi2;
use vanefit::estimate::FitData;
use vanefit::estimate::Likelihood;
use vanefit::estimate::{minimize, Layout, NelderMeadSettings, Restart};
use vanefit::estimate::{ParamSpace, Problem, DEFAULT_ESTIMATED};
use vanefit::model::Motor;
use vanefit::numerics::DefaultSolver;
use vanefit::objective::CostOptions;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [dataset, fit, name, value] = &args[..] else {
        eprintln!("usage: profile_probe DATASET FIT.json NAME VALUE");
        std::process::exit(2);
    };
    let ds = Dataset::load(Path::new(dataset))?;
    let data = FitData::new(&ds, CostOptions::default())?;
    let est = FitFile::read(Path::new(fit))?;
    let target = data.target_at(&Motor::new(est.params.clone(), est.effects.clone()));
    let lik = Likelihood {
        cost: &data.smoothed,
        target: &target,
        solver: DefaultSolver::default(),
    };
    let all = ParamSpace::new(&DEFAULT_ESTIMATED, est.params.clone(), est.effects.clone())?;
    let full = Problem::new(&lik, &all, false);
    let chi2_hat = full.evaluate(&all.theta(&est.params)).chi2;
    let fixed = est.params.with(name, value.parse()?)?;
    let others: Vec<&str> = DEFAULT_ESTIMATED
        .iter()
        .copied()
        .filter(|n| n != name)
        .collect();
    let space = ParamSpace::new(&others, fixed.clone(), est.effects.clone())?;
    let p = Problem::new(&lik, &space, false);
    let x0 = space.theta(&fixed);
    let c0 = p.evaluate(&x0).chi2;
    let (x_lm, c_lm) = polish_chi2(&p, &x0, 400);
    let nm = NelderMeadSettings {
        sd_tolerance: 1e-10,
        step: 0.01,
        layout: Layout::Forward,
        adaptive: true,
        restart: Restart::Never,
    };
    let (x_lm2, c_lm2) = polish_chi2(&p, &x_lm, 400);
    let f0 = p.evaluate(&x_lm2).cost;
    let s = minimize(&p, x_lm2.clone(), f0, nm, 4000, 1000);
    let c_nm = p.evaluate(s.x()).chi2;
    println!(
        "chi2 at estimate {chi2_hat:.3}; {name}={value}: start {:.3}, LM {:.3}, LM again {:.3}, then NM {:.3} (delta {:.3})",
        c0 - chi2_hat,
        c_lm - chi2_hat,
        c_lm2 - chi2_hat,
        c_nm - chi2_hat,
        c_nm - chi2_hat
    );
    let _ = x_lm;
    Ok(())
}
