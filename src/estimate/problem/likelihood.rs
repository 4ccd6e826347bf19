//! The likelihood of the recorded rows ([`crate::objective::likelihood`]) as an estimation
//! objective: what the diagnosis fits, and what a fit's intervals are measured on.

use crate::estimate::problem::objective::{Evaluation, Objective};
use crate::model::motor::Motor;
use crate::numerics::DefaultSolver;
use crate::objective::cost::{CostModel, FAILURE_PENALTY};
use crate::objective::likelihood::Target;

/// The likelihood of eq. \[1\] as an estimation objective: cost = χ²/n (≈ 1 for a correct
/// model), failures give the cost module's penalty.
pub struct Likelihood<'a> {
    /// The cost model, which simulates the compared rows.
    pub cost: &'a CostModel,
    /// The recorded data and noise at those rows.
    pub target: &'a Target,
    /// The ODE solver.
    pub solver: DefaultSolver,
}

impl Objective for Likelihood<'_> {
    fn residuals(&self, motor: &Motor) -> Option<Vec<f64>> {
        self.target.residuals(self.cost, motor, &self.solver)
    }

    fn evaluate(&self, motor: &Motor) -> Evaluation {
        let n = self.target.n_points();
        match self.target.chi2(self.cost, motor, &self.solver) {
            Some(chi2) => Evaluation {
                cost: chi2 / n.max(1) as f64,
                chi2,
                n_points: n,
                failed: false,
            },
            None => Evaluation {
                cost: FAILURE_PENALTY,
                chi2: FAILURE_PENALTY,
                n_points: n,
                failed: true,
            },
        }
    }
}
