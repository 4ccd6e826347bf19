//! rig.toml (docs/formats.md, "rig.toml") and truth.json (vanefit.fit/1, docs/formats.md,
//! "Fit files") of a twin dataset.

use super::motor::TwinMotor;
use super::record::{Offsets, RecordConfig};
use serde_json::{json, Map, Value};

/// The §5 effect ids the motor has switched on (the Δp² leak has no id).
pub fn effect_ids(m: &TwinMotor) -> Vec<&'static str> {
    let mut ids = Vec::new();
    if m.breakaway_friction.is_some() {
        ids.push("breakaway_friction");
    }
    if m.vane_friction_speed_squared.is_some() {
        ids.push("vane_friction_speed_squared");
    }
    if m.speed_dependent_leakage.is_some() {
        ids.push("speed_dependent_leakage");
    }
    ids
}

/// (name, value, unit) of every parameter vanefit knows, base (docs/model.md,
/// "Parameters") then effects ("Missing-physics catalog").
pub fn parameters(m: &TwinMotor) -> Vec<(&'static str, f64, &'static str)> {
    let cond = "m3/(s*Pa)";
    let mut p = vec![
        ("c_in1", m.c_in1, cond),
        ("c_out2", m.c_out2, cond),
        ("c_ext", m.c_ext, cond),
        ("c_1e", m.c_1e, cond),
        ("c_2e", m.c_2e, cond),
        ("c_12", m.c_12, cond),
        ("b_crit", m.b_crit, "1"),
        ("z", m.z, "1"),
        ("v_disp", m.v_disp, "m3"),
        ("eps", m.eps, "1"),
        ("v_dead", m.v_dead, "m3"),
        ("n_poly", m.n_poly, "1"),
        ("vol1", m.vol1, "m3"),
        ("vol2", m.vol2, "m3"),
        ("vole", m.vole, "m3"),
        ("inertia", m.inertia, "kg*m2"),
        ("t_coulomb", m.t_coulomb, "N*m"),
        ("visc", m.visc, "N*m*s/rad"),
        ("w_reg", m.w_reg, "rad/s"),
    ];
    if let Some(b) = m.breakaway_friction {
        p.push(("t_static", b.t_static_nm, "N*m"));
        p.push(("w_stribeck", b.w_stribeck_rad_s, "rad/s"));
    }
    if let Some(c_w2) = m.vane_friction_speed_squared {
        p.push(("c_w2", c_w2, "N*m*s2/rad2"));
    }
    if let Some(s) = m.speed_dependent_leakage {
        p.push(("g_seal", s.g_seal, "1"));
        p.push(("w_seal", s.w_seal_rad_s, "rad/s"));
    }
    p
}

fn offsets_json(o: &Offsets) -> Value {
    json!({
        "flow1_g_s": o.flow1_g_s,
        "flow2_g_s": o.flow2_g_s,
        "speed_rpm": o.speed_rpm,
        "brake_torque_nm": o.brake_torque_nm,
        "p_port1_pa": o.p_port1_pa,
    })
}

/// One line describing the recording configuration (rig.toml `description`).
pub fn describe(m: &TwinMotor, cfg: &RecordConfig, seed: u64, off: &Offsets) -> String {
    let (c, n) = (&cfg.conditions, &cfg.noise);
    format!(
        "twin generator (tests/twin), seed {seed}; {} Hz, {} datasheet points, supply {} MPa; \
         noise flow1 {} g/s, flow2 {} g/s, speed {} rpm, torque {} N*m, brake torque {} N*m, \
         p_port1 {} Pa, c_port2 {}; offsets flow1 {} g/s, flow2 {} g/s, speed {} rpm, \
         brake torque {} N*m, p_port1 {} Pa; brake-torque channel {}; effects {:?}; \
         leak_1e_dp2 {:?} kg/(s*Pa2)",
        c.rate_hz,
        c.datasheet_points,
        c.p_supply_pa * 1e-6,
        n.flow1_g_s,
        n.flow2_g_s,
        n.speed_rpm,
        n.torque_nm,
        n.brake_torque_nm,
        n.p_port1_pa,
        n.c_port2_rel,
        off.flow1_g_s,
        off.flow2_g_s,
        off.speed_rpm,
        off.brake_torque_nm,
        off.p_port1_pa,
        cfg.brake_torque,
        effect_ids(m),
        m.leak_1e_dp2_kg_s_pa2,
    )
}

