//! `fit` as a task: [`FitOptions`] → [`FitOptions::check`] → [`FitSettings`], the fit itself
//! ([`fit`], `fit_dataset`) giving a [`Fit`], and the files a fit leaves ([`FitPaths`],
//! [`write_fit`]: fit file, plots, report); [`fit_to`] does all of it for the command line,
//! `batch` the same steps for a fleet, so both give the same fit for a seed.

use super::{Opt, OptionError};
use crate::data::dataset::{DataError, Dataset, Kind, FIGURES};
use crate::data::fitfile::FitFile;
use crate::estimate::engine::Engine;
use crate::estimate::error::EstimateError;
use crate::estimate::fit::displacement::{describe_fitted, DisplacementEstimate};
use crate::estimate::fit::setup::{
    catalogue_only, displacement_unprinted, page_displacement, page_estimates, search_space,
    PageChoice, SetupError, SpaceRequest,
};
pub use crate::estimate::fit::setup::{ParamRange, Pinning, RangeSyntax};
use crate::estimate::fit::{
    fit as estimate_fit, fit_file, FitData, FitOutcome, FitSetup, UncertaintyMethod,
};
use crate::estimate::optimize::multistart::RunObserver;
use crate::estimate::optimize::settings::MultiStartConfig;
use crate::estimate::problem::space::SpaceError;
use crate::io::side_path;
use crate::model::effects::EffectSet;
use crate::model::params::ParamId;
use crate::objective::cost::{CostError, CostOptions};
use crate::predict::{PredictOptions, ROW_FIGURES};
use crate::report::fit as report;
use crate::report::plot::PlotError;
use crate::units::Unit;
use std::path::{Path, PathBuf};

/// Options of a fit as given (unchecked); [`FitOptions::check`] makes them [`FitSettings`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Number of start points (Latin hypercube), ≥ 1.
    pub starts: usize,
    /// Seed of the start design; a seed gives the same result whatever the thread count.
    pub seed: u64,
    /// Worker threads (`None`: one per core), ≥ 1.
    pub threads: Option<usize>,
    /// Effects switched on; their parameters are estimated too.
    pub effects: EffectSet,
    /// Parameters to estimate (`None`: six conductances, t_coulomb, visc; for a dataset of
    /// catalogue pages only, those of them the catalogue pins down).
    pub estimate: Option<Vec<String>>,
    /// Search bounds overriding the parameters' own, SI.
    pub bounds: Vec<ParamRange>,
    /// Where start points are drawn, SI; default: a factor `start_spread` either side of
    /// the rig's nominal value, within the bounds.
    pub start_ranges: Vec<ParamRange>,
    /// Default start range: this factor (> 1) either side of the nominal value.
    pub start_spread: f64,
    /// Iteration budget of each start.
    pub max_iters: u64,
    /// Hand each start still running after its first round of Nelder–Mead over to
    /// Levenberg–Marquardt on the cost's residuals (docs/performance.md, "The hand-over to Levenberg–Marquardt").
    /// `false` runs Nelder–Mead alone, round after round.
    pub handoff: bool,
    /// How 95 % intervals are computed.
    pub uncertainty: UncertaintyMethod,
    /// Continue an interrupted run from its results file.
    pub resume: bool,
    /// Keep every start's cost trace in the results file.
    pub trace: bool,
    /// Fit with the motor prior (docs/estimation.md, "Priors": each parameter log-normal
    /// around its default scaled to the displacement): the estimate is the posterior's mode,
    /// and what the data cannot pin rests on the prior. `false`: the likelihood alone.
    pub priors: bool,
}

impl Default for FitOptions {
    /// The command line's defaults: 32 starts, seed 1, profile intervals.
    fn default() -> Self {
        Self {
            starts: 32,
            seed: 1,
            threads: None,
            effects: EffectSet::empty(),
            estimate: None,
            bounds: Vec::new(),
            start_ranges: Vec::new(),
            start_spread: 3.0,
            max_iters: 3000,
            handoff: true,
            uncertainty: UncertaintyMethod::Profile,
            resume: false,
            trace: false,
            priors: true,
        }
    }
}

