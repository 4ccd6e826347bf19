//! Synthetic datasets: the simulator run on the three reference experiments, with realistic
//! sensor noise, written as a complete dataset folder (rig.toml marked synthetic, CSVs).
//! Used for examples, tests, and to prove the estimator and the diagnosis on known truth.

use crate::data::dataset::{Column, DataError, ExperimentData, Kind, Recording};
use crate::model::effects::EffectSet;
use crate::model::motor::{idx, Boundary, Load, Motor};
use crate::model::spec::SizeLaw;
use crate::numerics::ode::StiffSolver;
use crate::sim::experiment::{Experiment, SimError};
use crate::sim::steady;
use crate::units::{column_name, Quantity, Unit};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Standard deviations of the simulated sensors, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorNoise {
    /// Flow sensors, kg/s.
    pub flow_kg_s: f64,
    /// Speed sensor, rad/s.
    pub speed_rad_s: f64,
    /// Torque sensor, N·m.
    pub torque_nm: f64,
    /// Pressure sensor, Pa.
    pub pressure_pa: f64,
    /// Relative noise of the conductance setting (log-normal).
    pub conductance_rel: f64,
}

impl SensorNoise {
    /// A careful rig: 0.01 g/s flow, 5 rpm, 2 mN·m, 1 kPa, 0.5% on the throttle setting.
    pub fn typical() -> Self {
        Self {
            flow_kg_s: 1e-5,
            speed_rad_s: 5.0 * std::f64::consts::PI / 30.0,
            torque_nm: 2e-3,
            pressure_pa: 1e3,
            conductance_rel: 5e-3,
        }
    }
    /// [`SensorNoise::typical`] for a motor of displacement `v_disp_m3`: a rig sized to its
    /// motor has sensors whose ranges, and so whose noise, follow the motor's flows
    /// (∝ s^⅔), speeds (∝ s^{-⅓}) and torques (∝ s) (`SizeLaw`); the pressure sensors and the
    /// throttle's relative setting do not change. The reference motor's rig is `typical()`.
    pub fn typical_for(v_disp_m3: f64) -> Self {
        let f = |k| SizeLaw::factor(v_disp_m3, k);
        let t = Self::typical();
        Self {
            flow_kg_s: t.flow_kg_s * f(SizeLaw::MASS_FLOW),
            speed_rad_s: t.speed_rad_s * f(SizeLaw::SPEED),
            torque_nm: t.torque_nm * f(SizeLaw::TORQUE),
            ..t
        }
    }

    /// No noise at all.
    pub fn none() -> Self {
        Self {
            flow_kg_s: 0.0,
            speed_rad_s: 0.0,
            torque_nm: 0.0,
            pressure_pa: 0.0,
            conductance_rel: 0.0,
        }
    }
    /// All standard deviations multiplied by `k`.
    pub fn scaled(self, k: f64) -> Self {
        Self {
            flow_kg_s: self.flow_kg_s * k,
            speed_rad_s: self.speed_rad_s * k,
            torque_nm: self.torque_nm * k,
            pressure_pa: self.pressure_pa * k,
            conductance_rel: self.conductance_rel * k,
        }
    }
}

/// The conditions of the three reference experiments.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthPlan {
    /// Atmospheric pressure, Pa.
    pub p_atm_pa: f64,
    /// Supply pressure, Pa (absolute).
    pub p_supply_pa: f64,
    /// Speeds of the datasheet characteristic.
    pub datasheet_points: usize,
    /// Length of the supply-pressure ramp, s.
    pub ramp_duration_s: f64,
    /// Length of the outlet-throttle ramp, s.
    pub throttle_duration_s: f64,
    /// Sampling rate of the transient recordings, Hz.
    pub sample_rate_hz: f64,
    /// Brake on the rig for the ramps.
    pub brake: Load,
    /// Port-2 conductance at start and end of the throttle ramp, m³/(s·Pa).
    pub c_port2_range: (f64, f64),
}

