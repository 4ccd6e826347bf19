//! Missing-physics diagnosis (SPEC §5, §6; `vanefit diagnose`): locate where the base model
//! misses the data, name the physics it leaves out, model it, refit, and show the gain.
//!
//! # What is fitted
//!
//! Every fit of a diagnosis maximises the Gaussian likelihood of the RECORDED rows
//! ([`target`]): χ² = Σ((simulated − recorded)/σ)² over the rows the cost compares, σ each
//! channel's noise estimated from the data alone (second differences). Not the project's
//! cost J against the reference polynomials: their σ also holds the polynomials' lack of
//! fit (threefold for a ramp's speed), and their systematic error is a signal that a fit to
//! one experiment can chase; both would make a correct model look wrong and separate fits
//! "disagree" on clean data. The recorded inputs of transients are replaced by their smooth
//! in time (errors in variables, [`target::smooth_inputs`]). `cost` in the output is J at the
//! fitted parameters, as `vanefit fit` reports it.
//!
//! # Procedure
//!
//! 1. **Baseline.** The base model's default parameters (SPEC §1.7: six conductances,
//!    `t_coulomb`, `visc`) are fitted by multi-start Nelder–Mead, one start at the rig's
//!    nominal motor plus `starts − 1` Latin-hypercube starts. A warm refit of the same model
//!    (the "null refit", same budget as a candidate) guards against crediting a candidate
//!    with what is only further convergence.
//! 2. **Locate** ([`analysis`]): residuals against the recorded data in noise units;
//!    regional bias, runs and trend per channel; the noise ratio.
//! 3. **Concealment.** A plain fit can hide a missing effect by shifting the base
//!    parameters. Each experiment is fitted alone (warm from the baseline): if the
//!    parameters agree across experiments, the joint χ² exceeds the sum of the separate
//!    ones by a χ²(k·(E − 1)) amount only (likelihood-ratio/Chow test; k estimated
//!    parameters, E experiments; the df is an upper bound when some parameter is not
//!    identifiable from one experiment alone, which makes the test conservative; rejected
//!    at p < [`CONCEALMENT_ALPHA`]). And each experiment is predicted from a fit to the
//!    others (held-out noise ratio), for the baseline, the best candidates and the selected
//!    model. The test is reported; it does not decide `mismatch` (ΔBIC does, and is more
//!    sensitive: an effect can fail this test and still be found by its refit).
//! 4. **Candidates.** Each applicable catalog effect is switched on and the model refitted
//!    warm from the baseline optimum (given starts: the effect "off", at its nested value,
//!    and at points of its search range). `valve_dynamics` is never a candidate here: the
//!    recorded port-1 pressure already is the valve's output and drives the simulation,
//!    and the ramps are orders of magnitude slower than a valve. `sensor_lag` is a
//!    candidate only when a transient experiment is present. Candidates are ranked by
//!    ΔBIC = BIC(candidate) − BIC(baseline), BIC = χ² + k·ln n (n compared points, k
//!    estimated parameters), and by held-out prediction. When the best single effect is
//!    significant, it is paired with the next three candidates.
//! 5. **Uncatalogued** ([`discover`]): sparse regression of the misfit over a library of
//!    terms in each balance, on the baseline and on the best catalog model; a term that the
//!    linearised regression supports is put into the model ([`crate::model::motor::ExtraTerm`])
//!    and refitted.
//! 6. **Selection.** Among the baseline and every refitted model, the simplest one within
//!    [`SELECT_DELTA_BIC`] = 10 of the lowest BIC is chosen, simplicity ordered baseline <
//!    one catalog effect < two catalog effects < an uncatalogued term < catalog effect(s)
//!    plus an uncatalogued term. ΔBIC < −10 is "very strong" evidence on Kass and
//!    Raftery's scale (a likelihood ratio above e⁵ ≈ 150 after the ln n penalty per
//!    parameter), so with ~3800 points a one-parameter effect must lower χ² by more than
//!    18: under the null hypothesis a χ²(1) exceeds that with probability 2e-5. A chosen
//!    model of several parts is checked by backward elimination: each part's removal is
//!    refitted warm from the chosen optimum and the part is dropped unless removing it costs
//!    more than 10. `mismatch` is true when something is selected, or when the baseline's
//!    noise ratio exceeds what noise alone explains ([`noise_ratio_limit`]).

pub mod analysis;
pub mod discover;
pub mod fitting;
pub mod stats;
pub mod target;

use crate::data::dataset::{Dataset, Kind};
use crate::data::fitfile::FitFile;
use crate::estimate::engine::Engine;
use crate::estimate::space::DEFAULT_ESTIMATED;
use crate::model::effects::{Category, Effect, EffectSet};
use crate::model::motor::ExtraTerm;
use crate::model::params::{spec, MotorParams};
use crate::numerics::ode::DiffsolBdf;
use crate::objective::cost::{CostModel, CostOptions};
use analysis::{ChannelData, Location};
use fitting::{FitJob, Fitted};
use serde_json::{json, Value};

use std::time::Instant;
use target::Target;

/// A refitted model must beat the simpler ones by this much BIC to be selected.
pub const SELECT_DELTA_BIC: f64 = 10.0;
/// Significance level of the concealment test.
pub const CONCEALMENT_ALPHA: f64 = 1e-3;
/// The format of `diagnosis.json`.
pub const FORMAT: &str = "vanefit.diagnosis/1";

