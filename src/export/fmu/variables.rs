//! The FMU's variables (docs/fmu.md, "Variables"): fixed inputs, outputs, states and
//! derivatives at fixed value references, then one tunable parameter per model parameter
//! of the fit (the base model's, each switched-on effect's, each discovered term's
//! coefficient). `modelDescription.xml` and the binary's runtime both read this table, so
//! their value references cannot drift apart.

use super::FmuError;
use crate::data::fitfile::FitFile;
use crate::model::extra::{coefficient_unit, describe};
use crate::model::params::BASE_PARAMS;

/// The model identifier: the shared library's file stem in `binaries/linux64/`.
pub const MODEL_IDENTIFIER: &str = "vanefit_fmu";

/// Value references of the fixed variables.
pub mod vr {
    /// Input: absolute pressure upstream of port 1, Pa.
    pub const P_SUPPLY: u32 = 0;
    /// Input: absolute pressure downstream of port 2, Pa.
    pub const P_BACK: u32 = 1;
    /// Input: load torque opposing forward rotation, N·m.
    pub const T_LOAD: u32 = 2;
    /// Input: conductance of an extra throttle in front of port 1, m³/(s·Pa) (0: none).
    pub const C_THROTTLE1: u32 = 3;
    /// Input: conductance of an extra throttle behind port 2, m³/(s·Pa) (0: none).
    pub const C_THROTTLE2: u32 = 4;
    /// Output: rotor speed, rad/s.
    pub const SPEED: u32 = 10;
    /// Output: shaft torque T − T_f, N·m.
    pub const TORQUE_SHAFT: u32 = 11;
    /// Output: mass flow into port 1, kg/s.
    pub const FLOW_PORT1: u32 = 12;
    /// Output: mass flow out of port 2, kg/s.
    pub const FLOW_PORT2: u32 = 13;
    /// Output: pressure in chamber 1, Pa.
    pub const P1: u32 = 14;
    /// Output: pressure in chamber 2, Pa.
    pub const P2: u32 = 15;
    /// Output: pressure in the exhaust chamber, Pa.
    pub const PE: u32 = 16;
    /// The continuous states p_1, p_2, p_e (Pa) and ω (rad/s).
    pub const STATES: [u32; 4] = [20, 21, 22, 23];
    /// Their time derivatives.
    pub const DERIVATIVES: [u32; 4] = [30, 31, 32, 33];
    /// Parameter: atmosphere the exhaust discharges to, Pa.
    pub const P_ATM: u32 = 40;
    /// Parameter: viscous brake on the shaft, N·m·s/rad.
    pub const C_BRAKE: u32 = 41;
    /// Boolean parameter: start from the steady state at the initial inputs.
    pub const START_STEADY: u32 = 42;
    /// The first model parameter; the k-th of `model_parameters` is this + k.
    pub const FIRST_MODEL_PARAMETER: u32 = 100;
}

/// What a variable is to the importing tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// An input, continuous.
    Input,
    /// An output, continuous.
    Output,
    /// A continuous state (local).
    State,
    /// The derivative of the state at this position of [`vr::STATES`] (local).
    Derivative(usize),
    /// A tunable parameter.
    Parameter,
}

/// One scalar variable of the FMU.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Its name in the importing tool.
    pub name: String,
    /// Its value reference.
    pub vr: u32,
    /// Input, output, state, derivative or parameter.
    pub role: Role,
    /// Its SI unit as vanefit writes units ("1": dimensionless).
    pub unit: String,
    /// What it is, in words.
    pub description: String,
    /// Start value, SI (inputs, states and parameters); for a Boolean 0 or 1.
    pub start: Option<f64>,
    /// A Boolean rather than a Real.
    pub boolean: bool,
}

/// Where a model parameter of the FMU lives in the model.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamSource {
    /// A named parameter of `model::params` (base model or a switched-on effect).
    Motor(&'static str),
    /// The coefficient of the discovered term at this position of the fit's list.
    Discovered(usize),
}

/// One model parameter of the FMU: its name, unit, description and fitted value.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelParameter {
    /// Its name in the FMU.
    pub name: String,
    /// Where it lives in the model.
    pub source: ParamSource,
    /// Its SI unit.
    pub unit: String,
    /// What it is, in words.
    pub description: String,
    /// The fitted value, SI.
    pub value: f64,
}

