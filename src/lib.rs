#![warn(missing_docs)]
#![deny(rustdoc::broken_intra_doc_links)]
//! vanefit: estimate the physical parameters of pneumatic vane motors from datasheets and
//! test-rig recordings, and find the physics that a model leaves out.
//!
//! The folders are the layers, and each depends only on the ones before it:
//! `units` → `io` → `numerics` → `model` → `sim` → `data` → `objective` → `estimate` →
//! {`diagnose`, `control`, `predict`, `export`} → `report` → `task` → `batch` → `cli`. SI
//! units everywhere inside; `units` converts at the file edge. `task` holds the work of the
//! `fit`, `diagnose` and `predict` commands as library functions; `batch` runs them over a
//! fleet of datasets in deterministic shards and merges the results.

pub mod batch;
pub mod cli;
pub mod control;
pub mod data;
pub mod diagnose;
pub mod estimate;
pub mod export;
pub mod io;
pub mod model;
pub mod numerics;
pub mod objective;
pub mod predict;
pub mod report;
pub mod sim;
pub mod task;
pub mod units;
