//! Speed control by throttling (paper §5.1): a nozzle in series at the inlet (port 1, paper
//! Figs. 14 and 15) or at the outlet (port 2).
//!
//! The throttle is an ISO 6358 nozzle of sonic conductance C_th (m³/(s·Pa)) in series with the
//! motor's own duct (`Boundary::c_port1_m3_s_pa` / `c_port2_m3_s_pa`), with the motor's
//! critical ratio b and no volume between the two (`nozzle::series_flow`).
//! * `speed_vs_conductance`: steady speed (free speed under the load, e.g. the rig's
//!   eddy-current brake) against C_th at constant supply pressure (Fig. 14).
//! * `torque_speed`: shaft torque T − T_f against imposed speed for one throttle (Fig. 15),
//!   from standstill up to the speed where the shaft torque reaches zero (free speed).

use super::ControlError;
use crate::model::motor::{idx, Boundary, Load, Motor, State};
use crate::sim::steady;

/// Where the throttle sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Port {
    /// In front of port 1 (supply side).
    Inlet,
    /// Behind port 2 (exhaust side).
    Outlet,
}

impl Port {
    /// `inlet` or `outlet`, as in the study names and messages.
    pub fn name(self) -> &'static str {
        match self {
            Port::Inlet => "inlet",
            Port::Outlet => "outlet",
        }
    }

    /// Boundary with supply at port 1 and the throttle fitted (`None`: no throttle).
    pub(crate) fn boundary(
        self,
        p_supply_pa: f64,
        p_atm_pa: f64,
        load: Load,
        c: Option<f64>,
    ) -> Boundary {
        let mut bc = Boundary::supplied(p_supply_pa, p_atm_pa, load);
        match self {
            Port::Inlet => bc.c_port1_m3_s_pa = c,
            Port::Outlet => bc.c_port2_m3_s_pa = c,
        }
        bc
    }
}

/// A steady state with a throttle fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThrottlePoint {
    /// Throttle conductance, m³/(s·Pa).
    pub c_m3_s_pa: f64,
    /// Steady speed, rad/s.
    pub speed_rad_s: f64,
    /// Shaft torque T − T_f, N·m (equal to the load torque in steady state).
    pub torque_nm: f64,
    /// Mass flow at port 1, kg/s.
    pub flow_kg_s: f64,
    /// Pressure in V_1 (behind an inlet throttle), Pa absolute.
    pub p1_pa: f64,
}

/// Steady speed against throttle conductance at supply `p_supply_pa` under `load`.
/// Solved from the largest conductance down, each state seeding the next. Errors name the
/// conductance at which no steady state was found.
pub(crate) fn speed_vs_conductance(
    motor: &Motor,
    port: Port,
    p_supply_pa: f64,
    p_atm_pa: f64,
    load: Load,
    conductances: &[f64],
) -> Result<Vec<ThrottlePoint>, ControlError> {
    let mut order: Vec<usize> = (0..conductances.len()).collect();
    order.sort_by(|a, b| conductances[*b].total_cmp(&conductances[*a]));
    let mut out = vec![None; conductances.len()];
    let mut guess: Option<State> = None;
    for i in order {
        let c = conductances[i];
        let bc = port.boundary(p_supply_pa, p_atm_pa, load, Some(c));
        let cold = steady::initial_guess(&bc);
        let x = guess
            .map_or_else(
                || steady::free(motor, &bc, &cold),
                |g| steady::free(motor, &bc, &g),
            )
            .or_else(|_| steady::free(motor, &bc, &cold))
            .map_err(|source| ControlError::Throttled {
                port: port.name(),
                c_m3_s_pa: c,
                source,
            })?;
        let b = motor.balance(&x, &bc);
        out[i] = Some(ThrottlePoint {
            c_m3_s_pa: c,
            speed_rad_s: x[idx::OMEGA],
            torque_nm: b.torque_shaft_nm(),
            flow_kg_s: b.flow_port1_kg_s,
            p1_pa: x[idx::P1],
        });
        guess = Some(x);
    }
    Ok(out.into_iter().flatten().collect())
}

/// First speed of a torque–speed curve, rad/s (≈ 48 rpm: friction and the forward/reverse
/// torque blend are fully developed, tanh(5/ω_reg) = tanh(5/ω_b) ≈ 1).
const W_CURVE_START_RAD_S: f64 = 5.0;

/// A point of a torque–speed characteristic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TorquePoint {
    /// Imposed speed, rad/s.
    pub speed_rad_s: f64,
    /// Shaft torque T − T_f, N·m.
    pub torque_nm: f64,
    /// Mass flow at port 1, kg/s.
    pub flow_kg_s: f64,
}

