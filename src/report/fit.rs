//! A fit for people: the table of its parameters (ids with their meaning, conductances in
//! m³/(s·Pa) and dm³/(s·bar)), the report `<fit>.report.md`, and its pictures: the
//! waterfall of final costs over the starts, and per experiment an overlay of data,
//! reference polynomial and simulation for every channel.

use crate::data::dataset::{Dataset, Kind};
use crate::estimate::fit::{FitOutcome, FitSetup};
use crate::estimate::problem::dimension::BoundSide;
use crate::estimate::problem::space::ParamSpace;
use crate::estimate::profile::uncertainty::Interval;
use crate::model::params::{conductance_dm3_s_bar, spec, Domain, MotorParams, ParamSpec, PARAMS};
use crate::objective::cost::{ChannelResiduals, CostModel};
use crate::objective::reference::{Abscissa, ChannelReference};
use crate::report::explain::{self, number};
use crate::report::plot::{Chart, Figure, Legend, PlotError, Series};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::estimate::optimize::multistart::StartResult;

/// One estimated parameter of a fit, as the summary and the report print it.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamRow {
    /// The parameter's id.
    pub name: String,
    /// What it is, in words ([`ParamSpec::description`]).
    pub description: &'static str,
    /// The estimate, SI.
    pub value: f64,
    /// Its SI unit.
    pub unit: &'static str,
    /// The 95% interval's ends (`None` on an open side); `None` when not computed.
    pub interval: Option<(Option<f64>, Option<f64>)>,
    /// A sonic conductance (also printed in dm³/(s·bar)).
    pub conductance: bool,
    /// Why the parameter is not identifiable, and which experiment would pin it down.
    pub(crate) not_identifiable: Option<String>,
}

impl ParamRow {
    /// The interval in SI, `[lo, hi]` with `open` for an open side, or `not computed`.
    fn interval_text(&self, convert: fn(f64) -> f64, digits: usize) -> String {
        match self.interval {
            None => "not computed".into(),
            Some((lo, hi)) => {
                let end = |x: Option<f64>| x.map_or("open".into(), |x| number(convert(x), digits));
                format!("[{}, {}]", end(lo), end(hi))
            }
        }
    }
}

/// The estimated parameters of a fit, in the order of its search space.
pub fn parameter_rows(ds: &Dataset, setup: &FitSetup, out: &FitOutcome) -> Vec<ParamRow> {
    setup
        .space
        .dims
        .iter()
        .map(|d| {
            let s = d.id.spec();
            let iv = out.intervals.iter().find(|i| i.name == d.name());
            let not_identifiable = iv.and_then(|i| i.why_not()).map(|why| {
                let would_pin = out.would_pin.iter().find(|(id, _)| *id == d.id);
                let hint = match would_pin.map(|(_, k)| *k) {
                    Some(k) if !ds.experiments.iter().any(|e| e.kind == k) => {
                        format!("; adding the {} experiment would pin it down", k.id())
                    }
                    _ => String::new(),
                };
                format!("{why}{hint}")
            });
            ParamRow {
                name: d.name().to_string(),
                description: s.description(),
                value: out.params.value(d.id),
                unit: s.unit,
                interval: iv.map(|i| (i.lo, i.hi)),
                conductance: s.is_conductance(),
                not_identifiable,
            }
        })
        .collect()
}

/// The parameters a fit held fixed (the base model's and those of the effects switched on
/// that were not estimated), with their values.
pub fn fixed_parameters(setup: &FitSetup, out: &FitOutcome) -> Vec<(&'static ParamSpec, f64)> {
    PARAMS
        .iter()
        .filter(|s| s.effect.is_none_or(|e| setup.space.effects.contains(e)))
        .filter(|s| !setup.space.dims.iter().any(|d| d.name() == s.name))
        .map(|s| (s, out.params.get(s.name).unwrap_or(s.default)))
        .collect()
}

/// The parameter table for a terminal: one line per parameter (id, value, 95% interval,
/// unit, meaning) and, under a conductance, the same in dm³/(s·bar); a parameter that is not
/// identifiable says why on a line of its own.
pub fn terminal_table(rows: &[ParamRow]) -> Vec<String> {
    let si = |v: f64| v;
    let mut lines = vec![format!(
        "{:<10} {:>12} {:>26}  {:<11}  meaning",
        "parameter", "value", "95% interval", "unit"
    )];
    for r in rows {
        lines.push(format!(
            "{:<10} {:>12} {:>26}  {:<11}  {}",
            r.name,
            number(r.value, 5),
            r.interval_text(si, 5),
            r.unit,
            r.description
        ));
        if r.conductance {
            lines.push(format!(
                "{:<10} {:>12} {:>26}  {}",
                "",
                number(conductance_dm3_s_bar(r.value), 5),
                r.interval_text(conductance_dm3_s_bar, 5),
                crate::model::params::CATALOGUE_CONDUCTANCE_UNIT
            ));
        }
        if let Some(why) = &r.not_identifiable {
            lines.push(format!("{:<10} NOT IDENTIFIABLE: {why}", ""));
        }
    }
    lines
}

/// The report's section of a page's printed figures outside the fit's bands
/// (`task::fit::figures_outside_bands`); empty without any.
pub fn figure_warnings(warnings: &[String]) -> String {
    if warnings.is_empty() {
        return String::new();
    }
    let mut md = String::from("\n## Printed figures outside the fit's bands\n\n");
    for w in warnings {
        let _ = writeln!(md, "- {w}");
    }
    md
}

