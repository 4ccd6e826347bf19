//! Where a catalogue page's power peaks (docs/model.md, "Cost J", the power-peak term).
//!
//! A page that prints its max power P̂ at a speed ω* says two things: the power there is P̂
//! (a row of the page's recording, compared like any other) and the power curve peaks there,
//! dP/dω = 0 at ω*. The second is a condition on the curve's shape, which no row states: a
//! table row prints no curve, and a model whose power peaks 20 % away from ω* still passes
//! through P̂ at ω* within its reading tolerance, because a peak is flat (a 20 % shift of
//! the peak changes the power at ω* by about 4 %, two reading tolerances). The catalogue
//! sweep gives the model's peak speed ω_m (`sim::experiment::catalogue`: the vertex of its
//! power at ω* and 5 % either side, and why that is a fair estimate); it is weighed as
//!
//! ```text
//!     r = (ω_m − ω*) / σ_ω,    σ_ω = tolerance · max ω                            [1]
//! ```
//!
//! σ_ω is the printed speed's reading tolerance, taken as every stated channel's is: the
//! page's `tolerance` times the channel's full scale (the largest speed the page prints, its
//! free speed where printed). Where the model's power is not concave around ω* it has no
//! peak there: the evaluation fails ([`SimError::NoPowerPeak`]), which the cost turns into
//! its finite failure penalty like any failed simulation.

use crate::data::dataset::catalogue::power_peak_row;
use crate::sim::experiment::{SimError, Simulated};
use crate::sim::recording::ExperimentData;
use crate::units::{Quantity, Unit};

/// One page's power-peak condition (eq. \[1\] of the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PowerPeak {
    /// The page's recording file name as given in rig.toml.
    pub(crate) file: String,
    /// The page's index among the dataset's experiments.
    pub(crate) experiment: usize,
    /// The recording row of the printed max-power point (0-based).
    pub(crate) row: usize,
    /// The printed speed at max power ω*, at the motor shaft, rad/s.
    pub(crate) speed_rad_s: f64,
    /// Its reading tolerance σ_ω, rad/s.
    pub(crate) sigma_rad_s: f64,
    /// The experiment's weight w_e.
    pub(crate) weight: f64,
}

impl PowerPeak {
    /// The condition of `data`, the dataset's experiment number `experiment`, where it is a
    /// catalogue page that prints its max power at a speed (`None` for any other).
    pub(crate) fn of(data: &ExperimentData, experiment: usize) -> Option<Self> {
        let tolerance = data.tolerance?;
        let row = power_peak_row(data)?;
        let speeds = data.recording.values(Quantity::Speed).ok()?;
        let speed_rad_s = *speeds.get(row)?;
        let full_scale = speeds
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let sigma_rad_s = tolerance * full_scale;
        (speed_rad_s > 0.0 && sigma_rad_s > 0.0).then(|| Self {
            file: data.file.clone(),
            experiment,
            row,
            speed_rad_s,
            sigma_rad_s,
            weight: data.weight,
        })
    }

    /// The model's peak speed ω_m, rad/s, from its page's simulation; an error where the
    /// power has no maximum around ω*.
    pub(crate) fn peak_speed(&self, sim: &Simulated) -> Result<f64, SimError> {
        sim.channel(Quantity::Speed)
            .and_then(|v| v.get(self.row).copied())
            .filter(|w| w.is_finite())
            .ok_or_else(|| SimError::NoPowerPeak {
                experiment: self.file.clone(),
                speed_rpm: Unit::Rpm.from_si(self.speed_rad_s, 0.0),
            })
    }

    /// r of eq. \[1\] for the model's peak speed `peak_rad_s`.
    pub(crate) fn residual(&self, peak_rad_s: f64) -> f64 {
        (peak_rad_s - self.speed_rad_s) / self.sigma_rad_s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn peak() -> PowerPeak {
        PowerPeak {
            file: "rig.toml".into(),
            experiment: 0,
            row: 1,
            speed_rad_s: 600.0,
            sigma_rad_s: 24.0,
            weight: 1.0,
        }
    }

    /// A page whose model has no power maximum around ω* (the sweep's NaN) is an error,
    /// which the cost turns into its finite penalty; a peak 36 rad/s above ω* is 1.5 σ_ω.
    #[test]
    fn no_peak_is_an_error_and_a_peak_is_its_distance_in_tolerances() {
        let sim = |w: f64| Simulated {
            outputs: vec![(Quantity::Speed, vec![w; 3])],
        };
        assert!(matches!(
            peak().peak_speed(&sim(f64::NAN)),
            Err(SimError::NoPowerPeak { .. })
        ));
        let w = peak().peak_speed(&sim(636.0)).unwrap();
        assert!((peak().residual(w) - 1.5).abs() < 1e-12);
    }
}