impl Default for SynthPlan {
    /// The paper's rig: 0.73 MPa supply, 60 s pressure ramp, 65 s throttle ramp, 10 Hz.
    fn default() -> Self {
        Self {
            p_atm_pa: crate::units::constants::P_ATM_PA,
            p_supply_pa: 0.73e6,
            datasheet_points: 25,
            ramp_duration_s: 60.0,
            throttle_duration_s: 65.0,
            sample_rate_hz: 10.0,
            brake: Load::ViscousBrake { c_nm_s_rad: 1.0e-4 },
            c_port2_range: (3e-8, 1.5e-9),
        }
    }
}

impl SynthPlan {
    /// The paper's rig ([`SynthPlan::default`]) scaled to a motor of displacement
    /// `v_disp_m3`: the brake loads it at the same share of its torque at the same share of
    /// its speed (c ∝ torque/speed ∝ s^{4/3}), and the outlet throttle spans the same range
    /// relative to its ports (conductances ∝ s^⅔). Pressures, ramp lengths and the sampling
    /// rate stay: the ramps are slow against every motor's time constants.
    pub fn for_motor(v_disp_m3: f64) -> Self {
        let d = Self::default();
        let f = |k| SizeLaw::factor(v_disp_m3, k);
        let brake = match d.brake {
            Load::ViscousBrake { c_nm_s_rad } => Load::ViscousBrake {
                c_nm_s_rad: c_nm_s_rad * f(SizeLaw::TORQUE - SizeLaw::SPEED),
            },
            other => other,
        };
        let area = f(SizeLaw::AREA);
        Self {
            brake,
            c_port2_range: (d.c_port2_range.0 * area, d.c_port2_range.1 * area),
            ..d
        }
    }
}

fn input_column(q: Quantity, u: Unit, si: Vec<f64>, p_atm: f64) -> Column {
    let raw = si
        .iter()
        .map(|v| format_value(u.from_si(*v, p_atm)))
        .collect();
    Column {
        name: column_name(q, u),
        quantity: q,
        unit: u,
        si,
        raw,
    }
}

fn format_value(v: f64) -> String {
    format!("{v:.6e}")
}

fn experiment_data(
    kind: Kind,
    file: &str,
    p_supply: Option<f64>,
    load: Load,
    columns: Vec<Column>,
) -> ExperimentData {
    let rows = columns[0].si.len();
    ExperimentData {
        p_supply_written: None,
        p_supply_line: None,
        tolerance: None,
        figures: Vec::new(),
        kind,
        file: file.to_string(),
        p_supply_pa: p_supply,
        load,
        weight: 1.0,
        channel_weights: BTreeMap::new(),
        recording: Recording {
            file: PathBuf::from(file),
            columns,
            lines: (2..rows as u64 + 2).collect(),
        },
    }
}

/// Free-running speed of a motor at a supply pressure, rad/s.
pub fn free_speed(motor: &Motor, p_supply_pa: f64, p_atm_pa: f64) -> Result<f64, SimError> {
    let bc = Boundary::supplied(p_supply_pa, p_atm_pa, Load::None);
    steady::free(motor, &bc, &steady::initial_guess(&bc))
        .map(|x| x[idx::OMEGA])
        .map_err(SimError::FreeSpeed)
}

