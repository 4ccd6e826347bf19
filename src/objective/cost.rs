//! The fitting cost (docs/model.md, "Cost J"): simulation against the reference
//! polynomials.
//!
//! For every measured channel c of every experiment e, with reference polynomial ŷ_c(x)
//! and noise level σ_c (both from [`crate::objective::reference`], SI), the simulated value y_c,i at
//! each recorded row i whose abscissa x_i (from [`Experiment::abscissa`]: imposed speed,
//! smoothed port-1 pressure, log10 of the smoothed port-2 conductance) lies within the
//! reference's valid range is compared with ŷ_c(x_i):
//!
//! ```text
//!     J = Σ_e Σ_c  w_e · w_c · (1/N_c) · Σ_i ((y_c,i − ŷ_c(x_i)) / σ_c)²        [1]
//! ```
//!
//! w_e is the experiment's `weight` in rig.toml (default 1), w_c the channel's entry in its
//! `weights = { flow1 = 2.0 }` table (keyed by column prefix, default 1), N_c the number of
//! rows compared. Each channel's term is its mean squared normalised residual, so a model
//! that matches the references to within their noise scores about 1 per unit weight or less
//! (a perfect model scores ≈ p/n per channel, the reference's own fitting error), whatever
//! the number of rows or the units. Rows are compared in recording order; at most
//! [`CostOptions::max_points_per_channel`] of them, evenly spaced.
//!
//! A catalogue page that prints its max power at a speed adds one term more, after every
//! channel: w_e·r² with r the distance of the model's power peak from the printed speed in
//! reading tolerances ([`super::peak`]); it is listed among the channels as
//! [`PEAK_COLUMN`].
//!
//! J never is NaN, infinite or an error: a simulation that fails, or a cost that is not
//! finite, gives the constant [`FAILURE_PENALTY`] (far above the cost of any completed
//! simulation: a residual of 10⁴σ on every point of ten channels gives 1e9) and is counted
//! ([`CostModel::failures`]). `CostModel` is `Sync`: the estimator calls it from many rayon
//! threads; the counters are atomic.

use crate::data::dataset::{DataError, Dataset, Kind};
use crate::model::motor::Motor;
use crate::numerics::ode::StiffSolver;
use crate::objective::peak::PowerPeak;
use crate::objective::reference::{
    experiment_references, ChannelReference, Reference, ReferenceOptions,
};
use crate::sim::experiment::{Experiment, SimError, Simulated};
use crate::units::Quantity;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// The column name under which a page's power-peak term (`objective::peak`) is listed among
/// the channels of a cost.
pub const PEAK_COLUMN: &str = "power peak at speed_at_max_power";

/// Cost given to a failed simulation or a non-finite cost (dimensionless, like J).
pub const FAILURE_PENALTY: f64 = 1e10;

/// How the cost is built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CostOptions {
    /// How the reference polynomials are fitted.
    pub reference: ReferenceOptions,
    /// Most rows compared per channel (evenly spaced over those in range).
    pub max_points_per_channel: usize,
}

impl Default for CostOptions {
    /// Default references; every row compared (the comparison costs microseconds next to
    /// the simulation, which produces every row anyway).
    fn default() -> Self {
        Self {
            reference: ReferenceOptions::default(),
            max_points_per_channel: usize::MAX,
        }
    }
}

/// Why a cost model could not be built (the objective layer's error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CostError {
    /// A recording cannot give a reference response.
    #[error(transparent)]
    Data(#[from] DataError),
    /// An experiment's inputs cannot drive a simulation.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A channel the cost compares has no column in its recording.
    #[error(transparent)]
    MissingColumn(#[from] crate::sim::recording::MissingColumn),
    /// An experiment of the cost model is not in the dataset it was built from.
    #[error("{0}: not in the dataset")]
    NotInDataset(String),
}

/// One channel's part of the cost.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelCost {
    /// The experiment's kind.
    pub experiment_kind: Kind,
    /// Its recording's file name.
    pub file: String,
    /// The measured channel.
    pub channel: Quantity,
    /// Column name as written in the recording.
    pub column: String,
    /// w_e·w_c.
    pub weight: f64,
    /// √(mean((y − ŷ)/σ)²), dimensionless.
    pub rms_normalized: f64,
    /// Rows compared.
    pub n: usize,
    /// This channel's term of J: weight·rms_normalized².
    pub cost: f64,
}

