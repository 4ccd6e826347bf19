//! Running a shard: every unit of the shard in order, each in its own folder. A unit already
//! finished is skipped, an interrupted fit resumes from its starts file, and a unit that
//! fails is recorded with its reason while the others go on.

use super::manifest::{Manifest, TaskKind};
use super::plan::{self, Shard, Unit};
use super::progress::BatchProgress;
use super::status::{State, UnitStatus};
use super::{BatchError, BatchRecord};
use crate::estimate::Engine;
use crate::task::diagnose::{diagnose_to, DiagnoseTaskError};
use crate::task::fit::{fit_dataset, write_fit_to, FitError, FitPaths};
use crate::task::predict::{predict_to, PredictTaskError};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to run a shard.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// The batch folder.
    pub out: PathBuf,
    /// Which shard.
    pub shard: Shard,
    /// Worker threads (None: one per core); results do not depend on it.
    pub threads: Option<usize>,
    /// Run units that failed before again (by default a failed unit is finished).
    pub retry_failed: bool,
}

/// What a shard did.
#[derive(Debug, Clone, Default)]
pub struct RunOutcome {
    /// Units of the shard.
    pub units: usize,
    /// Units run now and done.
    pub done: usize,
    /// Units skipped because an earlier run finished them.
    pub skipped: usize,
    /// Units that failed (now or before), with their reason.
    pub failed: Vec<(String, String)>,
}

