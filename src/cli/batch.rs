//! `vanefit batch` and `vanefit merge` (docs/cli.md, "batch" and "merge"): the options and what is printed;
//! the work is `batch`.

use crate::cli::Failure;
use std::path::PathBuf;
use vanefit::batch;
use vanefit::batch::{submit, SlurmOptions};
use vanefit::batch::{BatchOptions, Manifest, Shard};

/// `vanefit batch` options.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct BatchArgs {
    /// The manifest (TOML): `[batch] datasets = [globs] tasks = [...]` and a table per task.
    pub(crate) manifest: PathBuf,
    /// The batch folder: one folder per unit (`<dataset>/<task>/`), `batch.json`, the summary.
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Run only shard i of N (1-based), e.g. `--shard 2/8`; the union of the N shards is the
    /// whole batch, and each unit's result is the same whatever N.
    #[arg(long, conflicts_with = "slurm")]
    pub(crate) shard: Option<Shard>,
    /// Worker threads (default: one per core); results do not depend on it.
    #[arg(long)]
    pub(crate) threads: Option<usize>,
    /// Run units that failed in an earlier run again (by default they count as finished).
    #[arg(long)]
    pub(crate) retry_failed: bool,
    /// Exit 0 when units failed (their failures are recorded); a Slurm array task uses it
    /// so that the merge job (afterok) still runs and reports them.
    #[arg(long)]
    pub(crate) allow_failed_units: bool,
    /// Submit the shards to Slurm as a job array, and a merge job after them.
    #[arg(long)]
    pub(crate) slurm: bool,
    /// Slurm partition.
    #[arg(long, requires = "slurm")]
    pub(crate) partition: Option<String>,
    /// Time limit of each array task (e.g. `2:00:00`); a task stopped by it and requeued
    /// continues where it stopped.
    #[arg(long, requires = "slurm")]
    pub(crate) time: Option<String>,
    /// CPUs (threads) of each array task.
    #[arg(long, requires = "slurm")]
    pub(crate) cpus_per_task: Option<usize>,
    /// At most this many array tasks at once.
    #[arg(long, requires = "slurm")]
    pub(crate) array_limit: Option<usize>,
    /// Number of array tasks (default: as many as the batch can use).
    #[arg(long, requires = "slurm")]
    pub(crate) shards: Option<usize>,
    /// Wait until the merge job has ended; exit 1 unless it ended well.
    #[arg(long, requires = "slurm")]
    pub(crate) wait: bool,
}

/// `vanefit merge` options.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct MergeArgs {
    /// The batch folder (`--out` of `vanefit batch`).
    pub(crate) dir: PathBuf,
}

/// `vanefit batch`: the shard here, or the whole batch submitted to Slurm.
pub(crate) fn run(args: &BatchArgs) -> Result<(), Failure> {
    for (option, v) in [
        ("--threads", args.threads),
        ("--cpus-per-task", args.cpus_per_task),
        ("--array-limit", args.array_limit),
        ("--shards", args.shards),
    ] {
        if v == Some(0) {
            return Err(Failure(format!("{option} must be at least 1")));
        }
    }
    let manifest = Manifest::load(&args.manifest)?;
    if args.slurm {
        return slurm(&manifest, args);
    }
    let settings = BatchOptions {
        out: args.out.clone(),
        shard: args.shard.unwrap_or(Shard::ALL),
        threads: args.threads,
        retry_failed: args.retry_failed,
    }
    .check()
    .map_err(Failure::option)?;
    let o = settings.run(&manifest)?;
    say!(
        "batch shard {}: {} unit(s): {} done now, {} finished before (skipped), {} failed",
        settings.shard(),
        o.units,
        o.done,
        o.skipped,
        o.failed.len()
    );
    for (unit, why) in &o.failed {
        say!("  failed {unit}: {why}");
    }
    if !o.failed.is_empty() && !args.allow_failed_units {
        return Err(Failure(format!(
            "{} of {} unit(s) failed (recorded in their status.json; `vanefit merge {}` lists them)",
            o.failed.len(),
            o.units,
            args.out.display()
        )));
    }
    Ok(())
}

/// `--slurm`: record the batch, write the scripts, submit, say how to watch.
fn slurm(manifest: &Manifest, args: &BatchArgs) -> Result<(), Failure> {
    let record = batch::BatchRecord::of(manifest);
    record.claim(&args.out)?;
    let out = std::fs::canonicalize(&args.out)
        .map_err(|e| Failure(format!("{}: {e}", args.out.display())))?;
    let groups = batch::plan::groups(&record.units);
    let opts = SlurmOptions {
        partition: args.partition.clone(),
        time: args.time.clone(),
        cpus_per_task: args.cpus_per_task,
        array_limit: args.array_limit,
        shards: args.shards.unwrap_or(groups).min(groups).max(1),
        wait: args.wait,
    };
    let exe = std::env::current_exe().map_err(|e| Failure(format!("vanefit's own path: {e}")))?;
    let submitted = std::time::SystemTime::now();
    let s = submit(&exe, &manifest.path, &out, &opts, &|what, id| {
        say!("submitted {what} job {id}");
        if what == "merge" {
            say!(
                "watch: squeue -j {id}; sacct -j {id}; logs in {}",
                out.join("slurm").display()
            );
        }
    })?;
    say!(
        "array {} ({} task(s), {}), merge {} after it ({})",
        s.array_job,
        opts.shards,
        s.array_script.display(),
        s.merge_job,
        s.merge_script.display()
    );
    say!(
        "watch: squeue -j {},{}   sacct -j {},{}",
        s.array_job,
        s.merge_job,
        s.array_job,
        s.merge_job
    );
    match s.merge_ok {
        Some(false) if merged_since(&out, submitted) => Err(Failure(format!(
            "the merge job {} ran and found failed or unfinished units: see {}",
            s.merge_job,
            out.join("summary.md").display()
        ))),
        Some(false) => Err(Failure(format!(
            "the merge job {} did not run or failed (an array task failed or was cancelled?): see sacct -j {},{} and the logs in {}",
            s.merge_job,
            s.array_job,
            s.merge_job,
            out.join("slurm").display()
        ))),
        Some(true) => {
            say!("merged: {}", out.join("summary.csv").display());
            Ok(())
        }
        None => Ok(()),
    }
}

/// Whether a merge wrote `summary.csv` after `since` (the merge job ran).
fn merged_since(out: &std::path::Path, since: std::time::SystemTime) -> bool {
    std::fs::metadata(out.join("summary.csv"))
        .and_then(|m| m.modified())
        .is_ok_and(|t| t >= since)
}

/// `vanefit merge`: the summary files; exit 1 when units failed or are unfinished.
pub(crate) fn merge(args: &MergeArgs) -> Result<(), Failure> {
    let o = batch::merge(&args.dir)?;
    for p in &o.written {
        say!("wrote {}", p.display());
    }
    say!(
        "{} unit(s): {} done, {} failed, {} unfinished",
        o.units,
        o.done,
        o.failed.len(),
        o.unfinished.len()
    );
    for (unit, why) in &o.failed {
        say!("  failed {unit}: {why}");
    }
    for unit in &o.unfinished {
        say!("  unfinished {unit}");
    }
    let bad = o.failed.len() + o.unfinished.len();
    if bad > 0 {
        return Err(Failure(format!(
            "{} failed and {} unfinished of {} unit(s)",
            o.failed.len(),
            o.unfinished.len(),
            o.units
        )));
    }
    Ok(())
}
