//! Units and shards. A unit is one task of one dataset; the units are listed in a fixed
//! order (datasets by name, then fit, diagnose, predict), and grouped so that a predict goes
//! with its dataset's fit (it reads the fit's file). Group `g` (0-based) belongs to shard
//! `g mod N + 1` of `N`: round robin, so that shards get a fair share of a sorted fleet,
//! and a shard's units never depend on how many threads or machines run the others.

use super::manifest::{Manifest, TaskKind};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One task of one dataset.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Unit {
    /// The dataset's name (its folder's).
    pub dataset: String,
    /// The dataset's folder.
    pub path: PathBuf,
    /// The task.
    pub task: TaskKind,
    /// Its group: units of one group run in one shard, in order.
    pub group: usize,
}

impl Unit {
    /// The unit's folder under the batch folder: `<dataset>/<task>`.
    pub fn folder(&self, out: &Path) -> PathBuf {
        out.join(&self.dataset).join(self.task.id())
    }

    /// `dataset/task`, as progress lines and messages name a unit.
    pub fn label(&self) -> String {
        format!("{}/{}", self.dataset, self.task.id())
    }
}

/// `--shard i/N`: the `i`-th of `N` shards, 1-based (as Slurm array task ids are).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1..=count.
    pub index: usize,
    /// Number of shards, ≥ 1.
    pub count: usize,
}

impl Shard {
    /// The whole batch as one shard.
    pub const ALL: Shard = Shard { index: 1, count: 1 };

    /// Whether group `group` is this shard's.
    pub(crate) fn owns(&self, group: usize) -> bool {
        group % self.count + 1 == self.index
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// A `--shard` value that is not `i/N` with 1 ≤ i ≤ N.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("'{0}' is not i/N with 1 <= i <= N (e.g. 2/8)")]
pub struct BadShard(pub String);

impl std::str::FromStr for Shard {
    type Err = BadShard;

    /// `i/N` with 1 ≤ i ≤ N (clap shows the message with the option named).
    fn from_str(s: &str) -> Result<Self, BadShard> {
        let bad = || BadShard(s.to_string());
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if count == 0 || index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

/// Every unit of the manifest in the fixed order, with its group.
pub fn units(m: &Manifest) -> Vec<Unit> {
    let mut out = Vec::new();
    let mut group = 0;
    for d in &m.datasets {
        // fit and predict share a group; diagnose is a group of its own.
        let mut fit_group = None;
        for &task in &m.tasks {
            let g = match (task, fit_group) {
                (TaskKind::Predict, Some(g)) => g,
                _ => {
                    group += 1;
                    group - 1
                }
            };
            if task == TaskKind::Fit {
                fit_group = Some(g);
            }
            out.push(Unit {
                dataset: d.name.clone(),
                path: d.path.clone(),
                task,
                group: g,
            });
        }
    }
    out
}

/// Number of groups (the most shards that all get work).
pub fn groups(units: &[Unit]) -> usize {
    units.iter().map(|u| u.group + 1).max().unwrap_or(0)
}

/// The units of `shard`, in order.
pub fn select(units: &[Unit], shard: Shard) -> Vec<Unit> {
    units
        .iter()
        .filter(|u| shard.owns(u.group))
        .cloned()
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_refuse() {
        assert_eq!("2/8".parse::<Shard>(), Ok(Shard { index: 2, count: 8 }));
        for bad in ["0/3", "4/3", "1/0", "a/b", "3", "-1/2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    /// Every group lands in exactly one shard, whatever N.
    #[test]
    fn shards_partition_the_groups() {
        for n in 1..7 {
            for g in 0..20 {
                let owners = (1..=n)
                    .filter(|&i| Shard { index: i, count: n }.owns(g))
                    .count();
                assert_eq!(owners, 1);
            }
        }
    }
}
