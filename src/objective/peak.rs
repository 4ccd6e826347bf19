//! Where a catalogue page's power peaks (docs/model.md, "Cost J", the power-peak term).
//!
//! A page that prints its max power P̂ at a speed ω* says two things: the power there is P̂
//! (a row of the page's recording, compared like any other) and the power curve peaks there,
//! dP/dω = 0 at ω*. The second is a condition on the curve's shape, which no row states: a
//! table row prints no curve, and a model whose power peaks 20 % away from ω* still passes
//! through P̂ at ω* within its reading tolerance, because a peak is flat (a 20 % shift of
//! the peak changes the power at ω* by about 4 %, two reading tolerances).
//!
//! The model's peak speed ω_m is taken as the vertex of the parabola through its steady
//! power at ω*(1 − h), ω*, ω*(1 + h) ([`PEAK_STEP`] h = 5 %), and weighed as
//!
//! ```text
//!     r = (ω_m − ω*) / σ_ω,    σ_ω = tolerance · max ω                            [1]
//! ```
//!
//! σ_ω is the printed speed's reading tolerance, taken as every stated channel's is: the
//! page's `tolerance` times the channel's full scale (the largest speed the page prints,
//! its free speed where printed). Why the vertex is a fair estimate: near its peak a smooth
//! power curve is P₀ + a·d² + c·d³ (d = ω − ω_peak); the parabola through three points
//! h·ω* apart places its vertex within c·h²·ω*²/(2|a|) of the true peak when ω* is there,
//! 0.1–0.3 % of ω* for h = 5 % on the model's curves (against σ_ω of 2–4 % of ω*), and exactly
//! for a quadratic power curve such as P = T₀·ω·(1 − ω/ω_f). A parabola is used rather than
//! a numerical dP/dω = 0 because its vertex is a speed, comparable with the printed one
//! on the page's own tolerance, and because h is wide enough that the power differences
//! (h²·P·ω²|P''|/P ≈ 0.25 % of P at h = 5 %) stand far above the steady solver's error.
//! Where the model's power is not concave over the three speeds it has no peak there: the
//! evaluation fails ([`SimError::NoPowerPeak`]), which the cost turns into its finite
//! failure penalty like any failed simulation.

use crate::data::dataset::catalogue::power_peak_row;
use crate::model::motor::Motor;
use crate::sim::experiment::SimError;
use crate::sim::operating_point::{at_speeds, Conditions};
use crate::sim::recording::ExperimentData;
use crate::units::{Quantity, Unit};

/// Half-spacing h of the speeds ω*(1 − h), ω*, ω*(1 + h) at which the model's power is
/// evaluated, relative to ω* (see the module documentation for why 5 %).
pub(crate) const PEAK_STEP: f64 = 0.05;

/// One page's power-peak condition (eq. \[1\] of the module documentation).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct PowerPeak {
    /// The page's recording file name as given in rig.toml.
    pub(crate) file: String,
    /// The recording row of the printed max-power point (0-based).
    pub(crate) row: usize,
    /// The printed speed at max power ω*, at the motor shaft, rad/s.
    pub(crate) speed_rad_s: f64,
    /// Its reading tolerance σ_ω, rad/s.
    pub(crate) sigma_rad_s: f64,
    /// The experiment's weight w_e.
    pub(crate) weight: f64,
    /// The page's supply.
    conditions: Conditions,
}

impl PowerPeak {
    /// The condition of a catalogue page that prints its max power at a speed (`None` for
    /// any other experiment or page).
    pub(crate) fn of(data: &ExperimentData, p_atm_pa: f64) -> Option<Self> {
        let tolerance = data.tolerance?;
        let row = power_peak_row(data)?;
        let speeds = data.recording.values(Quantity::Speed).ok()?;
        let speed_rad_s = *speeds.get(row)?;
        let full_scale = speeds
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let sigma_rad_s = tolerance * full_scale;
        let p_supply_pa = data.p_supply_pa?;
        (speed_rad_s > 0.0 && sigma_rad_s > 0.0).then(|| Self {
            file: data.file.clone(),
            row,
            speed_rad_s,
            sigma_rad_s,
            weight: data.weight,
            conditions: Conditions::supplied(p_supply_pa, p_atm_pa),
        })
    }

