//! Speed of the simulation core: one datasheet characteristic (25 speeds),
//! one 60 s pressure ramp, one 65 s outlet-throttle ramp, and all three, each with the
//! default solver (Rodas4, `numerics::DefaultSolver`) and with diffsol's BDF at its own
//! default tolerance (the solver before Rodas4), in one run so that the two compare on
//! the same machine state. Run: `cargo bench --bench simulate`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use vanefit::data::{free_speed, plan_experiments, SynthPlan};
use vanefit::model::Motor;
use vanefit::numerics::DefaultSolver;
use vanefit::numerics::{DiffsolBdf, StiffSolver};
use vanefit::sim::Experiment;

fn experiments() -> (Motor, Vec<Experiment>) {
    let motor = Motor::default_motor();
    let plan = SynthPlan::default();
    let w_free = free_speed(&motor, plan.p_supply_pa, plan.p_atm_pa).unwrap();
    let ex = plan_experiments(&plan, w_free)
        .iter()
        .map(|d| Experiment::new(d, plan.p_atm_pa).unwrap())
        .collect();
    (motor, ex)
}

fn bench(c: &mut Criterion) {
    let (motor, ex) = experiments();
    let solvers: [(&str, Box<dyn StiffSolver>); 2] = [
        ("rodas4", Box::new(DefaultSolver::default())),
        ("bdf", Box::new(DiffsolBdf::default())),
    ];
    let names = [
        "datasheet_25_speeds",
        "pressure_ramp_60s",
        "outlet_throttle_65s",
    ];
    for (solver_name, solver) in &solvers {
        let solver = solver.as_ref();
        for (name, e) in names.iter().zip(&ex) {
            c.bench_function(&format!("{name}/{solver_name}"), |b| {
                b.iter(|| black_box(e.simulate(black_box(&motor), solver).unwrap()))
            });
        }
        c.bench_function(&format!("all_three/{solver_name}"), |b| {
            b.iter(|| {
                for e in &ex {
                    black_box(e.simulate(black_box(&motor), solver).unwrap());
                }
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
