//! Which measurement next (docs/plan.md): candidate measurements ranked by how much they
//! are expected to shrink the 95 % bands at the user's operating points.
//!
//! The parameters' uncertainty is the one `predict`'s delta bands propagate
//! (`ParamUncertainty::for_bands`: the fit's curvature covariance of ln θ, the inverse of its
//! Fisher information JᵀWJ plus the motor prior's precision at the estimate, stretched along
//! each parameter's profile path to its profile interval's width). The operating points'
//! figures (the catalogue figures at each asked pressure, or torque, power and air at each
//! asked speed there) and each candidate's observables (`candidates`) are differentiated by
//! the same central differences; `design` adds each candidate's information GᵀΣ⁻¹G and
//! gives the bands after it, the shrinkage of each, and the D and V criteria. Candidates
//! are ranked by V per hour of rig time.
//!
//! All of it is linear about the estimate. Where the fit says the delta method is not to
//! be trusted (`predict::delta_unreliable`: a parameter not identifiable, or an interval
//! lopsided in its logarithm), the plan says so ([`Plan::not_gaussian`]); it does not
//! simulate outcomes over posterior samples.

mod candidates;
mod design;
mod options;

pub use candidates::{Candidate, RigSettings};
pub use options::{CandidateKind, PlanOptions, DEFAULT_TOP};

use crate::data::fitfile::FitFile;
use crate::model::gear::Gear;
use crate::model::motor::Motor;
use crate::predict::{log_band, BandBasis, ParamUncertainty, PredictError, Z95};
use crate::sim::operating_point::{at_speeds, catalogue_row, CatalogueRow, Conditions};
use crate::units::Quantity;
use nalgebra::DMatrix;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Why a plan failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// No supply pressure was asked for.
    #[error("no operating pressure to plan for")]
    NoPressures,
    /// A pressure is not above atmosphere.
    #[error("pressure {0} Pa is not an absolute pressure above atmosphere")]
    BadPressure(f64),
    /// A speed is not a number ≥ 0 (NaN: an empty list).
    #[error("speed {0} rad/s is not a number ≥ 0")]
    BadSpeed(f64),
    /// A cost is not a positive number of hours.
    #[error("the cost of {kind} must be a positive number of hours, not {hours}")]
    BadCost {
        /// The candidate kind's name.
        kind: &'static str,
        /// The cost given.
        hours: f64,
    },
    /// The fixed parameters' spread is not a factor above 1.
    #[error("the fixed parameters' spread {0} is not a factor > 1")]
    BadSpread(f64),
    /// No candidate is to be detailed.
    #[error("at least one candidate must be detailed")]
    BadTop,
    /// No candidate kind is to be weighed.
    #[error("at least one kind of candidate must be weighed")]
    NoKinds,
    /// The fit states no uncertainty to shrink.
    #[error("the fit file has neither a covariance nor intervals: there is no band to shrink (a stated --fixed-spread gives one)")]
    NoUncertainty,
    /// The fitted motor's figures could not be found.
    #[error(transparent)]
    Predict(#[from] PredictError),
}

/// A figure at an operating point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum TargetFigure {
    /// Maximum power (continuous optimum), W.
    MaxPower,
    /// Free speed, rad/s.
    FreeSpeed,
    /// Stall torque, N·m.
    StallTorque,
    /// Air into port 1 at maximum power, kg/s.
    AirAtMaxPower,
    /// Shaft torque at an asked speed, N·m.
    Torque,
    /// Shaft power at an asked speed, W.
    Power,
    /// Air into port 1 at an asked speed, kg/s.
    Air,
}

