//! Speed of estimation (issue 4): cost evaluations per second on one core, and a small
//! multi-start fit of the shipped dataset on one and on two threads (parallel efficiency).
//! Run: `cargo bench --bench estimate`. The full 256-start figure comes from the CLI:
//! `time target/release/vanefit fit measurements/ar034-synthetic --starts 256 --uncertainty none --out /tmp/fit256.json`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::path::Path;
use vanefit::data::dataset::Dataset;
use vanefit::estimate::fit::DataObjective;
use vanefit::estimate::multistart::{self, Silent};
use vanefit::estimate::{Engine, MultiStartConfig};
use vanefit::estimate::{Objective, ParamSpace, DEFAULT_ESTIMATED};
use vanefit::model::effects::EffectSet;
use vanefit::model::motor::Motor;
use vanefit::model::params::MotorParams;
use vanefit::numerics::ode::DiffsolBdf;
use vanefit::objective::cost::{CostModel, CostOptions};

fn bench(c: &mut Criterion) {
    let ds = Dataset::load(Path::new("measurements/ar034-synthetic")).unwrap();
    let cost = CostModel::new(&ds, CostOptions::default()).unwrap();
    let objective = DataObjective {
        cost: &cost,
        solver: Box::new(DiffsolBdf::default()),
    };
    let motor = Motor::default_motor();
    c.bench_function("cost_evaluation", |b| {
        b.iter(|| black_box(objective.evaluate(black_box(&motor))))
    });
    let space = ParamSpace::new(
        &DEFAULT_ESTIMATED,
        MotorParams::default(),
        EffectSet::empty(),
    )
    .unwrap();
    let mut group = c.benchmark_group("multistart_4_starts_300_iterations");
    group.sample_size(10);
    for threads in [1, 2] {
        let cfg = MultiStartConfig {
            starts: 4,
            seed: 1,
            max_iters: 300,
            kill_factor: f64::INFINITY,
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
