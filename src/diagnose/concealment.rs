//! Phase 6, concealment: each experiment fitted alone (warm from the baseline) against the
//! joint fit (likelihood-ratio/Chow test), and each experiment predicted from a fit to the
//! others (held-out noise ratio) for the baseline, the best candidates and the chosen model.

use super::analysis::noise_ratio_limit;
use super::context::Context;
use super::error::DiagnoseError;
use super::fitting::{self, FitJob, Fitted};
use super::locate::Baseline;
use super::models::{refit_job, subset, Models};
use super::observe::{ChowTest, Note};
use super::{analysis, stats, Candidate, Concealment, ExperimentCheck};
use crate::data::dataset::Dataset;
use crate::objective::cost::{CostModel, CostOptions};
use crate::objective::likelihood::Target;

/// A fit of the concealment test: (model index into the held-out models, or None for the
/// base model fitted to the experiment alone; experiment index; the fit).
type Task = (Option<usize>, usize, FitJob);

/// Each experiment alone and the others without it, with their costs and targets.
struct Split {
    cost_only: Vec<CostModel>,
    cost_without: Vec<CostModel>,
    target_only: Vec<Target>,
    target_without: Vec<Target>,
}

impl Split {
    fn new(ds: &Dataset) -> Result<Self, DiagnoseError> {
        let n_exp = ds.experiments.len();
        let only: Vec<Dataset> = (0..n_exp).map(|i| subset(ds, |j| j == i)).collect();
        let without: Vec<Dataset> = (0..n_exp).map(|i| subset(ds, |j| j != i)).collect();
        let costs = |sets: &[Dataset]| -> Result<Vec<CostModel>, DiagnoseError> {
            sets.iter()
                .map(|d| Ok(CostModel::new(d, CostOptions::default())?))
                .collect()
        };
        let cost_only = costs(&only)?;
        let cost_without = costs(&without)?;
        let targets =
            |costs: &[CostModel], sets: &[Dataset]| -> Result<Vec<Target>, DiagnoseError> {
                costs
                    .iter()
                    .zip(sets)
                    .map(|(c, d)| Ok(Target::new(c, d)?))
                    .collect()
            };
        Ok(Self {
            target_only: targets(&cost_only, &only)?,
            target_without: targets(&cost_without, &without)?,
            cost_only,
            cost_without,
        })
    }
}

/// Whether the test runs: asked for, and two experiments or more.
pub(crate) fn applies(cx: &Context) -> bool {
    cx.opts.concealment && cx.ds.experiments.len() >= 2
}

/// Runs the test ([`applies`] says when); sets the held-out ratio of `baseline_c` and of
/// the held-out models in `models`.
pub(crate) fn test(
    cx: &Context,
    base: &Baseline,
    baseline_c: &mut Candidate,
    models: &mut Models,
    chosen: Option<&Candidate>,
    notes: &mut Vec<Note>,
) -> Result<Concealment, DiagnoseError> {
    let split = Split::new(cx.ds)?;
    let held = held_models(cx, baseline_c, &models.all, chosen);
    let tasks = tasks(cx, &base.fitted, &held);
    let fitted = fit_tasks(cx, &split, &tasks)?;
    notes.push(Note::Evaluated(fitted.iter().map(|f| f.evaluations).sum()));
    let mut checks: Vec<ExperimentCheck> = Vec::new();
    let mut held_ms: Vec<Vec<f64>> = vec![Vec::new(); held.len()];
    for ((m, i, _), f) in tasks.iter().zip(fitted) {
        let ex = &cx.ds.experiments[*i];
        match m {
            None => checks.push(alone_check(cx, base, &split, *i, &f)?),
            Some(m) => {
                let ch = analysis::channel_data(
                    &split.cost_only[*i],
                    &split.target_only[*i],
                    &f.motor(),
                    &cx.solver,
                )
                .map(|c| analysis::noise_ratio(&c))
                .unwrap_or(f64::INFINITY);
                held_ms[*m].push(ch * ch);
                if *m == 0 {
                    if let Some(c) = checks.iter_mut().find(|c| c.file == ex.file) {
                        c.held_out_ratio = Some(ch);
                    }
                }
            }
        }
    }
    for (m, c) in held.iter().enumerate() {
        let v = (held_ms[m].iter().sum::<f64>() / held_ms[m].len().max(1) as f64).sqrt();
        if m == 0 {
            baseline_c.held_out = Some(v);
        } else if let Some(x) = models.all.iter_mut().find(|x| x.label == c.label) {
            x.held_out = Some(v);
        }
    }
    let (test, concealment) = chow(cx, &base.fitted, checks);
    notes.push(Note::ConcealmentResult(test));
    Ok(concealment)
}

