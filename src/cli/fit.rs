//! `vanefit fit` (docs/cli.md, "fit"): the options, progress and summary on the terminal; the fit
//! itself is `vanefit::task::fit` (named by its module, where it is defined), shared with
//! `batch` and the Python package.

use crate::cli::Failure;
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use vanefit::data::Dataset;
use vanefit::estimate::multistart::{RunObserver, StartResult};
use vanefit::estimate::DisplacementEstimate;
use vanefit::estimate::UncertaintyMethod;
use vanefit::model::EffectSet;
use vanefit::report::fit::{self as report, SummaryLine};
use vanefit::task::fit::{
    displacement_start_line, fit_to, pinning_lines, FitObserver, FitOptions, ParamRange, Pinning,
};

use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Options of `vanefit fit`.
#[derive(Args, Debug, Clone)]
pub(crate) struct FitArgs {
    /// Dataset folder (rig.toml and recordings).
    pub(crate) dataset: PathBuf,
    /// Number of start points (Latin hypercube).
    #[arg(long, default_value_t = 32, value_parser = crate::cli::at_least_one)]
    pub(crate) starts: usize,
    #[command(flatten)]
    pub(crate) run: crate::cli::RunArgs,
    #[arg(
        long,
        default_value = "",
        value_parser = crate::cli::effects_arg,
        help = crate::cli::effects_help("Effects to switch on (their parameters are estimated too)")
    )]
    pub(crate) effects: String,
    /// Parameters to estimate (comma-separated; default: six conductances, t_coulomb, visc).
    #[arg(long)]
    pub(crate) estimate: Option<String>,
    /// Search bounds, e.g. `c_in1=1e-9:2e-8,visc=1e-6:1e-3` (SI).
    #[arg(long)]
    pub(crate) bounds: Option<String>,
    /// Where start points are drawn, e.g. `c_12=1e-10:1e-9` (SI); default: a factor
    /// `--start-spread` either side of the default (AR034-11 values scaled with the rig's
    /// displacement for conductances), within the bounds.
    #[arg(long)]
    pub(crate) start_range: Option<String>,
    /// Default start range: this factor either side of the default value.
    #[arg(long, default_value_t = 3.0)]
    pub(crate) start_spread: f64,
    /// Iteration budget of each start.
    #[arg(long, default_value_t = 3000)]
    pub(crate) max_iters: u64,
    /// Run Nelder–Mead alone, round after round, instead of handing each start over to
    /// least squares (Levenberg–Marquardt) after its first round (docs/performance.md).
    #[arg(long)]
    pub(crate) no_handoff: bool,
    /// How to compute 95% intervals.
    #[arg(long, value_enum, default_value_t = Uncertainty::Profile)]
    pub(crate) uncertainty: Uncertainty,
    /// Continue an interrupted run from its results file (`<out>.starts.jsonl`).
    #[arg(long)]
    pub(crate) resume: bool,
    /// Keep every start's cost trace in the results file.
    #[arg(long)]
    pub(crate) trace: bool,
    /// Skip the plots.
    #[arg(long)]
    pub(crate) no_plots: bool,
    /// The prior of the motor's parameters: `size` (log-normal around the defaults scaled
    /// to the displacement; docs/estimation.md, "Priors") or `none` (the likelihood alone).
    #[arg(long, value_enum, default_value_t = Priors::Size)]
    pub(crate) priors: Priors,
    /// Fit file to write (vanefit.fit/1); results and plots go next to it.
    #[arg(long)]
    pub(crate) out: PathBuf,
}

/// `--priors`: which prior the fit adds to the likelihood.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Priors {
    /// Log-normal around the defaults scaled to the motor's displacement.
    Size,
    /// None: maximum likelihood.
    None,
}

/// `--uncertainty`: how 95% intervals are computed.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Uncertainty {
    /// Profile likelihood.
    Profile,
    /// Curvature of χ² only.
    Curvature,
    /// No intervals.
    None,
}

