//! The electro-pneumatic speed control loop of paper §5.2 (Figs. 17–20): a pressure control
//! valve feeding port 1, the motor, a speed pick-up and a digital PI controller.
//!
//! ## Valve
//! The command u (V) is saturated to [0, u_max] and asks for the gauge pressure
//! p_cmd = p_atm + u·p_max,g/u_max (default 0–10 V → 0–6 bar gauge, Festo MPPE-3-1/8 of the
//! paper's appendix). The valve is an ideal pressure source (its flow capacity is not
//! limiting) whose output pressure p_v follows p_cmd
//! * by default through a first-order lag, τ·ṗ_v = p_cmd − p_v ("a simple first-order model",
//!   §5.2), τ = `valve_tau` (0.05 s unless the fit file says otherwise);
//! * with the `valve_dynamics` effect on, through a second-order lag
//!   τ²·p̈_v + 2ζτ·ṗ_v + p_v = p_cmd, τ = `valve_tau`, ζ = `valve_zeta`.
//!
//! The motor sees p_port1 = max(p_v, p_atm) (the valve exhausts to atmosphere, it cannot
//! make vacuum).
//!
//! ## Controller
//! Discrete PI with sample time T_s (default 1 ms) and zero-order hold. At t_k the pick-up
//! gives ω_k (ideal, no lag); with e_k = (ω_ref,k − ω_k)/ω_unit,
//!
//! ```text
//! v_k = K_p·e_k + I_k,   u_k = sat(v_k) ∈ [u_min, u_max],
//! I_{k+1} = I_k + K_i·T_s·e_k                       (integral by forward Euler)
//! ```
//!
//! which is G(s) = K_p + K_i/s = (K_p·s + K_i)/s; the paper's controller
//! (0.85·s + 4)/s is K_p = 0.85, K_i = 4 1/s.
//!
//! **Units.** ω_unit = 1000 rpm: the error is in krpm and the command in V, so K_p is in
//! V/krpm and K_i in V/(krpm·s). This is the same as a speed pick-up scaled to 1 V per
//! 1000 rpm (10 V at 10 000 rpm, the motor's range, like the valve's 0–10 V) feeding a
//! controller whose input and output are both volts. With this scaling the paper's gains
//! give a sensible loop on the default motor at the paper's 0.35 MPa operating point: the
//! plant valve + motor has a static gain of ≈ 1 krpm/V and a dominant lag of ≈ 0.9 s, so the
//! loop crosses over near 2 rad/s with ≈ 45–50° phase margin (see `design::margins`). With
//! the error in rad/s the same gains would give a hundred times the loop gain and an
//! unstable loop with the 50 ms valve; in rpm a thousand times.
//!
//! **Anti-windup.** When v_k is outside [u_min, u_max]:
//! * `Conditional` (clamping, the default): the integral is frozen while the error would
//!   drive the saturated command further out (e > 0 at u_max, e < 0 at u_min);
//! * `BackCalculation`: I_{k+1} = I_k + T_s·(K_i·e_k + (u_k − v_k)/T_t), tracking time
//!   T_t = T_i = K_p/K_i;
//! * `None`: plain integration (for comparison).
//!
//! The motor ODE keeps its four states: within a sample interval the command is constant,
//! so the valve pressure is a known function of time (an exponential, or the 2×2 matrix
//! exponential for the second-order valve); the motor is integrated sample to sample by the
//! stiff solver, the state carried across.

use super::error::UnknownAntiWindup;
use super::{ControlError, RAD_S_PER_RPM};
use crate::model::motor::{idx, Boundary, Load, Motor, State};
use crate::numerics::ode::StiffSolver;
use crate::sim::steady;
use nalgebra::{Complex, Matrix2, Vector2};

/// How the valve's output pressure follows its set pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ValveDynamics {
    /// τ·ṗ + p = p_cmd.
    FirstOrder {
        /// Time constant τ, s.
        tau_s: f64,
    },
    /// τ²·p̈ + 2ζτ·ṗ + p = p_cmd.
    SecondOrder {
        /// Time constant τ = 1/ω_n, s.
        tau_s: f64,
        /// Damping ratio ζ.
        zeta: f64,
    },
}

