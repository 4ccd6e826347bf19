//! The objective as argmin sees it: search coordinates x → motor → cost, behind argmin's
//! [`CostFunction`] over a plain parameter vector. Kept apart from the model (which knows
//! nothing of optimizers) and from the solver (which knows nothing of motors), as argmin
//! keeps `problem` apart from `solver`.
//!
//! What the coordinates mean is a [`Coordinates`]: a [`ParamSpace`] (θ of named parameters,
//! the fit of a dataset), or a space extended by coefficients of discovered terms (the
//! refits of a diagnosis). Both give the same [`Problem`], so both use the same optimizer.

use crate::estimate::problem::space::ParamSpace;
use crate::model::motor::Motor;
use argmin::core::{CostFunction, Error};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;

/// Cost returned for parameters that break a model constraint. Large, finite, and constant:
/// Nelder–Mead only compares costs, so a plateau is enough to turn it back.
const INVALID_PARAMS_COST: f64 = 1e12;

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
    /// The cost and χ² of one motor.
    fn evaluate(&self, motor: &Motor) -> Evaluation;

    /// Residuals whose squares sum to χ², where the objective is a least-squares one
    /// (`None`: it is not, or the simulation failed); enables Levenberg–Marquardt.
    fn residuals(&self, motor: &Motor) -> Option<Vec<f64>> {
        let _ = motor;
        None
    }

    /// Residuals whose squares sum to the fitting cost (not χ²: each channel's rows scaled
    /// by √(w/N) of its weight and row count, docs/model.md, "Cost J"), where the objective
    /// can give them (`None`: it cannot, or the simulation failed); lets a multi-start hand
    /// a start over to Levenberg–Marquardt ([`crate::estimate::optimize::multistart`]). One residual per
    /// compared row, so the prior's share of the cost (χ²_prior/n) is its residuals
    /// scaled by 1/√n with n their count.
    fn cost_residuals(&self, motor: &Motor) -> Option<Vec<f64>> {
        let _ = motor;
        None
    }

    /// Whether [`Objective::cost_residuals`] gives residuals (where the simulation runs).
    fn has_cost_residuals(&self) -> bool {
        false
    }
}

/// What a point of the search coordinates is: a motor, or `None` where the point breaks a
/// model constraint (penalised with `INVALID_PARAMS_COST`).
pub trait Coordinates: Sync {
    /// The motor at `x`.
    fn motor(&self, x: &[f64]) -> Option<Motor>;

    /// The prior's residuals of the motor at `x` (`estimate::problem::prior`): their squares are
    /// added to χ² (and divided by the number of points, to the cost). None by default.
    fn prior_residuals(&self, motor: &Motor) -> Vec<f64> {
        let _ = motor;
        Vec::new()
    }

    /// What coordinate `j` is called where its interval is stated (a parameter's id).
    fn coordinate_name(&self, j: usize) -> String;

    /// The value, SI, that coordinate `j` stands for at `x_j` (what its interval is stated
    /// in).
    fn coordinate_value(&self, j: usize, x_j: f64) -> f64;
}

impl Coordinates for ParamSpace {
    fn motor(&self, theta: &[f64]) -> Option<Motor> {
        self.params(theta)
            .ok()
            .map(|p| Motor::new(p, self.effects.clone()))
    }

    fn prior_residuals(&self, motor: &Motor) -> Vec<f64> {
        if self.prior.is_empty() {
            return Vec::new();
        }
        self.prior.residuals(&self.dims, motor.params())
    }

    fn coordinate_name(&self, j: usize) -> String {
        self.dims[j].name().to_string()
    }

    fn coordinate_value(&self, j: usize, x_j: f64) -> f64 {
        self.dims[j].value(x_j)
    }
}