/// Why a unit failed (recorded in its status file; the batch goes on).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub(crate) enum UnitError {
    /// The fit failed.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// The diagnosis failed.
    #[error(transparent)]
    Diagnose(#[from] DiagnoseTaskError),
    /// The prediction failed.
    #[error(transparent)]
    Predict(#[from] PredictTaskError),
    /// A prediction without a finished fit of its dataset.
    #[error("no fit to predict from: the fit of this dataset is {0}")]
    NoFit(String),
    /// The unit's log could not be written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// A bug: the unit panicked (the batch goes on).
    #[error("internal error: {0}")]
    Panic(String),
}

/// What became of a unit in this run.
enum Ran {
    /// Finished by an earlier run (its status then).
    Skipped(UnitStatus),
    /// Run now (its new status).
    Now(UnitStatus),
}

/// Runs the units of `opts.shard` of `manifest` into `opts.out`: the shard's groups side by
/// side on the engine's threads (rayon), a group's units in order (a predict after its fit),
/// every fit's starts on the same threads by work stealing. Units write only into their own
/// folders, and each unit's result is independent of the others, so the parallelism changes
/// nothing but the time.
pub fn run(manifest: &Manifest, opts: &RunOptions) -> Result<RunOutcome, BatchError> {
    let record = BatchRecord::of(manifest);
    record.claim(&opts.out)?;
    let units = plan::select(&record.units, opts.shard);
    let engine = Engine::with_threads(opts.threads)?;
    let progress = BatchProgress::new(units.len(), opts.shard.to_string());
    progress.line(&format!(
        "{} of {} units on {} thread(s)",
        units.len(),
        record.units.len(),
        engine.threads()
    ));
    let groups = by_group(units);
    let ran = engine.map(&groups, |group| {
        group
            .iter()
            .map(|u| run_or_skip(&engine, manifest, u, opts, &progress).map(|r| (u.label(), r)))
            .collect::<Result<Vec<_>, BatchError>>()
    });
    let mut outcome = RunOutcome::default();
    for (label, r) in ran
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?
        .into_iter()
        .flatten()
    {
        outcome.units += 1;
        match r {
            Ran::Skipped(s) => {
                outcome.skipped += 1;
                if s.status == State::Failed {
                    outcome.failed.push((label, s.message));
                }
            }
            Ran::Now(s) if s.status == State::Done => outcome.done += 1,
            Ran::Now(s) => outcome.failed.push((label, s.message)),
        }
    }
    progress.line("shard finished");
    Ok(outcome)
}

/// The units gathered by group, groups in order of their first unit, each group's units in
/// plan order. A group's units need not be neighbours in the plan (a dataset's predict comes
/// after its diagnose, in the fit's group): gathering only neighbours would run a predict
/// beside its fit instead of after it, and fail it for want of a fit on more than one thread.
fn by_group(units: Vec<Unit>) -> Vec<Vec<Unit>> {
    let mut groups: Vec<Vec<Unit>> = Vec::new();
    for u in units {
        match groups.iter_mut().find(|g| g[0].group == u.group) {
            Some(g) => g.push(u),
            None => groups.push(vec![u]),
        }
    }
    groups
}

/// Skips a finished unit (done, or failed unless `retry_failed`), runs any other, and says
/// so on the progress lines.
fn run_or_skip(
    engine: &Engine,
    manifest: &Manifest,
    unit: &Unit,
    opts: &RunOptions,
    progress: &BatchProgress,
) -> Result<Ran, BatchError> {
    let before = UnitStatus::read(&unit.folder(&opts.out));
    if let Some(s) = before
        .filter(|s| s.status == State::Done || (s.status == State::Failed && !opts.retry_failed))
    {
        progress.unit_finished();
        progress.line(&format!(
            "{}: {} before, skipped",
            unit.label(),
            s.status.id()
        ));
        return Ok(Ran::Skipped(s));
    }
    let status = run_one(engine, manifest, unit, &opts.out, progress)?;
    progress.unit_finished();
    if status.status == State::Done {
        progress.line(&format!(
            "{}: done in {:.1} s ({})",
            unit.label(),
            status.wall_s,
            status.message
        ));
    } else {
        progress.line(&format!("{}: FAILED: {}", unit.label(), status.message));
    }
    Ok(Ran::Now(status))
}

/// Runs one unit between its `running` and its final status file; a panic is caught and
/// recorded, so that one bad unit never takes the batch down.
fn run_one(
    engine: &Engine,
    manifest: &Manifest,
    unit: &Unit,
    out: &Path,
    progress: &BatchProgress,
) -> Result<UnitStatus, BatchError> {
    let folder = unit.folder(out);
    let write = |s: &UnitStatus| {
        s.write(&folder).map_err(|source| BatchError::Io {
            path: folder.join("status.json"),
            source,
        })
    };
    let (dataset, task) = (unit.dataset.as_str(), unit.task.id());
    write(&UnitStatus::new(
        dataset,
        task,
        State::Running,
        String::new(),
        0.0,
    ))?;
    progress.line(&format!("{}: started", unit.label()));
    let t0 = Instant::now();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        execute(engine, manifest, unit, out, progress)
    }))
    .unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        Err(UnitError::Panic(what))
    });
    let wall_s = t0.elapsed().as_secs_f64();
    let status = match result {
        Ok(message) => UnitStatus::new(dataset, task, State::Done, message, wall_s),
        Err(e) => UnitStatus::new(dataset, task, State::Failed, e.to_string(), wall_s),
    };
    write(&status)?;
    Ok(status)
}

/// Writes what a unit's fit said before fitting (`notes`: a catalogue's pinning, its
/// displacement) to the unit's `fit.log`, and one progress line pointing there; nothing
/// without notes.
fn write_notes(
    folder: &Path,
    notes: &[String],
    progress: &BatchProgress,
    label: &str,
) -> Result<(), UnitError> {
    if notes.is_empty() {
        return Ok(());
    }
    let path = folder.join("fit.log");
    let text: String = notes.iter().map(|l| format!("{l}\n")).collect();
    crate::io::write_atomic(&path, text.as_bytes()).map_err(|source| UnitError::Io {
        path: path.clone(),
        source,
    })?;
    progress.line(&format!("{label}: {}: see {}", notes[0], path.display()));
    Ok(())
}