/// The electro-pneumatic pressure control valve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Valve {
    /// How the output pressure follows the set pressure.
    pub(crate) dynamics: ValveDynamics,
    /// Command for full pressure, V (default 10).
    pub u_max_v: f64,
    /// Gauge pressure at full command, Pa (default 6 bar).
    pub(crate) p_max_gauge_pa: f64,
    /// Atmosphere, Pa.
    pub p_atm_pa: f64,
}

/// Output pressure and its rate, Pa and Pa/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ValveState {
    /// Output pressure, Pa absolute.
    pub p_pa: f64,
    /// Its rate, Pa/s.
    dp_pa_s: f64,
}

impl Valve {
    /// The valve that the motor's model implies: second order with `valve_tau` and
    /// `valve_zeta` when the `valve_dynamics` effect is on, otherwise first order with
    /// `valve_tau` (default 0.05 s); 0–10 V → 0–6 bar gauge.
    pub(crate) fn for_motor(motor: &Motor, p_atm_pa: f64) -> Self {
        let valve = motor.supply_valve();
        let dynamics = match valve.zeta {
            Some(zeta) => ValveDynamics::SecondOrder {
                tau_s: valve.tau_s,
                zeta,
            },
            None => ValveDynamics::FirstOrder { tau_s: valve.tau_s },
        };
        Self {
            dynamics,
            u_max_v: 10.0,
            p_max_gauge_pa: 6e5,
            p_atm_pa,
        }
    }

    /// Static gain, Pa per V.
    fn gain_pa_per_v(&self) -> f64 {
        self.p_max_gauge_pa / self.u_max_v
    }

    /// Set pressure (absolute, Pa) for command u (V), saturated to [0, u_max].
    pub(crate) fn set_pressure_pa(&self, u_v: f64) -> f64 {
        self.p_atm_pa + self.gain_pa_per_v() * u_v.clamp(0.0, self.u_max_v)
    }

    /// Command (V) for an absolute set pressure (Pa), not saturated.
    pub fn command_for_v(&self, p_pa: f64) -> f64 {
        (p_pa - self.p_atm_pa) / self.gain_pa_per_v()
    }

    /// Settled at a command.
    pub(crate) fn settled(&self, u_v: f64) -> ValveState {
        ValveState {
            p_pa: self.set_pressure_pa(u_v),
            dp_pa_s: 0.0,
        }
    }

    /// State after time t (s) at a constant set pressure, from `s0` (exact solution).
    pub fn advance(&self, s0: &ValveState, p_cmd_pa: f64, t_s: f64) -> ValveState {
        match self.dynamics {
            ValveDynamics::FirstOrder { tau_s } => {
                let a = (-t_s / tau_s).exp();
                let y = (s0.p_pa - p_cmd_pa) * a;
                ValveState {
                    p_pa: p_cmd_pa + y,
                    dp_pa_s: -y / tau_s,
                }
            }
            ValveDynamics::SecondOrder { tau_s, zeta } => {
                let wn = 1.0 / tau_s;
                let a = Matrix2::new(0.0, 1.0, -wn * wn, -2.0 * zeta * wn);
                let y = (a * t_s).exp() * Vector2::new(s0.p_pa - p_cmd_pa, s0.dp_pa_s);
                ValveState {
                    p_pa: p_cmd_pa + y[0],
                    dp_pa_s: y[1],
                }
            }
        }
    }

    /// Frequency response from command to output pressure, Pa/V (unsaturated).
    pub fn response(&self, w_rad_s: f64) -> Complex<f64> {
        let s = Complex::new(0.0, w_rad_s);
        let k = Complex::new(self.gain_pa_per_v(), 0.0);
        match self.dynamics {
            ValveDynamics::FirstOrder { tau_s } => k / (s * tau_s + 1.0),
            ValveDynamics::SecondOrder { tau_s, zeta } => {
                k / (s * s * tau_s * tau_s + s * (2.0 * zeta * tau_s) + 1.0)
            }
        }
    }
}

