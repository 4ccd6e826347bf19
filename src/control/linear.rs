//! The motor linearised about a steady operating point, its frequency response from supply
//! pressure to speed (paper Fig. 16), and the fit of two first-order lags in series that the
//! paper suggests for controller design (§5.2).
//!
//! About a steady state (x₀, u₀) with f(x₀, u₀) = 0, where f is `Motor::derivatives`, x the
//! state [p_1, p_2, p_e, ω] and u the supply pressure at port 1 (Pa absolute):
//!
//! ```text
//! Δẋ = A·Δx + B·Δu + E·ΔT_load,   Δω = C·Δx,   C = [0 0 0 1]
//! ```
//!
//! A = ∂f/∂x and B = ∂f/∂u by central differences; E = [0 0 0 −1/J] (an extra load torque
//! acts on the torque balance only). The frequency response is
//! G(jω) = C·(jω·I − A)⁻¹·B in (rad/s)/Pa, solved as a complex 4×4 system per frequency.
//! The linearisation is meaningful only while the motor turns: at standstill the Coulomb
//! friction T_c·tanh(ω/ω_reg) has a slope of T_c/ω_reg that models the stuck rotor, not a
//! running one. [`operating_point`] refuses stalled or unstable points.

use super::ControlError;
use crate::model::motor::{idx, Boundary, Motor, State, N_STATES};
use crate::sim::steady;
use nalgebra::{Complex, Matrix4, Vector4};
use std::f64::consts::PI;

/// A steady operating point: the boundary and the state that balances it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OperatingPoint {
    /// The boundary (supply, exhaust, load).
    pub bc: Boundary,
    /// The steady state there.
    pub x: State,
}

impl OperatingPoint {
    /// Its speed, rad/s.
    pub fn speed_rad_s(&self) -> f64 {
        self.x[idx::OMEGA]
    }
}

/// Lowest speed at which the motor counts as running for linearisation, rad/s:
/// 50·ω_reg (so that the Coulomb friction is saturated, tanh(50) = 1) and at least 10 rad/s.
fn min_running_speed_rad_s(motor: &Motor) -> f64 {
    (50.0 * motor.params().w_reg()).max(10.0)
}

/// Steady state with free speed under `bc`, started from standstill (so that, where several
/// steady states exist, it is the one reached by starting the motor). Refuses a stalled
/// motor (speed below `min_running_speed_rad_s`).
pub fn operating_point(motor: &Motor, bc: &Boundary) -> Result<OperatingPoint, ControlError> {
    let x = steady::free(motor, bc, &steady::initial_guess(bc))?;
    let w = x[idx::OMEGA];
    let w_min = min_running_speed_rad_s(motor);
    if w.is_nan() || w < w_min {
        return Err(ControlError::Stalled {
            p_supply_mpa: bc.p_port1_pa / 1e6,
            speed_rpm: w / super::RAD_S_PER_RPM,
            min_rpm: w_min / super::RAD_S_PER_RPM,
        });
    }
    Ok(OperatingPoint { bc: *bc, x })
}

/// The linearised motor: Δẋ = A·Δx + B·Δp_supply + E·ΔT_load, Δω = Δx₃ (the speed).
#[derive(Debug, Clone, PartialEq)]
pub struct LinearModel {
    /// ∂f/∂x, 1/s (mixed units: Pa/s per Pa, Pa/s per rad/s, rad/s² per Pa, …).
    pub a: Matrix4<f64>,
    /// ∂f/∂p_supply: Pa/s per Pa for the pressures, rad/s² per Pa for the speed.
    pub b: Vector4<f64>,
    /// ∂f/∂T_load: rad/s² per N·m on the speed (−1/J), 0 on the pressures.
    pub e: Vector4<f64>,
    /// Where the motor is linearised.
    pub op: OperatingPoint,
}

