//! Outputs checked before work: every command that writes calls [`prepare_file`] or
//! [`prepare_dir`] before it computes, so an unwritable `--out`, an `--out` that is a folder
//! where a file is wanted (or the reverse), or a parent path that is a file fails in a
//! moment with a message naming the path, not after a 20-second diagnosis.
//!
//! A missing output folder (or a fit file's missing parent folder) is created, and the
//! command says so on stderr: batch scripts on clusters name fresh folders, and refusing them
//! would only move the `mkdir` into every script. It is done before the work and said on
//! stderr.
//!
//! Both return the output's [`OutputLock`], held until the command ends.

use super::lock::{LockError, OutputLock};
use std::path::{Path, PathBuf};

/// Why an output cannot be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// A file output names an existing folder.
    #[error("{}: is a folder, not a file", .0.display())]
    IsDir(PathBuf),
    /// A folder output names an existing file.
    #[error("{}: is a file, not a folder", .0.display())]
    IsFile(PathBuf),
    /// A parent of the output is a file.
    #[error("{}: cannot write here: {} is a file, not a folder", path.display(), file.display())]
    ParentIsFile {
        /// The output.
        path: PathBuf,
        /// The file in its way.
        file: PathBuf,
    },
    /// A missing folder cannot be created.
    #[error("{}: cannot create the folder: {source}", path.display())]
    Create {
        /// The folder.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// The folder exists but this run cannot write into it.
    #[error("{}: cannot write into this folder: {source}", path.display())]
    NotWritable {
        /// The folder.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// Another run writes the same output.
    #[error("{}: {source}", path.display())]
    InUse {
        /// The output.
        path: PathBuf,
        /// The lock held by the other run.
        source: LockError,
    },
}

/// The lock file of a file output: `<path without extension>.lock` beside it.
fn lock_path_of_file(path: &Path) -> PathBuf {
    let stem = path.with_extension("");
    PathBuf::from(format!("{}.lock", stem.display()))
}

/// The lock file of a folder output: `.vanefit.lock` inside it.
fn lock_path_of_dir(dir: &Path) -> PathBuf {
    dir.join(".vanefit.lock")
}

/// Checks that the file `path` can be written (its folder exists or is created, and is
/// writable; `path` is not a folder) and locks it for this run.
pub fn prepare_file(path: &Path) -> Result<OutputLock, OutputError> {
    if path.is_dir() {
        return Err(OutputError::IsDir(path.to_path_buf()));
    }
    let parent = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    ensure_dir(parent, path)?;
    lock(&lock_path_of_file(path), parent, path)
}

/// Checks, without writing anything, that the folder `dir` could be written: it is not a
/// file and no parent of it is one (for commands that promise to write nothing when an input
/// is bad, and so create their folder only once the work is done).
pub fn check_dir(dir: &Path) -> Result<(), OutputError> {
    if dir.exists() && !dir.is_dir() {
        return Err(OutputError::IsFile(dir.to_path_buf()));
    }
    match dir.ancestors().find(|a| a.is_file()) {
        Some(file) => Err(OutputError::ParentIsFile {
            path: dir.to_path_buf(),
            file: file.to_path_buf(),
        }),
        None => Ok(()),
    }
}

/// Checks that the folder `dir` can be written (it exists or is created, and is writable)
/// and locks it for this run.
pub fn prepare_dir(dir: &Path) -> Result<OutputLock, OutputError> {
    if dir.exists() && !dir.is_dir() {
        return Err(OutputError::IsFile(dir.to_path_buf()));
    }
    ensure_dir(dir, dir)?;
    lock(&lock_path_of_dir(dir), dir, dir)
}

/// Creates `dir` if missing (saying so), after checking that no parent of it is a file.
fn ensure_dir(dir: &Path, output: &Path) -> Result<(), OutputError> {
    if dir.is_dir() {
        return Ok(());
    }
    if let Some(file) = dir.ancestors().find(|a| a.is_file()) {
        return Err(OutputError::ParentIsFile {
            path: output.to_path_buf(),
            file: file.to_path_buf(),
        });
    }
    std::fs::create_dir_all(dir).map_err(|source| OutputError::Create {
        path: dir.to_path_buf(),
        source,
    })?;
    eprintln!("created folder {} (it did not exist)", dir.display());
    Ok(())
}

/// Takes the lock; a failure to create the lock file means the folder is not writable.
fn lock(lock_file: &Path, dir: &Path, output: &Path) -> Result<OutputLock, OutputError> {
    match OutputLock::acquire(lock_file) {
        Ok(l) => {
            if let Some(pid) = l.took_over {
                eprintln!(
                    "took over the lock file {} of pid {pid}, which is no longer running",
                    lock_file.display()
                );
            }
            Ok(l)
        }
        Err(LockError::Io { source, .. }) => Err(OutputError::NotWritable {
            path: dir.to_path_buf(),
            source,
        }),
        Err(source) => Err(OutputError::InUse {
            path: output.to_path_buf(),
            source,
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parent_that_is_a_file_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("f");
        std::fs::write(&f, "x").unwrap();
        let e = prepare_file(&f.join("sub/fit.json"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a file, not a folder"), "{e}");
        assert!(e.contains(&f.display().to_string()), "{e}");
        let e = prepare_dir(&f).unwrap_err().to_string();
        assert!(e.ends_with("f: is a file, not a folder"), "{e}");
    }

    #[test]
    fn folder_as_file_output_is_refused_and_missing_parent_created() {
        let dir = tempfile::tempdir().unwrap();
        let e = prepare_file(dir.path()).unwrap_err().to_string();
        assert!(e.contains("is a folder, not a file"), "{e}");
        let out = dir.path().join("new/fit.json");
        let l = prepare_file(&out).unwrap();
        assert!(dir.path().join("new").is_dir());
        assert_eq!(l.path(), dir.path().join("new/fit.lock"));
    }
}