/// What the integrator does while the command is saturated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum AntiWindup {
    /// Plain integration (winds up).
    None,
    /// Conditional integration (clamping).
    #[default]
    Conditional,
    /// Back-calculation with tracking time T_t = K_p/K_i.
    BackCalculation,
}

impl std::str::FromStr for AntiWindup {
    type Err = UnknownAntiWindup;
    fn from_str(s: &str) -> Result<Self, UnknownAntiWindup> {
        match s {
            "none" => Ok(Self::None),
            "conditional" => Ok(Self::Conditional),
            "back-calculation" => Ok(Self::BackCalculation),
            _ => Err(UnknownAntiWindup(s.to_string())),
        }
    }
}

/// Discrete PI controller, G(s) = K_p + K_i/s on (speed error in `speed_unit_rpm`) → V.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PiController {
    /// V per speed unit.
    pub kp: f64,
    /// V per speed unit per second.
    pub ki: f64,
    /// Sample time, s.
    pub(crate) ts_s: f64,
    /// Speed unit of the error, rpm (1000: error in krpm).
    pub speed_unit_rpm: f64,
    /// Lower output limit, V.
    pub(crate) u_min_v: f64,
    /// Upper output limit, V.
    pub u_max_v: f64,
    /// What the integrator does while the output is saturated.
    pub anti_windup: AntiWindup,
}

impl Default for PiController {
    /// The paper's (0.85·s + 4)/s on krpm → V, 1 ms, 0–10 V, conditional integration.
    fn default() -> Self {
        Self {
            kp: 0.85,
            ki: 4.0,
            ts_s: 1e-3,
            speed_unit_rpm: 1000.0,
            u_min_v: 0.0,
            u_max_v: 10.0,
            anti_windup: AntiWindup::Conditional,
        }
    }
}

impl PiController {
    /// Speed unit in rad/s.
    pub(crate) fn speed_unit_rad_s(&self) -> f64 {
        self.speed_unit_rpm * RAD_S_PER_RPM
    }

    /// One controller step: command (V, saturated) and next integral state.
    pub fn step(&self, integral: f64, setpoint_rad_s: f64, speed_rad_s: f64) -> (f64, f64) {
        let e = (setpoint_rad_s - speed_rad_s) / self.speed_unit_rad_s();
        let v = self.kp * e + integral;
        let u = v.clamp(self.u_min_v, self.u_max_v);
        let next = match self.anti_windup {
            AntiWindup::None => integral + self.ki * self.ts_s * e,
            AntiWindup::Conditional => {
                let pushing_out = (v > self.u_max_v && e > 0.0) || (v < self.u_min_v && e < 0.0);
                if pushing_out {
                    integral
                } else {
                    integral + self.ki * self.ts_s * e
                }
            }
            AntiWindup::BackCalculation => {
                let tt = self.kp / self.ki;
                integral + self.ts_s * (self.ki * e + (u - v) / tt)
            }
        };
        (u, next)
    }

    /// Frequency response K_p + K_i/(jw), V per speed unit.
    pub fn response(&self, w_rad_s: f64) -> Complex<f64> {
        Complex::new(self.kp, -self.ki / w_rad_s)
    }
}

/// A piecewise-constant signal: `initial` until the first step, then each step's value from
/// its time on (times increasing).
#[derive(Debug, Clone, PartialEq)]
pub struct Steps {
    /// Value before the first step.
    pub(crate) initial: f64,
    /// (time s, value) of each step, times increasing.
    pub steps: Vec<(f64, f64)>,
}

impl Steps {
    /// `v` throughout.
    pub fn constant(v: f64) -> Self {
        Self {
            initial: v,
            steps: Vec::new(),
        }
    }

    /// `initial`, then `value` from `t_s` (s) on.
    pub fn step(initial: f64, t_s: f64, value: f64) -> Self {
        Self {
            initial,
            steps: vec![(t_s, value)],
        }
    }

