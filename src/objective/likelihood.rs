//! The likelihood of the recorded data themselves (what the diagnosis fits and what a
//! fit's intervals are measured on), with a noise estimate per channel
//! that does not depend on any model or polynomial.
//!
//! # Why not the cost's references
//!
//! The fitting cost ([`crate::objective::cost`]) compares simulations with reference polynomials and
//! normalises by the polynomial's residual σ. Where a polynomial cannot follow the curve
//! (a pressure ramp's breakaway, a sharp knee) that σ holds the polynomial's lack of fit
//! too: on the shipped kind of dataset it overstates the noise of the ramp's speed about
//! threefold. And the polynomial's own systematic error is a signal that a fit to one
//! experiment can chase. Both break the statistics of a diagnosis (a correct model would
//! score a noise ratio well below 1; separate fits would "disagree" on clean data). So the
//! diagnosis uses the Gaussian likelihood of the recorded rows:
//!
//! ```text
//!     χ² = Σ_c Σ_i ((y_sim,ci − y_data,ci)/σ_c)²                    [1]
//! ```
//!
//! over the rows the cost compares (abscissa inside the reference's valid range; the rows
//! inside a breakaway jump are left out as there), with σ_c from the data alone.
//!
//! # Systematic errors
//!
//! A calibrated sensor may still read a constant offset, and the recorded supply pressure
//! that drives a ramp may be off by its sensor's offset. A fit's intervals treat these as
//! nuisance parameters with the rig's calibration tolerances as Gaussian priors
//! ([`calibration_tolerance`]), profiled out in closed form ([`super::nuisance`]): an offset
//! the data cannot tell from a parameter change widens the interval instead of biasing it.
//! The diagnosis keeps none (an offset there would be a finding).
//!
//! # Noise estimate
//!
//! Second differences d_i = y_{i+1} − 2y_i + y_{i−1} of the recorded channel, rows in
//! time order (transients) or in abscissa order (datasheet), remove any smooth curve (its
//! contribution is f''·h², negligible at these sampling rates) and leave noise with
//! variance 6σ². Jumps (a motor breaking away) give a few huge d_i, so those beyond five
//! robust standard deviations (from the median |d_i|) are dropped, then
//! σ² = mean(d_i²)/6 over the rest. As in the references, σ is at least max|y|/4096 (a
//! 12-bit converter's resolution), so noise-free data do not get an infinite weight.

use super::cost::{compared_rows, CostError, CostModel};
use super::nuisance::{Nuisance, Nuisances};
use super::reference::{Reference, ReferenceOptions};
use crate::data::dataset::{Dataset, Kind};
use crate::model::motor::Motor;
use crate::model::spec::SizeLaw;
use crate::numerics::DefaultSolver;
use crate::units::Quantity;

/// One compared channel: rows, recorded values there, noise.
#[derive(Debug, Clone)]
pub struct ChannelTarget {
    /// The recording.
    pub file: String,
    /// The compared quantity.
    pub quantity: Quantity,
    /// Recording rows compared (the cost's rows).
    pub rows: Vec<usize>,
    /// Recorded values at those rows, SI.
    pub data: Vec<f64>,
    /// Noise standard deviation of the channel, SI (see the module documentation).
    pub sigma: f64,
    /// Stated data (a catalogue): σ is the reading tolerance and no sensor took the values,
    /// so no sensor offset is profiled out.
    pub stated: bool,
}

impl ChannelTarget {
    /// (simulated − recorded)/σ at the compared rows, appended to `out`.
    fn normalised(&self, simulated: &[f64], out: &mut Vec<f64>) {
        out.extend(
            simulated
                .iter()
                .zip(&self.data)
                .map(|(s, d)| (s - d) / self.sigma),
        );
    }
}

