//! The twin generator: an independent implementation of the model and the reference experiments of
//! docs/model.md (and some effects of its "Missing-physics catalog"), written from the docs and the
//! paper only, that writes datasets in vanefit's file formats, so that a mistake shared by
//! vanefit's model and its own synthetic data can show. It shares no code with vanefit (no `use
//! vanefit::…`), and integrates with TR-BDF2 where vanefit uses Rodas4/BDF: "same physics,
//! different code".
//!
//! It is a crate of its own, `vanefit-twin` (lib `twin`, tests/twin/Cargo.toml), a
//! dev-dependency of vanefit, compiled once: a test binary's `main.rs` names it with
//! `extern crate twin;` (so that its modules' `use crate::twin;` reach it), an example
//! uses `twin::…` directly. (`#[path = "../twin/mod.rs"] mod twin;` includes it as a module
//! as well.)
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
pub mod pair;
pub mod record;
pub mod rig;
pub mod sizes;
pub mod steady;
pub mod styles;

pub use cases::{perturbed_motor, perturbed_motor_within, varied_config, CALIBRATION_TOL};
pub use experiment::Conditions;
pub use motor::{Breakaway, SealLeakage, TwinMotor};
pub use record::{
    write_dataset, write_experiment, Experiment, FlowUnit, NoiseSigmas, OffsetSpec, Offsets,
    PressureUnit, RecordConfig, SpeedUnit, Units, WrittenDataset,
};
