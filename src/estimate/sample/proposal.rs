//! What the Metropolis–Hastings chains ([`super::run_chains`]) propose from ([`Proposal`]):
//! independence draws with their density, and the Gaussian that shapes their random-walk
//! steps. The Laplace approximation's t ([`TProposal`]) is one.

use super::laplace::{Laplace, TProposal};

/// What the Metropolis–Hastings chains propose from: independence draws with their
/// density, and the Cholesky factor of their random-walk steps.
pub trait Proposal: Sync {
    /// Dimension d.
    fn dim(&self) -> usize;
    /// A draw.
    fn draw_with(&self, rng: &mut rand_xoshiro::Xoshiro256PlusPlus) -> Vec<f64>;
    /// ln q(x) up to a constant.
    fn log_q(&self, x: &[f64]) -> f64;
    /// The Gaussian whose Cholesky factor shapes the random-walk steps, and whose mean is
    /// the chains' start of last resort.
    fn walk(&self) -> &Laplace;
    /// Numbers that identify the proposal (a checkpoint's key).
    fn numbers(&self) -> Vec<f64>;
}

impl Proposal for TProposal {
    fn dim(&self) -> usize {
        self.laplace.dim()
    }
    fn draw_with(&self, rng: &mut rand_xoshiro::Xoshiro256PlusPlus) -> Vec<f64> {
        self.draw(rng)
    }
    fn log_q(&self, x: &[f64]) -> f64 {
        TProposal::log_q(self, x)
    }
    fn walk(&self) -> &Laplace {
        &self.laplace
    }
    fn numbers(&self) -> Vec<f64> {
        let l = &self.laplace;
        l.mode
            .iter()
            .chain(l.chol.iter())
            .chain([self.nu, self.scale].iter())
            .copied()
            .collect()
    }
}