/// rig.toml with the shipped dataset's keys (plus the motor's dead volume).
pub fn rig_toml(m: &TwinMotor, cfg: &RecordConfig, seed: u64, off: &Offsets) -> String {
    let c = &cfg.conditions;
    let desc = describe(m, cfg, seed, off)
        .replace('\\', "\\\\")
        .replace('"', "\\\"");
    let p_mpa = c.p_supply_pa * 1e-6;
    let load = format!(
        "load = {{ kind = \"viscous_brake\", c_nm_s_rad = {:e} }}",
        c.brake_nm_s_rad
    );
    format!(
        "# Synthetic dataset written by the twin generator (tests/twin), an independent\n\
         # implementation of the physics of docs/model.md. seed {seed}.\n\
         synthetic = true\n\
         description = \"{desc}\"\n\n\
         [motor]\nname = \"AR034-11 (twin)\"\nvanes = {}\ndisplacement_m3 = {:e}\n\
         expansion_ratio = {}\ndead_volume_m3 = {:e}\n\n\
         [conditions]\np_atm_pa = {}\ntemperature_k = 293.15\n\n\
         [[experiment]]\nkind = \"datasheet\"\nfile = \"datasheet.csv\"\np_supply_mpa = {p_mpa}\n\n\
         [[experiment]]\nkind = \"pressure_ramp\"\nfile = \"ramp.csv\"\n{load}\n\n\
         [[experiment]]\nkind = \"outlet_throttle\"\nfile = \"throttle.csv\"\n\
         p_supply_mpa = {p_mpa}\n{load}\n",
        m.z.round() as u32,
        m.v_disp,
        m.eps,
        m.v_dead,
        c.p_atm_pa,
    )
}

/// truth.json: the motor as a vanefit.fit/1 file (nothing estimated); what vanefit has no
/// name for (the Δp² leak, offsets, noise) goes under the top-level `"twin"` object.
pub fn truth_json(
    m: &TwinMotor,
    dataset: &str,
    cfg: &RecordConfig,
    seed: u64,
    off: &Offsets,
) -> Value {
    let mut params = Map::new();
    for (name, value, unit) in parameters(m) {
        let entry = json!({ "value": value, "unit": unit, "estimated": false, "ci95": null });
        params.insert(name.to_string(), entry);
    }
    let n = &cfg.noise;
    json!({
        "format": "vanefit.fit/1",
        "dataset": dataset,
        "model": { "effects": effect_ids(m) },
        "parameters": params,
        "cost": null,
        "starts": null,
        "seed": null,
        "run": null,
        "version": "twin",
        "twin": {
            "generator": "tests/twin",
            "seed": seed,
            "leak_1e_dp2_kg_s_pa2": m.leak_1e_dp2_kg_s_pa2,
            "laws": m.laws.iter().map(|l| l.describe()).collect::<Vec<_>>(),
            "rate_hz": cfg.conditions.rate_hz,
            "throttle_b_crit": cfg.conditions.throttle_b_crit,
            "brake_torque_channel": cfg.brake_torque,
            "noise": {
                "flow1_g_s": n.flow1_g_s, "flow2_g_s": n.flow2_g_s, "speed_rpm": n.speed_rpm,
                "torque_nm": n.torque_nm, "brake_torque_nm": n.brake_torque_nm,
                "p_port1_pa": n.p_port1_pa, "c_port2_rel": n.c_port2_rel,
            },
            "offsets": offsets_json(off),
        },
    })
}
