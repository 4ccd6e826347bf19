//! Fitting a dataset: the runner that owns the multi-start, the uncertainty analysis and the
//! export. It joins the data's cost (`cost::CostModel`) to the estimator through the
//! [`Objective`] trait.
//!
//! # One estimate, two scores
//!
//! The multi-start minimises the cost J (docs/model.md, "Cost J"; simulation against the
//! reference polynomials, each channel normalised by its polynomial's scatter): smooth,
//! cheap to rank starts by, and the project's contract. Its best start is then carried to
//! the maximum of the likelihood of the RECORDED rows ([`crate::objective::likelihood`]: σ
//! from the data alone, the inputs' smooth driving the simulation, sensor offsets as
//! nuisances), which is the estimate, whatever `--uncertainty` asks: a point and its
//! interval belong to one likelihood, and the exported parameters do not depend on whether
//! intervals were computed. J at that point is a little above the best start's J (the two
//! scores weigh the channels differently); both are reported. The goodness of fit
//! ([`crate::estimate::fit::goodness`]) is measured against the data's noise, and intervals are widened
//! where the model misses it.

pub(crate) mod displacement;
pub(crate) mod fit_likelihood;
pub(crate) mod goodness;
pub(crate) mod max_likelihood;
pub(crate) mod setup;

use crate::data::dataset::Kind;
use crate::data::fitfile::{
    FitConditions, FitFile, LogCovariance, ParamVerdict, ProfilePath, RunInfo, Starts,
};
pub use crate::data::statistics::UncertaintyMethod;
use crate::data::statistics::{BoundEntry, EstimateMethod, FitStatistics, PriorEntry};
use crate::estimate::engine::Engine;
use crate::estimate::error::EstimateError;
use crate::estimate::fit::goodness::{competitors, mark_competitors, worst_channel, GoodnessOfFit};
use crate::estimate::fit::max_likelihood::{lowest, maximum_likelihood, MlFit, Polished};
use crate::estimate::history::ResultsFile;
use crate::estimate::optimize::local::{LocalOptimizer, NelderMead};
use crate::estimate::optimize::multistart::{
    self, cluster, Cluster, MultiStartOutcome, RunObserver,
};
use crate::estimate::optimize::nelder_mead::Restart;
use crate::estimate::optimize::settings::{MultiStartConfig, MultiStartSettings};
pub use crate::estimate::problem::fit_data::FitData;
use crate::estimate::problem::likelihood::Likelihood;
use crate::estimate::problem::objective::{Evaluation, Objective, Problem};
use crate::estimate::problem::space::{BoundHit, ParamSpace};
use crate::estimate::profile::uncertainty::{self, Interval};
use crate::model::motor::Motor;
use crate::model::params::{MotorParams, ParamId};
use crate::numerics::DefaultSolver;
use crate::objective::cost::{ChannelResiduals, CostModel, FAILURE_PENALTY};
use crate::sim::experiment::SimError;
use nalgebra::DMatrix;
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

    /// Each channel's normalised residuals (y − ŷ)/σ scaled by √(w/N): their squares sum
    /// to J (docs/model.md, "Cost J", eq. 1).
    fn cost_residuals(&self, motor: &Motor) -> Option<Vec<f64>> {
        let channels = self.cost.residuals(motor, self.solver.as_ref()).ok()?;
        let mut out = Vec::with_capacity(channels.iter().map(|c| c.normalized.len()).sum());
        for ch in &channels {
            let n = ch.normalized.len();
            if n == 0 {
                continue;
            }
            let scale = (ch.weight / n as f64).sqrt();
            out.extend(ch.normalized.iter().map(|r| r * scale));
        }
        Some(out)
    }

    fn has_cost_residuals(&self) -> bool {
        true
    }
}