/// Catalog effects the FMU cannot carry, and why: both describe the rig around the motor,
/// not the motor, and the FMU's user models those parts in their own system.
const UNREPRESENTABLE: &[(&str, &str)] = &[
    (
        "sensor_lag",
        "it filters what the rig's flow and speed sensors record, not the motor; an FMU of \
         the motor has no sensors",
    ),
    (
        "valve_dynamics",
        "it is the rig's supply valve in front of port 1; the FMU's input is the pressure at \
         port 1 itself, so the valve belongs in the model that drives it",
    ),
];

/// The fit's model parameters in FMU order: the base model's, then each switched-on
/// effect's, then each discovered term's coefficient (`discovered_<k>`). Refuses a fit
/// with an effect the FMU cannot represent, naming it.
pub fn model_parameters(fit: &FitFile) -> Result<Vec<ModelParameter>, FmuError> {
    for e in fit.effects.iter() {
        if let Some((id, why)) = UNREPRESENTABLE.iter().find(|(id, _)| *id == e.id()) {
            return Err(FmuError::Unrepresentable {
                effect: (*id).to_string(),
                why,
            });
        }
    }
    let specs = BASE_PARAMS
        .iter()
        .chain(fit.effects.iter().flat_map(|e| e.specs().iter()));
    let mut out: Vec<ModelParameter> = specs
        .map(|s| ModelParameter {
            name: s.name.to_string(),
            source: ParamSource::Motor(s.name),
            unit: s.unit.to_string(),
            description: s.description().to_string(),
            value: fit.params.get(s.name).unwrap_or(s.default),
        })
        .collect();
    out.extend(fit.extra.iter().enumerate().map(|(k, t)| ModelParameter {
        name: format!("discovered_{}", k + 1),
        source: ParamSource::Discovered(k),
        unit: coefficient_unit(t),
        description: format!("coefficient of a discovered term: {}", describe(t)),
        value: t.coefficient,
    }));
    Ok(out)
}

/// Start value of the supply pressure: the highest the fit covered, else 7.3 bar.
fn supply_start(fit: &FitFile) -> f64 {
    fit.conditions
        .and_then(|c| c.p_supply_range_pa)
        .map_or(7.3e5, |[_, hi]| hi)
}

/// The atmosphere of the fit's rig, else the standard atmosphere, Pa.
pub fn p_atm_start(fit: &FitFile) -> f64 {
    fit.conditions.map_or(101_325.0, |c| c.p_atm_pa)
}

fn var(name: &str, vr: u32, role: Role, unit: &str, description: &str) -> Variable {
    Variable {
        name: name.into(),
        vr,
        role,
        unit: unit.into(),
        description: description.into(),
        start: None,
        boolean: false,
    }
}

fn with_start(mut v: Variable, start: f64) -> Variable {
    v.start = Some(start);
    v
}

/// The inputs and outputs.
fn inputs_and_outputs(fit: &FitFile) -> Vec<Variable> {
    let mut v = inputs(fit);
    v.extend(outputs());
    v
}

/// The inputs (boundary pressures, load torque, extra throttles), each with its start
/// value: the fit's highest supply pressure and its atmosphere, no load, no throttle.
fn inputs(fit: &FitFile) -> Vec<Variable> {
    const C: &str = "m3/(s*Pa)";
    let p_atm = p_atm_start(fit);
    let inputs = [
        (
            "p_supply",
            vr::P_SUPPLY,
            "Pa",
            "absolute pressure upstream of port 1",
            supply_start(fit),
        ),
        (
            "p_back",
            vr::P_BACK,
            "Pa",
            "absolute pressure downstream of port 2",
            p_atm,
        ),
        (
            "t_load",
            vr::T_LOAD,
            "N*m",
            "load torque opposing forward rotation",
            0.0,
        ),
        (
            "c_throttle1",
            vr::C_THROTTLE1,
            C,
            "sonic conductance of an extra throttle in front of port 1 (0: none)",
            0.0,
        ),
        (
            "c_throttle2",
            vr::C_THROTTLE2,
            C,
            "sonic conductance of an extra throttle behind port 2 (0: none)",
            0.0,
        ),
    ];
    inputs
        .into_iter()
        .map(|(name, reference, unit, what, start)| {
            with_start(var(name, reference, Role::Input, unit, what), start)
        })
        .collect()
}

