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
    let mut p = perturbed();
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
    let data = synthesize(&truth, &solver, &SynthPlan::default(), &noise, 11).unwrap();
    let ds = dataset(data);
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
