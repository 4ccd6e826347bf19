//! The missing-physics diagnosis (`vanefit::diagnose`) on synthetic data with known truth.

mod cases;
mod support;
#[allow(clippy::type_complexity)] // the twin generator is another engineer's code
#[path = "../twin/mod.rs"]
mod twin;
