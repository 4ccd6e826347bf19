//! The fitting objective: polynomial reference responses and the cost built on them, and
//! the likelihood of the recorded rows with a noise estimate from the data.

pub mod cost;
pub mod likelihood;
pub mod nuisance;
pub mod reference;
