//! PI design from the linearised motor and the valve (paper §5.2, Fig. 17: "the frequency
//! response of the valve and the motor … was used for the design of a PI-controller").
//!
//! Open loop, in the controller's units (speed unit per V, see `closed_loop`):
//!
//! ```text
//! P(jw) = V(jw)·G(jw)·e^{−jw·T_s/2} / ω_unit,   L(jw) = C(jw)·P(jw),
//! C(jw) = K_p + K_i/(jw)
//! ```
//!
//! with V the valve (Pa/V), G the linearised motor ((rad/s)/Pa, `linear`), the half-sample
//! delay of the zero-order hold and ω_unit the speed unit in rad/s.
//!
//! Design for a crossover w_c and phase margin φ_m: the PI must add the phase
//! φ_C = −180° + φ_m − arg P(jw_c), which a PI can do only for −90° < φ_C < 0°; then
//! T_i = 1/(w_c·tan(−φ_C)), K_p = 1/(|P(jw_c)|·√(1 + 1/(w_c·T_i)²)), K_i = K_p/T_i.
//! Design for a phase margin alone: w_c is the frequency where arg P = −180° + φ_m + 15°,
//! i.e. the PI is allowed 15° of phase lag at crossover (T_i ≈ 3.7/w_c), the usual rule.

use super::closed_loop::{PiController, Valve};
use super::linear::LinearModel;
use super::ControlError;
use nalgebra::Complex;

/// Plant seen by the controller, speed unit per V (see module doc).
pub fn plant(lin: &LinearModel, valve: &Valve, pi: &PiController, w_rad_s: f64) -> Complex<f64> {
    let delay = Complex::from_polar(1.0, -w_rad_s * pi.ts_s / 2.0);
    valve.response(w_rad_s) * lin.speed_per_supply(w_rad_s) * delay / pi.speed_unit_rad_s()
}

/// Open-loop L(jw) = C(jw)·P(jw).
pub(crate) fn open_loop(
    lin: &LinearModel,
    valve: &Valve,
    pi: &PiController,
    w_rad_s: f64,
) -> Complex<f64> {
    pi.response(w_rad_s) * plant(lin, valve, pi, w_rad_s)
}

/// Stability margins of the loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Margins {
    /// Gain crossover |L| = 1, rad/s (NaN if none in the searched band).
    pub crossover_rad_s: f64,
    /// 180° + arg L at crossover, degrees.
    pub phase_margin_deg: f64,
    /// Phase crossover arg L = −180°, rad/s (NaN if none in the band).
    phase_crossover_rad_s: f64,
    /// −20·log10|L| at the phase crossover, dB (+∞ if none).
    pub gain_margin_db: f64,
}

/// Unwrapped phase of `f` along a log grid of `w` (radians), starting in (−π, π].
fn unwrapped(f: &dyn Fn(f64) -> Complex<f64>, w: &[f64]) -> Vec<f64> {
    let g: Vec<Complex<f64>> = w.iter().map(|w| f(*w)).collect();
    super::linear::unwrapped_phase_deg(&g)
        .into_iter()
        .map(f64::to_radians)
        .collect()
}

/// Band searched for crossovers, rad/s.
const W_LO: f64 = 1e-3;
const W_HI: f64 = 1e5;
const N_GRID: usize = 800;

