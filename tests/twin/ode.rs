//! The twin's own integrator: TR-BDF2 (Bank et al. 1985, in the Hosea–Shampine 1996 form),
//! an L-stable, stiffly accurate, second-order one-step method with an embedded third-order
//! error estimate, adaptive steps, a finite-difference 4×4 Jacobian and simplified Newton.
//! (vanefit itself uses Rodas4/BDF: a different method on purpose.)
//!
//! With γ = 2 − √2, d = γ/2, w = √2/4, one step of size h from (t, y):
//!
//!   z   = y + d·h·(f(t, y) + f(t + γh, z))                       trapezoidal stage
//!   y⁺  = y + h·(w·f(t, y) + w·f(t + γh, z) + d·f(t + h, y⁺))      BDF2 stage
//!   err = (I − d·h·J)⁻¹ · h·((4w − 1)/3·f₀ − 1/3·f_z + 2d/3·f₊)    (Shampine's filtered
//!         difference to the third-order weights ((1 − w)/3, (3w + 1)/3, d/3))
//!
//! Both implicit stages share the iteration matrix I − d·h·J.

use nalgebra::{Matrix4, Vector4};

/// State vector [p_1, p_2, p_e, ω] (Pa, Pa, Pa, rad/s).
pub type State = [f64; 4];

const SQRT2: f64 = std::f64::consts::SQRT_2;
const GAMMA: f64 = 2.0 - SQRT2;
const D: f64 = GAMMA / 2.0;
const W: f64 = SQRT2 / 4.0;

/// Error tolerances: a component's error is weighed by atol_i + rtol·|y_i|.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Relative tolerance, 1.
    pub rtol: f64,
    /// Absolute tolerances in the state's units (Pa, Pa, Pa, rad/s).
    pub atol: State,
}

impl Default for Tolerances {
    /// rtol 1e-8, 1e-3 Pa, 1e-6 rad/s: errors far below any sensor's noise.
    fn default() -> Self {
        Self {
            rtol: 1e-8,
            atol: [1e-3, 1e-3, 1e-3, 1e-6],
        }
    }
}

/// Typical magnitudes of the state (for finite-difference increments), Pa and rad/s.
const STATE_SCALE: State = [1e5, 1e5, 1e5, 1.0];

/// An adaptive TR-BDF2 integrator of dy/dt = f(t, y).
pub struct TrBdf2<F: Fn(f64, &State) -> State> {
    f: F,
    tol: Tolerances,
    h_s: f64,
    /// Largest step, s.
    pub h_max_s: f64,
    /// Accepted and rejected steps so far.
    pub steps: (usize, usize),
}

fn to_vec(y: &State) -> Vector4<f64> {
    Vector4::from_column_slice(y)
}

fn to_arr(v: &Vector4<f64>) -> State {
    [v[0], v[1], v[2], v[3]]
}

/// Forward-difference Jacobian ∂f/∂y at (t, y), given f₀ = f(t, y).
pub fn fd_jacobian(f: impl Fn(&State) -> State, y: &State, f0: &State) -> Matrix4<f64> {
    let mut jac = Matrix4::zeros();
    for j in 0..4 {
        let dy = f64::EPSILON.sqrt() * y[j].abs().max(STATE_SCALE[j]);
        let mut yp = *y;
        yp[j] += dy;
        let fp = f(&yp);
        for i in 0..4 {
            jac[(i, j)] = (fp[i] - f0[i]) / dy;
        }
    }
    jac
}

impl<F: Fn(f64, &State) -> State> TrBdf2<F> {
    /// An integrator of dy/dt = f(t, y) with these tolerances.
    pub fn new(f: F, tol: Tolerances) -> Self {
        Self {
            f,
            tol,
            h_s: 1e-5,
            h_max_s: 1.0,
            steps: (0, 0),
        }
    }

    fn weights(&self, a: &State, b: &State) -> State {
        std::array::from_fn(|i| self.tol.atol[i] + self.tol.rtol * a[i].abs().max(b[i].abs()))
    }

