//! The dataset a fit was made from, found from its fit file (docs/formats.md, "Fit
//! files", `dataset_path`): the one rule `predict` (command line, `batch`, Python) follows
//! when no dataset is named.
//!
//! 1. A fit file that records `dataset_path` (relative to the fit file's folder, so that a
//!    moved checkout still finds it): that folder, if it holds `rig.toml` and its name is the
//!    fit's `dataset`. Otherwise nothing is found, with a warning saying why: a recorded path
//!    is not guessed around.
//! 2. An older fit file without it: `measurements/<dataset>` beside the fit file's folder
//!    (`<fit folder>/../measurements/<dataset>`, the shipped layout), then in the current
//!    folder.

use super::dataset::dataset_name;
use super::fitfile::FitFile;
use std::path::{Component, Path, PathBuf};

/// How a fit's dataset was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum FoundBy {
    /// The fit file's `dataset_path`.
    RecordedPath,
    /// Its name, under `measurements/` (a fit file without `dataset_path`).
    Name,
}

/// The outcome of [`locate_dataset`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Located {
    /// The dataset folder, and how it was found.
    Found(PathBuf, FoundBy),
    /// Not found: the folders looked at, and what was wrong with the recorded path (`None`:
    /// the file records none).
    Missing {
        /// The folders looked at, in order.
        tried: Vec<PathBuf>,
        /// Why the fit file's `dataset_path` does not lead to the dataset.
        recorded: Option<String>,
    },
}

impl Located {
    /// One line saying where the dataset was found or was looked for, e.g. "dataset
    /// ar034 at ../measurements/ar034 (the fit file's dataset_path)".
    pub fn describe(&self, name: &str) -> String {
        match self {
            Located::Found(p, by) => format!(
                "dataset {name} at {} ({})",
                p.canonicalize().as_deref().unwrap_or(p).display(),
                match by {
                    FoundBy::RecordedPath => "the fit file's dataset_path",
                    FoundBy::Name => "found by its name: the fit file records no dataset_path",
                }
            ),
            Located::Missing { tried, recorded } => {
                let looked: Vec<String> = tried.iter().map(|p| p.display().to_string()).collect();
                let mut text = format!(
                    "the dataset {name} was not found (looked at {})",
                    if looked.is_empty() {
                        "nothing: the fit file names no dataset".into()
                    } else {
                        looked.join(", ")
                    }
                );
                if let Some(why) = recorded {
                    text.push_str(&format!(": {why}"));
                }
                text
            }
        }
    }
}

/// Why a folder does not hold the dataset a fit names.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
enum NotHeld {
    /// The folder does not exist.
    #[error("no such folder")]
    NoFolder,
    /// It has no `rig.toml`.
    #[error("the folder has no rig.toml")]
    NoRig,
    /// It holds another dataset.
    #[error("the folder holds dataset {found}, not {name}")]
    Other {
        /// The dataset the folder holds.
        found: String,
        /// The dataset the fit names.
        name: String,
    },
}

/// Whether `dir` holds the dataset named `name`: its `rig.toml` is a file and the folder's
/// name is `name` (a dataset's name is its folder's, `Dataset::load`).
fn holds(dir: &Path, name: &str) -> Result<(), NotHeld> {
    if !dir.is_dir() {
        return Err(NotHeld::NoFolder);
    }
    if !dir.join("rig.toml").is_file() {
        return Err(NotHeld::NoRig);
    }
    let found = dataset_name(dir);
    if found != name {
        return Err(NotHeld::Other {
            found,
            name: name.to_string(),
        });
    }
    Ok(())
}

/// The dataset `fit` (read from `fit_path`, `None` for a fit held in memory) was made
/// from, by the rule of the module documentation. A relative `dataset_path` of a fit
/// without a path is taken from the current folder.
pub fn locate_dataset(fit_path: Option<&Path>, fit: &FitFile) -> Located {
    let fit_dir = fit_path.and_then(Path::parent).map(|p| {
        if p.as_os_str().is_empty() {
            Path::new(".")
        } else {
            p
        }
    });
    let name = fit.dataset.as_str();
    if let Some(rel) = &fit.dataset_path {
        let dir = fit_dir.map_or_else(|| PathBuf::from(rel), |d| d.join(rel));
        return match holds(&dir, name) {
            Ok(()) => Located::Found(dir, FoundBy::RecordedPath),
            Err(why) => Located::Missing {
                recorded: Some(format!("the fit file's dataset_path {rel}: {why}")),
                tried: vec![dir],
            },
        };
    }
    if name.is_empty() {
        return Located::Missing {
            tried: Vec::new(),
            recorded: None,
        };
    }
    let mut tried: Vec<PathBuf> = fit_dir
        .map(|d| d.join("..").join("measurements").join(name))
        .into_iter()
        .collect();
    tried.push(Path::new("measurements").join(name));
    match tried.iter().find(|d| holds(d, name).is_ok()) {
        Some(d) => Located::Found(d.clone(), FoundBy::Name),
        None => Located::Missing {
            tried,
            recorded: None,
        },
    }
}

