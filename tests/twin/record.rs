//! Sensors and files: noise, offsets, column units, and the dataset writer (docs/formats.md,
//! "Datasets" and "Fit files").

use super::experiment::{self, Conditions, DatasheetRows, TransientRows};
use super::motor::{TwinMotor, RHO0_KG_M3};
use rand::{Rng, SeedableRng};
use rand_distr::Normal;
use rand_xoshiro::Xoshiro256PlusPlus;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

/// Gaussian sensor noise, 1σ per channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseSigmas {
    /// Port-1 mass flow, g/s.
    pub flow1_g_s: f64,
    /// Port-2 mass flow, g/s.
    pub flow2_g_s: f64,
    /// Speed of the transient recordings, rpm.
    pub speed_rpm: f64,
    /// Datasheet shaft torque, N·m.
    pub torque_nm: f64,
    /// Brake-torque channel of the transient recordings, N·m.
    pub brake_torque_nm: f64,
    /// Recorded port-1 pressure (the ramp's input as measured), Pa.
    pub p_port1_pa: f64,
    /// Recorded port-2 conductance, relative (0.005 = 0.5 %), 1.
    pub c_port2_rel: f64,
}

impl NoiseSigmas {
    /// The shipped dataset's noise (measurements/ar034-synthetic, estimated from its
    /// residuals): flows 0.01 g/s, speed 5 rpm, torques 2 mN·m, pressure 1 kPa, conductance
    /// 0.5 %.
    pub const TYPICAL: NoiseSigmas = NoiseSigmas {
        flow1_g_s: 0.01,
        flow2_g_s: 0.01,
        speed_rpm: 5.0,
        torque_nm: 0.002,
        brake_torque_nm: 0.002,
        p_port1_pa: 1000.0,
        c_port2_rel: 0.005,
    };
    /// No noise at all.
    pub const NONE: NoiseSigmas = NoiseSigmas {
        flow1_g_s: 0.0,
        flow2_g_s: 0.0,
        speed_rpm: 0.0,
        torque_nm: 0.0,
        brake_torque_nm: 0.0,
        p_port1_pa: 0.0,
        c_port2_rel: 0.0,
    };

    /// Every σ multiplied by k.
    pub fn scaled(&self, k: f64) -> Self {
        NoiseSigmas {
            flow1_g_s: k * self.flow1_g_s,
            flow2_g_s: k * self.flow2_g_s,
            speed_rpm: k * self.speed_rpm,
            torque_nm: k * self.torque_nm,
            brake_torque_nm: k * self.brake_torque_nm,
            p_port1_pa: k * self.p_port1_pa,
            c_port2_rel: k * self.c_port2_rel,
        }
    }
}

/// Constant sensor offsets of the rig's channels (ramp and throttle; the datasheet comes from
/// the manufacturer and has none).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Offsets {
    /// Port-1 flow, g/s.
    pub flow1_g_s: f64,
    /// Port-2 flow, g/s.
    pub flow2_g_s: f64,
    /// Speed, rpm.
    pub speed_rpm: f64,
    /// Brake torque, N·m.
    pub brake_torque_nm: f64,
    /// Recorded port-1 pressure, Pa.
    pub p_port1_pa: f64,
}

/// Where the offsets come from.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum OffsetSpec {
    /// No offsets.
    #[default]
    None,
    /// These values.
    Given(Offsets),
    /// Each channel's offset drawn from N(0, tol²) (tol is the 1σ calibration tolerance)
    /// with its own seed.
    Drawn {
        /// 1σ tolerance per channel (same units as [`Offsets`]).
        tol: Offsets,
        /// Seed of the draw.
        seed: u64,
    },
}

impl OffsetSpec {
    /// The offsets this spec stands for.
    pub fn resolve(&self) -> Offsets {
        match *self {
            OffsetSpec::None => Offsets::default(),
            OffsetSpec::Given(o) => o,
            OffsetSpec::Drawn { tol, seed } => {
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
                let mut draw = |s: f64| s * rng.sample::<f64, _>(rand_distr::StandardNormal);
                Offsets {
                    flow1_g_s: draw(tol.flow1_g_s),
                    flow2_g_s: draw(tol.flow2_g_s),
                    speed_rpm: draw(tol.speed_rpm),
                    brake_torque_nm: draw(tol.brake_torque_nm),
                    p_port1_pa: draw(tol.p_port1_pa),
                }
            }
        }
    }
}

