//! `vanefit batch --slurm`: the shards as a Slurm job array, and a merge job that runs when
//! every array task has ended well (`--dependency=afterok`). The scripts are written into
//! `<out>/slurm/` next to the results, so that they can be read, edited and resubmitted by
//! hand. A task requeued after a time limit, a node failure or preemption (`--requeue`)
//! runs its shard again: finished units are skipped and an interrupted fit resumes from its
//! starts file; its log is appended to (`--open-mode=append`), not overwritten.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// How to submit.
#[derive(Debug, Clone, Default)]
pub struct SlurmOptions {
    /// `--partition`.
    pub partition: Option<String>,
    /// `--time` of each array task (Slurm's formats, e.g. `2:00:00`).
    pub time: Option<String>,
    /// `--cpus-per-task`, also the thread count of each shard (default 1).
    pub cpus_per_task: Option<usize>,
    /// At most this many array tasks at once (`--array=1-N%L`).
    pub array_limit: Option<usize>,
    /// Number of array tasks (shards).
    pub shards: usize,
    /// Wait for the merge job to end (`sbatch --wait`).
    pub wait: bool,
}

/// Why submitting failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SlurmError {
    /// `sbatch` could not be started.
    #[error("cannot run sbatch ({0}): is Slurm installed and sbatch on PATH?")]
    NoSbatch(std::io::Error),
    /// `sbatch` refused the job.
    #[error("sbatch {script} failed: {message}")]
    Refused {
        /// The script submitted.
        script: String,
        /// What sbatch said.
        message: String,
    },
    /// A script cannot be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The script.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// What was submitted.
#[derive(Debug, Clone)]
pub struct Submitted {
    /// The array's job id.
    pub array_job: String,
    /// The merge job's id.
    pub merge_job: String,
    /// The array script.
    pub array_script: PathBuf,
    /// The merge script.
    pub merge_script: PathBuf,
    /// With `wait`: whether the merge job ended well (`sbatch --wait`'s status was 0).
    pub merge_ok: Option<bool>,
}

/// A word for `sh`, quoted.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The `#SBATCH` lines the options ask for.
fn resource_lines(opts: &SlurmOptions) -> String {
    let mut s = String::new();
    if let Some(p) = &opts.partition {
        s += &format!("#SBATCH --partition={p}\n");
    }
    if let Some(t) = &opts.time {
        s += &format!("#SBATCH --time={t}\n");
    }
    s
}

/// The array script: task `i` runs shard `i/N`; failed units do not fail the task (they
/// are recorded, and the merge reports them), so the merge job still runs.
pub fn array_script(exe: &Path, manifest: &Path, out: &Path, opts: &SlurmOptions) -> String {
    let cpus = opts.cpus_per_task.unwrap_or(1);
    let n = opts.shards;
    let limit = opts
        .array_limit
        .map(|l| format!("%{l}"))
        .unwrap_or_default();
    let log = out.join("slurm").join("shard-%a.log");
    format!(
        "#!/bin/sh\n\
         # vanefit batch as a Slurm job array: task i runs shard i/{n}. Written by `vanefit batch --slurm`.\n\
         #SBATCH --job-name=vanefit-batch\n\
         #SBATCH --array=1-{n}{limit}\n\
         #SBATCH --cpus-per-task={cpus}\n\
         {res}#SBATCH --output={log}\n\
         #SBATCH --open-mode=append\n\
         #SBATCH --requeue\n\
         echo \"vanefit shard ${{SLURM_ARRAY_TASK_ID}}/{n} on $(hostname), job ${{SLURM_JOB_ID}}, restart ${{SLURM_RESTART_COUNT:-0}}\" >&2\n\
         exec {exe} batch {manifest} --out {out} --shard \"${{SLURM_ARRAY_TASK_ID}}/{n}\" --threads {cpus} --allow-failed-units\n",
        res = resource_lines(opts),
        log = log.display(),
        exe = quote(&exe.to_string_lossy()),
        manifest = quote(&manifest.to_string_lossy()),
        out = quote(&out.to_string_lossy()),
    )
}

