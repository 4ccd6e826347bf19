//! What every phase of a diagnosis reads: the dataset, the cost and likelihood built on it,
//! the options and the thread pool. The orchestrator (`diagnose_observed`) keeps the rest:
//! the observer and the phase clock; a phase returns what it did ([`super::observe::Note`]).

use super::error::DiagnoseError;
use super::fitting::FitJob;
use super::DiagnoseOptions;
use crate::data::dataset::Dataset;
use crate::estimate::Engine;
use crate::model::effects::EffectSet;
use crate::model::params::estimated_names as names_for;
use crate::numerics::DefaultSolver;
use crate::objective::cost::{CostModel, CostOptions};
use crate::objective::likelihood::Target;

/// The state the phases share, read-only.
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
    /// Names estimated in the base model.
    pub(crate) base_names: Vec<String>,
    /// The baseline fit: the nominal motor plus Latin-hypercube starts, with the baseline's
    /// budget (each warm refit of the base model starts from it).
    pub(crate) base_job: FitJob,
    /// The one thread pool every fit and regression of the diagnosis runs on.
    pub engine: &'a Engine,
}

impl<'a> Context<'a> {
    /// Builds the cost and the likelihood target of `ds`.
    pub fn new(
        ds: &'a Dataset,
        opts: &'a DiagnoseOptions,
        engine: &'a Engine,
    ) -> Result<Self, DiagnoseError> {
        let solver = DefaultSolver::default();
        let cost = CostModel::new(ds, CostOptions::default())?;
        let target = Target::new(&cost, ds)?;
        let nominal = ds.nominal_params()?;
        let base_names = names_for(&EffectSet::empty());
        let base_job = FitJob {
            label: "baseline".into(),
            effects: EffectSet::empty(),
            extra: Vec::new(),
            names: base_names.clone(),
            starts: vec![nominal.clone()],
            lhs: opts.starts - 1,
            max_iters: opts.baseline_iters,
            seed: opts.seed,
        };
        Ok(Self {
            ds,
            opts,
            cost,
            target,
            solver,
            base_names,
            base_job,
            engine,
        })
    }
}