impl FitArgs {
    /// The library's options: the range lists parsed (a bad item names its flag).
    pub(crate) fn options(&self) -> Result<FitOptions, Failure> {
        let ranges = |text: &Option<String>, flag: &str| {
            ParamRange::parse_list(text.as_deref().unwrap_or(""))
                .map_err(|e| Failure(format!("{flag}: {e}")))
        };
        Ok(FitOptions {
            starts: self.starts,
            seed: self.run.seed,
            threads: self.run.threads,
            effects: EffectSet::parse_list(&self.effects)?,
            estimate: self
                .estimate
                .as_ref()
                .map(|list| list.split(',').map(str::to_string).collect()),
            bounds: ranges(&self.bounds, "--bounds")?,
            start_ranges: ranges(&self.start_range, "--start-range")?,
            start_spread: self.start_spread,
            max_iters: self.max_iters,
            handoff: !self.no_handoff,
            uncertainty: match self.uncertainty {
                Uncertainty::Profile => UncertaintyMethod::Profile,
                Uncertainty::Curvature => UncertaintyMethod::Curvature,
                Uncertainty::None => UncertaintyMethod::None,
            },
            resume: self.resume,
            trace: self.trace,
            priors: self.priors == Priors::Size,
        })
    }
}

/// Progress of a fit: on a terminal a bar over the starts, then one over the profiles;
/// without one (a log file, a pipe, a Slurm job) periodic lines on stderr, so that a log
/// shows a live run and what phase it is in.
enum Progress {
    /// The indicatif bar of the current phase.
    Bar(Mutex<ProgressBar>),
    /// Lines at most every [`LINE_EVERY`], and at each phase's start and end.
    Lines(Lines),
}

/// How often a log line is written at most while starts or profiles finish.
const LINE_EVERY: Duration = Duration::from_secs(10);

/// State of the log lines.
struct Lines {
    t0: Instant,
    last: Mutex<Instant>,
    total: AtomicUsize,
    done: AtomicUsize,
    phase: Mutex<(String, usize)>,
}

impl Lines {
    fn line(&self, text: &str) {
        eprintln!("[{:7.1} s] fit: {text}", self.t0.elapsed().as_secs_f64());
    }
    /// Whether a periodic line is due (always for the last step).
    fn due(&self, last_step: bool) -> bool {
        let mut last = self.last.lock().unwrap_or_else(|p| p.into_inner());
        if last_step || last.elapsed() >= LINE_EVERY {
            *last = Instant::now();
            return true;
        }
        false
    }
}

impl RunObserver for Progress {
    fn started(&self, total: usize, already_done: usize) {
        match self {
            Progress::Bar(bar) => {
                let bar = bar.lock().unwrap_or_else(|p| p.into_inner());
                bar.set_length(total as u64);
                bar.set_position(already_done as u64);
            }
            Progress::Lines(l) => {
                l.total.store(total, Ordering::Relaxed);
                l.done.store(already_done, Ordering::Relaxed);
                l.line(&format!(
                    "starts {already_done}/{total}{}",
                    if already_done > 0 { " (resumed)" } else { "" }
                ));
            }
        }
    }
    fn start_finished(&self, _r: &StartResult, best: f64) {
        match self {
            Progress::Bar(bar) => {
                let bar = bar.lock().unwrap_or_else(|p| p.into_inner());
                bar.inc(1);
                bar.set_message(format!("best cost J {best:.4}"));
            }
            Progress::Lines(l) => {
                let done = l.done.fetch_add(1, Ordering::Relaxed) + 1;
                let total = l.total.load(Ordering::Relaxed);
                if l.due(done >= total) {
                    l.line(&format!("starts {done}/{total}, best cost J {best:.4}"));
                }
            }
        }
    }
    fn finished(&self) {
        if let Progress::Bar(bar) = self {
            bar.lock()
                .unwrap_or_else(|p| p.into_inner())
                .finish_and_clear();
        }
    }
    fn phase(&self, name: &str, steps: usize) {
        match self {
            Progress::Bar(bar) => {
                let mut bar = bar.lock().unwrap_or_else(|p| p.into_inner());
                bar.finish_and_clear();
                let what = if steps > 0 {
                    format!("{{pos}}/{{len}} {name}")
                } else {
                    name.to_string()
                };
                *bar = new_bar(steps as u64, &what);
            }
            Progress::Lines(l) => {
                *l.phase.lock().unwrap_or_else(|p| p.into_inner()) = (name.to_string(), steps);
                let of = if steps > 0 {
                    format!(" (0/{steps})")
                } else {
                    String::new()
                };
                l.line(&format!("{name}{of}"));
            }
        }
    }
    fn phase_step(&self, done: usize) {
        match self {
            Progress::Bar(bar) => {
                let bar = bar.lock().unwrap_or_else(|p| p.into_inner());
                bar.set_position(done as u64);
                if bar.length() == Some(done as u64) {
                    bar.finish_and_clear();
                }
            }
            Progress::Lines(l) => {
                let (name, steps) = l.phase.lock().unwrap_or_else(|p| p.into_inner()).clone();
                if l.due(done >= steps) {
                    l.line(&format!("{name} {done}/{steps}"));
                }
            }
        }
    }
}