/// The merge script.
pub fn merge_script(exe: &Path, out: &Path, opts: &SlurmOptions) -> String {
    format!(
        "#!/bin/sh\n\
         # vanefit merge of the batch, after every array task ended well. Written by `vanefit batch --slurm`.\n\
         #SBATCH --job-name=vanefit-merge\n\
         #SBATCH --cpus-per-task=1\n\
         {res}#SBATCH --output={log}\n\
         #SBATCH --open-mode=append\n\
         exec {exe} merge {out}\n",
        res = resource_lines(&SlurmOptions {
            time: None,
            ..opts.clone()
        }),
        log = out.join("slurm").join("merge.log").display(),
        exe = quote(&exe.to_string_lossy()),
        out = quote(&out.to_string_lossy()),
    )
}

/// Runs `sbatch --parsable <args> <script>` and returns the job id (the first field of its
/// output); with `wait`, reports the id as soon as sbatch prints it, then waits for the job.
fn sbatch(
    args: &[String],
    script: &Path,
    on_id: &dyn Fn(&str),
) -> Result<(String, bool), SlurmError> {
    let mut child = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .arg(script)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(SlurmError::NoSbatch)?;
    let mut first = String::new();
    if let Some(stdout) = child.stdout.take() {
        BufReader::new(stdout).read_line(&mut first).ok();
    }
    let id = first.trim().split(';').next().unwrap_or("").to_string();
    if !id.is_empty() {
        on_id(&id);
    }
    let output = child.wait_with_output().map_err(SlurmError::NoSbatch)?;
    let refused = || SlurmError::Refused {
        script: script.display().to_string(),
        message: String::from_utf8_lossy(&output.stderr).trim().to_string(),
    };
    if id.is_empty() {
        return Err(refused());
    }
    Ok((id, output.status.success()))
}

/// Writes the scripts into `<out>/slurm/` and submits the array and the merge job;
/// `on_id(what, id)` hears each job id as soon as it is known (before a `wait`).
pub fn submit(
    exe: &Path,
    manifest: &Path,
    out: &Path,
    opts: &SlurmOptions,
    on_id: &dyn Fn(&str, &str),
) -> Result<Submitted, SlurmError> {
    let dir = out.join("slurm");
    let write = |name: &str, text: String| {
        let path = dir.join(name);
        crate::io::write_atomic(&path, text.as_bytes())
            .map(|()| path.clone())
            .map_err(|source| SlurmError::Write { path, source })
    };
    let array_script = write("batch.sbatch", array_script(exe, manifest, out, opts))?;
    let merge_script = write("merge.sbatch", merge_script(exe, out, opts))?;
    let (array_job, _) = sbatch(&[], &array_script, &|id| on_id("array", id))?;
    let mut args = vec![
        format!("--dependency=afterok:{array_job}"),
        "--kill-on-invalid-dep=yes".to_string(),
    ];
    if opts.wait {
        args.push("--wait".into());
    }
    let (merge_job, ok) = sbatch(&args, &merge_script, &|id| on_id("merge", id))?;
    if !opts.wait && !ok {
        return Err(SlurmError::Refused {
            script: merge_script.display().to_string(),
            message: "sbatch ended with an error".into(),
        });
    }
    Ok(Submitted {
        array_job,
        merge_job,
        array_script,
        merge_script,
        merge_ok: opts.wait.then_some(ok),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The array script runs shard i/N with the requeue and append settings.
    #[test]
    fn array_script_runs_its_shard() {
        let opts = SlurmOptions {
            shards: 4,
            array_limit: Some(2),
            partition: Some("short".into()),
            ..Default::default()
        };
        let s = array_script(
            Path::new("/bin/vanefit"),
            Path::new("/m it's.toml"),
            Path::new("/out"),
            &opts,
        );
        for want in [
            "#SBATCH --array=1-4%2\n",
            "#SBATCH --requeue\n",
            "#SBATCH --open-mode=append\n",
            "#SBATCH --partition=short\n",
            "--shard \"${SLURM_ARRAY_TASK_ID}/4\"",
            r"'/m it'\''s.toml'",
        ] {
            assert!(s.contains(want), "{want} missing from\n{s}");
        }
    }
}
