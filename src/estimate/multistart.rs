//! Multi-start Nelder–Mead (argmin) in parallel (rayon), deterministic for a given seed
//! whatever the thread count, interruptible without losing finished starts.
//!
//! Starts advance in rounds of `stage_iters` iterations. Between rounds (a barrier, so the
//! decision never depends on thread timing) starts that have converged or used their budget
//! finish, and starts that stall far above the best cost seen so far stop early. Each
//! finished start is appended to a results file at once; `resume` reads it back and replays
//! the kill decisions from the recorded per-round histories, so a resumed run ends exactly
//! where an uninterrupted one would.

use super::engine::Engine;
use super::error::EstimateError;
use super::history::ResultsFile;
use super::objective::{Objective, Problem};
use super::optimize::{RestartedNelderMead, Status};
use super::settings::MultiStartSettings;
use super::space::ParamSpace;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

/// How a start ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    /// A restart found nothing better (or the restarts ran out).
    Converged,
    /// The iteration budget ran out (or the optimizer failed).
    Budget,
    /// Stopped far above the best cost (see `kill_after_rounds`).
    StoppedEarly,
    /// Reached the cost of a start that had already converged (within `join_tolerance`)
    /// and stopped there instead of polishing the same minimum again.
    Joined,
}

/// The outcome of one start.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StartResult {
    /// Start index (given starts first, then the Latin hypercube).
    pub index: usize,
    /// Start point in optimizer coordinates.
    pub theta0: Vec<f64>,
    /// End point in optimizer coordinates.
    pub theta: Vec<f64>,
    /// Cost at the end point.
    pub cost: f64,
    /// How the start ended.
    pub ending: Ending,
    /// Nelder–Mead iterations used.
    pub iterations: u64,
    /// Cost evaluations used.
    pub evaluations: u64,
    /// Best cost after each round.
    pub history: Vec<f64>,
    /// Every cost evaluated, in order (when traces are kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trace: Option<Vec<f64>>,
}

/// Receives progress of a run (progress bars, logs): an observer, not part of the solver.
pub trait RunObserver: Sync {
    /// A run of `total` starts begins, `already_done` of them read from the results file.
    fn started(&self, _total: usize, _already_done: usize) {}
    /// A start finished; `best_cost` is the best over every finished start.
    fn start_finished(&self, _result: &StartResult, _best_cost: f64) {}
    /// The run is over.
    fn finished(&self) {}
    /// A later phase of the fit begins after the starts (the profiles take as long as the
    /// starts), with `steps` steps of work, so a watcher can tell a long run from a hung one.
    fn phase(&self, _name: &str, _steps: usize) {}
    /// `done` steps of the current phase are finished.
    fn phase_step(&self, _done: usize) {}
    /// Asked before every round of starts: `false` stops the run with
    /// [`EstimateError::Interrupted`] (the starts finished so far are in the results file,
    /// so a run with `resume` continues from them). Default: go on.
    fn keep_going(&self) -> bool {
        true
    }
}

/// Observes nothing.
pub struct Silent;
impl RunObserver for Silent {}

/// Latin-hypercube start points in the unit cube, one row per start, from the seed alone.
pub fn latin_hypercube(starts: usize, dims: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut points = vec![vec![0.0; dims]; starts];
    for d in 0..dims {
        let mut strata: Vec<usize> = (0..starts).collect();
        strata.shuffle(&mut rng);
        for (p, s) in points.iter_mut().zip(strata) {
            p[d] = (s as f64 + rng.random::<f64>()) / starts as f64;
        }
    }
    points
}

/// One start: its restarted Nelder–Mead and what the run records of it.
struct Runner {
    index: usize,
    theta0: Vec<f64>,
    search: RestartedNelderMead,
    evaluations: u64,
    history: Vec<f64>,
    trace: Vec<f64>,
}

impl Runner {
    fn new(index: usize, theta0: Vec<f64>, cfg: &MultiStartSettings) -> Self {
        Self {
            index,
            search: RestartedNelderMead::new(theta0.clone(), f64::INFINITY, cfg.nelder_mead()),
            theta0,
            evaluations: 0,
            history: Vec::new(),
            trace: Vec::new(),
        }
    }

    /// Runs one stage of Nelder–Mead from where the last one stopped.
    fn advance(&mut self, objective: &dyn Objective, space: &ParamSpace, cfg: &MultiStartSettings) {
        if self.search.status() != Status::Running {
            return;
        }
        let problem = Problem::new(objective, space, cfg.keep_traces());
        let iters = cfg
            .stage_iters()
            .min(cfg.max_iters() - self.search.iterations());
        self.search.advance(&problem, iters);
        self.evaluations += problem.evaluations();
        if let Some(t) = problem.take_trace() {
            self.trace.extend(t);
        }
    }

