//! Numbers for messages: short, exact enough to recognise the value a user wrote.

/// A number in few characters: plain between 1e-3 and 1e6, else in exponent form, with
/// trailing zeros dropped (`5`, `0.73`, `1e30`, `1.047e-5`).
pub fn short(v: f64) -> String {
    let plain = v == 0.0 || (1e-3..1e6).contains(&v.abs());
    let s = if plain {
        format!("{v:.6}")
    } else {
        format!("{v:.3e}")
    };
    trim_zeros(&s)
}

/// `s`, a formatted number, without the trailing zeros of its mantissa (and without a
/// trailing point): `0.730000` → `0.73`, `1.000e30` → `1e30`; a number without a point is
/// left as it is.
pub fn trim_zeros(s: &str) -> String {
    let (mantissa, exponent) = s.split_once('e').unwrap_or((s, ""));
    let mantissa = if mantissa.contains('.') {
        mantissa.trim_end_matches('0').trim_end_matches('.')
    } else {
        mantissa
    };
    if exponent.is_empty() {
        mantissa.to_string()
    } else {
        format!("{mantissa}e{exponent}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_shown_short() {
        assert_eq!(short(5.0), "5");
        assert_eq!(short(0.73), "0.73");
        assert_eq!(short(1e30), "1e30");
        assert_eq!(short(-1.0471975e-5), "-1.047e-5");
        assert_eq!(short(0.0), "0");
    }
}
