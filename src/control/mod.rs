//! Speed control of the vane motor (paper §5): throttling (§5.1, Figs. 14–15), the
//! linearised motor and its frequency response (Fig. 16), the electro-pneumatic control loop
//! with a pressure control valve and a discrete PI controller (§5.2, Figs. 17–20), and a PI
//! design helper.
//!
//! * [`throttle`]: steady speed against throttle conductance, torque–speed curves (§5.1).
//! * [`linear`]: linearisation A, B, C by central differences of `Motor::derivatives`, Bode
//!   data, fit of K/((1+sT1)(1+sT2)) (§5.2, Fig. 16).
//! * [`closed_loop`]: valve, discrete PI with anti-windup, sample-to-sample simulation
//!   (Figs. 18–20).
//! * [`design`]: margins of the loop and PI gains for a phase margin or crossover.
//! * [`min_speed`]: lowest speed without control (pressure-ramp start-up) and with control.
//! * [`study`]: `vanefit control <study>`, CSV and SVG output.
//!
//! The motor is integrated with `ode::DiffsolBdf`, which steps and interpolates itself and so
//! serves the many short sample-to-sample intervals of the closed loop.
//!
//! SI units inside (Pa absolute, rad/s, N·m, s). The controller's signals are the exception
//! that the paper imposes: the command is in volts (0–10 V to the valve) and the speed error in
//! krpm, see [`closed_loop::PiController`]. Units at the edges are named in identifiers and
//! CSV columns (`_rpm`, `_mpa`, `_v`, …).

pub mod closed_loop;
pub mod design;
pub mod linear;
pub mod min_speed;
pub mod throttle;

use std::fmt;

/// Why a control study could not be done.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlError(pub String);

impl fmt::Display for ControlError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ControlError {}

impl From<crate::sim::steady::SteadyError> for ControlError {
    fn from(e: crate::sim::steady::SteadyError) -> Self {
        ControlError(e.to_string())
    }
}

impl From<crate::numerics::ode::SolveError> for ControlError {
    fn from(e: crate::numerics::ode::SolveError) -> Self {
        ControlError(e.to_string())
    }
}

/// rad/s per rpm.
pub const RAD_S_PER_RPM: f64 = std::f64::consts::PI / 30.0;
