//! The fits a diagnosis runs: the base model and every candidate extension, warm-started
//! from a previous optimum, several at once.
//!
//! Every fit minimises the likelihood of the recorded data ([`crate::objective::likelihood`]). Catalog
//! models go through the project's multi-start estimator ([`crate::estimate::optimize::multistart`])
//! with the warm points as `given_starts`. Models with discovered terms ([`ExtraTerm`]) are
//! not expressible as a [`ParamSpace`] (their coefficients are not named parameters), so
//! they are fitted here by restarted Nelder–Mead over the space's θ plus one coordinate per
//! term, the coefficient in units of its starting value.

use crate::estimate::engine::Engine;
use crate::estimate::error::EstimateError;
use crate::estimate::optimize::local::polish_residuals;
use crate::estimate::optimize::local::{LocalOptimizer, NelderMead};
use crate::estimate::optimize::multistart::{self, Silent};
use crate::estimate::optimize::nelder_mead::{Layout, NelderMeadSettings, Restart};
use crate::estimate::optimize::settings::MultiStartConfig;
use crate::estimate::problem::likelihood::Likelihood;
use crate::estimate::problem::objective::Evaluation;
use crate::estimate::problem::objective::{Coordinates, Objective, Problem};
use crate::estimate::problem::space::{ParamSpace, SpaceError};
use crate::model::effects::EffectSet;
use crate::model::motor::{ExtraTerm, Motor};
use crate::model::params::MotorParams;
use crate::numerics::DefaultSolver;
use crate::objective::cost::CostModel;
use crate::objective::likelihood::Target;
use std::time::Instant;

/// Why a fit could not run (every message starts with the fit's label).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RefitError {
    /// The job has no start point.
    #[error("{0}: no start point")]
    NoStart(String),
    /// The estimated names do not make a parameter space.
    #[error("{0}")]
    Space(#[from] SpaceError),
    /// The multi-start failed.
    #[error("{label}: {source}")]
    Run {
        /// The fit.
        label: String,
        /// What failed.
        source: EstimateError,
    },
    /// A discovered term starts at zero (its coefficient is searched relative to its start).
    #[error("{0}: a discovered term needs a non-zero start")]
    ZeroTerm(String),
    /// The best point breaks a model constraint.
    #[error("{0}: best point is not valid")]
    InvalidBest(String),
}

/// The diagnosis still reports errors as text.
/// A fitted model.
#[derive(Debug, Clone)]
pub struct Fitted {
    /// Effects switched on.
    pub effects: EffectSet,
    /// Discovered terms with their fitted coefficients.
    pub extra: Vec<ExtraTerm>,
    /// Fitted parameters.
    pub params: MotorParams,
    /// The project's fitting cost J (`cost::CostModel::evaluate`) at these parameters.
    pub cost: f64,
    /// χ² against the recorded data (`objective::likelihood`, eq. 1), which the fit minimises.
    pub chi2: f64,
    /// Data points behind χ².
    pub n_points: usize,
    /// Number of estimated parameters (coefficients of discovered terms included).
    pub k: usize,
    /// Cost evaluations.
    pub evaluations: u64,
    /// Wall time, s.
    pub wall_s: f64,
}

impl Fitted {
    /// The fitted motor, discovered terms included.
    pub fn motor(&self) -> Motor {
        Motor::new(self.params.clone(), self.effects.clone()).with_extra(&self.extra)
    }

    /// BIC = χ² + k·ln n (χ² is −2 ln L up to a constant for Gaussian noise of known σ).
    pub(crate) fn bic(&self) -> f64 {
        self.chi2 + self.k as f64 * (self.n_points.max(1) as f64).ln()
    }
}

/// One fit to run.
#[derive(Debug, Clone)]
pub struct FitJob {
    /// Name in messages.
    pub label: String,
    /// Effects switched on.
    pub effects: EffectSet,
    /// Discovered terms; their coefficients are the starting values (must be non-zero).
    pub extra: Vec<ExtraTerm>,
    /// Estimated parameter names (base and effect parameters).
    pub names: Vec<String>,
    /// Start points (every estimated parameter taken from each); the first also gives the
    /// values of everything fixed.
    pub starts: Vec<MotorParams>,
    /// Latin-hypercube starts on top of the given ones (catalog models only).
    pub lhs: usize,
    /// Iteration budget of each start.
    pub max_iters: u64,
    /// Seed of the Latin hypercube.
    pub seed: u64,
}

