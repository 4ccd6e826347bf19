mod diagnose_support;
use std::path::PathBuf;
use vanefit::dataset::Dataset;
use vanefit::diagnose::{diagnose, summary, DiagnoseOptions};
use vanefit::effects::EffectSet;
use vanefit::motor::Motor;
use vanefit::ode::DiffsolBdf;
use vanefit::params::MotorParams;
use vanefit::synth::{synthesize, SensorNoise, SynthPlan};

fn perturbed() -> MotorParams {
    let mut p = MotorParams::default();
    for (n, f) in [
        ("c_in1", 1.25),
        ("c_out2", 0.8),
        ("c_ext", 1.3),
        ("c_1e", 0.7),
        ("c_2e", 1.35),
        ("c_12", 0.75),
        ("t_coulomb", 1.3),
        ("visc", 0.75),
    ] {
        p = p.with(n, p.get(n).unwrap() * f).unwrap();
    }
    p
}

fn dataset(experiments: Vec<vanefit::dataset::ExperimentData>) -> Dataset {
    Dataset {
        dir: PathBuf::from("mem"),
        name: "mem".into(),
        synthetic: true,
        description: None,
        motor: vanefit::dataset::MotorSection {
            name: None,
            vanes: None,
            displacement_m3: None,
            expansion_ratio: None,
            length_m: None,
            r_stator_m: None,
            r_rotor_m: None,
        },
        p_atm_pa: 101325.0,
        temperature_k: 293.15,
        experiments,
    }
}

#[test]
#[ignore]
fn probe() {
    let effects = std::env::var("FX").unwrap_or_default();
    let set = EffectSet::parse_list(&effects).unwrap();
    let mut p = diagnose_support::perturbed_base();
    if let Ok(v) = std::env::var("PV") {
        for kv in v.split(',') {
            let (k, v) = kv.split_once('=').unwrap();
            p = p.with(k, v.parse().unwrap()).unwrap();
        }
    }
    let solver = DiffsolBdf::default();
    let truth = Motor::new(p, set);
    let mut noise = SensorNoise::typical();
    if std::env::var("NOINPUT").is_ok() {
        noise.pressure_pa = 0.0;
        noise.conductance_rel = 0.0;
    }
    let _ = (&noise, &solver);
    let ds = diagnose_support::dataset("probe", diagnose_support::synthesize(&truth, 11));
    let mut o = if std::env::var("FULL").is_ok() {
        DiagnoseOptions::full(4, 1)
    } else {
        DiagnoseOptions::quick(1)
    };
    o.progress = true;
    let d = diagnose(&ds, &o).unwrap();
    eprintln!("{}", summary(&d));
    eprintln!(
        "{}",
        serde_json::to_string_pretty(&vanefit::diagnose::to_json(&d)).unwrap()
    );
    vanefit::diagnose::write(&d, std::path::Path::new("/tmp/diag_probe")).unwrap();
}

#[test]
#[ignore]
fn probe_steady() {
    use vanefit::motor::{Boundary, Load};
    use vanefit::steady;
    for (ts, dp) in [
        (0.06, -10.0),
        (0.06, -1e-6),
        (0.06, 1e-6),
        (0.06, 5.0),
        (0.06, 0.5),
        (0.02, -10.0),
        (0.02, -1.0),
    ] {
        let p = MotorParams::default().with("t_static", ts).unwrap();
        let m = Motor::new(p, EffectSet::parse_list("breakaway_friction").unwrap());
        let bc = Boundary::supplied(
            101325.0 + dp,
            101325.0,
            Load::ViscousBrake { c_nm_s_rad: 1e-4 },
        );
        let r = steady::free(&m, &bc, &steady::initial_guess(&bc));
        eprintln!("t_static {ts} dp {dp}: {:?}", r);
    }
}

#[test]
#[ignore]
fn probe_steady2() {
    use vanefit::motor::{Boundary, Load};
    use vanefit::schedule::Schedule;
    use vanefit::steady;
    let plan = SynthPlan::default();
    let p = MotorParams::default();
    let m = Motor::new(p, EffectSet::parse_list("breakaway_friction").unwrap());
    let w = vanefit::synth::free_speed(&m, plan.p_supply_pa, plan.p_atm_pa).unwrap();
    let exps = vanefit::synth::plan_experiments(&plan, w);
    let ramp = &exps[1];
    let t = ramp
        .recording
        .values(vanefit::units::Quantity::Time)
        .unwrap();
    let pp = ramp
        .recording
        .values(vanefit::units::Quantity::PPort1)
        .unwrap();
    let s = Schedule::smoothed(t, pp);
    let p0 = s.at(t[0]);
    eprintln!("p0 - patm = {:e}", p0 - 101325.0);
    let bc = Boundary::supplied(p0, 101325.0, Load::ViscousBrake { c_nm_s_rad: 1e-4 });
    eprintln!("{:?}", steady::free(&m, &bc, &steady::initial_guess(&bc)));
}

#[test]
#[ignore]
fn probe_steady3() {
    let plan = SynthPlan::default();
    let p = perturbed();
    let m = Motor::new(p, EffectSet::parse_list("breakaway_friction").unwrap());
    let w = vanefit::synth::free_speed(&m, plan.p_supply_pa, plan.p_atm_pa).unwrap();
    let exps = vanefit::synth::plan_experiments(&plan, w);
    let ex = vanefit::experiment::Experiment::new(&exps[1], plan.p_atm_pa).unwrap();
    eprintln!("{:?}", ex.simulate(&m, &DiffsolBdf::default()).map(|_| ()));
    let mut m2 = m.clone();
    m2.params = m2.params.with("t_static", 0.05).unwrap();
    let m2 = Motor::new(m2.params, m2.effects);
    eprintln!("{:?}", ex.simulate(&m2, &DiffsolBdf::default()).map(|_| ()));
}
