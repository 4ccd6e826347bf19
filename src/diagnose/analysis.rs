//! Residual analysis of a fitted model against the recorded data: the noise ratio, and where
//! (experiment, channel, abscissa range) the model misses by more than noise.
//!
//! # Noise ratio
//!
//! For every compared row i of channel c (the rows the cost compares, [`ChannelResiduals`]),
//! r_ci = (y_sim − y_data)/σ_c with y_data the RECORDED value at that row and σ_c the
//! channel's noise estimate from the data alone (second differences,
//! [`crate::objective::likelihood::noise_sigma`]). Then
//!
//! ```text
//!     noise_ratio = √( (1/C) Σ_c mean_i r_ci² )
//! ```
//!
//! the RMS residual in units of the noise, every channel counting the same (as in the cost,
//! so that a 25-point datasheet is not drowned by 600-row ramps). A model that reproduces
//! the true curve scores ≈ 1 (the data scatter by σ about it); the residual against the
//! reference polynomial would not do (the polynomial already averages noise out and a
//! perfect model scores ≈ √(p/n) ≪ 1 against it), nor would the polynomial's residual σ as
//! noise estimate (it holds the polynomial's lack of fit; see [`crate::objective::likelihood`]). Values
//! clearly above 1 are misfit; see [`super::noise_ratio_limit`] for how far above.
//!
//! # Locations
//!
//! In each channel the normalised residuals r_ci are taken in abscissa order and tested:
//! * regional bias: windows of n/20, n/10 and n/5 points slide by half a width; a window
//!   whose mean m has |m|·√w above the Bonferroni-corrected normal quantile (family-wise
//!   α = 1% over every window of every channel) is flagged; flagged windows of one sign
//!   merge into a region;
//! * runs (Wald–Wolfowitz: too few sign changes) and trend (Legendre degree 1–3 of the
//!   abscissa, χ²(3)), each at α = 1%/C (Bonferroni over the C channels); when both fire
//!   and no window did, the window of largest |m| is reported.
//!
//! A location's severity is |m|, the mean residual over the region in units of the noise
//! σ (1 means the model is off by one noise standard deviation throughout the region).

use super::context::Context;
use super::fitting::Fitted;
use super::observe::Note;
use super::stats;
use crate::data::dataset::Kind;
use crate::model::motor::Motor;
use crate::numerics::ode::StiffSolver;
use crate::objective::cost::{ChannelResiduals, CostModel};
use crate::objective::likelihood::Target;
use crate::objective::reference::Abscissa;
use crate::sim::experiment::SimError;
use crate::units::{Quantity, Unit};

/// Family-wise false-alarm rate of the location tests.
const LOCATION_ALPHA: f64 = 0.01;

/// One channel of one experiment: simulation against data at the compared rows, SI.
#[derive(Debug, Clone)]
pub struct ChannelData {
    /// The experiment's kind.
    pub kind: Kind,
    /// Its recording.
    pub file: String,
    /// The measured quantity.
    pub quantity: Quantity,
    /// The recording's column name.
    pub column: String,
    /// The column's unit (for display).
    pub unit: Unit,
    /// The abscissa the channel is compared against.
    pub abscissa: Abscissa,
    /// Abscissa of each compared row (SI; log10 SI for the outlet throttle).
    pub x: Vec<f64>,
    /// Recorded values at the rows, SI.
    pub data: Vec<f64>,
    /// The reference polynomial at the rows (for plots).
    pub reference: Vec<f64>,
    /// Simulated values at the rows, SI.
    pub sim: Vec<f64>,
    /// Noise standard deviation (SI) from [`Target`].
    pub sigma: f64,
}

impl ChannelData {
    /// Normalised residuals (sim − data)/σ.
    pub(crate) fn normalized(&self) -> Vec<f64> {
        self.sim
            .iter()
            .zip(&self.data)
            .map(|(s, d)| (s - d) / self.sigma)
            .collect()
    }

    /// Mean squared normalised residual against the data.
    pub(crate) fn mean_square(&self) -> f64 {
        let r = self.normalized();
        r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64
    }

    /// An abscissa value (SI, log10 SI for conductance) as SI of the abscissa quantity
    /// (the conductance itself, m³/(s·Pa)).
    fn x_si(&self, x: f64) -> f64 {
        if self.abscissa.log10 {
            10f64.powf(x)
        } else {
            x
        }
    }
}

/// Simulation against data for every compared row of every channel (`target` built on
/// `cost`).
pub(crate) fn channel_data(
    cost: &CostModel,
    target: &Target,
    motor: &Motor,
    solver: &dyn StiffSolver,
) -> Result<Vec<ChannelData>, SimError> {
    let res: Vec<ChannelResiduals> = cost.residuals(motor, solver)?;
    let mut out = Vec::with_capacity(res.len());
    for ((r, reference), t) in res.into_iter().zip(cost.references()).zip(&target.channels) {
        debug_assert_eq!(r.rows, t.rows);
        out.push(ChannelData {
            kind: r.experiment_kind,
            file: r.file,
            quantity: r.channel,
            column: r.column,
            unit: reference.unit,
            abscissa: reference.abscissa.clone(),
            data: t.data.clone(),
            x: r.x,
            reference: r.measured,
            sim: r.simulated,
            sigma: t.sigma,
        });
    }
    Ok(out)
}