/// The search coordinates of a model with discovered terms: θ of the space, then each
/// term's coefficient over its starting value (so every coordinate starts near 1).
pub(super) struct TermSpace<'a> {
    pub(super) space: &'a ParamSpace,
    pub(super) terms: &'a [ExtraTerm],
}

impl Coordinates for TermSpace<'_> {
    fn motor(&self, x: &[f64]) -> Option<Motor> {
        let p = self.space.params(&x[..self.space.len()]).ok()?;
        let terms: Vec<ExtraTerm> = self
            .terms
            .iter()
            .zip(&x[self.space.len()..])
            .map(|(t, v)| ExtraTerm {
                coefficient: v * t.coefficient,
                ..*t
            })
            .collect();
        Some(Motor::new(p, self.space.effects.clone()).with_extra(&terms))
    }

    /// A term's coordinate is called "coefficient" (which term: by its place after θ).
    fn coordinate_name(&self, j: usize) -> String {
        match j.checked_sub(self.space.len()) {
            None => self.space.coordinate_name(j),
            Some(_) => "coefficient".into(),
        }
    }

    /// A term's coordinate times its starting coefficient.
    fn coordinate_value(&self, j: usize, x_j: f64) -> f64 {
        match j.checked_sub(self.space.len()) {
            None => self.space.coordinate_value(j, x_j),
            Some(i) => x_j * self.terms[i].coefficient,
        }
    }
}

/// The refit of a model with discovered terms: restarted Nelder–Mead from an inward axis
/// simplex of edge 0.3 with Gao–Han coefficients, converged at a spread of 1e-7; a fresh
/// simplex of half the edge (at least 0.02) after every stage until one gains at most 1e-7
/// relative, at most 12 stages.
const REFIT: NelderMeadSettings = NelderMeadSettings {
    sd_tolerance: 1e-7,
    step: 0.3,
    layout: Layout::Inward,
    adaptive: true,
    restart: Restart::Halving {
        rounds: 12,
        min_edge: 0.02,
        gain: 1e-7,
    },
};

/// The result of a search: the motor at the best point, the number of coordinates and the
/// evaluations used.
struct Found {
    motor: Motor,
    k: usize,
    evaluations: u64,
}

/// The likelihood of a diagnosis fit, with its cost residuals: χ²'s residuals over √n (their
/// squares sum to the cost χ²/n). They let every start hand over to Levenberg–Marquardt
/// after one round of Nelder–Mead (`MultiStartConfig::handoff_after_rounds`, the project's
/// fit does the same with J): Nelder–Mead brings a start into its basin, the Gauss–Newton
/// steps cross the curved valley to its floor in a few iterations, where Nelder–Mead
/// crawled for hundreds (docs/diagnosis.md, "Fits").
pub(super) struct HandOver<'a>(pub(super) Likelihood<'a>);

impl Objective for HandOver<'_> {
    fn evaluate(&self, motor: &Motor) -> Evaluation {
        self.0.evaluate(motor)
    }

    fn residuals(&self, motor: &Motor) -> Option<Vec<f64>> {
        self.0.residuals(motor)
    }

    fn cost_residuals(&self, motor: &Motor) -> Option<Vec<f64>> {
        let scale = 1.0 / (self.0.target.n_points().max(1) as f64).sqrt();
        let r = self.0.residuals(motor)?;
        Some(r.into_iter().map(|v| v * scale).collect())
    }

    fn has_cost_residuals(&self) -> bool {
        true
    }
}

/// Runs one fit of `target` (built on `cost`) on the engine's threads.
pub fn run_job(
    cost: &CostModel,
    target: &Target,
    job: &FitJob,
    engine: &Engine,
) -> Result<Fitted, RefitError> {
    let t0 = Instant::now();
    let solver = DefaultSolver::default();
    let objective = HandOver(Likelihood {
        cost,
        target,
        solver: DefaultSolver::default(),
    });
    let names: Vec<&str> = job.names.iter().map(String::as_str).collect();
    let first = job
        .starts
        .first()
        .ok_or_else(|| RefitError::NoStart(job.label.clone()))?;
    let space = ParamSpace::new(&names, first.clone(), job.effects.clone())?;
    let found = if job.extra.is_empty() {
        catalog_fit(engine, &objective, &space, job)?
    } else {
        term_fit(&objective, &space, job)?
    };
    let e = objective.evaluate(&found.motor);
    Ok(Fitted {
        effects: job.effects.clone(),
        extra: found.motor.extra.clone(),
        cost: cost.evaluate(&found.motor, &solver).total,
        params: found.motor.params().clone(),
        chi2: e.chi2,
        n_points: e.n_points,
        k: found.k,
        evaluations: found.evaluations + 2,
        wall_s: t0.elapsed().as_secs_f64(),
    })
}