/// The cost of one parameter set.
#[derive(Debug, Clone, PartialEq)]
pub struct CostValue {
    /// J of eq. \[1\], or `FAILURE_PENALTY`; always finite.
    pub total: f64,
    /// Why the simulation failed or the cost was not finite, if it did.
    pub failed: Option<String>,
    /// The terms of J (those computed before a failure).
    pub channels: Vec<ChannelCost>,
}

/// Residuals of one channel, for diagnosis. All values SI, one entry per compared row.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelResiduals {
    /// The experiment's kind.
    pub experiment_kind: Kind,
    /// Its recording's file name.
    pub file: String,
    /// The measured channel.
    pub channel: Quantity,
    /// The channel's column name in the recording.
    pub column: String,
    /// Indices of the compared rows in the recording (0-based data rows).
    pub rows: Vec<usize>,
    /// Abscissa of each row as simulated (rad/s, Pa or log10 m³/(s·Pa)).
    pub x: Vec<f64>,
    /// Reference polynomial at x (the measurement as described by its reference).
    pub measured: Vec<f64>,
    /// Simulated values, SI, one per row.
    pub simulated: Vec<f64>,
    /// (simulated − measured)/σ.
    pub(crate) normalized: Vec<f64>,
    /// σ of the reference.
    pub sigma: f64,
    /// w_e·w_c.
    pub weight: f64,
}

/// A channel ready to compare: which rows, where, and what the reference says there.
#[derive(Debug, Clone)]
struct Channel {
    reference: ChannelReference,
    weight: f64,
    rows: Vec<usize>,
    x: Vec<f64>,
    y_ref: Vec<f64>,
    sigma: f64,
}

/// The simulation's values of a compared channel, or the error that it gives none.
fn channel_values<'a>(sim: &'a Simulated, ch: &Channel) -> Result<&'a [f64], SimError> {
    sim.channel(ch.reference.quantity)
        .ok_or_else(|| SimError::NoChannel {
            experiment: ch.reference.file.clone(),
            column: ch.reference.column.clone(),
        })
}

#[derive(Debug, Clone)]
struct ExperimentCost {
    experiment: Experiment,
    channels: Vec<Channel>,
}

/// The rows of a channel that the cost and the likelihood compare: those with a value
/// (a catalogue's empty cells are NaN) whose abscissa the reference covers.
pub(crate) fn compared_rows(abscissa: &[f64], reference: &Reference, values: &[f64]) -> Vec<usize> {
    (0..abscissa.len())
        .filter(|&i| values.get(i).is_some_and(|v| v.is_finite()))
        .filter(|&i| reference.eval(abscissa[i]).is_some())
        .collect()
}

/// The cost J (docs/model.md, "Cost J") of one dataset: experiments and references are
/// built once.
#[derive(Debug)]
pub struct CostModel {
    experiments: Vec<ExperimentCost>,
    /// Each page's power-peak condition, compared after every channel.
    peaks: Vec<PowerPeak>,
    n_points: usize,
    evaluations: AtomicU64,
    failures: AtomicU64,
}