impl FitOptions {
    /// Checks the values that need no dataset: `starts` and `threads` ≥ 1, `start_spread`
    /// > 1. Parameter names and ranges are checked against the dataset by the fit.
    pub fn check(&self) -> Result<FitSettings, OptionError> {
        if self.starts == 0 {
            return Err(OptionError::of(Opt::FitStarts, " must be at least 1"));
        }
        if self.threads == Some(0) {
            return Err(OptionError::of(Opt::FitThreads, " must be at least 1"));
        }
        if !(self.start_spread.is_finite() && self.start_spread > 1.0) {
            return Err(OptionError::of(
                Opt::FitStartSpread,
                format!(" {}: must be a number > 1", self.start_spread),
            ));
        }
        Ok(FitSettings(self.clone()))
    }
}

/// Checked [`FitOptions`]: private fields, read through the getters.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSettings(FitOptions);

impl FitSettings {
    /// The options these settings were checked from.
    pub fn options(&self) -> &FitOptions {
        &self.0
    }
    /// Number of starts (≥ 1).
    pub fn starts(&self) -> usize {
        self.0.starts
    }
    /// Seed of the start design.
    pub fn seed(&self) -> u64 {
        self.0.seed
    }
    /// Worker threads (`None`: one per core).
    pub fn threads(&self) -> Option<usize> {
        self.0.threads
    }
    /// How 95 % intervals are computed.
    pub fn uncertainty(&self) -> UncertaintyMethod {
        self.0.uncertainty
    }
}