/// The three reference experiments with their inputs and no measured channels yet.
pub fn plan_experiments(plan: &SynthPlan, free_speed_rad_s: f64) -> Vec<ExperimentData> {
    let p_atm = plan.p_atm_pa;
    let n = plan.datasheet_points.max(2);
    let speeds: Vec<f64> = (0..n)
        .map(|k| free_speed_rad_s * k as f64 / (n - 1) as f64)
        .collect();
    let datasheet = experiment_data(
        Kind::Datasheet,
        "datasheet.csv",
        Some(plan.p_supply_pa),
        Load::None,
        vec![input_column(Quantity::Speed, Unit::Rpm, speeds, p_atm)],
    );
    let times = |duration: f64| -> Vec<f64> {
        let m = (duration * plan.sample_rate_hz).round() as usize;
        (0..=m).map(|k| k as f64 / plan.sample_rate_hz).collect()
    };
    let t_ramp = times(plan.ramp_duration_s);
    let p_ramp: Vec<f64> = t_ramp
        .iter()
        .map(|t| p_atm + (plan.p_supply_pa - p_atm) * t / plan.ramp_duration_s)
        .collect();
    let ramp = experiment_data(
        Kind::PressureRamp,
        "ramp.csv",
        None,
        plan.brake,
        vec![
            input_column(Quantity::Time, Unit::S, t_ramp.clone(), p_atm),
            input_column(Quantity::PPort1, Unit::Mpa, p_ramp, p_atm),
        ],
    );
    let t_thr = times(plan.throttle_duration_s);
    let (c_hi, c_lo) = plan.c_port2_range;
    let c: Vec<f64> = t_thr
        .iter()
        .map(|t| c_hi * (c_lo / c_hi).powf(t / plan.throttle_duration_s))
        .collect();
    let throttle = experiment_data(
        Kind::OutletThrottle,
        "throttle.csv",
        Some(plan.p_supply_pa),
        plan.brake,
        vec![
            input_column(Quantity::Time, Unit::S, t_thr, p_atm),
            input_column(Quantity::CPort2, Unit::M3SPa, c, p_atm),
        ],
    );
    vec![datasheet, ramp, throttle]
}

/// Simulates each planned experiment and adds its measured channels, with noise.
pub fn synthesize(
    motor: &Motor,
    solver: &dyn StiffSolver,
    plan: &SynthPlan,
    noise: &SensorNoise,
    seed: u64,
) -> Result<Vec<ExperimentData>, SimError> {
    let w_free = free_speed(motor, plan.p_supply_pa, plan.p_atm_pa)?;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut out = Vec::new();
    for mut data in plan_experiments(plan, w_free) {
        let sim = Experiment::new(&data, plan.p_atm_pa)?.simulate(motor, solver)?;
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
            let clean = sim.channel(*q).expect("simulated channel");
            let noisy = add_noise(clean, sd, &mut rng);
            data.recording
                .columns
                .push(input_column(*q, *u, noisy, plan.p_atm_pa));
        }
        // Recorded inputs carry their own sensor noise (the simulation saw the true input).
        for col in &mut data.recording.columns {
            let perturbed: Option<Vec<f64>> = match col.quantity {
                Quantity::PPort1 => Some(add_noise(&col.si, noise.pressure_pa, &mut rng)),
                Quantity::CPort2 => Some(
                    add_noise(&vec![0.0; col.si.len()], noise.conductance_rel, &mut rng)
                        .iter()
                        .zip(&col.si)
                        .map(|(e, c)| c * e.exp())
                        .collect(),
                ),
                _ => None,
            };
            if let Some(si) = perturbed {
                *col = input_column(col.quantity, col.unit, si, plan.p_atm_pa);
            }
        }
        out.push(data);
    }
    Ok(out)
}

fn add_noise(values: &[f64], sd: f64, rng: &mut Xoshiro256PlusPlus) -> Vec<f64> {
    if sd <= 0.0 {
        return values.to_vec();
    }
    let normal = Normal::new(0.0, sd).expect("finite positive sd");
    values.iter().map(|v| v + normal.sample(rng)).collect()
}

/// Renders a recording as CSV text (header, then one line per row, raw values).
fn recording_csv(rec: &Recording) -> String {
    let mut s = rec
        .columns
        .iter()
        .map(|c| c.name.as_str())
        .collect::<Vec<_>>()
        .join(",");
    s.push('\n');
    for r in 0..rec.rows() {
        let row: Vec<&str> = rec.columns.iter().map(|c| &c.raw[r]).collect();
        s.push_str(&row.join(","));
        s.push('\n');
    }
    s
}

