//! The human report of a diagnosis: `report.md` with SVG plots next to it.
//!
//! * `overlay.<experiment>.svg`: per channel, the recorded data, the baseline and the
//!   extended model against the abscissa, in the recording's units;
//! * `residuals.<experiment>.svg`: per channel, (simulation − data)/σ of the baseline and of
//!   the extended model (noise is ±1);
//! * `ranking.svg`: ΔBIC of every refitted model.

use crate::diagnose::analysis::ChannelData;
use crate::diagnose::{discover, num, summary, Candidate, Concealment, Diagnosis, ModelKind};
use crate::estimate::Method;
use crate::model::effects::Effect;
use crate::model::params::{conductance_dm3_s_bar, description, is_conductance, spec};
use crate::report::explain::{self, number};
use crate::report::plot::{Chart, Figure, Legend, PlotError, Series};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Why the report of a diagnosis could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReportError {
    /// A plot could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The output folder cannot be created.
    #[error("{}: cannot create: {source}", path.display())]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A file cannot be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// Writes `bytes` to `path` atomically.
fn write_file(path: PathBuf, bytes: &[u8]) -> Result<(), ReportError> {
    crate::io::write_atomic(&path, bytes).map_err(|source| ReportError::Write { path, source })
}

/// The abscissa's axis label.
fn x_label(ch: &ChannelData) -> String {
    if ch.abscissa.log10 {
        format!("{} (log scale)", ch.abscissa.column)
    } else {
        ch.abscissa.column.clone()
    }
}

/// (display x, display y) of a channel's values, sorted by x.
fn curve(ch: &ChannelData, y: &[f64], p_atm: f64, as_display: bool) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> =
        ch.x.iter()
            .zip(y)
            .map(|(x, y)| {
                (
                    ch.abscissa.display(*x, p_atm),
                    if as_display {
                        ch.unit.from_si(*y, p_atm)
                    } else {
                        *y
                    },
                )
            })
            .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// A recording's file name without its extension.
fn stem(file: &str) -> String {
    Path::new(file)
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| file.to_string())
}

/// Writes the plots and `report.md`.
pub fn write(d: &Diagnosis, out: &Path) -> Result<(), ReportError> {
    let figures = write_figures(d, out)?;
    let mut md = String::new();
    overview(&mut md, d);
    inputs(&mut md, d);
    locations(&mut md, d);
    concealment(&mut md, d);
    candidates(&mut md, d);
    selected(&mut md, d);
    let _ = writeln!(md, "## Plots\n");
    for (file, o, r) in &figures {
        let _ = writeln!(md, "### {file}\n\n![overlay]({o})\n\n![residuals]({r})\n");
    }
    let _ = writeln!(md, "## Run\n\n| phase | s | evaluations |\n|---|---|---|");
    for ((p, s), (_, n)) in d.phases.iter().zip(&d.phase_evaluations) {
        let _ = writeln!(md, "| {p} | {s:.1} | {n} |");
    }
    let _ = writeln!(md, "| total | {:.1} | {} |", d.wall_s, d.evaluations());
    write_file(out.join("report.md"), md.as_bytes())
}

/// Writes the overlay and residual figures of each experiment and the ranking; returns
/// (file, overlay figure, residual figure) of each experiment with channels.
fn write_figures(d: &Diagnosis, out: &Path) -> Result<Vec<(String, String, String)>, ReportError> {
    let mut files: Vec<String> = d.baseline_channels.iter().map(|c| c.file.clone()).collect();
    files.dedup();
    let ext_label = if d.selected.is_empty() {
        "extended (= baseline)".to_string()
    } else {
        format!("extended ({})", d.extended.label)
    };
    let mut figures: Vec<(String, String, String)> = Vec::new();
    for file in &files {
        let (overlays, residuals): (Vec<Chart>, Vec<Chart>) = d
            .baseline_channels
            .iter()
            .zip(&d.extended_channels)
            .filter(|(b, _)| &b.file == file)
            .map(|(b, e)| {
                (
                    overlay_chart(file, b, e, &ext_label, d.p_atm_pa),
                    residual_chart(file, b, e, &ext_label, d.p_atm_pa),
                )
            })
            .unzip();
        if overlays.is_empty() {
            continue;
        }
        let s = stem(file);
        let cols = overlays.len().min(3);
        let o = format!("overlay.{s}.svg");
        let r = format!("residuals.{s}.svg");
        Figure::new(overlays, cols).write_svg(&out.join(&o))?;
        Figure::new(residuals, cols).write_svg(&out.join(&r))?;
        figures.push((file.clone(), o, r));
    }
    let mut ranking =
        Chart::new("Refitted models", "rank", "dBIC against the baseline").legend(Legend::Right);
    for (i, c) in d.candidates.iter().enumerate().take(12) {
        ranking = ranking.with(Series::points(
            &c.label,
            vec![((i + 1) as f64, c.delta_bic)],
        ));
    }
    if !d.candidates.is_empty() {
        ranking.write_svg(&out.join("ranking.svg"))?;
    }
    Ok(figures)
}

