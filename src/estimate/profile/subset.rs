//! Which parameters a dataset can pin down, before fitting it: forward selection on the
//! sensitivities of the likelihood's normalised residuals (subset selection for
//! identifiability, as in Brun, Reichert & Künsch 2001). A catalogue page pins a few
//! parameters and leaves the rest to defaults; this says which, and how well.
//!
//! With J the Jacobian of the residuals r = (y_sim − y)/σ with respect to ln θ at the
//! nominal motor, the standard deviation of ln θ_j when the parameters S are estimated with
//! it is √[(J_Sᵀ J_S)⁻¹]_jj. The selection adds, one at a time, the parameter whose column
//! is least explained by the ones chosen (the largest residual norm after projecting them
//! out, 1/norm = its conditional σ), while that σ stays below the limit; then it drops the
//! worst-determined one while any joint σ exceeds the limit.

use crate::estimate::problem::fit_data::FitData;
use crate::model::motor::Motor;
use crate::numerics::DefaultSolver;
use nalgebra::{DMatrix, DVector};

/// Relative 1σ (of ln θ) up to which a parameter counts as pinned: 10 %, a 95 % interval of
/// about ±20 %.
pub(crate) const PINNED_RELATIVE_SD: f64 = 0.10;

/// Step of the central differences in ln θ.
const LOG_STEP: f64 = 1e-3;

/// A parameter's verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// The parameter.
    pub name: String,
    /// Relative 1σ: jointly with the other chosen ones for a chosen parameter; for one left
    /// out, its σ if it were added to the chosen ones (∞ when the data do not see it).
    pub(crate) relative_sd: f64,
    /// Whether the data pin it (it is estimated).
    pub(crate) pinned: bool,
}

/// The columns ∂r/∂ln θ_j at `motor` for `names` (`None` if a simulation fails).
fn sensitivities(data: &FitData, motor: &Motor, names: &[String]) -> Option<DMatrix<f64>> {
    let solver = DefaultSolver::default();
    let residuals = |m: &Motor| data.target.residuals(&data.smoothed, m, &solver);
    let n = residuals(motor)?.len();
    let mut jac = DMatrix::zeros(n, names.len());
    for (j, name) in names.iter().enumerate() {
        let v = motor.params().get(name)?;
        let at = |f: f64| {
            let p = motor.params().with(name, v * f).ok()?;
            residuals(&Motor::new(p, motor.effects.clone()))
        };
        let (plus, minus) = (at(LOG_STEP.exp())?, at((-LOG_STEP).exp())?);
        for i in 0..n {
            jac[(i, j)] = (plus[i] - minus[i]) / (2.0 * LOG_STEP);
        }
    }
    Some(jac)
}

/// The columns `cols` of `jac`.
fn columns(jac: &DMatrix<f64>, cols: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(jac.nrows(), cols.len(), |i, k| jac[(i, cols[k])])
}

/// Joint σ of ln θ for the columns `cols`: √diag (JᵀJ)⁻¹ (∞ where singular).
fn joint_sd(jac: &DMatrix<f64>, cols: &[usize]) -> Vec<f64> {
    let a = columns(jac, cols);
    match (a.transpose() * &a).try_inverse() {
        Some(inv) => (0..cols.len())
            .map(|k| inv[(k, k)].max(0.0).sqrt())
            .collect(),
        None => vec![f64::INFINITY; cols.len()],
    }
}

/// σ of ln θ_j if added to `chosen`: 1/‖(I − P_chosen)·J_j‖.
fn conditional_sd(jac: &DMatrix<f64>, chosen: &[usize], j: usize) -> f64 {
    let col: DVector<f64> = jac.column(j).into();
    let rest = if chosen.is_empty() {
        col
    } else {
        let a = columns(jac, chosen);
        let qr = a.clone().qr();
        let q = qr.q();
        &col - &q * (q.transpose() * &col)
    };
    let norm = rest.norm();
    if norm > 0.0 {
        1.0 / norm
    } else {
        f64::INFINITY
    }
}

/// The selection (see the module documentation) among `names` at `motor`, in the order of
/// `names`; `None` if the nominal motor cannot be simulated.
pub(crate) fn pinned_subset(
    data: &FitData,
    motor: &Motor,
    names: &[String],
) -> Option<Vec<Verdict>> {
    let jac = sensitivities(data, motor, names)?;
    let mut chosen: Vec<usize> = Vec::new();
    loop {
        let best = (0..names.len())
            .filter(|j| !chosen.contains(j))
            .map(|j| (j, conditional_sd(&jac, &chosen, j)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        match best {
            Some((j, sd)) if sd <= PINNED_RELATIVE_SD => chosen.push(j),
            _ => break,
        }
    }
    loop {
        let sd = joint_sd(&jac, &chosen);
        let Some((k, worst)) = sd
            .iter()
            .copied()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
        else {
            break;
        };
        if worst <= PINNED_RELATIVE_SD {
            break;
        }
        chosen.remove(k);
    }
    let sd = joint_sd(&jac, &chosen);
    Some(
        names
            .iter()
            .enumerate()
            .map(|(j, name)| match chosen.iter().position(|c| *c == j) {
                Some(k) => Verdict {
                    name: name.clone(),
                    relative_sd: sd[k],
                    pinned: true,
                },
                None => Verdict {
                    name: name.clone(),
                    relative_sd: conditional_sd(&jac, &chosen, j),
                    pinned: false,
                },
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn collinear_columns_are_not_both_chosen() {
        // Columns 0 and 1 are identical, column 2 is independent and weak.
        let jac =
            DMatrix::from_row_slice(3, 3, &[100.0, 100.0, 0.0, 50.0, 50.0, 0.0, 0.0, 0.0, 1.0]);
        assert!(joint_sd(&jac, &[0, 1])[0].is_infinite() || joint_sd(&jac, &[0, 1])[0] > 1e6);
        let c = conditional_sd(&jac, &[0], 1);
        assert!(c > 1e6, "{c}");
        // The weak column is seen with σ = 1/1.
        assert!((conditional_sd(&jac, &[0], 2) - 1.0).abs() < 1e-12);
        // Orthogonal columns: σ = 1/‖J_j‖.
        let sd = joint_sd(&jac, &[0, 2]);
        assert!((sd[0] - 1.0 / (100f64.powi(2) + 50f64.powi(2)).sqrt()).abs() < 1e-12);
        assert!((sd[1] - 1.0).abs() < 1e-12);
    }
}