/// Typical calibration tolerance (1σ) of a rig's sensor, SI, for a motor `size` times
/// AR034-11's displacement: the zero offset a calibrated sensor may still carry. For the
/// reference motor's rig: flow meters 0.02 g/s (0.2% of a 10 g/s range), speed 2 rpm,
/// torque 2 mN·m (0.2% of a 1 N·m transducer), the supply-pressure sensor 2 kPa (0.2% of
/// 1 MPa). A rig sized to its motor has sensors ranged to what they measure, and a zero
/// error that is the same share of the range: flows × s^⅔, speeds × s^{-⅓}, torques × s
/// (`SizeLaw`); pressures do not change. `None` for quantities without one (time, the
/// throttle's conductance setting).
pub fn calibration_tolerance(q: Quantity, size: f64) -> Option<f64> {
    let f = |k: f64| size.powf(k);
    match q {
        Quantity::Flow1 | Quantity::Flow2 => Some(2e-5 * f(SizeLaw::MASS_FLOW)),
        Quantity::Speed => Some(2.0 * std::f64::consts::PI / 60.0 * f(SizeLaw::SPEED)),
        Quantity::Torque => Some(2e-3 * f(SizeLaw::TORQUE)),
        Quantity::PPort1 => Some(2e3),
        _ => None,
    }
}

/// Every compared channel of a dataset, in the cost's channel order.
#[derive(Debug, Clone)]
pub struct Target {
    /// The channels, in the cost's channel order.
    pub channels: Vec<ChannelTarget>,
    /// Systematic errors profiled out (none unless added).
    nuisances: Option<Nuisances>,
}

/// Noise standard deviation of samples in order (see the module documentation).
pub(crate) fn noise_sigma(y: &[f64]) -> f64 {
    let floor = (y.iter().fold(0.0f64, |m, v| m.max(v.abs())) / 4096.0).max(f64::MIN_POSITIVE);
    if y.len() < 5 {
        return floor;
    }
    let d: Vec<f64> = y.windows(3).map(|w| w[2] - 2.0 * w[1] + w[0]).collect();
    let mut abs: Vec<f64> = d.iter().map(|v| v.abs()).collect();
    abs.sort_by(f64::total_cmp);
    let median = abs[abs.len() / 2];
    // For Gaussian d with sd s, median |d| = 0.6745 s; keep |d| ≤ 5 s.
    let cut = 5.0 * median / 0.6745;
    let kept: Vec<f64> = d.iter().copied().filter(|v| v.abs() <= cut).collect();
    if kept.is_empty() {
        return floor;
    }
    let ms = kept.iter().map(|v| v * v).sum::<f64>() / kept.len() as f64;
    (ms / 6.0).sqrt().max(floor)
}

/// What `smooth_inputs` did to one recorded input column.
#[derive(Debug, Clone, PartialEq)]
pub struct InputSmoothing {
    /// The recording.
    pub file: String,
    /// The input column.
    pub column: String,
    /// Noise of the recorded column (SI; relative for a conductance, whose log10 is smoothed).
    pub noise: f64,
    /// RMS of smooth − recorded (same scale as `noise`).
    pub(crate) rms_change: f64,
    /// Degree of the smooth (highest over its pieces); `None` when left as recorded.
    pub degree: Option<usize>,
}

