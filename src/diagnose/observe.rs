//! Progress of a diagnosis, reported to an observer the caller passes in (as argmin's
//! observers watch a solver): the library prints nothing; the command line prints each
//! event as a line on stderr.

use super::fitting::Fitted;
use super::Candidate;
use crate::model::effects::Effect;
use crate::model::motor::ExtraTerm;
use std::fmt;

/// Watches a diagnosis. Both methods default to doing nothing.
pub trait DiagnoseObserver {
    /// Something happened, `elapsed_s` seconds after the diagnosis started.
    fn progress(&self, elapsed_s: f64, event: &Progress<'_>) {
        let _ = (elapsed_s, event);
    }

    /// A phase (as listed in [`super::Diagnosis::phases`]) ended after `seconds`.
    fn phase(&self, name: &str, seconds: f64) {
        let _ = (name, seconds);
    }
}

/// The observer that ignores everything: the multi-start's, silent here too, so one `Silent`
/// serves every task.
pub use crate::estimate::optimize::multistart::Silent;

impl DiagnoseObserver for Silent {}

/// One step of a diagnosis. `Display` gives the command line's progress line.
#[derive(Debug, Clone, Copy)]
#[non_exhaustive]
pub enum Progress<'a> {
    /// The baseline fit starts.
    BaselineStart {
        /// Starts of the multi-start fit.
        starts: usize,
        /// Compared points.
        points: usize,
        /// Compared channels.
        channels: usize,
    },
    /// The baseline is fitted.
    BaselineFitted(&'a Fitted),
    /// The catalog effects (and the null refit) are refitted warm from the baseline.
    CandidatesStart(&'a [Effect]),
    /// The null refit converged further than the baseline fit and replaces it.
    NullRefitImproved {
        /// Cost J before.
        before: f64,
        /// Cost J after.
        after: f64,
    },
    /// A refit failed; `what` names it ("candidate", "pair", …).
    Failed {
        /// What failed.
        what: &'a str,
        /// Its error message.
        error: &'a str,
    },
    /// The baseline's residuals are located.
    BaselineLocated {
        /// Noise ratio of the baseline.
        ratio: f64,
        /// [`super::noise_ratio_limit`] of its channels.
        limit: f64,
        /// Number of locations found.
        locations: usize,
    },
    /// A single catalog effect's refit is scored (with its effort).
    Ranked(&'a Candidate),
    /// A further refit (pair, discovered term, part removal) is scored.
    Scored(&'a Candidate),
    /// Pairs of effects are refitted.
    PairsStart(usize),
    /// The sparse regression of the baseline misfit starts.
    RegressionStart,
    /// The regression proposes a term.
    Proposed(Proposal<'a>),
    /// Models with discovered terms are refitted.
    DiscoveredStart(usize),
    /// Backward elimination of a chosen model of several parts.
    Elimination(&'a str),
    /// The concealment test starts.
    ConcealmentStart,
    /// The concealment test's result.
    ConcealmentResult(ChowTest),
    /// The 95 % intervals of the extended model's estimated parameters are computed.
    IntervalsStart {
        /// Estimated parameters (discovered terms' coefficients included).
        parameters: usize,
        /// By profile likelihood (else from the curvature).
        profile: bool,
    },
    /// The diagnosis is complete.
    Done {
        /// Wall time, s.
        wall_s: f64,
    },
}

impl fmt::Display for Progress<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Progress::BaselineStart {
                starts,
                points,
                channels,
            } => write!(
                f,
                "baseline fit: {starts} start(s), {points} points in {channels} channels"
            ),
            Progress::BaselineFitted(b) => write!(
                f,
                "baseline cost {:.4}, chi2 {:.1} ({} evaluations, {:.1} s)",
                b.cost, b.chi2, b.evaluations, b.wall_s
            ),
            Progress::CandidatesStart(tried) => write!(
                f,
                "refitting {} candidate(s) warm from the baseline: {}",
                tried.len(),
                tried.iter().map(|e| e.id()).collect::<Vec<_>>().join(", ")
            ),
            Progress::NullRefitImproved { before, after } => write!(
                f,
                "null refit improved the baseline: cost {before:.4} -> {after:.4}"
            ),
            Progress::Failed { what, error } => write!(f, "{what} failed: {error}"),
            Progress::BaselineLocated {
                ratio,
                limit,
                locations,
            } => write!(
                f,
                "baseline noise ratio {ratio:.3} (limit {limit:.3}); {locations} location(s)"
            ),
            Progress::Ranked(c) => write!(
                f,
                "  {:<28} dBIC {:>9.1}  noise ratio {:.3}  ({} evaluations, {:.1} s)",
                c.label, c.delta_bic, c.noise_ratio, c.fitted.evaluations, c.fitted.wall_s
            ),
            Progress::Scored(c) => write!(
                f,
                "  {:<28} dBIC {:>9.1}  noise ratio {:.3}",
                c.label, c.delta_bic, c.noise_ratio
            ),
            Progress::PairsStart(n) => write!(f, "refitting {n} pair(s)"),
            Progress::RegressionStart => write!(
                f,
                "sparse regression of the baseline misfit over the term library"
            ),
            Progress::Proposed(p) => p.fmt(f),
            Progress::DiscoveredStart(n) => {
                write!(f, "refitting {n} model(s) with discovered terms")
            }
            Progress::Elimination(label) => write!(
                f,
                "checking {label}: refitting each part's removal warm from its optimum"
            ),
            Progress::ConcealmentStart => write!(
                f,
                "concealment: each experiment fitted alone and predicted from the others"
            ),
            Progress::ConcealmentResult(t) => t.fmt(f),
            Progress::IntervalsStart {
                parameters,
                profile,
            } => write!(
                f,
                "95 % intervals of the extended model's {parameters} parameters ({})",
                if profile {
                    "profile likelihood"
                } else {
                    "curvature"
                }
            ),
            Progress::Done { wall_s } => write!(f, "done in {wall_s:.1} s"),
        }
    }
}

/// What a phase did, returned to the orchestrator (`diagnose_observed`), which tells the
/// observer and counts the work of the phase: the phases compute, they do not report. Each
/// note but [`Note::Evaluated`] is one [`Progress`] event, owned, so that it outlives the
/// phase that made it; the events that open a phase the orchestrator says itself, before
/// it runs the phase.
#[derive(Debug, Clone)]
pub(crate) enum Note {
    /// `n` cost evaluations (whole simulations of every experiment): a fit, a regression, a
    /// grid, or the one simulation of a fitted model's channels.
    Evaluated(u64),
    /// [`Progress::NullRefitImproved`].
    NullRefitImproved {
        /// Cost J before.
        before: f64,
        /// Cost J after.
        after: f64,
    },
    /// [`Progress::Failed`].
    Failed {
        /// What failed.
        what: String,
        /// Its error message.
        error: String,
    },
    /// [`Progress::Scored`].
    Scored(Box<Candidate>),
    /// [`Progress::PairsStart`].
    PairsStart(usize),
    /// [`Progress::Proposed`].
    Proposed {
        /// The term.
        term: ExtraTerm,
        /// Its linearised ΔBIC.
        delta_bic: f64,
        /// The catalog model it extends (None: the baseline).
        on_top_of: Option<String>,
    },
    /// [`Progress::DiscoveredStart`].
    DiscoveredStart(usize),
    /// [`Progress::Elimination`].
    Elimination(String),
    /// [`Progress::ConcealmentResult`].
    ConcealmentResult(ChowTest),
}

impl Note {
    /// A failed refit, `what` naming it.
    pub(crate) fn failed(what: &str, error: &dyn std::error::Error) -> Self {
        Note::Failed {
            what: what.to_string(),
            error: error.to_string(),
        }
    }

    /// The event the observer is told (`None` for [`Note::Evaluated`], which is counted).
    pub(crate) fn progress(&self) -> Option<Progress<'_>> {
        Some(match self {
            Note::Evaluated(_) => return None,
            Note::NullRefitImproved { before, after } => Progress::NullRefitImproved {
                before: *before,
                after: *after,
            },
            Note::Failed { what, error } => Progress::Failed { what, error },
            Note::Scored(c) => Progress::Scored(c),
            Note::PairsStart(n) => Progress::PairsStart(*n),
            Note::Proposed {
                term,
                delta_bic,
                on_top_of,
            } => Progress::Proposed(Proposal {
                term,
                delta_bic: *delta_bic,
                on_top_of: on_top_of.as_deref(),
            }),
            Note::DiscoveredStart(n) => Progress::DiscoveredStart(*n),
            Note::Elimination(label) => Progress::Elimination(label),
            Note::ConcealmentResult(t) => Progress::ConcealmentResult(*t),
        })
    }
}

/// A term proposed by the linearised regression ([`super::discover`]).
#[derive(Debug, Clone, Copy)]
pub struct Proposal<'a> {
    /// The term.
    pub term: &'a ExtraTerm,
    /// Its linearised ΔBIC.
    pub delta_bic: f64,
    /// The catalog model it extends (None: the baseline).
    pub on_top_of: Option<&'a str>,
}

