//! The reference experiments of SPEC §2 as first-class types: each knows its inputs (from the
//! rig and its recording) and simulates the channels that were measured, one value per row.

use crate::model::motor::{idx, Boundary, Load, Motor, State};
use crate::numerics::ode::StiffSolver;
use crate::sim::recording::{ExperimentData, Kind, MissingColumn};
use crate::sim::schedule::Schedule;
use crate::sim::steady;
use crate::units::Quantity;
use std::fmt;

/// Why a simulation failed.
#[derive(Debug, Clone, PartialEq)]
pub struct SimError {
    pub experiment: String,
    pub message: String,
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "simulating {}: {}", self.experiment, self.message)
    }
}

impl std::error::Error for SimError {}

/// Simulated channels of one experiment, SI, one value per recorded row.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulated {
    pub outputs: Vec<(Quantity, Vec<f64>)>,
}

impl Simulated {
    pub fn channel(&self, q: Quantity) -> Option<&[f64]> {
        self.outputs
            .iter()
            .find(|(k, _)| *k == q)
            .map(|(_, v)| v.as_slice())
    }
}

/// How the experiment drives the motor.
#[derive(Debug, Clone)]
enum Drive {
    /// Steady states at imposed speeds and supply pressures (one per row).
    Datasheet {
        speeds: Vec<f64>,
        p_supply: Vec<f64>,
    },
    /// Transient driven by supply pressure and port-2 conductance schedules.
    Transient {
        times: Vec<f64>,
        p_supply: Schedule,
        /// log10 of the port-2 conductance, if a throttle is fitted.
        log10_c_port2: Option<Schedule>,
    },
}

/// A reference experiment ready to simulate.
#[derive(Debug, Clone)]
pub struct Experiment {
    pub kind: Kind,
    pub file: String,
    pub load: Load,
    pub p_atm_pa: f64,
    drive: Drive,
}

impl Experiment {
    /// Builds the experiment's inputs from its recording (validated by `dataset`).
    pub fn new(data: &ExperimentData, p_atm_pa: f64) -> Result<Self, SimError> {
        let rec = &data.recording;
        let err = |e: MissingColumn| SimError {
            experiment: data.file.clone(),
            message: e.to_string(),
        };
        let rows = rec.rows();
        let supply_column = rec.column(Quantity::PPort1).map(|c| c.si.clone());
        let drive = match data.kind {
            Kind::Datasheet => Drive::Datasheet {
                speeds: rec.values(Quantity::Speed).map_err(err)?.to_vec(),
                p_supply: match data.p_supply_pa {
                    Some(p) => vec![p; rows],
                    None => supply_column.clone().unwrap_or_default(),
                },
            },
            Kind::PressureRamp | Kind::OutletThrottle => {
                let times = rec.values(Quantity::Time).map_err(err)?.to_vec();
                let p_supply = match (data.kind, data.p_supply_pa, &supply_column) {
                    (Kind::OutletThrottle, Some(p), _) => Schedule::constant(p),
                    (_, _, Some(p)) => Schedule::smoothed(&times, p),
                    (_, Some(p), None) => Schedule::constant(p),
                    (_, None, None) => {
                        return Err(SimError {
                            experiment: data.file.clone(),
                            message: "no supply pressure".into(),
                        })
                    }
                };
                let log10_c_port2 = match data.kind {
                    Kind::OutletThrottle => {
                        let c = rec.values(Quantity::CPort2).map_err(err)?;
                        let logc: Vec<f64> = c.iter().map(|v| v.log10()).collect();
                        Some(Schedule::smoothed(&times, &logc))
                    }
                    _ => None,
                };
                Drive::Transient {
                    times,
                    p_supply,
                    log10_c_port2,
                }
            }
        };
        Ok(Self {
            kind: data.kind,
            file: data.file.clone(),
            load: data.load,
            p_atm_pa,
            drive,
        })
    }

    /// The abscissa of each recorded row, SI, as the reference responses use it: imposed
    /// speed (rad/s) for the datasheet, port-1 pressure (Pa) for the pressure ramp, log10 of
    /// the port-2 conductance (log10 m³/(s·Pa)) for the outlet throttle. For transient
    /// experiments it is the smoothed input that drove the simulation, not the noisy samples.
    pub fn abscissa(&self) -> Vec<f64> {
        match &self.drive {
            Drive::Datasheet { speeds, .. } => speeds.clone(),
            Drive::Transient {
                times,
                p_supply,
                log10_c_port2,
            } => match (self.kind, log10_c_port2) {
                (Kind::OutletThrottle, Some(c)) => times.iter().map(|t| c.at(*t)).collect(),
                _ => times.iter().map(|t| p_supply.at(*t)).collect(),
            },
        }
    }