/// Local optima of the multi-start, besides the best, polished on the likelihood: candidates
/// for the estimate and, when they fit as well, evidence that a parameter is not identifiable.
const RIVALS: usize = 8;

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
    /// Cost J at the estimate.
    pub cost: f64,
    /// J of the best start (the multi-start's optimum, before the likelihood's polish).
    pub best_start_cost: f64,
    /// The likelihood's χ² at the estimate (σ widened per `FitOutcome::widening`, the
    /// nuisances' prior terms included); the estimate minimises, and the intervals are
    /// profiled on, this plus [`FitOutcome::prior_chi2`].
    pub chi2: f64,
    /// The motor prior's χ²_prior at the estimate (`estimate::problem::prior`; 0 without a prior).
    pub prior_chi2: f64,
    /// Rise of that χ² that bounds a 95 % profile interval (`None` without a simulation).
    pub threshold: Option<f64>,
    /// Data points behind χ².
    pub n_points: usize,
    /// Goodness of fit against the data's noise (`None` if the estimate cannot be simulated):
    /// the record the fit file's statistics state.
    pub goodness: Option<GoodnessOfFit>,
    /// The channel farthest from its noise, "file column" and √(χ²_c/n_c)
    /// (`goodness::worst_channel`; `None` where `goodness` is).
    pub worst_channel: Option<(String, f64)>,
    /// How the intervals were computed.
    pub method: UncertaintyMethod,
    /// The systematic errors profiled out at the estimate (label, value SI: sensor offsets
    /// in the sensor's unit, the supply-pressure offset in Pa).
    pub nuisances: Vec<(String, f64)>,
    /// Channels whose noise estimate was widened to their residual scatter ("file column",
    /// factor > 1), widened where the residuals at the estimate scatter more than the data's σ.
    pub(crate) widening: Vec<(String, f64)>,
    /// The estimated parameters (name, SI value) at which the supply-pressure offset's effect
    /// on the rows was linearised ([`FitData::target_at`]).
    pub linearised_at: Vec<(String, f64)>,
    /// 95% intervals (empty when not asked for).
    pub intervals: Vec<Interval>,
    /// Covariance of θ (optimizer coordinates) from the curvature of χ², scaled as the
    /// intervals are (`None` when no intervals were asked for or the curvature is not
    /// positive definite); see `FitOutcome::log_covariance`.
    pub covariance: Option<DMatrix<f64>>,
    /// The atmosphere and the supply pressures that the fitted recordings cover.
    pub conditions: FitConditions,
    /// Local minima found by the starts.
    pub clusters: Vec<Cluster>,
    /// The estimate's simulation of every channel the cost J compares, beside its reference
    /// (what the fit's overlay plots draw), or why it could not be simulated.
    pub channels: Result<Vec<ChannelResiduals>, SimError>,
    /// For each estimated parameter that the data leave open (its interval says why), the
    /// reference experiment that would pin it (`most_sensitive_experiment`), where one is
    /// found.
    pub would_pin: Vec<(ParamId, Kind)>,
    /// The estimated parameters that ended on a bound of their search range
    /// (`ParamSpace::bounds_reached`): the data pushed them out of the range that real
    /// motors of this size span, or the model lacks what the data show.
    pub on_bound: Vec<BoundHit>,
    /// Every start.
    pub run: MultiStartOutcome,
    /// Cost evaluations in all.
    pub evaluations: u64,
    /// Wall time, s.
    pub wall_s: f64,
}

impl FitOutcome {
    /// The covariance of the estimated parameters' logarithms ([`log_covariance`]).
    fn log_covariance(&self, space: &ParamSpace) -> Option<LogCovariance> {
        log_covariance(space, &self.theta, self.covariance.as_ref()?)
    }
}