impl CostModel {
    /// Builds every experiment's inputs and every channel's reference.
    pub fn new(ds: &Dataset, options: CostOptions) -> Result<CostModel, CostError> {
        let mut experiments = Vec::with_capacity(ds.experiments.len());
        let peaks: Vec<PowerPeak> = ds
            .experiments
            .iter()
            .enumerate()
            .filter_map(|(e, data)| PowerPeak::of(data, e))
            .collect();
        for data in &ds.experiments {
            let experiment = Experiment::new(data, ds.p_atm_pa)?;
            let abscissa = experiment.abscissa();
            let mut channels = Vec::new();
            for reference in experiment_references(data, &options.reference)? {
                let w_c = data
                    .channel_weights
                    .get(reference.quantity.prefix())
                    .copied()
                    .unwrap_or(1.0);
                let values = data.recording.values(reference.quantity)?;
                let in_range = compared_rows(&abscissa, &reference.reference, values);
                let rows = evenly_spaced(&in_range, options.max_points_per_channel);
                let x: Vec<f64> = rows.iter().map(|&i| abscissa[i]).collect();
                let y_ref: Vec<f64> = x
                    .iter()
                    .map(|&v| reference.reference.eval(v).expect("in range"))
                    .collect();
                let sigma = reference.reference.sigma();
                channels.push(Channel {
                    weight: data.weight * w_c,
                    rows,
                    x,
                    y_ref,
                    sigma,
                    reference,
                });
            }
            experiments.push(ExperimentCost {
                experiment,
                channels,
            });
        }
        let n_points = experiments
            .iter()
            .flat_map(|e| &e.channels)
            .map(|c| c.rows.len())
            .sum::<usize>()
            + peaks.len();
        Ok(CostModel {
            experiments,
            peaks,
            n_points,
            evaluations: AtomicU64::new(0),
            failures: AtomicU64::new(0),
        })
    }

    /// J of eq. \[1\] for a motor; never NaN, infinite or an error (see the module docs).
    pub fn evaluate(&self, motor: &Motor, solver: &dyn StiffSolver) -> CostValue {
        self.evaluations.fetch_add(1, Ordering::Relaxed);
        let mut channels = Vec::new();
        let mut total = 0.0;
        let sims = self.simulate_all(motor, solver);
        for (ex, sim) in self.experiments.iter().zip(&sims) {
            let sim = match sim {
                Ok(s) => s,
                Err(e) => return self.failed(e.to_string(), channels),
            };
            for ch in &ex.channels {
                let Some(values) = sim.channel(ch.reference.quantity) else {
                    let msg = format!(
                        "{}: the simulation gives no {}",
                        ch.reference.file, ch.reference.column
                    );
                    return self.failed(msg, channels);
                };
                let mut sum = 0.0;
                for (k, &row) in ch.rows.iter().enumerate() {
                    let r = (values[row] - ch.y_ref[k]) / ch.sigma;
                    sum += r * r;
                }
                let n = ch.rows.len();
                let mean = if n > 0 { sum / n as f64 } else { 0.0 };
                let cost = ch.weight * mean;
                channels.push(ChannelCost {
                    experiment_kind: ch.reference.kind,
                    file: ch.reference.file.clone(),
                    channel: ch.reference.quantity,
                    column: ch.reference.column.clone(),
                    weight: ch.weight,
                    rms_normalized: mean.sqrt(),
                    n,
                    cost,
                });
                if !cost.is_finite() {
                    let msg = format!(
                        "{} {}: cost is not finite (simulated values {})",
                        ch.reference.file,
                        ch.reference.column,
                        if values.iter().all(|v| v.is_finite()) {
                            "overflow"
                        } else {
                            "are not finite"
                        }
                    );
                    return self.failed(msg, channels);
                }
                total += cost;
            }
        }
        for peak in &self.peaks {
            match simulated(&sims, peak).and_then(|sim| peak_cost(peak, sim)) {
                Ok(c) => {
                    total += c.cost;
                    channels.push(c);
                }
                Err(e) => return self.failed(e.to_string(), channels),
            }
        }
        if !total.is_finite() {
            return self.failed("total cost is not finite".into(), channels);
        }
        CostValue {
            total,
            failed: None,
            channels,
        }
    }

    /// Every experiment simulated, in rig.toml order. Inside a rayon pool (the estimator's
    /// engine) the experiments are offered to idle threads: when fewer starts are left than
    /// threads, the ramps of one evaluation run side by side instead of leaving a core idle;
    /// when every thread is busy the pool runs them in turn at the cost of a few queue
    /// operations. Outside a pool they run in turn on the caller's thread, so a single-core
    /// caller never gets a second core by accident. Either way the results, and the sum
    /// taken from them in order, are the same.
    fn simulate_all(
        &self,
        motor: &Motor,
        solver: &dyn StiffSolver,
    ) -> Vec<Result<Simulated, SimError>> {
        let one = |ex: &ExperimentCost| ex.experiment.simulate(motor, solver);
        if rayon::current_thread_index().is_some() {
            self.experiments.par_iter().map(one).collect()
        } else {
            self.experiments.iter().map(one).collect()
        }
    }

