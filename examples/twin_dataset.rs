//! Writes one twin-generator dataset (tests/twin: an independent implementation of the
//! physics of docs/model.md) with chosen noise, offsets and missing physics, e.g. for the
//! diagnosis cases of docs/validation.md:
//!
//! ```text
//! cargo run --release --example twin_dataset -- OUT_DIR [--seed S] [--rate HZ]
//!     [--noise-scale K] [--offsets] [--brake-torque] [--stiction TS,WS] [--leak-dp2 K]
//!     [--seal G,WS] [--vane-w2 C] [--base-perturb SEED] [--varied SEED] [--size-cm3 V]
//! ```
//!
//! Noise is K × the shipped dataset's (flows 0.01 g/s, speed 5 rpm, torque 2 mN·m, pressure
//! 1 kPa, conductance 0.5 %); `--offsets` draws sensor offsets within the calibration
//! tolerance (flows 0.02 g/s, speed 2 rpm, torque 2 mN·m, pressure 2 kPa, 1σ);
//! `--stiction` is t_static (N·m) and w_stribeck (rad/s); `--leak-dp2` is k in kg/(s·Pa²);
//! `--seal` is g_seal and w_seal (rad/s); `--vane-w2` is c_w2 in N·m·s²/rad²;
//! `--base-perturb` moves the conductances and friction by seeded factors in [0.7, 1.4];
//! `--varied SEED` writes `tests/estimate/coverage.rs`'s case SEED (its base motor, rate, noise,
//! offsets and brake-torque channel; it overrides the other recording options and the seed);
//! `--size-cm3 V` makes the motor V cm³ large by geometric similarity and scales the rig to
//! it (brake, throttle range, sensor noise and offsets; `twin::sizes::scaled_motor` and
//! `scaled_config`), the missing physics given as is.

use std::path::PathBuf;
use twin::{Breakaway, NoiseSigmas, OffsetSpec, RecordConfig, SealLeakage, TwinMotor};

const USAGE: &str = "usage: twin_dataset OUT_DIR [--seed S] [--rate HZ] [--noise-scale K] \
[--offsets] [--brake-torque] [--stiction TS,WS] [--leak-dp2 K] [--seal G,WS] [--vane-w2 C] \
[--base-perturb SEED] [--varied SEED] [--size-cm3 V]";

struct Args {
    out: PathBuf,
    seed: u64,
    motor: TwinMotor,
    cfg: RecordConfig,
}

fn number<T: std::str::FromStr>(flag: &str, v: Option<String>) -> Result<T, String> {
    let v = v.ok_or(format!("{flag} needs a value"))?;
    v.parse()
        .map_err(|_| format!("{flag}: '{v}' is not a valid number"))
}

fn pair(flag: &str, v: Option<String>) -> Result<(f64, f64), String> {
    let v: String = v.ok_or(format!("{flag} needs a value A,B"))?;
    let (a, b) = v
        .split_once(',')
        .ok_or(format!("{flag}: '{v}' is not A,B"))?;
    Ok((number(flag, Some(a.into()))?, number(flag, Some(b.into()))?))
}

fn parse(mut it: impl Iterator<Item = String>) -> Result<Args, String> {
    let out = PathBuf::from(
        it.next()
            .filter(|a| !a.starts_with("--"))
            .ok_or("OUT_DIR missing")?,
    );
    let (mut seed, mut motor, mut cfg) = (1, TwinMotor::default(), RecordConfig::default());
    let (mut noise_scale, mut offsets, mut base) = (1.0, false, None);
    let (mut varied, mut size_cm3) = (None, None);
    while let Some(flag) = it.next() {
        match flag.as_str() {
            "--seed" => seed = number(&flag, it.next())?,
            "--rate" => cfg.conditions.rate_hz = number(&flag, it.next())?,
            "--noise-scale" => noise_scale = number(&flag, it.next())?,
            "--offsets" => offsets = true,
            "--brake-torque" => cfg.brake_torque = true,
            "--stiction" => {
                let (t_static_nm, w_stribeck_rad_s) = pair(&flag, it.next())?;
                motor.breakaway_friction = Some(Breakaway {
                    t_static_nm,
                    w_stribeck_rad_s,
                });
            }
            "--leak-dp2" => motor.leak_1e_dp2_kg_s_pa2 = Some(number(&flag, it.next())?),
            "--seal" => {
                let (g_seal, w_seal_rad_s) = pair(&flag, it.next())?;
                motor.speed_dependent_leakage = Some(SealLeakage {
                    g_seal,
                    w_seal_rad_s,
                });
            }
            "--vane-w2" => motor.vane_friction_speed_squared = Some(number(&flag, it.next())?),
            "--base-perturb" => base = Some(number::<u64>(&flag, it.next())?),
            "--varied" => varied = Some(number::<u64>(&flag, it.next())?),
            "--size-cm3" => size_cm3 = Some(number::<f64>(&flag, it.next())?),
            _ => return Err(format!("unknown argument '{flag}'")),
        }
    }
    check(noise_scale, cfg.conditions.rate_hz)?;
    cfg.noise = NoiseSigmas::TYPICAL.scaled(noise_scale);
    if offsets {
        let tol = twin::CALIBRATION_TOL;
        cfg.offsets = OffsetSpec::Drawn {
            tol,
            seed: seed ^ 0x0ff5_e75e_ed00_0000,
        };
    }
    if let Some(s) = base {
        motor = twin::perturbed_motor_within(s, 0.7, 1.4).with_effects_of(&motor);
    }
    if let Some(s) = varied {
        // The coverage test's case `s`: its base motor and recording configuration.
        motor = twin::perturbed_motor(s).with_effects_of(&motor);
        cfg = twin::varied_config(s);
        seed = s;
    }
    if let Some(v) = size_cm3 {
        if !(v > 0.0 && v.is_finite()) {
            return Err(format!(
                "--size-cm3 {v} must be a positive displacement in cm³"
            ));
        }
        let s = v * 1e-6 / motor.v_disp;
        motor = twin::sizes::scaled_motor(&motor, v * 1e-6);
        cfg = twin::sizes::scaled_config(&cfg, s);
    }
    Ok(Args {
        out,
        seed,
        motor,
        cfg,
    })
}

fn check(noise_scale: f64, rate_hz: f64) -> Result<(), String> {
    if !(noise_scale >= 0.0 && noise_scale.is_finite()) {
        return Err(format!(
            "--noise-scale {noise_scale} must be finite and >= 0"
        ));
    }
    if !(rate_hz > 0.0 && rate_hz <= 1000.0) {
        return Err(format!("--rate {rate_hz} Hz must be in (0, 1000]"));
    }
    Ok(())
}

fn main() {
    let args = match parse(std::env::args().skip(1)) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("twin_dataset: {e}\n{USAGE}");
            std::process::exit(1);
        }
    };
    let t0 = std::time::Instant::now();
    match twin::write_dataset(&args.out, &args.motor, &args.cfg, args.seed) {
        Ok(_) => println!(
            "wrote {} ({:.2} s)",
            args.out.display(),
            t0.elapsed().as_secs_f64()
        ),
        Err(e) => {
            eprintln!("twin_dataset: {}: {e}", args.out.display());
            std::process::exit(1);
        }
    }
}
