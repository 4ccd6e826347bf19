//! Data at the file edge: datasets (rig.toml + CSV), fit files, synthetic datasets.

pub mod dataset;
pub mod fitfile;
pub mod motor;
pub mod synth;
pub(crate) mod synth_catalogue;
