//! `vanefit predict`: the shipped fit end to end ([`predict`]), a catalogue page fitted and
//! predicted at other pressures ([`catalogue_predict`]) and the catalogue rows against the
//! independent twin ([`twin_catalogue`]).

mod catalogue_predict;
#[path = "../common/mod.rs"]
mod common;
mod every_size;
mod geared;
mod page_bands;
mod page_coverage;
mod page_pairs;
mod plan_cli;
mod plan_twin;
mod plan_twin_rig;
mod predict;
mod sampled_bands;
extern crate twin;
mod twin_catalogue;
