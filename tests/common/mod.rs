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

/// The fit's own wall time, s: from its summary line on stdout ("fit of …: … evaluations,
/// 0.9 s on 1 thread(s)"), or `run.wall_s` of the fit file where an older vanefit wrote it
/// there.
pub fn fit_wall_s(fit: &Path, stdout: &str) -> Option<f64> {
    let printed = stdout
        .lines()
        .find(|l| l.starts_with("fit of "))
        .and_then(|l| l.split(" evaluations, ").nth(1))
        .and_then(|rest| rest.split(" s on ").next())
        .and_then(|v| v.trim().parse::<f64>().ok());
    printed.or_else(|| {
        let text = std::fs::read_to_string(fit).ok()?;
        let json: serde_json::Value = serde_json::from_str(&text).ok()?;
        json["run"]["wall_s"].as_f64()
    })
}
