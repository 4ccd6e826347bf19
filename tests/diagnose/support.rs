//! Shared by the diagnosis tests: synthetic datasets with known truth.

#![allow(dead_code)]

use std::path::PathBuf;
use vanefit::data::{Dataset, ExperimentData, MotorSection};
use vanefit::data::{SensorNoise, SynthPlan};
use vanefit::model::Motor;
use vanefit::model::MotorParams;
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
    vanefit::data::synthesize(
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
        p_atm_pa: vanefit::units::P_ATM_PA,
        temperature_k: vanefit::units::T0_K,
        experiments,
    }
}

/// The sensor noise of a test rig's recordings: 0.03 g/s on the flows, 15 rpm on the
/// speed, 4 mN·m on the torque, 2 kPa on the recorded supply pressure.
pub fn rig_noise() -> SensorNoise {
    SensorNoise {
        flow_kg_s: 3e-5,
        speed_rad_s: 15.0 * std::f64::consts::PI / 30.0,
        torque_nm: 4e-3,
        pressure_pa: 2e3,
        ..SensorNoise::typical()
    }
}

/// The paper's experiments recorded at 20 Hz, as a test rig does.
pub fn rig_plan() -> SynthPlan {
    SynthPlan {
        sample_rate_hz: 20.0,
        ..SynthPlan::default()
    }
}

/// [`synthesize`] with the rig's plan and `noise`.
pub fn synthesize_with(truth: &Motor, seed: u64, noise: &SensorNoise) -> Vec<ExperimentData> {
    vanefit::data::synthesize(truth, &DefaultSolver::default(), &rig_plan(), noise, seed).unwrap()
}

/// The options of the ignored tables: the command line's defaults
/// (`DiagnoseOptions::full(4, 1)`: 4 baseline starts, seed 1), or the quick ones when the
/// environment says `DIAG_EFFORT=quick`; with the name to print.
pub fn table_options() -> (vanefit::diagnose::DiagnoseOptions, &'static str) {
    use vanefit::diagnose::DiagnoseOptions;
    match std::env::var("DIAG_EFFORT").as_deref() {
        Ok("quick") => (
            DiagnoseOptions::quick(1),
            "quick (DiagnoseOptions::quick(1))",
        ),
        _ => (
            DiagnoseOptions::full(4, 1),
            "default (DiagnoseOptions::full(4, 1), the command line's)",
        ),
    }
}

/// Cost evaluations of the baseline fit and every refitted model of a diagnosis (the
/// concealment's fits of experiment subsets not included).
pub fn evaluations(d: &vanefit::diagnose::Diagnosis) -> u64 {
    std::iter::once(&d.baseline)
        .chain(&d.candidates)
        .map(|c| c.fitted.evaluations)
        .sum()
}

/// The size of the motor of table row `seed`, cm³, from `DIAG_SIZES` (the size dimension of
/// the random-effect and false-alarm tables): unset, the reference motor (3.8 cm³, the
/// tables as they were); `LO-HI` (e.g. `1-150`), a displacement drawn log-uniformly in that
/// band per seed (`twin::sizes::displacement_in_band`); one number, that size.
pub fn table_size_cm3(seed: u64) -> Option<f64> {
    let v = std::env::var("DIAG_SIZES").ok()?;
    match v.split_once('-') {
        Some((lo, hi)) => {
            let band = (lo.trim().parse().ok()?, hi.trim().parse().ok()?);
            Some(twin::sizes::displacement_in_band(seed, band) * 1e6)
        }
        None => v.trim().parse().ok(),
    }
}

/// `motor` and `cfg` (made for the 3.8 cm³ reference) at `size_cm3` (unchanged when `None`):
/// the motor by geometric similarity, the rig scaled to it (tests/twin/sizes.rs).
pub fn sized(
    motor: twin::TwinMotor,
    cfg: twin::RecordConfig,
    size_cm3: Option<f64>,
) -> (twin::TwinMotor, twin::RecordConfig) {
    match size_cm3 {
        None => (motor, cfg),
        Some(v) => {
            let s = v * 1e-6 / motor.v_disp;
            (
                twin::sizes::scaled_motor(&motor, v * 1e-6),
                twin::sizes::scaled_config(&cfg, s),
            )
        }
    }
}
