//! Missing-physics diagnosis (docs/model.md, "Missing-physics catalog"; `vanefit diagnose`,
//! docs/cli.md): locate where the base model misses the data, name the physics it leaves
//! out, model it, refit, and show the gain.
//!
//! # What is fitted
//!
//! Every fit of a diagnosis maximises the Gaussian likelihood of the RECORDED rows
//! (`objective::likelihood`): χ² = Σ((simulated − recorded)/σ)² over the rows the cost compares, σ each
//! channel's noise estimated from the data alone (second differences). Not the project's
//! cost J against the reference polynomials: their σ also holds the polynomials' lack of
//! fit (threefold for a ramp's speed), and their systematic error is a signal that a fit to
//! one experiment can chase; both would make a correct model look wrong and separate fits
//! "disagree" on clean data. The recorded inputs of transients are replaced by their smooth
//! in time (errors in variables, `crate::objective::likelihood::smooth_inputs`). `cost` in the output is J at the
//! fitted parameters, as `vanefit fit` reports it.
//!
//! # Procedure
//!
//! 1. **Baseline.** The base model's default parameters (docs/model.md, "Parameters": six
//!    conductances, `t_coulomb`, `visc`) are fitted by multi-start Nelder–Mead, one start
//!    at the rig's nominal motor plus `starts − 1` Latin-hypercube starts. A warm refit of
//!    the same model (the "null refit", same budget as a candidate) guards against
//!    crediting a candidate with what is only further convergence.
//! 2. **Locate** (`analysis`): residuals against the recorded data in noise units;
//!    regional bias, runs and trend per channel; the noise ratio.
//! 3. **Concealment.** A plain fit can hide a missing effect by shifting the base
//!    parameters. Each experiment is fitted alone (warm from the baseline): if the
//!    parameters agree across experiments, the joint χ² exceeds the sum of the separate
//!    ones by a χ²(k·(E − 1)) amount only (likelihood-ratio/Chow test; k estimated
//!    parameters, E experiments; the df is an upper bound when some parameter is not
//!    identifiable from one experiment alone, which makes the test conservative; rejected
//!    at p < `CONCEALMENT_ALPHA`). And each experiment is predicted from a fit to the
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
//!    significant, it is paired with the next three candidates. `breakaway_friction` starts
//!    from the best points of a grid over static torque and (log-spaced) Stribeck speed.
//! 5. **Uncatalogued** ([`discover`]): sparse regression of the misfit over a library of
//!    terms in each balance, on the baseline and on the best catalog model; a term that the
//!    linearised regression supports is put into the model ([`crate::model::motor::ExtraTerm`])
//!    and refitted. Leak paths (mass leaves one volume and enters another, or atmosphere)
//!    are preferred to one-balance mass terms. A discovered term may imitate a catalog
//!    effect: the best single effect is then also paired with the best catalog effect of
//!    the term's category, so that "pair" and "single + uncatalogued" compete.
//! 6. **Selection.** Among the baseline and every refitted model, the simplest one within
//!    `SELECT_DELTA_BIC` = 10 of the lowest BIC is chosen, simplicity ordered baseline <
//!    one catalog effect < two catalog effects < an uncatalogued term < catalog effect(s)
//!    plus an uncatalogued term. ΔBIC < −10 is "very strong" evidence on Kass and
//!    Raftery's scale (a likelihood ratio above e⁵ ≈ 150 after the ln n penalty per
//!    parameter), so with ~3800 points a one-parameter effect must lower χ² by more than
//!    18: under the null hypothesis a χ²(1) exceeds that with probability 2e-5. A chosen
//!    model of several parts is checked by backward elimination: each part's removal is
//!    refitted warm from the chosen optimum and the part is dropped unless removing it costs
//!    more than 10. `mismatch` is true when something is selected, or when the baseline's
//!    noise ratio exceeds what noise alone explains ([`noise_ratio_limit`]).
//! 7. **Intervals** (`intervals.rs`). When something is selected, every estimated parameter
//!    of the extended model, discovered terms' coefficients included, gets a 95 % interval
//!    as `vanefit fit` computes it: profile likelihood (the command line's effort) or the
//!    curvature at the optimum (the reduced effort), ending where χ² rises by 3.841·s²,
//!    s = max(1, noise ratio).
//!
//! # Code
//!
//! `diagnose_observed` runs the phases in turn, one file each, passing a small read-only
//! context (dataset, cost, likelihood target, options, thread pool): `baseline.rs` (1),
//! `candidates.rs` (the single refits with the null refit, which may still improve the
//! baseline, so they run before locating; then the pairs), `locate.rs` (2),
//! `uncatalogued.rs` (5), `select.rs` (backward elimination, then the extended model),
//! `concealment.rs` (3) and `intervals.rs` (7). A phase returns its result and what it did
//! (`observe::Note`s: a refit scored or failed, a term proposed, the cost evaluations it
//! spent); the orchestrator says the event that opens each phase, tells the notes, and keeps
//! the phases' clock. A phase that refits models plans them (a `models::Batch`: the jobs
//! and the line that announces them) and the orchestrator runs them (`Models::run`, the one
//! place a model is refitted: the line is said before the work), handing the scored models
//! back; backward elimination does so at each step of its loop. The types are in `types.rs`, the outputs in `json.rs` and
//! `summary.rs`. Progress goes to a [`DiagnoseObserver`]: the library prints nothing.

