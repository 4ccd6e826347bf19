//! One explanation before a patchwork, and the runners-up (docs/diagnosis.md, "One
//! explanation").
//!
//! A chosen model that puts catalog effects (or a second term) beside a discovered term may
//! be a patchwork: the term's law was not the data's, and the other parts make up the
//! difference. Before it is accepted, the term alone is refitted with every flow law of the
//! term library on its path (for a Coulomb-like torque term: every pressure's Coulomb law
//! and the load-dependent one on the air torque),
//! and the best-ranked path terms of the baseline's regression too, each warm from the
//! baseline; a one-part model within [`SELECT_DELTA_BIC`] of the patchwork is
//! chosen instead (it explains the data as well with fewer parts).
//!
//! Every other model within [`ALSO_CONSISTENT_DELTA_BIC`] of the chosen one is "also
//! consistent": the data cannot separate them, and the report names an experiment that
//! would.

use super::context::Context;
use super::discover::{self, Regression};
use super::fitting::{FitJob, Fitted};
use super::models::{parts, refit_job, Batch, Models};
use super::{AlsoConsistent, Candidate, ModelKind, Selected, SELECT_DELTA_BIC};
use crate::model::effects::{Category, EffectSet};
use crate::model::motor::{BalanceId, ExtraTerm, PressureFactor, SpeedFactor};

/// ΔBIC within which another model is reported as "also consistent" with the data (the
/// selection's own margin: less than "very strong" evidence on Kass and Raftery's scale).
pub const ALSO_CONSISTENT_DELTA_BIC: f64 = 10.0;
/// Path terms of the baseline's regression ranking also refitted alone.
const RANKED_PATH_TERMS: usize = 2;
/// Most models listed as also consistent.
const MAX_ALSO: usize = 4;

/// The regression of a chosen model that holds a discovered term beside other parts (a
/// possible patchwork, see the module documentation); None otherwise.
fn patchwork<'a>(c: &Candidate, reg: Option<&'a Regression>) -> Option<&'a Regression> {
    reg.filter(|_| !c.fitted.extra.is_empty() && parts(&c.fitted) >= 2)
}

/// The refits that test a patchwork `chosen` against one explanation: each term of
/// [`alone_terms`] alone, warm from the baseline, unless already fitted. None when there is
/// nothing to refit.
pub(crate) fn alone_refits(
    cx: &Context,
    reg: Option<&Regression>,
    baseline: &Fitted,
    models: &Models,
    chosen: Option<&Candidate>,
) -> Option<Batch> {
    let c = chosen?;
    let reg = patchwork(c, reg)?;
    let jobs: Vec<(ModelKind, FitJob)> = alone_terms(c, reg)
        .into_iter()
        .map(|t| (ModelKind::Uncatalogued, term_job(cx, t, baseline)))
        .filter(|(_, j)| !models.all.iter().any(|m| m.label == j.label))
        .collect();
    Batch::discovered(jobs, "one-explanation refit")
}

/// The chosen model, or, when it is a patchwork, the best one-part model of `models` within
/// [`SELECT_DELTA_BIC`] of it (after [`alone_refits`] joined `models`).
pub(crate) fn one_explanation(
    reg: Option<&Regression>,
    models: &Models,
    chosen: Option<Candidate>,
) -> Option<Candidate> {
    let c = chosen?;
    if patchwork(&c, reg).is_none() {
        return Some(c);
    }
    let one = models
        .all
        .iter()
        .filter(|m| parts(&m.fitted) == 1 && m.delta_bic <= c.delta_bic + SELECT_DELTA_BIC)
        .min_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic))
        .cloned();
    Some(one.unwrap_or(c))
}

/// The models also consistent with the data beside the extended `model`, and an experiment
/// that would separate them; none when nothing is `selected`.
pub(crate) fn runners_up(
    model: &Candidate,
    selected: &[Selected],
    all: &[Candidate],
) -> (Vec<AlsoConsistent>, Option<String>) {
    if selected.is_empty() {
        return (Vec::new(), None);
    }
    let also = also_consistent(model, all);
    let experiment = separating_experiment(model, &also);
    (also, experiment)
}

