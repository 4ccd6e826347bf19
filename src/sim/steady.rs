//! Steady operating points by Newton's method on the balances (mass at V_1, V_2, V_e and,
//! when speed is free, torque), globalised by pseudo-transient continuation: each step solves
//! (I/Δt − J)·Δx = f(x) with Δt growing as the residual falls (switched evolution relaxation),
//! so that far from the solution it follows the physical transient and near it it is Newton.

use crate::model::motor::{idx, Boundary, Motor, State, N_STATES};
use crate::numerics::lu::Lu;

/// What the steady solver could not do.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SteadyError {
    /// Every damped Newton step, down to a millionth of the full one, left a pressure ≤ 0
    /// or a residual that is not finite.
    #[error("no steady state: pressures would turn negative")]
    NegativePressures,
    /// The iteration did not converge within its limit.
    #[error(
        "no steady state: not converged after {iterations} iterations (residual {residual:.3e})"
    )]
    NotConverged {
        /// The iteration limit.
        iterations: usize,
        /// The scaled residual norm at the last iterate.
        residual: f64,
    },
}

/// The iteration limit of [`solve`].
const MAX_ITERATIONS: usize = 200;

/// Typical magnitude of each state (for steps and convergence).
const SCALE: State = [1e5, 1e5, 1e5, 100.0];

/// Steady state at an imposed speed ω (the datasheet experiment): pressures that close the
/// three mass balances. `guess` seeds the iteration (its ω is replaced).
pub fn at_speed(
    motor: &Motor,
    bc: &Boundary,
    omega: f64,
    guess: &State,
) -> Result<State, SteadyError> {
    solve(motor, bc, with_speed(guess, omega), true, 1e-3)
}

/// As [`at_speed`], from the solution at a nearby speed (a sweep): the guess is close, so
/// the iteration starts as plain Newton (pseudo-time step 1e6 s) instead of following the
/// physical transient from 1 ms; if the residual grows, the continuation takes over as
/// usual. Measured on the shipped 25-speed datasheet (callgrind): about a third fewer
/// instructions for the sweep.
pub(crate) fn at_speed_from_neighbour(
    motor: &Motor,
    bc: &Boundary,
    omega: f64,
    neighbour: &State,
) -> Result<State, SteadyError> {
    solve(motor, bc, with_speed(neighbour, omega), true, 1e6)
}

/// `x` with its speed replaced by ω.
fn with_speed(x: &State, omega: f64) -> State {
    let mut x = *x;
    x[idx::OMEGA] = omega;
    x
}

/// Steady state with the speed free (torque balanced by friction and load).
pub fn free(motor: &Motor, bc: &Boundary, guess: &State) -> Result<State, SteadyError> {
    solve(motor, bc, *guess, false, 1e-3)
}

/// A first guess: inlet at supply, the rest at atmosphere, standing still.
pub fn initial_guess(bc: &Boundary) -> State {
    [bc.p_port1_pa, bc.p_port2_pa, bc.p_atm_pa, 0.0]
}

