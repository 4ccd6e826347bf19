//! Ready-made cases for later tests: a perturbed motor and a varied recording configuration,
//! both drawn from a seed (Xoshiro256PlusPlus), so a test names a case by one number.

use super::motor::TwinMotor;
use super::record::{NoiseSigmas, OffsetSpec, Offsets, RecordConfig};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Factor drawn log-uniformly in [lo, hi], 1.
fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.random::<f64>() * (hi / lo).ln()).exp()
}

/// The default motor with each conductance (c_in1, c_out2, c_ext, c_1e, c_2e, c_12) and
/// t_coulomb and visc multiplied by its own factor, log-uniform in [0.75, 1.33].
pub fn perturbed_motor(seed: u64) -> TwinMotor {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut f = || log_uniform(&mut rng, 0.75, 1.33);
    let d = TwinMotor::default();
    TwinMotor {
        c_in1: d.c_in1 * f(),
        c_out2: d.c_out2 * f(),
        c_ext: d.c_ext * f(),
        c_1e: d.c_1e * f(),
        c_2e: d.c_2e * f(),
        c_12: d.c_12 * f(),
        t_coulomb: d.t_coulomb * f(),
        visc: d.visc * f(),
        ..d
    }
}

/// 1σ calibration tolerances of [`varied_config`]'s offsets: flows ±0.02 g/s, speed ±2 rpm,
/// brake torque ±2 mN·m, port-1 pressure ±2 kPa (a calibrated rig's zero errors).
pub const CALIBRATION_TOL: Offsets = Offsets {
    flow1_g_s: 0.02,
    flow2_g_s: 0.02,
    speed_rpm: 2.0,
    brake_torque_nm: 0.002,
    p_port1_pa: 2000.0,
};

/// A recording configuration unlike vanefit synth's defaults, drawn from `seed`:
/// - sample rate, Hz: one of 5, 10, 20, 50;
/// - noise σ, each × its own factor uniform in [0.5, 3]: flows 0.03 g/s, speed 15 rpm,
///   datasheet torque and brake torque 4 mN·m; port-1 pressure 2 kPa and conductance 0.5 %
///   (relative) fixed;
/// - offsets drawn from N(0, [`CALIBRATION_TOL`]²) per channel (their own seed, from `seed`);
/// - the brake-torque channel on in half the cases;
/// - 25 datasheet points, 0.73 MPa supply, g/s, MPa and rpm as usual.
pub fn varied_config(seed: u64) -> RecordConfig {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x7717_c0f1_9000_0000);
    let rate_hz = [5.0, 10.0, 20.0, 50.0][rng.random_range(0..4)];
    let mut k = || 0.5 + 2.5 * rng.random::<f64>();
    let noise = NoiseSigmas {
        flow1_g_s: 0.03 * k(),
        flow2_g_s: 0.03 * k(),
        speed_rpm: 15.0 * k(),
        torque_nm: 0.004 * k(),
        brake_torque_nm: 0.004 * k(),
        p_port1_pa: 2000.0,
        c_port2_rel: 0.005,
    };
    let offsets = OffsetSpec::Drawn {
        tol: CALIBRATION_TOL,
        seed: rng.random(),
    };
    let brake_torque = rng.random::<bool>();
    let mut cfg = RecordConfig {
        noise,
        offsets,
        brake_torque,
        ..RecordConfig::default()
    };
    cfg.conditions.rate_hz = rate_hz;
    cfg
}
