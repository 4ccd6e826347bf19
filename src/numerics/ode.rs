//! Stiff time integration behind a small trait, so that the integrator can be swapped.
//!
//! The motor is stiff: the lumped volumes fill in milliseconds (τ ≈ V/(C·ρ0·R·T0) ≈ 3 ms)
//! while the rotor and the ramps move over seconds. Two backends implement the trait:
//! [`super::rodas::Rodas4`], the default ([`super::DefaultSolver`]), which takes the model's
//! own Jacobian through [`StiffSolver::solve_with_jacobian`]; and diffsol's variable-order
//! BDF ([`DiffsolBdf`]), kept as an independent cross-check (tests compare the two, and the
//! recovery test makes its data with the BDF).

/// Number of components of a state (the motor's p_1, p_2, p_e and ω).
pub const N_STATES: usize = 4;
/// A state vector. Fixed-size so that a step allocates nothing.
pub type State = [f64; N_STATES];

/// Right-hand side dx/dt = f(t, x).
pub type Rhs<'a> = dyn Fn(f64, &State) -> State + 'a;

/// f(t, x) together with its Jacobian ∂f/∂x, row-major (`j[i][k]` = ∂f_i/∂x_k), and
/// ∂f/∂t where the model has them in closed form (sharing the work of both); `None` makes
/// the solver call the right-hand side and use finite differences.
pub type Jacobian<'a> = dyn Fn(f64, &State) -> Option<Slopes> + 'a;

/// How many kink indicators a model reports ([`Kinks`]).
pub(crate) const N_KINKS: usize = 6;

/// Where the right-hand side has kinks: indicators g_i(t, x) whose sign changes where f
/// is continuous but its slope is not (a nozzle entering its laminar range). A step that
/// straddles such a point makes the error estimate of a higher-order method blow up; a
/// solver that knows the indicators can land just past the kink instead of halving its way
/// through it. Indicators that a model does not use stay at a constant positive value.
pub type Kinks<'a> = dyn Fn(f64, &State) -> [f64; N_KINKS] + 'a;

/// What a model can say in closed form about its right-hand side at one (t, x).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slopes {
    /// f(t, x).
    pub f: State,
    /// ∂f/∂x, row-major: `jac[i][k]` = ∂f_i/∂x_k.
    pub jac: [State; N_STATES],
    /// ∂f/∂t (`None`: the solver takes a forward difference in time, one more evaluation
    /// of f).
    pub(crate) f_t: Option<State>,
}

/// Integration tolerances: |error_i| ≤ atol_i + rtol·|x_i|.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Relative tolerance, 1.
    pub rtol: f64,
    /// Absolute tolerance per state, in the state's unit.
    pub atol: State,
}

impl Default for Tolerances {
    /// rtol 3e-8; 0.03 Pa on pressures, 3e-5 rad/s on speed: the BDF's default (Rodas4 has
    /// its own, see [`super::rodas::Rodas4`]). Chosen by measurement so that
    /// the fitting cost is smooth in the parameters: an adaptive integrator changes its step
    /// sequence when a parameter changes, and the cost jitters with its tolerance. Over a
    /// 1e-5 change of c_12 the jitter was 2e-2 cost units at rtol 1e-6, 3e-3 at 1e-7 and
    /// 5e-4 at 3e-8, and the largest output error 0.02σ, 0.006σ and 0.0004σ of the sensor
    /// noise; Nelder–Mead stalls in this problem's narrow valleys at the looser settings.
    fn default() -> Self {
        Self::with_rtol(3e-8)
    }
}

impl Tolerances {
    /// rtol with absolute tolerances of 1e6·rtol Pa on pressures and 1e3·rtol rad/s on
    /// speed (the states' typical magnitudes times rtol).
    pub fn with_rtol(rtol: f64) -> Self {
        Self {
            rtol,
            atol: [1e6 * rtol, 1e6 * rtol, 1e6 * rtol, 1e3 * rtol],
        }
    }
}