impl TargetFigure {
    /// Its name in the outputs.
    pub fn name(self) -> &'static str {
        match self {
            TargetFigure::MaxPower => "max_power",
            TargetFigure::FreeSpeed => "free_speed",
            TargetFigure::StallTorque => "stall_torque",
            TargetFigure::AirAtMaxPower => "air_at_max_power",
            TargetFigure::Torque => "torque",
            TargetFigure::Power => "power",
            TargetFigure::Air => "air",
        }
    }

    /// Its quantity (for units).
    pub fn quantity(self) -> Quantity {
        match self {
            TargetFigure::MaxPower | TargetFigure::Power => Quantity::Power,
            TargetFigure::FreeSpeed => Quantity::Speed,
            TargetFigure::StallTorque | TargetFigure::Torque => Quantity::Torque,
            TargetFigure::AirAtMaxPower | TargetFigure::Air => Quantity::Flow1,
        }
    }
}

/// A figure at an operating point, with its band now.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Target {
    /// Supply pressure, Pa absolute.
    pub p_supply_pa: f64,
    /// The asked speed, rad/s (`None`: a catalogue figure).
    pub speed_rad_s: Option<f64>,
    /// Which figure.
    pub figure: TargetFigure,
    /// At the estimate, SI (the output shaft's for a geared motor).
    pub value: f64,
    /// 95 % band now (delta method, as `predict`).
    pub band_before: [f64; 2],
}

/// A candidate and what it is expected to do.
#[derive(Debug, Clone, PartialEq)]
pub struct Assessed {
    /// The measurement.
    pub candidate: Candidate,
    /// Expected 95 % band of each target after it (the order of [`Plan::targets`]).
    pub band_after: Vec<[f64; 2]>,
    /// Expected shrinkage of each target's half-width, 1 − after/before.
    pub shrinkage: Vec<f64>,
    /// V: the reduction of the mean relative variance at the operating points.
    pub v_reduction: f64,
    /// D: information gained, nats.
    pub d_gain_nats: f64,
    /// σ of ln θ of each covered parameter after it (the order of [`Plan::parameters`]).
    pub sd_after: Vec<f64>,
}

impl Assessed {
    /// V per hour of rig time: the ranking's key.
    pub fn v_per_hour(&self) -> f64 {
        self.v_reduction / self.candidate.cost_h
    }

    /// The mean expected shrinkage of the targets' half-widths.
    pub fn mean_shrinkage(&self) -> f64 {
        self.shrinkage.iter().sum::<f64>() / self.shrinkage.len().max(1) as f64
    }
}

/// A plan: the operating points' bands now, and the candidates ranked.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// What was asked.
    pub options: PlanOptions,
    /// The figures at the operating points.
    pub targets: Vec<Target>,
    /// The candidates, best V per hour first.
    pub ranked: Vec<Assessed>,
    /// The parameters the bands and the update span (ln θ): those `predict`'s delta bands
    /// cover.
    pub parameters: Vec<String>,
    /// Their σ of ln θ now.
    pub sd_before: Vec<f64>,
    /// What the bands stand on.
    pub basis: BandBasis,
    /// Estimated parameters the bands do not cover, with the reason.
    pub uncovered: Vec<(String, String)>,
    /// Why the linearisation is not to be trusted for this fit (`None`: nothing known).
    pub not_gaussian: Option<String>,
    /// Candidates left out, with the reason.
    pub dropped: Vec<(String, String)>,
    /// The fit's gearbox: targets are its output shaft's, candidates the motor shaft's.
    pub gear: Option<Gear>,
}

