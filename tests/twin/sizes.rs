//! Motors and rigs of every size a maker sells: size bands, random motors drawn in a band,
//! and rig datasets of any displacement with the rig scaled to the motor.
//!
//! Everything scales from the reference motor AR034-11 (3.8 cm³) by geometric similarity,
//! s = V_disp/3.8 cm³ and every length × s^⅓ (the laws of tests/twin/page.rs and
//! docs/model.md, "Defaults that follow the motor's size"): conductances (areas) × s^⅔,
//! volumes and dry friction × s, viscous friction × s^{4/3}, inertia × s^{5/3}. At one
//! supply pressure the operating point then scales as: torque ∝ s (pressure × swept volume),
//! mass flow ∝ s^⅔ (ports' areas), speed ∝ flow/volume ∝ s^{-⅓}, power ∝ s^⅔; the rig's
//! pneumatic time constants V/(C·RT0·ρ0) ∝ s^⅓ and the mechanical one J/(∂T/∂ω) ∝
//! s^{5/3}/s^{4/3} = s^⅓.

use super::cases::{perturbed_motor, varied_config};
use super::motor::TwinMotor;
use super::page::{random_motor_sized, Spread, V_REF_M3};
use super::record::{OffsetSpec, RecordConfig};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// The size bands of the tables, cm³ (low, high): from the smallest hand-tool motors to the
/// largest vane motors in makers' catalogues.
pub const SIZE_BANDS_CM3: [(f64, f64); 5] = [
    (0.3, 1.0),
    (1.0, 5.0),
    (5.0, 25.0),
    (25.0, 100.0),
    (100.0, 500.0),
];

/// The range of the rig datasets, cm³ (docs/validation.md, "Every size and page style"):
/// the bands of [`SIZE_BANDS_CM3`] are cut to it for rigs.
pub const RIG_RANGE_CM3: (f64, f64) = (0.5, 250.0);

/// A band as people read it, e.g. "5–25 cm³".
pub fn band_label(band: (f64, f64)) -> String {
    format!("{}–{} cm³", band.0, band.1)
}

/// A displacement, m³, drawn log-uniformly in `band` (cm³) from `seed` (a stream of its
/// own, so the motor's other draws do not depend on it).
pub fn displacement_in_band(seed: u64, band: (f64, f64)) -> f64 {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x512e_ba4d_0000_0003);
    let (lo, hi) = (band.0.ln(), band.1.ln());
    (lo + rng.random::<f64>() * (hi - lo)).exp() * 1e-6
}

/// A random motor of the band (cm³): [`random_motor_sized`] of `seed` at a displacement
/// drawn by [`displacement_in_band`].
pub fn random_motor_in_band(seed: u64, band: (f64, f64), sp: &Spread) -> TwinMotor {
    random_motor_sized(seed, displacement_in_band(seed, band), sp)
}

/// The size factor s = V_disp/3.8 cm³ of a displacement in m³.
pub fn size_factor(v_disp_m3: f64) -> f64 {
    v_disp_m3 / V_REF_M3
}

/// [`perturbed_motor`]'s motor `seed` (AR034-11 with the six conductances and both
/// frictions × factors in [0.75, 1.33]) made `v_disp_m3` large by geometric similarity:
/// conductances × s^⅔, dead volume and lumped volumes × s, Coulomb friction × s, viscous
/// friction × s^{4/3}, inertia × s^{5/3}; vanes, expansion ratio, polytropic index and
/// critical ratio unchanged. The laws are those of vanefit's size-scaled defaults, so the
/// parameters a rig fit does not estimate are right at every size and only the eight
/// estimated ones are off their defaults, as at 3.8 cm³ (tests/estimate/coverage.rs).
pub fn perturbed_motor_sized(seed: u64, v_disp_m3: f64) -> TwinMotor {
    scaled_motor(&perturbed_motor(seed), v_disp_m3)
}

