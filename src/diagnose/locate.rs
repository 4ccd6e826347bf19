//! Phase 3, locate: where the fitted baseline misses the data ([`super::analysis`]), and
//! how much misfit noise alone explains.

use super::analysis::{self, channels, noise_ratio_limit, ChannelData, Location};
use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::Fitted;
use super::observe::Note;
use super::{Candidate, ModelKind};

/// The fitted baseline against the data.
pub(crate) struct Baseline {
    /// The fit (after the null refit).
    pub fitted: Fitted,
    /// Its channels against the data.
    pub channels: Vec<ChannelData>,
    /// [`super::noise_ratio_limit`] of the channels.
    pub limit: f64,
    /// Its noise ratio.
    pub ratio: f64,
    /// Where it misses.
    pub locations: Vec<Location>,
}

impl Baseline {
    /// The baseline as a scored model (ΔBIC 0).
    pub(crate) fn candidate(&self) -> Candidate {
        Candidate {
            label: "baseline".into(),
            kind: ModelKind::Baseline,
            fitted: self.fitted.clone(),
            delta_bic: 0.0,
            noise_ratio: self.ratio,
            held_out: None,
        }
    }
}

/// Residuals of the fitted baseline in noise units, the noise ratio and the locations.
pub(crate) fn baseline(
    cx: &Context,
    fitted: Fitted,
    notes: &mut Vec<Note>,
) -> Result<Baseline, DiagnoseError> {
    let channels = channels(cx, &fitted, notes)?;
    let limit = noise_ratio_limit(&channels);
    let ratio = analysis::noise_ratio(&channels);
    let locations = analysis::locate(&channels, cx.ds.p_atm_pa);
    Ok(Baseline {
        fitted,
        channels,
        limit,
        ratio,
        locations,
    })
}