    fn norm(v: &Vector4<f64>, wt: &State) -> f64 {
        (0..4).map(|i| (v[i] / wt[i]).abs()).fold(0.0, f64::max)
    }

    /// Solves x = base + d·h·f(t, x) by simplified Newton with the factored I − d·h·J.
    fn solve_stage(
        &self,
        lu: &nalgebra::LU<f64, nalgebra::U4, nalgebra::U4>,
        t: f64,
        dh: f64,
        base: &Vector4<f64>,
        guess: Vector4<f64>,
        wt: &State,
    ) -> Option<(Vector4<f64>, Vector4<f64>)> {
        let mut x = guess;
        let mut last = f64::INFINITY;
        for _ in 0..12 {
            let fx = to_vec(&(self.f)(t, &to_arr(&x)));
            let resid = x - base - fx * dh;
            let dx = lu.solve(&resid)?;
            x -= dx;
            let size = Self::norm(&dx, wt);
            if !size.is_finite() || size > 2.0 * last {
                return None;
            }
            if size < 1e-3 || (size < 1e-1 && size * size / last < 1e-3) {
                let fx = to_vec(&(self.f)(t, &to_arr(&x)));
                return Some((x, fx));
            }
            last = size;
        }
        None
    }

    /// One TR-BDF2 step of size h from (t, y): the new state, f there, and the scaled error.
    fn step(&self, t: f64, y: &State, f0: &State, h: f64) -> Option<(State, f64)> {
        let jac = fd_jacobian(|x| (self.f)(t, x), y, f0);
        let lu = (Matrix4::identity() - jac * (D * h)).lu();
        let (y0, f0v) = (to_vec(y), to_vec(f0));
        let wt = self.weights(y, y);
        let base_z = y0 + f0v * (D * h);
        let (z, fz) = self.solve_stage(
            &lu,
            t + GAMMA * h,
            D * h,
            &base_z,
            y0 + f0v * (GAMMA * h),
            &wt,
        )?;
        let base_y = y0 + (f0v + fz) * (W * h);
        let guess = z + fz * ((1.0 - GAMMA) * h);
        let (y1, f1) = self.solve_stage(&lu, t + h, D * h, &base_y, guess, &wt)?;
        let diff = (f0v * ((4.0 * W - 1.0) / 3.0) - fz / 3.0 + f1 * (2.0 * D / 3.0)) * h;
        let est = lu.solve(&diff)?;
        let y1 = to_arr(&y1);
        let err = Self::norm(&est, &self.weights(y, &y1));
        err.is_finite().then_some((y1, err))
    }

    /// Integrates from (t0, y0) to t1 and returns y(t1).
    pub fn advance(&mut self, t0: f64, y0: &State, t1: f64) -> Result<State, String> {
        let (mut t, mut y) = (t0, *y0);
        while t < t1 {
            let last = self.h_s.min(self.h_max_s) >= t1 - t;
            let h = if last {
                t1 - t
            } else {
                self.h_s.min(self.h_max_s)
            };
            let f0 = (self.f)(t, &y);
            match self.step(t, &y, &f0, h) {
                Some((y1, err)) if err <= 1.0 => {
                    (t, y) = if last { (t1, y1) } else { (t + h, y1) };
                    self.steps.0 += 1;
                    let grow = (0.9 * err.max(1e-10).powf(-1.0 / 3.0)).clamp(0.2, 4.0);
                    self.h_s = if last {
                        self.h_s.max(h * grow)
                    } else {
                        h * grow
                    };
                }
                Some((_, err)) => {
                    self.steps.1 += 1;
                    self.h_s = h * (0.9 * err.powf(-1.0 / 3.0)).clamp(0.1, 0.5);
                }
                None => {
                    self.steps.1 += 1;
                    self.h_s = h * 0.25;
                }
            }
            if self.h_s < 1e-14 * t1.abs().max(1.0) {
                return Err(format!("TR-BDF2: step size underflow at t = {t} s"));
            }
        }
        Ok(y)
    }
}
