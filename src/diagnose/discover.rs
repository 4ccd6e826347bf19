//! Finding a term outside the catalog: sparse regression of the misfit over a library of
//! candidate terms in each balance (docs/model.md, "Missing-physics catalog":
//! uncatalogued mismatches).
//!
//! # Method
//!
//! A term k·f(x) added to one balance b (torque; mass at V_1, V_2 or V_e) changes the
//! simulated outputs y by k·s_bf to first order, where s_bf = ∂y/∂k is the output
//! sensitivity, computed by central differences of whole simulations of every experiment
//! with the term switched on at ±δ (δ sized so the term is about one noise level of its
//! balance at a typical operating point: 2 mN·m, 10 mg/s). The features f are evaluated on
//! the simulated states [p_1, p_2, p_e, ω] along the experiments inside the model
//! ([`crate::model::motor::ExtraTerm`]); regressing the residual on s_bf is regressing the balance's
//! residual on f, seen through the model's dynamics, which is what the recordings observe
//! (the balances themselves are not measured). The base parameters may move too: their
//! sensitivities are nuisance columns that every model contains (a concealed effect hides in
//! them).
//!
//! With r = (recorded − simulated)/σ over every compared point (σ the channel's noise,
//! `objective::likelihood`) and S the normalised
//! sensitivities, forward selection with BIC: the nuisance columns are projected out, each
//! library column's χ² reduction (sᵀr)²/(sᵀs) of the projected quantities is computed, and
//! the best is kept while its ΔBIC = −Δχ² + ln n is below `DISCOVERY_DELTA_BIC`; at most
//! `MAX_TERMS` terms. The linear step only proposes: the chosen term is then put into the
//! model and refitted nonlinearly, and only the refitted ΔBIC counts.
//!
//! # Library
//!
//! Torque (a loss torque): p·ω for p ∈ {p_1, p_2, p_e} and the differences p_1 − p_e,
//! p_2 − p_e, p_1 − p_2 times ω, and pressure-dependent Coulomb-like terms
//! (p_1 + p_2 − 2·p_e, p_2 − p_e, p_1 − p_2, gauge pressures)·tanh(ω/ω_reg), load-dependent
//! Coulomb friction |T_air|·tanh(ω/ω_reg) (T_air the model's own air torque at the state,
//! [`Motor::air_torque_nm`]), a power-law
//! viscous loss ω·|ω|^(1/2) and the exponential Stribeck excess exp(−|ω|/ω_s)·tanh(ω/ω_reg).
//! Terms the model already has are left out: tanh and ω alone are the base model's `t_coulomb` and `visc`, ω·|ω| is
//! `vane_friction_speed_squared`, (p_1 − p_e)·tanh is `pressure_dependent_friction`.
//! Leak paths ([`crate::model::extra::LeakPath`]: V_1→V_e, V_2→V_e, V_1→V_2 and each
//! volume to atmosphere; the mass one balance loses the other gains) with each flow law
//! (docs/diagnosis.md, "Term library": laminar Δp, compressible laminar p_a² − p_b²,
//! turbulent Δp^(4/7), Δp·|Δp|, orifice √Δp, ISO 6358), constant or times |ω|. Mass into one of
//! V_1, V_2, V_e alone: gauge pressures and pressure differences (a volume's own gauge
//! pressure is the laminar path to atmosphere and is left to the paths); ω, absolute
//! pressures times ω and pressure differences times ω (speed-driven flows: pumping,
//! carry-over). 123 terms in all. A one-balance mass term gives way to a path that explains
//! the misfit within `PATH_PREFERENCE` as well (mass conservation is physics).

