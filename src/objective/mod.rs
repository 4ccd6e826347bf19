//! The fitting objective: polynomial reference responses and the cost built on them, and
//! the likelihood of the recorded rows with a noise estimate from the data.

pub(crate) mod cost;
pub(crate) mod likelihood;
pub(crate) mod nuisance;
pub(crate) mod peak;
pub(crate) mod reference;

pub use cost::{
    ChannelCost, ChannelResiduals, CostError, CostModel, CostOptions, CostValue, PEAK_COLUMN,
};
pub use likelihood::{ChannelTarget, InputSmoothing, Target};
pub use nuisance::{Nuisance, Nuisances};
pub use reference::{
    experiment_references, Abscissa, ChannelReference, Piece, Reference, ReferenceError,
    ReferenceOptions,
};

/// The former name of [`ReferenceOptions`] (one `FitOptions` is the fit task's).
#[deprecated(note = "renamed `ReferenceOptions`")]
pub type FitOptions = ReferenceOptions;

/// The former name of [`ReferenceError`] (one `FitError` is the fit task's).
#[deprecated(note = "renamed `ReferenceError`")]
pub type FitError = ReferenceError;
