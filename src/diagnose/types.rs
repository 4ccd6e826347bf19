//! What a diagnosis is asked to do and what it finds.

use super::analysis::{ChannelData, Location};
use super::fitting::Fitted;
use super::{discover, CONCEALMENT_ALPHA};
use crate::data::dataset::Kind;
use crate::estimate::Interval;
use crate::model::effects::{Category, Effect};
use crate::model::motor::ExtraTerm;
use crate::model::params::MotorParams;
use crate::objective::likelihood;

/// Nelder–Mead iterations per start of a warm refit: at 400 (against 2000 or 1500) every
/// named case of `tests/diagnose` gives the same answer within its tolerance (the Levenberg–Marquardt polish of every start finishes the convergence) and
/// a refit costs about half the evaluations (docs/validation.md, "Diagnosis time").
pub(crate) const REFIT_ITERS: u64 = 400;

/// How thorough a diagnosis is.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Starts of the baseline fit (≥ 1; the first is the nominal motor).
    pub starts: usize,
    /// Seed of the Latin-hypercube start designs.
    pub seed: u64,
    /// Worker threads (None: one per core). Results do not depend on it.
    pub threads: Option<usize>,
    /// Iteration budget per start of the baseline fit.
    pub baseline_iters: u64,
    /// Nelder–Mead iteration budget per start of every warm refit (each start is then
    /// finished by Levenberg–Marquardt, which converges in a few Gauss–Newton steps where
    /// Nelder–Mead crawls: the budget only has to bring a start into its basin).
    pub refit_iters: u64,
    /// Given starts per candidate: the effect off, then points of its search range.
    pub effect_starts: usize,
    /// Try pairs whenever the best single effect is significant (otherwise only when its
    /// residuals still show structure).
    pub pairs_always: bool,
    /// Fit experiments separately and predict each from the others.
    pub concealment: bool,
    /// Held-out prediction of this many best candidates (plus the selected model).
    pub held_out_top: usize,
    /// Look for uncatalogued terms.
    pub discover: bool,
    /// The extended model's 95 % intervals by profile likelihood (else from the curvature
    /// at the optimum, much cheaper).
    pub profile_intervals: bool,
}

impl DiagnoseOptions {
    /// The command line's settings.
    pub fn full(starts: usize, seed: u64) -> Self {
        Self {
            starts: starts.max(1),
            seed,
            threads: None,
            baseline_iters: 3000,
            refit_iters: REFIT_ITERS,
            effect_starts: 3,
            pairs_always: true,
            concealment: true,
            held_out_top: 3,
            discover: true,
            profile_intervals: true,
        }
    }

    /// Reduced effort for tests: one baseline start, pairs only when needed, held-out
    /// prediction of the selected model only, the extended model's intervals from the
    /// curvature.
    pub fn quick(seed: u64) -> Self {
        Self {
            starts: 1,
            baseline_iters: 3000,
            refit_iters: REFIT_ITERS,
            effect_starts: 3,
            pairs_always: false,
            held_out_top: 0,
            profile_intervals: false,
            ..Self::full(1, seed)
        }
    }
}

/// What kind of model a refit is (the order is the simplicity order of the selection).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[non_exhaustive]
pub enum ModelKind {
    /// The base model (docs/model.md, "Parameters", "What is estimated").
    Baseline,
    /// One catalog effect.
    Single,
    /// Two catalog effects.
    Pair,
    /// The base model with discovered terms.
    Uncatalogued,
    /// Catalog effect(s) with discovered terms.
    CatalogAndUncatalogued,
}

/// A refitted model with its scores.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Effect id, "a+b" for a pair, "uncatalogued" or "a+uncatalogued".
    pub label: String,
    /// Its place in the simplicity order.
    pub kind: ModelKind,
    /// The fit.
    pub fitted: Fitted,
    /// BIC(this) − BIC(baseline).
    pub delta_bic: f64,
    /// Noise ratio against the data (see `super::analysis`).
    pub noise_ratio: f64,
    /// √(mean over experiments of the squared noise ratio of each experiment predicted by
    /// a fit to the others), when computed.
    pub(crate) held_out: Option<f64>,
}

/// One experiment in the concealment test.
#[derive(Debug, Clone)]
pub struct ExperimentCheck {
    /// The experiment's kind.
    pub kind: Kind,
    /// Its recording.
    pub file: String,
    /// Noise ratio of the joint baseline on this experiment.
    pub joint_ratio: f64,
    /// Noise ratio of the base model fitted to this experiment alone.
    pub alone_ratio: f64,
    /// [`super::noise_ratio_limit`] of this experiment's channels: below it, the separate
    /// fit "looks acceptable".
    pub alone_limit: f64,
    /// χ² (against the references) of the fit to this experiment alone.
    pub alone_chi2: f64,
    /// The separate fit's parameters.
    pub alone_params: MotorParams,
    /// Noise ratio of this experiment predicted by the base model fitted to the others.
    pub held_out_ratio: Option<f64>,
}

/// Separate against joint fits.
#[derive(Debug, Clone)]
pub struct Concealment {
    /// Each experiment fitted alone.
    pub experiments: Vec<ExperimentCheck>,
    /// Likelihood ratio statistic χ²_joint − Σ χ²_alone.
    pub lr: f64,
    /// Its degrees of freedom, k·(E − 1) (an upper bound).
    pub df: f64,
    /// P(χ²(df) > lr).
    pub p_value: f64,
}

