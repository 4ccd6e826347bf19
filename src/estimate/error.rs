//! Errors of the estimate layer: bad run settings (one variant per bad value, checked once
//! by [`crate::estimate::optimize::settings::MultiStartConfig::check`]), the thread pool, the results file.

use crate::model::params::ParamError;
use std::path::PathBuf;

/// An error of an estimation run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum EstimateError {
    /// The observer asked the run to stop ([`crate::estimate::optimize::multistart::RunObserver::keep_going`]).
    #[error("interrupted: the starts finished so far are in the results file; resume to continue")]
    Interrupted,
    /// No start point asked for.
    #[error("--starts must be at least 1")]
    NoStarts,
    /// A round of zero iterations would never end.
    #[error("stage iterations must be at least 1")]
    NoStageIterations,
    /// argmin needs a finite tolerance ≥ 0.
    #[error("sd tolerance {0}: must be a finite number >= 0")]
    SdTolerance(f64),
    /// The join rule needs a number (negative: never join).
    #[error("join tolerance {0}: must be a number")]
    JoinTolerance(f64),
    /// The restart rule needs a finite gain ≥ 0.
    #[error("restart gain {0}: must be a finite number >= 0")]
    RestartGain(f64),
    /// The first simplex needs a finite edge > 0.
    #[error("initial step {0}: must be a finite number > 0")]
    InitialStep(f64),
    /// The early-stop rule compares against `factor`·best + `margin`.
    #[error("kill factor {0}: must be a number >= 0")]
    KillFactor(f64),
    /// See [`EstimateError::KillFactor`].
    #[error("kill margin {0}: must not be NaN")]
    KillMargin(f64),
    /// The hand-over's convergence test needs a finite gain ≥ 0.
    #[error("hand-over gain {0}: must be a finite number >= 0")]
    HandoffGain(f64),
    /// A given start point has the wrong number of coordinates.
    #[error("given start {index}: {got} coordinates, the space has {want}")]
    GivenStart {
        /// Index of the start.
        index: usize,
        /// Its length.
        got: usize,
        /// The space's dimension.
        want: usize,
    },
    /// rayon could not build the worker threads.
    #[error("thread pool: {0}")]
    ThreadPool(#[from] rayon::ThreadPoolBuildError),
    /// Reading or writing the results file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The results file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// A line of the results file is unreadable or belongs elsewhere.
    #[error("{}:{line}: {why}", path.display())]
    ResultsLine {
        /// The results file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong with it.
        why: ResultsLineError,
    },
    /// No start reached a cost that can be evaluated: the best point of the multi-start
    /// still carries the cost's failure penalty (`objective::cost::FAILURE_PENALTY`), so
    /// there is no estimate to report.
    #[error(
        "no start of the fit reached a cost that can be evaluated, so there is no estimate: {why}"
    )]
    NoFiniteCost {
        /// Why the cost at the best start could not be evaluated (the cost model's words).
        why: String,
    },
    /// The best point breaks a model constraint (it cannot: penalised points never win).
    #[error("best parameters: {0}")]
    BestParameters(#[from] ParamError),
}

/// What is wrong with a line of a results file (`EstimateError::ResultsLine`).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ResultsLineError {
    /// The line cannot be read.
    #[error(transparent)]
    Read(#[from] std::io::Error),
    /// The header is not JSON of a header.
    #[error(transparent)]
    Header(#[from] serde_json::Error),
    /// The header is another run's.
    #[error(
        "belongs to a different run (seed, starts, parameters or effects differ); remove it or \
         drop --resume"
    )]
    OtherRun,
    /// A start that this run cannot have made.
    #[error("{0}: not a start of this run; remove the file or drop --resume")]
    NotOfThisRun(ForeignStart),
}

/// Why a recorded start cannot be one of this run's.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ForeignStart {
    /// A point with another number of coordinates than the run has parameters.
    #[error("start {index}: {key} has {len} coordinates where the run has {n} parameters")]
    Coordinates {
        /// The start's index.
        index: usize,
        /// Which point: `theta0` or `theta`.
        key: &'static str,
        /// Its coordinates.
        len: usize,
        /// The run's parameters.
        n: usize,
    },
    /// A coordinate that is not a finite number.
    #[error("start {index} has a coordinate that is not a finite number")]
    NotFiniteCoordinate {
        /// The start's index.
        index: usize,
    },
    /// A cost that is not a finite number.
    #[error("start {index} has a cost that is not a finite number")]
    NotFiniteCost {
        /// The start's index.
        index: usize,
    },
}
