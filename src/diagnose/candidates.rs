//! Phases 2 and 4, candidates: every applicable catalog effect switched on and refitted warm
//! from the baseline optimum (with the null refit, which guards against crediting an effect
//! with further convergence), ranked by ΔBIC; then the best significant effect paired with
//! the next three.

use super::analysis::channels;
use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::{self, FitJob, Fitted};
use super::models::{label_of, refit_job, Batch, Models};
use super::observe::Note;
use super::{analysis, off_value, Candidate, ModelKind, Skipped};
use super::{Effect, SELECT_DELTA_BIC};
use crate::data::dataset::Dataset;
use crate::model::effects::EffectSet;
use crate::model::params::{spec, MotorParams, ParamId, DEFAULT_ESTIMATED_IDS};
use crate::model::spec::SizeLaw;

/// The refits of phase 2.
pub(crate) struct Refits {
    /// The baseline, replaced by the null refit when that converged further.
    pub baseline: Fitted,
    /// Each single effect's refit.
    pub(crate) singles: Vec<(FitJob, Fitted)>,
}

/// The catalog effects tried on a dataset, and those skipped with the reason.
pub(crate) fn applicable_effects(ds: &Dataset) -> (Vec<Effect>, Vec<Skipped>) {
    let transient = ds.experiments.iter().any(|e| e.kind.is_transient());
    let mut tried = Vec::new();
    let mut skipped = Vec::new();
    for e in Effect::ALL {
        use crate::model::effects::ShowsIn;
        match e.shows_in() {
            ShowsIn::Never { reason } => skipped.push(Skipped {
                effect: e,
                reason: reason.into(),
            }),
            ShowsIn::TransientOnly { reason } if !transient => skipped.push(Skipped {
                effect: e,
                reason: reason.into(),
            }),
            _ => tried.push(e),
        }
    }
    (tried, skipped)
}

/// Refits the base model (the null refit) and each effect of `tried`, warm from `baseline`;
/// what it did goes to `notes`.
pub(crate) fn refit_singles(
    cx: &Context,
    baseline: Fitted,
    tried: &[Effect],
    notes: &mut Vec<Note>,
) -> Result<Refits, DiagnoseError> {
    let mut jobs = vec![FitJob {
        label: "null refit".into(),
        starts: vec![baseline.params.clone()],
        lhs: 0,
        max_iters: cx.opts.refit_iters,
        ..cx.base_job.clone()
    }];
    for e in tried {
        let mut starts = effect_starts(&[*e], &baseline.params, cx.opts.effect_starts);
        if *e == Effect::BreakawayFriction {
            starts.truncate(1);
            starts.extend(stribeck_starts(cx, &baseline.params, notes));
        }
        jobs.push(refit_job(
            cx,
            e.id().into(),
            EffectSet::empty().with(*e),
            Vec::new(),
            starts,
        ));
    }
    let results = fitting::run_jobs(&cx.cost, &cx.target, &jobs, cx.engine);
    let mut baseline = baseline;
    let mut singles = Vec::new();
    for (job, r) in jobs.into_iter().zip(results) {
        if let Ok(f) = &r {
            notes.push(Note::Evaluated(f.evaluations));
        }
        match r {
            Ok(f) if job.label == "null refit" => {
                if f.cost < baseline.cost {
                    notes.push(Note::NullRefitImproved {
                        before: baseline.cost,
                        after: f.cost,
                    });
                    baseline = f;
                }
            }
            Ok(f) => singles.push((job, f)),
            Err(e) => notes.push(Note::failed("candidate", &e)),
        }
    }
    Ok(Refits { baseline, singles })
}

/// Scores the single effects' refits into `models`, best ΔBIC first.
pub(crate) fn rank_singles(
    cx: &Context,
    models: &mut Models,
    singles: Vec<(FitJob, Fitted)>,
    notes: &mut Vec<Note>,
) {
    for (job, f) in singles {
        // As in `Models::refit`: a fitted point that does not simulate is a failed fit.
        match models.score(cx, &job.label, ModelKind::Single, f, notes) {
            Ok(c) => models.all.push(c),
            Err(e) => notes.push(Note::failed("candidate", &e)),
        }
    }
    models.sort();
}