    fn failed(&self, message: String, channels: Vec<ChannelCost>) -> CostValue {
        self.failures.fetch_add(1, Ordering::Relaxed);
        CostValue {
            total: FAILURE_PENALTY,
            failed: Some(message),
            channels,
        }
    }

    /// Per-row residuals of every channel (for diagnosis). Unlike [`CostModel::evaluate`]
    /// a failed simulation is an error here, and the counters are not touched.
    pub fn residuals(
        &self,
        motor: &Motor,
        solver: &dyn StiffSolver,
    ) -> Result<Vec<ChannelResiduals>, SimError> {
        let mut out = Vec::new();
        for ex in &self.experiments {
            let sim = ex.experiment.simulate(motor, solver)?;
            for ch in &ex.channels {
                let values = channel_values(&sim, ch)?;
                let simulated: Vec<f64> = ch.rows.iter().map(|&i| values[i]).collect();
                let normalized = simulated
                    .iter()
                    .zip(&ch.y_ref)
                    .map(|(s, m)| (s - m) / ch.sigma)
                    .collect();
                out.push(ChannelResiduals {
                    experiment_kind: ch.reference.kind,
                    file: ch.reference.file.clone(),
                    channel: ch.reference.quantity,
                    column: ch.reference.column.clone(),
                    rows: ch.rows.clone(),
                    x: ch.x.clone(),
                    measured: ch.y_ref.clone(),
                    simulated,
                    normalized,
                    sigma: ch.sigma,
                    weight: ch.weight,
                });
            }
        }
        Ok(out)
    }

    /// The simulated values at every channel's compared rows, SI, in channel order (the lean
    /// part of [`CostModel::residuals`], for likelihoods evaluated thousands of times),
    /// followed by each page's power peak ω_m, rad/s, one value each ([`CostModel::peaks`]).
    pub(crate) fn simulated_rows(
        &self,
        motor: &Motor,
        solver: &dyn StiffSolver,
    ) -> Result<Vec<Vec<f64>>, SimError> {
        self.simulated_at(motor, solver, |_, ch| &ch.rows)
    }

    /// Every channel's compared rows (recording rows, 0-based), in channel order.
    pub fn rows(&self) -> Vec<Vec<usize>> {
        self.experiments
            .iter()
            .flat_map(|e| e.channels.iter().map(|c| c.rows.clone()))
            .collect()
    }

    /// The simulated values at given rows of every channel (`rows[c]` for channel c, in
    /// channel order; e.g. another cost model's rows of the same recordings), SI.
    pub(crate) fn simulated_at_rows(
        &self,
        motor: &Motor,
        solver: &dyn StiffSolver,
        rows: &[Vec<usize>],
    ) -> Result<Vec<Vec<f64>>, SimError> {
        self.simulated_at(motor, solver, |i, _| rows.get(i).map_or(&[][..], |r| r))
    }

    fn simulated_at<'a>(
        &'a self,
        motor: &Motor,
        solver: &dyn StiffSolver,
        rows_of: impl Fn(usize, &'a Channel) -> &'a [usize],
    ) -> Result<Vec<Vec<f64>>, SimError> {
        let mut out = Vec::with_capacity(self.n_channels() + self.peaks.len());
        let sims = self.simulate_all(motor, solver);
        for (ex, sim) in self.experiments.iter().zip(&sims) {
            let sim = sim.as_ref().map_err(Clone::clone)?;
            for ch in &ex.channels {
                let values = channel_values(sim, ch)?;
                let rows = rows_of(out.len(), ch);
                out.push(
                    rows.iter()
                        .filter_map(|&i| values.get(i).copied())
                        .collect(),
                );
            }
        }
        for peak in &self.peaks {
            out.push(vec![peak.peak_speed(simulated(&sims, peak)?)?]);
        }
        Ok(out)
    }

    /// Each page's power-peak condition, in rig.toml order: compared after every channel
    /// (the trailing entries of [`CostModel::simulated_rows`]).
    pub(crate) fn peaks(&self) -> &[PowerPeak] {
        &self.peaks
    }

