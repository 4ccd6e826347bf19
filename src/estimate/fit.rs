//! Fitting a dataset: the runner that owns the multi-start, the uncertainty analysis and the
//! export. It joins the data's cost (`cost::CostModel`) to the estimator through the
//! [`Objective`] trait.

use super::engine::Engine;
use super::error::EstimateError;
use super::history::ResultsFile;
use super::multistart::{self, cluster, Cluster, MultiStartOutcome, RunObserver};
use super::objective::{Evaluation, Objective, Problem};
use super::optimize::{minimize, Restart};
use super::settings::{MultiStartConfig, MultiStartSettings};
use super::space::ParamSpace;
use super::uncertainty::{self, Interval};
use crate::data::dataset::Kind;
use crate::data::fitfile::{FitFile, RunInfo, Starts};
use crate::model::motor::Motor;
use crate::model::params::MotorParams;
use crate::numerics::DefaultSolver;
use crate::objective::cost::CostModel;
use std::path::PathBuf;
use std::time::Instant;

/// The data's cost as an estimation objective.
pub struct DataObjective<'a> {
    /// The cost of the dataset.
    pub cost: &'a CostModel,
    /// The ODE solver of the simulations.
    pub solver: Box<dyn crate::numerics::ode::StiffSolver + 'a>,
}

impl Objective for DataObjective<'_> {
    fn evaluate(&self, motor: &Motor) -> Evaluation {
        let v = self.cost.evaluate(motor, self.solver.as_ref());
        // χ² over every compared row: n·mean((y − ŷ)/σ)², unweighted.
        let (chi2, n_points) = v.channels.iter().fold((0.0, 0), |(c, n), ch| {
            (c + ch.n as f64 * ch.rms_normalized.powi(2), n + ch.n)
        });
        Evaluation {
            cost: v.total,
            chi2: if v.failed.is_some() { v.total } else { chi2 },
            n_points,
            failed: v.failed.is_some(),
        }
    }
}

/// How intervals are computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UncertaintyMethod {
    /// Profile likelihood (curvature sizes the steps and fills in if it fails).
    Profile,
    /// Curvature of χ² only (fast).
    Curvature,
    /// No intervals.
    None,
}

/// Everything a fit needs besides the data.
pub struct FitSetup {
    /// What is estimated.
    pub space: ParamSpace,
    /// The multi-start (checked by [`fit`]).
    pub multistart: MultiStartConfig,
    /// How intervals are computed.
    pub uncertainty: UncertaintyMethod,
    /// Where finished starts are recorded.
    pub results_file: Option<PathBuf>,
    /// Continue from the results file.
    pub resume: bool,
}

/// The outcome of a fit.
#[derive(Debug, Clone)]
pub struct FitOutcome {
    /// The estimate.
    pub params: MotorParams,
    /// The estimate in optimizer coordinates.
    pub theta: Vec<f64>,
    /// Cost at the estimate.
    pub cost: f64,
    /// χ² at the estimate.
    pub chi2: f64,
    /// Data points behind χ².
    pub n_points: usize,
    /// 95% intervals (empty when not asked for).
    pub intervals: Vec<Interval>,
    /// Local minima found by the starts.
    pub clusters: Vec<Cluster>,
    /// Every start.
    pub run: MultiStartOutcome,
    /// Cost evaluations in all.
    pub evaluations: u64,
    /// Wall time, s.
    pub wall_s: f64,
}

impl FitOutcome {
    /// Bayesian information criterion, χ² + k·ln n.
    pub fn bic(&self) -> f64 {
        self.chi2 + self.theta.len() as f64 * (self.n_points.max(1) as f64).ln()
    }
}