/// When the best single effect is significant, the refits of it paired with each of the next
/// three (always, or only when its residuals still show structure beyond the baseline's noise
/// ratio `limit`, by [`super::DiagnoseOptions::pairs_always`]).
pub(crate) fn pairs(
    cx: &Context,
    limit: f64,
    models: &Models,
    notes: &mut Vec<Note>,
) -> Result<Option<Batch>, DiagnoseError> {
    let singles = &models.all;
    let Some(best) = singles.first().filter(|b| b.delta_bic < -SELECT_DELTA_BIC) else {
        return Ok(None);
    };
    let best_channels = channels(cx, &best.fitted, notes)?;
    let structure = analysis::noise_ratio(&best_channels) > limit
        || !analysis::locate(&best_channels, cx.ds.p_atm_pa).is_empty();
    if !(cx.opts.pairs_always || structure) {
        return Ok(None);
    }
    let jobs: Vec<(ModelKind, FitJob)> = singles
        .iter()
        .skip(1)
        .take(3)
        .map(|other| (ModelKind::Pair, pair_job(cx, best, other)))
        .collect();
    Ok(Some(pair_batch(jobs)))
}

/// Pairs to refit, announced.
fn pair_batch(jobs: Vec<(ModelKind, FitJob)>) -> Batch {
    Batch {
        opening: Note::PairsStart(jobs.len()),
        jobs,
        what: Some("pair"),
    }
}

/// A discovered term can imitate a catalog effect that was never tried together with the best
/// single one. For every significant model with discovered terms, the best single effect
/// is paired with every catalog effect of each term's category (the best-ranked one alone
/// can miss it: ω² vane friction ranks below breakaway friction on its own, yet is the
/// partner of speed-dependent leakage); pairs already fitted are not refitted. The simplicity order then
/// prefers the pair over "single + uncatalogued" whenever it explains the data as well.
/// None when there is no such pair to refit.
pub(crate) fn similar_pairs(cx: &Context, models: &Models) -> Option<Batch> {
    let singles: Vec<&Candidate> = models
        .all
        .iter()
        .filter(|c| c.kind == ModelKind::Single)
        .collect();
    let best = singles
        .first()
        .filter(|b| b.delta_bic < -SELECT_DELTA_BIC)?;
    let categories: Vec<_> = models
        .all
        .iter()
        .filter(|c| c.kind >= ModelKind::Uncatalogued && c.delta_bic < -SELECT_DELTA_BIC)
        .flat_map(|c| c.fitted.extra.iter().map(super::discover::category))
        .collect();
    let mut jobs: Vec<(ModelKind, FitJob)> = Vec::new();
    for cat in categories {
        let others = singles.iter().skip(1).filter(|c| {
            c.fitted
                .effects
                .iter()
                .next()
                .is_some_and(|e| e.category() == cat)
        });
        for other in others {
            let job = pair_job(cx, best, other);
            let done = models.all.iter().any(|c| c.label == job.label)
                || jobs.iter().any(|(_, j)| j.label == job.label);
            if !done {
                jobs.push((ModelKind::Pair, job));
            }
        }
    }
    (!jobs.is_empty()).then(|| pair_batch(jobs))
}