/// The report of a fit, `<fit>.report.md`: run, goodness of fit with what its numbers mean,
/// estimated and fixed parameters, systematic errors, and the plots (`plots`: file names
/// next to the report).
pub fn markdown(
    ds: &Dataset,
    setup: &FitSetup,
    out: &FitOutcome,
    seed: u64,
    plots: &[PathBuf],
) -> String {
    let mut md = String::new();
    let run = &out.run;
    let _ = writeln!(md, "# Fit of `{}`\n", ds.name);
    let effects = if setup.space.effects.is_empty() {
        "the base model (no catalog effect)".to_string()
    } else {
        format!("effects {}", setup.space.effects.ids().join(", "))
    };
    let _ = writeln!(
        md,
        "{} starts (seed {seed}, {} converged to the best minimum), {} evaluations; {effects}. \
         The estimate is the maximum of the likelihood of the recorded rows, reached from the \
         best start; intervals by {}.\n",
        run.results.len(),
        run.converged(),
        out.evaluations,
        out.method.id()
    );
    if let Some(g) = ds.gear() {
        let _ = writeln!(
            md,
            "Geared motor: the pages' figures are the gearbox's OUTPUT shaft's and were moved to the motor shaft (speed × G, torque ÷ η·G, power ÷ η); the parameters are the MOTOR shaft's. {}.\n",
            g.describe()
        );
    }
    goodness_section(&mut md, out);
    parameter_section(&mut md, &parameter_rows(ds, setup, out));
    let warnings = bound_warnings(out);
    if !warnings.is_empty() {
        let _ = writeln!(md, "## Estimates on a bound\n");
        for w in warnings {
            let _ = writeln!(md, "- {w}");
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(
        md,
        "## Fixed parameters\n\n| parameter | meaning | value |\n|---|---|---|"
    );
    for (s, v) in fixed_parameters(setup, out) {
        let _ = writeln!(
            md,
            "| `{}` | {} | {} |",
            s.name,
            s.description(),
            explain::value(s.name, v, 5)
        );
    }
    let _ = writeln!(md);
    if !out.nuisances.is_empty() {
        let _ = writeln!(
            md,
            "## Systematic errors at the estimate\n\nSensor offsets and the supply-pressure \
             sensor's offset, profiled out within their calibration tolerances (each in the \
             unit people read that sensor in):\n\n| offset | value | unit |\n|---|---|---|"
        );
        for (k, v) in &out.nuisances {
            let (value, unit) = offset_in_reading_unit(k, *v);
            let _ = writeln!(md, "| {k} | {} | {unit} |", number(value, 4));
        }
        let _ = writeln!(md);
    }
    if !plots.is_empty() {
        let _ = writeln!(md, "## Plots\n");
        for p in plots {
            let name = p
                .file_name()
                .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            let _ = writeln!(md, "![{name}]({name})\n");
        }
    }
    md
}

/// One sentence per estimate that ended on a bound of its search range
/// (`FitOutcome::on_bound`): which parameter, which bound, and why what depends on it is
/// unreliable. A non-negative parameter on its lower bound is one the data see none of.
pub fn bound_warnings(out: &FitOutcome) -> Vec<String> {
    out.on_bound
        .iter()
        .map(|h| {
            let s = h.id.spec();
            let why = if h.side == BoundSide::Lower && s.domain == Domain::NonNegative {
                "the data see none of it (that bound stands for zero)"
            } else {
                "the search range of a motor of this size stopped it, not the data"
            };
            format!(
                "{} ({}) ended on its {} bound {}: {why}; it and every prediction that depends                  on it are unreliable. Widen its range with --bounds {}=LO:HI, or look for                  missing physics with `vanefit diagnose`.",
                s.name,
                s.description(),
                h.side,
                explain::value(s.name, h.bound, 3),
                s.name
            )
        })
        .collect()
}

/// χ² of a fit as the terminal and the report name it: `chi2 X over N rows, chi2/dof Y
/// (dof D)`, the rows against the data's own noise (docs/model.md, "χ² and χ²/dof");
/// `chi2/dof undefined (dof D ≤ 0)` when there are no more rows than estimated parameters.
pub fn chi2_summary(g: &crate::estimate::fit::goodness::GoodnessOfFit) -> String {
    match g.chi2_per_dof {
        Some(r) => format!(
            "chi2 {:.1} over {} rows, chi2/dof {r:.3} (dof {})",
            g.chi2, g.n_points, g.dof
        ),
        None => format!(
            "chi2 {:.1} over {} rows, chi2/dof undefined (dof {} ≤ 0)",
            g.chi2, g.n_points, g.dof
        ),
    }
}

/// The warning of a fit with no degrees of freedom left (dof = n − k ≤ 0): χ²/dof is
/// undefined and a small χ² says nothing about the model; `None` when dof > 0.
pub fn dof_warning(g: &crate::estimate::fit::goodness::GoodnessOfFit) -> Option<String> {
    (g.dof <= 0).then(|| {
        let k = g.n_points as i64 - g.dof;
        format!(
            "{} rows for {k} estimated parameters (dof {} ≤ 0): chi2/dof is undefined and a \
             small chi2 does not show that the model fits; the data cannot test it",
            g.n_points, g.dof
        )
    })
}

/// The likelihood χ² of a fit (what the estimate minimises), named apart from χ², with the
/// channels whose σ was widened; `None` when it is χ² itself (no channel widened and χ²
/// known), so that one number is never shown under two names.
pub fn likelihood_chi2_summary(out: &FitOutcome) -> Option<String> {
    if out.goodness.is_some() && out.widening.is_empty() {
        return None;
    }
    let widened = if out.widening.is_empty() {
        "no channel widened".to_string()
    } else {
        let list: Vec<String> = out
            .widening
            .iter()
            .map(|(c, f)| format!("{c} ×{f:.2}"))
            .collect();
        format!("σ widened: {}", list.join(", "))
    };
    Some(format!(
        "likelihood chi2 {:.1} over {} rows ({widened})",
        out.chi2, out.n_points
    ))
}

/// A line of the terminal summary of a fit: for stdout, or a warning for stderr.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum SummaryLine {
    /// A line for stdout.
    Say(String),
    /// A warning for stderr (`warning: …`).
    Warn(String),
}

/// What `vanefit fit` prints after the fit, from what the fit computed: the run, the
/// dataset's notes (gearbox, catalogue tolerances), the estimate and its goodness of fit
/// (`goodness_summary`), the parameter table, the fixed parameters, the local minima and
/// the fit file written to `path`.
pub fn terminal_summary(
    ds: &Dataset,
    setup: &FitSetup,
    out: &FitOutcome,
    path: &Path,
) -> Vec<SummaryLine> {
    let mut lines = Vec::new();
    let mut say = |text: String| lines.push(SummaryLine::Say(text));
    let run = &out.run;
    say(format!(
        "fit of {}: {} starts ({} converged), {} evaluations, {:.1} s on {} thread(s)",
        ds.name,
        run.results.len(),
        run.converged(),
        out.evaluations,
        out.wall_s,
        run.threads
    ));
    if !setup.space.effects.is_empty() {
        say(format!("effects: {}", setup.space.effects.ids().join(", ")));
    }
    if let Some(g) = ds.gear() {
        say(format!(
            "geared motor: the pages' figures are the OUTPUT shaft's, moved to the motor shaft (speed × G, torque ÷ η·G, power ÷ η); the parameters below are the MOTOR shaft's (with the gearbox's drag in its friction). {}{}",
            g.describe(),
            if g.efficiency_printed { "" } else { "; its spread is profiled out of the likelihood as a gain on the pages' torques and powers, so the intervals hold it" }
        ));
    }
    for ex in ds.experiments.iter().filter(|e| e.kind == Kind::Catalogue) {
        say(format!(
            "{}: catalogue points weigh with their reading tolerance ({:.0} % of each curve's full scale) as σ, not a noise estimate, and carry no sensor offsets",
            ex.file,
            100.0 * ex.tolerance.unwrap_or(0.0)
        ));
    }
    lines.extend(goodness_summary(out));
    let mut say = |text: String| lines.push(SummaryLine::Say(text));
    for line in terminal_table(&parameter_rows(ds, setup, out)) {
        say(line);
    }
    for w in bound_warnings(out) {
        say(format!("warning: {w}"));
    }
    say("fixed (not estimated):".to_string());
    for (s, v) in fixed_parameters(setup, out) {
        say(format!(
            "  {:<10} {:<42} {}",
            s.name,
            explain::value(s.name, v, 5),
            s.description()
        ));
    }
    let minima: Vec<String> = out
        .clusters
        .iter()
        .take(5)
        .map(|c| format!("{:.4} (x{})", c.cost, c.members.len()))
        .collect();
    say(format!(
        "local minima (cost J x starts): {}",
        minima.join(", ")
    ));
    say(format!("wrote {}", path.display()));
    lines
}

/// What the estimate is, how well it fits, and cost against χ² (of [`terminal_summary`]).
fn goodness_summary(out: &FitOutcome) -> Vec<SummaryLine> {
    let mut lines = Vec::new();
    let mut say = |text: String| lines.push(SummaryLine::Say(text));
    say(
        "estimate: the maximum-likelihood point of the recorded rows (each channel's σ from the data's noise, a catalogue's from its reading tolerance; recorded sensors' offsets within calibration tolerance profiled out)".to_string()
    );
    if !out.nuisances.is_empty() {
        let list: Vec<String> = out
            .nuisances
            .iter()
            .map(|(k, v)| format!("{k} {v:+.3e}"))
            .collect();
        say(format!(
            "systematic errors at the estimate (SI): {}",
            list.join(", ")
        ));
    }
    if let Some(g) = &out.goodness {
        let verdict = if g.noise_reached {
            "the model reaches the noise".to_string()
        } else {
            let worst = out
                .worst_channel
                .as_ref()
                .map(|(c, r)| format!("; worst {c} at {r:.2}x its noise"))
                .unwrap_or_default();
            format!(
                "the model does NOT reach the noise{worst}: intervals widened {:.2}x; do not trust them without a look at the plots",
                g.interval_scale
            )
        };
        say(format!(
            "goodness of fit: {}, noise ratio {:.3} (limit {:.3}): {verdict}",
            chi2_summary(g),
            g.noise_ratio,
            g.noise_ratio_limit
        ));
        if let Some(warning) = dof_warning(g) {
            lines.push(SummaryLine::Warn(warning));
        }
    }
    let mut say = |text: String| lines.push(SummaryLine::Say(text));
    let likelihood = likelihood_chi2_summary(out);
    if let Some(line) = &likelihood {
        say(line.clone());
    }
    say(format!(
        "cost J {:.4} at the estimate; the best start reached {:.4} (J weighs each channel by its reference polynomial's scatter, chi2 by the data's noise, so their optima differ a little)",
        out.cost, out.best_start_cost
    ));
    say(format!("  what these are: {}.", explain::NOISE_RATIO));
    say(format!(
        "  {}; {}.",
        explain::CHI2_PER_DOF,
        explain::CHI2_OFFSETS
    ));
    if likelihood.is_some() {
        say(format!("  {}.", explain::LIKELIHOOD_CHI2));
    }
    say(format!("  {}.", explain::COST_J));
    say(format!("  {}.", explain::CONDUCTANCE_UNITS));
    lines
}

/// The goodness of fit and the cost, each with one line on what it is.
fn goodness_section(md: &mut String, out: &FitOutcome) {
    let _ = writeln!(md, "## How well it fits\n");
    if let Some(g) = &out.goodness {
        let verdict = if g.noise_reached {
            "the model reaches the noise".to_string()
        } else {
            format!(
                "the model does NOT reach the noise: intervals widened {:.2}×",
                g.interval_scale
            )
        };
        let _ = writeln!(
            md,
            "* noise ratio {:.3} (limit {:.3}): {verdict}\n* {}",
            g.noise_ratio,
            g.noise_ratio_limit,
            chi2_summary(g)
        );
    }
    if let Some(warning) = out.goodness.as_ref().and_then(dof_warning) {
        let _ = writeln!(md, "* **warning:** {warning}");
    }
    let likelihood = likelihood_chi2_summary(out);
    if let Some(line) = &likelihood {
        let _ = writeln!(md, "* {line}");
    }
    let _ = writeln!(
        md,
        "* cost J {:.4} at the estimate; the best start reached {:.4}\n\n\
         What these are:\n\n* {}.\n* {}; {}.",
        out.cost,
        out.best_start_cost,
        explain::NOISE_RATIO,
        explain::CHI2_PER_DOF,
        explain::CHI2_OFFSETS,
    );
    if likelihood.is_some() {
        let _ = writeln!(md, "* {}.", explain::LIKELIHOOD_CHI2);
    }
    let _ = writeln!(md, "* {}.\n", explain::COST_J);
}

/// The table of estimated parameters, conductances in both units.
fn parameter_section(md: &mut String, rows: &[ParamRow]) {
    let _ = writeln!(
        md,
        "## Estimated parameters\n\nValues and 95% intervals in SI; {}.\n\n\
         | parameter | meaning | value | 95% interval | unit | in dm3/(s*bar) | identifiable |\n\
         |---|---|---|---|---|---|---|",
        explain::CONDUCTANCE_UNITS
    );
    for r in rows {
        let catalogue = if r.conductance {
            format!(
                "{} {}",
                number(conductance_dm3_s_bar(r.value), 5),
                r.interval_text(conductance_dm3_s_bar, 5)
            )
        } else {
            String::new()
        };
        let identifiable = match (&r.not_identifiable, r.interval) {
            (Some(why), _) => format!("no: {why}"),
            (None, None) => "not computed".into(),
            (None, Some(_)) => "yes".into(),
        };
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {} | {} | {catalogue} | {identifiable} |",
            r.name,
            r.description,
            number(r.value, 5),
            r.interval_text(|v| v, 5),
            r.unit
        );
    }
    let _ = writeln!(md);
}