/// How thorough a diagnosis is.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Starts of the baseline fit (≥ 1; the first is the nominal motor).
    pub starts: usize,
    pub seed: u64,
    /// Worker threads (None: one per core). Results do not depend on it.
    pub threads: Option<usize>,
    /// Iteration budget per start of the baseline fit.
    pub baseline_iters: u64,
    /// Iteration budget per start of every warm refit.
    pub refit_iters: u64,
    /// Given starts per candidate: the effect off, then points of its search range.
    pub effect_starts: usize,
    /// Try pairs whenever the best single effect is significant (otherwise only when its
    /// residuals still show structure).
    pub pairs_always: bool,
    /// Fit experiments separately and predict each from the others.
    pub concealment: bool,
    /// Held-out prediction of this many best candidates (plus the selected model).
    pub held_out_top: usize,
    /// Look for uncatalogued terms.
    pub discover: bool,
    /// Progress lines on stderr.
    pub progress: bool,
}

impl DiagnoseOptions {
    /// The command line's settings.
    pub fn full(starts: usize, seed: u64) -> Self {
        Self {
            starts: starts.max(1),
            seed,
            threads: None,
            baseline_iters: 3000,
            refit_iters: 2000,
            effect_starts: 3,
            pairs_always: true,
            concealment: true,
            held_out_top: 3,
            discover: true,
            progress: true,
        }
    }

    /// Reduced effort for tests: one baseline start, a smaller refit budget, pairs only when
    /// needed, held-out prediction of the selected model only.
    pub fn quick(seed: u64) -> Self {
        Self {
            starts: 1,
            baseline_iters: 3000,
            refit_iters: 1500,
            effect_starts: 3,
            pairs_always: false,
            held_out_top: 0,
            progress: false,
            ..Self::full(1, seed)
        }
    }
}

/// What kind of model a refit is (the order is the simplicity order of the selection).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum ModelKind {
    Baseline,
    Single,
    Pair,
    Uncatalogued,
    CatalogAndUncatalogued,
}

/// A refitted model with its scores.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Effect id, "a+b" for a pair, "uncatalogued" or "a+uncatalogued".
    pub label: String,
    pub kind: ModelKind,
    pub fitted: Fitted,
    /// BIC(this) − BIC(baseline).
    pub delta_bic: f64,
    /// Noise ratio against the data (see [`analysis`]).
    pub noise_ratio: f64,
    /// √(mean over experiments of the squared noise ratio of each experiment predicted by
    /// a fit to the others), when computed.
    pub held_out: Option<f64>,
}

/// One experiment in the concealment test.
#[derive(Debug, Clone)]
pub struct ExperimentCheck {
    pub kind: Kind,
    pub file: String,
    /// Noise ratio of the joint baseline on this experiment.
    pub joint_ratio: f64,
    /// Noise ratio of the base model fitted to this experiment alone.
    pub alone_ratio: f64,
    /// [`noise_ratio_limit`] of this experiment's channels: below it, the separate fit
    /// "looks acceptable".
    pub alone_limit: f64,
    /// χ² (against the references) of the fit to this experiment alone.
    pub alone_chi2: f64,
    /// The separate fit's parameters.
    pub alone_params: MotorParams,
    /// Noise ratio of this experiment predicted by the base model fitted to the others.
    pub held_out_ratio: Option<f64>,
}

/// Separate against joint fits.
#[derive(Debug, Clone)]
pub struct Concealment {
    pub experiments: Vec<ExperimentCheck>,
    /// χ²_joint − Σ χ²_alone.
    pub lr: f64,
    pub df: f64,
    pub p_value: f64,
}

impl Concealment {
    /// The parameters disagree between experiments (p below [`CONCEALMENT_ALPHA`]).
    pub fn disagree(&self) -> bool {
        self.p_value < CONCEALMENT_ALPHA
    }
}

/// One selected extension (SPEC §6 `selected`).
#[derive(Debug, Clone)]
pub struct Selected {
    /// Catalog id, or "uncatalogued".
    pub effect: String,
    pub category: Category,
    /// Parameter names, SI values and units.
    pub parameters: Vec<(String, f64, String)>,
    /// BIC of the model with this entry minus BIC without it (entries in order: the deltas
    /// add up to the extended model's ΔBIC against the baseline).
    pub delta_bic: f64,
    /// The discovered term (uncatalogued only).
    pub term: Option<ExtraTerm>,
}

/// A catalog effect that was not tried, and why.
#[derive(Debug, Clone)]
pub struct Skipped {
    pub effect: Effect,
    pub reason: String,
}

/// The outcome of a diagnosis.
#[derive(Debug, Clone)]
pub struct Diagnosis {
    pub dataset: String,
    pub p_atm_pa: f64,
    pub mismatch: bool,
    pub baseline: Candidate,
    /// Channels of the baseline against the data.
    pub baseline_channels: Vec<ChannelData>,
    pub locations: Vec<Location>,
    /// Every refitted model, best ΔBIC first.
    pub candidates: Vec<Candidate>,
    pub skipped: Vec<Skipped>,
    pub selected: Vec<Selected>,
    /// The chosen model (the baseline when nothing is selected).
    pub extended: Candidate,
    pub extended_channels: Vec<ChannelData>,
    /// Locations left after the extension.
    pub extended_locations: Vec<Location>,
    pub concealment: Option<Concealment>,
    /// Regression of the baseline's misfit over the term library.
    pub regression: Option<discover::Regression>,
    /// Noise ratio that noise alone would exceed with probability 0.1% (see
    /// [`noise_ratio_limit`]).
    pub noise_ratio_limit: f64,
    /// Names estimated in the baseline.
    pub estimated: Vec<String>,
    /// How the recorded inputs of transient experiments were smoothed.
    pub inputs: Vec<target::InputSmoothing>,
    /// (phase, seconds).
    pub phases: Vec<(String, f64)>,
    pub wall_s: f64,
    pub threads: usize,
}

impl Diagnosis {
    /// Noise ratio of the baseline and of the extended model.
    pub fn noise_ratios(&self) -> (f64, f64) {
        (self.baseline.noise_ratio, self.extended.noise_ratio)
    }