    /// How the start ends after a round, if it does (`best`: best cost over every start;
    /// `known`: best cost of the starts that converged in earlier rounds).
    fn ending(
        &self,
        cfg: &MultiStartSettings,
        round: usize,
        best: f64,
        known: f64,
    ) -> Option<Ending> {
        match self.search.status() {
            Status::Converged => Some(Ending::Converged),
            Status::Failed => Some(Ending::Budget),
            Status::Running if self.search.iterations() >= cfg.max_iters() => Some(Ending::Budget),
            Status::Running if cfg.joins(self.search.cost(), known) => Some(Ending::Joined),
            Status::Running
                if round >= cfg.kill_after_rounds()
                    && cfg.stops_early(self.search.cost(), best) =>
            {
                Some(Ending::StoppedEarly)
            }
            Status::Running => None,
        }
    }

    fn finish(self, ending: Ending, keep_trace: bool) -> StartResult {
        StartResult {
            index: self.index,
            theta0: self.theta0,
            theta: self.search.x().to_vec(),
            cost: self.search.cost(),
            ending,
            iterations: self.search.iterations(),
            evaluations: self.evaluations,
            history: self.history,
            trace: keep_trace.then_some(self.trace),
        }
    }
}

/// All starts of a run, sorted by start index.
#[derive(Debug, Clone, PartialEq)]
pub struct MultiStartOutcome {
    /// Every start, by index.
    pub results: Vec<StartResult>,
    /// Cost evaluations over every start.
    pub evaluations: u64,
    /// Worker threads of the engine that ran it.
    pub threads: usize,
}

impl MultiStartOutcome {
    /// The start with the lowest cost (ties: lowest index).
    pub fn best(&self) -> &StartResult {
        self.results
            .iter()
            .min_by(|a, b| a.cost.total_cmp(&b.cost).then(a.index.cmp(&b.index)))
            .expect("at least one start")
    }
    /// Number of starts that converged (or joined a converged start's minimum).
    pub fn converged(&self) -> usize {
        self.results
            .iter()
            .filter(|r| matches!(r.ending, Ending::Converged | Ending::Joined))
            .count()
    }
}

/// The start points in θ: the given ones, then the Latin hypercube of the seed.
fn start_points(
    space: &ParamSpace,
    cfg: &MultiStartSettings,
) -> Result<Vec<Vec<f64>>, EstimateError> {
    if let Some((index, s)) =
        (cfg.given_starts().iter().enumerate()).find(|(_, s)| s.len() != space.len())
    {
        return Err(EstimateError::GivenStart {
            index,
            got: s.len(),
            want: space.len(),
        });
    }
    let given = cfg.given_starts().len().min(cfg.starts());
    let lhs = latin_hypercube(cfg.starts() - given, space.len(), cfg.seed());
    Ok(cfg.given_starts()[..given]
        .iter()
        .cloned()
        .chain(lhs.iter().map(|u| space.theta_of_unit(u)))
        .collect())
}

/// Runs the multi-start estimation on the engine's threads. With a results file, every
/// finished start is appended at once; with `resume`, the starts it holds are not run
/// again (see the module documentation).
pub fn run(
    engine: &Engine,
    objective: &dyn Objective,
    space: &ParamSpace,
    cfg: &MultiStartSettings,
    observer: &dyn RunObserver,
    results_file: Option<&ResultsFile>,
    resume: bool,
) -> Result<MultiStartOutcome, EstimateError> {
    let done: Vec<StartResult> = match (results_file, resume) {
        (Some(f), true) => f.load(space, cfg)?,
        _ => Vec::new(),
    };
    if let Some(f) = results_file {
        if done.is_empty() {
            f.create(space, cfg)?;
        }
    }
    let live: Vec<Runner> = start_points(space, cfg)?
        .into_iter()
        .enumerate()
        .filter(|(i, _)| !done.iter().any(|d| d.index == *i))
        .map(|(i, theta)| Runner::new(i, theta, cfg))
        .collect();
    observer.started(cfg.starts(), done.len());
    let rounds = Rounds {
        engine,
        objective,
        space,
        cfg,
        observer,
        results_file,
    };
    let mut finished = rounds.run(live, &done)?;
    observer.finished();
    finished.sort_by_key(|r| r.index);
    Ok(MultiStartOutcome {
        evaluations: finished.iter().map(|r| r.evaluations).sum(),
        results: finished,
        threads: engine.threads(),
    })
}

