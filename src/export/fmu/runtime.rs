//! The model behind the FMU's C functions (the `fmu/` crate is only the C interface): the
//! fit's motor with its parameters as tunable values, the inputs, the state, its
//! derivatives for model exchange and a Rodas4 step for co-simulation, all from the same
//! model code as `vanefit simulate` (`model::motor`, `numerics::rodas`, `sim::steady`).

use super::variables::{model_parameters, p_atm_start, vr, ModelParameter, ParamSource};
use crate::data::fitfile::FitFile;
use crate::model::jacobian::BoundaryRate;
use crate::model::motor::{idx, Boundary, Load, Motor, State};
use crate::model::params::ParamSet;
use crate::numerics::ode::{Slopes, SolveError, StiffSolver};
use crate::numerics::rodas::Rodas4;
use crate::sim::steady::{self, SteadyError};

/// Why a call into the FMU's model failed (the C interface logs it and returns an error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RuntimeError {
    /// No variable of this type has the value reference.
    #[error("no variable with value reference {0}")]
    UnknownReference(u32),
    /// A value is refused (the variable's name and why).
    #[error("{name} = {value}: {why}")]
    BadValue {
        /// The variable.
        name: String,
        /// The value given.
        value: f64,
        /// Why it is refused.
        why: String,
    },
    /// No steady state at the initial inputs.
    #[error("steady start: {0}")]
    Steady(#[source] SteadyError),
    /// The stiff integrator failed in a co-simulation step.
    #[error("step from t = {t} s: {source}")]
    Step {
        /// Start of the step, s.
        t: f64,
        /// The integrator's error.
        source: SolveError,
    },
}

/// The five inputs of the FMU, SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inputs {
    /// Absolute pressure upstream of port 1, Pa.
    pub p_supply_pa: f64,
    /// Absolute pressure downstream of port 2, Pa.
    pub p_back_pa: f64,
    /// Load torque opposing forward rotation, N·m.
    pub t_load_nm: f64,
    /// Extra throttle in front of port 1, m³/(s·Pa) (0: none).
    pub c_throttle1_m3_s_pa: f64,
    /// Extra throttle behind port 2, m³/(s·Pa) (0: none).
    pub c_throttle2_m3_s_pa: f64,
}

/// The inputs' value references in the order of [`Inputs`].
pub const INPUTS: [u32; 5] = [
    vr::P_SUPPLY,
    vr::P_BACK,
    vr::T_LOAD,
    vr::C_THROTTLE1,
    vr::C_THROTTLE2,
];

/// The motor of a fit as the FMU runs it.
#[derive(Debug, Clone)]
pub struct MotorFmu {
    fit: FitFile,
    params: Vec<ModelParameter>,
    values: Vec<f64>,
    motor: Motor,
    /// The inputs.
    pub inputs: Inputs,
    /// Atmosphere the exhaust discharges to, Pa.
    pub p_atm_pa: f64,
    /// Viscous brake on the shaft, N·m·s/rad.
    pub c_brake_nm_s_rad: f64,
    /// Start from the steady state at the initial inputs.
    pub start_steady: bool,
    /// First time derivatives of the inputs for the next co-simulation step (FMI
    /// `fmi2SetRealInputDerivatives`), per second, in the order of [`Inputs`]; cleared by
    /// a step and by setting the input.
    pub input_slopes: [f64; 5],
    /// Simulation time, s.
    pub time_s: f64,
    /// The state [p_1, p_2, p_e (Pa), ω (rad/s)].
    pub x: State,
}

impl MotorFmu {
    /// The FMU of `fit` at its start values (fitted parameters; inputs as
    /// `modelDescription.xml` gives them).
    pub fn new(fit: FitFile) -> Result<Self, super::FmuError> {
        let params = model_parameters(&fit)?;
        let values = params.iter().map(|p| p.value).collect();
        let p_atm = p_atm_start(&fit);
        let supply = fit
            .conditions
            .and_then(|c| c.p_supply_range_pa)
            .map_or(7.3e5, |[_, hi]| hi);
        let motor = Motor::new(fit.params.clone(), fit.effects.clone()).with_extra(&fit.extra);
        Ok(Self {
            fit,
            params,
            values,
            motor,
            inputs: Inputs {
                p_supply_pa: supply,
                p_back_pa: p_atm,
                t_load_nm: 0.0,
                c_throttle1_m3_s_pa: 0.0,
                c_throttle2_m3_s_pa: 0.0,
            },
            p_atm_pa: p_atm,
            c_brake_nm_s_rad: 0.0,
            start_steady: true,
            input_slopes: [0.0; 5],
            time_s: 0.0,
            x: [p_atm, p_atm, p_atm, 0.0],
        })
    }

