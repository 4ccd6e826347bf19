//! ISO 6358 (1989 form) restriction with a laminar extension near pressure ratio 1
//! (SPEC §1.4). Used for the ducts and for every leakage path.
//!
//! ṁ = C·ρ0·p_u·√(T0/T_u)·ψ(r),  r = p_d/p_u,
//! ψ = 1                                 for r ≤ b       (choked)
//! ψ = √(1 − ((r − b)/(1 − b))²)         for b < r ≤ r_lam (subsonic)
//! ψ = ψ(r_lam)·(1 − r)/(1 − r_lam)      for r > r_lam = 0.999 (laminar)
//!
//! C in m³/(s·Pa), pressures in Pa absolute, ṁ in kg/s. The model is isothermal (T_u = T0),
//! so the temperature factor is 1. Flow reverses by symmetry when p_d > p_u.

use crate::constants::RHO0_KG_M3;

/// Pressure ratio above which the flow is taken as laminar (linear in Δp).
pub const R_LAMINAR: f64 = 0.999;

/// An ISO 6358 restriction: sonic conductance C (m³/(s·Pa)) and critical ratio b.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nozzle {
    pub c_m3_s_pa: f64,
    pub b_crit: f64,
}

/// Flow function ψ(r) for 0 ≤ r ≤ 1: continuous, monotone non-increasing, ψ(1) = 0,
/// with finite slope everywhere (the laminar branch removes the infinite slope at r = 1).
pub fn psi(r: f64, b_crit: f64) -> f64 {
    if r <= b_crit {
        1.0
    } else if r <= R_LAMINAR {
        subsonic(r, b_crit)
    } else {
        subsonic(R_LAMINAR, b_crit) * ((1.0 - r) / (1.0 - R_LAMINAR)).max(0.0)
    }
}

fn subsonic(r: f64, b_crit: f64) -> f64 {
    let x = (r - b_crit) / (1.0 - b_crit);
    (1.0 - x * x).max(0.0).sqrt()
}

impl Nozzle {
    pub fn new(c_m3_s_pa: f64, b_crit: f64) -> Self {
        Self { c_m3_s_pa, b_crit }
    }

    /// Mass flow from the port at `p_a` to the port at `p_b`, kg/s (negative when p_b > p_a).
    pub fn flow(&self, p_a: f64, p_b: f64) -> f64 {
        if p_a >= p_b {
            self.forward(p_a, p_b)
        } else {
            -self.forward(p_b, p_a)
        }
    }

    fn forward(&self, p_u: f64, p_d: f64) -> f64 {
        if p_u <= 0.0 {
            return 0.0;
        }
        self.c_m3_s_pa * RHO0_KG_M3 * p_u * psi(p_d / p_u, self.b_crit)
    }
}

/// Steady flow through two restrictions in series with no volume between them, kg/s, and
/// the pressure between them, Pa. The intermediate pressure is the root of
/// `first.flow(p_a, p_m) = second.flow(p_m, p_b)`, which is unique because the left side
/// falls and the right side rises with p_m; it is bracketed by [min, max] of p_a and p_b and
/// found by bisection refined with the Illinois false-position step.
pub fn series_flow(first: &Nozzle, second: &Nozzle, p_a: f64, p_b: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (p_a.min(p_b), p_a.max(p_b));
    let residual = |p_m: f64| first.flow(p_a, p_m) - second.flow(p_m, p_b);
    let (mut f_lo, mut f_hi) = (residual(lo), residual(hi));
    if hi - lo <= 0.0 {
        return (0.0, p_a);
    }
    // residual falls with p_m: f(lo) ≥ 0 ≥ f(hi).
    let mut side = 0i8;
    for _ in 0..100 {
        let mut p_m = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if !p_m.is_finite() || p_m <= lo || p_m >= hi {
            p_m = 0.5 * (lo + hi);
        }
        let f = residual(p_m);
        if f > 0.0 {
            lo = p_m;
            f_lo = f;
            if side == 1 {
                f_hi *= 0.5;
            }
            side = 1;
        } else {
            hi = p_m;
            f_hi = f;
            if side == -1 {
                f_lo *= 0.5;
            }
            side = -1;
        }
        if hi - lo <= 1e-10 * hi {
            break;
        }
    }
    let p_m = 0.5 * (lo + hi);
    (0.5 * (first.flow(p_a, p_m) + second.flow(p_m, p_b)), p_m)
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
    fn series_of_equal_nozzles_has_midpoint_between() {
        let n = Nozzle::new(5e-9, 0.5);
        let (flow, p_m) = series_flow(&n, &n, 6e5, 1e5);
        assert!(p_m > 1e5 && p_m < 6e5);
        assert!((n.flow(6e5, p_m) - flow).abs() < 1e-9 * flow);
        assert!((n.flow(p_m, 1e5) - flow).abs() < 1e-9 * flow);
        assert!(flow < n.flow(6e5, 1e5));
    }
}
