//! The speed-control studies of paper §5 on the twin, written from the paper and
//! docs/model.md ("Reference experiments", "Speed control"), sharing no code with vanefit:
//!
//! * throttling (§5.1, Figs. 14, 15): a nozzle of conductance C_th and the motor's critical
//!   ratio b in series with the motor's duct, no volume between them. Inlet: supply →
//!   throttle → in_1 → V_1 (the throttle sits in front of port 1, on the supply side, for
//!   either direction of flow); outlet: V_2 → out_2 → throttle → atmosphere;
//! * the frequency response supply pressure → speed (§5.2, Fig. 16) from the twin's own
//!   linearisation: central differences of its own right-hand side about its own steady
//!   state, G(jω) = e_ω·(jω·I − A)⁻¹·b;
//! * the speed loop of Figs. 18–20: a first-order pressure valve τ·ṗ_v + p_v = p_cmd(u),
//!   u ∈ [0, 10] V → 0–6 bar gauge, a discrete PI on the speed error in krpm sampled every T_s
//!   with the command held between samples, and clamping of the integrator while the command
//!   is saturated and the error pushes it further out;
//! * the loop's stability margins from L(jω) = C(jω)·V(jω)·G(jω)·e^(−jωT_s/2)/ω_unit;
//! * the start-up on a slow pressure ramp (the lowest speed without control): the supply
//!   pressure p_eq(ω) at which ω is a steady speed, and the pressure p_b at which the
//!   standing motor breaks away.
//!
//! SI units: Pa absolute, rad/s, N·m, s.

use super::motor::{self, TwinMotor};
use super::ode::{State, Tolerances, TrBdf2};
use super::rig::series_flow_kg_s;
use super::steady::steady_state;
use nalgebra::{Complex, Matrix4, Vector4};

/// Revolutions per minute in rad/s.
pub const RAD_S_PER_RPM: f64 = std::f64::consts::PI / 30.0;

/// What the surroundings impose on the motor: supply at port 1, atmosphere behind port 2 and
/// the exhaust, optional throttles, a viscous brake and an extra constant load torque.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rig {
    /// Supply pressure in front of port 1 (in front of an inlet throttle), Pa absolute.
    pub p_supply_pa: f64,
    /// Atmosphere (behind port 2 and the exhaust), Pa.
    pub p_atm_pa: f64,
    /// Conductance of a throttle in front of port 1, m³/(s·Pa).
    pub inlet_throttle: Option<f64>,
    /// Conductance of a throttle behind port 2, m³/(s·Pa).
    pub outlet_throttle: Option<f64>,
    /// Viscous brake c, N·m·s/rad.
    pub brake_nm_s_rad: f64,
    /// Extra load torque opposing the motor, N·m.
    pub extra_load_nm: f64,
}

impl Rig {
    /// Supply `p_supply_pa`, atmosphere, brake `brake`, no throttle, no extra load.
    pub fn supplied(p_supply_pa: f64, brake: f64) -> Self {
        Self {
            p_supply_pa,
            p_atm_pa: motor::P_ATM_PA,
            inlet_throttle: None,
            outlet_throttle: None,
            brake_nm_s_rad: brake,
            extra_load_nm: 0.0,
        }
    }
}

/// Mass flow supply → V_1, kg/s: supply → \[throttle\] → in_1 → V_1 (negative when V_1 blows
/// back into the supply line; the throttle stays on the supply side).
pub fn port1_flow_kg_s(m: &TwinMotor, rig: &Rig, p1_pa: f64) -> f64 {
    match rig.inlet_throttle {
        None => motor::nozzle_flow_kg_s(m.c_in1, m.b_crit, rig.p_supply_pa, p1_pa),
        Some(c) => series_flow_kg_s((c, m.b_crit), (m.c_in1, m.b_crit), rig.p_supply_pa, p1_pa),
    }
}