use super::fitting::Fitted;
pub use crate::data::fitfile::{term_from_json, term_to_json};
use crate::estimate::engine::Engine;
use crate::estimate::problem::derivatives::central_column;
use crate::estimate::problem::space::{ParamSpace, SpaceError};
pub use crate::model::extra::{
    balance_name, balance_symbol, category, coefficient_unit, describe, feature_name, formula,
    pressure_id, speed_id,
};
use crate::model::motor::{
    BalanceId, ExtraTerm, LeakPath, Motor, PressureFactor as P, SpeedFactor as W,
};
use crate::model::spec::SizeLaw;
use crate::numerics::DefaultSolver;
use crate::objective::cost::CostModel;
use crate::objective::likelihood::Target;
use nalgebra::{DMatrix, DVector};

/// Linearised ΔBIC a library term must reach to be refitted.
const DISCOVERY_DELTA_BIC: f64 = -10.0;
/// χ² by which a leak path may explain less than a one-balance mass term and still be
/// preferred to it (the selection's own margin, [`super::SELECT_DELTA_BIC`]).
const PATH_PREFERENCE: f64 = 10.0;
/// Most terms selected in one regression.
const MAX_TERMS: usize = 2;

/// Typical state of the reference motor (AR034-11) used to size the perturbation δ of each
/// feature: p1, p2, pe in Pa and ω in rad/s ([`typical_state`] scales ω to a motor's size).
const TYPICAL: [f64; 4] = [5e5, 2e5, 1.5e5, 800.0];
/// Size of a perturbation in each balance of the reference motor (one noise level of its
/// rig): torque N·m, mass kg/s. [`step`] scales them to a motor's size.
const TORQUE_STEP: f64 = 2e-3;
const MASS_STEP: f64 = 1e-5;

/// [`TYPICAL`] for a motor `size` times AR034-11's displacement: the pressures are the
/// same, the speed follows the vane-tip speed (ω ∝ s^{-⅓}, `SizeLaw::SPEED`).
fn typical_state(size: f64) -> [f64; 4] {
    let [p1, p2, pe, w] = TYPICAL;
    [p1, p2, pe, w * size.powf(SizeLaw::SPEED)]
}

/// The library of candidate terms (coefficient 1).
pub fn library() -> Vec<ExtraTerm> {
    let mut out = torque_terms();
    // Leak paths (mass leaves one balance and enters the other): every path, every flow
    // law, constant or scaled by the speed's magnitude.
    for path in LeakPath::ALL {
        for law in P::LAWS {
            for w in [W::One, W::AbsOmega] {
                out.push(unit_term(BalanceId::Path(path), law, w));
            }
        }
    }
    for b in [BalanceId::Mass1, BalanceId::Mass2, BalanceId::MassE] {
        out.extend(mass_terms(b));
    }
    out
}

/// A library term: `pressure`·`speed` in `balance`, coefficient 1.
fn unit_term(balance: BalanceId, pressure: P, speed: W) -> ExtraTerm {
    ExtraTerm {
        balance,
        pressure,
        speed,
        coefficient: 1.0,
    }
}

/// The chambers' absolute pressures and their differences, the factors that multiply the
/// speed in the library's speed-driven terms.
const ABSOLUTE_AND_DIFFERENCES: [P; 6] = [
    P::P1,
    P::P2,
    P::Pe,
    P::P1MinusPe,
    P::P2MinusPe,
    P::P1MinusP2,
];

/// The library's loss torques: pressures times speed, pressure- and load-dependent
/// Coulomb-like terms, and friction laws beyond Coulomb and viscous.
fn torque_terms() -> Vec<ExtraTerm> {
    let mut out = Vec::new();
    // Speed only: ω is `visc`, ω·|ω| is `vane_friction_speed_squared`; pressure times speed:
    for p in ABSOLUTE_AND_DIFFERENCES {
        out.push(unit_term(BalanceId::Torque, p, W::Omega));
    }
    // Coulomb-like, pressure-dependent ((p_1 − p_e)·tanh is `pressure_dependent_friction`;
    // the chamber sum is vanes pressed by both chambers, one law where the catalog effect
    // plus a (p_2 − p_e) term would be two parts):
    for p in [
        P::ChamberSum,
        // Load-dependent: the torque the vanes and bearings transmit loads them (k·|T_air|,
        // the air torque weighing p_1, p_2 and p_e as the cycle does):
        P::AirTorque,
        P::P2MinusPe,
        P::P1MinusP2,
        P::P1Gauge,
        P::P2Gauge,
        P::PeGauge,
    ] {
        out.push(unit_term(BalanceId::Torque, p, W::Sign));
    }
    // Friction laws beyond Coulomb and viscous: a power-law viscous loss and the exponential
    // Stribeck curve (the Gaussian one is `breakaway_friction`):
    out.push(unit_term(BalanceId::Torque, P::One, W::OmegaPow15));
    out.push(unit_term(BalanceId::Torque, P::One, W::StribeckExp));
    out
}

