//! The missing-physics diagnosis proved on synthetic data with known truth (issue 5).
//!
//! Every dataset is the paper's three experiments simulated with typical sensor noise
//! (on the outputs AND on the recorded inputs) from a motor whose base parameters are moved
//! 20–40% from the defaults ([`diagnose_support::perturbed_base`]), with one effect switched
//! on at a CONCEALED size: a base-model fit to each experiment alone passes the noise-ratio
//! test the diagnosis applies (below [`vanefit::diagnose::noise_ratio_limit`] of that
//! experiment). The sizes and why (torque noise 2 mN·m, flow noise 0.01 g/s, speed noise
//! 5 rpm; free speed ≈ 1250 rad/s):
//!
//! | effect | truth | what it does at that size |
//! |---|---|---|
//! | `breakaway_friction` | t_static = 0.0265 N·m (T_c = 0.026) | 0.5 mN·m of static excess: the ramp's breakaway moves by ~1 kPa; any more and the ramp alone cannot be fitted |
//! | `vane_friction_speed_squared` | c_w2 = 3e-9 N·m·s²/rad² | 5 mN·m at free speed, 8% of the viscous loss, which a viscous term absorbs per experiment |
//! | `speed_dependent_leakage` | g_seal = 0.03, w_seal = 300 rad/s | 3% more leakage at standstill |
//! | `dead_volume_carryover` | v_carry = 0.02e-6 m³ | 20% of the dead volume carried back |
//! | `incomplete_filling` | w_fill = 6000 rad/s | compartments 4% short of port pressure at free speed |
//! | `pressure_dependent_friction` | k_fric_p = 1.5e-8 N·m/Pa | 9 mN·m more dry friction at full supply |
//! | `sensor_lag` | tau_sensor = 0.25 s | flows and speed lag by 0.25 s in the 60–65 s ramps |
//! | uncatalogued torque | 3e-11 N·m·s/(rad·Pa) · p2·ω | 4.5 mN·m at free speed, growing as the outlet is throttled |
//! | uncatalogued leak | −2e-8 kg/rad · ω at V_1 | 0.025 g/s at free speed |
//!
//! `valve_dynamics` has no case: the recorded port-1 pressure is the valve's output and drives
//! the simulation, so no valve dynamics can show in these experiments (the model has no valve
//! either); the diagnosis says so and never tries it.
//!
//! The normal run diagnoses a representative subset with reduced effort
//! ([`DiagnoseOptions::quick`]): the clean dataset, breakaway friction (torque loss),
//! carry-over (inlet flow) and the uncatalogued torque. The full table (every case, the
//! command line's settings) is `#[ignore]`d; it writes `target/diagnosis-results.md`:
//!
//! ```sh
//! cargo test --release --test diagnose -- --ignored --nocapture full_results_table
//! ```

use crate::support as diagnose_support;
use crate::twin;

use diagnose_support::{dataset, issue_noise, perturbed_base, synthesize, synthesize_with};
use std::time::Instant;
use vanefit::data::dataset::Dataset;
use vanefit::diagnose::{
    diagnose, discover, noise_ratio_limit, summary, to_json, Candidate, DiagnoseOptions, Diagnosis,
};
use vanefit::model::effects::{Effect, EffectSet};
use vanefit::model::motor::{
    BalanceId, Chamber, ExtraTerm, LeakPath, Motor, PressureFactor, SpeedFactor,
};