/// Mass flow V_2 → atmosphere, kg/s: V_2 → out_2 → \[throttle\] → atmosphere.
pub fn port2_flow_kg_s(m: &TwinMotor, rig: &Rig, p2_pa: f64) -> f64 {
    match rig.outlet_throttle {
        None => motor::nozzle_flow_kg_s(m.c_out2, m.b_crit, p2_pa, rig.p_atm_pa),
        Some(c) => series_flow_kg_s((m.c_out2, m.b_crit), (c, m.b_crit), p2_pa, rig.p_atm_pa),
    }
}

/// Net torque on the shaft, N·m: air torque less friction, brake and extra load.
pub fn net_torque_nm(m: &TwinMotor, rig: &Rig, y: &State) -> f64 {
    motor::air_torque_nm(m, [y[0], y[1], y[2]], y[3])
        - motor::friction_torque_nm(m, y[3])
        - rig.brake_nm_s_rad * y[3]
        - rig.extra_load_nm
}

/// dy/dt on the rig; with `speed_imposed` dω/dt = 0 (a speed held by a dynamometer).
pub fn rhs(m: &TwinMotor, rig: &Rig, y: &State, speed_imposed: bool) -> State {
    let [q1, q2, qe] = motor::internal_flows_kg_s(m, [y[0], y[1], y[2]], y[3], rig.p_atm_pa);
    let rt = motor::RT0_J_KG;
    [
        rt / m.vol1 * (q1 + port1_flow_kg_s(m, rig, y[0])),
        rt / m.vol2 * (q2 - port2_flow_kg_s(m, rig, y[1])),
        rt / m.vole * qe,
        if speed_imposed {
            0.0
        } else {
            net_torque_nm(m, rig, y) / m.inertia
        },
    ]
}

/// Steady state with free speed reached by starting the motor from standstill at atmosphere.
pub fn free_steady(m: &TwinMotor, rig: &Rig) -> Result<State, String> {
    let p = rig.p_atm_pa;
    steady_state(|y| rhs(m, rig, y, false), &[p, p, p, 0.0], false)
}

/// Steady pressures at the imposed speed `w_rad_s`, from `guess` (its speed is replaced).
pub fn steady_at_speed(
    m: &TwinMotor,
    rig: &Rig,
    w_rad_s: f64,
    guess: &State,
) -> Result<State, String> {
    let y0 = [guess[0], guess[1], guess[2], w_rad_s];
    steady_state(|y| rhs(m, rig, y, true), &y0, true)
}

/// A steady state with a throttle fitted (paper Fig. 14).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThrottledPoint {
    /// Throttle conductance, m³/(s·Pa).
    pub c_m3_s_pa: f64,
    /// Steady state [p_1, p_2, p_e, ω].
    pub y: State,
    /// Port-1 mass flow, kg/s.
    pub flow1_kg_s: f64,
}

/// Where a throttle sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThrottlePort {
    /// In front of port 1.
    Inlet,
    /// Behind port 2.
    Outlet,
}

/// `rig` with a throttle of conductance `c` at `port`.
pub fn with_throttle(rig: &Rig, port: ThrottlePort, c: Option<f64>) -> Rig {
    match port {
        ThrottlePort::Inlet => Rig {
            inlet_throttle: c,
            ..*rig
        },
        ThrottlePort::Outlet => Rig {
            outlet_throttle: c,
            ..*rig
        },
    }
}

/// Steady speed against throttle conductance at constant supply (Fig. 14), each point
/// started from standstill.
pub fn speed_vs_conductance(
    m: &TwinMotor,
    rig: &Rig,
    port: ThrottlePort,
    conductances: &[f64],
) -> Result<Vec<ThrottledPoint>, String> {
    conductances
        .iter()
        .map(|&c| {
            let r = with_throttle(rig, port, Some(c));
            let y = free_steady(m, &r)?;
            Ok(ThrottledPoint {
                c_m3_s_pa: c,
                y,
                flow1_kg_s: port1_flow_kg_s(m, &r, y[0]),
            })
        })
        .collect()
}

/// Shaft torque (air torque less friction) at imposed speeds (Fig. 15), N·m, each speed's
/// pressures seeded by the previous one.
pub fn torque_speed(m: &TwinMotor, rig: &Rig, speeds_rad_s: &[f64]) -> Result<Vec<f64>, String> {
    let mut y = [rig.p_supply_pa, rig.p_atm_pa, rig.p_atm_pa, 0.0];
    speeds_rad_s
        .iter()
        .map(|&w| {
            y = steady_at_speed(m, rig, w, &y)?;
            Ok(motor::air_torque_nm(m, [y[0], y[1], y[2]], w) - motor::friction_torque_nm(m, w))
        })
        .collect()
}

