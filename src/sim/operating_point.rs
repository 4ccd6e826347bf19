//! Steady operating points of a motor at a supply pressure, and the figures a catalogue
//! gives for it (free speed, maximum power, stall torque, air consumption): what `vanefit
//! predict` tabulates (docs/formats.md, "Contracts added later"; docs/model.md, "Catalogue
//! figures and predictions").
//!
//! Every point is a steady state at an imposed speed ω ([`steady::at_speed`], as the
//! datasheet experiment measures it; docs/model.md, "Reference experiments") with no load,
//! supply at port 1, port 2 and the exhaust to atmosphere, and optionally an extra ISO 6358
//! nozzle in series in front of port 1 or behind port 2 ([`Boundary::c_port1_m3_s_pa`],
//! [`Boundary::c_port2_m3_s_pa`]). The shaft torque is T − T_f (docs/model.md, "Mechanics
//! and friction"); at exactly ω = 0 it is the stall torque by the convention of
//! docs/model.md, "Conventions" (`shaft_torque`, shared with the datasheet experiment).
//! Power is P = T·ω (W); air consumption is the mass flow into port 1 (kg/s).

use crate::model::motor::{idx, Balance, Boundary, Load, Motor, State};
use crate::numerics::scalar::{brent_minimize, brent_root, Bracket};
use crate::sim::steady::{self, SteadyError};

/// Where and how the motor is supplied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Conditions {
    /// Supply pressure at port 1, Pa absolute.
    pub p_supply_pa: f64,
    /// Atmosphere that port 2 and the exhaust discharge to, Pa absolute.
    pub p_atm_pa: f64,
    /// Extra nozzle in series in front of port 1 (inlet throttling), m³/(s·Pa).
    pub(crate) c_inlet_m3_s_pa: Option<f64>,
    /// Extra nozzle in series behind port 2 (outlet throttling), m³/(s·Pa).
    pub(crate) c_outlet_m3_s_pa: Option<f64>,
}

impl Conditions {
    /// Supply at port 1, no extra nozzle.
    pub fn supplied(p_supply_pa: f64, p_atm_pa: f64) -> Self {
        Self {
            p_supply_pa,
            p_atm_pa,
            c_inlet_m3_s_pa: None,
            c_outlet_m3_s_pa: None,
        }
    }

    /// The motor's boundary: no load (the speed is imposed), nozzles as given.
    pub(crate) fn boundary(&self) -> Boundary {
        Boundary {
            c_port1_m3_s_pa: self.c_inlet_m3_s_pa,
            c_port2_m3_s_pa: self.c_outlet_m3_s_pa,
            ..Boundary::supplied(self.p_supply_pa, self.p_atm_pa, Load::None)
        }
    }
}

/// A steady state at an imposed speed, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OperatingPoint {
    /// Imposed speed ω, rad/s.
    pub speed_rad_s: f64,
    /// Shaft torque T − T_f, N·m (`shaft_torque`).
    pub torque_nm: f64,
    /// Shaft power T·ω, W.
    pub power_w: f64,
    /// Mass flow into port 1 (the air consumption), kg/s.
    pub flow1_kg_s: f64,
    /// Mass flow out of port 2, kg/s.
    pub flow2_kg_s: f64,
}

/// The shaft torque at a steady state `x` with balance `b`, N·m: T − T_f while turning; at
/// exactly ω = 0 the air torque less the full dry friction at rest
/// ([`Motor::friction_at_rest`]), since a brake holding the rotor measures a datasheet's
/// stall torque against the breakaway friction, where the regularised T_c·tanh(ω/ω_reg)
/// would be zero (docs/model.md, "Reference experiments", datasheet). The one place this
/// rule lives: the datasheet experiment and the catalogue figures use it alike.
pub(crate) fn shaft_torque(motor: &Motor, x: &State, b: &Balance) -> f64 {
    if x[idx::OMEGA] == 0.0 {
        b.torque_ideal_nm - motor.friction_at_rest(x[idx::P1], x[idx::PE])
    } else {
        b.torque_shaft_nm()
    }
}

/// Steady states at several imposed speeds (rad/s), returned in the order given. They are
/// solved in speed order, each from its neighbour's solution (as the datasheet experiment
/// sweeps), falling back to a cold start where that fails.
pub(crate) fn at_speeds(
    motor: &Motor,
    conditions: &Conditions,
    speeds_rad_s: &[f64],
) -> Result<Vec<OperatingPoint>, SteadyError> {
    let mut order: Vec<usize> = (0..speeds_rad_s.len()).collect();
    order.sort_by(|a, b| speeds_rad_s[*a].total_cmp(&speeds_rad_s[*b]));
    let mut sweep = Sweep::new(motor, conditions);
    let mut out = vec![None; speeds_rad_s.len()];
    for i in order {
        out[i] = Some(sweep.point(speeds_rad_s[i])?);
    }
    Ok(out.into_iter().flatten().collect())
}

