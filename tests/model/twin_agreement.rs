//! vanefit against an independent implementation of the same physics: a mistake shared by
//! the model and the synthetic data it fits cannot show otherwise.
//!
//! The twin generator (`tests/twin`, written from docs/model.md and the paper, integrated
//! with TR-BDF2) writes noise-free datasets; `vanefit simulate <dataset> --params truth.json`
//! recomputes every recorded channel with vanefit's own model and solvers; the two must agree
//! row by row to a small fraction of a typical sensor's noise (flow 0.01 g/s, speed 5 rpm,
//! torque 2 mN·m): max |Δ| < 0.1 σ on every channel of every experiment. No row is excluded,
//! not even around the breakaway jump of the stiction case (both models regularise friction
//! with tanh(ω/ω_reg), so the jump is steep but continuous and both resolve it).
//!
//! Run with `cargo test --release --test model twin_agreement -- --nocapture` to see the figures.

use crate::twin;

use std::path::{Path, PathBuf};
use std::process::Command;
use twin::motor::{self, TwinMotor};
use twin::{
    experiment, write_dataset, Breakaway, FlowUnit, PressureUnit, RecordConfig, SealLeakage,
    SpeedUnit, Units,
};

/// Typical sensor noise (1σ) in SI: flow kg/s, speed rad/s, torque N·m.
const SIGMA_FLOW_KG_S: f64 = 0.01e-3;
const SIGMA_SPEED_RAD_S: f64 = 5.0 * std::f64::consts::PI / 30.0;
const SIGMA_TORQUE_NM: f64 = 2e-3;
/// Agreement required, in σ.
const MAX_SIGMA: f64 = 0.1;

/// A CSV file: header and numeric rows.
fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut lines = text.lines();
    let header = lines
        .next()
        .expect("header")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("number")).collect())
        .collect();
    (header, rows)
}

/// (σ of the channel in its column unit, or None for an input column) from the column name.
fn sigma_in_column_unit(column: &str) -> Option<f64> {
    let flow_per_kg_s = |c: &str| match c {
        _ if c.ends_with("_g_s") => 1e3,
        _ if c.ends_with("_kg_s") => 1.0,
        _ if c.ends_with("_l_min_anr") => 60.0 / (1e-3 * motor::RHO0_KG_M3),
        _ => panic!("unexpected flow unit in {c}"),
    };
    if column.starts_with("flow") {
        Some(SIGMA_FLOW_KG_S * flow_per_kg_s(column))
    } else if column == "torque_nm" {
        Some(SIGMA_TORQUE_NM)
    } else if column == "speed_rpm" {
        Some(SIGMA_SPEED_RAD_S * 30.0 / std::f64::consts::PI)
    } else if column == "speed_rad_s" {
        Some(SIGMA_SPEED_RAD_S)
    } else {
        None
    }
}

/// Runs `vanefit simulate` on a dataset under its truth.json; returns the output folder.
fn vanefit_simulate(dataset: &Path) -> PathBuf {
    let out = dataset.with_extension("vanefit");
    let status = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .arg("simulate")
        .arg(dataset)
        .arg("--params")
        .arg(dataset.join("truth.json"))
        .arg("--out")
        .arg(&out)
        .output()
        .expect("run vanefit");
    assert!(
        status.status.success(),
        "vanefit simulate failed: {}",
        String::from_utf8_lossy(&status.stderr)
    );
    out
}

/// Largest |twin − vanefit| of one recording per measured channel, in σ, with its row;
/// input columns must be passed through unchanged.
fn deviations(twin_csv: &Path, vanefit_csv: &Path) -> Vec<(String, f64, usize)> {
    let (head_t, rows_t) = read_csv(twin_csv);
    let (head_v, rows_v) = read_csv(vanefit_csv);
    assert_eq!(head_t, head_v, "{twin_csv:?}: columns differ");
    assert_eq!(
        rows_t.len(),
        rows_v.len(),
        "{twin_csv:?}: row count differs"
    );
    let mut out = Vec::new();
    for (j, name) in head_t.iter().enumerate() {
        let column = rows_t.iter().zip(&rows_v).map(|(a, b)| (a[j], b[j]));
        let Some(sigma) = sigma_in_column_unit(name) else {
            for (i, (a, b)) in column.enumerate() {
                assert!(
                    (a - b).abs() <= 1e-12 * a.abs(),
                    "{name} row {i}: input {a} → {b}"
                );
            }
            continue;
        };
        let (row, dev) = column
            .map(|(a, b)| (a - b).abs() / sigma)
            .enumerate()
            .fold((0, 0.0), |m, (i, d)| if d > m.1 { (i, d) } else { m });
        out.push((name.clone(), dev, row));
    }
    out
}

