//! Functions of one variable: a bracketed root (Brent's method) and a bracketed minimum
//! (Brent's minimiser), both for functions that may fail to evaluate (a steady solve).
//!
//! R. P. Brent, *Algorithms for Minimization without Derivatives*, Prentice-Hall 1973,
//! chapters 4 (`zero`) and 5 (`localmin`): inverse quadratic or linear interpolation where it
//! gains, bisection or golden section where it does not, so that convergence is never slower
//! than bisection and usually superlinear.

/// An interval [a, b] on which f changes sign (f(a)·f(b) ≤ 0): only such a bracket can be
/// searched, so a root is guaranteed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bracket {
    a: f64,
    fa: f64,
    b: f64,
    fb: f64,
}

impl Bracket {
    /// The bracket of the ends a, b with values f(a), f(b); `None` unless every value is
    /// finite and the signs differ (or one value is zero).
    pub fn new(a: f64, fa: f64, b: f64, fb: f64) -> Option<Self> {
        let finite = [a, fa, b, fb].iter().all(|v| v.is_finite());
        (finite && fa * fb <= 0.0).then_some(Self { a, fa, b, fb })
    }
}

/// The root of f in a bracket, to within `rel_tol`·|x| (plus 4 ulps), by Brent's `zero`.
/// Each evaluation may fail; the first failure is returned. Gives up after 200 evaluations
/// with the best estimate so far (bisection alone would need ~60 for full precision).
pub(crate) fn brent_root<E>(
    mut f: impl FnMut(f64) -> Result<f64, E>,
    bracket: Bracket,
    rel_tol: f64,
) -> Result<f64, E> {
    let Bracket {
        mut a,
        mut fa,
        mut b,
        mut fb,
    } = bracket;
    let (mut c, mut fc) = (a, fa);
    let mut d = b - a;
    let mut e = d;
    for _ in 0..200 {
        if (fb > 0.0 && fc > 0.0) || (fb < 0.0 && fc < 0.0) {
            (c, fc) = (a, fa);
            d = b - a;
            e = d;
        }
        if fc.abs() < fb.abs() {
            (a, fa) = (b, fb);
            (b, fb) = (c, fc);
            (c, fc) = (a, fa);
        }
        let tol = 2.0 * f64::EPSILON * b.abs() + 0.5 * rel_tol * b.abs();
        let m = 0.5 * (c - b);
        if m.abs() <= tol || fb == 0.0 {
            return Ok(b);
        }
        if e.abs() < tol || fa.abs() <= fb.abs() {
            d = m;
            e = m;
        } else {
            // Secant (two points) or inverse quadratic interpolation (three).
            let s = fb / fa;
            let (mut p, mut q) = if a == c {
                (2.0 * m * s, 1.0 - s)
            } else {
                let (q, r) = (fa / fc, fb / fc);
                (
                    s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0)),
                    (q - 1.0) * (r - 1.0) * (s - 1.0),
                )
            };
            if p > 0.0 {
                q = -q;
            } else {
                p = -p;
            }
            if 2.0 * p < (3.0 * m * q - (tol * q).abs()).min((e * q).abs()) {
                e = d;
                d = p / q;
            } else {
                d = m;
                e = m;
            }
        }
        (a, fa) = (b, fb);
        b += if d.abs() > tol { d } else { tol.copysign(m) };
        fb = f(b)?;
    }
    Ok(b)
}