/// The refit of `best`'s effect with `other`'s: warm from `best`'s optimum with `other`'s
/// fitted parameters, with `other`'s effect off, and at two points of its ranges.
fn pair_job(cx: &Context, best: &Candidate, other: &Candidate) -> FitJob {
    let (a, b) = (
        best.fitted.effects.iter().next().expect("one effect"),
        other.fitted.effects.iter().next().expect("one effect"),
    );
    let effects = EffectSet::empty().with(a).with(b);
    let warm = &best.fitted.params;
    let other_set = EffectSet::empty().with(b);
    let mut starts = vec![with_effect_params(warm, &other.fitted.params, &other_set)];
    // Also at the middle and lower quarter of `other`'s ranges: when `other` alone gains
    // nothing (ω² vane friction beside unmodelled leakage), its fitted value is at the
    // bound, where the refit cannot leave it.
    starts.extend(effect_starts(&[b], warm, 3));
    refit_job(cx, label_of(&effects, 0).0, effects, Vec::new(), starts)
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
                        let (lo, hi) = s.search_at(base.size());
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

/// Static torques scanned for `breakaway_friction`, in units of the start's T_c.
const STATIC_OVER_COULOMB: [f64; 5] = [1.3, 1.8, 2.5, 3.5, 5.0];
/// Coulomb torques scanned, in units of the baseline's T_c: a base fit of a motor with
/// stiction raises T_c to spread the start-up torque over the whole run (to twice the true
/// T_c at T_s = 3·T_c), and from that T_c the refit does not find the true one.
const COULOMB_SCALE: [f64; 3] = [1.0, 0.7, 0.5];
/// Speeds, rad/s, at which the Coulomb torque taken off ([`COULOMB_SCALE`]) is handed to
/// the viscous term (d += ΔT_c/ω): the base fit lowers d as it raises T_c (to its lower
/// bound under stiction), and a lower T_c alone makes the whole run too fast.
const HANDOVER_SPEEDS: [f64; 3] = [250.0, 500.0, 1000.0];
/// Stribeck speeds scanned, rad/s: a log grid over the range where a start-up in a ramp can
/// show them (below 1 rad/s the Stribeck curve is a step; above 200 rad/s it covers the
/// whole low-speed range).
const STRIBECK_GRID: [f64; 7] = [1.0, 2.4, 5.8, 14.0, 34.0, 83.0, 200.0];

/// Starts of the `breakaway_friction` refit that cover the Stribeck range: the likelihood
/// over a grid of Coulomb torque ([`COULOMB_SCALE`] × the baseline's T_c, the difference
/// handed to the viscous term at [`HANDOVER_SPEEDS`]), static torque
/// ([`STATIC_OVER_COULOMB`] × that T_c) and Stribeck speed ([`STRIBECK_GRID`], log-spaced),
/// the other base parameters held; the best point of each Coulomb scale. A warm start from
/// one Stribeck speed stays in its valley: the static excess and the Stribeck speed trade
/// against each other along the ramp's start-up, and a late start can be fitted by a high
/// T_s that decays fast or a lower one that decays slowly.
fn stribeck_starts(cx: &Context, base: &MotorParams, notes: &mut Vec<Note>) -> Vec<MotorParams> {
    let base = &unpinned(base);
    // The grids' speeds are the reference motor's; a motor of another size runs at speeds
    // ∝ s^{-⅓} (`SizeLaw::SPEED`), and so do its Stribeck and hand-over speeds.
    let speed_scale = base.size().powf(SizeLaw::SPEED);
    let grid: Vec<(usize, MotorParams)> = (0..COULOMB_SCALE.len())
        .flat_map(|s| HANDOVER_SPEEDS.iter().map(move |h| (s, h)))
        .flat_map(|(s, h)| STATIC_OVER_COULOMB.iter().map(move |k| (s, h, k)))
        .flat_map(|(s, h, k)| STRIBECK_GRID.iter().map(move |w| (s, h, k, w)))
        .filter_map(|(s, h, k, w)| {
            let t_c = COULOMB_SCALE[s] * base.t_coulomb();
            let visc = base.visc() + (base.t_coulomb() - t_c) / (h * speed_scale);
            base.with_value(ParamId::T_COULOMB, t_c)
                .and_then(|p| p.with_value(ParamId::VISC, visc))
                .and_then(|p| p.with_value(ParamId::T_STATIC, k * t_c))
                .and_then(|p| p.with_value(ParamId::W_STRIBECK, w * speed_scale))
                .ok()
                .map(|p| (s, p))
        })
        .collect();
    let effects = EffectSet::empty().with(Effect::BreakawayFriction);
    let (cost, target, solver) = (&cx.cost, &cx.target, &cx.solver);
    notes.push(Note::Evaluated(grid.len() as u64));
    let chi2 = cx.engine.map(&grid, |(_, p)| {
        let motor = crate::model::motor::Motor::new(p.clone(), effects.clone());
        target.chi2(cost, &motor, solver).unwrap_or(f64::INFINITY)
    });
    // The best point of each Coulomb scale: a held lower T_c makes the run too fast, so
    // the lower scales would never rank among the best of the whole grid.
    (0..COULOMB_SCALE.len())
        .filter_map(|s| {
            (0..grid.len())
                .filter(|i| grid[*i].0 == s && chi2[*i].is_finite())
                .min_by(|a, b| chi2[*a].total_cmp(&chi2[*b]))
        })
        .map(|i| grid[i].1.clone())
        .collect()
}

/// `base` with every estimated base parameter that sits at the lower end of its search
/// range given back its default: a base fit of a motor with stiction drives a conductance
/// (c_12) to its bound, where its logarithmic coordinate has no gradient, and a refit from
/// there never brings it back.
fn unpinned(base: &MotorParams) -> MotorParams {
    let mut p = base.clone();
    for id in DEFAULT_ESTIMATED_IDS {
        let s = id.spec();
        if base.value(id) <= s.search_at(base.size()).0 * 1.01 {
            p = p.with_value(id, s.default).unwrap_or(p);
        }
    }
    p
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