/// Writes the case's noise-free dataset, simulates it with vanefit and checks agreement.
fn agreement(case: &str, m: &TwinMotor, cfg: &RecordConfig) {
    let dir = tempfile::tempdir().expect("tempdir");
    let dataset = dir.path().join(case);
    let t0 = std::time::Instant::now();
    write_dataset(&dataset, m, cfg, 1).expect("twin dataset");
    let gen_s = t0.elapsed().as_secs_f64();
    let sim = vanefit_simulate(&dataset);
    let mut failures = Vec::new();
    let mut report = format!("{case} (twin generation {gen_s:.3} s):");
    for file in ["datasheet.csv", "ramp.csv", "throttle.csv"] {
        for (column, dev, row) in deviations(&dataset.join(file), &sim.join(file)) {
            report += &format!(" {file}:{column} {dev:.4}σ@{row};");
            if dev >= MAX_SIGMA {
                failures.push(format!("{file} {column}: {dev:.3} σ at row {row}"));
            }
        }
    }
    println!("{report}");
    assert!(
        failures.is_empty(),
        "{case}: twin and vanefit disagree: {failures:?}"
    );
}

#[test]
fn default_motor_agrees() {
    agreement(
        "default",
        &TwinMotor::default(),
        &RecordConfig::noise_free(),
    );
}

#[test]
fn moved_conductances_and_double_friction_agree() {
    let d = TwinMotor::default();
    let m = TwinMotor {
        c_in1: 0.7 * d.c_in1,
        c_out2: 1.4 * d.c_out2,
        c_ext: 0.7 * d.c_ext,
        c_1e: 1.4 * d.c_1e,
        c_2e: 0.7 * d.c_2e,
        c_12: 1.4 * d.c_12,
        t_coulomb: 2.0 * d.t_coulomb,
        visc: 2.0 * d.visc,
        ..d
    };
    agreement("moved", &m, &RecordConfig::noise_free());
}

#[test]
fn breakaway_friction_agrees() {
    let m = TwinMotor {
        breakaway_friction: Some(Breakaway {
            t_static_nm: 0.035,
            w_stribeck_rad_s: 3.0,
        }),
        ..TwinMotor::default()
    };
    agreement("breakaway", &m, &RecordConfig::noise_free());
}

#[test]
fn vane_friction_speed_squared_agrees() {
    let m = TwinMotor {
        vane_friction_speed_squared: Some(1e-8),
        ..TwinMotor::default()
    };
    agreement("vane_w2", &m, &RecordConfig::noise_free());
}

#[test]
fn speed_dependent_leakage_agrees() {
    let m = TwinMotor {
        speed_dependent_leakage: Some(SealLeakage {
            g_seal: 0.3,
            w_seal_rad_s: 300.0,
        }),
        ..TwinMotor::default()
    };
    agreement("seal", &m, &RecordConfig::noise_free());
}

/// Other critical ratio, isothermal cycle, other volumes, inertia and dead volume, 5 Hz. (With
/// b_crit ≠ 0.5 the twin follows (docs/model.md, "Parameters"), "critical pressure ratio of every
/// nozzle", and gives the rig's outlet throttle the motor's b_crit, as vanefit does.)
#[test]
fn other_fixed_parameters_agree() {
    let m = TwinMotor {
        b_crit: 0.3,
        n_poly: 1.0,
        vol1: 5e-6,
        vole: 1e-6,
        inertia: 5e-4,
        w_reg: 0.5,
        v_dead: 0.2e-6,
        ..twin::perturbed_motor(12)
    };
    let mut cfg = RecordConfig::noise_free();
    cfg.conditions.rate_hz = 5.0;
    agreement("fixed", &m, &cfg);
}

/// Other column units (l/min ANR, bar abs, rad/s), 20 Hz and the brake-torque channel.
#[test]
fn other_units_rate_and_brake_torque_agree() {
    let mut cfg = RecordConfig::noise_free();
    cfg.units = Units {
        flow: FlowUnit::LMinAnr,
        pressure: PressureUnit::BarAbs,
        speed: SpeedUnit::RadS,
    };
    cfg.conditions.rate_hz = 20.0;
    cfg.brake_torque = true;
    agreement("units", &twin::perturbed_motor(5), &cfg);
}

// ---- Twin-only physics checks (docs/model.md) -------------------------------------------

