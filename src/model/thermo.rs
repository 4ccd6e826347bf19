//! Thermodynamics of the ideal motor: polytropic cycle work and torque (paper eqs. 8–13 with
//! the sign corrections of docs/model.md, "Cycle work and torque") and the displacement
//! flows (eqs. 14–18; docs/model.md, "Flows through the ideal motor").
//!
//! Pressures in Pa (absolute), volumes in m³, work in J, torque in N·m, ω in rad/s,
//! mass flows in kg/s.

use crate::units::constants::{OMEGA_BLEND_RAD_S, RT0};
use std::f64::consts::PI;

/// The volumes and polytropic index that define one compartment's cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cycle {
    /// Number of vanes z (compartments per revolution).
    pub vanes: f64,
    /// Filling volume V_fill = V_disp/z, m³.
    pub v_fill_m3: f64,
    /// Dead volume V_d, m³.
    pub(crate) v_dead_m3: f64,
    /// Expansion ratio ε = V_exp/V_fill.
    pub eps: f64,
    /// Polytropic index n, 1 ≤ n ≤ 1.4.
    pub n_poly: f64,
    /// V_fill·(1 − ε^(1−n))/(n−1) and V_exp·(ε^(n−1) − 1)/(n−1), m³, computed once: the
    /// right-hand side evaluates the work many thousand times per simulation.
    expansion_m3: f64,
    compression_m3: f64,
    /// V_fill − V_d, m³, computed once (the displacement term of every [`Cycle::work`]).
    swept_m3: f64,
    /// k = V_disp/(2π·R·T0) of the displacement flows (eqs. 16–17), kg/(s·Pa·rad/s),
    /// computed once: the right-hand side and the linearisation divided by 2π·R·T0 on
    /// every call for a value the parameters fix.
    displacement_k: f64,
    /// The cycle torque at the unit pressures (1, 0, 0), (0, 1, 0) and (0, 0, 1): its
    /// gradient, the torque being linear and homogeneous in its three pressures; computed
    /// once for every linearisation.
    unit_torques: [f64; 3],
}

/// `(ε^(n−1) − 1)/(n−1)`, continuous through n = 1 where it equals ln ε.
///
/// Written with `expm1` so that n → 1 loses no digits (no 0/0).
fn compression_factor(eps: f64, n_poly: f64) -> f64 {
    let ln_eps = eps.ln();
    let x = (n_poly - 1.0) * ln_eps;
    if x.abs() < 1e-12 {
        ln_eps * (1.0 + 0.5 * x)
    } else {
        ln_eps * x.exp_m1() / x
    }
}

/// `(1 − ε^(1−n))/(n−1)`, continuous through n = 1 where it equals ln ε.
fn expansion_factor(eps: f64, n_poly: f64) -> f64 {
    let ln_eps = eps.ln();
    let x = (n_poly - 1.0) * ln_eps;
    if x.abs() < 1e-12 {
        ln_eps * (1.0 - 0.5 * x)
    } else {
        -ln_eps * (-x).exp_m1() / x
    }
}

impl Cycle {
    /// A cycle from its volumes, m³, expansion ratio and polytropic index.
    pub fn new(vanes: f64, v_fill_m3: f64, v_dead_m3: f64, eps: f64, n_poly: f64) -> Self {
        let mut cycle = Self {
            vanes,
            v_fill_m3,
            v_dead_m3,
            eps,
            n_poly,
            expansion_m3: v_fill_m3 * expansion_factor(eps, n_poly),
            compression_m3: eps * v_fill_m3 * compression_factor(eps, n_poly),
            swept_m3: v_fill_m3 - v_dead_m3,
            displacement_k: 0.0,
            unit_torques: [0.0; 3],
        };
        // Cached once per motor; written as the per-call expressions they stand for, so
        // that the cached values are the same bits.
        cycle.displacement_k = cycle.v_disp_m3() / (2.0 * PI * RT0);
        cycle.unit_torques = [
            cycle.torque_one_way(1.0, 0.0, 0.0),
            cycle.torque_one_way(0.0, 1.0, 0.0),
            cycle.torque_one_way(0.0, 0.0, 1.0),
        ];
        cycle
    }

