//! Simulation: the reference experiments (docs/model.md, "Reference experiments") driven by
//! recorded inputs, steady states, steady operating points and catalogue figures, input
//! schedules.

pub(crate) mod experiment;
pub(crate) mod operating_point;
pub(crate) mod recording;
pub(crate) mod schedule;
pub mod steady;

pub use experiment::{
    AbscissaSpec, Drive, Experiment, ExperimentKind, InputCheck, Setting, SimError, Simulated,
};
pub use operating_point::{CatalogueRow, Conditions, OperatingPointError};
pub use recording::{Column, ExperimentData, Figure, MissingColumn};
