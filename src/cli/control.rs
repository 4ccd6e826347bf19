//! `vanefit control <study>`: the speed-control studies of paper §5 from a parameter set,
//! each writing CSV tables and SVG figures into `--out` (atomically) and printing a summary.
//!
//! Studies: `throttle-inlet`, `throttle-outlet` (Figs. 14, 15), `bode` (Figs. 16, 17),
//! `step` (Fig. 19), `disturbance` (Fig. 20), `min-speed` (§5.2's 2900 vs 365 rpm) and
//! `design` (PI gains for a phase margin or crossover, checked by simulation).
//!
//! This module holds only the command line: the clap arguments, their conversion to the
//! library's `ControlStudy` and the printed summaries. The study runs as
//! `vanefit::task::control`: the motor checked, the output folder created, the rest
//! checked, the study run and written, then the summary printed. Its errors name the
//! options by their flags ([`flag`], by the [`ControlOpt`] they carry).

use crate::cli::Failure;
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};
use vanefit::control::rpm;
use vanefit::control::ControlOpt;
use vanefit::control::Loop;
use vanefit::control::Port;
use vanefit::control::{BodeOptions, BodeStudy};
use vanefit::control::{DesignOptions, DesignRun, DesignStudy};
use vanefit::control::{DisturbanceOptions, DisturbanceStudy};
use vanefit::control::{GainOptions, LoopOptions, MotorOptions, PiOptions, ValveOptions};
use vanefit::control::{MinSpeedOptions, MinSpeedStudy};
use vanefit::control::{StepOptions, StepStudy};
use vanefit::control::{ThrottleOptions, ThrottleStudy};
use vanefit::io::prepare_dir;
use vanefit::report::control::bode::RPM_PER_BAR;
use vanefit::report::control::{describe_load, describe_pi, describe_valve};
use vanefit::report::explain;
use vanefit::task;
use vanefit::task::{write_study, ControlStudy, StudyResult};

/// `vanefit control` arguments.
#[derive(Args, Debug)]
pub(crate) struct ControlArgs {
    #[command(subcommand)]
    study: Study,
}

/// The studies.
#[derive(Subcommand, Debug)]
pub(crate) enum Study {
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
pub(crate) struct CommonArgs {
    /// Fit file (vanefit.fit/1); omitted: the default motor.
    #[arg(long)]
    params: Option<PathBuf>,
    #[arg(
        long,
        value_parser = crate::cli::effects_arg,
        help = crate::cli::effects_help("Effects to switch on, overriding the fit file's")
    )]
    effects: Option<String>,
    /// Output folder (created); default `./control-<study>`.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Eddy-current brake on the shaft, N*m*s/rad (default 1e-4; 0 for min-speed, which the
    /// paper reports without load).
    #[arg(long)]
    brake_nm_s_rad: Option<f64>,
}

/// `throttle-inlet` / `throttle-outlet` arguments.
#[derive(Args, Debug)]
pub(crate) struct ThrottleArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Constant supply pressure, MPa absolute.
    #[arg(long, default_value_t = 0.73)]
    p_supply_mpa: f64,
    /// Smallest throttle conductance, m3/(s*Pa).
    #[arg(long, default_value_t = 3e-10)]
    c_min_m3_s_pa: f64,
    /// Largest throttle conductance, m3/(s*Pa).
    #[arg(long, default_value_t = 1e-7)]
    c_max_m3_s_pa: f64,
    /// Number of conductances (log-spaced).
    #[arg(long, default_value_t = 40)]
    points: usize,
    /// Throttles for the torque-speed curves, comma-separated m3/(s*Pa); "none" for no
    /// throttle.
    #[arg(long, default_value = "none,1e-8,4e-9,2e-9,1e-9")]
    curves_m3_s_pa: String,
}