mod alternatives;
mod baseline;
mod candidates;
mod concealment;
mod context;
mod error;
mod intervals;
pub use analysis::{ChannelData, Location};
pub use fitting::{run_job, FitJob, Fitted, RefitError};

/// The former name of [`RefitError`] (one `FitError` is the fit task's).
#[deprecated(note = "renamed `RefitError`")]
pub type FitError = RefitError;
mod json;
mod locate;
mod models;
mod observe;
mod select;
mod summary;
mod types;
mod uncatalogued;

pub(crate) mod analysis;
pub mod discover;
pub(crate) mod fitting;
pub(crate) mod stats;

pub use alternatives::ALSO_CONSISTENT_DELTA_BIC;
pub use analysis::noise_ratio_limit;
pub use error::DiagnoseError;
pub use json::{extended_fit_file, to_json};
pub use observe::{ChowTest, DiagnoseObserver, Progress, Proposal, Silent};
/// A number for people (also in the report).
pub(crate) use summary::num;
pub use summary::summary;
pub use types::{
    AlsoConsistent, Candidate, Concealment, DiagnoseOptions, Diagnosis, ExperimentCheck,
    ExtendedInterval, ModelKind, Selected, Skipped,
};

use crate::data::dataset::Dataset;
use crate::estimate::Engine;
use crate::model::effects::Effect;
use crate::model::params::{spec, MotorParams};
use context::Context;
use models::Models;
use observe::Note;
use std::time::Instant;

/// A refitted model must beat the simpler ones by this much BIC to be selected.
pub(crate) const SELECT_DELTA_BIC: f64 = 10.0;
/// Significance level of the concealment test.
pub(crate) const CONCEALMENT_ALPHA: f64 = 1e-3;
/// The format of `diagnosis.json`.
pub(crate) const FORMAT: &str = "vanefit.diagnosis/1";
/// Runs a diagnosis of a dataset, silently, on a thread pool of `opts.threads` threads.
pub fn diagnose(recorded: &Dataset, opts: &DiagnoseOptions) -> Result<Diagnosis, DiagnoseError> {
    let engine = Engine::with_threads(opts.threads)?;
    diagnose_observed(recorded, opts, &engine, &Silent)
}