/// Errors in variables. A transient experiment is driven by its RECORDED input columns
/// (port-1 pressure, port-2 conductance), which carry their own sensor noise; the
/// experiment's schedule averages them in bins of ~n/64 samples, which leaves input errors
/// of σ_in/√(n/64) that stay constant over a bin. The outputs follow them (the ramp's speed
/// moves ≈ 1.6 rad/s per kPa, so 1 kPa of pressure noise leaves ≈ 0.5 rad/s, one noise σ of
/// a speed sensor, correlated over a second), and a flexible candidate fits that structure:
/// on clean synthetic data a breakaway friction then "wins" by ΔBIC −80. So the diagnosis
/// drives the simulation with the least-squares smooth of each input column in time (the
/// reference method: Chebyshev polynomial, degree by cross-validation, pieces at jumps), whose
/// error is σ_in·√(p/n) and smooth, when that smooth describes the column to within its noise
/// (its residual σ at most 1.2 times the second-difference noise of the column); otherwise the
/// column is used as recorded. The conductance is smoothed as log10.
pub(crate) fn smooth_inputs(ds: &Dataset) -> (Dataset, Vec<InputSmoothing>) {
    let mut out = ds.clone();
    let mut notes = Vec::new();
    for ex in &mut out.experiments {
        if !ex.kind.is_transient() {
            continue;
        }
        let Some(times) = ex.recording.column(Quantity::Time).map(|c| c.si.clone()) else {
            continue;
        };
        for col in &mut ex.recording.columns {
            let log = match col.quantity {
                Quantity::PPort1 => false,
                Quantity::CPort2 => true,
                _ => continue,
            };
            let v: Vec<f64> = if log {
                if col.si.iter().any(|c| *c <= 0.0) {
                    continue;
                }
                col.si.iter().map(|c| c.log10()).collect()
            } else {
                col.si.clone()
            };
            let noise = noise_sigma(&v);
            let smooth = Reference::fit(&times, &v, &ReferenceOptions::default()).ok();
            let accepted = smooth
                .as_ref()
                .filter(|r| r.sigma_residual() <= 1.2 * noise);
            let scale = if log { std::f64::consts::LN_10 } else { 1.0 };
            let mut note = InputSmoothing {
                file: ex.file.clone(),
                column: col.name.clone(),
                noise: noise * scale,
                rms_change: 0.0,
                degree: None,
            };
            if let Some(r) = accepted {
                let new: Vec<f64> = times
                    .iter()
                    .zip(&v)
                    .map(|(t, old)| r.eval(*t).unwrap_or(*old))
                    .collect();
                note.rms_change = (new
                    .iter()
                    .zip(&v)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    / v.len().max(1) as f64)
                    .sqrt()
                    * scale;
                note.degree = Some(r.degree());
                col.si = if log {
                    new.iter().map(|x| 10f64.powf(*x)).collect()
                } else {
                    new
                };
            }
            notes.push(note);
        }
    }
    (out, notes)
}

impl Target {
    /// The compared rows of every channel of `cost` (built from `ds`), the recorded values
    /// there and each channel's noise, then each page's power peak (`super::peak`: the
    /// printed speed at max power and its reading tolerance).
    pub fn new(cost: &CostModel, ds: &Dataset) -> Result<Self, CostError> {
        let mut channels = Vec::new();
        for ex in cost.experiments() {
            let data = ds
                .experiments
                .iter()
                .find(|e| e.file == ex.file)
                .ok_or_else(|| CostError::NotInDataset(ex.file.clone()))?;
            let abscissa = ex.abscissa();
            for r in cost.references().filter(|r| r.file == ex.file) {
                let values = data.recording.values(r.quantity)?;
                let rows = compared_rows(&abscissa, &r.reference, values);
                let ordered: Vec<f64> = match data.kind {
                    Kind::Datasheet => {
                        let mut idx: Vec<usize> = (0..values.len()).collect();
                        idx.sort_by(|a, b| abscissa[*a].total_cmp(&abscissa[*b]));
                        idx.iter().map(|&i| values[i]).collect()
                    }
                    _ => values.to_vec(),
                };
                channels.push(ChannelTarget {
                    stated: data.tolerance.is_some(),
                    file: ex.file.clone(),
                    quantity: r.quantity,
                    data: rows.iter().map(|&i| values[i]).collect(),
                    rows,
                    // Stated data (a catalogue) carry their reading tolerance, not noise.
                    sigma: match data.tolerance {
                        Some(_) => r.reference.sigma(),
                        None => noise_sigma(&ordered),
                    },
                });
            }
        }
        // Each page's power peak, after every channel as the cost simulates it.
        channels.extend(cost.peaks().iter().map(|p| ChannelTarget {
            file: p.file.clone(),
            quantity: Quantity::Speed,
            rows: vec![p.row],
            data: vec![p.speed_rad_s],
            sigma: p.sigma_rad_s,
            stated: true,
        }));
        Ok(Self {
            channels,
            nuisances: None,
        })
    }

    /// The same target with a constant offset of each compared sensor as a nuisance, with
    /// the sensor's [`calibration_tolerance`] for a motor `size` times AR034-11's as prior σ
    /// (one per channel and recording).
    pub(crate) fn with_offsets(self, size: f64) -> Self {
        let n = self.n_points();
        let mut items = Vec::new();
        let mut start = 0;
        for c in &self.channels {
            if let Some(tau) = calibration_tolerance(c.quantity, size).filter(|_| !c.stated) {
                let mut shape = vec![0.0; n];
                shape[start..start + c.rows.len()].fill(1.0);
                items.push(Nuisance {
                    label: format!("{} {} offset", c.file, c.quantity.prefix()),
                    prior_sd: tau,
                    shape,
                });
            }
            start += c.rows.len();
        }
        self.with_nuisances(items)
    }

