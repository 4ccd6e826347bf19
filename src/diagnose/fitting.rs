//! The fits a diagnosis runs: the base model and every candidate extension, warm-started
//! from a previous optimum, several at once.
//!
//! Every fit minimises the likelihood of the recorded data ([`super::target`]). Catalog
//! models go through the project's multi-start estimator ([`crate::estimate::multistart`])
//! with the warm points as `given_starts`. Models with discovered terms ([`ExtraTerm`]) are
//! not expressible as a [`ParamSpace`] (their coefficients are not named parameters), so
//! they are fitted here by restarted Nelder–Mead over the space's θ plus one coordinate per
//! term, the coefficient in units of its starting value.

use super::target::{Likelihood, Target};
use crate::estimate::multistart::{self, MultiStartConfig, Silent};
use crate::estimate::objective::Objective;
use crate::estimate::space::ParamSpace;
use crate::model::effects::EffectSet;
use crate::model::motor::{ExtraTerm, Motor};
use crate::model::params::MotorParams;
use crate::numerics::ode::DiffsolBdf;
use crate::objective::cost::CostModel;
use argmin::core::{CostFunction, Error, Executor, State};
use argmin::solver::neldermead::NelderMead;
use rayon::prelude::*;
use std::time::Instant;

/// A fitted model.
#[derive(Debug, Clone)]
pub struct Fitted {
    pub effects: EffectSet,
    /// Discovered terms with their fitted coefficients.
    pub extra: Vec<ExtraTerm>,
    pub params: MotorParams,
    /// The project's fitting cost J (`cost::CostModel::evaluate`) at these parameters.
    pub cost: f64,
    /// χ² against the recorded data ([`super::target`], eq. 1), which the fit minimises.
    pub chi2: f64,
    pub n_points: usize,
    /// Number of estimated parameters (coefficients of discovered terms included).
    pub k: usize,
    pub evaluations: u64,
    pub wall_s: f64,
}

impl Fitted {
    pub fn motor(&self) -> Motor {
        Motor::new(self.params.clone(), self.effects.clone()).with_extra(&self.extra)
    }

    /// BIC = χ² + k·ln n (χ² is −2 ln L up to a constant for Gaussian noise of known σ).
    pub fn bic(&self) -> f64 {
        self.chi2 + self.k as f64 * (self.n_points.max(1) as f64).ln()
    }
}

/// One fit to run.
#[derive(Debug, Clone)]
pub struct FitJob {
    pub label: String,
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
    pub max_iters: u64,
    pub seed: u64,
}

/// J of the project's cost at a motor.
fn project_cost(cost: &CostModel, motor: &Motor, solver: &DiffsolBdf) -> f64 {
    cost.evaluate(motor, solver).total
}

/// Runs one fit of `target` (built on `cost`) with `threads` worker threads (None: one per
/// core).
pub fn run_job(
    cost: &CostModel,
    target: &Target,
    job: &FitJob,
    threads: Option<usize>,
) -> Result<Fitted, String> {
    let t0 = Instant::now();
    let solver = DiffsolBdf::default();
    let objective = Likelihood {
        cost,
        target,
        solver: DiffsolBdf::default(),
    };
    let names: Vec<&str> = job.names.iter().map(String::as_str).collect();
    let first = job
        .starts
        .first()
        .ok_or_else(|| format!("{}: no start point", job.label))?;
    let space =
        ParamSpace::new(&names, first.clone(), job.effects.clone()).map_err(|e| e.to_string())?;
    let finish = |motor: Motor, k: usize, evaluations: u64| -> Result<Fitted, String> {
        let e = objective.evaluate(&motor);
        Ok(Fitted {
            effects: job.effects.clone(),
            extra: motor.extra.clone(),
            params: motor.params.clone(),
            cost: project_cost(cost, &motor, &solver),
            chi2: e.chi2,
            n_points: e.n_points,
            k,
            evaluations: evaluations + 2,
            wall_s: t0.elapsed().as_secs_f64(),
        })
    };
    if job.extra.is_empty() {
        let cfg = MultiStartConfig {
            starts: job.starts.len() + job.lhs,
            seed: job.seed,
            threads,
            max_iters: job.max_iters,
            given_starts: job.starts.iter().map(|p| space.theta(p)).collect(),
            ..MultiStartConfig::default()
        };
        let run = multistart::run(&objective, &space, &cfg, &Silent, None, false)
            .map_err(|e| format!("{}: {e}", job.label))?;
        let best = run.best();
        let params = space
            .params(&best.theta)
            .map_err(|e| format!("{}: best parameters: {e}", job.label))?;
        return finish(
            Motor::new(params, job.effects.clone()),
            space.len(),
            run.evaluations,
        );
    }
    // Discovered terms: θ of the space, then each coefficient over its starting value.
    let scales: Vec<f64> = job.extra.iter().map(|t| t.coefficient).collect();
    if scales.iter().any(|s| *s == 0.0 || !s.is_finite()) {
        return Err(format!(
            "{}: a discovered term needs a non-zero start",
            job.label
        ));
    }
    let build = |x: &[f64]| -> Option<Motor> {
        let p = space.params(&x[..space.len()]).ok()?;
        let terms: Vec<ExtraTerm> = job
            .extra
            .iter()
            .zip(&x[space.len()..])
            .zip(&scales)
            .map(|((t, v), s)| ExtraTerm {
                coefficient: v * s,
                ..*t
            })
            .collect();
        Some(Motor::new(p, job.effects.clone()).with_extra(&terms))
    };
    let f = |x: &[f64]| -> f64 {
        match build(x) {
            Some(m) => objective.evaluate(&m).cost,
            None => crate::estimate::objective::INVALID_PARAMS_COST,
        }
    };
    let mut best: Option<(Vec<f64>, f64)> = None;
    let mut evaluations = 0;
    for p in &job.starts {
        let mut x0 = space.theta(p);
        x0.extend(std::iter::repeat_n(1.0, scales.len()));
        let (x, fx, e) = nelder_mead(&f, &x0, 0.3, job.max_iters);
        evaluations += e;
        if best.as_ref().is_none_or(|(_, b)| fx < *b) {
            best = Some((x, fx));
        }
    }
    let (x, _) = best.expect("at least one start");
    let motor = build(&x).ok_or_else(|| format!("{}: best point is not valid", job.label))?;
    finish(motor, x.len(), evaluations)
}

