//! `sensor_lag` (docs/model.md, "Missing-physics catalog"; measurement): the flow and speed
//! sensors lag their signal by a first order, y_m' = (y − y_m)/τ; it shows only in
//! transient recordings.

use super::{Category, CatalogEffect, Effect, ShowsIn, Term};
use crate::model::spec::{effect_params, Domain, OffValue, ParamSpec};

/// The effect (see the module documentation).
pub struct SensorLag;

effect_params! {
    /// Its parameter τ; off at the bottom of its search range.
    Effect::SensorLag {
        TAU_SENSOR tau_sensor: "s" = 0.5, Domain::Positive, (1e-3, 10.0),
            "first-order lag of the flow and speed sensors",
            size None, off OffValue::SearchLower;
    }
}

impl Term for SensorLag {
    /// The channel through `first_order_lag` with τ.
    fn measure(&self, own: &[f64], times: &[f64], y: Vec<f64>) -> Vec<f64> {
        first_order_lag(times, &y, own[TAU_SENSOR])
    }
}

impl CatalogEffect for SensorLag {
    fn id(&self) -> &'static str {
        "sensor_lag"
    }
    fn category(&self) -> Category {
        Category::Measurement
    }
    fn physics(&self) -> &'static str {
        "a sensor's first-order lag in transient recordings"
    }
    fn specs(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn shows_in(&self) -> ShowsIn {
        ShowsIn::TransientOnly {
            reason: "a sensor lag shows only in transient recordings; this dataset has \
                     steady-state experiments only",
        }
    }
}

/// A sensor's first-order lag y_m' = (y − y_m)/τ applied to samples of y, exact when y is
/// linear between samples (first-order hold); the sensor starts settled at y(t_0).
fn first_order_lag(times: &[f64], y: &[f64], tau: f64) -> Vec<f64> {
    let mut out = Vec::with_capacity(y.len());
    let Some(&first) = y.first() else { return out };
    let mut ym = first;
    out.push(ym);
    for k in 1..y.len() {
        let h = times[k] - times[k - 1];
        let a = (-h / tau).exp();
        let ramp = (y[k] - y[k - 1]) * (1.0 - tau / h * (1.0 - a));
        ym = a * ym + (1.0 - a) * y[k - 1] + ramp;
        out.push(ym);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_is_the_base_model() {
        crate::model::testing::reproduces_base(Effect::SensorLag, &[], 0.0);
    }

    #[test]
    fn sensor_lag_of_a_ramp_trails_by_tau() {
        // For y = t the settled lag output is t − τ(1 − e^{−t/τ}).
        let times: Vec<f64> = (0..200).map(|k| f64::from(k) * 0.05).collect();
        let tau = 0.7;
        let ym = SensorLag.measure(&[tau], &times, times.clone());
        for (t, v) in times.iter().zip(&ym) {
            let exact = t - tau * (1.0 - (-t / tau).exp());
            assert!((v - exact).abs() < 1e-12, "t {t}: {v} vs {exact}");
        }
    }
}
