//! Temporaries of runs that died. [`super::write_atomic`] writes `.<name>.tmp<pid>-<host>`
//! and renames it; a run killed (SIGKILL, a Slurm time limit, power loss) between the two
//! leaves the temporary behind, and nothing else ever would remove it. The first atomic
//! write of a later run into a folder removes the temporaries there whose writer is gone.
//!
//! Only files of this naming scheme are touched, and only those that cannot be in use:
//! the writer's pid must not be running on this host. A temporary of another host (a
//! cluster's shared file system, where shards on other nodes write into one batch folder)
//! is left alone, since a pid of another node means nothing here. A pid that a new process
//! has taken since keeps its stale file: erring that way never breaks a live write.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

/// The temporary [`super::write_atomic`] uses for the file `name`: hidden, and naming
/// this process and host so that a later run can tell whether its writer is gone.
pub fn temporary_name(name: &str) -> String {
    format!(".{name}.tmp{}-{}", std::process::id(), host())
}

/// This machine's host name (empty where it cannot be had), as written in temporaries.
fn host() -> &'static str {
    static HOST: OnceLock<String> = OnceLock::new();
    HOST.get_or_init(|| {
        let mut buf = [0u8; 256];
        // SAFETY: gethostname(2) writes at most `buf.len()` bytes into the buffer we own.
        let rc = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
        if rc != 0 {
            return String::new();
        }
        let len = buf.iter().position(|b| *b == 0).unwrap_or(buf.len());
        // A host name is letters, digits, '-' and '.'; anything else is not written into
        // file names.
        String::from_utf8_lossy(&buf[..len])
            .chars()
            .filter(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '.')
            .collect()
    })
}

/// The writer of a temporary file name of this scheme: its pid and host (`None` for a name
/// of another scheme). Names of the earlier scheme, `.<name>.tmp<pid>`, give no host.
fn writer(file_name: &str) -> Option<(u32, Option<&str>)> {
    let rest = file_name.strip_prefix('.')?;
    let at = rest.rfind(".tmp")?;
    if at == 0 {
        return None;
    }
    let suffix = &rest[at + 4..];
    let (pid, host) = match suffix.split_once('-') {
        Some((pid, host)) => (pid, Some(host)),
        None => (suffix, None),
    };
    if pid.is_empty() || !pid.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some((pid.parse().ok()?, host))
}

/// Whether process `pid` runs on this host (a process of another user counts).
#[cfg(unix)]
fn running(pid: u32) -> bool {
    let Ok(pid) = libc::pid_t::try_from(pid) else {
        return false;
    };
    if pid <= 0 {
        return true; // not a process: never treated as gone
    }
    // SAFETY: kill(2) with signal 0 only checks that the process exists; nothing is sent.
    let rc = unsafe { libc::kill(pid, 0) };
    rc == 0 || std::io::Error::last_os_error().raw_os_error() != Some(libc::ESRCH)
}

/// Elsewhere a writer cannot be checked: it is assumed to run.
#[cfg(not(unix))]
fn running(_pid: u32) -> bool {
    true
}

/// Removes the temporaries in `dir` whose writer is gone (see the module documentation);
/// returns the files removed. Errors (an unreadable folder, a file removed meanwhile by
/// another run) are not the caller's business: the write that follows reports its own.
fn remove_stale(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let me = std::process::id();
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name();
        let Some((pid, their_host)) = name.to_str().and_then(writer) else {
            continue;
        };
        let local = their_host.is_none_or(|h| h == host());
        if !local || pid == me || running(pid) {
            continue;
        }
        if e.file_type().is_ok_and(|t| t.is_file()) && std::fs::remove_file(e.path()).is_ok() {
            removed.push(e.path());
        }
    }
    removed
}

/// [`remove_stale`] of `dir`, once per folder in this process (a run writes many files
/// into one folder; one look is enough).
pub(crate) fn remove_once(dir: &Path) {
    static SEEN: OnceLock<Mutex<HashSet<PathBuf>>> = OnceLock::new();
    let seen = SEEN.get_or_init(Default::default);
    let first = seen
        .lock()
        .map(|mut s| s.insert(dir.to_path_buf()))
        .unwrap_or(false);
    if first {
        remove_stale(dir);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_of_this_scheme_give_their_writer() {
        assert_eq!(writer(".fit.json.tmp123-node7"), Some((123, Some("node7"))));
        assert_eq!(writer(".fit.json.tmp123"), Some((123, None)));
        assert_eq!(writer(".a.tmp.tmp9-h.x"), Some((9, Some("h.x"))));
        for other in [
            "fit.json.tmp1",
            ".tmp1",
            ".x.tmp",
            ".x.tmpab-h",
            ".x.tmp-1-h",
        ] {
            assert_eq!(writer(other), None, "{other}");
        }
        let mine = temporary_name("fit.json");
        assert_eq!(writer(&mine), Some((std::process::id(), Some(host()))));
    }

    #[test]
    fn only_temporaries_of_gone_writers_on_this_host_are_removed() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        // A pid above the kernel's limit (2^22) has no process.
        let gone = format!(".fit.json.tmp4194305-{}", host());
        let parent = std::os::unix::process::parent_id();
        let keep = [
            temporary_name("mine.json"),
            format!(".live.json.tmp{parent}-{}", host()),
            ".other.json.tmp4194305-another-host".to_string(),
            "fit.json".to_string(),
            "notes.tmp4194305".to_string(),
        ];
        for f in keep
            .iter()
            .chain([&gone, &".old.json.tmp4194305".to_string()])
        {
            std::fs::write(d.join(f), "x").unwrap();
        }
        let mut removed = remove_stale(d);
        removed.sort();
        assert_eq!(removed, vec![d.join(&gone), d.join(".old.json.tmp4194305")]);
        for f in &keep {
            assert!(d.join(f).exists(), "{f} kept");
        }
    }
}
