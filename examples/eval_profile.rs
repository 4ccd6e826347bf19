//! Times one full cost evaluation of the shipped dataset and counts the right-hand-side
//! evaluations behind it: `cargo run --release --example eval_profile [n [rtol [atol_p atol_w]]]`
//! (`SOLVER=rodas4`, `bdf` or `quasi_steady` runs one solver only; the quasi-steady
//! approximation of the ramps is not accurate enough to fit with, see docs/performance.md).
#[path = "common/support.rs"]
mod support;

use vanefit::model::Motor;
use vanefit::numerics::Rodas4;
use vanefit::numerics::{DiffsolBdf, QuasiSteady, StiffSolver, Tolerances};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (n, _, cost) = support::shipped(200)?;
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
    let solvers: [(&str, Box<dyn StiffSolver>); 3] = [
        (
            "bdf",
            Box::new(given.map_or_else(DiffsolBdf::default, |tol| DiffsolBdf { tol })),
        ),
        (
            "rodas4",
            Box::new(given.map_or_else(Rodas4::default, |tol| Rodas4 { tol })),
        ),
        ("quasi_steady", Box::new(QuasiSteady::default())),
    ];
    let only = std::env::var("SOLVER").ok();
    for (name, solver) in &solvers {
        if only.as_deref().is_some_and(|o| o != *name) {
            continue;
        }
        let (c, calls, us) = support::count_and_time(&cost, &motor, solver.as_ref(), n);
        println!(
            "{name}: cost {:.10} failed {:?}; rhs calls {calls}; {us:.1} µs per evaluation",
            c.total, c.failed
        );
    }
    Ok(())
}