/// Steady solves at one condition, each started from the solved state nearest in speed.
struct Sweep<'a> {
    motor: &'a Motor,
    bc: Boundary,
    solved: Vec<(f64, State)>,
}

impl<'a> Sweep<'a> {
    fn new(motor: &'a Motor, conditions: &Conditions) -> Self {
        Self {
            motor,
            bc: conditions.boundary(),
            solved: Vec::new(),
        }
    }

    /// The operating point at ω, rad/s.
    fn point(&mut self, omega: f64) -> Result<OperatingPoint, SteadyError> {
        let near = self
            .solved
            .iter()
            .min_by(|a, b| (a.0 - omega).abs().total_cmp(&(b.0 - omega).abs()))
            .map(|(_, x)| *x);
        let (motor, bc) = (self.motor, &self.bc);
        // From the usual guess (inlet at supply), else from every chamber at atmosphere: a
        // motor starved by an inlet nozzle (C ≲ 1e-12 m³/(s·Pa)) sits a few pascals above
        // atmosphere, which continuation from supply pressure does not reach in its budget.
        let cold = || {
            steady::at_speed(motor, bc, omega, &steady::initial_guess(bc))
                .or_else(|_| steady::at_speed(motor, bc, omega, &[bc.p_atm_pa; 4]))
        };
        let x = match near {
            Some(g) => steady::at_speed_from_neighbour(motor, bc, omega, &g).or_else(|_| cold()),
            None => cold(),
        }?;
        self.solved.push((omega, x));
        let b = motor.balance(&x, bc);
        let torque_nm = shaft_torque(motor, &x, &b);
        Ok(OperatingPoint {
            speed_rad_s: omega,
            torque_nm,
            power_w: torque_nm * omega,
            flow1_kg_s: b.flow_port1_kg_s,
            flow2_kg_s: b.flow_port2_kg_s,
        })
    }
}

/// Why a catalogue row could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum OperatingPointError {
    /// A steady state was not found.
    #[error(transparent)]
    Steady(#[from] SteadyError),
    /// The stall torque is not positive: the motor does not start at this pressure.
    #[error(
        "the motor does not start: its stall torque is {stall_torque_nm:.4} N·m (≤ 0, the \
         air cannot overcome the friction at rest)"
    )]
    DoesNotStart {
        /// Supply pressure, Pa absolute.
        p_supply_pa: f64,
        /// Stall torque, N·m.
        stall_torque_nm: f64,
    },
    /// The shaft torque stays positive up to an absurd speed.
    #[error("the shaft torque is still positive at {up_to_rad_s:.3e} rad/s: no free speed")]
    NoFreeSpeed {
        /// Supply pressure, Pa absolute.
        p_supply_pa: f64,
        /// The highest speed tried, rad/s.
        up_to_rad_s: f64,
    },
    /// The speed grid of the maximum power is not a positive number.
    #[error("the speed grid must be a positive number of rad/s, not {0}")]
    BadGrid(f64),
}

/// What a catalogue states for one supply pressure, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CatalogueRow {
    /// Supply pressure, Pa absolute.
    pub p_supply_pa: f64,
    /// Free (no-load) speed, where the shaft torque is zero, rad/s.
    pub free_speed_rad_s: f64,
    /// Maximum shaft power on the speed grid, W.
    pub max_power_w: f64,
    /// The grid speed k·Δ of the maximum power, rad/s.
    pub speed_at_max_power_rad_s: f64,
    /// Shaft torque at that speed, N·m.
    pub torque_at_max_power_nm: f64,
    /// Shaft torque at standstill (`shaft_torque` at ω = 0), N·m.
    pub stall_torque_nm: f64,
    /// Mass flow into port 1 at the maximum power's grid speed, kg/s.
    pub air_at_max_power_kg_s: f64,
    /// Mass flow into port 1 at the free speed, kg/s.
    pub air_at_free_speed_kg_s: f64,
    /// The grid spacing Δ of the maximum power, rad/s.
    pub(crate) speed_grid_rad_s: f64,
    /// The maximum power off the grid (the continuous optimum of P(ω)): smooth in the
    /// parameters, where the grid point moves in steps of Δ.
    pub(crate) optimum: OperatingPoint,
}

