//! Speed of posterior sampling (docs/estimation.md, "Posterior sampling"):
//! * `page_posterior/ensemble_40x200`: the shipped catalogue page's posterior (its fit, with
//!   the motor prior, made once before timing), 40 walkers × 200 steps after 50 of the
//!   ensemble `predict` samples a page with; per step of 40 walkers, 40 evaluations;
//! * `page_posterior/laplace_check`: the Laplace approximation of the same posterior and the
//!   400-draw importance check that picks the sampler;
//! * `page_posterior/transport_map_fit`: the quadratic transport map fitted to 8000 draws of
//!   a pilot ensemble of the same posterior (`estimate::QuadraticMap`), and
//!   `page_posterior/transport_chains_8x200`: 8 chains × 200 steps after 50 in its
//!   coordinates, as `predict` samples a page with;
//! * `rig_posterior/laplace_chains_8x200`: the shipped rig fit's posterior
//!   (`fits/ar034-synthetic.json`), 8 Laplace-guided chains × 200 steps after 50.
//!
//! Run: `cargo bench --bench sample`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;
use std::path::Path;
use vanefit::data::{Dataset, FitFile};
use vanefit::estimate::multistart::Silent;
use vanefit::estimate::{
    run_chains, run_ensemble_with, straightened, ChainSettings, EnsembleSettings, FitLikelihood,
    FitPosterior, ImportanceCheck, LogDensity, LogPrior, Mapped, Moves, QuadraticMap,
};
use vanefit::task::FitOptions;

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

fn bench(c: &mut Criterion) {
    let page = root().join("measurements/ar034-synthetic-catalogue");
    let settings = FitOptions::default().check().unwrap();
    let fit = vanefit::task::fit(&page, &settings, None, &Silent)
        .unwrap()
        .file;
    let ds = Dataset::load(&page).unwrap();
    let like = FitLikelihood::from_fit(&ds, &fit).unwrap();
    let prior = |v: &[f64]| like.log_prior(v);
    let post = FitPosterior::new(&like).with_prior(&prior as &dyn LogPrior);
    let x0 = post.to_coords(&like.estimate());
    let d = post.dim();
    let walkers = (4 * d).max(16).div_ceil(2) * 2;
    let starts: Vec<Vec<f64>> = (0..walkers)
        .map(|k| {
            let mut x = x0.clone();
            x[k % d] += 1e-3 * (k as f64 / walkers as f64 - 0.5);
            x
        })
        .collect();
    let mut group = c.benchmark_group("page_posterior");
    group.sample_size(10);
    let es = EnsembleSettings {
        walkers,
        steps: 200,
        burn_in: 50,
        seed: 1,
    };
    let moves = Moves::Mixed { de: 0.8 };
    group.bench_function(format!("ensemble_{walkers}x200"), |b| {
        b.iter(|| black_box(run_ensemble_with(&post, &starts, &es, moves, &|_, _| {}).unwrap()))
    });
    group.bench_function("laplace_check", |b| {
        b.iter(|| {
            let q = post.proposal().unwrap();
            black_box(ImportanceCheck::of(&post, &q, 400, 1))
        })
    });
    // The transport sampler's parts: the quadratic map fitted to the pilot's draws (made
    // once here: 40 walkers × 200 steps), and 8 chains × 200 steps after 50 in its
    // coordinates.
    let pilot = EnsembleSettings {
        walkers,
        steps: 200,
        burn_in: 200,
        seed: 1,
    };
    let draws = run_ensemble_with(&post, &starts, &pilot, moves, &|_, _| {})
        .unwrap()
        .flat();
    group.bench_function("transport_map_fit", |b| {
        b.iter(|| black_box(QuadraticMap::fit(&draws, 1e-6).unwrap()))
    });
    let (map, qz) = straightened(&draws, 1e-6, 5.0, 1.2).unwrap();
    let mapped = Mapped {
        density: &post,
        map: &map,
    };
    let cs = ChainSettings {
        chains: 8,
        steps: 200,
        burn_in: 50,
        block: 250,
        seed: 1,
    };
    group.bench_function("transport_chains_8x200", |b| {
        b.iter(|| black_box(run_chains(&mapped, &qz, &cs, None, &|_, _| {}).unwrap()))
    });
    group.finish();

    let rig = FitFile::read(&root().join("fits/ar034-synthetic.json")).unwrap();
    let ds = Dataset::load(&root().join("measurements/ar034-synthetic")).unwrap();
    let like = FitLikelihood::from_fit(&ds, &rig).unwrap();
    let post = FitPosterior::new(&like);
    let q = post.proposal().unwrap();
    let cs = ChainSettings {
        chains: 8,
        steps: 200,
        burn_in: 50,
        block: 250,
        seed: 1,
    };
    let mut group = c.benchmark_group("rig_posterior");
    group.sample_size(10);
    group.bench_function("laplace_chains_8x200", |b| {
        b.iter(|| black_box(run_chains(&post, &q, &cs, None, &|_, _| {}).unwrap()))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