/// The outputs: rotor speed, shaft torque, port flows and chamber pressures.
fn outputs() -> Vec<Variable> {
    let outputs = [
        ("speed", vr::SPEED, "rad/s", "rotor speed"),
        (
            "torque_shaft",
            vr::TORQUE_SHAFT,
            "N*m",
            "shaft torque: the ideal motor's torque less friction",
        ),
        (
            "flow_port1",
            vr::FLOW_PORT1,
            "kg/s",
            "mass flow into the motor at port 1",
        ),
        (
            "flow_port2",
            vr::FLOW_PORT2,
            "kg/s",
            "mass flow out of the motor at port 2",
        ),
        (
            "p_chamber1",
            vr::P1,
            "Pa",
            "absolute pressure in chamber 1 (inlet side)",
        ),
        (
            "p_chamber2",
            vr::P2,
            "Pa",
            "absolute pressure in chamber 2 (outlet side)",
        ),
        (
            "p_exhaust",
            vr::PE,
            "Pa",
            "absolute pressure in the exhaust chamber",
        ),
    ];
    outputs
        .into_iter()
        .map(|(name, reference, unit, what)| var(name, reference, Role::Output, unit, what))
        .collect()
}

/// The states, their derivatives and the fixed parameters.
fn states_and_fixed_parameters(p_atm: f64) -> Vec<Variable> {
    use Role::{Derivative, Parameter, State};
    let mut v = Vec::new();
    let states = [
        ("p1", "Pa", "state: pressure in chamber 1", p_atm),
        ("p2", "Pa", "state: pressure in chamber 2", p_atm),
        ("pe", "Pa", "state: pressure in the exhaust chamber", p_atm),
        ("omega", "rad/s", "state: rotor speed", 0.0),
    ];
    for (k, (name, unit, what, start)) in states.into_iter().enumerate() {
        v.push(with_start(
            var(name, vr::STATES[k], State, unit, what),
            start,
        ));
    }
    for (k, (name, unit, what, _)) in states.into_iter().enumerate() {
        let unit = if unit == "Pa" { "Pa/s" } else { "rad/s2" };
        let what = format!(
            "time derivative of the {}",
            what.trim_start_matches("state: ")
        );
        v.push(var(
            &format!("der({name})"),
            vr::DERIVATIVES[k],
            Derivative(k),
            unit,
            &what,
        ));
    }
    v.push(with_start(
        var(
            "p_atm",
            vr::P_ATM,
            Parameter,
            "Pa",
            "atmosphere the exhaust port discharges to",
        ),
        p_atm,
    ));
    v.push(with_start(
        var(
            "c_brake",
            vr::C_BRAKE,
            Parameter,
            "N*m*s/rad",
            "viscous brake on the shaft: load torque c_brake*omega (0: none)",
        ),
        0.0,
    ));
    let mut steady = var(
        "start_steady",
        vr::START_STEADY,
        Parameter,
        "1",
        "start from the steady state at the initial inputs (false: from the states' start values)",
    );
    steady.start = Some(1.0);
    steady.boolean = true;
    v.push(steady);
    v
}

/// A geared motor's shaft variables say that they are the motor shaft's (the FMU models
/// the motor; the gearbox's output turns G times slower with η·G times the torque,
/// docs/formats.md, "Geared motors").
fn at_motor_shaft(vars: &mut [Variable], g: &crate::model::gear::Gear) {
    let note = format!(
        " (MOTOR shaft; gearbox output: speed/{}, torque × {:.6})",
        g.ratio,
        g.efficiency * g.ratio
    );
    for v in vars.iter_mut() {
        if [
            vr::SPEED,
            vr::TORQUE_SHAFT,
            vr::T_LOAD,
            vr::C_BRAKE,
            vr::STATES[3],
        ]
        .contains(&v.vr)
        {
            v.description.push_str(&note);
        }
    }
}

/// Every variable of the FMU of `fit`, in the order of `modelDescription.xml`.
pub fn variables(fit: &FitFile) -> Result<Vec<Variable>, FmuError> {
    let mut v = inputs_and_outputs(fit);
    v.extend(states_and_fixed_parameters(p_atm_start(fit)));
    if let Some(g) = &fit.gear {
        at_motor_shaft(&mut v, g);
    }
    for (k, p) in model_parameters(fit)?.into_iter().enumerate() {
        v.push(with_start(
            var(
                &p.name,
                vr::FIRST_MODEL_PARAMETER + k as u32,
                Role::Parameter,
                &p.unit,
                &p.description,
            ),
            p.value,
        ));
    }
    Ok(v)
}
