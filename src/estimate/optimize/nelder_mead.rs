//! The one optimizer: restarted Nelder–Mead (argmin) over a parameter vector behind
//! argmin's [`CostFunction`]. The solver sees only the problem, never a motor.
//!
//! Nelder–Mead's known failure is a simplex that collapses (or crawls along a curved
//! valley) before the minimum; the cure is a fresh simplex at the best point, and a restart
//! that finds nothing better is the convergence test. How the simplices are laid out and when
//! to restart are settings ([`NelderMeadSettings`]), so that each caller keeps its own rules:
//! the multi-start restarts with curvature-shaped simplices, a diagnosis refit with axis
//! simplices of halving edge, a profile point runs one simplex.

use crate::estimate::problem::derivatives::hessian;
use argmin::core::{CostFunction, Error, Executor, State, TerminationReason};
use argmin::solver::neldermead::NelderMead;

/// Where the edges of an axis simplex point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// Along +e_i where θ_i ≤ 0 and −e_i where θ_i > 0: towards the middle of the range,
    /// so that the simplex stays well inside it.
    Inward,
    /// Along +e_i.
    Forward,
}

/// When a fresh simplex is started.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Restart {
    /// One simplex only.
    Never,
    /// When the simplex collapses or a stage gains nothing (relative 1e-9), a simplex shaped
    /// by the curvature at the best point (`curvature_simplex`; an axis simplex of edge
    /// step·2⁻ʳ, at least 1e-3, if the curvature is unusable), until a restart gains at
    /// most `min_gain`·(1 + |f|) or after `max_restarts`. Ties of the best cost move the
    /// point.
    Curvature {
        /// Most restarts.
        max_restarts: u32,
        /// Relative gain below which a restart counts as finding nothing better.
        min_gain: f64,
    },
    /// After every stage, an axis simplex of half the edge (at least `min_edge`) until a
    /// stage gains at most `gain`·(1 + |f|), after at most `rounds` stages. Only a strict
    /// improvement moves the point (the start is evaluated first).
    Halving {
        /// Most stages.
        rounds: u32,
        /// Smallest edge.
        min_edge: f64,
        /// Relative gain below which a stage ends the search.
        gain: f64,
    },
}

/// How one Nelder–Mead search runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NelderMeadSettings {
    /// Convergence of a simplex: standard deviation of its costs below this.
    pub sd_tolerance: f64,
    /// Edge of the first axis simplex.
    pub step: f64,
    /// Direction of the axis simplices.
    pub layout: Layout,
    /// Gao and Han's (2012) dimension-adaptive coefficients instead of argmin's defaults.
    pub adaptive: bool,
    /// Restart rule.
    pub restart: Restart,
}

/// A cost function by reference: argmin's executor owns its problem, the caller keeps it.
struct Borrowed<'a, P>(&'a P);

impl<P: CostFunction<Param = Vec<f64>, Output = f64>> CostFunction for Borrowed<'_, P> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
        self.0.cost(x)
    }
}

/// A Nelder–Mead solver on `vertices`; with `adaptive`, the expansion and shrink of Gao and
/// Han (2012), γ = 1 + 2/n, σ = 1 − 1/n, which keep the simplex from collapsing in more
/// than a few dimensions (their contraction 0.75 − 1/(2n) is outside argmin's (0, 0.5], so
/// ρ stays 0.5). `n` is the dimension, at least 2.
fn solver(vertices: Vec<Vec<f64>>, sd_tolerance: f64, adaptive: bool) -> NelderMead<Vec<f64>, f64> {
    let n = (vertices.len().max(3) - 1) as f64;
    let nm = NelderMead::new(vertices).with_sd_tolerance(sd_tolerance);
    let nm = if adaptive {
        nm.and_then(|s| s.with_gamma(1.0 + 2.0 / n))
            .and_then(|s| s.with_sigma(1.0 - 1.0 / n))
    } else {
        nm
    };
    // The tolerance is checked with the settings and the coefficients are in range for n ≥ 2.
    nm.expect("valid Nelder-Mead settings")
}

/// A right-angled simplex at `x` with edge `step`, laid out as `layout` says.
fn axis_simplex(x: &[f64], step: f64, layout: Layout) -> Vec<Vec<f64>> {
    let mut simplex = vec![x.to_vec()];
    for i in 0..x.len() {
        let mut v = x.to_vec();
        v[i] += match layout {
            Layout::Inward if x[i] > 0.0 => -step,
            _ => step,
        };
        simplex.push(v);
    }
    simplex
}

