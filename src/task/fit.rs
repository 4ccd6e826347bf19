//! `fit` as a task: [`FitOptions`] → [`FitOptions::check`] → [`FitSettings`], the fit itself
//! ([`fit`], `fit_dataset`) giving a [`Fit`], and the files a fit leaves ([`write_fit`]:
//! fit file, plots, report), called by the command line for one dataset and by `batch` for
//! a fleet, so both give the same fit for a seed.

use super::{Opt, OptionError};
use crate::data::dataset::{DataError, Dataset, Kind};
use crate::data::fitfile::FitFile;
use crate::estimate::engine::Engine;
use crate::estimate::error::EstimateError;
use crate::estimate::fit::displacement::{
    describe_cm3, displacement_missing, from_page as displacement_from_page, DisplacementEstimate,
};
use crate::estimate::fit::{
    fit as estimate_fit, fit_file, most_sensitive_experiment, FitData, FitOutcome, FitSetup,
    UncertaintyMethod,
};
use crate::estimate::optimize::multistart::RunObserver;
use crate::estimate::optimize::settings::MultiStartConfig;
use crate::estimate::problem::prior::Prior;
use crate::estimate::problem::space::{Dimension, ParamSpace, SpaceError, DEFAULT_ESTIMATED};
use crate::io::side_path;
use crate::model::effects::EffectSet;
use crate::model::motor::Motor;
use crate::model::params::{estimated_names, page_prior_extra, ParamId};
use crate::objective::cost::{CostError, CostOptions};
use crate::report::fit as report;
use crate::report::plot::PlotError;
use std::path::{Path, PathBuf};

/// A search or start range of one parameter, SI.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamRange {
    /// The parameter.
    pub name: String,
    /// Lower end, SI.
    pub lo: f64,
    /// Upper end, SI.
    pub hi: f64,
}

/// An item of a range list that is not `name=lo:hi`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{0}' is not name=lo:hi")]
pub struct RangeSyntax(pub String);

impl ParamRange {
    /// Parses `name=lo:hi,...` (empty items skipped), e.g. `c_in1=1e-9:2e-8,visc=1e-6:1e-3`.
    pub fn parse_list(text: &str) -> Result<Vec<ParamRange>, RangeSyntax> {
        text.split(',')
            .filter(|s| !s.trim().is_empty())
            .map(|item| {
                let bad = || RangeSyntax(item.to_string());
                let (name, range) = item.split_once('=').ok_or_else(bad)?;
                let (lo, hi) = range.split_once(':').ok_or_else(bad)?;
                let lo: f64 = lo.trim().parse().map_err(|_| bad())?;
                let hi: f64 = hi.trim().parse().map_err(|_| bad())?;
                Ok(ParamRange {
                    name: name.trim().to_string(),
                    lo,
                    hi,
                })
            })
            .collect()
    }
}

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