/// Progress of the work: (stage, done, total).
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// Ranks the candidate measurements for `fit` at the operating points of `options` (see
/// the module documentation).
pub fn plan(fit: &FitFile, options: &PlanOptions, progress: Progress) -> Result<Plan, PlanError> {
    options.check()?;
    let unc = ParamUncertainty::for_bands(fit, options.fixed_spread);
    if unc.is_empty() {
        return Err(PlanError::NoUncertainty);
    }
    let motor = unc.motor_at(fit, &unc.log_values)?;
    let gear = fit.gear;
    let rows = options
        .pressures_pa
        .iter()
        .map(|p| row_at(&motor, options, *p))
        .collect::<Result<Vec<_>, _>>()?;
    let (labels, values) = targets_of(&motor, options, gear.as_ref())?;
    let figures = |m: &Motor| targets_of(m, options, gear.as_ref()).map(|t| t.1);
    progress("operating points", 0, 1);
    let g_t = unc.jacobian(fit, values.len(), &figures)?;
    progress("operating points", 1, 1);
    let var_before = design::variances(&unc.cov, &g_t);
    let all = candidates::candidates(&motor, options, &rows);
    let n_obs: usize = all.iter().map(|c| c.sigma.len()).sum();
    let done = AtomicUsize::new(0);
    let total = 2 * unc.len();
    let observe = |m: &Motor| {
        let z: Vec<f64> = all
            .iter()
            .flat_map(|c| c.observe(m, options.p_atm_pa))
            .collect();
        progress(
            "candidates",
            done.fetch_add(1, Ordering::Relaxed) + 1,
            total,
        );
        Ok(z)
    };
    let g_c = unc.jacobian(fit, n_obs, &observe)?;
    let targets = labels
        .iter()
        .zip(&values)
        .zip(&var_before)
        .map(|((l, y), v)| Target {
            p_supply_pa: l.0,
            speed_rad_s: l.1,
            figure: l.2,
            value: *y,
            band_before: log_band(*y, Z95 * v.sqrt()),
        })
        .collect();
    let now = Now {
        prior: design::Prior {
            curvature: &unc.curvature,
            stretch: &unc.stretch,
        },
        g_targets: &g_t,
        values: &values,
        var_before: &var_before,
    };
    let (ranked, dropped) = rank(all, &g_c, &now);
    Ok(Plan {
        options: options.clone(),
        targets,
        ranked,
        sd_before: unc.sd.clone(),
        parameters: unc.names.clone(),
        basis: unc.basis,
        uncovered: unc.uncovered.clone(),
        not_gaussian: crate::predict::delta_unreliable(fit),
        dropped,
        gear,
    })
}

/// The state now that every candidate is weighed against.
struct Now<'a> {
    /// The parameters' covariance now, C = A·C_c·Aᵀ (`predict`'s).
    prior: design::Prior<'a>,
    /// The targets' gradients over the parameters.
    g_targets: &'a DMatrix<f64>,
    /// The targets' values.
    values: &'a [f64],
    /// The targets' variances now (`predict`'s).
    var_before: &'a [f64],
}

/// Every candidate assessed (its rows of `g_c`, the candidates' sensitivities stacked in
/// their order), best V per hour first, and those left out with the reason.
fn rank(
    all: Vec<Candidate>,
    g_c: &DMatrix<f64>,
    now: &Now,
) -> (Vec<Assessed>, Vec<(String, String)>) {
    let (mut ranked, mut dropped) = (Vec::new(), Vec::new());
    let mut row0 = 0;
    for c in all {
        let rows_c = row0..row0 + c.sigma.len();
        row0 = rows_c.end;
        let g = g_c.rows(rows_c.start, rows_c.len()).clone_owned();
        let name = label(&c);
        match assess(c, &g, now) {
            Ok(a) => ranked.push(a),
            Err(why) => dropped.push((name, why.to_string())),
        }
    }
    ranked.sort_by(|a, b| b.v_per_hour().total_cmp(&a.v_per_hour()));
    (ranked, dropped)
}

/// A candidate's name with where it is measured, SI ("datasheet at 500000 Pa"); the
/// reports name the pressure in the user's unit.
fn label(c: &Candidate) -> String {
    match c.at_pa {
        Some(p) => format!("{} at {p:.0} Pa", c.kind.name()),
        None => c.kind.name().to_string(),
    }
}