    /// The same target with a geared page's unprinted gearbox efficiency as a nuisance:
    /// its pages were moved to the motor shaft with the prior's median η̂
    /// (`model::gear::Gear::prior`), so if the true η is η̂·e^δ every stated torque and
    /// power is off by the factor e^−δ ≈ 1 − δ, one δ for all of them, with prior
    /// σ(δ) = `ln_sd`. The nuisance's shape is the stated value itself on the torque and
    /// power rows (0 elsewhere), which profiled out (`super::nuisance`) widens the
    /// intervals of what sets the torque's scale, so that `predict`'s bands hold η's spread.
    /// Unchanged when `ln_sd` is not > 0 (η printed) or no torque or power is stated.
    pub(crate) fn with_gear_efficiency(self, ln_sd: f64) -> Self {
        let shape: Vec<f64> = self
            .channels
            .iter()
            .flat_map(|c| {
                let scaled = c.stated && matches!(c.quantity, Quantity::Torque | Quantity::Power);
                c.data.iter().map(move |v| if scaled { *v } else { 0.0 })
            })
            .collect();
        if ln_sd.is_nan() || ln_sd <= 0.0 || shape.iter().all(|v| *v == 0.0) {
            return self;
        }
        self.with_nuisances(vec![Nuisance {
            label: "gearbox efficiency (ln η, prior)".into(),
            prior_sd: ln_sd,
            shape,
        }])
    }

    /// The same target with `more` nuisances added (shapes over every compared row, in
    /// channel order); unchanged if they do not fit the rows.
    pub(crate) fn with_nuisances(mut self, more: Vec<Nuisance>) -> Self {
        let mut items: Vec<Nuisance> = self
            .nuisances
            .as_ref()
            .map(|n| n.items().to_vec())
            .unwrap_or_default();
        items.extend(more);
        let sigma: Vec<f64> = self
            .channels
            .iter()
            .flat_map(|c| std::iter::repeat_n(c.sigma, c.rows.len()))
            .collect();
        if let Some(n) = Nuisances::new(items, &sigma) {
            self.nuisances = Some(n);
        }
        self
    }

    /// The same target with each channel's σ multiplied by its factor (same order; factors
    /// below 1 are taken as 1), the nuisances re-normalised to the new σ.
    pub fn widened(&self, factors: &[f64]) -> Self {
        let mut out = self.clone();
        for (c, k) in out.channels.iter_mut().zip(factors) {
            c.sigma *= k.max(1.0);
        }
        let items: Vec<Nuisance> = out
            .nuisances
            .take()
            .map(|n| n.items().to_vec())
            .unwrap_or_default();
        out.with_nuisances(items)
    }

    /// The nuisances profiled out, if any.
    pub fn nuisances(&self) -> Option<&Nuisances> {
        self.nuisances.as_ref()
    }

    /// Number of compared points.
    pub fn n_points(&self) -> usize {
        self.channels.iter().map(|c| c.rows.len()).sum()
    }

    /// The residual vector of simulated values (one list per channel, the compared rows):
    /// (simulated − recorded)/σ, corrected by the profiled nuisances, whose prior rows follow
    /// (see [`super::nuisance`]); its squares sum to χ².
    pub(crate) fn residual_vector(&self, simulated: &[Vec<f64>]) -> Vec<f64> {
        let mut u = Vec::with_capacity(self.n_points() + 16);
        for (t, s) in self.channels.iter().zip(simulated) {
            t.normalised(s, &mut u);
        }
        if let Some(n) = &self.nuisances {
            n.apply(&mut u);
        }
        u
    }

    /// The profiled nuisances β̂ for simulated values (label and value in the nuisance's unit,
    /// SI); empty without nuisances.
    pub(crate) fn nuisance_estimates(&self, simulated: &[Vec<f64>]) -> Vec<(String, f64)> {
        let Some(n) = &self.nuisances else {
            return Vec::new();
        };
        let mut u = Vec::with_capacity(self.n_points());
        for (t, s) in self.channels.iter().zip(simulated) {
            t.normalised(s, &mut u);
        }
        n.items()
            .iter()
            .map(|it| it.label.clone())
            .zip(n.estimate(&u))
            .collect()
    }