/// Models whose held-out prediction is wanted: the baseline, the top candidates, the chosen
/// one.
fn held_models(
    cx: &Context,
    baseline_c: &Candidate,
    all: &[Candidate],
    chosen: Option<&Candidate>,
) -> Vec<Candidate> {
    let mut held: Vec<Candidate> = vec![baseline_c.clone()];
    for c in all.iter().take(cx.opts.held_out_top) {
        held.push(c.clone());
    }
    if let Some(c) = chosen {
        if !held.iter().any(|h| h.label == c.label) {
            held.push(c.clone());
        }
    }
    held
}

/// The base model fitted to each experiment alone, then each held-out model fitted without
/// each experiment, all warm from their optimum.
fn tasks(cx: &Context, baseline: &Fitted, held: &[Candidate]) -> Vec<Task> {
    let experiments = &cx.ds.experiments;
    let mut tasks: Vec<Task> = Vec::new();
    for (i, ex) in experiments.iter().enumerate() {
        tasks.push((
            None,
            i,
            FitJob {
                label: format!("alone {}", ex.file),
                starts: vec![baseline.params.clone()],
                lhs: 0,
                max_iters: cx.opts.refit_iters,
                ..cx.base_job.clone()
            },
        ));
    }
    for (m, c) in held.iter().enumerate() {
        for (i, ex) in experiments.iter().enumerate() {
            let job = refit_job(
                cx,
                format!("{} without {}", c.label, ex.file),
                c.fitted.effects.clone(),
                c.fitted.extra.clone(),
                vec![c.fitted.params.clone()],
            );
            tasks.push((Some(m), i, job));
        }
    }
    tasks
}

/// Runs every task in parallel, in task order.
fn fit_tasks(cx: &Context, split: &Split, tasks: &[Task]) -> Result<Vec<Fitted>, DiagnoseError> {
    let threads = cx.engine;
    let Split {
        cost_only,
        cost_without,
        target_only,
        target_without,
    } = split;
    let results = threads.map(tasks, |(m, i, job)| {
        let (c, t) = if m.is_none() {
            (&cost_only[*i], &target_only[*i])
        } else {
            (&cost_without[*i], &target_without[*i])
        };
        fitting::run_job(c, t, job, threads)
    });
    let fitted: Vec<Fitted> = results
        .into_iter()
        .map(|r| r.map_err(DiagnoseError::from))
        .collect::<Result<_, _>>()?;
    Ok(fitted)
}

/// The check of experiment `i` fitted alone (`f`) against the joint baseline.
fn alone_check(
    cx: &Context,
    base: &Baseline,
    split: &Split,
    i: usize,
    f: &Fitted,
) -> Result<ExperimentCheck, DiagnoseError> {
    let ex = &cx.ds.experiments[i];
    let ch = analysis::channel_data(
        &split.cost_only[i],
        &split.target_only[i],
        &f.motor(),
        &cx.solver,
    )?;
    let joint: Vec<_> = base
        .channels
        .iter()
        .filter(|c| c.file == ex.file)
        .cloned()
        .collect();
    Ok(ExperimentCheck {
        kind: ex.kind,
        file: ex.file.clone(),
        joint_ratio: analysis::noise_ratio(&joint),
        alone_ratio: analysis::noise_ratio(&ch),
        alone_limit: noise_ratio_limit(&ch),
        alone_chi2: f.chi2,
        alone_params: f.params.clone(),
        held_out_ratio: None,
    })
}

/// The likelihood-ratio (Chow) test: χ²_joint − Σ χ²_alone against χ²(k·(E − 1)); its
/// statistic and the concealment it finds.
fn chow(cx: &Context, baseline: &Fitted, checks: Vec<ExperimentCheck>) -> (ChowTest, Concealment) {
    let n_exp = cx.ds.experiments.len();
    let sum_alone: f64 = checks.iter().map(|c| c.alone_chi2).sum();
    let lr = (baseline.chi2 - sum_alone).max(0.0);
    let df = (cx.base_names.len() * (n_exp - 1)) as f64;
    let p_value = stats::chi2_sf(lr, df);
    let test = ChowTest {
        joint: baseline.chi2,
        separate: sum_alone,
        lr,
        df,
        p_value,
    };
    let concealment = Concealment {
        experiments: checks,
        lr,
        df,
        p_value,
    };
    (test, concealment)
}
