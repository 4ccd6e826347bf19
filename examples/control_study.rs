//! A speed-control study: the closed-loop response of the shipped fit to a set-point step.
//!
//! `cargo run --release --example control_study [out-folder]` (with a folder, the CSV
//! tables and SVG figures of `vanefit control step` are written there).

use std::path::{Path, PathBuf};
use vanefit::control::StepOptions;
use vanefit::control::{LoopOptions, MotorOptions};
use vanefit::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let params = Path::new(env!("CARGO_MANIFEST_DIR")).join("fits/ar034-synthetic.json");
    let study = ControlStudy {
        motor: MotorOptions {
            params: Some(params),
            ..MotorOptions::default()
        },
        study: Study::Step(
            LoopOptions::default(),
            StepOptions {
                from_rpm: 3000.0,
                to_rpm: 4500.0,
                t_step_s: 0.5,
                duration_s: 8.0,
            },
        ),
    };
    let result = vanefit::run_study(&study)?;
    if let StudyResult::Step(r) = &result {
        let m = &r.metrics;
        println!(
            "step 3000 -> 4500 rpm: rise {:.3} s, overshoot {:.1} %, settling {:.3} s",
            m.rise_time_s, m.overshoot_pct, m.settling_time_s
        );
    }
    if let Some(out) = std::env::args().nth(1).map(PathBuf::from) {
        vanefit::write_study(&result, &out, &mut |p| println!("wrote {}", p.display()))?;
    }
    Ok(())
}