/// Runs a diagnosis of a dataset, telling `observer` how it goes: the phases of the module
/// documentation, one after the other, every fit on `engine` (the thread count of
/// `opts` is not used: the engine has its own). The phases compute and return what they
/// did, and plan the refits they need; this orchestrator runs those ([`Models::run`]), tells the
/// observer and keeps the phases' clock ([`Account`]).
pub(crate) fn diagnose_observed(
    recorded: &Dataset,
    opts: &DiagnoseOptions,
    engine: &Engine,
    observer: &dyn DiagnoseObserver,
) -> Result<Diagnosis, DiagnoseError> {
    let mut account = Account::new(observer);
    let (smoothed, inputs) = crate::objective::likelihood::smooth_inputs(recorded);
    let cx = Context::new(&smoothed, opts, engine)?;
    let notes = &mut Vec::new();
    let Found {
        base,
        mut models,
        skipped,
        regression,
    } = search(&cx, &mut account, notes)?;
    let reg = regression.as_ref();
    let chosen = chosen_model(&cx, &mut account, reg, &base.fitted, &mut models, notes);
    let mut baseline_c = base.candidate();
    let concealed = if concealment::applies(&cx) {
        account.say(Progress::ConcealmentStart);
        let held = chosen.as_ref();
        let test = concealment::test(&cx, &base, &mut baseline_c, &mut models, held, notes);
        account.tell(notes);
        Some(test?)
    } else {
        None
    };
    account.end_phase("concealment and held-out prediction");
    let extended = select::extended(&cx, chosen, &models.all, &baseline_c, notes);
    account.tell(notes);
    let extended = extended?;
    account.end_phase("selection");
    let parameters = intervals::parameters(&extended.model);
    if parameters > 0 {
        account.say(Progress::IntervalsStart {
            parameters,
            profile: opts.profile_intervals,
        });
    }
    let extended_intervals = intervals::of_extended(&cx, &extended.model, notes);
    account.tell(notes);
    let extended_intervals = extended_intervals?;
    if !extended_intervals.is_empty() {
        account.end_phase("intervals of the extended model");
    }
    let (also_consistent, separating_experiment) =
        alternatives::runners_up(&extended.model, &extended.selected, &models.all);
    let d = Diagnosis {
        dataset: smoothed.name.clone(),
        p_atm_pa: smoothed.p_atm_pa,
        mismatch: !extended.selected.is_empty() || base.ratio > base.limit,
        baseline: baseline_c,
        baseline_channels: base.channels,
        locations: base.locations,
        candidates: models.all,
        skipped,
        selected: extended.selected,
        extended: extended.model,
        extended_channels: extended.channels,
        extended_locations: extended.locations,
        extended_intervals,
        also_consistent,
        separating_experiment,
        concealment: concealed,
        regression,
        noise_ratio_limit: base.limit,
        estimated: cx.base_names.clone(),
        inputs,
        phases: account.phases(),
        phase_evaluations: account.phase_evaluations(),
        wall_s: account.elapsed_s(),
        threads: engine.threads(),
    };
    account.say(Progress::Done { wall_s: d.wall_s });
    Ok(d)
}

/// What the search of phases 1 to 5 found.
struct Found {
    /// The fitted baseline against the data.
    base: locate::Baseline,
    /// Every refitted model.
    models: Models,
    /// The catalog effects not tried.
    skipped: Vec<Skipped>,
    /// The regression of the baseline's misfit (None when discovery is off).
    regression: Option<discover::Regression>,
}

/// Phases 1 to 5 in turn: the baseline, the candidates, where the baseline misses, then
/// [`widen`]; each phase's notes told to `account`.
fn search(
    cx: &Context,
    account: &mut Account,
    notes: &mut Vec<Note>,
) -> Result<Found, DiagnoseError> {
    account.say(Progress::BaselineStart {
        starts: cx.opts.starts,
        points: cx.cost.n_points(),
        channels: cx.cost.n_channels(),
    });
    let fitted = baseline::fit(cx)?;
    account.count(fitted.evaluations);
    account.say(Progress::BaselineFitted(&fitted));
    account.end_phase("baseline fit");
    let (tried, skipped) = candidates::applicable_effects(cx.ds);
    account.say(Progress::CandidatesStart(&tried));
    let refits = candidates::refit_singles(cx, fitted, &tried, notes);
    account.tell(notes);
    let refits = refits?;
    account.end_phase("candidate refits");
    let base = locate::baseline(cx, refits.baseline, notes);
    account.tell(notes);
    let base = base?;
    account.say(Progress::BaselineLocated {
        ratio: base.ratio,
        limit: base.limit,
        locations: base.locations.len(),
    });
    let mut models = Models::new(base.fitted.bic());
    candidates::rank_singles(cx, &mut models, refits.singles, notes);
    account.tell(notes);
    for c in &models.all {
        account.say(Progress::Ranked(c));
    }
    let regression = widen(cx, account, &base, &mut models, notes)?;
    Ok(Found {
        base,
        models,
        skipped,
        regression,
    })
}