impl FitObserver for Progress {
    /// A page's reading errors are said before the search, not found in its residuals.
    fn read(&self, ds: &Dataset) {
        for ex in &ds.experiments {
            crate::cli::print_page_warnings(ds, ex);
        }
    }
    fn pinning(&self, limit_pct: f64, rows: &[Pinning]) {
        for line in pinning_lines(limit_pct, rows) {
            say!("{line}");
        }
    }
    fn displacement(&self, estimate: &DisplacementEstimate) {
        say!("{}", displacement_start_line(estimate));
    }
}

impl Progress {
    /// Takes a bar still drawn off the terminal before the summary is printed.
    fn clear(&self) {
        if let Progress::Bar(bar) = self {
            bar.lock()
                .unwrap_or_else(|p| p.into_inner())
                .finish_and_clear();
        }
    }
}

/// A bar of `len` steps labelled by `what` (an indicatif template fragment).
fn new_bar(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    if let Ok(style) =
        ProgressStyle::with_template(&format!("{{elapsed_precise}} [{{bar:30}}] {what}  {{msg}}"))
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// The progress of a fit for where stderr goes.
fn progress() -> Progress {
    if std::io::stderr().is_terminal() {
        Progress::Bar(Mutex::new(new_bar(0, "{pos}/{len} starts")))
    } else {
        Progress::Lines(Lines {
            t0: Instant::now(),
            last: Mutex::new(Instant::now()),
            total: AtomicUsize::new(0),
            done: AtomicUsize::new(0),
            phase: Mutex::new((String::new(), 0)),
        })
    }
}

/// Runs `vanefit fit`: fit, fit file, summary, plots.
pub(crate) fn run(args: &FitArgs) -> Result<(), Failure> {
    // Before the search: an unwritable or busy output fails now, not after the starts.
    let _lock = vanefit::io::prepare_file(&args.out).map_err(|e| Failure(format!("--out {e}")))?;
    let settings = args.options()?.check().map_err(Failure::option)?;
    let progress = progress();
    let done = fit_to(
        &args.dataset,
        &settings,
        &args.out,
        !args.no_plots,
        &progress,
    );
    progress.clear();
    let (fitted, written) = done.map_err(Failure::fit)?;
    let summary =
        report::terminal_summary(&fitted.dataset, &fitted.setup, &fitted.outcome, &args.out);
    for line in summary {
        match line {
            SummaryLine::Say(text) => say!("{text}"),
            SummaryLine::Warn(text) => eprintln!("warning: {text}"),
        }
    }
    for w in &fitted.figure_warnings {
        say!("{w}");
    }
    if let Some(line) = fitted.displacement_line() {
        say!("{line}: not printed on the page, fitted with the other parameters (every size-scaled default and prior follows it)");
    }
    if !written.plots.is_empty() {
        say!(
            "plots: {}",
            written
                .plots
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    say!("report: {}", written.report.display());
    Ok(())
}
