//! `vanefit control <study>`: the speed-control studies of paper §5 from a parameter set,
//! each writing CSV tables and SVG figures into `--out` (atomically) and printing a summary.
//!
//! Studies: `throttle-inlet`, `throttle-outlet` (Figs. 14, 15), `bode` (Figs. 16, 17),
//! `step` (Fig. 19), `disturbance` (Fig. 20), `min-speed` (§5.2's 2900 vs 365 rpm) and
//! `design` (PI gains for a phase margin or crossover, checked by simulation).
//!
//! CSV columns carry their unit in the name, as the data files do (SPEC §3): speeds in rpm,
//! pressures in MPa absolute, conductances in m3/(s*Pa), torques in N*m, flows in g/s,
//! commands in V.

use crate::cli::Failure;
use crate::control::closed_loop::{
    disturbance_metrics, step_metrics, AntiWindup, Loop, PiController, Scenario, Steps, Trace,
    Valve, ValveDynamics,
};
use crate::control::design::{design_pi, margins, open_loop, plant, Margins, Target};
use crate::control::linear::{
    fit_two_lags, log_grid, operating_point, rad_s, two_lag_guess, unwrapped_phase_deg, LinearModel,
};
use crate::control::min_speed::{closed_loop_min_speed, open_loop_start, ramp_simulation};
use crate::control::throttle::{conductance_grid, speed_vs_conductance, torque_speed, Port};
use crate::control::{ControlError, RAD_S_PER_RPM};
use crate::data::fitfile::FitFile;
use crate::model::effects::EffectSet;
use crate::model::motor::{idx, Boundary, Load, Motor};
use crate::model::params::MotorParams;
use crate::numerics::ode::DiffsolBdf;
use crate::report::plot::{Chart, Figure, Legend, Series};
use crate::units::constants::P_ATM_PA;
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};

/// `vanefit control` arguments.
#[derive(Args, Debug)]
pub struct ControlArgs {
    #[command(subcommand)]
    pub study: Study,
}

/// The studies.
#[derive(Subcommand, Debug)]
pub enum Study {
    /// Steady speed against the conductance of an inlet throttle, and torque-speed curves
    /// for several inlet throttles (paper Figs. 14, 15).
    #[command(allow_negative_numbers = true)]
    ThrottleInlet(ThrottleArgs),
    /// The same with the throttle behind port 2.
    #[command(allow_negative_numbers = true)]
    ThrottleOutlet(ThrottleArgs),
    /// Frequency response supply pressure -> speed about an operating point, fit of two
    /// first-order lags (paper Fig. 16), and valve + motor (Fig. 17).
    #[command(allow_negative_numbers = true)]
    Bode(BodeArgs),
    /// Closed-loop response to a speed set-point step (paper Fig. 19).
    #[command(allow_negative_numbers = true)]
    Step(StepArgs),
    /// Closed-loop rejection of a load-torque step (paper Fig. 20).
    #[command(allow_negative_numbers = true)]
    Disturbance(DisturbanceArgs),
    /// Lowest steady speed without control (pressure-ramp start-up) and with control.
    #[command(allow_negative_numbers = true)]
    MinSpeed(MinSpeedArgs),
    /// PI gains for a phase margin or crossover, checked by closed-loop simulation.
    #[command(allow_negative_numbers = true)]
    Design(DesignArgs),
}

/// Options every study takes.
#[derive(Args, Debug)]
pub struct CommonArgs {
    /// Fit file (vanefit.fit/1); omitted: the default motor.
    #[arg(long)]
    pub params: Option<PathBuf>,
    /// Effects to switch on (comma-separated ids), overriding the fit file's.
    #[arg(long)]
    pub effects: Option<String>,
    /// Output folder (created); default `./control-<study>`.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Eddy-current brake on the shaft, N*m*s/rad (default 1e-4; 0 for min-speed, which the
    /// paper reports without load).
    #[arg(long)]
    pub brake_nm_s_rad: Option<f64>,
}

#[derive(Args, Debug)]
pub struct ThrottleArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Constant supply pressure, MPa absolute.
    #[arg(long, default_value_t = 0.73)]
    pub p_supply_mpa: f64,
    /// Smallest throttle conductance, m3/(s*Pa).
    #[arg(long, default_value_t = 3e-10)]
    pub c_min_m3_s_pa: f64,
    /// Largest throttle conductance, m3/(s*Pa).
    #[arg(long, default_value_t = 1e-7)]
    pub c_max_m3_s_pa: f64,
    /// Number of conductances (log-spaced).
    #[arg(long, default_value_t = 40)]
    pub points: usize,
    /// Throttles for the torque-speed curves, comma-separated m3/(s*Pa); "none" for no
    /// throttle.
    #[arg(long, default_value = "none,1e-8,4e-9,2e-9,1e-9")]
    pub curves_m3_s_pa: String,
}

#[derive(Args, Debug)]
pub struct BodeArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    #[command(flatten)]
    pub valve: ValveArgs,
    /// Mean supply pressure of the operating point, MPa absolute.
    #[arg(long, default_value_t = 0.35)]
    pub p_mean_mpa: f64,
    #[arg(long, default_value_t = 0.01)]
    pub f_min_hz: f64,
    #[arg(long, default_value_t = 100.0)]
    pub f_max_hz: f64,
    /// Number of frequencies (log-spaced); the two-lag fit uses all of them.
    #[arg(long, default_value_t = 200)]
    pub points: usize,
}

/// The pressure control valve.
#[derive(Args, Debug)]
pub struct ValveArgs {
    /// Valve time constant, s (default: the parameter set's valve_tau, 0.05 s). The valve is
    /// first order unless the valve_dynamics effect is on (then second order with
    /// valve_zeta).
    #[arg(long)]
    pub valve_tau_s: Option<f64>,
    /// Command for full pressure, V.
    #[arg(long, default_value_t = 10.0)]
    pub valve_u_max_v: f64,
    /// Gauge pressure at full command, bar.
    #[arg(long, default_value_t = 6.0)]
    pub valve_p_max_bar_g: f64,
}

/// Controller settings other than the gains.
#[derive(Args, Debug)]
pub struct PiArgs {
    /// Sample time, ms.
    #[arg(long, default_value_t = 1.0)]
    pub ts_ms: f64,
    /// Speed unit of the controller's error, rpm (1000: error in krpm, command in V).
    #[arg(long, default_value_t = 1000.0)]
    pub speed_unit_rpm: f64,
    /// conditional, back-calculation or none.
    #[arg(long, default_value = "conditional")]
    pub anti_windup: String,
}

/// PI gains (paper: G(s) = (0.85 s + 4)/s).
#[derive(Args, Debug)]
pub struct GainArgs {
    /// Proportional gain, V per speed unit.
    #[arg(long, default_value_t = 0.85)]
    pub kp: f64,
    /// Integral gain, V per speed unit per s.
    #[arg(long, default_value_t = 4.0)]
    pub ki: f64,
}

