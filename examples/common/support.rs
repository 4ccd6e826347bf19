//! What the measuring examples share: a solver wrapper that counts right-hand-side
//! evaluations, and the shipped dataset's cost model.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;
use vanefit::data::Dataset;
use vanefit::model::Motor;
use vanefit::numerics::{Jacobian, Kinks, Rhs, SolveError, State, StiffSolver};
use vanefit::objective::{CostModel, CostOptions, CostValue};

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

/// `rhs`, counting its calls.
fn counted<'a>(rhs: &'a Rhs<'_>) -> impl Fn(f64, &State) -> State + 'a {
    move |t, x| {
        CALLS.fetch_add(1, Ordering::Relaxed);
        rhs(t, x)
    }
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
        self.0.solve(&counted(rhs), t0, x0, t_out)
    }

    // (`solve` above stays the inner solver's own `solve`: for a solver that builds its
    // own Jacobian the two differ.)
    fn solve_with_jacobian(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        self.0
            .solve_with_jacobian(&counted(rhs), jacobian, t0, x0, t_out)
    }

    fn solve_with_kinks(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        kinks: &Kinks<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        self.0
            .solve_with_kinks(&counted(rhs), jacobian, kinks, t0, x0, t_out)
    }
}

/// The first command-line argument as a count (`default` without one), the shipped dataset
/// and its cost model.
pub fn shipped(default: usize) -> Result<(usize, Dataset, CostModel), Box<dyn std::error::Error>> {
    let n = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(default);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("measurements/ar034-synthetic");
    let ds = Dataset::load(&dir)?;
    let cost = CostModel::new(&ds, CostOptions::default())?;
    Ok((n, ds, cost))
}

/// One evaluation through [`Counting`] (its cost and right-hand-side calls), then the mean
/// time of `n` plain evaluations, µs.
pub fn count_and_time(
    cost: &CostModel,
    motor: &Motor,
    solver: &dyn StiffSolver,
    n: usize,
) -> (CostValue, u64, f64) {
    reset();
    let value = cost.evaluate(motor, &Counting(solver));
    let rhs_calls = calls();
    let t = Instant::now();
    for _ in 0..n {
        std::hint::black_box(cost.evaluate(motor, solver));
    }
    let us = t.elapsed().as_secs_f64() * 1e6 / n.max(1) as f64;
    (value, rhs_calls, us)
}