fn solve(
    motor: &Motor,
    bc: &Boundary,
    x0: State,
    speed_fixed: bool,
    dt0: f64,
) -> Result<State, SteadyError> {
    let n_free = if speed_fixed { 3 } else { 4 };
    let f = |x: &State| motor.derivatives(x, bc);
    // f and, for the base model, its Jacobian in one pass: the Jacobian at each accepted
    // point is the next iteration's (a separate Jacobian would evaluate f again).
    let linearise = |x: &State| match motor.derivatives_and_jacobian(x, bc) {
        Some((fx, jac)) => (fx, Some(jac)),
        None => (f(x), None),
    };
    let mut x = x0;
    let (mut fx, mut jx) = linearise(&x);
    let mut res = residual_norm(&fx, n_free);
    let mut dt = dt0;
    for _ in 0..MAX_ITERATIONS {
        if res == 0.0 {
            return Ok(x);
        }
        // The model's own Jacobian where it has one (the base model), else differences.
        let jac = jx.unwrap_or_else(|| jacobian(&f, &x, &fx, n_free));
        let Some(dx) = newton_step(&jac, &fx, dt, speed_fixed) else {
            dt *= 0.1;
            continue;
        };
        let mut step = 1.0;
        let (x_new, (f_new, j_new), res_new) = loop {
            let cand: State = std::array::from_fn(|i| x[i] + step * dx[i]);
            if cand[..3].iter().all(|p| *p > 0.0) {
                let lc = linearise(&cand);
                let rc = residual_norm(&lc.0, n_free);
                if rc.is_finite() {
                    break (cand, lc, rc);
                }
            }
            step *= 0.5;
            if step < 1e-6 {
                return Err(SteadyError::NegativePressures);
            }
        };
        let small_step =
            (0..n_free).all(|i| (step * dx[i]).abs() <= 1e-10 * x_new[i].abs().max(SCALE[i]));
        dt = if res_new == 0.0 {
            1e12
        } else {
            (dt * (res / res_new).clamp(0.2, 1e3)).min(1e12)
        };
        x = x_new;
        fx = f_new;
        jx = j_new;
        res = res_new;
        // Converged when Newton's steps vanish, or when the balances are closed to far below
        // anything measurable (1e-4 Pa/s on the pressures, 1e-7 rad/s² on the speed): at
        // standstill the displacement flows have a corner at ω = 0 (they are ∝ |ω|), where
        // the steps can dither at 1e-9 rad/s without ever getting smaller.
        if (small_step && dt > 1.0) || res < 1e-9 {
            return Ok(x);
        }
    }
    Err(SteadyError::NotConverged {
        iterations: MAX_ITERATIONS,
        residual: res,
    })
}

/// The step Δx of (I/Δt − J)·Δx = f(x); with the speed fixed, the speed's row and column are
/// replaced by the identity and its right-hand side by 0 (so Δω = 0). `None` when the
/// matrix is singular.
fn newton_step(jac: &[State; N_STATES], fx: &State, dt: f64, speed_fixed: bool) -> Option<State> {
    let mut a: [State; N_STATES] = std::array::from_fn(|i| {
        std::array::from_fn(|j| f64::from(u8::from(i == j)) / dt - jac[i][j])
    });
    let mut rhs = *fx;
    if speed_fixed {
        for (i, row) in a.iter_mut().enumerate() {
            row[idx::OMEGA] = 0.0;
            if i == idx::OMEGA {
                *row = [0.0; N_STATES];
            }
        }
        a[idx::OMEGA][idx::OMEGA] = 1.0;
        rhs[idx::OMEGA] = 0.0;
    }
    Some(Lu::new(a)?.solve(rhs))
}

/// Residual in state units per second, each scaled by its typical magnitude.
fn residual_norm(fx: &State, n_free: usize) -> f64 {
    (0..n_free)
        .map(|i| (fx[i] / SCALE[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn jacobian(
    f: &dyn Fn(&State) -> State,
    x: &State,
    fx: &State,
    n_free: usize,
) -> [State; N_STATES] {
    let mut jac = [[0.0; N_STATES]; N_STATES];
    for j in 0..n_free {
        let h = 1e-7 * x[j].abs().max(SCALE[j]);
        let mut xh = *x;
        xh[j] += h;
        let fh = f(&xh);
        for i in 0..N_STATES {
            jac[i][j] = (fh[i] - fx[i]) / h;
        }
    }
    jac
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motor::Load;

    #[test]
    fn steady_state_closes_every_balance() {
        let m = Motor::default_motor();
        let bc = Boundary::supplied(7.3e5, 101_325.0, Load::ViscousBrake { c_nm_s_rad: 2e-4 });
        let x = free(&m, &bc, &initial_guess(&bc)).unwrap();
        let d = m.derivatives(&x, &bc);
        for (i, dp) in d.iter().take(3).enumerate() {
            assert!(dp.abs() < 1e-3, "dp{i}/dt = {dp}");
        }
        assert!(d[3].abs() < 1e-6);
        assert!(x[idx::OMEGA] > 100.0);
    }
}