#[derive(Args, Debug)]
pub struct StepArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    #[command(flatten)]
    pub valve: ValveArgs,
    #[command(flatten)]
    pub pi: PiArgs,
    #[command(flatten)]
    pub gains: GainArgs,
    /// Set-point before the step, rpm (the loop starts settled there).
    #[arg(long, default_value_t = 3000.0)]
    pub from_rpm: f64,
    /// Set-point after the step, rpm.
    #[arg(long, default_value_t = 4500.0)]
    pub to_rpm: f64,
    #[arg(long, default_value_t = 0.5)]
    pub t_step_s: f64,
    #[arg(long, default_value_t = 8.0)]
    pub duration_s: f64,
}

#[derive(Args, Debug)]
pub struct DisturbanceArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    #[command(flatten)]
    pub valve: ValveArgs,
    #[command(flatten)]
    pub pi: PiArgs,
    #[command(flatten)]
    pub gains: GainArgs,
    /// Speed set-point, rpm.
    #[arg(long, default_value_t = 4000.0)]
    pub rpm: f64,
    /// Extra load torque switched on at --t-step-s, N*m.
    #[arg(long, default_value_t = 0.03)]
    pub load_step_nm: f64,
    #[arg(long, default_value_t = 0.5)]
    pub t_step_s: f64,
    #[arg(long, default_value_t = 8.0)]
    pub duration_s: f64,
}

#[derive(Args, Debug)]
pub struct MinSpeedArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    #[command(flatten)]
    pub valve: ValveArgs,
    #[command(flatten)]
    pub pi: PiArgs,
    #[command(flatten)]
    pub gains: GainArgs,
    /// Top of the pressure ramp, MPa absolute (the paper's 0.73).
    #[arg(long, default_value_t = 0.73)]
    pub p_max_mpa: f64,
    /// Duration of the simulated pressure ramp, s (the paper's rig: 60 s).
    #[arg(long, default_value_t = 60.0)]
    pub ramp_s: f64,
    /// Each closed-loop candidate set-point is this fraction of the previous one.
    #[arg(long, default_value_t = 0.8)]
    pub factor: f64,
    /// Lowest set-point tried, rpm (default: 5·max(w_reg, 1 rad/s), about 48 rpm, below
    /// which the model's friction regularisation, not physics, sets the behaviour).
    #[arg(long)]
    pub floor_rpm: Option<f64>,
    /// Duration of each stage of the set-point staircase, s (its last 2 s judge whether the
    /// set-point is held).
    #[arg(long, default_value_t = 5.0)]
    pub stage_s: f64,
}

#[derive(Args, Debug)]
pub struct DesignArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    #[command(flatten)]
    pub valve: ValveArgs,
    #[command(flatten)]
    pub pi: PiArgs,
    /// Requested phase margin, degrees.
    #[arg(long, default_value_t = 60.0)]
    pub pm_deg: f64,
    /// Requested crossover (bandwidth), Hz; omitted: the highest crossover at which a PI
    /// gives the phase margin with 15° of its own lag.
    #[arg(long)]
    pub crossover_hz: Option<f64>,
    /// Mean supply pressure of the operating point, MPa absolute.
    #[arg(long, default_value_t = 0.35)]
    pub p_mean_mpa: f64,
    /// Set-point step of the check simulation, rpm (from the operating point's speed).
    #[arg(long, default_value_t = 300.0)]
    pub step_rpm: f64,
    #[arg(long, default_value_t = 5.0)]
    pub duration_s: f64,
}

/// Runs `vanefit control <study>`.
pub fn run(args: ControlArgs) -> Result<(), Failure> {
    let r = match &args.study {
        Study::ThrottleInlet(a) => throttle(a, Port::Inlet),
        Study::ThrottleOutlet(a) => throttle(a, Port::Outlet),
        Study::Bode(a) => bode(a),
        Study::Step(a) => step(a),
        Study::Disturbance(a) => disturbance(a),
        Study::MinSpeed(a) => min_speed(a),
        Study::Design(a) => design(a),
    };
    r.map_err(|e| Failure(e.0))
}

// ---------------------------------------------------------------------------------------
// Option checking and set-up

fn bad(option: &str, v: impl std::fmt::Display, must: &str) -> ControlError {
    ControlError(format!("{option} {v}: must be {must}"))
}

fn positive(option: &str, v: f64) -> Result<f64, ControlError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(bad(option, v, "a number > 0"))
    }
}

fn non_negative(option: &str, v: f64) -> Result<f64, ControlError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(bad(option, v, "a number >= 0"))
    }
}

/// The motor, brake and output folder of a study.
struct Setup {
    motor: Motor,
    load: Load,
    out: PathBuf,
}

fn setup(c: &CommonArgs, study: &str, default_brake: f64) -> Result<Setup, ControlError> {
    let (params, mut effects) = match &c.params {
        Some(p) => {
            let f = FitFile::read(p).map_err(|e| ControlError(e.to_string()))?;
            (f.params, f.effects)
        }
        None => (MotorParams::default(), EffectSet::empty()),
    };
    if let Some(list) = &c.effects {
        effects =
            EffectSet::parse_list(list).map_err(|m| ControlError(format!("--effects: {m}")))?;
    }
    let brake = non_negative(
        "--brake-nm-s-rad",
        c.brake_nm_s_rad.unwrap_or(default_brake),
    )?;
    let load = if brake > 0.0 {
        Load::ViscousBrake { c_nm_s_rad: brake }
    } else {
        Load::None
    };
    let out = c
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("control-{study}")));
    std::fs::create_dir_all(&out)
        .map_err(|e| ControlError(format!("--out {}: cannot create: {e}", out.display())))?;
    Ok(Setup {
        motor: Motor::new(params, effects),
        load,
        out,
    })
}

fn valve(a: &ValveArgs, motor: &Motor) -> Result<Valve, ControlError> {
    let mut v = Valve::for_motor(motor, P_ATM_PA);
    if let Some(tau) = a.valve_tau_s {
        let tau = positive("--valve-tau-s", tau)?;
        v.dynamics = match v.dynamics {
            ValveDynamics::FirstOrder { .. } => ValveDynamics::FirstOrder { tau_s: tau },
            ValveDynamics::SecondOrder { zeta, .. } => {
                ValveDynamics::SecondOrder { tau_s: tau, zeta }
            }
        };
    }
    v.u_max_v = positive("--valve-u-max-v", a.valve_u_max_v)?;
    v.p_max_gauge_pa = positive("--valve-p-max-bar-g", a.valve_p_max_bar_g)? * 1e5;
    Ok(v)
}

