//! `vanefit plan` judged on twin rig datasets (docs/validation.md, "Which measurement next",
//! rigs): the twin records a motor's datasheet at its rig's supply pressure (about 6.3 bar g;
//! the rig sized to the motor, tests/twin/sizes.rs), `vanefit fit` fits it, `vanefit plan`
//! ranks the rig measurements at 3, 4 and 5 bar g (datasheet sweeps at each, outlet-throttle
//! ramps at each, the pressure ramp), the twin records the recommended one and a random other
//! one of equal cost on the same rig (its sensor offsets, a fresh noise draw) at the settings
//! plan.json states, the dataset with it is refitted, and the bands at the operating points
//! after the refit are compared with the promise, with the random one's and with the truth
//! (the twin's own catalogue figures). The columns are those of `plan_twin_table`.
//!
//! ```sh
//! PLAN_RIGS=4 cargo test --release --test predict -- --ignored --nocapture plan_twin_rig_table
//! ```
//!
//! Knobs: `PLAN_RIGS` (motors per size band, default 4), `PLAN_BANDS` (indices of
//! `SIZE_BANDS_CM3`, default 0–3), `PLAN_THREADS` (default 2), `PLAN_STARTS` (`fit --starts`,
//! default 4), `PLAN_OUT` (default target/plan-twin-rig.md), `PLAN_DIR`, `VANEFIT_BIN`.

use crate::plan_twin::{
    bands, env_usize, fit_with, judge_all, mean_shrinkage, numbers, plan_with, v_achieved,
    write_table, Judged,
};
use crate::twin;

use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde_json::Value;
use std::path::Path;
use twin::catalogue::catalogue_row;
use twin::motor::{TwinMotor, P_ATM_PA};
use twin::sizes::{displacement_in_band, perturbed_motor_sized, scaled_rig_config, SIZE_BANDS_CM3};
use twin::{write_dataset, write_experiment, Experiment, RecordConfig};

/// The operating pressures, bar g.
const OPERATING_BAR_G: [f64; 3] = [3.0, 4.0, 5.0];
/// The kinds weighed, with equal rig times so that the random comparison is of equal cost.
const KINDS: &str = "datasheet,outlet_throttle,pressure_ramp";
const COSTS: &str = "datasheet=1,outlet_throttle=1,pressure_ramp=1";

/// Fits the rig dataset in `data` to `fit`.
fn fit(data: &Path, fit: &Path, starts: usize) -> Result<(), String> {
    fit_with(data, fit, &["--starts", &starts.to_string()])
}

/// `vanefit plan` of `fit` with the rig candidates; its plan.json.
fn plan(fit: &Path, out: &Path) -> Result<Value, String> {
    plan_with(fit, out, KINDS, COSTS)
}

/// The rig of `cfg` set as plan.json's `rig` of `cand` says: the supply pressure (a ramp's
/// end), the datasheet's points, the throttle's range.
fn rig_for(cfg: &RecordConfig, cand: &Value) -> Result<(RecordConfig, Experiment), String> {
    let mut cfg = *cfg;
    let rig = &cand["rig"];
    let p = numbers(&rig["p_supply_pa"]);
    let c = &mut cfg.conditions;
    c.p_supply_pa = p[1];
    let kind = match cand["kind"].as_str() {
        Some("datasheet") => {
            c.datasheet_points = rig["points"].as_u64().ok_or("no points")? as usize;
            Experiment::Datasheet
        }
        Some("outlet_throttle") => {
            let t = numbers(&rig["throttle_m3_s_pa"]);
            c.c_throttle_m3_s_pa = (t[0], t[1]);
            Experiment::OutletThrottle
        }
        Some("pressure_ramp") => Experiment::PressureRamp,
        other => return Err(format!("the twin does not record {other:?}")),
    };
    Ok((cfg, kind))
}

/// Copies the base dataset `from` into `to` and adds the measurement `cand`.
fn measured(
    from: &Path,
    to: &Path,
    m: &TwinMotor,
    cfg: &RecordConfig,
    cand: &Value,
    seed: u64,
) -> Result<(), String> {
    std::fs::create_dir_all(to).map_err(|e| e.to_string())?;
    for f in ["rig.toml", "datasheet.csv"] {
        std::fs::copy(from.join(f), to.join(f)).map_err(|e| e.to_string())?;
    }
    let (cfg, kind) = rig_for(cfg, cand)?;
    let entry =
        write_experiment(to, m, &cfg, seed, kind, "extra.csv").map_err(|e| e.to_string())?;
    let mut toml = std::fs::read_to_string(to.join("rig.toml")).map_err(|e| e.to_string())?;
    toml += &entry;
    std::fs::write(to.join("rig.toml"), toml).map_err(|e| e.to_string())
}

/// The twin's datasheet-only rig dataset of `seed` in `dir`: the whole dataset written, its
/// ramp and throttle experiments left out of rig.toml.
fn base_dataset(dir: &Path, m: &TwinMotor, cfg: &RecordConfig, seed: u64) -> Result<(), String> {
    write_dataset(dir, m, cfg, seed).map_err(|e| format!("twin: {e}"))?;
    let toml = std::fs::read_to_string(dir.join("rig.toml")).map_err(|e| e.to_string())?;
    let mut parts = toml.split("\n[[experiment]]");
    let head = parts.next().unwrap_or_default().to_string();
    let sheet = parts
        .find(|p| p.contains("kind = \"datasheet\""))
        .ok_or("no datasheet")?;
    for f in ["ramp.csv", "throttle.csv"] {
        std::fs::remove_file(dir.join(f)).map_err(|e| e.to_string())?;
    }
    std::fs::write(
        dir.join("rig.toml"),
        format!("{head}\n[[experiment]]{}\n", sheet.trim_end()),
    )
    .map_err(|e| e.to_string())
}