/// Typical magnitude of each state, to size the difference steps.
const SCALE: State = [1e5, 1e5, 1e5, 100.0];
/// Relative step of the central differences.
const REL_STEP: f64 = 1e-5;

impl LinearModel {
    /// Linearises `motor` about `op` by central differences of `Motor::derivatives`.
    /// Refuses an operating point at which the linear model is unstable (a pole with a
    /// non-negative real part): the steady state is then not one the motor can run at.
    pub(crate) fn linearise(motor: &Motor, op: &OperatingPoint) -> Result<Self, ControlError> {
        let f = |x: &State, bc: &Boundary| motor.derivatives(x, bc);
        let mut a = Matrix4::zeros();
        for j in 0..N_STATES {
            let h = REL_STEP * op.x[j].abs().max(SCALE[j]);
            let (mut xp, mut xm) = (op.x, op.x);
            xp[j] += h;
            xm[j] -= h;
            let (fp, fm) = (f(&xp, &op.bc), f(&xm, &op.bc));
            for i in 0..N_STATES {
                a[(i, j)] = (fp[i] - fm[i]) / (2.0 * h);
            }
        }
        let h = REL_STEP * op.bc.p_port1_pa;
        let (mut bp, mut bm) = (op.bc, op.bc);
        bp.p_port1_pa += h;
        bm.p_port1_pa -= h;
        let (fp, fm) = (f(&op.x, &bp), f(&op.x, &bm));
        let b = Vector4::from_fn(|i, _| (fp[i] - fm[i]) / (2.0 * h));
        let e = Vector4::new(0.0, 0.0, 0.0, -1.0 / motor.params().inertia());
        let lin = Self { a, b, e, op: *op };
        if let Some(p) = lin.poles().iter().find(|p| p.re >= 0.0 || p.re.is_nan()) {
            return Err(ControlError::Unstable {
                p_supply_mpa: op.bc.p_port1_pa / 1e6,
                speed_rpm: op.speed_rad_s() / super::RAD_S_PER_RPM,
                re: p.re,
                im: p.im,
            });
        }
        Ok(lin)
    }

    /// Eigenvalues of A, 1/s, slowest first.
    pub fn poles(&self) -> Vec<Complex<f64>> {
        let mut p: Vec<Complex<f64>> = self.a.complex_eigenvalues().iter().copied().collect();
        p.sort_by(|x, y| x.norm().total_cmp(&y.norm()));
        p
    }

    /// Speed per supply pressure at angular frequency w (rad/s): G(jw), (rad/s)/Pa.
    pub fn speed_per_supply(&self, w_rad_s: f64) -> Complex<f64> {
        self.response(w_rad_s, &self.b)
    }

    /// Speed per extra load torque at angular frequency w: (rad/s)/(N·m).
    pub fn speed_per_load(&self, w_rad_s: f64) -> Complex<f64> {
        self.response(w_rad_s, &self.e)
    }

    fn response(&self, w: f64, input: &Vector4<f64>) -> Complex<f64> {
        let jw = Complex::new(0.0, w);
        let m = Matrix4::<Complex<f64>>::from_fn(|i, j| {
            let d = if i == j { jw } else { Complex::new(0.0, 0.0) };
            d - Complex::new(self.a[(i, j)], 0.0)
        });
        let rhs = input.map(|v| Complex::new(v, 0.0));
        match m.lu().solve(&rhs) {
            Some(x) => x[idx::OMEGA],
            None => Complex::new(f64::NAN, f64::NAN),
        }
    }

    /// Static gain −C·A⁻¹·B, (rad/s)/Pa.
    pub fn dc_gain(&self) -> f64 {
        self.speed_per_supply(0.0).re
    }

    /// Speed deviation after a supply step Δu at t = 0, from Δx(t) = A⁻¹(e^{At} − I)·B·Δu,
    /// rad/s, one value per time (s, ≥ 0).
    pub fn step_speed(&self, du_pa: f64, t_s: &[f64]) -> Vec<f64> {
        let Some(a_inv) = self.a.try_inverse() else {
            return vec![f64::NAN; t_s.len()];
        };
        let ab = a_inv * self.b * du_pa;
        t_s.iter()
            .map(|&t| {
                let dx = (self.a * t).exp() * ab - ab;
                dx[idx::OMEGA]
            })
            .collect()
    }
}

