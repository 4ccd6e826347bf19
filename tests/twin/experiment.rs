//! The three reference experiments (docs/model.md, "Reference experiments"), noise-free, in
//! SI units.

use super::motor::{self, TwinMotor};
use super::ode::{State, Tolerances, TrBdf2};
use super::rig::{self, Boundary, Port2};
use super::steady::steady_state;

/// How the experiments are run (the physical conditions, not the sensors).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conditions {
    /// Atmospheric pressure, Pa.
    pub p_atm_pa: f64,
    /// Constant supply pressure (datasheet, throttle; end of the ramp), Pa absolute.
    pub p_supply_pa: f64,
    /// Viscous brake of the transient experiments, N·m·s/rad.
    pub brake_nm_s_rad: f64,
    /// Duration of the pressure ramp, s.
    pub ramp_s: f64,
    /// Duration of the outlet throttle experiment, s.
    pub throttle_s: f64,
    /// Throttle conductance at the start and the end (log-spaced in time), m³/(s·Pa).
    pub c_throttle_m3_s_pa: (f64, f64),
    /// Sample rate of the transient recordings, Hz.
    pub rate_hz: f64,
    /// Number of datasheet points, evenly spaced from 0 to the free speed.
    pub datasheet_points: usize,
    /// Critical pressure ratio of the outlet throttle, 1; `None`: the motor's b_crit
    /// ((docs/model.md, "Parameters"): "critical pressure ratio of every nozzle").
    pub throttle_b_crit: Option<f64>,
    /// Integrator tolerances of the transients.
    pub tol: Tolerances,
}

impl Default for Conditions {
    /// The shipped dataset's conditions: 0.73 MPa abs, brake 1e-4 N·m·s/rad, 60 s ramp,
    /// 65 s throttle from 3e-8 to 1.5e-9 m³/(s·Pa), 10 Hz, 25 datasheet points.
    fn default() -> Self {
        Self {
            p_atm_pa: motor::P_ATM_PA,
            p_supply_pa: 0.73e6,
            brake_nm_s_rad: 1e-4,
            ramp_s: 60.0,
            throttle_s: 65.0,
            c_throttle_m3_s_pa: (3e-8, 1.5e-9),
            rate_hz: 10.0,
            datasheet_points: 25,
            throttle_b_crit: None,
            tol: Tolerances::default(),
        }
    }
}

/// A noise-free datasheet: shaft torque and port-1 flow at imposed speeds.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DatasheetRows {
    /// Imposed speed, rad/s.
    pub speed_rad_s: Vec<f64>,
    /// Shaft torque (air torque less friction; less static friction at ω = 0), N·m.
    pub torque_nm: Vec<f64>,
    /// Port-1 mass flow into the motor, kg/s.
    pub flow1_kg_s: Vec<f64>,
}

/// A noise-free transient recording, one entry per sample.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TransientRows {
    /// Time, s.
    pub t_s: Vec<f64>,
    /// The input: port-1 pressure in Pa (ramp) or port-2 conductance in m³/(s·Pa) (throttle).
    pub input: Vec<f64>,
    /// Port-1 mass flow into the motor, kg/s.
    pub flow1_kg_s: Vec<f64>,
    /// Port-2 mass flow out of the motor, kg/s.
    pub flow2_kg_s: Vec<f64>,
    /// Speed, rad/s.
    pub speed_rad_s: Vec<f64>,
    /// Brake torque c·ω, N·m (what a torque sensor between motor and brake reads).
    pub brake_torque_nm: Vec<f64>,
    /// Exhaust mass flow V_e → atmosphere, kg/s (not a recorded channel; for checks).
    pub exhaust_kg_s: Vec<f64>,
}

fn atm_state(c: &Conditions) -> State {
    [c.p_atm_pa, c.p_atm_pa, c.p_atm_pa, 0.0]
}

fn open_boundary(c: &Conditions, p_port1_pa: f64, brake: f64) -> Boundary {
    Boundary {
        p_port1_pa,
        port2: Port2::Open,
        p_atm_pa: c.p_atm_pa,
        brake_nm_s_rad: brake,
        throttle_b_crit: c.throttle_b_crit,
    }
}

