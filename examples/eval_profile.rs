//! Times one full cost evaluation of the shipped dataset and counts the right-hand-side
//! evaluations behind it: `cargo run --release --example eval_profile [n [rtol [atol_p atol_w]]]`
//! (`SOLVER=rodas4` or `bdf` runs one solver only).
#[path = "common/counting.rs"]
mod counting;

use counting::Counting;
use std::path::Path;
use std::time::Instant;
use vanefit::data::dataset::Dataset;
use vanefit::model::motor::Motor;
use vanefit::numerics::ode::{DiffsolBdf, StiffSolver, Tolerances};
use vanefit::numerics::rodas::Rodas4;
use vanefit::objective::cost::{CostModel, CostOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let n: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(200);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("measurements/ar034-synthetic");
    let ds = Dataset::load(&dir)?;
    let cost = CostModel::new(&ds, CostOptions::default())?;
    let motor = Motor::default_motor();
    // Without tolerances on the command line each solver runs at its own default.
    let arg = |k: usize| {
        std::env::args()
            .nth(k)
            .map(|s| s.parse::<f64>())
            .transpose()
    };
    let given = arg(2)?.map(|rtol| {
        let mut tol = Tolerances::with_rtol(rtol);
        if let (Ok(Some(ap)), Ok(Some(aw))) = (arg(3), arg(4)) {
            tol.atol = [ap, ap, ap, aw];
        }
        tol
    });
    let solvers: [(&str, Box<dyn StiffSolver>); 2] = [
        (
            "bdf",
            Box::new(given.map_or_else(DiffsolBdf::default, |tol| DiffsolBdf { tol })),
        ),
        (
            "rodas4",
            Box::new(given.map_or_else(Rodas4::default, |tol| Rodas4 { tol })),
        ),
    ];
    let only = std::env::var("SOLVER").ok();
    for (name, solver) in &solvers {
        if only.as_deref().is_some_and(|o| o != *name) {
            continue;
        }
        counting::reset();
        let c = cost.evaluate(&motor, &Counting(solver.as_ref()));
        let calls = counting::calls();
        let t = Instant::now();
        for _ in 0..n {
            std::hint::black_box(cost.evaluate(&motor, solver.as_ref()));
        }
        let us = t.elapsed().as_secs_f64() * 1e6 / n as f64;
        println!(
            "{name}: cost {:.10} failed {:?}; rhs calls {calls}; {us:.1} µs per evaluation",
            c.total, c.failed
        );
    }
    Ok(())
}