/// The covariance of the estimated parameters' logarithms from that of the optimizer's
/// coordinates θ: Σ_log = D·Σ_θ·D with D = diag(d ln v_j/dθ_j) at θ. With u = 1/(1 + e^(−θ))
/// the position in the bounds, d ln v/dθ = (ln hi − ln lo)·u·(1 − u) on a log scale and
/// (hi − lo)·u·(1 − u)/v on a linear one (`estimate::problem::space`). Symmetrised against rounding.
/// A parameter without variance (one the curvature left out, on a bound of the search) is
/// left out of it, since a fit file's covariance states positive variances only.
/// `None` when the sizes disagree or a linearly placed parameter is not positive (it has no
/// logarithm).
fn log_covariance(space: &ParamSpace, theta: &[f64], cov: &DMatrix<f64>) -> Option<LogCovariance> {
    let k = space.len();
    if cov.nrows() != k || cov.ncols() != k || theta.len() != k {
        return None;
    }
    let d: Vec<f64> = space
        .dims
        .iter()
        .zip(theta)
        .map(|(dim, t)| {
            let u = 1.0 / (1.0 + (-t).exp());
            let slope = u * (1.0 - u);
            if dim.log_scale {
                Some((dim.hi.ln() - dim.lo.ln()) * slope)
            } else {
                let v = dim.value(*t);
                (v > 0.0).then(|| (dim.hi - dim.lo) * slope / v)
            }
        })
        .collect::<Option<_>>()?;
    let held: Vec<usize> = (0..k)
        .filter(|&i| d[i] * d[i] * cov[(i, i)] > 0.0)
        .collect();
    let matrix = held
        .iter()
        .map(|&i| {
            held.iter()
                .map(|&j| d[i] * 0.5 * (cov[(i, j)] + cov[(j, i)]) * d[j])
                .collect()
        })
        .collect();
    let names = space.names();
    Some(LogCovariance {
        parameters: held.iter().map(|&i| names[i].clone()).collect(),
        matrix,
    })
}

