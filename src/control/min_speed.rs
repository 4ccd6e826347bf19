//! Lowest steady speed without and with speed control (paper §5.2: "the minimum speed of the
//! motor without load is reduced from 2900 rpm without control to 365 rpm with control").
//!
//! **Without control** the supply pressure is raised slowly from atmospheric (reference
//! experiment 2, the pressure ramp) and the motor follows its steady states
//! quasi-statically. For each speed ω ≥ ω_lo (see `lowest_running_speed_rad_s`) let
//! p_eq(ω) be the supply pressure at which ω is a steady speed: the root in p of the net
//! torque N(ω, p) = T(ω, p) − T_f(ω) − T_load(ω) with the pressures of V_1, V_2, V_e in
//! steady state at that speed (`steady::at_speed`). N rises with p, so
//! dp_eq/dω = −(∂N/∂ω)/(∂N/∂p): a steady state is stable exactly where p_eq rises with ω.
//! The standing motor breaks away at p_b, where the forward torque at standstill reaches
//! the static friction plus the load. If p_eq(ω) < p_b for the lowest speeds (static
//! friction above the running friction, as with `breakaway_friction`), the motor cannot
//! run there: at p_b it accelerates to the lowest speed with p_eq = p_b, and that landing
//! speed is its lowest speed without control (the paper's 2900 rpm); the speeds below are
//! open-loop unstable or not steady at all. Otherwise it creeps from standstill and the
//! lowest speed is ω_lo; a later local maximum of p_eq, if any, is reported as a jump too.
//!
//! **With control** the loop is settled at a reachable start speed and the set-point is
//! lowered in a staircase, by a constant factor every few seconds, as an operator would;
//! a stage counts as held when over its last `HOLD_WINDOW_S` the mean speed is within
//! 5 % (at least 5 rpm) of the set-point, the speed varies by less than 20 % of it peak to
//! peak and never drops below half of it. The lowest set-point held before the first stage
//! that is not is the minimum speed with control. What ends the staircase is the loop
//! itself: the motor's gain dω/dp_supply grows without bound towards the open-loop fold,
//! so a PI with fixed gains ends in a limit cycle (or stalls the motor) below some speed.

use super::closed_loop::{Loop, Scenario, Steps, Trace};
use super::{ControlError, RAD_S_PER_RPM};
use crate::model::motor::{idx, Boundary, Load, Motor, State};
use crate::numerics::DefaultSolver;
use crate::sim::steady;

/// A jump of the speed on the ramp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Jump {
    /// Supply pressure at which it happens, Pa absolute.
    pub p_pa: f64,
    /// Speed before, rad/s (0 for the breakaway from standstill).
    pub from_rad_s: f64,
    /// Speed after, rad/s.
    pub to_rad_s: f64,
}

/// The open-loop start-up analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct StartUp {
    /// (ω rad/s, p_eq Pa absolute) along the speed grid, ascending in ω.
    pub curve: Vec<(f64, f64)>,
    /// Supply pressure at which the standing motor breaks away, Pa absolute.
    pub p_breakaway_pa: f64,
    /// The first jump on the ramp (at breakaway or at a later fold of p_eq); `None` if the
    /// speed rises continuously.
    pub jump: Option<Jump>,
    /// Lowest speed the motor runs at without control, rad/s: the landing speed when the
    /// motor jumps at breakaway, else the lowest speed of the grid (it creeps).
    pub w_min_rad_s: f64,
}

/// Lowest speed of the analysis, rad/s: 5·max(ω_reg, ω_b). Below it the friction
/// regularisation tanh(ω/ω_reg) and the forward/reverse torque blend tanh(ω/ω_b) are not
/// yet saturated; those are numerical devices for standstill, and the motor counts as
/// standing there.
pub(crate) fn lowest_running_speed_rad_s(motor: &Motor) -> f64 {
    5.0 * motor
        .params()
        .w_reg()
        .max(crate::units::constants::OMEGA_BLEND_RAD_S)
}