/// The motor linearised about a steady state: Δẏ = A·Δy + b·Δp_supply.
#[derive(Debug, Clone, PartialEq)]
pub struct Linearised {
    /// ∂f/∂y.
    pub a: Matrix4<f64>,
    /// ∂f/∂p_supply.
    pub b: Vector4<f64>,
    /// The steady state.
    pub y: State,
}

/// Linearises the free-running motor about its steady state on `rig` by central differences
/// (steps 1e-4 of each state's size: 10 Pa on a pressure, 1e-4 rad/s on ω at least).
pub fn linearise(m: &TwinMotor, rig: &Rig) -> Result<Linearised, String> {
    let y = free_steady(m, rig)?;
    let scale = [1e5, 1e5, 1e5, 1.0];
    let mut a = Matrix4::zeros();
    for j in 0..4 {
        let h = 1e-4 * y[j].abs().max(scale[j]);
        let (mut yp, mut ym) = (y, y);
        yp[j] += h;
        ym[j] -= h;
        let (fp, fm) = (rhs(m, rig, &yp, false), rhs(m, rig, &ym, false));
        for i in 0..4 {
            a[(i, j)] = (fp[i] - fm[i]) / (2.0 * h);
        }
    }
    let h = 1e-4 * rig.p_supply_pa;
    let up = Rig {
        p_supply_pa: rig.p_supply_pa + h,
        ..*rig
    };
    let down = Rig {
        p_supply_pa: rig.p_supply_pa - h,
        ..*rig
    };
    let (fp, fm) = (rhs(m, &up, &y, false), rhs(m, &down, &y, false));
    let b = Vector4::from_fn(|i, _| (fp[i] - fm[i]) / (2.0 * h));
    Ok(Linearised { a, b, y })
}

impl Linearised {
    /// Speed per supply pressure at angular frequency w: e_ω·(jw·I − A)⁻¹·b, (rad/s)/Pa.
    pub fn speed_per_supply(&self, w_rad_s: f64) -> Complex<f64> {
        let jw = Complex::new(0.0, w_rad_s);
        let m = Matrix4::<Complex<f64>>::identity() * jw - self.a.map(|v| Complex::new(v, 0.0));
        let b = self.b.map(|v| Complex::new(v, 0.0));
        let x = m.lu().solve(&b).expect("jwI - A regular");
        x[3]
    }
}

/// The first-order pressure valve and the discrete PI of the speed loop (paper §5.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpeedLoop {
    /// Valve time constant τ, s.
    pub valve_tau_s: f64,
    /// Command for full pressure, V.
    pub u_max_v: f64,
    /// Gauge pressure at full command, Pa.
    pub p_max_gauge_pa: f64,
    /// Proportional gain, V per krpm.
    pub kp: f64,
    /// Integral gain, V per krpm per s.
    pub ki: f64,
    /// Sample time, s.
    pub ts_s: f64,
}

impl Default for SpeedLoop {
    /// The paper's loop: valve τ = 0.05 s, 0–10 V → 0–6 bar g, PI (0.85·s + 4)/s, 1 ms.
    fn default() -> Self {
        Self {
            valve_tau_s: 0.05,
            u_max_v: 10.0,
            p_max_gauge_pa: 6e5,
            kp: 0.85,
            ki: 4.0,
            ts_s: 1e-3,
        }
    }
}

/// Speed unit of the controller's error: 1 krpm in rad/s.
pub const KRPM_RAD_S: f64 = 1000.0 * RAD_S_PER_RPM;

impl SpeedLoop {
    /// Valve set pressure for command u (saturated to [0, u_max]), Pa absolute.
    pub fn set_pressure_pa(&self, u_v: f64, p_atm_pa: f64) -> f64 {
        p_atm_pa + self.p_max_gauge_pa * u_v.clamp(0.0, self.u_max_v) / self.u_max_v
    }

