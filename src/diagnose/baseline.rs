//! Phase 1, baseline: the base model's default parameters fitted by multi-start
//! Nelder–Mead from the rig's nominal motor plus Latin-hypercube starts.

use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::{self, Fitted};

/// Fits the base model.
pub(crate) fn fit(cx: &Context) -> Result<Fitted, DiagnoseError> {
    Ok(fitting::run_job(
        &cx.cost,
        &cx.target,
        &cx.base_job,
        cx.engine,
    )?)
}
