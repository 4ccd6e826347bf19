//! File-system helpers: never lose work, never run twice into the same output, and never
//! die because stdout was closed.

pub(crate) mod lock;
pub(crate) mod out;
pub(crate) mod stale;

pub use lock::{LockError, OutputLock};
pub use out::{check_dir, prepare_dir, prepare_file, OutputError};
pub use stale::temporary_name;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

/// Where a run's side files go: `<out without .json>.<suffix>` (`fit.json` →
/// `fit.report.md`, `fit.starts.jsonl`).
pub fn side_path(out: &Path, suffix: &str) -> PathBuf {
    let stem = out.with_extension("");
    PathBuf::from(format!("{}.{suffix}", stem.display()))
}

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, synced, then
/// renamed over the target, so that a reader sees either the old or the new file, never half.
/// The temporary file is removed again when any step fails (a full disk, a folder that
/// vanished), so a failed write leaves nothing behind. A missing folder is created, but
/// commands create and check their output folders before they compute (see `out`).
/// A run killed between creating and renaming its temporary cannot remove it; the first
/// atomic write of a later run into the folder does (`stale`).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    stale::remove_once(dir);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(stale::temporary_name(&name));
    let written = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if written.is_err() {
        // Best effort: the error that matters is the write's, not the clean-up's.
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// Set once stdout is found closed (`vanefit … | head`): later lines are dropped silently.
static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);
/// Set once another stdout error has been reported, so it is reported once only.
static STDOUT_FAILED: AtomicBool = AtomicBool::new(false);

/// Writes one line to stdout, as `println!` does, but without panicking when stdout is
/// closed: a reader that stops early (`| head -1`) must not stop the command before it has
/// written its files. A broken pipe silences stdout for the rest of the run; any other
/// error is reported once on stderr and the command carries on. Called through the command line's `say!` macro.
pub fn say_line(args: std::fmt::Arguments<'_>) {
    if STDOUT_CLOSED.load(Ordering::Relaxed) {
        return;
    }
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_fmt(format_args!("{args}\n")) {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            STDOUT_CLOSED.store(true, Ordering::Relaxed);
        } else if !STDOUT_FAILED.swap(true, Ordering::Relaxed) {
            eprintln!("warning: stdout: {e}; the command goes on, its files are written");
        }
    }
}