    /// The value at time `t` (s); a step counts from 1e-12 s before its time, so that a
    /// sample at the step's time sees it despite rounding.
    pub fn at(&self, t: f64) -> f64 {
        self.steps
            .iter()
            .rev()
            .find(|(ts, _)| t >= *ts - 1e-12)
            .map_or(self.initial, |s| s.1)
    }
}

/// The loop: valve, controller and the load on the motor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Loop {
    /// The pressure control valve feeding port 1.
    pub valve: Valve,
    /// The speed controller.
    pub pi: PiController,
    /// Base load (e.g. the eddy-current brake).
    pub load: Load,
}

/// What the loop is asked to do.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// Length, s.
    pub duration_s: f64,
    /// Speed set-point, rad/s.
    pub setpoint_rad_s: Steps,
    /// Extra load torque on top of `Loop::load`, N·m: constant, opposing forward rotation
    /// (an active load like `Load::Torque`, it would also drive a standing motor backwards).
    pub(crate) load_torque_nm: Steps,
}

/// Recorded signals, one entry per controller sample (t = 0, T_s, 2T_s, …).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trace {
    /// Sample times, s.
    pub t_s: Vec<f64>,
    /// Speed set-point, rad/s.
    pub setpoint_rad_s: Vec<f64>,
    /// Measured speed, rad/s.
    pub speed_rad_s: Vec<f64>,
    /// Controller output (held over the following sample), V.
    pub command_v: Vec<f64>,
    /// Valve output pressure, Pa absolute.
    pub(crate) p_valve_pa: Vec<f64>,
    /// Pressure in the motor's inlet volume V_1, Pa absolute.
    pub p1_pa: Vec<f64>,
    /// Controller integral state, V.
    pub(crate) integral_v: Vec<f64>,
    /// Total load torque (base load + extra), N·m.
    pub(crate) load_nm: Vec<f64>,
}

/// Where the loop starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopStart {
    /// The motor's state.
    pub x: State,
    /// The valve's state.
    pub valve: ValveState,
    /// The controller's integral state, V.
    pub(crate) integral_v: f64,
}

impl Loop {
    /// The same loop with the controller's gains set to zero: the command stays where it
    /// started (the open-loop comparison of a disturbance study).
    pub(crate) fn without_control(&self) -> Self {
        Self {
            pi: PiController {
                kp: 0.0,
                ki: 0.0,
                ..self.pi
            },
            ..*self
        }
    }

    /// Boundary seen by the motor at valve pressure p_v.
    fn boundary(&self, p_valve_pa: f64) -> Boundary {
        Boundary::supplied(
            p_valve_pa.max(self.valve.p_atm_pa),
            self.valve.p_atm_pa,
            self.load,
        )
    }

