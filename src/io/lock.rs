//! One run per output: a lock file beside the output, holding the owner's pid.
//!
//! Two `fit --out X` at once would interleave their starts in one results file, so the
//! second run finds the lock and stops before any work. The lock is an OS file lock
//! (`flock`) on `<output>.lock`, so a run killed with `SIGKILL` cannot leave a lock that
//! blocks the next run: the OS drops the lock with the process, and the next run takes the
//! file over (saying whose pid it held). The pid in the file is for people and messages.

use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Why an output cannot be locked.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LockError {
    /// Another live run holds the lock.
    #[error("output in use by pid {pid} (lock file {})", path.display())]
    InUse {
        /// The owner's pid as written in the lock file (0 if not yet written).
        pid: u32,
        /// The lock file.
        path: PathBuf,
    },
    /// The lock file cannot be created or written (an unwritable folder, a full disk).
    #[error("{}: cannot create the lock file: {source}", path.display())]
    Io {
        /// The lock file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
}

/// A held output lock; dropping it (on every exit path, panics included) removes the file
/// and releases the lock.
#[derive(Debug)]
pub struct OutputLock {
    /// Kept open: the OS lock lives as long as this descriptor.
    _file: File,
    path: PathBuf,
    /// The pid of a dead run whose lock file this run took over, if any.
    pub(crate) took_over: Option<u32>,
}

impl OutputLock {
    /// Locks `path` (the lock file itself) for this process.
    pub fn acquire(path: &Path) -> Result<Self, LockError> {
        let io = |source| LockError::Io {
            path: path.to_path_buf(),
            source,
        };
        // A holder may remove the file between our open and our lock; then we locked a file
        // nobody else sees and try again on the new one.
        for _ in 0..16 {
            let mut file = OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(path)
                .map_err(io)?;
            let previous = read_pid(&mut file);
            if !try_lock(&file).map_err(io)? {
                return Err(LockError::InUse {
                    pid: previous.unwrap_or(0),
                    path: path.to_path_buf(),
                });
            }
            if !same_file(&file, path) {
                continue;
            }
            let me = std::process::id();
            if let Err(e) = write_pid(&mut file, me) {
                // Held by us and useless (a full disk): not left behind.
                let _ = std::fs::remove_file(path);
                return Err(io(e));
            }
            return Ok(OutputLock {
                _file: file,
                path: path.to_path_buf(),
                took_over: previous.filter(|p| *p != me),
            });
        }
        Err(io(std::io::Error::other(
            "the lock file keeps changing under this run",
        )))
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        // Removed before the file is closed (which releases the lock), so a waiting run
        // re-opens a fresh file (see `acquire`).
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Takes the OS lock of `file` without waiting: `false` when another process holds it.
#[cfg(unix)]
fn try_lock(file: &File) -> std::io::Result<bool> {
    use std::os::unix::io::AsRawFd;
    // SAFETY: flock(2) on a descriptor this `File` owns and keeps open; no memory is shared.
    let rc = unsafe { libc::flock(file.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    if rc == 0 {
        return Ok(true);
    }
    let e = std::io::Error::last_os_error();
    match e.raw_os_error() {
        Some(code) if code == libc::EWOULDBLOCK => Ok(false),
        _ => Err(e),
    }
}

/// Elsewhere there is no OS lock: the lock file only names the owner.
#[cfg(not(unix))]
fn try_lock(_file: &File) -> std::io::Result<bool> {
    Ok(true)
}

/// Replaces the lock file's content by `pid`.
fn write_pid(file: &mut File, pid: u32) -> std::io::Result<()> {
    file.set_len(0)?;
    file.seek(SeekFrom::Start(0))?;
    writeln!(file, "{pid}")?;
    file.sync_all()
}

/// The pid written in a lock file, if any.
fn read_pid(file: &mut File) -> Option<u32> {
    let mut text = String::new();
    file.read_to_string(&mut text).ok()?;
    text.trim().parse().ok()
}

/// Whether `path` still names the file `file` is open on.
#[cfg(unix)]
fn same_file(file: &File, path: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (file.metadata(), std::fs::metadata(path)) {
        (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
        _ => false,
    }
}

/// Whether `path` still names the file `file` is open on (assumed elsewhere).
#[cfg(not(unix))]
fn same_file(_file: &File, path: &Path) -> bool {
    path.exists()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn second_holder_is_refused_and_lock_goes_with_drop() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.lock");
        let a = OutputLock::acquire(&p).unwrap();
        assert_eq!(a.took_over, None);
        let e = OutputLock::acquire(&p).unwrap_err().to_string();
        assert!(
            e.contains(&format!("output in use by pid {}", std::process::id())),
            "{e}"
        );
        drop(a);
        assert!(!p.exists());
        OutputLock::acquire(&p).unwrap();
    }

    #[test]
    fn stale_lock_file_of_a_dead_run_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.lock");
        std::fs::write(&p, "4000000\n").unwrap();
        let a = OutputLock::acquire(&p).unwrap();
        assert_eq!(a.took_over, Some(4_000_000));
        let pid: u32 = std::fs::read_to_string(&p).unwrap().trim().parse().unwrap();
        assert_eq!(pid, std::process::id());
    }
}
