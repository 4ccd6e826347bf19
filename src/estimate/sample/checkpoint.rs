//! Checkpoints of [`super::chains::run_chains`] and [`super::run_ensemble_resumable`]: the
//! chains' (walkers') state after each block, so that
//! a run that was killed resumes where its last block ended and ends with the same chains
//! as a run that was not (every block draws from streams fixed by seed, chain and block).
//!
//! # Format (version 1)
//!
//! ```text
//!     vanefit samples checkpoint 1\n
//!     {JSON header}\n
//!     kept draws and ln p of chain 0, chain 1, …: f64 little-endian
//! ```
//!
//! The header holds the sampler (`chains` or `ensemble`), the settings (chains or walkers,
//! steps, burn-in, block, seed), a fingerprint of what fixes the posterior and the starts
//! (bit for bit: a chains run's proposal, its mode, covariance factor, ν and scale; an
//! ensemble's starts and DE share: the fit, its dataset and the seed), the dimension, the blocks done and each chain's state (position, ln p, ln ε,
//! proposals counted, accepted kept steps, kept draws). Each chain's kept
//! draws follow as `kept·d` numbers and its ln p as `kept` numbers. JSON numbers are written
//! to round-trip exactly. The file is written through a temporary file and a rename, so a
//! run killed while writing leaves the previous checkpoint whole.
//!
//! A checkpoint made with other settings, for another posterior or in another format is an
//! error naming the file ([`CheckpointError`]); it is never silently overwritten.

use super::proposal::Proposal;
use super::settings::ChainSettings;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The first line of a checkpoint.
pub const MAGIC: &str = "vanefit samples checkpoint";
/// The format version written.
pub const FORMAT_VERSION: u32 = 1;

/// Why a checkpoint cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CheckpointError {
    /// It cannot be read, written or removed.
    #[error("{}: {why}", path.display())]
    Io {
        /// The checkpoint.
        path: PathBuf,
        /// What the system said.
        why: String,
    },
    /// It is not a checkpoint of this format.
    #[error("{}: not a vanefit samples checkpoint of format {FORMAT_VERSION}: {why}", path.display())]
    Format {
        /// The checkpoint.
        path: PathBuf,
        /// What is wrong.
        why: String,
    },
    /// It was made with other settings or for another posterior.
    #[error(
        "{}: the checkpoint was made with {what} {saved}, this run has {now}; remove the file or run with the same settings",
        path.display()
    )]
    Settings {
        /// The checkpoint.
        path: PathBuf,
        /// The setting that differs.
        what: &'static str,
        /// Its value in the checkpoint.
        saved: String,
        /// Its value now.
        now: String,
    },
}

/// The state of one chain between blocks.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChainState {
    /// Position.
    pub x: Vec<f64>,
    /// ln p at x.
    pub lp: f64,
    /// ln ε of the random-walk move.
    pub log_eps: f64,
    /// Proposals counted: a chain's random-walk proposals during the burn-in (the tuning's
    /// step count), an ensemble walker's differential-evolution proposals.
    pub tried: u64,
    /// Accepted proposals among the kept steps.
    pub accepted: u64,
    /// Kept draws.
    pub draws: Vec<Vec<f64>>,
    /// ln p of the kept draws.
    pub lps: Vec<f64>,
}

impl ChainState {
    /// A chain at `x` (ln p `lp`) with ln ε `log_eps`, nothing kept yet.
    pub fn new(x: Vec<f64>, lp: f64, log_eps: f64) -> Self {
        Self {
            x,
            lp,
            log_eps,
            tried: 0,
            accepted: 0,
            draws: Vec::new(),
            lps: Vec::new(),
        }
    }
}

/// What a checkpoint held.
pub(crate) struct Saved {
    /// Each chain's state.
    pub states: Vec<ChainState>,
    /// Blocks run.
    pub blocks_done: usize,
}

#[derive(Serialize, Deserialize, PartialEq, Debug)]
struct Settings {
    chains: usize,
    steps: usize,
    burn_in: usize,
    block: usize,
    seed: u64,
}

