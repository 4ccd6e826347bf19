//! `vanefit merge DIR`: every unit of a batch folder into one fleet summary —
//! `summary.csv` (docs/formats.md, "Contracts added later": one row per dataset × task,
//! `dataset, task, status, message`, then `cost` and `<name>, <name>_ci_lo, <name>_ci_hi`
//! for every estimated parameter, SI), `summary.md` for people and `fleet.svg` (each
//! parameter across the motors with its interval). Everything comes from the unit folders
//! alone, in the batch's unit order, so the summary is the same whichever shards, machines
//! or threads made the units.

use super::manifest::TaskKind;
use super::plan::Unit;
use super::status::{State, UnitStatus};
use super::{BatchError, BatchRecord};
use crate::data::fitfile::FitFile;
use crate::model::params::PARAMS;
use crate::report::plot::{Chart, Figure, Series};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What a merge found and wrote.
#[derive(Debug, Clone, Default)]
pub struct MergeOutcome {
    /// Units of the batch.
    pub units: usize,
    /// Units done.
    pub done: usize,
    /// Units failed, with their reason.
    pub failed: Vec<(String, String)>,
    /// Units not finished (never started, or interrupted and not yet resumed).
    pub unfinished: Vec<String>,
    /// The files written.
    pub written: Vec<PathBuf>,
}

/// One unit as the summary shows it.
struct Row {
    unit: Unit,
    status: State,
    message: String,
    fit: Option<FitFile>,
    diagnosis: Option<serde_json::Value>,
}

/// Reads a file's text: the file system for `merge`, memory for the fuzz target.
pub(crate) type ReadText<'a> = &'a dyn Fn(&Path) -> std::io::Result<String>;

/// Reads a unit's status and, for a done fit or diagnosis, its result file; a result file
/// that cannot be read makes the row failed with the reason.
fn row(out: &Path, unit: &Unit, read_text: ReadText<'_>) -> Row {
    let folder = unit.folder(out);
    let status = read_text(&folder.join("status.json"))
        .ok()
        .and_then(|t| UnitStatus::parse(&t));
    let (mut status, mut message) = match status {
        Some(s) => (s.status, s.message),
        None => (State::Pending, String::new()),
    };
    let (mut fit, mut diagnosis) = (None, None);
    if status == State::Done {
        let read = match unit.task {
            TaskKind::Fit => {
                let path = folder.join("fit.json");
                FitFile::from_read(&path, read_text(&path))
                    .map(|f| fit = Some(f))
                    .map_err(|e| e.to_string())
            }
            TaskKind::Diagnose => read_text(&folder.join("diagnosis.json"))
                .map_err(|e| format!("diagnosis.json: {e}"))
                .and_then(|t| serde_json::from_str(&t).map_err(|e| format!("diagnosis.json: {e}")))
                .map(|v| diagnosis = Some(v)),
            TaskKind::Predict => Ok(()),
        };
        if let Err(why) = read {
            (status, message) = (State::Failed, why);
        }
    }
    Row {
        unit: unit.clone(),
        status,
        message,
        fit,
        diagnosis,
    }
}

/// The estimated parameters of every fit, in the fixed order of the parameter table.
fn parameter_names(rows: &[Row]) -> Vec<&'static str> {
    PARAMS
        .iter()
        .map(|s| s.name)
        .filter(|n| {
            rows.iter()
                .filter_map(|r| r.fit.as_ref())
                .any(|f| f.estimated.iter().any(|e| e == n))
        })
        .collect()
}

/// A number in the summary: shortest exact form (`{:e}`), empty when absent.
fn cell(v: Option<f64>) -> String {
    v.map(|x| format!("{x:e}")).unwrap_or_default()
}

/// A fit's value and interval of `name` (the interval only where one was computed).
fn estimate(f: &FitFile, name: &str) -> (Option<f64>, Option<[f64; 2]>) {
    if !f.estimated.iter().any(|e| e == name) {
        return (None, None);
    }
    let ci = f.ci95.iter().find(|(n, _)| n == name).map(|(_, c)| *c);
    (f.params.get(name), ci)
}

