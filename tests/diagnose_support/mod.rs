//! Shared by the diagnosis tests: synthetic datasets with known truth.

#![allow(dead_code)]

use std::path::PathBuf;
use vanefit::data::dataset::{Dataset, ExperimentData, MotorSection};
use vanefit::data::synth::{SensorNoise, SynthPlan};
use vanefit::model::motor::Motor;
use vanefit::model::params::MotorParams;
use vanefit::numerics::DefaultSolver;

/// The base parameters of the test motor: the AR034-11 defaults with every estimated
/// parameter moved by 20–40% (so that the diagnosis cannot lean on the defaults).
pub fn perturbed_base() -> MotorParams {
    let mut p = MotorParams::default();
    for (name, factor) in [
        ("c_in1", 1.25),
        ("c_out2", 0.8),
        ("c_ext", 1.3),
        ("c_1e", 0.7),
        ("c_2e", 1.35),
        ("c_12", 0.75),
        ("t_coulomb", 1.3),
        ("visc", 0.75),
    ] {
        p = p.with(name, p.get(name).unwrap() * factor).unwrap();
    }
    p
}

/// The paper's three experiments (`synth::SynthPlan::default`) simulated with `truth`
/// by `synth::synthesize`, typical sensor noise on the measured channels and on the
/// recorded inputs.
pub fn synthesize(truth: &Motor, seed: u64) -> Vec<ExperimentData> {
    vanefit::data::synth::synthesize(
        truth,
        &DefaultSolver::default(),
        &SynthPlan::default(),
        &SensorNoise::typical(),
        seed,
    )
    .unwrap()
}

/// A dataset in memory.
pub fn dataset(name: &str, experiments: Vec<ExperimentData>) -> Dataset {
    Dataset {
        dir: PathBuf::from(name),
        name: name.into(),
        synthetic: true,
        description: None,
        motor: MotorSection::default(),
        p_atm_pa: vanefit::units::constants::P_ATM_PA,
        temperature_k: vanefit::units::constants::T0_K,
        experiments,
    }
}
