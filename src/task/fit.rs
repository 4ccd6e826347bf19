//! `fit` as a task: the options of `vanefit fit`, the fit itself (`fit_run`) and the files a
//! fit leaves (fit file, plots, report), called by the command line for one dataset and by
//! `batch` for a fleet, so both give the same fit for a seed.

use crate::data::dataset::{DataError, Dataset, Kind};
use crate::data::fitfile::FitFile;
use crate::estimate::engine::Engine;
use crate::estimate::error::EstimateError;
use crate::estimate::fit::{
    fit, fit_file, most_sensitive_experiment, FitData, FitOutcome, FitSetup, UncertaintyMethod,
};
use crate::estimate::multistart::RunObserver;
use crate::estimate::settings::MultiStartConfig;
use crate::estimate::space::{Dimension, ParamSpace, SpaceError, DEFAULT_ESTIMATED};
use crate::io::say;
use crate::model::effects::EffectSet;
use crate::model::motor::Motor;
use crate::model::params::spec;
use crate::objective::cost::{CostError, CostOptions};
use crate::report::fit as report;
use crate::report::plot::PlotError;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};

/// Why `vanefit fit` failed (the messages users and tests see).
#[derive(Debug, thiserror::Error)]
pub enum FitCommandError {
    /// `--starts 0`.
    #[error("--starts must be at least 1")]
    NoStarts,
    /// `--threads 0`.
    #[error("--threads must be at least 1")]
    NoThreads,
    /// An item of `--bounds` or `--start-range` is not `name=lo:hi`.
    #[error("{option}: '{item}' is not name=lo:hi")]
    Range {
        /// The option.
        option: &'static str,
        /// The bad item.
        item: String,
    },
    /// `--bounds` names a parameter that is not estimated.
    #[error("--bounds: '{0}' is not estimated")]
    NotEstimated(String),
    /// A catalogue pins none of the parameters.
    #[error("the catalogue pins none of {0} to within {1:.0} % (1σ): add curves, key figures or a rig experiment, or name parameters with --estimate")]
    NothingPinned(String, f64),
    /// `--start-spread` must exceed 1.
    #[error("--start-spread {0}: must be a number > 1")]
    StartSpread(f64),
    /// `--effects` names an unknown effect.
    #[error("--effects: {0}")]
    Effects(crate::model::effects::UnknownEffect),
    /// A dimension of the search space is bad.
    #[error("--estimate/--bounds/--start-range: {0}")]
    Dimension(SpaceError),
    /// The search space is bad.
    #[error("{0}")]
    Space(#[from] SpaceError),
    /// The dataset could not be read.
    #[error("{0}")]
    Data(#[from] DataError),
    /// The dataset's cost could not be set up.
    #[error("{0}")]
    Cost(#[from] CostError),
    /// The estimation failed.
    #[error("{0}")]
    Estimate(#[from] EstimateError),
    /// The fit file could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The fit file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// A plot could not be drawn.
    #[error("{0}")]
    Plot(#[from] PlotError),
    /// The output cannot be written or is in use by another run (checked before the fit).
    #[error("--out {0}")]
    Output(#[from] crate::io::out::OutputError),
}

/// Options of `vanefit fit`.
#[derive(Args, Debug, Clone)]
pub struct FitArgs {
    /// Dataset folder (rig.toml and recordings).
    pub dataset: PathBuf,
    /// Number of start points (Latin hypercube).
    #[arg(long, default_value_t = 32, value_parser = crate::task::at_least_one)]
    pub starts: usize,
    /// Seed of the start design; a seed gives the same result whatever the thread count.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: one per core).
    #[arg(long, value_parser = crate::task::at_least_one)]
    pub threads: Option<usize>,
    /// Effects to switch on (comma-separated ids of SPEC §5); their parameters are estimated too.
    #[arg(long, default_value = "", value_parser = crate::task::effects_arg)]
    pub effects: String,
    /// Parameters to estimate (comma-separated; default: six conductances, t_coulomb, visc).
    #[arg(long)]
    pub estimate: Option<String>,
    /// Search bounds, e.g. `c_in1=1e-9:2e-8,visc=1e-6:1e-3` (SI).
    #[arg(long)]
    pub bounds: Option<String>,
    /// Where start points are drawn, e.g. `c_12=1e-10:1e-9` (SI); default: a factor
    /// `--start-spread` either side of the default (AR034-11 values scaled with the rig's
    /// displacement for conductances), within the bounds.
    #[arg(long)]
    pub start_range: Option<String>,
    /// Default start range: this factor either side of the default value.
    #[arg(long, default_value_t = 3.0)]
    pub start_spread: f64,
    /// Iteration budget of each start.
    #[arg(long, default_value_t = 3000)]
    pub max_iters: u64,
    /// How to compute 95% intervals.
    #[arg(long, value_enum, default_value_t = Uncertainty::Profile)]
    pub uncertainty: Uncertainty,
    /// Continue an interrupted run from its results file (`<out>.starts.jsonl`).
    #[arg(long)]
    pub resume: bool,
    /// Keep every start's cost trace in the results file.
    #[arg(long)]
    pub trace: bool,
    /// Skip the plots.
    #[arg(long)]
    pub no_plots: bool,
    /// Fit file to write (vanefit.fit/1); results and plots go next to it.
    #[arg(long)]
    pub out: PathBuf,
}

/// `--uncertainty`: how 95% intervals are computed.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Uncertainty {
    /// Profile likelihood.
    Profile,
    /// Curvature of χ² only.
    Curvature,
    /// No intervals.
    None,
}

/// Parses `name=lo:hi,...` (the value of `option`) into dimensions.
pub fn parse_bounds(
    text: &str,
    option: &'static str,
) -> Result<Vec<(String, f64, f64)>, FitCommandError> {
    text.split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|item| {
            let bad = || FitCommandError::Range {
                option,
                item: item.to_string(),
            };
            let (name, range) = item.split_once('=').ok_or_else(bad)?;
            let (lo, hi) = range.split_once(':').ok_or_else(bad)?;
            let lo: f64 = lo.trim().parse().map_err(|_| bad())?;
            let hi: f64 = hi.trim().parse().map_err(|_| bad())?;
            Ok((name.trim().to_string(), lo, hi))
        })
        .collect()
}

/// The search space of a fit from the options: estimated names (default set plus every
/// parameter of the effects switched on), bounds overrides.
pub fn space_from_args(ds: &Dataset, args: &FitArgs) -> Result<ParamSpace, FitCommandError> {
    let effects = EffectSet::parse_list(&args.effects).map_err(FitCommandError::Effects)?;
    let fixed = ds.nominal_params()?;
    let mut names: Vec<String> = match &args.estimate {
        Some(list) => list
            .split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect(),
        None => DEFAULT_ESTIMATED.iter().map(|s| s.to_string()).collect(),
    };
    for e in effects.iter() {
        for p in e.parameters() {
            if !names.iter().any(|n| n == p) {
                names.push(p.to_string());
            }
        }
    }
    let overrides = parse_bounds(args.bounds.as_deref().unwrap_or(""), "--bounds")?;
    if let Some((n, _, _)) = overrides.iter().find(|(n, _, _)| !names.contains(n)) {
        return Err(FitCommandError::NotEstimated(n.clone()));
    }
    let starts = parse_bounds(args.start_range.as_deref().unwrap_or(""), "--start-range")?;
    if !(args.start_spread.is_finite() && args.start_spread > 1.0) {
        return Err(FitCommandError::StartSpread(args.start_spread));
    }
    let dims = names
        .iter()
        .map(|n| {
            let d = match overrides.iter().find(|(m, _, _)| m == n) {
                Some((_, lo, hi)) => Dimension::with_bounds(n, *lo, *hi)?,
                None => Dimension::for_param(n)?,
            };
            match starts.iter().find(|(m, _, _)| m == n) {
                Some((_, lo, hi)) => d.with_start_range(*lo, *hi),
                None => {
                    // The rig's nominal value: defaults scaled with the displacement.
                    let centre = fixed
                        .get(n)
                        .unwrap_or_else(|| spec(n).map_or(0.0, |s| s.default));
                    if d.log_scale && centre > 0.0 {
                        d.clone()
                            .with_start_range(
                                centre / args.start_spread,
                                centre * args.start_spread,
                            )
                            .or(Ok(d))
                    } else {
                        Ok(d)
                    }
                }
            }
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(FitCommandError::Dimension)?;
    Ok(ParamSpace::from_dims(dims, fixed, effects)?)
}

/// Where the run's side files go: `<out without .json>.<suffix>`.
pub fn side_path(out: &Path, suffix: &str) -> PathBuf {
    let stem = out.with_extension("");
    PathBuf::from(format!("{}.{suffix}", stem.display()))
}

/// For a dataset of catalogue pages only and no `--estimate`: the parameters the catalogue
/// pins down (`estimate::subset`), printed with what would pin the rest; otherwise `args`
/// as they are.
fn catalogue_estimates(
    ds: &Dataset,
    data: &FitData,
    args: &FitArgs,
) -> Result<FitArgs, FitCommandError> {
    let catalogue_only = ds.experiments.iter().all(|e| e.kind == Kind::Catalogue);
    if args.estimate.is_some() || !catalogue_only {
        return Ok(args.clone());
    }
    let motor = Motor::new(ds.nominal_params()?, EffectSet::empty());
    let names: Vec<String> = DEFAULT_ESTIMATED.iter().map(|s| s.to_string()).collect();
    let limit = 100.0 * crate::estimate::subset::PINNED_RELATIVE_SD;
    let Some(pinning) = crate::estimate::subset::pinned_subset(data, &motor, &names) else {
        return Err(FitCommandError::NothingPinned(names.join(", "), limit));
    };
    say!("catalogue only: what it pins down at the nominal motor (relative 1σ; pinned: ≤ {limit:.0} %)");
    for p in &pinning {
        let sd = if p.relative_sd.is_finite() {
            format!("{:.1} %", 100.0 * p.relative_sd)
        } else {
            "unseen".to_string()
        };
        let verdict = if p.pinned {
            "estimated".to_string()
        } else {
            let value = motor.params.get(&p.name).unwrap_or(f64::NAN);
            let hint = match most_sensitive_experiment(&motor, &p.name) {
                Some(k) => format!("; the {} experiment would pin it", k.id()),
                None => String::new(),
            };
            format!("fixed at {value:.4e} (default scaled to the displacement){hint}")
        };
        say!("  {:<10} {:>9}  {verdict}", p.name, sd);
    }
    let chosen: Vec<&str> = pinning
        .iter()
        .filter(|p| p.pinned)
        .map(|p| p.name.as_str())
        .collect();
    if chosen.is_empty() {
        return Err(FitCommandError::NothingPinned(names.join(", "), limit));
    }
    Ok(FitArgs {
        estimate: Some(chosen.join(",")),
        ..args.clone()
    })
}

/// A finished fit as `vanefit fit` makes it: the dataset, its fit data, what was estimated,
/// the outcome and the fit file (not yet written).
pub struct FitRun {
    /// The dataset fitted.
    pub dataset: Dataset,
    /// Its cost and likelihood.
    pub data: FitData,
    /// What was estimated and how.
    pub setup: FitSetup,
    /// The estimate, its intervals and every start.
    pub outcome: FitOutcome,
    /// The fit file of the outcome.
    pub file: FitFile,
}

/// Loads the dataset and fits it as `vanefit fit` does (the catalogue's subset, the search
/// space, the multi-start, the intervals), reporting starts to `observer` and recording them
/// in `results_file` (`None`: kept in memory only). The command line and the Python package
/// both fit through here, so a seed gives the same fit in both.
pub fn fit_run(
    args: &FitArgs,
    results_file: Option<PathBuf>,
    observer: &dyn RunObserver,
) -> Result<FitRun, FitCommandError> {
    if args.threads == Some(0) {
        return Err(FitCommandError::NoThreads);
    }
    // The one thread pool of the run.
    let engine = Engine::with_threads(args.threads)?;
    fit_run_on(&engine, args, results_file, observer)
}

/// [`fit_run`] on a thread pool the caller owns (`args.threads` is not looked at): a batch
/// builds one pool and fits every unit on it.
pub fn fit_run_on(
    engine: &Engine,
    args: &FitArgs,
    results_file: Option<PathBuf>,
    observer: &dyn RunObserver,
) -> Result<FitRun, FitCommandError> {
    if args.starts == 0 {
        return Err(FitCommandError::NoStarts);
    }
    let ds = Dataset::load(&args.dataset)?;
    let data = FitData::new(&ds, CostOptions::default())?;
    let args = &catalogue_estimates(&ds, &data, args)?;
    let space = space_from_args(&ds, args)?;
    let setup = FitSetup {
        space,
        multistart: MultiStartConfig {
            starts: args.starts,
            seed: args.seed,
            max_iters: args.max_iters,
            keep_traces: args.trace,
            ..MultiStartConfig::default()
        },
        uncertainty: match args.uncertainty {
            Uncertainty::Profile => UncertaintyMethod::Profile,
            Uncertainty::Curvature => UncertaintyMethod::Curvature,
            Uncertainty::None => UncertaintyMethod::None,
        },
        results_file,
        resume: args.resume,
    };
    let outcome = fit(engine, &data, &setup, observer)?;
    let file = fit_file(&ds.name, &setup, &outcome, args.seed);
    Ok(FitRun {
        dataset: ds,
        data,
        setup,
        outcome,
        file,
    })
}

/// The files a fit left next to its fit file.
#[derive(Debug, Clone, Default)]
pub struct FitWritten {
    /// The SVG plots (waterfall, parameters across starts, profiles, one overlay per
    /// experiment); empty with `--no-plots`.
    pub plots: Vec<PathBuf>,
    /// The report for people (`<out>.report.md`).
    pub report: PathBuf,
}

/// Writes what `vanefit fit` leaves of a finished fit: the fit file at `out`, the plots
/// (unless `plots` is false) and the report next to it. Split from the fit so that a batch
/// unit writes exactly what the command writes.
pub fn write_fit(
    run: &FitRun,
    out: &Path,
    seed: u64,
    plots: bool,
) -> Result<FitWritten, FitCommandError> {
    let write_error = |path: &Path| {
        let path = path.to_path_buf();
        move |source| FitCommandError::Write { path, source }
    };
    run.file.write(out).map_err(write_error(out))?;
    let mut written = FitWritten::default();
    if plots {
        let best = Motor::new(run.outcome.params.clone(), run.setup.space.effects.clone());
        let waterfall = side_path(out, "waterfall.svg");
        report::waterfall(&run.outcome.run.results, &waterfall)?;
        written.plots.push(waterfall);
        let across = side_path(out, "parameters.svg");
        report::parameters_across_starts(
            &run.outcome.run.results,
            &run.setup.space,
            &run.outcome.params,
            &across,
        )?;
        written.plots.push(across);
        written.plots.extend(report::profiles(
            &run.outcome.intervals,
            run.outcome.threshold,
            &side_path(out, "profiles.svg"),
        )?);
        written.plots.extend(report::overlays(
            &run.dataset,
            &run.data.cost,
            &[("fit", &best)],
            &out.with_extension(""),
        )?);
    }
    let md = side_path(out, "report.md");
    let text = report::markdown(&run.dataset, &run.setup, &run.outcome, seed, &written.plots);
    crate::io::write_atomic(&md, text.as_bytes()).map_err(write_error(&md))?;
    written.report = md;
    Ok(written)
}
