//! The local optimizers behind one trait: from a start point down to a local minimum of a
//! [`Problem`]. The multi-start hands its starts over through it, the fit finishes its best
//! start through it, and the diagnosis refits models with discovered terms through it, so a
//! new local method is one implementation here.
//!
//! Nelder–Mead's rounds inside the multi-start stay on [`RestartedNelderMead`] itself: they
//! advance a number of iterations at a time between the run's barriers, which a call that
//! runs to the end cannot do.

use crate::estimate::optimize::least_squares::{chi2, levenberg_marquardt_from, LmSettings};
#[cfg(doc)]
use crate::estimate::optimize::nelder_mead::RestartedNelderMead;
use crate::estimate::optimize::nelder_mead::{self, NelderMeadSettings, Status};
use crate::estimate::problem::objective::{Coordinates, Problem};

/// Where a local optimizer ended.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalMinimum {
    /// The best point.
    pub x: Vec<f64>,
    /// What the optimizer minimised, at `x`: the problem's cost, or the sum of squares of
    /// the residuals it was given (∞ where they cannot be computed at the start).
    pub value: f64,
    /// It stopped by its own convergence test, not by its budget or a failure.
    pub converged: bool,
}

/// A local optimizer.
pub trait LocalOptimizer {
    /// Minimises `problem` from `x0`, whose value is `f0` (∞ if not evaluated; a method
    /// that evaluates its start itself ignores it).
    fn minimize<C: Coordinates + ?Sized>(
        &self,
        problem: &Problem<'_, C>,
        x0: &[f64],
        f0: f64,
    ) -> LocalMinimum;
}

/// Restarted Nelder–Mead on the problem's cost (argmin's simplex; `estimate::optimize::nelder_mead`)
/// until its restart rule or `max_iters` iterations end it, in stages of at most
/// `stage_iters`.
#[derive(Debug, Clone, Copy)]
pub struct NelderMead {
    /// The simplex and its restart rule.
    pub settings: NelderMeadSettings,
    /// The iteration budget.
    pub max_iters: u64,
    /// Iterations per stage.
    pub stage_iters: u64,
}

impl LocalOptimizer for NelderMead {
    fn minimize<C: Coordinates + ?Sized>(
        &self,
        problem: &Problem<'_, C>,
        x0: &[f64],
        f0: f64,
    ) -> LocalMinimum {
        let search = nelder_mead::minimize(
            problem,
            x0.to_vec(),
            f0,
            self.settings,
            self.max_iters,
            self.stage_iters,
        );
        LocalMinimum {
            x: search.x().to_vec(),
            value: search.cost(),
            converged: search.status() == Status::Converged,
        }
    }
}

/// Which residuals Levenberg–Marquardt minimises the squares of.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Residuals {
    /// Those whose squares sum to the problem's cost ([`Problem::cost_residuals`]).
    Cost,
    /// Those whose squares sum to χ² ([`Problem::residuals`]).
    Chi2,
}

/// Levenberg–Marquardt on the problem's residuals (`estimate::optimize::least_squares`).
#[derive(Debug, Clone, Copy)]
pub struct LevenbergMarquardt {
    /// Its budget and tolerances.
    pub settings: LmSettings,
    /// The residuals it works on.
    pub residuals: Residuals,
}

impl LocalOptimizer for LevenbergMarquardt {
    fn minimize<C: Coordinates + ?Sized>(
        &self,
        problem: &Problem<'_, C>,
        x0: &[f64],
        _f0: f64,
    ) -> LocalMinimum {
        match self.residuals_at(problem, x0) {
            Some(r0) => self.minimize_from(problem, x0, r0),
            None => LocalMinimum {
                x: x0.to_vec(),
                value: f64::INFINITY,
                converged: false,
            },
        }
    }
}

impl LevenbergMarquardt {
    /// The residuals it works on, at `x` (`None` where they cannot be computed).
    fn residuals_at<C: Coordinates + ?Sized>(
        &self,
        problem: &Problem<'_, C>,
        x: &[f64],
    ) -> Option<Vec<f64>> {
        match self.residuals {
            Residuals::Cost => problem.cost_residuals(x),
            Residuals::Chi2 => problem.residuals(x),
        }
    }

    /// [`LocalOptimizer::minimize`] from `x0` whose residuals `r0` the caller has.
    pub(crate) fn minimize_from<C: Coordinates + ?Sized>(
        &self,
        problem: &Problem<'_, C>,
        x0: &[f64],
        r0: Vec<f64>,
    ) -> LocalMinimum {
        let f = |t: &[f64]| self.residuals_at(problem, t);
        let out = levenberg_marquardt_from(&f, x0, r0, self.settings);
        LocalMinimum {
            x: out.x,
            value: out.chi2,
            converged: out.converged,
        }
    }
}

/// Levenberg–Marquardt on a problem's χ² residuals from `x`, kept only where χ² falls: the
/// better of the start and the polish, with its χ²; `None` when the problem has no residuals
/// at `x` (not a least-squares objective, or a failed simulation).
pub(crate) fn polish_residuals<C: Coordinates + ?Sized>(
    problem: &Problem<'_, C>,
    x: &[f64],
) -> Option<(Vec<f64>, f64)> {
    let r0 = problem.residuals(x)?;
    let start = chi2(&r0);
    let lm = LevenbergMarquardt {
        settings: LmSettings::default(),
        residuals: Residuals::Chi2,
    };
    let polished = lm.minimize_from(problem, x, r0);
    Some(if polished.value < start {
        (polished.x, polished.value)
    } else {
        (x.to_vec(), start)
    })
}