/// `summary.csv` (docs/formats.md, "`summary.csv`").
fn summary_csv(rows: &[Row], names: &[&str]) -> String {
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header: Vec<String> = ["dataset", "task", "status", "message", "cost"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    for n in names {
        header.extend([n.to_string(), format!("{n}_ci_lo"), format!("{n}_ci_hi")]);
    }
    w.write_record(&header).expect("in memory");
    for r in rows {
        let mut rec = vec![
            r.unit.dataset.clone(),
            r.unit.task.id().to_string(),
            r.status.id().to_string(),
            r.message.clone(),
            cell(r.fit.as_ref().and_then(|f| f.cost)),
        ];
        for n in names {
            let (v, ci) = r.fit.as_ref().map_or((None, None), |f| estimate(f, n));
            rec.extend([cell(v), cell(ci.map(|c| c[0])), cell(ci.map(|c| c[1]))]);
        }
        w.write_record(&rec).expect("in memory");
    }
    String::from_utf8(w.into_inner().expect("in memory")).expect("UTF-8 cells")
}

/// `summary.md`: parameters with intervals per motor, diagnosis verdicts, failures.
fn summary_md(record: &BatchRecord, rows: &[Row], names: &[&str]) -> String {
    let mut s = String::new();
    let count = |st: State| rows.iter().filter(|r| r.status == st).count();
    let _ = writeln!(s, "# Fleet summary\n");
    let _ = writeln!(
        s,
        "Batch of `{}`: {} units, {} done, {} failed, {} unfinished. Values SI; intervals 95 %.\n",
        record.manifest.display(),
        rows.len(),
        count(State::Done),
        count(State::Failed),
        rows.len() - count(State::Done) - count(State::Failed)
    );
    let fits: Vec<&Row> = rows.iter().filter(|r| r.fit.is_some()).collect();
    if !fits.is_empty() {
        let _ = writeln!(s, "## Parameters\n");
        let _ = writeln!(s, "| # | dataset | cost J | {} |", names.join(" | "));
        let _ = writeln!(s, "|---|---|---|{}", "---|".repeat(names.len()));
        for (k, r) in fits.iter().enumerate() {
            let f = r.fit.as_ref().expect("filtered");
            let cells: Vec<String> = names
                .iter()
                .map(|n| {
                    let flag = match f.verdicts.iter().find(|v| v.name == *n) {
                        Some(v) if !v.identifiable => " (not identifiable)",
                        _ => "",
                    };
                    match estimate(f, n) {
                        (Some(v), Some([lo, hi])) => format!("{v:.4e} [{lo:.4e}, {hi:.4e}]{flag}"),
                        (Some(v), None) => format!("{v:.4e}{flag}"),
                        _ => "-".into(),
                    }
                })
                .collect();
            let cost = f.cost.map_or("-".into(), |c| format!("{c:.4}"));
            let _ = writeln!(
                s,
                "| {} | {} | {cost} | {} |",
                k + 1,
                r.unit.dataset,
                cells.join(" | ")
            );
        }
        let _ = writeln!(s, "\n![each parameter across the motors](fleet.svg)\n");
    }
    diagnoses_md(&mut s, rows);
    let others: Vec<&Row> = rows.iter().filter(|r| r.status != State::Done).collect();
    if !others.is_empty() {
        let _ = writeln!(s, "## Failed and unfinished units\n");
        for r in others {
            let why = if r.message.is_empty() {
                "-"
            } else {
                &r.message
            };
            let _ = writeln!(s, "- `{}`: {}: {why}", r.unit.label(), r.status.id());
        }
    }
    s
}

/// The diagnoses' verdicts as a table (nothing when the batch diagnosed nothing).
fn diagnoses_md(s: &mut String, rows: &[Row]) {
    let diag: Vec<&Row> = rows.iter().filter(|r| r.diagnosis.is_some()).collect();
    if diag.is_empty() {
        return;
    }
    let _ = writeln!(s, "## Diagnoses\n");
    let _ = writeln!(
        s,
        "| dataset | mismatch | selected | noise ratio before | after |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    for r in diag {
        let d = r.diagnosis.as_ref().expect("filtered");
        let selected: Vec<String> = d["selected"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x["effect"].as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default();
        let ratio = |k: &str| {
            d[k]["noise_ratio"]
                .as_f64()
                .map_or("-".into(), |v| format!("{v:.3}"))
        };
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} |",
            r.unit.dataset,
            d["mismatch"]
                .as_bool()
                .map_or("-", |m| if m { "yes" } else { "no" }),
            if selected.is_empty() {
                "-".into()
            } else {
                selected.join(", ")
            },
            ratio("baseline"),
            ratio("extended")
        );
    }
    let _ = writeln!(s);
}

