//! Reports: SVG charts and the written results of fits, diagnoses, control studies and
//! predictions.

pub mod control;
pub mod diagnose;
pub mod explain;
pub mod fit;
pub mod plan;
pub mod plot;
pub mod predict;
