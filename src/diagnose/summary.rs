//! The one-paragraph summary of a diagnosis, for people.

use super::{discover, Diagnosis};
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
    let mut s = String::new();
    if let Some(l) = d.locations.first() {
        let (a, b) = (l.x_range_display[0], l.x_range_display[1]);
        let verb = if l.bias_display > 0.0 {
            "over-predicts"
        } else {
            "under-predicts"
        };
        // A conductance abscissa in the other unit too (1 dm3/(s*bar) = 1e-8 m3/(s*Pa)).
        let catalogue = if l.x_column.ends_with("_dm3_s_bar") {
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
        };
        s += &format!(
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
    }
    s += &format!(
        "Noise ratio {:.2} -> {:.2}.",
        d.baseline.noise_ratio, d.extended.noise_ratio
    );
    s
}