/// A simplex shaped like the cost's valley at `x`: edges along the eigenvectors of the
/// finite-difference Hessian H (step `h`), each long enough to raise the cost by about
/// `rise` (length √(2·rise/λ), at most 2). A simplex aligned with a long, narrow, tilted
/// valley moves along it at once where a right-angled one crosses it in many small steps.
/// `None` if H has no usable curvature.
fn curvature_simplex(
    f: &dyn Fn(&[f64]) -> f64,
    x: &[f64],
    f0: f64,
    h: f64,
    rise: f64,
) -> Option<Vec<Vec<f64>>> {
    let hess = hessian(f, x, f0, h);
    if !hess.iter().all(|v| v.is_finite()) {
        return None;
    }
    let eig = nalgebra::SymmetricEigen::new(hess);
    let largest = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(*v));
    if largest <= 0.0 {
        return None;
    }
    let mut simplex = vec![x.to_vec()];
    for (j, lambda) in eig.eigenvalues.iter().enumerate() {
        // Flat or negative directions get the length of the flattest usable one, capped.
        let curvature = lambda.max(largest * 1e-10);
        let len = (2.0 * rise / curvature).sqrt().min(2.0);
        let mut v = x.to_vec();
        for (i, xi) in v.iter_mut().enumerate() {
            *xi += len * eig.eigenvectors[(i, j)];
        }
        simplex.push(v);
    }
    Some(simplex)
}

/// Where a search stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Status {
    /// More stages would go on searching.
    Running,
    /// The restart rule says the minimum is found.
    Converged,
    /// The optimizer failed (argmin returned an error); the best point so far stands.
    Failed,
}

/// A restarted Nelder–Mead search, advanced stage by stage (a stage is one argmin run of a
/// given number of iterations, continuing the current simplex).
pub struct RestartedNelderMead {
    settings: NelderMeadSettings,
    solver: Option<NelderMead<Vec<f64>, f64>>,
    x: Vec<f64>,
    fx: f64,
    iterations: u64,
    restarts: u32,
    /// Best cost when the current simplex was started.
    cost_at_restart: f64,
    edge: f64,
    status: Status,
}

impl RestartedNelderMead {
    /// A search from `x0` whose cost is `f0` (∞ if not evaluated).
    pub fn new(x0: Vec<f64>, f0: f64, settings: NelderMeadSettings) -> Self {
        let vertices = axis_simplex(&x0, settings.step, settings.layout);
        Self {
            solver: Some(solver(vertices, settings.sd_tolerance, settings.adaptive)),
            settings,
            x: x0,
            fx: f0,
            iterations: 0,
            restarts: 0,
            cost_at_restart: f64::INFINITY,
            edge: settings.step,
            status: Status::Running,
        }
    }

    /// Best point so far.
    pub fn x(&self) -> &[f64] {
        &self.x
    }

    /// Its cost.
    pub fn cost(&self) -> f64 {
        self.fx
    }

    /// Iterations used.
    pub fn iterations(&self) -> u64 {
        self.iterations
    }

    /// Where the search stands.
    pub fn status(&self) -> Status {
        self.status
    }

    /// Ends the search at `x` (cost `fx`) when that is no worse than the best point so far
    /// (another method, e.g. a least-squares polish, converged there): the status becomes
    /// [`Status::Converged`]. A worse point leaves the search as it was.
    pub fn conclude(&mut self, x: Vec<f64>, fx: f64) -> bool {
        if fx > self.fx {
            return false;
        }
        self.x = x;
        self.fx = fx;
        self.status = Status::Converged;
        true
    }

    /// Moves the search to `x` (cost `fx`, lower than the best so far) with a fresh axis
    /// simplex of edge `step` there, keeping the iteration and restart counts.
    pub fn move_to(&mut self, x: Vec<f64>, fx: f64, step: f64) {
        if fx >= self.fx || self.status != Status::Running {
            return;
        }
        let s = &self.settings;
        let vertices = axis_simplex(&x, step, s.layout);
        self.solver = Some(solver(vertices, s.sd_tolerance, s.adaptive));
        self.x = x;
        self.fx = fx;
    }

    /// Runs one stage of at most `iters` iterations, then applies the restart rule.
    pub fn advance<P>(&mut self, problem: &P, iters: u64)
    where
        P: CostFunction<Param = Vec<f64>, Output = f64>,
    {
        let Some(solver) = self.solver.take() else {
            return;
        };
        let cost_before = self.fx;
        let result = Executor::new(Borrowed(problem), solver)
            .configure(|s| s.max_iters(iters))
            .ctrlc(false)
            .run();
        let Ok(res) = result else {
            self.status = Status::Failed;
            return;
        };
        let state = &res.state;
        self.iterations += state.get_iter();
        if let Some(p) = state.get_best_param() {
            let c = state.get_best_cost();
            let better = match self.settings.restart {
                Restart::Halving { .. } => c < self.fx,
                _ => c <= self.fx,
            };
            if better {
                self.x = p.clone();
                self.fx = c;
            }
        }
        let collapsed = state.get_termination_reason() == Some(&TerminationReason::SolverConverged);
        self.solver = Some(res.solver);
        match self.settings.restart {
            Restart::Never => self.status = Status::Converged,
            Restart::Curvature {
                max_restarts,
                min_gain,
            } => self.curvature_restart(problem, cost_before, collapsed, max_restarts, min_gain),
            Restart::Halving {
                rounds,
                min_edge,
                gain,
            } => self.halving_restart(cost_before, rounds, min_edge, gain),
        }
    }