impl Concealment {
    /// The parameters disagree between experiments (p below `CONCEALMENT_ALPHA`).
    pub fn disagree(&self) -> bool {
        self.p_value < CONCEALMENT_ALPHA
    }
}

/// One selected extension (`selected` in docs/formats.md, "Diagnosis").
#[derive(Debug, Clone)]
pub struct Selected {
    /// Catalog id, or "uncatalogued".
    pub effect: String,
    /// Category of the physics (docs/model.md, "Missing-physics catalog").
    pub category: Category,
    /// Parameter names, SI values and units.
    pub parameters: Vec<(String, f64, String)>,
    /// BIC of the model with this entry minus BIC without it (entries in order: the deltas
    /// add up to the extended model's ΔBIC against the baseline).
    pub delta_bic: f64,
    /// The discovered term (uncatalogued only).
    pub term: Option<ExtraTerm>,
}

/// Another model that explains the data nearly as well as the chosen one (within
/// [`super::ALSO_CONSISTENT_DELTA_BIC`]).
#[derive(Debug, Clone)]
pub struct AlsoConsistent {
    /// Its label (as in the candidates).
    pub label: String,
    /// Its parts in words.
    pub description: String,
    /// Its BIC minus the chosen model's (positive: worse).
    pub delta_bic: f64,
    /// The categories of its parts.
    pub categories: Vec<Category>,
}

/// A 95 % interval of one estimated parameter of the extended model (docs/diagnosis.md,
/// "Intervals of the extended model").
#[derive(Debug, Clone)]
pub struct ExtendedInterval {
    /// The interval, SI: its `name` is the parameter's id, or "coefficient" for a discovered
    /// term's coefficient (in the term's unit, `discover::coefficient_unit`).
    pub interval: Interval,
    /// The discovered term whose coefficient it is (`None`: a named parameter).
    pub term: Option<ExtraTerm>,
}

/// A catalog effect that was not tried, and why.
#[derive(Debug, Clone)]
pub struct Skipped {
    /// The effect.
    pub effect: Effect,
    /// Why it cannot show in this dataset.
    pub reason: String,
}

/// The outcome of a diagnosis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    /// Dataset name.
    pub dataset: String,
    /// Ambient pressure of the rig, Pa.
    pub p_atm_pa: f64,
    /// The base model misses the data (`mismatch` in docs/formats.md, "Diagnosis").
    pub mismatch: bool,
    /// The fitted base model.
    pub baseline: Candidate,
    /// Channels of the baseline against the data.
    pub baseline_channels: Vec<ChannelData>,
    /// Where the baseline misses, worst first.
    pub locations: Vec<Location>,
    /// Every refitted model, best ΔBIC first.
    pub candidates: Vec<Candidate>,
    /// Catalog effects not tried.
    pub skipped: Vec<Skipped>,
    /// The chosen extensions, in order.
    pub selected: Vec<Selected>,
    /// The chosen model (the baseline when nothing is selected).
    pub extended: Candidate,
    /// Channels of the extended model against the data.
    pub extended_channels: Vec<ChannelData>,
    /// Locations left after the extension.
    pub extended_locations: Vec<Location>,
    /// 95 % intervals of the extended model's estimated parameters, discovered terms'
    /// coefficients included (empty when nothing is selected: the baseline has none).
    pub extended_intervals: Vec<ExtendedInterval>,
    /// Other models within [`super::ALSO_CONSISTENT_DELTA_BIC`] of the chosen one, best
    /// first: the data cannot separate them from it.
    pub also_consistent: Vec<AlsoConsistent>,
    /// An experiment that would separate the chosen model from those also consistent.
    pub separating_experiment: Option<String>,
    /// The concealment test, when run.
    pub concealment: Option<Concealment>,
    /// Regression of the baseline's misfit over the term library.
    pub regression: Option<discover::Regression>,
    /// Noise ratio that noise alone would exceed with probability 0.1% (see
    /// [`super::noise_ratio_limit`]).
    pub noise_ratio_limit: f64,
    /// Names estimated in the baseline.
    pub estimated: Vec<String>,
    /// How the recorded inputs of transient experiments were smoothed.
    pub inputs: Vec<likelihood::InputSmoothing>,
    /// (phase, seconds).
    pub phases: Vec<(String, f64)>,
    /// (phase, cost evaluations): every fit's, the regressions' and the Stribeck grid's
    /// simulations of the whole dataset.
    pub phase_evaluations: Vec<(String, u64)>,
    /// Wall time of the whole diagnosis, s.
    pub wall_s: f64,
    /// Worker threads used.
    pub threads: usize,
}

impl Diagnosis {
    /// Cost evaluations of the whole diagnosis: the sum of `phase_evaluations` (no phase
    /// is left unfinished when a diagnosis is returned).
    pub fn evaluations(&self) -> u64 {
        self.phase_evaluations.iter().map(|(_, n)| n).sum()
    }

    /// Noise ratio of the baseline and of the extended model.
    pub fn noise_ratios(&self) -> (f64, f64) {
        (self.baseline.noise_ratio, self.extended.noise_ratio)
    }

    /// Total ΔBIC of the extended model against the baseline.
    pub fn delta_bic(&self) -> f64 {
        self.extended.delta_bic
    }

    /// A candidate by label.
    pub fn candidate(&self, label: &str) -> Option<&Candidate> {
        self.candidates.iter().find(|c| c.label == label)
    }
}