/// The fitted motor's curves at a catalogue page's supply pressure, from standstill to the
/// free speed, with their 95 % bands (computed by the task layer with `predict`; the
/// report only draws them over the page's points).
#[derive(Debug, Clone, PartialEq)]
pub struct PageCurve {
    /// The page's file (as rig.toml names the experiment).
    pub file: String,
    /// Torque, power and air against speed, SI.
    pub points: Vec<crate::predict::CurvePoint>,
}

/// Where a fit's plots go, next to its fit file (`<stem>.waterfall.svg`, `.parameters.svg`,
/// `.profiles.svg`, and `<stem>.<recording>.svg` per experiment).
#[derive(Debug, Clone, PartialEq)]
pub struct PlotPaths {
    /// Sorted final costs of every start.
    pub waterfall: PathBuf,
    /// The estimated parameters across starts.
    pub parameters: PathBuf,
    /// The likelihood profiles.
    pub profiles: PathBuf,
    /// The overlays' common prefix (the fit file without its extension).
    pub overlay_prefix: PathBuf,
}

/// Every plot of a fit, written to `paths`: the paths written. `page_curves`: the model
/// over each catalogue page's whole speed range.
pub(crate) fn plots(
    dataset: &Dataset,
    cost: &CostModel,
    space: &ParamSpace,
    outcome: &FitOutcome,
    page_curves: &[PageCurve],
    paths: &PlotPaths,
) -> Result<Vec<PathBuf>, PlotError> {
    let results = &outcome.run.results;
    waterfall(results, &paths.waterfall)?;
    parameters_across_starts(results, space, &outcome.params, &paths.parameters)?;
    let mut written = vec![paths.waterfall.clone(), paths.parameters.clone()];
    written.extend(profiles(
        &outcome.intervals,
        outcome.threshold,
        &paths.profiles,
    )?);
    let fit = outcome
        .channels
        .as_deref()
        .map_err(|e| PlotError::Sim(e.clone()))?;
    written.extend(overlays(
        dataset,
        cost,
        &[("fit", fit)],
        page_curves,
        &paths.overlay_prefix,
    )?);
    Ok(written)
}

