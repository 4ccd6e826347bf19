//! Multi-start Nelder–Mead (argmin) in parallel (rayon), deterministic for a given seed
//! whatever the thread count, interruptible without losing finished starts.
//!
//! Starts advance in rounds of `stage_iters` iterations. Between rounds (a barrier, so the
//! decision never depends on thread timing) starts that have converged or used their budget
//! finish, and starts that stall far above the best cost seen so far stop early. Each
//! finished start is appended to a results file at once; `resume` reads it back and replays
//! the kill decisions from the recorded per-round histories, so a resumed run ends exactly
//! where an uninterrupted one would.

use super::objective::{Objective, Problem};
use super::space::ParamSpace;
use argmin::core::{Executor, State, TerminationReason};
use argmin::solver::neldermead::NelderMead;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::io::{BufRead, Write};
use std::path::{Path, PathBuf};

/// Settings of a multi-start run.
#[derive(Debug, Clone, PartialEq)]
pub struct MultiStartConfig {
    pub starts: usize,
    pub seed: u64,
    /// Worker threads (None: rayon's default, one per core).
    pub threads: Option<usize>,
    /// Nelder–Mead iterations between barriers.
    pub stage_iters: u64,
    /// Iteration budget of one start.
    pub max_iters: u64,
    /// Convergence: standard deviation of the simplex costs below this.
    pub sd_tolerance: f64,
    /// Size of the initial simplex in optimizer coordinates θ.
    pub initial_step: f64,
    /// A start stops early after this many rounds if its cost exceeds
    /// `kill_factor`·best + `kill_margin`.
    pub kill_after_rounds: usize,
    pub kill_factor: f64,
    pub kill_margin: f64,
    /// Keep every start's cost trace.
    pub keep_traces: bool,
    /// Start points given in optimizer coordinates θ (e.g. a previous fit's optimum); they
    /// take the first start indices, the Latin hypercube fills the rest.
    pub given_starts: Vec<Vec<f64>>,
    /// Fresh simplices around the best point after convergence (restarted Nelder–Mead):
    /// a collapsed simplex is the method's known failure, and a restart that finds nothing
    /// better is the convergence test.
    pub max_restarts: u32,
}

impl Default for MultiStartConfig {
    fn default() -> Self {
        Self {
            starts: 32,
            seed: 1,
            threads: None,
            stage_iters: 100,
            max_iters: 3000,
            sd_tolerance: 1e-6,
            initial_step: 0.5,
            kill_after_rounds: 5,
            kill_factor: 3.0,
            kill_margin: 10.0,
            keep_traces: false,
            max_restarts: 20,
            given_starts: Vec::new(),
        }
    }
}

/// How a start ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Ending {
    Converged,
    Budget,
    StoppedEarly,
}

/// The outcome of one start.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StartResult {
    pub index: usize,
    /// Start point and end point in optimizer coordinates.
    pub theta0: Vec<f64>,
    pub theta: Vec<f64>,
    pub cost: f64,
    pub ending: Ending,
    pub iterations: u64,
    pub evaluations: u64,
    /// Best cost after each round.
    pub history: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trace: Option<Vec<f64>>,
}

/// Receives progress of a run (progress bars, logs): an observer, not part of the solver.
pub trait RunObserver: Sync {
    fn started(&self, _total: usize, _already_done: usize) {}
    fn start_finished(&self, _result: &StartResult, _best_cost: f64) {}
    fn finished(&self) {}
}

/// Observes nothing.
pub struct Silent;
impl RunObserver for Silent {}

/// An error of the runner (results file, bad configuration).
#[derive(Debug, Clone, PartialEq)]
pub struct RunError(pub String);

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for RunError {}

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

struct Runner {
    index: usize,
    restarts: u32,
    /// Best cost when the current simplex was started.
    cost_at_restart: f64,
    theta0: Vec<f64>,
    solver: Option<NelderMead<Vec<f64>, f64>>,
    theta: Vec<f64>,
    cost: f64,
    iterations: u64,
    evaluations: u64,
    converged: bool,
    history: Vec<f64>,
    trace: Vec<f64>,
}