    /// The fit the FMU was made from.
    pub fn fit(&self) -> &FitFile {
        &self.fit
    }

    /// The motor as it stands (fitted parameters with any changes made since).
    pub fn motor(&self) -> &Motor {
        &self.motor
    }

    fn bad(name: &str, value: f64, why: impl Into<String>) -> RuntimeError {
        RuntimeError::BadValue {
            name: name.into(),
            value,
            why: why.into(),
        }
    }

    /// Sets model parameter `k` of [`model_parameters`] and rebuilds the motor; a value the
    /// model's parameter check refuses leaves everything as it was.
    fn set_model_parameter(&mut self, k: usize, value: f64) -> Result<(), RuntimeError> {
        let name = self.params[k].name.clone();
        if !value.is_finite() {
            return Err(Self::bad(&name, value, "not a finite number"));
        }
        let mut values = self.values.clone();
        values[k] = value;
        let mut set = ParamSet::from(self.fit.params.clone());
        let mut extra = self.fit.extra.clone();
        for (p, v) in self.params.iter().zip(&values) {
            match p.source {
                ParamSource::Motor(n) => set
                    .set(n, *v)
                    .map_err(|e| Self::bad(&name, value, e.message))?,
                ParamSource::Discovered(j) => extra[j].coefficient = *v,
            }
        }
        let checked = set
            .check()
            .map_err(|e| Self::bad(&name, value, e.to_string()))?;
        self.motor = Motor::new(checked, self.fit.effects.clone()).with_extra(&extra);
        self.values = values;
        Ok(())
    }

    /// Sets the Real variable `r`.
    pub fn set_real(&mut self, r: u32, value: f64) -> Result<(), RuntimeError> {
        let pressure = |name: &str| {
            if value.is_finite() && value > 0.0 {
                Ok(value)
            } else {
                Err(Self::bad(
                    name,
                    value,
                    "an absolute pressure must be positive, Pa",
                ))
            }
        };
        let non_negative = |name: &str| {
            if value.is_finite() && value >= 0.0 {
                Ok(value)
            } else {
                Err(Self::bad(name, value, "must be zero or positive"))
            }
        };
        if let Some(k) = INPUTS.iter().position(|i| *i == r) {
            self.input_slopes[k] = 0.0;
        }
        match r {
            vr::P_SUPPLY => self.inputs.p_supply_pa = pressure("p_supply")?,
            vr::P_BACK => self.inputs.p_back_pa = pressure("p_back")?,
            vr::T_LOAD if value.is_finite() => self.inputs.t_load_nm = value,
            vr::T_LOAD => return Err(Self::bad("t_load", value, "not a finite number")),
            vr::C_THROTTLE1 => self.inputs.c_throttle1_m3_s_pa = non_negative("c_throttle1")?,
            vr::C_THROTTLE2 => self.inputs.c_throttle2_m3_s_pa = non_negative("c_throttle2")?,
            vr::P_ATM => self.p_atm_pa = pressure("p_atm")?,
            vr::C_BRAKE => self.c_brake_nm_s_rad = non_negative("c_brake")?,
            _ => match self.parameter_index(r) {
                Some(k) => self.set_model_parameter(k, value)?,
                None => return Err(RuntimeError::UnknownReference(r)),
            },
        }
        Ok(())
    }

    fn parameter_index(&self, r: u32) -> Option<usize> {
        let k = r.checked_sub(vr::FIRST_MODEL_PARAMETER)? as usize;
        (k < self.params.len()).then_some(k)
    }

    /// Sets the continuous states (model exchange).
    pub fn set_states(&mut self, x: &[f64]) {
        for (s, v) in self.x.iter_mut().zip(x) {
            *s = *v;
        }
    }

    /// The boundary conditions of the current inputs.
    pub fn boundary(&self) -> Boundary {
        self.boundary_of(&self.inputs)
    }

    fn boundary_of(&self, i: &Inputs) -> Boundary {
        let throttle = |c: f64| (c > 0.0).then_some(c);
        Boundary {
            p_port1_pa: i.p_supply_pa,
            p_port2_pa: i.p_back_pa,
            p_atm_pa: self.p_atm_pa,
            c_port1_m3_s_pa: throttle(i.c_throttle1_m3_s_pa),
            c_port2_m3_s_pa: throttle(i.c_throttle2_m3_s_pa),
            load: Load::BrakeAndTorque {
                c_nm_s_rad: self.c_brake_nm_s_rad,
                t_nm: i.t_load_nm,
            },
        }
    }