/// `m` made `v_disp_m3` large by geometric similarity (s = v_disp_m3/m.v_disp): the laws of
/// [`perturbed_motor_sized`]. The optional effects and laws keep their values.
pub fn scaled_motor(m: &TwinMotor, v_disp_m3: f64) -> TwinMotor {
    let s = v_disp_m3 / m.v_disp;
    let area = s.powf(2.0 / 3.0);
    TwinMotor {
        c_in1: m.c_in1 * area,
        c_out2: m.c_out2 * area,
        c_ext: m.c_ext * area,
        c_1e: m.c_1e * area,
        c_2e: m.c_2e * area,
        c_12: m.c_12 * area,
        v_dead: m.v_dead * s,
        vol1: m.vol1 * s,
        vol2: m.vol2 * s,
        vole: m.vole * s,
        inertia: m.inertia * s.powf(5.0 / 3.0),
        t_coulomb: m.t_coulomb * s,
        visc: m.visc * s.powf(4.0 / 3.0),
        v_disp: v_disp_m3,
        ..m.clone()
    }
}

/// [`varied_config`]'s recording configuration `seed` with the rig scaled to a motor of
/// `v_disp_m3` (s = V_disp/3.8 cm³), so that each experiment covers the motor's range as it
/// covers the reference motor's and each sensor is as good relative to what it measures:
/// - the brake: c × s^{4/3} — a brake torque c·ω at the same fraction of the free speed
///   is then the same fraction of the motor's torque (torque ∝ s, speed ∝ s^{-⅓});
/// - the outlet throttle: both ends of its conductance sweep × s^⅔ — an outlet valve is
///   sized to the motor's ports (an area), so it throttles from about open to about shut
///   as it does the reference motor;
/// - the noise: flows × s^⅔ (flow meters are ranged to the flow, their noise a share of
///   full scale), brake and datasheet torque × s (a torque sensor ranged to the torque),
///   speed × s^{-⅓} (an encoder's error is a share of the speed it reads); the pressure
///   (the same supply) and the throttle's relative conductance noise unchanged;
/// - the sensor offsets' calibration tolerances scale as their channels' noise;
/// - the sample rate: as drawn (5, 10, 20 or 50 Hz). The rig's time constants grow as
///   s^⅓ (0.5× the reference's at 0.5 cm³, 4× at 250 cm³), all of them a few tenths of a
///   second or more against a 60 s ramp and a 65 s throttle sweep that the motor follows
///   quasi-statically, so the same rates sample every size, and the same number of rows
///   keeps the fit times comparable across sizes.
///
/// At s = 1 this is [`varied_config`] itself.
pub fn scaled_rig_config(seed: u64, v_disp_m3: f64) -> RecordConfig {
    scaled_config(&varied_config(seed), size_factor(v_disp_m3))
}

/// `cfg`, a rig made for the reference motor, scaled to a motor `s` times its displacement
/// (the laws of [`scaled_rig_config`]).
pub fn scaled_config(cfg: &RecordConfig, s: f64) -> RecordConfig {
    let mut cfg = *cfg;
    let (flow, torque, speed) = (s.powf(2.0 / 3.0), s, s.powf(-1.0 / 3.0));
    let c = &mut cfg.conditions;
    c.brake_nm_s_rad *= s.powf(4.0 / 3.0);
    c.c_throttle_m3_s_pa = (c.c_throttle_m3_s_pa.0 * flow, c.c_throttle_m3_s_pa.1 * flow);
    let n = &mut cfg.noise;
    n.flow1_g_s *= flow;
    n.flow2_g_s *= flow;
    n.torque_nm *= torque;
    n.brake_torque_nm *= torque;
    n.speed_rpm *= speed;
    if let OffsetSpec::Drawn { tol, .. } = &mut cfg.offsets {
        tol.flow1_g_s *= flow;
        tol.flow2_g_s *= flow;
        tol.brake_torque_nm *= torque;
        tol.speed_rpm *= speed;
    }
    cfg
}