/// A channel's recorded data, the baseline (`b`) and the extended model (`e`).
fn overlay_chart(file: &str, b: &ChannelData, e: &ChannelData, ext: &str, p_atm: f64) -> Chart {
    let chart = Chart::new(&format!("{file}: {}", b.column), &x_label(b), &b.column)
        .with(Series::points("data", curve(b, &b.data, p_atm, true)))
        .with(Series::line("baseline", curve(b, &b.sim, p_atm, true)))
        .with(Series::line(ext, curve(e, &e.sim, p_atm, true)))
        .legend(Legend::Below);
    if b.abscissa.log10 {
        chart.log_x()
    } else {
        chart
    }
}

/// A channel's residuals in noise units, of the baseline (`b`) and the extended model (`e`).
fn residual_chart(file: &str, b: &ChannelData, e: &ChannelData, ext: &str, p_atm: f64) -> Chart {
    let chart = Chart::new(
        &format!("{file}: {} residual / noise", b.column),
        &x_label(b),
        "(simulation - data) / sigma",
    )
    .with(Series::points(
        "baseline",
        curve(b, &b.normalized(), p_atm, false),
    ))
    .with(Series::points(ext, curve(e, &e.normalized(), p_atm, false)))
    .legend(Legend::Below);
    if b.abscissa.log10 {
        chart.log_x()
    } else {
        chart
    }
}

/// Title, summary, the verdict and how to read the numbers.
fn overview(md: &mut String, d: &Diagnosis) {
    let _ = writeln!(md, "# Diagnosis of `{}`\n", d.dataset);
    let _ = writeln!(md, "{}\n", summary(d));
    let _ = writeln!(
        md,
        "**mismatch: {}**. Baseline noise ratio {:.3} (a correct model exceeds {:.3} with \
         probability 0.1%), extended {:.3}. Wall time {:.1} s on {} thread(s).\n",
        d.mismatch,
        d.baseline.noise_ratio,
        d.noise_ratio_limit,
        d.extended.noise_ratio,
        d.wall_s,
        d.threads
    );
    let _ = writeln!(
        md,
        "How to read the numbers:\n\n* {}.\n* {} (every fit of a diagnosis minimises it; no \
         sensor offset is profiled out here: an offset would be a finding). BIC = χ² + k·ln n \
         over the n = {} compared points, k estimated parameters; a model is selected only \
         when it beats every simpler one by ΔBIC < −10.\n* `cost` is J at the fitted \
         parameters: {}.\n* {}.\n",
        explain::NOISE_RATIO,
        explain::CHI2_PER_DOF,
        d.baseline.fitted.n_points,
        explain::COST_J,
        explain::CONDUCTANCE_UNITS
    );
}

/// A parameter id for the report, in code style, with its meaning: `` `c_1e` (leak, ...) ``.
fn md_label(name: &str) -> String {
    match description(name) {
        Some(words) => format!("`{name}` ({words})"),
        None => format!("`{name}`"),
    }
}

/// How the recorded inputs of the transients were smoothed.
fn inputs(md: &mut String, d: &Diagnosis) {
    if d.inputs.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "Recorded inputs of the transients (errors in variables: the simulation is driven \
         by their smooth in time where it fits to within noise):\n\n\
         | file | column | noise | RMS change | smooth |\n|---|---|---|---|---|"
    );
    for i in &d.inputs {
        let rel = i.column.starts_with("c_port2");
        let size = |v: f64| {
            if rel {
                format!("{:.2}%", 100.0 * v)
            } else {
                format!("{} Pa", num(v))
            }
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            i.file,
            i.column,
            size(i.noise),
            size(i.rms_change),
            i.degree
                .map_or("kept as recorded".into(), |g| format!("degree {g}"))
        );
    }
    let _ = writeln!(md);
}

