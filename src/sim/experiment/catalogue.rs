//! The catalogue experiment: a manufacturer's curves and key figures at one supply
//! pressure, read off a printed page. Like the datasheet (docs/model.md, "Reference
//! experiments", 1) it is a set of steady states at imposed speeds, but it measures shaft
//! torque, shaft power P = T·ω and air consumption (the port-1 flow) and its points are
//! sparse: a row may give any subset of them. Key figures arrive as rows too (the data
//! layer turns free speed, stall torque and the max-power point into points on these
//! curves), so the stall row at ω = 0 follows the datasheet's stall convention.

use super::{missing, AbscissaSpec, Drive, ExperimentKind, InputCheck, Setting, SimError, Simulated};
use crate::model::motor::Motor;
use crate::numerics::ode::StiffSolver;
use crate::sim::operating_point::{at_speeds, Conditions};
use crate::sim::recording::ExperimentData;
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
        }))
    }
}

/// Steady states at the catalogue's speeds (rad/s) and its supply pressure (Pa).
#[derive(Debug, Clone)]
struct CatalogueSweep {
    speeds: Vec<f64>,
    p_supply_pa: f64,
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
        let points = at_speeds(motor, &conditions, &self.speeds)
            .map_err(|e| setting.steady_failed(e))?;
        Ok(Simulated {
            outputs: vec![
                (Quantity::Torque, points.iter().map(|p| p.torque_nm).collect()),
                (Quantity::Power, points.iter().map(|p| p.power_w).collect()),
                (Quantity::Flow1, points.iter().map(|p| p.flow1_kg_s).collect()),
            ],
        })
    }
}