/// Sorted final costs of every start (log scale): a flat floor reached by many starts is a
/// well-found minimum; steps are distinct local minima.
pub(crate) fn waterfall(results: &[StartResult], path: &Path) -> Result<(), PlotError> {
    let mut costs: Vec<f64> = results.iter().map(|r| r.cost.max(1e-12)).collect();
    costs.sort_by(f64::total_cmp);
    let points = costs
        .iter()
        .enumerate()
        .map(|(i, c)| ((i + 1) as f64, *c))
        .collect();
    Chart::new(
        "Final cost J of every start, sorted",
        "start (sorted by cost)",
        "cost J",
    )
    .log_y()
    .with(Series::points("final cost", points))
    .write_svg(path)
}

/// Each estimated parameter's likelihood profile, one panel each: Δχ² with the others
/// re-optimised against the parameter's value, and the threshold whose crossings are the 95 %
/// interval's ends (pyPESTO's profile plot). `None` when no profile was computed.
pub fn profiles(
    intervals: &[Interval],
    threshold: Option<f64>,
    path: &Path,
) -> Result<Option<PathBuf>, PlotError> {
    let panels: Vec<Chart> = intervals
        .iter()
        .filter(|iv| iv.path.len() > 1)
        .map(|iv| profile_panel(iv, threshold))
        .collect();
    if panels.is_empty() {
        return Ok(None);
    }
    Figure::new(panels, 3).write_svg(path)?;
    Ok(Some(path.to_path_buf()))
}

/// One profile's panel: the path, the estimate, the threshold across the path's range. A
/// log x axis where every value is positive (conductances and friction span decades).
fn profile_panel(iv: &Interval, threshold: Option<f64>) -> Chart {
    // The far points where the search overshot (Δχ² in the thousands) would flatten the
    // interesting part: the panel shows Δχ² up to three thresholds.
    let cap = threshold.map_or(f64::INFINITY, |t| 3.0 * t);
    let points: Vec<(f64, f64)> = iv
        .path
        .iter()
        .filter(|p| p.delta_chi2 <= cap)
        .map(|p| (p.value, p.delta_chi2))
        .collect();
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (x, _)| {
            (a.min(*x), b.max(*x))
        });
    let unit = spec(&iv.name).map_or("", |s| s.unit);
    let mut chart = Chart::new(&iv.name, &format!("{} / {unit}", iv.name), "Δχ²")
        .with(Series::line("profile", points))
        .with(Series::points("estimate", vec![(iv.value, 0.0)]))
        .legend(Legend::Below);
    if let Some(t) = threshold {
        chart = chart.with(Series::line("95 % threshold", vec![(lo, t), (hi, t)]));
    }
    // A log axis only where the path spans a decade: over a narrow span it would label
    // nothing between its ends.
    if lo > 0.0 && hi > 10.0 * lo {
        chart = chart.log_x();
    }
    chart
}

