//! The drive shared by the transient kinds: supply pressure and port-2 conductance
//! schedules in time, integrated from a steady start.

use super::{Drive, Setting, SimError, Simulated};
use crate::model::jacobian::BoundaryRate;
use crate::model::motor::{idx, Boundary, Motor, State};
use crate::numerics::ode::{Slopes, StiffSolver};
use crate::sim::recording::{Column, ExperimentData};
use crate::sim::schedule::Schedule;
use crate::sim::steady;
use crate::units::Quantity;
use std::cell::Cell;

/// Transient driven by supply pressure and port-2 conductance schedules.
#[derive(Debug, Clone)]
pub(super) struct Transient {
    /// Time of each recorded row, s.
    times: Vec<f64>,
    /// Supply pressure at port 1, Pa.
    p_supply: Schedule,
    /// log10 of the port-2 conductance (m³/(s·Pa)), if a throttle is fitted; it is then
    /// the abscissa, otherwise the supply pressure is.
    log10_c_port2: Option<Schedule>,
    /// The inputs at each recorded row (supply pressure, Pa; port-2 conductance,
    /// m³/(s·Pa)), evaluated once: they do not depend on the motor, and every evaluation
    /// of the cost needs the port flows at every row (evaluated per step, the schedules and
    /// the conductance's `exp` were ~5 % of an evaluation's instructions).
    row_inputs: Vec<(f64, Option<f64>)>,
}

impl Transient {
    /// The drive of these recorded times and input schedules.
    pub fn new(times: Vec<f64>, p_supply: Schedule, log10_c_port2: Option<Schedule>) -> Self {
        let row_inputs = times
            .iter()
            .map(|&t| inputs_at(&p_supply, log10_c_port2.as_ref(), t))
            .collect();
        Self {
            times,
            p_supply,
            log10_c_port2,
            row_inputs,
        }
    }

    /// How fast the inputs move at time t, where the supply schedule is at `p_supply` (zero
    /// supply slope where the supply is held at its floor, as [`boundary`] holds it).
    fn rate_at(&self, setting: &Setting<'_>, t: f64, p_supply: f64) -> BoundaryRate {
        let held = p_supply < setting.p_atm_pa * 0.5;
        BoundaryRate {
            p_port1_pa_s: if held { 0.0 } else { self.p_supply.slope_at(t) },
            ln_c_port2_per_s: self
                .log10_c_port2
                .as_ref()
                .map_or(0.0, |s| s.slope_at(t) * std::f64::consts::LN_10),
        }
    }

    /// Boundary conditions at time t.
    fn boundary_at(&self, setting: &Setting<'_>, t: f64) -> Boundary {
        let inputs = inputs_at(&self.p_supply, self.log10_c_port2.as_ref(), t);
        boundary(setting, inputs)
    }
}

/// The schedules' values at time t: supply pressure (Pa) and port-2 conductance
/// (m³/(s·Pa), from its log10).
fn inputs_at(p_supply: &Schedule, log10_c_port2: Option<&Schedule>, t: f64) -> (f64, Option<f64>) {
    (
        p_supply.at(t),
        log10_c_port2.map(|s| (s.at(t) * std::f64::consts::LN_10).exp()),
    )
}

/// The boundary conditions of given inputs (supply pressure, Pa; port-2 conductance,
/// m³/(s·Pa)), the supply held at least at half the atmosphere.
fn boundary(setting: &Setting<'_>, (p_supply, c_port2): (f64, Option<f64>)) -> Boundary {
    let mut bc = Boundary::supplied(
        p_supply.max(setting.p_atm_pa * 0.5),
        setting.p_atm_pa,
        setting.load,
    );
    bc.c_port2_m3_s_pa = c_port2;
    bc
}

impl Drive for Transient {
    fn abscissa(&self) -> Vec<f64> {
        let input = self.log10_c_port2.as_ref().unwrap_or(&self.p_supply);
        self.times.iter().map(|t| input.at(*t)).collect()
    }

