//! Multi-start Nelder–Mead (argmin) in parallel (rayon), deterministic for a given seed
//! whatever the thread count, interruptible without losing finished starts.
//!
//! Starts advance in rounds of `stage_iters` iterations. Between rounds (a barrier, so the
//! decision never depends on thread timing) starts that stall far above the best cost seen
//! so far stop early, and starts that reach the cost of a converged one join it. A start
//! that converges or uses its budget ends by itself: it is appended to the results file the
//! moment its stage ends, by the worker that ran it, not at the round's end, so a run killed
//! inside its first (possibly only) round keeps every start that had ended. `resume` reads
//! the file back and replays the round decisions from the recorded per-round histories, so
//! a resumed run ends exactly where an uninterrupted one would, whatever the thread count.
//!
//! After `handoff_after_rounds` rounds a start still running is handed over to
//! Levenberg–Marquardt on the cost's residuals for one stage ([`Objective::cost_residuals`],
//! where the objective has them): Nelder–Mead finds the basin, least squares its floor.
//! The rule looks at the start alone, so it keeps the run independent of the thread count.

use crate::estimate::engine::Engine;
use crate::estimate::error::EstimateError;
use crate::estimate::history::ResultsFile;
use crate::estimate::optimize::local::{LevenbergMarquardt, LocalOptimizer, Residuals};
use crate::estimate::optimize::nelder_mead::{RestartedNelderMead, Status};
use crate::estimate::optimize::settings::MultiStartSettings;
use crate::estimate::problem::objective::{Objective, Problem};
use crate::estimate::problem::space::ParamSpace;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