/// `dataset_dir` relative to the folder of the fit file `fit_path`, `/`-separated (both
/// made absolute and free of symbolic links first), as `dataset_path` records it; `None`
/// where either cannot be resolved (a dataset held in memory) or they share no root.
pub fn relative_dataset_path(dataset_dir: &Path, fit_path: &Path) -> Option<String> {
    let fit_dir = match fit_path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let to = dataset_dir.canonicalize().ok()?;
    let from = fit_dir.canonicalize().ok()?;
    let (a, b): (Vec<Component>, Vec<Component>) =
        (from.components().collect(), to.components().collect());
    if a.first() != b.first() {
        return None;
    }
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<String> = vec!["..".to_string(); a.len() - common];
    parts.extend(
        b[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    Some(if parts.is_empty() {
        ".".into()
    } else {
        parts.join("/")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dataset folder `root/<parts>` with a rig.toml.
    fn dataset(root: &Path, parts: &str) -> PathBuf {
        let d = root.join(parts);
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(d.join("rig.toml"), "").unwrap();
        d
    }

    fn fit(name: &str, path: Option<&str>) -> FitFile {
        let mut f = FitFile::from_params(
            name,
            crate::model::params::MotorParams::default(),
            crate::model::effects::EffectSet::empty(),
        );
        f.dataset_path = path.map(str::to_string);
        f
    }

    /// The recorded path is relative to the fit file's folder and survives moving both.
    #[test]
    fn a_recorded_path_is_relative_to_the_fit_file_and_survives_a_move() {
        let t = tempfile::tempdir().unwrap();
        let ds = dataset(t.path(), "a/measurements/m1");
        std::fs::create_dir_all(t.path().join("a/fits/deep")).unwrap();
        let fit_path = t.path().join("a/fits/deep/f.json");
        let rel = relative_dataset_path(&ds, &fit_path).unwrap();
        assert_eq!(rel, "../../measurements/m1");
        std::fs::rename(t.path().join("a"), t.path().join("b")).unwrap();
        let moved = t.path().join("b/fits/deep/f.json");
        match locate_dataset(Some(&moved), &fit("m1", Some(&rel))) {
            Located::Found(p, FoundBy::RecordedPath) => {
                assert_eq!(
                    p.canonicalize().unwrap(),
                    t.path().join("b/measurements/m1").canonicalize().unwrap()
                )
            }
            other => panic!("{other:?}"),
        }
    }

    /// A recorded path that is gone, or holds another dataset, is not guessed around.
    #[test]
    fn a_wrong_recorded_path_is_missing_with_the_reason() {
        let t = tempfile::tempdir().unwrap();
        dataset(t.path(), "measurements/other");
        dataset(t.path(), "measurements/m1");
        std::fs::create_dir_all(t.path().join("fits")).unwrap();
        let fit_path = t.path().join("fits/f.json");
        for (rel, why) in [
            ("../measurements/gone", "no such folder"),
            ("../measurements/other", "holds dataset other, not m1"),
        ] {
            let l = locate_dataset(Some(&fit_path), &fit("m1", Some(rel)));
            let Located::Missing {
                recorded: Some(r),
                tried,
            } = &l
            else {
                panic!("{l:?}")
            };
            assert!(r.contains(why) && r.contains(rel), "{r}");
            assert_eq!(tried.len(), 1);
            assert!(
                l.describe("m1").contains("was not found"),
                "{}",
                l.describe("m1")
            );
        }
    }

    /// Without a recorded path: `measurements/<name>` beside the fit file's folder.
    #[test]
    fn an_older_fit_file_is_found_by_name_beside_its_folder() {
        let t = tempfile::tempdir().unwrap();
        let ds = dataset(t.path(), "measurements/m1");
        std::fs::create_dir_all(t.path().join("fits")).unwrap();
        let fit_path = t.path().join("fits/f.json");
        match locate_dataset(Some(&fit_path), &fit("m1", None)) {
            Located::Found(p, FoundBy::Name) => {
                assert_eq!(p.canonicalize().unwrap(), ds.canonicalize().unwrap())
            }
            other => panic!("{other:?}"),
        }
        let l = locate_dataset(Some(&fit_path), &fit("nope", None));
        let Located::Missing {
            tried,
            recorded: None,
        } = &l
        else {
            panic!("{l:?}")
        };
        assert_eq!(tried.len(), 2);
    }
}