/// Runs several fits at once, results in job order. Each fit's starts may also use the
/// pool's threads (so the last, longest fits do not leave a core idle); results do not
/// depend on the number of threads.
pub fn run_jobs(
    cost: &CostModel,
    target: &Target,
    jobs: &[FitJob],
    threads: Option<usize>,
) -> Vec<Result<Fitted, String>> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(k) = threads {
        builder = builder.num_threads(k);
    }
    match builder.build() {
        Ok(pool) => pool.install(|| {
            jobs.par_iter()
                .map(|j| run_job(cost, target, j, threads))
                .collect()
        }),
        Err(e) => jobs
            .iter()
            .map(|_| Err(format!("thread pool: {e}")))
            .collect(),
    }
}

struct Closure<'a>(
    &'a (dyn Fn(&[f64]) -> f64 + Sync),
    &'a std::sync::atomic::AtomicU64,
);

impl CostFunction for Closure<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, p: &Self::Param) -> Result<f64, Error> {
        self.1.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Ok((self.0)(p))
    }
}

/// Restarted Nelder–Mead (argmin) from x0 with an axis simplex of edge `step`, with the
/// dimension-adaptive coefficients of Gao and Han (2012); a fresh simplex of half the edge
/// is started at the best point until one gains nothing (relative 1e-7) or the iteration
/// budget is spent. Returns (x, f(x), evaluations).
pub fn nelder_mead(
    f: &(dyn Fn(&[f64]) -> f64 + Sync),
    x0: &[f64],
    step: f64,
    max_iters: u64,
) -> (Vec<f64>, f64, u64) {
    let n = x0.len().max(2) as f64;
    let mut x = x0.to_vec();
    let mut fx = f(&x);
    let counter = std::sync::atomic::AtomicU64::new(1);
    let mut used = 0;
    let mut edge = step;
    for _ in 0..12 {
        if used >= max_iters {
            break;
        }
        let mut simplex = vec![x.clone()];
        for i in 0..x.len() {
            let mut v = x.clone();
            v[i] += if x[i] > 0.0 { -edge } else { edge };
            simplex.push(v);
        }
        let solver = NelderMead::new(simplex)
            .with_sd_tolerance(1e-7)
            .and_then(|s| s.with_gamma(1.0 + 2.0 / n))
            .and_then(|s| s.with_sigma(1.0 - 1.0 / n))
            .expect("valid Nelder-Mead coefficients");
        let iters = (max_iters - used).min(max_iters.max(400) / 2);
        let Ok(res) = Executor::new(Closure(f, &counter), solver)
            .configure(|s| s.max_iters(iters))
            .ctrlc(false)
            .run()
        else {
            break;
        };
        let state = res.state();
        used += state.get_iter();
        let before = fx;
        if let Some(p) = state.get_best_param() {
            if state.get_best_cost() < fx {
                x = p.clone();
                fx = state.get_best_cost();
            }
        }
        if before - fx <= 1e-7 * (1.0 + fx.abs()) {
            break;
        }
        edge = (edge * 0.5).max(0.02);
    }
    (x, fx, counter.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nelder_mead_finds_a_quadratic_minimum() {
        let f =
            |x: &[f64]| (x[0] - 1.0).powi(2) + 10.0 * (x[1] + 2.0).powi(2) + (x[2] * 0.5).powi(2);
        let (x, fx, e) = nelder_mead(&f, &[0.0, 0.0, 1.0], 0.5, 3000);
        assert!(fx < 1e-6, "{fx} at {x:?}");
        assert!(
            (x[0] - 1.0).abs() < 1e-2 && (x[1] + 2.0).abs() < 1e-2,
            "{x:?}"
        );
        assert!(e > 10);
    }
}
