//! Reports: SVG charts and the written results of fits and diagnoses.

pub mod diagnose;
pub mod fit;
pub mod plot;
