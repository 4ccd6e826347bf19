//! A quasi-steady "solver" for slowly driven stiff systems: instead of integrating
//! dx/dt = f(t, x), it puts the state on the slow manifold at each output time and adds the
//! first-order lag of that manifold.
//!
//! Why it can work for the motor's ramps: they last about a minute while the chamber
//! volumes fill in milliseconds and the rotor settles in tens of milliseconds, so after the
//! start the state follows the steady states of the inputs, lagging them slightly.
//!
//! The approximation (a singular-perturbation expansion to first order). Let h(t) close
//! the balances, f(t, h) = 0. Differentiating, J·ḣ + f_t = 0, so ḣ = −J⁻¹·f_t (J = ∂f/∂x,
//! f_t = ∂f/∂t, both at (t, h)). The solution that has forgotten its start is x = h + η
//! with f(t, h + η) ≈ J·η = ẋ ≈ ḣ, so η = J⁻¹·ḣ = −J⁻²·f_t. For one lag ẋ = (u − x)/τ this
//! is x ≈ u − τ·u̇ (J = −1/τ). What is left is O(τ²·ḧ) plus what the start's transient
//! has not yet forgotten (the state starts at the steady state of the first inputs).
//!
//! The steady states come from Newton's method, warm-started by extrapolating the last two
//! (the inputs move little between recorded rows). Where Newton does not converge at some
//! row (a kink it dithers across, a singular Jacobian), the whole call falls back to the
//! integrator it wraps, so an answer is never worse than that integrator's for lack of a
//! steady state. How far the approximation is from the full model is not known in advance:
//! it must be checked against the integrator (examples/quasi_steady.rs measures it).

use super::lu::Lu;
use super::ode::{Jacobian, Kinks, Rhs, SolveError, State, StiffSolver, N_STATES};
use super::rodas::Rodas4;

/// Typical magnitude of each state (pressures in Pa, then a speed in rad/s): the scale of
/// Newton's convergence test and of the time-derivative difference.
const STATE_SCALE: State = [1e5, 1e5, 1e5, 100.0];

/// Most Newton iterations per output time before falling back to the integrator.
const MAX_NEWTON: usize = 12;

/// The quasi-steady approximation (see the module documentation), falling back to `full`.
#[derive(Debug, Clone, Copy)]
pub struct QuasiSteady {
    /// Newton stops when every step is below this fraction of the state's typical magnitude
    /// (1e5 Pa, 100 rad/s), 1.
    pub newton_tol: f64,
    /// Whether the first-order lag η = −J⁻²·f_t is added (without it, the steady states).
    pub lag: bool,
    /// The integrator used where a steady state is not found.
    pub full: Rodas4,
}

impl Default for QuasiSteady {
    /// Newton to 1e-9 of the typical magnitudes (0.1 mPa, 1e-7 rad/s), with the lag, falling
    /// back to the default Rodas4.
    fn default() -> Self {
        Self {
            newton_tol: 1e-9,
            lag: true,
            full: Rodas4::default(),
        }
    }
}

/// Why one output time had no steady state (the caller falls back to the integrator).
struct NoSteadyState;

impl QuasiSteady {
    /// The quasi-steady state at every output time, or [`NoSteadyState`].
    fn manifold(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, NoSteadyState> {
        let mut out = Vec::with_capacity(t_out.len());
        // The last two steady states (time, state), for the warm start.
        let mut last: [(f64, State); 2] = [(f64::NAN, x0); 2];
        for &t in t_out {
            let guess = extrapolate(&last, t);
            let (h, eta) = self.steady_and_lag(rhs, jacobian, t, guess)?;
            last = [last[1], (t, h)];
            if last[0].0.is_nan() {
                last[0] = last[1];
            }
            out.push(if self.lag {
                std::array::from_fn(|i| h[i] + eta[i])
            } else {
                h
            });
        }
        Ok(out)
    }

    /// Newton from `guess` to h with f(t, h) = 0, and the lag η = −J⁻²·f_t there.
    fn steady_and_lag(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        t: f64,
        guess: State,
    ) -> Result<(State, State), NoSteadyState> {
        let mut x = guess;
        for _ in 0..MAX_NEWTON {
            let slopes = jacobian(t, &x).ok_or(NoSteadyState)?;
            let lu = Lu::new(slopes.jac).ok_or(NoSteadyState)?;
            let dx = lu.solve(slopes.f);
            let mut small = true;
            for i in 0..N_STATES {
                x[i] -= dx[i];
                small &= dx[i].abs() <= self.newton_tol * STATE_SCALE[i];
            }
            if !x.iter().all(|v| v.is_finite()) || x[..3].iter().any(|p| *p <= 0.0) {
                return Err(NoSteadyState);
            }
            if small {
                // J and f_t from the last linearisation, one (negligible) Newton step away.
                let f_t = match slopes.f_t {
                    Some(f_t) => f_t,
                    None => time_slope(rhs, t, &x),
                };
                let h_dot = lu.solve(f_t.map(|v| -v));
                return Ok((x, lu.solve(h_dot)));
            }
        }
        Err(NoSteadyState)
    }
}

/// ∂f/∂t by a central difference (for models without it in closed form).
fn time_slope(rhs: &Rhs<'_>, t: f64, x: &State) -> State {
    let dt = 1e-6 * t.abs().max(1.0);
    let (a, b) = (rhs(t + dt, x), rhs(t - dt, x));
    std::array::from_fn(|i| (a[i] - b[i]) / (2.0 * dt))
}

/// The line through the last two steady states at t (the last one alone at the start).
fn extrapolate(last: &[(f64, State); 2], t: f64) -> State {
    let [(ta, xa), (tb, xb)] = *last;
    if tb.is_nan() || ta == tb {
        return xb;
    }
    let s = (t - tb) / (tb - ta);
    std::array::from_fn(|i| xb[i] + s * (xb[i] - xa[i]))
}

impl StiffSolver for QuasiSteady {
    /// Without a Jacobian the steady states need differences: the integrator answers.
    fn solve(
        &self,
        rhs: &Rhs<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        self.full.solve(rhs, t0, x0, t_out)
    }

