//! Steady states: pseudo-transient continuation with the TR-BDF2 integrator (robust from any
//! start, follows the physical branch, e.g. standstill when the motor cannot turn), then a
//! damped Newton polish on f(y) = 0 with a finite-difference Jacobian.

use super::ode::{fd_jacobian, State, Tolerances, TrBdf2};
use nalgebra::Vector4;

const SCALE: State = [1e5, 1e5, 1e5, 1.0];

/// Residual norm: each rate of change relative to its state's size, 1/s.
fn residual_norm(g: &State, y: &State) -> f64 {
    (0..4)
        .map(|i| (g[i] / (y[i].abs() + SCALE[i])).abs())
        .fold(0.0, f64::max)
}

/// Steady state of dy/dt = f(y) reached from y0. With `hold_speed` the speed stays `y0[3]`
/// (f must then return dω/dt = 0) and only the pressures settle.
pub fn steady_state(
    f: impl Fn(&State) -> State,
    y0: &State,
    hold_speed: bool,
) -> Result<State, String> {
    let mut integ = TrBdf2::new(|_t: f64, y: &State| f(y), Tolerances::default());
    integ.h_max_s = 2.0;
    let mut y = *y0;
    let mut t_s = 0.0;
    while t_s < 200.0 && residual_norm(&f(&y), &y) > 1e-7 {
        y = integ.advance(t_s, &y, t_s + 2.0)?;
        t_s += 2.0;
    }
    let resid = |y: &State| {
        let mut g = f(y);
        if hold_speed {
            g[3] = y[3] - y0[3];
        }
        g
    };
    newton_polish(resid, y)
}

/// Damped Newton on g(y) = 0 until the correction is below 1e-12 of each state's size.
fn newton_polish(g: impl Fn(&State) -> State, mut y: State) -> Result<State, String> {
    for _ in 0..40 {
        let gy = g(&y);
        let jac = fd_jacobian(&g, &y, &gy);
        let dy = jac
            .lu()
            .solve(&Vector4::from_column_slice(&gy))
            .ok_or("steady state: singular Jacobian")?;
        let r0 = residual_norm(&gy, &y);
        let mut lambda = 1.0;
        let mut y_new = y;
        for _ in 0..30 {
            y_new = std::array::from_fn(|i| y[i] - lambda * dy[i]);
            if residual_norm(&g(&y_new), &y_new) <= r0 {
                break;
            }
            lambda *= 0.5;
        }
        y = y_new;
        let small = (0..4).all(|i| dy[i].abs() <= 1e-12 * (y[i].abs() + SCALE[i]));
        if small {
            return Ok(y);
        }
    }
    let r = residual_norm(&g(&y), &y);
    if r < 1e-9 {
        Ok(y)
    } else {
        Err(format!(
            "steady state: Newton did not converge (residual {r:e} 1/s)"
        ))
    }
}