/// The twin's own catalogue figures at 3, 4, 5 bar g, in the plan's order (max_power,
/// free_speed, stall_torque, air_at_max_power).
fn truth(m: &TwinMotor, cfg: &RecordConfig, bar_g: f64) -> Result<[f64; 4], String> {
    let mut c = cfg.conditions;
    c.p_supply_pa = P_ATM_PA + bar_g * 1e5;
    c.p_atm_pa = P_ATM_PA;
    let r = catalogue_row(m, &c)?;
    Ok([
        r.max_power_w,
        r.free_speed_rad_s,
        r.stall_torque_nm,
        r.air_at_max_power_kg_s,
    ])
}

/// Records, fits, plans, measures (recommended and random) and refits one motor in `dir`.
fn judge(seed: u64, band: (f64, f64), starts: usize, dir: &Path) -> Result<Judged, String> {
    let v = displacement_in_band(seed, band);
    let m = perturbed_motor_sized(seed, v);
    let cfg = scaled_rig_config(seed, v);
    let d0 = dir.join("data");
    base_dataset(&d0, &m, &cfg, seed)?;
    fit(&d0, &dir.join("fit.json"), starts)?;
    let plan0 = plan(&dir.join("fit.json"), &dir.join("plan"))?;
    let before = bands(&plan0);
    let ranked = plan0["ranked"].as_array().ok_or("no ranking")?;
    if ranked.len() < 2 {
        return Err(format!("{} candidate(s) ranked", ranked.len()));
    }
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x9a11);
    let other = 1 + rng.random_range(0..ranked.len() - 1);
    let mut after = Vec::new();
    for (name, c) in [("top", &ranked[0]), ("random", &ranked[other])] {
        let dd = dir.join(format!("data-{name}"));
        measured(&d0, &dd, &m, &cfg, c, seed ^ 0x5eed)?;
        let f = dir.join(format!("fit-{name}.json"));
        fit(&dd, &f, starts)?;
        after.push(bands(&plan(&f, &dir.join(format!("plan-{name}")))?));
    }
    let figure = |n: &str| {
        [
            "max_power",
            "free_speed",
            "stall_torque",
            "air_at_max_power",
        ]
        .iter()
        .position(|f| *f == n)
    };
    let truths = OPERATING_BAR_G
        .iter()
        .map(|b| truth(&m, &cfg, *b))
        .collect::<Result<Vec<_>, _>>()?;
    let targets = plan0["targets"].as_array().unwrap();
    let held = targets
        .iter()
        .zip(&after[0])
        .filter(|(t, b)| {
            let p = ((t["p_supply_pa"].as_f64().unwrap() - P_ATM_PA) / 1e5).round() as usize - 3;
            let y = figure(t["figure"].as_str().unwrap()).map(|f| truths[p][f]);
            y.is_some_and(|y| b[0] <= y && y <= b[1])
        })
        .count();
    let name = |c: &Value| match c["p_supply_pa"].as_f64() {
        Some(p) => format!(
            "{} at {:.0} bar g",
            c["kind"].as_str().unwrap(),
            (p - P_ATM_PA) / 1e5
        ),
        None => c["kind"].as_str().unwrap().to_string(),
    };
    let top = &ranked[0];
    let promised = |c: &Value| numbers(&c["shrinkage"]).iter().sum::<f64>() / before.len() as f64;
    Ok(Judged {
        promised: promised(top),
        achieved: mean_shrinkage(&before, &after[0]),
        random: mean_shrinkage(&before, &after[1]),
        promised_v: top["v_reduction"].as_f64().unwrap(),
        achieved_v: v_achieved(&before, &after[0]),
        random_v: v_achieved(&before, &after[1]),
        random_promised: promised(&ranked[other]),
        random_promised_v: ranked[other]["v_reduction"].as_f64().unwrap(),
        held,
        bands: before.len(),
        top: name(top),
        other: name(&ranked[other]),
    })
}

#[test]
#[ignore = "long: fits three rig datasets per motor; run with --ignored --nocapture"]
fn plan_twin_rig_table() {
    let per_band = env_usize("PLAN_RIGS", 4);
    let starts = env_usize("PLAN_STARTS", 4);
    let (bands, results) = judge_all(per_band, &|seed, band, dir| judge(seed, band, starts, dir));
    write_table(&bands, &results, "target/plan-twin-rig.md");
}

/// One twin rig end to end: the recommended measurement, recorded by the twin and
/// refitted, narrows the bands at the operating points about as much as the plan promised,
/// and the bands after still hold the twin's figures.
#[test]
fn the_recommended_rig_measurement_narrows_the_bands_as_promised() {
    let tmp = tempfile::tempdir().unwrap();
    let j = judge(101, SIZE_BANDS_CM3[1], 4, tmp.path()).unwrap();
    assert!(j.promised > 0.3, "{j:?}");
    assert!((j.achieved / j.promised - 1.0).abs() < 0.25, "{j:?}");
    assert!(j.achieved > j.random, "{j:?}");
    assert!(j.held >= 11, "{j:?}");
}
