//! Estimation, one folder per concern as in pyPESTO:
//!
//! * `problem`: what is estimated and how: each parameter's dimension (bounds and the
//!   coordinate the optimizers move in), the space of them, the motor prior, the objective
//!   the optimizers see (the cost J or the likelihood's χ²), the data behind both and
//!   finite-difference derivatives;
//! * `optimize`: the local optimizers (restarted Nelder–Mead, Levenberg–Marquardt), their
//!   settings and the multi-start over them;
//! * `profile`: profile-likelihood and curvature intervals, and what a dataset can pin down;
//! * `sample`: the posterior's ensemble sampler and its diagnostics;
//! * `fit`: the fit of a dataset (multi-start, maximum-likelihood polish, goodness of fit,
//!   intervals) and the fit file's likelihood;
//! * the parallel `engine` passed in by the caller, the starts' results file (`history`)
//!   and the layer's errors.
//!
//! Progress goes to a [`RunObserver`]; nothing here prints.

pub(crate) mod engine;
pub(crate) mod error;
pub(crate) mod fit;
pub(crate) mod history;
pub(crate) mod optimize;
pub(crate) mod problem;
pub(crate) mod profile;
pub(crate) mod sample;

pub use optimize::multistart;

pub use fit::displacement::DisplacementEstimate;
pub use fit::fit_likelihood::{
    Breakdown, ChannelRows, FitLikelihood, FitLikelihoodError, MotorPriorTerm,
};
pub use fit::goodness::{ChannelChi2, GoodnessOfFit};
pub use fit::{fit, fit_file, DataObjective, FitData, FitOutcome, FitSetup, UncertaintyMethod};
pub use multistart::{Ending, MultiStartOutcome, RunObserver, Silent, StartResult};
pub use optimize::nelder_mead::{
    minimize, Layout, NelderMeadSettings, Restart, RestartedNelderMead, Status,
};
pub use optimize::settings::{MultiStartConfig, MultiStartSettings};
pub use problem::likelihood::Likelihood;
pub use problem::objective::{Coordinates, Evaluation, Objective, Problem};
pub use problem::prior::{Prior, PriorTerm};
pub use problem::space::{Dimension, ParamSpace, SpaceError, DEFAULT_ESTIMATED};
pub use profile::uncertainty::{
    curvature_covariance, curvature_intervals, polish_chi2, profile_intervals, Interval, Method,
    ProfilePoint, CHI2_95,
};
pub use sample::diagnostics::ParamDiagnostics;
pub use sample::posterior::LogPrior;
pub use sample::{
    ess, ess_bulk, ess_tail, gaussian_of, rhat_rank, run_chains, run_ensemble,
    run_ensemble_resumable, run_ensemble_with, straightened, summarise, ChainSettings, Chains,
    Checkpoint, CheckpointError, EnsembleSettings, FitPosterior, ImportanceCheck, Laplace,
    LogDensity, Mapped, Moves, Proposal, QuadraticMap, SampleError, TProposal, Unbounded,
    INDEPENDENCE_SHARE, K_HAT_LIMIT, PROPOSAL_NU, PROPOSAL_SCALE, RW_TARGET,
};

pub use engine::Engine;
pub use error::{EstimateError, ForeignStart, ResultsLineError};
pub use history::ResultsFile;