/// `fleet.svg`: one panel per parameter, the motors (by dataset name) along x,
/// each estimate a point and its 95 % interval a vertical bar, in percent from the fleet's
/// median, so that an odd motor stands out and the axis labels read as the spread (the
/// values themselves differ in the 4th digit, which absolute tick labels would not show).
fn fleet_plot(rows: &[Row], names: &[&str]) -> Option<Figure> {
    let motors: Vec<String> = rows
        .iter()
        .filter(|r| r.fit.is_some())
        .map(|r| r.unit.dataset.clone())
        .collect();
    let fits: Vec<&FitFile> = rows.iter().filter_map(|r| r.fit.as_ref()).collect();
    if fits.is_empty() || names.is_empty() {
        return None;
    }
    let panels = names
        .iter()
        .map(|n| {
            let mut values: Vec<f64> = fits.iter().filter_map(|f| estimate(f, n).0).collect();
            values.sort_by(f64::total_cmp);
            let median = values.get(values.len() / 2).copied().unwrap_or(f64::NAN);
            let pct = |v: f64| 100.0 * (v / median - 1.0);
            let (mut points, mut bars) = (Vec::new(), Vec::new());
            for (i, f) in fits.iter().enumerate() {
                let x = (i + 1) as f64;
                let (v, ci) = estimate(f, n);
                if let Some(v) = v {
                    points.push((x, pct(v)));
                }
                if let Some([lo, hi]) = ci {
                    // A non-finite point breaks the line: one bar per motor.
                    bars.extend([(x, pct(lo)), (x, pct(hi)), (f64::NAN, f64::NAN)]);
                }
            }
            let unit = crate::model::params::spec(n).map_or("", |s| s.unit);
            let title = format!("{n} (fleet median {median:.5e} {unit})");
            let mut chart = Chart::new(&title, "motor (dataset)", "% from the median")
                .with(Series::points("estimate", points))
                .with(Series::line("95 % interval", bars));
            chart.x_range = Some((0.5, fits.len() as f64 + 0.5));
            chart.x_names = motors.clone();
            chart
        })
        .collect();
    Some(Figure::new(panels, 2))
}

/// What `merge` writes, in memory.
pub struct Summary {
    /// The units' counts (nothing written yet).
    pub outcome: MergeOutcome,
    /// `summary.csv`.
    pub csv: String,
    /// `summary.md`.
    pub md: String,
    /// `fleet.svg`, when some fit estimated a parameter.
    pub fleet: Option<Figure>,
}

/// The summary of the batch `record` in folder `out`, from its unit folders' files as
/// `read_text` gives them: everything `merge` reads and computes, without writing, so that
/// the fuzz target can serve the files a user may have edited from memory.
pub fn summarize(out: &Path, record: &BatchRecord, read_text: ReadText<'_>) -> Summary {
    let rows: Vec<Row> = record
        .units
        .iter()
        .map(|u| row(out, u, read_text))
        .collect();
    let names = parameter_names(&rows);
    let mut outcome = MergeOutcome {
        units: rows.len(),
        ..Default::default()
    };
    for r in &rows {
        match r.status {
            State::Done => outcome.done += 1,
            State::Failed => outcome.failed.push((r.unit.label(), r.message.clone())),
            _ => outcome.unfinished.push(r.unit.label()),
        }
    }
    Summary {
        outcome,
        csv: summary_csv(&rows, &names),
        md: summary_md(record, &rows, &names),
        fleet: fleet_plot(&rows, &names),
    }
}

/// Merges the batch folder `out` into `summary.csv`, `summary.md` and `fleet.svg`.
pub fn merge(out: &Path) -> Result<MergeOutcome, BatchError> {
    let record = BatchRecord::read(out)?;
    let summary = summarize(out, &record, &|p: &Path| std::fs::read_to_string(p));
    let mut outcome = summary.outcome;
    let write = |name: &str, text: &str| {
        let path = out.join(name);
        crate::io::write_atomic(&path, text.as_bytes())
            .map(|()| path.clone())
            .map_err(|source| BatchError::Io { path, source })
    };
    outcome.written.push(write("summary.csv", &summary.csv)?);
    outcome.written.push(write("summary.md", &summary.md)?);
    if let Some(fig) = summary.fleet {
        let path = out.join("fleet.svg");
        fig.write_svg(&path)?;
        outcome.written.push(path);
    }
    Ok(outcome)
}