    /// The settled loop at a set-point: the command u₀ whose steady speed is the set-point
    /// (found by bisection on u, the steady speed rising with supply pressure), the valve
    /// settled at u₀ and the integral at u₀ (so that the start is bumpless). A set-point the
    /// motor cannot reach open loop (above its speed at full command, or in a speed band
    /// where there is no steady state) is an error.
    pub(crate) fn settled_at(
        &self,
        motor: &Motor,
        setpoint_rad_s: f64,
    ) -> Result<LoopStart, ControlError> {
        let speed_at = |u: f64| -> Result<State, ControlError> {
            let bc = self.boundary(self.valve.set_pressure_pa(u));
            Ok(steady::free(motor, &bc, &steady::initial_guess(&bc))?)
        };
        let (mut lo, mut hi) = (
            self.pi.u_min_v.max(0.0),
            self.pi.u_max_v.min(self.valve.u_max_v),
        );
        let x_hi = speed_at(hi)?;
        if x_hi[idx::OMEGA] < setpoint_rad_s {
            return Err(ControlError::AboveFullCommand {
                setpoint_rpm: setpoint_rad_s / RAD_S_PER_RPM,
                full_rpm: x_hi[idx::OMEGA] / RAD_S_PER_RPM,
            });
        }
        let mut x = x_hi;
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            let xm = speed_at(mid)?;
            if xm[idx::OMEGA] < setpoint_rad_s {
                lo = mid;
            } else {
                hi = mid;
                x = xm;
            }
            if hi - lo < 1e-9 {
                break;
            }
        }
        let rel = (x[idx::OMEGA] - setpoint_rad_s).abs() / setpoint_rad_s.abs().max(1.0);
        if rel > 0.01 {
            return Err(ControlError::NoSteadySpeed {
                setpoint_rpm: setpoint_rad_s / RAD_S_PER_RPM,
                nearest_rpm: x[idx::OMEGA] / RAD_S_PER_RPM,
            });
        }
        Ok(LoopStart {
            x,
            valve: self.valve.settled(hi),
            integral_v: hi,
        })
    }

    /// Everything at rest: motor at atmosphere and standstill, valve closed, integral 0.
    pub fn at_rest(&self) -> LoopStart {
        let p = self.valve.p_atm_pa;
        LoopStart {
            x: [p, p, p, 0.0],
            valve: self.valve.settled(0.0),
            integral_v: 0.0,
        }
    }

    /// Simulates the closed loop from `start` for the scenario.
    pub fn simulate(
        &self,
        motor: &Motor,
        solver: &dyn StiffSolver,
        scenario: &Scenario,
        start: &LoopStart,
    ) -> Result<Trace, ControlError> {
        Ok(self.simulate_to_end(motor, solver, scenario, start)?.0)
    }

    /// Like [`Loop::simulate`], also returning the loop's state at the end (to continue
    /// from; the command computed at the last sample is not yet applied).
    pub(crate) fn simulate_to_end(
        &self,
        motor: &Motor,
        solver: &dyn StiffSolver,
        scenario: &Scenario,
        start: &LoopStart,
    ) -> Result<(Trace, LoopStart), ControlError> {
        let ts = self.pi.ts_s;
        let n = (scenario.duration_s / ts).round() as usize;
        let mut tr = Trace::default();
        let (mut x, mut valve, mut integral) = (start.x, start.valve, start.integral_v);
        let inertia = motor.params().inertia();
        for k in 0..=n {
            let t = k as f64 * ts;
            let r = scenario.setpoint_rad_s.at(t);
            let (u, next) = self.pi.step(integral, r, x[idx::OMEGA]);
            let extra = scenario.load_torque_nm.at(t);
            tr.t_s.push(t);
            tr.setpoint_rad_s.push(r);
            tr.speed_rad_s.push(x[idx::OMEGA]);
            tr.command_v.push(u);
            tr.p_valve_pa.push(valve.p_pa);
            tr.p1_pa.push(x[idx::P1]);
            tr.integral_v.push(integral);
            tr.load_nm.push(self.load.torque(x[idx::OMEGA]) + extra);
            if k == n {
                break;
            }
            let p_cmd = self.valve.set_pressure_pa(u);
            let v0 = valve;
            let rhs = |tau: f64, xs: &State| {
                let pv = self.valve.advance(&v0, p_cmd, tau - t).p_pa;
                let mut d = motor.derivatives(xs, &self.boundary(pv));
                d[idx::OMEGA] -= extra / inertia;
                d
            };
            let xs = solver
                .solve(&rhs, t, x, &[t + ts])
                .map_err(|source| ControlError::LoopStep { t_s: t, source })?;
            x = xs[0];
            valve = self.valve.advance(&v0, p_cmd, ts);
            integral = next;
        }
        let end = LoopStart {
            x,
            valve,
            integral_v: integral,
        };
        Ok((tr, end))
    }
}

/// Figures of merit of a set-point step at `t_step` from the trace (speeds in rad/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepMetrics {
    /// Largest excursion beyond the new set-point, % of the step.
    pub overshoot_pct: f64,
    /// 10 %–90 % rise time, s (NaN if never reached).
    pub rise_time_s: f64,
    /// Time after the step until the speed stays within ±2 % of the step, s (NaN if never).
    pub settling_time_s: f64,
    /// Mean error (set-point − speed) over the last 10 % of the trace, rad/s.
    pub final_error_rad_s: f64,
}

