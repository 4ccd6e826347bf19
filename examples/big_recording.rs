//! Writes the shipped dataset (`measurements/ar034-synthetic`) with its pressure ramp
//! repeated until that one recording holds about `MB` megabytes, time still increasing: the
//! large-input test (`check` on a 100 MB recording within 10 s and 500 MB), reproducible.
//!
//! ```text
//! cargo run --release --example big_recording -- OUT_DIR [MB]    # MB: default 100
//! /usr/bin/time -v target/release/vanefit check OUT_DIR
//! ```
//!
//! The datasheet and the outlet throttle stay as shipped (one large recording is the harder
//! case: its text, cells and values are all held at once). Each repetition copies the shipped rows unchanged except time, which continues
//! from the previous repetition's last value plus one sampling step (written in the shipped
//! `%.6e` form), so the file reads like one long recording of a rig cycling its program.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const USAGE: &str = "usage: big_recording OUT_DIR [MB]";

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(out) = args.next().map(PathBuf::from) else {
        eprintln!("{USAGE}");
        std::process::exit(2);
    };
    let mb: f64 = match args.next().map(|s| s.parse()) {
        None => 100.0,
        Some(Ok(v)) if v > 0.0 => v,
        _ => {
            eprintln!("{USAGE}");
            std::process::exit(2);
        }
    };
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("measurements/ar034-synthetic");
    std::fs::create_dir_all(&out).expect("output folder");
    for file in ["rig.toml", "datasheet.csv", "throttle.csv"] {
        std::fs::copy(src.join(file), out.join(file)).expect("copy");
    }
    let text = std::fs::read_to_string(src.join("ramp.csv")).expect("shipped recording");
    let big = repeated(&text, (mb * 1e6) as usize);
    std::fs::write(out.join("ramp.csv"), &big).expect("write");
    eprintln!("{}: {} bytes", out.join("ramp.csv").display(), big.len());
}

/// `text` (a header, then rows whose first cell is time) repeated to at least `bytes`
/// bytes, time shifted in each repetition so that it keeps increasing by the shipped step.
fn repeated(text: &str, bytes: usize) -> String {
    let mut lines = text.lines();
    let header = lines.next().expect("header");
    assert!(header.starts_with("t_s,"), "time first");
    let rows: Vec<(f64, &str)> = lines
        .map(|l| {
            let (t, rest) = l.split_once(',').expect("a row");
            (t.parse().expect("time"), rest)
        })
        .collect();
    let (t0, t1) = (rows[0].0, rows[rows.len() - 1].0);
    let step = rows[1].0 - rows[0].0;
    let period = t1 - t0 + step;
    let mut out = String::with_capacity(bytes + text.len());
    out.push_str(header);
    out.push('\n');
    let mut rep = 0u64;
    let mut last = String::new();
    while out.len() < bytes {
        // Integer sample counts, so that rounding never makes time stand still.
        for (k, (_, rest)) in rows.iter().enumerate() {
            let t = format!("{:.6e}", t0 + rep as f64 * period + k as f64 * step);
            assert!(
                t != last,
                "time {t} repeats: seven digits no longer resolve the step"
            );
            let _ = writeln!(out, "{t},{rest}");
            last = t;
        }
        rep += 1;
    }
    out
}