/// `bode` arguments.
#[derive(Args, Debug)]
pub(crate) struct BodeArgs {
    #[command(flatten)]
    common: CommonArgs,
    #[command(flatten)]
    valve: ValveArgs,
    /// Mean supply pressure of the operating point, MPa absolute.
    #[arg(long, default_value_t = 0.35)]
    p_mean_mpa: f64,
    /// Lowest frequency of the response, Hz.
    #[arg(long, default_value_t = 0.01)]
    f_min_hz: f64,
    /// Highest frequency of the response, Hz.
    #[arg(long, default_value_t = 100.0)]
    f_max_hz: f64,
    /// Number of frequencies (log-spaced); the two-lag fit uses all of them.
    #[arg(long, default_value_t = 200)]
    points: usize,
}

/// The pressure control valve.
#[derive(Args, Debug)]
pub(crate) struct ValveArgs {
    /// Valve time constant, s (default: the parameter set's valve_tau, 0.05 s). The valve is
    /// first order unless the valve_dynamics effect is on (then second order with
    /// valve_zeta).
    #[arg(long)]
    valve_tau_s: Option<f64>,
    /// Command for full pressure, V.
    #[arg(long, default_value_t = 10.0)]
    valve_u_max_v: f64,
    /// Gauge pressure at full command, bar.
    #[arg(long, default_value_t = 6.0)]
    valve_p_max_bar_g: f64,
}

/// Controller settings other than the gains.
#[derive(Args, Debug)]
pub(crate) struct PiArgs {
    /// Sample time, ms.
    #[arg(long, default_value_t = 1.0)]
    ts_ms: f64,
    /// Speed unit of the controller's error, rpm (1000: error in krpm, command in V).
    #[arg(long, default_value_t = 1000.0)]
    speed_unit_rpm: f64,
    /// Anti-windup of the integrator when the command saturates: conditional (the integral
    /// is frozen while the error would drive the command further out), back-calculation
    /// (tracking time kp/ki) or none.
    #[arg(
        long,
        default_value = "conditional",
        value_parser = clap::builder::PossibleValuesParser::new(["conditional", "back-calculation", "none"])
    )]
    anti_windup: String,
}

/// PI gains (paper: G(s) = (0.85 s + 4)/s).
#[derive(Args, Debug)]
pub(crate) struct GainArgs {
    /// Proportional gain, V per speed unit.
    #[arg(long, default_value_t = 0.85)]
    kp: f64,
    /// Integral gain, V per speed unit per s.
    #[arg(long, default_value_t = 4.0)]
    ki: f64,
}

/// `step` arguments.
#[derive(Args, Debug)]
pub(crate) struct StepArgs {
    #[command(flatten)]
    common: CommonArgs,
    #[command(flatten)]
    valve: ValveArgs,
    #[command(flatten)]
    pi: PiArgs,
    #[command(flatten)]
    gains: GainArgs,
    /// Set-point before the step, rpm (the loop starts settled there).
    #[arg(long, default_value_t = 3000.0)]
    from_rpm: f64,
    /// Set-point after the step, rpm.
    #[arg(long, default_value_t = 4500.0)]
    to_rpm: f64,
    /// Time of the set-point step after the start of the simulation, s (before
    /// --duration-s).
    #[arg(long, default_value_t = 0.5)]
    t_step_s: f64,
    /// Simulated time, s: the response is judged over it (settling, the mean error over
    /// its last 10 %).
    #[arg(long, default_value_t = 8.0)]
    duration_s: f64,
}

/// `disturbance` arguments.
#[derive(Args, Debug)]
pub(crate) struct DisturbanceArgs {
    #[command(flatten)]
    common: CommonArgs,
    #[command(flatten)]
    valve: ValveArgs,
    #[command(flatten)]
    pi: PiArgs,
    #[command(flatten)]
    gains: GainArgs,
    /// Speed set-point, rpm.
    #[arg(long, default_value_t = 4000.0)]
    rpm: f64,
    /// Extra load torque switched on at --t-step-s, N*m.
    #[arg(long, default_value_t = 0.03)]
    load_step_nm: f64,
    /// Time of the load step after the start of the simulation, s (before --duration-s).
    #[arg(long, default_value_t = 0.5)]
    t_step_s: f64,
    /// Simulated time, s: the recovery is judged over it (the drop, the time back within
    /// 1 %, the mean error over its last 10 %).
    #[arg(long, default_value_t = 8.0)]
    duration_s: f64,
}