/// Unit of the flow columns ((docs/formats.md, "CSV recordings"); ANR free air at ρ0 = 1.185 kg/m³,
/// as vanefit reads it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FlowUnit {
    /// g/s (`_g_s`).
    #[default]
    GS,
    /// Free-air l/min ANR (`_l_min_anr`): kg/s = v·1e-3·ρ0/60.
    LMinAnr,
}

/// Unit of the port-1 pressure column.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PressureUnit {
    /// MPa absolute (`_mpa`).
    #[default]
    Mpa,
    /// bar absolute (`_bar_abs`).
    BarAbs,
}

/// Unit of the speed columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SpeedUnit {
    /// rpm (`_rpm`).
    #[default]
    Rpm,
    /// rad/s (`_rad_s`).
    RadS,
}

/// The CSV column units (default: the shipped dataset's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Units {
    /// Flow columns.
    pub flow: FlowUnit,
    /// Port-1 pressure column.
    pub pressure: PressureUnit,
    /// Speed columns.
    pub speed: SpeedUnit,
}

impl Units {
    /// Flow column suffix and the value in that unit of a flow in kg/s.
    pub fn flow(&self, kg_s: f64) -> (&'static str, f64) {
        match self.flow {
            FlowUnit::GS => ("g_s", kg_s * 1e3),
            FlowUnit::LMinAnr => ("l_min_anr", kg_s * 60.0 / (1e-3 * RHO0_KG_M3)),
        }
    }
    /// Pressure column suffix and the value in that unit of a pressure in Pa.
    pub fn pressure(&self, pa: f64) -> (&'static str, f64) {
        match self.pressure {
            PressureUnit::Mpa => ("mpa", pa * 1e-6),
            PressureUnit::BarAbs => ("bar_abs", pa * 1e-5),
        }
    }
    /// Speed column suffix and the value in that unit of a speed in rad/s.
    pub fn speed(&self, rad_s: f64) -> (&'static str, f64) {
        match self.speed {
            SpeedUnit::Rpm => ("rpm", rad_s * 30.0 / std::f64::consts::PI),
            SpeedUnit::RadS => ("rad_s", rad_s),
        }
    }
}

/// Everything about a recording that is not the motor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RecordConfig {
    /// Physical conditions: supply pressure (Pa), sample rate (Hz), datasheet points, …
    pub conditions: Conditions,
    /// Sensor noise.
    pub noise: NoiseSigmas,
    /// Sensor offsets.
    pub offsets: OffsetSpec,
    /// Record the brake torque c·ω as `torque_nm` in the ramp and the throttle.
    pub brake_torque: bool,
    /// CSV column units.
    pub units: Units,
}

impl Default for RecordConfig {
    /// The shipped dataset's conventions: 10 Hz, 25 datasheet points, 0.73 MPa, typical
    /// noise, no offsets, no brake-torque channel, g/s, MPa and rpm.
    fn default() -> Self {
        Self {
            conditions: Conditions::default(),
            noise: NoiseSigmas::TYPICAL,
            offsets: OffsetSpec::None,
            brake_torque: false,
            units: Units::default(),
        }
    }
}

impl RecordConfig {
    /// The default conditions without noise or offsets (for exact comparisons).
    pub fn noise_free() -> Self {
        Self {
            noise: NoiseSigmas::NONE,
            ..Self::default()
        }
    }
}

/// What [`write_dataset`] wrote: the noise-free truth (SI) and the offsets applied.
#[derive(Debug, Clone, PartialEq)]
pub struct WrittenDataset {
    /// Noise-free datasheet.
    pub datasheet: DatasheetRows,
    /// Noise-free pressure ramp.
    pub ramp: TransientRows,
    /// Noise-free outlet throttle.
    pub throttle: TransientRows,
    /// The sensor offsets in the files.
    pub offsets: Offsets,
}

/// Gaussian noise source: N(0, σ²) per call, σ = 0 gives exactly 0.
struct Noise(Xoshiro256PlusPlus);

impl Noise {
    fn draw(&mut self, sigma: f64) -> f64 {
        let n = Normal::new(0.0, sigma.max(0.0)).expect("finite σ");
        self.0.sample(n)
    }
}

