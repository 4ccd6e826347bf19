//! Stiff time integration behind a small trait, so that the integrator can be swapped.
//!
//! The motor is stiff: the lumped volumes fill in milliseconds (τ ≈ V/(C·ρ0·R·T0) ≈ 3 ms)
//! while the rotor and the ramps move over seconds. The default backend is diffsol's
//! variable-order BDF with a dense LU on the 4×4 Jacobian.

use crate::motor::{State, N_STATES};
use std::fmt;

/// Right-hand side dx/dt = f(t, x).
pub type Rhs<'a> = dyn Fn(f64, &State) -> State + 'a;

/// Integration tolerances: |error_i| ≤ atol_i + rtol·|x_i|.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    pub rtol: f64,
    pub atol: State,
}

impl Default for Tolerances {
    /// rtol 1e-6; 1 Pa on pressures, 1e-3 rad/s on speed. Tight enough that the fitting cost
    /// is smooth in the parameters (its steps are far below the sensors' noise).
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol: [1.0, 1.0, 1.0, 1e-3],
        }
    }
}

/// Why an integration failed.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveError(pub String);

impl fmt::Display for SolveError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "integration failed: {}", self.0)
    }
}

impl std::error::Error for SolveError {}

/// A stiff initial-value solver.
pub trait StiffSolver: Send + Sync {
    /// Integrates from (t0, x0) and returns the state at each time of `t_out`
    /// (increasing, all ≥ t0).
    fn solve(
        &self,
        rhs: &Rhs<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError>;
}

/// Typical magnitude of each state, used to size finite-difference steps.
const STATE_SCALE: State = [1e5, 1e5, 1e5, 1.0];

/// Jacobian-vector product J·v by a forward difference, with a step sized so that each
/// state moves by about 1e-7 of its magnitude.
fn jacobian_times(rhs: &Rhs<'_>, t: f64, x: &State, v: &State) -> State {
    let mut ratio: f64 = 0.0;
    for i in 0..N_STATES {
        ratio = ratio.max(v[i].abs() / x[i].abs().max(STATE_SCALE[i]));
    }
    if ratio == 0.0 || !ratio.is_finite() {
        return if ratio.is_finite() {
            [0.0; N_STATES]
        } else {
            [f64::NAN; N_STATES]
        };
    }
    let h = 1e-7 / ratio;
    let f0 = rhs(t, x);
    let mut xh = *x;
    for i in 0..N_STATES {
        xh[i] += h * v[i];
    }
    let f1 = rhs(t, &xh);
    let mut jv = [0.0; N_STATES];
    for i in 0..N_STATES {
        jv[i] = (f1[i] - f0[i]) / h;
    }
    jv
}

/// diffsol's BDF (variable order 1–5, like MATLAB's ode15s) with nalgebra's dense LU.
#[derive(Debug, Clone, Copy, Default)]
pub struct DiffsolBdf {
    pub tol: Tolerances,
}

impl StiffSolver for DiffsolBdf {
    fn solve(
        &self,
        rhs: &Rhs<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        use diffsol::{DenseMatrix, NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod};
        let err = |e: diffsol::DiffsolError| SolveError(e.to_string());
        let problem = OdeBuilder::<NalgebraMat<f64>>::new()
            .t0(t0)
            .rtol(self.tol.rtol)
            .atol(self.tol.atol)
            .rhs_implicit(
                |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| {
                    y.copy_from_slice(&rhs(t, &to_state(x)));
                },
                |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
                    y.copy_from_slice(&jacobian_times(rhs, t, &to_state(x), &to_state(v)));
                },
            )
            .init(
                move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&x0),
                N_STATES,
            )
            .build()
            .map_err(err)?;
        let mut solver = problem.bdf::<NalgebraLU<f64>>().map_err(err)?;
        let (ys, _stop) = solver.solve_dense(t_out).map_err(err)?;
        Ok((0..t_out.len())
            .map(|j| std::array::from_fn(|i| ys.get_index(i, j)))
            .collect())
    }
}

fn to_state(x: &[f64]) -> State {
    std::array::from_fn(|i| x[i])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stiff linear test problem with a known solution (as diffsol pairs each test problem
    /// with its reference): x0' = −1000·(x0 − cos t), x1' = −x1; x0 follows cos t closely.
    #[test]
    fn bdf_solves_stiff_linear_problem() {
        let rhs = |t: f64, x: &State| [-1000.0 * (x[0] - t.cos()), -x[1], 0.0, 0.0];
        let t_out: Vec<f64> = (0..=10).map(|k| f64::from(k) * 0.5).collect();
        let solver = DiffsolBdf {
            tol: Tolerances {
                rtol: 1e-8,
                atol: [1e-10; 4],
            },
        };
        let xs = solver
            .solve(&rhs, 0.0, [1.0, 1.0, 0.0, 0.0], &t_out)
            .unwrap();
        for (t, x) in t_out.iter().zip(&xs) {
            // Exact: x0 = (1000² cos t + 1000 sin t)/(1000² + 1) + C e^{−1000 t}.
            let a = 1e6 / (1e6 + 1.0);
            let b = 1e3 / (1e6 + 1.0);
            let exact0 = a * t.cos() + b * t.sin() + (1.0 - a) * (-1000.0 * t).exp();
            assert!((x[0] - exact0).abs() < 1e-6, "t={t}: {} vs {exact0}", x[0]);
            assert!((x[1] - (-t).exp()).abs() < 1e-6);
        }
    }
}