/// Fits the space's parameters to the cost on the engine's threads.
pub fn fit(
    engine: &Engine,
    cost: &CostModel,
    setup: &FitSetup,
    observer: &dyn RunObserver,
) -> Result<FitOutcome, EstimateError> {
    let settings = setup.multistart.check()?;
    let t0 = Instant::now();
    let objective = DataObjective {
        cost,
        solver: Box::new(DefaultSolver::default()),
    };
    let file = setup.results_file.as_deref().map(ResultsFile::new);
    let run = multistart::run(
        engine,
        &objective,
        &setup.space,
        &settings,
        observer,
        file.as_ref(),
        setup.resume,
    )?;
    let best = run.best().clone();
    let problem = Problem::new(&objective, &setup.space, false);
    let best_theta = finish(&problem, &best.theta, best.cost, &settings);
    // With intervals, the estimate is the maximum-likelihood point (χ² polished from the best
    // start), so that value and interval belong together; without, the best start's point.
    let (theta, intervals) = match intervals(engine, &problem, &best_theta, setup.uncertainty) {
        Some((theta_ml, iv)) => (theta_ml, iv),
        None => (best_theta, Vec::new()),
    };
    let at = problem.evaluate(&theta);
    let clusters = cluster(&run.results, &setup.space, 0.02);
    let params = setup.space.params(&theta)?;
    Ok(FitOutcome {
        params,
        cost: at.cost,
        chi2: at.chi2,
        n_points: at.n_points,
        theta,
        intervals,
        clusters,
        evaluations: run.evaluations + problem.evaluations(),
        run,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

/// The best start carried on to a tight convergence (simplex costs within 1e-6, restarts
/// until one gains less than 1e-6 relative). The starts themselves stop at the looser
/// [`MultiStartConfig::sd_tolerance`], enough to rank them; the one that is exported and
/// that intervals are measured from is finished as every start used to be (issue 10:
/// this keeps the estimate where a run with the tight tolerance for every start ends,
/// for a few hundred evaluations instead of a third of all of them).
///
/// `f0` is the cost at `theta`, as the multi-start recorded it.
fn finish(
    problem: &Problem<'_>,
    theta: &[f64],
    f0: f64,
    settings: &MultiStartSettings,
) -> Vec<f64> {
    let mut nm = settings.nelder_mead();
    nm.sd_tolerance = nm.sd_tolerance.min(1e-6);
    if let Restart::Curvature { min_gain, .. } = &mut nm.restart {
        *min_gain = min_gain.min(1e-6);
    }
    let search = minimize(
        problem,
        theta.to_vec(),
        f0,
        nm,
        settings.max_iters(),
        settings.stage_iters(),
    );
    if search.cost() <= f0 {
        search.x().to_vec()
    } else {
        theta.to_vec()
    }
}

/// The maximum-likelihood point and the intervals around it (`None` when not asked for).
fn intervals(
    engine: &Engine,
    problem: &Problem<'_>,
    theta: &[f64],
    method: UncertaintyMethod,
) -> Option<(Vec<f64>, Vec<Interval>)> {
    if method == UncertaintyMethod::None {
        return None;
    }
    let (theta_ml, chi2_min) = uncertainty::polish_chi2(problem, theta, 400);
    let cov = uncertainty::curvature_covariance(problem, &theta_ml, 1e-3);
    let intervals = match method {
        UncertaintyMethod::Curvature => {
            uncertainty::curvature_intervals(problem, &theta_ml, cov.as_ref())
        }
        _ => {
            uncertainty::profile_intervals(engine, problem, &theta_ml, chi2_min, cov.as_ref(), 300)
        }
    };
    Some((theta_ml, intervals))
}

/// The experiment kind whose outputs move most (relative to typical sensor noise) when a
/// parameter changes by 20%, among the three reference experiments: where a parameter that
/// these data leave open would be pinned down.
pub fn most_sensitive_experiment(motor: &Motor, name: &str) -> Option<Kind> {
    use crate::data::synth::{free_speed, plan_experiments, SensorNoise, SynthPlan};
    use crate::sim::experiment::Experiment;
    use crate::units::Quantity;
    let plan = SynthPlan::default();
    let noise = SensorNoise::typical();
    let value = motor.params.get(name)?;
    let changed = Motor::new(
        motor.params.with(name, value * 1.2).ok()?,
        motor.effects.clone(),
    );
    let w_free = free_speed(motor, plan.p_supply_pa, plan.p_atm_pa).ok()?;
    let solver = DefaultSolver::default();
    plan_experiments(&plan, w_free)
        .iter()
        .filter_map(|d| {
            let ex = Experiment::new(d, plan.p_atm_pa).ok()?;
            let (a, b) = (
                ex.simulate(motor, &solver).ok()?,
                ex.simulate(&changed, &solver).ok()?,
            );
            let score: f64 = a
                .outputs
                .iter()
                .zip(&b.outputs)
                .map(|((q, ya), (_, yb))| {
                    let sd = match q {
                        Quantity::Speed => noise.speed_rad_s,
                        Quantity::Torque => noise.torque_nm,
                        _ => noise.flow_kg_s,
                    };
                    ya.iter()
                        .zip(yb)
                        .map(|(u, v)| ((u - v) / sd).powi(2))
                        .sum::<f64>()
                        / ya.len() as f64
                })
                .sum();
            Some((d.kind, score))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(k, _)| k)
}

/// The fit file of an outcome (SPEC §4).
pub fn fit_file(dataset: &str, setup: &FitSetup, out: &FitOutcome, seed: u64) -> FitFile {
    FitFile {
        dataset: dataset.to_string(),
        effects: setup.space.effects.clone(),
        params: out.params.clone(),
        estimated: setup.space.names(),
        ci95: out
            .intervals
            .iter()
            .filter_map(|iv| iv.ci95().map(|c| (iv.name.clone(), c)))
            .collect(),
        cost: Some(out.cost),
        starts: Some(Starts {
            total: out.run.results.len(),
            converged: out.run.converged(),
        }),
        seed: Some(seed),
        run: Some(RunInfo {
            evaluations: out.evaluations,
            wall_s: out.wall_s,
            threads: out.run.threads,
        }),
        extra: Vec::new(),
    }
}