    /// Per channel χ² of simulated values at the compared rows (same channel order):
    /// Σ((sim − data)/σ)² after the nuisances' correction (their prior terms are not in any
    /// channel).
    pub(crate) fn channel_chi2(&self, simulated: &[Vec<f64>]) -> Vec<f64> {
        let r = self.residual_vector(simulated);
        let mut start = 0;
        self.channels
            .iter()
            .map(|c| {
                let part = &r[start..start + c.rows.len()];
                start += c.rows.len();
                part.iter().map(|v| v * v).sum()
            })
            .collect()
    }

    /// The residual vector for a motor, or `None` if the simulation fails or a residual is
    /// not finite.
    pub fn residuals(
        &self,
        cost: &CostModel,
        motor: &Motor,
        solver: &DefaultSolver,
    ) -> Option<Vec<f64>> {
        let sim = cost.simulated_rows(motor, solver).ok()?;
        let r = self.residual_vector(&sim);
        r.iter().all(|v| v.is_finite()).then_some(r)
    }

    /// χ² for a motor (the squares of [`Target::residuals`]), or `None` if the simulation
    /// fails or is not finite.
    pub fn chi2(&self, cost: &CostModel, motor: &Motor, solver: &DefaultSolver) -> Option<f64> {
        let c: f64 = self
            .residuals(cost, motor, solver)?
            .iter()
            .map(|v| v * v)
            .sum();
        c.is_finite().then_some(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// The gearbox nuisance is the stated torques and powers themselves (one common gain),
    /// nothing on speed or air; none when η is printed or nothing is stated.
    #[test]
    fn the_gearbox_efficiency_is_a_gain_on_stated_torque_and_power() {
        let channel = |q, data: Vec<f64>, stated| ChannelTarget {
            file: "page.csv".into(),
            quantity: q,
            rows: (0..data.len()).collect(),
            data,
            sigma: 0.01,
            stated,
        };
        let page = Target {
            channels: vec![
                channel(Quantity::Speed, vec![100.0, 200.0], true),
                channel(Quantity::Torque, vec![0.3, 0.2], true),
                channel(Quantity::Power, vec![20.0, 40.0], true),
                channel(Quantity::Flow1, vec![0.004], true),
            ],
            nuisances: None,
        };
        let geared = page.clone().with_gear_efficiency(0.05);
        let items = geared.nuisances().unwrap().items();
        assert_eq!(items.len(), 1);
        assert_eq!(items[0].prior_sd, 0.05);
        assert_eq!(items[0].shape, vec![0.0, 0.0, 0.3, 0.2, 20.0, 40.0, 0.0]);
        // A common 3 % low reading of torque and power is absorbed up to its prior: the
        // profiled χ² is far below the unprofiled one.
        let sim: Vec<Vec<f64>> = geared
            .channels
            .iter()
            .map(|c| {
                let k = if matches!(c.quantity, Quantity::Torque | Quantity::Power) {
                    0.97
                } else {
                    1.0
                };
                c.data.iter().map(|v| v * k).collect()
            })
            .collect();
        let chi2 = |t: &Target| t.residual_vector(&sim).iter().map(|r| r * r).sum::<f64>();
        assert!(
            chi2(&geared) < 0.5 * chi2(&page),
            "{} {}",
            chi2(&geared),
            chi2(&page)
        );
        assert!(page.clone().with_gear_efficiency(0.0).nuisances().is_none());
        let mut recorded = page;
        recorded.channels.iter_mut().for_each(|c| c.stated = false);
        assert!(recorded.with_gear_efficiency(0.05).nuisances().is_none());
    }

    #[test]
    fn noise_of_a_smooth_curve_with_a_jump_is_the_noise() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        let d = Normal::new(0.0, 0.5).unwrap();
        let y: Vec<f64> = (0..600)
            .map(|i| {
                let t = i as f64 / 10.0;
                let jump = if i > 200 { 400.0 + 5.0 * t } else { 0.0 };
                1000.0 * (t / 60.0).powi(2) + jump + d.sample(&mut rng)
            })
            .collect();
        let s = noise_sigma(&y);
        assert!((s - 0.5).abs() < 0.05, "{s}");
    }
}