/// Phases 4 and 5 beyond the single effects: the pairs, the uncatalogued terms (returns the
/// baseline's regression when discovery is on) and the pairs that a discovered term calls for.
fn widen(
    cx: &Context,
    account: &mut Account,
    base: &locate::Baseline,
    models: &mut Models,
    notes: &mut Vec<Note>,
) -> Result<Option<discover::Regression>, DiagnoseError> {
    let pairs = candidates::pairs(cx, base.limit, models, notes);
    account.tell(notes);
    if let Some(batch) = pairs? {
        let found = models.run(cx, batch, notes, &mut |n| account.tell(n));
        models.all.extend(found);
    }
    account.end_phase("pairs");
    let regression = if cx.opts.discover {
        account.say(Progress::RegressionStart);
        let reg = uncatalogued::regress(cx, &base.fitted, notes);
        account.tell(notes);
        let reg = reg?;
        let batch = uncatalogued::term_refits(cx, &base.fitted, &reg, base.limit, models, notes);
        account.tell(notes);
        if let Some(batch) = batch? {
            let found = models.run(cx, batch, notes, &mut |n| account.tell(n));
            models.all.extend(found);
        }
        Some(reg)
    } else {
        None
    };
    if let Some(batch) = candidates::similar_pairs(cx, models) {
        let found = models.run(cx, batch, notes, &mut |n| account.tell(n));
        models.all.extend(found);
    }
    account.end_phase("uncatalogued search");
    Ok(regression)
}

/// The chosen model (phase 6): backward elimination ([`select::elimination`]) refits each
/// part's removal of a model of several parts and chooses again, until the choice stands;
/// then a patchwork is held against one explanation ([`alternatives::one_explanation`],
/// warm from the `baseline`). The refits join `models`.
fn chosen_model(
    cx: &Context,
    account: &mut Account,
    reg: Option<&discover::Regression>,
    baseline: &fitting::Fitted,
    models: &mut Models,
    notes: &mut Vec<Note>,
) -> Option<Candidate> {
    models.sort();
    let mut chosen = select::choose(&models.all);
    while let Some(batch) = chosen.as_ref().and_then(|c| select::elimination(cx, c)) {
        let subs = models.run(cx, batch, notes, &mut |n| account.tell(n));
        let next = select::rechoose(models, subs);
        if next.as_ref().map(|n| &n.label) == chosen.as_ref().map(|c| &c.label) {
            break;
        }
        chosen = next;
    }
    let batch = alternatives::alone_refits(cx, reg, baseline, models, chosen.as_ref());
    if let Some(batch) = batch {
        let found = models.run(cx, batch, notes, &mut |n| account.tell(n));
        models.all.extend(found);
        models.sort();
    }
    alternatives::one_explanation(reg, models, chosen)
}

/// The orchestrator's account of a diagnosis: it tells the observer what each phase did,
/// and keeps each finished phase's time and cost evaluations ([`Diagnosis::phases`],
/// [`Diagnosis::phase_evaluations`]).
struct Account<'a> {
    observer: &'a dyn DiagnoseObserver,
    /// When the diagnosis started.
    t0: Instant,
    /// When the current phase started (the end of the previous one).
    phase_start: Instant,
    /// Cost evaluations (whole simulations of every experiment) of the current phase.
    evaluations: u64,
    /// (phase, seconds, cost evaluations) of each finished phase.
    phases: Vec<(String, f64, u64)>,
}

impl<'a> Account<'a> {
    /// The account of a diagnosis starting now.
    fn new(observer: &'a dyn DiagnoseObserver) -> Self {
        let t0 = Instant::now();
        Self {
            observer,
            t0,
            phase_start: t0,
            evaluations: 0,
            phases: Vec::new(),
        }
    }

    /// Tells the observer of one event, with the seconds since the start.
    fn say(&self, event: Progress<'_>) {
        self.observer.progress(self.elapsed_s(), &event);
    }

    /// Counts `n` cost evaluations of the current phase.
    fn count(&mut self, n: u64) {
        self.evaluations += n;
    }