/// A Nelder–Mead solver on a right-angled simplex at `theta` with edge `step`, with the
/// dimension-adaptive expansion and shrink of Gao and Han (2012): γ = 1 + 2/n,
/// σ = 1 − 1/n, which keep the simplex from collapsing in more than a few dimensions
/// (their contraction 0.75 − 1/(2n) is outside argmin's (0, 0.5], so ρ stays 0.5).
fn simplex_solver(vertices: Vec<Vec<f64>>, sd_tolerance: f64) -> NelderMead<Vec<f64>, f64> {
    let n = (vertices.len().max(3) - 1) as f64;
    NelderMead::new(vertices)
        .with_sd_tolerance(sd_tolerance)
        .and_then(|s| s.with_gamma(1.0 + 2.0 / n))
        .and_then(|s| s.with_sigma(1.0 - 1.0 / n))
        .expect("valid Nelder-Mead coefficients")
}

/// A right-angled simplex at `theta` with edge `step`, stepping towards the middle of the
/// range so that it stays well inside it.
fn axis_simplex(theta: &[f64], step: f64) -> Vec<Vec<f64>> {
    let mut simplex = vec![theta.to_vec()];
    for i in 0..theta.len() {
        let mut v = theta.to_vec();
        v[i] += if theta[i] > 0.0 { -step } else { step };
        simplex.push(v);
    }
    simplex
}

/// A simplex shaped like the cost's valley at `theta`: edges along the eigenvectors of the
/// finite-difference Hessian H, each long enough to raise the cost by about `rise`
/// (length √(2·rise/λ)). Nelder–Mead's weakness is a long, narrow, tilted valley, which a
/// right-angled simplex crosses in many small steps; a simplex aligned with the valley
/// moves along it at once. `None` if H has no usable curvature.
fn curvature_simplex(
    problem: &Problem<'_>,
    theta: &[f64],
    f0: f64,
    h: f64,
    rise: f64,
) -> Option<Vec<Vec<f64>>> {
    let k = theta.len();
    let f = |t: &[f64]| problem.evaluate(t).cost;
    let at = |moves: &[(usize, f64)]| {
        let mut t = theta.to_vec();
        for (i, d) in moves {
            t[*i] += d;
        }
        f(&t)
    };
    let mut hess = nalgebra::DMatrix::<f64>::zeros(k, k);
    let (plus, minus): (Vec<f64>, Vec<f64>) =
        (0..k).map(|i| (at(&[(i, h)]), at(&[(i, -h)]))).unzip();
    for i in 0..k {
        hess[(i, i)] = (plus[i] - 2.0 * f0 + minus[i]) / (h * h);
        for j in 0..i {
            let v = (at(&[(i, h), (j, h)]) - at(&[(i, h), (j, -h)]) - at(&[(i, -h), (j, h)])
                + at(&[(i, -h), (j, -h)]))
                / (4.0 * h * h);
            hess[(i, j)] = v;
            hess[(j, i)] = v;
        }
    }
    if !hess.iter().all(|v| v.is_finite()) {
        return None;
    }
    let eig = nalgebra::SymmetricEigen::new(hess);
    let largest = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(*v));
    if largest <= 0.0 {
        return None;
    }
    let mut simplex = vec![theta.to_vec()];
    for (j, lambda) in eig.eigenvalues.iter().enumerate() {
        // Flat or negative directions get the length of the flattest usable one, capped.
        let curvature = lambda.max(largest * 1e-10);
        let len = (2.0 * rise / curvature).sqrt().min(2.0);
        let mut v = theta.to_vec();
        for (i, x) in v.iter_mut().enumerate() {
            *x += len * eig.eigenvectors[(i, j)];
        }
        simplex.push(v);
    }
    Some(simplex)
}

impl Runner {
    fn new(index: usize, theta0: Vec<f64>, cfg: &MultiStartConfig) -> Self {
        let solver = simplex_solver(axis_simplex(&theta0, cfg.initial_step), cfg.sd_tolerance);
        Self {
            index,
            restarts: 0,
            cost_at_restart: f64::INFINITY,
            theta: theta0.clone(),
            theta0,
            solver: Some(solver),
            cost: f64::INFINITY,
            iterations: 0,
            evaluations: 0,
            converged: false,
            history: Vec::new(),
            trace: Vec::new(),
        }
    }

