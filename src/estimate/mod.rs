//! Estimation: parameter space and transforms (`space`), the argmin objective (`objective`),
//! the multi-start runner (`multistart`) and parameter uncertainty (`uncertainty`).

pub mod fit;
pub mod multistart;
pub mod objective;
pub mod space;
pub mod uncertainty;

pub use multistart::{MultiStartConfig, MultiStartOutcome, RunObserver, StartResult};
pub use objective::{Evaluation, Objective, Problem};
pub use space::{Dimension, ParamSpace, DEFAULT_ESTIMATED};