#[derive(Serialize, Deserialize)]
struct StateRecord {
    x: Vec<f64>,
    lp: f64,
    log_eps: f64,
    tried: u64,
    accepted: u64,
    kept: usize,
}

#[derive(Serialize, Deserialize)]
struct Header {
    sampler: String,
    settings: Settings,
    posterior: String,
    dim: usize,
    blocks_done: usize,
    states: Vec<StateRecord>,
}

/// Where a run's checkpoint lives, and a test's hook to stop it.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// The file.
    pub path: PathBuf,
    /// Stop with [`super::SampleError::Halted`] once this many blocks are done and saved (a
    /// test's stand-in for a killed run).
    pub halt_after: Option<usize>,
}

/// What a checkpoint must match: the sampler, its settings and a fingerprint of the
/// posterior it samples.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Key {
    /// `chains` or `ensemble`.
    pub sampler: &'static str,
    /// The settings (an ensemble's walkers as chains).
    pub settings: ChainSettings,
    /// [`fingerprint`] of what fixes the posterior and the starts.
    pub fingerprint: String,
    /// Dimension d.
    pub dim: usize,
}

/// FNV-1a over the bits of `numbers` (for a chains run: the proposal's mode, L, ν and
/// scale; for an ensemble: its starts and DE share), as 16 hex digits.
pub(crate) fn fingerprint<'a>(numbers: impl Iterator<Item = &'a f64>) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for v in numbers {
        for b in v.to_bits().to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    format!("{h:016x}")
}

/// The key of a chains run with the proposal `q`.
pub(crate) fn chains_key(settings: &ChainSettings, q: &dyn Proposal) -> Key {
    Key {
        sampler: "chains",
        settings: settings.clone(),
        fingerprint: fingerprint(q.numbers().iter()),
        dim: q.dim(),
    }
}

fn settings_of(s: &ChainSettings) -> Settings {
    Settings {
        chains: s.chains,
        steps: s.steps,
        burn_in: s.burn_in,
        block: s.block,
        seed: s.seed,
    }
}

