//! The twin generator (issue 11): an independent implementation of the SPEC §1–§2 physics
//! (and some §5 effects), written from the SPEC and the paper only, that writes datasets in
//! vanefit's file formats. It shares no code with vanefit (no `use vanefit::…`), and
//! integrates with TR-BDF2 where vanefit uses Rodas4/BDF: "same physics, different code".
//!
//! Include it with `mod twin;` from an integration test, or with
//! `#[path = "../tests/twin/mod.rs"] mod twin;` from an example.
#![allow(dead_code, unused_imports)]

pub mod cases;
pub mod catalogue;
pub mod experiment;
pub mod files;
pub mod motor;
pub mod ode;
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
