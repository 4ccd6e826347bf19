//! What the numbers of a report mean, in one line each, and how parameters are written for
//! people: every printed summary and written report takes its sentences and formats from
//! here, so that the terminal, `report.md` and the docs (`docs/model.md`) say the same.
//!
//! The definitions are the code's: J is `objective::cost` eq. \[1\], χ² is
//! `objective::likelihood` eq. \[1\] (with the sensor offsets of
//! `objective::nuisance` profiled out in a fit), the noise ratio and its limit are
//! `estimate::fit::goodness` eqs. \[1\]–\[2\].

use crate::model::params::{
    conductance_dm3_s_bar, spec, CATALOGUE_CONDUCTANCE_UNIT, CONDUCTANCE_UNIT,
};
use crate::units::format::trim_zeros;

/// What the cost J is.
pub const COST_J: &str = "cost J = sum over experiments and channels of \
    w·mean(((simulated − reference polynomial)/σ_ref)²), σ_ref the channel's scatter about its \
    polynomial (docs/model.md, \"Cost J\"): a channel adds 1 when the simulation is off its \
    reference by one noise σ (RMS), so a model that follows the data to within the noise keeps \
    J below the number of channels (8 for the three reference experiments); lower is better";

/// What χ² and χ²/dof are.
pub const CHI2_PER_DOF: &str = "chi2 = sum over the recorded rows of \
    ((simulated − recorded)/σ)², σ each channel's noise from the data alone; chi2/dof = \
    chi2/(rows − estimated parameters) ≈ 1 when the model explains the data to within their \
    noise, well above 1 when it misses";

/// What a fit's likelihood χ² is, and how it differs from χ².
pub const LIKELIHOOD_CHI2: &str = "likelihood chi2 = what the estimate minimises and the \
    profile intervals rise from: chi2 with the σ of each channel whose residuals scatter more \
    than its noise estimate widened to that scatter, plus the sensor offsets' calibration \
    priors; lower than chi2 where a channel was widened (fit file: \
    statistics.likelihood_chi2; chi2 is statistics.chi2)";

/// How a fit's χ² treats the rig's systematic errors (the diagnosis keeps none).
pub const CHI2_OFFSETS: &str = "in a fit, each sensor's zero offset and the supply-pressure \
    sensor's offset are profiled out of chi2 within their calibration tolerances";

/// What the noise ratio and its limit are.
pub const NOISE_RATIO: &str = "noise ratio = √(mean over channels of chi2_c/n_c), the RMS \
    residual in noise units with every channel counted alike: ≈ 1 at the noise; a correct \
    model exceeds the limit with probability 0.1%";

/// Which units conductances are written in.
pub const CONDUCTANCE_UNITS: &str = "conductances in m3/(s*Pa) and, as catalogues and \
    ISO 6358 give them, in dm3/(s*bar) (1 dm3/(s*bar) = 1e-8 m3/(s*Pa))";

/// A number with `digits` significant digits, in scientific notation outside 1e-3..1e5
/// (`6.7583e-9`, `0.67583`, `0.02`, `12000`).
pub fn number(v: f64, digits: usize) -> String {
    let a = v.abs();
    if !v.is_finite() {
        return format!("{v}");
    }
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        return trim_zeros(&format!("{v:.*e}", digits.saturating_sub(1)));
    }
    let decimals = if a == 0.0 {
        0
    } else {
        (digits as i32 - 1 - a.log10().floor() as i32).max(0) as usize
    };
    trim_zeros(&format!("{v:.decimals$}"))
}

/// A conductance in both units: `6.7583e-9 m3/(s*Pa) (0.67583 dm3/(s*bar))`.
pub fn conductance(c_m3_s_pa: f64, digits: usize) -> String {
    format!(
        "{} {CONDUCTANCE_UNIT} ({} {CATALOGUE_CONDUCTANCE_UNIT})",
        number(c_m3_s_pa, digits),
        number(conductance_dm3_s_bar(c_m3_s_pa), digits)
    )
}

/// A parameter's value with its unit, and for a conductance in dm³/(s·bar) too:
/// `0.02 N*m`, `6.7583e-9 m3/(s*Pa) (0.67583 dm3/(s*bar))`. An unknown name gets no unit.
pub fn value(name: &str, v: f64, digits: usize) -> String {
    match spec(name) {
        Some(s) if s.is_conductance() => conductance(v, digits),
        Some(s) if s.unit != "1" => format!("{} {}", number(v, digits), s.unit),
        _ => number(v, digits),
    }
}

/// `v` with `decimals` decimals, never a negative zero: a value that rounds to zero prints
/// as `0.00`, not `-0.00` (a mean error of −0.001 rpm is no error to the shown precision).
pub fn fixed(v: f64, decimals: usize) -> String {
    let text = format!("{v:.decimals$}");
    match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What rounds to zero loses its sign; what does not keeps it.
    #[test]
    fn fixed_never_prints_a_negative_zero() {
        assert_eq!(fixed(-0.001, 2), "0.00");
        assert_eq!(fixed(-0.0, 2), "0.00");
        assert_eq!(fixed(-0.004999, 2), "0.00");
        assert_eq!(fixed(-0.006, 2), "-0.01");
        assert_eq!(fixed(0.004, 2), "0.00");
        assert_eq!(fixed(-12.5, 1), "-12.5");
        assert_eq!(fixed(-0.2, 0), "0");
        assert_eq!(fixed(f64::NAN, 2), "NaN");
    }

    #[test]
    fn numbers_are_short_and_conductances_come_in_both_units() {
        assert_eq!(number(6.758344e-9, 5), "6.7583e-9");
        assert_eq!(number(0.6758344, 5), "0.67583");
        assert_eq!(number(0.02, 4), "0.02");
        assert_eq!(number(12000.0, 4), "12000");
        assert_eq!(number(0.0, 4), "0");
        assert_eq!(number(6e-5, 5), "6e-5");
        assert_eq!(number(-1.25e7, 3), "-1.25e7");
        assert_eq!(
            conductance(6.76e-9, 3),
            "6.76e-9 m3/(s*Pa) (0.676 dm3/(s*bar))"
        );
        assert_eq!(
            value("c_1e", 2.077886e-9, 4),
            "2.078e-9 m3/(s*Pa) (0.2078 dm3/(s*bar))"
        );
        assert_eq!(value("t_coulomb", 0.02, 4), "0.02 N*m");
        assert_eq!(value("eps", 1.071, 4), "1.071");
        assert_eq!(value("no_such", 3.0, 4), "3");
    }
}
