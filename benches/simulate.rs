//! Speed of the simulation core (issue 2): one datasheet characteristic (25 speeds), one 60 s
//! pressure ramp, one 65 s outlet-throttle ramp, and one full evaluation of all three.
//! Run: `cargo bench --bench simulate`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use vanefit::data::synth::{free_speed, plan_experiments, SynthPlan};
use vanefit::model::motor::Motor;
use vanefit::numerics::ode::{DiffsolBdf, Tolerances};
use vanefit::sim::experiment::Experiment;

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
    let solver = DiffsolBdf::default();
    let names = [
        "datasheet_25_speeds",
        "pressure_ramp_60s",
        "outlet_throttle_65s",
    ];
    for (name, e) in names.iter().zip(&ex) {
        c.bench_function(name, |b| {
            b.iter(|| black_box(e.simulate(black_box(&motor), &solver).unwrap()))
        });
    }
    c.bench_function("all_three", |b| {
        b.iter(|| {
            for e in &ex {
                black_box(e.simulate(black_box(&motor), &solver).unwrap());
            }
        })
    });
    // The same at rtol 1e-6, the tolerance a plain simulation would use; the default
    // (3e-8) is chosen for a smooth fitting cost (see `ode::Tolerances`).
    let loose = DiffsolBdf {
        tol: Tolerances::with_rtol(1e-6),
    };
    c.bench_function("all_three_rtol_1e-6", |b| {
        b.iter(|| {
            for e in &ex {
                black_box(e.simulate(black_box(&motor), &loose).unwrap());
            }
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