fn controller(
    a: &PiArgs,
    gains: Option<&GainArgs>,
    valve: &Valve,
) -> Result<PiController, ControlError> {
    let base = PiController::default();
    let (kp, ki) = match gains {
        Some(g) => (non_negative("--kp", g.kp)?, non_negative("--ki", g.ki)?),
        None => (base.kp, base.ki),
    };
    let ts = positive("--ts-ms", a.ts_ms)? * 1e-3;
    if ts > 0.1 {
        return Err(bad("--ts-ms", a.ts_ms, "at most 100 ms"));
    }
    let anti_windup: AntiWindup = a
        .anti_windup
        .parse()
        .map_err(|m: String| ControlError(format!("--anti-windup: {m}")))?;
    if anti_windup == AntiWindup::BackCalculation && (kp == 0.0 || ki == 0.0) {
        return Err(ControlError(
            "--anti-windup back-calculation needs --kp > 0 and --ki > 0 (tracking time kp/ki)"
                .into(),
        ));
    }
    Ok(PiController {
        kp,
        ki,
        ts_s: ts,
        speed_unit_rpm: positive("--speed-unit-rpm", a.speed_unit_rpm)?,
        u_min_v: 0.0,
        u_max_v: valve.u_max_v,
        anti_windup,
    })
}

fn describe_valve(v: &Valve) -> String {
    let dyn_ = match v.dynamics {
        ValveDynamics::FirstOrder { tau_s } => format!("first order, tau {tau_s} s"),
        ValveDynamics::SecondOrder { tau_s, zeta } => {
            format!("second order, tau {tau_s} s, zeta {zeta}")
        }
    };
    format!(
        "valve {dyn_}; 0-{} V -> 0-{} bar gauge",
        v.u_max_v,
        v.p_max_gauge_pa / 1e5
    )
}

fn describe_load(l: &Load) -> String {
    match l {
        Load::None => "no load".into(),
        Load::ViscousBrake { c_nm_s_rad } => format!("brake {c_nm_s_rad:e} N*m*s/rad"),
        Load::Torque { t_nm } => format!("torque {t_nm} N*m"),
    }
}

// ---------------------------------------------------------------------------------------
// Output

