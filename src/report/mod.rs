//! Reports: SVG charts and the written results of fits, diagnoses and control studies.

pub mod control;
pub mod diagnose;
pub mod explain;
pub mod fit;
pub mod plot;