/// Root in p ∈ [p_lo, p_hi] of an increasing function (bisection with the Illinois
/// false-position step); `None` if f(p_hi) < 0; p_lo if f(p_lo) ≥ 0.
fn increasing_root(
    p_lo: f64,
    p_hi: f64,
    f: &mut dyn FnMut(f64) -> Result<f64, ControlError>,
) -> Result<Option<f64>, ControlError> {
    let (mut lo, mut hi) = (p_lo, p_hi);
    let mut f_hi = f(hi)?;
    if f_hi < 0.0 {
        return Ok(None);
    }
    let mut f_lo = f(lo)?;
    if f_lo >= 0.0 {
        return Ok(Some(lo));
    }
    let mut side = 0i8;
    for _ in 0..100 {
        let mut p = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if !p.is_finite() || p <= lo || p >= hi {
            p = 0.5 * (lo + hi);
        }
        let v = f(p)?;
        if v < 0.0 {
            lo = p;
            f_lo = v;
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            hi = p;
            f_hi = v;
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
        if hi - lo <= 1e-9 * hi {
            break;
        }
    }
    Ok(Some(0.5 * (lo + hi)))
}

/// Steady pressures at imposed speed `w` under supply `p`, seeded by `guess`.
fn pressures_at(
    motor: &Motor,
    load: Load,
    p_atm: f64,
    p: f64,
    w: f64,
    guess: &State,
) -> Result<(Boundary, State), ControlError> {
    let bc = Boundary::supplied(p, p_atm, load);
    let x = steady::at_speed(motor, &bc, w, guess)
        .or_else(|_| steady::at_speed(motor, &bc, w, &steady::initial_guess(&bc)))?;
    Ok((bc, x))
}

/// Supply pressure (Pa absolute) at which `w` is a steady speed; None if even `p_max`
/// cannot hold it. Updates `guess` with the steady state found.
fn p_equilibrium(
    motor: &Motor,
    load: Load,
    p_atm: f64,
    p_max: f64,
    w: f64,
    guess: &mut State,
) -> Result<Option<f64>, ControlError> {
    let mut g = *guess;
    let r = increasing_root(p_atm, p_max, &mut |p| {
        let (bc, x) = pressures_at(motor, load, p_atm, p, w, &g)?;
        g = x;
        let b = motor.balance(&x, &bc);
        Ok(b.torque_ideal_nm - b.torque_friction_nm - b.torque_load_nm)
    })?;
    *guess = g;
    Ok(r)
}

/// Supply pressure (Pa absolute) at which the standing motor breaks away: the forward
/// torque of the ideal motor with the steady pressures at standstill reaches the static
/// friction (friction at ω_reg·5, where tanh(ω/ω_reg) ≈ 1 and any Stribeck decay is still
/// negligible) plus the load at standstill.
fn breakaway_pressure(
    motor: &Motor,
    load: Load,
    p_atm: f64,
    p_max: f64,
) -> Result<Option<f64>, ControlError> {
    let w_st = 5.0 * motor.params().w_reg();
    let mut g = steady::initial_guess(&Boundary::supplied(p_max, p_atm, load));
    increasing_root(p_atm, p_max, &mut |p| {
        let (_, x) = pressures_at(motor, load, p_atm, p, 0.0, &g)?;
        g = x;
        let t_fwd = motor
            .cycle()
            .torque_one_way(x[idx::P1], x[idx::P2], x[idx::PE]);
        let t_static = motor.friction_torque(w_st, x[idx::P1], x[idx::PE]) / (5.0f64).tanh();
        Ok(t_fwd - t_static - load.torque(0.0))
    })
}

/// Open-loop start-up on a slow pressure ramp from atmosphere to `p_max_pa` (see module
/// doc), on `n` log-spaced speeds from `lowest_running_speed_rad_s` up to the speed
/// `p_max_pa` can hold.
pub fn open_loop_start(
    motor: &Motor,
    load: Load,
    p_atm_pa: f64,
    p_max_pa: f64,
    n: usize,
) -> Result<StartUp, ControlError> {
    let bc = Boundary::supplied(p_max_pa, p_atm_pa, load);
    let top = steady::free(motor, &bc, &steady::initial_guess(&bc))?;
    let w_top = top[idx::OMEGA];
    let w_lo = lowest_running_speed_rad_s(motor);
    let p_break = breakaway_pressure(motor, load, p_atm_pa, p_max_pa)?;
    let p_break = match p_break {
        Some(p) if w_top > 2.0 * w_lo => p,
        _ => {
            return Err(ControlError::NoStart {
                p_max_mpa: p_max_pa / 1e6,
            })
        }
    };
    let grid = super::linear::log_grid(w_lo, 0.999 * w_top, n.max(10));
    let mut curve = Vec::with_capacity(grid.len());
    let mut guess = top;
    for w in grid {
        match p_equilibrium(motor, load, p_atm_pa, p_max_pa, w, &mut guess)? {
            Some(p) => curve.push((w, p)),
            None => break,
        }
    }
    if curve.is_empty() {
        return Err(ControlError::NoSteadyOnRamp);
    }
    // Where p_eq first reaches `p` at or after grid index `from`, interpolated; the top
    // speed if never.
    let landing = |from: usize, p: f64| -> f64 {
        match (from..curve.len()).find(|&j| curve[j].1 >= p) {
            Some(0) => curve[0].0,
            Some(j) => {
                let ((w0, p0), (w1, p1)) = (curve[j - 1], curve[j]);
                let f = ((p - p0) / (p1 - p0)).clamp(0.0, 1.0);
                w0 + f * (w1 - w0)
            }
            None => w_top,
        }
    };
    let (jump, w_min) = if curve[0].1 < p_break {
        // Breaks away into a speed band without steady states: lands where p_eq = p_break.
        let to = landing(0, p_break);
        let j = Jump {
            p_pa: p_break,
            from_rad_s: 0.0,
            to_rad_s: to,
        };
        (Some(j), to)
    } else {
        // Creeps from standstill; the first local maximum of p_eq (ignoring wiggles below
        // 1 Pa), if any, is where it jumps later.
        let fold = (1..curve.len()).find(|&k| curve[k].1 < curve[k - 1].1 - 1.0);
        let j = fold.map(|k| Jump {
            p_pa: curve[k - 1].1,
            from_rad_s: curve[k - 1].0,
            to_rad_s: landing(k, curve[k - 1].1),
        });
        (j, curve[0].0)
    };
    Ok(StartUp {
        curve,
        p_breakaway_pa: p_break,
        jump,
        w_min_rad_s: w_min,
    })
}

/// Seconds at the end of each closed-loop run over which "held" is judged.
pub(crate) const HOLD_WINDOW_S: f64 = 2.0;

/// One closed-loop attempt to hold a set-point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldAttempt {
    /// The set-point, rad/s.
    pub setpoint_rad_s: f64,
    /// Mean speed over the hold window, rad/s.
    pub(crate) mean_rad_s: f64,
    /// Lowest speed over the hold window, rad/s.
    pub min_rad_s: f64,
    /// Highest speed over the hold window, rad/s.
    pub max_rad_s: f64,
    /// Whether the set-point counts as held (see the module doc).
    pub held: bool,
}

