//! Pictures of a fit: the waterfall of final costs over the starts, and per experiment an
//! overlay of data, reference polynomial and simulation for every channel.

use crate::data::dataset::Dataset;
use crate::model::motor::Motor;
use crate::numerics::DefaultSolver;
use crate::objective::cost::{ChannelResiduals, CostModel};
use crate::objective::reference::{Abscissa, ChannelReference};
use crate::report::plot::{Chart, Figure, PlotError, Series};
use std::path::{Path, PathBuf};

use crate::estimate::multistart::StartResult;

/// Sorted final costs of every start (log scale): a flat floor reached by many starts is a
/// well-found minimum; steps are distinct local minima.
pub fn waterfall(results: &[StartResult], path: &Path) -> Result<(), PlotError> {
    let mut costs: Vec<f64> = results.iter().map(|r| r.cost.max(1e-12)).collect();
    costs.sort_by(f64::total_cmp);
    let points = costs
        .iter()
        .enumerate()
        .map(|(i, c)| ((i + 1) as f64, *c))
        .collect();
    Chart::new(
        "Final cost of every start, sorted",
        "start (sorted by cost)",
        "cost",
    )
    .log_y()
    .with(Series::points("final cost", points))
    .write_svg(path)
}

/// One figure per experiment: for each channel, the recorded data, the reference polynomial
/// and one or more simulations, in the recording's units. Returns the files written.
pub fn overlays(
    ds: &Dataset,
    cost: &CostModel,
    models: &[(&str, &Motor)],
    prefix: &Path,
) -> Result<Vec<PathBuf>, PlotError> {
    let solver = DefaultSolver::default();
    let runs: Vec<(&str, Vec<ChannelResiduals>)> = models
        .iter()
        .map(|(name, m)| {
            cost.residuals(m, &solver)
                .map(|r| (*name, r))
                .map_err(|e| PlotError(e.to_string()))
        })
        .collect::<Result<_, _>>()?;
    let mut written = Vec::new();
    for ex in &ds.experiments {
        let rec = &ex.recording;
        let mut panels = Vec::new();
        for reference in cost.references().filter(|r| r.file == ex.file) {
            let ax = &reference.abscissa;
            let x_meas = ax.measured(rec).map_err(|e| PlotError(e.to_string()))?;
            let y_meas = rec
                .values(reference.quantity)
                .map_err(|e| PlotError(e.to_string()))?;
            let p_atm = ds.p_atm_pa;
            let data = x_meas
                .iter()
                .zip(y_meas)
                .map(|(x, y)| (ax.display(*x, p_atm), reference.display(*y, p_atm)))
                .collect();
            let mut chart = Chart::new(
                &format!("{} — {}", ex.file, reference.column),
                &axis_label(ax),
                &reference.column,
            )
            .with(Series::points("data", data));
            if ax.log10 {
                chart = chart.log_x();
            }
            chart = with_simulations(chart, &runs, &ex.file, reference, p_atm);
            panels.push(chart);
        }
        if panels.is_empty() {
            continue;
        }
        let stem = Path::new(&ex.file)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let path = PathBuf::from(format!("{}.{stem}.svg", prefix.display()));
        let columns = panels.len().min(3);
        Figure::new(panels, columns).write_svg(&path)?;
        written.push(path);
    }
    Ok(written)
}

/// Adds to `chart` the reference polynomial (once) and each model's simulation of the
/// channel `reference` of experiment `file`, sorted along the abscissa.
fn with_simulations(
    mut chart: Chart,
    runs: &[(&str, Vec<ChannelResiduals>)],
    file: &str,
    reference: &ChannelReference,
    p_atm: f64,
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
        if k == 0 {
            let line = pairs
                .iter()
                .map(|(x, m, _)| (ax.display(*x, p_atm), reference.display(*m, p_atm)))
                .collect();
            chart = chart.with(Series::line("reference polynomial", line));
        }
        let line = pairs
            .iter()
            .map(|(x, _, s)| (ax.display(*x, p_atm), reference.display(*s, p_atm)))
            .collect();
        chart = chart.with(Series::line(name, line));
    }
    chart
}

/// The abscissa's axis title.
fn axis_label(ax: &Abscissa) -> String {
    if ax.log10 {
        format!("{} (log scale)", ax.column)
    } else {
        ax.column.clone()
    }
}
