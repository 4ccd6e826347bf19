//! Phase 6 and 7, selection: the simplest model within [`SELECT_DELTA_BIC`] of the lowest
//! BIC, checked by backward elimination; then the extended model and its `selected`
//! entries.

use super::analysis::channels;
use super::analysis::{self, ChannelData, Location};
use super::context::Context;
use super::discover;
use super::error::DiagnoseError;
use super::fitting::FitJob;
use super::models::{label_of, parts, refit_job, Batch, Models};
use super::observe::Note;
use super::{Candidate, Effect, ModelKind, Selected, SELECT_DELTA_BIC};
use crate::model::effects::EffectSet;
use crate::model::motor::ExtraTerm;
use crate::model::params::spec;

/// Backward elimination, one step at a time (the orchestrator runs the refits between): a
/// chosen model of several parts keeps each part only if dropping it, refitted warm from the
/// same optimum (so with the same convergence), costs more than [`SELECT_DELTA_BIC`]: a pair
/// can otherwise "win" by converging better than its single. The refits that check
/// `chosen`: each part's removal; None when it has one part.
pub(crate) fn elimination(cx: &Context, chosen: &Candidate) -> Option<Batch> {
    (parts(&chosen.fitted) >= 2).then(|| Batch {
        opening: Note::Elimination(chosen.label.clone()),
        jobs: removals(cx, chosen),
        what: None,
    })
}

/// Takes the refitted removals `subs` into `models` (a model already there keeps the better
/// ΔBIC) and chooses again.
pub(crate) fn rechoose(models: &mut Models, subs: Vec<Candidate>) -> Option<Candidate> {
    for sub in subs {
        match models.all.iter_mut().find(|x| x.label == sub.label) {
            Some(x) if x.delta_bic <= sub.delta_bic => {}
            Some(x) => *x = sub,
            None => models.all.push(sub),
        }
    }
    models.sort();
    choose(&models.all)
}

/// The refits of `c` without each of its parts, warm from its optimum.
fn removals(cx: &Context, c: &Candidate) -> Vec<(ModelKind, FitJob)> {
    let effects: Vec<Effect> = c.fitted.effects.iter().collect();
    (0..parts(&c.fitted))
        .map(|drop| {
            let keep_effects: EffectSet = effects
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != drop)
                .map(|(_, e)| *e)
                .collect();
            let keep_terms: Vec<ExtraTerm> = c
                .fitted
                .extra
                .iter()
                .enumerate()
                .filter(|(i, _)| i + effects.len() != drop)
                .map(|(_, t)| *t)
                .collect();
            let (label, kind) = label_of(&keep_effects, keep_terms.len());
            let starts = vec![c.fitted.params.clone()];
            (kind, refit_job(cx, label, keep_effects, keep_terms, starts))
        })
        .collect()
}

/// The simplest model within [`SELECT_DELTA_BIC`] of the lowest BIC, or `None` when no
/// model beats the baseline by [`SELECT_DELTA_BIC`].
pub(crate) fn choose(candidates: &[Candidate]) -> Option<Candidate> {
    let best = candidates
        .iter()
        .map(|c| c.delta_bic)
        .fold(0.0f64, f64::min);
    if best + SELECT_DELTA_BIC >= 0.0 {
        return None;
    }
    candidates
        .iter()
        .filter(|c| c.delta_bic <= best + SELECT_DELTA_BIC)
        .min_by(|a, b| {
            a.kind
                .cmp(&b.kind)
                .then(a.delta_bic.total_cmp(&b.delta_bic))
        })
        .cloned()
}

/// The chosen model against the data.
pub(crate) struct Extended {
    /// The chosen model (the baseline when nothing is chosen).
    pub model: Candidate,
    /// Its `selected` entries.
    pub selected: Vec<Selected>,
    /// Its channels against the data.
    pub channels: Vec<ChannelData>,
    /// The locations it leaves.
    pub locations: Vec<Location>,
}

/// The extended model: `chosen` as last scored in `all` (with its held-out ratio), or the
/// baseline.
pub(crate) fn extended(
    cx: &Context,
    chosen: Option<Candidate>,
    all: &[Candidate],
    baseline: &Candidate,
    notes: &mut Vec<Note>,
) -> Result<Extended, DiagnoseError> {
    let chosen = chosen.map(|c| {
        all.iter()
            .find(|x| x.label == c.label)
            .cloned()
            .unwrap_or(c)
    });
    let selected = match &chosen {
        Some(c) => selected_entries(c, all),
        None => Vec::new(),
    };
    let model = chosen.unwrap_or_else(|| baseline.clone());
    let channels = channels(cx, &model.fitted, notes)?;
    let locations = analysis::locate(&channels, cx.ds.p_atm_pa);
    Ok(Extended {
        model,
        selected,
        channels,
        locations,
    })
}

/// The `selected` entries of a chosen model. Entries come in order (catalog effects by
/// their single-effect ΔBIC, then discovered terms); each entry's ΔBIC is the BIC of the
/// model up to and including it minus the BIC of the model before it (taken from the
/// refitted nested models), so the entries add up to the extended model's ΔBIC.
fn selected_entries(chosen: &Candidate, all: &[Candidate]) -> Vec<Selected> {
    let single_delta = |e: Effect| {
        all.iter()
            .find(|c| c.kind == ModelKind::Single && c.label == e.id())
            .map_or(0.0, |c| c.delta_bic)
    };
    let mut effects: Vec<Effect> = chosen.fitted.effects.iter().collect();
    effects.sort_by(|a, b| single_delta(*a).total_cmp(&single_delta(*b)));
    let n = effects.len() + chosen.fitted.extra.len();
    // ΔBIC of the nested model made of the first i entries.
    let nested = |i: usize| -> f64 {
        if i == n {
            return chosen.delta_bic;
        }
        let set: EffectSet = effects.iter().take(i).copied().collect();
        let terms = i.saturating_sub(effects.len());
        all.iter()
            .find(|c| c.fitted.effects == set && c.fitted.extra.len() == terms)
            .map_or(chosen.delta_bic, |c| c.delta_bic)
    };
    let mut out = Vec::new();
    let mut previous = 0.0;
    for i in 0..n {
        let now = nested(i + 1);
        let delta_bic = now - previous;
        previous = now;
        out.push(match effects.get(i) {
            Some(e) => effect_entry(*e, chosen, delta_bic),
            None => term_entry(chosen.fitted.extra[i - effects.len()], delta_bic),
        });
    }
    out
}

/// The entry of a catalog effect of the chosen model.
fn effect_entry(e: Effect, chosen: &Candidate, delta_bic: f64) -> Selected {
    Selected {
        effect: e.id().to_string(),
        category: e.category(),
        parameters: e
            .parameters()
            .iter()
            .map(|n| {
                (
                    n.to_string(),
                    chosen.fitted.params.get(n).unwrap_or(f64::NAN),
                    spec(n).map_or(String::new(), |s| s.unit.to_string()),
                )
            })
            .collect(),
        delta_bic,
        term: None,
    }
}

/// The entry of a discovered term of the chosen model.
fn term_entry(t: ExtraTerm, delta_bic: f64) -> Selected {
    Selected {
        effect: "uncatalogued".into(),
        category: discover::category(&t),
        parameters: vec![(
            "coefficient".into(),
            t.coefficient,
            discover::coefficient_unit(&t),
        )],
        delta_bic,
        term: Some(t),
    }
}