/// The catalogue figures at one condition.
///
/// * Stall torque: `shaft_torque` at ω = 0. A motor whose stall torque is ≤ 0 does not
///   start: [`OperatingPointError::DoesNotStart`].
/// * Free speed ω_0: the root of the shaft torque T(ω) = 0, bracketed by doubling an upper
///   speed from 64 rad/s until T < 0, then found by Brent's method to 1e-9 relative.
/// * Maximum power: P(ω) = T(ω)·ω on [0, ω_0]. A coarse scan (32 intervals) brackets the
///   global maximum, Brent's minimiser finds the continuous optimum ω* (to 1e-7 relative),
///   and the result is exact on the grid of spacing Δ = `speed_grid_rad_s` (1 rpm in the
///   command line): of the grid points k·Δ from ⌊ω*/Δ⌋ − 1 to ⌈ω*/Δ⌉ + 1 inside [0, ω_0],
///   the one of largest power (P is concave there, so no grid point farther off can beat
///   them). Torque and air at maximum power are those of that grid point.
pub fn catalogue_row(
    motor: &Motor,
    conditions: &Conditions,
    speed_grid_rad_s: f64,
) -> Result<CatalogueRow, OperatingPointError> {
    if !(speed_grid_rad_s.is_finite() && speed_grid_rad_s > 0.0) {
        return Err(OperatingPointError::BadGrid(speed_grid_rad_s));
    }
    let mut sweep = Sweep::new(motor, conditions);
    let stall = sweep.point(0.0)?;
    if stall.torque_nm.is_nan() || stall.torque_nm <= 0.0 {
        return Err(OperatingPointError::DoesNotStart {
            p_supply_pa: conditions.p_supply_pa,
            stall_torque_nm: stall.torque_nm,
        });
    }
    let free = free_speed(&mut sweep, &stall, conditions.p_supply_pa)?;
    let (optimum, best) = max_power(&mut sweep, free.speed_rad_s, speed_grid_rad_s)?;
    Ok(CatalogueRow {
        p_supply_pa: conditions.p_supply_pa,
        free_speed_rad_s: free.speed_rad_s,
        max_power_w: best.power_w,
        speed_at_max_power_rad_s: best.speed_rad_s,
        torque_at_max_power_nm: best.torque_nm,
        stall_torque_nm: stall.torque_nm,
        air_at_max_power_kg_s: best.flow1_kg_s,
        air_at_free_speed_kg_s: free.flow1_kg_s,
        speed_grid_rad_s,
        optimum,
    })
}

/// The first upper speed tried for the free speed, rad/s (≈ 600 rpm: a few doublings reach
/// any vane motor's free speed).
const FIRST_UPPER_RAD_S: f64 = 64.0;
/// Doublings of the upper speed before giving up (64·2²⁰ rad/s ≈ 6e8 rpm).
const MAX_DOUBLINGS: usize = 20;

/// The point of zero shaft torque above standstill (see [`catalogue_row`]).
fn free_speed(
    sweep: &mut Sweep<'_>,
    stall: &OperatingPoint,
    p_supply_pa: f64,
) -> Result<OperatingPoint, OperatingPointError> {
    let (mut lo, mut t_lo) = (0.0, stall.torque_nm);
    let mut hi = FIRST_UPPER_RAD_S;
    let mut bracket = None;
    for _ in 0..=MAX_DOUBLINGS {
        let t_hi = sweep.point(hi)?.torque_nm;
        bracket = Bracket::new(lo, t_lo, hi, t_hi);
        if bracket.is_some() {
            break;
        }
        (lo, t_lo) = (hi, t_hi);
        hi *= 2.0;
    }
    let bracket = bracket.ok_or(OperatingPointError::NoFreeSpeed {
        p_supply_pa,
        up_to_rad_s: lo,
    })?;
    let root = brent_root(|w| sweep.point(w).map(|p| p.torque_nm), bracket, 1e-9)?;
    Ok(sweep.point(root)?)
}

/// Intervals of the coarse scan that brackets the maximum power.
const COARSE_INTERVALS: usize = 32;

