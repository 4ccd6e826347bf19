//! The one-paragraph summary of a diagnosis, for people.

use super::{discover, Diagnosis, Location};
use crate::model::params::conductance_dm3_s_bar;

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
    let mut s = location_sentences(d);
    if let Some(c) = &d.concealment {
        if c.disagree() {
            s += &format!(
                "Separate fits of the experiments disagree (LR {:.0}, p {:.1e}): a plain fit conceals a mismatch. ",
                c.lr, c.p_value
            );
        }
    }
    if d.selected.is_empty() {
        s += &no_extension_sentences(d);
    } else {
        s += &explanation_sentences(d);
    }
    s += &format!(
        "Noise ratio {:.2} -> {:.2}.",
        d.baseline.noise_ratio, d.extended.noise_ratio
    );
    s
}

/// Where the baseline misses the data most (and how many more places), or that it misses
/// nowhere by more than noise.
fn location_sentences(d: &Diagnosis) -> String {
    let Some(l) = d.locations.first() else {
        return if d.selected.is_empty() {
            "No channel misses the data by more than noise. ".into()
        } else {
            "No region of any channel misses by more than noise on its own: the mismatch is concealed. ".into()
        };
    };
    let (a, b) = (l.x_range_display[0], l.x_range_display[1]);
    let verb = if l.bias_display > 0.0 {
        "over-predicts"
    } else {
        "under-predicts"
    };
    let catalogue = conductance_in_other_unit(l);
    let mut s = format!(
        "{}, {}, for {} from {} to {}{catalogue}: baseline {verb} by {} {} on average ({:.1} sigma). ",
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
    s
}

/// A conductance abscissa's range in the other unit too (1 dm3/(s*bar) = 1e-8
/// m3/(s*Pa)), in brackets; empty for any other abscissa.
fn conductance_in_other_unit(l: &Location) -> String {
    if l.x_column.ends_with("_dm3_s_bar") {
        format!(
            " ({} to {} m3/(s*Pa))",
            num(l.x_range[0]),
            num(l.x_range[1])
        )
    } else if l.x_column.starts_with("c_port") {
        format!(
            " ({} to {} dm3/(s*bar))",
            num(conductance_dm3_s_bar(l.x_range[0])),
            num(conductance_dm3_s_bar(l.x_range[1]))
        )
    } else {
        String::new()
    }
}

/// With nothing selected: the best candidate tried, and whether a mismatch stays
/// unexplained.
fn no_extension_sentences(d: &Diagnosis) -> String {
    let mut s = match d.candidates.first() {
        Some(c) => format!(
            "No extension is needed (best candidate {}, dBIC {:+.1}). ",
            c.label, c.delta_bic
        ),
        None => "No candidates were tried. ".into(),
    };
    if d.mismatch {
        s += "But the baseline misses by more than noise and nothing tried explains it. ";
    }
    s
}

/// The selected extension, and the alternatives the data cannot tell from it (with the
/// experiment that would, where one was found).
fn explanation_sentences(d: &Diagnosis) -> String {
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
    let mut s = format!(
        "Best explanation: {} (dBIC {:.0}). ",
        names.join(" + "),
        d.extended.delta_bic
    );
    if !d.also_consistent.is_empty() {
        let also: Vec<String> = d
            .also_consistent
            .iter()
            .map(|a| format!("{} (dBIC {:+.1})", a.label, a.delta_bic))
            .collect();
        s += &format!(
            "Also consistent (within dBIC {:.0} of it): {}; these data cannot separate them",
            super::ALSO_CONSISTENT_DELTA_BIC,
            also.join(", ")
        );
        match &d.separating_experiment {
            Some(e) => s += &format!(", {e} would. "),
            None => s += ". ",
        }
    }
    s
}
