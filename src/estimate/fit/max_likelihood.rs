//! The maximum-likelihood point of a fit: the multi-start's optima polished on the
//! likelihood of the recorded rows (`maximum_likelihood`).

use crate::estimate::engine::Engine;
use crate::estimate::error::EstimateError;
use crate::estimate::problem::fit_data::FitData;
use crate::estimate::problem::likelihood::Likelihood;
use crate::estimate::problem::objective::Problem;
use crate::estimate::problem::space::ParamSpace;
use crate::estimate::profile::uncertainty;
use crate::model::motor::Motor;
use crate::numerics::DefaultSolver;
use crate::objective::likelihood::Target;

/// A point polished on the likelihood: θ and its χ².
pub(crate) type Polished = (Vec<f64>, f64);

/// Index of the lowest χ² of polished points.
pub(crate) fn lowest(polished: &[Polished]) -> usize {
    (0..polished.len())
        .min_by(|a, b| polished[*a].1.total_cmp(&polished[*b].1))
        .unwrap_or(0)
}

/// What [`maximum_likelihood`] found.
pub(crate) struct MlFit {
    /// The likelihood's target (the data's noise estimates), linearised at the estimate.
    pub target: Target,
    /// The same with each channel's σ widened to its residual scatter where that is larger.
    pub widened: Target,
    /// The widened channels and their factors.
    pub(crate) widening: Vec<(String, f64)>,
    /// The points, each polished on the widened target's χ².
    pub polished: Vec<Polished>,
    /// The motor at which the supply-pressure offset's effect was linearised (the best
    /// point of the first polish): exported so that the likelihood can be rebuilt exactly.
    pub linearised_at: Motor,
}

/// The likelihood's target and `points` (the best start first, then the multi-start's other
/// local optima) each polished on its χ². J knows neither the data's noise nor the sensors'
/// offsets, so its best start need not lie in the likelihood's deepest valley: every point
/// is polished and the lowest is the estimate. The supply-pressure offset's effect on the
/// rows is linearised at a motor; where the motor breaks away in a ramp moves that effect
/// row by row, so it is taken at the best polished point and everything polished again.
///
/// A channel's σ from second differences of few rows is itself uncertain (±30% for a
/// 25-point datasheet, whose torque pins T_c): an underestimate would give that channel too
/// much weight and its parameters intervals too narrow. So where a channel's residuals at
/// the estimate scatter more than its σ, σ is widened to √(χ²_c/n_c)·σ (Birge's ratio per
/// channel; never narrowed) and the points are polished once more. The goodness of fit is
/// still reported against the data's own σ.
pub(crate) fn maximum_likelihood(
    engine: &Engine,
    data: &FitData,
    space: &ParamSpace,
    points: &[Vec<f64>],
) -> Result<MlFit, EstimateError> {
    let motor = |theta: &[f64]| -> Result<Motor, EstimateError> {
        Ok(Motor::new(space.params(theta)?, space.effects.clone()))
    };
    let polish_all = |target: &Target, points: &[Vec<f64>]| {
        let likelihood = Likelihood {
            cost: &data.smoothed,
            target,
            solver: DefaultSolver::default(),
        };
        let ml = Problem::new(&likelihood, space, false);
        engine.map(points, |t| uncertainty::polish_chi2(&ml, t, 400))
    };
    let thetas = |p: Vec<Polished>| -> Vec<Vec<f64>> { p.into_iter().map(|(t, _)| t).collect() };
    let first = data.target_at(&motor(&points[0])?);
    let polished = polish_all(&first, points);
    let linearised_at = motor(&polished[lowest(&polished)].0)?;
    let target = data.target_at(&linearised_at);
    let polished = polish_all(&target, &thetas(polished));
    let best = motor(&polished[lowest(&polished)].0)?;
    let channels = data
        .simulate(&best)
        .map(|sim| data.channel_chi2(&target, &sim))
        .unwrap_or_default();
    let factors: Vec<f64> = channels
        .iter()
        .map(|c| (c.chi2 / c.n.max(1) as f64).sqrt().max(1.0))
        .collect();
    let widening = channels
        .iter()
        .zip(&factors)
        .filter(|(_, f)| **f > 1.0)
        .map(|(c, f)| (c.label.clone(), *f))
        .collect();
    let widened = target.widened(&factors);
    let polished = polish_all(&widened, &thetas(polished));
    Ok(MlFit {
        target,
        widened,
        widening,
        polished,
        linearised_at,
    })
}
