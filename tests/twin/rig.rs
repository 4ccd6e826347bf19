//! The motor on the rig: port boundaries, load and the state equations (docs/model.md,
//! "Lumped volumes and nozzles", "Mechanics and friction", "Reference experiments").
//!
//! State y = [p_1, p_2, p_e, ω] (Pa, Pa, Pa, rad/s). Isothermal volumes:
//! dp_i/dt = R·T0/V_i · Σṁ_i; mechanics: J·dω/dt = T_air − T_f(ω) − T_load.

use super::motor::{self, TwinMotor};

/// What lies behind port 2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Port2 {
    /// Port 2 open to atmosphere.
    Open,
    /// A nozzle of this sonic conductance (m³/(s·Pa)) in series behind out_2, then atmosphere.
    Throttle(f64),
}

/// The rig's boundary conditions at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boundary {
    /// Absolute pressure at port 1, Pa.
    pub p_port1_pa: f64,
    /// Port 2's connection.
    pub port2: Port2,
    /// Atmospheric pressure, Pa.
    pub p_atm_pa: f64,
    /// Viscous brake coefficient c, N·m·s/rad (load torque c·ω).
    pub brake_nm_s_rad: f64,
    /// Critical pressure ratio of the rig's outlet throttle, 1; `None`: the motor's b_crit, which
    /// (docs/model.md, "Parameters") defines as the ratio "of every nozzle" (vanefit reads it so
    /// too).
    pub throttle_b_crit: Option<f64>,
}

/// Mass flow through two nozzles in series with no volume between them, kg/s, from p_u to
/// p_d: the intermediate pressure p_x solves ṁ_a(p_u, p_x) = ṁ_b(p_x, p_d), found by
/// bisection (ṁ_a − ṁ_b falls monotonically in p_x) to the last representable digit.
pub fn series_flow_kg_s(ca: (f64, f64), cb: (f64, f64), pu_pa: f64, pd_pa: f64) -> f64 {
    let flow_a = |px: f64| motor::nozzle_flow_kg_s(ca.0, ca.1, pu_pa, px);
    let flow_b = |px: f64| motor::nozzle_flow_kg_s(cb.0, cb.1, px, pd_pa);
    let (mut lo, mut hi) = (pu_pa.min(pd_pa), pu_pa.max(pd_pa));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if flow_a(mid) > flow_b(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let px = 0.5 * (lo + hi);
    0.5 * (flow_a(px) + flow_b(px))
}

/// Port-1 mass flow INTO the motor (supply → in_1 → V_1), kg/s.
pub fn flow1_kg_s(m: &TwinMotor, bc: &Boundary, p1_pa: f64) -> f64 {
    motor::nozzle_flow_kg_s(m.c_in1, m.b_crit, bc.p_port1_pa, p1_pa)
}

/// Port-2 mass flow OUT of the motor (V_2 → out_2 → \[throttle\] → atmosphere), kg/s.
pub fn flow2_kg_s(m: &TwinMotor, bc: &Boundary, p2_pa: f64) -> f64 {
    match bc.port2 {
        Port2::Open => motor::nozzle_flow_kg_s(m.c_out2, m.b_crit, p2_pa, bc.p_atm_pa),
        Port2::Throttle(c) => series_flow_kg_s(
            (m.c_out2, m.b_crit),
            (c, bc.throttle_b_crit.unwrap_or(m.b_crit)),
            p2_pa,
            bc.p_atm_pa,
        ),
    }
}

/// Net mass flows into V_1, V_2, V_e, kg/s, including the port flows.
pub fn volume_flows_kg_s(m: &TwinMotor, bc: &Boundary, y: &[f64; 4]) -> [f64; 3] {
    let p = [y[0], y[1], y[2]];
    let [q1, q2, qe] = motor::internal_flows_kg_s(m, p, y[3], bc.p_atm_pa);
    [
        q1 + flow1_kg_s(m, bc, y[0]),
        q2 - flow2_kg_s(m, bc, y[1]),
        qe,
    ]
}

/// Shaft torque delivered to the load, T_air − T_f(ω), N·m.
pub fn shaft_torque_nm(m: &TwinMotor, y: &[f64; 4]) -> f64 {
    let p = [y[0], y[1], y[2]];
    motor::air_torque_nm(m, p, y[3])
        - motor::friction_torque_nm(m, y[3])
        - motor::law_friction_nm(m, p, y[3])
}

/// dy/dt. With `speed_imposed` the speed is held (dω/dt = 0), as on a datasheet's brake.
pub fn rhs(m: &TwinMotor, bc: &Boundary, y: &[f64; 4], speed_imposed: bool) -> [f64; 4] {
    let q = volume_flows_kg_s(m, bc, y);
    let rt = motor::RT0_J_KG;
    let dw = if speed_imposed {
        0.0
    } else {
        (shaft_torque_nm(m, y) - bc.brake_nm_s_rad * y[3]) / m.inertia
    };
    [
        rt / m.vol1 * q[0],
        rt / m.vol2 * q[1],
        rt / m.vole * q[2],
        dw,
    ]
}