    fn simulate(
        &self,
        setting: &Setting<'_>,
        motor: &Motor,
        solver: &dyn StiffSolver,
    ) -> Result<Simulated, SimError> {
        let times = &self.times;
        let t0 = times[0];
        let bc0 = self.boundary_at(setting, t0);
        let x0 = steady::free(motor, &bc0, &steady::initial_guess(&bc0)).map_err(|source| {
            SimError::InitialState {
                experiment: setting.file.to_string(),
                source,
            }
        })?;
        // The inputs at the last time asked for: a Rosenbrock step evaluates its last two
        // stages at the same time, and the next step's linearisation there again (the
        // schedules and the conductance's `exp` were ~6 % of an evaluation's instructions).
        let last = Cell::new((f64::NAN, (0.0, None)));
        let inputs = |t: f64| {
            let (t_last, known) = last.get();
            if t_last == t {
                return known;
            }
            let now = inputs_at(&self.p_supply, self.log10_c_port2.as_ref(), t);
            last.set((t, now));
            now
        };
        let rhs = |t: f64, x: &State| motor.derivatives(x, &boundary(setting, inputs(t)));
        let jacobian = |t: f64, x: &State| {
            let inputs = inputs(t);
            let bc = boundary(setting, inputs);
            let rate = self.rate_at(setting, t, inputs.0);
            let (f, jac, f_t) = motor.derivatives_jacobian_and_time_slope(x, &bc, &rate)?;
            Some(Slopes {
                f,
                jac,
                f_t: Some(f_t),
            })
        };
        let kinks = |t: f64, x: &State| motor.laminar_margins(x, &boundary(setting, inputs(t)));
        let states = solver
            .solve_with_kinks(&rhs, &jacobian, &kinks, t0, x0, times)
            .map_err(|source| SimError::Solve {
                experiment: setting.file.to_string(),
                source,
            })?;
        let n = times.len();
        let mut out: [Vec<f64>; 4] = std::array::from_fn(|_| Vec::with_capacity(n));
        for (inputs, x) in self.row_inputs.iter().zip(&states) {
            let bc = boundary(setting, *inputs);
            let (flow1, flow2) = motor.port_flows(x, &bc);
            out[0].push(flow1);
            out[1].push(flow2);
            out[2].push(x[idx::OMEGA]);
            out[3].push(bc.load.torque(x[idx::OMEGA]));
        }
        // What the flow and speed sensors record (a lag where `sensor_lag` is on).
        for ch in out.iter_mut().take(3) {
            *ch = motor.measured(times, std::mem::take(ch));
        }
        let [flow1, flow2, speed, torque] = out;
        Ok(Simulated {
            outputs: vec![
                (Quantity::Flow1, flow1),
                (Quantity::Flow2, flow2),
                (Quantity::Speed, speed),
                (Quantity::Torque, torque),
            ],
        })
    }
}

/// Which supply a transient kind takes when rig.toml and the recording both give one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum SupplyFrom {
    /// The recorded port-1 pressure (the pressure ramp: the supply is what is varied).
    Recording,
    /// `p_supply_mpa` of rig.toml (the outlet throttle: the supply is held).
    Rig,
}

/// The supply-pressure schedule of a transient: the recorded port-1 pressure smoothed, or
/// the constant `p_supply_mpa`, whichever `prefer` names when both are given; the other
/// when only one is; an error naming the file when neither is.
pub(super) fn supply_schedule(
    data: &ExperimentData,
    times: &[f64],
    prefer: SupplyFrom,
) -> Result<Schedule, SimError> {
    let recorded = data.recording.column(Quantity::PPort1);
    let smoothed = |p: &Column| Schedule::smoothed(times, &p.si);
    match (data.p_supply_pa, recorded, prefer) {
        (Some(p), _, SupplyFrom::Rig) | (Some(p), None, SupplyFrom::Recording) => {
            Ok(Schedule::constant(p))
        }
        (_, Some(col), _) => Ok(smoothed(col)),
        (None, None, _) => Err(SimError::NoSupply {
            experiment: data.file.clone(),
        }),
    }
}

/// The measured channels of the transient kinds, in the simulator's order.
pub(super) const CHANNELS: &[Quantity] = &[
    Quantity::Flow1,
    Quantity::Flow2,
    Quantity::Speed,
    Quantity::Torque,
];
