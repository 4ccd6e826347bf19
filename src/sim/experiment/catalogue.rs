//! The catalogue experiment: a manufacturer's curves and key figures at one supply
//! pressure, read off a printed page. Like the datasheet (docs/model.md, "Reference
//! experiments", 1) it is a set of steady states at imposed speeds, but it measures shaft
//! torque, shaft power P = T·ω and air consumption (the port-1 flow) and its points are
//! sparse: a row may give any subset of them. Key figures arrive as rows too (the data
//! layer turns free speed, stall torque and the max-power point into points on these
//! curves), so the stall row at ω = 0 follows the datasheet's stall convention.
//!
//! A page that prints its max power at a speed ω* says too that its power curve peaks
//! there. The sweep then also gives, as its `speed` channel (the same value on every row),
//! the model's peak speed ω_m: the vertex of the parabola through its power at ω*(1 − h),
//! ω*, ω*(1 + h), h = [`PEAK_STEP`], solved in the same sweep as the rows (each started from
//! its nearest solved neighbour), NaN where the power is not concave there.
//!
//! Why the vertex is a fair estimate: near its peak a smooth power curve is
//! P₀ + a·d² + c·d³ (d = ω − ω_peak); the parabola through three points Δ = h·ω* apart
//! places its vertex c·Δ²/(2|a|) from the true peak when ω* is there, 0.1–0.3 % of ω* for
//! h = 5 % on the model's curves (against a reading tolerance of 2–4 % of ω*), and exactly on
//! a power curve quadratic in speed, P = T₀·ω·(1 − ω/ω_f), whose peak is ω_f/2. Why h = 5 %:
//! the power differences it leaves, h²·ω*²·|P''| ≈ 0.25 % of P, stand far above the steady
//! solver's error, and the cubic term's bias stays well inside the tolerance. The residual
//! it enters is the objective's (`objective::peak`).

use super::{missing, AbscissaSpec, Drive, ExperimentKind, InputCheck, Setting, SimError, Simulated};
use crate::model::motor::Motor;
use crate::numerics::ode::StiffSolver;
use crate::sim::operating_point::{at_speeds, Conditions};
use crate::sim::recording::{ExperimentData, Figure};
use crate::units::Quantity;
use std::sync::Arc;

/// The kind (see the module documentation).
pub struct Catalogue;

impl ExperimentKind for Catalogue {
    fn id(&self) -> &'static str {
        "catalogue"
    }
    fn inputs(&self) -> &'static [InputCheck] {
        &[InputCheck::Column(Quantity::Speed), InputCheck::Supply]
    }
    fn channels(&self) -> &'static [Quantity] {
        &[Quantity::Torque, Quantity::Power, Quantity::Flow1]
    }
    fn abscissa(&self) -> AbscissaSpec {
        AbscissaSpec {
            quantity: Quantity::Speed,
            log10: false,
        }
    }
    fn is_transient(&self) -> bool {
        false
    }
    fn build(&self, data: &ExperimentData) -> Result<Arc<dyn Drive>, SimError> {
        let rec = &data.recording;
        let speeds = rec.values(Quantity::Speed).map_err(missing(data))?.to_vec();
        let p_supply_pa = data
            .p_supply_pa
            .ok_or_else(|| SimError::CatalogueWithoutSupply {
                experiment: data.file.clone(),
            })?;
        Ok(Arc::new(CatalogueSweep {
            p_supply_pa,
            speeds,
            peak_rad_s: power_peak_speed(&data.figures),
        }))
    }
}

/// Half-spacing h of the speeds ω*(1 − h), ω*, ω*(1 + h) at which the model's power is
/// solved around a printed speed at max power, relative to ω* (module documentation).
pub const PEAK_STEP: f64 = 0.05;

/// The speed where a page says the power peaks, rad/s at the motor shaft: its
/// `speed_at_max_power` where it also prints `max_power` (a maker measures the power curve
/// and prints its maximum and where it lies). `None` on any other page.
pub fn power_peak_speed(figures: &[Figure]) -> Option<f64> {
    let si = |k: &str| figures.iter().find(|f| f.key == k).map(|f| f.si);
    si("max_power")?;
    si("speed_at_max_power").filter(|w| *w > 0.0)
}

/// The abscissa of the maximum of the parabola through (x₀ − Δ, y₀), (x₀, y₁), (x₀ + Δ, y₂):
///
/// ```text
///     x_v = x₀ + Δ · (y₀ − y₂) / (2·(y₀ − 2y₁ + y₂))
/// ```
///
/// `None` where the parabola has no maximum (y₀ − 2y₁ + y₂ ≥ 0) or a value is not finite.
pub fn parabola_vertex(x0: f64, dx: f64, y: [f64; 3]) -> Option<f64> {
    let curvature = y[0] - 2.0 * y[1] + y[2];
    // A NaN curvature is refused too.
    if curvature.is_nan() || curvature >= 0.0 {
        return None;
    }
    let x = x0 + dx * (y[0] - y[2]) / (2.0 * curvature);
    x.is_finite().then_some(x)
}

/// Steady states at the catalogue's speeds (rad/s) and its supply pressure (Pa), and the
/// speeds around a printed speed at max power, if any.
#[derive(Debug, Clone)]
struct CatalogueSweep {
    speeds: Vec<f64>,
    p_supply_pa: f64,
    peak_rad_s: Option<f64>,
}

impl Drive for CatalogueSweep {
    fn abscissa(&self) -> Vec<f64> {
        self.speeds.clone()
    }

    fn simulate(
        &self,
        setting: &Setting<'_>,
        motor: &Motor,
        _solver: &dyn StiffSolver,
    ) -> Result<Simulated, SimError> {
        // The operating points `predict` uses: one stall convention, one sweep.
        let conditions = Conditions::supplied(self.p_supply_pa, setting.p_atm_pa);
        let n = self.speeds.len();
        let mut speeds = self.speeds.clone();
        if let Some(w) = self.peak_rad_s {
            speeds.extend([w * (1.0 - PEAK_STEP), w, w * (1.0 + PEAK_STEP)]);
        }
        let points =
            at_speeds(motor, &conditions, &speeds).map_err(|e| setting.steady_failed(e))?;
        let (rows, probes) = points.split_at(n);
        let mut outputs = vec![
            (Quantity::Torque, rows.iter().map(|p| p.torque_nm).collect()),
            (Quantity::Power, rows.iter().map(|p| p.power_w).collect()),
            (Quantity::Flow1, rows.iter().map(|p| p.flow1_kg_s).collect()),
        ];
        if let (Some(w), [a, b, c]) = (self.peak_rad_s, probes) {
            let power = [a.power_w, b.power_w, c.power_w];
            let peak = parabola_vertex(w, PEAK_STEP * w, power).unwrap_or(f64::NAN);
            outputs.push((Quantity::Speed, vec![peak; n]));
        }
        Ok(Simulated { outputs })
    }
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