    /// Runs one stage of Nelder–Mead from where the last one stopped.
    fn advance(&mut self, objective: &dyn Objective, space: &ParamSpace, cfg: &MultiStartConfig) {
        let Some(solver) = self.solver.take() else {
            return;
        };
        let cost_before = self.cost;
        let problem = Problem::new(objective, space, cfg.keep_traces);
        let iters = cfg.stage_iters.min(cfg.max_iters - self.iterations);
        let result = Executor::new(problem, solver)
            .configure(|s| s.max_iters(iters))
            .ctrlc(false)
            .run();
        match result {
            Ok(res) => {
                let state = &res.state;
                self.iterations += state.get_iter();
                if let Some(p) = state.get_best_param() {
                    if state.get_best_cost() <= self.cost {
                        self.theta = p.clone();
                        self.cost = state.get_best_cost();
                    }
                }
                let collapsed =
                    state.get_termination_reason() == Some(&TerminationReason::SolverConverged);
                let problem = res.problem.problem.expect("problem is returned");
                if let Some(t) = problem.take_trace() {
                    self.trace.extend(t);
                }
                self.solver = Some(res.solver);
                // A stage that gained nothing has stagnated (a simplex stuck in a curved
                // valley): treat it like a collapse and restart around the best point.
                let stalled = cost_before.is_finite()
                    && cost_before - self.cost <= 1e-9 * (1.0 + self.cost.abs());
                if collapsed || stalled {
                    let gained = self.cost_at_restart - self.cost > 1e-6 * (1.0 + self.cost.abs());
                    if gained && self.restarts < cfg.max_restarts {
                        self.restarts += 1;
                        self.cost_at_restart = self.cost;
                        // Aim each edge at a rise of 1% of the cost (at least 0.01).
                        let rise = (0.01 * self.cost).max(0.01);
                        let vertices =
                            curvature_simplex(&problem, &self.theta, self.cost, 1e-3, rise)
                                .unwrap_or_else(|| {
                                    axis_simplex(
                                        &self.theta,
                                        (cfg.initial_step * 0.5f64.powi(self.restarts as i32))
                                            .max(1e-3),
                                    )
                                });
                        self.solver = Some(simplex_solver(vertices, cfg.sd_tolerance));
                    } else {
                        self.converged = true;
                    }
                }
                self.evaluations += problem.evaluations();
                if let Some(t) = problem.take_trace() {
                    self.trace.extend(t);
                }
            }
            Err(_) => self.converged = false,
        }
    }

    fn finish(self, ending: Ending, keep_trace: bool) -> StartResult {
        StartResult {
            index: self.index,
            theta0: self.theta0,
            theta: self.theta,
            cost: self.cost,
            ending,
            iterations: self.iterations,
            evaluations: self.evaluations,
            history: self.history,
            trace: keep_trace.then_some(self.trace),
        }
    }
}

/// Header line of a results file: what run it belongs to.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Header {
    format: String,
    seed: u64,
    starts: usize,
    parameters: Vec<String>,
    effects: Vec<String>,
}

const RESULTS_FORMAT: &str = "vanefit.starts/1";

/// Append-only file of finished starts (JSON lines).
pub struct ResultsFile {
    path: PathBuf,
}

impl ResultsFile {
    pub fn new(path: &Path) -> Self {
        Self {
            path: path.to_path_buf(),
        }
    }

    fn header(space: &ParamSpace, cfg: &MultiStartConfig) -> Header {
        Header {
            format: RESULTS_FORMAT.into(),
            seed: cfg.seed,
            starts: cfg.starts,
            parameters: space.names(),
            effects: space.effects.ids(),
        }
    }

    /// Reads finished starts of a matching earlier run (empty if there is no file).
    fn load(
        &self,
        space: &ParamSpace,
        cfg: &MultiStartConfig,
    ) -> Result<Vec<StartResult>, RunError> {
        let file = match std::fs::File::open(&self.path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
            Err(e) => return Err(RunError(format!("{}: {e}", self.path.display()))),
        };
        let mut lines = std::io::BufReader::new(file).lines();
        let bad = |n: usize, m: String| RunError(format!("{}:{n}: {m}", self.path.display()));
        let Some(first) = lines.next() else {
            return Ok(Vec::new());
        };
        let header: Header = serde_json::from_str(&first.map_err(|e| bad(1, e.to_string()))?)
            .map_err(|e| bad(1, e.to_string()))?;
        if header != Self::header(space, cfg) {
            return Err(bad(1, "belongs to a different run (seed, starts, parameters or effects differ); remove it or drop --resume".into()));
        }
        let mut out = Vec::new();
        for (i, line) in lines.enumerate() {
            let line = line.map_err(|e| bad(i + 2, e.to_string()))?;
            // A line cut short by an interruption is simply not finished.
            if let Ok(r) = serde_json::from_str::<StartResult>(&line) {
                if r.index < cfg.starts && !out.iter().any(|o: &StartResult| o.index == r.index) {
                    out.push(r);
                }
            }
        }
        Ok(out)
    }