/// Gain and phase margins of C·P over 1e-3..1e5 rad/s (the first crossings from below).
pub fn margins(lin: &LinearModel, valve: &Valve, pi: &PiController) -> Margins {
    let w = super::linear::log_grid(W_LO, W_HI, N_GRID);
    let l = |w: f64| open_loop(lin, valve, pi, w);
    let mag: Vec<f64> = w.iter().map(|w| l(*w).norm().ln()).collect();
    let ph = unwrapped(&l, &w);
    let crossing = |y: &[f64], level: f64| -> Option<(usize, f64)> {
        (1..y.len())
            .find(|&k| (y[k - 1] - level) * (y[k] - level) <= 0.0 && y[k - 1] != y[k])
            .map(|k| (k, (level - y[k - 1]) / (y[k] - y[k - 1])))
    };
    let interp = |v: &[f64], k: usize, f: f64| v[k - 1] + f * (v[k] - v[k - 1]);
    let lw: Vec<f64> = w.iter().map(|w| w.ln()).collect();
    let (wc, pm) = match crossing(&mag, 0.0) {
        Some((k, f)) => (
            interp(&lw, k, f).exp(),
            180.0 + interp(&ph, k, f).to_degrees(),
        ),
        None => (f64::NAN, f64::NAN),
    };
    let (wp, gm) = match crossing(&ph, -std::f64::consts::PI) {
        Some((k, f)) => (
            interp(&lw, k, f).exp(),
            -20.0 * interp(&mag, k, f) / std::f64::consts::LN_10,
        ),
        None => (f64::NAN, f64::INFINITY),
    };
    Margins {
        crossover_rad_s: wc,
        phase_margin_deg: pm,
        phase_crossover_rad_s: wp,
        gain_margin_db: gm,
    }
}

/// What the design asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Target {
    /// Phase margin only (degrees); the crossover follows from the 15° rule.
    PhaseMargin {
        /// Phase margin, degrees.
        pm_deg: f64,
    },
    /// Crossover frequency (rad/s) and phase margin (degrees).
    Bandwidth {
        /// Crossover, rad/s.
        crossover_rad_s: f64,
        /// Phase margin, degrees.
        pm_deg: f64,
    },
}

/// Phase lag the PI may add at crossover when only a phase margin is asked for, degrees.
const PI_LAG_DEG: f64 = 15.0;

