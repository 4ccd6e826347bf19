//! Parameter recovery: data synthesised from known parameters are fitted back.
//! Without noise the estimates land within 1% of the truth; with sensor noise the truth lies
//! inside the reported 95% intervals of the identifiable parameters.

use vanefit::data::Dataset;
use vanefit::data::{synthesize, write_dataset, SensorNoise, SynthPlan};
use vanefit::estimate::multistart::Silent;
use vanefit::estimate::{fit, FitData, FitSetup, UncertaintyMethod};
use vanefit::estimate::{Engine, MultiStartConfig};
use vanefit::estimate::{ParamSpace, DEFAULT_ESTIMATED};
use vanefit::model::EffectSet;
use vanefit::model::Motor;
use vanefit::model::MotorParams;
use vanefit::numerics::DiffsolBdf;
use vanefit::objective::CostOptions;

/// A motor that is not the default one: conductances and friction moved by up to 40%.
fn truth() -> MotorParams {
    let changes = [
        ("c_in1", 1.25),
        ("c_out2", 0.85),
        ("c_ext", 1.15),
        ("c_1e", 0.7),
        ("c_2e", 1.3),
        ("c_12", 1.4),
        ("t_coulomb", 0.8),
        ("visc", 1.2),
    ];
    changes.iter().fold(MotorParams::default(), |p, (n, k)| {
        let v = p.get(n).unwrap();
        p.with(n, v * k).unwrap()
    })
}

fn dataset(noise: SensorNoise, seed: u64) -> (tempfile::TempDir, Dataset) {
    let dir = tempfile::tempdir().unwrap();
    let motor = Motor::new(truth(), EffectSet::empty());
    let plan = SynthPlan::default();
    // The data come from the other integrator (diffsol's BDF) than the fit's Rodas4, so that
    // the fit does not meet its own discretisation error in the data.
    let experiments = synthesize(&motor, &DiffsolBdf::default(), &plan, &noise, seed).unwrap();
    write_dataset(
        dir.path(),
        &experiments,
        &plan,
        &motor,
        &EffectSet::empty(),
        "recovery test",
    )
    .unwrap();
    let ds = Dataset::load(dir.path()).unwrap();
    (dir, ds)
}

/// Fits from the default motor (every parameter 15–40% off) plus a few Latin-hypercube starts.
fn fit_back(ds: &Dataset, uncertainty: UncertaintyMethod) -> vanefit::estimate::FitOutcome {
    let data = FitData::new(ds, CostOptions::default()).unwrap();
    let space = ParamSpace::new(
        &DEFAULT_ESTIMATED,
        MotorParams::default(),
        EffectSet::empty(),
    )
    .unwrap();
    let start = space.theta(&MotorParams::default());
    let setup = FitSetup {
        multistart: MultiStartConfig {
            starts: 2,
            seed: 4,
            given_starts: vec![start],
            max_iters: 4000,
            ..MultiStartConfig::default()
        },
        space,
        uncertainty,
        results_file: None,
        resume: false,
    };
    fit(&Engine::with_threads(None).unwrap(), &data, &setup, &Silent).unwrap()
}

#[test]
fn noise_free_data_are_fitted_back_within_one_percent() {
    let (_dir, ds) = dataset(SensorNoise::none(), 1);
    let out = fit_back(&ds, UncertaintyMethod::None);
    let t = truth();
    for n in DEFAULT_ESTIMATED {
        let (est, tru) = (out.params.get(n).unwrap(), t.get(n).unwrap());
        eprintln!(
            "{n:<10} true {tru:.5e} estimate {est:.5e} error {:+.4}%",
            100.0 * (est / tru - 1.0)
        );
        assert!(
            (est / tru - 1.0).abs() < 0.01,
            "{n}: estimated {est:e}, true {tru:e} (cost {})",
            out.cost
        );
    }
}

#[test]
fn with_noise_the_truth_lies_inside_the_95_percent_intervals() {
    let (_dir, ds) = dataset(SensorNoise::typical(), 7);
    let out = fit_back(&ds, UncertaintyMethod::Profile);
    let t = truth();
    let mut identifiable = 0;
    for iv in &out.intervals {
        let tru = t.get(&iv.name).unwrap();
        eprintln!(
            "{:<10} true {tru:.4e} estimate {:.4e} interval {:?} .. {:?}",
            iv.name, iv.value, iv.lo, iv.hi
        );
        if let (Some(lo), Some(hi)) = (iv.lo, iv.hi) {
            identifiable += 1;
            assert!(
                lo <= tru && tru <= hi,
                "{}: true {tru:e} outside [{lo:e}, {hi:e}] (estimate {:e})",
                iv.name,
                iv.value
            );
        }
    }
    assert!(
        identifiable >= 6,
        "only {identifiable} identifiable parameters: {:?}",
        out.intervals
    );
}