/// Whether a trace's last [`HOLD_WINDOW_S`] holds `setpoint` (see module doc).
fn judge_hold(t_s: &[f64], speed: &[f64], setpoint: f64) -> HoldAttempt {
    let t_end = t_s.last().copied().unwrap_or(0.0);
    let w: Vec<f64> = t_s
        .iter()
        .zip(speed)
        .filter(|(t, _)| **t >= t_end - HOLD_WINDOW_S)
        .map(|(_, w)| *w)
        .collect();
    let mean = w.iter().sum::<f64>() / w.len().max(1) as f64;
    let min = w.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = w.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let tol = (0.05 * setpoint).max(5.0 * RAD_S_PER_RPM);
    let held =
        (mean - setpoint).abs() <= tol && (max - min) <= 0.2 * setpoint && min >= 0.5 * setpoint;
    HoldAttempt {
        setpoint_rad_s: setpoint,
        mean_rad_s: mean,
        min_rad_s: min,
        max_rad_s: max,
        held,
    }
}

/// Result of `closed_loop_min_speed`.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlledMin {
    /// Every stage, from the highest set-point down.
    pub attempts: Vec<HoldAttempt>,
    /// Lowest set-point held (NaN if none was).
    pub w_min_rad_s: f64,
    /// Speed the loop was settled at before the first stage, rad/s.
    w_start_rad_s: f64,
    /// The whole staircase run, stages joined end to end (time from the first stage).
    pub trace: Trace,
}