/// What a case should be diagnosed as.
#[derive(Debug, Clone)]
enum Expect {
    Nothing,
    /// The effect, its main parameter and the relative tolerance of its recovery.
    Effect(Effect, &'static str, f64),
    /// A discovered term in this balance with this feature; relative tolerance of the
    /// coefficient.
    Uncatalogued(BalanceId, &'static str, f64),
    /// Exactly these effects, each parameter within its relative tolerance (issue 11).
    Effects(Vec<Effect>, Vec<(&'static str, f64)>),
    /// One discovered leak along this path with this flow law (issue 11); relative
    /// tolerance of the coefficient.
    Leak(LeakPath, PressureFactor, f64),
}

struct Case {
    effects: EffectSet,
    params: Vec<(&'static str, f64)>,
    extra: Vec<ExtraTerm>,
    expect: Expect,
    /// Issue 11's recordings: 20 Hz, its noise levels ([`diagnose_support::issue_noise`]),
    /// the effect visible (not concealed).
    issue11: bool,
}

/// Issue 11's cases (20 Hz, its noise, effects clearly visible).
fn issue_case(name: &str) -> Option<Case> {
    let issue = |effects: EffectSet, params: Vec<(&'static str, f64)>, extra, expect| Case {
        effects,
        params,
        extra,
        expect,
        issue11: true,
    };
    let t_c = perturbed_base().t_coulomb();
    Some(match name {
        "clean (issue noise)" => issue(EffectSet::empty(), Vec::new(), Vec::new(), Expect::Nothing),
        // Static friction 3× Coulomb, Stribeck speed 8 rad/s: a late start in the ramp.
        "stiction" => issue(
            EffectSet::empty().with(Effect::BreakawayFriction),
            vec![("t_static", 3.0 * t_c), ("w_stribeck", 8.0)],
            Vec::new(),
            Expect::Effects(
                vec![Effect::BreakawayFriction],
                vec![("t_static", 0.1), ("w_stribeck", 0.5)],
            ),
        ),
        // Worn vane tips: V1 -> Ve growing with (p1 - pe)², ≈ 0.15 g/s at full supply.
        "dp2 leak v1-ve" => issue(
            EffectSet::empty(),
            Vec::new(),
            vec![ExtraTerm::leak(
                LeakPath::new(Chamber::V1, Chamber::Ve),
                PressureFactor::Quadratic,
                SpeedFactor::One,
                6e-16,
            )],
            Expect::Leak(
                LeakPath::new(Chamber::V1, Chamber::Ve),
                PressureFactor::Quadratic,
                0.2,
            ),
        ),
        "leakage+vane pair" => issue(
            EffectSet::empty()
                .with(Effect::SpeedDependentLeakage)
                .with(Effect::VaneFrictionSpeedSquared),
            vec![("g_seal", 0.5), ("w_seal", 300.0), ("c_w2", 1e-8)],
            Vec::new(),
            Expect::Effects(
                vec![
                    Effect::SpeedDependentLeakage,
                    Effect::VaneFrictionSpeedSquared,
                ],
                vec![("g_seal", 0.25), ("c_w2", 0.2)],
            ),
        ),
        _ => return None,
    })
}

fn case(name: &str) -> Case {
    if let Some(c) = issue_case(name) {
        return c;
    }
    let effect = |e: Effect, params: Vec<(&'static str, f64)>, main: &'static str, tol: f64| Case {
        effects: EffectSet::empty().with(e),
        params,
        extra: Vec::new(),
        expect: Expect::Effect(e, main, tol),
        issue11: false,
    };
    match name {
        "clean" => Case {
            effects: EffectSet::empty(),
            params: Vec::new(),
            extra: Vec::new(),
            expect: Expect::Nothing,
            issue11: false,
        },
        "breakaway_friction" => effect(
            Effect::BreakawayFriction,
            vec![("t_static", 0.0265), ("w_stribeck", 30.0)],
            "t_static",
            0.02,
        ),
        "vane_friction_speed_squared" => effect(
            Effect::VaneFrictionSpeedSquared,
            vec![("c_w2", 3e-9)],
            "c_w2",
            0.15,
        ),
        "speed_dependent_leakage" => effect(
            Effect::SpeedDependentLeakage,
            vec![("g_seal", 0.03), ("w_seal", 300.0)],
            "g_seal",
            0.15,
        ),
        "dead_volume_carryover" => effect(
            Effect::DeadVolumeCarryover,
            vec![("v_carry", 0.02e-6)],
            "v_carry",
            0.15,
        ),
        "incomplete_filling" => effect(
            Effect::IncompleteFilling,
            vec![("w_fill", 6000.0)],
            "w_fill",
            0.15,
        ),
        "pressure_dependent_friction" => effect(
            Effect::PressureDependentFriction,
            vec![("k_fric_p", 1.5e-8)],
            "k_fric_p",
            0.15,
        ),
        "sensor_lag" => effect(
            Effect::SensorLag,
            vec![("tau_sensor", 0.25)],
            "tau_sensor",
            0.15,
        ),
        "uncatalogued torque" => Case {
            effects: EffectSet::empty(),
            params: Vec::new(),
            extra: vec![ExtraTerm {
                balance: BalanceId::Torque,
                pressure: PressureFactor::P2,
                speed: SpeedFactor::Omega,
                coefficient: 3e-11,
            }],
            expect: Expect::Uncatalogued(BalanceId::Torque, "p2*omega", 0.15),
            issue11: false,
        },
        "uncatalogued leak" => Case {
            effects: EffectSet::empty(),
            params: Vec::new(),
            extra: vec![ExtraTerm {
                balance: BalanceId::Mass1,
                pressure: PressureFactor::One,
                speed: SpeedFactor::Omega,
                coefficient: -2e-8,
            }],
            expect: Expect::Uncatalogued(BalanceId::Mass1, "omega", 0.15),
            issue11: false,
        },
        _ => panic!("no case {name}"),
    }
}

/// The case's true motor.
fn truth(c: &Case) -> Motor {
    let mut p = perturbed_base();
    for (n, v) in &c.params {
        p = p.with(n, *v).unwrap();
    }
    Motor::new(p, c.effects.clone()).with_extra(&c.extra)
}

/// One row of the results table.
struct Row {
    name: String,
    detected: String,
    delta_bic: f64,
    truth: String,
    recovered: String,
    ratios: (f64, f64),
    alone: Vec<(f64, f64)>,
    wall_s: f64,
    ok: Result<(), String>,
}

fn check(c: &Case, motor: &Motor, d: &Diagnosis) -> Result<(), String> {
    let conc = d.concealment.as_ref().ok_or("no concealment test")?;
    // Concealed: every experiment fitted alone passes the noise-ratio test.
    for e in &conc.experiments {
        if !c.issue11 && e.alone_ratio >= e.alone_limit {
            return Err(format!(
                "not concealed: {} alone has noise ratio {:.3} (limit {:.3})",
                e.file, e.alone_ratio, e.alone_limit
            ));
        }
    }
    let (before, after) = d.noise_ratios();
    match &c.expect {
        Expect::Nothing => {
            if d.mismatch || !d.selected.is_empty() {
                return Err(format!("claimed {:?}", d.selected));
            }
            if conc.disagree() {
                return Err(format!("separate fits disagree, p {:.2e}", conc.p_value));
            }
            if !d.locations.is_empty() {
                return Err(format!("{} location(s) on clean data", d.locations.len()));
            }
        }
        Expect::Effect(e, main, tol) => {
            let ids: Vec<&str> = d.selected.iter().map(|s| s.effect.as_str()).collect();
            if ids != [e.id()] || !d.mismatch {
                return Err(format!("selected {ids:?}, expected [{}]", e.id()));
            }
            let got = d.extended.fitted.params.get(main).unwrap();
            let want = motor.params.get(main).unwrap();
            if ((got - want) / want).abs() > *tol {
                return Err(format!("{main} {got:.4e}, true {want:.4e}"));
            }
        }
        Expect::Uncatalogued(balance, feature, tol) => {
            let terms: Vec<&ExtraTerm> =
                d.selected.iter().filter_map(|s| s.term.as_ref()).collect();
            if d.selected.len() != 1 || terms.len() != 1 {
                return Err(format!("selected {:?}", d.selected));
            }
            let t = terms[0];
            if t.balance != *balance || discover::feature_name(t) != *feature {
                return Err(format!("found {}", discover::formula(t)));
            }
            let want = c.extra[0].coefficient;
            if ((t.coefficient - want) / want).abs() > *tol {
                return Err(format!(
                    "coefficient {:.4e}, true {want:.4e}",
                    t.coefficient
                ));
            }
            if d.selected[0].category != discover::category(&c.extra[0]) {
                return Err(format!("category {:?}", d.selected[0].category));
            }
        }
        Expect::Effects(effects, tolerances) => {
            check_effects(effects, tolerances, &|n| motor.params.get(n).unwrap(), d)?
        }
        Expect::Leak(path, law, tol) => check_leak(*path, *law, *tol, c.extra[0].coefficient, d)?,
    }
    if c.issue11 && after > ISSUE_RATIO {
        return Err(format!("noise ratio {before:.3} -> {after:.3}"));
    }
    if !matches!(c.expect, Expect::Nothing) {
        if d.delta_bic() > -10.0 {
            return Err(format!("dBIC {:.1}", d.delta_bic()));
        }
        // Near 1: within what noise alone gives.
        let limit = noise_ratio_limit(&d.extended_channels);
        if after > limit || after > before {
            return Err(format!(
                "noise ratio {before:.3} -> {after:.3} (limit {limit:.3})"
            ));
        }
    }
    Ok(())
}

/// Noise ratio an issue-11 case must reach with the selected model.
const ISSUE_RATIO: f64 = 1.1;

/// The selected effects are exactly `effects`, each parameter near the truth.
fn check_effects(
    effects: &[Effect],
    tolerances: &[(&str, f64)],
    truth: &dyn Fn(&str) -> f64,
    d: &Diagnosis,
) -> Result<(), String> {
    let mut ids: Vec<&str> = d.selected.iter().map(|s| s.effect.as_str()).collect();
    let mut want: Vec<&str> = effects.iter().map(|e| e.id()).collect();
    ids.sort();
    want.sort();
    if ids != want || !d.mismatch {
        return Err(format!("selected {ids:?}, expected {want:?}"));
    }
    for s in &d.selected {
        let e: Effect = s.effect.parse().map_err(|_| "unknown effect")?;
        if s.category != e.category() {
            return Err(format!("{} in category {:?}", s.effect, s.category));
        }
    }
    for (name, tol) in tolerances {
        let got = d.extended.fitted.params.get(name).unwrap();
        let want = truth(name);
        if ((got - want) / want).abs() > *tol {
            return Err(format!(
                "{name} {got:.4e}, true {want:.4e} (tolerance {tol})"
            ));
        }
    }
    Ok(())
}

/// One discovered leak along `path` by `law`, in the path's category, its coefficient
/// near the truth.
fn check_leak(
    path: LeakPath,
    law: PressureFactor,
    tol: f64,
    want: f64,
    d: &Diagnosis,
) -> Result<(), String> {
    let terms: Vec<&ExtraTerm> = d.selected.iter().filter_map(|s| s.term.as_ref()).collect();
    if d.selected.len() != 1 || terms.len() != 1 {
        return Err(format!("selected {:?}", d.selected));
    }
    let t = terms[0];
    if t.balance != BalanceId::Path(path) || t.pressure != law {
        return Err(format!("found {}", discover::formula(t)));
    }
    if d.selected[0].category != path.category() {
        return Err(format!("category {:?}", d.selected[0].category));
    }
    if ((t.coefficient - want) / want).abs() > tol {
        return Err(format!(
            "coefficient {:.4e}, true {want:.4e}",
            t.coefficient
        ));
    }
    Ok(())
}

fn run(name: &str, opts: &DiagnoseOptions) -> (Row, Diagnosis) {
    let c = case(name);
    let motor = truth(&c);
    let experiments = if c.issue11 {
        synthesize_with(&motor, 11, &issue_noise())
    } else {
        synthesize(&motor, 11)
    };
    let v: Vec<String> = [
        "t_coulomb",
        "t_static",
        "w_stribeck",
        "c_w2",
        "g_seal",
        "w_seal",
    ]
    .iter()
    .map(|n| format!("{n}={:.4e}", motor.params.get(n).unwrap_or(f64::NAN)))
    .collect();
    eprintln!("  truth: {}", v.join(" "));
    let ds = dataset(&format!("synthetic {name}"), experiments);
    let t0 = Instant::now();
    let d = diagnose(&ds, opts).unwrap();
    let wall_s = t0.elapsed().as_secs_f64();
    let (truth_s, recovered) = match &c.expect {
        Expect::Nothing => ("-".to_string(), "-".to_string()),
        Expect::Effect(_, main, _) => (
            format!("{main} = {:.4e}", motor.params.get(main).unwrap()),
            format!("{:.4e}", d.extended.fitted.params.get(main).unwrap()),
        ),
        Expect::Effects(_, tolerances) => (
            tolerances
                .iter()
                .map(|(n, _)| format!("{n} = {:.4e}", motor.params.get(n).unwrap()))
                .collect::<Vec<_>>()
                .join(", "),
            tolerances
                .iter()
                .map(|(n, _)| format!("{:.4e}", d.extended.fitted.params.get(n).unwrap()))
                .collect::<Vec<_>>()
                .join(", "),
        ),
        Expect::Uncatalogued(..) | Expect::Leak(..) => (
            discover::formula(&c.extra[0]),
            d.selected
                .iter()
                .find_map(|s| s.term.as_ref())
                .map_or("-".into(), |t| format!("{:.4e}", t.coefficient)),
        ),
    };
    let detected = if d.selected.is_empty() {
        format!("none (mismatch {})", d.mismatch)
    } else {
        d.selected
            .iter()
            .map(|s| match &s.term {
                Some(t) => format!(
                    "uncatalogued {} ({})",
                    discover::feature_name(t),
                    s.category.id()
                ),
                None => s.effect.clone(),
            })
            .collect::<Vec<_>>()
            .join(" + ")
    };
    let alone = d
        .concealment
        .as_ref()
        .map(|c| {
            c.experiments
                .iter()
                .map(|e| (e.alone_ratio, e.alone_limit))
                .collect()
        })
        .unwrap_or_default();
    let row = Row {
        name: name.to_string(),
        detected,
        delta_bic: d.delta_bic(),
        truth: truth_s,
        recovered,
        ratios: d.noise_ratios(),
        alone,
        wall_s,
        ok: check(&c, &motor, &d),
    };
    eprintln!("{name}: {}", summary(&d));
    (row, d)
}

fn assert_case(name: &str) -> Diagnosis {
    let (row, d) = run(name, &DiagnoseOptions::quick(1));
    eprintln!(
        "{name}: detected {}, dBIC {:.1}, {} -> {}, noise ratio {:.3} -> {:.3}, {:.1} s",
        row.detected,
        row.delta_bic,
        row.truth,
        row.recovered,
        row.ratios.0,
        row.ratios.1,
        row.wall_s
    );
    eprintln!("{name}: phases {:?}", d.phases);
    print_candidates(&d);
    if let Err(e) = &row.ok {
        panic!("{name}: {e}\n{}", summary(&d));
    }
    d
}

#[test]
fn clean_dataset_has_no_mismatch_and_the_output_follows_spec() {
    let d = assert_case("clean");
    // diagnosis.json exactly in SPEC §6 form, report and plots next to it.
    let dir = tempfile::tempdir().unwrap();
    vanefit::report::diagnose::write_all(&d, dir.path()).unwrap();
    let text = std::fs::read_to_string(dir.path().join("diagnosis.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(
        keys,
        [
            "format",
            "mismatch",
            "baseline",
            "locations",
            "candidates",
            "selected",
            "extended"
        ]
    );
    assert_eq!(v["format"], "vanefit.diagnosis/1");
    assert_eq!(v["mismatch"], false);
    assert_eq!(v["selected"].as_array().unwrap().len(), 0);
    assert_eq!(v["baseline"], v["extended"]);
    for k in ["cost", "noise_ratio"] {
        assert!(v["baseline"][k].as_f64().unwrap() > 0.0);
    }
    let candidates = v["candidates"].as_array().unwrap();
    assert_eq!(candidates.len(), 7, "{candidates:?}");
    for c in candidates {
        let o = c.as_object().unwrap();
        assert_eq!(
            o.keys().collect::<Vec<_>>(),
            ["effect", "cost", "delta_bic"]
        );
        assert!(o["delta_bic"].as_f64().unwrap() > -10.0);
    }
    assert!(!candidates.iter().any(|c| c["effect"] == "valve_dynamics"));
    assert_eq!(to_json(&d), v);
    let report = std::fs::read_to_string(dir.path().join("report.md")).unwrap();
    assert!(report.contains("valve_dynamics"), "{report}");
    // Issue 12: read without the source. Every parameter id with its meaning, conductances
    // also in the catalogues' dm3/(s*bar), and what cost J and the noise ratio are.
    for needle in [
        "`c_1e` (leak, inlet side → exhaust)",
        "`t_coulomb` (Coulomb friction torque)",
        "dm3/(s*bar)",
        "cost J = sum over experiments and channels",
        "noise ratio = √(mean over channels",
    ] {
        assert!(report.contains(needle), "{needle}");
    }
    for f in [
        "ranking.svg",
        "overlay.datasheet.svg",
        "residuals.ramp.svg",
        "overlay.throttle.svg",
    ] {
        assert!(dir.path().join(f).is_file(), "{f}");
        assert!(report.contains(f), "{f}");
    }
}

#[test]
fn concealed_breakaway_friction_is_named() {
    let d = assert_case("breakaway_friction");
    // Concealed to the point that the baseline's noise ratio is within noise: only the
    // refit of the candidates shows it.
    let v = to_json(&d);
    assert_eq!(v["selected"][0]["category"], "torque_loss");
    assert_eq!(
        v["selected"][0]["parameters"]
            .as_object()
            .unwrap()
            .keys()
            .collect::<Vec<_>>(),
        ["t_static", "w_stribeck"]
    );
}

#[test]
fn concealed_dead_volume_carryover_is_named() {
    let d = assert_case("dead_volume_carryover");
    assert!(!d.locations.is_empty());
    assert_eq!(to_json(&d)["selected"][0]["category"], "inlet_flow");
}

/// In the full table; left out of the normal run to keep it short.
#[test]
#[ignore]
fn concealed_sensor_lag_is_named() {
    assert_case("sensor_lag");
}

#[test]
fn uncatalogued_torque_is_discovered_and_modelled() {
    let d = assert_case("uncatalogued torque");
    let v = to_json(&d);
    let s = &v["selected"][0];
    assert_eq!(s["effect"], "uncatalogued");
    assert_eq!(s["category"], "torque_loss");
    assert_eq!(s["balance"], "torque");
    assert!(s["formula"].as_str().unwrap().contains("p2*omega"), "{s}");
    // The extended model's fit file carries the term and still reads as a fit file.
    let dir = tempfile::tempdir().unwrap();
    vanefit::report::diagnose::write_all(&d, dir.path()).unwrap();
    let path = dir.path().join("extended.json");
    let file = vanefit::data::fitfile::FitFile::read(&path).unwrap();
    assert_eq!(file.extra, d.extended.fitted.extra);
}

/// The table for the README (every case, the command line's settings).
#[test]
#[ignore]
fn full_results_table() {
    let names = [
        "clean",
        "breakaway_friction",
        "vane_friction_speed_squared",
        "speed_dependent_leakage",
        "dead_volume_carryover",
        "incomplete_filling",
        "pressure_dependent_friction",
        "sensor_lag",
        "uncatalogued torque",
        "uncatalogued leak",
    ];
    let opts = DiagnoseOptions::full(4, 1);
    let mut md = String::from(
        "| case | detected | ΔBIC | truth | recovered | noise ratio before → after | each experiment fitted alone (limit) | wall s | ok |\n|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut failures = Vec::new();
    for name in names {
        let (row, _) = run(name, &opts);
        let alone: Vec<String> = row
            .alone
            .iter()
            .map(|(r, l)| format!("{r:.3} ({l:.3})"))
            .collect();
        md += &format!(
            "| {} | {} | {:.1} | {} | {} | {:.3} → {:.3} | {} | {:.1} | {} |\n",
            row.name,
            row.detected,
            row.delta_bic,
            row.truth,
            row.recovered,
            row.ratios.0,
            row.ratios.1,
            alone.join(", "),
            row.wall_s,
            match &row.ok {
                Ok(()) => "yes".to_string(),
                Err(e) => format!("NO: {e}"),
            }
        );
        if let Err(e) = row.ok {
            failures.push(format!("{name}: {e}"));
        }
        eprintln!("{md}");
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/diagnosis-results.md");
    std::fs::write(&path, &md).unwrap();
    println!("{md}");
    assert!(failures.is_empty(), "{failures:?}");
}

/// Every candidate's χ², ΔBIC, noise ratio and breakaway parameters (to stderr).
fn print_candidates(d: &Diagnosis) {
    let p = |c: &Candidate, n: &str| c.fitted.params.get(n).unwrap_or(f64::NAN);
    for c in std::iter::once(&d.baseline).chain(&d.candidates) {
        eprintln!(
            "  {:<50} chi2 {:>12.1} dBIC {:>10.1} ratio {:.3} t_static {:.4e} w_stribeck {:.3} evals {}",
            c.label,
            c.fitted.chi2,
            c.delta_bic,
            c.noise_ratio,
            p(c, "t_static"),
            p(c, "w_stribeck"),
            c.fitted.evaluations
        );
    }
    for c in std::iter::once(&d.baseline).chain(&d.candidates).take(6) {
        let v: Vec<String> = d
            .estimated
            .iter()
            .map(|n| format!("{n}={:.4e}", c.fitted.params.get(n).unwrap_or(f64::NAN)))
            .collect();
        eprintln!("  {}: {}", c.label, v.join(" "));
    }
}

/// An issue-11 case with quick options, its summary and JSON checked.
fn assert_issue_case(name: &str) -> Diagnosis {
    let d = assert_case(name);
    let v = to_json(&d);
    for (s, e) in v["selected"].as_array().unwrap().iter().zip(&d.selected) {
        assert_eq!(s["category"], e.category.id());
    }
    d
}

/// Issue 11: static friction 3× Coulomb with a Stribeck speed of 8 rad/s starts the motor
/// late in the ramp; breakaway friction alone explains it, its Stribeck speed estimated.
/// ω_s is weakly determined by the ramp: χ² at the truth is 7389 (7519 points), the fit
/// ends at 7322 with ω_s 10.9, an earlier fit stalled at 7344 with ω_s 1.1; within 50%.
#[test]
fn stiction_is_breakaway_friction_with_its_stribeck_speed() {
    let d = assert_issue_case("stiction");
    assert_eq!(d.selected[0].category.id(), "torque_loss");
}

/// Issue 11: a leak V1 -> Ve growing with (p1 - pe)² is found as that leak path, in words
/// (the normal run has the twin-data version of this case).
#[test]
#[ignore]
fn quadratic_internal_leak_is_a_leak_path() {
    let d = assert_issue_case("dp2 leak v1-ve");
    let v = to_json(&d);
    let s = &v["selected"][0];
    assert_eq!(s["effect"], "uncatalogued");
    assert_eq!(s["category"], "internal_leakage");
    assert_eq!(s["balance"], "leak_path");
    assert_eq!(
        (s["from"].as_str(), s["to"].as_str()),
        (Some("v1"), Some("ve"))
    );
    let words = s["description"].as_str().unwrap();
    assert!(
        words.contains("square of the pressure difference"),
        "{words}"
    );
    // The extended fit file carries the path and reads back.
    let dir = tempfile::tempdir().unwrap();
    vanefit::report::diagnose::write_all(&d, dir.path()).unwrap();
    let file = vanefit::data::fitfile::FitFile::read(&dir.path().join("extended.json")).unwrap();
    assert_eq!(file.extra, d.extended.fitted.extra);
}

/// Issue 11: speed-dependent leakage with ω² vane friction is found as the pair (the pair is
/// tried because a discovered torque-loss term stands in for the ω² friction).
#[test]
fn leakage_and_vane_friction_are_found_as_a_pair() {
    assert_issue_case("leakage+vane pair");
}

// ---- Issue 11 on data NOT made by vanefit: the independent twin generator (tests/twin). ----

/// Issue 11's recording: 20 Hz, flows 0.03 g/s, speed 15 rpm, torques 4 mN·m, recorded
/// supply pressure 2 kPa, no calibration offsets.
fn twin_issue_config() -> twin::RecordConfig {
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
fn twin_dataset(motor: &twin::TwinMotor, cfg: &twin::RecordConfig, seed: u64) -> Dataset {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("twin-{seed}"));
    twin::write_dataset(&path, motor, cfg, seed).unwrap();
    vanefit::data::dataset::Dataset::load(&path).unwrap()
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
    let ds = twin_dataset(&c.motor, &twin_issue_config(), 11);
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
        (after <= ISSUE_RATIO)
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

/// Issue 11 on twin data: stiction is breakaway friction alone, reproduced to the noise
/// (fixed by the Levenberg–Marquardt polish and the breakaway starts that lower T_c and
/// unpin c_12 from the bound the base fit drove it to).
#[test]
fn twin_stiction_is_breakaway_friction() {
    let (d, _, ok) = twin_run("stiction", &DiagnoseOptions::quick(1));
    ok.unwrap_or_else(|e| panic!("{e}\n{}", summary(&d)));
}

/// Issue 11 on twin data: the Δp² leak V1 -> Ve is that leak path.
#[test]
fn twin_quadratic_leak_is_a_leak_path() {
    let (d, _, ok) = twin_run("dp2 leak v1-ve", &DiagnoseOptions::quick(1));
    ok.unwrap_or_else(|e| panic!("{e}\n{}", summary(&d)));
}

/// Issue 11 on twin data: the pair is found as the pair (full effort: `#[ignore]`d, it is
/// in the normal run on vanefit's own data).
#[test]
#[ignore]
fn twin_leakage_and_vane_friction_pair() {
    let (d, _, ok) = twin_run("leakage+vane pair", &DiagnoseOptions::quick(1));
    ok.unwrap_or_else(|e| panic!("{e}\n{}", summary(&d)));
}

/// A clean twin dataset: a perturbed motor ([`twin::perturbed_motor`]) recorded with a
/// varied configuration ([`twin::varied_config`]: rate, noise levels, brake channel) but
/// without calibration offsets (a rig's zero errors are not in any model).
fn clean_twin(seed: u64) -> Dataset {
    let cfg = twin::RecordConfig {
        offsets: twin::record::OffsetSpec::None,
        ..twin::varied_config(seed)
    };
    twin_dataset(&twin::perturbed_motor(seed), &cfg, seed)
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
        "| twin seed {seed} | {} | {:.3} | {} | {:.1} | {:.1} |\n",
        d.mismatch,
        d.baseline.noise_ratio,
        if selected.is_empty() {
            "-".to_string()
        } else {
            selected.join(" + ")
        },
        best,
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
/// levels); writes `target/false-alarms.md`:
///
/// ```sh
/// cargo test --release --test diagnose -- --ignored --nocapture false_alarm_table
/// ```
#[test]
#[ignore]
fn false_alarm_table() {
    let mut md = String::from(
        "| dataset | mismatch | noise ratio | selected | best ΔBIC | wall s |\n|---|---|---|---|---|---|\n",
    );
    let mut alarms = 0;
    for seed in 1..=20 {
        let (mismatch, row) = false_alarm_row(seed, &DiagnoseOptions::quick(1));
        alarms += usize::from(mismatch);
        md += &row;
    }
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/false-alarms.md");
    std::fs::write(&path, &md).unwrap();
    println!("{md}");
    assert!(alarms <= 1, "{alarms} false alarms in 20\n{md}");
}

/// The one false alarm of the table (seed 11), alone. KNOWN FAILING (ignored): with the
/// Levenberg–Marquardt polish the baseline still ends at noise ratio 1.101 and an
/// uncatalogued term gains ΔBIC −270.6: not a stalled baseline fit; cause not yet found.
///
/// ```sh
/// cargo test --release --test diagnose -- --ignored --nocapture false_alarm_seed_11
/// ```
#[test]
#[ignore]
fn false_alarm_seed_11() {
    let (mismatch, row) = false_alarm_row(11, &DiagnoseOptions::quick(1));
    assert!(!mismatch, "false alarm: {row}");
}

/// χ² of breakaway friction at the true parameters and a refit started there (synth and
/// twin stiction): whether the fitted Stribeck speed is the likelihood's or a stall.
#[test]
#[ignore]
fn stiction_likelihood_at_the_truth() {
    use vanefit::diagnose::fitting::{run_job, FitJob};
    use vanefit::objective::{cost::CostModel, cost::CostOptions, likelihood::Target};
    let c = case("stiction");
    let synth = truth(&c);
    let ds_synth = dataset("synth", synthesize_with(&synth, 11, &issue_noise()));
    let tc = twin_case("stiction");
    let mut p = perturbed_base();
    for (n, v, _) in twin::files::parameters(&tc.motor) {
        p = p.with(n, v).unwrap();
    }
    let ds_twin = twin_dataset(&tc.motor, &twin_issue_config(), 11);
    let engine = vanefit::estimate::engine::Engine::with_threads(Some(1)).unwrap();
    let effects = EffectSet::empty().with(Effect::BreakawayFriction);
    let mut names: Vec<String> = vanefit::estimate::space::DEFAULT_ESTIMATED
        .iter()
        .map(|s| s.to_string())
        .collect();
    names.extend(["t_static".to_string(), "w_stribeck".to_string()]);
    for (label, ds, params) in [("synth", ds_synth, synth.params), ("twin", ds_twin, p)] {
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
