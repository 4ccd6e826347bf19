//! The datasheet experiment (docs/model.md, "Reference experiments"): steady states at
//! imposed speeds and supply pressures, one per row; measured torque and flows against
//! speed.

use super::{missing, AbscissaSpec, Drive, ExperimentKind, InputCheck, Setting, SimError, Simulated};
use crate::model::motor::{Boundary, Load, Motor, State};
use crate::numerics::ode::StiffSolver;
use crate::sim::operating_point::shaft_torque;
use crate::sim::recording::ExperimentData;
use crate::sim::steady;
use crate::units::Quantity;
use std::sync::Arc;

/// The kind (see the module documentation).
pub(crate) struct Datasheet;

impl ExperimentKind for Datasheet {
    fn id(&self) -> &'static str {
        "datasheet"
    }
    fn inputs(&self) -> &'static [InputCheck] {
        &[
            InputCheck::Column(Quantity::Speed),
            InputCheck::Spans(Quantity::Speed, 0.05),
            InputCheck::Supply,
        ]
    }
    fn channels(&self) -> &'static [Quantity] {
        &[Quantity::Torque, Quantity::Flow1, Quantity::Flow2]
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
        let p_supply = match data.p_supply_pa {
            Some(p) => vec![p; rec.rows()],
            None => rec
                .column(Quantity::PPort1)
                .map(|c| c.si.clone())
                .unwrap_or_default(),
        };
        Ok(Arc::new(SteadySweep { speeds, p_supply }))
    }
}

/// Steady states at imposed speeds (rad/s) and supply pressures (Pa), one per row.
#[derive(Debug, Clone)]
struct SteadySweep {
    speeds: Vec<f64>,
    p_supply: Vec<f64>,
}

impl Drive for SteadySweep {
    fn abscissa(&self) -> Vec<f64> {
        self.speeds.clone()
    }

    fn simulate(
        &self,
        setting: &Setting<'_>,
        motor: &Motor,
        _solver: &dyn StiffSolver,
    ) -> Result<Simulated, SimError> {
        let rows = steady_sweep(setting, motor, &self.speeds, &self.p_supply)?;
        Ok(Simulated {
            outputs: vec![
                (Quantity::Torque, rows.iter().map(|r| r[0]).collect()),
                (Quantity::Flow1, rows.iter().map(|r| r[1]).collect()),
                (Quantity::Flow2, rows.iter().map(|r| r[2]).collect()),
            ],
        })
    }
}

/// Steady states at imposed speeds (rad/s) and supply pressures (Pa), one per row, in the
/// rows' order: `[shaft torque N·m, port-1 flow kg/s, port-2 flow kg/s]`; each row may have
/// its own supply pressure (a p_port1 column), which `operating_point::at_speeds` (one
/// pressure) does not allow.
fn steady_sweep(
    setting: &Setting<'_>,
    motor: &Motor,
    speeds: &[f64],
    p_supply: &[f64],
) -> Result<Vec<[f64; 3]>, SimError> {
    let n = speeds.len();
    // Sweep in speed order so that each solve starts from its neighbour's solution.
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|a, b| speeds[*a].total_cmp(&speeds[*b]));
    let mut results = vec![[0.0; 3]; n];
    // The last two solutions and their rows: each solve starts from the line through them.
    let mut last: Option<(usize, State)> = None;
    let mut before: Option<(usize, State)> = None;
    for &i in &order {
        let bc = Boundary::supplied(p_supply[i], setting.p_atm_pa, Load::None);
        let start = last.map(|l| secant_guess(speeds, p_supply, i, l, before));
        let near = start.map(|g| steady::at_speed_from_neighbour(motor, &bc, speeds[i], &g));
        let x = near
            .filter(Result::is_ok)
            .unwrap_or_else(|| steady::at_speed(motor, &bc, speeds[i], &steady::initial_guess(&bc)))
            .map_err(|source| SimError::SteadyRow {
                experiment: setting.file.to_string(),
                row: i + 1,
                source,
            })?;
        let b = motor.balance(&x, &bc);
        // At standstill the brake holds the rotor against the full dry friction.
        let torque = shaft_torque(motor, &x, &b);
        results[i] = [torque, b.flow_port1_kg_s, b.flow_port2_kg_s];
        before = last;
        last = Some((i, x));
    }
    Ok(results)
}

/// The start of row `i`'s steady solve: the pressures extrapolated along the line through
/// the last two solutions (`last` and `before`, each a row and its state, at the same supply
/// pressure and two different speeds), else the last solution itself. On the shipped
/// 25-speed datasheet the line's guess saves about one Newton iteration per speed
/// (callgrind, see docs/performance.md); a guess with a pressure at or below zero falls back
/// to the last solution.
fn secant_guess(
    speeds: &[f64],
    p_supply: &[f64],
    i: usize,
    last: (usize, State),
    before: Option<(usize, State)>,
) -> State {
    let (l, x) = last;
    let Some((b, xb)) = before else {
        return x;
    };
    let span = speeds[l] - speeds[b];
    if p_supply[l] != p_supply[i] || p_supply[b] != p_supply[i] || span == 0.0 {
        return x;
    }
    let s = (speeds[i] - speeds[l]) / span;
    let line: State = std::array::from_fn(|k| x[k] + s * (x[k] - xb[k]));
    if line[..3].iter().all(|p| *p > 0.0 && p.is_finite()) {
        line
    } else {
        x
    }
}
