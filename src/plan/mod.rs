//! Which measurement next (docs/plan.md): candidate measurements ranked by how much they
//! are expected to shrink the 95 % bands at the user's operating points.
//!
//! The parameters' uncertainty is the one `predict` propagates (`ParamUncertainty`: the
//! fit's covariance of ln θ, the inverse of its Fisher information JᵀWJ plus the motor
//! prior's precision at the estimate, with profile-interval widths). The operating points'
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
    /// The parameters the update spans (ln θ): those `predict` covers, then those it leaves
    /// out that the fit's covariance holds.
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
    let shown = ParamUncertainty::of(fit, options.fixed_spread);
    if shown.is_empty() {
        return Err(PlanError::NoUncertainty);
    }
    let unc = with_flat_parameters(fit, &shown);
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
    let k = shown.len();
    let shown_var = design::variances(&shown.cov, &g_t.columns(0, k).clone_owned());
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
        .zip(&shown_var)
        .map(|((l, y), v)| Target {
            p_supply_pa: l.0,
            speed_rad_s: l.1,
            figure: l.2,
            value: *y,
            band_before: log_band(*y, Z95 * v.sqrt()),
        })
        .collect();
    let now = Now {
        deflate: profile_inflation(fit, &unc),
        cov: &unc.cov,
        g_targets: &g_t,
        values: &values,
        var_before: &var_before,
        shown_var: &shown_var,
    };
    let (ranked, dropped) = rank(all, &g_c, &now);
    Ok(Plan {
        options: options.clone(),
        targets,
        ranked,
        sd_before: unc.sd.clone(),
        parameters: unc.names.clone(),
        basis: shown.basis,
        uncovered: shown.uncovered.clone(),
        not_gaussian: crate::predict::delta_unreliable(fit),
        dropped,
        gear,
    })
}

/// `shown` (the parameters `predict`'s bands cover) with the parameters it leaves out that
/// the fit's covariance holds (an estimated parameter the profile found flat, such as a
/// page's `b_crit`): σ of ln θ from the covariance's diagonal, correlated with the rest as
/// the covariance says. A measurement's information is shared with them (it depends on
/// them too), so the update is made over all of them, and what it does to a band is the
/// ratio of its variance after to before in that space ([`assess`]).
fn with_flat_parameters(fit: &FitFile, shown: &ParamUncertainty) -> ParamUncertainty {
    let mut unc = shown.clone();
    let Some(file) = &fit.covariance else {
        return unc;
    };
    let at = |n: &str| file.parameters.iter().position(|m| m == n);
    for (n, _) in &shown.uncovered {
        let (Some(i), Some(v)) = (at(n), fit.params.get(n).filter(|v| *v > 0.0)) else {
            continue;
        };
        let sd = file.matrix[i][i].max(0.0).sqrt();
        if sd > 0.0 {
            unc.names.push(n.clone());
            unc.log_values.push(v.ln());
            unc.sd.push(sd);
        }
    }
    let k0 = shown.len();
    let k = unc.names.len();
    let corr = |a: usize, b: usize| match (at(&unc.names[a]), at(&unc.names[b])) {
        (Some(i), Some(j)) => file.matrix[i][j] / (file.matrix[i][i] * file.matrix[j][j]).sqrt(),
        _ => 0.0,
    };
    unc.cov = DMatrix::from_fn(k, k, |a, b| {
        if a < k0 && b < k0 {
            shown.cov[(a, b)]
        } else if a == b {
            unc.sd[a] * unc.sd[a]
        } else {
            unc.sd[a] * corr(a, b) * unc.sd[b]
        }
    });
    unc
}

/// For each parameter of `unc`: σ of ln θ by the curvature (the fit's covariance) over the
/// σ it has in `unc` (a profile interval's, usually wider where the likelihood is not
/// quadratic); 1 where the covariance does not hold it. The update takes that inflation to
/// persist after the measurement (what widens a profile interval is the likelihood's shape,
/// which more data of the same kind do not remove at first order):
/// C' = D·(C_c⁻¹ + GᵀΣ⁻¹G)⁻¹·D with C = D·C_c·D, D = diag(1/deflate), which is the plain
/// update of C by the sensitivities G·diag(deflate). On twin pages, promising the
/// curvature's shrinkage to profile-width bands overstated it by half.
fn profile_inflation(fit: &FitFile, unc: &ParamUncertainty) -> Vec<f64> {
    let file = fit.covariance.as_ref();
    unc.names
        .iter()
        .zip(&unc.sd)
        .map(|(n, sd)| {
            let i = file.and_then(|c| c.parameters.iter().position(|m| m == n));
            let curv = i.and_then(|i| file.map(|c| c.matrix[i][i].max(0.0).sqrt()));
            match curv {
                Some(c) if c > 0.0 && *sd > 0.0 => c / sd,
                _ => 1.0,
            }
        })
        .collect()
}

