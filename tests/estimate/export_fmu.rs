//! `export-fmu` after the README's build: `cargo build --release` builds the FMU's shared
//! library with vanefit, and a `vanefit` that was copied elsewhere (`cargo install --path .`
//! puts it in `~/.cargo/bin`) still finds the library in the target folder of the tree it was
//! built from.

use crate::common::stderr;
use std::path::Path;
use std::process::Command;

/// `cargo build` at the root builds the workspace's default members: the FMU crate must be
/// one of them, so that the README's single build command leaves `export-fmu` working.
#[test]
fn the_readme_build_command_builds_the_fmu_library() {
    let o = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args([
            "metadata",
            "--no-deps",
            "--format-version",
            "1",
            "--offline",
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let meta: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let name_of = |id: &serde_json::Value| {
        meta["packages"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| &p["id"] == id)
            .map(|p| p["name"].as_str().unwrap().to_string())
            .unwrap()
    };
    let defaults: Vec<String> = meta["workspace_default_members"]
        .as_array()
        .expect("cargo ≥ 1.71 lists the default members")
        .iter()
        .map(name_of)
        .collect();
    for want in ["vanefit", "vanefit-fmu"] {
        assert!(defaults.iter().any(|n| n == want), "{defaults:?}");
    }
}

/// An installed copy of the binary (away from `target/release/`) finds the library that the
/// build left in the target folder (`$CARGO_TARGET_DIR` here) and packs it.
#[test]
fn an_installed_binary_finds_the_library_in_its_build_tree() {
    let dir = tempfile::tempdir().unwrap();
    let bin = dir.path().join("bin");
    std::fs::create_dir(&bin).unwrap();
    let exe = bin.join("vanefit");
    std::fs::copy(env!("CARGO_BIN_EXE_vanefit"), &exe).unwrap();
    let target = dir.path().join("target");
    let release = target.join("release");
    std::fs::create_dir_all(&release).unwrap();
    // Newer than any real build's copy, so that it is the one chosen.
    let library = release.join("libvanefit_fmu.so");
    std::fs::write(&library, b"stands in for the shared library").unwrap();
    let fit = Path::new(env!("CARGO_MANIFEST_DIR")).join("fits/ar034-synthetic.json");
    let fmu = dir.path().join("motor.fmu");
    let o = Command::new(&exe)
        .args(["export-fmu", fit.to_str().unwrap(), "--out"])
        .arg(&fmu)
        .env_remove("VANEFIT_FMU_BINARY")
        .env("CARGO_TARGET_DIR", &target)
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let printed = String::from_utf8_lossy(&o.stdout);
    assert!(
        printed.contains(&format!("binary {}", library.display())),
        "{printed}"
    );
    let mut archive = zip::ZipArchive::new(std::fs::File::open(&fmu).unwrap()).unwrap();
    let mut packed = Vec::new();
    std::io::Read::read_to_end(
        &mut archive.by_name("binaries/linux64/vanefit_fmu.so").unwrap(),
        &mut packed,
    )
    .unwrap();
    assert_eq!(packed, b"stands in for the shared library");
}

/// The features of every crate as a build resolves them (`cargo tree -e normal,build`):
/// `name version` → features.
fn resolved_features(args: &[&str]) -> std::collections::BTreeMap<String, String> {
    let o = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
        .args([
            "tree",
            "--offline",
            "-e",
            "normal,build",
            "--prefix",
            "none",
        ])
        .args(["-f", "{p} [{f}]"])
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| {
            let (package, features) = l.trim_end_matches(" (*)").split_once(" [")?;
            let mut words = package.split_whitespace();
            let key = format!("{} {}", words.next()?, words.next()?);
            Some((key, features.trim_end_matches(']').to_string()))
        })
        .collect()
}

/// maturin's build of the Python crate reuses what the README's `cargo build --release`
/// compiled: every crate both builds use is resolved with the same features (a crate that
/// differs, such as syn under pyo3's macros, is compiled again with everything built on it).
#[test]
fn the_python_build_resolves_shared_crates_as_the_root_build() {
    let root = resolved_features(&[]);
    let python = resolved_features(&[
        "-p",
        "vanefit-python",
        "--features",
        "pyo3/extension-module",
    ]);
    let differ: Vec<String> = python
        .iter()
        .filter_map(|(k, f)| {
            let r = root.get(k)?;
            (r != f).then(|| format!("{k}: root [{r}], python [{f}]"))
        })
        .collect();
    assert!(differ.is_empty(), "{differ:#?}");
    assert!(
        root.keys().any(|k| k.starts_with("syn v3")),
        "syn 3 is shared"
    );
}