/// Every estimated parameter across the starts, one panel each: the end point of each start
/// against its rank by final cost (best first), and the estimate. Starts that agree with
/// the best on a parameter form a flat run at the left; a parameter that scatters among
/// equally good starts is poorly determined (pyPESTO's parameters plot, one axis each).
pub(crate) fn parameters_across_starts(
    results: &[StartResult],
    space: &ParamSpace,
    estimate: &MotorParams,
    path: &Path,
) -> Result<(), PlotError> {
    let mut order: Vec<&StartResult> = results.iter().collect();
    order.sort_by(|a, b| a.cost.total_cmp(&b.cost));
    let panels: Vec<Chart> = space
        .dims
        .iter()
        .enumerate()
        .map(|(j, d)| {
            let points = order
                .iter()
                .enumerate()
                .filter_map(|(rank, r)| r.theta.get(j).map(|t| ((rank + 1) as f64, d.value(*t))))
                .collect::<Vec<_>>();
            let (lo, hi) = points
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (_, v)| {
                    (a.min(*v), b.max(*v))
                });
            let positive = lo > 0.0 && hi > 10.0 * lo;
            let unit = d.id.spec().unit;
            let mut chart = Chart::new(
                d.name(),
                "start (by final cost)",
                &format!("{} / {unit}", d.id),
            )
            .with(Series::points("end of start", points))
            .legend(Legend::Below);
            if let Some(v) = estimate.get(d.name()) {
                let n = order.len().max(1) as f64;
                chart = chart.with(Series::line("estimate", vec![(1.0, v), (n, v)]));
            }
            if positive {
                chart = chart.log_y();
            }
            chart
        })
        .collect();
    Figure::new(panels, 3).write_svg(path)
}

/// One figure per experiment: for each channel, the recorded data, the reference polynomial
/// and one or more simulations, in the recording's units; a catalogue page's channel
/// against speed with its model curve over the whole speed range and the curve's 95 % band
/// (`page_curves`) instead of the fit at the page's speeds only. Returns the files written.
pub(crate) fn overlays(
    ds: &Dataset,
    cost: &CostModel,
    runs: &[(&str, &[ChannelResiduals])],
    page_curves: &[PageCurve],
    prefix: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    let mut written = Vec::new();
    for ex in &ds.experiments {
        let rec = &ex.recording;
        let (mut panels, mut residuals) = (Vec::new(), Vec::new());
        for reference in cost.references().filter(|r| r.file == ex.file) {
            let ax = &reference.abscissa;
            let x_meas = ax.measured(rec)?;
            let y_meas = rec.values(reference.quantity)?;
            let p_atm = ds.p_atm_pa;
            let data = x_meas
                .iter()
                .zip(y_meas)
                .map(|(x, y)| (ax.display(*x, p_atm), reference.display(*y, p_atm)))
                .collect();
            let labels = Labels::of(reference);
            let mut chart = Chart::new(
                &format!("{} — {}", ex.file, labels.words),
                &labels.x,
                &labels.y,
            )
            .with(Series::points("data", data));
            if ax.log10 {
                chart = chart.log_x();
            }
            let curve = page_curves
                .iter()
                .find(|c| c.file == ex.file)
                .and_then(|c| model_curve(c, reference, p_atm));
            chart = with_simulations(chart, runs, &ex.file, reference, p_atm, curve.is_none());
            if let Some((line, band)) = curve {
                chart = chart
                    .with(Series::line("fit (model)", line))
                    .with(Series::line("fit's 95 % band", band));
            }
            panels.push(chart);
            residuals.push(residual_panel(
                runs,
                &ex.file,
                (reference, &labels),
                (&x_meas, y_meas),
                p_atm,
            ));
        }
        if panels.is_empty() {
            continue;
        }
        // One column per channel, its residuals in the row under it.
        let columns = panels.len();
        panels.extend(residuals);
        let stem = Path::new(&ex.file)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let path = PathBuf::from(format!("{}.{stem}.svg", prefix.display()));
        Figure::new(panels, columns).write_svg(&path)?;
        written.push(path);
    }
    Ok(written)
}

/// A series' (x, y) points in the chart's units.
type Points = Vec<(f64, f64)>;

/// The model curve of a page's channel `reference` against speed, in the channel's units,
/// and its 95 % band as one closed outline (the lower edge out, the upper edge back);
/// `None` for a channel the curve does not hold or an abscissa other than speed.
fn model_curve(
    curve: &PageCurve,
    reference: &ChannelReference,
    p_atm: f64,
) -> Option<(Points, Points)> {
    use crate::predict::CurvePoint;
    use crate::units::Quantity;
    let ax = &reference.abscissa;
    if ax.quantity != Quantity::Speed || ax.log10 {
        return None;
    }
    let of: fn(&CurvePoint) -> &crate::predict::Banded = match reference.quantity {
        Quantity::Torque => |p| &p.torque_nm,
        Quantity::Power => |p| &p.power_w,
        Quantity::Flow1 => |p| &p.air_kg_s,
        _ => return None,
    };
    let at = |p: &CurvePoint, y: f64| {
        (
            ax.display(p.speed_rad_s, p_atm),
            reference.display(y, p_atm),
        )
    };
    let line = curve.points.iter().map(|p| at(p, of(p).value)).collect();
    let edge = |side: usize| {
        curve
            .points
            .iter()
            .filter_map(move |p| of(p).band95.map(|b| at(p, b[side])))
    };
    let band: Vec<(f64, f64)> = edge(0)
        .chain(edge(1).collect::<Vec<_>>().into_iter().rev())
        .collect();
    Some((line, band))
}

