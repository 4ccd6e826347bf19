//! Are the fit's 95% intervals calibrated on data vanefit did not make? Intervals checked
//! only on vanefit's own synthetic data would share its mistakes.
//!
//! Every dataset here comes from the twin generator (`tests/twin/`): an independent
//! implementation of docs/model.md (its own code and integrator, TR-BDF2), with a recording
//! configuration unlike vanefit's `synth` defaults, drawn per seed ([`twin::varied_config`]):
//! 5, 10, 20 or 50 Hz; each channel's noise 0.5–3× (0.03 g/s, 15 rpm, 4 mN·m); 2 kPa noise
//! on the recorded supply pressure and 0.5% on the throttle's conductance; constant sensor
//! offsets within a calibrated rig's tolerance (flows 0.02 g/s, speed 2 rpm, torque 2 mN·m,
//! pressure 2 kPa, 1σ); a brake-torque channel in half of them. The motor's base
//! parameters are moved by factors in [0.75, 1.33] ([`twin::perturbed_motor`]).
//!
//! Each dataset is fitted as `vanefit fit` does (profile-likelihood intervals) and every
//! estimated parameter's interval is checked against the twin's truth; an open side counts
//! as unbounded. The normal run fits 6 datasets (48 intervals): under calibrated 95%
//! intervals more than 7 misses has probability 0.2%. The full table (50 datasets, per
//! parameter) is `#[ignore]`d and writes `target/coverage-table.md`:
//!
//! ```sh
//! cargo test --release --test estimate -- --ignored --nocapture coverage_table
//! ```

use crate::twin;

use std::fmt::Write as _;
use vanefit::data::Dataset;
use vanefit::estimate::multistart::Silent;
use vanefit::estimate::{fit, fit_file, FitData, FitSetup, UncertaintyMethod};
use vanefit::estimate::{Engine, MultiStartConfig, ParamSpace, Prior, DEFAULT_ESTIMATED};
use vanefit::model::EffectSet;
use vanefit::objective::CostOptions;
use vanefit::predict::{predict, PredictOptions, ROW_FIGURES};

/// One parameter of one fit against the truth.
struct Check {
    name: &'static str,
    truth: f64,
    estimate: f64,
    lo: Option<f64>,
    hi: Option<f64>,
    identifiable: bool,
}

impl Check {
    fn covers(&self) -> bool {
        self.lo.is_none_or(|lo| lo <= self.truth) && self.hi.is_none_or(|hi| self.truth <= hi)
    }
}