impl fmt::Display for Proposal<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (formula, delta_bic) = (super::discover::formula(self.term), self.delta_bic);
        match self.on_top_of {
            Some(label) => write!(
                f,
                "  on top of {label}: proposed {formula} (linearised dBIC {delta_bic:.1})"
            ),
            None => write!(f, "  proposed {formula} (linearised dBIC {delta_bic:.1})"),
        }
    }
}

/// The concealment test's statistic (see [`super::Concealment`]).
#[derive(Debug, Clone, Copy)]
pub struct ChowTest {
    /// χ² of the joint baseline.
    pub joint: f64,
    /// Σ χ² of the experiments fitted alone.
    pub separate: f64,
    /// Likelihood ratio statistic.
    pub lr: f64,
    /// Its degrees of freedom.
    pub df: f64,
    /// Its p-value.
    pub p_value: f64,
}

impl fmt::Display for ChowTest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "concealment: chi2 joint {:.1} vs separate {:.1}: LR {:.1}, df {}, p {:.2e}",
            self.joint, self.separate, self.lr, self.df, self.p_value
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn progress_lines_read_as_before() {
        let t = super::super::discover::library()[0];
        let formula = super::super::discover::formula(&t);
        let line = |on_top_of| {
            Progress::Proposed(Proposal {
                term: &t,
                delta_bic: -12.34,
                on_top_of,
            })
            .to_string()
        };
        assert_eq!(
            line(None),
            format!("  proposed {formula} (linearised dBIC -12.3)")
        );
        assert_eq!(
            line(Some("sensor_lag")),
            format!("  on top of sensor_lag: proposed {formula} (linearised dBIC -12.3)")
        );
        let chow = ChowTest {
            joint: 3793.04,
            separate: 3764.9,
            lr: 28.14,
            df: 16.0,
            p_value: 0.0308,
        };
        assert_eq!(
            Progress::ConcealmentResult(chow).to_string(),
            "concealment: chi2 joint 3793.0 vs separate 3764.9: LR 28.1, df 16, p 3.08e-2"
        );
        assert_eq!(Progress::PairsStart(3).to_string(), "refitting 3 pair(s)");
    }
}