/// The rounds of a run: every live start advances one stage, then (a barrier) starts end.
struct Rounds<'a> {
    engine: &'a Engine,
    objective: &'a dyn Objective,
    space: &'a ParamSpace,
    cfg: &'a MultiStartSettings,
    observer: &'a dyn RunObserver,
    results_file: Option<&'a ResultsFile>,
}

impl Rounds<'_> {
    /// Advances `live` round by round until every start has ended; `done` are the starts
    /// read back from the results file. Returns every finished start (`done` first).
    fn run(
        &self,
        mut live: Vec<Runner>,
        done: &[StartResult],
    ) -> Result<Vec<StartResult>, EstimateError> {
        let (objective, space, cfg) = (self.objective, self.space, self.cfg);
        let mut finished = done.to_vec();
        let mut round = 0usize;
        while !live.is_empty() {
            if !self.observer.keep_going() {
                return Err(EstimateError::Interrupted);
            }
            self.engine
                .for_each_mut(&mut live, |r| r.advance(objective, space, cfg));
            round += 1;
            for r in &mut live {
                r.history.push(r.search.cost());
            }
            // Best cost after this round over every start, replaying resumed ones' histories.
            let best = live
                .iter()
                .map(|r| r.search.cost())
                .chain(
                    done.iter()
                        .map(|d| d.history.get(round - 1).copied().unwrap_or(d.cost)),
                )
                .chain(
                    finished
                        .iter()
                        .filter(|f| !done.contains(f))
                        .map(|f| f.cost),
                )
                .fold(f64::INFINITY, f64::min);
            // Converged before this round, whether in this run or read back on resume (a
            // start's history has one entry per round it ran).
            let known = finished
                .iter()
                .filter(|f| f.ending == Ending::Converged && f.history.len() < round)
                .map(|f| f.cost)
                .fold(f64::INFINITY, f64::min);
            let mut still = Vec::with_capacity(live.len());
            let mut newly = Vec::new();
            for r in live {
                match r.ending(cfg, round, best, known) {
                    Some(e) => newly.push(r.finish(e, cfg.keep_traces())),
                    None => still.push(r),
                }
            }
            live = still;
            self.report(&finished, &newly, best)?;
            finished.extend(newly);
        }
        Ok(finished)
    }

    /// Appends the starts that ended this round to the results file and tells the observer.
    fn report(
        &self,
        finished: &[StartResult],
        newly: &[StartResult],
        best: f64,
    ) -> Result<(), EstimateError> {
        if let Some(f) = self.results_file {
            f.append(newly)?;
        }
        let best_now = finished
            .iter()
            .chain(newly)
            .map(|r| r.cost)
            .fold(best, f64::min);
        for r in newly {
            self.observer.start_finished(r, best_now);
        }
        Ok(())
    }
}

/// A distinct local minimum: starts that ended at (nearly) the same point and cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Cluster {
    /// Cost of its best start.
    pub cost: f64,
    /// θ of its best start.
    pub theta: Vec<f64>,
    /// Start indices that reached it.
    pub members: Vec<usize>,
}

/// Groups start results into local minima: sorted by cost, a start joins the first cluster
/// whose representative lies within `radius` in unit-cube coordinates and whose cost is
/// within 1% (+0.01). Stopped-early starts are left out.
pub fn cluster(results: &[StartResult], space: &ParamSpace, radius: f64) -> Vec<Cluster> {
    let mut sorted: Vec<&StartResult> = results
        .iter()
        .filter(|r| r.ending != Ending::StoppedEarly)
        .collect();
    sorted.sort_by(|a, b| a.cost.total_cmp(&b.cost).then(a.index.cmp(&b.index)));
    let mut clusters: Vec<Cluster> = Vec::new();
    for r in sorted {
        let u = space.unit_of_theta(&r.theta);
        let home = clusters.iter_mut().find(|c| {
            let uc = space.unit_of_theta(&c.theta);
            let d = u
                .iter()
                .zip(&uc)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            d <= radius && (r.cost - c.cost).abs() <= 0.01 * c.cost.abs() + 0.01
        });
        match home {
            Some(c) => c.members.push(r.index),
            None => clusters.push(Cluster {
                cost: r.cost,
                theta: r.theta.clone(),
                members: vec![r.index],
            }),
        }
    }
    clusters
}
