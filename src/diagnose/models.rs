//! The refitted models of a diagnosis: their names, labels and scores.

use super::analysis::channels;
use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::{self, FitJob, Fitted};
use super::observe::Note;
use super::{analysis, Candidate, ModelKind};
use crate::data::dataset::Dataset;
use crate::model::effects::EffectSet;
use crate::model::motor::ExtraTerm;
use crate::model::params::{estimated_names as names_for, MotorParams};

/// Every refitted model so far, scored against the baseline's BIC.
pub(crate) struct Models {
    /// BIC of the baseline (after the null refit).
    base_bic: f64,
    /// The refitted models.
    pub all: Vec<Candidate>,
}

impl Models {
    /// No models yet, against a baseline of BIC `base_bic`.
    pub fn new(base_bic: f64) -> Self {
        Self {
            base_bic,
            all: Vec::new(),
        }
    }

    /// Best ΔBIC first (stable: ties keep their order).
    pub fn sort(&mut self) {
        self.all.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    }

    /// A fit with its ΔBIC and noise ratio (the simulation of its channels noted in `notes`).
    pub(crate) fn score(
        &self,
        cx: &Context,
        label: &str,
        kind: ModelKind,
        f: Fitted,
        notes: &mut Vec<Note>,
    ) -> Result<Candidate, DiagnoseError> {
        let ch = channels(cx, &f, notes)?;
        Ok(Candidate {
            label: label.to_string(),
            kind,
            delta_bic: f.bic() - self.base_bic,
            noise_ratio: analysis::noise_ratio(&ch),
            fitted: f,
            held_out: None,
        })
    }

    /// Runs the refits a phase planned, the one place a diagnosis refits a model: `tell`
    /// (the orchestrator's account) hears what the phase noted so far, then the batch's
    /// opening line, before the work, then the fits' scores. Returns the scored models.
    pub fn run(
        &self,
        cx: &Context,
        batch: Batch,
        notes: &mut Vec<Note>,
        tell: &mut dyn FnMut(&mut Vec<Note>),
    ) -> Vec<Candidate> {
        tell(notes);
        tell(&mut vec![batch.opening]);
        let found = self.refit(cx, &batch.jobs, batch.what, notes);
        tell(notes);
        found
    }

    /// Runs the fits and scores each, noting it; a failed fit is noted as `what` failed
    /// (None: the job's label) and left out.
    fn refit(
        &self,
        cx: &Context,
        jobs: &[(ModelKind, FitJob)],
        what: Option<&str>,
        notes: &mut Vec<Note>,
    ) -> Vec<Candidate> {
        let only: Vec<FitJob> = jobs.iter().map(|(_, j)| j.clone()).collect();
        let results = fitting::run_jobs(&cx.cost, &cx.target, &only, cx.engine);
        count_refits(jobs.len());
        let mut out = Vec::new();
        for ((kind, job), r) in jobs.iter().zip(results) {
            let what = what.unwrap_or(&job.label);
            match r {
                Ok(f) => {
                    notes.push(Note::Evaluated(f.evaluations));
                    // A fitted point whose simulation then fails (a datasheet row without
                    // steady state) is a failed fit, not a failed diagnosis.
                    match self.score(cx, &job.label, *kind, f, notes) {
                        Ok(c) => {
                            notes.push(Note::Scored(Box::new(c.clone())));
                            out.push(c);
                        }
                        Err(e) => notes.push(Note::failed(what, &e)),
                    }
                }
                Err(e) => notes.push(Note::failed(what, &e)),
            }
        }
        out
    }
}

/// Refits a phase plans and the orchestrator runs ([`Models::run`]): the note that opens
/// them, said before the work, the fits, and what a failed one is called (None: its label).
pub(crate) struct Batch {
    /// The progress line that announces the refits.
    pub opening: Note,
    /// The fits, each with the kind of model it makes.
    pub jobs: Vec<(ModelKind, FitJob)>,
    /// What a failed fit is called in its progress line.
    pub what: Option<&'static str>,
}

impl Batch {
    /// Models with discovered terms to refit, announced as such ([`Note::DiscoveredStart`]),
    /// a failed one called `what`; None when there are none.
    pub fn discovered(jobs: Vec<(ModelKind, FitJob)>, what: &'static str) -> Option<Self> {
        if jobs.is_empty() {
            return None;
        }
        Some(Self {
            opening: Note::DiscoveredStart(jobs.len()),
            jobs,
            what: Some(what),
        })
    }
}

/// A warm refit of a model (catalog `effects` and discovered terms `extra`) from given
/// starts, with the refit budget: what [`Models::run`] runs.
pub(crate) fn refit_job(
    cx: &Context,
    label: String,
    effects: EffectSet,
    extra: Vec<ExtraTerm>,
    starts: Vec<MotorParams>,
) -> FitJob {
    FitJob {
        label,
        names: names_for(&effects),
        effects,
        extra,
        starts,
        lhs: 0,
        max_iters: cx.opts.refit_iters,
        seed: cx.opts.seed,
    }
}

/// Number of parts (catalog effects and discovered terms) of a model.
pub(crate) fn parts(f: &Fitted) -> usize {
    f.effects.iter().count() + f.extra.len()
}

/// Label and kind of a model made of catalog effects and `terms` discovered terms.
pub(crate) fn label_of(effects: &EffectSet, terms: usize) -> (String, ModelKind) {
    let mut parts: Vec<String> = effects.ids();
    let n_effects = parts.len();
    match terms {
        0 => {}
        1 => parts.push("uncatalogued".into()),
        _ => parts.push(format!("uncatalogued ({terms} terms)")),
    }
    let kind = match (n_effects, terms) {
        (0, 0) => ModelKind::Baseline,
        (1, 0) => ModelKind::Single,
        (_, 0) => ModelKind::Pair,
        (0, _) => ModelKind::Uncatalogued,
        _ => ModelKind::CatalogAndUncatalogued,
    };
    if parts.is_empty() {
        return ("baseline".into(), kind);
    }
    (parts.join("+"), kind)
}

/// A dataset with the experiments whose index passes `keep`.
pub(crate) fn subset(ds: &Dataset, keep: impl Fn(usize) -> bool) -> Dataset {
    Dataset {
        experiments: ds
            .experiments
            .iter()
            .enumerate()
            .filter(|(i, _)| keep(*i))
            .map(|(_, e)| e.clone())
            .collect(),
        ..ds.clone()
    }
}

/// Counts `n` refits run on this thread ([`REFITS_RUN`]); nothing outside the tests.
#[cfg(not(test))]
fn count_refits(_n: usize) {}

/// Counts `n` refits run on this thread ([`REFITS_RUN`]).
#[cfg(test)]
fn count_refits(n: usize) {
    REFITS_RUN.with(|c| c.set(c.get() + n));
}

#[cfg(test)]
thread_local! {
    /// Refits that [`Models::run`] has run on this thread: a test observer reads it to see
    /// whether a progress line arrives before the work it announces.
    pub(crate) static REFITS_RUN: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}