/// Fits the space's parameters to the data on the engine's threads (see the module docs):
/// the multi-start on the cost J (`search`), the maximum-likelihood polish of its best
/// minima, and the estimate's assessment (`assess`).
pub fn fit(
    engine: &Engine,
    data: &FitData,
    setup: &FitSetup,
    observer: &dyn RunObserver,
) -> Result<FitOutcome, EstimateError> {
    let settings = setup.multistart.check()?;
    let t0 = Instant::now();
    let objective = DataObjective {
        cost: &data.cost,
        solver: Box::new(DefaultSolver::default()),
    };
    let problem = Problem::new(&objective, &setup.space, false);
    let searched = search(engine, &objective, &problem, setup, &settings, observer)?;
    let ml_fit = maximum_likelihood(engine, data, &setup.space, &searched.points)?;
    let linearised_at = setup
        .space
        .names()
        .into_iter()
        .map(|n| {
            let v = ml_fit.linearised_at.params().get(&n).unwrap_or(f64::NAN);
            (n, v)
        })
        .collect();
    let widening = ml_fit.widening.clone();
    let a = assess(engine, data, setup, ml_fit, observer)?;
    let at = problem.evaluate(&a.theta);
    let on_bound = setup.space.bounds_reached(&a.params);
    Ok(FitOutcome {
        params: a.params,
        cost: at.cost,
        best_start_cost: searched.best_cost,
        chi2: a.chi2,
        prior_chi2: a.prior_chi2,
        threshold: a.threshold,
        n_points: data.target.n_points(),
        goodness: a.goodness,
        worst_channel: a.worst_channel,
        method: setup.uncertainty,
        nuisances: a.nuisances,
        widening,
        linearised_at,
        theta: a.theta,
        intervals: a.intervals,
        covariance: a.covariance,
        conditions: data.conditions,
        clusters: searched.clusters,
        channels: a.channels,
        would_pin: a.would_pin,
        on_bound,
        evaluations: searched.run.evaluations + problem.evaluations() + a.evaluations,
        run: searched.run,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

/// What the multi-start on the cost J found: every start, its local minima, and the points
/// the likelihood's polish starts from (the best start carried to a tight convergence, then
/// the best of the rival minima).
struct Searched {
    run: MultiStartOutcome,
    best_cost: f64,
    clusters: Vec<Cluster>,
    points: Vec<Vec<f64>>,
}

/// The multi-start on the cost J and the tight finish of its best start.
fn search(
    engine: &Engine,
    objective: &DataObjective<'_>,
    problem: &Problem<'_>,
    setup: &FitSetup,
    settings: &MultiStartSettings,
    observer: &dyn RunObserver,
) -> Result<Searched, EstimateError> {
    let file = setup.results_file.as_deref().map(ResultsFile::new);
    let run = multistart::run(
        engine,
        objective,
        &setup.space,
        settings,
        observer,
        file.as_ref(),
        setup.resume,
    )?;
    let best = run.best().clone();
    if best.cost >= FAILURE_PENALTY {
        check_evaluated(objective, &setup.space, &best.theta)?;
    }
    observer.phase("maximum likelihood", 0);
    let best_theta = finish(problem, &best.theta, best.cost, settings);
    let clusters = cluster(&run.results, &setup.space, 0.02);
    let mut points = vec![best_theta];
    points.extend(
        clusters
            .iter()
            .skip(1)
            .take(RIVALS)
            .map(|c| c.theta.clone()),
    );
    Ok(Searched {
        run,
        best_cost: best.cost,
        clusters,
        points,
    })
}

/// The error of a best start whose cost could not be evaluated: the cost model's penalty
/// keeps the optimizer's values finite, so the search itself runs on, but a best start that
/// never had a finite cost is no estimate ([`EstimateError::NoFiniteCost`]). `Ok` where the
/// cost at `theta` was evaluated (a real cost as high as the penalty).
fn check_evaluated(
    objective: &DataObjective<'_>,
    space: &ParamSpace,
    theta: &[f64],
) -> Result<(), EstimateError> {
    let motor = Motor::new(space.params(theta)?, space.effects.clone());
    match objective
        .cost
        .evaluate(&motor, objective.solver.as_ref())
        .failed
    {
        Some(why) => Err(EstimateError::NoFiniteCost { why }),
        None => Ok(()),
    }
}

/// The estimate and what is known of it (the fields of [`FitOutcome`] of the same names).
struct Assessed {
    params: MotorParams,
    theta: Vec<f64>,
    chi2: f64,
    prior_chi2: f64,
    threshold: Option<f64>,
    goodness: Option<GoodnessOfFit>,
    worst_channel: Option<(String, f64)>,
    nuisances: Vec<(String, f64)>,
    intervals: Vec<Interval>,
    covariance: Option<DMatrix<f64>>,
    channels: Result<Vec<ChannelResiduals>, SimError>,
    would_pin: Vec<(ParamId, Kind)>,
    /// Likelihood evaluations of the intervals.
    evaluations: u64,
}

/// The estimate (the lowest of the polished points) and what is known of it: χ² and the
/// prior's share, goodness of fit, the systematic errors, intervals and covariance, the
/// simulated channels and what would pin an open parameter.
fn assess(
    engine: &Engine,
    data: &FitData,
    setup: &FitSetup,
    ml_fit: MlFit,
    observer: &dyn RunObserver,
) -> Result<Assessed, EstimateError> {
    let (target, widened, mut polished) = (ml_fit.target, ml_fit.widened, ml_fit.polished);
    let likelihood = Likelihood {
        cost: &data.smoothed,
        target: &widened,
        solver: DefaultSolver::default(),
    };
    let ml = Problem::new(&likelihood, &setup.space, false);
    let best_i = lowest(&polished);
    let (theta, posterior_chi2) = polished.swap_remove(best_i);
    let params = setup.space.params(&theta)?;
    let prior_chi2 = setup.space.prior.chi2(&setup.space.dims, &params);
    let motor = Motor::new(params.clone(), setup.space.effects.clone());
    let k = theta.len();
    let simulated = data.simulate(&motor);
    let chi2s = simulated
        .as_ref()
        .map(|sim| data.channel_chi2(&target, sim));
    let goodness = chi2s.as_deref().map(|c| GoodnessOfFit::new(c, k));
    let worst_channel = chi2s.as_deref().and_then(worst_channel);
    let scored = simulated
        .as_ref()
        .map(|sim| GoodnessOfFit::new(&data.channel_chi2(&widened, sim), k));
    let nuisances = simulated
        .as_ref()
        .map(|sim| target.nuisance_estimates(sim))
        .unwrap_or_default();
    let (intervals, covariance) = match &scored {
        Some(g) => intervals(
            engine,
            &ml,
            &theta,
            posterior_chi2,
            g,
            &polished,
            setup,
            observer,
        ),
        None => (Vec::new(), None),
    };
    let channels = data.cost.residuals(&motor, &DefaultSolver::default());
    let would_pin = open_parameters(&setup.space, &intervals)
        .filter_map(|id| Some((id, most_sensitive_experiment(&motor, id.name())?)))
        .collect();
    Ok(Assessed {
        params,
        chi2: posterior_chi2 - prior_chi2,
        prior_chi2,
        threshold: scored.as_ref().map(GoodnessOfFit::threshold),
        goodness,
        worst_channel,
        nuisances,
        theta,
        intervals,
        covariance,
        channels,
        would_pin,
        evaluations: ml.evaluations(),
    })
}

/// The estimated parameters whose interval says why the data leave them open.
fn open_parameters<'a>(
    space: &'a ParamSpace,
    intervals: &'a [Interval],
) -> impl Iterator<Item = ParamId> + 'a {
    space.dims.iter().map(|d| d.id).filter(|id| {
        intervals
            .iter()
            .any(|i| i.name == id.name() && i.why_not().is_some())
    })
}

/// The best start carried on to a tight convergence (simplex costs within 1e-6, restarts
/// until one gains less than 1e-6 relative). The starts themselves stop at the looser
/// [`MultiStartConfig::sd_tolerance`], enough to rank them; the one that is exported and
/// that intervals are measured from is finished to the tight tolerance alone (this keeps
/// the estimate where a run with the tight tolerance for every start ends, for a few
/// hundred evaluations instead of a third of all of them).
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
    let tight = NelderMead {
        settings: nm,
        max_iters: settings.max_iters(),
        stage_iters: settings.stage_iters(),
    };
    let search = tight.minimize(problem, theta, f0);
    if search.value <= f0 {
        search.x
    } else {
        theta.to_vec()
    }
}

