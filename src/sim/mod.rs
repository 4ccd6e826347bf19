//! Simulation: the reference experiments (docs/model.md, "Reference experiments") driven by
//! recorded inputs, steady states, steady operating points and catalogue figures, input
//! schedules.

pub mod experiment;
pub mod operating_point;
pub mod recording;
pub(crate) mod schedule;
pub mod steady;
