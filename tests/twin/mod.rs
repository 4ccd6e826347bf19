//! The twin generator: an independent implementation of the model and the reference experiments of
//! docs/model.md (and some effects of its "Missing-physics catalog"), written from the docs and the
//! paper only, that writes datasets in vanefit's file formats, so that a mistake shared by
//! vanefit's model and its own synthetic data can show. It shares no code with vanefit (no `use
//! vanefit::…`), and integrates with TR-BDF2 where vanefit uses Rodas4/BDF: "same physics,
//! different code".
//!
//! Include it with `#[path = "../twin/mod.rs"] mod twin;` from a test binary's `main.rs`, or with
//! `#[path = "../tests/twin/mod.rs"] mod twin;` from an example.
#![allow(dead_code, unused_imports)]

pub mod cases;
pub mod catalogue;
pub mod control;
pub mod experiment;
pub mod files;
pub mod laws;
pub mod motor;
pub mod ode;
pub mod page;
pub mod record;
pub mod rig;
pub mod steady;

pub use cases::{perturbed_motor, perturbed_motor_within, varied_config, CALIBRATION_TOL};
pub use experiment::Conditions;
pub use motor::{Breakaway, SealLeakage, TwinMotor};
pub use record::{
    write_dataset, FlowUnit, NoiseSigmas, OffsetSpec, Offsets, PressureUnit, RecordConfig,
    SpeedUnit, Units, WrittenDataset,
};