/// The search space of a fit: estimated names (default set plus every parameter of the
/// effects switched on), bounds and start ranges, around the dataset's nominal motor.
fn search_space(
    ds: &Dataset,
    o: &FitOptions,
    displacement: Option<&DisplacementEstimate>,
) -> Result<ParamSpace, FitError> {
    let fixed = ds.nominal_params()?;
    let mut names: Vec<String> = match &o.estimate {
        Some(list) => list
            .iter()
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect(),
        None => estimated_names(&EffectSet::empty()),
    };
    for e in o.effects.iter() {
        for p in e.parameters() {
            if !names.iter().any(|n| n == p) {
                names.push(p.to_string());
            }
        }
    }
    if let Some(b) = o.bounds.iter().find(|b| !names.contains(&b.name)) {
        let after = format!(": '{}' is not estimated", b.name);
        return Err(OptionError::of(Opt::FitBounds, after).into());
    }
    let find = |list: &[ParamRange], n: &str| list.iter().find(|r| r.name == n).cloned();
    let dims = names
        .iter()
        .map(|n| {
            let id = ParamId::from_name(n);
            let d = match (find(&o.bounds, n), displacement) {
                (Some(r), _) => Dimension::with_bounds(n, r.lo, r.hi)?,
                (None, Some(e)) if id == Some(ParamId::V_DISP) => displacement_dimension(e)?,
                (None, _) if id == Some(ParamId::V_DEAD) && fixed.v_dead() > 0.0 => {
                    dead_volume_dimension(fixed.v_dead(), fixed.v_disp() / fixed.z())?
                }
                (None, _) => Dimension::for_param(n)?,
            };
            if id == Some(ParamId::V_DISP) && find(&o.start_ranges, n).is_none() {
                if let Some(e) = displacement {
                    return d.with_start_range(e.ci95_m3[0], e.ci95_m3[1]);
                }
            }
            match find(&o.start_ranges, n) {
                Some(r) => d.with_start_range(r.lo, r.hi),
                None => {
                    // The rig's nominal value: defaults scaled with the displacement.
                    let centre = fixed.get(n).unwrap_or(0.0);
                    if d.log_scale && centre > 0.0 {
                        d.clone()
                            .with_start_range(centre / o.start_spread, centre * o.start_spread)
                            .or(Ok(d))
                    } else {
                        Ok(d)
                    }
                }
            }
        })
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| OptionError::of(Opt::FitRanges, format!(": {e}")))?;
    let prior = if o.priors {
        Prior::for_motor(&fixed)
    } else {
        Prior::none()
    };
    let v_ref = fixed.v_disp();
    let space = ParamSpace::from_dims(dims, fixed, o.effects.clone())?.with_prior(prior);
    // A page without a displacement: what is fixed follows the estimated one (similarity).
    Ok(match displacement {
        Some(_) => space.with_size_following(v_ref),
        None => space,
    })
}

/// The search dimension of the dead volume (whose default search range starts at 0, no
/// logarithm): 1/10 to 10 times its nominal value `v0`, and below 0.9 of the filling volume
/// `v_fill` (it must stay below it).
fn dead_volume_dimension(v0: f64, v_fill: f64) -> Result<Dimension, SpaceError> {
    let hi = (10.0 * v0).min(0.9 * v_fill);
    Dimension::with_id_bounds(ParamId::V_DEAD, (v0 / 10.0).min(0.5 * hi), hi)
}

/// The search dimension of a displacement estimated from a page: bounds ×/÷ 5 around the
/// page's estimate (wider where its interval is), within the parameter's own domain.
fn displacement_dimension(e: &DisplacementEstimate) -> Result<Dimension, SpaceError> {
    let (domain_lo, domain_hi) = ParamId::V_DISP.spec().search;
    let lo = (e.v_disp_m3 / 5.0).min(e.ci95_m3[0] / 2.0).max(domain_lo);
    let hi = (e.v_disp_m3 * 5.0).max(e.ci95_m3[1] * 2.0).min(domain_hi);
    Dimension::with_id_bounds(ParamId::V_DISP, lo, hi)
}

/// For a dataset of catalogue pages only whose `[motor]` gives neither a displacement nor
/// a geometry: the displacement estimated from the pages (`estimate::fit::displacement`).
fn page_displacement(ds: &Dataset, data: &FitData) -> Option<DisplacementEstimate> {
    let catalogue_only = ds.experiments.iter().all(|e| e.kind == Kind::Catalogue);
    (catalogue_only && displacement_missing(&ds.motor))
        .then(|| displacement_from_page(data, &ds.motor))
        .flatten()
}

/// One parameter of a catalogue's pinning: how well the catalogue pins it, and whether it
/// is estimated.
#[derive(Debug, Clone, PartialEq)]
pub struct Pinning {
    /// The parameter.
    pub name: String,
    /// Relative 1σ at the nominal motor (infinite: unseen).
    pub(crate) relative_sd: f64,
    /// Estimated (pinned to within the limit).
    pub(crate) pinned: bool,
    /// The value it stays fixed at when not pinned, SI.
    pub value: f64,
    /// The kind of experiment that would pin it (when not pinned).
    pub pinned_by: Option<Kind>,
    /// When not pinned and the fit has a prior: the prior's 95 % factor F, on which the
    /// parameter then rests (it is estimated, and its interval is the prior's ×/÷ F).
    pub prior_factor: Option<f64>,
}