/// argmin's view of an objective over search coordinates (by default a parameter space).
pub struct Problem<'a, C: Coordinates + ?Sized = ParamSpace> {
    /// Scores motors.
    pub objective: &'a dyn Objective,
    /// Maps the search coordinates to motors.
    pub space: &'a C,
    evaluations: AtomicU64,
    /// Every cost seen, in order, when a trace is kept.
    trace: Option<Mutex<Vec<f64>>>,
}

impl<'a, C: Coordinates + ?Sized> Problem<'a, C> {
    /// A problem that counts its evaluations and, with `keep_trace`, records every cost.
    pub fn new(objective: &'a dyn Objective, space: &'a C, keep_trace: bool) -> Self {
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
        let e = match self.space.motor(theta) {
            Some(m) => {
                let e = self.objective.evaluate(&m);
                let prior: f64 = self.space.prior_residuals(&m).iter().map(|r| r * r).sum();
                if e.failed || prior == 0.0 {
                    e
                } else {
                    // The posterior: χ² + χ²_prior; the cost (≈ χ²/n) gains χ²_prior/n.
                    Evaluation {
                        cost: e.cost + prior / e.n_points.max(1) as f64,
                        chi2: e.chi2 + prior,
                        ..e
                    }
                }
            }
            None => Evaluation {
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

    /// The objective's residual vector at θ (counted as an evaluation); `None` where θ
    /// breaks a model constraint, the simulation fails, or the objective has none.
    pub fn residuals(&self, theta: &[f64]) -> Option<Vec<f64>> {
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        let motor = self.space.motor(theta)?;
        let mut r = self.objective.residuals(&motor)?;
        r.extend(self.space.prior_residuals(&motor));
        Some(r)
    }

    /// The objective's cost residuals at θ ([`Objective::cost_residuals`], counted as an
    /// evaluation), with the prior's residuals scaled by 1/√n so that the squares sum to
    /// [`Problem::evaluate`]'s cost; `None` where θ breaks a model constraint, the
    /// simulation fails, a residual is not finite, or the objective has none.
    pub fn cost_residuals(&self, theta: &[f64]) -> Option<Vec<f64>> {
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        let motor = self.space.motor(theta)?;
        let mut r = self.objective.cost_residuals(&motor)?;
        let scale = 1.0 / (r.len().max(1) as f64).sqrt();
        r.extend(
            self.space
                .prior_residuals(&motor)
                .into_iter()
                .map(|v| v * scale),
        );
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    /// Evaluations so far.
    pub fn evaluations(&self) -> u64 {
        self.evaluations.load(Ordering::Relaxed)
    }

    /// The costs recorded since the last call (`None` without a trace).
    pub(crate) fn take_trace(&self) -> Option<Vec<f64>> {
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

impl<C: Coordinates + ?Sized> CostFunction for Problem<'_, C> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, theta: &Self::Param) -> Result<f64, Error> {
        Ok(self.evaluate(theta).cost)
    }
}

/// A problem over a sub-space: some coordinates held at given values (profile likelihood).
pub(crate) struct Profiled<'a, C: Coordinates + ?Sized = ParamSpace> {
    /// The problem over every coordinate.
    pub inner: &'a Problem<'a, C>,
    /// Full θ; the free coordinates are overwritten by the optimizer's.
    pub(crate) template: Vec<f64>,
    /// Indices of the free coordinates.
    pub free: Vec<usize>,
    /// Optimize χ² instead of the weighted cost.
    pub(crate) use_chi2: bool,
}

impl<C: Coordinates + ?Sized> Profiled<'_, C> {
    /// The full θ of the free coordinates' values.
    pub fn full(&self, free_theta: &[f64]) -> Vec<f64> {
        let mut t = self.template.clone();
        for (i, v) in self.free.iter().zip(free_theta) {
            t[*i] = *v;
        }
        t
    }
}

impl<C: Coordinates + ?Sized> CostFunction for Profiled<'_, C> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, free_theta: &Self::Param) -> Result<f64, Error> {
        let e = self.inner.evaluate(&self.full(free_theta));
        Ok(if self.use_chi2 { e.chi2 } else { e.cost })
    }
}