/// Why a fit failed (the messages users and tests see).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FitError {
    /// An option is bad (named by its field).
    #[error(transparent)]
    Option(#[from] OptionError),
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
    /// The fit file or the report could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// A plot could not be drawn.
    #[error("{0}")]
    Plot(#[from] PlotError),
}

/// A failed set-up of the search, with the option it concerns named.
fn setup_error(e: SetupError) -> FitError {
    let option = match e {
        SetupError::NotEstimated { name } => {
            OptionError::of(Opt::FitBounds, format!(": '{name}' is not estimated"))
        }
        SetupError::Dimension(e) => OptionError::of(Opt::FitRanges, format!(": {e}")),
        SetupError::NothingPinned { names, limit_pct } => {
            let before = format!(
                "the catalogue pins none of {} to within {limit_pct:.0} % (1σ): add curves, key figures or a rig experiment, or name parameters with ",
                names.join(", ")
            );
            OptionError::of_within(Opt::FitEstimate, before, "")
        }
        SetupError::Space(e) => return FitError::Space(e),
    };
    FitError::Option(option)
}

/// For a dataset of catalogue pages only and no `estimate`: what the pages let the fit
/// estimate (`estimate::fit::setup::page_estimates`), its pinning reported to `observer`
/// with what would pin the rest; `None` otherwise (the options say what is estimated).
fn page_choice(
    ds: &Dataset,
    data: &FitData,
    o: &FitOptions,
    observer: &dyn FitObserver,
    displacement: Option<&DisplacementEstimate>,
) -> Result<Option<PageChoice>, FitError> {
    if let Some(e) = displacement {
        observer.displacement(e);
    }
    if o.estimate.is_some() || !catalogue_only(ds) {
        return Ok(None);
    }
    let nominal = ds.nominal_params()?;
    let choice = page_estimates(data, nominal, o.priors, displacement.is_some())
        .map_err(|e| page_setup_error(ds, e))?;
    observer.pinning(choice.limit_pct, &choice.pinning);
    match choice.nothing_pinned() {
        Some(e) => Err(page_setup_error(ds, e)),
        None => Ok(Some(choice)),
    }
}

/// [`setup_error`] for pages: one that pins nothing says which of the key figures the
/// pages do not print could be added ([`unprinted_figures`]).
fn page_setup_error(ds: &Dataset, e: SetupError) -> FitError {
    let SetupError::NothingPinned { names, limit_pct } = e else {
        return setup_error(e);
    };
    let add = unprinted_figures(ds)
        .iter()
        .map(|(key, words)| format!("the {words} ({key})"))
        .collect::<Vec<_>>();
    let figures = match add.as_slice() {
        [] => String::new(),
        [one] => format!("{one}, "),
        [first @ .., last] => format!("{} or {last}, ", first.join(", ")),
    };
    let before = format!(
        "the catalogue pins none of {} to within {limit_pct:.0} % (1σ), so the fit would be the motor prior alone: add {figures}curves, or a rig experiment, or name parameters with ",
        names.join(", ")
    );
    FitError::Option(OptionError::of_within(Opt::FitEstimate, before, ""))
}

/// The key figures (rig.toml key, words) that no catalogue page of `ds` prints, in
/// [`FIGURES`] order, without the minimum start torque (never compared).
pub fn unprinted_figures(ds: &Dataset) -> Vec<(&'static str, &'static str)> {
    FIGURES
        .iter()
        .filter(|(key, _, _)| *key != "min_start_torque")
        .filter(|(key, _, _)| {
            !ds.experiments
                .iter()
                .any(|e| e.figures.iter().any(|f| f.key == *key))
        })
        .map(|(key, _, words)| (*key, *words))
        .collect()
}

/// The experiment that would pin each open parameter, said once: a page fit prints its
/// pinning (`most_sensitive_experiment` at the nominal motor) before it fits, and the fit's
/// report repeats that answer rather than a second one at the fitted motor, where the
/// ranking of two nearly equal experiments can flip. Parameters the pinning does not name
/// keep the fit's answer.
fn one_would_pin(would_pin: &mut [(ParamId, Kind)], pinning: &[Pinning]) {
    for p in pinning {
        let (Some(id), Some(kind)) = (ParamId::from_name(&p.name), p.pinned_by) else {
            continue;
        };
        if let Some(entry) = would_pin.iter_mut().find(|(i, _)| *i == id) {
            entry.1 = kind;
        }
    }
}

/// The pinning as the command line prints it: a heading, then one line per parameter
/// (relative 1σ, and estimated or the value it stays fixed at and what would pin it).
pub fn pinning_lines(limit_pct: f64, rows: &[Pinning]) -> Vec<String> {
    let mut lines = vec![format!(
        "catalogue only: what it pins down at the nominal motor (relative 1σ; pinned: ≤ {limit_pct:.0} %)"
    )];
    for p in rows {
        // Beyond ×/÷ e^10 the pages do not see the parameter at all: a finite σ that large is
        // the rounding of a zero sensitivity, not a width.
        let sd = if p.relative_sd.is_finite() && p.relative_sd < UNSEEN_RELATIVE_SD {
            format!("{:.1} %", 100.0 * p.relative_sd)
        } else {
            "unseen".to_string()
        };
        let verdict = if p.pinned {
            "estimated".to_string()
        } else {
            let hint = match p.pinned_by {
                Some(k) => format!("; the {} experiment would pin it", k.id()),
                None => String::new(),
            };
            match p.prior_factor {
                Some(f) => format!(
                    "rests on its prior: {:.4e} ×/÷ {f:.1} (default scaled to the displacement){hint}",
                    p.value
                ),
                None => format!(
                    "fixed at {:.4e} (default scaled to the displacement){hint}",
                    p.value
                ),
            }
        };
        lines.push(format!("  {:<10} {:>9}  {verdict}", p.name, sd));
    }
    lines
}

/// Where `fit` starts the displacement of a page that does not print it: the similarity
/// estimate's value only, so that the fit's output states one displacement estimate, the
/// fit's own ([`Fit::displacement_line`]).
pub fn displacement_start_line(estimate: &DisplacementEstimate) -> String {
    let v = estimate.v_disp_m3 * 1e6;
    format!(
        "the page does not print the displacement: the fit estimates it with the other parameters, its search centred on {v:.3} cm³ by similarity with AR034-11 (torque per supply pressure, air per revolution)"
    )
}

/// The similarity estimate of a page's displacement as `check` prints it.
pub fn displacement_first_line(estimate: &DisplacementEstimate) -> String {
    format!(
        "{}, by similarity with AR034-11 (torque per supply pressure, air per revolution): the page does not print it, so the fit estimates it with the other parameters",
        estimate.describe()
    )
}

/// For `vanefit check`: the displacement of a dataset of catalogue pages only whose
/// `[motor]` gives neither a displacement nor a geometry, estimated from the pages
/// (`None` otherwise, or where no displacement gives a motor the pages can be simulated at).
pub fn page_displacement_of(ds: &Dataset) -> Result<Option<DisplacementEstimate>, FitError> {
    if !displacement_unprinted(ds) {
        return Ok(None);
    }
    let data = FitData::new(ds, CostOptions::default())?;
    Ok(page_displacement(ds, &data))
}

/// What a fit reports while it runs: the multi-start's events ([`RunObserver`], which
/// can also stop the run) and, for a dataset of catalogue pages only, what the catalogue
/// pins down before the starts begin. Every method has a default that does nothing.
pub trait FitObserver: RunObserver {
    /// The dataset is read, before anything is fitted ([`fit_to`]).
    fn read(&self, ds: &Dataset) {
        let _ = ds;
    }

    /// The catalogue's pinning at the nominal motor (`limit_pct`: the relative 1σ, %, below
    /// which a parameter counts as pinned and is estimated).
    fn pinning(&self, limit_pct: f64, rows: &[Pinning]) {
        let _ = (limit_pct, rows);
    }

    /// A page that does not print the displacement: its estimate from the page by
    /// similarity, before the fit estimates it with the other parameters.
    fn displacement(&self, estimate: &DisplacementEstimate) {
        let _ = estimate;
    }
}

impl FitObserver for crate::estimate::optimize::multistart::Silent {}

/// A finished fit: the dataset, its fit data, what was estimated, the outcome and the fit
/// file (not yet written).
pub struct Fit {
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
    /// The seed of the start design.
    pub seed: u64,
    /// For a dataset of catalogue pages only: what the catalogue pins down (empty
    /// otherwise).
    pub pinning: Vec<Pinning>,
    /// For pages that do not print the displacement: its first estimate from the pages
    /// (the fit then estimates `v_disp` with the rest; its interval is the fit file's).
    pub displacement: Option<DisplacementEstimate>,
    /// For catalogue pages: a warning per printed figure outside the fit's 95 % band at its
    /// page's pressure (`figures_outside_bands`).
    pub figure_warnings: Vec<String>,
}

impl Fit {
    /// For pages that do not print the displacement: the fit's estimate and 95 % interval
    /// in words ("displacement estimated from the page: 4.1 cm³ [3.8, 4.5] (95 %)"; the
    /// interval is the page estimate's where the fit gives none).
    pub fn displacement_line(&self) -> Option<String> {
        self.displacement.as_ref()?;
        Some(describe_fitted(&self.file))
    }
}

/// Loads the dataset at `dataset` and fits it on a thread pool of its own (the catalogue's
/// subset, the search space, the multi-start, the intervals), reporting starts to
/// `observer` and recording them in `results_file` (`None`: kept in memory only). The
/// command line and the Python package both fit through here, so a seed gives the same
/// fit in both. The observer can stop the run between rounds of starts
/// ([`RunObserver::keep_going`]); the starts finished by then stay in `results_file`, and a
/// run with `resume` continues from them.
pub fn fit<O: FitObserver>(
    dataset: &Path,
    settings: &FitSettings,
    results_file: Option<PathBuf>,
    observer: &O,
) -> Result<Fit, FitError> {
    // The one thread pool of the run.
    let engine = Engine::with_threads(settings.threads())?;
    let ds = Dataset::load(dataset)?;
    fit_dataset(&engine, ds, settings, results_file, observer)
}

/// `vanefit fit` below the command line, each step once and in turn: every file the fit
/// leaves is resolved from `out` ([`FitPaths::beside`]), the dataset is read and shown to
/// `observer` ([`FitObserver::read`]: the command line prints a page's reading warnings
/// before the search), fitted on a thread pool of its own with its starts recorded beside
/// `out` ([`fit`]), and the one result is written ([`write_fit_to`]: the fit file, the
/// plots unless `plots` is false, the report).
pub fn fit_to<O: FitObserver>(
    dataset: &Path,
    settings: &FitSettings,
    out: &Path,
    plots: bool,
    observer: &O,
) -> Result<(Fit, FitWritten), FitError> {
    let paths = FitPaths::beside(out);
    let ds = Dataset::load(dataset)?;
    observer.read(&ds);
    let engine = Engine::with_threads(settings.threads())?;
    let fitted = fit_dataset(&engine, ds, settings, Some(paths.starts.clone()), observer)?;
    let written = write_fit_to(&fitted, &paths, plots)?;
    Ok((fitted, written))
}

/// [`fit`] of a loaded dataset on a thread pool the caller owns (`threads` is not looked
/// at): a batch builds one pool and fits every unit on it.
pub(crate) fn fit_dataset<O: FitObserver>(
    engine: &Engine,
    ds: Dataset,
    settings: &FitSettings,
    results_file: Option<PathBuf>,
    observer: &O,
) -> Result<Fit, FitError> {
    let data = FitData::new(&ds, CostOptions::default())?;
    let mut ds = ds;
    let displacement = page_displacement(&ds, &data);
    if let Some(e) = &displacement {
        // Every default and prior is scaled to the page's size, as if it had printed it.
        ds.motor.displacement_m3 = Some(e.v_disp_m3);
    }
    let o = settings.options();
    let choice = page_choice(&ds, &data, o, observer, displacement.as_ref())?;
    let request = SpaceRequest {
        estimate: match &choice {
            Some(c) => Some(c.names.as_slice()),
            None => o.estimate.as_deref(),
        },
        effects: &o.effects,
        bounds: &o.bounds,
        start_ranges: &o.start_ranges,
        start_spread: o.start_spread,
        priors: o.priors,
    };
    let space =
        search_space(ds.nominal_params()?, &request, displacement.as_ref()).map_err(setup_error)?;
    let setup = FitSetup {
        space,
        multistart: MultiStartConfig {
            starts: o.starts,
            seed: o.seed,
            max_iters: o.max_iters,
            keep_traces: o.trace,
            handoff_after_rounds: if o.handoff {
                MultiStartConfig::default().handoff_after_rounds
            } else {
                0
            },
            ..MultiStartConfig::default()
        },
        uncertainty: o.uncertainty,
        results_file,
        resume: o.resume,
    };
    let mut outcome = estimate_fit(engine, &data, &setup, observer)?;
    if let Some(c) = &choice {
        one_would_pin(&mut outcome.would_pin, &c.pinning);
    }
    let mut file = fit_file(&ds.name, &setup, &outcome, o.seed);
    // The parameters are the motor shaft's; the gearbox says how the pages' shaft relates.
    file.gear = ds.gear();
    let figure_warnings = if catalogue_only(&ds) {
        figures_outside_bands(&ds, &file)
    } else {
        Vec::new()
    };
    Ok(Fit {
        dataset: ds,
        data,
        setup,
        outcome,
        file,
        seed: o.seed,
        pinning: choice.map(|c| c.pinning).unwrap_or_default(),
        displacement,
        figure_warnings,
    })
}

/// For a dataset of catalogue pages: a warning for each printed key figure that lies
/// outside the fit's own 95 % band (`predict`'s delta-method band from the fit file) at
/// its page's supply pressure, naming it: the fit does not reproduce what the page prints.
/// A page whose figures cannot be predicted from the fit gets one warning that says so.
pub fn figures_outside_bands(ds: &Dataset, file: &FitFile) -> Vec<String> {
    let mut out = Vec::new();
    for ex in &ds.experiments {
        let (Some(p), false) = (ex.p_supply_pa, ex.figures.is_empty()) else {
            continue;
        };
        let mut options = PredictOptions::new(ds.p_atm_pa);
        options.pressures_pa = vec![p];
        options.reference_pa = p;
        let bar_g = Unit::BarG.from_si(p, ds.p_atm_pa);
        let prediction = match crate::predict::predict(file, &options) {
            Ok(pr) => pr,
            Err(e) => {
                out.push(format!(
                    "WARNING: the page at {bar_g:.3} bar g ({}): its figures could not be checked against the fit's bands: {e}",
                    ex.file
                ));
                continue;
            }
        };
        let at = &prediction.pressures[0].figures;
        for f in &ex.figures {
            let Some(k) = ROW_FIGURES.iter().position(|r| *r == f.key) else {
                continue;
            };
            let Some([lo, hi]) = at[k].band95 else {
                continue;
            };
            // The bands are the shaft's the page printed (a gearbox's output); the figures
            // were read onto the motor shaft.
            let printed_si = file
                .gear
                .as_ref()
                .map_or(f.si, |g| g.to_output_shaft(f.quantity, f.si));
            if (lo..=hi).contains(&printed_si) {
                continue;
            }
            let shown = |v: f64| crate::report::explain::number(f.unit.from_si(v, ds.p_atm_pa), 4);
            let unit = f.unit.symbol();
            out.push(format!(
                "WARNING: the printed {} ({} {unit}, page at {bar_g:.2} bar g) lies outside the fit's 95 % band [{}, {}] {unit} (fit: {} {unit}): the fit does not reproduce it",
                f.key,
                f.written,
                shown(lo),
                shown(hi),
                shown(at[k].value)
            ));
        }
    }
    out
}

/// Relative 1σ above which the pinning says a parameter is unseen (e^10 ≈ ×/÷ 22 000).
const UNSEEN_RELATIVE_SD: f64 = 10.0;

/// Points of a page's model curve in the fit's plot: as many as `predict`'s default curve
/// twice over, so that the curve is smooth between the page's points.
const PAGE_CURVE_POINTS: usize = 2 * crate::predict::DEFAULT_CURVE_POINTS - 1;

/// The fitted motor over each catalogue page's whole speed range (standstill to the free
/// speed) at the page's supply pressure, with the 95 % bands of `predict` (the fit file's
/// covariance): what the fit's plot draws over the page's points. A page without a stated
/// supply pressure, or one the prediction fails at, gets none (its plot then shows the fit
/// at the page's speeds).
fn page_curves(run: &Fit) -> Vec<report::PageCurve> {
    use crate::predict::{predict, PredictOptions};
    // The plot holds a geared page's points at the motor shaft (where the fit compares
    // them), so its model curve is the motor shaft's too, not the output's that `predict`
    // gives a geared fit.
    let motor_shaft = crate::data::fitfile::FitFile {
        gear: None,
        ..run.file.clone()
    };
    run.dataset
        .experiments
        .iter()
        .filter(|ex| ex.kind == Kind::Catalogue)
        .filter_map(|ex| {
            let mut options = PredictOptions::new(run.dataset.p_atm_pa);
            options.pressures_pa = vec![ex.p_supply_pa?];
            options.curve_points = PAGE_CURVE_POINTS;
            let at = predict(&motor_shaft, &options)
                .ok()?
                .pressures
                .into_iter()
                .next()?;
            Some(report::PageCurve {
                file: ex.file.clone(),
                points: at.curve,
            })
        })
        .collect()
}

/// The files a fit left next to its fit file.
#[derive(Debug, Clone, Default)]
pub struct FitWritten {
    /// The SVG plots (waterfall, parameters across starts, profiles, one overlay per
    /// experiment); empty without plots.
    pub plots: Vec<PathBuf>,
    /// The report for people (`<out>.report.md`).
    pub report: PathBuf,
}

/// Every file a fit leaves, resolved once from its fit file's path: the fit file, the
/// starts' record and the report beside it (`fit.json` → `fit.starts.jsonl`,
/// `fit.report.md`), and the plots.
#[derive(Debug, Clone, PartialEq)]
pub struct FitPaths {
    /// The fit file.
    pub fit: PathBuf,
    /// The record of every start (`--resume` continues from it).
    pub starts: PathBuf,
    /// The report for people.
    pub report: PathBuf,
    /// The plots.
    pub plots: report::PlotPaths,
}

impl FitPaths {
    /// The files of a fit whose fit file is `out`.
    pub fn beside(out: &Path) -> Self {
        Self {
            fit: out.to_path_buf(),
            starts: side_path(out, "starts.jsonl"),
            report: side_path(out, "report.md"),
            plots: report::PlotPaths {
                waterfall: side_path(out, "waterfall.svg"),
                parameters: side_path(out, "parameters.svg"),
                profiles: side_path(out, "profiles.svg"),
                overlay_prefix: out.with_extension(""),
            },
        }
    }
}

/// Writes what `vanefit fit` leaves of a finished fit: the fit file at `out`, the plots
/// (unless `plots` is false) and the report next to it ([`FitPaths::beside`]). Split from
/// the fit so that a batch unit writes exactly what the command writes.
pub fn write_fit(run: &Fit, out: &Path, plots: bool) -> Result<FitWritten, FitError> {
    write_fit_to(run, &FitPaths::beside(out), plots)
}

/// Writes the fit file `file` to `out` with the folder of the dataset it was fitted to
/// (`dataset_dir`) recorded relative to it (`dataset_path`), so that `predict` finds the
/// dataset (`data::locate`) wherever the checkout is moved: as `vanefit fit` and Python's
/// `fit(out=)` write it. Returns the file as written.
pub fn write_fit_file(file: &FitFile, dataset_dir: &Path, out: &Path) -> Result<FitFile, FitError> {
    let file = FitFile {
        dataset_path: crate::data::locate::relative_dataset_path(dataset_dir, out),
        ..file.clone()
    };
    file.write(out).map_err(|source| FitError::Write {
        path: out.to_path_buf(),
        source,
    })?;
    Ok(file)
}

/// [`write_fit`] to paths resolved before the fit.
pub fn write_fit_to(run: &Fit, paths: &FitPaths, plots: bool) -> Result<FitWritten, FitError> {
    let write_error = |path: &Path| {
        let path = path.to_path_buf();
        move |source| FitError::Write { path, source }
    };
    let out = &paths.fit;
    write_fit_file(&run.file, &run.dataset.dir, out)?;
    let mut written = FitWritten::default();
    if plots {
        // Predicted here, not by the report, which formats what it is given.
        let curves = page_curves(run);
        written.plots = report::plots(
            &run.dataset,
            &run.data.cost,
            &run.setup.space,
            &run.outcome,
            &curves,
            &paths.plots,
        )?;
    }
    let md = paths.report.clone();
    let text = report::markdown(
        &run.dataset,
        &run.setup,
        &run.outcome,
        run.seed,
        &written.plots,
    ) + &report::figure_warnings(&run.figure_warnings);
    crate::io::write_atomic(&md, text.as_bytes()).map_err(write_error(&md))?;
    written.report = md;
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pinning(name: &str, by: Option<Kind>) -> Pinning {
        Pinning {
            name: name.into(),
            relative_sd: 0.25,
            pinned: false,
            value: 0.5,
            pinned_by: by,
            prior_factor: Some(1.6),
        }
    }

    /// A page fit that printed "the outlet_throttle experiment would pin b_crit" before
    /// fitting says the same of b_crit after it, though the fitted motor ranks the pressure
    /// ramp first; a parameter the pinning says nothing of keeps the fit's answer, and one
    /// the fit pinned gets no hint.
    #[test]
    fn the_fit_repeats_the_pinnings_experiment() {
        let mut would_pin = vec![
            (ParamId::B_CRIT, Kind::PressureRamp),
            (ParamId::C_12, Kind::Datasheet),
        ];
        let said = [
            pinning("b_crit", Some(Kind::OutletThrottle)),
            pinning("c_12", None),
            pinning("visc", Some(Kind::OutletThrottle)),
        ];
        one_would_pin(&mut would_pin, &said);
        assert_eq!(
            would_pin,
            vec![
                (ParamId::B_CRIT, Kind::OutletThrottle),
                (ParamId::C_12, Kind::Datasheet),
            ]
        );
    }
}
