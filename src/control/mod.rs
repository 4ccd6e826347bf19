//! Speed control of the vane motor (paper §5): throttling (§5.1, Figs. 14–15), the
//! linearised motor and its frequency response (Fig. 16), the electro-pneumatic control loop
//! with a pressure control valve and a discrete PI controller (§5.2, Figs. 17–20), and a PI
//! design helper.
//!
//! * `throttle`: steady speed against throttle conductance, torque–speed curves (§5.1).
//! * `linear`: linearisation A, B, C by central differences of `Motor::derivatives`, Bode
//!   data, fit of K/((1+sT1)(1+sT2)) (§5.2, Fig. 16).
//! * `closed_loop`: valve, discrete PI with anti-windup, sample-to-sample simulation
//!   (Figs. 18–20).
//! * `design`: margins of the loop and PI gains for a phase margin or crossover.
//! * `min_speed`: lowest speed without control (pressure-ramp start-up) and with control.
//! * `study`: the studies of `vanefit control <study>`: their checked settings and a
//!   `study` function each that returns the results (no printing, no files; the CSV tables
//!   and SVG figures are `report::control`'s).
//! * `option`: the studies' options as values ([`ControlOpt`]), as the errors name them.
//! * `error`: why a study could not be done.
//!
//! The motor is integrated with `numerics::DefaultSolver`, which steps and interpolates
//! itself and so serves the many short sample-to-sample intervals of the closed loop.
//!
//! SI units inside (Pa absolute, rad/s, N·m, s). The controller's signals are the exception
//! that the paper imposes: the command is in volts (0–10 V to the valve) and the speed error in
//! krpm, see [`closed_loop::PiController`]. Units at the edges are named in identifiers and
//! CSV columns (`_rpm`, `_mpa`, `_v`, …).

pub(crate) mod closed_loop;
pub(crate) mod design;
pub(crate) mod error;
pub(crate) mod linear;
pub(crate) mod min_speed;
pub(crate) mod option;
pub(crate) mod study;
pub(crate) mod throttle;

pub use closed_loop::{
    AntiWindup, DisturbanceMetrics, Loop, LoopStart, PiController, Scenario, StepMetrics, Steps,
    Trace, Valve, ValveState,
};
pub use design::{design_pi, margins, Margins, Target};
pub use error::{ControlError, SettingsError, UnknownAntiWindup};
pub use linear::{LagFit, LinearModel, OperatingPoint, TwoLags};
pub use min_speed::{open_loop_start, ControlledMin, HoldAttempt, Jump, StartUp};
pub use option::ControlOpt;
pub use study::bode::BodeSettings;
pub use study::design::DesignSettings;
pub use study::disturbance::DisturbanceSettings;
pub use study::min_speed::MinSpeedSettings;
pub use study::step::StepSettings;
pub use study::throttle::{ThrottleSettings, TorqueCurve};
pub use study::{
    linear_at, BodeOptions, BodeStudy, DesignOptions, DesignRun, DesignStudy, DisturbanceOptions,
    DisturbanceStudy, GainOptions, LoopOptions, MinSpeedOptions, MinSpeedStudy, MotorOptions,
    PiOptions, Plant, StepOptions, StepStudy, ThrottleOptions, ThrottleStudy, ValveOptions,
};
pub use throttle::{Port, ThrottlePoint, TorquePoint};

/// rad/s per rpm.
pub(crate) const RAD_S_PER_RPM: f64 = std::f64::consts::PI / 30.0;

/// A speed in rpm from rad/s.
pub fn rpm(w_rad_s: f64) -> f64 {
    w_rad_s / RAD_S_PER_RPM
}