/// The continuous maximum of P(ω) on [0, ω_0] and the best grid point near it (see
/// [`catalogue_row`]).
fn max_power(
    sweep: &mut Sweep<'_>,
    free_speed_rad_s: f64,
    grid_rad_s: f64,
) -> Result<(OperatingPoint, OperatingPoint), SteadyError> {
    let n = COARSE_INTERVALS;
    let at = |k: usize| free_speed_rad_s * k as f64 / n as f64;
    let mut best_k = 1;
    let mut best_p = f64::NEG_INFINITY;
    for k in 1..n {
        let p = sweep.point(at(k))?.power_w;
        if p > best_p {
            (best_k, best_p) = (k, p);
        }
    }
    let (w_opt, _) = brent_minimize(
        |w| sweep.point(w).map(|p| -p.power_w),
        at(best_k - 1),
        at(best_k + 1),
        1e-7,
        1e-9 * free_speed_rad_s,
    )?;
    let optimum = sweep.point(w_opt)?;
    let k_max = (free_speed_rad_s / grid_rad_s).floor();
    let k_lo = ((w_opt / grid_rad_s).floor() - 1.0).clamp(0.0, k_max);
    let k_hi = ((w_opt / grid_rad_s).ceil() + 1.0).clamp(0.0, k_max);
    let mut best: Option<OperatingPoint> = None;
    let mut k = k_lo;
    while k <= k_hi {
        let p = sweep.point(k * grid_rad_s)?;
        if best.is_none_or(|b| p.power_w > b.power_w) {
            best = Some(p);
        }
        k += 1.0;
    }
    Ok((optimum, best.unwrap_or(optimum)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::MotorParams;
    use crate::numerics::DefaultSolver;
    use crate::sim::experiment::Experiment;
    use crate::sim::recording::{Column, ExperimentData, Kind, Recording};
    use crate::units::{Quantity, Unit};
    use std::f64::consts::PI;

    const P_ATM: f64 = 101_325.0;
    const RPM: f64 = PI / 30.0;

    fn at_6_3_bar_g() -> Conditions {
        Conditions::supplied(6.3e5 + P_ATM, P_ATM)
    }

    #[test]
    fn max_power_is_the_best_grid_point_of_a_dense_scan() {
        let m = Motor::default_motor();
        let c = at_6_3_bar_g();
        let row = catalogue_row(&m, &c, RPM).unwrap();
        let k0 = (row.speed_at_max_power_rad_s / RPM).round();
        assert!(
            (row.speed_at_max_power_rad_s - k0 * RPM).abs() < 1e-9,
            "not on the grid"
        );
        let speeds: Vec<f64> = (-50..=50).map(|j| (k0 + j as f64) * RPM).collect();
        let scan = at_speeds(&m, &c, &speeds).unwrap();
        let best = scan
            .iter()
            .max_by(|a, b| a.power_w.total_cmp(&b.power_w))
            .unwrap();
        // Neighbouring grid points differ by ~1e-6 W here, far above the solver's noise.
        assert!(
            (best.power_w - row.max_power_w).abs() <= 1e-9 * row.max_power_w,
            "{} vs {}",
            best.power_w,
            row.max_power_w
        );
        assert_eq!(best.speed_rad_s, row.speed_at_max_power_rad_s);
        assert!(row.optimum.power_w >= row.max_power_w);
        // docs/model.md, "Parameters": ≈ 100 W near half the free speed, ≈ 12 000 rpm free
        // (at 0.73 MPa).
        assert!((60.0..140.0).contains(&row.max_power_w), "{row:?}");
        let ratio = row.speed_at_max_power_rad_s / row.free_speed_rad_s;
        assert!((0.3..0.7).contains(&ratio), "{ratio}");
    }

    #[test]
    fn free_speed_has_zero_torque_and_stall_matches_the_datasheet_experiment() {
        let m = Motor::default_motor();
        let c = at_6_3_bar_g();
        let row = catalogue_row(&m, &c, RPM).unwrap();
        let at_free = at_speeds(&m, &c, &[row.free_speed_rad_s]).unwrap()[0];
        assert!(at_free.torque_nm.abs() < 1e-9, "{}", at_free.torque_nm);
        assert!((row.air_at_free_speed_kg_s - at_free.flow1_kg_s).abs() < 1e-12);
        // The datasheet experiment at speeds 0, 100, 200 rad/s and the same supply.
        let speeds = vec![0.0, 100.0, 200.0];
        let data = ExperimentData {
            kind: Kind::Datasheet,
            file: "d.csv".into(),
            p_supply_pa: Some(c.p_supply_pa),
            load: Load::None,
            weight: 1.0,
            channel_weights: Default::default(),
            p_supply_written: None,
            p_supply_line: None,
            tolerance: None,
            figures: Vec::new(),
            recording: Recording {
                file: "d.csv".into(),
                columns: vec![Column {
                    name: "speed_rad_s".into(),
                    quantity: Quantity::Speed,
                    unit: Unit::RadS,
                    raw: speeds.iter().map(|v| v.to_string()).collect(),
                    si: speeds.clone(),
                }],
                lines: vec![2, 3, 4],
            },
        };
        let sim = Experiment::new(&data, P_ATM)
            .unwrap()
            .simulate(&m, &DefaultSolver::default())
            .unwrap();
        let torque = sim.channel(Quantity::Torque).unwrap();
        assert!(
            (torque[0] - row.stall_torque_nm).abs() < 1e-12,
            "{} vs {}",
            torque[0],
            row.stall_torque_nm
        );
        let points = at_speeds(&m, &c, &speeds).unwrap();
        for (p, t) in points.iter().zip(torque) {
            assert!((p.torque_nm - t).abs() < 1e-9, "{} vs {t}", p.torque_nm);
        }
        // ≈ 0.31 N·m at 0.73 MPa (docs/model.md, "Parameters"), less the friction at rest.
        assert!((0.2..0.4).contains(&row.stall_torque_nm), "{row:?}");
    }

    #[test]
    fn an_inlet_nozzle_lowers_free_speed_and_power() {
        let m = Motor::default_motor();
        let open = catalogue_row(&m, &at_6_3_bar_g(), RPM).unwrap();
        let throttled = Conditions {
            c_inlet_m3_s_pa: Some(3e-9),
            ..at_6_3_bar_g()
        };
        let t = catalogue_row(&m, &throttled, RPM).unwrap();
        assert!(t.free_speed_rad_s < open.free_speed_rad_s, "{t:?}");
        assert!(t.max_power_w < open.max_power_w);
        assert!(t.air_at_max_power_kg_s < open.air_at_max_power_kg_s);
    }

    #[test]
    fn a_motor_that_cannot_start_says_so() {
        let p = MotorParams::default().with("t_coulomb", 0.5).unwrap();
        let m = Motor::new(p, Default::default());
        let e = catalogue_row(&m, &at_6_3_bar_g(), RPM).unwrap_err();
        assert!(matches!(e, OperatingPointError::DoesNotStart { .. }), "{e}");
        assert!(e.to_string().contains("does not start"));
        let e = catalogue_row(&m, &at_6_3_bar_g(), 0.0).unwrap_err();
        assert_eq!(e, OperatingPointError::BadGrid(0.0));
    }

    #[test]
    fn a_motor_starved_by_its_inlet_nozzle_does_not_start_instead_of_failing() {
        // `predict --inlet-nozzle 1e-13` used to end in "no steady state". Starved, the
        // chambers sit at atmosphere and the stall torque is the friction at rest, −T_c.
        let m = Motor::new(MotorParams::default(), Default::default());
        for c in [1e-12, 1e-13, 1e-15] {
            let mut cond = at_6_3_bar_g();
            cond.c_inlet_m3_s_pa = Some(c);
            match catalogue_row(&m, &cond, RPM) {
                Err(OperatingPointError::DoesNotStart {
                    stall_torque_nm, ..
                }) => {
                    let t_c = MotorParams::default().get("t_coulomb").unwrap();
                    assert!(
                        (stall_torque_nm + t_c).abs() < 1e-3 * t_c,
                        "{c}: {stall_torque_nm}"
                    );
                }
                other => panic!("{c}: {other:?}"),
            }
        }
    }

    #[test]
    fn a_symmetric_motor_reversed_mirrors_its_torque_and_flows() {
        // The default motor is symmetric (c_in1 = c_out2, c_1e = c_2e): supplied at port 2 and
        // turning backwards it must give the mirrored point.
        let m = Motor::default_motor();
        let c = at_6_3_bar_g();
        let fwd = at_speeds(&m, &c, &[300.0]).unwrap()[0];
        let mut bc = c.boundary();
        (bc.p_port1_pa, bc.p_port2_pa) = (P_ATM, c.p_supply_pa);
        let x = steady::at_speed(&m, &bc, -300.0, &steady::initial_guess(&bc)).unwrap();
        let b = m.balance(&x, &bc);
        let rev = shaft_torque(&m, &x, &b);
        assert!(
            (rev + fwd.torque_nm).abs() < 1e-9,
            "{rev} vs {}",
            fwd.torque_nm
        );
        assert!((b.flow_port2_kg_s + fwd.flow1_kg_s).abs() < 1e-12);
    }
}