/// A CSV under construction: header and rows of already-converted values.
struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    fn text(&self) -> String {
        let mut s = self.header.join(",") + "\n";
        for row in &self.rows {
            let cells: Vec<String> = row.iter().map(|v| format!("{v:e}")).collect();
            let _ = writeln!(s, "{}", cells.join(","));
        }
        s
    }
}

fn datasheet_csv(rows: &DatasheetRows, cfg: &RecordConfig, noise: &mut Noise) -> Csv {
    let u = cfg.units;
    let sig = cfg.noise;
    let header = vec![
        format!("speed_{}", u.speed(0.0).0),
        "torque_nm".to_string(),
        format!("flow1_{}", u.flow(0.0).0),
    ];
    let mut out = Vec::new();
    for i in 0..rows.speed_rad_s.len() {
        let torque = rows.torque_nm[i] + noise.draw(sig.torque_nm);
        let flow1 = rows.flow1_kg_s[i] + 1e-3 * noise.draw(sig.flow1_g_s);
        out.push(vec![
            u.speed(rows.speed_rad_s[i]).1,
            torque,
            u.flow(flow1).1,
        ]);
    }
    Csv { header, rows: out }
}

/// A recording's input column: its header, and the measured value in the column unit of a
/// true input (Pa or m³/(s·Pa)), drawing noise from the source.
type InputColumn<'a> = (String, &'a mut dyn FnMut(f64, &mut Noise) -> f64);

/// A transient recording's CSV; `input_column` gives the input's header and, per row, its
/// measured value in the column unit.
fn transient_csv(
    rows: &TransientRows,
    cfg: &RecordConfig,
    off: &Offsets,
    noise: &mut Noise,
    input_column: InputColumn<'_>,
) -> Csv {
    let (u, sig) = (cfg.units, cfg.noise);
    let (input_name, input_value) = input_column;
    let mut header = vec!["t_s".to_string(), input_name];
    header.push(format!("flow1_{}", u.flow(0.0).0));
    header.push(format!("flow2_{}", u.flow(0.0).0));
    header.push(format!("speed_{}", u.speed(0.0).0));
    if cfg.brake_torque {
        header.push("torque_nm".to_string());
    }
    let rpm = std::f64::consts::PI / 30.0;
    let mut out = Vec::new();
    for i in 0..rows.t_s.len() {
        let input = input_value(rows.input[i], noise);
        let f1 = rows.flow1_kg_s[i] + 1e-3 * (off.flow1_g_s + noise.draw(sig.flow1_g_s));
        let f2 = rows.flow2_kg_s[i] + 1e-3 * (off.flow2_g_s + noise.draw(sig.flow2_g_s));
        let w = rows.speed_rad_s[i] + rpm * (off.speed_rpm + noise.draw(sig.speed_rpm));
        let mut row = vec![rows.t_s[i], input, u.flow(f1).1, u.flow(f2).1, u.speed(w).1];
        if cfg.brake_torque {
            let tq = off.brake_torque_nm + noise.draw(sig.brake_torque_nm);
            row.push(rows.brake_torque_nm[i] + tq);
        }
        out.push(row);
    }
    Csv { header, rows: out }
}

