//! The estimation problem: each estimated parameter's bounds and coordinate
//! (`dimension`), the space of them over the fixed parameters (`space`), the motor prior
//! (`prior`), the objective that the optimizers, profiles and sampler evaluate
//! (`objective`: the cost J or the likelihood's χ², plus the prior), the dataset's cost and
//! likelihood behind them (`fit_data`, `likelihood`) and their finite-difference
//! derivatives (`derivatives`).

pub(crate) mod derivatives;
pub(crate) mod dimension;
pub(crate) mod fit_data;
pub(crate) mod likelihood;
pub(crate) mod objective;
pub(crate) mod prior;
pub(crate) mod space;
