//! Goodness of fit against a noise estimate from the data, and the check that no other local
//! optimum competes with the estimate (intervals are trusted only where the model
//! reaches the noise and the optimum is unique).
//!
//! # Noise ratio
//!
//! With χ²_c the likelihood's χ² of channel c over its n_c rows ([`crate::objective::likelihood`],
//! σ_c estimated from the data), the noise ratio is
//!
//! ```text
//!     r = √( (1/C) Σ_c χ²_c / n_c )                                    [1]
//! ```
//!
//! (each channel counts alike, so a 25-point datasheet is not drowned by 600-row ramps; the
//! diagnosis reports the same number). For a model that reaches the noise, χ²_c/n_c has
//! relative variance 2/n_c from the noise itself and ≈ 3.9/n_c from the estimate of σ_c² by
//! second differences (their mean square has variance 140σ⁴/m over m rows; divided by 6² that
//! is 3.89σ⁴/m). The model "reaches the noise" when
//!
//! ```text
//!     r² ≤ 1 + 3.09 · √(Σ_c 5.89/n_c) / C                              [2]
//! ```
//!
//! (a one-sided 0.1% test). Intervals are widened by s² = max(1, r²): the profile threshold
//! becomes 3.841·s² (Birge's ratio), so a model that misses gets intervals as wide as its
//! scatter warrants, and the summary says that it misses.
//!
//! # Competing optima
//!
//! A profile explores one valley. The multi-start's other local optima, polished on χ², that
//! fit within the threshold with a parameter outside its interval make that parameter not
//! identifiable ([`mark_competitors`]).

pub use crate::data::statistics::GoodnessOfFit;
use crate::estimate::problem::space::ParamSpace;
use crate::estimate::profile::uncertainty::Interval;

/// One channel's share of χ².
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelChi2 {
    /// "file column".
    pub label: String,
    /// χ²_c.
    pub chi2: f64,
    /// n_c.
    pub n: usize,
}

/// The record ([`GoodnessOfFit`], in `data` with the fit file that states it) as this layer
/// computes and uses it.
impl GoodnessOfFit {
    /// The goodness of fit of channels' χ² with `k` estimated parameters.
    pub fn new(channels: &[ChannelChi2], k: usize) -> Self {
        let n_points: usize = channels.iter().map(|c| c.n).sum();
        let chi2: f64 = channels.iter().map(|c| c.chi2).sum();
        // n − k, not clamped: with as many estimated parameters as rows or more, χ²/dof is
        // undefined (the data cannot test the model), and says so.
        let dof = n_points as i64 - k as i64;
        let used: Vec<&ChannelChi2> = channels.iter().filter(|c| c.n > 0).collect();
        let c = used.len().max(1) as f64;
        let r2 = used.iter().map(|ch| ch.chi2 / ch.n as f64).sum::<f64>() / c;
        let spread: f64 = used.iter().map(|ch| 5.89 / ch.n as f64).sum();
        let limit2 = 1.0 + 3.09 * spread.sqrt() / c;
        Self {
            chi2,
            n_points,
            dof,
            chi2_per_dof: (dof > 0).then(|| chi2 / dof as f64),
            noise_ratio: r2.sqrt(),
            noise_ratio_limit: limit2.sqrt(),
            noise_reached: r2 <= limit2,
            interval_scale: r2.sqrt().max(1.0),
        }
    }

    /// The rise of χ² that ends a 95% profile interval: 3.841·s².
    pub fn threshold(&self) -> f64 {
        interval_threshold(self.interval_scale)
    }
}

/// The rise of χ² that ends a 95% profile interval of a model whose noise ratio is `r`
/// ([1]): 3.841·s², s = max(1, r) (Birge's ratio; the diagnosis's extended model uses it
/// too).
pub fn interval_threshold(noise_ratio: f64) -> f64 {
    crate::estimate::profile::uncertainty::CHI2_95 * noise_ratio.max(1.0).powi(2)
}

