//! Phase 1, baseline: the base model's default parameters fitted by multi-start
//! Nelder–Mead from the rig's nominal motor plus Latin-hypercube starts.

use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::{self, Fitted};
use super::observe::Progress;

/// Fits the base model.
pub(crate) fn fit(cx: &Context) -> Result<Fitted, DiagnoseError> {
    cx.say(Progress::BaselineStart {
        starts: cx.opts.starts,
        points: cx.cost.n_points(),
        channels: cx.cost.n_channels(),
    });
    let baseline = fitting::run_job(&cx.cost, &cx.target, &cx.base_job(), cx.threads())?;
    cx.count(baseline.evaluations);
    cx.say(Progress::BaselineFitted(&baseline));
    Ok(baseline)
}