/// Why an integration failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// The output times decrease somewhere, or the first lies before the start time.
    #[error("integration failed: output times must increase from t0")]
    OutputTimesNotIncreasing,
    /// The step size fell below rounding at a time.
    #[error("integration failed: step size underflow at t = {t} s")]
    StepSizeUnderflow {
        /// Where the integration stopped, s.
        t: f64,
    },
    /// The step limit was reached before the last output time.
    #[error(
        "integration failed: more than {max_steps} steps before t = {t_end} s (stopped at t = \
         {t} s)"
    )]
    TooManySteps {
        /// The step limit.
        max_steps: usize,
        /// The last output time, s.
        t_end: f64,
        /// Where the integration stopped, s.
        t: f64,
    },
    /// diffsol's BDF failed (its own message).
    #[cfg(feature = "bdf")]
    #[error("integration failed: {0}")]
    Bdf(#[source] BdfError),
}

/// An error of diffsol's BDF ([`DiffsolBdf`]). Equal when the messages are (diffsol's
/// error does not compare).
#[cfg(feature = "bdf")]
#[derive(Debug, Clone, thiserror::Error)]
#[error(transparent)]
pub struct BdfError(#[from] pub diffsol::DiffsolError);

#[cfg(feature = "bdf")]
impl PartialEq for BdfError {
    fn eq(&self, other: &Self) -> bool {
        self.0.to_string() == other.0.to_string()
    }
}

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

    /// As [`StiffSolver::solve`], with the model's own Jacobian where it has one. Solvers
    /// that do not use Jacobians (or build their own) ignore it.
    fn solve_with_jacobian(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        let _ = jacobian;
        self.solve(rhs, t0, x0, t_out)
    }

    /// As [`StiffSolver::solve_with_jacobian`], told where the right-hand side has kinks.
    /// Solvers that do not place steps against kinks ignore them.
    fn solve_with_kinks(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        kinks: &Kinks<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        let _ = kinks;
        self.solve_with_jacobian(rhs, jacobian, t0, x0, t_out)
    }
}

/// Typical magnitude of each state (pressures in Pa, then a speed in rad/s), used to size
/// finite-difference steps.
#[cfg(feature = "bdf")]
const STATE_SCALE: State = [1e5, 1e5, 1e5, 1.0];

/// Jacobian-vector product J·v by a forward difference, with a step sized so that each
/// state moves by about 1e-7 of its magnitude.
#[cfg(feature = "bdf")]
fn jacobian_times(rhs: &Rhs<'_>, t: f64, x: &State, f0: &State, v: &State) -> State {
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
///
/// Behind the cargo feature `bdf` (on by default): the fuzz targets build vanefit without
/// it, which spares their instrumented build diffsol and its linear-algebra crates.
#[cfg(feature = "bdf")]
#[derive(Debug, Clone, Copy, Default)]
pub struct DiffsolBdf {
    /// Integration tolerances.
    pub tol: Tolerances,
}

#[cfg(feature = "bdf")]
impl StiffSolver for DiffsolBdf {
    fn solve(
        &self,
        rhs: &Rhs<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder};
        // diffsol builds its Jacobian column by column from J·e_j at one state: keep f(t, x)
        // of the last state so that each column costs one evaluation, not two.
        let last = std::cell::RefCell::new((f64::NAN, [f64::NAN; N_STATES], [0.0; N_STATES]));
        let f_at = |t: f64, x: &State| {
            let mut c = last.borrow_mut();
            if c.0 != t || c.1 != *x {
                *c = (t, *x, rhs(t, x));
            }
            c.2
        };
        let problem = OdeBuilder::<NalgebraMat<f64>>::new()
            .t0(t0)
            .rtol(self.tol.rtol)
            .atol(self.tol.atol)
            .rhs_implicit(
                |x: &[f64], _p: &[f64], t: f64, y: &mut [f64]| {
                    y.copy_from_slice(&rhs(t, &to_state(x)));
                },
                |x: &[f64], _p: &[f64], t: f64, v: &[f64], y: &mut [f64]| {
                    let x = to_state(x);
                    y.copy_from_slice(&jacobian_times(rhs, t, &x, &f_at(t, &x), &to_state(v)));
                },
            )
            .init(
                move |_p: &[f64], _t: f64, y: &mut [f64]| y.copy_from_slice(&x0),
                N_STATES,
            )
            .build()
            .map_err(diffsol_error)?;
        let mut solver = problem.bdf::<NalgebraLU<f64>>().map_err(diffsol_error)?;
        step_to_outputs(&mut solver, t0, t_out)
    }
}

