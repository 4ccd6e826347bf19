//! `vanefit fit` (SPEC §6): progress and summary on the terminal; the options and the fit
//! itself are `task::fit`, shared with `batch`.

pub use crate::task::fit::{
    fit_run, side_path, space_from_args, write_fit, FitArgs, FitCommandError, FitRun, FitWritten,
    Uncertainty,
};

use crate::data::dataset::{Dataset, Kind};
use crate::estimate::fit::{FitOutcome, FitSetup};
use crate::estimate::multistart::{RunObserver, StartResult};
use crate::report::explain;
use crate::report::fit as report;
use indicatif::{ProgressBar, ProgressStyle};
use std::path::Path;

/// A progress bar over starts with the best cost so far; drawn only on a terminal.
struct Progress(ProgressBar);

impl RunObserver for Progress {
    fn started(&self, total: usize, already_done: usize) {
        self.0.set_length(total as u64);
        self.0.set_position(already_done as u64);
    }
    fn start_finished(&self, _r: &StartResult, best: f64) {
        self.0.inc(1);
        self.0.set_message(format!("best cost J {best:.4}"));
    }
    fn finished(&self) {
        self.0.finish_and_clear();
    }
}

fn progress() -> Progress {
    let bar = ProgressBar::new(0);
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:30}] {pos}/{len} starts  {msg}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    Progress(bar)
}

/// Runs `vanefit fit`: fit, fit file, summary, plots.
pub fn run(args: &FitArgs) -> Result<(), FitCommandError> {
    let fitted = fit_run(
        args,
        Some(side_path(&args.out, "starts.jsonl")),
        &progress(),
    )?;
    let written = write_fit(&fitted, &args.out, args.seed, !args.no_plots)?;
    print_summary(&fitted.dataset, &fitted.setup, &fitted.outcome, &args.out);
    if !written.plots.is_empty() {
        println!(
            "plots: {}",
            written
                .plots
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    println!("report: {}", written.report.display());
    Ok(())
}

fn print_summary(ds: &Dataset, setup: &FitSetup, out: &FitOutcome, path: &Path) {
    let run = &out.run;
    println!(
        "fit of {}: {} starts ({} converged), {} evaluations, {:.1} s on {} thread(s)",
        ds.name,
        run.results.len(),
        run.converged(),
        out.evaluations,
        out.wall_s,
        run.threads
    );
    if !setup.space.effects.is_empty() {
        println!("effects: {}", setup.space.effects.ids().join(", "));
    }
    for ex in ds.experiments.iter().filter(|e| e.kind == Kind::Catalogue) {
        println!(
            "{}: catalogue points weigh with their reading tolerance ({:.0} % of each curve's full scale) as σ, not a noise estimate, and carry no sensor offsets",
            ex.file,
            100.0 * ex.tolerance.unwrap_or(0.0)
        );
    }
    print_goodness(out);
    for line in report::terminal_table(&report::parameter_rows(ds, setup, out)) {
        println!("{line}");
    }
    println!("fixed (not estimated):");
    for (s, v) in report::fixed_parameters(setup, out) {
        println!(
            "  {:<10} {:<42} {}",
            s.name,
            explain::value(s.name, v, 5),
            s.description()
        );
    }
    let minima: Vec<String> = out
        .clusters
        .iter()
        .take(5)
        .map(|c| format!("{:.4} (x{})", c.cost, c.members.len()))
        .collect();
    println!("local minima (cost J x starts): {}", minima.join(", "));
    println!("wrote {}", path.display());
}

/// What the estimate is, how well it fits, and cost against χ².
fn print_goodness(out: &FitOutcome) {
    println!(
        "estimate: the maximum-likelihood point of the recorded rows (chi2 {:.1} over {} points; each channel's σ from the data's noise, a catalogue's from its reading tolerance; recorded sensors' offsets within calibration tolerance profiled out)",
        out.chi2, out.n_points
    );
    if !out.nuisances.is_empty() {
        let list: Vec<String> = out
            .nuisances
            .iter()
            .map(|(k, v)| format!("{k} {v:+.3e}"))
            .collect();
        println!(
            "systematic errors at the estimate (SI): {}",
            list.join(", ")
        );
    }
    if let Some(g) = &out.goodness {
        let verdict = if g.noise_reached {
            "the model reaches the noise".to_string()
        } else {
            let worst = g
                .worst_channel
                .as_ref()
                .map(|(c, r)| format!("; worst {c} at {r:.2}x its noise"))
                .unwrap_or_default();
            format!(
                "the model does NOT reach the noise{worst}: intervals widened {:.2}x; do not trust them without a look at the plots",
                g.interval_scale
            )
        };
        println!(
            "goodness of fit: chi2/dof {:.3} (dof {}), noise ratio {:.3} (limit {:.3}): {verdict}",
            g.chi2_per_dof, g.dof, g.noise_ratio, g.noise_ratio_limit
        );
    }
    println!(
        "cost J {:.4} at the estimate; the best start reached {:.4} (J weighs each channel by its reference polynomial's scatter, chi2 by the data's noise, so their optima differ a little)",
        out.cost, out.best_start_cost
    );
    println!("  what these are: {}.", explain::NOISE_RATIO);
    println!("  {}; {}.", explain::CHI2_PER_DOF, explain::CHI2_OFFSETS);
    println!("  {}.", explain::COST_J);
    println!("  {}.", explain::CONDUCTANCE_UNITS);
}