/// The terms to refit alone: every flow law (constant and times |ω|) on the paths of the
/// chosen model's terms, every pressure-loaded Coulomb term of the library beside a
/// Coulomb-like torque term, its other terms as they are, and the best path terms of the
/// regression's ranking; each with its linearised coefficient.
fn alone_terms(c: &Candidate, reg: &Regression) -> Vec<ExtraTerm> {
    let linearised = |t: &ExtraTerm| {
        reg.ranking
            .iter()
            .find(|s| {
                (s.term.balance, s.term.pressure, s.term.speed) == (t.balance, t.pressure, t.speed)
            })
            .map(|s| s.term)
            .filter(|s| s.coefficient != 0.0 && s.coefficient.is_finite())
    };
    let mut out: Vec<ExtraTerm> = Vec::new();
    let push = |t: ExtraTerm, out: &mut Vec<ExtraTerm>| {
        let same =
            |u: &ExtraTerm| (u.balance, u.pressure, u.speed) == (t.balance, t.pressure, t.speed);
        if !out.iter().any(same) {
            out.push(t);
        }
    };
    for t in &c.fitted.extra {
        match t.balance {
            BalanceId::Path(_) => {
                for law in PressureFactor::LAWS {
                    for speed in [SpeedFactor::One, SpeedFactor::AbsOmega] {
                        let u = ExtraTerm {
                            pressure: law,
                            speed,
                            ..*t
                        };
                        if let Some(u) = linearised(&u) {
                            push(u, &mut out);
                        }
                    }
                }
            }
            // A pressure-loaded Coulomb term beside other parts: every Coulomb law of the
            // library alone, pressure- and load-dependent (a catalog
            // `pressure_dependent_friction` plus a (p_2 − p_e) term is the chamber-sum law, or
            // the air-torque law, in two parts).
            BalanceId::Torque if t.speed == SpeedFactor::Sign => {
                push(*t, &mut out);
                for s in reg.ranking.iter().filter(|s| {
                    s.term.balance == BalanceId::Torque
                        && s.term.speed == SpeedFactor::Sign
                        && s.term.coefficient != 0.0
                        && s.term.coefficient.is_finite()
                }) {
                    push(s.term, &mut out);
                }
            }
            _ => push(*t, &mut out),
        }
    }
    for s in reg
        .ranking
        .iter()
        .filter(|s| matches!(s.term.balance, BalanceId::Path(_)) && s.term.coefficient != 0.0)
        .take(RANKED_PATH_TERMS)
    {
        push(s.term, &mut out);
    }
    out
}

/// The refit of the base model with `t` alone, warm from the baseline, labelled by the
/// term's formula.
fn term_job(cx: &Context, t: ExtraTerm, baseline: &Fitted) -> FitJob {
    refit_job(
        cx,
        format!(
            "uncatalogued {} ~ {}",
            discover::balance_symbol(t.balance),
            discover::feature_name(&t)
        ),
        EffectSet::empty(),
        vec![t],
        vec![baseline.params.clone()],
    )
}

/// Whether every part of `small` is in `big`.
fn contains(big: &Fitted, small: &Fitted) -> bool {
    let key = |t: &ExtraTerm| (t.balance, t.pressure, t.speed);
    small.effects.iter().all(|e| big.effects.contains(e))
        && small
            .extra
            .iter()
            .all(|t| big.extra.iter().any(|u| key(u) == key(t)))
}

/// The models within [`ALSO_CONSISTENT_DELTA_BIC`] of `chosen` that are not `chosen` with
/// parts added, best first (at most four, one per label).
pub(crate) fn also_consistent(chosen: &Candidate, all: &[Candidate]) -> Vec<AlsoConsistent> {
    let mut out: Vec<AlsoConsistent> = Vec::new();
    let mut sorted: Vec<&Candidate> = all.iter().collect();
    sorted.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    for c in sorted {
        let near = c.delta_bic <= chosen.delta_bic + ALSO_CONSISTENT_DELTA_BIC
            && c.delta_bic < -SELECT_DELTA_BIC;
        if !near
            || c.label == chosen.label
            || contains(&c.fitted, &chosen.fitted)
            || out.iter().any(|o| o.label == c.label)
        {
            continue;
        }
        out.push(AlsoConsistent {
            label: c.label.clone(),
            description: describe(&c.fitted),
            delta_bic: c.delta_bic - chosen.delta_bic,
            categories: categories(&c.fitted),
        });
        if out.len() == MAX_ALSO {
            break;
        }
    }
    out
}

/// A model's parts in words.
fn describe(f: &Fitted) -> String {
    let mut parts: Vec<String> = f.effects.ids();
    parts.extend(f.extra.iter().map(discover::describe));
    parts.join(" + ")
}

/// The categories of a model's parts.
fn categories(f: &Fitted) -> Vec<Category> {
    let mut out: Vec<Category> = f.effects.iter().map(|e| e.category()).collect();
    out.extend(f.extra.iter().map(discover::category));
    out
}

/// An experiment that would separate `chosen` from the models also consistent with the
/// data, by what they disagree on: the law of one leak path (how the flow grows with the
/// pressure difference), the path (where the air goes), or flow against torque.
pub(crate) fn separating_experiment(chosen: &Candidate, also: &[AlsoConsistent]) -> Option<String> {
    let first = also.first()?;
    let mine = categories(&chosen.fitted);
    let torque = |c: &[Category]| c.iter().all(|c| *c == Category::TorqueLoss);
    let flow = |c: &[Category]| c.iter().all(|c| *c != Category::TorqueLoss);
    let same_paths = chosen.fitted.extra.len() == 1
        && also.iter().all(|a| a.categories == mine)
        && matches!(chosen.fitted.extra[0].balance, BalanceId::Path(_));
    Some(if same_paths {
        "a test at several supply pressures (or an outlet throttle sweep reaching small and large \
         pressure differences), whose flows show how the leak grows with the pressure difference"
            .into()
    } else if torque(&mine) && torque(&first.categories) {
        "a slow speed sweep on a brake at two supply pressures, separating the speed and the \
         pressure dependence of the friction (start-up included)"
            .into()
    } else if flow(&mine) && flow(&first.categories) {
        "recording the chamber pressures p1, p2, pe (or the exhaust flow): the candidates put the \
         lost air in different places"
            .into()
    } else {
        "a stall-torque and flow test at several supply pressures: a leak changes the flow with \
         little torque, a friction the torque with little flow"
            .into()
    })
}