/// Free-running steady state (no load) at the supply pressure; its speed is the free speed.
pub fn free_running_state(m: &TwinMotor, c: &Conditions) -> Result<State, String> {
    let bc = open_boundary(c, c.p_supply_pa, 0.0);
    steady_state(|y| rig::rhs(m, &bc, y, false), &atm_state(c), false)
}

/// Datasheet (docs/model.md, "Reference experiments"): steady pressures at N speeds evenly spaced
/// from 0 to the free speed.
pub fn datasheet(m: &TwinMotor, c: &Conditions) -> Result<DatasheetRows, String> {
    let w_free = free_running_state(m, c)?[3];
    let bc = open_boundary(c, c.p_supply_pa, 0.0);
    let mut rows = DatasheetRows::default();
    let mut y = atm_state(c);
    let n = c.datasheet_points;
    for i in 0..n {
        y[3] = w_free * i as f64 / (n - 1) as f64;
        y = steady_state(|x| rig::rhs(m, &bc, x, true), &y, true)?;
        let torque = if i == 0 {
            motor::air_torque_nm(m, [y[0], y[1], y[2]], 0.0)
                - motor::static_friction_nm(m)
                - motor::law_static_nm(m, [y[0], y[1], y[2]])
        } else {
            rig::shaft_torque_nm(m, &y)
        };
        rows.speed_rad_s.push(y[3]);
        rows.torque_nm.push(torque);
        rows.flow1_kg_s.push(rig::flow1_kg_s(m, &bc, y[0]));
    }
    Ok(rows)
}

/// Pressure ramp (docs/model.md, "Reference experiments"): port 1 from p_atm linearly to the supply
/// over `ramp_s`.
pub fn pressure_ramp(m: &TwinMotor, c: &Conditions) -> Result<TransientRows, String> {
    let slope_pa_s = (c.p_supply_pa - c.p_atm_pa) / c.ramp_s;
    let bc = |t: f64| open_boundary(c, c.p_atm_pa + slope_pa_s * t, c.brake_nm_s_rad);
    transient(m, c, c.ramp_s, bc, |b| b.p_port1_pa)
}

/// Outlet throttle (docs/model.md, "Reference experiments"): constant supply; the port-2 nozzle's
/// conductance falls log-spaced, c(t) = c_0·(c_1/c_0)^(t/T), over `throttle_s`.
pub fn outlet_throttle(m: &TwinMotor, c: &Conditions) -> Result<TransientRows, String> {
    let (c0, c1) = c.c_throttle_m3_s_pa;
    let bc = |t: f64| Boundary {
        port2: Port2::Throttle(c0 * (c1 / c0).powf(t / c.throttle_s)),
        ..open_boundary(c, c.p_supply_pa, c.brake_nm_s_rad)
    };
    let input = |b: &Boundary| match b.port2 {
        Port2::Throttle(c) => c,
        Port2::Open => f64::NAN,
    };
    transient(m, c, c.throttle_s, bc, input)
}

/// Runs a transient from the steady state at t = 0 and samples it at `rate_hz`.
fn transient(
    m: &TwinMotor,
    c: &Conditions,
    duration_s: f64,
    bc: impl Fn(f64) -> Boundary,
    input: impl Fn(&Boundary) -> f64,
) -> Result<TransientRows, String> {
    let b0 = bc(0.0);
    let mut y = steady_state(|x| rig::rhs(m, &b0, x, false), &atm_state(c), false)?;
    let mut integ = TrBdf2::new(|t: f64, x: &State| rig::rhs(m, &bc(t), x, false), c.tol);
    let n = (duration_s * c.rate_hz).round() as usize;
    let mut rows = TransientRows::default();
    for k in 0..=n {
        let t_s = k as f64 / c.rate_hz;
        if k > 0 {
            y = integ.advance((k - 1) as f64 / c.rate_hz, &y, t_s)?;
        }
        let b = bc(t_s);
        rows.t_s.push(t_s);
        rows.input.push(input(&b));
        rows.flow1_kg_s.push(rig::flow1_kg_s(m, &b, y[0]));
        rows.flow2_kg_s.push(rig::flow2_kg_s(m, &b, y[1]));
        rows.speed_rad_s.push(y[3]);
        rows.brake_torque_nm.push(b.brake_nm_s_rad * y[3]);
        rows.exhaust_kg_s
            .push(motor::exhaust_flow_kg_s(m, y[2], c.p_atm_pa));
    }
    Ok(rows)
}