    /// The inputs `dt` seconds into a step, moved along their slopes (pressures kept
    /// positive and conductances non-negative where a slope would cross zero).
    fn inputs_at(&self, dt: f64) -> Inputs {
        let i = &self.inputs;
        let d = &self.input_slopes;
        Inputs {
            p_supply_pa: (i.p_supply_pa + d[0] * dt).max(1.0),
            p_back_pa: (i.p_back_pa + d[1] * dt).max(1.0),
            t_load_nm: i.t_load_nm + d[2] * dt,
            c_throttle1_m3_s_pa: (i.c_throttle1_m3_s_pa + d[3] * dt).max(0.0),
            c_throttle2_m3_s_pa: (i.c_throttle2_m3_s_pa + d[4] * dt).max(0.0),
        }
    }

    /// How fast the boundary moves when the inputs follow their slopes: the supply and
    /// the port-2 throttle have closed-form time slopes in the model; `None` when another
    /// input moves (the integrator then takes ∂f/∂t by a difference).
    fn boundary_rate(&self) -> Option<BoundaryRate> {
        let d = &self.input_slopes;
        if d[1] != 0.0 || d[2] != 0.0 || d[3] != 0.0 {
            return None;
        }
        let c2 = self.inputs.c_throttle2_m3_s_pa;
        if d[4] != 0.0 && c2 <= 0.0 {
            return None;
        }
        Some(BoundaryRate {
            p_port1_pa_s: d[0],
            ln_c_port2_per_s: if d[4] != 0.0 { d[4] / c2 } else { 0.0 },
        })
    }

    /// dx/dt at the current state and inputs.
    pub fn derivatives(&self) -> State {
        self.motor.derivatives(&self.x, &self.boundary())
    }

    /// The value of the Real variable `r`.
    pub fn get_real(&self, r: u32) -> Result<f64, RuntimeError> {
        let i = &self.inputs;
        let state = |k: usize| self.x[k];
        Ok(match r {
            vr::P_SUPPLY => i.p_supply_pa,
            vr::P_BACK => i.p_back_pa,
            vr::T_LOAD => i.t_load_nm,
            vr::C_THROTTLE1 => i.c_throttle1_m3_s_pa,
            vr::C_THROTTLE2 => i.c_throttle2_m3_s_pa,
            vr::SPEED => state(idx::OMEGA),
            vr::P1 => state(idx::P1),
            vr::P2 => state(idx::P2),
            vr::PE => state(idx::PE),
            vr::TORQUE_SHAFT | vr::FLOW_PORT1 | vr::FLOW_PORT2 => {
                let b = self.motor.balance(&self.x, &self.boundary());
                match r {
                    vr::TORQUE_SHAFT => b.torque_shaft_nm(),
                    vr::FLOW_PORT1 => b.flow_port1_kg_s,
                    _ => b.flow_port2_kg_s,
                }
            }
            vr::P_ATM => self.p_atm_pa,
            vr::C_BRAKE => self.c_brake_nm_s_rad,
            _ => {
                if let Some(k) = vr::STATES.iter().position(|s| *s == r) {
                    state(k)
                } else if let Some(k) = vr::DERIVATIVES.iter().position(|s| *s == r) {
                    self.derivatives()[k]
                } else if let Some(k) = self.parameter_index(r) {
                    self.values[k]
                } else {
                    return Err(RuntimeError::UnknownReference(r));
                }
            }
        })
    }

    /// Leaves initialisation: with `start_steady`, the state becomes the steady state at
    /// the initial inputs (`sim::steady::free`, as `vanefit simulate` starts a transient).
    pub fn initialize(&mut self) -> Result<(), RuntimeError> {
        if self.start_steady {
            let bc = self.boundary();
            self.x = steady::free(&self.motor, &bc, &steady::initial_guess(&bc))
                .map_err(RuntimeError::Steady)?;
        }
        Ok(())
    }