/// A CSV table: header names with units, rows of numbers.
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Table {
    fn new(header: &[&str]) -> Self {
        Self {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    fn push(&mut self, row: Vec<f64>) {
        debug_assert_eq!(row.len(), self.header.len());
        self.rows.push(row);
    }

    fn text(&self) -> String {
        let mut s = self.header.join(",") + "\n";
        for r in &self.rows {
            let cells: Vec<String> = r.iter().map(|v| format!("{v:.6e}")).collect();
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        s
    }
}

fn write_file(path: &Path, bytes: &[u8]) -> Result<(), ControlError> {
    crate::io::write_atomic(path, bytes)
        .map_err(|e| ControlError(format!("{}: {e}", path.display())))?;
    println!("wrote {}", path.display());
    Ok(())
}

fn write_csv(dir: &Path, name: &str, t: &Table) -> Result<(), ControlError> {
    write_file(&dir.join(name), t.text().as_bytes())
}

fn write_figure(dir: &Path, name: &str, fig: &Figure) -> Result<(), ControlError> {
    let svg = fig.to_svg().map_err(|e| ControlError(e.to_string()))?;
    write_file(&dir.join(name), svg.as_bytes())
}

fn rpm(w_rad_s: f64) -> f64 {
    w_rad_s / RAD_S_PER_RPM
}

// ---------------------------------------------------------------------------------------
// Throttling (Figs. 14, 15)

fn parse_curves(list: &str) -> Result<Vec<Option<f64>>, ControlError> {
    let mut out = Vec::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if item == "none" {
            out.push(None);
        } else {
            let v: f64 = item
                .parse()
                .map_err(|_| bad("--curves-m3-s-pa", item, "\"none\" or a conductance > 0"))?;
            out.push(Some(positive("--curves-m3-s-pa", v)?));
        }
    }
    if out.is_empty() {
        return Err(bad("--curves-m3-s-pa", list, "a non-empty list"));
    }
    Ok(out)
}

/// An absolute pressure option in MPa, checked to lie above atmosphere; returned in Pa.
fn absolute_pressure_pa(option: &str, mpa: f64) -> Result<f64, ControlError> {
    let p = positive(option, mpa)? * 1e6;
    if p <= P_ATM_PA {
        return Err(bad(option, mpa, "above atmospheric (0.101325)"));
    }
    Ok(p)
}

fn throttle(a: &ThrottleArgs, port: Port) -> Result<(), ControlError> {
    let study = format!("throttle-{}", port.name());
    let s = setup(&a.common, &study, 1e-4)?;
    let p_supply = absolute_pressure_pa("--p-supply-mpa", a.p_supply_mpa)?;
    let c_min = positive("--c-min-m3-s-pa", a.c_min_m3_s_pa)?;
    let c_max = positive("--c-max-m3-s-pa", a.c_max_m3_s_pa)?;
    if c_max <= c_min {
        return Err(bad("--c-max-m3-s-pa", c_max, "larger than --c-min-m3-s-pa"));
    }
    if a.points < 2 {
        return Err(bad("--points", a.points, "at least 2"));
    }
    let curves = parse_curves(&a.curves_m3_s_pa)?;
    let m = &s.motor;
    let c_col = match port {
        Port::Inlet => "c_port1_m3_s_pa",
        Port::Outlet => "c_port2_m3_s_pa",
    };
    let pts = speed_vs_conductance(
        m,
        port,
        p_supply,
        P_ATM_PA,
        s.load,
        &conductance_grid(c_min, c_max, a.points),
    )?;
    let mut t = Table::new(&[c_col, "speed_rpm", "torque_nm", "flow1_g_s", "p1_mpa"]);
    for p in &pts {
        t.push(vec![
            p.c_m3_s_pa,
            rpm(p.speed_rad_s),
            p.torque_nm,
            p.flow_kg_s * 1e3,
            p.p1_pa / 1e6,
        ]);
    }
    let stem = format!("throttle_{}", port.name());
    write_csv(&s.out, &format!("{stem}_speed.csv"), &t)?;

    // Torque-speed curves up to the unthrottled free speed.
    let bc = port.boundary(p_supply, P_ATM_PA, Load::None, None);
    let free = crate::sim::steady::free(m, &bc, &crate::sim::steady::initial_guess(&bc))?;
    let w_max = 1.02 * free[idx::OMEGA];
    let mut tq = Table::new(&[c_col, "speed_rpm", "torque_nm", "flow1_g_s"]);
    let mut curve_series = Vec::new();
    for c in &curves {
        let tsp = torque_speed(m, port, p_supply, P_ATM_PA, *c, w_max, 60)?;
        for p in &tsp {
            // No throttle is written as conductance 0 in the table.
            tq.push(vec![
                c.unwrap_or(0.0),
                rpm(p.speed_rad_s),
                p.torque_nm,
                p.flow_kg_s * 1e3,
            ]);
        }
        let name = c.map_or("no throttle".to_string(), |c| format!("C = {c:.2e}"));
        curve_series.push(Series::line(
            &name,
            tsp.iter()
                .map(|p| (rpm(p.speed_rad_s), p.torque_nm))
                .collect(),
        ));
    }
    write_csv(&s.out, &format!("{stem}_torque_speed.csv"), &tq)?;

    let mut speed_chart = Chart::new(
        &format!(
            "Steady speed vs {} throttle ({} MPa, {})",
            port.name(),
            a.p_supply_mpa,
            describe_load(&s.load)
        ),
        &format!("{} throttle conductance [m3/(s*Pa)]", port.name()),
        "speed [rpm]",
    )
    .log_x()
    .legend(Legend::LowerRight)
    .with(Series::line(
        "speed",
        pts.iter()
            .map(|p| (p.c_m3_s_pa, rpm(p.speed_rad_s)))
            .collect(),
    ));
    speed_chart.y_range = Some((
        0.0,
        1.05 * rpm(pts.iter().map(|p| p.speed_rad_s).fold(0.0, f64::max)).max(1.0),
    ));
    let mut torque_chart = Chart::new(
        &format!("Torque vs speed, {} throttles", port.name()),
        "speed [rpm]",
        "shaft torque [N*m]",
    );
    torque_chart.series = curve_series;
    write_figure(
        &s.out,
        &format!("{stem}.svg"),
        &Figure::new(vec![speed_chart, torque_chart], 2),
    )?;

    let (lo, hi) = (
        pts.first().expect("points >= 2"),
        pts.last().expect("points >= 2"),
    );
    println!(
        "{} throttle at {} MPa, {}: speed {:.0} rpm at C = {:.2e} .. {:.0} rpm at C = {:.2e} \
        m3/(s*Pa) (unthrottled free speed without load {:.0} rpm)",
        port.name(),
        a.p_supply_mpa,
        describe_load(&s.load),
        rpm(lo.speed_rad_s),
        lo.c_m3_s_pa,
        rpm(hi.speed_rad_s),
        hi.c_m3_s_pa,
        rpm(free[idx::OMEGA])
    );
    if let Some(w) = pts.windows(2).find(|w| {
        w[0].speed_rad_s < 0.5 * hi.speed_rad_s && w[1].speed_rad_s >= 0.5 * hi.speed_rad_s
    }) {
        println!(
            "  half of that speed at C ~ {:.2e} m3/(s*Pa)",
            (w[0].c_m3_s_pa * w[1].c_m3_s_pa).sqrt()
        );
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Frequency response (Figs. 16, 17)

fn linear_at(m: &Motor, load: Load, p_mean_pa: f64) -> Result<LinearModel, ControlError> {
    let op = operating_point(m, &Boundary::supplied(p_mean_pa, P_ATM_PA, load))?;
    LinearModel::linearise(m, &op)
}

fn bode(a: &BodeArgs) -> Result<(), ControlError> {
    let s = setup(&a.common, "bode", 1e-4)?;
    let p_mean = positive("--p-mean-mpa", a.p_mean_mpa)? * 1e6;
    let f_min = positive("--f-min-hz", a.f_min_hz)?;
    let f_max = positive("--f-max-hz", a.f_max_hz)?;
    if f_max <= f_min {
        return Err(bad("--f-max-hz", f_max, "larger than --f-min-hz"));
    }
    if a.points < 5 {
        return Err(bad("--points", a.points, "at least 5"));
    }
    let v = valve(&a.valve, &s.motor)?;
    let pi = PiController::default();
    let lin = linear_at(&s.motor, s.load, p_mean)?;
    let f = log_grid(f_min, f_max, a.points);
    let w: Vec<f64> = f.iter().map(|f| rad_s(*f)).collect();
    let g: Vec<_> = w.iter().map(|w| lin.speed_per_supply(*w)).collect();
    let fit = fit_two_lags(&w, &g, two_lag_guess(&lin));
    let gf: Vec<_> = w.iter().map(|w| fit.lags.at(*w)).collect();
    let pl: Vec<_> = w.iter().map(|w| plant(&lin, &v, &pi, *w)).collect();
    let (ph, phf, php) = (
        unwrapped_phase_deg(&g),
        unwrapped_phase_deg(&gf),
        unwrapped_phase_deg(&pl),
    );
    // (rad/s)/Pa -> rpm/bar.
    let to_rpm_bar = 1e5 / RAD_S_PER_RPM;
    let mut t = Table::new(&[
        "f_hz",
        "motor_mag_rpm_per_bar",
        "motor_phase_deg",
        "fit_mag_rpm_per_bar",
        "fit_phase_deg",
        "valve_motor_mag_rpm_per_v",
        "valve_motor_phase_deg",
    ]);
    for k in 0..f.len() {
        t.push(vec![
            f[k],
            g[k].norm() * to_rpm_bar,
            ph[k],
            gf[k].norm() * to_rpm_bar,
            phf[k],
            pl[k].norm() * pi.speed_unit_rpm,
            php[k],
        ]);
    }
    write_csv(&s.out, "bode.csv", &t)?;
    let op = &lin.op;
    let poles = lin.poles();
    let lags = fit.lags;
    let summary = serde_json::json!({
        "operating_point": {
            "p_supply_mpa": op.bc.p_port1_pa / 1e6,
            "speed_rpm": rpm(op.speed_rad_s()),
            "p1_mpa": op.x[idx::P1] / 1e6,
            "p2_mpa": op.x[idx::P2] / 1e6,
            "pe_mpa": op.x[idx::PE] / 1e6,
            "load": describe_load(&op.bc.load),
        },
        "poles_1_s": poles.iter().map(|p| [p.re, p.im]).collect::<Vec<_>>(),
        "static_gain_rpm_per_bar": lin.dc_gain() * to_rpm_bar,
        "two_lags": {
            "k_rpm_per_bar": lags.k * to_rpm_bar,
            "t1_s": lags.t1_s,
            "t2_s": lags.t2_s,
            "band_hz": [f_min, f_max],
            "rms_mag_db": fit.rms_mag_db,
            "max_mag_db": fit.max_mag_db,
            "rms_phase_deg": fit.rms_phase_deg,
            "max_phase_deg": fit.max_phase_deg,
        },
    });
    write_file(
        &s.out.join("bode_fit.json"),
        (serde_json::to_string_pretty(&summary).expect("plain JSON") + "\n").as_bytes(),
    )?;
    let pairs = |v: &[f64]| f.iter().zip(v).map(|(f, y)| (*f, *y)).collect::<Vec<_>>();
    let mags = |z: &[nalgebra::Complex<f64>], scale: f64| {
        z.iter().map(|z| z.norm() * scale).collect::<Vec<_>>()
    };
    let title = format!(
        "Motor {:.2} MPa, {:.0} rpm",
        op.bc.p_port1_pa / 1e6,
        rpm(op.speed_rad_s())
    );
    let mag = Chart::new(
        &format!("{title}: |speed/supply|"),
        "f [Hz]",
        "|G| [rpm/bar]",
    )
    .log_x()
    .log_y()
    .with(Series::line("model", pairs(&mags(&g, to_rpm_bar))))
    .with(Series::line(
        &format!(
            "K/((1+sT1)(1+sT2)), T1 {:.3} s, T2 {:.2} ms",
            lags.t1_s,
            lags.t2_s * 1e3
        ),
        pairs(&mags(&gf, to_rpm_bar)),
    ))
    .legend(Legend::LowerLeft);
    let phase = Chart::new(&format!("{title}: phase"), "f [Hz]", "phase [deg]")
        .log_x()
        .with(Series::line("model", pairs(&ph)))
        .with(Series::line("two lags", pairs(&phf)))
        .legend(Legend::LowerLeft);
    let pmag = Chart::new(
        "Valve + motor (open loop, Fig. 17)",
        "f [Hz]",
        "|P| [rpm/V]",
    )
    .log_x()
    .log_y()
    .with(Series::line(
        "valve + motor",
        pairs(&mags(&pl, pi.speed_unit_rpm)),
    ))
    .legend(Legend::LowerLeft);
    let pph = Chart::new("Valve + motor: phase", "f [Hz]", "phase [deg]")
        .log_x()
        .with(Series::line("valve + motor", pairs(&php)))
        .legend(Legend::LowerLeft);
    write_figure(
        &s.out,
        "bode.svg",
        &Figure::new(vec![mag, phase, pmag, pph], 2),
    )?;
    println!(
        "operating point {:.3} MPa, {}: {:.0} rpm; static gain {:.1} rpm/bar; poles {}",
        op.bc.p_port1_pa / 1e6,
        describe_load(&op.bc.load),
        rpm(op.speed_rad_s()),
        lin.dc_gain() * to_rpm_bar,
        poles
            .iter()
            .map(|p| format!("{:.4}", p.re))
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!(
        "two lags {:.1} rpm/bar / ((1 + {:.4} s)(1 + {:.5} s)): T1 = {:.4} s, T2 = {:.3} ms; fit \
        error {:.3} dB rms ({:.3} max), {:.2} deg rms ({:.2} max) over {}-{} Hz",
        lags.k * to_rpm_bar,
        lags.t1_s,
        lags.t2_s,
        lags.t1_s,
        lags.t2_s * 1e3,
        fit.rms_mag_db,
        fit.max_mag_db,
        fit.rms_phase_deg,
        fit.max_phase_deg,
        f_min,
        f_max
    );
    println!("{}", describe_valve(&v));
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Closed loop (Figs. 19, 20)

fn trace_table(tr: &Trace) -> Table {
    let mut t = Table::new(&[
        "t_s",
        "setpoint_rpm",
        "speed_rpm",
        "command_v",
        "p_valve_mpa",
        "p1_mpa",
        "integral_v",
        "load_nm",
    ]);
    for k in 0..tr.t_s.len() {
        t.push(vec![
            tr.t_s[k],
            rpm(tr.setpoint_rad_s[k]),
            rpm(tr.speed_rad_s[k]),
            tr.command_v[k],
            tr.p_valve_pa[k] / 1e6,
            tr.p1_pa[k] / 1e6,
            tr.integral_v[k],
            tr.load_nm[k],
        ]);
    }
    t
}

/// Fig. 19/20 style panels: speed (and set-point), command, pressures.
fn trace_figure(title: &str, runs: &[(&str, &Trace)]) -> Figure {
    let xy = |tr: &Trace, v: &dyn Fn(usize) -> f64| {
        (0..tr.t_s.len())
            .map(|k| (tr.t_s[k], v(k)))
            .collect::<Vec<_>>()
    };
    let mut speed =
        Chart::new(&format!("{title}: speed"), "t [s]", "speed [rpm]").legend(Legend::LowerRight);
    let mut cmd = Chart::new("valve command y", "t [s]", "command [V]").legend(Legend::LowerRight);
    let mut pres = Chart::new("pressure at the motor inlet", "t [s]", "pressure [MPa abs]")
        .legend(Legend::LowerRight);
    if let Some((_, tr)) = runs.first() {
        speed.series.push(Series::line(
            "set-point",
            xy(tr, &|k| rpm(tr.setpoint_rad_s[k])),
        ));
    }
    for (name, tr) in runs {
        speed
            .series
            .push(Series::line(name, xy(tr, &|k| rpm(tr.speed_rad_s[k]))));
        cmd.series
            .push(Series::line(name, xy(tr, &|k| tr.command_v[k])));
        pres.series.push(Series::line(
            &format!("{name}: valve"),
            xy(tr, &|k| tr.p_valve_pa[k] / 1e6),
        ));
        pres.series.push(Series::line(
            &format!("{name}: V1"),
            xy(tr, &|k| tr.p1_pa[k] / 1e6),
        ));
    }
    Figure::new(vec![speed, cmd, pres], 1)
}

struct LoopSetup {
    s: Setup,
    lp: Loop,
}

fn loop_setup(
    c: &CommonArgs,
    study: &str,
    va: &ValveArgs,
    pa: &PiArgs,
    gains: Option<&GainArgs>,
    default_brake: f64,
) -> Result<LoopSetup, ControlError> {
    let s = setup(c, study, default_brake)?;
    let valve = valve(va, &s.motor)?;
    let pi = controller(pa, gains, &valve)?;
    let lp = Loop {
        valve,
        pi,
        load: s.load,
    };
    Ok(LoopSetup { s, lp })
}

fn describe_pi(pi: &PiController) -> String {
    format!(
        "PI ({:.4} s + {:.4})/s on error in {} rpm -> V, Ts {} ms, anti-windup {:?}",
        pi.kp,
        pi.ki,
        pi.speed_unit_rpm,
        pi.ts_s * 1e3,
        pi.anti_windup
    )
}

/// A scenario's length and the time of its step, checked: `--t-step-s` must fall inside
/// `--duration-s`.
fn step_window(duration_s: f64, t_step_s: f64) -> Result<(f64, f64), ControlError> {
    let dur = positive("--duration-s", duration_s)?;
    let t_step = non_negative("--t-step-s", t_step_s)?;
    if t_step >= dur {
        return Err(bad("--t-step-s", t_step, "before --duration-s"));
    }
    Ok((dur, t_step))
}

fn step(a: &StepArgs) -> Result<(), ControlError> {
    let LoopSetup { s, lp } = loop_setup(&a.common, "step", &a.valve, &a.pi, Some(&a.gains), 1e-4)?;
    let from = positive("--from-rpm", a.from_rpm)? * RAD_S_PER_RPM;
    let to = positive("--to-rpm", a.to_rpm)? * RAD_S_PER_RPM;
    let (dur, t_step) = step_window(a.duration_s, a.t_step_s)?;
    let start = lp
        .settled_at(&s.motor, from)
        .map_err(|e| ControlError(format!("--from-rpm {}: {e}", a.from_rpm)))?;
    let sc = Scenario {
        duration_s: dur,
        setpoint_rad_s: Steps::step(from, t_step, to),
        load_torque_nm: Steps::constant(0.0),
    };
    let tr = lp.simulate(&s.motor, &DiffsolBdf::default(), &sc, &start)?;
    write_csv(&s.out, "step.csv", &trace_table(&tr))?;
    write_figure(
        &s.out,
        "step.svg",
        &trace_figure(
            &format!("Set-point step {:.0} -> {:.0} rpm", a.from_rpm, a.to_rpm),
            &[("controlled", &tr)],
        ),
    )?;
    let m = step_metrics(&tr, t_step, from, to);
    println!(
        "{}; {}; {}",
        describe_pi(&lp.pi),
        describe_valve(&lp.valve),
        describe_load(&lp.load)
    );
    let bc_full = Boundary::supplied(
        lp.valve.set_pressure_pa(lp.valve.u_max_v),
        P_ATM_PA,
        lp.load,
    );
    let full = crate::sim::steady::free(
        &s.motor,
        &bc_full,
        &crate::sim::steady::initial_guess(&bc_full),
    )?;
    if full[idx::OMEGA] < to {
        println!(
            "note: --to-rpm {} is above the speed at full command ({:.0} rpm); the command \
            saturates",
            a.to_rpm,
            rpm(full[idx::OMEGA])
        );
    }
    println!(
        "step {:.0} -> {:.0} rpm: rise time (10-90 %) {:.3} s, overshoot {:.1} %, settling (2 %) \
        {:.3} s, mean error over the last 10 % {:.2} rpm; command {:.2} .. {:.2} V",
        a.from_rpm,
        a.to_rpm,
        m.rise_time_s,
        m.overshoot_pct,
        m.settling_time_s,
        rpm(m.final_error_rad_s),
        tr.command_v.iter().cloned().fold(f64::INFINITY, f64::min),
        tr.command_v
            .iter()
            .cloned()
            .fold(f64::NEG_INFINITY, f64::max),
    );
    Ok(())
}

fn disturbance(a: &DisturbanceArgs) -> Result<(), ControlError> {
    let LoopSetup { s, lp } = loop_setup(
        &a.common,
        "disturbance",
        &a.valve,
        &a.pi,
        Some(&a.gains),
        1e-4,
    )?;
    let w = positive("--rpm", a.rpm)? * RAD_S_PER_RPM;
    let dt = a.load_step_nm;
    if !dt.is_finite() {
        return Err(bad("--load-step-nm", dt, "a number"));
    }
    let (dur, t_step) = step_window(a.duration_s, a.t_step_s)?;
    let start = lp
        .settled_at(&s.motor, w)
        .map_err(|e| ControlError(format!("--rpm {}: {e}", a.rpm)))?;
    let sc = Scenario {
        duration_s: dur,
        setpoint_rad_s: Steps::constant(w),
        load_torque_nm: Steps::step(0.0, t_step, dt),
    };
    let solver = DiffsolBdf::default();
    let tr = lp.simulate(&s.motor, &solver, &sc, &start)?;
    // Without control: the command stays where it was (the controller's gains set to zero).
    let open = lp.without_control();
    let tr_open = open.simulate(&s.motor, &solver, &sc, &start)?;
    write_csv(&s.out, "disturbance.csv", &trace_table(&tr))?;
    write_csv(&s.out, "disturbance_open_loop.csv", &trace_table(&tr_open))?;
    write_figure(
        &s.out,
        "disturbance.svg",
        &trace_figure(
            &format!("Load step {} N*m at {:.0} rpm", dt, a.rpm),
            &[("controlled", &tr), ("constant command", &tr_open)],
        ),
    )?;
    let d = disturbance_metrics(&tr, t_step, (0.01 * w).max(5.0 * RAD_S_PER_RPM));
    println!(
        "{}; {}; {}",
        describe_pi(&lp.pi),
        describe_valve(&lp.valve),
        describe_load(&lp.load)
    );
    println!(
        "load step {} N*m at {:.0} rpm: largest drop {:.0} rpm, back within 1 % after {:.3} s, \
        mean error over the last 10 % {:.2} rpm; without control the speed settles {:.0} rpm \
        lower",
        dt,
        a.rpm,
        rpm(d.max_drop_rad_s),
        d.recovery_time_s,
        rpm(d.final_error_rad_s),
        rpm(crate::control::closed_loop::tail_mean_error(&tr_open, 0.1)),
    );
    Ok(())
}

// ---------------------------------------------------------------------------------------
// Minimum speed

fn min_speed(a: &MinSpeedArgs) -> Result<(), ControlError> {
    let LoopSetup { s, lp } =
        loop_setup(&a.common, "min-speed", &a.valve, &a.pi, Some(&a.gains), 0.0)?;
    let p_max = absolute_pressure_pa("--p-max-mpa", a.p_max_mpa)?;
    let ramp_s = positive("--ramp-s", a.ramp_s)?;
    if !(a.factor > 0.0 && a.factor < 1.0) {
        return Err(bad("--factor", a.factor, "between 0 and 1"));
    }
    let floor = match a.floor_rpm {
        Some(f) => positive("--floor-rpm", f)? * RAD_S_PER_RPM,
        None => crate::control::min_speed::lowest_running_speed_rad_s(&s.motor),
    };
    let stage_s = positive("--stage-s", a.stage_s)?;
    if stage_s <= crate::control::min_speed::HOLD_WINDOW_S + 1.0 {
        return Err(bad("--stage-s", stage_s, "longer than 3 s"));
    }
    let m = &s.motor;
    let open = open_loop_start(m, lp.load, P_ATM_PA, p_max, 150)?;
    let ramp = ramp_simulation(m, lp.load, P_ATM_PA, p_max, ramp_s, 600)?;
    let mut t = Table::new(&["speed_rpm", "p_port1_mpa"]);
    for (w, p) in &open.curve {
        t.push(vec![rpm(*w), p / 1e6]);
    }
    write_csv(&s.out, "min_speed_steady.csv", &t)?;
    let mut t = Table::new(&["p_port1_mpa", "speed_rpm"]);
    for (p, w) in &ramp {
        t.push(vec![p / 1e6, rpm(*w)]);
    }
    write_csv(&s.out, "min_speed_ramp.csv", &t)?;

    // Start the loop settled well above the open-loop minimum (where it runs open loop).
    let w_start = (1.25 * open.w_min_rad_s).max(1000.0 * RAD_S_PER_RPM);
    let c = closed_loop_min_speed(m, &lp, w_start, a.factor, floor, stage_s).map_err(|e| {
        ControlError(format!(
            "closed loop started at {:.0} rpm (1.25 x the open-loop minimum, at least 1000 rpm): {e}",
            rpm(w_start)
        ))
    })?;
    let mut t = Table::new(&["setpoint_rpm", "mean_rpm", "min_rpm", "max_rpm", "held"]);
    for at in &c.attempts {
        t.push(vec![
            rpm(at.setpoint_rad_s),
            rpm(at.mean_rad_s),
            rpm(at.min_rad_s),
            rpm(at.max_rad_s),
            if at.held { 1.0 } else { 0.0 },
        ]);
    }
    write_csv(&s.out, "min_speed_attempts.csv", &t)?;

    let held = c.attempts.iter().rev().find(|x| x.held);
    let failed = c.attempts.iter().find(|x| !x.held);
    write_csv(&s.out, "min_speed_controlled.csv", &trace_table(&c.trace))?;
    let mut ramp_chart = Chart::new(
        &format!("Start-up on a pressure ramp ({})", describe_load(&lp.load)),
        "supply pressure [MPa abs]",
        "speed [rpm]",
    )
    .legend(Legend::UpperLeft)
    .with(Series::line(
        "steady states (p_eq)",
        open.curve.iter().map(|(w, p)| (p / 1e6, rpm(*w))).collect(),
    ))
    .with(Series::line(
        &format!("ramp {ramp_s} s (simulated)"),
        ramp.iter().map(|(p, w)| (p / 1e6, rpm(*w))).collect(),
    ));
    ramp_chart.series.push(Series::points(
        "breakaway",
        vec![(open.p_breakaway_pa / 1e6, 0.0)],
    ));
    if let Some(j) = open.jump {
        ramp_chart.series.push(Series::points(
            "jump",
            vec![
                (j.p_pa / 1e6, rpm(j.from_rad_s)),
                (j.p_pa / 1e6, rpm(j.to_rad_s)),
            ],
        ));
    }
    let tr = &c.trace;
    let pick = |v: &[f64]| {
        tr.t_s
            .iter()
            .zip(v)
            .map(|(t, w)| (*t, rpm(*w)))
            .collect::<Vec<_>>()
    };
    let loop_chart = Chart::new(
        &format!(
            "Controlled: set-point lowered by {} every {} s",
            a.factor, a.stage_s
        ),
        "t [s]",
        "speed [rpm]",
    )
    .with(Series::line("set-point", pick(&tr.setpoint_rad_s)))
    .with(Series::line("speed", pick(&tr.speed_rad_s)));
    write_figure(
        &s.out,
        "min_speed.svg",
        &Figure::new(vec![ramp_chart, loop_chart], 2),
    )?;

    println!(
        "{}; {}; {}",
        describe_pi(&lp.pi),
        describe_valve(&lp.valve),
        describe_load(&lp.load)
    );
    match open.jump {
        Some(j) if j.from_rad_s == 0.0 => println!(
            "without control (pressure ramp to {} MPa): the motor breaks away at {:.4} MPa and \
            jumps to {:.0} rpm: lowest speed without control {:.0} rpm",
            a.p_max_mpa,
            j.p_pa / 1e6,
            rpm(j.to_rad_s),
            rpm(open.w_min_rad_s)
        ),
        other => {
            println!(
                "without control (pressure ramp to {} MPa): the motor breaks away at {:.4} MPa \
                and creeps from standstill (lowest speed analysed {:.0} rpm); no start-up jump \
                (the paper's comes from static friction above Coulomb: effect \
                breakaway_friction)",
                a.p_max_mpa,
                open.p_breakaway_pa / 1e6,
                rpm(open.w_min_rad_s)
            );
            if let Some(j) = other {
                println!(
                    "  later jump at {:.4} MPa from {:.0} to {:.0} rpm",
                    j.p_pa / 1e6,
                    rpm(j.from_rad_s),
                    rpm(j.to_rad_s)
                );
            }
        }
    }
    match (held, failed) {
        (Some(h), f) => {
            println!(
            "with control: lowest set-point held {:.0} rpm{} (paper: 2900 rpm without, 365 rpm \
            with control)",
            rpm(h.setpoint_rad_s),
            f.map_or(format!("; the staircase reached --floor-rpm {:.0}", rpm(floor)), |f| format!(
                "; {:.0} rpm is not held (speed {:.0} .. {:.0} rpm)",
                rpm(f.setpoint_rad_s),
                rpm(f.min_rad_s),
                rpm(f.max_rad_s)
            ))
        )
        }
        (None, _) => println!(
            "with control: no set-point below the start speed {:.0} rpm was held",
            rpm(w_start)
        ),
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// PI design

fn design(a: &DesignArgs) -> Result<(), ControlError> {
    let LoopSetup { s, lp } = loop_setup(&a.common, "design", &a.valve, &a.pi, None, 1e-4)?;
    let pm = a.pm_deg;
    if !(pm > 0.0 && pm < 90.0) {
        return Err(bad("--pm-deg", pm, "between 0 and 90"));
    }
    let target = match a.crossover_hz {
        Some(f) => Target::Bandwidth {
            crossover_rad_s: rad_s(positive("--crossover-hz", f)?),
            pm_deg: pm,
        },
        None => Target::PhaseMargin { pm_deg: pm },
    };
    let p_mean = positive("--p-mean-mpa", a.p_mean_mpa)? * 1e6;
    let step = positive("--step-rpm", a.step_rpm)? * RAD_S_PER_RPM;
    let dur = positive("--duration-s", a.duration_s)?;
    let lin = linear_at(&s.motor, s.load, p_mean)?;
    let designed = design_pi(&lin, &lp.valve, &lp.pi, target)?;
    let paper = PiController {
        kp: 0.85,
        ki: 4.0,
        ..lp.pi
    };
    let w0 = lin.op.speed_rad_s();
    let solver = DiffsolBdf::default();
    let sim = |pi: PiController| -> Result<(Trace, Margins), ControlError> {
        let l = Loop { pi, ..lp };
        let start = l.settled_at(&s.motor, w0)?;
        let sc = Scenario {
            duration_s: dur,
            setpoint_rad_s: Steps::step(w0, 0.1, w0 + step),
            load_torque_nm: Steps::constant(0.0),
        };
        Ok((
            l.simulate(&s.motor, &solver, &sc, &start)?,
            margins(&lin, &lp.valve, &pi),
        ))
    };
    let (tr_d, m_d) = sim(designed)?;
    let (tr_p, m_p) = sim(paper)?;
    let met_d = step_metrics(&tr_d, 0.1, w0, w0 + step);
    let met_p = step_metrics(&tr_p, 0.1, w0, w0 + step);
    write_csv(&s.out, "design_step.csv", &trace_table(&tr_d))?;
    write_csv(&s.out, "design_step_paper_gains.csv", &trace_table(&tr_p))?;
    let f = log_grid(1e-3, 1e2, 300);
    let mut t = Table::new(&[
        "f_hz",
        "designed_mag",
        "designed_phase_deg",
        "paper_mag",
        "paper_phase_deg",
    ]);
    let ld: Vec<_> = f
        .iter()
        .map(|f| open_loop(&lin, &lp.valve, &designed, rad_s(*f)))
        .collect();
    let lpp: Vec<_> = f
        .iter()
        .map(|f| open_loop(&lin, &lp.valve, &paper, rad_s(*f)))
        .collect();
    let (phd, php) = (unwrapped_phase_deg(&ld), unwrapped_phase_deg(&lpp));
    for k in 0..f.len() {
        t.push(vec![f[k], ld[k].norm(), phd[k], lpp[k].norm(), php[k]]);
    }
    write_csv(&s.out, "design_open_loop.csv", &t)?;
    let pairs = |v: &[f64]| f.iter().zip(v).map(|(f, y)| (*f, *y)).collect::<Vec<_>>();
    let mag = Chart::new("Open loop |L| = |C P|", "f [Hz]", "|L|")
        .log_x()
        .log_y()
        .with(Series::line(
            "designed",
            pairs(&ld.iter().map(|z| z.norm()).collect::<Vec<_>>()),
        ))
        .with(Series::line(
            "paper (0.85 s + 4)/s",
            pairs(&lpp.iter().map(|z| z.norm()).collect::<Vec<_>>()),
        ))
        .with(Series::line("1", vec![(f[0], 1.0), (f[f.len() - 1], 1.0)]));
    let ph = Chart::new("Open loop phase", "f [Hz]", "phase [deg]")
        .log_x()
        .legend(Legend::LowerLeft)
        .with(Series::line("designed", pairs(&phd)))
        .with(Series::line("paper (0.85 s + 4)/s", pairs(&php)));
    let xy = |tr: &Trace| {
        tr.t_s
            .iter()
            .zip(&tr.speed_rad_s)
            .map(|(t, w)| (*t, rpm(*w)))
            .collect::<Vec<_>>()
    };
    let stepc = Chart::new(
        "Closed-loop check (nonlinear motor)",
        "t [s]",
        "speed [rpm]",
    )
    .legend(Legend::LowerRight)
    .with(Series::line(
        "set-point",
        tr_d.t_s
            .iter()
            .zip(&tr_d.setpoint_rad_s)
            .map(|(t, w)| (*t, rpm(*w)))
            .collect(),
    ))
    .with(Series::line("designed", xy(&tr_d)))
    .with(Series::line("paper gains", xy(&tr_p)));
    write_figure(&s.out, "design.svg", &Figure::new(vec![mag, ph, stepc], 2))?;

    println!(
        "operating point {:.3} MPa, {}: {:.0} rpm; {}",
        p_mean / 1e6,
        describe_load(&lp.load),
        rpm(w0),
        describe_valve(&lp.valve)
    );
    let show = |name: &str,
                pi: &PiController,
                m: &Margins,
                st: &crate::control::closed_loop::StepMetrics| {
        println!(
            "{name}: kp {:.4} V/({} rpm), ki {:.4} V/({} rpm*s) [G(s) = ({:.4} s + {:.4})/s]; \
            crossover {:.3} rad/s ({:.3} Hz), phase margin {:.1} deg, gain margin {:.1} dB; \
            simulated +{:.0} rpm step: overshoot {:.1} %, rise {:.3} s, settling {:.3} s, mean \
            error over the last 10 % {:.2} rpm",
            pi.kp,
            pi.speed_unit_rpm,
            pi.ki,
            pi.speed_unit_rpm,
            pi.kp,
            pi.ki,
            m.crossover_rad_s,
            m.crossover_rad_s / (2.0 * std::f64::consts::PI),
            m.phase_margin_deg,
            m.gain_margin_db,
            a.step_rpm,
            st.overshoot_pct,
            st.rise_time_s,
            st.settling_time_s,
            rpm(st.final_error_rad_s)
        );
    };
    show("designed", &designed, &m_d, &met_d);
    show("paper   ", &paper, &m_p, &met_p);
    if met_d.settling_time_s.is_nan() || rpm(met_d.final_error_rad_s).abs() > 0.02 * a.step_rpm {
        return Err(ControlError(format!(
            "the designed loop does not settle in the {dur} s check simulation (final error \
            {:.1} rpm); try a larger --pm-deg or a lower --crossover-hz",
            rpm(met_d.final_error_rad_s)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::cli::{run, Cli};
    use clap::Parser;

    fn cli(args: &[&str]) -> Cli {
        let mut all = vec!["vanefit", "control"];
        all.extend_from_slice(args);
        Cli::try_parse_from(all).unwrap()
    }

    #[test]
    fn bode_study_writes_tables_and_figure() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("bode");
        let out_s = out.to_str().unwrap();
        run(cli(&["bode", "--out", out_s, "--points", "30"])).unwrap();
        let csv = std::fs::read_to_string(out.join("bode.csv")).unwrap();
        let mut lines = csv.lines();
        assert!(lines
            .next()
            .unwrap()
            .starts_with("f_hz,motor_mag_rpm_per_bar,"));
        assert_eq!(lines.count(), 30);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("bode_fit.json")).unwrap())
                .unwrap();
        let lags = &json["two_lags"];
        let (t1, t2) = (
            lags["t1_s"].as_f64().unwrap(),
            lags["t2_s"].as_f64().unwrap(),
        );
        assert!(t1 > 10.0 * t2 && t2 > 0.0, "{lags}");
        let svg = std::fs::read_to_string(out.join("bode.svg")).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("Valve + motor"));
    }

    #[test]
    fn bad_options_are_refused_naming_the_option() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().to_str().unwrap();
        let cases: [(&[&str], &str); 5] = [
            (&["bode", "--p-mean-mpa", "-0.2"], "--p-mean-mpa"),
            (&["bode", "--p-mean-mpa", "0.105"], "stalled"),
            (&["step", "--anti-windup", "sometimes"], "--anti-windup"),
            (
                &["step", "--from-rpm", "50000"],
                "above the speed at full command",
            ),
            (
                &["throttle-inlet", "--curves-m3-s-pa", "none,big"],
                "--curves-m3-s-pa",
            ),
        ];
        for (args, needle) in cases {
            let mut a = args.to_vec();
            a.extend_from_slice(&["--out", out]);
            let e = run(cli(&a)).unwrap_err();
            assert!(e.0.contains(needle), "{args:?}: {}", e.0);
        }
        // Unknown studies and options are usage errors for clap (exit status 2).
        assert!(Cli::try_parse_from(["vanefit", "control", "warp-drive"]).is_err());
        assert!(Cli::try_parse_from(["vanefit", "control", "bode", "--kp", "1"]).is_err());
    }
}