    /// Boundary conditions of a transient experiment at time t.
    fn boundary_at(&self, p_supply: &Schedule, log10_c: Option<&Schedule>, t: f64) -> Boundary {
        let mut bc = Boundary::supplied(
            p_supply.at(t).max(self.p_atm_pa * 0.5),
            self.p_atm_pa,
            self.load,
        );
        bc.c_port2_m3_s_pa = log10_c.map(|s| (s.at(t) * std::f64::consts::LN_10).exp());
        bc
    }

    /// Simulates every row of the recording.
    pub fn simulate(&self, motor: &Motor, solver: &dyn StiffSolver) -> Result<Simulated, SimError> {
        match &self.drive {
            Drive::Datasheet { speeds, p_supply } => {
                self.simulate_datasheet(motor, speeds, p_supply)
            }
            Drive::Transient {
                times,
                p_supply,
                log10_c_port2,
            } => self.simulate_transient(motor, solver, times, p_supply, log10_c_port2.as_ref()),
        }
    }

    fn fail(&self, message: String) -> SimError {
        SimError {
            experiment: self.file.clone(),
            message,
        }
    }

    fn simulate_datasheet(
        &self,
        motor: &Motor,
        speeds: &[f64],
        p_supply: &[f64],
    ) -> Result<Simulated, SimError> {
        let n = speeds.len();
        let (mut torque, mut flow1, mut flow2) = (
            Vec::with_capacity(n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        // Sweep in speed order so that each solve starts from its neighbour's solution.
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|a, b| speeds[*a].total_cmp(&speeds[*b]));
        let mut results = vec![[0.0; 3]; n];
        let mut guess: Option<State> = None;
        for &i in &order {
            let bc = Boundary::supplied(p_supply[i], self.p_atm_pa, Load::None);
            let g = guess.unwrap_or_else(|| steady::initial_guess(&bc));
            let x = steady::at_speed(motor, &bc, speeds[i], &g)
                .or_else(|_| steady::at_speed(motor, &bc, speeds[i], &steady::initial_guess(&bc)))
                .map_err(|e| self.fail(format!("row {}: {e}", i + 1)))?;
            let b = motor.balance(&x, &bc);
            // At standstill the brake holds the rotor against the full dry friction.
            let torque = if speeds[i] == 0.0 {
                b.torque_ideal_nm - motor.friction_at_rest(x[idx::P1], x[idx::PE])
            } else {
                b.torque_shaft_nm()
            };
            results[i] = [torque, b.flow_port1_kg_s, b.flow_port2_kg_s];
            guess = Some(x);
        }
        for r in results {
            torque.push(r[0]);
            flow1.push(r[1]);
            flow2.push(r[2]);
        }
        Ok(Simulated {
            outputs: vec![
                (Quantity::Torque, torque),
                (Quantity::Flow1, flow1),
                (Quantity::Flow2, flow2),
            ],
        })
    }

    fn simulate_transient(
        &self,
        motor: &Motor,
        solver: &dyn StiffSolver,
        times: &[f64],
        p_supply: &Schedule,
        log10_c: Option<&Schedule>,
    ) -> Result<Simulated, SimError> {
        let t0 = times[0];
        let bc0 = self.boundary_at(p_supply, log10_c, t0);
        let x0 = steady::free(motor, &bc0, &steady::initial_guess(&bc0))
            .map_err(|e| self.fail(format!("initial state: {e}")))?;
        let rhs = |t: f64, x: &State| motor.derivatives(x, &self.boundary_at(p_supply, log10_c, t));
        let states = solver
            .solve(&rhs, t0, x0, times)
            .map_err(|e| self.fail(e.to_string()))?;
        let n = times.len();
        let mut out: [Vec<f64>; 4] = std::array::from_fn(|_| Vec::with_capacity(n));
        for (t, x) in times.iter().zip(&states) {
            let bc = self.boundary_at(p_supply, log10_c, *t);
            let b = motor.balance(x, &bc);
            out[0].push(b.flow_port1_kg_s);
            out[1].push(b.flow_port2_kg_s);
            out[2].push(x[idx::OMEGA]);
            out[3].push(b.torque_load_nm);
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

/// A sensor's first-order lag (defined with the `sensor_lag` effect).
pub use crate::model::effects::sensor_lag::first_order_lag;