/// Lowest set-point the loop holds, found as an operator would: the loop is settled at
/// `w_start` (reachable open loop), then the set-point is lowered by `factor` every
/// `stage_s` seconds (each stage continuing from where the last one ended) until a stage
/// is not held or the set-point falls below `w_floor`.
pub(crate) fn closed_loop_min_speed(
    motor: &Motor,
    lp: &Loop,
    w_start_rad_s: f64,
    factor: f64,
    w_floor_rad_s: f64,
    stage_s: f64,
) -> Result<ControlledMin, ControlError> {
    let mut state = lp.settled_at(motor, w_start_rad_s)?;
    let solver = DefaultSolver::default();
    let mut attempts = Vec::new();
    let mut trace = Trace::default();
    let mut w_min = f64::NAN;
    let mut w = w_start_rad_s * factor;
    let mut t0 = 0.0;
    while w >= w_floor_rad_s {
        let sc = Scenario {
            duration_s: stage_s,
            setpoint_rad_s: Steps::constant(w),
            load_torque_nm: Steps::constant(0.0),
        };
        let (tr, end) = lp.simulate_to_end(motor, &solver, &sc, &state)?;
        let a = judge_hold(&tr.t_s, &tr.speed_rad_s, w);
        append(&mut trace, &tr, t0);
        t0 += stage_s;
        state = end;
        attempts.push(a);
        if !a.held {
            break;
        }
        w_min = w;
        w *= factor;
    }
    Ok(ControlledMin {
        attempts,
        w_min_rad_s: w_min,
        w_start_rad_s,
        trace,
    })
}

/// Appends `tr` shifted by `t0` to `all`, dropping its first sample when it repeats the
/// last one of `all` (stages share their boundary instant).
fn append(all: &mut Trace, tr: &Trace, t0: f64) {
    let skip = usize::from(!all.t_s.is_empty());
    all.t_s.extend(tr.t_s.iter().skip(skip).map(|t| t + t0));
    all.setpoint_rad_s
        .extend(tr.setpoint_rad_s.iter().skip(skip));
    all.speed_rad_s.extend(tr.speed_rad_s.iter().skip(skip));
    all.command_v.extend(tr.command_v.iter().skip(skip));
    all.p_valve_pa.extend(tr.p_valve_pa.iter().skip(skip));
    all.p1_pa.extend(tr.p1_pa.iter().skip(skip));
    all.integral_v.extend(tr.integral_v.iter().skip(skip));
    all.load_nm.extend(tr.load_nm.iter().skip(skip));
}

