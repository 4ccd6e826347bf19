//! Speed of estimation:
//! * `cost_evaluation/{rodas4,bdf}`: one full cost evaluation of the shipped dataset (25
//!   datasheet speeds, 60 s pressure ramp, 65 s outlet throttle) on one core, with the
//!   default solver and with the BDF used before Rodas4, in the same run;
//! * `multistart_16_starts_200_iterations/{1,2}_threads`: a fixed amount of work (16
//!   starts, 200 Nelder–Mead iterations each, no early stopping, no restarts) on one and on
//!   two threads; parallel efficiency = t(1 thread) / (2 · t(2 threads)).
//!
//! Run: `cargo bench --bench estimate`. The 256-start figure comes from the command line:
//! `time target/release/vanefit fit measurements/ar034-synthetic --starts 256 --uncertainty none --out /tmp/fit256.json`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::path::Path;
use vanefit::data::Dataset;
use vanefit::estimate::multistart;
use vanefit::estimate::multistart::Silent;
use vanefit::estimate::DataObjective;
use vanefit::estimate::{Engine, MultiStartConfig};
use vanefit::estimate::{Objective, ParamSpace, DEFAULT_ESTIMATED};
use vanefit::model::EffectSet;
use vanefit::model::Motor;
use vanefit::model::MotorParams;
use vanefit::numerics::DefaultSolver;
use vanefit::numerics::{DiffsolBdf, StiffSolver};
use vanefit::objective::{CostModel, CostOptions};

fn bench(c: &mut Criterion) {
    let ds = Dataset::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../measurements/ar034-synthetic"),
    )
    .unwrap();
    let cost = CostModel::new(&ds, CostOptions::default()).unwrap();
    let motor = Motor::default_motor();
    let solvers: [(&str, Box<dyn StiffSolver>); 2] = [
        ("rodas4", Box::new(DefaultSolver::default())),
        ("bdf", Box::new(DiffsolBdf::default())),
    ];
    for (name, solver) in solvers {
        let objective = DataObjective {
            cost: &cost,
            solver,
        };
        c.bench_function(&format!("cost_evaluation/{name}"), |b| {
            b.iter(|| black_box(objective.evaluate(black_box(&motor))))
        });
    }
    let objective = DataObjective {
        cost: &cost,
        solver: Box::new(DefaultSolver::default()),
    };
    let space = ParamSpace::new(
        &DEFAULT_ESTIMATED,
        MotorParams::default(),
        EffectSet::empty(),
    )
    .unwrap();
    let mut group = c.benchmark_group("multistart_16_starts_200_iterations");
    group.sample_size(10);
    for threads in [1, 2] {
        let cfg = MultiStartConfig {
            starts: 16,
            seed: 1,
            max_iters: 200,
            kill_factor: f64::INFINITY,
            max_restarts: 0,
            sd_tolerance: 0.0,
            ..MultiStartConfig::default()
        };
        let cfg = cfg.check().unwrap();
        let engine = Engine::with_threads(Some(threads)).unwrap();
        group.bench_function(format!("{threads}_threads"), |b| {
            b.iter(|| {
                black_box(
                    multistart::run(&engine, &objective, &space, &cfg, &Silent, None, false)
                        .unwrap(),
                )
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