/// The library's flows into the one mass balance `b` alone: pressure-driven and
/// speed-driven.
fn mass_terms(b: BalanceId) -> Vec<ExtraTerm> {
    let mut out = Vec::new();
    // Pressure-driven flows into one balance (gauge pressures and differences; an
    // absolute pressure alone would blow at vacuum). A volume's own gauge pressure is
    // the laminar leak path to atmosphere, so it is left to the paths:
    let own = match b {
        BalanceId::Mass1 => P::P1Gauge,
        BalanceId::Mass2 => P::P2Gauge,
        _ => P::PeGauge,
    };
    for p in [
        P::P1Gauge,
        P::P2Gauge,
        P::PeGauge,
        P::P1MinusPe,
        P::P2MinusPe,
        P::P1MinusP2,
    ] {
        if p != own {
            out.push(unit_term(b, p, W::One));
        }
    }
    // Speed-driven flows (pumping, carry-over: density times swept volume):
    out.push(unit_term(b, P::One, W::Omega));
    for p in ABSOLUTE_AND_DIFFERENCES {
        out.push(unit_term(b, p, W::Omega));
    }
    out
}

/// Perturbation δ of a library term's coefficient: the size of one noise level of its
/// balance at the typical state of a motor `size` times AR034-11's displacement
/// ([`typical_state`]), where the motor's air torque is `t_air_nm`. The noise levels
/// follow the size as the rig's sensors do (torque ∝ s, mass flow ∝ s^⅔), so that a term's
/// step is the same share of the motor's own balance at every size.
fn step(t: &ExtraTerm, t_air_nm: f64, size: f64) -> f64 {
    let unit = ExtraTerm {
        coefficient: 1.0,
        ..*t
    };
    let f = unit
        .feature(
            &typical_state(size),
            crate::units::constants::P_ATM_PA,
            0.2,
            t_air_nm,
        )
        .abs()
        .max(1e-30);
    match t.balance {
        BalanceId::Torque => TORQUE_STEP * size.powf(SizeLaw::TORQUE) / f,
        _ => MASS_STEP * size.powf(SizeLaw::MASS_FLOW) / f,
    }
}

