//! Disk faults: output into a read-only file system, under a missing parent and
//! onto a full one. Each ends with a message naming the path, exit status 1, no temporary
//! or lock file left and earlier results intact. The file systems are small tmpfs mounts,
//! which need root: without it the test says loudly that it did not run.

use crate::common;
use common::{stderr, vanefit, DATASET};

use std::path::{Path, PathBuf};
use std::process::Command;

/// A tmpfs mounted for the test, unmounted when dropped.
struct Mount(PathBuf);

impl Mount {
    fn new(at: &Path, options: &str) -> Option<Mount> {
        std::fs::create_dir_all(at).unwrap();
        let ok = Command::new("mount")
            .args(["-t", "tmpfs", "-o", options, "tmpfs"])
            .arg(at)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            eprintln!(
                "\n*** disk_faults: SKIPPED: cannot mount a tmpfs at {} (needs root); \
                 the full and read-only file system cases did not run ***\n",
                at.display()
            );
        }
        ok.then(|| Mount(at.to_path_buf()))
    }
}

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// Every file under `dir` with its bytes, names sorted.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| {
            let bytes = std::fs::read(e.path()).unwrap_or_default();
            (e.file_name().to_string_lossy().into_owned(), bytes)
        })
        .collect();
    files.sort();
    files
}

/// Fills the file system at `dir` up, leaving `pages` 4 KiB pages free.
fn fill(dir: &Path, pages: usize) {
    let page = vec![7u8; 4096];
    let mut chunks = Vec::new();
    for k in 0.. {
        let p = dir.join(format!("filler{k}"));
        if std::fs::write(&p, &page).is_err() {
            let _ = std::fs::remove_file(&p);
            break;
        }
        chunks.push(p);
    }
    for p in chunks.iter().rev().take(pages) {
        std::fs::remove_file(p).unwrap();
    }
}

#[test]
fn full_read_only_and_missing_folders_fail_cleanly_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    // A missing parent: created and said (see tests/hardening/hardening.rs); a parent that is a
    // file is named.
    let Some(ro) = Mount::new(&dir.path().join("ro"), "ro,size=64k") else {
        return;
    };
    let target = ro.0.join("sub");
    let o = vanefit(&["simulate", DATASET, "--out", target.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let want = format!(
        "{}: cannot create the folder: Read-only file system",
        target.display()
    );
    assert!(stderr(&o).contains(&want), "{}", stderr(&o));
    let fit = ro.0.join("fit.json");
    let o = vanefit(&["fit", DATASET, "--out", fit.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let want = format!(
        "{}: cannot write into this folder: Read-only",
        ro.0.display()
    );
    assert!(stderr(&o).contains(&want), "{}", stderr(&o));

    let Some(full) = Mount::new(&dir.path().join("full"), "size=256k") else {
        return;
    };
    let out = full.0.join("sim");
    let o = vanefit(&["simulate", DATASET, "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = snapshot(&out);
    fill(&full.0, 2);
    // Other parameters, so every file would change: the first that does not fit fails.
    let o = vanefit(&[
        "simulate",
        DATASET,
        "--params",
        "fits/ar034-synthetic.json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let e = stderr(&o);
    eprintln!("simulate onto a full disk: {}", e.trim());
    assert!(e.contains(&out.display().to_string()), "{e}");
    assert!(e.contains("No space left on device"), "{e}");
    let after = snapshot(&out);
    // The files not rewritten are byte for byte the earlier results, and nothing else is
    // there (no temporary file, no lock).
    assert_eq!(
        after.iter().map(|f| &f.0).collect::<Vec<_>>(),
        before.iter().map(|f| &f.0).collect::<Vec<_>>()
    );
    let intact = before
        .iter()
        .zip(&after)
        .filter(|(b, a)| b.1 == a.1)
        .count();
    assert!(intact >= 1, "earlier results intact");

    // A fit onto the full disk: named, exit 1, no lock or temporary file left.
    let fit = full.0.join("fit.json");
    let o = vanefit(&[
        "fit",
        DATASET,
        "--starts",
        "2",
        "--max-iters",
        "30",
        "--uncertainty",
        "none",
        "--out",
        fit.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    eprintln!("fit onto a full disk: {}", stderr(&o).trim());
    assert!(
        stderr(&o).contains(&full.0.display().to_string()),
        "{}",
        stderr(&o)
    );
    let names: Vec<String> = snapshot(&full.0).into_iter().map(|f| f.0).collect();
    assert!(
        names
            .iter()
            .all(|n| n.starts_with("filler") || n == "sim" || n.ends_with("starts.jsonl")),
        "{names:?}"
    );
}
