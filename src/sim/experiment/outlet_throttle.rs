//! The outlet throttle (docs/model.md, "Reference experiments"): a transient at constant
//! supply driven by the recorded port-2 conductance; measured flows, speed and torque
//! against log10 of that conductance.

use super::transient::{supply_schedule, SupplyFrom, Transient, CHANNELS};
use super::{missing, AbscissaSpec, Drive, ExperimentKind, InputCheck, SimError};
use crate::sim::recording::ExperimentData;
use crate::sim::schedule::Schedule;
use crate::units::Quantity;
use std::sync::Arc;

/// The kind (see the module documentation).
pub(crate) struct OutletThrottle;

impl ExperimentKind for OutletThrottle {
    fn id(&self) -> &'static str {
        "outlet_throttle"
    }
    fn inputs(&self) -> &'static [InputCheck] {
        &[
            InputCheck::Column(Quantity::Time),
            InputCheck::Column(Quantity::CPort2),
            InputCheck::Supply,
            InputCheck::Positive(Quantity::CPort2, "conductance"),
            InputCheck::Spans(Quantity::CPort2, 0.05),
        ]
    }
    fn channels(&self) -> &'static [Quantity] {
        CHANNELS
    }
    fn abscissa(&self) -> AbscissaSpec {
        AbscissaSpec {
            quantity: Quantity::CPort2,
            log10: true,
        }
    }
    fn is_transient(&self) -> bool {
        true
    }
    /// The supply is `p_supply_mpa` (or the recorded port-1 pressure, smoothed); the
    /// throttle follows log10 of the recorded conductance, smoothed.
    fn build(&self, data: &ExperimentData) -> Result<Arc<dyn Drive>, SimError> {
        let rec = &data.recording;
        let times = rec.values(Quantity::Time).map_err(missing(data))?.to_vec();
        let p_supply = supply_schedule(data, &times, SupplyFrom::Rig)?;
        let c = rec.values(Quantity::CPort2).map_err(missing(data))?;
        let logc: Vec<f64> = c.iter().map(|v| v.log10()).collect();
        let log10_c_port2 = Some(Schedule::smoothed(&times, &logc));
        Ok(Arc::new(Transient::new(times, p_supply, log10_c_port2)))
    }
}