/// One dataset's fit.
struct Case {
    seed: u64,
    rate_hz: f64,
    brake_torque: bool,
    noise_ratio: f64,
    noise_reached: bool,
    checks: Vec<Check>,
    /// Each predicted catalogue figure (4 and 6.3 bar(g)): whether its 95 % band holds the
    /// twin's own figure.
    bands: Vec<(&'static str, bool)>,
}

/// `vanefit predict`'s catalogue rows at 4 and 6.3 bar(g) from the fit, each figure's band
/// against the twin's figure for the true motor (its own steady states and search).
fn band_checks(
    file: &vanefit::data::FitFile,
    motor: &twin::TwinMotor,
    p_atm_pa: f64,
) -> Vec<(&'static str, bool)> {
    let mut options = PredictOptions::new(p_atm_pa);
    options.pressures_pa = vec![p_atm_pa + 4e5, p_atm_pa + 6.3e5];
    let pr = predict(file, &options).unwrap();
    let mut out = Vec::new();
    for pp in &pr.pressures {
        let c = twin::Conditions {
            p_supply_pa: pp.p_supply_pa,
            p_atm_pa,
            ..twin::Conditions::default()
        };
        let t = twin::catalogue::catalogue_row(motor, &c).unwrap();
        let truth = [
            t.free_speed_rad_s,
            t.max_power_w,
            t.speed_at_max_power_rad_s,
            t.torque_at_max_power_nm,
            t.stall_torque_nm,
            t.air_at_max_power_kg_s,
            t.air_at_free_speed_kg_s,
        ];
        for ((name, b), y) in ROW_FIGURES.iter().zip(&pp.figures).zip(truth) {
            let [lo, hi] = b.band95.expect("the fit has intervals");
            if !(lo <= y && y <= hi) && std::env::var("BAND_DEBUG").is_ok() {
                eprintln!("{name} at {:.0}: value {:.6e} band [{lo:.6e}, {hi:.6e}] truth {y:.6e} (half-width {:.2e}, miss by {:.2} half-widths)", pp.p_supply_pa, b.value, (hi - lo) / 2.0, (y - b.value).abs() / ((hi - lo) / 2.0));
            }
            out.push((*name, lo <= y && y <= hi));
        }
    }
    out
}

/// Per figure: bands and how many hold the truth.
fn band_table(cases: &[Case]) -> String {
    let mut s = String::from(
        "| predicted figure (4 and 6.3 bar g) | bands | hold the twin's truth |\n|---|---|---|\n",
    );
    for name in ROW_FIGURES {
        let ks: Vec<bool> = cases
            .iter()
            .flat_map(|c| &c.bands)
            .filter(|(n, _)| *n == name)
            .map(|(_, k)| *k)
            .collect();
        let _ = writeln!(
            s,
            "| {name} | {} | {} |",
            ks.len(),
            ks.iter().filter(|k| **k).count()
        );
    }
    let all: Vec<bool> = cases
        .iter()
        .flat_map(|c| &c.bands)
        .map(|(_, k)| *k)
        .collect();
    let held = all.iter().filter(|k| **k).count();
    let _ = writeln!(
        s,
        "| all | {} | {held} ({:.1}%) |",
        all.len(),
        100.0 * held as f64 / all.len().max(1) as f64
    );
    s
}

fn truth_of(m: &twin::TwinMotor, name: &str) -> f64 {
    match name {
        "c_in1" => m.c_in1,
        "c_out2" => m.c_out2,
        "c_ext" => m.c_ext,
        "c_1e" => m.c_1e,
        "c_2e" => m.c_2e,
        "c_12" => m.c_12,
        "t_coulomb" => m.t_coulomb,
        "visc" => m.visc,
        other => panic!("no truth for {other}"),
    }
}

/// Writes the twin dataset of `seed`, fits it with `starts` starts and checks every interval.
fn run_case(seed: u64, starts: usize, engine: &Engine) -> Case {
    let dir = tempfile::tempdir().unwrap();
    let motor = twin::perturbed_motor(seed);
    let cfg = twin::varied_config(seed);
    twin::write_dataset(dir.path(), &motor, &cfg, seed).unwrap();
    let ds = Dataset::load(dir.path()).unwrap();
    let data = FitData::new(&ds, CostOptions::default()).unwrap();
    // As `vanefit fit` does: the motor prior around the size-scaled defaults.
    let space = ParamSpace::new(
        &DEFAULT_ESTIMATED,
        ds.nominal_params().unwrap(),
        EffectSet::empty(),
    )
    .unwrap()
    .with_prior(Prior::for_motor(&ds.nominal_params().unwrap()));
    let setup = FitSetup {
        multistart: MultiStartConfig {
            starts,
            seed,
            ..MultiStartConfig::default()
        },
        space,
        uncertainty: UncertaintyMethod::Profile,
        results_file: None,
        resume: false,
    };
    let out = fit(engine, &data, &setup, &Silent).unwrap();
    let g = out.goodness.clone().expect("the estimate simulates");
    let checks = DEFAULT_ESTIMATED
        .iter()
        .map(|name| {
            let iv = out.intervals.iter().find(|i| i.name == *name).unwrap();
            Check {
                name,
                truth: truth_of(&motor, name),
                estimate: iv.value,
                lo: iv.lo,
                hi: iv.hi,
                identifiable: iv.identifiable(),
            }
        })
        .collect();
    let bands = band_checks(&fit_file("twin", &setup, &out, seed), &motor, ds.p_atm_pa);
    Case {
        bands,
        seed,
        rate_hz: cfg.conditions.rate_hz,
        brake_torque: cfg.brake_torque,
        noise_ratio: g.noise_ratio,
        noise_reached: g.noise_reached,
        checks,
    }
}

fn misses(cases: &[Case]) -> usize {
    cases
        .iter()
        .flat_map(|c| &c.checks)
        .filter(|k| !k.covers())
        .count()
}

/// The markdown table: per parameter, then per dataset.
fn table(cases: &[Case]) -> String {
    let mut s = String::from(
        "| parameter | intervals | cover the truth | coverage | identifiable | median half-width |\n|---|---|---|---|---|---|\n",
    );
    for name in DEFAULT_ESTIMATED {
        let ks: Vec<&Check> = cases
            .iter()
            .flat_map(|c| &c.checks)
            .filter(|k| k.name == name)
            .collect();
        let covered = ks.iter().filter(|k| k.covers()).count();
        let ident = ks.iter().filter(|k| k.identifiable).count();
        let mut widths: Vec<f64> = ks
            .iter()
            .filter_map(|k| Some(100.0 * (k.hi? - k.lo?) / (2.0 * k.estimate)))
            .collect();
        widths.sort_by(f64::total_cmp);
        let median = widths.get(widths.len() / 2).copied().unwrap_or(f64::NAN);
        let _ = writeln!(
            s,
            "| {name} | {} | {covered} | {:.0}% | {ident} | {median:.2}% |",
            ks.len(),
            100.0 * covered as f64 / ks.len().max(1) as f64
        );
    }
    let total: usize = cases.iter().map(|c| c.checks.len()).sum();
    let _ = writeln!(
        s,
        "| all | {total} | {} | {:.1}% | | |\n",
        total - misses(cases),
        100.0 * (total - misses(cases)) as f64 / total.max(1) as f64
    );
    s.push_str("| seed | rate Hz | brake torque | noise ratio | reaches noise | misses | bands held |\n|---|---|---|---|---|---|---|\n");
    for c in cases {
        let missed: Vec<&str> = c
            .checks
            .iter()
            .filter(|k| !k.covers())
            .map(|k| k.name)
            .collect();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.3} | {} | {} | {}/{} |",
            c.seed,
            c.rate_hz,
            c.brake_torque,
            c.noise_ratio,
            c.noise_reached,
            missed.join(", "),
            c.bands.iter().filter(|(_, k)| *k).count(),
            c.bands.len()
        );
    }
    s
}