    /// Total ΔBIC of the extended model against the baseline.
    pub fn delta_bic(&self) -> f64 {
        self.extended.delta_bic
    }

    /// A candidate by label.
    pub fn candidate(&self, label: &str) -> Option<&Candidate> {
        self.candidates.iter().find(|c| c.label == label)
    }
}

/// The noise ratio that a correct model exceeds with probability ≈ 0.1%: with C channels of
/// n_c points and Gaussian noise, each channel's mean square is ≈ χ²(n_c)/n_c (variance
/// 2/n_c), so the squared ratio (their mean) has standard deviation √(2·Σ1/n_c)/C; the
/// limit is √(1 + 3.09·that) (≈ 1.08 for the paper's three experiments, ≈ 1.05 for one
/// 600-row transient). The spread of the estimated σ is left out, which makes the limit
/// strict: it is also the test that a fit "looks acceptable".
pub fn noise_ratio_limit(channels: &[ChannelData]) -> f64 {
    let c = channels.len().max(1) as f64;
    let var: f64 = channels
        .iter()
        .map(|ch| 2.0 / ch.x.len().max(1) as f64)
        .sum();
    (1.0 + 3.09 * var.sqrt() / c).sqrt()
}

/// The catalog effects tried on a dataset, and those skipped with the reason.
pub fn applicable_effects(ds: &Dataset) -> (Vec<Effect>, Vec<Skipped>) {
    let transient = ds
        .experiments
        .iter()
        .any(|e| matches!(e.kind, Kind::PressureRamp | Kind::OutletThrottle));
    let mut tried = Vec::new();
    let mut skipped = Vec::new();
    for e in Effect::ALL {
        match e {
            Effect::ValveDynamics => skipped.push(Skipped {
                effect: e,
                reason: "the recorded port-1 pressure is the valve's output and drives the \
                         simulation; the datasheet and outlet-throttle supplies are constant \
                         and the pressure ramp is ~10^3 times slower than a valve, so valve \
                         dynamics cannot show in these experiments (and the model has no \
                         valve)"
                    .into(),
            }),
            Effect::SensorLag if !transient => skipped.push(Skipped {
                effect: e,
                reason: "a sensor lag shows only in transient recordings; this dataset has \
                         steady-state experiments only"
                    .into(),
            }),
            _ => tried.push(e),
        }
    }
    (tried, skipped)
}

/// The "off" value of an effect parameter (the nested base model, or as near as the search
/// range allows), given the base parameters.
fn off_value(name: &str, base: &MotorParams) -> f64 {
    let s = spec(name).expect("effect parameter");
    match name {
        "t_static" => base.t_coulomb().clamp(s.search.0, s.search.1),
        "w_stribeck" => s.default,
        "w_seal" => s.default,
        "w_fill" => s.search.1,
        _ => s.search.0,
    }
}