/// Where the baseline misses, and each channel's noise ratio before and after.
fn locations(md: &mut String, d: &Diagnosis) {
    let _ = writeln!(md, "## Where the baseline misses\n");
    if d.locations.is_empty() {
        let _ = writeln!(
            md,
            "No channel shows a regional bias, runs or trend beyond noise (family-wise α = 1%).\n"
        );
    } else {
        let _ = writeln!(
            md,
            "| experiment | channel | abscissa range | severity (σ) | mean sim − data | test |\n|---|---|---|---|---|---|"
        );
        for l in &d.locations {
            let _ = writeln!(
                md,
                "| {} | {} | {} {} .. {}{} | {:.2} | {} {} | {} |",
                l.kind.id(),
                l.column,
                l.x_column,
                num(l.x_range_display[0]),
                num(l.x_range_display[1]),
                conductance_range(&l.x_column, l.x_range),
                l.severity,
                num(l.bias_display),
                l.unit,
                l.test
            );
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(
        md,
        "| experiment | channel | noise ratio baseline | noise ratio extended |\n|---|---|---|---|"
    );
    for (b, e) in d.baseline_channels.iter().zip(&d.extended_channels) {
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {:.3} |",
            b.file,
            b.column,
            b.mean_square().sqrt(),
            e.mean_square().sqrt()
        );
    }
    let _ = writeln!(md);
}

/// For a conductance abscissa (`c_port…` columns), its range in both units (`x_range`: SI);
/// nothing for other abscissae.
fn conductance_range(x_column: &str, x_range: [f64; 2]) -> String {
    if !x_column.starts_with("c_port") {
        return String::new();
    }
    format!(
        " (= {} .. {} m3/(s*Pa) = {} .. {} dm3/(s*bar))",
        num(x_range[0]),
        num(x_range[1]),
        num(conductance_dm3_s_bar(x_range[0])),
        num(conductance_dm3_s_bar(x_range[1]))
    )
}

/// A parameter value for a table: a conductance also in dm³/(s·bar), in brackets.
fn param_cell(name: &str, v: f64) -> String {
    if is_conductance(name) {
        format!("{} ({})", num(v), num(conductance_dm3_s_bar(v)))
    } else {
        num(v)
    }
}

/// The concealment test: the statistic, each experiment's ratios and parameters.
fn concealment(md: &mut String, d: &Diagnosis) {
    let _ = writeln!(md, "## Concealment\n");
    let Some(c) = &d.concealment else {
        let _ = writeln!(md, "Not tested (one experiment, or switched off).\n");
        return;
    };
    let _ = writeln!(
        md,
        "Each experiment fitted alone against the joint fit: χ²_joint − Σχ²_alone = \
         {:.1} on at most {} degrees of freedom, p = {:.2e} ({}). Held-out: each \
         experiment predicted by the base model fitted to the others (a held-out ratio \
         well above 1 can also mean that the other experiments leave a parameter open: \
         compare models by it rather than reading it alone).\n",
        c.lr,
        c.df,
        c.p_value,
        if c.disagree() {
            "the experiments disagree: a plain fit conceals a mismatch"
        } else {
            "the parameters agree"
        }
    );
    let _ = writeln!(
        md,
        "| experiment | noise ratio, joint fit | fitted alone (limit) | predicted from the others |\n|---|---|---|---|"
    );
    for e in &c.experiments {
        let _ = writeln!(
            md,
            "| {} | {:.3} | {:.3} ({:.3}) | {} |",
            e.file,
            e.joint_ratio,
            e.alone_ratio,
            e.alone_limit,
            e.held_out_ratio.map_or("-".into(), |v| format!("{v:.3}"))
        );
    }
    separate_parameters(md, d, c);
}

/// The estimated parameters of the joint fit and of each experiment fitted alone.
fn separate_parameters(md: &mut String, d: &Diagnosis, c: &Concealment) {
    let _ = write!(
        md,
        "\nEstimated parameters, SI (conductances in m3/(s*Pa), in brackets in dm3/(s*bar)):\n\n\
         | parameter | joint |"
    );
    for e in &c.experiments {
        let _ = write!(md, " {} alone |", e.file);
    }
    let _ = write!(md, "\n|---|---|");
    for _ in &c.experiments {
        let _ = write!(md, "---|");
    }
    let _ = writeln!(md);
    for n in &d.estimated {
        let unit = spec(n).map_or(String::new(), |s| format!(", {}", s.unit));
        let _ = write!(
            md,
            "| {}{unit} | {} |",
            md_label(n),
            param_cell(n, d.baseline.fitted.params.get(n).unwrap_or(f64::NAN))
        );
        for e in &c.experiments {
            let _ = write!(
                md,
                " {} |",
                param_cell(n, e.alone_params.get(n).unwrap_or(f64::NAN))
            );
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(md);
}

/// Every refitted model, the effects not tried and the term library's ranking.
fn candidates(md: &mut String, d: &Diagnosis) {
    let _ = writeln!(md, "## Candidates\n");
    let _ = writeln!(
        md,
        "Each refitted warm from the baseline optimum; ranked by ΔBIC.\n\n![ranking](ranking.svg)\n"
    );
    let _ = writeln!(
        md,
        "| model | kind | k | cost | χ² | ΔBIC | noise ratio | held-out noise ratio |\n|---|---|---|---|---|---|---|---|"
    );
    for c in std::iter::once(&d.baseline).chain(&d.candidates) {
        candidate_row(md, c);
    }
    let _ = writeln!(md);
    effects_tried(md, d);
    for s in &d.skipped {
        let _ = writeln!(md, "* `{}` not tried: {}.", s.effect.id(), s.reason);
    }
    let _ = writeln!(md);
    if let Some(r) = &d.regression {
        let _ = writeln!(
            md,
            "### Term library: linearised regression of the baseline misfit\n\n\
             Each term alone, on top of a refit of the base parameters (first-order \
             sensitivities), best first:\n\n| term | linearised ΔBIC |\n|---|---|"
        );
        for t in r.ranking.iter().take(8) {
            let _ = writeln!(
                md,
                "| `{}` | {:.1} |",
                discover::formula(&t.term),
                t.delta_bic
            );
        }
        let _ = writeln!(md);
    }
}

/// What each catalog effect among the candidates is, with its parameters in words.
fn effects_tried(md: &mut String, d: &Diagnosis) {
    let tried: Vec<Effect> = Effect::ALL
        .into_iter()
        .filter(|e| d.candidates.iter().any(|c| c.fitted.effects.contains(*e)))
        .collect();
    if tried.is_empty() {
        return;
    }
    let _ = writeln!(md, "The catalog effects refitted:\n");
    for e in tried {
        let params: Vec<String> = e.specs().iter().map(|s| md_label(s.name)).collect();
        let _ = writeln!(
            md,
            "* `{}` ({}): {}; parameters: {}.",
            e.id(),
            e.category().id(),
            e.physics(),
            params.join(", ")
        );
    }
    let _ = writeln!(md);
}

/// One row of the candidates' table.
fn candidate_row(md: &mut String, c: &Candidate) {
    let _ = writeln!(
        md,
        "| {} | {:?} | {} | {:.4} | {:.1} | {:.1} | {:.3} | {} |",
        c.label,
        c.kind,
        c.fitted.k,
        c.fitted.cost,
        c.fitted.chi2,
        c.delta_bic,
        c.noise_ratio,
        c.held_out.map_or("-".into(), |v| format!("{v:.3}"))
    );
}

/// The selected extensions and the locations they leave.
fn selected(md: &mut String, d: &Diagnosis) {
    let _ = writeln!(md, "## Selected\n");
    if d.selected.is_empty() {
        let _ = writeln!(md, "Nothing: the base model is kept.\n");
        return;
    }
    for s in &d.selected {
        let params: Vec<String> = s
            .parameters
            .iter()
            .map(|(n, v, u)| {
                let value = if is_conductance(n) {
                    explain::conductance(*v, 4)
                } else {
                    format!("{} {u}", num(*v))
                };
                format!("{} = {value}", md_label(n))
            })
            .collect();
        let _ = writeln!(
            md,
            "* **{}** ({}): {}; ΔBIC {:.1}{}",
            s.effect,
            s.category.id(),
            params.join(", "),
            s.delta_bic,
            s.term
                .as_ref()
                .map_or(String::new(), |t| format!("; `{}`", discover::formula(t)))
        );
    }
    let _ = writeln!(md);
    if d.extended.kind != ModelKind::Baseline {
        let _ = writeln!(
            md,
            "Locations left after the extension: {}.\n",
            if d.extended_locations.is_empty() {
                "none".to_string()
            } else {
                d.extended_locations
                    .iter()
                    .map(|l| format!("{} {} ({:.1}σ)", l.kind.id(), l.column, l.severity))
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        );
        extended_intervals(md, d);
    }
}

/// The extended model's 95 % intervals (`Diagnosis::extended_intervals`): a table of every
/// estimated parameter, discovered terms' coefficients included, and how they were read.
fn extended_intervals(md: &mut String, d: &Diagnosis) {
    let Some(first) = d.extended_intervals.first() else {
        return;
    };
    let method = match first.interval.method {
        Method::Profile => "profile likelihood: each parameter held, the others refitted",
        _ => "the curvature of χ² at the optimum",
    };
    let _ = writeln!(
        md,
        "### The extended model's 95 % intervals\n\n\
         By {method}, on the likelihood every fit of the diagnosis maximises; an interval ends \
         where χ² rises by 3.84·s², s = max(1, noise ratio) = {:.3} (wider where the model \
         misses the noise); \"open\": the data do not bound that side. The values are those \
         of `extended.json`; `diagnosis.json` has the intervals (`extended.intervals`).\n\n\
         | parameter | estimate | 95 % interval | unit |\n|---|---|---|---|",
        d.extended.noise_ratio.max(1.0)
    );
    for e in &d.extended_intervals {
        let i = &e.interval;
        let (label, unit) = match &e.term {
            Some(t) => (
                format!("coefficient of `{}`", discover::formula(t)),
                discover::coefficient_unit(t),
            ),
            None => (
                md_label(&i.name),
                spec(&i.name).map_or(String::new(), |s| s.unit.to_string()),
            ),
        };
        // Four digits: an interval is often narrower than the third digit of its estimate.
        let cell = |v: f64| match is_conductance(&i.name) {
            true => format!("{} ({})", number(v, 4), number(conductance_dm3_s_bar(v), 4)),
            false => number(v, 4),
        };
        let end = |v: Option<f64>| v.map_or("open".to_string(), cell);
        let _ = writeln!(
            md,
            "| {label} | {} | [{}, {}] | {unit} |",
            cell(i.value),
            end(i.lo),
            end(i.hi)
        );
    }
    let _ = writeln!(md);
}

/// Writes `diagnosis.json`, `extended.json` (the extended model's fit file), `report.md`
/// and the plots into `out`.
pub fn write_all(d: &Diagnosis, out: &Path) -> Result<(), ReportError> {
    std::fs::create_dir_all(out).map_err(|source| ReportError::CreateDir {
        path: out.to_path_buf(),
        source,
    })?;
    for (name, v) in [
        ("diagnosis.json", crate::diagnose::to_json(d)),
        ("extended.json", crate::diagnose::extended_fit_file(d)),
    ] {
        let text = serde_json::to_string_pretty(&v).expect("plain data") + "\n";
        write_file(out.join(name), text.as_bytes())?;
    }
    write(d, out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Conductances in the diagnosis report come in both units, ids with their meaning.
    #[test]
    fn conductances_in_both_units_and_ids_in_words() {
        assert_eq!(
            param_cell("c_1e", 2.077886e-9),
            format!("{} ({})", num(2.077886e-9), num(0.2077886))
        );
        assert_eq!(param_cell("visc", 6e-5), num(6e-5));
        assert_eq!(md_label("c_1e"), "`c_1e` (leak, inlet side → exhaust)");
        assert_eq!(
            md_label("t_static"),
            "`t_static` (static (breakaway) friction torque)"
        );
        assert_eq!(md_label("k_poly"), "`k_poly`");
        let range = conductance_range("c_port2_m3_s_pa", [3e-10, 1e-7]);
        assert!(range.contains("3.000e-10 .. 1.000e-7 m3/(s*Pa)"), "{range}");
        assert!(range.contains("0.030 .. 10.000 dm3/(s*bar)"), "{range}");
        assert_eq!(conductance_range("p_port1_mpa", [1e5, 7e5]), "");
    }
}
