//! The model and its simulation: physics the core must reproduce ([`physics`]), the same
//! data in other units ([`units_equivalence`]) and vanefit against an independent
//! implementation of the same physics ([`twin_agreement`]).

mod physics;
extern crate twin;
mod twin_agreement;
mod units_equivalence;