/// Adds to `chart` the reference polynomial (once) and each model's simulation of the
/// channel `reference` of experiment `file`, sorted along the abscissa (`fit_lines`: also
/// the simulations through several points, else only single-point markers).
fn with_simulations(
    mut chart: Chart,
    runs: &[(&str, &[ChannelResiduals])],
    file: &str,
    reference: &ChannelReference,
    p_atm: f64,
    fit_lines: bool,
) -> Chart {
    let ax = &reference.abscissa;
    for (k, (name, res)) in runs.iter().enumerate() {
        let Some(ch) = res
            .iter()
            .find(|c| c.file == file && c.channel == reference.quantity)
        else {
            continue;
        };
        let mut pairs: Vec<(f64, f64, f64)> =
            ch.x.iter()
                .zip(&ch.measured)
                .zip(&ch.simulated)
                .map(|((x, m), s)| (*x, *m, *s))
                .collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let [(x, _, s)] = pairs[..] {
            // A single point (a catalogue's key figure): no line to draw, so the fitted value
            // is a marker, and a polynomial through one point says nothing.
            let point = (ax.display(x, p_atm), reference.display(s, p_atm));
            chart = chart.with(Series::marker(name, vec![point]));
            continue;
        }
        if k == 0 {
            let line = pairs
                .iter()
                .map(|(x, m, _)| (ax.display(*x, p_atm), reference.display(*m, p_atm)))
                .collect();
            chart = chart.with(Series::line("reference polynomial", line));
        }
        if !fit_lines {
            continue;
        }
        let line = pairs
            .iter()
            .map(|(x, _, s)| (ax.display(*x, p_atm), reference.display(*s, p_atm)))
            .collect();
        chart = chart.with(Series::line(name, line));
    }
    chart
}

