//! Run settings as linfa's `ParamGuard` keeps them: an unchecked [`MultiStartConfig`] with
//! public fields and defaults, turned by [`MultiStartConfig::check`] into a
//! [`MultiStartSettings`] whose fields are private, so a run never sees a bad value.

use crate::estimate::error::EstimateError;
use crate::estimate::optimize::least_squares::LmSettings;
use crate::estimate::optimize::nelder_mead::{Layout, NelderMeadSettings, Restart};

/// Settings of a multi-start run as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct MultiStartConfig {
    /// Number of starts (given ones first, then a Latin hypercube).
    pub starts: usize,
    /// Seed of the start design.
    pub seed: u64,
    /// Nelder–Mead iterations between barriers.
    pub stage_iters: u64,
    /// Iteration budget of one start.
    pub max_iters: u64,
    /// Convergence: standard deviation of the simplex costs below this (cost units).
    /// Default 1e-5: at most 0.01 in χ² (the largest channel has ~650 rows, and χ² = Σ N_c·J_c),
    /// far below anything an interval sees, and about the cost's own jitter from adaptive
    /// integration (a tolerance below it is met only by a fully collapsed simplex).
    /// Measured on the shipped dataset, 32 starts: 38 038 evaluations instead of 60 121 at
    /// 1e-6, the best cost 1.4e-5 higher, every parameter within 6e-5 relative.
    pub sd_tolerance: f64,
    /// Size of the initial simplex in optimizer coordinates θ.
    pub initial_step: f64,
    /// A start stops early after this many rounds if its cost exceeds
    /// `kill_factor`·best + `kill_margin`.
    pub kill_after_rounds: usize,
    /// See `kill_after_rounds`.
    pub kill_factor: f64,
    /// See `kill_after_rounds`.
    pub kill_margin: f64,
    /// A running start whose cost comes within this fraction of (1 + cost) of a start that
    /// has already converged stops as `joined`: it has found a minimum of that cost, and
    /// polishing it to the last digit only repeats work (the best start is finished to
    /// full convergence before export anyway). Default 1e-4: Δχ² ≈ 0.1 at the shipped
    /// dataset's optimum. Measured on 256 starts of the shipped dataset: the
    /// converged starts used two thirds of all evaluations, half of them after reaching
    /// their final cost to 0.1%. Negative: never join.
    pub join_tolerance: f64,
    /// Keep every start's cost trace.
    pub keep_traces: bool,
    /// Start points given in optimizer coordinates θ (e.g. a previous fit's optimum); they
    /// take the first start indices, the Latin hypercube fills the rest.
    pub given_starts: Vec<Vec<f64>>,
    /// Fresh simplices around the best point after convergence (restarted Nelder–Mead):
    /// a collapsed simplex is the method's known failure, and a restart that finds nothing
    /// better is the convergence test.
    pub max_restarts: u32,
    /// A restart that lowers the cost by at most this fraction of (1 + cost) finds
    /// "nothing better" and ends the start. Default 3e-5 (≈1e-4 cost units at the shipped
    /// dataset's optimum, below 0.1 in χ²): gains smaller than the cost's jitter are noise.
    pub restart_gain: f64,
    /// Hand-over to least squares: after this many rounds of Nelder–Mead, a start still
    /// running takes Levenberg–Marquardt on the cost's residuals for its next stage
    /// ([`crate::estimate::optimize::multistart`]); 0: never (objectives without cost residuals never do).
    /// The rule looks at the start alone, so it does not depend on the thread count.
    /// Nelder–Mead's later iterations crawl along the cost's narrow valleys at about 1.6
    /// evaluations an iteration; Levenberg–Marquardt crosses them from the linearised
    /// residuals in steps of k + 1 evaluations. Measured on the shipped dataset, 32 starts
    /// (docs/performance.md, "The hand-over to Levenberg–Marquardt"): 37 057 evaluations
    /// with Nelder–Mead alone, 9 712 with the hand-over after one round, every start at
    /// the best minimum.
    pub handoff_after_rounds: usize,
    /// Most Levenberg–Marquardt iterations of a hand-over.
    pub handoff_iters: usize,
    /// A hand-over has converged when a step lowers the cost (or the linear model predicts
    /// that it would) by less than this fraction of (1 + cost). Default 3e-7 (1e-6 cost
    /// units at the shipped dataset's optimum, twice the cost's jitter): looser, and the
    /// starts stop along the valley's floor at costs a few 1e-3 apart.
    pub handoff_gain: f64,
}

impl Default for MultiStartConfig {
    fn default() -> Self {
        Self {
            starts: 32,
            seed: 1,
            stage_iters: 100,
            max_iters: 3000,
            sd_tolerance: 1e-5,
            initial_step: 0.5,
            kill_after_rounds: 5,
            kill_factor: 3.0,
            kill_margin: 10.0,
            join_tolerance: 1e-4,
            keep_traces: false,
            max_restarts: 20,
            restart_gain: 3e-5,
            given_starts: Vec::new(),
            handoff_after_rounds: 1,
            handoff_iters: 40,
            handoff_gain: 3e-7,
        }
    }
}

