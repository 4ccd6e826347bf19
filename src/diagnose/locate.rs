//! Phase 3, locate: where the fitted baseline misses the data ([`super::analysis`]), and
//! how much misfit noise alone explains.

use super::analysis::{self, ChannelData, Location};
use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::Fitted;
use super::observe::Progress;
use super::{Candidate, ModelKind};

/// The fitted baseline against the data.
pub(crate) struct Baseline {
    /// The fit (after the null refit).
    pub fitted: Fitted,
    /// Its channels against the data.
    pub channels: Vec<ChannelData>,
    /// [`noise_ratio_limit`] of the channels.
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
pub(crate) fn baseline(cx: &Context, fitted: Fitted) -> Result<Baseline, DiagnoseError> {
    let channels = cx.channels(&fitted)?;
    let limit = noise_ratio_limit(&channels);
    let ratio = analysis::noise_ratio(&channels);
    let locations = analysis::locate(&channels, cx.ds.p_atm_pa);
    cx.say(Progress::BaselineLocated {
        ratio,
        limit,
        locations: locations.len(),
    });
    Ok(Baseline {
        fitted,
        channels,
        limit,
        ratio,
        locations,
    })
}

/// The noise ratio that a correct model exceeds with probability ≈ 0.1%: with C channels of
/// n_c points and Gaussian noise, each channel's mean square is ≈ χ²(n_c)/n_c (variance
/// 2/n_c), so the squared ratio (their mean) has standard deviation √(2·Σ1/n_c)/C; the
/// limit is √(1 + 3.09·that) (≈ 1.08 for the paper's three experiments, ≈ 1.05 for one
/// 600-row transient). The spread of the estimated σ is left out, which makes the limit
/// strict: it is also the test that a fit "looks acceptable".
pub fn noise_ratio_limit(channels: &[ChannelData]) -> f64 {
    let c = channels.len().max(1) as f64;
    let var: f64 = channels
        .iter()
        .map(|ch| 2.0 / ch.x.len().max(1) as f64)
        .sum();
    (1.0 + 3.09 * var.sqrt() / c).sqrt()
}