impl Checkpoint {
    /// A checkpoint at `path`.
    pub fn at(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            halt_after: None,
        }
    }

    fn io(&self, e: &std::io::Error) -> CheckpointError {
        CheckpointError::Io {
            path: self.path.clone(),
            why: e.to_string(),
        }
    }

    fn format(&self, why: impl Into<String>) -> CheckpointError {
        CheckpointError::Format {
            path: self.path.clone(),
            why: why.into(),
        }
    }

    /// Writes the chains' `states` after `blocks_done` blocks; then, when the hook asks,
    /// stops the run.
    pub(crate) fn save(
        &self,
        key: &Key,
        states: &[ChainState],
        blocks_done: usize,
    ) -> Result<(), super::SampleError> {
        let header = Header {
            sampler: key.sampler.to_string(),
            settings: settings_of(&key.settings),
            posterior: key.fingerprint.clone(),
            dim: key.dim,
            blocks_done,
            states: states
                .iter()
                .map(|s| StateRecord {
                    x: s.x.clone(),
                    lp: s.lp,
                    log_eps: s.log_eps,
                    tried: s.tried,
                    accepted: s.accepted,
                    kept: s.draws.len(),
                })
                .collect(),
        };
        let json = serde_json::to_string(&header).map_err(|e| self.format(e.to_string()))?;
        let mut bytes = format!("{MAGIC} {FORMAT_VERSION}\n{json}\n").into_bytes();
        for s in states {
            for v in s.draws.iter().flatten().chain(&s.lps) {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        crate::io::write_atomic(&self.path, &bytes).map_err(|e| self.io(&e))?;
        if self.halt_after == Some(blocks_done) {
            return Err(super::SampleError::Halted(blocks_done));
        }
        Ok(())
    }

    /// The saved state, if the file exists; an error if it was made otherwise.
    pub(crate) fn load(&self, key: &Key) -> Result<Option<Saved>, CheckpointError> {
        let bytes = match std::fs::read(&self.path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(self.io(&e)),
        };
        let (header, payload) = self.split(&bytes)?;
        self.check(&header, key)?;
        let d = header.dim;
        let need: usize = header.states.iter().map(|s| s.kept * (d + 1)).sum();
        if payload.len() != 8 * need {
            return Err(self.format(format!(
                "{} bytes of draws, the header asks for {}",
                payload.len(),
                8 * need
            )));
        }
        let mut numbers = payload
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap_or([0; 8])));
        let states = header
            .states
            .into_iter()
            .map(|r| {
                let draws = (0..r.kept)
                    .map(|_| numbers.by_ref().take(d).collect())
                    .collect();
                let lps = numbers.by_ref().take(r.kept).collect();
                ChainState {
                    x: r.x,
                    lp: r.lp,
                    log_eps: r.log_eps,
                    tried: r.tried,
                    accepted: r.accepted,
                    draws,
                    lps,
                }
            })
            .collect();
        Ok(Some(Saved {
            states,
            blocks_done: header.blocks_done,
        }))
    }

    /// The header and the binary payload of a checkpoint's `bytes`.
    fn split<'b>(&self, bytes: &'b [u8]) -> Result<(Header, &'b [u8]), CheckpointError> {
        let line = |from: usize| {
            bytes[from..]
                .iter()
                .position(|b| *b == b'\n')
                .map(|n| from + n)
        };
        let first = line(0).ok_or_else(|| self.format("no first line"))?;
        let magic = std::str::from_utf8(&bytes[..first]).unwrap_or("");
        if magic != format!("{MAGIC} {FORMAT_VERSION}") {
            return Err(self.format(format!(
                "its first line is '{}'",
                magic.chars().take(60).collect::<String>()
            )));
        }
        let second = line(first + 1).ok_or_else(|| self.format("no header line"))?;
        let header: Header = serde_json::from_slice(&bytes[first + 1..second])
            .map_err(|e| self.format(format!("header: {e}")))?;
        Ok((header, &bytes[second + 1..]))
    }

    /// That `header` was made with `settings` for the proposal `q`.
    fn check(&self, header: &Header, key: &Key) -> Result<(), CheckpointError> {
        let settings = &key.settings;
        let now = settings_of(settings);
        let s = &header.settings;
        let differ = |what: &'static str, saved: String, now: String| CheckpointError::Settings {
            path: self.path.clone(),
            what,
            saved,
            now,
        };
        let pairs: [(&'static str, u64, u64); 5] = [
            ("chains", s.chains as u64, now.chains as u64),
            ("steps", s.steps as u64, now.steps as u64),
            ("burn-in", s.burn_in as u64, now.burn_in as u64),
            ("block", s.block as u64, now.block as u64),
            ("seed", s.seed, now.seed),
        ];
        if header.sampler != key.sampler {
            return Err(differ(
                "the sampler",
                header.sampler.clone(),
                key.sampler.to_string(),
            ));
        }
        for (what, a, b) in pairs {
            if a != b {
                return Err(differ(what, a.to_string(), b.to_string()));
            }
        }
        let fp = &key.fingerprint;
        if &header.posterior != fp || header.dim != key.dim {
            return Err(differ(
                "the posterior",
                format!("{} ({} parameters)", header.posterior, header.dim),
                format!("{fp} ({} parameters): another fit or dataset", key.dim),
            ));
        }
        if header.states.len() != s.chains
            || header.blocks_done > settings.blocks()
            || header.states.iter().any(|r| r.x.len() != header.dim)
        {
            return Err(self.format("the chains' states do not match its settings"));
        }
        Ok(())
    }

    /// Removes the file (the run is complete); a missing file is fine.
    pub(crate) fn remove(&self) -> Result<(), CheckpointError> {
        match std::fs::remove_file(&self.path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
            Err(e) => Err(self.io(&e)),
        }
    }

    /// The checkpoint's path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}
