//! A solver wrapper that counts right-hand-side evaluations (shared by the examples).

use std::sync::atomic::{AtomicU64, Ordering};
use vanefit::numerics::ode::{Jacobian, Rhs, SolveError, State, StiffSolver};

/// Right-hand-side evaluations since the last [`reset`].
pub static CALLS: AtomicU64 = AtomicU64::new(0);

/// Sets the count to zero.
pub fn reset() {
    CALLS.store(0, Ordering::Relaxed);
}

/// The count so far.
pub fn calls() -> u64 {
    CALLS.load(Ordering::Relaxed)
}

/// Wraps a solver and counts every call of the right-hand side it makes (the model's own
/// Jacobian, where the solver uses one, is passed through and not counted).
pub struct Counting<'a>(pub &'a dyn StiffSolver);

impl StiffSolver for Counting<'_> {
    fn solve(
        &self,
        rhs: &Rhs<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        let f = |t: f64, x: &State| {
            CALLS.fetch_add(1, Ordering::Relaxed);
            rhs(t, x)
        };
        self.0.solve(&f, t0, x0, t_out)
    }

    fn solve_with_jacobian(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        let f = |t: f64, x: &State| {
            CALLS.fetch_add(1, Ordering::Relaxed);
            rhs(t, x)
        };
        self.0.solve_with_jacobian(&f, jacobian, t0, x0, t_out)
    }
}