    /// The model's peak speed ω_m, rad/s: the vertex of its power at ω*(1 ∓ h) and ω*.
    /// An error where a steady state is not found or the power has no maximum there.
    pub(crate) fn simulate(&self, motor: &Motor) -> Result<f64, SimError> {
        let w = self.speed_rad_s;
        let speeds = [w * (1.0 - PEAK_STEP), w, w * (1.0 + PEAK_STEP)];
        let points =
            at_speeds(motor, &self.conditions, &speeds).map_err(|source| SimError::Steady {
                experiment: self.file.clone(),
                source,
            })?;
        let power = [points[0].power_w, points[1].power_w, points[2].power_w];
        parabola_vertex(w, PEAK_STEP * w, power).ok_or_else(|| SimError::NoPowerPeak {
            experiment: self.file.clone(),
            speed_rpm: Unit::Rpm.from_si(w, 0.0),
        })
    }

    /// r of eq. \[1\] for the model's peak speed `peak_rad_s`.
    pub(crate) fn residual(&self, peak_rad_s: f64) -> f64 {
        (peak_rad_s - self.speed_rad_s) / self.sigma_rad_s
    }
}

/// The abscissa of the maximum of the parabola through (x₀ − Δ, y₀), (x₀, y₁), (x₀ + Δ, y₂):
///
/// ```text
///     x_v = x₀ + Δ · (y₀ − y₂) / (2·(y₀ − 2y₁ + y₂))
/// ```
///
/// `None` where the parabola has no maximum (y₀ − 2y₁ + y₂ ≥ 0) or a value is not finite.
pub(crate) fn parabola_vertex(x0: f64, dx: f64, y: [f64; 3]) -> Option<f64> {
    let curvature = y[0] - 2.0 * y[1] + y[2];
    // Written so that a NaN curvature is refused too.
    if !(curvature < 0.0) {
        return None;
    }
    let x = x0 + dx * (y[0] - y[2]) / (2.0 * curvature);
    x.is_finite().then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// P = T₀·ω·(1 − ω/ω_f) peaks at ω_f/2 (dP/dω = T₀·(1 − 2ω/ω_f) = 0), wherever the
    /// three speeds are taken around it.
    #[test]
    fn the_vertex_of_a_linear_torque_curve_is_half_the_free_speed() {
        let (t0, wf) = (0.8, 1200.0);
        let power = |w: f64| t0 * w * (1.0 - w / wf);
        for centre in [300.0, 550.0, 600.0, 700.0, 1000.0] {
            for h in [0.01, PEAK_STEP, 0.2] {
                let dx = h * centre;
                let y = [power(centre - dx), power(centre), power(centre + dx)];
                let v = parabola_vertex(centre, dx, y).expect("concave");
                assert!((v - wf / 2.0).abs() < 1e-9 * wf, "{centre} {h}: {v}");
            }
        }
    }

    #[test]
    fn a_curve_without_a_maximum_has_no_vertex() {
        assert_eq!(parabola_vertex(1.0, 0.1, [1.0, 1.0, 1.0]), None);
        assert_eq!(parabola_vertex(1.0, 0.1, [1.0, 0.5, 1.0]), None);
        assert_eq!(parabola_vertex(1.0, 0.1, [1.0, f64::NAN, 1.0]), None);
    }

    /// A cubic power curve P₀ − a·d² + c·d³ about its peak: the vertex lies within
    /// c·Δ²/(2a) of it (the module documentation's bound).
    #[test]
    fn the_vertex_of_a_skewed_peak_is_within_the_stated_bound() {
        let (peak, a, c) = (500.0, 1e-3, 1e-6);
        let power = |w: f64| 100.0 - a * (w - peak).powi(2) + c * (w - peak).powi(3);
        let dx = PEAK_STEP * peak;
        let y = [power(peak - dx), power(peak), power(peak + dx)];
        let v = parabola_vertex(peak, dx, y).expect("concave");
        assert!((v - peak).abs() <= c * dx * dx / (2.0 * a) * (1.0 + 1e-9), "{v}");
    }
}