    /// k = V_disp/(2π·R·T0), the displacement mass flow per pascal of pressure and rad/s of
    /// speed, kg/(s·Pa·rad/s) (eqs. 16–17), as computed once by [`Cycle::new`].
    pub(crate) fn displacement_k(&self) -> f64 {
        self.displacement_k
    }

    /// ∂T/∂(p_fill, p_dis, p_e) of [`Cycle::torque_one_way`], N·m/Pa: its value at the
    /// unit pressures, as computed once by [`Cycle::new`].
    pub(crate) fn unit_torques(&self) -> [f64; 3] {
        self.unit_torques
    }

    /// Expanded volume V_exp = ε·V_fill, m³.
    pub fn v_exp_m3(&self) -> f64 {
        self.eps * self.v_fill_m3
    }

    /// Nominal displacement V_disp = z·V_fill (eq. 7), m³.
    pub(crate) fn v_disp_m3(&self) -> f64 {
        self.vanes * self.v_fill_m3
    }

    /// Work done BY the air in one compartment per cycle (eqs. 9–12; docs/model.md, "Cycle
    /// work and torque"), J:
    ///
    /// ```text
    /// W = (p_a − p_b)(V_fill − V_d)
    ///   + p_a·V_fill·(1 − ε^(1−n))/(n−1)      (expansion b→c)
    ///   − p_e·V_exp·(ε^(n−1) − 1)/(n−1)       (compression d→e, from p_e)
    /// ```
    ///
    /// `p_a`: filling pressure, `p_b`: discharge pressure, `p_e`: exhaust pressure, all Pa.
    pub fn work(&self, p_a: f64, p_b: f64, p_e: f64) -> f64 {
        let displacement = (p_a - p_b) * self.swept_m3;
        displacement + p_a * self.expansion_m3 - p_e * self.compression_m3
    }

    /// Torque of the ideal motor turning forward, T = z·W/(2π) (eq. 13), N·m,
    /// filled from `p_fill`, discharging to `p_dis`, exhausting to `p_e`.
    pub(crate) fn torque_one_way(&self, p_fill: f64, p_dis: f64, p_e: f64) -> f64 {
        self.vanes * self.work(p_fill, p_dis, p_e) / (2.0 * PI)
    }
}

/// Weight of the forward direction in the torque blend, ½(1 + tanh(ω/ω_b)) (docs/model.md,
/// "Cycle work and torque").
pub(crate) fn forward_weight(omega: f64) -> f64 {
    0.5 * (1.0 + crate::numerics::scalar::tanh(omega / OMEGA_BLEND_RAD_S))
}

/// Displacement mass flows of the ideal motor, kg/s, as net flows INTO each lumped volume.
///
/// They sum to zero exactly (eq. 18): the ideal motor stores no air.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DisplacementFlows {
    /// Into V_1, kg/s.
    pub(crate) into_1_kg_s: f64,
    /// Into V_2, kg/s.
    pub(crate) into_2_kg_s: f64,
    /// Into V_e, kg/s.
    pub(crate) into_e_kg_s: f64,
}

