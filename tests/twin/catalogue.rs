//! A catalogue row computed by the twin, independently of vanefit: free speed from the
//! free-running steady state, stall torque by the datasheet's stall convention, maximum
//! power by golden-section search of P(ω) = T(ω)·ω on [0, free speed] (after a scan that
//! brackets it), air consumption as the port-1 mass flow.

use super::experiment::Conditions;
use super::motor::{self, TwinMotor};
use super::rig::{self, Boundary, Port2};
use super::steady::steady_state;

/// The catalogue row of a motor at one supply pressure, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwinRow {
    /// Free speed, rad/s.
    pub free_speed_rad_s: f64,
    /// Maximum shaft power, W.
    pub max_power_w: f64,
    /// Speed of maximum power, rad/s.
    pub speed_at_max_power_rad_s: f64,
    /// Shaft torque there, N·m.
    pub torque_at_max_power_nm: f64,
    /// Stall torque (air torque at ω = 0 less the full static friction), N·m.
    pub stall_torque_nm: f64,
    /// Port-1 mass flow at maximum power, kg/s.
    pub air_at_max_power_kg_s: f64,
    /// Port-1 mass flow at free speed, kg/s.
    pub air_at_free_speed_kg_s: f64,
}

/// (shaft torque N·m, port-1 flow kg/s) at an imposed speed `w_rad_s` under the conditions
/// `c` (port 2 open, no load): a point of a catalogue page's curves.
pub fn curve_point(m: &TwinMotor, c: &Conditions, w_rad_s: f64) -> Result<(f64, f64), String> {
    let bc = Boundary {
        p_port1_pa: c.p_supply_pa,
        port2: Port2::Open,
        p_atm_pa: c.p_atm_pa,
        brake_nm_s_rad: 0.0,
        throttle_b_crit: c.throttle_b_crit,
    };
    at_speed(m, &bc, w_rad_s)
}

/// (shaft torque N·m, port-1 flow kg/s) at an imposed speed.
fn at_speed(m: &TwinMotor, bc: &Boundary, w: f64) -> Result<(f64, f64), String> {
    let y0 = [bc.p_port1_pa, bc.p_atm_pa, bc.p_atm_pa, w];
    let y = steady_state(|x| rig::rhs(m, bc, x, true), &y0, true)?;
    let torque = if w == 0.0 {
        motor::air_torque_nm(m, [y[0], y[1], y[2]], 0.0)
            - motor::static_friction_nm(m)
            - motor::law_static_nm(m, [y[0], y[1], y[2]])
    } else {
        rig::shaft_torque_nm(m, &y)
    };
    Ok((torque, rig::flow1_kg_s(m, bc, y[0])))
}

/// The row at `c.p_supply_pa` (port 2 open, no load).
pub fn catalogue_row(m: &TwinMotor, c: &Conditions) -> Result<TwinRow, String> {
    let bc = Boundary {
        p_port1_pa: c.p_supply_pa,
        port2: Port2::Open,
        p_atm_pa: c.p_atm_pa,
        brake_nm_s_rad: 0.0,
        throttle_b_crit: c.throttle_b_crit,
    };
    let free = super::experiment::free_running_state(m, c)?;
    let w_free = free[3];
    let power = |w: f64| at_speed(m, &bc, w).map(|(t, _)| t * w);
    // Scan 40 intervals, then golden section inside the best point's neighbours.
    let n = 40;
    let mut best = (0, f64::NEG_INFINITY);
    for k in 1..n {
        let p = power(w_free * k as f64 / n as f64)?;
        if p > best.1 {
            best = (k, p);
        }
    }
    let (mut a, mut b) = (
        w_free * (best.0 - 1) as f64 / n as f64,
        w_free * (best.0 + 1) as f64 / n as f64,
    );
    let g = (5f64.sqrt() - 1.0) / 2.0;
    while b - a > 1e-7 * w_free {
        let (x1, x2) = (b - g * (b - a), a + g * (b - a));
        if power(x1)? > power(x2)? {
            b = x2;
        } else {
            a = x1;
        }
    }
    let w_max = 0.5 * (a + b);
    let (t_max, air_max) = at_speed(m, &bc, w_max)?;
    let (stall, _) = at_speed(m, &bc, 0.0)?;
    Ok(TwinRow {
        free_speed_rad_s: w_free,
        max_power_w: t_max * w_max,
        speed_at_max_power_rad_s: w_max,
        torque_at_max_power_nm: t_max,
        stall_torque_nm: stall,
        air_at_max_power_kg_s: air_max,
        air_at_free_speed_kg_s: rig::flow1_kg_s(m, &bc, free[0]),
    })
}
