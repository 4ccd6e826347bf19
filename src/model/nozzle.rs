//! ISO 6358 (1989 form) restriction with a laminar extension near pressure ratio 1
//! (docs/model.md, "Lumped volumes and nozzles"). Used for the ducts and for every leakage
//! path.
//!
//! ṁ = C·ρ0·p_u·√(T0/T_u)·ψ(r),  r = p_d/p_u,
//! ψ = 1                                 for r ≤ b       (choked)
//! ψ = √(1 − ((r − b)/(1 − b))²)         for b < r ≤ r_lam (subsonic)
//! ψ = ψ(r_lam)·(1 − r)/(1 − r_lam)      for r > r_lam = 0.999 (laminar)
//!
//! C in m³/(s·Pa), pressures in Pa absolute, ṁ in kg/s. The model is isothermal (T_u = T0),
//! so the temperature factor is 1. Flow reverses by symmetry when p_d > p_u.

use crate::units::constants::RHO0_KG_M3;

/// Pressure ratio above which the flow is taken as laminar (linear in Δp).
pub const R_LAMINAR: f64 = 0.999;

/// An ISO 6358 restriction: sonic conductance C (m³/(s·Pa)) and critical ratio b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nozzle {
    /// Sonic conductance C, m³/(s·Pa).
    pub c_m3_s_pa: f64,
    /// Critical pressure ratio b, 1.
    pub b_crit: f64,
}

/// Flow function ψ(r) for 0 ≤ r ≤ 1: continuous, monotone non-increasing, ψ(1) = 0,
/// with finite slope everywhere (the laminar branch removes the infinite slope at r = 1).
pub fn psi(r: f64, b_crit: f64) -> f64 {
    psi_given(r, b_crit, 1.0 - b_crit)
}

/// [`psi`] with 1 − b given (formed once per nozzle by [`PreparedNozzle`]).
#[inline]
fn psi_given(r: f64, b_crit: f64, one_minus_b: f64) -> f64 {
    if r <= b_crit {
        1.0
    } else if r <= R_LAMINAR {
        subsonic_given(r, b_crit, one_minus_b)
    } else {
        subsonic_given(R_LAMINAR, b_crit, one_minus_b) * ((1.0 - r) / (1.0 - R_LAMINAR)).max(0.0)
    }
}

fn subsonic(r: f64, b_crit: f64) -> f64 {
    subsonic_given(r, b_crit, 1.0 - b_crit)
}

#[inline]
fn subsonic_given(r: f64, b_crit: f64, one_minus_b: f64) -> f64 {
    let x = (r - b_crit) / one_minus_b;
    (1.0 - x * x).max(0.0).sqrt()
}

/// A nozzle with C·ρ0 (kg/(s·Pa)) and 1 − b formed once, for the motor's own nozzles, whose
/// flows the right-hand side evaluates thousands of times per simulation with the same
/// parameters. [`PreparedNozzle::flow`] is [`Nozzle::flow`] (which builds one per call):
/// the same operations on the same values, so the same bits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PreparedNozzle {
    /// The nozzle as given: C and b (the series flow reads them).
    nozzle: Nozzle,
    /// C·ρ0, kg/(s·Pa).
    k: f64,
    /// 1 − b.
    one_minus_b: f64,
}

impl PreparedNozzle {
    /// The nozzle `n` prepared.
    #[inline]
    pub(crate) fn new(n: &Nozzle) -> Self {
        Self {
            nozzle: *n,
            k: n.c_m3_s_pa * RHO0_KG_M3,
            one_minus_b: 1.0 - n.b_crit,
        }
    }

    /// The nozzle as given.
    #[inline]
    pub(crate) fn nozzle(&self) -> &Nozzle {
        &self.nozzle
    }

    /// Mass flow from the port at `p_a` to the port at `p_b`, kg/s (negative when
    /// p_b > p_a): ṁ = C·ρ0·p_u·ψ(p_d/p_u).
    #[inline]
    pub(crate) fn flow(&self, p_a: f64, p_b: f64) -> f64 {
        if p_a >= p_b {
            self.forward(p_a, p_b)
        } else {
            -self.forward(p_b, p_a)
        }
    }

    #[inline]
    fn forward(&self, p_u: f64, p_d: f64) -> f64 {
        if p_u <= 0.0 {
            return 0.0;
        }
        self.k * p_u * psi_given(p_d / p_u, self.nozzle.b_crit, self.one_minus_b)
    }
}

