//! The multi-start runner on objectives with known answers: it finds the minimum, gives the
//! same result whatever the thread count, and a resumed run ends where an uninterrupted one
//! would.

use vanefit::estimate::multistart;
use vanefit::estimate::multistart::{cluster, Ending, MultiStartOutcome, Silent};
use vanefit::estimate::{
    Engine, Evaluation, MultiStartConfig, Objective, ParamSpace, ResultsFile, DEFAULT_ESTIMATED,
};

/// Runs a multi-start on a fresh engine of `threads` workers.
fn run(
    threads: usize,
    obj: &dyn Objective,
    s: &ParamSpace,
    cfg: &MultiStartConfig,
    file: Option<&ResultsFile>,
    resume: bool,
) -> MultiStartOutcome {
    let engine = Engine::with_threads(Some(threads)).unwrap();
    let cfg = cfg.check().unwrap();
    multistart::run(&engine, obj, s, &cfg, &Silent, file, resume).unwrap()
}
use vanefit::model::EffectSet;
use vanefit::model::Motor;
use vanefit::model::MotorParams;

/// χ² of log-parameters against a known truth: a bowl with its bottom at the truth.
struct Bowl {
    truth: MotorParams,
}

impl Objective for Bowl {
    fn evaluate(&self, motor: &Motor) -> Evaluation {
        let chi2: f64 = DEFAULT_ESTIMATED
            .iter()
            .map(|n| {
                let (a, b) = (motor.params().get(n).unwrap(), self.truth.get(n).unwrap());
                ((a.ln() - b.ln()) / 0.05).powi(2)
            })
            .sum();
        Evaluation {
            cost: chi2,
            chi2,
            n_points: 100,
            failed: false,
        }
    }
}

/// Two valleys: the true one and a worse local one (a double well in c_ext).
struct DoubleWell;

impl Objective for DoubleWell {
    fn evaluate(&self, motor: &Motor) -> Evaluation {
        let x = (motor.params().c_ext() / 1e-8).log10(); // in [-1, 1] over the bounds
        let cost = 10.0 * (x * x - 0.25).powi(2) + 0.3 * x + 1.0;
        Evaluation {
            cost,
            chi2: cost,
            n_points: 10,
            failed: false,
        }
    }
}

fn truth() -> MotorParams {
    let p = MotorParams::default();
    p.with("c_in1", 8.1e-9)
        .unwrap()
        .with("c_12", 1.3e-9)
        .unwrap()
        .with("visc", 9e-5)
        .unwrap()
}

fn space() -> ParamSpace {
    ParamSpace::new(
        &DEFAULT_ESTIMATED,
        MotorParams::default(),
        EffectSet::empty(),
    )
    .unwrap()
}

#[test]
fn recovers_the_bottom_of_a_bowl() {
    let obj = Bowl { truth: truth() };
    let s = space();
    let cfg = MultiStartConfig {
        starts: 8,
        seed: 3,
        sd_tolerance: 1e-12,
        max_iters: 4000,
        ..Default::default()
    };
    let out = run(2, &obj, &s, &cfg, None, false);
    let best = s.params(&out.best().theta).unwrap();
    for n in DEFAULT_ESTIMATED {
        let (a, b) = (best.get(n).unwrap(), truth().get(n).unwrap());
        assert!((a / b - 1.0).abs() < 1e-3, "{n}: {a} vs {b}");
    }
    assert!(out.converged() >= 1);
}

#[test]
fn same_seed_same_result_whatever_the_thread_count() {
    let obj = Bowl { truth: truth() };
    let s = space();
    let cfg = MultiStartConfig {
        starts: 6,
        seed: 11,
        stage_iters: 40,
        max_iters: 400,
        ..Default::default()
    };
    let (one, two) = (
        run(1, &obj, &s, &cfg, None, false),
        run(2, &obj, &s, &cfg, None, false),
    );
    assert_eq!(one.results, two.results);
    assert_eq!(one.threads, 1);
    assert_eq!(two.threads, 2);
}

#[test]
fn resumed_run_ends_where_an_uninterrupted_one_would() {
    let obj = DoubleWell;
    let s = space();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("starts.jsonl");
    let cfg = MultiStartConfig {
        starts: 12,
        seed: 5,
        stage_iters: 5,
        max_iters: 300,
        kill_after_rounds: 1,
        kill_factor: 1.0,
        kill_margin: 0.1,
        join_tolerance: 1e-2,
        ..Default::default()
    };
    let file = ResultsFile::new(&path);
    let full = run(2, &obj, &s, &cfg, Some(&file), false);
    for (ending, what) in [
        (Ending::StoppedEarly, "early stops"),
        (Ending::Joined, "starts that join a converged one"),
    ] {
        assert!(
            full.results.iter().any(|r| r.ending == ending),
            "the test needs {what}: {:?}",
            full.results.iter().map(|r| r.ending).collect::<Vec<_>>()
        );
    }
    // Interrupt: keep the header and the first few finished starts, and a torn last line.
    let text = std::fs::read_to_string(&path).unwrap();
    let mut kept: Vec<&str> = text.lines().take(4).collect();
    let torn = &text.lines().nth(4).unwrap()[..20];
    kept.push(torn);
    std::fs::write(&path, kept.join("\n")).unwrap();
    let resumed = run(2, &obj, &s, &cfg, Some(&file), true);
    assert_eq!(full.results, resumed.results);
}