/// PI gains for `target` on the loop of `lin` and `valve`; `base` gives the sample time,
/// speed unit, limits and anti-windup that are kept.
pub fn design_pi(
    lin: &LinearModel,
    valve: &Valve,
    base: &PiController,
    target: Target,
) -> Result<PiController, ControlError> {
    let p = |w: f64| plant(lin, valve, base, w);
    let (wc, pm) = match target {
        Target::Bandwidth {
            crossover_rad_s,
            pm_deg,
        } => (crossover_rad_s, pm_deg),
        Target::PhaseMargin { pm_deg } => {
            let goal = (-180.0 + pm_deg + PI_LAG_DEG).to_radians();
            let w = super::linear::log_grid(W_LO, W_HI, N_GRID);
            let ph = unwrapped(&p, &w);
            let k = (1..ph.len())
                .find(|&k| ph[k - 1] >= goal && ph[k] < goal)
                .ok_or_else(|| ControlError::NoPhaseCrossing {
                    goal_deg: goal.to_degrees(),
                    pm_deg,
                })?;
            // Refine by bisection in log w on the (continuous) phase near the grid crossing.
            let (mut a, mut b) = (w[k - 1].ln(), w[k].ln());
            let ph_at = |lw: f64| {
                let z = p(lw.exp());
                let mut v = z.arg();
                while v - ph[k - 1] > std::f64::consts::PI {
                    v -= 2.0 * std::f64::consts::PI;
                }
                while v - ph[k - 1] < -std::f64::consts::PI {
                    v += 2.0 * std::f64::consts::PI;
                }
                v
            };
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if ph_at(m) >= goal {
                    a = m;
                } else {
                    b = m;
                }
            }
            ((0.5 * (a + b)).exp(), pm_deg)
        }
    };
    if !(wc > 0.0 && wc.is_finite() && pm > 0.0 && pm < 90.0) {
        return Err(ControlError::BadTarget {
            crossover_rad_s: wc,
            pm_deg: pm,
        });
    }
    // Phase of P at wc, unwrapped from low frequency.
    let w = super::linear::log_grid(W_LO.min(wc / 10.0), wc, 400);
    let theta = *unwrapped(&p, &w).last().expect("grid not empty");
    let phi_c = (-180.0 + pm).to_radians() - theta;
    if phi_c >= 0.0 {
        return Err(ControlError::NeedsLead {
            pm_deg: pm,
            crossover_rad_s: wc,
            phase_deg: theta.to_degrees(),
        });
    }
    if phi_c <= -std::f64::consts::FRAC_PI_2 {
        return Err(ControlError::NeedsTooMuchLag {
            pm_deg: pm,
            crossover_rad_s: wc,
            phase_deg: theta.to_degrees(),
        });
    }
    let ti = 1.0 / (wc * (-phi_c).tan());
    let kp = 1.0 / (p(wc).norm() * (1.0 + 1.0 / (wc * ti).powi(2)).sqrt());
    Ok(PiController {
        kp,
        ki: kp / ti,
        ..*base
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::closed_loop::{step_metrics, Loop, Scenario, Steps};
    use crate::control::linear::operating_point;
    use crate::control::RAD_S_PER_RPM;
    use crate::model::motor::{idx, Boundary, Load, Motor};
    use crate::numerics::DefaultSolver;

    const P_ATM: f64 = 101_325.0;

    fn setup() -> (Motor, LinearModel, Valve) {
        let m = Motor::default_motor();
        let load = Load::ViscousBrake { c_nm_s_rad: 1e-4 };
        let op = operating_point(&m, &Boundary::supplied(3.5e5, P_ATM, load)).unwrap();
        let lin = LinearModel::linearise(&m, &op).unwrap();
        let valve = Valve::for_motor(&m, P_ATM);
        (m, lin, valve)
    }

    #[test]
    fn designed_gains_meet_the_requested_margins() {
        let (_, lin, valve) = setup();
        let base = PiController::default();
        for pm in [35.0, 50.0, 65.0] {
            let pi = design_pi(&lin, &valve, &base, Target::PhaseMargin { pm_deg: pm }).unwrap();
            let mg = margins(&lin, &valve, &pi);
            assert!((mg.phase_margin_deg - pm).abs() < 0.5, "{pm}: {mg:?}");
        }
        let wc = 5.0;
        let pi = design_pi(
            &lin,
            &valve,
            &base,
            Target::Bandwidth {
                crossover_rad_s: wc,
                pm_deg: 60.0,
            },
        )
        .unwrap();
        let mg = margins(&lin, &valve, &pi);
        assert!((mg.crossover_rad_s / wc - 1.0).abs() < 0.01, "{mg:?}");
        assert!((mg.phase_margin_deg - 60.0).abs() < 0.5, "{mg:?}");
        // A crossover beyond the valve's reach cannot be had with a PI.
        let e = design_pi(
            &lin,
            &valve,
            &base,
            Target::Bandwidth {
                crossover_rad_s: 200.0,
                pm_deg: 60.0,
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("cannot"), "{e}");
    }

    /// The closed-loop simulation of the nonlinear motor confirms the design: a larger phase
    /// margin gives a smaller overshoot, and both settle on the set-point.
    #[test]
    fn closed_loop_simulation_confirms_the_design() {
        let (m, lin, valve) = setup();
        let w0 = lin.op.x[idx::OMEGA];
        let sim = |pm: f64| {
            let pi = design_pi(
                &lin,
                &valve,
                &PiController::default(),
                Target::PhaseMargin { pm_deg: pm },
            )
            .unwrap();
            let lp = Loop {
                valve,
                pi,
                load: lin.op.bc.load,
            };
            let start = lp.settled_at(&m, w0).unwrap();
            let to = w0 + 300.0 * RAD_S_PER_RPM;
            let sc = Scenario {
                duration_s: 5.0,
                setpoint_rad_s: Steps::step(w0, 0.1, to),
                load_torque_nm: Steps::constant(0.0),
            };
            let tr = lp
                .simulate(&m, &DefaultSolver::default(), &sc, &start)
                .unwrap();
            step_metrics(&tr, 0.1, w0, to)
        };
        let low = sim(30.0);
        let high = sim(65.0);
        assert!(
            low.overshoot_pct > high.overshoot_pct + 10.0,
            "{low:?} vs {high:?}"
        );
        assert!(high.overshoot_pct < 12.0, "{high:?}");
        for s in [low, high] {
            assert!(s.final_error_rad_s.abs() < 1.0, "{s:?}");
        }
    }
}
