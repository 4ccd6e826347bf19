//! How a run of Metropolis–Hastings chains is set: what [`super::chains`] runs and what a
//! [`super::checkpoint`] records, so that a checkpoint made with other settings is refused.

/// How to run the chains.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainSettings {
    /// Independent chains.
    pub chains: usize,
    /// Steps kept per chain after the burn-in.
    pub steps: usize,
    /// Steps per chain run first, tuning ε, and discarded.
    pub burn_in: usize,
    /// Steps per block (each block ends with a checkpoint, when one is asked).
    pub block: usize,
    /// Seed of the chains' streams.
    pub seed: u64,
}

impl ChainSettings {
    /// Steps per chain, burn-in and kept.
    pub fn total(&self) -> usize {
        self.burn_in + self.steps
    }

    /// Blocks of [`Self::block`] steps (the last may be shorter).
    pub fn blocks(&self) -> usize {
        self.total().div_ceil(self.block.max(1))
    }
}
