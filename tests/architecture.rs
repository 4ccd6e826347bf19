//! The layering of `src/`: every folder may import only the folders below it, so the
//! dependencies point one way (`src/lib.rs` documents the order). This test fails on an
//! upward import, on an import between two folders of the same layer (a cycle waiting to
//! happen), and on a folder that is not in the list. Test modules (`#[cfg(test)]` and
//! after) may use any layer, as the shared yardstick `structure.py` also allows.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

/// The layers, lowest first; folders on one line are siblings that must not import each other.
const LAYERS: &[&[&str]] = &[
    &["units"],
    &["io"],
    &["numerics"],
    &["model"],
    &["sim"],
    &["data"],
    &["objective"],
    &["estimate"],
    &["diagnose", "control", "predict", "export"],
    // The planner of the next measurement propagates predict's uncertainty.
    &["plan"],
    &["report"],
    &["task"],
    &["batch"],
    // The prelude re-exports the front door: above every folder of the library.
    &["prelude"],
    // The command line: part of the `vanefit` binary (src/main.rs), not of the library.
    &["cli"],
];

fn rank(unit: &str) -> Option<usize> {
    LAYERS.iter().position(|layer| layer.contains(&unit))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level unit of a file: its first folder under src/, or its stem.
fn unit_of(src: &Path, file: &Path) -> String {
    let rel = file.strip_prefix(src).unwrap();
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// Every `crate::name` in the library part of a file (before `#[cfg(test)]`), with its line.
fn crate_imports(text: &str) -> Vec<(usize, String)> {
    let library = text.split("#[cfg(test)]").next().unwrap_or("");
    let mut found = Vec::new();
    for (n, line) in library.lines().enumerate() {
        let code = line.split("//").next().unwrap_or("");
        let mut rest = code;
        while let Some(i) = rest.find("crate::") {
            let before = rest[..i].chars().last();
            rest = &rest[i + "crate::".len()..];
            if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
                continue; // e.g. `some_crate::`
            }
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                found.push((n + 1, name));
            }
        }
    }
    found
}

#[test]
fn every_folder_imports_only_the_layers_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    let mut problems = BTreeSet::new();
    for file in &files {
        let unit = unit_of(&src, file);
        if unit == "lib" || unit == "main" {
            continue;
        }
        let Some(own) = rank(&unit) else {
            problems.insert(format!(
                "{}: folder '{unit}' is in no layer",
                file.display()
            ));
            continue;
        };
        let text = fs::read_to_string(file).unwrap();
        for (line, target) in crate_imports(&text) {
            if target == unit {
                continue;
            }
            match rank(&target) {
                Some(r) if r < own => {}
                Some(_) => {
                    problems.insert(format!(
                        "{}:{line}: '{unit}' imports '{target}', which is not below it",
                        file.display()
                    ));
                }
                None => {
                    problems.insert(format!(
                        "{}:{line}: '{unit}' imports '{target}', which is in no layer",
                        file.display()
                    ));
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "layering broken:\n{}",
        problems.into_iter().collect::<Vec<_>>().join("\n")
    );
}

#[test]
fn the_scanner_sees_upward_imports() {
    // The check above is only as good as this scanner: it must see every form of import.
    let text = "use crate::cli::Failure;\nfn f() { crate::report::plot::x(); }\n\
                // crate::commented::out\nlet y = my_crate::not_this;\n\
                #[cfg(test)]\nuse crate::test_only;";
    let names: Vec<_> = crate_imports(text).into_iter().map(|(_, n)| n).collect();
    assert_eq!(names, vec!["cli", "report"]);
    assert!(rank("cli") > rank("model"));
    assert_eq!(rank("diagnose"), rank("control"));
}
