//! The diagnosis on data NOT made by vanefit: the independent twin generator (tests/twin).

use crate::cases::*;
use crate::support::{dataset, perturbed_base, rig_noise, synthesize_with};
use crate::twin;
use std::time::Instant;
use vanefit::data::Dataset;
use vanefit::diagnose::{diagnose, summary, DiagnoseOptions, Diagnosis};
use vanefit::model::{Chamber, LeakPath, Motor, PressureFactor};
use vanefit::model::{Effect, EffectSet};

/// A test rig's recording: 20 Hz, flows 0.03 g/s, speed 15 rpm, torques 4 mN·m, recorded
/// supply pressure 2 kPa, no calibration offsets.
pub(crate) fn twin_rig_config() -> twin::RecordConfig {
    let mut cfg = twin::RecordConfig {
        noise: twin::NoiseSigmas {
            flow1_g_s: 0.03,
            flow2_g_s: 0.03,
            speed_rpm: 15.0,
            torque_nm: 0.004,
            brake_torque_nm: 0.004,
            p_port1_pa: 2000.0,
            c_port2_rel: 0.005,
        },
        ..twin::RecordConfig::default()
    };
    cfg.conditions.rate_hz = 20.0;
    cfg
}

/// A twin dataset written to a temporary folder and loaded as vanefit reads any rig.
pub(crate) fn twin_dataset(
    motor: &twin::TwinMotor,
    cfg: &twin::RecordConfig,
    seed: u64,
) -> Dataset {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("twin-{seed}"));
    twin::write_dataset(&path, motor, cfg, seed).unwrap();
    vanefit::data::Dataset::load(&path).unwrap()
}