/// How a start ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum Ending {
    /// A restart found nothing better (or the restarts ran out), or the least-squares
    /// hand-over converged.
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
fn latin_hypercube(starts: usize, dims: usize, seed: u64) -> Vec<Vec<f64>> {
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
    /// How the start ended by itself in the last stage (converged, failed, out of budget).
    ended: Option<Ending>,
    /// The outcome of recording that ending in the results file (checked at the barrier).
    recorded: Option<Result<(), EstimateError>>,
    /// The hand-over has happened (a start gets one).
    handed: bool,
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
            ended: None,
            recorded: None,
            handed: false,
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

    /// The hand-over stage: Levenberg–Marquardt on the cost's residuals from the best point
    /// ([`MultiStartSettings::handoff_lm`]). Converged and no worse, the start ends there
    /// (as converged: a minimum of the cost, found by another method). Otherwise, where it
    /// went lower, Nelder–Mead goes on from there with a simplex a tenth of the first's
    /// edge; where it did not, Nelder–Mead goes on as it was.
    fn hand_over(
        &mut self,
        objective: &dyn Objective,
        space: &ParamSpace,
        cfg: &MultiStartSettings,
    ) {
        self.handed = true;
        let problem = Problem::new(objective, space, false);
        let lm = LevenbergMarquardt {
            settings: cfg.handoff_lm(),
            residuals: Residuals::Cost,
        };
        let out = lm.minimize(&problem, self.search.x(), self.search.cost());
        self.evaluations += problem.evaluations();
        if out.converged && out.value.is_finite() && self.search.conclude(out.x.clone(), out.value)
        {
            return;
        }
        if out.value < self.search.cost() {
            let step = cfg.nelder_mead().step * 0.1;
            self.search.move_to(out.x, out.value, step);
        }
    }

    /// How the start ends by itself after its stage, if it does: converged, failed or out of
    /// budget. This needs no other start, so the worker decides it (and records the start)
    /// as soon as the stage ends.
    fn own_ending(&self, cfg: &MultiStartSettings) -> Option<Ending> {
        match self.search.status() {
            Status::Converged => Some(Ending::Converged),
            Status::Failed => Some(Ending::Budget),
            Status::Running if self.search.iterations() >= cfg.max_iters() => Some(Ending::Budget),
            Status::Running => None,
        }
    }

    /// How a start still running after a round ends at the barrier, if it does (`best`: best
    /// cost over every start; `known`: best cost of the starts that converged in earlier
    /// rounds).
    fn round_ending(
        &self,
        cfg: &MultiStartSettings,
        round: usize,
        best: f64,
        known: f64,
    ) -> Option<Ending> {
        if cfg.joins(self.search.cost(), known) {
            Some(Ending::Joined)
        } else if round >= cfg.kill_after_rounds() && cfg.stops_early(self.search.cost(), best) {
            Some(Ending::StoppedEarly)
        } else {
            None
        }
    }

    fn result(&self, ending: Ending, keep_trace: bool) -> StartResult {
        StartResult {
            index: self.index,
            theta0: self.theta0.clone(),
            theta: self.search.x().to_vec(),
            cost: self.search.cost(),
            ending,
            iterations: self.search.iterations(),
            evaluations: self.evaluations,
            history: self.history.clone(),
            trace: keep_trace.then(|| self.trace.clone()),
        }
    }

    /// One stage, then (on the worker) the start's own ending, recorded in `file` at once.
    fn stage(
        &mut self,
        objective: &dyn Objective,
        space: &ParamSpace,
        cfg: &MultiStartSettings,
        file: Option<&ResultsFile>,
    ) {
        let handing = !self.handed
            && self.search.status() == Status::Running
            && objective.has_cost_residuals()
            && cfg.hands_off(self.history.len());
        if handing {
            self.hand_over(objective, space, cfg);
        } else {
            self.advance(objective, space, cfg);
        }
        self.history.push(self.search.cost());
        self.ended = self.own_ending(cfg);
        if let (Some(ending), Some(f)) = (self.ended, file) {
            self.recorded = Some(f.append(&[self.result(ending, cfg.keep_traces())]));
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
    if let Some(f) = results_file {
        f.sort()?;
    }
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
            let file = self.results_file;
            self.engine
                .for_each_mut(&mut live, |r| r.stage(objective, space, cfg, file));
            round += 1;
            if let Some(e) = live.iter_mut().find_map(|r| r.recorded.take()?.err()) {
                return Err(e);
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
            let (mut newly, mut unrecorded) = (Vec::new(), Vec::new());
            for r in live {
                if let Some(e) = r.ended {
                    newly.push(r.result(e, cfg.keep_traces()));
                } else if let Some(e) = r.round_ending(cfg, round, best, known) {
                    newly.push(r.result(e, cfg.keep_traces()));
                    unrecorded.push(newly.len() - 1);
                } else {
                    still.push(r);
                }
            }
            live = still;
            if let Some(f) = self.results_file {
                let at_barrier: Vec<StartResult> =
                    unrecorded.iter().map(|&i| newly[i].clone()).collect();
                f.append(&at_barrier)?;
            }
            self.report(&finished, &newly, best);
            finished.extend(newly);
        }
        Ok(finished)
    }

    /// Tells the observer of the starts that ended this round (in start order).
    fn report(&self, finished: &[StartResult], newly: &[StartResult], best: f64) {
        let best_now = finished
            .iter()
            .chain(newly)
            .map(|r| r.cost)
            .fold(best, f64::min);
        for r in newly {
            self.observer.start_finished(r, best_now);
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::optimize::settings::MultiStartConfig;
    use crate::estimate::problem::objective::Evaluation;
    use crate::estimate::problem::space::DEFAULT_ESTIMATED;
    use crate::model::effects::EffectSet;
    use crate::model::motor::Motor;
    use crate::model::params::MotorParams;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// A bowl in the log-parameters that stands for a kill (panics) at its `kill_at`-th
    /// evaluation: the run dies mid-round, as a fit killed with SIGKILL does.
    /// With `least_squares`, it gives its cost as residuals too (a start is handed over).
    struct Bowl {
        evaluations: AtomicU64,
        kill_at: u64,
        least_squares: bool,
    }

    impl Bowl {
        fn count(&self) {
            if self.evaluations.fetch_add(1, Ordering::SeqCst) + 1 == self.kill_at {
                panic!("killed");
            }
        }
        /// ln p − ln p₀ of every parameter, the bottom p₀ at twice the default values
        /// (inside every bound).
        fn offsets(motor: &Motor) -> Vec<f64> {
            let bottom = MotorParams::default();
            DEFAULT_ESTIMATED
                .iter()
                .map(|n| motor.params().get(n).unwrap().ln() - (2.0 * bottom.get(n).unwrap()).ln())
                .collect()
        }
    }

    impl Objective for Bowl {
        fn evaluate(&self, motor: &Motor) -> Evaluation {
            self.count();
            let chi2: f64 = Self::offsets(motor).iter().map(|r| r * r).sum();
            Evaluation {
                cost: chi2,
                chi2,
                n_points: 10,
                failed: false,
            }
        }

        fn cost_residuals(&self, motor: &Motor) -> Option<Vec<f64>> {
            self.count();
            self.least_squares.then(|| Self::offsets(motor))
        }

        fn has_cost_residuals(&self) -> bool {
            self.least_squares
        }
    }

    fn bowl(kill_at: u64) -> Bowl {
        Bowl {
            evaluations: AtomicU64::new(0),
            kill_at,
            least_squares: false,
        }
    }

    fn least_squares_bowl(kill_at: u64) -> Bowl {
        Bowl {
            least_squares: true,
            ..bowl(kill_at)
        }
    }

    fn run_on(
        threads: usize,
        obj: &Bowl,
        cfg: &MultiStartSettings,
        file: &ResultsFile,
        resume: bool,
    ) -> MultiStartOutcome {
        let engine = Engine::with_threads(Some(threads)).unwrap();
        let space = ParamSpace::new(
            &DEFAULT_ESTIMATED,
            MotorParams::default(),
            EffectSet::empty(),
        )
        .unwrap();
        run(&engine, obj, &space, cfg, &Silent, Some(file), resume).unwrap()
    }

    #[test]
    fn a_run_killed_inside_its_only_round_keeps_the_starts_that_ended() {
        // Every start ends in the first round (its budget is shorter than a stage).
        let cfg = MultiStartConfig {
            starts: 4,
            seed: 7,
            stage_iters: 100,
            max_iters: 60,
            ..Default::default()
        }
        .check()
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let whole = ResultsFile::new(&dir.path().join("whole.jsonl"));
        let full = run_on(2, &bowl(0), &cfg, &whole, false);
        assert!(full.results.iter().all(|r| r.history.len() == 1));

        // One worker runs the starts in index order: killed inside start 2, starts 0 and 1
        // have ended and must be on disk.
        let path = dir.path().join("killed.jsonl");
        let killed = ResultsFile::new(&path);
        let kill_at = full.results[0].evaluations + full.results[1].evaluations + 5;
        let died = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            run_on(1, &bowl(kill_at), &cfg, &killed, false)
        }));
        assert!(died.is_err());
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 3, "header and two starts:\n{text}");

        // Resumed (on another thread count), it runs only the other two and ends as the
        // uninterrupted run did.
        let counting = bowl(0);
        let resumed = run_on(2, &counting, &cfg, &killed, true);
        assert_eq!(resumed.results, full.results);
        // Recorded as they end, rewritten in start order when the run ends: the resumed
        // run's file is the uninterrupted one's, line for line.
        let whole_text = std::fs::read_to_string(dir.path().join("whole.jsonl")).unwrap();
        let order: Vec<usize> = whole_text
            .lines()
            .skip(1)
            .map(|l| serde_json::from_str::<StartResult>(l).unwrap().index)
            .collect();
        assert_eq!(order, [0, 1, 2, 3]);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), whole_text);
        assert_eq!(
            counting.evaluations.load(Ordering::SeqCst),
            full.results[2].evaluations + full.results[3].evaluations
        );
    }

    #[test]
    fn a_handed_over_start_ends_at_the_bottom_with_fewer_evaluations() {
        let cfg = |handoff_after_rounds| {
            MultiStartConfig {
                starts: 6,
                seed: 3,
                stage_iters: 40,
                handoff_after_rounds,
                ..Default::default()
            }
            .check()
            .unwrap()
        };
        let dir = tempfile::tempdir().unwrap();
        let file = |name: &str| ResultsFile::new(&dir.path().join(name));
        let nelder_mead = run_on(2, &least_squares_bowl(0), &cfg(0), &file("nm.jsonl"), false);
        let handed = run_on(2, &least_squares_bowl(0), &cfg(1), &file("lm.jsonl"), false);
        // The same run on one thread: the hand-over looks at each start alone.
        let one = run_on(
            1,
            &least_squares_bowl(0),
            &cfg(1),
            &file("one.jsonl"),
            false,
        );
        assert_eq!(one.results, handed.results);
        for r in &handed.results {
            // Handed over after one stage, converged in that next one.
            assert_eq!(r.ending, Ending::Converged, "start {}", r.index);
            assert_eq!(r.history.len(), 2, "start {}", r.index);
            assert!(
                r.cost < 1e-5,
                "start {}: cost {} at {:?} from {:?}",
                r.index,
                r.cost,
                r.theta,
                r.theta0
            );
        }
        // Without residuals the same settings never hand over.
        let plain = run_on(2, &bowl(0), &cfg(1), &file("plain.jsonl"), false);
        assert_eq!(
            plain.evaluations, nelder_mead.evaluations,
            "an objective without residuals runs Nelder-Mead alone"
        );
        assert!(
            2 * handed.evaluations < nelder_mead.evaluations,
            "hand-over {} evaluations, Nelder-Mead alone {}",
            handed.evaluations,
            nelder_mead.evaluations
        );
        assert!(handed.best().cost <= nelder_mead.best().cost + 1e-5);
    }

    #[test]
    fn a_run_killed_during_a_hand_over_resumes_to_the_same_end() {
        let cfg = MultiStartConfig {
            starts: 4,
            seed: 9,
            stage_iters: 30,
            ..Default::default()
        }
        .check()
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let whole = ResultsFile::new(&dir.path().join("whole.jsonl"));
        let full = run_on(1, &least_squares_bowl(0), &cfg, &whole, false);
        assert!(full.results.iter().all(|r| r.history.len() == 2));
        // One worker runs every start's first stage, then the hand-overs in index order:
        // killed inside the last start's hand-over, the other three have ended.
        let path = dir.path().join("killed.jsonl");
        let killed = ResultsFile::new(&path);
        let kill_at = full.evaluations - 3;
        let died = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            run_on(1, &least_squares_bowl(kill_at), &cfg, &killed, false)
        }));
        assert!(died.is_err());
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text.lines().count(), 4, "header and three starts:\n{text}");
        let resumed = run_on(2, &least_squares_bowl(0), &cfg, &killed, true);
        assert_eq!(resumed.results, full.results);
    }
}