/// The pinning as the command line prints it: a heading, then one line per parameter
/// (relative 1σ, and estimated or the value it stays fixed at and what would pin it).
pub fn pinning_lines(limit_pct: f64, rows: &[Pinning]) -> Vec<String> {
    let mut lines = vec![format!(
        "catalogue only: what it pins down at the nominal motor (relative 1σ; pinned: ≤ {limit_pct:.0} %)"
    )];
    for p in rows {
        let sd = if p.relative_sd.is_finite() {
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

/// For a dataset of catalogue pages only and no `estimate`: the parameters the catalogue
/// pins down (`estimate::profile::subset`), reported to `report` with what would pin the rest;
/// otherwise `o` as it is.
fn catalogue_estimates(
    ds: &Dataset,
    data: &FitData,
    o: &FitOptions,
    observer: &dyn FitObserver,
    displacement: Option<&DisplacementEstimate>,
) -> Result<FitOptions, FitError> {
    let catalogue_only = ds.experiments.iter().all(|e| e.kind == Kind::Catalogue);
    if let Some(e) = displacement {
        observer.displacement(e);
    }
    if o.estimate.is_some() || !catalogue_only {
        return Ok(o.clone());
    }
    let motor = Motor::new(ds.nominal_params()?, EffectSet::empty());
    let prior = if o.priors {
        Prior::for_motor(motor.params())
    } else {
        Prior::none()
    };
    let mut names: Vec<String> = DEFAULT_ESTIMATED.iter().map(|s| s.to_string()).collect();
    if !prior.is_empty() {
        // With the motor prior, the two parameters that shape how torque and flow change with
        // the supply pressure are estimated too, resting on their priors where the page is
        // silent: held at their defaults, a page's torque deficit went into the Coulomb
        // friction, a constant that eats a growing share of the torque at lower pressures
        // (docs/estimation.md, "What a page cannot pin").
        names.extend(
            page_prior_extra()
                .into_iter()
                .filter(|id| prior.term(*id).is_some())
                .map(|id| id.name().to_string()),
        );
    }
    let limit = 100.0 * crate::estimate::profile::subset::PINNED_RELATIVE_SD;
    let nothing = || {
        let before = format!(
            "the catalogue pins none of {} to within {limit:.0} % (1σ): add curves, key figures or a rig experiment, or name parameters with ",
            names.join(", ")
        );
        FitError::Option(OptionError::of_within(Opt::FitEstimate, before, ""))
    };
    let Some(pinning) = crate::estimate::profile::subset::pinned_subset(data, &motor, &names)
    else {
        return Err(nothing());
    };
    let rows: Vec<Pinning> = pinning
        .iter()
        .map(|p| Pinning {
            name: p.name.clone(),
            relative_sd: p.relative_sd,
            pinned: p.pinned,
            value: motor.params().get(&p.name).unwrap_or(f64::NAN),
            pinned_by: most_sensitive_experiment(&motor, &p.name),
            prior_factor: (!p.pinned)
                .then(|| {
                    ParamId::from_name(&p.name)
                        .and_then(|id| prior.term(id))
                        .map(|t| t.factor95())
                })
                .flatten(),
        })
        .collect();
    observer.pinning(limit, &rows);
    // With a prior every parameter is estimated: what the pages leave open rests on its
    // prior, and the covariance (and so predict's bands) carries it.
    let chosen: Vec<String> = rows
        .iter()
        .filter(|p| p.pinned || p.prior_factor.is_some())
        .map(|p| p.name.clone())
        .collect();
    if chosen.is_empty() {
        return Err(nothing());
    }
    let mut chosen = chosen;
    if displacement.is_some() {
        // Not printed: the displacement is estimated with the rest, from the page.
        chosen.push(ParamId::V_DISP.name().to_string());
    }
    Ok(FitOptions {
        estimate: Some(chosen),
        ..o.clone()
    })
}

/// The first estimate of a page's displacement as `fit` and `check` print it.
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
    let catalogue_only = ds.experiments.iter().all(|e| e.kind == Kind::Catalogue);
    if !(catalogue_only && displacement_missing(&ds.motor)) {
        return Ok(None);
    }
    let data = FitData::new(ds, CostOptions::default())?;
    Ok(page_displacement(ds, &data))
}

/// What a fit reports while it runs: the multi-start's events ([`RunObserver`], which
/// can also stop the run) and, for a dataset of catalogue pages only, what the catalogue
/// pins down before the starts begin. Every method has a default that does nothing.
pub trait FitObserver: RunObserver {
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

/// The caller's observer, with the pinning kept for the [`Fit`].
struct Noted<'a> {
    inner: &'a dyn FitObserver,
    pinning: &'a std::sync::Mutex<Vec<Pinning>>,
}

impl FitObserver for Noted<'_> {
    fn pinning(&self, limit_pct: f64, rows: &[Pinning]) {
        *self.pinning.lock().unwrap_or_else(|p| p.into_inner()) = rows.to_vec();
        self.inner.pinning(limit_pct, rows);
    }
    fn displacement(&self, estimate: &DisplacementEstimate) {
        self.inner.displacement(estimate);
    }
}

impl RunObserver for Noted<'_> {}

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
}