/// The state now that every candidate is weighed against.
struct Now<'a> {
    /// Each parameter's σ by the curvature over its σ here ([`profile_inflation`]).
    deflate: Vec<f64>,
    /// Covariance of ln θ over every parameter the update spans.
    cov: &'a DMatrix<f64>,
    /// The targets' gradients over them.
    g_targets: &'a DMatrix<f64>,
    /// The targets' values.
    values: &'a [f64],
    /// The targets' variances in that space.
    var_before: &'a [f64],
    /// The targets' variances as `predict` shows them (its parameters only).
    shown_var: &'a [f64],
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

/// One candidate's expected effect, or why it has none. Each band after is the band
/// `predict` shows with its variance scaled by Var'/Var of the update's space.
fn assess(c: Candidate, g: &DMatrix<f64>, now: &Now) -> Result<Assessed, &'static str> {
    if !g.iter().all(|v| v.is_finite()) {
        return Err("the motor moved within its uncertainty has no steady state at its settings");
    }
    let g = DMatrix::from_fn(g.nrows(), g.ncols(), |i, j| g[(i, j)] * now.deflate[j]);
    let Some(e) = design::expected(now.cov, &g, &c.sigma, now.g_targets) else {
        return Err("its noise is not a positive number");
    };
    let ratio: Vec<f64> = now
        .var_before
        .iter()
        .zip(&e.var_after)
        .map(|(b, a)| {
            if *b > 0.0 {
                (a / b).clamp(0.0, 1.0)
            } else {
                1.0
            }
        })
        .collect();
    let band_after = now
        .values
        .iter()
        .zip(now.shown_var)
        .zip(&ratio)
        .map(|((y, v), r)| log_band(*y, Z95 * (v * r).sqrt()))
        .collect();
    Ok(Assessed {
        band_after,
        shrinkage: now
            .var_before
            .iter()
            .zip(&e.var_after)
            .map(|(b, a)| design::shrinkage(*b, *a))
            .collect(),
        v_reduction: design::v_reduction(now.values, now.var_before, &e.var_after),
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::fitfile::LogCovariance;
    use crate::model::effects::EffectSet;
    use crate::model::params::MotorParams;

    /// Two estimated parameters with a covariance, one of them with a profile interval
    /// twice the curvature's width, and a third the covariance holds that is flat.
    fn fit_file() -> FitFile {
        let mut f = FitFile::from_params("t", MotorParams::default(), EffectSet::empty());
        f.estimated = vec!["c_in1".into(), "c_ext".into(), "b_crit".into()];
        let c = f.params.get("c_in1").unwrap();
        let r = 2.0 * Z95 * 0.1; // σ 0.2 of ln c_in1 from the profile
        f.ci95 = vec![("c_in1".into(), [c * (-r).exp(), c * r.exp()])];
        f.covariance = Some(LogCovariance {
            parameters: vec!["c_in1".into(), "c_ext".into(), "b_crit".into()],
            matrix: vec![
                vec![0.01, 0.003, 0.004],
                vec![0.003, 0.04, 0.0],
                vec![0.004, 0.0, 0.09],
            ],
        });
        f.verdicts = vec![crate::data::fitfile::ParamVerdict {
            name: "b_crit".into(),
            bounds95: [None, None],
            identifiable: false,
            why: None,
        }];
        f
    }

    /// The flat parameter joins the update with the covariance's σ and correlations; the
    /// profile's inflation over the curvature is σ_curv/σ_profile = 0.1/0.2 for c_in1 and 1
    /// for the rest; the update's covariance is then the curvature's: D⁻¹·C·D⁻¹ = C_c.
    #[test]
    fn the_update_spans_the_flat_parameters_in_the_curvature_s_units() {
        let f = fit_file();
        let shown = ParamUncertainty::of(&f, None);
        assert_eq!(shown.names, vec!["c_in1", "c_ext"]);
        let all = with_flat_parameters(&f, &shown);
        assert_eq!(all.names, vec!["c_in1", "c_ext", "b_crit"]);
        assert!((all.sd[2] - 0.3).abs() < 1e-12);
        let d = profile_inflation(&f, &all);
        assert!(
            (d[0] - 0.5).abs() < 1e-9 && (d[1] - 1.0).abs() < 1e-12 && (d[2] - 1.0).abs() < 1e-12,
            "{d:?}"
        );
        let file = &f.covariance.as_ref().unwrap().matrix;
        for a in 0..3 {
            for b in 0..3 {
                let c_c = all.cov[(a, b)] * d[a] * d[b];
                assert!(
                    (c_c - file[a][b]).abs() < 1e-12,
                    "({a},{b}): {c_c} vs {}",
                    file[a][b]
                );
            }
        }
    }
}