#[test]
fn intervals_cover_the_truth_on_twin_data() {
    let engine = Engine::with_threads(None).unwrap();
    let cases: Vec<Case> = (1..=6).map(|s| run_case(s, 10, &engine)).collect();
    let t = table(&cases);
    eprintln!("{t}");
    let m = misses(&cases);
    assert!(m <= 7, "{m} of 48 intervals miss the truth:\n{t}");
    let b = band_table(&cases);
    eprintln!("{b}");
    let held = cases
        .iter()
        .flat_map(|c| &c.bands)
        .filter(|(_, k)| *k)
        .count();
    // The floor comes from the 50-dataset table (`coverage_table`, per-dataset "bands held"),
    // not from this run: drawing 6 datasets from those 50 (bootstrap, 200 000 draws), the
    // bands held sum to 62 or more in 99 % of draws (median 78). Bands are correlated within
    // a dataset, so 84 bands are worth far fewer independent ones; seeds 1–6 hold 66, seed 2
    // (5 of 14: the estimate in a curved valley of the leakage conductances that a linear,
    // delta-method band does not follow) being the worst of all 50. The floor was 70 while
    // the χ² Hessian's jitter made seed 2's covariance indefinite and its fallback bands 7×
    // too wide, which held the truth by being useless.
    assert!(
        held >= 62,
        "{held} of 84 predicted bands hold the truth:\n{b}"
    );
    let reached = cases.iter().filter(|c| c.noise_reached).count();
    assert!(
        reached >= 5,
        "only {reached} of 6 fits reach the noise:\n{t}"
    );
}

#[test]
#[ignore = "50 fits, several minutes: the coverage table on twin data"]
fn coverage_table() {
    let engine = Engine::with_threads(None).unwrap();
    let mut cases = Vec::new();
    for s in 1..=50 {
        let c = run_case(s, 12, &engine);
        eprintln!(
            "seed {s}: noise ratio {:.3}, misses {}",
            c.noise_ratio,
            c.checks.iter().filter(|k| !k.covers()).count()
        );
        cases.push(c);
    }
    let t = table(&cases) + "\n" + &band_table(&cases);
    std::fs::create_dir_all("target").unwrap();
    std::fs::write("target/coverage-table.md", &t).unwrap();
    eprintln!("{t}");
    let total: usize = cases.iter().map(|c| c.checks.len()).sum();
    let covered = total - misses(&cases);
    assert!(
        covered as f64 >= 0.9 * total as f64,
        "coverage {covered}/{total}:\n{t}"
    );
    // Nominal 95 % bands: 630 of 700 (90.0 %) hold the twin's figure today; below 85 % they
    // would be clearly over-confident.
    let bands: usize = cases.iter().map(|c| c.bands.len()).sum();
    let held: usize = cases
        .iter()
        .flat_map(|c| &c.bands)
        .filter(|(_, k)| *k)
        .count();
    assert!(
        held as f64 >= 0.85 * bands as f64,
        "bands {held}/{bands}:\n{t}"
    );
}

/// Results never depend on the thread count (docs/cli.md), the intervals and the polish of the
/// local optima included.
#[test]
fn a_fit_with_intervals_does_not_depend_on_the_thread_count() {
    let one = run_case(3, 4, &Engine::with_threads(Some(1)).unwrap());
    let two = run_case(3, 4, &Engine::with_threads(Some(2)).unwrap());
    assert_eq!(one.noise_ratio.to_bits(), two.noise_ratio.to_bits());
    for (a, b) in one.checks.iter().zip(&two.checks) {
        assert_eq!(a.estimate.to_bits(), b.estimate.to_bits(), "{}", a.name);
        assert_eq!(a.lo.map(f64::to_bits), b.lo.map(f64::to_bits), "{}", a.name);
        assert_eq!(a.hi.map(f64::to_bits), b.hi.map(f64::to_bits), "{}", a.name);
    }
}