impl Fit {
    /// For pages that do not print the displacement: the fit's estimate and 95 % interval
    /// in words ("displacement estimated from the page: 4.1 cm³ [3.8, 4.5] (95 %)"; the
    /// interval is the page estimate's where the fit gives none).
    pub fn displacement_line(&self) -> Option<String> {
        let first = self.displacement.as_ref()?;
        let v = self.outcome.params.v_disp();
        let ci = self
            .file
            .ci95
            .iter()
            .find(|(n, _)| n == ParamId::V_DISP.name())
            .map_or(first.ci95_m3, |(_, c)| *c);
        Some(describe_cm3(v, ci))
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
    let pinning = std::sync::Mutex::new(Vec::new());
    let noted = Noted {
        inner: observer,
        pinning: &pinning,
    };
    let o = &catalogue_estimates(
        &ds,
        &data,
        settings.options(),
        &noted,
        displacement.as_ref(),
    )?;
    let space = search_space(&ds, o, displacement.as_ref())?;
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
    let outcome = estimate_fit(engine, &data, &setup, observer)?;
    let file = fit_file(&ds.name, &setup, &outcome, o.seed);
    Ok(Fit {
        dataset: ds,
        data,
        setup,
        outcome,
        file,
        seed: o.seed,
        pinning: pinning.into_inner().unwrap_or_else(|p| p.into_inner()),
        displacement,
    })
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

/// Writes what `vanefit fit` leaves of a finished fit: the fit file at `out`, the plots
/// (unless `plots` is false) and the report next to it. Split from the fit so that a batch
/// unit writes exactly what the command writes.
pub fn write_fit(run: &Fit, out: &Path, plots: bool) -> Result<FitWritten, FitError> {
    let write_error = |path: &Path| {
        let path = path.to_path_buf();
        move |source| FitError::Write { path, source }
    };
    run.file.write(out).map_err(write_error(out))?;
    let mut written = FitWritten::default();
    if plots {
        written.plots = report::plots(
            &run.dataset,
            &run.data.cost,
            &run.setup.space,
            &run.outcome,
            out,
        )?;
    }
    let md = side_path(out, "report.md");
    let text = report::markdown(
        &run.dataset,
        &run.setup,
        &run.outcome,
        run.seed,
        &written.plots,
    );
    crate::io::write_atomic(&md, text.as_bytes()).map_err(write_error(&md))?;
    written.report = md;
    Ok(written)
}
