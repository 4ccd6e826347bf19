//! Data at the file edge: datasets (rig.toml + CSV), fit files and their statistics,
//! synthetic datasets.

pub(crate) mod dataset;
pub(crate) mod fitfile;
pub mod locate;
pub(crate) mod motor;
pub(crate) mod statistics;
pub(crate) mod synth;
pub(crate) mod synth_catalogue;

pub use dataset::catalogue::ValueError;
pub use dataset::page_rules::PageWarning;
pub use dataset::{
    page_warnings, parse_value, Cells, DataError, Dataset, ExperimentData, Kind, MotorSection,
    Recording, FIGURES,
};
pub use fitfile::{
    FitConditions, FitFile, FitFileError, LogCovariance, ParamVerdict, ProfilePath, RunInfo,
    Starts, TermError,
};
pub use motor::MotorSpecError;
pub use statistics::{EstimateMethod, FitStatistics, GoodnessOfFit, PriorEntry, UncertaintyMethod};
pub use synth::{free_speed, plan_experiments, synthesize, write_dataset, SensorNoise, SynthPlan};
