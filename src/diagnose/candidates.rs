//! Phases 2 and 4, candidates: every applicable catalog effect switched on and refitted warm
//! from the baseline optimum (with the null refit, which guards against crediting an effect
//! with further convergence), ranked by ΔBIC; then the best significant effect paired with
//! the next three.

use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::{self, FitJob, Fitted};
use super::models::{label_of, Models};
use super::observe::Progress;
use super::{analysis, applicable_effects, off_value, Candidate, ModelKind, Skipped};
use super::{Effect, SELECT_DELTA_BIC};
use crate::model::effects::EffectSet;
use crate::model::params::{spec, MotorParams};

/// The refits of phase 2.
pub(crate) struct Refits {
    /// The baseline, replaced by the null refit when that converged further.
    pub baseline: Fitted,
    /// Each single effect's refit.
    pub singles: Vec<(FitJob, Fitted)>,
    /// The catalog effects not tried.
    pub skipped: Vec<Skipped>,
}

/// Refits the base model (the null refit) and each applicable effect, warm from `baseline`.
pub(crate) fn refit_singles(cx: &Context, baseline: Fitted) -> Result<Refits, DiagnoseError> {
    let (tried, skipped) = applicable_effects(cx.ds);
    let mut jobs = vec![FitJob {
        label: "null refit".into(),
        starts: vec![baseline.params.clone()],
        lhs: 0,
        max_iters: cx.opts.refit_iters,
        ..cx.base_job()
    }];
    for e in &tried {
        let starts = effect_starts(&[*e], &baseline.params, cx.opts.effect_starts);
        jobs.push(cx.refit_job(
            e.id().into(),
            EffectSet::empty().with(*e),
            Vec::new(),
            starts,
        ));
    }
    cx.say(Progress::CandidatesStart(&tried));
    let results = fitting::run_jobs(&cx.cost, &cx.target, &jobs, cx.threads());
    let mut baseline = baseline;
    let mut singles = Vec::new();
    for (job, r) in jobs.into_iter().zip(results) {
        match r {
            Ok(f) if job.label == "null refit" => {
                if f.cost < baseline.cost {
                    cx.say(Progress::NullRefitImproved {
                        before: baseline.cost,
                        after: f.cost,
                    });
                    baseline = f;
                }
            }
            Ok(f) => singles.push((job, f)),
            Err(e) => cx.say(Progress::Failed {
                what: "candidate",
                error: &e.to_string(),
            }),
        }
    }
    Ok(Refits {
        baseline,
        singles,
        skipped,
    })
}

/// Scores the single effects' refits into `models`, best ΔBIC first.
pub(crate) fn rank_singles(
    cx: &Context,
    models: &mut Models,
    singles: Vec<(FitJob, Fitted)>,
) -> Result<(), DiagnoseError> {
    for (job, f) in singles {
        let c = models.score(cx, &job.label, ModelKind::Single, f)?;
        models.all.push(c);
    }
    models.sort();
    for c in &models.all {
        cx.say(Progress::Ranked(c));
    }
    Ok(())
}

/// When the best single effect is significant, refits it paired with each of the next three
/// (always, or only when its residuals still show structure beyond the baseline's noise
/// ratio `limit`, by [`super::DiagnoseOptions::pairs_always`]).
pub(crate) fn pairs(cx: &Context, limit: f64, models: &mut Models) -> Result<(), DiagnoseError> {
    let singles: Vec<Candidate> = models.all.clone();
    let Some(best) = singles.first().filter(|b| b.delta_bic < -SELECT_DELTA_BIC) else {
        return Ok(());
    };
    let best_channels = cx.channels(&best.fitted)?;
    let structure = analysis::noise_ratio(&best_channels) > limit
        || !analysis::locate(&best_channels, cx.ds.p_atm_pa).is_empty();
    if !(cx.opts.pairs_always || structure) {
        return Ok(());
    }
    let jobs: Vec<(ModelKind, FitJob)> = singles
        .iter()
        .skip(1)
        .take(3)
        .map(|other| (ModelKind::Pair, pair_job(cx, best, other)))
        .collect();
    cx.say(Progress::PairsStart(jobs.len()));
    let found = models.refit(cx, &jobs, Some("pair"))?;
    models.all.extend(found);
    Ok(())
}

/// The refit of `best`'s effect with `other`'s: warm from `best`'s optimum with `other`'s
/// fitted parameters, and with `other`'s effect off.
fn pair_job(cx: &Context, best: &Candidate, other: &Candidate) -> FitJob {
    let (a, b) = (
        best.fitted.effects.iter().next().expect("one effect"),
        other.fitted.effects.iter().next().expect("one effect"),
    );
    let effects = EffectSet::empty().with(a).with(b);
    let warm = &best.fitted.params;
    let other_set = EffectSet::empty().with(b);
    let mut starts = vec![with_effect_params(warm, &other.fitted.params, &other_set)];
    starts.extend(effect_starts(&[b], warm, 1));
    cx.refit_job(label_of(&effects, 0).0, effects, Vec::new(), starts)
}

/// Start points of a candidate: `base` with the effect off, then at positions u of the
/// effects' search ranges (log-spaced for positive parameters).
pub(crate) fn effect_starts(effects: &[Effect], base: &MotorParams, n: usize) -> Vec<MotorParams> {
    let mut out = Vec::new();
    let set = |u: Option<f64>| {
        let mut p = base.clone();
        for e in effects {
            for name in e.parameters() {
                let s = spec(name).expect("declared");
                let v = match u {
                    None => off_value(name, base),
                    Some(u) => {
                        let (lo, hi) = s.search;
                        if lo > 0.0 {
                            (lo.ln() + u * (hi.ln() - lo.ln())).exp()
                        } else {
                            lo + u * (hi - lo)
                        }
                    }
                };
                p = p.with(name, v).unwrap_or(p);
            }
        }
        p
    };
    out.push(set(None));
    for u in [0.5, 0.25, 0.75, 0.1, 0.9]
        .into_iter()
        .take(n.saturating_sub(1))
    {
        out.push(set(Some(u)));
    }
    out
}

/// A copy of `base` with every parameter of `effects` taken from `from`.
fn with_effect_params(base: &MotorParams, from: &MotorParams, effects: &EffectSet) -> MotorParams {
    let mut p = base.clone();
    for e in effects.iter() {
        for name in e.parameters() {
            if let Some(v) = from.get(name) {
                p = p.with(name, v).unwrap_or(p);
            }
        }
    }
    p
}