    /// One co-simulation step of `h_s` seconds: Rodas4 with the model's analytic Jacobian
    /// and kink indicators, at its default tolerances (those of `vanefit simulate`). The
    /// inputs are held, or follow their slopes where the importer set them
    /// (`fmi2SetRealInputDerivatives`); the step ends with the inputs where they arrived,
    /// so that the outputs at its end belong to its end, and the slopes cleared.
    pub fn do_step(&mut self, h_s: f64) -> Result<(), RuntimeError> {
        let t0 = self.time_s;
        if !(h_s.is_finite() && h_s >= 0.0) {
            return Err(Self::bad("communicationStepSize", h_s, "must be ≥ 0 s"));
        }
        if h_s > 0.0 {
            let motor = &self.motor;
            let rate = self.boundary_rate();
            let bc_at = |t: f64| self.boundary_of(&self.inputs_at(t - t0));
            let rhs = |t: f64, x: &State| motor.derivatives(x, &bc_at(t));
            let jacobian = |t: f64, x: &State| {
                let bc = bc_at(t);
                let slopes = |(f, jac, f_t)| Slopes { f, jac, f_t };
                match &rate {
                    Some(r) => motor
                        .derivatives_jacobian_and_time_slope(x, &bc, r)
                        .map(|(f, jac, f_t)| slopes((f, jac, Some(f_t)))),
                    None => motor
                        .derivatives_and_jacobian(x, &bc)
                        .map(|(f, jac)| slopes((f, jac, None))),
                }
            };
            let kinks = |t: f64, x: &State| motor.laminar_margins(x, &bc_at(t));
            let out = Rodas4::default()
                .solve_with_kinks(&rhs, &jacobian, &kinks, t0, self.x, &[t0 + h_s])
                .map_err(|source| RuntimeError::Step { t: t0, source })?;
            self.x = out[0];
            self.inputs = self.inputs_at(h_s);
        }
        self.input_slopes = [0.0; 5];
        self.time_s = t0 + h_s;
        Ok(())
    }

    /// Sets the first time derivative of input `r`, per second (co-simulation).
    pub fn set_input_slope(&mut self, r: u32, slope: f64) -> Result<(), RuntimeError> {
        let k = INPUTS
            .iter()
            .position(|i| *i == r)
            .ok_or(RuntimeError::UnknownReference(r))?;
        if !slope.is_finite() {
            return Err(Self::bad("input derivative", slope, "not a finite number"));
        }
        self.input_slopes[k] = slope;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::params::MotorParams;

    fn fmu() -> MotorFmu {
        let fit = FitFile::from_params("t", MotorParams::default(), Default::default());
        MotorFmu::new(fit).unwrap()
    }

    #[test]
    fn steady_start_has_no_derivatives_and_steps_stay_there() {
        let mut m = fmu();
        m.c_brake_nm_s_rad = 1e-4;
        m.inputs.t_load_nm = 0.05;
        m.initialize().unwrap();
        let f = m.derivatives();
        assert!(
            f[idx::OMEGA].abs() < 1e-3 && f[idx::P1].abs() < 1.0,
            "{f:?}"
        );
        let x0 = m.x;
        m.do_step(0.1).unwrap();
        assert!((m.x[idx::OMEGA] - x0[idx::OMEGA]).abs() < 1e-3 * x0[idx::OMEGA]);
        // The load torque balances the shaft torque at steady speed: T_shaft = c·ω + t.
        let t_shaft = m.get_real(vr::TORQUE_SHAFT).unwrap();
        let load = 1e-4 * m.x[idx::OMEGA] + 0.05;
        assert!((t_shaft - load).abs() < 1e-6, "{t_shaft} vs {load}");
    }

    #[test]
    fn a_step_with_input_slopes_is_the_step_of_the_moving_input() {
        // One 0.2 s step along a supply ramp against forty 5 ms steps of held inputs
        // re-set at each step's middle: the two agree, and both end at the ramp's end.
        let mut a = fmu();
        a.initialize().unwrap();
        let mut b = a.clone();
        let slope = -5e5;
        a.set_input_slope(vr::P_SUPPLY, slope).unwrap();
        a.do_step(0.2).unwrap();
        let p0 = b.inputs.p_supply_pa;
        for k in 0..40 {
            b.set_real(vr::P_SUPPLY, p0 + slope * 0.005 * (f64::from(k) + 0.5))
                .unwrap();
            b.do_step(0.005).unwrap();
        }
        assert!((a.inputs.p_supply_pa - (p0 + 0.2 * slope)).abs() < 1e-6);
        assert_eq!(a.input_slopes, [0.0; 5]);
        let (wa, wb) = (a.x[idx::OMEGA], b.x[idx::OMEGA]);
        assert!((wa - wb).abs() < 1e-3 * wa, "{wa} vs {wb}");
        let mut start = fmu();
        start.initialize().unwrap();
        assert!(
            wa < start.x[idx::OMEGA],
            "the falling supply slows the motor"
        );
    }

    #[test]
    fn a_refused_parameter_leaves_the_motor_as_it_was() {
        let mut m = fmu();
        let r = vr::FIRST_MODEL_PARAMETER; // c_in1
        assert!(m.set_real(r, -1.0).is_err());
        assert_eq!(m.get_real(r).unwrap(), MotorParams::default().c_in1());
        m.set_real(r, 2e-9).unwrap();
        assert_eq!(m.motor().params().c_in1(), 2e-9);
        assert!(matches!(
            m.set_real(99, 1.0),
            Err(RuntimeError::UnknownReference(99))
        ));
    }
}
