//! Why a diagnosis failed.

use super::discover::RegressError;
use super::fitting::RefitError;
use crate::data::dataset::DataError;
use crate::estimate::EstimateError;
use crate::objective::cost::CostError;
use crate::sim::experiment::SimError;
use crate::sim::recording::MissingColumn;

/// Why a diagnosis could not be made. Every message is the wrapped error's own (the data
/// layer's are located "file:line:column" messages).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DiagnoseError {
    /// A recording or the rig description is unusable (e.g. no nominal motor).
    #[error(transparent)]
    Data(#[from] DataError),
    /// The cost model cannot be built from the dataset.
    #[error(transparent)]
    Cost(#[from] CostError),
    /// A simulation of a fitted model failed.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A channel the cost compares has no column in its recording.
    #[error(transparent)]
    MissingColumn(#[from] MissingColumn),
    /// A fit failed.
    #[error(transparent)]
    Fit(#[from] RefitError),
    /// The regression of the misfit on the term library failed.
    #[error(transparent)]
    Regression(#[from] RegressError),
    /// The worker pool could not be built.
    #[error(transparent)]
    Engine(#[from] EstimateError),
}
