//! Estimation, one folder per concern as in pyPESTO: the parameter space and its transforms
//! (`space`), the problem argmin sees (`objective`), the one optimizer (`optimize`: restarted
//! Nelder–Mead) and its finite differences (`derivatives`), the parallel engine passed in by
//! the caller (`engine`), run settings (`settings`), the multi-start runner (`multistart`)
//! and its results file (`history`), profile-likelihood intervals (`uncertainty`), and the fit
//! of a dataset (`fit`). Progress goes to a [`RunObserver`]; nothing here prints.

pub mod derivatives;
pub mod displacement;
pub mod engine;
pub mod error;
pub mod fit;
pub(crate) mod fit_data;
pub mod fit_likelihood;
pub mod goodness;
pub mod history;
pub(crate) mod least_squares;
pub mod likelihood;
pub(crate) mod max_likelihood;
pub mod multistart;
pub mod objective;
pub mod optimize;
pub mod prior;
pub mod sample;
pub mod settings;
pub mod space;
pub(crate) mod subset;
pub mod uncertainty;

pub use engine::Engine;
pub use error::EstimateError;
pub use history::ResultsFile;
pub use multistart::{MultiStartOutcome, RunObserver, StartResult};
pub use objective::{Coordinates, Evaluation, Objective, Problem};
pub use prior::Prior;
pub use settings::{MultiStartConfig, MultiStartSettings};
pub use space::{Dimension, ParamSpace, DEFAULT_ESTIMATED};
