//! Estimation, one folder per concern as in pyPESTO: the parameter space and its transforms
//! (`space`), the problem argmin sees (`objective`), the one optimizer (`optimize`: restarted
//! Nelder–Mead) and its finite differences (`derivatives`), the parallel engine passed in by
//! the caller (`engine`), run settings (`settings`), the multi-start runner (`multistart`)
//! and its results file (`history`), profile-likelihood intervals (`uncertainty`), and the fit
//! of a dataset (`fit`). Progress goes to a [`RunObserver`]; nothing here prints.

pub(crate) mod derivatives;
pub(crate) mod dimension;
pub(crate) mod displacement;
pub(crate) mod engine;
pub(crate) mod error;
pub(crate) mod fit;
pub(crate) mod fit_data;
pub(crate) mod fit_likelihood;
pub(crate) mod goodness;
pub(crate) mod history;
pub(crate) mod least_squares;
pub(crate) mod likelihood;
pub(crate) mod max_likelihood;
pub mod multistart;
pub(crate) mod objective;
pub(crate) mod optimize;
pub(crate) mod prior;
pub(crate) mod sample;
pub(crate) mod settings;
pub(crate) mod space;
pub(crate) mod subset;
pub(crate) mod uncertainty;

pub use fit::{fit, fit_file, DataObjective, FitData, FitOutcome, FitSetup, UncertaintyMethod};
pub use fit_likelihood::{
    Breakdown, ChannelRows, FitLikelihood, FitLikelihoodError, MotorPriorTerm,
};
pub use goodness::{ChannelChi2, GoodnessOfFit};
pub use likelihood::Likelihood;
pub use multistart::{Ending, MultiStartOutcome, RunObserver, Silent, StartResult};
pub use optimize::{minimize, Layout, NelderMeadSettings, Restart, RestartedNelderMead, Status};
pub use prior::{Prior, PriorTerm};
pub use sample::diagnostics::ParamDiagnostics;
pub use sample::posterior::LogPrior;
pub use sample::{
    ess, ess_bulk, ess_tail, rhat_rank, run_ensemble, run_ensemble_with, summarise, Chains,
    EnsembleSettings, FitPosterior, LogDensity, Moves, SampleError,
};
pub use space::{Dimension, ParamSpace, SpaceError, DEFAULT_ESTIMATED};
pub use uncertainty::{
    curvature_covariance, curvature_intervals, polish_chi2, profile_intervals, Interval, Method,
    ProfilePoint, CHI2_95,
};

pub use displacement::DisplacementEstimate;
pub use engine::Engine;
pub use error::{EstimateError, ForeignStart, ResultsLineError};
pub use history::ResultsFile;
pub use objective::{Coordinates, Evaluation, Objective, Problem};
pub use settings::{MultiStartConfig, MultiStartSettings};
