//! Phase 7, the extended model's 95 % intervals: every estimated parameter of the chosen
//! model, the coefficients of its discovered terms included, by the method of `vanefit fit`
//! (`crate::estimate::profile::uncertainty`) on the likelihood every diagnosis fit
//! maximises. The rise of χ² that ends an interval is 3.841·s², s = max(1, r) with r the
//! model's noise ratio (Birge's ratio, `crate::estimate::fit::goodness`, eq. 1: the
//! diagnosis's noise ratio is the same number), and the curvature covariance is scaled by
//! the same s². A discovered term's coordinate is its coefficient over the fitted value, so
//! its interval is linear in the coefficient.
//!
//! Profiles with the command line's effort (`DiagnoseOptions::profile_intervals`); the
//! reduced effort takes the curvature at the optimum (2k + 1 residual evaluations against a
//! profile's few hundred).

use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::{HandOver, RefitError, TermSpace};
use super::observe::Note;
use super::{Candidate, ExtendedInterval, ModelKind};
use crate::estimate::fit::goodness::interval_threshold;
use crate::estimate::problem::likelihood::Likelihood;
use crate::estimate::problem::objective::Problem;
use crate::estimate::problem::space::ParamSpace;
use crate::estimate::profile::uncertainty::{
    curvature_covariance, curvature_intervals, profile_intervals, Interval, CHI2_95,
    CURVATURE_STEP, PROFILE_ITERS,
};
use crate::model::params::estimated_names as names_for;
use crate::numerics::DefaultSolver;

/// The parameters of `model` that get an interval: its estimated ones and one per discovered
/// term; none when `model` is the baseline (nothing selected).
pub(crate) fn parameters(model: &Candidate) -> usize {
    if model.kind == ModelKind::Baseline {
        return 0;
    }
    names_for(&model.fitted.effects).len() + model.fitted.extra.len()
}

/// The 95 % intervals of `model`'s estimated parameters in the order of its estimated names,
/// then one per discovered term; none when `model` is the baseline (nothing selected).
pub(crate) fn of_extended(
    cx: &Context,
    model: &Candidate,
    notes: &mut Vec<Note>,
) -> Result<Vec<ExtendedInterval>, DiagnoseError> {
    if model.kind == ModelKind::Baseline {
        return Ok(Vec::new());
    }
    let f = &model.fitted;
    let names = names_for(&f.effects);
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let space =
        ParamSpace::new(&names, f.params.clone(), f.effects.clone()).map_err(RefitError::from)?;
    let coordinates = TermSpace {
        space: &space,
        terms: &f.extra,
    };
    let objective = HandOver(Likelihood {
        cost: &cx.cost,
        target: &cx.target,
        solver: DefaultSolver::default(),
    });
    let problem = Problem::new(&objective, &coordinates, false);
    let mut x = space.theta(&f.params);
    x.extend(std::iter::repeat_n(1.0, f.extra.len()));
    let profile = cx.opts.profile_intervals;
    let threshold = interval_threshold(model.noise_ratio);
    let cov = curvature_covariance(&problem, &x, CURVATURE_STEP, threshold / CHI2_95);
    let intervals = if profile {
        let chi2_min = problem.evaluate(&x).chi2;
        let (engine, cov) = (cx.engine, cov.as_ref());
        profile_intervals(
            engine,
            &problem,
            &x,
            chi2_min,
            threshold,
            cov,
            PROFILE_ITERS,
        )
    } else {
        curvature_intervals(&problem, &x, cov.as_ref())
    };
    notes.push(Note::Evaluated(problem.evaluations()));
    Ok(intervals
        .into_iter()
        .enumerate()
        .map(|(j, interval)| {
            let term = j.checked_sub(space.len()).map(|i| f.extra[i]);
            let falling = term.is_some_and(|t| t.coefficient < 0.0);
            ExtendedInterval {
                interval: ascending(interval, falling),
                term,
            }
        })
        .collect())
}

/// The interval with its ends in increasing value: the coordinate of a negative
/// coefficient (`falling`) grows as the coefficient falls, so its lower side is the upper
/// end.
fn ascending(mut interval: Interval, falling: bool) -> Interval {
    if falling {
        std::mem::swap(&mut interval.lo, &mut interval.hi);
    }
    interval
}