    fn create(&self, space: &ParamSpace, cfg: &MultiStartConfig) -> Result<(), RunError> {
        let text = serde_json::to_string(&Self::header(space, cfg)).expect("plain data") + "\n";
        crate::io::write_atomic(&self.path, text.as_bytes())
            .map_err(|e| RunError(format!("{}: {e}", self.path.display())))
    }

    fn append(&self, results: &[StartResult]) -> Result<(), RunError> {
        let io = |e: std::io::Error| RunError(format!("{}: {e}", self.path.display()));
        let mut f = std::fs::OpenOptions::new()
            .append(true)
            .open(&self.path)
            .map_err(io)?;
        let mut text = String::new();
        for r in results {
            text += &(serde_json::to_string(r).expect("plain data") + "\n");
        }
        f.write_all(text.as_bytes()).map_err(io)?;
        f.sync_data().map_err(io)
    }
}

/// All starts of a run, sorted by start index.
#[derive(Debug, Clone, PartialEq)]
pub struct MultiStartOutcome {
    pub results: Vec<StartResult>,
    pub evaluations: u64,
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
    pub fn converged(&self) -> usize {
        self.results
            .iter()
            .filter(|r| r.ending == Ending::Converged)
            .count()
    }
}

/// Runs the multi-start estimation.
pub fn run(
    objective: &dyn Objective,
    space: &ParamSpace,
    cfg: &MultiStartConfig,
    observer: &dyn RunObserver,
    results_file: Option<&ResultsFile>,
    resume: bool,
) -> Result<MultiStartOutcome, RunError> {
    if cfg.starts == 0 {
        return Err(RunError("--starts must be at least 1".into()));
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(k) = cfg.threads {
        builder = builder.num_threads(k);
    }
    let pool = builder
        .build()
        .map_err(|e| RunError(format!("thread pool: {e}")))?;
    let done: Vec<StartResult> = match (results_file, resume) {
        (Some(f), true) => f.load(space, cfg)?,
        _ => Vec::new(),
    };
    if let Some(f) = results_file {
        if done.is_empty() {
            f.create(space, cfg)?;
        }
    }
    let given = cfg.given_starts.len().min(cfg.starts);
    let lhs = latin_hypercube(cfg.starts - given, space.len(), cfg.seed);
    let points: Vec<Vec<f64>> = cfg.given_starts[..given]
        .iter()
        .cloned()
        .chain(lhs.iter().map(|u| space.theta_of_unit(u)))
        .collect();
    let mut live: Vec<Runner> = points
        .into_iter()
        .enumerate()
        .filter(|(i, _)| !done.iter().any(|d| d.index == *i))
        .map(|(i, theta)| Runner::new(i, theta, cfg))
        .collect();
    observer.started(cfg.starts, done.len());
    let mut finished = done.clone();
    let mut round = 0usize;
    while !live.is_empty() {
        pool.install(|| {
            live.par_iter_mut()
                .for_each(|r| r.advance(objective, space, cfg))
        });
        round += 1;
        for r in &mut live {
            r.history.push(r.cost);
        }
        // Best cost after this round over every start, replaying resumed ones' histories.
        let best = live
            .iter()
            .map(|r| r.cost)
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
        let mut still = Vec::with_capacity(live.len());
        let mut newly = Vec::new();
        for r in live {
            let ending = if r.converged {
                Some(Ending::Converged)
            } else if r.iterations >= cfg.max_iters || r.solver.is_none() {
                Some(Ending::Budget)
            } else if round >= cfg.kill_after_rounds
                && r.cost > cfg.kill_factor * best + cfg.kill_margin
            {
                Some(Ending::StoppedEarly)
            } else {
                None
            };
            match ending {
                Some(e) => newly.push(r.finish(e, cfg.keep_traces)),
                None => still.push(r),
            }
        }
        live = still;
        if let Some(f) = results_file {
            f.append(&newly)?;
        }
        let best_now = finished
            .iter()
            .chain(&newly)
            .map(|r| r.cost)
            .fold(best, f64::min);
        for r in &newly {
            observer.start_finished(r, best_now);
        }
        finished.extend(newly);
    }
    observer.finished();
    finished.sort_by_key(|r| r.index);
    Ok(MultiStartOutcome {
        evaluations: finished.iter().map(|r| r.evaluations).sum(),
        results: finished,
        threads: pool.current_num_threads(),
    })
}

/// A distinct local minimum: starts that ended at (nearly) the same point and cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Cluster {
    pub cost: f64,
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
