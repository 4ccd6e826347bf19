//! The fitting objective: polynomial reference responses and the cost built on them.

pub mod cost;
pub mod reference;