/// Steady state: what enters at port 1 leaves at port 2 and the exhaust (docs/model.md,
/// "Flows through the ideal motor" and "Lumped volumes and nozzles"),
/// also with the Δp² leak and speed-dependent leakage on.
#[test]
fn steady_state_conserves_mass() {
    let motors = [
        TwinMotor::default(),
        TwinMotor {
            leak_1e_dp2_kg_s_pa2: Some(2e-15),
            speed_dependent_leakage: Some(SealLeakage {
                g_seal: 0.5,
                w_seal_rad_s: 200.0,
            }),
            ..twin::perturbed_motor(2)
        },
    ];
    let c = experiment::Conditions {
        ramp_s: 2.0,
        throttle_s: 2.0,
        ..Default::default()
    };
    for m in &motors {
        let thr = experiment::outlet_throttle(m, &c).expect("throttle");
        let imbalance = thr.flow1_kg_s[0] - thr.flow2_kg_s[0] - thr.exhaust_kg_s[0];
        assert!(
            imbalance.abs() < 1e-12,
            "throttle start: {imbalance:e} kg/s"
        );
        assert!(thr.flow1_kg_s[0] > 4e-3 && thr.exhaust_kg_s[0] > 1e-3);
        let y = experiment::free_running_state(m, &c).expect("free running");
        let bc = twin::rig::Boundary {
            p_port1_pa: c.p_supply_pa,
            port2: twin::rig::Port2::Open,
            p_atm_pa: c.p_atm_pa,
            brake_nm_s_rad: 0.0,
            throttle_b_crit: None,
        };
        let f1 = twin::rig::flow1_kg_s(m, &bc, y[0]);
        let f2 = twin::rig::flow2_kg_s(m, &bc, y[1]);
        let fe = motor::exhaust_flow_kg_s(m, y[2], c.p_atm_pa);
        assert!(
            (f1 - f2 - fe).abs() < 1e-12 * f1,
            "free running: {f1} {f2} {fe}"
        );
    }
}

/// ε = 1: no expansion, the gear-motor torque z·(p_1 − p_2)(V_fill − V_d)/(2π) for any n.
#[test]
fn gear_motor_limit() {
    for n_poly in [1.0, 1.2, 1.4] {
        let m = TwinMotor {
            eps: 1.0,
            n_poly,
            ..TwinMotor::default()
        };
        let (p1, p2, pe) = (6.5e5, 1.8e5, 1.3e5);
        let gear = m.z * (p1 - p2) * (m.v_disp / m.z - m.v_dead) / (2.0 * std::f64::consts::PI);
        let t = motor::cycle_torque_nm(&m, p1, p2, pe);
        assert!((t - gear).abs() < 1e-14, "n = {n_poly}: {t} vs {gear}");
        let at_speed = motor::air_torque_nm(&m, [p1, p2, pe], 500.0);
        assert!(
            (at_speed - gear).abs() < 1e-12,
            "blended: {at_speed} vs {gear}"
        );
    }
}

/// n → 1: the torque is continuous and equals the isothermal cycle (ln ε terms).
#[test]
fn isothermal_limit_is_continuous() {
    let (p1, p2, pe) = (6.5e5, 1.8e5, 1.3e5);
    let at = |n_poly: f64| {
        let m = TwinMotor {
            n_poly,
            ..TwinMotor::default()
        };
        motor::cycle_torque_nm(&m, p1, p2, pe)
    };
    let m = TwinMotor::default();
    let (v_fill, ln_eps) = (m.v_disp / m.z, m.eps.ln());
    let work =
        (p1 - p2) * (v_fill - m.v_dead) + p1 * v_fill * ln_eps - pe * m.eps * v_fill * ln_eps;
    let isothermal = m.z * work / (2.0 * std::f64::consts::PI);
    assert!((at(1.0) - isothermal).abs() < 1e-14);
    for dn in [1e-12, 1e-9, 1e-6] {
        let jump = (at(1.0 + dn) - at(1.0)).abs();
        assert!(jump < 1e-3 * dn.sqrt().max(1e-9), "dn {dn}: {jump}");
    }
    assert!(
        at(1.3) < at(1.0) && at(1.4) < at(1.3),
        "less work as n grows (ε > 1)"
    );
}

/// A reversible motor: swapping ports 1 and 2 and reversing the speed mirrors torque and
/// flows (with c_1e = c_2e the leaks are symmetric too).
#[test]
fn reversible_symmetry() {
    let m = TwinMotor {
        speed_dependent_leakage: Some(SealLeakage {
            g_seal: 0.2,
            w_seal_rad_s: 300.0,
        }),
        ..TwinMotor::default()
    };
    for w in [0.0, 0.3, 2.0, 700.0] {
        let (p1, p2, pe) = (6.1e5, 2.2e5, 1.4e5);
        let t_fwd = motor::air_torque_nm(&m, [p1, p2, pe], w);
        let t_rev = motor::air_torque_nm(&m, [p2, p1, pe], -w);
        assert!(
            (t_fwd + t_rev).abs() < 1e-13,
            "torque at {w}: {t_fwd} vs {t_rev}"
        );
        let q = motor::internal_flows_kg_s(&m, [p1, p2, pe], w, 101_325.0);
        let r = motor::internal_flows_kg_s(&m, [p2, p1, pe], -w, 101_325.0);
        for (a, b) in [(q[0], r[1]), (q[1], r[0]), (q[2], r[2])] {
            assert!((a - b).abs() < 1e-15, "flows at {w}: {q:?} vs {r:?}");
        }
        let f_fwd = motor::friction_torque_nm(&m, w);
        assert_eq!(f_fwd, -motor::friction_torque_nm(&m, -w));
    }
}

