//! vanefit: estimate the physical parameters of pneumatic vane motors from datasheets and
//! test-rig recordings, and find the physics that a model leaves out.
//!
//! Layout follows the architecture: physics (`geometry`, `thermo`, `nozzle`, `friction`) makes
//! the `motor` model (parameters → state derivatives); `ode` and `steady` solve it;
//! `experiment` drives it with the inputs of a `dataset`; `fitfile` reads and writes
//! parameter sets. SI units everywhere inside; `units` converts at the file edge.

pub mod cli;
pub mod constants;
pub mod control;
pub mod cost;
pub mod dataset;
pub mod diagnose;
pub mod effects;
pub mod estimate;
pub mod experiment;
pub mod fitfile;
pub mod friction;
pub mod fsutil;
pub mod geometry;
pub mod motor;
pub mod nozzle;
pub mod ode;
pub mod params;
pub mod plot;
pub mod reference;
pub mod schedule;
pub mod steady;
pub mod synth;
pub mod thermo;
pub mod units;
