//! What every phase of a diagnosis shares: the dataset, the cost and likelihood built on it,
//! the options, the observer and the clock.

use super::analysis::{self, ChannelData};
use super::error::DiagnoseError;
use super::fitting::{FitJob, Fitted};
use super::observe::{DiagnoseObserver, Progress};
use super::DiagnoseOptions;
use crate::data::dataset::Dataset;
use crate::estimate::Engine;
use crate::model::effects::EffectSet;
use crate::model::motor::ExtraTerm;
use crate::model::params::estimated_names as names_for;
use crate::model::params::MotorParams;
use crate::numerics::DefaultSolver;
use crate::objective::cost::{CostModel, CostOptions};
use crate::objective::likelihood::Target;
use crate::sim::experiment::SimError;
use std::cell::{Cell, RefCell};
use std::time::Instant;

/// The state shared by the phases (read-only but for the phase clock).
pub(crate) struct Context<'a> {
    /// The dataset with the inputs of transients smoothed.
    pub ds: &'a Dataset,
    /// How thorough the diagnosis is.
    pub opts: &'a DiagnoseOptions,
    /// The project's cost on `ds` (its rows are the compared rows).
    pub cost: CostModel,
    /// The recorded data and noise at the compared rows (what every fit maximises).
    pub target: Target,
    /// The ODE solver of the analyses (each fit has its own).
    pub solver: DefaultSolver,
    /// The rig's nominal motor (the first baseline start).
    pub nominal: MotorParams,
    /// Names estimated in the base model.
    pub(crate) base_names: Vec<String>,
    /// The one thread pool every fit and regression of the diagnosis runs on.
    pub engine: &'a Engine,
    observer: &'a dyn DiagnoseObserver,
    t0: Instant,
    phase_start: Cell<Instant>,
    /// (phase, seconds, cost evaluations) of each finished phase.
    phases: RefCell<Vec<(String, f64, u64)>>,
    /// Cost evaluations (whole simulations of every experiment) of the current phase.
    phase_evaluations: Cell<u64>,
}

impl<'a> Context<'a> {
    /// Builds the cost and the likelihood target of `ds`; `t0` is the diagnosis's start.
    pub fn new(
        ds: &'a Dataset,
        opts: &'a DiagnoseOptions,
        engine: &'a Engine,
        observer: &'a dyn DiagnoseObserver,
        t0: Instant,
    ) -> Result<Self, DiagnoseError> {
        let phase_start = Cell::new(Instant::now());
        let solver = DefaultSolver::default();
        let cost = CostModel::new(ds, CostOptions::default())?;
        let target = Target::new(&cost, ds)?;
        let nominal = ds.nominal_params()?;
        Ok(Self {
            ds,
            opts,
            cost,
            target,
            solver,
            nominal,
            base_names: names_for(&EffectSet::empty()),
            engine,
            observer,
            t0,
            phase_start,
            phases: RefCell::new(Vec::new()),
            phase_evaluations: Cell::new(0),
        })
    }

    /// Tells the observer.
    pub fn say(&self, event: Progress<'_>) {
        self.observer
            .progress(self.t0.elapsed().as_secs_f64(), &event);
    }

    /// Ends the phase `name` (its time counts from the end of the previous one).
    pub(crate) fn end_phase(&self, name: &str) {
        let seconds = self.phase_start.get().elapsed().as_secs_f64();
        let evaluations = self.phase_evaluations.replace(0);
        self.phases
            .borrow_mut()
            .push((name.to_string(), seconds, evaluations));
        self.phase_start.set(Instant::now());
        self.observer.phase(name, seconds);
    }

    /// Counts `n` cost evaluations (the work of a fit, a regression or a grid).
    pub(crate) fn count(&self, n: u64) {
        self.phase_evaluations.set(self.phase_evaluations.get() + n);
    }

    /// (phase, evaluations) of the finished phases.
    pub fn phase_evaluations(&self) -> Vec<(String, u64)> {
        let phases = self.phases.borrow();
        phases.iter().map(|(p, _, n)| (p.clone(), *n)).collect()
    }

    /// (phase, seconds) so far.
    pub fn phases(&self) -> Vec<(String, f64)> {
        let phases = self.phases.borrow();
        phases.iter().map(|(p, s, _)| (p.clone(), *s)).collect()
    }

    /// Seconds since the diagnosis started.
    pub fn elapsed_s(&self) -> f64 {
        self.t0.elapsed().as_secs_f64()
    }

    /// The thread pool of the diagnosis.
    pub fn threads(&self) -> &Engine {
        self.engine
    }

    /// The baseline fit: the nominal motor plus Latin-hypercube starts.
    pub(crate) fn base_job(&self) -> FitJob {
        FitJob {
            label: "baseline".into(),
            effects: EffectSet::empty(),
            extra: Vec::new(),
            names: self.base_names.clone(),
            starts: vec![self.nominal.clone()],
            lhs: self.opts.starts - 1,
            max_iters: self.opts.baseline_iters,
            seed: self.opts.seed,
        }
    }

    /// A warm refit of a model from given starts, with the refit budget.
    pub(crate) fn refit_job(
        &self,
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
            max_iters: self.opts.refit_iters,
            seed: self.opts.seed,
        }
    }

    /// A fitted model's channels against the data.
    pub fn channels(&self, f: &Fitted) -> Result<Vec<ChannelData>, SimError> {
        self.count(1);
        analysis::channel_data(&self.cost, &self.target, &f.motor(), &self.solver)
    }
}