/// A catalog model: the project's multi-start with the job's points as given starts.
fn catalog_fit(
    engine: &Engine,
    objective: &HandOver<'_>,
    space: &ParamSpace,
    job: &FitJob,
) -> Result<Found, RefitError> {
    let run_error = |source| RefitError::Run {
        label: job.label.clone(),
        source,
    };
    let cfg = MultiStartConfig {
        starts: job.starts.len() + job.lhs,
        seed: job.seed,
        max_iters: job.max_iters,
        given_starts: job.starts.iter().map(|p| space.theta(p)).collect(),
        ..MultiStartConfig::default()
    };
    let settings = cfg.check().map_err(run_error)?;
    let run = multistart::run(engine, objective, space, &settings, &Silent, None, false)
        .map_err(run_error)?;
    let problem = Problem::new(objective, space, false);
    // Every start polished: the best Nelder–Mead end is not always the best after the
    // polish (a start stalled on a curved valley's floor may lie below the others).
    let theta = run
        .results
        .iter()
        .map(|r| lm_polish(&problem, r.theta.clone()))
        .map(|t| (problem.evaluate(&t).chi2, t))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map_or_else(|| run.best().theta.clone(), |(_, t)| t);
    let params = space
        .params(&theta)
        .map_err(|e| run_error(EstimateError::BestParameters(e)))?;
    Ok(Found {
        motor: Motor::new(params, job.effects.clone()),
        k: space.len(),
        evaluations: run.evaluations + problem.evaluations(),
    })
}

/// A model with discovered terms ([`TermSpace`]): [`REFIT`] from every start point in turn,
/// keeping the best. No hand-over to Levenberg–Marquardt here (see [`HandOver`]).
fn term_fit(
    objective: &HandOver<'_>,
    space: &ParamSpace,
    job: &FitJob,
) -> Result<Found, RefitError> {
    if job
        .extra
        .iter()
        .any(|t| t.coefficient == 0.0 || !t.coefficient.is_finite())
    {
        return Err(RefitError::ZeroTerm(job.label.clone()));
    }
    let coordinates = TermSpace {
        space,
        terms: &job.extra,
    };
    let problem = Problem::new(objective, &coordinates, false);
    let refit = NelderMead {
        settings: REFIT,
        max_iters: job.max_iters,
        stage_iters: job.max_iters.max(400) / 2,
    };
    let mut best: Option<(Vec<f64>, f64)> = None;
    for p in &job.starts {
        let mut x0 = space.theta(p);
        x0.extend(std::iter::repeat_n(1.0, job.extra.len()));
        let f0 = problem.evaluate(&x0).cost;
        let search = refit.minimize(&problem, &x0, f0);
        if best.as_ref().is_none_or(|(_, b)| search.value < *b) {
            best = Some((search.x, search.value));
        }
    }
    let (x, _) = best.ok_or_else(|| RefitError::NoStart(job.label.clone()))?;
    let x = lm_polish(&problem, x);
    let motor = coordinates
        .motor(&x)
        .ok_or_else(|| RefitError::InvalidBest(job.label.clone()))?;
    Ok(Found {
        k: x.len(),
        motor,
        evaluations: problem.evaluations(),
    })
}

/// The Levenberg–Marquardt polish of a search's best point `x` ([`polish_residuals`] on
/// the likelihood's residuals): Nelder–Mead stalls in narrow curved valleys (T_s against ω_s
/// of breakaway friction), a Gauss–Newton step follows them. The polished point is kept only
/// if its χ² is lower.
fn lm_polish<C: Coordinates + ?Sized>(problem: &Problem<'_, C>, x: Vec<f64>) -> Vec<f64> {
    polish_residuals(problem, &x).map_or(x, |(polished, _)| polished)
}

/// Runs several fits at once on the engine, results in job order. Each fit's starts use the
/// same threads (so the last, longest fits do not leave a core idle); results do not
/// depend on the number of threads.
pub(crate) fn run_jobs(
    cost: &CostModel,
    target: &Target,
    jobs: &[FitJob],
    engine: &Engine,
) -> Vec<Result<Fitted, RefitError>> {
    engine.map(jobs, |j| run_job(cost, target, j, engine))
}