    /// [`Restart::Curvature`] after a stage.
    fn curvature_restart<P>(
        &mut self,
        problem: &P,
        before: f64,
        collapsed: bool,
        max: u32,
        min_gain: f64,
    ) where
        P: CostFunction<Param = Vec<f64>, Output = f64>,
    {
        // A stage that gained nothing has stagnated (a simplex stuck in a curved valley):
        // treat it like a collapse and restart around the best point.
        let stalled = before.is_finite() && before - self.fx <= 1e-9 * (1.0 + self.fx.abs());
        if !(collapsed || stalled) {
            return;
        }
        let gained = self.cost_at_restart - self.fx > min_gain * (1.0 + self.fx.abs());
        if !(gained && self.restarts < max) {
            self.status = Status::Converged;
            return;
        }
        self.restarts += 1;
        self.cost_at_restart = self.fx;
        // Aim each edge at a rise of 1% of the cost (at least 0.01).
        let rise = (0.01 * self.fx).max(0.01);
        let f = |x: &[f64]| problem.cost(&x.to_vec()).unwrap_or(f64::INFINITY);
        let vertices = curvature_simplex(&f, &self.x, self.fx, 1e-3, rise).unwrap_or_else(|| {
            let step = (self.settings.step * 0.5f64.powi(self.restarts as i32)).max(1e-3);
            axis_simplex(&self.x, step, self.settings.layout)
        });
        let s = &self.settings;
        self.solver = Some(solver(vertices, s.sd_tolerance, s.adaptive));
    }

    /// [`Restart::Halving`] after a stage.
    fn halving_restart(&mut self, before: f64, rounds: u32, min_edge: f64, gain: f64) {
        self.restarts += 1;
        if before - self.fx <= gain * (1.0 + self.fx.abs()) || self.restarts >= rounds {
            self.status = Status::Converged;
            return;
        }
        self.edge = (self.edge * 0.5).max(min_edge);
        let s = &self.settings;
        let vertices = axis_simplex(&self.x, self.edge, s.layout);
        self.solver = Some(solver(vertices, s.sd_tolerance, s.adaptive));
    }
}

/// Runs a search from `x0` (cost `f0`, ∞ if not evaluated) until the restart rule or the
/// budget of `max_iters` iterations ends it, in stages of at most `stage_iters`.
pub fn minimize<P>(
    problem: &P,
    x0: Vec<f64>,
    f0: f64,
    settings: NelderMeadSettings,
    max_iters: u64,
    stage_iters: u64,
) -> RestartedNelderMead
where
    P: CostFunction<Param = Vec<f64>, Output = f64>,
{
    let mut search = RestartedNelderMead::new(x0, f0, settings);
    while search.status == Status::Running && search.iterations < max_iters {
        search.advance(problem, (max_iters - search.iterations).min(stage_iters));
    }
    search
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quadratic bowl as an argmin problem.
    struct Bowl;

    impl CostFunction for Bowl {
        type Param = Vec<f64>;
        type Output = f64;
        fn cost(&self, x: &Vec<f64>) -> Result<f64, Error> {
            Ok((x[0] - 1.0).powi(2) + 10.0 * (x[1] + 2.0).powi(2) + (x[2] * 0.5).powi(2))
        }
    }

    #[test]
    fn every_restart_rule_finds_a_quadratic_minimum() {
        let halving = Restart::Halving {
            rounds: 12,
            min_edge: 0.02,
            gain: 1e-7,
        };
        for restart in [
            halving,
            Restart::Curvature {
                max_restarts: 20,
                min_gain: 1e-6,
            },
        ] {
            let settings = NelderMeadSettings {
                sd_tolerance: 1e-10,
                step: 0.5,
                layout: Layout::Inward,
                adaptive: true,
                restart,
            };
            let x0 = vec![0.0, 0.0, 1.0];
            let f0 = Bowl.cost(&x0).unwrap();
            let s = minimize(&Bowl, x0, f0, settings, 3000, 200);
            let x = s.x();
            assert!(s.cost() < 1e-6, "{restart:?}: {} at {x:?}", s.cost());
            assert!((x[0] - 1.0).abs() < 1e-2 && (x[1] + 2.0).abs() < 1e-2);
            assert_eq!(s.status(), Status::Converged);
        }
    }

    #[test]
    fn axis_simplices_point_inward_or_forward() {
        let inward = axis_simplex(&[1.0, -1.0], 0.5, Layout::Inward);
        assert_eq!(
            inward,
            vec![vec![1.0, -1.0], vec![0.5, -1.0], vec![1.0, -0.5]]
        );
        let forward = axis_simplex(&[1.0, -1.0], 0.5, Layout::Forward);
        assert_eq!(forward[1], vec![1.5, -1.0]);
    }
}