    /// Every channel's reference, in experiment and channel order.
    pub fn references(&self) -> impl Iterator<Item = &ChannelReference> {
        self.experiments
            .iter()
            .flat_map(|e| e.channels.iter().map(|c| &c.reference))
    }

    /// The experiments, in rig.toml order.
    pub fn experiments(&self) -> impl Iterator<Item = &Experiment> {
        self.experiments.iter().map(|e| &e.experiment)
    }

    /// Total number of compared points Σ N_c (for information criteria such as BIC).
    pub fn n_points(&self) -> usize {
        self.n_points
    }

    /// Number of channels compared.
    pub(crate) fn n_channels(&self) -> usize {
        self.experiments.iter().map(|e| e.channels.len()).sum()
    }

    /// Calls of [`CostModel::evaluate`] so far.
    pub fn evaluations(&self) -> u64 {
        self.evaluations.load(Ordering::Relaxed)
    }

    /// Calls of [`CostModel::evaluate`] that returned the failure penalty.
    pub fn failures(&self) -> u64 {
        self.failures.load(Ordering::Relaxed)
    }
}

/// The simulation of a power peak's page among every experiment's (`sims`, in rig.toml
/// order).
fn simulated<'a>(
    sims: &'a [Result<Simulated, SimError>],
    peak: &PowerPeak,
) -> Result<&'a Simulated, SimError> {
    match sims.get(peak.experiment) {
        Some(Ok(s)) => Ok(s),
        Some(Err(e)) => Err(e.clone()),
        None => Err(SimError::NoChannel {
            experiment: peak.file.clone(),
            column: PEAK_COLUMN.into(),
        }),
    }
}

/// A page's power-peak term of J: w_e·r² ([`super::peak`]), from its page's simulation.
fn peak_cost(peak: &PowerPeak, sim: &Simulated) -> Result<ChannelCost, SimError> {
    let r = peak.residual(peak.peak_speed(sim)?);
    Ok(ChannelCost {
        experiment_kind: Kind::Catalogue,
        file: peak.file.clone(),
        channel: Quantity::Speed,
        column: PEAK_COLUMN.into(),
        weight: peak.weight,
        rms_normalized: r.abs(),
        n: 1,
        cost: peak.weight * r * r,
    })
}