/// Why the term regression could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RegressError {
    /// The model whose residual is regressed does not simulate.
    #[error("the model to regress does not simulate")]
    NoSimulation,
    /// The estimated names do not make a parameter space.
    #[error("{0}")]
    Space(#[from] SpaceError),
    /// The least-squares problem of the selected terms has no solution (nalgebra's
    /// reason).
    #[error("{0}")]
    Solve(&'static str),
}

/// One library term's linearised score.
#[derive(Debug, Clone)]
pub struct TermScore {
    /// The term with the least-squares coefficient (SI).
    pub term: ExtraTerm,
    /// χ² reduction after the nuisance parameters are refitted (linearised).
    pub delta_chi2: f64,
    /// −Δχ² + ln n.
    pub delta_bic: f64,
}

/// The outcome of a regression.
#[derive(Debug, Clone, Default)]
pub struct Regression {
    /// Every library term scored alone (on top of the nuisance), best first.
    pub ranking: Vec<TermScore>,
    /// Terms chosen by forward selection, with their joint least-squares coefficients.
    pub selected: Vec<TermScore>,
    /// Compared points n (of ln n in the BIC).
    pub n_points: usize,
}

/// Normalised outputs of a motor over every compared point: simulation/σ, concatenated in
/// channel order.
fn outputs(
    cost: &CostModel,
    target: &Target,
    motor: &Motor,
    solver: &DefaultSolver,
) -> Option<Vec<f64>> {
    let res = cost.residuals(motor, solver).ok()?;
    let v: Vec<f64> = res
        .iter()
        .zip(&target.channels)
        .flat_map(|(c, t)| c.simulated.iter().map(move |s| s / t.sigma))
        .collect();
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// Regresses the misfit of `model` (estimated parameters `names`, whose sensitivities are
/// nuisance) over the library (see the module documentation).
pub(crate) fn regress(
    cost: &CostModel,
    target: &Target,
    model: &Fitted,
    names: &[String],
    engine: &Engine,
) -> Result<Regression, RegressError> {
    let solver = DefaultSolver::default();
    let sim = outputs(cost, target, &model.motor(), &solver).ok_or(RegressError::NoSimulation)?;
    let data: Vec<f64> = target
        .channels
        .iter()
        .flat_map(|t| t.data.iter().map(move |d| d / t.sigma))
        .collect();
    let r: Vec<f64> = data.iter().zip(&sim).map(|(d, s)| d - s).collect();
    let n = r.len();
    let lib = library();
    let (n_nuisance, columns) = sensitivities(cost, target, model, names, &lib, engine)?;
    let nuisance: Vec<&Vec<f64>> = columns[..n_nuisance].iter().flatten().collect();
    let basis = nuisance_basis(&nuisance, n);
    let lib_cols: Vec<(ExtraTerm, DVector<f64>)> = lib
        .iter()
        .zip(&columns[n_nuisance..])
        .filter_map(|(t, c)| c.as_ref().map(|c| (*t, DVector::from_column_slice(c))))
        .collect();
    let ln_n = (n.max(1) as f64).ln();
    let r0 = DVector::from_vec(r);
    let r_perp = project(&r0, &basis);
    let mut ranking: Vec<TermScore> = score(&lib_cols, &basis, &r_perp)
        .into_iter()
        .map(|(i, d, beta)| TermScore {
            term: ExtraTerm {
                coefficient: beta,
                ..lib_cols[i].0
            },
            delta_chi2: d,
            delta_bic: -d + ln_n,
        })
        .collect();
    ranking.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    let (chosen, gains) = forward_select(&lib_cols, basis, r_perp, ln_n);
    let selected = if chosen.is_empty() {
        Vec::new()
    } else {
        let beta = joint_coefficients(&nuisance, &lib_cols, &chosen, &r0)?;
        chosen
            .iter()
            .enumerate()
            .map(|(k, &i)| TermScore {
                term: ExtraTerm {
                    coefficient: beta[nuisance.len() + k],
                    ..lib_cols[i].0
                },
                delta_chi2: gains[k],
                delta_bic: -gains[k] + ln_n,
            })
            .collect()
    };
    Ok(Regression {
        ranking,
        selected,
        n_points: n,
    })
}

/// Simulations of a regression with `nuisance` estimated parameters: the model once, then
/// every nuisance and library column at ±δ.
pub(crate) fn evaluations(nuisance: usize) -> u64 {
    (1 + 2 * (nuisance + library().len())) as u64
}

/// The sensitivity columns: how many lead as nuisance, then every column (`None` where a
/// perturbed model does not simulate).
type Sensitivities = (usize, Vec<Option<Vec<f64>>>);

/// A column of the sensitivity matrix.
enum Col {
    /// An estimated parameter, in search coordinates θ (nuisance).
    Theta(usize),
    /// A discovered term already in the model, by relative change (nuisance).
    Extra(usize),
    /// A library term at ±δ.
    Library(ExtraTerm, f64),
}

/// Normalised output sensitivities by central differences of whole simulations: first the
/// nuisance columns (their count is returned), then one per library term; `None` where a
/// perturbed model does not simulate.
fn sensitivities(
    cost: &CostModel,
    target: &Target,
    model: &Fitted,
    names: &[String],
    lib: &[ExtraTerm],
    engine: &Engine,
) -> Result<Sensitivities, RegressError> {
    let solver = DefaultSolver::default();
    let motor = model.motor();
    let name_refs: Vec<&str> = names.iter().map(String::as_str).collect();
    let space = ParamSpace::new(&name_refs, model.params.clone(), model.effects.clone())?;
    let theta = space.theta(&model.params);
    let h = 1e-2;
    let mut cols: Vec<Col> = (0..theta.len()).map(Col::Theta).collect();
    cols.extend((0..model.extra.len()).map(Col::Extra));
    let n_nuisance = cols.len();
    let size = model.params.size();
    let t_air_nm = motor.air_torque_nm(&typical_state(size));
    cols.extend(
        lib.iter()
            .map(|t| Col::Library(*t, step(t, t_air_nm, size))),
    );
    let column = |c: &Col| -> Option<Vec<f64>> {
        let at = |sign: f64| -> Option<Vec<f64>> {
            let m = match c {
                Col::Theta(i) => {
                    let mut th = theta.clone();
                    th[*i] += sign * h;
                    Motor::new(space.params(&th).ok()?, model.effects.clone())
                        .with_extra(&model.extra)
                }
                Col::Extra(i) => {
                    let mut extra = model.extra.clone();
                    extra[*i].coefficient *= 1.0 + sign * 0.05;
                    Motor::new(model.params.clone(), model.effects.clone()).with_extra(&extra)
                }
                Col::Library(t, d) => motor.clone().with_extra(&[ExtraTerm {
                    coefficient: sign * d,
                    ..*t
                }]),
            };
            outputs(cost, target, &m, &solver)
        };
        let (plus, minus) = (at(1.0)?, at(-1.0)?);
        let denom = match c {
            Col::Theta(_) => 2.0 * h,
            Col::Extra(_) => 2.0 * 0.05,
            Col::Library(_, d) => 2.0 * d,
        };
        Some(central_column(&plus, &minus, denom))
    };
    Ok((n_nuisance, engine.map(&cols, column)))
}

/// Orthonormal basis of the nuisance columns (SVD, dropping directions with singular value
/// below 1e-8 of the largest: parameters these data cannot see).
fn nuisance_basis(nuisance: &[&Vec<f64>], n: usize) -> Vec<DVector<f64>> {
    let mut basis: Vec<DVector<f64>> = Vec::new();
    if !nuisance.is_empty() {
        let a = DMatrix::from_fn(n, nuisance.len(), |i, j| nuisance[j][i]);
        let svd = a.svd(true, false);
        let u = svd.u.expect("requested");
        let smax = svd.singular_values.max();
        for (j, s) in svd.singular_values.iter().enumerate() {
            if *s > 1e-8 * smax {
                basis.push(u.column(j).into_owned());
            }
        }
    }
    basis
}

/// `v` with its components along the orthonormal `basis` removed.
fn project(v: &DVector<f64>, basis: &[DVector<f64>]) -> DVector<f64> {
    let mut out = v.clone();
    for q in basis {
        let c = q.dot(&out);
        out.axpy(-c, q, 1.0);
    }
    out
}

/// Each library column's (index, χ² reduction (sᵀr)²/(sᵀs), coefficient sᵀr/(sᵀs)) after
/// projecting out `basis`; columns that vanish in the projection are left out.
fn score(
    lib_cols: &[(ExtraTerm, DVector<f64>)],
    basis: &[DVector<f64>],
    r: &DVector<f64>,
) -> Vec<(usize, f64, f64)> {
    lib_cols
        .iter()
        .enumerate()
        .filter_map(|(i, (_, s))| {
            let sp = project(s, basis);
            let ss = sp.dot(&sp);
            (ss > 1e-12 * s.dot(s).max(1e-300)).then(|| {
                let sr = sp.dot(r);
                (i, sr * sr / ss, sr / ss)
            })
        })
        .collect()
}

/// Forward selection: the best remaining column while its ΔBIC = −Δχ² + ln n is below
/// [`DISCOVERY_DELTA_BIC`], at most [`MAX_TERMS`]; returns the chosen columns and their
/// χ² reductions.
fn forward_select(
    lib_cols: &[(ExtraTerm, DVector<f64>)],
    mut basis: Vec<DVector<f64>>,
    mut r_perp: DVector<f64>,
    ln_n: f64,
) -> (Vec<usize>, Vec<f64>) {
    let mut chosen: Vec<usize> = Vec::new();
    let mut gains: Vec<f64> = Vec::new();
    while chosen.len() < MAX_TERMS {
        let scores: Vec<(usize, f64, f64)> = score(lib_cols, &basis, &r_perp)
            .into_iter()
            .filter(|(i, _, _)| !chosen.contains(i))
            .collect();
        let Some((i, d)) = prefer_paths(lib_cols, &scores) else {
            break;
        };
        if -d + ln_n >= DISCOVERY_DELTA_BIC {
            break;
        }
        let sp = project(&lib_cols[i].1, &basis);
        let q = &sp / sp.norm();
        r_perp = project(&r_perp, std::slice::from_ref(&q));
        basis.push(q);
        chosen.push(i);
        gains.push(d);
    }
    (chosen, gains)
}

/// The best column of `scores` (index, χ² reduction, _), except that a one-balance mass
/// term gives way to the best leak path within [`PATH_PREFERENCE`] of it: a path conserves
/// mass, which is physics, where a one-balance term makes or destroys it.
fn prefer_paths(
    lib_cols: &[(ExtraTerm, DVector<f64>)],
    scores: &[(usize, f64, f64)],
) -> Option<(usize, f64)> {
    let best_of = |keep: &dyn Fn(&ExtraTerm) -> bool| {
        scores
            .iter()
            .filter(|(i, _, _)| keep(&lib_cols[*i].0))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, d, _)| (*i, *d))
    };
    let (i, d) = best_of(&|_| true)?;
    let one_balance_mass = |t: &ExtraTerm| {
        matches!(
            t.balance,
            BalanceId::Mass1 | BalanceId::Mass2 | BalanceId::MassE
        )
    };
    if !one_balance_mass(&lib_cols[i].0) {
        return Some((i, d));
    }
    match best_of(&|t| matches!(t.balance, BalanceId::Path(_))) {
        Some((j, dj)) if dj >= d - PATH_PREFERENCE => Some((j, dj)),
        _ => Some((i, d)),
    }
}