/// One candidate's expected effect, or why it has none: the bands after are the delta
/// method's with the updated covariance ([`design::expected`]).
fn assess(c: Candidate, g: &DMatrix<f64>, now: &Now) -> Result<Assessed, &'static str> {
    if !g.iter().all(|v| v.is_finite()) {
        return Err("the motor moved within its uncertainty has no steady state at its settings");
    }
    let Some(e) = design::expected(&now.prior, g, &c.sigma, now.g_targets) else {
        return Err("its noise is not a positive number");
    };
    let var_after: Vec<f64> = now
        .var_before
        .iter()
        .zip(&e.var_after)
        .map(|(b, a)| a.min(*b))
        .collect();
    Ok(Assessed {
        band_after: now
            .values
            .iter()
            .zip(&var_after)
            .map(|(y, v)| log_band(*y, Z95 * v.sqrt()))
            .collect(),
        shrinkage: now
            .var_before
            .iter()
            .zip(&var_after)
            .map(|(b, a)| design::shrinkage(*b, *a))
            .collect(),
        v_reduction: design::v_reduction(now.values, now.var_before, &var_after),
        d_gain_nats: e.d_gain_nats,
        sd_after: e
            .cov_after
            .diagonal()
            .iter()
            .map(|v| v.max(0.0).sqrt())
            .collect(),
        candidate: c,
    })
}

/// The fitted motor's catalogue row at supply `p` (motor shaft).
fn row_at(motor: &Motor, options: &PlanOptions, p: f64) -> Result<CatalogueRow, PredictError> {
    catalogue_row(
        motor,
        &Conditions::supplied(p, options.p_atm_pa),
        candidates::GRID_RAD_S,
    )
    .map_err(|source| PredictError::AtPressure {
        p_supply_pa: p,
        source,
    })
}

/// A target's place: (supply Pa, asked speed rad/s, figure).
type TargetLabel = (f64, Option<f64>, TargetFigure);

/// The operating points' figures of `motor` (the output shaft's with a gearbox): at each
/// pressure the catalogue figures, or torque, power and air at each asked speed.
fn targets_of(
    motor: &Motor,
    options: &PlanOptions,
    gear: Option<&Gear>,
) -> Result<(Vec<TargetLabel>, Vec<f64>), PredictError> {
    let out = |q: Quantity, v: f64| gear.map_or(v, |g| g.to_output_shaft(q, v));
    let ratio = gear.map_or(1.0, |g| g.ratio);
    let mut labels = Vec::new();
    let mut values = Vec::new();
    for &p in &options.pressures_pa {
        match &options.speeds_rad_s {
            None => {
                let r = row_at(motor, options, p)?;
                for (f, q, v) in [
                    (TargetFigure::MaxPower, Quantity::Power, r.optimum.power_w),
                    (TargetFigure::FreeSpeed, Quantity::Speed, r.free_speed_rad_s),
                    (
                        TargetFigure::StallTorque,
                        Quantity::Torque,
                        r.stall_torque_nm,
                    ),
                    (
                        TargetFigure::AirAtMaxPower,
                        Quantity::Flow1,
                        r.optimum.flow1_kg_s,
                    ),
                ] {
                    labels.push((p, None, f));
                    values.push(out(q, v));
                }
            }
            Some(speeds) => {
                let motor_speeds: Vec<f64> = speeds.iter().map(|w| w * ratio).collect();
                let c = Conditions::supplied(p, options.p_atm_pa);
                let pts =
                    at_speeds(motor, &c, &motor_speeds).map_err(|e| PredictError::AtPressure {
                        p_supply_pa: p,
                        source: e.into(),
                    })?;
                for (w, pt) in speeds.iter().zip(pts) {
                    for (f, q, v) in [
                        (TargetFigure::Torque, Quantity::Torque, pt.torque_nm),
                        (TargetFigure::Power, Quantity::Power, pt.power_w),
                        (TargetFigure::Air, Quantity::Flow1, pt.flow1_kg_s),
                    ] {
                        labels.push((p, Some(*w), f));
                        values.push(out(q, v));
                    }
                }
            }
        }
    }
    Ok((labels, values))
}
