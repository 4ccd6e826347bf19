//! The objective as argmin sees it: optimizer coordinates θ → parameters → motor → cost.
//! Kept apart from the model (which knows nothing of optimizers) and from the solver (which
//! knows nothing of motors), as argmin keeps `problem` apart from `solver`.

use super::space::ParamSpace;
use crate::model::motor::Motor;
use argmin::core::{CostFunction, Error};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Cost returned for parameters that break a model constraint. Large, finite, and constant:
/// Nelder–Mead only compares costs, so a plateau is enough to turn it back.
pub const INVALID_PARAMS_COST: f64 = 1e12;

/// What an objective says about one motor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Evaluation {
    /// The fitting cost (finite, ≥ 0).
    pub cost: f64,
    /// χ² = Σ over data points of (simulation − reference)²/σ², unweighted (finite): the
    /// −2·log-likelihood up to a constant, used for confidence intervals and BIC.
    pub chi2: f64,
    /// Number of data points behind χ².
    pub n_points: usize,
    /// The simulation failed and the cost is a penalty.
    pub failed: bool,
}

/// Anything that scores a motor against data (the cost of the data module, or a test model
/// with a known answer).
pub trait Objective: Sync {
    fn evaluate(&self, motor: &Motor) -> Evaluation;
}

/// argmin's view of an objective over a parameter space.
pub struct Problem<'a> {
    pub objective: &'a dyn Objective,
    pub space: &'a ParamSpace,
    evaluations: AtomicU64,
    /// Every cost seen, in order, when a trace is kept.
    trace: Option<Mutex<Vec<f64>>>,
}

impl<'a> Problem<'a> {
    pub fn new(objective: &'a dyn Objective, space: &'a ParamSpace, keep_trace: bool) -> Self {
        Self {
            objective,
            space,
            evaluations: AtomicU64::new(0),
            trace: keep_trace.then(|| Mutex::new(Vec::new())),
        }
    }

    /// Evaluates the objective at θ (never NaN, never an error).
    pub fn evaluate(&self, theta: &[f64]) -> Evaluation {
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        let e = match self.space.params(theta) {
            Ok(p) => self
                .objective
                .evaluate(&Motor::new(p, self.space.effects.clone())),
            Err(_) => Evaluation {
                cost: INVALID_PARAMS_COST,
                chi2: INVALID_PARAMS_COST,
                n_points: 0,
                failed: true,
            },
        };
        let e = Evaluation {
            cost: finite_or_penalty(e.cost),
            chi2: finite_or_penalty(e.chi2),
            ..e
        };
        if let Some(t) = &self.trace {
            t.lock().expect("trace lock").push(e.cost);
        }
        e
    }

    pub fn evaluations(&self) -> u64 {
        self.evaluations.load(Ordering::Relaxed)
    }

    pub fn take_trace(&self) -> Option<Vec<f64>> {
        self.trace
            .as_ref()
            .map(|t| std::mem::take(&mut *t.lock().expect("trace lock")))
    }
}

fn finite_or_penalty(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        INVALID_PARAMS_COST
    }
}

impl CostFunction for Problem<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, theta: &Self::Param) -> Result<f64, Error> {
        Ok(self.evaluate(theta).cost)
    }
}

/// A problem over a sub-space: some coordinates held at given values (profile likelihood).
pub struct Profiled<'a> {
    pub inner: &'a Problem<'a>,
    /// Full θ; the free coordinates are overwritten by the optimizer's.
    pub template: Vec<f64>,
    pub free: Vec<usize>,
    /// Optimize χ² instead of the weighted cost.
    pub use_chi2: bool,
}

impl Profiled<'_> {
    pub fn full(&self, free_theta: &[f64]) -> Vec<f64> {
        let mut t = self.template.clone();
        for (i, v) in self.free.iter().zip(free_theta) {
            t[*i] = *v;
        }
        t
    }
}

impl CostFunction for Profiled<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, free_theta: &Self::Param) -> Result<f64, Error> {
        let e = self.inner.evaluate(&self.full(free_theta));
        Ok(if self.use_chi2 { e.chi2 } else { e.cost })
    }
}