/// The minimum of f on [a, b] (a < b), to within `rel_tol`·|x| + `abs_tol`, by Brent's
/// `localmin` (golden section with parabolic steps): returns (x, f(x)). A local minimum
/// only: the caller brackets the global one. Each evaluation may fail; the first failure is
/// returned.
pub(crate) fn brent_minimize<E>(
    mut f: impl FnMut(f64) -> Result<f64, E>,
    mut a: f64,
    mut b: f64,
    rel_tol: f64,
    abs_tol: f64,
) -> Result<(f64, f64), E> {
    // (3 − √5)/2: the golden-section fraction.
    const GOLDEN: f64 = 0.381_966_011_250_105_1;
    let mut x = a + GOLDEN * (b - a);
    let (mut w, mut v) = (x, x);
    let mut fx = f(x)?;
    let (mut fw, mut fv) = (fx, fx);
    let (mut d, mut e): (f64, f64) = (0.0, 0.0);
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        let tol = rel_tol * x.abs() + abs_tol;
        let t2 = 2.0 * tol;
        if (x - m).abs() <= t2 - 0.5 * (b - a) {
            break;
        }
        let (mut p, mut q, mut r) = (0.0, 0.0, 0.0);
        if e.abs() > tol {
            // Parabola through x, w, v.
            r = (x - w) * (fx - fv);
            q = (x - v) * (fx - fw);
            p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            r = e;
            e = d;
        }
        if p.abs() < (0.5 * q * r).abs() && p > q * (a - x) && p < q * (b - x) {
            d = p / q;
            let u = x + d;
            if u - a < t2 || b - u < t2 {
                d = if x < m { tol } else { -tol };
            }
        } else {
            e = if x < m { b - x } else { a - x };
            d = GOLDEN * e;
        }
        let u = x + if d.abs() >= tol { d } else { tol.copysign(d) };
        let fu = f(u)?;
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv) = (w, fw);
            (w, fw) = (x, fx);
            (x, fx) = (u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv) = (w, fw);
                (w, fw) = (u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    Ok((x, fx))
}

/// tanh x, with the saturated range answered without a library call: for |x| ≥ 22,
/// 1 − tanh|x| = 2/(e^{2|x|} + 1) < 1.6e-19 is far below 2⁻⁵⁴ ≈ 5.6e-17 (half the spacing
/// of doubles just below 1), so the correctly rounded tanh is exactly ±1 there (glibc's `tanh` returns the same ±1 from its
/// own |x| ≥ 22 branch). The model's friction and torque blend take tanh of ω over a
/// regularisation speed of a few rad/s at most at every right-hand side, and at running speeds
/// the argument is in the hundreds: the call and its checks were ~3 % of an evaluation.
#[inline]
pub fn tanh(x: f64) -> f64 {
    if x.abs() >= 22.0 {
        1.0_f64.copysign(x)
    } else {
        x.tanh()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::convert::Infallible;

    #[test]
    fn root_of_a_cubic_to_the_tolerance() {
        let f = |x: f64| Ok::<_, Infallible>(x * x * x - 2.0 * x - 5.0);
        let br = Bracket::new(2.0, f(2.0).unwrap(), 3.0, f(3.0).unwrap()).unwrap();
        let mut n = 0;
        let x = brent_root(
            |x| {
                n += 1;
                f(x)
            },
            br,
            1e-12,
        )
        .unwrap();
        assert!((x - 2.094_551_481_542_326_5).abs() < 1e-11, "{x}");
        assert!(n < 15, "{n} evaluations");
        assert!(Bracket::new(0.0, 1.0, 1.0, 2.0).is_none());
        assert!(Bracket::new(0.0, f64::NAN, 1.0, -2.0).is_none());
    }

    #[test]
    fn minimum_of_a_smooth_function_and_errors_pass_through() {
        let (x, fx) = brent_minimize(
            |x: f64| Ok::<_, Infallible>((x - 0.3).powi(2) + 1.0),
            0.0,
            2.0,
            1e-10,
            1e-12,
        )
        .unwrap();
        assert!((x - 0.3).abs() < 1e-8 && (fx - 1.0).abs() < 1e-15, "{x}");
        let e = brent_minimize(|_| Err::<f64, _>("no"), 0.0, 1.0, 1e-8, 0.0);
        assert_eq!(e, Err("no"));
    }

    #[test]
    fn tanh_equals_the_library_tanh_bit_for_bit() {
        let mut x = -40.0_f64;
        while x <= 40.0 {
            assert_eq!(tanh(x).to_bits(), x.tanh().to_bits(), "x = {x}");
            x += 0.012_345;
        }
        for x in [
            21.999_999_999,
            22.0,
            1e300,
            f64::INFINITY,
            -22.0,
            -f64::INFINITY,
        ] {
            assert_eq!(tanh(x).to_bits(), x.tanh().to_bits(), "x = {x}");
        }
        assert!(tanh(f64::NAN).is_nan());
    }
}