/// diffsol's error as the integrator's.
#[cfg(feature = "bdf")]
fn diffsol_error(e: diffsol::DiffsolError) -> SolveError {
    SolveError::Bdf(BdfError(e))
}

/// The states at the times `t_out` (increasing, all ≥ `t0`, the solver's start): steps
/// `solver` freely and interpolates each output time from the step that covers it.
/// (diffsol's `solve_dense` can panic when its internal time stops a rounding error short
/// of the last output time; stepping ourselves keeps that a plain error.)
#[cfg(feature = "bdf")]
fn step_to_outputs<'a, Eqn, S>(
    solver: &mut S,
    t0: f64,
    t_out: &[f64],
) -> Result<Vec<State>, SolveError>
where
    Eqn: diffsol::OdeEquations<T = f64, V = diffsol::NalgebraVec<f64>> + 'a,
    S: diffsol::OdeSolverMethod<'a, Eqn>,
{
    use diffsol::OdeSolverStopReason;
    let mut out = Vec::with_capacity(t_out.len());
    let Some(&t_end) = t_out.last() else {
        return Ok(out);
    };
    if t_out.windows(2).any(|w| w[1] < w[0]) || t_out[0] < t0 {
        return Err(SolveError::OutputTimesNotIncreasing);
    }
    if t_end > t0 {
        solver.set_stop_time(t_end).map_err(diffsol_error)?;
    }
    let mut k = 0;
    loop {
        let now = solver.state().t;
        while k < t_out.len() && t_out[k] <= now {
            out.push(if t_out[k] == now {
                read_state(solver.state().y)
            } else {
                read_state(&solver.interpolate(t_out[k]).map_err(diffsol_error)?)
            });
            k += 1;
        }
        if k == t_out.len() {
            return Ok(out);
        }
        if let OdeSolverStopReason::TstopReached = solver.step().map_err(diffsol_error)? {
            // Stopped at t_end, up to rounding: interpolate what lies inside the last
            // step; an output a rounding error beyond it is the final state.
            let now = solver.state().t;
            while k < t_out.len() && t_out[k] < now {
                out.push(read_state(
                    &solver.interpolate(t_out[k]).map_err(diffsol_error)?,
                ));
                k += 1;
            }
            let y = read_state(solver.state().y);
            out.extend(std::iter::repeat_n(y, t_out.len() - k));
            return Ok(out);
        }
    }
}

/// A diffsol state vector as a [`State`].
#[cfg(feature = "bdf")]
fn read_state(y: &diffsol::NalgebraVec<f64>) -> State {
    use diffsol::Vector;
    std::array::from_fn(|i| y.get_index(i))
}

#[cfg(feature = "bdf")]
fn to_state(x: &[f64]) -> State {
    std::array::from_fn(|i| x[i])
}

#[cfg(all(test, feature = "bdf"))]
mod tests {
    use super::*;

    #[test]
    fn many_short_intervals_match_the_exact_solution() {
        // Restarting every millisecond (as a sampled controller does) loses no accuracy.
        let rhs = |t: f64, x: &State| [-(x[0] - t.cos()), -50.0 * x[1], 0.0, 0.0];
        let solver = DiffsolBdf {
            tol: Tolerances {
                rtol: 1e-9,
                atol: [1e-12; 4],
            },
        };
        let ts = 1e-3;
        let mut x = [1.0, 1.0, 0.0, 0.0];
        for k in 0..3000 {
            let t = f64::from(k) * ts;
            x = solver.solve(&rhs, t, x, &[t + ts]).unwrap()[0];
        }
        let t: f64 = 3.0;
        let exact = 0.5 * (t.cos() + t.sin()) + 0.5 * (-t).exp();
        assert!((x[0] - exact).abs() < 1e-6, "{} vs {exact}", x[0]);
        assert!((x[1] - (-50.0 * t).exp()).abs() < 1e-6);
    }

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