    /// Tells the observer what a phase did (`notes`, emptied), in order, and counts its
    /// evaluations. The orchestrator tells a phase's notes before it looks at the phase's
    /// result, so that a failing phase's lines are said before its error ends the diagnosis.
    fn tell(&mut self, notes: &mut Vec<Note>) {
        for note in notes.drain(..) {
            match note.progress() {
                Some(event) => self.say(event),
                None => {
                    if let Note::Evaluated(n) = note {
                        self.count(n);
                    }
                }
            }
        }
    }

    /// Ends the phase `name` (its time counts from the end of the previous one).
    fn end_phase(&mut self, name: &str) {
        let seconds = self.phase_start.elapsed().as_secs_f64();
        let evaluations = std::mem::take(&mut self.evaluations);
        self.phases.push((name.to_string(), seconds, evaluations));
        self.phase_start = Instant::now();
        self.observer.phase(name, seconds);
    }

    /// (phase, seconds) of the finished phases.
    fn phases(&self) -> Vec<(String, f64)> {
        self.phases
            .iter()
            .map(|(p, s, _)| (p.clone(), *s))
            .collect()
    }

    /// (phase, evaluations) of the finished phases.
    fn phase_evaluations(&self) -> Vec<(String, u64)> {
        self.phases
            .iter()
            .map(|(p, _, n)| (p.clone(), *n))
            .collect()
    }

    /// Seconds since the diagnosis started.
    fn elapsed_s(&self) -> f64 {
        self.t0.elapsed().as_secs_f64()
    }
}

/// The "off" value of an effect parameter (the nested base model, or as near as the search
/// range allows), given the base parameters.
fn off_value(name: &str, base: &MotorParams) -> f64 {
    spec(name).expect("effect parameter").off_value(base)
}
#[cfg(test)]
mod tests {
    use super::candidates::{applicable_effects, effect_starts};
    use super::fitting::Fitted;
    use super::models::{label_of, subset};
    use super::select::choose;
    use super::*;
    use crate::data::{SensorNoise, SynthPlan};
    use crate::model::effects::EffectSet;
    use crate::model::params::ParamId;
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

    /// An observer that keeps what it is told.
    #[derive(Default)]
    struct Recorder {
        lines: std::cell::RefCell<Vec<String>>,
        phases: std::cell::RefCell<Vec<String>>,
    }

    impl DiagnoseObserver for Recorder {
        fn progress(&self, _elapsed_s: f64, event: &Progress<'_>) {
            self.lines.borrow_mut().push(event.to_string());
        }
        fn phase(&self, name: &str, _seconds: f64) {
            self.phases.borrow_mut().push(name.to_string());
        }
    }

    /// The orchestrator tells the observer a phase's notes in the order the phase made
    /// them, counts their evaluations into that phase alone, and empties the notes.
    #[test]
    fn the_account_tells_a_phases_notes_in_order_and_counts_its_evaluations() {
        let recorder = Recorder::default();
        let mut account = Account::new(&recorder);
        let notes = &mut vec![
            Note::PairsStart(2),
            Note::Evaluated(40),
            Note::Failed {
                what: "pair".into(),
                error: "no start".into(),
            },
            Note::Evaluated(2),
        ];
        account.count(7);
        account.tell(notes);
        assert!(notes.is_empty());
        account.end_phase("pairs");
        account.tell(&mut vec![Note::Evaluated(5)]);
        account.end_phase("selection");
        assert_eq!(
            *recorder.lines.borrow(),
            ["refitting 2 pair(s)", "pair failed: no start"]
        );
        assert_eq!(*recorder.phases.borrow(), ["pairs", "selection"]);
        assert_eq!(
            account.phase_evaluations(),
            [
                ("pairs".to_string(), 7 + 40 + 2),
                ("selection".to_string(), 5)
            ]
        );
        let names: Vec<String> = account.phases().into_iter().map(|(p, _)| p).collect();
        assert_eq!(names, ["pairs", "selection"]);
    }

    /// An observer that notes, for each event, its line, the refits it announces (at least)
    /// and how many refits had run when it arrived.
    #[derive(Default)]
    struct RefitClock {
        events: std::cell::RefCell<Vec<(String, usize, usize)>>,
    }