/// At most `max` of `items`, evenly spaced and including the first and the last.
fn evenly_spaced(items: &[usize], max: usize) -> Vec<usize> {
    let n = items.len();
    if n <= max {
        return items.to_vec();
    }
    if max <= 1 {
        return items.iter().take(max).copied().collect();
    }
    (0..max)
        .map(|k| items[(k * (n - 1) + (max - 1) / 2) / (max - 1)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::synth::{synthesize, SensorNoise, SynthPlan};
    use crate::model::effects::EffectSet;
    use crate::model::params::MotorParams;
    use crate::numerics::DefaultSolver;

    fn dataset(experiments: Vec<crate::data::dataset::ExperimentData>) -> Dataset {
        Dataset::in_memory(experiments)
    }

    /// A short plan so that the tests stay fast.
    fn short_plan() -> SynthPlan {
        SynthPlan {
            ramp_duration_s: 20.0,
            throttle_duration_s: 20.0,
            sample_rate_hz: 5.0,
            ..SynthPlan::default()
        }
    }

    #[test]
    fn evenly_spaced_keeps_ends() {
        let v: Vec<usize> = (0..10).collect();
        assert_eq!(evenly_spaced(&v, 20), v);
        assert_eq!(evenly_spaced(&v, 4), vec![0, 3, 6, 9]);
        assert_eq!(evenly_spaced(&v, 2), vec![0, 9]);
    }

    /// With σ the reference's RMS residual, a model that reproduces the data exactly scores
    /// RSS/(n·σ²) = (n − p)/n per channel wherever the polynomial does not describe the
    /// curve to within the resolution floor, and ≈ 0 where it does.
    #[test]
    fn generating_model_costs_almost_nothing_and_others_cost_more() {
        let motor = Motor::default_motor();
        let solver = DefaultSolver::default();
        let plan = short_plan();
        let clean = synthesize(&motor, &solver, &plan, &SensorNoise::none(), 1).unwrap();
        let noisy = synthesize(&motor, &solver, &plan, &SensorNoise::typical(), 1).unwrap();
        let worse = Motor::new(
            MotorParams::default().with("c_in1", 6.0e-9).unwrap(),
            EffectSet::empty(),
        );
        for (label, data) in [("noise-free", clean), ("noisy", noisy)] {
            let model = CostModel::new(&dataset(data), CostOptions::default()).unwrap();
            let c = model.evaluate(&motor, &solver);
            assert!(c.failed.is_none());
            let w = model.evaluate(&worse, &solver);
            for (ch, r) in c.channels.iter().zip(model.references()) {
                let fit = &r.reference;
                if fit.sigma() > 10.0 * fit.sigma_residual() {
                    // The reference is exact to the resolution: the cost is 0-ish.
                    assert!(ch.rms_normalized < 0.1, "{label}: {ch:?}");
                } else {
                    // The reference's own error: about √(p/n) from noise, plus its lack of
                    // fit; a 25-point datasheet leaves a cubic's worth of scatter.
                    assert!(ch.rms_normalized < 1.25, "{label}: {ch:?}");
                }
            }
            let exact = model
                .references()
                .filter(|r| r.reference.sigma() > 10.0 * r.reference.sigma_residual())
                .count();
            if label == "noise-free" {
                assert!(exact >= 3, "{exact} references at the resolution floor");
            }
            assert!(
                c.total < model.n_channels() as f64 * 0.5,
                "{label}: {}",
                c.total
            );
            assert!(
                w.total > 10.0 * c.total,
                "{label}: {} vs {}",
                w.total,
                c.total
            );
            assert_eq!(model.evaluations(), 2);
            assert_eq!(model.failures(), 0);
            assert_eq!(c.channels.len(), model.n_channels());
            assert_eq!(
                c.channels.iter().map(|c| c.n).sum::<usize>(),
                model.n_points()
            );
        }
    }

    #[test]
    fn absurd_parameters_give_a_finite_cost() {
        let solver = DefaultSolver::default();
        let plan = short_plan();
        let data = synthesize(
            &Motor::default_motor(),
            &solver,
            &plan,
            &SensorNoise::typical(),
            2,
        )
        .unwrap();
        let model = CostModel::new(&dataset(data), CostOptions::default()).unwrap();
        let mut p = MotorParams::default();
        for (name, v) in [
            ("c_in1", 1e-3),
            ("c_ext", 1e-15),
            ("inertia", 1e-9),
            ("t_coulomb", 50.0),
        ] {
            p = p.with(name, v).unwrap_or(p);
        }
        let absurd = Motor::new(p, EffectSet::empty());
        let c = model.evaluate(&absurd, &solver);
        assert!(c.total.is_finite() && c.total > 0.0, "{c:?}");
        assert!(c.total >= 100.0, "{}", c.total);
        assert_eq!(model.evaluations(), 1);
        assert_eq!(model.failures(), u64::from(c.failed.is_some()));
        // Every base parameter at either end of its search range, one at a time.
        let mut n = 1;
        for spec in crate::model::params::PARAMS
            .iter()
            .filter(|s| s.effect.is_none())
        {
            for v in [spec.search.0, spec.search.1] {
                let Ok(p) = MotorParams::default().with(spec.name, v) else {
                    continue;
                };
                let c = model.evaluate(&Motor::new(p, EffectSet::empty()), &solver);
                n += 1;
                assert!(
                    c.total.is_finite() && c.total >= 0.0,
                    "{} = {v}: {c:?}",
                    spec.name
                );
                assert_eq!(c.failed.is_some(), c.total == FAILURE_PENALTY);
            }
        }
        assert_eq!(model.evaluations(), n);
    }

    /// A solver that fails, or returns NaN, to exercise the penalty.
    struct BrokenSolver {
        nan: bool,
    }

    impl StiffSolver for BrokenSolver {
        fn solve(
            &self,
            _rhs: &crate::numerics::ode::Rhs<'_>,
            _t0: f64,
            x0: crate::model::motor::State,
            t_out: &[f64],
        ) -> Result<Vec<crate::model::motor::State>, crate::numerics::ode::SolveError> {
            if self.nan {
                Ok(vec![[f64::NAN; crate::model::motor::N_STATES]; t_out.len()])
            } else {
                let _ = x0;
                Err(crate::numerics::ode::SolveError::StepSizeUnderflow { t: 0.0 })
            }
        }
    }

    #[test]
    fn failures_give_the_finite_penalty_and_are_counted() {
        let solver = DefaultSolver::default();
        let data = synthesize(
            &Motor::default_motor(),
            &solver,
            &short_plan(),
            &SensorNoise::typical(),
            5,
        )
        .unwrap();
        let model = CostModel::new(&dataset(data), CostOptions::default()).unwrap();
        let motor = Motor::default_motor();
        let failed = model.evaluate(&motor, &BrokenSolver { nan: false });
        assert_eq!(failed.total, FAILURE_PENALTY);
        assert!(
            failed.failed.as_deref().unwrap().contains("step size"),
            "{failed:?}"
        );
        // The datasheet (steady states, no integration) was costed before the failure.
        assert_eq!(failed.channels.len(), 2);
        let nan = model.evaluate(&motor, &BrokenSolver { nan: true });
        assert_eq!(nan.total, FAILURE_PENALTY);
        assert!(
            nan.failed.as_deref().unwrap().contains("not finite"),
            "{nan:?}"
        );
        let ok = model.evaluate(&motor, &solver);
        assert!(ok.failed.is_none() && ok.total < 10.0);
        assert_eq!((model.evaluations(), model.failures()), (3, 2));
        assert!(model
            .residuals(&motor, &BrokenSolver { nan: false })
            .is_err());
    }

    #[test]
    fn weights_scale_channel_terms() {
        let solver = DefaultSolver::default();
        let plan = short_plan();
        let mut data = synthesize(
            &Motor::default_motor(),
            &solver,
            &plan,
            &SensorNoise::typical(),
            3,
        )
        .unwrap();
        let worse = Motor::new(
            MotorParams::default().with("c_ext", 2.0e-8).unwrap(),
            EffectSet::empty(),
        );
        let base = CostModel::new(&dataset(data.clone()), CostOptions::default())
            .unwrap()
            .evaluate(&worse, &solver);
        data[1].weight = 3.0;
        data[1].channel_weights.insert("flow1".into(), 2.0);
        let weighted = CostModel::new(&dataset(data), CostOptions::default())
            .unwrap()
            .evaluate(&worse, &solver);
        for (a, b) in base.channels.iter().zip(&weighted.channels) {
            let factor = match (a.experiment_kind, a.channel) {
                (Kind::PressureRamp, Quantity::Flow1) => 6.0,
                (Kind::PressureRamp, _) => 3.0,
                _ => 1.0,
            };
            assert_eq!(b.weight, factor);
            assert!(
                (b.cost - factor * a.cost).abs() <= 1e-12 * b.cost,
                "{a:?} {b:?}"
            );
        }
    }

    #[test]
    fn residuals_agree_with_the_cost() {
        let solver = DefaultSolver::default();
        let data = synthesize(
            &Motor::default_motor(),
            &solver,
            &short_plan(),
            &SensorNoise::typical(),
            4,
        )
        .unwrap();
        let model = CostModel::new(&dataset(data), CostOptions::default()).unwrap();
        let m = Motor::new(
            MotorParams::default().with("t_coulomb", 0.03).unwrap(),
            EffectSet::empty(),
        );
        let cost = model.evaluate(&m, &solver);
        let res = model.residuals(&m, &solver).unwrap();
        assert_eq!(res.len(), cost.channels.len());
        for (r, c) in res.iter().zip(&cost.channels) {
            let ms = r.normalized.iter().map(|v| v * v).sum::<f64>() / r.normalized.len() as f64;
            assert!((r.weight * ms - c.cost).abs() <= 1e-12 * c.cost.max(1e-300));
            assert_eq!(r.x.len(), c.n);
        }
        // The counters are for evaluate only.
        assert_eq!(model.evaluations(), 1);
    }

    #[test]
    fn cost_model_is_sync() {
        fn assert_sync<T: Sync + Send>() {}
        assert_sync::<CostModel>();
    }
}