/// The channel with the largest χ²_c/n_c: its "file column" and √(χ²_c/n_c) (`None`
/// without a compared row). Said beside the goodness of fit where the model misses the
/// noise; not part of the record, which a fit file states without it.
pub fn worst_channel(channels: &[ChannelChi2]) -> Option<(String, f64)> {
    channels
        .iter()
        .filter(|c| c.n > 0)
        .map(|ch| (ch.label.clone(), (ch.chi2 / ch.n as f64).sqrt()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// A local optimum of the multi-start other than the estimate, re-polished on χ².
#[derive(Debug, Clone, PartialEq)]
pub struct Competitor {
    /// θ of the optimum.
    pub theta: Vec<f64>,
    /// Its χ² minus the estimate's.
    pub(crate) excess: f64,
}

/// The other local optima (θ and χ², each already polished on χ²: they were found on the
/// cost J, whose weights differ) that fit within `threshold` of the estimate's χ².
pub(crate) fn competitors(
    others: &[(Vec<f64>, f64)],
    chi2_min: f64,
    threshold: f64,
) -> Vec<Competitor> {
    others
        .iter()
        .map(|(theta, chi2)| Competitor {
            theta: theta.clone(),
            excess: chi2 - chi2_min,
        })
        .filter(|c| c.excess < threshold)
        .collect()
}

/// Marks each interval whose parameter a competing optimum puts outside it.
pub fn mark_competitors(intervals: &mut [Interval], space: &ParamSpace, rivals: &[Competitor]) {
    for (j, iv) in intervals.iter_mut().enumerate() {
        let Some(d) = space.dims.get(j) else { continue };
        for r in rivals {
            let v = d.value(r.theta[j]);
            let below = iv.lo.is_some_and(|lo| v < lo);
            let above = iv.hi.is_some_and(|hi| v > hi);
            if below || above {
                iv.other_optimum = Some(v);
                break;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ch(chi2: f64, n: usize) -> ChannelChi2 {
        ChannelChi2 {
            label: format!("c{n}"),
            chi2,
            n,
        }
    }

    /// Four rows and eleven estimated parameters leave dof = 4 − 11 = −7: χ²/dof is
    /// undefined (not χ²/1 from a dof clamped to 1), the summary says so and warns.
    #[test]
    fn no_degrees_of_freedom_leave_chi2_per_dof_undefined() {
        let g = GoodnessOfFit::new(&[ch(0.272, 4)], 11);
        assert_eq!(g.dof, -7);
        assert_eq!(g.chi2_per_dof, None);
        let line = crate::report::fit::chi2_summary(&g);
        assert!(line.contains("chi2/dof undefined (dof -7 ≤ 0)"), "{line}");
        let warning = crate::report::fit::dof_warning(&g).expect("a warning");
        assert!(
            warning.contains("4 rows for 11 estimated parameters"),
            "{warning}"
        );
        let exact = GoodnessOfFit::new(&[ch(0.5, 11)], 11);
        assert_eq!((exact.dof, exact.chi2_per_dof), (0, None));
        let one = GoodnessOfFit::new(&[ch(0.5, 12)], 11);
        assert_eq!((one.dof, one.chi2_per_dof), (1, Some(0.5)));
        assert!(crate::report::fit::dof_warning(&one).is_none());
    }

    /// A model at the noise scores r ≈ 1 and passes; a channel twice as far off fails,
    /// and the intervals widen by the ratio.
    #[test]
    fn noise_ratio_and_its_limit() {
        let ok = GoodnessOfFit::new(&[ch(25.0, 25), ch(600.0, 600), ch(650.0, 650)], 8);
        assert!((ok.noise_ratio - 1.0).abs() < 1e-12);
        assert!(ok.noise_reached);
        assert_eq!(ok.interval_scale, 1.0);
        assert_eq!(ok.dof, 1267);
        assert_eq!(ok.chi2_per_dof, Some(1275.0 / 1267.0));
        let limit2 = 1.0 + 3.09 * (5.89f64 / 25.0 + 5.89 / 600.0 + 5.89 / 650.0).sqrt() / 3.0;
        assert!((ok.noise_ratio_limit - limit2.sqrt()).abs() < 1e-12);
        let bad = GoodnessOfFit::new(&[ch(100.0, 25), ch(600.0, 600), ch(650.0, 650)], 8);
        assert!(!bad.noise_reached);
        assert!((bad.interval_scale - 2.0f64.sqrt()).abs() < 1e-12);
        assert!((bad.threshold() - 2.0 * super::super::uncertainty::CHI2_95).abs() < 1e-9);
        let channels = [ch(100.0, 25), ch(600.0, 600), ch(650.0, 650)];
        assert_eq!(worst_channel(&channels).unwrap().0, "c25");
        assert_eq!(worst_channel(&[ch(0.0, 0)]), None);
    }
}