    /// Loop gain L(jw) = (K_p + K_i/(jw))·V(jw)·G(jw)·e^(−jwT_s/2)/ω_unit.
    pub fn open_loop(&self, lin: &Linearised, w_rad_s: f64) -> Complex<f64> {
        let jw = Complex::new(0.0, w_rad_s);
        let pi = Complex::new(self.kp, 0.0) + Complex::new(self.ki, 0.0) / jw;
        let valve =
            Complex::new(self.p_max_gauge_pa / self.u_max_v, 0.0) / (jw * self.valve_tau_s + 1.0);
        let hold = Complex::from_polar(1.0, -w_rad_s * self.ts_s / 2.0);
        pi * valve * lin.speed_per_supply(w_rad_s) * hold / KRPM_RAD_S
    }
}

/// Gain crossover |L| = 1 (rad/s) and the phase margin there (degrees), found by bisection
/// in log w between `w_lo` (|L| > 1) and `w_hi` (|L| < 1); the phase is unwrapped by
/// following arg L on a fine log grid from `w_lo`.
pub fn crossover(lp: &SpeedLoop, lin: &Linearised, w_lo: f64, w_hi: f64) -> (f64, f64) {
    let mag = |w: f64| lp.open_loop(lin, w).norm();
    let (mut lo, mut hi) = (w_lo.ln(), w_hi.ln());
    assert!(
        mag(w_lo) > 1.0 && mag(w_hi) < 1.0,
        "no gain crossover in the band"
    );
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if mag(mid.exp()) > 1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let wc = (0.5 * (lo + hi)).exp();
    let n = 4000;
    let mut phase = lp.open_loop(lin, w_lo).arg();
    let mut prev = lp.open_loop(lin, w_lo);
    for k in 1..=n {
        let w = (w_lo.ln() + (wc.ln() - w_lo.ln()) * k as f64 / n as f64).exp();
        let l = lp.open_loop(lin, w);
        phase += (l / prev).arg();
        prev = l;
    }
    (wc, 180.0 + phase.to_degrees())
}

/// Supply pressure at which ω is a steady speed, Pa absolute (the root of the net torque in
/// the supply pressure, the pressures inside steady at ω), by the secant method from the
/// bracket [`p_lo`, `p_hi`]; `guess` seeds the pressures. Returns the pressure and the state.
pub fn supply_for_speed(
    m: &TwinMotor,
    rig: &Rig,
    w_rad_s: f64,
    (p_lo, p_hi): (f64, f64),
) -> Result<(f64, State), String> {
    let eval = |p: f64| -> Result<(f64, State), String> {
        let r = Rig {
            p_supply_pa: p,
            ..*rig
        };
        let y = steady_at_speed(m, &r, w_rad_s, &[p, r.p_atm_pa, r.p_atm_pa, w_rad_s])?;
        Ok((net_torque_nm(m, &r, &y), y))
    };
    let (mut a, mut b) = (p_lo, p_hi);
    let (mut fa, _) = eval(a)?;
    let (mut fb, mut yb) = eval(b)?;
    if fa * fb > 0.0 {
        return Err(format!(
            "no supply pressure in [{a}, {b}] Pa holds {w_rad_s} rad/s"
        ));
    }
    // Illinois-modified regula falsi: keeps the bracket, converges superlinearly.
    let mut side = 0;
    for _ in 0..100 {
        let c = b - fb * (b - a) / (fb - fa);
        let (fc, yc) = eval(c)?;
        if fc * fb < 0.0 {
            (a, fa) = (b, fb);
            side = 0;
        } else {
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        }
        (b, fb, yb) = (c, fc, yc);
        if (b - a).abs() < 1e-9 * b || fb == 0.0 {
            break;
        }
    }
    Ok((b, yb))
}

/// A closed-loop scenario: set-point and extra load torque as steps at `t_step_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopScenario {
    /// Set-point before and after the step, rad/s.
    pub setpoint_rad_s: (f64, f64),
    /// Extra load torque before and after the step, N·m.
    pub load_nm: (f64, f64),
    /// Time of the step, s.
    pub t_step_s: f64,
    /// Length, s.
    pub duration_s: f64,
}