/// Torque–speed characteristic at supply `p_supply_pa` with throttle `c` (`None`: none), at
/// `n` speeds from [`W_CURVE_START_RAD_S`] to `w_max`; the curve ends at the first speed
/// where the shaft torque is no longer positive, cut at zero torque by linear
/// interpolation. It starts just above standstill because at ω = 0 exactly the regularised
/// Coulomb friction T_c·tanh(ω/ω_reg) is zero, which would show the stall torque without
/// friction.
pub(crate) fn torque_speed(
    motor: &Motor,
    port: Port,
    p_supply_pa: f64,
    p_atm_pa: f64,
    c: Option<f64>,
    w_max_rad_s: f64,
    n: usize,
) -> Result<Vec<TorquePoint>, ControlError> {
    let bc = port.boundary(p_supply_pa, p_atm_pa, Load::None, c);
    let mut guess = steady::initial_guess(&bc);
    let mut out: Vec<TorquePoint> = Vec::with_capacity(n);
    let n = n.max(2);
    for k in 0..n {
        let w =
            W_CURVE_START_RAD_S + (w_max_rad_s - W_CURVE_START_RAD_S) * k as f64 / (n - 1) as f64;
        let x = steady::at_speed(motor, &bc, w, &guess)
            .or_else(|_| steady::at_speed(motor, &bc, w, &steady::initial_guess(&bc)))
            .map_err(|source| ControlError::TorqueSpeed {
                port: port.name(),
                c_m3_s_pa: c,
                speed_rpm: w / super::RAD_S_PER_RPM,
                source,
            })?;
        let b = motor.balance(&x, &bc);
        let p = TorquePoint {
            speed_rad_s: w,
            torque_nm: b.torque_shaft_nm(),
            flow_kg_s: b.flow_port1_kg_s,
        };
        if p.torque_nm <= 0.0 && k > 0 {
            if let Some(prev) = out.last().copied() {
                let f = prev.torque_nm / (prev.torque_nm - p.torque_nm);
                out.push(TorquePoint {
                    speed_rad_s: prev.speed_rad_s + f * (p.speed_rad_s - prev.speed_rad_s),
                    torque_nm: 0.0,
                    flow_kg_s: prev.flow_kg_s + f * (p.flow_kg_s - prev.flow_kg_s),
                });
            }
            break;
        }
        out.push(p);
        guess = x;
    }
    Ok(out)
}

/// Log-spaced conductances from `c_min` to `c_max` (both included), m³/(s·Pa).
pub(crate) fn conductance_grid(c_min: f64, c_max: f64, n: usize) -> Vec<f64> {
    super::linear::log_grid(c_min, c_max, n)
}

#[cfg(test)]
mod tests {
    use super::*;

    const P_ATM: f64 = 101_325.0;
    const BRAKE: Load = Load::ViscousBrake { c_nm_s_rad: 1e-4 };

    #[test]
    fn speed_rises_with_conductance_and_approaches_the_unthrottled_speed() {
        let m = Motor::default_motor();
        let cs = conductance_grid(3e-10, 1e-7, 12);
        for port in [Port::Inlet, Port::Outlet] {
            let pts = speed_vs_conductance(&m, port, 7.3e5, P_ATM, BRAKE, &cs).unwrap();
            assert_eq!(pts.len(), cs.len());
            for w in pts.windows(2) {
                // Non-decreasing (a wide-open outlet throttle changes the speed by less
                // than the steady solver's tolerance).
                assert!(
                    w[1].speed_rad_s >= w[0].speed_rad_s * (1.0 - 1e-9),
                    "{port:?}: {:?} then {:?}",
                    w[0],
                    w[1]
                );
            }
            let bc = port.boundary(7.3e5, P_ATM, BRAKE, None);
            let free = steady::free(&m, &bc, &steady::initial_guess(&bc)).unwrap();
            let last = pts.last().unwrap().speed_rad_s;
            // A throttle 15 times the duct's conductance costs only a few percent of speed…
            // (equal within the steady solver's tolerance when the throttle is wide open)
            assert!(last <= free[idx::OMEGA] * (1.0 + 1e-9) && last > 0.9 * free[idx::OMEGA]);
            // …and the smallest one brings the motor well down.
            assert!(pts[0].speed_rad_s < 0.5 * free[idx::OMEGA], "{:?}", pts[0]);
        }
    }

    #[test]
    fn inlet_throttle_lowers_torque_at_every_speed() {
        let m = Motor::default_motor();
        let w_max = 1300.0;
        let open = torque_speed(&m, Port::Inlet, 7.3e5, P_ATM, None, w_max, 30).unwrap();
        let thr = torque_speed(&m, Port::Inlet, 7.3e5, P_ATM, Some(3e-9), w_max, 30).unwrap();
        // Each curve ends at zero torque (free speed), the throttled one earlier.
        assert_eq!(open.last().unwrap().torque_nm, 0.0);
        assert_eq!(thr.last().unwrap().torque_nm, 0.0);
        assert!(thr.last().unwrap().speed_rad_s < open.last().unwrap().speed_rad_s);
        for (a, b) in thr.iter().zip(&open).take(thr.len() - 1) {
            assert!(a.torque_nm < b.torque_nm, "{a:?} vs {b:?}");
        }
    }
}