/// Log-spaced frequencies from f_min to f_max (both included), Hz.
pub(crate) fn log_grid(f_min: f64, f_max: f64, n: usize) -> Vec<f64> {
    let n = n.max(2);
    let (l0, l1) = (f_min.log10(), f_max.log10());
    (0..n)
        .map(|k| 10f64.powf(l0 + (l1 - l0) * k as f64 / (n - 1) as f64))
        .collect()
}

/// Phase in degrees, unwrapped along the list (no jumps of more than 180°), starting in
/// (−180°, 180°].
pub(crate) fn unwrapped_phase_deg(g: &[Complex<f64>]) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::with_capacity(g.len());
    for z in g {
        let mut p = z.arg().to_degrees();
        if let Some(prev) = out.last() {
            while p - prev > 180.0 {
                p -= 360.0;
            }
            while p - prev < -180.0 {
                p += 360.0;
            }
        }
        out.push(p);
    }
    out
}

/// K/((1 + s·T1)(1 + s·T2)), T1 ≥ T2: the paper's description of the motor for controller
/// design ("two first order systems in series", §5.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoLags {
    /// Static gain, in the units of the data fitted ((rad/s)/Pa for the motor).
    pub k: f64,
    /// Slow time constant T1, s.
    pub t1_s: f64,
    /// Fast time constant T2, s.
    pub t2_s: f64,
}

impl TwoLags {
    /// The response K/((1 + jωT1)(1 + jωT2)) at ω (rad/s).
    pub fn at(&self, w_rad_s: f64) -> Complex<f64> {
        let s = Complex::new(0.0, w_rad_s);
        Complex::new(self.k, 0.0) / ((s * self.t1_s + 1.0) * (s * self.t2_s + 1.0))
    }
}

/// Result of `fit_two_lags`, with the fit error over the fitted band.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LagFit {
    /// The fitted lags.
    pub lags: TwoLags,
    /// RMS magnitude error, dB.
    pub rms_mag_db: f64,
    /// Largest magnitude error, dB.
    pub max_mag_db: f64,
    /// RMS phase error, degrees.
    pub rms_phase_deg: f64,
    /// Largest phase error, degrees.
    pub max_phase_deg: f64,
}