impl Nozzle {
    /// A nozzle of conductance C (m³/(s·Pa)) and critical ratio b.
    pub fn new(c_m3_s_pa: f64, b_crit: f64) -> Self {
        Self { c_m3_s_pa, b_crit }
    }

    /// Mass flow from the port at `p_a` to the port at `p_b`, kg/s (negative when p_b > p_a).
    pub fn flow(&self, p_a: f64, p_b: f64) -> f64 {
        PreparedNozzle::new(self).flow(p_a, p_b)
    }
}

/// Steady flow through two restrictions in series with no volume between them, kg/s, and
/// the pressure between them, Pa. The intermediate pressure is the root of
/// g(p_m) = first.flow(p_a, p_m) − second.flow(p_m, p_b), unique because g falls strictly
/// with p_m; it is bracketed by [min, max] of p_a and p_b and found by Newton's method with
/// the analytic slope, falling back to bisection whenever a step leaves the bracket.
pub(crate) fn series_flow(first: &Nozzle, second: &Nozzle, p_a: f64, p_b: f64) -> (f64, f64) {
    let (closed, sign) = if p_a > p_b {
        (series_closed_form(first, second, p_a, p_b), 1.0)
    } else {
        (series_closed_form(second, first, p_b, p_a), -1.0)
    };
    if let Some((p_m, flow_squared)) = closed {
        return (sign * flow_squared.max(0.0).sqrt(), p_m);
    }
    series_newton(first, second, p_a, p_b)
}

/// Closed-form intermediate pressure for flow from `p_u` through `up` then `down` to `p_d`
/// (p_u > p_d) when neither nozzle is in its laminar range. In the choked and subsonic
/// ranges the squared flow is a quadratic polynomial in the pressures,
/// ṁ² = (C·ρ0)²·(p_u² − ((p_d − b·p_u)/(1 − b))²) or (C·ρ0·p_u)², so ṁ_up² = ṁ_down² is a
/// quadratic in p_m for each of the four regime pairs. The balance
/// g(p_m) = ṁ_up² − ṁ_down² falls strictly with p_m, so the sign of g at the two regime
/// boundaries (p_m = b_up·p_u, where the first nozzle stops choking, and p_m = p_d/b_down,
/// where the second starts) tells which pair holds the root; one quadratic is then solved.
/// Returns p_m and ṁ² there from the upstream nozzle's polynomial (the flow itself without
/// evaluating either nozzle again: the outlet throttle's rows and right-hand
/// sides spend most of their time here); `None` when the root lies in a laminar range.
fn series_closed_form(up: &Nozzle, down: &Nozzle, p_u: f64, p_d: f64) -> Option<(f64, f64)> {
    let (k1, k2) = (
        (up.c_m3_s_pa * RHO0_KG_M3).powi(2),
        (down.c_m3_s_pa * RHO0_KG_M3).powi(2),
    );
    let (b1, b2) = (up.b_crit, down.b_crit);
    // The motor's nozzles share one critical ratio: one division instead of two.
    let s1 = 1.0 / (1.0 - b1).powi(2);
    let s2 = if b2 == b1 {
        s1
    } else {
        1.0 / (1.0 - b2).powi(2)
    };
    // ṁ² = a·p² + l·p + c as a polynomial in p = p_m, for each nozzle's subsonic regime; a
    // choked nozzle passes k1·p_u² (the first) or k2·p² (the second). Each polynomial is
    // formed once (formed per use, they were a third of this function's instructions).
    let choked_up = k1 * p_u * p_u;
    let sub_up = (
        -k1 * s1,
        2.0 * k1 * s1 * b1 * p_u,
        choked_up * (1.0 - b1 * b1 * s1),
    );
    let sub_down = (
        k2 * (1.0 - b2 * b2 * s2),
        2.0 * k2 * s2 * b2 * p_d,
        -k2 * s2 * p_d * p_d,
    );
    let eval = |(a, l, c): (f64, f64, f64), p: f64| (a * p + l) * p + c;
    let (edge_up, edge_down) = (b1 * p_u, p_d / b2);
    let up_at = |p: f64| {
        if p <= edge_up {
            choked_up
        } else {
            eval(sub_up, p)
        }
    };
    let down_at = |p: f64| {
        if p >= edge_down {
            k2 * p * p
        } else {
            eval(sub_down, p)
        }
    };
    let up_choked = edge_up > p_d && choked_up - down_at(edge_up) <= 0.0;
    let down_choked = edge_down < p_u && up_at(edge_down) - k2 * edge_down * edge_down >= 0.0;
    let (a1, l1, c1) = if up_choked {
        (0.0, 0.0, choked_up)
    } else {
        sub_up
    };
    let (a2, l2, c2) = if down_choked {
        (k2, 0.0, 0.0)
    } else {
        sub_down
    };
    let in_regimes = |p: f64| {
        let up_ok = if up_choked {
            p <= edge_up
        } else {
            p > edge_up && p <= R_LAMINAR * p_u
        };
        let down_ok = if down_choked {
            p_d <= b2 * p
        } else {
            p_d > b2 * p && p_d <= R_LAMINAR * p
        };
        p > p_d && p < p_u && up_ok && down_ok
    };
    let p_m = quadratic_root_where(a1 - a2, l1 - l2, c1 - c2, in_regimes)?;
    let flow_squared = if up_choked {
        choked_up
    } else {
        eval(sub_up, p_m)
    };
    Some((p_m, flow_squared))
}