/// The 95% intervals around the maximum-likelihood point `theta` (χ² `chi2_min`), widened
/// where the model misses the noise, each marked when another polished optimum of the
/// multi-start (`others`) fits as well with the parameter outside it; empty when not asked
/// for. With them the curvature covariance of θ that sized the profiles' steps (kept for
/// the fit file's joint uncertainty).
// The observer is the eighth: it only watches, and bundling it would hide that.
#[allow(clippy::too_many_arguments)]
fn intervals(
    engine: &Engine,
    ml: &Problem<'_>,
    theta: &[f64],
    chi2_min: f64,
    goodness: &GoodnessOfFit,
    others: &[Polished],
    setup: &FitSetup,
    observer: &dyn RunObserver,
) -> (Vec<Interval>, Option<DMatrix<f64>>) {
    if setup.uncertainty == UncertaintyMethod::None {
        return (Vec::new(), None);
    }
    let threshold = goodness.threshold();
    let scale2 = goodness.interval_scale.powi(2);
    let cov = uncertainty::curvature_covariance(ml, theta, uncertainty::CURVATURE_STEP, scale2);
    let mut out = match setup.uncertainty {
        UncertaintyMethod::Curvature => uncertainty::curvature_intervals(ml, theta, cov.as_ref()),
        _ => {
            observer.phase("profiles", 2 * theta.len());
            let sides = uncertainty::ProfileSides {
                max_iters: uncertainty::PROFILE_ITERS,
                on_side: &|done| observer.phase_step(done),
            };
            uncertainty::profile_intervals_observed(
                engine,
                ml,
                theta,
                chi2_min,
                threshold,
                cov.as_ref(),
                &sides,
            )
        }
    };
    let rivals = competitors(others, chi2_min, threshold);
    mark_competitors(&mut out, &setup.space, &rivals);
    (out, cov)
}