/// Fits K/((1+sT1)(1+sT2)) to frequency-response data (w in rad/s, g complex) by
/// Levenberg–Marquardt on the complex log error ln(G_fit/G) (real part: log magnitude,
/// imaginary part: phase in radians; both weighted alike at every frequency), in the
/// parameters ln K, ln T1, ln T2. `guess` seeds the search (e.g. K = static gain, T from the
/// two slowest poles). The data must have a positive static gain (phase near 0 at low
/// frequency).
pub(crate) fn fit_two_lags(w_rad_s: &[f64], g: &[Complex<f64>], guess: TwoLags) -> LagFit {
    let resid = |th: &[f64; 3]| -> Vec<Complex<f64>> {
        let m = TwoLags {
            k: th[0].exp(),
            t1_s: th[1].exp(),
            t2_s: th[2].exp(),
        };
        w_rad_s
            .iter()
            .zip(g)
            .map(|(w, gi)| (m.at(*w) / gi).ln())
            .collect()
    };
    let cost = |r: &[Complex<f64>]| r.iter().map(|z| z.norm_sqr()).sum::<f64>();
    let mut th = [guess.k.ln(), guess.t1_s.ln(), guess.t2_s.ln()];
    let mut r = resid(&th);
    let mut c = cost(&r);
    let mut lambda = 1e-3;
    for _ in 0..200 {
        let (jtj, jtr) = normal_equations(w_rad_s, &r, &th);
        let mut improved = false;
        while lambda < 1e12 {
            let mut m = jtj;
            for a in 0..3 {
                m[(a, a)] += lambda * jtj[(a, a)].max(1e-12);
            }
            let Some(step) = m.lu().solve(&(-jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let cand = [th[0] + step[0], th[1] + step[1], th[2] + step[2]];
            let rc = resid(&cand);
            let cc = cost(&rc);
            if cc.is_finite() && cc < c {
                let done = (c - cc) <= 1e-14 * c.max(1e-300) || step.norm() < 1e-12;
                th = cand;
                r = rc;
                c = cc;
                lambda = (lambda * 0.3).max(1e-9);
                improved = !done;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    let (t1, t2) = (th[1].exp(), th[2].exp());
    let lags = TwoLags {
        k: th[0].exp(),
        t1_s: t1.max(t2),
        t2_s: t1.min(t2),
    };
    let n = r.len().max(1) as f64;
    let db = |z: &Complex<f64>| 20.0 * z.re / std::f64::consts::LN_10;
    LagFit {
        lags,
        rms_mag_db: (r.iter().map(|z| db(z).powi(2)).sum::<f64>() / n).sqrt(),
        max_mag_db: r.iter().map(|z| db(z).abs()).fold(0.0, f64::max),
        rms_phase_deg: (r.iter().map(|z| z.im.to_degrees().powi(2)).sum::<f64>() / n).sqrt(),
        max_phase_deg: r
            .iter()
            .map(|z| z.im.to_degrees().abs())
            .fold(0.0, f64::max),
    }
}

/// JᵀJ and Jᵀr of the complex log residuals `r` at parameters `th` = (ln K, ln T1, ln T2),
/// real and imaginary parts as separate rows, with the analytic Jacobian of ln G_fit:
/// d/dlnK = 1, d/dlnT = −jωT/(1 + jωT).
fn normal_equations(
    w_rad_s: &[f64],
    r: &[Complex<f64>],
    th: &[f64; 3],
) -> (nalgebra::Matrix3<f64>, nalgebra::Vector3<f64>) {
    let mut jtj = nalgebra::Matrix3::<f64>::zeros();
    let mut jtr = nalgebra::Vector3::<f64>::zeros();
    for (w, ri) in w_rad_s.iter().zip(r) {
        let d = |lnt: f64| {
            let jwt = Complex::new(0.0, w * lnt.exp());
            -jwt / (jwt + 1.0)
        };
        let cols = [Complex::new(1.0, 0.0), d(th[1]), d(th[2])];
        for a in 0..3 {
            jtr[a] += cols[a].re * ri.re + cols[a].im * ri.im;
            for b in 0..3 {
                jtj[(a, b)] += cols[a].re * cols[b].re + cols[a].im * cols[b].im;
            }
        }
    }
    (jtj, jtr)
}

/// A start for [`fit_two_lags`] from the model: K = static gain, T1 and T2 = 1/|λ| of the two
/// slowest poles.
pub(crate) fn two_lag_guess(lin: &LinearModel) -> TwoLags {
    let p = lin.poles();
    let t = |k: usize| p.get(k).map_or(1e-3, |z| 1.0 / z.norm().max(1e-9));
    TwoLags {
        k: lin.dc_gain(),
        t1_s: t(0),
        t2_s: t(1),
    }
}

/// Angular frequency of a frequency in Hz.
pub fn rad_s(f_hz: f64) -> f64 {
    2.0 * PI * f_hz
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::motor::Load;
    use crate::numerics::ode::{StiffSolver, Tolerances};
    use crate::numerics::DefaultSolver;

    fn default_point(p_supply_pa: f64) -> (Motor, OperatingPoint) {
        let m = Motor::default_motor();
        let bc = Boundary::supplied(
            p_supply_pa,
            101_325.0,
            Load::ViscousBrake { c_nm_s_rad: 1e-4 },
        );
        let op = operating_point(&m, &bc).unwrap();
        (m, op)
    }

    /// The linear model's step response matches the nonlinear model's response to a small
    /// supply step, integrated by the stiff solver from the same steady state.
    #[test]
    fn linearisation_matches_nonlinear_small_step() {
        let (m, op) = default_point(3.5e5);
        let lin = LinearModel::linearise(&m, &op).unwrap();
        let du = 500.0; // Pa, 0.14 % of the supply
        let mut bc = op.bc;
        bc.p_port1_pa += du;
        let t: Vec<f64> = [0.002, 0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0].to_vec();
        let solver = DefaultSolver {
            tol: Tolerances {
                rtol: 1e-10,
                atol: [1e-4, 1e-4, 1e-4, 1e-7],
            },
        };
        let rhs = |_t: f64, x: &State| m.derivatives(x, &bc);
        let xs = solver.solve(&rhs, 0.0, op.x, &t).unwrap();
        let lin_dw = lin.step_speed(du, &t);
        let final_dw = lin.dc_gain() * du;
        assert!(final_dw > 0.0, "more pressure, more speed: {final_dw}");
        for ((ti, x), l) in t.iter().zip(&xs).zip(&lin_dw) {
            let nl = x[idx::OMEGA] - op.speed_rad_s();
            assert!(
                (nl - l).abs() < 0.02 * final_dw,
                "t = {ti}: nonlinear {nl:.5} vs linear {l:.5} rad/s (final {final_dw:.4})"
            );
        }
        // The response has settled by the last time (≈ 10 T1) and agrees with the static gain.
        let nl_end = xs.last().unwrap()[idx::OMEGA] - op.speed_rad_s();
        assert!((nl_end - final_dw).abs() < 0.02 * final_dw);
    }

    #[test]
    fn frequency_response_starts_at_static_gain_and_falls() {
        let (m, op) = default_point(3.5e5);
        let lin = LinearModel::linearise(&m, &op).unwrap();
        let g0 = lin.speed_per_supply(0.0);
        assert!(g0.im.abs() < 1e-12 * g0.re.abs());
        let g_low = lin.speed_per_supply(1e-4);
        assert!((g_low - g0).norm() < 1e-3 * g0.norm());
        let g_hi = lin.speed_per_supply(rad_s(1e3));
        assert!(g_hi.norm() < 1e-3 * g0.norm());
    }

    #[test]
    fn two_lag_fit_recovers_known_lags() {
        let truth = TwoLags {
            k: 3.0e-3,
            t1_s: 0.4,
            t2_s: 0.01,
        };
        let w: Vec<f64> = log_grid(0.01, 100.0, 60).into_iter().map(rad_s).collect();
        let g: Vec<Complex<f64>> = w.iter().map(|w| truth.at(*w)).collect();
        let fit = fit_two_lags(
            &w,
            &g,
            TwoLags {
                k: 1e-3,
                t1_s: 0.05,
                t2_s: 0.05,
            },
        );
        assert!((fit.lags.k / truth.k - 1.0).abs() < 1e-6, "{fit:?}");
        assert!((fit.lags.t1_s / truth.t1_s - 1.0).abs() < 1e-6, "{fit:?}");
        assert!((fit.lags.t2_s / truth.t2_s - 1.0).abs() < 1e-6, "{fit:?}");
        assert!(fit.rms_mag_db < 1e-6 && fit.max_phase_deg < 1e-6);
    }

    #[test]
    fn stalled_operating_point_is_refused() {
        let m = Motor::default_motor();
        // Barely above atmosphere: the motor cannot overcome Coulomb friction.
        let bc = Boundary::supplied(1.05e5, 101_325.0, Load::ViscousBrake { c_nm_s_rad: 1e-4 });
        let e = operating_point(&m, &bc).unwrap_err();
        assert!(e.to_string().contains("stalled"), "{e}");
    }
}
