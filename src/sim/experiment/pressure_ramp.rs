//! The pressure ramp (docs/model.md, "Reference experiments"): a transient driven by the
//! recorded supply pressure at port 1; measured flows, speed and torque against that
//! pressure.

use super::transient::{supply_schedule, SupplyFrom, Transient, CHANNELS};
use super::{missing, AbscissaSpec, Drive, ExperimentKind, InputCheck, SimError};
use crate::sim::recording::ExperimentData;
use crate::units::Quantity;
use std::sync::Arc;

/// The kind (see the module documentation).
pub(crate) struct PressureRamp;

impl ExperimentKind for PressureRamp {
    fn id(&self) -> &'static str {
        "pressure_ramp"
    }
    fn inputs(&self) -> &'static [InputCheck] {
        &[
            InputCheck::Column(Quantity::Time),
            InputCheck::Column(Quantity::PPort1),
            InputCheck::Spans(Quantity::PPort1, 0.05),
        ]
    }
    fn channels(&self) -> &'static [Quantity] {
        CHANNELS
    }
    fn abscissa(&self) -> AbscissaSpec {
        AbscissaSpec {
            quantity: Quantity::PPort1,
            log10: false,
        }
    }
    fn is_transient(&self) -> bool {
        true
    }
    /// The supply is the recorded port-1 pressure, smoothed (a constant `p_supply_mpa`
    /// only without that column).
    fn build(&self, data: &ExperimentData) -> Result<Arc<dyn Drive>, SimError> {
        let rec = &data.recording;
        let times = rec.values(Quantity::Time).map_err(missing(data))?.to_vec();
        let p_supply = supply_schedule(data, &times, SupplyFrom::Recording)?;
        Ok(Arc::new(Transient::new(times, p_supply, None)))
    }
}