/// `min-speed` arguments.
#[derive(Args, Debug)]
pub(crate) struct MinSpeedArgs {
    #[command(flatten)]
    common: CommonArgs,
    #[command(flatten)]
    valve: ValveArgs,
    #[command(flatten)]
    pi: PiArgs,
    #[command(flatten)]
    gains: GainArgs,
    /// Top of the pressure ramp, MPa absolute (the paper's 0.73).
    #[arg(long, default_value_t = 0.73)]
    p_max_mpa: f64,
    /// Duration of the simulated pressure ramp, s (the paper's rig: 60 s).
    #[arg(long, default_value_t = 60.0)]
    ramp_s: f64,
    /// Each closed-loop candidate set-point is this fraction of the previous one.
    #[arg(long, default_value_t = 0.8)]
    factor: f64,
    /// Lowest set-point tried, rpm (default: 5·max(w_reg, 1 rad/s), about 48 rpm, below
    /// which the model's friction regularisation, not physics, sets the behaviour).
    #[arg(long)]
    floor_rpm: Option<f64>,
    /// Duration of each stage of the set-point staircase, s (its last 2 s judge whether the
    /// set-point is held).
    #[arg(long, default_value_t = 5.0)]
    stage_s: f64,
}

/// `design` arguments.
#[derive(Args, Debug)]
pub(crate) struct DesignArgs {
    #[command(flatten)]
    common: CommonArgs,
    #[command(flatten)]
    valve: ValveArgs,
    #[command(flatten)]
    pi: PiArgs,
    /// Requested phase margin, degrees.
    #[arg(long, default_value_t = 60.0)]
    pm_deg: f64,
    /// Requested crossover (bandwidth), Hz; omitted: the highest crossover at which a PI
    /// gives the phase margin with 15° of its own lag.
    #[arg(long)]
    crossover_hz: Option<f64>,
    /// Mean supply pressure of the operating point, MPa absolute.
    #[arg(long, default_value_t = 0.35)]
    p_mean_mpa: f64,
    /// Set-point step of the check simulation, rpm (from the operating point's speed).
    #[arg(long, default_value_t = 300.0)]
    step_rpm: f64,
    /// Simulated time of the check simulation, s.
    #[arg(long, default_value_t = 5.0)]
    duration_s: f64,
}

/// The flag that sets a control study's option (`vanefit::control::study`, whose errors
/// name it by its field).
pub(crate) fn flag(o: ControlOpt) -> &'static str {
    match o {
        ControlOpt::BodePMean | ControlOpt::DesignPMean => "--p-mean-mpa",
        ControlOpt::BodeFMin => "--f-min-hz",
        ControlOpt::BodeFMax => "--f-max-hz",
        ControlOpt::BodePoints | ControlOpt::ThrottlePoints => "--points",
        ControlOpt::ThrottlePSupply => "--p-supply-mpa",
        ControlOpt::ThrottleCMin => "--c-min-m3-s-pa",
        ControlOpt::ThrottleCMax => "--c-max-m3-s-pa",
        ControlOpt::ThrottleCurves => "--curves-m3-s-pa",
        ControlOpt::StepFrom => "--from-rpm",
        ControlOpt::StepTo => "--to-rpm",
        ControlOpt::StepTStep | ControlOpt::DisturbanceTStep => "--t-step-s",
        ControlOpt::StepDuration | ControlOpt::DisturbanceDuration | ControlOpt::DesignDuration => {
            "--duration-s"
        }
        ControlOpt::DisturbanceRpm => "--rpm",
        ControlOpt::DisturbanceLoadStep => "--load-step-nm",
        ControlOpt::MinSpeedPMax => "--p-max-mpa",
        ControlOpt::MinSpeedRamp => "--ramp-s",
        ControlOpt::MinSpeedFactor => "--factor",
        ControlOpt::MinSpeedFloor => "--floor-rpm",
        ControlOpt::MinSpeedStage => "--stage-s",
        ControlOpt::DesignPhaseMargin => "--pm-deg",
        ControlOpt::DesignCrossover => "--crossover-hz",
        ControlOpt::DesignStep => "--step-rpm",
        ControlOpt::MotorParams => "--params",
        ControlOpt::MotorEffects => "--effects",
        ControlOpt::MotorBrake => "--brake-nm-s-rad",
        ControlOpt::ValveTau => "--valve-tau-s",
        ControlOpt::ValveUMax => "--valve-u-max-v",
        ControlOpt::ValvePMax => "--valve-p-max-bar-g",
        ControlOpt::PiSampleTime => "--ts-ms",
        ControlOpt::PiSpeedUnit => "--speed-unit-rpm",
        ControlOpt::PiAntiWindup => "--anti-windup",
        ControlOpt::GainKp => "--kp",
        ControlOpt::GainKi => "--ki",
        // An option added to the library without a flag here keeps its field's name.
        other => other.field(),
    }
}

