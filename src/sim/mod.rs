//! Simulation: the reference experiments (SPEC §2) driven by recorded inputs, steady states,
//! input schedules.

pub mod experiment;
pub mod recording;
pub mod schedule;
pub mod steady;