#[test]
fn double_well_has_two_minima_and_the_deeper_one_wins() {
    let obj = DoubleWell;
    let s = ParamSpace::new(&["c_ext"], MotorParams::default(), EffectSet::empty()).unwrap();
    let cfg = MultiStartConfig {
        starts: 16,
        seed: 2,
        sd_tolerance: 1e-12,
        kill_factor: 1e9,
        ..Default::default()
    };
    let out = run(2, &obj, &s, &cfg, None, false);
    let clusters = cluster(&out.results, &s, 0.02);
    assert_eq!(clusters.len(), 2, "{clusters:?}");
    assert_eq!(clusters.iter().map(|c| c.members.len()).sum::<usize>(), 16);
    let x = (s.params(&out.best().theta).unwrap().c_ext() / 1e-8).log10();
    // Exact minimum of 10(x²−¼)² + 0.3x on the left: 40x(x²−¼) + 0.3 = 0 near x = −0.5.
    let g = 40.0 * x * (x * x - 0.25) + 0.3;
    assert!(x < 0.0 && g.abs() < 1e-3, "x = {x}, gradient {g}");
}

#[test]
fn profile_and_curvature_intervals_match_the_closed_form_of_a_bowl() {
    use vanefit::estimate::Problem;
    use vanefit::estimate::{curvature_covariance, curvature_intervals, profile_intervals};
    let truth = truth();
    let obj = Bowl {
        truth: truth.clone(),
    };
    let s = ParamSpace::new(
        &["c_in1", "c_12", "visc"],
        MotorParams::default(),
        EffectSet::empty(),
    )
    .unwrap();
    let problem = Problem::new(&obj, &s, false);
    let engine = Engine::with_threads(Some(2)).unwrap();
    let theta = s.theta(&truth);
    let chi2_95 = vanefit::estimate::CHI2_95;
    // χ² = Σ (Δ ln p / 0.05)²: the 95% interval of each is ln p ± 1.96·0.05 (1.96² = 3.84);
    // widened by s = 2 (a model that misses its noise twofold) it doubles. (The curvature's
    // interval is symmetric in the search coordinate, whose logistic map bends ln p at the
    // doubled width by more than the 2e-3 checked here, so only s = 1 is checked for it.)
    for s2 in [1.0, 4.0] {
        let cov = curvature_covariance(&problem, &theta, 1e-3, s2).unwrap();
        let half = 0.05 * (chi2_95 * s2).sqrt();
        let curvature = curvature_intervals(&problem, &theta, Some(&cov));
        let intervals = curvature
            .into_iter()
            .filter(|_| s2 == 1.0)
            .chain(profile_intervals(
                &engine,
                &problem,
                &theta,
                0.0,
                chi2_95 * s2,
                Some(&cov),
                400,
            ));
        check_half_widths(intervals, &truth, half);
    }
}

fn check_half_widths(
    intervals: impl Iterator<Item = vanefit::estimate::Interval>,
    truth: &MotorParams,
    half: f64,
) {
    for iv in intervals {
        let v = truth.get(&iv.name).unwrap();
        let (lo, hi) = (iv.lo.unwrap(), iv.hi.unwrap());
        assert!(
            ((v / lo).ln() - half).abs() < 2e-3,
            "{} {:?}: lo {lo:e}",
            iv.name,
            iv.method
        );
        assert!(
            ((hi / v).ln() - half).abs() < 2e-3,
            "{} {:?}: hi {hi:e}",
            iv.name,
            iv.method
        );
    }
}

#[test]
fn a_parameter_the_cost_ignores_is_not_identifiable() {
    use vanefit::estimate::profile_intervals;
    use vanefit::estimate::Problem;
    let truth = truth();
    let obj = Bowl {
        truth: truth.clone(),
    };
    // b_crit does not enter the bowl: its profile is flat on both sides.
    let s = ParamSpace::new(&["c_in1", "b_crit"], truth.clone(), EffectSet::empty()).unwrap();
    let problem = Problem::new(&obj, &s, false);
    let engine = Engine::with_threads(Some(2)).unwrap();
    let theta = s.theta(&truth);
    let chi2_95 = vanefit::estimate::CHI2_95;
    let ivs = profile_intervals(&engine, &problem, &theta, 0.0, chi2_95, None, 200);
    assert!(ivs[0].identifiable(), "{ivs:?}");
    assert!(!ivs[1].identifiable());
    assert_eq!((ivs[1].lo, ivs[1].hi), (None, None));
}

/// An objective that breaks: NaN, infinity, then a proper value.
struct Broken;

impl Objective for Broken {
    fn evaluate(&self, motor: &Motor) -> Evaluation {
        let x = motor.params().c_in1().log10();
        let cost = if x > -8.2 {
            f64::NAN
        } else if x < -8.8 {
            f64::INFINITY
        } else {
            (x + 8.5).powi(2)
        };
        Evaluation {
            cost,
            chi2: cost,
            n_points: 1,
            failed: !cost.is_finite(),
        }
    }
}

#[test]
fn no_nan_or_infinity_reaches_the_optimizer() {
    use vanefit::estimate::Problem;
    let s = ParamSpace::new(&["c_in1"], MotorParams::default(), EffectSet::empty()).unwrap();
    let problem = Problem::new(&Broken, &s, false);
    for t in [-30.0, -3.0, -1.0, 0.0, 1.0, 3.0, 30.0] {
        let e = problem.evaluate(&[t]);
        assert!(e.cost.is_finite() && e.chi2.is_finite(), "θ = {t}: {e:?}");
    }
    // And the search still finds the finite valley between the broken regions.
    let cfg = MultiStartConfig {
        starts: 4,
        seed: 9,
        sd_tolerance: 1e-14,
        kill_factor: f64::INFINITY,
        ..Default::default()
    };
    let out = run(2, &Broken, &s, &cfg, None, false);
    let x = s.params(&out.best().theta).unwrap().c_in1().log10();
    assert!((x + 8.5).abs() < 1e-3, "log10 c_in1 = {x}");
}
