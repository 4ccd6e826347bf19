//! What a fit is scored on: the cost J (docs/model.md, "Cost J"; on the dataset as
//! recorded) and the likelihood of the recorded rows (inputs smoothed, sensor offsets and
//! the supply-pressure sensor's offset as nuisances); see [`crate::estimate::fit`] for how the two
//! are used.

use crate::data::dataset::Dataset;
use crate::data::fitfile::FitConditions;
use crate::estimate::fit::goodness::ChannelChi2;
use crate::model::motor::Motor;
use crate::numerics::DefaultSolver;
use crate::objective::cost::{CostError, CostModel, CostOptions};
use crate::objective::likelihood::{calibration_tolerance, smooth_inputs, InputSmoothing, Target};
use crate::objective::nuisance::Nuisance;
use crate::units::Quantity;

/// What a fit is scored on: the cost J that the multi-start minimises, and the likelihood of
/// the recorded rows that gives the estimate, its intervals and its goodness of fit.
pub struct FitData {
    /// J (docs/model.md, "Cost J") on the dataset as recorded.
    pub cost: CostModel,
    /// The same experiments driven by the smooth of each recorded input column.
    pub smoothed: CostModel,
    /// The recorded rows, their noise, and the sensors' calibration offsets as nuisances.
    pub target: Target,
    /// What the smoothing did to each input column.
    pub inputs: Vec<InputSmoothing>,
    /// The atmosphere and the supply pressures the recordings cover (as recorded, before
    /// any smoothing), exported with the fit.
    pub conditions: FitConditions,
    /// `smoothed` with the recorded supply pressure raised by [`PRESSURE_STEP_PA`] (for the
    /// pressure sensor's offset; `None` when no experiment records that pressure).
    raised: Option<CostModel>,
}

/// The step by which the supply pressure's effect on the rows is differenced, Pa: 1 kPa,
/// half the sensor's tolerance, where the response is linear and far above solver jitter.
const PRESSURE_STEP_PA: f64 = 1e3;

impl FitData {
    /// The cost and the likelihood of a dataset.
    pub fn new(ds: &Dataset, options: CostOptions) -> Result<Self, CostError> {
        let cost = CostModel::new(ds, options)?;
        let (smooth_ds, inputs) = smooth_inputs(ds);
        let smoothed = CostModel::new(&smooth_ds, options)?;
        let gear_ln_sd = ds.gear().map_or(0.0, |g| g.efficiency_ln_sd);
        // The sensors' calibration tolerances follow the rig, which follows the motor's size.
        let size = ds.nominal_params().map_or(1.0, |p| p.size());
        let target = Target::new(&smoothed, &smooth_ds)?
            .with_offsets(size)
            .with_gear_efficiency(gear_ln_sd);
        let raised = match raise_supply(&smooth_ds) {
            Some(ds) => Some(CostModel::new(&ds, options)?),
            None => None,
        };
        Ok(Self {
            cost,
            smoothed,
            target,
            inputs,
            conditions: FitConditions::of(ds.p_atm_pa, &ds.experiments),
            raised,
        })
    }

    /// The likelihood's target with the supply-pressure sensor's offset as one more nuisance:
    /// its effect on every compared row is the simulation's response to a raised recorded
    /// pressure, differenced at `motor` (the rows respond linearly to 2 kPa, and the
    /// response hardly changes over a parameter's interval). The target as it is when no
    /// experiment records the pressure or the rows do not match.
    pub fn target_at(&self, motor: &Motor) -> Target {
        let solver = DefaultSolver::default();
        let Some(raised) = &self.raised else {
            return self.target.clone();
        };
        let (Ok(base), Ok(up)) = (
            self.smoothed.simulated_rows(motor, &solver),
            raised.simulated_at_rows(motor, &solver, &self.smoothed.rows()),
        ) else {
            return self.target.clone();
        };
        if base.len() != up.len() || base.iter().zip(&up).any(|(a, b)| a.len() != b.len()) {
            return self.target.clone();
        }
        let shape: Vec<f64> = base
            .iter()
            .flatten()
            .zip(up.iter().flatten())
            .map(|(a, b)| (b - a) / PRESSURE_STEP_PA)
            .collect();
        // A pressure sensor's tolerance does not depend on the motor's size.
        let tau = calibration_tolerance(Quantity::PPort1, 1.0).unwrap_or(PRESSURE_STEP_PA);
        self.target.clone().with_nuisances(vec![Nuisance {
            label: "supply pressure sensor offset".into(),
            prior_sd: tau,
            shape,
        }])
    }

    /// The simulated values at every compared row of the likelihood (`None` if the
    /// simulation fails).
    pub fn simulate(&self, motor: &Motor) -> Option<Vec<Vec<f64>>> {
        self.smoothed
            .simulated_rows(motor, &DefaultSolver::default())
            .ok()
    }

    /// Each channel's χ² under the likelihood of `target`, from [`FitData::simulate`]'s values,
    /// then each page's power-peak term (one row each), labelled as [`FitData::labels`].
    pub(crate) fn channel_chi2(&self, target: &Target, simulated: &[Vec<f64>]) -> Vec<ChannelChi2> {
        self.labels()
            .into_iter()
            .zip(simulated)
            .zip(target.channel_chi2(simulated))
            .map(|((label, s), c)| ChannelChi2 {
                label,
                chi2: c,
                n: s.len(),
            })
            .collect()
    }

    /// The label of every compared channel ("file column"), then of each page's power-peak
    /// term ("file power peak at speed_at_max_power"), in the likelihood's order.
    pub(crate) fn labels(&self) -> Vec<String> {
        let channels = self
            .smoothed
            .references()
            .map(|r| format!("{} {}", r.file, r.column));
        let peaks = self
            .smoothed
            .peaks()
            .iter()
            .map(|p| format!("{} {}", p.file, crate::objective::PEAK_COLUMN));
        channels.chain(peaks).collect()
    }
}

/// The dataset with every recorded port-1 pressure raised by [`PRESSURE_STEP_PA`] (`None`
/// when none is recorded).
fn raise_supply(ds: &Dataset) -> Option<Dataset> {
    let mut out = ds.clone();
    let mut any = false;
    for col in out
        .experiments
        .iter_mut()
        .flat_map(|e| e.recording.columns.iter_mut())
        .filter(|c| c.quantity == Quantity::PPort1)
    {
        col.si.iter_mut().for_each(|p| *p += PRESSURE_STEP_PA);
        any = true;
    }
    any.then_some(out)
}
