//! Phase 5, uncatalogued terms ([`super::discover`]): sparse regression of the misfit over
//! the term library, on the baseline and on the best significant catalog model; each
//! proposed term is put into the model, and the orchestrator refits it.

use super::analysis::channels;
use super::context::Context;
use super::discover::{self, Regression};
use super::error::DiagnoseError;
use super::fitting::{FitJob, Fitted};
use super::models::{label_of, refit_job, Batch, Models};
use super::observe::Note;
use super::{ModelKind, SELECT_DELTA_BIC};
use crate::model::params::estimated_names as names_for;

/// Regresses the baseline's misfit over the term library and notes the terms it proposes
/// (discovery on: the orchestrator asks).
pub(crate) fn regress(
    cx: &Context,
    baseline: &Fitted,
    notes: &mut Vec<Note>,
) -> Result<Regression, DiagnoseError> {
    let reg = discover::regress(&cx.cost, &cx.target, baseline, &cx.base_names, cx.engine)?;
    notes.push(Note::Evaluated(discover::evaluations(cx.base_names.len())));
    for t in &reg.selected {
        notes.push(Note::Proposed {
            term: t.term,
            delta_bic: t.delta_bic,
            on_top_of: None,
        });
    }
    Ok(reg)
}

/// The refits of the models with discovered terms: the baseline's proposals (`reg`), and the
/// best catalog model with a term of its own misfit. None when nothing is proposed. `limit`
/// is the noise ratio that noise alone stays below ([`super::noise_ratio_limit`] of the
/// baseline's channels).
pub(crate) fn term_refits(
    cx: &Context,
    baseline: &Fitted,
    reg: &Regression,
    limit: f64,
    models: &Models,
    notes: &mut Vec<Note>,
) -> Result<Option<Batch>, DiagnoseError> {
    let mut jobs = on_the_baseline(cx, baseline, reg);
    jobs.extend(on_the_best_catalog_model(cx, limit, models, notes)?);
    Ok(Batch::discovered(jobs, "discovered-term refit"))
}

/// The base model with the first proposed term, and with every proposed term when there
/// are several (warm from the baseline with the refit budget: the coefficients start from
/// their linearised values).
fn on_the_baseline(cx: &Context, baseline: &Fitted, reg: &Regression) -> Vec<(ModelKind, FitJob)> {
    let mut jobs = Vec::new();
    let Some(first) = reg.selected.first() else {
        return jobs;
    };
    jobs.push((
        ModelKind::Uncatalogued,
        FitJob {
            label: "uncatalogued".into(),
            extra: vec![first.term],
            starts: vec![baseline.params.clone()],
            max_iters: cx.opts.refit_iters,
            ..cx.base_job.clone()
        },
    ));
    if reg.selected.len() > 1 {
        jobs.push((
            ModelKind::Uncatalogued,
            FitJob {
                label: "uncatalogued (2 terms)".into(),
                extra: reg.selected.iter().map(|t| t.term).collect(),
                starts: vec![baseline.params.clone()],
                max_iters: cx.opts.refit_iters,
                ..cx.base_job.clone()
            },
        ));
    }
    jobs
}

/// The best catalog model, when significant, with the first term its own misfit proposes;
/// nothing when that model alone reaches the noise (noise ratio within `limit`, no location
/// left): a term on top of it would be a patchwork, and its regression and refit the
/// costliest part of the search.
fn on_the_best_catalog_model(
    cx: &Context,
    limit: f64,
    models: &Models,
    notes: &mut Vec<Note>,
) -> Result<Option<(ModelKind, FitJob)>, DiagnoseError> {
    let Some(bc) = models
        .all
        .iter()
        .filter(|c| c.kind <= ModelKind::Pair)
        .min_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic))
        .filter(|c| c.delta_bic < -SELECT_DELTA_BIC)
    else {
        return Ok(None);
    };
    if bc.noise_ratio <= limit {
        let channels = channels(cx, &bc.fitted, notes)?;
        if super::analysis::locate(&channels, cx.ds.p_atm_pa).is_empty() {
            return Ok(None);
        }
    }
    let names = names_for(&bc.fitted.effects);
    let reg = discover::regress(&cx.cost, &cx.target, &bc.fitted, &names, cx.engine)?;
    notes.push(Note::Evaluated(discover::evaluations(names.len())));
    let Some(first) = reg.selected.first() else {
        return Ok(None);
    };
    notes.push(Note::Proposed {
        term: first.term,
        delta_bic: first.delta_bic,
        on_top_of: Some(bc.label.clone()),
    });
    let job = refit_job(
        cx,
        label_of(&bc.fitted.effects, 1).0,
        bc.fitted.effects.clone(),
        vec![first.term],
        vec![bc.fitted.params.clone()],
    );
    Ok(Some((ModelKind::CatalogAndUncatalogued, job)))
}