/// The first real root of a·x² + b·x + c = 0 that `accept` takes, in the order q/a, c/q with
/// q = −(b + sign(b)·√(b² − 4ac))/2 (both without cancellation); the second root is only
/// formed when the first is refused (the series flow's root is usually the first).
fn quadratic_root_where(a: f64, b: f64, c: f64, accept: impl Fn(f64) -> bool) -> Option<f64> {
    if a.abs() <= 1e-14 * (b.abs() + c.abs() / 1e5) {
        return (b != 0.0).then(|| -c / b).filter(|x| accept(*x));
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let first = q / a;
    if accept(first) {
        return Some(first);
    }
    (q != 0.0).then(|| c / q).filter(|x| accept(*x))
}

/// Safeguarded Newton solve of the series balance (used in the laminar ranges).
fn series_newton(first: &Nozzle, second: &Nozzle, p_a: f64, p_b: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (p_a.min(p_b), p_a.max(p_b));
    if hi - lo <= 0.0 {
        return (0.0, p_a);
    }
    // Start from the exact answer for b = 0, where ṁ² = (C·ρ0)²·(p_u² − p_d²) per nozzle:
    // p_m² = (C1²·p_a² + C2²·p_b²)/(C1² + C2²).
    let (c1, c2) = (first.c_m3_s_pa.powi(2), second.c_m3_s_pa.powi(2));
    let mut p_m = ((c1 * p_a * p_a + c2 * p_b * p_b) / (c1 + c2)).sqrt();
    if !(p_m > lo && p_m < hi) {
        p_m = 0.5 * (lo + hi);
    }
    for _ in 0..60 {
        let (f1, _, d1_dm) = first.flow_with_slopes(p_a, p_m);
        let (f2, d2_dm, _) = second.flow_with_slopes(p_m, p_b);
        let g = f1 - f2;
        if g > 0.0 {
            lo = p_m;
        } else {
            hi = p_m;
        }
        let slope = d1_dm - d2_dm;
        let newton = p_m - g / slope;
        // The bracket is closed: once Newton has hit the root, g rounds to either sign and
        // the new bracket end is p_m itself, which the step then returns to; an open test
        // would reject that step and bisect away from the root by up to 1e-12·p_m.
        let next = if slope < 0.0 && newton >= lo && newton <= hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        let converged = (next - p_m).abs() <= 1e-12 * p_m || hi - lo <= 1e-12 * hi;
        p_m = next;
        if converged {
            break;
        }
    }
    (0.5 * (first.flow(p_a, p_m) + second.flow(p_m, p_b)), p_m)
}

impl Nozzle {
    /// Mass flow from `p_a` to `p_b` and its partial derivatives (ṁ, ∂ṁ/∂p_a, ∂ṁ/∂p_b),
    /// in kg/s and kg/(s·Pa). With m = C·ρ0·p_u·ψ(r), r = p_d/p_u:
    /// ∂m/∂p_d = C·ρ0·ψ'(r), ∂m/∂p_u = C·ρ0·(ψ − r·ψ'(r)).
    pub fn flow_with_slopes(&self, p_a: f64, p_b: f64) -> (f64, f64, f64) {
        let k = self.c_m3_s_pa * RHO0_KG_M3;
        let (p_u, p_d, sign) = if p_a >= p_b {
            (p_a, p_b, 1.0)
        } else {
            (p_b, p_a, -1.0)
        };
        if p_u <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let r = p_d / p_u;
        let (ps, dps) = (psi(r, self.b_crit), psi_slope(r, self.b_crit));
        let (m, dm_du, dm_dd) = (k * p_u * ps, k * (ps - r * dps), k * dps);
        if sign > 0.0 {
            (m, dm_du, dm_dd)
        } else {
            (-m, -dm_dd, -dm_du)
        }
    }
}

/// dψ/dr for 0 ≤ r ≤ 1 (finite everywhere thanks to the laminar branch).
fn psi_slope(r: f64, b_crit: f64) -> f64 {
    if r <= b_crit {
        0.0
    } else if r <= R_LAMINAR {
        let x = (r - b_crit) / (1.0 - b_crit);
        -x / ((1.0 - b_crit) * (1.0 - x * x).max(1e-300).sqrt())
    } else {
        -subsonic(R_LAMINAR, b_crit) / (1.0 - R_LAMINAR)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn choked_flow_is_c_rho_p() {
        let n = Nozzle::new(6.758282e-9, 0.5);
        let expected = 6.758282e-9 * RHO0_KG_M3 * 7.3e5;
        assert!((n.flow(7.3e5, 1.0e5) - expected).abs() < 1e-15);
    }

    #[test]
    fn psi_is_continuous_at_b_and_at_laminar_threshold() {
        for b in [0.2, 0.5, 0.528] {
            assert!((psi(b - 1e-12, b) - psi(b + 1e-12, b)).abs() < 1e-5);
            let below = psi(R_LAMINAR - 1e-13, b);
            let above = psi(R_LAMINAR + 1e-13, b);
            assert!((below - above).abs() < 1e-6);
            assert_eq!(psi(1.0, b), 0.0);
        }
    }

    #[test]
    fn slopes_match_finite_differences() {
        let n = Nozzle::new(5e-9, 0.45);
        for (pa, pb) in [
            (6e5, 1e5),
            (6e5, 4e5),
            (3e5, 2.9995e5),
            (2e5, 5e5),
            (1e5, 1.00005e5),
        ] {
            let (m, da, db) = n.flow_with_slopes(pa, pb);
            assert_eq!(m, n.flow(pa, pb));
            let h = 1e-3;
            let fd_a = (n.flow(pa + h, pb) - n.flow(pa - h, pb)) / (2.0 * h);
            let fd_b = (n.flow(pa, pb + h) - n.flow(pa, pb - h)) / (2.0 * h);
            assert!(
                (da - fd_a).abs() <= 1e-5 * da.abs().max(1e-12),
                "{pa} {pb}: {da} vs {fd_a}"
            );
            assert!(
                (db - fd_b).abs() <= 1e-5 * db.abs().max(1e-12),
                "{pa} {pb}: {db} vs {fd_b}"
            );
        }
    }

    /// Both real roots of a·x² + b·x + c = 0, without cancellation: the reference that
    /// `quadratic_root_where` (which forms the second only when the first is refused)
    /// must agree with.
    fn quadratic_roots(a: f64, b: f64, c: f64) -> [Option<f64>; 2] {
        if a.abs() <= 1e-14 * (b.abs() + c.abs() / 1e5) {
            return [(b != 0.0).then(|| -c / b), None];
        }
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return [None, None];
        }
        let q = -0.5 * (b + b.signum() * disc.sqrt());
        [Some(q / a), (q != 0.0).then(|| c / q)]
    }

    #[test]
    fn the_first_accepted_root_is_the_first_accepted_of_both() {
        let accept = |x: f64| x > 0.5 && x < 3.0;
        for (a, b, c) in [
            (1.0, -3.0, 2.0),
            (1.0, -5.0, 6.0),
            (-2.0, 1.0, 3.0),
            (1.0, 2.0, 5.0),
            (0.0, 2.0, -3.0),
            (1e-20, 2.0, -3.0),
            (1.0, 0.0, -4.0),
        ] {
            let eager = quadratic_roots(a, b, c)
                .into_iter()
                .flatten()
                .find(|x| accept(*x));
            assert_eq!(quadratic_root_where(a, b, c, accept), eager, "{a} {b} {c}");
        }
    }

    #[test]
    fn closed_form_series_agrees_with_newton_in_every_regime() {
        let duct = Nozzle::new(6.758e-9, 0.5);
        for c in [5e-8, 1e-8, 3e-9, 1e-9, 2e-10] {
            let thr = Nozzle::new(c, 0.4);
            for p_up in [1.02e5, 1.5e5, 2.5e5, 4e5, 8e5] {
                for (a, b, pa, pb) in [
                    (&duct, &thr, p_up, 1.01325e5),
                    (&thr, &duct, 1.01325e5, p_up),
                ] {
                    let (flow, p_m) = series_flow(a, b, pa, pb);
                    let (flow_n, p_m_n) = series_newton(a, b, pa, pb);
                    assert!(
                        (p_m - p_m_n).abs() < 1e-6 * p_m,
                        "c {c:e} p {p_up}: {p_m} vs {p_m_n}"
                    );
                    assert!(
                        (flow - flow_n).abs() < 1e-9 * flow.abs(),
                        "{flow} vs {flow_n}"
                    );
                }
            }
        }
    }

    #[test]
    fn closed_form_picks_each_regime_pair_correctly() {
        // The regime pair is chosen from the sign of the balance at the regime edges; check
        // that every pair occurs and that each closed-form root equals Newton's.
        let mut seen = [[0usize; 2]; 2];
        for (c1, b1) in [(6.758e-9, 0.5), (2e-9, 0.3), (1e-8, 0.45), (1e-9, 0.5)] {
            for (c2, b2) in [
                (5e-8, 0.4),
                (6e-9, 0.5),
                (3e-9, 0.5),
                (1e-9, 0.2),
                (2e-10, 0.4),
            ] {
                for p_u in [1.05e5, 1.5e5, 2.5e5, 4e5, 8e5, 1.2e6] {
                    let (up, down) = (Nozzle::new(c1, b1), Nozzle::new(c2, b2));
                    let p_d = 1.01325e5;
                    let Some((p, m2)) = series_closed_form(&up, &down, p_u, p_d) else {
                        continue;
                    };
                    let (m_newton, p_newton) = series_newton(&up, &down, p_u, p_d);
                    assert!((p - p_newton).abs() < 1e-6 * p, "{p} vs {p_newton}");
                    // The flow from the polynomial is each nozzle's flow at p_m.
                    let m = m2.sqrt();
                    for flow in [up.flow(p_u, p), down.flow(p, p_d)] {
                        assert!((m - flow).abs() <= 1e-12 * m, "{m} vs {flow}");
                    }
                    assert!((m - m_newton).abs() < 1e-6 * m, "{m} vs {m_newton}");
                    seen[usize::from(p <= b1 * p_u)][usize::from(p_d <= b2 * p)] += 1;
                }
            }
        }
        assert!(
            seen.iter().flatten().all(|&n| n > 0),
            "regime pairs hit: {seen:?}"
        );
    }

    #[test]
    fn newton_series_balances_to_rounding() {
        // A wide throttle behind the duct sits in its laminar range (the Newton path); the
        // flows of the two nozzles must agree to rounding, not to the solver's tolerance,
        // or finite differences of the flow turn noisy.
        let duct = Nozzle::new(6.758282e-9, 0.5);
        let thr = Nozzle::new(1e-7, 0.5);
        for i in 0..200 {
            let p_a = 0.9e5 + f64::from(i) * 0.01;
            let (flow, p_m) = series_flow(&duct, &thr, p_a, 101_325.0);
            let residual = duct.flow(p_a, p_m) - thr.flow(p_m, 101_325.0);
            assert!(
                residual.abs() <= 1e-12 * flow.abs(),
                "{p_a}: residual {residual:e} of {flow:e}"
            );
        }
    }

    #[test]
    fn series_of_equal_nozzles_has_midpoint_between() {
        let n = Nozzle::new(5e-9, 0.5);
        let (flow, p_m) = series_flow(&n, &n, 6e5, 1e5);
        assert!(p_m > 1e5 && p_m < 6e5);
        assert!((n.flow(6e5, p_m) - flow).abs() < 1e-9 * flow);
        assert!((n.flow(p_m, 1e5) - flow).abs() < 1e-9 * flow);
        assert!(flow < n.flow(6e5, 1e5));
    }
}