impl MultiStartConfig {
    /// Checks every value (one error per kind of bad value).
    pub fn check(&self) -> Result<MultiStartSettings, EstimateError> {
        if self.starts == 0 {
            return Err(EstimateError::NoStarts);
        }
        if self.stage_iters == 0 {
            return Err(EstimateError::NoStageIterations);
        }
        if !(self.sd_tolerance.is_finite() && self.sd_tolerance >= 0.0) {
            return Err(EstimateError::SdTolerance(self.sd_tolerance));
        }
        if !(self.restart_gain.is_finite() && self.restart_gain >= 0.0) {
            return Err(EstimateError::RestartGain(self.restart_gain));
        }
        if !(self.initial_step.is_finite() && self.initial_step > 0.0) {
            return Err(EstimateError::InitialStep(self.initial_step));
        }
        if self.kill_factor.is_nan() || self.kill_factor < 0.0 {
            return Err(EstimateError::KillFactor(self.kill_factor));
        }
        if self.kill_margin.is_nan() {
            return Err(EstimateError::KillMargin(self.kill_margin));
        }
        if self.join_tolerance.is_nan() {
            return Err(EstimateError::JoinTolerance(self.join_tolerance));
        }
        if !(self.handoff_gain.is_finite() && self.handoff_gain >= 0.0) {
            return Err(EstimateError::HandoffGain(self.handoff_gain));
        }
        Ok(MultiStartSettings(self.clone()))
    }
}

/// Checked settings of a multi-start run (see [`MultiStartConfig`] for the meaning).
#[derive(Debug, Clone, PartialEq)]
pub struct MultiStartSettings(MultiStartConfig);

impl MultiStartSettings {
    /// Number of starts (≥ 1).
    pub fn starts(&self) -> usize {
        self.0.starts
    }
    /// Seed of the start design.
    pub fn seed(&self) -> u64 {
        self.0.seed
    }
    /// Iterations between barriers (≥ 1).
    pub fn stage_iters(&self) -> u64 {
        self.0.stage_iters
    }
    /// Iteration budget of one start.
    pub fn max_iters(&self) -> u64 {
        self.0.max_iters
    }
    /// Rounds before the early-stop rule applies.
    pub fn kill_after_rounds(&self) -> usize {
        self.0.kill_after_rounds
    }
    /// Whether a start with `cost` stops early when the best cost so far is `best`.
    pub fn stops_early(&self, cost: f64, best: f64) -> bool {
        cost > self.0.kill_factor * best + self.0.kill_margin
    }
    /// Whether a running start at `cost` joins the minimum of converged starts at `known`.
    pub fn joins(&self, cost: f64, known: f64) -> bool {
        let tol = self.0.join_tolerance;
        known.is_finite() && tol >= 0.0 && (cost - known).abs() <= tol * (1.0 + known.abs())
    }
    /// Whether a start that has run `rounds` rounds of Nelder–Mead is handed over to
    /// Levenberg–Marquardt now (see [`MultiStartConfig::handoff_after_rounds`]).
    pub fn hands_off(&self, rounds: usize) -> bool {
        let c = &self.0;
        c.handoff_after_rounds > 0 && c.handoff_iters > 0 && rounds >= c.handoff_after_rounds
    }
    /// The Levenberg–Marquardt settings of a hand-over: converged at a gain below
    /// `handoff_gain`·(1 + cost), the cost where the step starts; no coordinate moves by
    /// more than 1 in θ in one step (the first simplex's edge is 0.5).
    pub(crate) fn handoff_lm(&self) -> LmSettings {
        LmSettings {
            max_iters: self.0.handoff_iters,
            tol: self.0.handoff_gain,
            rel_tol: self.0.handoff_gain,
            max_step: 1.0,
        }
    }
    /// Keep every start's cost trace.
    pub fn keep_traces(&self) -> bool {
        self.0.keep_traces
    }
    /// Start points given in θ.
    pub fn given_starts(&self) -> &[Vec<f64>] {
        &self.0.given_starts
    }
    /// The Nelder–Mead of each start: an inward axis simplex of edge `initial_step`,
    /// Gao–Han coefficients, curvature-shaped restarts.
    pub fn nelder_mead(&self) -> NelderMeadSettings {
        NelderMeadSettings {
            sd_tolerance: self.0.sd_tolerance,
            step: self.0.initial_step,
            layout: Layout::Inward,
            adaptive: true,
            restart: Restart::Curvature {
                max_restarts: self.0.max_restarts,
                min_gain: self.0.restart_gain,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bad_value_has_its_own_error() {
        let ok = MultiStartConfig::default();
        assert!(ok.check().is_ok());
        let bad = |c: MultiStartConfig| c.check().unwrap_err().to_string();
        assert_eq!(
            bad(MultiStartConfig {
                starts: 0,
                ..ok.clone()
            }),
            "--starts must be at least 1"
        );
        assert!(bad(MultiStartConfig {
            stage_iters: 0,
            ..ok.clone()
        })
        .contains("stage"));
        assert!(bad(MultiStartConfig {
            sd_tolerance: -1.0,
            ..ok.clone()
        })
        .contains("sd"));
        assert!(bad(MultiStartConfig {
            join_tolerance: f64::NAN,
            ..ok.clone()
        })
        .contains("join"));
        assert!(bad(MultiStartConfig {
            restart_gain: f64::INFINITY,
            ..ok.clone()
        })
        .contains("restart gain"));
        assert!(bad(MultiStartConfig {
            handoff_gain: -1.0,
            ..ok.clone()
        })
        .contains("hand-over"));
        assert!(bad(MultiStartConfig {
            initial_step: 0.0,
            ..ok.clone()
        })
        .contains("step"));
        assert!(bad(MultiStartConfig {
            kill_factor: f64::NAN,
            ..ok.clone()
        })
        .contains("kill"));
        assert!(bad(MultiStartConfig {
            kill_margin: f64::NAN,
            ..ok
        })
        .contains("margin"));
    }
}