/// Does a unit's work through the same task function as its command; the result in one
/// line for the status file and the summary.
fn execute(
    engine: &Engine,
    manifest: &Manifest,
    unit: &Unit,
    out: &Path,
    progress: &BatchProgress,
) -> Result<String, UnitError> {
    let folder = unit.folder(out);
    let observer = progress.unit(&unit.label());
    match unit.task {
        TaskKind::Fit => {
            let mut options = manifest.fit.clone();
            // A fit interrupted before resumes from the starts it finished.
            options.resume = true;
            let settings = options.check().map_err(FitError::from)?;
            let paths = FitPaths::beside(&folder.join("fit.json"));
            let ds = crate::data::dataset::Dataset::load(&unit.path).map_err(FitError::from)?;
            let fitted = fit_dataset(engine, ds, &settings, Some(paths.starts.clone()), &observer);
            write_notes(&folder, &observer.take_notes(), progress, &unit.label())?;
            let fitted = fitted?;
            write_fit_to(&fitted, &paths, manifest.fit_plots)?;
            Ok(match &fitted.outcome.goodness {
                Some(g) => format!(
                    "cost J {:.4}, noise ratio {:.3} (limit {:.3})",
                    fitted.outcome.cost, g.noise_ratio, g.noise_ratio_limit
                ),
                None => format!("cost J {:.4}", fitted.outcome.cost),
            })
        }
        TaskKind::Diagnose => {
            let settings = manifest.diagnose.check().map_err(DiagnoseTaskError::from)?;
            let d = diagnose_to(engine, &unit.path, &settings, &observer, &folder)?;
            let (before, after) = d.noise_ratios();
            Ok(if d.selected.is_empty() && !d.mismatch {
                format!("no mismatch (noise ratio {before:.3})")
            } else {
                let names: Vec<&str> = d.selected.iter().map(|s| s.effect.as_str()).collect();
                format!(
                    "mismatch: {} (noise ratio {before:.3} -> {after:.3})",
                    if names.is_empty() {
                        "nothing selected".to_string()
                    } else {
                        names.join(" + ")
                    }
                )
            })
        }
        TaskKind::Predict => {
            let fit_folder = out.join(&unit.dataset).join(TaskKind::Fit.id());
            match UnitStatus::read(&fit_folder).map(|s| s.status) {
                Some(State::Done) => {}
                other => {
                    return Err(UnitError::NoFit(
                        other.unwrap_or(State::Pending).id().into(),
                    ))
                }
            }
            let p = predict_to(&fit_folder.join("fit.json"), &manifest.predict, &folder)?;
            Ok(format!(
                "{} pressure(s), {} file(s)",
                p.prediction.pressures.len(),
                p.written.len()
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn unit(dataset: &str, task: TaskKind, group: usize) -> Unit {
        Unit {
            dataset: dataset.into(),
            path: PathBuf::from(dataset),
            task,
            group,
        }
    }

    /// The plan of `tasks = ["fit", "diagnose", "predict"]`: each predict runs in its fit's
    /// group, after the fit, whatever lies between them in the plan.
    #[test]
    fn a_predict_runs_after_its_fit_in_one_group() {
        let plan = vec![
            unit("a", TaskKind::Fit, 0),
            unit("a", TaskKind::Diagnose, 1),
            unit("a", TaskKind::Predict, 0),
            unit("b", TaskKind::Fit, 2),
            unit("b", TaskKind::Diagnose, 3),
            unit("b", TaskKind::Predict, 2),
        ];
        let labels: Vec<Vec<String>> = by_group(plan)
            .iter()
            .map(|g| g.iter().map(Unit::label).collect())
            .collect();
        assert_eq!(
            labels,
            [
                vec!["a/fit", "a/predict"],
                vec!["a/diagnose"],
                vec!["b/fit", "b/predict"],
                vec!["b/diagnose"],
            ]
        );
    }
}
