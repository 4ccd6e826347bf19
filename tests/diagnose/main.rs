//! The missing-physics diagnosis (`vanefit::diagnose`) on synthetic data with known truth:
//! the cases and their checks ([`cases`]), vanefit's own synthetic data ([`own_data`]) and
//! data written by the independent twin generator ([`twin_data`]).

extern crate twin;

mod cases;
mod own_data;
mod random_effects;
mod support;
mod twin_data;