/// A twin case: its motor, what must be selected, and the truth of the checked values.
struct TwinCase {
    motor: twin::TwinMotor,
    expect: Expect,
    truth: Vec<(&'static str, f64)>,
}

fn twin_case(name: &str) -> TwinCase {
    let base = twin::perturbed_motor(7);
    let t_c = base.t_coulomb;
    match name {
        "stiction" => TwinCase {
            motor: twin::TwinMotor {
                breakaway_friction: Some(twin::Breakaway {
                    t_static_nm: 3.0 * t_c,
                    w_stribeck_rad_s: 8.0,
                }),
                ..base
            },
            expect: Expect::Effects(
                vec![Effect::BreakawayFriction],
                vec![("t_static", 0.15), ("w_stribeck", 0.5)],
            ),
            truth: vec![("t_static", 3.0 * t_c), ("w_stribeck", 8.0)],
        },
        "dp2 leak v1-ve" => TwinCase {
            motor: twin::TwinMotor {
                leak_1e_dp2_kg_s_pa2: Some(6e-16),
                ..base
            },
            expect: Expect::Leak(
                LeakPath::new(Chamber::V1, Chamber::Ve),
                PressureFactor::Quadratic,
                0.25,
            ),
            truth: vec![("coefficient", 6e-16)],
        },
        "leakage+vane pair" => TwinCase {
            motor: twin::TwinMotor {
                speed_dependent_leakage: Some(twin::SealLeakage {
                    g_seal: 0.5,
                    w_seal_rad_s: 300.0,
                }),
                vane_friction_speed_squared: Some(1e-8),
                ..base
            },
            expect: Expect::Effects(
                vec![
                    Effect::SpeedDependentLeakage,
                    Effect::VaneFrictionSpeedSquared,
                ],
                vec![("g_seal", 0.3), ("c_w2", 0.25)],
            ),
            truth: vec![("g_seal", 0.5), ("w_seal", 300.0), ("c_w2", 1e-8)],
        },
        _ => panic!("no twin case {name}"),
    }
}

/// Diagnoses a twin case and checks it (selected physics, category, parameters, noise ratio).
fn twin_run(name: &str, opts: &DiagnoseOptions) -> (Diagnosis, f64, Result<(), String>) {
    let c = twin_case(name);
    let ds = twin_dataset(&c.motor, &twin_rig_config(), 11);
    let t0 = Instant::now();
    let d = diagnose(&ds, opts).unwrap();
    let wall_s = t0.elapsed().as_secs_f64();
    let truth = |n: &str| c.truth.iter().find(|(k, _)| *k == n).unwrap().1;
    let (_, after) = d.noise_ratios();
    let ok = match &c.expect {
        Expect::Effects(effects, tol) => check_effects(effects, tol, &truth, &d),
        Expect::Leak(path, law, tol) => check_leak(*path, *law, *tol, truth("coefficient"), &d),
        _ => Ok(()),
    }
    .and_then(|()| {
        (after <= RIG_RATIO)
            .then_some(())
            .ok_or(format!("noise ratio {after:.3}"))
    });
    eprintln!(
        "twin {name}: {}\n  phases {:?}, {wall_s:.1} s",
        summary(&d),
        d.phases
    );
    print_candidates(&d);
    (d, wall_s, ok)
}

/// Rig case on twin data: stiction is breakaway friction alone, reproduced to the noise
/// (fixed by the Levenberg–Marquardt polish and the breakaway starts that lower T_c and
/// unpin c_12 from the bound the base fit drove it to).
#[test]
fn twin_stiction_is_breakaway_friction() {
    let (d, _, ok) = twin_run("stiction", &DiagnoseOptions::quick(1));
    ok.unwrap_or_else(|e| panic!("{e}\n{}", summary(&d)));
    // The reduced effort's intervals come from the curvature, one per estimated parameter,
    // each holding its estimate.
    assert_eq!(d.extended_intervals.len(), d.extended.fitted.k);
    for e in &d.extended_intervals {
        let i = &e.interval;
        assert_eq!(i.method, vanefit::estimate::Method::Curvature, "{}", i.name);
        let (lo, hi) = (i.lo.unwrap(), i.hi.unwrap());
        assert!(
            lo < i.value && i.value < hi,
            "{}: {lo:e} {:e} {hi:e}",
            i.name,
            i.value
        );
    }
}

/// Rig case on twin data: the Δp² leak V1 -> Ve is that leak path.
#[test]
fn twin_quadratic_leak_is_a_leak_path() {
    let (d, _, ok) = twin_run("dp2 leak v1-ve", &DiagnoseOptions::quick(1));
    ok.unwrap_or_else(|e| panic!("{e}\n{}", summary(&d)));
}

/// The extended fit's 95 % intervals (issue 45): on twin data with a Δp² leak V1 → Ve that
/// the base model does not have, every estimated parameter of the extended model (the
/// discovered term's coefficient included) has a profile interval that holds its estimate,
/// the coefficient's is closed and holds the twin's true coefficient, and `diagnosis.json`
/// states the same intervals.
#[test]
fn twin_extended_fit_intervals_hold_the_true_coefficient() {
    let c = twin_case("dp2 leak v1-ve");
    let ds = twin_dataset(&c.motor, &twin_rig_config(), 11);
    let opts = DiagnoseOptions {
        profile_intervals: true,
        ..DiagnoseOptions::quick(1)
    };
    let d = diagnose(&ds, &opts).unwrap();
    let f = &d.extended.fitted;
    assert_eq!(f.extra.len(), 1, "{}", summary(&d));
    assert_eq!(
        d.extended_intervals.len(),
        f.k,
        "{:?}",
        d.extended_intervals
    );
    for e in &d.extended_intervals {
        let i = &e.interval;
        assert_eq!(i.method, vanefit::estimate::Method::Profile);
        let holds = i.lo.is_none_or(|lo| lo <= i.value) && i.hi.is_none_or(|hi| i.value <= hi);
        assert!(
            holds,
            "{} = {:e} outside [{:?}, {:?}]",
            i.name, i.value, i.lo, i.hi
        );
        let fitted = match &e.term {
            Some(t) => t.coefficient,
            None => f.params.get(&i.name).unwrap(),
        };
        assert!(
            (i.value - fitted).abs() <= 1e-12 * fitted.abs(),
            "{}",
            i.name
        );
    }
    let coefficient = d
        .extended_intervals
        .iter()
        .find(|e| e.term.is_some())
        .unwrap();
    let (lo, hi) = (coefficient.interval.lo, coefficient.interval.hi);
    let truth = c.truth[0].1;
    let (lo, hi) = (lo.expect("closed below"), hi.expect("closed above"));
    eprintln!(
        "coefficient {:e} [{lo:e}, {hi:e}], true {truth:e}",
        coefficient.interval.value
    );
    assert!(
        lo <= truth && truth <= hi,
        "true {truth:e} outside [{lo:e}, {hi:e}]"
    );
    let json = vanefit::diagnose::to_json(&d);
    let listed = json["extended"]["intervals"].as_array().unwrap();
    assert_eq!(listed.len(), d.extended_intervals.len());
    let term = listed.iter().find(|v| v.get("formula").is_some()).unwrap();
    assert_eq!(term["parameter"], "coefficient");
    assert_eq!(term["lo"].as_f64(), Some(lo));
    assert_eq!(term["hi"].as_f64(), Some(hi));
}

/// Rig case on twin data: the pair is found as the pair (full effort: `#[ignore]`d, it is
/// in the normal run on vanefit's own data).
#[test]
#[ignore]
fn twin_leakage_and_vane_friction_pair() {
    let (d, _, ok) = twin_run("leakage+vane pair", &DiagnoseOptions::quick(1));
    ok.unwrap_or_else(|e| panic!("{e}\n{}", summary(&d)));
}

/// A clean twin dataset: a perturbed motor ([`twin::perturbed_motor`]) recorded with a
/// varied configuration ([`twin::varied_config`]: rate, noise levels, brake channel) but
/// without calibration offsets (a rig's zero errors are not in any model), both at the size
/// `DIAG_SIZES` gives the seed ([`crate::support::table_size_cm3`]; unset: 3.8 cm³).
fn clean_twin(seed: u64) -> Dataset {
    let cfg = twin::RecordConfig {
        offsets: twin::record::OffsetSpec::None,
        ..twin::varied_config(seed)
    };
    let size = crate::support::table_size_cm3(seed);
    let (motor, cfg) = crate::support::sized(twin::perturbed_motor(seed), cfg, size);
    twin_dataset(&motor, &cfg, seed)
}

/// One row of the false-alarm table.
fn false_alarm_row(seed: u64, opts: &DiagnoseOptions) -> (bool, String) {
    let d = diagnose(&clean_twin(seed), opts).unwrap();
    let best = d
        .candidates
        .iter()
        .map(|c| c.delta_bic)
        .fold(f64::INFINITY, f64::min);
    let selected: Vec<&str> = d.selected.iter().map(|s| s.effect.as_str()).collect();
    let row = format!(
        "| twin seed {seed} | {:.2} | {} | {:.3} | {} | {:.1} | {} | {:.1} |\n",
        crate::support::table_size_cm3(seed).unwrap_or(3.8),
        d.mismatch,
        d.baseline.noise_ratio,
        if selected.is_empty() {
            "-".to_string()
        } else {
            selected.join(" + ")
        },
        best,
        crate::support::evaluations(&d),
        d.wall_s
    );
    eprint!("{row}");
    (d.mismatch, row)
}

/// Clean data are not flagged (normal run: two clean twin datasets, quick options).
#[test]
fn clean_twin_datasets_are_not_flagged() {
    for seed in [7, 8] {
        let (mismatch, row) = false_alarm_row(seed, &DiagnoseOptions::quick(1));
        assert!(!mismatch, "false alarm: {row}");
    }
}

/// At most 1 false alarm in 20 clean twin datasets (different base motors, rates and noise
/// levels), the command line's default options (`DIAG_EFFORT=quick` for the quick ones), on
/// motors of the size `DIAG_SIZES` says (e.g. `1-150`; unset: 3.8 cm³); writes
/// `target/false-alarms.md` (or `FALSE_ALARMS_OUT_MD`):
///
/// ```sh
/// cargo test --release --test diagnose -- --ignored --nocapture false_alarm_table
/// ```
#[test]
#[ignore]
fn false_alarm_table() {
    let (opts, opts_name) = crate::support::table_options();
    let sizes = std::env::var("DIAG_SIZES").unwrap_or("3.8".into());
    let mut md = format!(
        "Options: {opts_name}; motor sizes {sizes} cm³.\n\n| dataset | V_disp cm³ | mismatch | noise ratio | selected | best ΔBIC | evaluations | wall s |\n|---|---|---|---|---|---|---|---|\n",
    );
    let path = std::env::var_os("FALSE_ALARMS_OUT_MD").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/false-alarms.md"),
        std::path::PathBuf::from,
    );
    let mut alarms = 0;
    for seed in 1..=20 {
        let (mismatch, row) = false_alarm_row(seed, &opts);
        alarms += usize::from(mismatch);
        md += &row;
        std::fs::write(&path, &md).unwrap();
    }
    std::fs::write(&path, &md).unwrap();
    println!("{md}");
    assert!(alarms <= 1, "{alarms} false alarms in 20\n{md}");
}