/// Speed against supply pressure on a ramp from atmosphere to `p_max_pa` over `ramp_s`,
/// simulated (the dynamic counterpart of [`open_loop_start`], reference experiment 2),
/// sampled `n` times: (p Pa, ω rad/s).
pub(crate) fn ramp_simulation(
    motor: &Motor,
    load: Load,
    p_atm_pa: f64,
    p_max_pa: f64,
    ramp_s: f64,
    n: usize,
) -> Result<Vec<(f64, f64)>, ControlError> {
    use crate::numerics::ode::StiffSolver;
    let p_at = |t: f64| p_atm_pa + (p_max_pa - p_atm_pa) * (t / ramp_s).clamp(0.0, 1.0);
    let rhs =
        |t: f64, x: &State| motor.derivatives(x, &Boundary::supplied(p_at(t), p_atm_pa, load));
    let n = n.max(2);
    let t_out: Vec<f64> = (1..n).map(|k| ramp_s * k as f64 / (n - 1) as f64).collect();
    let x0 = [p_atm_pa, p_atm_pa, p_atm_pa, 0.0];
    let xs = DefaultSolver::default().solve(&rhs, 0.0, x0, &t_out)?;
    let mut out = vec![(p_atm_pa, 0.0)];
    out.extend(
        t_out
            .iter()
            .zip(&xs)
            .map(|(t, x)| (p_at(*t), x[idx::OMEGA])),
    );
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::closed_loop::{PiController, Valve};
    use crate::model::effects::{Effect, EffectSet};
    use crate::model::params::MotorParams;

    const P_ATM: f64 = 101_325.0;

    fn sticky_motor() -> Motor {
        Motor::new(
            MotorParams::default(),
            EffectSet::empty().with(Effect::BreakawayFriction),
        )
    }

    /// With breakaway friction the motor jumps at breakaway into running: p_eq lies below
    /// the breakaway pressure up to the landing speed. The dynamic ramp agrees: the motor
    /// stands until about the breakaway pressure and then crosses the speed gap within a
    /// small pressure rise (the time it takes to accelerate).
    #[test]
    fn breakaway_friction_makes_the_start_up_jump() {
        let m = sticky_motor();
        let s = open_loop_start(&m, Load::None, P_ATM, 7.3e5, 80).unwrap();
        let j = s.jump.expect("a jump");
        assert_eq!(j.from_rad_s, 0.0);
        assert_eq!(j.p_pa, s.p_breakaway_pa);
        assert!(s.w_min_rad_s > 100.0, "{s:?}");
        for (w, p) in s.curve.iter().filter(|(w, _)| *w < 0.99 * s.w_min_rad_s) {
            assert!(
                *p < s.p_breakaway_pa,
                "steady state at {w} rad/s below breakaway"
            );
        }
        let ramp = ramp_simulation(&m, Load::None, P_ATM, 7.3e5, 60.0, 1200).unwrap();
        let w_lo = lowest_running_speed_rad_s(&m);
        let (p_start, _) = *ramp.iter().find(|(_, w)| *w > w_lo).unwrap();
        assert!(
            p_start > s.p_breakaway_pa - 2e3 && p_start < s.p_breakaway_pa + 1e4,
            "starts at {p_start} Pa, breakaway {} Pa",
            s.p_breakaway_pa
        );
        let in_gap: Vec<f64> = ramp
            .iter()
            .filter(|(_, w)| *w > w_lo && *w < 0.7 * s.w_min_rad_s)
            .map(|(p, _)| *p)
            .collect();
        let span = in_gap.iter().cloned().fold(f64::MIN, f64::max)
            - in_gap.iter().cloned().fold(f64::MAX, f64::min);
        assert!(span < 3e4, "crossing the gap takes {span} Pa of the ramp");
    }

    /// The base model (Coulomb friction only) creeps from standstill: no jump, p_eq rises
    /// with speed, and the lowest running speed is the lowest of the grid.
    #[test]
    fn coulomb_friction_starts_without_a_jump() {
        let m = Motor::default_motor();
        let s = open_loop_start(&m, Load::None, P_ATM, 7.3e5, 40).unwrap();
        assert!(s.jump.is_none(), "{s:?}");
        assert!(s.curve[0].1 >= s.p_breakaway_pa);
        for w in s.curve.windows(2) {
            assert!(w[1].1 >= w[0].1 - 1.0, "{w:?}");
        }
        assert!((s.w_min_rad_s / lowest_running_speed_rad_s(&m) - 1.0).abs() < 1e-12);
    }

    /// Speed control holds set-points inside the open-loop gap: the controlled minimum is
    /// below the open-loop one.
    #[test]
    fn control_holds_speeds_below_the_open_loop_minimum() {
        let m = sticky_motor();
        let open = open_loop_start(&m, Load::None, P_ATM, 7.3e5, 60).unwrap();
        let lp = Loop {
            valve: Valve::for_motor(&m, P_ATM),
            pi: PiController::default(),
            load: Load::None,
        };
        let w_start = 1.2 * open.w_min_rad_s;
        let c = closed_loop_min_speed(&m, &lp, w_start, 0.7, 0.1 * open.w_min_rad_s, 5.0).unwrap();
        assert!(c.w_min_rad_s < 0.6 * open.w_min_rad_s, "{c:?} vs {open:?}");
        // The staircase ends because the loop stops holding, not at the floor.
        assert!(!c.attempts.last().unwrap().held, "{:?}", c.attempts);
    }
}
