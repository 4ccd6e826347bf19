//! Data at the file edge: datasets (rig.toml + CSV), fit files, synthetic datasets.

pub(crate) mod dataset;
pub(crate) mod fitfile;
pub(crate) mod motor;
pub(crate) mod synth;
pub(crate) mod synth_catalogue;

pub use dataset::catalogue::ValueError;
pub use dataset::page_rules::PageWarning;
pub use dataset::{
    page_warnings, parse_value, Cells, DataError, Dataset, ExperimentData, Kind, MotorSection,
    Recording, FIGURES,
};
pub use fitfile::{
    FitConditions, FitFile, FitFileError, FitStatistics, LogCovariance, ParamVerdict, PriorEntry,
    ProfilePath, RunInfo, Starts, TermError,
};
pub use motor::MotorSpecError;
pub use synth::{free_speed, plan_experiments, synthesize, write_dataset, SensorNoise, SynthPlan};