/// Sampled closed-loop response: (t s, speed rad/s, command V) at every controller sample.
pub type LoopTrace = Vec<(f64, f64, f64)>;

/// Simulates the loop on `rig` (its supply is the valve's) from the state settled at the
/// initial set-point: the valve settled, the integral at the settled command (bumpless).
pub fn simulate_loop(
    m: &TwinMotor,
    rig: &Rig,
    lp: &SpeedLoop,
    sc: &LoopScenario,
) -> Result<LoopTrace, String> {
    let p_atm = rig.p_atm_pa;
    let full = lp.set_pressure_pa(lp.u_max_v, p_atm);
    let rig0 = Rig {
        extra_load_nm: sc.load_nm.0,
        ..*rig
    };
    let (p0, mut y) = supply_for_speed(m, &rig0, sc.setpoint_rad_s.0, (p_atm * 1.05, full))?;
    let mut p_valve = p0;
    let mut integral = (p0 - p_atm) * lp.u_max_v / lp.p_max_gauge_pa;
    let n = (sc.duration_s / lp.ts_s).round() as usize;
    let mut trace = Vec::with_capacity(n + 1);
    let tol = Tolerances {
        rtol: 1e-9,
        atol: [1e-3, 1e-3, 1e-3, 1e-6],
    };
    for k in 0..=n {
        let t = k as f64 * lp.ts_s;
        let after = t >= sc.t_step_s - 1e-12;
        let r = if after {
            sc.setpoint_rad_s.1
        } else {
            sc.setpoint_rad_s.0
        };
        let extra = if after { sc.load_nm.1 } else { sc.load_nm.0 };
        let e = (r - y[3]) / KRPM_RAD_S;
        let v = lp.kp * e + integral;
        let u = v.clamp(0.0, lp.u_max_v);
        trace.push((t, y[3], u));
        if k == n {
            break;
        }
        let pushing_out = (v > lp.u_max_v && e > 0.0) || (v < 0.0 && e < 0.0);
        if !pushing_out {
            integral += lp.ki * lp.ts_s * e;
        }
        let p_cmd = lp.set_pressure_pa(u, p_atm);
        let pv0 = p_valve;
        let valve_at = |s: f64| p_cmd + (pv0 - p_cmd) * (-s / lp.valve_tau_s).exp();
        let f = |tau: f64, x: &State| {
            let r = Rig {
                p_supply_pa: valve_at(tau).max(p_atm),
                extra_load_nm: extra,
                ..*rig
            };
            rhs(m, &r, x, false)
        };
        let mut integ = TrBdf2::new(f, tol);
        integ.h_max_s = lp.ts_s;
        y = integ.advance(0.0, &y, lp.ts_s)?;
        p_valve = valve_at(lp.ts_s);
    }
    Ok(trace)
}

/// Forward air torque at standstill with the pressures steady there, less the static
/// friction and the load at rest, N·m, at supply `p_supply_pa`.
fn breakaway_margin_nm(m: &TwinMotor, rig: &Rig, p_supply_pa: f64) -> Result<f64, String> {
    let r = Rig {
        p_supply_pa,
        ..*rig
    };
    let y = steady_at_speed(m, &r, 0.0, &[p_supply_pa, r.p_atm_pa, r.p_atm_pa, 0.0])?;
    Ok(
        motor::cycle_torque_nm(m, y[0], y[1], y[2])
            - motor::static_friction_nm(m)
            - r.extra_load_nm,
    )
}

/// Supply pressure at which the standing motor breaks away (forward torque at standstill =
/// static friction + load), Pa absolute, by bisection in [p_atm, `p_max`].
pub fn breakaway_pressure_pa(m: &TwinMotor, rig: &Rig, p_max: f64) -> Result<f64, String> {
    let (mut lo, mut hi) = (rig.p_atm_pa, p_max);
    if breakaway_margin_nm(m, rig, hi)? < 0.0 {
        return Err("the motor does not break away below the ramp's top".into());
    }
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if breakaway_margin_nm(m, rig, mid)? < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}
