//! Shared by the diagnosis tests: synthetic datasets with known truth.

#![allow(dead_code)]

use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::path::PathBuf;
use vanefit::dataset::{Column, Dataset, ExperimentData, Kind, MotorSection};
use vanefit::experiment::Experiment;
use vanefit::motor::Motor;
use vanefit::ode::DiffsolBdf;
use vanefit::params::MotorParams;
use vanefit::synth::{free_speed, plan_experiments, SensorNoise, SynthPlan};
use vanefit::units::{column_name, Quantity, Unit};

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

/// Pressure the synthetic ramp starts from above atmosphere, Pa. `synth::plan_experiments`
/// starts it AT atmosphere, where with breakaway friction and some parameter sets the
/// steady solver stalls at round-off (residual ~1e-12, never "converged"); 3 kPa above, the
/// standstill state is well defined. The diagnosis is not affected: it simulates whatever
/// the recording says.
pub const RAMP_START_ABOVE_ATM_PA: f64 = 3e3;

fn column(q: Quantity, u: Unit, si: Vec<f64>, p_atm: f64) -> Column {
    Column {
        name: column_name(q, u),
        quantity: q,
        unit: u,
        raw: si
            .iter()
            .map(|v| format!("{:.6e}", u.from_si(*v, p_atm)))
            .collect(),
        si,
    }
}

/// `synth::synthesize` with the ramp starting [`RAMP_START_ABOVE_ATM_PA`] above atmosphere:
/// the paper's three experiments simulated with `truth`, typical sensor noise on the
/// measured channels and on the recorded inputs.
pub fn synthesize(truth: &Motor, seed: u64) -> Vec<ExperimentData> {
    let plan = SynthPlan::default();
    let noise = SensorNoise::typical();
    let p_atm = plan.p_atm_pa;
    let w_free = free_speed(truth, plan.p_supply_pa, p_atm).unwrap();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut add = |v: &[f64], sd: f64| -> Vec<f64> {
        let d = Normal::new(0.0, sd).unwrap();
        v.iter().map(|x| x + d.sample(&mut rng)).collect()
    };
    let mut out = Vec::new();
    for mut data in plan_experiments(&plan, w_free) {
        if data.kind == Kind::PressureRamp {
            let t = data.recording.values(Quantity::Time).unwrap().to_vec();
            let t_end = *t.last().unwrap();
            let p0 = p_atm + RAMP_START_ABOVE_ATM_PA;
            let p: Vec<f64> = t
                .iter()
                .map(|t| p0 + (plan.p_supply_pa - p0) * t / t_end)
                .collect();
            for c in &mut data.recording.columns {
                if c.quantity == Quantity::PPort1 {
                    *c = column(Quantity::PPort1, c.unit, p.clone(), p_atm);
                }
            }
        }
        let sim = Experiment::new(&data, p_atm)
            .unwrap()
            .simulate(truth, &DiffsolBdf::default())
            .unwrap();
        let wanted: &[(Quantity, Unit)] = match data.kind {
            Kind::Datasheet => &[(Quantity::Torque, Unit::Nm), (Quantity::Flow1, Unit::GS)],
            _ => &[
                (Quantity::Flow1, Unit::GS),
                (Quantity::Flow2, Unit::GS),
                (Quantity::Speed, Unit::Rpm),
            ],
        };
        for (q, u) in wanted {
            let sd = match q {
                Quantity::Torque => noise.torque_nm,
                Quantity::Speed => noise.speed_rad_s,
                _ => noise.flow_kg_s,
            };
            let noisy = add(sim.channel(*q).unwrap(), sd);
            data.recording.columns.push(column(*q, *u, noisy, p_atm));
        }
        for c in &mut data.recording.columns {
            let si = match c.quantity {
                Quantity::PPort1 => add(&c.si, noise.pressure_pa),
                Quantity::CPort2 => add(&vec![0.0; c.si.len()], noise.conductance_rel)
                    .iter()
                    .zip(&c.si)
                    .map(|(e, v)| v * e.exp())
                    .collect(),
                _ => continue,
            };
            *c = column(c.quantity, c.unit, si, p_atm);
        }
        out.push(data);
    }
    out
}

/// A dataset in memory.
pub fn dataset(name: &str, experiments: Vec<ExperimentData>) -> Dataset {
    Dataset {
        dir: PathBuf::from(name),
        name: name.into(),
        synthetic: true,
        description: None,
        motor: MotorSection {
            name: None,
            vanes: None,
            displacement_m3: None,
            expansion_ratio: None,
            length_m: None,
            r_stator_m: None,
            r_rotor_m: None,
        },
        p_atm_pa: vanefit::constants::P_ATM_PA,
        temperature_k: vanefit::constants::T0_K,
        experiments,
    }
}