/// Step metrics for a set-point step from `from` to `to` (rad/s) at `t_step` (s).
pub(crate) fn step_metrics(tr: &Trace, t_step: f64, from: f64, to: f64) -> StepMetrics {
    let h = to - from;
    let after: Vec<(f64, f64)> = tr
        .t_s
        .iter()
        .zip(&tr.speed_rad_s)
        .filter(|(t, _)| **t >= t_step)
        .map(|(t, w)| (*t - t_step, (*w - from) / h))
        .collect();
    let first = |lvl: f64| after.iter().find(|(_, y)| *y >= lvl).map(|p| p.0);
    let rise = match (first(0.1), first(0.9)) {
        (Some(a), Some(b)) => b - a,
        _ => f64::NAN,
    };
    let overshoot = after.iter().map(|p| p.1 - 1.0).fold(0.0, f64::max) * 100.0;
    let settle = match after.iter().rposition(|(_, y)| (y - 1.0).abs() > 0.02) {
        None => 0.0,
        Some(i) if i + 1 < after.len() => after[i + 1].0,
        Some(_) => f64::NAN,
    };
    StepMetrics {
        overshoot_pct: overshoot,
        rise_time_s: rise,
        settling_time_s: settle,
        final_error_rad_s: tail_mean_error(tr, 0.1),
    }
}

/// Mean of set-point − speed over the last `fraction` of the trace, rad/s.
pub(crate) fn tail_mean_error(tr: &Trace, fraction: f64) -> f64 {
    let n = tr.t_s.len();
    let k0 = ((1.0 - fraction) * n as f64) as usize;
    let m = (n - k0.min(n)).max(1) as f64;
    (k0..n)
        .map(|k| tr.setpoint_rad_s[k] - tr.speed_rad_s[k])
        .sum::<f64>()
        / m
}

/// Disturbance figures: largest speed drop after `t_step` and the time until the speed is
/// back within `band` (rad/s) of the set-point for good.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisturbanceMetrics {
    /// Largest set-point − speed after the step, rad/s.
    pub max_drop_rad_s: f64,
    /// Time after the step until the error stays within the band, s (NaN if never).
    pub recovery_time_s: f64,
    /// Mean error (set-point − speed) over the last 10 % of the trace, rad/s.
    pub final_error_rad_s: f64,
}