/// Start points of a candidate: `base` with the effect off, then at positions u of the
/// effects' search ranges (log-spaced for positive parameters).
fn effect_starts(effects: &[Effect], base: &MotorParams, n: usize) -> Vec<MotorParams> {
    let mut out = Vec::new();
    let set = |u: Option<f64>| {
        let mut p = base.clone();
        for e in effects {
            for name in e.parameters() {
                let s = spec(name).expect("declared");
                let v = match u {
                    None => off_value(name, base),
                    Some(u) => {
                        let (lo, hi) = s.search;
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

fn names_for(effects: &EffectSet) -> Vec<String> {
    let mut names: Vec<String> = DEFAULT_ESTIMATED.iter().map(|s| s.to_string()).collect();
    for e in effects.iter() {
        names.extend(e.parameters().iter().map(|s| s.to_string()));
    }
    names
}

/// Runs a diagnosis of a dataset.
pub fn diagnose(recorded: &Dataset, opts: &DiagnoseOptions) -> Result<Diagnosis, String> {
    let t0 = Instant::now();
    let (smoothed, inputs) = target::smooth_inputs(recorded);
    let ds = &smoothed;
    let mut phases: Vec<(String, f64)> = Vec::new();
    let mut phase_start = Instant::now();
    let say = |msg: &str| {
        if opts.progress {
            eprintln!("[{:6.1} s] {msg}", t0.elapsed().as_secs_f64());
        }
    };
    let mut end_phase = |name: &str, phases: &mut Vec<(String, f64)>| {
        phases.push((name.to_string(), phase_start.elapsed().as_secs_f64()));
        phase_start = Instant::now();
    };
    let solver = DiffsolBdf::default();
    let cost = CostModel::new(ds, CostOptions::default()).map_err(|e| e.to_string())?;
    let target = Target::new(&cost, ds)?;
    let nominal = ds.nominal_params().map_err(|e| e.to_string())?;
    let base_names = names_for(&EffectSet::empty());
    // The one thread pool of the diagnosis; every fit and regression runs on it.
    let engine = Engine::with_threads(opts.threads).map_err(|e| e.to_string())?;
    let threads = &engine;

    // 1. Baseline.
    say(&format!(
        "baseline fit: {} start(s), {} points in {} channels",
        opts.starts,
        cost.n_points(),
        cost.n_channels()
    ));
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
    let mut baseline = fitting::run_job(&cost, &target, &base_job, threads)?;
    say(&format!(
        "baseline cost {:.4}, chi2 {:.1} ({} evaluations, {:.1} s)",
        baseline.cost, baseline.chi2, baseline.evaluations, baseline.wall_s
    ));
    end_phase("baseline fit", &mut phases);

    // 2. Candidates (and the null refit) warm from the baseline.
    let (tried, skipped) = applicable_effects(ds);
    let mut jobs = vec![FitJob {
        label: "null refit".into(),
        starts: vec![baseline.params.clone()],
        lhs: 0,
        max_iters: opts.refit_iters,
        ..base_job.clone()
    }];
    for e in &tried {
        let effects = EffectSet::empty().with(*e);
        jobs.push(FitJob {
            label: e.id().into(),
            names: names_for(&effects),
            starts: effect_starts(&[*e], &baseline.params, opts.effect_starts),
            effects,
            extra: Vec::new(),
            lhs: 0,
            max_iters: opts.refit_iters,
            seed: opts.seed,
        });
    }
    say(&format!(
        "refitting {} candidate(s) warm from the baseline: {}",
        tried.len(),
        tried.iter().map(|e| e.id()).collect::<Vec<_>>().join(", ")
    ));
    let results = fitting::run_jobs(&cost, &target, &jobs, threads);
    let mut fitted: Vec<(FitJob, Fitted)> = Vec::new();
    for (job, r) in jobs.into_iter().zip(results) {
        match r {
            Ok(f) if job.label == "null refit" => {
                if f.cost < baseline.cost {
                    say(&format!(
                        "null refit improved the baseline: cost {:.4} -> {:.4}",
                        baseline.cost, f.cost
                    ));
                    baseline = f;
                }
            }
            Ok(f) => fitted.push((job, f)),
            Err(e) => say(&format!("candidate failed: {e}")),
        }
    }
    end_phase("candidate refits", &mut phases);

    let base_channels = analysis::channel_data(&cost, &target, &baseline.motor(), &solver)?;
    let limit = noise_ratio_limit(&base_channels);
    let base_ratio = analysis::noise_ratio(&base_channels);
    let locations = analysis::locate(&base_channels, ds.p_atm_pa);
    say(&format!(
        "baseline noise ratio {base_ratio:.3} (limit {limit:.3}); {} location(s)",
        locations.len()
    ));
    let base_bic = baseline.bic();
    let score = |label: &str, kind: ModelKind, f: Fitted| -> Result<Candidate, String> {
        let ch = analysis::channel_data(&cost, &target, &f.motor(), &solver)?;
        Ok(Candidate {
            label: label.to_string(),
            kind,
            delta_bic: f.bic() - base_bic,
            noise_ratio: analysis::noise_ratio(&ch),
            fitted: f,
            held_out: None,
        })
    };
    let mut candidates: Vec<Candidate> = Vec::new();
    for (job, f) in &fitted {
        candidates.push(score(&job.label, ModelKind::Single, f.clone())?);
    }
    candidates.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    for c in &candidates {
        say(&format!(
            "  {:<28} dBIC {:>9.1}  noise ratio {:.3}  ({} evaluations, {:.1} s)",
            c.label, c.delta_bic, c.noise_ratio, c.fitted.evaluations, c.fitted.wall_s
        ));
    }

    // 3. Pairs.
    let singles: Vec<Candidate> = candidates.clone();
    if let Some(best) = singles.first().filter(|b| b.delta_bic < -SELECT_DELTA_BIC) {
        let best_channels = analysis::channel_data(&cost, &target, &best.fitted.motor(), &solver)?;
        let structure = analysis::noise_ratio(&best_channels) > limit
            || !analysis::locate(&best_channels, ds.p_atm_pa).is_empty();
        if opts.pairs_always || structure {
            let mut pair_jobs = Vec::new();
            for other in singles.iter().skip(1).take(3) {
                let (a, b) = (
                    best.fitted.effects.iter().next().expect("one effect"),
                    other.fitted.effects.iter().next().expect("one effect"),
                );
                let effects = EffectSet::empty().with(a).with(b);
                let warm = &best.fitted.params;
                let other_set = EffectSet::empty().with(b);
                let mut starts = vec![with_effect_params(warm, &other.fitted.params, &other_set)];
                starts.extend(effect_starts(&[b], warm, 1));
                pair_jobs.push(FitJob {
                    label: label_of(&effects, 0).0,
                    names: names_for(&effects),
                    effects,
                    extra: Vec::new(),
                    starts,
                    lhs: 0,
                    max_iters: opts.refit_iters,
                    seed: opts.seed,
                });
            }
            say(&format!("refitting {} pair(s)", pair_jobs.len()));
            for (job, r) in pair_jobs
                .iter()
                .zip(fitting::run_jobs(&cost, &target, &pair_jobs, threads))
            {
                match r {
                    Ok(f) => {
                        let c = score(&job.label, ModelKind::Pair, f)?;
                        say(&format!(
                            "  {:<28} dBIC {:>9.1}  noise ratio {:.3}",
                            c.label, c.delta_bic, c.noise_ratio
                        ));
                        candidates.push(c);
                    }
                    Err(e) => say(&format!("pair failed: {e}")),
                }
            }
        }
    }
    end_phase("pairs", &mut phases);

    // 4. Uncatalogued terms.
    let mut regression = None;
    if opts.discover {
        say("sparse regression of the baseline misfit over the term library");
        let reg = discover::regress(&cost, &target, &baseline, &base_names, threads)?;
        let mut disc_jobs = Vec::new();
        if let Some(first) = reg.selected.first() {
            for t in &reg.selected {
                say(&format!(
                    "  proposed {} (linearised dBIC {:.1})",
                    discover::formula(&t.term),
                    t.delta_bic
                ));
            }
            disc_jobs.push((
                ModelKind::Uncatalogued,
                FitJob {
                    label: "uncatalogued".into(),
                    extra: vec![first.term],
                    starts: vec![baseline.params.clone()],
                    ..base_job.clone()
                },
            ));
            if reg.selected.len() > 1 {
                disc_jobs.push((
                    ModelKind::Uncatalogued,
                    FitJob {
                        label: "uncatalogued (2 terms)".into(),
                        extra: reg.selected.iter().map(|t| t.term).collect(),
                        starts: vec![baseline.params.clone()],
                        ..base_job.clone()
                    },
                ));
            }
        }
        // On top of the best catalog model, when it is significant.
        let best_catalog = candidates
            .iter()
            .filter(|c| c.kind <= ModelKind::Pair)
            .min_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic))
            .filter(|c| c.delta_bic < -SELECT_DELTA_BIC)
            .cloned();
        if let Some(bc) = &best_catalog {
            let names = names_for(&bc.fitted.effects);
            let reg2 = discover::regress(&cost, &target, &bc.fitted, &names, threads)?;
            if let Some(first) = reg2.selected.first() {
                say(&format!(
                    "  on top of {}: proposed {} (linearised dBIC {:.1})",
                    bc.label,
                    discover::formula(&first.term),
                    first.delta_bic
                ));
                disc_jobs.push((
                    ModelKind::CatalogAndUncatalogued,
                    FitJob {
                        label: label_of(&bc.fitted.effects, 1).0,
                        effects: bc.fitted.effects.clone(),
                        extra: vec![first.term],
                        names,
                        starts: vec![bc.fitted.params.clone()],
                        lhs: 0,
                        max_iters: opts.refit_iters,
                        seed: opts.seed,
                    },
                ));
            }
        }
        let only: Vec<FitJob> = disc_jobs.iter().map(|(_, j)| j.clone()).collect();
        if !only.is_empty() {
            say(&format!(
                "refitting {} model(s) with discovered terms",
                only.len()
            ));
        }
        for ((kind, job), r) in disc_jobs
            .iter()
            .zip(fitting::run_jobs(&cost, &target, &only, threads))
        {
            match r {
                Ok(f) => {
                    let c = score(&job.label, *kind, f)?;
                    say(&format!(
                        "  {:<28} dBIC {:>9.1}  noise ratio {:.3}",
                        c.label, c.delta_bic, c.noise_ratio
                    ));
                    candidates.push(c);
                }
                Err(e) => say(&format!("discovered-term refit failed: {e}")),
            }
        }
        regression = Some(reg);
    }
    end_phase("uncatalogued search", &mut phases);

    // 5. Selection: the simplest model within SELECT_DELTA_BIC of the best.
    candidates.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
    let mut baseline_c = Candidate {
        label: "baseline".into(),
        kind: ModelKind::Baseline,
        fitted: baseline.clone(),
        delta_bic: 0.0,
        noise_ratio: base_ratio,
        held_out: None,
    };
    let mut chosen = choose(&candidates);
    // Backward elimination: a model of several parts keeps each part only if dropping it,
    // refitted warm from the same optimum (so with the same convergence), costs more than
    // SELECT_DELTA_BIC. A pair can otherwise "win" by converging better than its single.
    while let Some(c) = chosen.clone().filter(|c| parts(&c.fitted) >= 2) {
        let mut sub_jobs = Vec::new();
        let effects: Vec<Effect> = c.fitted.effects.iter().collect();
        for drop in 0..parts(&c.fitted) {
            let keep_effects: EffectSet = effects
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != drop)
                .map(|(_, e)| *e)
                .collect();
            let keep_terms: Vec<ExtraTerm> = c
                .fitted
                .extra
                .iter()
                .enumerate()
                .filter(|(i, _)| i + effects.len() != drop)
                .map(|(_, t)| *t)
                .collect();
            let (label, _) = label_of(&keep_effects, keep_terms.len());
            sub_jobs.push(FitJob {
                label,
                names: names_for(&keep_effects),
                starts: vec![c.fitted.params.clone()],
                effects: keep_effects,
                extra: keep_terms,
                lhs: 0,
                max_iters: opts.refit_iters,
                seed: opts.seed,
            });
        }
        say(&format!(
            "checking {}: refitting each part's removal warm from its optimum",
            c.label
        ));
        let mut subs = Vec::new();
        for (job, r) in sub_jobs
            .iter()
            .zip(fitting::run_jobs(&cost, &target, &sub_jobs, threads))
        {
            match r {
                Ok(f) => {
                    let (label, kind) = label_of(&f.effects, f.extra.len());
                    let sub = score(&label, kind, f)?;
                    say(&format!(
                        "  {:<28} dBIC {:>9.1}  noise ratio {:.3}",
                        sub.label, sub.delta_bic, sub.noise_ratio
                    ));
                    subs.push(sub);
                }
                Err(e) => say(&format!("{} failed: {e}", job.label)),
            }
        }
        for sub in &subs {
            match candidates.iter_mut().find(|x| x.label == sub.label) {
                Some(x) if x.delta_bic <= sub.delta_bic => {}
                Some(x) => *x = sub.clone(),
                None => candidates.push(sub.clone()),
            }
        }
        candidates.sort_by(|a, b| a.delta_bic.total_cmp(&b.delta_bic));
        let next = choose(&candidates);
        if next.as_ref().map(|n| &n.label) == Some(&c.label) {
            break;
        }
        chosen = next;
    }

    // 6. Concealment and held-out prediction.
    let mut concealment = None;
    let n_exp = ds.experiments.len();
    if opts.concealment && n_exp >= 2 {
        say("concealment: each experiment fitted alone and predicted from the others");
        let only: Vec<Dataset> = (0..n_exp).map(|i| subset(ds, |j| j == i)).collect();
        let without: Vec<Dataset> = (0..n_exp).map(|i| subset(ds, |j| j != i)).collect();
        let cost_only: Vec<CostModel> = only
            .iter()
            .map(|d| CostModel::new(d, CostOptions::default()).map_err(|e| e.to_string()))
            .collect::<Result<_, _>>()?;
        let cost_without: Vec<CostModel> = without
            .iter()
            .map(|d| CostModel::new(d, CostOptions::default()).map_err(|e| e.to_string()))
            .collect::<Result<_, _>>()?;
        let target_only: Vec<Target> = cost_only
            .iter()
            .zip(&only)
            .map(|(c, d)| Target::new(c, d))
            .collect::<Result<_, _>>()?;
        let target_without: Vec<Target> = cost_without
            .iter()
            .zip(&without)
            .map(|(c, d)| Target::new(c, d))
            .collect::<Result<_, _>>()?;
        // Models whose held-out prediction is wanted: baseline, the top candidates, the
        // chosen one.
        let mut held: Vec<Candidate> = vec![baseline_c.clone()];
        for c in candidates.iter().take(opts.held_out_top) {
            held.push(c.clone());
        }
        if let Some(c) = &chosen {
            if !held.iter().any(|h| h.label == c.label) {
                held.push(c.clone());
            }
        }
        // Jobs: (model index or none for "alone", experiment index, job).
        let mut tasks: Vec<(Option<usize>, usize, FitJob)> = Vec::new();
        for i in 0..n_exp {
            tasks.push((
                None,
                i,
                FitJob {
                    label: format!("alone {}", ds.experiments[i].file),
                    starts: vec![baseline.params.clone()],
                    lhs: 0,
                    max_iters: opts.refit_iters,
                    ..base_job.clone()
                },
            ));
        }
        for (m, c) in held.iter().enumerate() {
            for i in 0..n_exp {
                tasks.push((
                    Some(m),
                    i,
                    FitJob {
                        label: format!("{} without {}", c.label, ds.experiments[i].file),
                        effects: c.fitted.effects.clone(),
                        extra: c.fitted.extra.clone(),
                        names: names_for(&c.fitted.effects),
                        starts: vec![c.fitted.params.clone()],
                        lhs: 0,
                        max_iters: opts.refit_iters,
                        seed: opts.seed,
                    },
                ));
            }
        }
        let results = threads.map(&tasks, |(m, i, job)| {
            let (c, t) = if m.is_none() {
                (&cost_only[*i], &target_only[*i])
            } else {
                (&cost_without[*i], &target_without[*i])
            };
            fitting::run_job(c, t, job, threads)
        });
        let mut checks: Vec<ExperimentCheck> = Vec::new();
        let mut held_ms: Vec<Vec<f64>> = vec![Vec::new(); held.len()];
        for ((m, i, _), r) in tasks.iter().zip(results) {
            let f = r?;
            let ex = &ds.experiments[*i];
            match m {
                None => {
                    let ch = analysis::channel_data(
                        &cost_only[*i],
                        &target_only[*i],
                        &f.motor(),
                        &solver,
                    )?;
                    let joint: Vec<ChannelData> = base_channels
                        .iter()
                        .filter(|c| c.file == ex.file)
                        .cloned()
                        .collect();
                    checks.push(ExperimentCheck {
                        kind: ex.kind,
                        file: ex.file.clone(),
                        joint_ratio: analysis::noise_ratio(&joint),
                        alone_ratio: analysis::noise_ratio(&ch),
                        alone_limit: noise_ratio_limit(&ch),
                        alone_chi2: f.chi2,
                        alone_params: f.params.clone(),
                        held_out_ratio: None,
                    });
                }
                Some(m) => {
                    let ch = analysis::channel_data(
                        &cost_only[*i],
                        &target_only[*i],
                        &f.motor(),
                        &solver,
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
            } else if let Some(x) = candidates.iter_mut().find(|x| x.label == c.label) {
                x.held_out = Some(v);
            }
        }
        let sum_alone: f64 = checks.iter().map(|c| c.alone_chi2).sum();
        let lr = (baseline.chi2 - sum_alone).max(0.0);
        let df = (base_names.len() * (n_exp - 1)) as f64;
        let p_value = stats::chi2_sf(lr, df);
        say(&format!(
            "concealment: chi2 joint {:.1} vs separate {:.1}: LR {lr:.1}, df {df}, p {p_value:.2e}",
            baseline.chi2, sum_alone
        ));
        concealment = Some(Concealment {
            experiments: checks,
            lr,
            df,
            p_value,
        });
    }
    end_phase("concealment and held-out prediction", &mut phases);

    // 7. The extended model.
    let chosen = chosen.map(|c| {
        candidates
            .iter()
            .find(|x| x.label == c.label)
            .cloned()
            .unwrap_or(c)
    });
    let selected = match &chosen {
        Some(c) => selected_entries(c, &candidates),
        None => Vec::new(),
    };
    let extended = chosen.clone().unwrap_or_else(|| baseline_c.clone());
    let extended_channels =
        analysis::channel_data(&cost, &target, &extended.fitted.motor(), &solver)?;
    let extended_locations = analysis::locate(&extended_channels, ds.p_atm_pa);
    let mismatch = !selected.is_empty() || base_ratio > limit;
    end_phase("selection", &mut phases);
    let d = Diagnosis {
        dataset: ds.name.clone(),
        p_atm_pa: ds.p_atm_pa,
        mismatch,
        baseline: baseline_c,
        baseline_channels: base_channels,
        locations,
        candidates,
        skipped,
        selected,
        extended,
        extended_channels,
        extended_locations,
        concealment,
        regression,
        noise_ratio_limit: limit,
        estimated: base_names,
        inputs,
        phases,
        wall_s: t0.elapsed().as_secs_f64(),
        threads: threads.threads(),
    };
    say(&format!("done in {:.1} s", d.wall_s));
    Ok(d)
}

/// The simplest model within [`SELECT_DELTA_BIC`] of the lowest BIC, or `None` when no
/// model beats the baseline by [`SELECT_DELTA_BIC`].
fn choose(candidates: &[Candidate]) -> Option<Candidate> {
    let best = candidates
        .iter()
        .map(|c| c.delta_bic)
        .fold(0.0f64, f64::min);
    if best + SELECT_DELTA_BIC >= 0.0 {
        return None;
    }
    candidates
        .iter()
        .filter(|c| c.delta_bic <= best + SELECT_DELTA_BIC)
        .min_by(|a, b| {
            a.kind
                .cmp(&b.kind)
                .then(a.delta_bic.total_cmp(&b.delta_bic))
        })
        .cloned()
}

/// Number of parts (catalog effects and discovered terms) of a model.
fn parts(f: &Fitted) -> usize {
    f.effects.iter().count() + f.extra.len()
}

/// Label and kind of a model made of catalog effects and `terms` discovered terms.
fn label_of(effects: &EffectSet, terms: usize) -> (String, ModelKind) {
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
fn subset(ds: &Dataset, keep: impl Fn(usize) -> bool) -> Dataset {
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

/// The `selected` entries of a chosen model. Entries come in order (catalog effects by
/// their single-effect ΔBIC, then discovered terms); each entry's ΔBIC is the BIC of the
/// model up to and including it minus the BIC of the model before it (taken from the
/// refitted nested models), so the entries add up to the extended model's ΔBIC.
fn selected_entries(chosen: &Candidate, all: &[Candidate]) -> Vec<Selected> {
    let single_delta = |e: Effect| {
        all.iter()
            .find(|c| c.kind == ModelKind::Single && c.label == e.id())
            .map_or(0.0, |c| c.delta_bic)
    };
    let mut effects: Vec<Effect> = chosen.fitted.effects.iter().collect();
    effects.sort_by(|a, b| single_delta(*a).total_cmp(&single_delta(*b)));
    let n = effects.len() + chosen.fitted.extra.len();
    // ΔBIC of the nested model made of the first i entries.
    let nested = |i: usize| -> f64 {
        if i == n {
            return chosen.delta_bic;
        }
        let set: EffectSet = effects.iter().take(i).copied().collect();
        let terms = i.saturating_sub(effects.len());
        all.iter()
            .find(|c| c.fitted.effects == set && c.fitted.extra.len() == terms)
            .map_or(chosen.delta_bic, |c| c.delta_bic)
    };
    let mut out = Vec::new();
    let mut previous = 0.0;
    for i in 0..n {
        let now = nested(i + 1);
        let delta_bic = now - previous;
        previous = now;
        if let Some(e) = effects.get(i) {
            out.push(Selected {
                effect: e.id().to_string(),
                category: e.category(),
                parameters: e
                    .parameters()
                    .iter()
                    .map(|n| {
                        (
                            n.to_string(),
                            chosen.fitted.params.get(n).unwrap_or(f64::NAN),
                            spec(n).map_or(String::new(), |s| s.unit.to_string()),
                        )
                    })
                    .collect(),
                delta_bic,
                term: None,
            });
        } else {
            let t = chosen.fitted.extra[i - effects.len()];
            out.push(Selected {
                effect: "uncatalogued".into(),
                category: discover::category(&t),
                parameters: vec![(
                    "coefficient".into(),
                    t.coefficient,
                    discover::coefficient_unit(&t),
                )],
                delta_bic,
                term: Some(t),
            });
        }
    }
    out
}

/// `diagnosis.json` (SPEC §6). Uncatalogued entries of `selected` also carry `balance`,
/// `feature` and `formula`.
pub fn to_json(d: &Diagnosis) -> Value {
    let loc = |l: &Location| {
        json!({
            "experiment": l.kind.id(),
            "channel": l.column,
            "x_range": [l.x_range[0], l.x_range[1]],
            "severity": round(l.severity),
        })
    };
    let candidates: Vec<Value> = d
        .candidates
        .iter()
        .filter(|c| matches!(c.kind, ModelKind::Single | ModelKind::Uncatalogued))
        .filter(|c| c.label != "uncatalogued (2 terms)")
        .map(|c| {
            json!({
                "effect": c.label,
                "cost": c.fitted.cost,
                "delta_bic": round(c.delta_bic),
            })
        })
        .collect();
    let selected: Vec<Value> = d
        .selected
        .iter()
        .map(|s| {
            let params: serde_json::Map<String, Value> = s
                .parameters
                .iter()
                .map(|(n, v, _)| (n.clone(), json!(v)))
                .collect();
            let mut o = serde_json::Map::new();
            o.insert("effect".into(), json!(s.effect));
            o.insert("category".into(), json!(s.category.id()));
            o.insert("parameters".into(), Value::Object(params));
            o.insert("delta_bic".into(), json!(round(s.delta_bic)));
            if let Some(t) = &s.term {
                o.insert("balance".into(), json!(discover::balance_name(t.balance)));
                o.insert("feature".into(), json!(discover::feature_name(t)));
                o.insert("formula".into(), json!(discover::formula(t)));
            }
            Value::Object(o)
        })
        .collect();
    json!({
        "format": FORMAT,
        "mismatch": d.mismatch,
        "baseline": { "cost": d.baseline.fitted.cost, "noise_ratio": round(d.baseline.noise_ratio) },
        "locations": d.locations.iter().map(loc).collect::<Vec<_>>(),
        "candidates": candidates,
        "selected": selected,
        "extended": { "cost": d.extended.fitted.cost, "noise_ratio": round(d.extended.noise_ratio) },
    })
}

/// Four decimals: enough for ratios and ΔBIC, and stable in diffs.
fn round(v: f64) -> f64 {
    if v.is_finite() {
        (v * 1e4).round() / 1e4
    } else {
        v
    }
}

/// A number for people.
pub(crate) fn num(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-2 || v.abs() >= 1e5) {
        format!("{v:.3e}")
    } else {
        format!("{v:.3}")
    }
}

/// The one-paragraph summary of the terminal (and the report's first paragraph).
pub fn summary(d: &Diagnosis) -> String {
    let mut s = String::new();
    if let Some(l) = d.locations.first() {
        let (a, b) = (l.x_range_display[0], l.x_range_display[1]);
        let verb = if l.bias_display > 0.0 {
            "over-predicts"
        } else {
            "under-predicts"
        };
        s += &format!(
            "{}, {}, for {} from {} to {}: baseline {verb} by {} {} on average ({:.1} sigma). ",
            l.kind.id(),
            l.column,
            l.x_column,
            num(a),
            num(b),
            num(l.bias_display.abs()),
            l.unit,
            l.severity
        );
        if d.locations.len() > 1 {
            s += &format!("{} more location(s). ", d.locations.len() - 1);
        }
    } else if d.selected.is_empty() {
        s += "No channel misses the data by more than noise. ";
    } else {
        s += "No region of any channel misses by more than noise on its own: the mismatch is concealed. ";
    }
    if let Some(c) = &d.concealment {
        if c.disagree() {
            s += &format!(
                "Separate fits of the experiments disagree (LR {:.0}, p {:.1e}): a plain fit conceals a mismatch. ",
                c.lr, c.p_value
            );
        }
    }
    if d.selected.is_empty() {
        match d.candidates.first() {
            Some(c) => {
                s += &format!(
                    "No extension is needed (best candidate {}, dBIC {:+.1}). ",
                    c.label, c.delta_bic
                )
            }
            None => s += "No candidates were tried. ",
        }
        if d.mismatch {
            s += "But the baseline misses by more than noise and nothing tried explains it. ";
        }
    } else {
        let names: Vec<String> = d
            .selected
            .iter()
            .map(|x| match &x.term {
                Some(t) => format!(
                    "uncatalogued {} ({})",
                    discover::formula(t),
                    x.category.id()
                ),
                None => x.effect.clone(),
            })
            .collect();
        s += &format!(
            "Best explanation: {} (dBIC {:.0}). ",
            names.join(" + "),
            d.extended.delta_bic
        );
    }
    s += &format!(
        "Noise ratio {:.2} -> {:.2}.",
        d.baseline.noise_ratio, d.extended.noise_ratio
    );
    s
}

/// The extended model as a fit file (SPEC §4, `vanefit.fit/1`). Discovered terms have no
/// catalog id, so they go in the extra list `model.discovered` ([`FitFile::extra`]): readers
/// that do not know it ignore it and then simulate without the terms.
pub fn extended_fit_file(d: &Diagnosis) -> Value {
    let f = &d.extended.fitted;
    let mut file = FitFile::from_params(&d.dataset, f.params.clone(), f.effects.clone());
    file.estimated = names_for(&f.effects);
    file.cost = Some(f.cost);
    file.extra = f.extra.clone();
    file.to_json()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn candidate(label: &str, kind: ModelKind, delta_bic: f64) -> Candidate {
        Candidate {
            label: label.into(),
            kind,
            fitted: Fitted {
                effects: EffectSet::empty(),
                extra: Vec::new(),
                params: MotorParams::default(),
                cost: 1.0,
                chi2: 1.0,
                n_points: 1,
                k: 1,
                evaluations: 0,
                wall_s: 0.0,
            },
            delta_bic,
            noise_ratio: 1.0,
            held_out: None,
        }
    }

    #[test]
    fn the_simplest_model_within_ten_of_the_best_is_chosen() {
        use ModelKind::*;
        // Nothing beats the baseline by 10: nothing is chosen.
        assert!(choose(&[candidate("a", Single, -9.0)]).is_none());
        let c = [
            candidate("pair", Pair, -120.0),
            candidate("uncatalogued", Uncatalogued, -125.0),
            candidate("a", Single, -117.0),
            candidate("b", Single, -50.0),
        ];
        assert_eq!(choose(&c).unwrap().label, "a");
        let c = [
            candidate("pair", Pair, -140.0),
            candidate("a", Single, -112.0),
        ];
        assert_eq!(choose(&c).unwrap().label, "pair");
        let set = EffectSet::empty()
            .with(Effect::SensorLag)
            .with(Effect::BreakawayFriction);
        assert_eq!(
            label_of(&set, 1),
            (
                "breakaway_friction+sensor_lag+uncatalogued".to_string(),
                CatalogAndUncatalogued
            )
        );
        assert_eq!(label_of(&EffectSet::empty(), 2).1, Uncatalogued);
    }

    #[test]
    fn valve_dynamics_is_never_a_candidate_and_sensor_lag_needs_a_transient() {
        let ds = Dataset::load(Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/measurements/ar034-synthetic"
        )))
        .unwrap();
        let (tried, skipped) = applicable_effects(&ds);
        assert_eq!(tried.len(), 7);
        assert_eq!(skipped.len(), 1);
        assert_eq!(skipped[0].effect, Effect::ValveDynamics);
        let steady = subset(&ds, |i| ds.experiments[i].kind == Kind::Datasheet);
        let (tried, skipped) = applicable_effects(&steady);
        assert!(!tried.contains(&Effect::SensorLag));
        assert_eq!(skipped.len(), 2);
    }

    #[test]
    fn effect_starts_begin_with_the_effect_off() {
        let base = MotorParams::default();
        let s = effect_starts(&[Effect::IncompleteFilling], &base, 3);
        assert_eq!(s.len(), 3);
        assert_eq!(s[0].w_fill(), 1e5);
        assert!(s[1].w_fill() < 1e5);
        let s = effect_starts(&[Effect::BreakawayFriction], &base, 1);
        assert_eq!(s[0].t_static(), base.t_coulomb());
    }
}
