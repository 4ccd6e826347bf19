//! What the command-line tests share: the shipped dataset and running the built binary.
#![allow(dead_code)] // each test crate uses its own subset

use std::path::Path;
use std::process::{Command, Output};

/// The shipped synthetic dataset (paths are relative to the crate root, where tests run).
pub const DATASET: &str = "measurements/ar034-synthetic";

/// Runs the built `vanefit` with `args` in the crate root.
pub fn vanefit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs the built `vanefit` with `args` in the folder `cwd`.
pub fn vanefit_in(args: &[&str], cwd: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap()
}

/// What a run wrote to stderr.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}