/// Disturbance figures of the trace for a load step at `t_step` (s), recovery band
/// `band_rad_s`.
pub(crate) fn disturbance_metrics(tr: &Trace, t_step: f64, band_rad_s: f64) -> DisturbanceMetrics {
    let idx: Vec<usize> = (0..tr.t_s.len()).filter(|k| tr.t_s[*k] >= t_step).collect();
    let err = |k: usize| tr.setpoint_rad_s[k] - tr.speed_rad_s[k];
    let max_drop = idx.iter().map(|k| err(*k)).fold(0.0, f64::max);
    let recovery = match idx.iter().rposition(|k| err(*k).abs() > band_rad_s) {
        None => 0.0,
        Some(i) if i + 1 < idx.len() => tr.t_s[idx[i + 1]] - t_step,
        Some(_) => f64::NAN,
    };
    DisturbanceMetrics {
        max_drop_rad_s: max_drop,
        recovery_time_s: recovery,
        final_error_rad_s: tail_mean_error(tr, 0.1),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numerics::DefaultSolver;

    const P_ATM: f64 = 101_325.0;

    fn rpm(v: f64) -> f64 {
        v * RAD_S_PER_RPM
    }

    fn default_loop(motor: &Motor) -> Loop {
        Loop {
            valve: Valve::for_motor(motor, P_ATM),
            pi: PiController::default(),
            load: Load::ViscousBrake { c_nm_s_rad: 1e-4 },
        }
    }

    #[test]
    fn valve_follows_its_differential_equation() {
        for dynamics in [
            ValveDynamics::FirstOrder { tau_s: 0.05 },
            ValveDynamics::SecondOrder {
                tau_s: 0.05,
                zeta: 0.4,
            },
            ValveDynamics::SecondOrder {
                tau_s: 0.03,
                zeta: 1.7,
            },
        ] {
            let v = Valve {
                dynamics,
                u_max_v: 10.0,
                p_max_gauge_pa: 6e5,
                p_atm_pa: P_ATM,
            };
            let s0 = v.settled(2.0);
            let p_cmd = v.set_pressure_pa(7.0);
            // Advancing in many small steps equals one big step (semigroup), and the rate
            // matches a difference quotient of the pressure.
            let mut s = s0;
            for _ in 0..100 {
                s = v.advance(&s, p_cmd, 1e-3);
            }
            let big = v.advance(&s0, p_cmd, 0.1);
            assert!((s.p_pa - big.p_pa).abs() < 1e-6 * p_cmd, "{dynamics:?}");
            let h = 1e-6;
            let a = v.advance(&s0, p_cmd, 0.02 - h).p_pa;
            let b = v.advance(&s0, p_cmd, 0.02 + h).p_pa;
            let rate = v.advance(&s0, p_cmd, 0.02).dp_pa_s;
            assert!(
                ((b - a) / (2.0 * h) - rate).abs() < 1e-5 * rate.abs(),
                "{dynamics:?}"
            );
            // Settles to the set pressure; the static gain is 0.6 bar/V.
            assert!((v.advance(&s0, p_cmd, 5.0).p_pa - p_cmd).abs() < 1e-6 * p_cmd);
            assert!((v.response(0.0).re - 6e4).abs() < 1e-9);
        }
    }

    #[test]
    fn anti_windup_stops_integration_while_saturated() {
        let pi = PiController::default();
        let big_error = rpm(20_000.0);
        let (u, i_cond) = pi.step(9.0, big_error, 0.0);
        assert_eq!(u, 10.0);
        assert_eq!(i_cond, 9.0);
        let plain = PiController {
            anti_windup: AntiWindup::None,
            ..pi
        };
        let (_, i_plain) = plain.step(9.0, big_error, 0.0);
        assert!(i_plain > 9.0);
        let back = PiController {
            anti_windup: AntiWindup::BackCalculation,
            ..pi
        };
        let (_, i_back) = back.step(9.0, big_error, 0.0);
        assert!(i_back < i_plain);
    }

    /// Set-point step 3000 → 4500 rpm with the paper's PI: tracked with no steady-state
    /// error (integral action), and the controller's steady command is the open-loop one.
    #[test]
    fn closed_loop_tracks_setpoint_step_without_steady_error() {
        let m = Motor::default_motor();
        let lp = default_loop(&m);
        let start = lp.settled_at(&m, rpm(3000.0)).unwrap();
        let sc = Scenario {
            duration_s: 6.0,
            setpoint_rad_s: Steps::step(rpm(3000.0), 0.2, rpm(4500.0)),
            load_torque_nm: Steps::constant(0.0),
        };
        let tr = lp
            .simulate(&m, &DefaultSolver::default(), &sc, &start)
            .unwrap();
        // Started settled: no movement before the step.
        let k_step = 190;
        assert!((tr.speed_rad_s[k_step] - rpm(3000.0)).abs() < rpm(2.0));
        let met = step_metrics(&tr, 0.2, rpm(3000.0), rpm(4500.0));
        assert!(met.final_error_rad_s.abs() < rpm(5.0), "{met:?}");
        assert!(met.settling_time_s < 5.0, "{met:?}");
        let end = lp.settled_at(&m, rpm(4500.0)).unwrap();
        let u_end = *tr.command_v.last().unwrap();
        assert!(
            (u_end - end.integral_v).abs() < 0.01,
            "{u_end} vs {}",
            end.integral_v
        );
    }

    /// A load-torque step is rejected: the speed drops, then returns to the set-point.
    #[test]
    fn closed_loop_rejects_load_step() {
        let m = Motor::default_motor();
        let lp = default_loop(&m);
        let w_ref = rpm(4000.0);
        let start = lp.settled_at(&m, w_ref).unwrap();
        let sc = Scenario {
            duration_s: 6.0,
            setpoint_rad_s: Steps::constant(w_ref),
            load_torque_nm: Steps::step(0.0, 0.2, 0.03),
        };
        let tr = lp
            .simulate(&m, &DefaultSolver::default(), &sc, &start)
            .unwrap();
        let d = disturbance_metrics(&tr, 0.2, rpm(20.0));
        assert!(d.max_drop_rad_s > rpm(50.0), "the step must be felt: {d:?}");
        assert!(d.final_error_rad_s.abs() < rpm(5.0), "{d:?}");
        assert!(d.recovery_time_s < 5.0, "{d:?}");
        // Without control the same torque step costs a lasting speed loss.
        let open = lp.without_control();
        let tr_open = open
            .simulate(&m, &DefaultSolver::default(), &sc, &start)
            .unwrap();
        let open_error = tail_mean_error(&tr_open, 0.1);
        assert!(open_error > rpm(50.0), "open loop loses {open_error} rad/s");
        assert!(open_error > 10.0 * d.final_error_rad_s.abs());
    }

    /// A large step down saturates the valve command at 0 V (the valve vents to atmosphere
    /// and the motor coasts down against friction and brake). Plain integration winds the
    /// integral far below 0 V, so the command stays at 0 V long after the speed has passed
    /// the set-point: the motor stops. With anti-windup the undershoot is a fraction of that
    /// and the loop settles seconds sooner.
    #[test]
    fn saturation_does_not_wind_up_the_integrator() {
        let m = Motor::default_motor();
        let base = default_loop(&m);
        let (from, to) = (rpm(7000.0), rpm(1000.0));
        let sc = Scenario {
            duration_s: 8.0,
            setpoint_rad_s: Steps::step(from, 0.1, to),
            load_torque_nm: Steps::constant(0.0),
        };
        let run = |aw: AntiWindup| {
            let lp = Loop {
                pi: PiController {
                    anti_windup: aw,
                    ..base.pi
                },
                ..base
            };
            let start = lp.settled_at(&m, from).unwrap();
            let tr = lp
                .simulate(&m, &DefaultSolver::default(), &sc, &start)
                .unwrap();
            let saturated = tr.command_v.iter().filter(|u| **u <= 0.0).count();
            let min_i = tr.integral_v.iter().cloned().fold(f64::MAX, f64::min);
            let min_w = tr.speed_rad_s.iter().cloned().fold(f64::MAX, f64::min);
            (step_metrics(&tr, 0.1, from, to), saturated, min_i, min_w)
        };
        let (with, sat_with, i_with, w_with) = run(AntiWindup::Conditional);
        let (without, sat_without, i_without, w_without) = run(AntiWindup::None);
        let (back, _, i_back, _) = run(AntiWindup::BackCalculation);
        assert!(
            sat_with > 100,
            "the step must saturate the valve: {sat_with}"
        );
        assert!(sat_without > sat_with + 500, "{sat_without} vs {sat_with}");
        assert!(
            i_with > -1.0 && i_back > -1.0,
            "integral stays near range: {i_with}, {i_back}"
        );
        assert!(i_without < -3.0, "plain integral winds up: {i_without}");
        assert!(
            w_with > 0.5 * to,
            "with anti-windup the motor keeps turning: {w_with}"
        );
        assert!(
            w_without < 0.1 * to,
            "wound-up integral stops the motor: {w_without}"
        );
        for good in [with, back] {
            assert!(
                without.overshoot_pct > 1.5 * good.overshoot_pct,
                "with {good:?}, without {without:?}"
            );
            assert!(without.settling_time_s > good.settling_time_s + 1.0);
            assert!(good.final_error_rad_s.abs() < rpm(5.0));
        }
    }
}