    fn solve_with_jacobian(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        self.manifold(rhs, jacobian, x0, t_out)
            .or_else(|NoSteadyState| self.full.solve_with_jacobian(rhs, jacobian, t0, x0, t_out))
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
        self.manifold(rhs, jacobian, x0, t_out)
            .or_else(|NoSteadyState| {
                self.full
                    .solve_with_kinks(rhs, jacobian, kinks, t0, x0, t_out)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::ode::Slopes;

    /// Time constants of the linear test system, s.
    const TAU: State = [1e-3, 5e-3, 2e-2, 0.1];
    /// Input u_i(t) = A_i + B_i·t.
    const A: State = [2e5, 1.5e5, 1.2e5, 50.0];
    const B: State = [1e3, -5e2, 2e2, 3.0];

    /// ẋ_i = (u_i(t) − x_i)/τ_i: after its start it follows x_i = u_i − τ_i·B_i exactly,
    /// which is what the first-order lag gives.
    fn lag_rhs(t: f64, x: &State) -> State {
        std::array::from_fn(|i| (A[i] + B[i] * t - x[i]) / TAU[i])
    }

    fn lag_slopes(t: f64, x: &State) -> Option<Slopes> {
        let mut jac = [[0.0; N_STATES]; N_STATES];
        for (i, row) in jac.iter_mut().enumerate() {
            row[i] = -1.0 / TAU[i];
        }
        Some(Slopes {
            f: lag_rhs(t, x),
            jac,
            f_t: Some(std::array::from_fn(|i| B[i] / TAU[i])),
        })
    }

    #[test]
    fn first_order_lag_matches_the_integrated_linear_lag() {
        let t_out: Vec<f64> = (1..=20).map(|k| 2.0 + 0.5 * f64::from(k)).collect();
        let x0 = A;
        let full = Rodas4 {
            tol: crate::numerics::Tolerances::with_rtol(1e-10),
        }
        .solve_with_jacobian(&lag_rhs, &lag_slopes, 0.0, x0, &t_out)
        .unwrap();
        let qs = QuasiSteady::default()
            .solve_with_jacobian(&lag_rhs, &lag_slopes, 0.0, x0, &t_out)
            .unwrap();
        let bare = QuasiSteady {
            lag: false,
            ..QuasiSteady::default()
        }
        .solve_with_jacobian(&lag_rhs, &lag_slopes, 0.0, x0, &t_out)
        .unwrap();
        for ((f, q), b) in full.iter().zip(&qs).zip(&bare) {
            for i in 0..N_STATES {
                let lag = TAU[i] * B[i];
                assert!((f[i] - q[i]).abs() <= 1e-6 * lag.abs(), "{i}: {f:?} {q:?}");
                // Without the lag term the answer is off by the lag itself.
                assert!(((f[i] - b[i]) - (-lag)).abs() <= 1e-6 * lag.abs(), "{i}");
            }
        }
    }

    #[test]
    fn without_a_steady_state_it_answers_as_the_integrator() {
        // ẋ = 1 for every state: the Jacobian is singular, no steady state exists.
        let rhs = |_: f64, _: &State| [1.0; N_STATES];
        let slopes = |t: f64, x: &State| {
            Some(Slopes {
                f: rhs(t, x),
                jac: [[0.0; N_STATES]; N_STATES],
                f_t: Some([0.0; N_STATES]),
            })
        };
        let t_out = [1.0, 2.0];
        let x0 = [1e5, 1e5, 1e5, 0.0];
        let qs = QuasiSteady::default().solve_with_jacobian(&rhs, &slopes, 0.0, x0, &t_out);
        let full = Rodas4::default().solve_with_jacobian(&rhs, &slopes, 0.0, x0, &t_out);
        assert_eq!(qs, full);
        assert!((qs.unwrap()[1][3] - 2.0).abs() < 1e-9);
    }
}