/// Runs `vanefit control <study>`.
pub(crate) fn run(args: ControlArgs) -> Result<(), Failure> {
    let (common, study) = study(&args.study);
    // The motor is checked first, then the output folder is created (default
    // `./control-<study>`) and locked for this run, then the loop and the study's options.
    let plant = study.check_plant().map_err(Failure::control)?;
    let out = common
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("control-{}", study.name())));
    let _lock = prepare_dir(&out).map_err(|e| Failure(format!("--out {e}")))?;
    let gear = plant.gear();
    let result = study
        .check_on(plant)
        .and_then(|checked| checked.run())
        .map_err(Failure::control)?;
    let mut print = |p: &Path| say!("wrote {}", p.display());
    write_study(&result, &out, &mut print)?;
    if let Some(g) = &gear {
        vanefit::report::control::write_shaft(g, &out, &mut print)
            .map_err(|e| Failure(e.to_string()))?;
        say!("{}", vanefit::report::control::shaft_note(g));
    }
    match &result {
        StudyResult::Throttle(r) => print_throttle(r),
        StudyResult::Bode(r) => print_bode(r),
        StudyResult::Step(r) => print_step(r),
        StudyResult::Disturbance(r) => print_disturbance(r),
        StudyResult::MinSpeed(r) => {
            say!("{}", describe_loop(&r.lp));
            print_open_loop_start(r);
            print_controlled_min(r);
        }
        StudyResult::Design(r) => {
            print_design(r);
            // The files and the summary are there to look at even when the check fails.
            r.check_settled().map_err(Failure::control)?;
        }
        _ => {}
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------
// From the arguments to the library's control study

/// The study of the command line: its common options and the library's study.
fn study(s: &Study) -> (&CommonArgs, ControlStudy) {
    let (common, study) = match s {
        Study::ThrottleInlet(a) => (&a.common, a.study(Port::Inlet)),
        Study::ThrottleOutlet(a) => (&a.common, a.study(Port::Outlet)),
        Study::Bode(a) => (
            &a.common,
            task::Study::Bode(BodeOptions {
                p_mean_mpa: a.p_mean_mpa,
                f_min_hz: a.f_min_hz,
                f_max_hz: a.f_max_hz,
                points: a.points,
                valve: a.valve.options(),
            }),
        ),
        Study::Step(a) => (
            &a.common,
            task::Study::Step(
                loop_options(&a.valve, &a.pi, Some(&a.gains)),
                StepOptions {
                    from_rpm: a.from_rpm,
                    to_rpm: a.to_rpm,
                    t_step_s: a.t_step_s,
                    duration_s: a.duration_s,
                },
            ),
        ),
        Study::Disturbance(a) => (
            &a.common,
            task::Study::Disturbance(
                loop_options(&a.valve, &a.pi, Some(&a.gains)),
                DisturbanceOptions {
                    rpm: a.rpm,
                    load_step_nm: a.load_step_nm,
                    t_step_s: a.t_step_s,
                    duration_s: a.duration_s,
                },
            ),
        ),
        Study::MinSpeed(a) => (
            &a.common,
            task::Study::MinSpeed(
                loop_options(&a.valve, &a.pi, Some(&a.gains)),
                MinSpeedOptions {
                    p_max_mpa: a.p_max_mpa,
                    ramp_s: a.ramp_s,
                    factor: a.factor,
                    floor_rpm: a.floor_rpm,
                    stage_s: a.stage_s,
                },
            ),
        ),
        Study::Design(a) => (
            &a.common,
            task::Study::Design(
                loop_options(&a.valve, &a.pi, None),
                DesignOptions {
                    pm_deg: a.pm_deg,
                    crossover_hz: a.crossover_hz,
                    p_mean_mpa: a.p_mean_mpa,
                    step_rpm: a.step_rpm,
                    duration_s: a.duration_s,
                },
            ),
        ),
    };
    let motor = MotorOptions {
        params: common.params.clone(),
        params_text: None,
        effects: common.effects.clone(),
        brake_nm_s_rad: common.brake_nm_s_rad,
    };
    (common, ControlStudy { motor, study })
}

impl ThrottleArgs {
    fn study(&self, port: Port) -> task::Study {
        task::Study::Throttle(ThrottleOptions {
            port,
            p_supply_mpa: self.p_supply_mpa,
            c_min_m3_s_pa: self.c_min_m3_s_pa,
            c_max_m3_s_pa: self.c_max_m3_s_pa,
            points: self.points,
            curves_m3_s_pa: self.curves_m3_s_pa.clone(),
        })
    }
}

impl ValveArgs {
    fn options(&self) -> ValveOptions {
        ValveOptions {
            tau_s: self.valve_tau_s,
            u_max_v: self.valve_u_max_v,
            p_max_bar_g: self.valve_p_max_bar_g,
        }
    }
}

/// The loop of a closed-loop study (unchecked).
fn loop_options(valve: &ValveArgs, pi: &PiArgs, gains: Option<&GainArgs>) -> LoopOptions {
    LoopOptions {
        valve: valve.options(),
        pi: PiOptions {
            ts_ms: pi.ts_ms,
            speed_unit_rpm: pi.speed_unit_rpm,
            anti_windup: pi.anti_windup.clone(),
        },
        gains: gains.map(|g| GainOptions { kp: g.kp, ki: g.ki }),
    }
}

/// The loop in one line: controller, valve, load.
fn describe_loop(lp: &Loop) -> String {
    format!(
        "{}; {}; {}",
        describe_pi(&lp.pi),
        describe_valve(&lp.valve),
        describe_load(&lp.load)
    )
}

// ---------------------------------------------------------------------------------------
// The summaries

fn print_throttle(r: &ThrottleStudy) {
    let (Some(lo), Some(hi)) = (r.speed.first(), r.speed.last()) else {
        return;
    };
    say!(
        "{} throttle at {} MPa, {}: speed {:.0} rpm at C = {} .. {:.0} rpm at C = {} \
        (unthrottled free speed without load {:.0} rpm)",
        r.settings.port().name(),
        r.settings.p_supply_mpa(),
        describe_load(&r.load),
        rpm(lo.speed_rad_s),
        explain::conductance(lo.c_m3_s_pa, 3),
        rpm(hi.speed_rad_s),
        explain::conductance(hi.c_m3_s_pa, 3),
        rpm(r.free_speed_rad_s)
    );
    if let Some(w) = r.speed.windows(2).find(|w| {
        w[0].speed_rad_s < 0.5 * hi.speed_rad_s && w[1].speed_rad_s >= 0.5 * hi.speed_rad_s
    }) {
        say!(
            "  half of that speed at C ~ {}",
            explain::conductance((w[0].c_m3_s_pa * w[1].c_m3_s_pa).sqrt(), 3)
        );
    }
}

fn print_bode(r: &BodeStudy) {
    let op = &r.lin.op;
    let lags = r.fit.lags;
    say!(
        "operating point {:.3} MPa, {}: {:.0} rpm; static gain {:.1} rpm/bar; poles {}",
        op.bc.p_port1_pa / 1e6,
        describe_load(&op.bc.load),
        rpm(op.speed_rad_s()),
        r.lin.dc_gain() * RPM_PER_BAR,
        r.poles
            .iter()
            .map(|p| format!("{:.4}", p.re))
            .collect::<Vec<_>>()
            .join(", ")
    );
    say!(
        "two lags {:.1} rpm/bar / ((1 + {:.4} s)(1 + {:.5} s)): T1 = {:.4} s, T2 = {:.3} ms; fit \
        error {:.3} dB rms ({:.3} max), {:.2} deg rms ({:.2} max) over {}-{} Hz",
        lags.k * RPM_PER_BAR,
        lags.t1_s,
        lags.t2_s,
        lags.t1_s,
        lags.t2_s * 1e3,
        r.fit.rms_mag_db,
        r.fit.max_mag_db,
        r.fit.rms_phase_deg,
        r.fit.max_phase_deg,
        r.settings.f_min_hz(),
        r.settings.f_max_hz()
    );
    say!("{}", describe_valve(r.settings.valve()));
}

fn print_step(r: &StepStudy) {
    let (s, m, tr) = (&r.settings, &r.metrics, &r.trace);
    say!("{}", describe_loop(&r.lp));
    if r.full_speed_rad_s < s.to_rad_s() {
        say!(
            "note: --to-rpm {} is above the speed at full command ({:.0} rpm); the command \
            saturates",
            s.to_rpm(),
            rpm(r.full_speed_rad_s)
        );
    }
    say!(
        "step {:.0} -> {:.0} rpm: rise time (10-90 %) {:.3} s, overshoot {:.1} %, settling (2 %) \
        {:.3} s, mean error over the last 10 % {} rpm; command {:.2} .. {:.2} V",
        s.from_rpm(),
        s.to_rpm(),
        m.rise_time_s,
        m.overshoot_pct,
        m.settling_time_s,
        explain::fixed(rpm(m.final_error_rad_s), 2),
        tr.command_v.iter().cloned().fold(f64::INFINITY, f64::min),
        tr.command_v
            .iter()
            .cloned()
            .fold(f64::NEG_INFINITY, f64::max),
    );
}

fn print_disturbance(r: &DisturbanceStudy) {
    let (s, d) = (&r.settings, &r.metrics);
    say!("{}", describe_loop(&r.lp));
    say!(
        "load step {} N*m at {:.0} rpm: largest drop {:.0} rpm, back within 1 % after {:.3} s, \
        mean error over the last 10 % {} rpm; without control the speed settles {:.0} rpm \
        lower",
        s.load_step_nm(),
        s.rpm(),
        rpm(d.max_drop_rad_s),
        d.recovery_time_s,
        explain::fixed(rpm(d.final_error_rad_s), 2),
        rpm(r.open_error_rad_s),
    );
}

/// The lowest speed without control: the start-up on the pressure ramp.
fn print_open_loop_start(r: &MinSpeedStudy) {
    let open = &r.open;
    let p_max_mpa = r.settings.p_max_mpa();
    match open.jump {
        Some(j) if j.from_rad_s == 0.0 => say!(
            "without control (pressure ramp to {} MPa): the motor breaks away at {:.4} MPa and \
            jumps to {:.0} rpm: lowest speed without control {:.0} rpm",
            p_max_mpa,
            j.p_pa / 1e6,
            rpm(j.to_rad_s),
            rpm(open.w_min_rad_s)
        ),
        other => {
            say!(
                "without control (pressure ramp to {} MPa): the motor breaks away at {:.4} MPa \
                and creeps from standstill (lowest speed analysed {:.0} rpm); no start-up jump \
                (the paper's comes from static friction above Coulomb: effect \
                breakaway_friction)",
                p_max_mpa,
                open.p_breakaway_pa / 1e6,
                rpm(open.w_min_rad_s)
            );
            if let Some(j) = other {
                say!(
                    "  later jump at {:.4} MPa from {:.0} to {:.0} rpm",
                    j.p_pa / 1e6,
                    rpm(j.from_rad_s),
                    rpm(j.to_rad_s)
                );
            }
        }
    }
}

/// The lowest speed with control: the last set-point of the staircase held.
fn print_controlled_min(r: &MinSpeedStudy) {
    let attempts = &r.controlled.attempts;
    let held = attempts.iter().rev().find(|x| x.held);
    let failed = attempts.iter().find(|x| !x.held);
    match (held, failed) {
        (Some(h), f) => {
            let end = f.map_or(
                format!(
                    "; the staircase reached --floor-rpm {:.0}",
                    rpm(r.settings.floor_rad_s())
                ),
                |f| {
                    format!(
                        "; {:.0} rpm is not held (speed {:.0} .. {:.0} rpm)",
                        rpm(f.setpoint_rad_s),
                        rpm(f.min_rad_s),
                        rpm(f.max_rad_s)
                    )
                },
            );
            say!(
                "with control: lowest set-point held {:.0} rpm{end} (paper: 2900 rpm without, \
                365 rpm with control)",
                rpm(h.setpoint_rad_s),
            )
        }
        (None, _) => say!(
            "with control: no set-point below the start speed {:.0} rpm was held",
            rpm(r.start_rad_s)
        ),
    }
}

fn print_design(r: &DesignStudy) {
    say!(
        "operating point {:.3} MPa, {}: {:.0} rpm; {}",
        r.settings.p_mean_pa() / 1e6,
        describe_load(&r.lp.load),
        rpm(r.w0_rad_s),
        describe_valve(&r.lp.valve)
    );
    print_design_run("designed", &r.designed, r.settings.step_rpm());
    print_design_run("paper   ", &r.paper, r.settings.step_rpm());
}

/// One controller of the design: gains, margins and the simulated step.
fn print_design_run(name: &str, run: &DesignRun, step_rpm: f64) {
    let (pi, m, st) = (&run.pi, &run.margins, &run.metrics);
    say!(
        "{name}: kp {:.4} V/({} rpm), ki {:.4} V/({} rpm*s) [G(s) = ({:.4} s + {:.4})/s]; \
        crossover {:.3} rad/s ({:.3} Hz), phase margin {:.1} deg, gain margin {:.1} dB; \
        simulated +{:.0} rpm step: overshoot {:.1} %, rise {:.3} s, settling {:.3} s, mean \
        error over the last 10 % {} rpm",
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
        step_rpm,
        st.overshoot_pct,
        st.rise_time_s,
        st.settling_time_s,
        explain::fixed(rpm(st.final_error_rad_s), 2)
    );
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

    /// `design.json` states the gains and margins in numbers: the designed loop has the
    /// requested phase margin, the paper's loop the paper's gains (0.85 s + 4)/s on krpm, and
    /// the designed step settles.
    #[test]
    fn design_writes_its_summary_in_numbers() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("design");
        let out_s = out.to_str().unwrap();
        run(cli(&["design", "--out", out_s, "--pm-deg", "55"])).unwrap();
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("design.json")).unwrap())
                .unwrap();
        let (d, p) = (&json["designed"], &json["paper"]);
        let num = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap();
        assert!((num(d, "phase_margin_deg") - 55.0).abs() < 0.5, "{d}");
        assert_eq!(
            (num(p, "kp_v_per_unit"), num(p, "ki_v_per_unit_s")),
            (0.85, 4.0)
        );
        assert_eq!(num(p, "speed_unit_rpm"), 1000.0);
        assert!(num(d, "settling_time_s") > 0.0 && num(d, "final_error_rpm").abs() < 6.0);
        assert!(num(&json, "speed_rpm") > 1000.0 && num(&json, "p_mean_pa") > 1e5);
    }

    #[test]
    fn bad_options_are_refused_naming_the_option() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().to_str().unwrap();
        let cases: [(&[&str], &str); 5] = [
            (&["bode", "--p-mean-mpa", "-0.2"], "--p-mean-mpa"),
            (&["bode", "--p-mean-mpa", "0.105"], "stalled"),
            (
                &["step", "--from-rpm", "50000"],
                "--from-rpm 50000: set-point 50000 rpm is above the speed at full command",
            ),
            (
                &["step", "--t-step-s", "9", "--duration-s", "8"],
                "--t-step-s 9: must be before --duration-s",
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
        // So is an anti-windup that does not exist.
        let e = Cli::try_parse_from(["vanefit", "control", "step", "--anti-windup", "sometimes"])
            .unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::InvalidValue);
        assert_eq!(e.exit_code(), 2);
    }
}