/// Writes a dataset folder: rig.toml (marked synthetic) and one CSV per experiment.
pub fn write_dataset(
    dir: &Path,
    experiments: &[ExperimentData],
    plan: &SynthPlan,
    motor: &Motor,
    effects: &EffectSet,
    description: &str,
) -> Result<(), DataError> {
    let io = |e: std::io::Error| DataError::new(dir, format!("cannot write: {e}"));
    std::fs::create_dir_all(dir).map_err(io)?;
    let mut rig = String::new();
    let p = motor.params();
    let _ = writeln!(
        rig,
        "# Synthetic dataset written by vanefit synth. {description}"
    );
    let _ = writeln!(rig, "synthetic = true");
    let _ = writeln!(
        rig,
        "description = {:?}",
        format!("{description} effects: [{}]", effects.ids().join(", "))
    );
    let _ = writeln!(rig, "\n[motor]\nname = \"AR034-11 (simulated)\"\nvanes = {}\ndisplacement_m3 = {:e}\nexpansion_ratio = {}", p.vanes(), p.v_disp(), p.eps());
    let _ = writeln!(
        rig,
        "\n[conditions]\np_atm_pa = {}\ntemperature_k = {}",
        plan.p_atm_pa,
        crate::units::constants::T0_K
    );
    for ex in experiments {
        let _ = writeln!(
            rig,
            "\n[[experiment]]\nkind = \"{}\"\nfile = \"{}\"",
            ex.kind.id(),
            ex.file
        );
        if let Some(ps) = ex.p_supply_pa {
            let _ = writeln!(rig, "p_supply_mpa = {}", ps * 1e-6);
        }
        match ex.load {
            Load::None => {}
            Load::ViscousBrake { c_nm_s_rad } => {
                let _ = writeln!(
                    rig,
                    "load = {{ kind = \"viscous_brake\", c_nm_s_rad = {c_nm_s_rad:e} }}"
                );
            }
            Load::Torque { t_nm } => {
                let _ = writeln!(rig, "load = {{ kind = \"torque\", t_nm = {t_nm:e} }}");
            }
            // rig.toml has no combined load (only an FMU's user sets one): brake, then torque.
            Load::BrakeAndTorque { c_nm_s_rad, t_nm } => {
                let _ = writeln!(
                    rig,
                    "load = {{ kind = \"viscous_brake\", c_nm_s_rad = {c_nm_s_rad:e} }}\n# and a constant torque of {t_nm:e} N*m, which rig.toml cannot state"
                );
            }
        }
        crate::io::write_atomic(&dir.join(&ex.file), recording_csv(&ex.recording).as_bytes())
            .map_err(io)?;
    }
    crate::io::write_atomic(&dir.join("rig.toml"), rig.as_bytes()).map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference motor's rig is the paper's; a motor s times its size gets a brake
    /// c × s^{4/3}, throttle conductances × s^⅔ and sensor noise following its flows
    /// (s^⅔), speeds (s^{-⅓}) and torques (s).
    #[test]
    fn the_rig_follows_the_motor_size() {
        assert_eq!(SynthPlan::for_motor(3.8e-6), SynthPlan::default());
        assert_eq!(SensorNoise::typical_for(3.8e-6), SensorNoise::typical());
        let s: f64 = 8.0;
        let plan = SynthPlan::for_motor(8.0 * 3.8e-6);
        let Load::ViscousBrake { c_nm_s_rad } = plan.brake else {
            panic!("{:?}", plan.brake)
        };
        assert!(
            (c_nm_s_rad / (1e-4 * 16.0) - 1.0).abs() < 1e-12,
            "{c_nm_s_rad}"
        );
        assert!((plan.c_port2_range.0 / (3e-8 * 4.0) - 1.0).abs() < 1e-12);
        let n = SensorNoise::typical_for(s * 3.8e-6);
        let t = SensorNoise::typical();
        assert!((n.flow_kg_s / (t.flow_kg_s * 4.0) - 1.0).abs() < 1e-12);
        assert!((n.speed_rad_s / (t.speed_rad_s / 2.0) - 1.0).abs() < 1e-12);
        assert!((n.torque_nm / (t.torque_nm * 8.0) - 1.0).abs() < 1e-12);
        assert_eq!(n.pressure_pa, t.pressure_pa);
    }
}