/// Joint least-squares coefficients of the nuisance columns and the chosen terms (in that
/// order) for the residual `r0`.
fn joint_coefficients(
    nuisance: &[&Vec<f64>],
    lib_cols: &[(ExtraTerm, DVector<f64>)],
    chosen: &[usize],
    r0: &DVector<f64>,
) -> Result<DVector<f64>, RegressError> {
    let nuis: Vec<DVector<f64>> = nuisance
        .iter()
        .map(|c| DVector::from_column_slice(c))
        .collect();
    let mut all: Vec<&DVector<f64>> = nuis.iter().collect();
    all.extend(chosen.iter().map(|&i| &lib_cols[i].1));
    let n = r0.len();
    let a = DMatrix::from_fn(n, all.len(), |i, j| all[j][i]);
    a.svd(true, true)
        .solve(r0, 1e-10)
        .map_err(RegressError::Solve)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The typical state and perturbations of the reference motor are the constants; a
    /// motor 8 times its size turns at half the speed, and a term's step is the same share
    /// of its own (scaled) balance.
    #[test]
    fn the_typical_state_and_steps_follow_the_size() {
        assert_eq!(typical_state(1.0), TYPICAL);
        let s8 = typical_state(8.0);
        assert_eq!(s8[..3], TYPICAL[..3]);
        assert!((s8[3] - TYPICAL[3] / 2.0).abs() < 1e-9);
        let t_air_nm = Motor::default_motor().air_torque_nm(&TYPICAL);
        let lib = library();
        let torque = lib.iter().find(|t| t.balance == BalanceId::Torque).unwrap();
        let unit = ExtraTerm {
            coefficient: 1.0,
            ..*torque
        };
        let f = |size: f64, t_air: f64| {
            unit.feature(
                &typical_state(size),
                crate::units::constants::P_ATM_PA,
                0.2,
                t_air,
            )
            .abs()
        };
        let (s1, s8) = (
            step(torque, t_air_nm, 1.0),
            step(torque, 8.0 * t_air_nm, 8.0),
        );
        // δ·f is the balance's noise level: 2 mN·m at size 1, 8 × that at size 8.
        assert!((s1 * f(1.0, t_air_nm) - TORQUE_STEP).abs() < 1e-12);
        assert!((s8 * f(8.0, 8.0 * t_air_nm) - 8.0 * TORQUE_STEP).abs() < 1e-9);
    }
    use crate::model::effects::Category;

    #[test]
    fn library_terms_are_distinct_and_described() {
        let lib = library();
        let t_air_nm = Motor::default_motor().air_torque_nm(&TYPICAL);
        for (i, a) in lib.iter().enumerate() {
            for b in &lib[..i] {
                assert!(
                    (a.balance, a.pressure, a.speed) != (b.balance, b.pressure, b.speed),
                    "{a:?}"
                );
            }
            assert!(step(a, t_air_nm, 1.0).is_finite() && step(a, t_air_nm, 1.0) > 0.0);
        }
        let t = ExtraTerm {
            balance: BalanceId::Torque,
            pressure: P::P2,
            speed: W::Omega,
            coefficient: 2e-10,
        };
        assert_eq!(feature_name(&t), "p2*omega");
        assert_eq!(coefficient_unit(&t), "N*m/(Pa*rad/s)");
        assert!(formula(&t).starts_with("T_loss += 2.0000e-10"));
        assert_eq!(category(&t), Category::TorqueLoss);
        for t in library() {
            assert_eq!(term_from_json(&term_to_json(&t)).unwrap(), t);
        }
        assert!(term_from_json(&serde_json::json!({"balance": "torque"})).is_err());
        // Load-dependent friction: a pure-number fraction of the air torque, torque only.
        let t = ExtraTerm {
            balance: BalanceId::Torque,
            pressure: P::AirTorque,
            speed: W::Sign,
            coefficient: 0.066,
        };
        assert_eq!(coefficient_unit(&t), "1");
        assert_eq!(
            formula(&t),
            "T_loss += 6.6000e-2 * |T_air|*tanh(omega/w_reg)"
        );
        let mut json = term_to_json(&t);
        json["balance"] = "mass_v1".into();
        let e = term_from_json(&json).unwrap_err().to_string();
        assert!(e.contains("air_torque") && e.contains("torque"), "{e}");
    }

    #[test]
    fn the_literature_laws_grow_as_their_sources_say() {
        use crate::model::extra::flow_law;
        // Compressible laminar: p_a² − p_b², odd under exchange of the ends.
        assert_eq!(flow_law(P::CompressibleLaminar, 3e5, 1e5), 8e10);
        assert_eq!(flow_law(P::CompressibleLaminar, 1e5, 3e5), -8e10);
        // Turbulent: 128 times the pressure difference gives 128^(4/7) = 16 times the flow.
        let ratio = flow_law(P::Turbulent, 1.28e6 + 1e5, 1e5) / flow_law(P::Turbulent, 1.1e5, 1e5);
        assert!((ratio - 16.0).abs() < 1e-9, "{ratio}");
        // Linear (finite slope) at Δp → 0, continuous at the switch.
        let below = flow_law(P::Turbulent, 1e5 + 999.999, 1e5);
        let above = flow_law(P::Turbulent, 1e5 + 1000.001, 1e5);
        assert!((below - above).abs() < 1e-4 * above);
        assert!(flow_law(P::Turbulent, 1e5 + 1.0, 1e5) > 0.0);
    }
}