/// Displacement flows (eqs. 16–18; docs/model.md, "Flows through the ideal motor") for
/// speed ω (rad/s).
///
/// Forward (ω > 0): ṁ_from1 = p_fill·ω·V_disp/(2π·RT) leaves volume 1,
/// ṁ_to2 = p_e·ω·ε·V_disp/(2π·RT) enters volume 2, the rest ṁ_from1 − ṁ_to2 enters volume e.
/// Reverse (ω < 0) mirrors ports 1 and 2 with |ω|. `carry_kg_s` is mass carried back from
/// the discharge side to the inlet side in the dead volume (the `dead_volume_carryover`
/// effect), which reduces both the inflow and the discharge; 0 for the base model.
/// `p_fill` is the filling pressure of the side that is the inlet for the sign of ω
/// (p_1 forward, p_2 reverse, in the base model).
/// The flows are ∝ |ω|, so they are continuous through ω = 0.
pub(crate) fn displacement_flows(
    cycle: &Cycle,
    omega: f64,
    p_fill: f64,
    p_e: f64,
    carry_kg_s: f64,
) -> DisplacementFlows {
    let k = cycle.displacement_k();
    let speed = omega.abs();
    let from_inlet = (p_fill * speed * k - carry_kg_s).max(0.0);
    let to_outlet = (p_e * speed * cycle.eps * k - carry_kg_s).max(0.0);
    let into_e = from_inlet - to_outlet;
    if omega >= 0.0 {
        DisplacementFlows {
            into_1_kg_s: -from_inlet,
            into_2_kg_s: to_outlet,
            into_e_kg_s: into_e,
        }
    } else {
        DisplacementFlows {
            into_1_kg_s: to_outlet,
            into_2_kg_s: -from_inlet,
            into_e_kg_s: into_e,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ar034(eps: f64, n_poly: f64) -> Cycle {
        Cycle::new(5.0, 3.8e-6 / 5.0, 0.1e-6, eps, n_poly)
    }

    #[test]
    fn eps_one_gives_gear_motor_torque() {
        let c = ar034(1.0, 1.3);
        let (p1, p2) = (7.3e5, 1.2e5);
        let gear = 5.0 * (p1 - p2) * (c.v_fill_m3 - c.v_dead_m3) / (2.0 * PI);
        assert!((c.torque_one_way(p1, p2, 1.1e5) - gear).abs() < 1e-12);
    }

    #[test]
    fn isothermal_limit_is_continuous_and_analytic() {
        let (p_a, p_b, p_e) = (7.0e5, 1.5e5, 1.2e5);
        let iso = ar034(1.071, 1.0).work(p_a, p_b, p_e);
        let c = ar034(1.071, 1.0);
        let ln_eps = 1.071f64.ln();
        let analytic = (p_a - p_b) * (c.v_fill_m3 - c.v_dead_m3) + p_a * c.v_fill_m3 * ln_eps
            - p_e * c.v_exp_m3() * ln_eps;
        assert!((iso - analytic).abs() < 1e-12 * analytic.abs());
        for dn in [1e-3, 1e-6, 1e-9, 1e-13] {
            let w = ar034(1.071, 1.0 + dn).work(p_a, p_b, p_e);
            assert!(
                (w - iso).abs() <= 2.0 * dn * iso.abs() + 1e-15,
                "dn {dn}: {w} vs {iso}"
            );
        }
    }

    #[test]
    fn expansion_factor_matches_direct_formula_away_from_one() {
        let (eps, n): (f64, f64) = (1.2, 1.3);
        let direct = (1.0 - eps.powf(1.0 - n)) / (n - 1.0);
        assert!((expansion_factor(eps, n) - direct).abs() < 1e-14);
        let direct = (eps.powf(n - 1.0) - 1.0) / (n - 1.0);
        assert!((compression_factor(eps, n) - direct).abs() < 1e-14);
    }

    #[test]
    fn displacement_flows_conserve_mass_both_ways() {
        let c = ar034(1.071, 1.3);
        for omega in [-900.0, -1.0, 0.0, 3.0, 1200.0] {
            let f = displacement_flows(&c, omega, 6e5, 1.3e5, 0.0);
            assert!((f.into_1_kg_s + f.into_2_kg_s + f.into_e_kg_s).abs() < 1e-18);
        }
    }

    #[test]
    fn reverse_flows_mirror_forward() {
        let c = ar034(1.071, 1.3);
        let fwd = displacement_flows(&c, 800.0, 6e5, 1.3e5, 0.0);
        let rev = displacement_flows(&c, -800.0, 6e5, 1.3e5, 0.0);
        assert_eq!(fwd.into_1_kg_s, rev.into_2_kg_s);
        assert_eq!(fwd.into_2_kg_s, rev.into_1_kg_s);
        assert_eq!(fwd.into_e_kg_s, rev.into_e_kg_s);
    }
}