/// The table's former false alarm (seed 11), alone, in the normal run: before the
/// diagnosis fits handed over to Levenberg–Marquardt after 100 Nelder–Mead iterations,
/// the baseline ended at noise ratio 1.101 and an uncatalogued term gained ΔBIC −270.6;
/// with the hand-over the baseline reaches 1.049 and nothing is proposed. A diagnosis
/// whose baseline fit stops short of its optimum must not come back as a finding.
#[test]
fn false_alarm_seed_11() {
    let (mismatch, row) = false_alarm_row(11, &DiagnoseOptions::quick(1));
    assert!(!mismatch, "false alarm: {row}");
}

/// χ² of breakaway friction at the true parameters and a refit started there (synth and
/// twin stiction): whether the fitted Stribeck speed is the likelihood's or a stall.
#[test]
#[ignore]
fn stiction_likelihood_at_the_truth() {
    use vanefit::diagnose::{run_job, FitJob};
    use vanefit::objective::{CostModel, CostOptions, Target};
    let c = case("stiction");
    let synth = truth(&c);
    let ds_synth = dataset("synth", synthesize_with(&synth, 11, &rig_noise()));
    let tc = twin_case("stiction");
    let mut p = perturbed_base();
    for (n, v, _) in twin::files::parameters(&tc.motor) {
        p = p.with(n, v).unwrap();
    }
    let ds_twin = twin_dataset(&tc.motor, &twin_rig_config(), 11);
    let engine = vanefit::estimate::Engine::with_threads(Some(1)).unwrap();
    let effects = EffectSet::empty().with(Effect::BreakawayFriction);
    let mut names: Vec<String> = vanefit::estimate::DEFAULT_ESTIMATED
        .iter()
        .map(|s| s.to_string())
        .collect();
    names.extend(["t_static".to_string(), "w_stribeck".to_string()]);
    for (label, ds, params) in [
        ("synth", ds_synth, synth.params().clone()),
        ("twin", ds_twin, p),
    ] {
        let cost = CostModel::new(&ds, CostOptions::default()).unwrap();
        let target = Target::new(&cost, &ds).unwrap();
        let solver = vanefit::numerics::DefaultSolver::default();
        let m = Motor::new(params.clone(), effects.clone());
        let chi2 = target.chi2(&cost, &m, &solver).unwrap();
        let job = FitJob {
            label: label.into(),
            effects: effects.clone(),
            extra: Vec::new(),
            names: names.clone(),
            starts: vec![params],
            lhs: 0,
            max_iters: 1500,
            seed: 1,
        };
        let f = run_job(&cost, &target, &job, &engine).unwrap();
        eprintln!(
            "{label}: n {} chi2 at truth {chi2:.1}; refit from truth chi2 {:.1} t_static {:.4e} w_stribeck {:.3} t_coulomb {:.4e}",
            target.n_points(),
            f.chi2,
            f.params.get("t_static").unwrap(),
            f.params.get("w_stribeck").unwrap(),
            f.params.get("t_coulomb").unwrap()
        );
    }
}