/// The experiment kind whose outputs move most (relative to typical sensor noise) when a
/// parameter changes by 20%, among the three reference experiments: where a parameter that
/// these data leave open would be pinned down.
pub(crate) fn most_sensitive_experiment(motor: &Motor, name: &str) -> Option<Kind> {
    use crate::data::synth::{free_speed, plan_experiments, SensorNoise, SynthPlan};
    use crate::sim::experiment::Experiment;
    use crate::units::Quantity;
    let plan = SynthPlan::for_motor(motor.params().v_disp());
    let noise = SensorNoise::typical_for(motor.params().v_disp());
    let value = motor.params().get(name)?;
    let changed = Motor::new(
        motor.params().with(name, value * 1.2).ok()?,
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

/// The fit file of an outcome (docs/formats.md, "Fit files", with identifiability and
/// statistics).
pub fn fit_file(dataset: &str, setup: &FitSetup, out: &FitOutcome, seed: u64) -> FitFile {
    let displacement_estimated = setup.space.estimates(ParamId::V_DISP);
    FitFile {
        dataset: dataset.to_string(),
        dataset_path: None,
        effects: setup.space.effects.clone(),
        params: out.params.clone(),
        estimated: setup.space.names(),
        ci95: out
            .intervals
            .iter()
            .filter(|iv| iv.identifiable())
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
        }),
        extra: Vec::new(),
        gear: None,
        covariance: out.log_covariance(&setup.space),
        conditions: Some(out.conditions),
        profiles: out
            .intervals
            .iter()
            .filter(|iv| !iv.path.is_empty())
            .map(|iv| ProfilePath {
                parameter: iv.name.clone(),
                value: iv.path.iter().map(|p| p.value).collect(),
                delta_chi2: iv.path.iter().map(|p| p.delta_chi2).collect(),
            })
            .collect(),
        verdicts: out
            .intervals
            .iter()
            .map(|iv| ParamVerdict {
                name: iv.name.clone(),
                bounds95: [iv.lo, iv.hi],
                identifiable: iv.identifiable(),
                why: iv.why_not(),
            })
            .collect(),
        statistics: out.goodness.as_ref().map(|g| FitStatistics {
            estimate: EstimateMethod::MaximumLikelihood,
            uncertainty: out.method,
            goodness: g.clone(),
            best_start_cost: out.best_start_cost,
            nuisances: out
                .nuisances
                .iter()
                .map(|(k, v)| (k.clone(), (*v).into()))
                .collect(),
            widened_noise: out
                .widening
                .iter()
                .map(|(k, v)| (k.clone(), (*v).into()))
                .collect(),
            likelihood_chi2: Some(out.chi2),
            prior: setup
                .space
                .dims
                .iter()
                .filter_map(|d| setup.space.prior.term(d.id))
                .map(|t| {
                    // Stated at the fit's displacement; where it was estimated, the median
                    // follows it (a page without one).
                    let size = setup.space.prior.size_of(&out.params);
                    PriorEntry {
                        parameter: t.name().to_string(),
                        median: t.median_at_size(size),
                        sd_ln: t.sd_ln,
                        size_exponent: displacement_estimated.then_some(t.size_exponent),
                    }
                })
                .collect(),
            prior_chi2: (!setup.space.prior.is_empty()).then_some(out.prior_chi2),
            on_bound: out
                .on_bound
                .iter()
                .map(|h| BoundEntry {
                    parameter: h.id.name().to_string(),
                    side: h.side.to_string(),
                    bound: h.bound,
                })
                .collect(),
            profile_threshold: out.threshold,
            linearised_at: out
                .linearised_at
                .iter()
                .map(|(k, v)| (k.clone(), (*v).into()))
                .collect(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::effects::EffectSet;

    /// A solver that never solves: every simulation fails, so every cost is the penalty.
    struct NeverSolves;

    impl crate::numerics::ode::StiffSolver for NeverSolves {
        fn solve(
            &self,
            _rhs: &crate::numerics::ode::Rhs<'_>,
            _t0: f64,
            _x0: crate::model::motor::State,
            _t_out: &[f64],
        ) -> Result<Vec<crate::model::motor::State>, crate::numerics::ode::SolveError> {
            Err(crate::numerics::ode::SolveError::StepSizeUnderflow { t: 0.0 })
        }
    }

    /// A best start whose cost was never evaluated is an error that says why, not an
    /// estimate; one whose cost was evaluated passes.
    #[test]
    fn a_best_start_without_a_finite_cost_is_an_error() {
        use crate::data::synth::{synthesize, SensorNoise, SynthPlan};
        let motor = Motor::default_motor();
        let plan = SynthPlan {
            ramp_duration_s: 20.0,
            throttle_duration_s: 20.0,
            sample_rate_hz: 5.0,
            ..SynthPlan::default()
        };
        let solver = DefaultSolver::default();
        let experiments = synthesize(&motor, &solver, &plan, &SensorNoise::none(), 1).unwrap();
        let ds = crate::data::dataset::Dataset::in_memory(experiments);
        let cost = CostModel::new(&ds, crate::objective::cost::CostOptions::default()).unwrap();
        let space =
            ParamSpace::new(&["c_in1"], MotorParams::default(), EffectSet::empty()).unwrap();
        let theta = vec![0.0];
        let broken = DataObjective {
            cost: &cost,
            solver: Box::new(NeverSolves),
        };
        match check_evaluated(&broken, &space, &theta) {
            Err(e @ EstimateError::NoFiniteCost { .. }) => {
                let text = e.to_string();
                assert!(
                    text.contains("no estimate") && text.contains("step size"),
                    "{text}"
                );
            }
            other => panic!("{other:?}"),
        }
        let working = DataObjective {
            cost: &cost,
            solver: Box::new(DefaultSolver::default()),
        };
        assert!(check_evaluated(&working, &space, &theta).is_ok());
    }

    #[test]
    fn log_covariance_follows_the_coordinate_transforms() {
        // c_in1 on a log scale, b_crit on a linear one: D_jj is the slope of ln v in θ.
        let space = ParamSpace::new(
            &["c_in1", "b_crit"],
            MotorParams::default(),
            EffectSet::empty(),
        )
        .unwrap();
        let theta = vec![0.7, -0.4];
        let cov = DMatrix::from_row_slice(2, 2, &[0.04, 0.01, 0.01, 0.09]);
        let lc = log_covariance(&space, &theta, &cov).unwrap();
        assert_eq!(lc.parameters, vec!["c_in1", "b_crit"]);
        let h = 1e-6;
        let slope: Vec<f64> = (0..2)
            .map(|j| {
                let d = &space.dims[j];
                (d.value(theta[j] + h).ln() - d.value(theta[j] - h).ln()) / (2.0 * h)
            })
            .collect();
        for i in 0..2 {
            for j in 0..2 {
                let want = slope[i] * cov[(i, j)] * slope[j];
                assert!((lc.matrix[i][j] - want).abs() < 1e-7 * want.abs(), "{i}{j}");
            }
        }
        assert!(log_covariance(&space, &theta[..1], &cov).is_none());
        // b_crit without variance (on a bound, left out by the curvature): c_in1 alone.
        let held = DMatrix::from_row_slice(2, 2, &[0.04, 0.0, 0.0, 0.0]);
        let lc = log_covariance(&space, &theta, &held).unwrap();
        assert_eq!(lc.parameters, vec!["c_in1"]);
        let want = slope[0] * 0.04 * slope[0];
        assert!(
            (lc.matrix[0][0] - want).abs() < 1e-7 * want,
            "{:?}",
            lc.matrix
        );
    }
}
