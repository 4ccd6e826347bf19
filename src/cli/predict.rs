//! `vanefit predict <fit.json>` (issue 12, SPEC §7): what the fitted motor does at other
//! supply pressures or with an extra nozzle, with 95 % bands; the work is
//! `task::predict` (shared with `batch`), this prints the tables.
//!
//! Every bad input (fit file, pressure list, unit, nozzle) is refused with a message that
//! names the file or option, exit status 1, before anything is written.

use crate::io::say;
pub use crate::task::predict::{predict_to, PredictArgs, PredictCommandError, Predicted};

use crate::report::predict::{notes, tables_markdown};
use std::time::Instant;

/// Runs `vanefit predict`.
pub fn run(args: &PredictArgs) -> Result<(), PredictCommandError> {
    let t0 = Instant::now();
    crate::io::out::check_dir(&args.out)?;
    let Predicted {
        prediction,
        display,
        source,
        written,
    } = predict_to(args)?;
    say!("prediction from {source}\n");
    say!("{}", tables_markdown(&prediction, &display));
    for n in notes(&prediction, &display) {
        say!("- {n}");
    }
    let written: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    say!(
        "\nwrote {} ({:.2} s)",
        written.join(", "),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