/// ISO 6358 ψ: continuous at b and r_lam, monotone, zero at r = 1 with a finite slope.
#[test]
fn nozzle_function_is_continuous_and_monotone() {
    let b = 0.5;
    let mut last = 1.0;
    for i in 0..=200_000 {
        let r = i as f64 / 200_000.0;
        let psi = motor::iso6358_psi(r, b);
        assert!(psi <= last + 1e-15 && psi >= 0.0, "r = {r}");
        assert!(last - psi < 1e-3, "jump at r = {r}");
        last = psi;
    }
    assert_eq!(motor::iso6358_psi(1.0, b), 0.0);
    let below = motor::iso6358_psi(motor::R_LAMINAR - 1e-12, b);
    let above = motor::iso6358_psi(motor::R_LAMINAR + 1e-12, b);
    assert!((below - above).abs() < 1e-8);
}

// ---- The twin's own numerics ----------------------------------------------------------

/// Integration error far below sensor noise: tolerances 100× tighter change no channel by
/// more than 0.01 σ (measured: ≤ 2e-3 σ, the largest at the stiction case's breakaway).
#[test]
fn integration_error_is_far_below_noise() {
    let stiction = TwinMotor {
        breakaway_friction: Some(Breakaway {
            t_static_nm: 0.035,
            w_stribeck_rad_s: 3.0,
        }),
        ..TwinMotor::default()
    };
    let c = experiment::Conditions::default();
    let mut fine = c;
    fine.tol.rtol *= 1e-2;
    fine.tol.atol = fine.tol.atol.map(|a| a * 1e-2);
    let worst = |x: &[f64], y: &[f64], s: f64| {
        x.iter()
            .zip(y)
            .map(|(p, q)| (p - q).abs() / s)
            .fold(0.0, f64::max)
    };
    for m in [TwinMotor::default(), stiction] {
        for run in [experiment::pressure_ramp, experiment::outlet_throttle] {
            let (a, b) = (run(&m, &c).expect("run"), run(&m, &fine).expect("fine run"));
            let d1 = worst(&a.flow1_kg_s, &b.flow1_kg_s, SIGMA_FLOW_KG_S);
            let d2 = worst(&a.flow2_kg_s, &b.flow2_kg_s, SIGMA_FLOW_KG_S);
            let dw = worst(&a.speed_rad_s, &b.speed_rad_s, SIGMA_SPEED_RAD_S);
            println!("tolerance ÷100: flow1 {d1:.1e} σ, flow2 {d2:.1e} σ, speed {dw:.1e} σ");
            assert!(d1 < 1e-2 && d2 < 1e-2 && dw < 1e-2, "{d1} {d2} {dw}");
        }
    }
}

/// Same seed, same files; another seed, other noise. One dataset takes well under a second.
/// CPU seconds the calling thread has used (CLOCK_THREAD_CPUTIME_ID).
fn thread_cpu_s() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes one timespec through a valid pointer.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    assert_eq!(rc, 0, "clock_gettime");
    t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64
}

#[test]
fn datasets_are_reproducible_and_fast() {
    let dir = tempfile::tempdir().expect("tempdir");
    let files = |run: &str, seed: u64| {
        let d = dir.path().join(run).join("case9");
        // CPU time of this thread (the twin runs on it alone), not wall time: on a busy
        // machine the wall time grows with the load, the work does not.
        let t0 = thread_cpu_s();
        write_dataset(&d, &twin::perturbed_motor(9), &twin::varied_config(9), seed).expect("write");
        let took_s = thread_cpu_s() - t0;
        println!("dataset (perturbed_motor(9), varied_config(9)): {took_s:.3} CPU-s");
        assert!(took_s < 2.0, "slow: {took_s} CPU-s");
        [
            "rig.toml",
            "datasheet.csv",
            "ramp.csv",
            "throttle.csv",
            "truth.json",
        ]
        .map(|f| std::fs::read(d.join(f)).expect("read"))
    };
    let a = files("a", 4);
    assert!(a == files("b", 4), "same seed, different files");
    let c = files("c", 5);
    assert!(a[2] != c[2] && a[3] != c[3], "another seed, same noise");
}