/// A fitted model's channels against the data: one simulation, noted in `notes`.
pub(crate) fn channels(
    cx: &Context,
    f: &Fitted,
    notes: &mut Vec<Note>,
) -> Result<Vec<ChannelData>, SimError> {
    notes.push(Note::Evaluated(1));
    channel_data(&cx.cost, &cx.target, &f.motor(), &cx.solver)
}

/// √(mean over channels of the mean squared normalised residual against the data) (see the
/// module documentation). 0 for no channels.
pub fn noise_ratio(channels: &[ChannelData]) -> f64 {
    if channels.is_empty() {
        return 0.0;
    }
    (channels.iter().map(ChannelData::mean_square).sum::<f64>() / channels.len() as f64).sqrt()
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

/// Where a model misses.
#[derive(Debug, Clone, PartialEq)]
pub struct Location {
    /// The experiment's kind.
    pub kind: Kind,
    /// Its recording.
    pub file: String,
    /// The channel's column name.
    pub column: String,
    /// The channel's quantity.
    pub quantity: Quantity,
    /// Abscissa range, SI of the abscissa quantity (rad/s, Pa, m³/(s·Pa)), ascending.
    pub(crate) x_range: [f64; 2],
    /// The same range in the abscissa column's unit, ascending.
    pub(crate) x_range_display: [f64; 2],
    /// Abscissa column name (for reports).
    pub(crate) x_column: String,
    /// |mean normalised residual| over the region, σ units.
    pub severity: f64,
    /// Mean (sim − data) over the region, in the channel's column unit (signed: positive
    /// means the model over-predicts).
    pub(crate) bias_display: f64,
    /// The column's unit suffix.
    pub unit: String,
    /// What fired: "bias", "runs+trend".
    pub test: String,
}

/// Locations of every channel that misses by more than noise (see the module docs), most
/// severe first.
pub(crate) fn locate(channels: &[ChannelData], p_atm_pa: f64) -> Vec<Location> {
    let n_windows: usize = channels
        .iter()
        .map(|c| stats::window_count(c.x.len()))
        .sum();
    let z_crit = stats::normal_quantile(1.0 - LOCATION_ALPHA / (2.0 * n_windows.max(1) as f64));
    let alpha_channel = LOCATION_ALPHA / channels.len().max(1) as f64;
    let mut out = Vec::new();
    for ch in channels {
        if ch.x.len() < 10 {
            continue;
        }
        let mut order: Vec<usize> = (0..ch.x.len()).collect();
        order.sort_by(|a, b| ch.x[*a].total_cmp(&ch.x[*b]));
        let r_all = ch.normalized();
        let r: Vec<f64> = order.iter().map(|&i| r_all[i]).collect();
        let x: Vec<f64> = order.iter().map(|&i| ch.x[i]).collect();
        let mut regions = stats::biased_regions(&r, z_crit);
        let mut test = "bias";
        if regions.is_empty() {
            let runs = stats::runs_test(&r).is_some_and(|(_, p)| p < alpha_channel);
            let trend = stats::trend_test(&x, &r, 3).is_some_and(|(_, p)| p < alpha_channel);
            if runs && trend {
                // The most biased window, whatever its size.
                if let Some(reg) = stats::biased_regions(&r, 0.0)
                    .into_iter()
                    .max_by(|a, b| a.bias.abs().total_cmp(&b.bias.abs()))
                {
                    regions.push(reg);
                    test = "runs+trend";
                }
            }
        }
        for reg in regions {
            let (a, b) = (x[reg.first], x[reg.last]);
            let (sa, sb) = (ch.x_si(a), ch.x_si(b));
            let (da, db) = (
                ch.abscissa.display(a, p_atm_pa),
                ch.abscissa.display(b, p_atm_pa),
            );
            let idx = &order[reg.first..=reg.last];
            let bias_si =
                idx.iter().map(|&i| ch.sim[i] - ch.data[i]).sum::<f64>() / idx.len() as f64;
            let bias_display = ch.unit.from_si(bias_si, p_atm_pa) - ch.unit.from_si(0.0, p_atm_pa);
            out.push(Location {
                kind: ch.kind,
                file: ch.file.clone(),
                column: ch.column.clone(),
                quantity: ch.quantity,
                x_range: [sa.min(sb), sa.max(sb)],
                x_range_display: [da.min(db), da.max(db)],
                x_column: ch.abscissa.column.clone(),
                severity: reg.bias.abs(),
                bias_display,
                unit: ch.unit.suffix().to_string(),
                test: test.to_string(),
            });
        }
    }
    out.sort_by(|a, b| b.severity.total_cmp(&a.severity));
    out
}