/// The residual panel of the channel `reference` of experiment `file`: the recorded value
/// minus each model's simulation at every compared row (not the reference polynomial, which
/// only describes the data), in the channel's unit, against the recorded abscissa, with a
/// zero line, titled by the channel's `labels`. `data` holds the recording's abscissa (as
/// [`Abscissa::measured`]) and channel values, SI, indexed by row.
fn residual_panel(
    runs: &[(&str, &[ChannelResiduals])],
    file: &str,
    (reference, labels): (&ChannelReference, &Labels),
    (x_meas, y_meas): (&[f64], &[f64]),
    p_atm: f64,
) -> Chart {
    let ax = &reference.abscissa;
    let mut chart = Chart::new(
        &format!("{file} — {} residual", labels.words),
        &labels.x,
        &format!("data − fit, {}", labels.y),
    );
    if ax.log10 {
        chart = chart.log_x();
    }
    let (mut x_lo, mut x_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for (name, res) in runs {
        let Some(ch) = res
            .iter()
            .find(|c| c.file == file && c.channel == reference.quantity)
        else {
            continue;
        };
        let points: Vec<(f64, f64)> = ch
            .rows
            .iter()
            .zip(&ch.simulated)
            .filter_map(|(&i, s)| {
                let x = ax.display(*x_meas.get(i)?, p_atm);
                Some((x, reference.display_difference(y_meas.get(i)? - s, p_atm)))
            })
            .collect();
        for (x, _) in points.iter().filter(|p| p.0.is_finite()) {
            x_lo = x_lo.min(*x);
            x_hi = x_hi.max(*x);
        }
        chart = chart.with(Series::points(&format!("data − {name}"), points));
    }
    if x_lo <= x_hi {
        chart = chart.with(Series::line("", vec![(x_lo, 0.0), (x_hi, 0.0)]));
    }
    chart
}

/// A channel's titles, read once from its column names for its overlay and residual
/// panels: the quantity in words, its axis title and the abscissa's.
struct Labels {
    /// The channel's quantity in words ([`quantity_words`]).
    words: String,
    /// The abscissa's axis title ([`axis_label`]).
    x: String,
    /// The channel's axis title ([`column_label`]).
    y: String,
}

impl Labels {
    /// The titles of the channel `reference`.
    fn of(reference: &ChannelReference) -> Self {
        Self {
            words: quantity_words(&reference.column),
            x: axis_label(&reference.abscissa),
            y: column_label(&reference.column),
        }
    }
}

/// The abscissa's axis title: its quantity and unit in words.
fn axis_label(ax: &Abscissa) -> String {
    if ax.log10 {
        format!("{} (log scale)", column_label(&ax.column))
    } else {
        column_label(&ax.column)
    }
}

/// A recording's column as an axis title, quantity and unit as people write them
/// (`p_port1_mpa` → `port 1 pressure [MPa]`); the column itself if it names no quantity.
fn column_label(column: &str) -> String {
    match crate::units::parse_column(column) {
        Ok((q, u)) => format!("{} [{}]", q.words(), u.symbol()),
        Err(_) => column.to_string(),
    }
}

/// A sensor offset (SI, labelled `<file> <quantity prefix> offset` or `supply pressure
/// sensor offset`) in the unit people read that sensor in: speed in rpm, flows in g/s,
/// torque in N·m, pressures in kPa (an offset is a difference: absolute and gauge alike).
/// An unknown label keeps its SI value and says so.
fn offset_in_reading_unit(label: &str, v_si: f64) -> (f64, &'static str) {
    use crate::units::{Quantity, Unit};
    let quantity = if label.starts_with("supply pressure") {
        Some(Quantity::PPort1)
    } else {
        let prefix = label
            .strip_suffix(" offset")
            .and_then(|l| l.rsplit(' ').next());
        Quantity::ALL
            .into_iter()
            .find(|q| Some(q.prefix()) == prefix)
    };
    let unit = match quantity {
        Some(Quantity::Speed) => Unit::Rpm,
        Some(Quantity::Flow1 | Quantity::Flow2) => Unit::GS,
        Some(Quantity::PPort1 | Quantity::PPort2) => return (v_si * 1e-3, "kPa"),
        Some(q) => q.si_unit(),
        None => return (v_si, "SI"),
    };
    (unit.from_si(v_si, 0.0), unit.symbol())
}

/// A column's quantity in words (`p_port1_mpa` → "port 1 pressure"), for panel titles.
fn quantity_words(column: &str) -> String {
    crate::units::parse_column(column)
        .map_or_else(|_| column.to_string(), |(q, _)| q.words().into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::plot::Style;

    fn row(name: &str, value: f64, interval: Option<(Option<f64>, Option<f64>)>) -> ParamRow {
        let s = spec(name).unwrap();
        ParamRow {
            name: name.into(),
            description: s.description(),
            value,
            unit: s.unit,
            interval,
            conductance: s.is_conductance(),
            not_identifiable: None,
        }
    }

    /// Conductances are printed in m³/(s·Pa) and dm³/(s·bar), every id with its meaning.
    #[test]
    fn terminal_table_gives_meanings_and_both_conductance_units() {
        let mut open = row("c_12", 7.6e-10, Some((Some(5e-10), None)));
        open.not_identifiable = Some("the data do not bound it from above".into());
        let rows = [
            row(
                "c_in1",
                6.758344e-9,
                Some((Some(6.7531e-9), Some(6.7636e-9))),
            ),
            row("t_coulomb", 0.0201, None),
            open,
        ];
        let lines = terminal_table(&rows);
        let text = lines.join("\n");
        assert!(lines[0].contains("meaning") && lines[0].contains("unit"));
        assert!(lines[1].starts_with("c_in1") && lines[1].contains("6.7583e-9"));
        assert!(lines[1].contains("[6.7531e-9, 6.7636e-9]") && lines[1].contains("m3/(s*Pa)"));
        assert!(lines[1].contains("inlet port, supply → chamber 1"));
        assert!(lines[2].contains("0.67583") && lines[2].contains("[0.67531, 0.67636]"));
        assert!(lines[2].contains("dm3/(s*bar)"));
        assert!(lines[3].contains("t_coulomb") && lines[3].contains("Coulomb friction torque"));
        assert!(lines[3].contains("not computed") && lines[3].contains("N*m"));
        assert!(!lines[3].contains("dm3") && !lines[4].starts_with("  "));
        assert!(lines[4].contains("leak, inlet side → outlet side"));
        assert!(
            lines[5].contains("0.076") && lines[5].contains("[0.05, open]"),
            "{text}"
        );
        assert!(lines[6].contains("NOT IDENTIFIABLE: the data do not bound it from above"));
        assert_eq!(lines.len(), 7);
    }

    /// Each sensor offset of the report's table carries its own unit: rpm for speed
    /// (1 rad/s = 30/π rpm), g/s for flows, N·m for torque, kPa for the supply pressure.
    #[test]
    fn offsets_are_given_each_in_its_unit() {
        let (v, u) = offset_in_reading_unit("ramp.csv speed offset", 0.01444);
        assert_eq!(u, "rpm");
        assert!((v - 0.01444 * 30.0 / std::f64::consts::PI).abs() < 1e-12);
        let (v, u) = offset_in_reading_unit("ramp.csv flow1 offset", 1.029e-6);
        assert_eq!(u, "g/s");
        assert!((v - 1.029e-3).abs() < 1e-15);
        assert_eq!(
            offset_in_reading_unit("datasheet.csv torque offset", -3.6e-4),
            (-3.6e-4, "N·m")
        );
        let (v, u) = offset_in_reading_unit("supply pressure sensor offset", -147.9);
        assert_eq!(u, "kPa");
        assert!((v + 0.1479).abs() < 1e-12);
    }

    /// Overlay axes name the quantity and its unit, not the raw column.
    #[test]
    fn axes_name_quantity_and_unit() {
        assert_eq!(column_label("p_port1_mpa"), "port 1 pressure [MPa abs]");
        assert_eq!(column_label("p_port1_bar_g"), "port 1 pressure [bar(g)]");
        // Every pressure unit an axis can carry says absolute or gauge.
        for u in crate::units::Quantity::PPort1.units() {
            let s = u.symbol();
            assert!(
                s.ends_with(" abs") || s.ends_with("(a)") || s.ends_with("(g)"),
                "{s}"
            );
        }
        assert_eq!(column_label("torque_nm"), "torque [N·m]");
        assert_eq!(
            column_label("air_l_min_anr"),
            "port 1 mass flow (air consumption) [l/min ANR]"
        );
        assert_eq!(column_label("no_such_column"), "no_such_column");
        let ax = Abscissa {
            quantity: crate::units::Quantity::CPort2,
            column: "c_port2_m3_s_pa".into(),
            unit: crate::units::Unit::M3SPa,
            log10: true,
        };
        assert_eq!(
            axis_label(&ax),
            "port 2 nozzle conductance [m³/(s·Pa)] (log scale)"
        );
    }

    /// A page's model curve is drawn over the whole speed range it was computed on (from
    /// standstill to the free speed, in rpm), not at the page's speeds only, with its band as
    /// one outline: the lower edge out, the upper edge back.
    #[test]
    fn a_page_curve_spans_the_whole_speed_range_with_its_band() {
        use crate::predict::{Banded, CurvePoint};
        let free_rad_s = 2000.0;
        let n = 11;
        let points: Vec<CurvePoint> = (0..n)
            .map(|k| {
                let w = free_rad_s * k as f64 / (n - 1) as f64;
                let t = 0.2 * (1.0 - w / free_rad_s);
                let banded = |v: f64| Banded {
                    value: v,
                    band95: Some([v - 0.01, v + 0.01]),
                };
                CurvePoint {
                    speed_rad_s: w,
                    torque_nm: banded(t),
                    power_w: banded(t * w),
                    air_kg_s: banded(1e-3),
                }
            })
            .collect();
        let curve = PageCurve {
            file: "page.csv".into(),
            points,
        };
        // The page's points lie in the middle of the range only.
        let reference = torque_reference(
            &[5000.0, 7000.0, 9000.0, 11000.0],
            &[0.15, 0.13, 0.11, 0.09],
        );
        let (line, band) = model_curve(&curve, &reference, 1e5).unwrap();
        assert_eq!(line.len(), n);
        assert_eq!(line[0], (0.0, 0.2));
        let free_rpm = free_rad_s * 30.0 / std::f64::consts::PI;
        assert!((line[n - 1].0 - free_rpm).abs() < 1e-9 && line[n - 1].1.abs() < 1e-12);
        assert_eq!(band.len(), 2 * n);
        assert!((band[0].1 - 0.19).abs() < 1e-12 && (band[2 * n - 1].1 - 0.21).abs() < 1e-12);
        assert!((band[n - 1].0 - free_rpm).abs() < 1e-9 && (band[n].0 - free_rpm).abs() < 1e-9);
    }

    /// A torque channel of a catalogue page against speed, its reference fitted to `y`.
    fn torque_reference(x: &[f64], y: &[f64]) -> ChannelReference {
        let (quantity, unit) = crate::units::parse_column("torque_nm").unwrap();
        let (ax_q, ax_unit) = crate::units::parse_column("speed_rpm").unwrap();
        let options = crate::objective::reference::ReferenceOptions::default();
        ChannelReference {
            kind: crate::data::dataset::Kind::Catalogue,
            file: "page.csv".into(),
            quantity,
            column: "torque_nm".into(),
            unit,
            abscissa: Abscissa {
                quantity: ax_q,
                column: "speed_rpm".into(),
                unit: ax_unit,
                log10: false,
            },
            reference: crate::objective::reference::Reference::fit(x, y, &options).unwrap(),
        }
    }

    /// Residuals of `reference`'s channel at recording `rows`, the simulation `simulated` and
    /// a reference polynomial value far from the data.
    fn channel_residuals(
        reference: &ChannelReference,
        rows: Vec<usize>,
        simulated: Vec<f64>,
    ) -> ChannelResiduals {
        ChannelResiduals {
            experiment_kind: reference.kind,
            file: reference.file.clone(),
            channel: reference.quantity,
            column: reference.column.clone(),
            x: rows.iter().map(|&i| i as f64).collect(),
            measured: vec![100.0; rows.len()],
            normalized: vec![0.0; rows.len()],
            rows,
            simulated,
            sigma: 1.0,
            weight: 1.0,
        }
    }

    /// The residual panel shows recorded value − simulation at the compared rows (not the
    /// reference polynomial), in the channel's unit, with a zero line, and is labelled so.
    #[test]
    fn residual_panel_is_data_minus_fit_at_the_compared_rows() {
        let x = [100.0, 200.0, 300.0, 400.0];
        let y = [0.30, 0.9, 0.20, 0.10];
        let reference = torque_reference(&x, &y);
        let fit = vec![channel_residuals(&reference, vec![0, 2], vec![0.25, 0.26])];
        let runs = [("fit", fit.as_slice())];
        let chart = residual_panel(
            &runs,
            "page.csv",
            (&reference, &Labels::of(&reference)),
            (&x, &y),
            101_325.0,
        );
        assert_eq!(chart.y_label, "data − fit, torque [N·m]");
        assert_eq!(chart.series[0].name, "data − fit");
        let got = &chart.series[0].points;
        assert_eq!(got.len(), 2);
        let rpm = |w: f64| w * 60.0 / (2.0 * std::f64::consts::PI);
        for ((gx, gy), (wx, wy)) in got.iter().zip([(rpm(100.0), 0.05), (rpm(300.0), -0.06)]) {
            assert!((gx - wx).abs() < 1e-9 && (gy - wy).abs() < 1e-12, "{got:?}");
        }
        let zero = &chart.series[1];
        assert_eq!(zero.points, vec![(rpm(100.0), 0.0), (rpm(300.0), 0.0)]);
        assert!(zero.name.is_empty());
        let svg = Figure::new(vec![chart], 1).to_svg().unwrap();
        assert!(
            svg.contains("data − fit, torque [N·m]"),
            "axis label missing"
        );
    }

    /// A channel with a single compared point shows the fitted value as a marker named
    /// after the model, and no reference polynomial; a longer one gets lines.
    #[test]
    fn single_point_channel_gets_a_fit_marker() {
        let reference = torque_reference(&[100.0, 200.0, 300.0, 400.0], &[0.3, 0.2, 0.1, 0.0]);
        let fit = vec![channel_residuals(&reference, vec![1], vec![0.21])];
        let one = [("fit", fit.as_slice())];
        let chart = with_simulations(
            Chart::new("t", "x", "y"),
            &one,
            "page.csv",
            &reference,
            1e5,
            true,
        );
        assert_eq!(chart.series.len(), 1);
        assert_eq!(chart.series[0].name, "fit");
        assert_eq!(chart.series[0].style, Style::Marker);
        let (px, py) = chart.series[0].points[0];
        assert!((px - 1.0 * 60.0 / (2.0 * std::f64::consts::PI)).abs() < 1e-9);
        assert_eq!(py, 0.21);
        let svg = chart.to_svg().unwrap();
        assert!(
            svg.contains(">fit<") || svg.contains(">\nfit"),
            "no legend entry"
        );
        let fit = vec![channel_residuals(&reference, vec![0, 1, 2], vec![0.3; 3])];
        let many = [("fit", fit.as_slice())];
        let chart = with_simulations(
            Chart::new("t", "x", "y"),
            &many,
            "page.csv",
            &reference,
            1e5,
            true,
        );
        let styles: Vec<_> = chart
            .series
            .iter()
            .map(|s| (s.name.as_str(), s.style))
            .collect();
        assert_eq!(
            styles,
            [("reference polynomial", Style::Line), ("fit", Style::Line)]
        );
    }

    #[test]
    fn markdown_parameter_table_has_both_units() {
        let mut md = String::new();
        parameter_section(
            &mut md,
            &[
                row("c_1e", 2.077886e-9, Some((Some(2.0e-9), Some(2.2e-9)))),
                row("visc", 6e-5, None),
            ],
        );
        assert!(md.contains("dm3/(s*bar)") && md.contains("1e-8 m3/(s*Pa)"));
        assert!(
            md.contains(
                "| `c_1e` | leak, inlet side → exhaust | 2.0779e-9 | [2e-9, 2.2e-9] | m3/(s*Pa) \
             | 0.20779 [0.2, 0.22] | yes |"
            ),
            "{md}"
        );
        assert!(
            md.contains(
                "| `visc` | viscous friction | 6e-5 | not computed | N*m*s/rad |  | not computed |"
            ),
            "{md}"
        );
    }
}