    impl DiagnoseObserver for RefitClock {
        fn progress(&self, _elapsed_s: f64, event: &Progress<'_>) {
            let announced = match event {
                Progress::PairsStart(n) | Progress::DiscoveredStart(n) => *n,
                Progress::Elimination(_) => 1,
                _ => 0,
            };
            let run = models::REFITS_RUN.with(|n| n.get());
            let line = event.to_string();
            self.events.borrow_mut().push((line, announced, run));
        }
    }

    /// A line that announces refits ("refitting 3 pair(s)") arrives before them: the next
    /// event (the first refit's score) finds that many more refits run. A diagnosis of
    /// synthetic data with breakaway friction, pairs always tried.
    #[test]
    fn a_line_that_announces_refits_arrives_before_them() {
        let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/measurements/ar034-synthetic");
        let mut ds = Dataset::load(Path::new(dir)).unwrap();
        let params = MotorParams::default()
            .with_value(ParamId::T_STATIC, 0.0265)
            .and_then(|p| p.with_value(ParamId::W_STRIBECK, 30.0))
            .unwrap();
        let effects = EffectSet::empty().with(Effect::BreakawayFriction);
        let truth = crate::model::motor::Motor::new(params, effects);
        let (plan, noise) = (SynthPlan::default(), SensorNoise::typical());
        let solver = crate::numerics::DefaultSolver::default();
        ds.experiments = crate::data::synthesize(&truth, &solver, &plan, &noise, 1).unwrap();
        let opts = DiagnoseOptions {
            concealment: false,
            pairs_always: true,
            ..DiagnoseOptions::quick(1)
        };
        let clock = RefitClock::default();
        let engine = Engine::with_threads(Some(2)).unwrap();
        diagnose_observed(&ds, &opts, &engine, &clock).unwrap();
        let events = clock.events.borrow();
        let opened: Vec<_> = events
            .windows(2)
            .filter(|w| w[0].1 > 0)
            .map(|w| (&w[0].0, w[0].1, w[1].2 - w[0].2))
            .collect();
        assert!(
            opened.iter().any(|(line, _, _)| line.ends_with("pair(s)")),
            "{events:#?}"
        );
        for (line, announced, ran_after) in opened {
            assert!(
                ran_after >= announced,
                "{line}: {ran_after} refit(s) after it"
            );
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
    fn models_within_ten_of_the_chosen_are_also_consistent() {
        use super::alternatives::{also_consistent, separating_experiment};
        use ModelKind::*;
        let mut chosen = candidate("a", Single, -100.0);
        chosen.fitted.effects = EffectSet::empty().with(Effect::BreakawayFriction);
        let mut near = candidate("b", Single, -95.0);
        near.fitted.effects = EffectSet::empty().with(Effect::VaneFrictionSpeedSquared);
        let mut superset = candidate("a+b", Pair, -99.0);
        superset.fitted.effects = chosen.fitted.effects.clone().with(Effect::SensorLag);
        let far = candidate("c", Single, -80.0);
        let all = [chosen.clone(), near, superset, far];
        let also = also_consistent(&chosen, &all);
        assert_eq!(also.len(), 1, "{also:?}");
        assert_eq!(also[0].label, "b");
        assert_eq!(also[0].delta_bic, 5.0);
        // Two friction laws: a brake sweep separates them.
        let e = separating_experiment(&chosen, &also).unwrap();
        assert!(e.contains("brake"), "{e}");
        assert!(separating_experiment(&chosen, &[]).is_none());
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
        let steady = subset(&ds, |i| {
            ds.experiments[i].kind == crate::data::dataset::Kind::Datasheet
        });
        let (tried, skipped) = applicable_effects(&steady);
        assert!(!tried.contains(&Effect::SensorLag));
        assert_eq!(skipped.len(), 2);
    }

    #[test]
    fn effect_starts_begin_with_the_effect_off() {
        let base = MotorParams::default();
        let s = effect_starts(&[Effect::IncompleteFilling], &base, 3);
        assert_eq!(s.len(), 3);
        assert_eq!(s[0].effect_values(Effect::IncompleteFilling), &[1e5]);
        assert!(s[1].effect_values(Effect::IncompleteFilling)[0] < 1e5);
        let s = effect_starts(&[Effect::BreakawayFriction], &base, 1);
        assert_eq!(s[0].value(ParamId::T_STATIC), base.t_coulomb());
    }
}