/// Simulates the three experiments and writes `dir/rig.toml`, `datasheet.csv`, `ramp.csv`,
/// `throttle.csv` and `truth.json` (vanefit.fit/1, the twin-only truth under `"twin"`).
/// The same motor, config and seed give identical files.
pub fn write_dataset(
    dir: &Path,
    motor: &TwinMotor,
    cfg: &RecordConfig,
    seed: u64,
) -> io::Result<WrittenDataset> {
    let c = &cfg.conditions;
    let datasheet = experiment::datasheet(motor, c).map_err(io::Error::other)?;
    let ramp = experiment::pressure_ramp(motor, c).map_err(io::Error::other)?;
    let throttle = experiment::outlet_throttle(motor, c).map_err(io::Error::other)?;
    let off = cfg.offsets.resolve();
    let mut noise = Noise(Xoshiro256PlusPlus::seed_from_u64(seed));
    let (u, sig) = (cfg.units, cfg.noise);
    let ds_csv = datasheet_csv(&datasheet, cfg, &mut noise);
    let mut p_in =
        |p_pa: f64, n: &mut Noise| u.pressure(p_pa + off.p_port1_pa + n.draw(sig.p_port1_pa)).1;
    let p_name = format!("p_port1_{}", u.pressure(0.0).0);
    let ramp_csv = transient_csv(&ramp, cfg, &off, &mut noise, (p_name, &mut p_in));
    let mut c_in = |c: f64, n: &mut Noise| c * (1.0 + n.draw(sig.c_port2_rel));
    let c_name = "c_port2_m3_s_pa".to_string();
    let thr_csv = transient_csv(&throttle, cfg, &off, &mut noise, (c_name, &mut c_in));
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join("datasheet.csv"), ds_csv.text())?;
    std::fs::write(dir.join("ramp.csv"), ramp_csv.text())?;
    std::fs::write(dir.join("throttle.csv"), thr_csv.text())?;
    std::fs::write(
        dir.join("rig.toml"),
        super::files::rig_toml(motor, cfg, seed, &off),
    )?;
    let name = dir
        .file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned());
    let truth = super::files::truth_json(motor, &name, cfg, seed, &off);
    std::fs::write(
        dir.join("truth.json"),
        serde_json::to_string_pretty(&truth)? + "\n",
    )?;
    Ok(WrittenDataset {
        datasheet,
        ramp,
        throttle,
        offsets: off,
    })
}

/// A reference experiment recorded on its own by [`write_experiment`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Experiment {
    /// Torque and air at `datasheet_points` speeds from 0 to the free speed.
    Datasheet,
    /// Port 1 from atmosphere to the supply pressure, shaft on the brake.
    PressureRamp,
    /// The outlet throttle's sweep at the supply pressure, shaft on the brake.
    OutletThrottle,
}

/// One more experiment on the rig of `cfg` (the same sensor offsets, a fresh noise draw from
/// `seed`) under `cfg.conditions` (supply pressure, throttle range, datasheet points, rate),
/// written as `dir/file` in the same columns as [`write_dataset`]'s; returns its
/// `[[experiment]]` entry for rig.toml.
pub fn write_experiment(
    dir: &Path,
    motor: &TwinMotor,
    cfg: &RecordConfig,
    seed: u64,
    kind: Experiment,
    file: &str,
) -> io::Result<String> {
    let c = &cfg.conditions;
    let off = cfg.offsets.resolve();
    let mut noise = Noise(Xoshiro256PlusPlus::seed_from_u64(seed));
    let (u, sig) = (cfg.units, cfg.noise);
    let p_mpa = c.p_supply_pa * 1e-6;
    let load = format!(
        "load = {{ kind = \"viscous_brake\", c_nm_s_rad = {:e} }}",
        c.brake_nm_s_rad
    );
    let (csv, entry) = match kind {
        Experiment::Datasheet => {
            let rows = experiment::datasheet(motor, c).map_err(io::Error::other)?;
            (
                datasheet_csv(&rows, cfg, &mut noise),
                format!("kind = \"datasheet\"\nfile = \"{file}\"\np_supply_mpa = {p_mpa}\n"),
            )
        }
        Experiment::PressureRamp => {
            let rows = experiment::pressure_ramp(motor, c).map_err(io::Error::other)?;
            let mut p_in = |p_pa: f64, n: &mut Noise| {
                u.pressure(p_pa + off.p_port1_pa + n.draw(sig.p_port1_pa)).1
            };
            let p_name = format!("p_port1_{}", u.pressure(0.0).0);
            (
                transient_csv(&rows, cfg, &off, &mut noise, (p_name, &mut p_in)),
                format!("kind = \"pressure_ramp\"\nfile = \"{file}\"\n{load}\n"),
            )
        }
        Experiment::OutletThrottle => {
            let rows = experiment::outlet_throttle(motor, c).map_err(io::Error::other)?;
            let mut c_in = |c: f64, n: &mut Noise| c * (1.0 + n.draw(sig.c_port2_rel));
            let c_name = "c_port2_m3_s_pa".to_string();
            (
                transient_csv(&rows, cfg, &off, &mut noise, (c_name, &mut c_in)),
                format!(
                    "kind = \"outlet_throttle\"\nfile = \"{file}\"\np_supply_mpa = {p_mpa}\n{load}\n"
                ),
            )
        }
    };
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join(file), csv.text())?;
    Ok(format!("\n[[experiment]]\n{entry}"))
}
