//! Compartment geometry of the vane motor (paper eqs. 1–7; docs/model.md, "Geometry").
//!
//! All lengths in m, volumes in m³, angles in rad. The paper's eq. 5 prints `V_α − V_{α−iγ}`
//! for the middle branch; the compartment between two neighbouring vanes is bounded by the vane
//! at α and the one at α − γ, so the middle branch is `V_α − V_{α−γ}`.

use std::f64::consts::PI;

/// Stator/rotor geometry of a vane motor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VaneGeometry {
    /// Rotor length L, m.
    pub(crate) length_m: f64,
    /// Stator (cylinder) radius R_S, m.
    pub r_stator_m: f64,
    /// Rotor radius R_R, m.
    pub(crate) r_rotor_m: f64,
    /// Number of vanes z.
    pub vanes: u32,
}

/// Port timing angles (position of the leading vane of a compartment), rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PortTiming {
    /// Angle at which the compartment opens to the inlet (state a: dead volume).
    pub(crate) alpha_dead_rad: f64,
    /// Angle at which the inlet cuts off (state b: filling volume).
    pub(crate) alpha_fill_rad: f64,
    /// Angle at which the exhaust opens (state c: expanded volume).
    pub(crate) alpha_exp_rad: f64,
}

/// Volumes derived from geometry and port timing (eqs. 5–7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DerivedVolumes {
    /// Dead volume per compartment V_0, m³ (eq. 5).
    pub(crate) v_dead_m3: f64,
    /// Compartment volume at inlet cut-off V_fill, m³ (eq. 5).
    pub v_fill_m3: f64,
    /// Compartment volume at exhaust opening V_exp, m³ (eq. 5).
    pub v_exp_m3: f64,
    /// ε = V_exp / V_fill (eq. 6).
    pub eps: f64,
    /// V_disp,nom = z·V_fill (eq. 7).
    pub(crate) v_disp_m3: f64,
}

impl VaneGeometry {
    /// Motor AR034-11 of the paper's appendix.
    #[cfg(test)]
    pub(crate) fn ar034_11() -> Self {
        Self {
            length_m: 32e-3,
            r_stator_m: 9e-3,
            r_rotor_m: 7.55e-3,
            vanes: 5,
        }
    }

    /// Vane angle γ = 2π/z (eq. 1), rad.
    pub(crate) fn gamma(&self) -> f64 {
        2.0 * PI / f64::from(self.vanes)
    }

    /// Eccentricity ex = R_S − R_R (eq. 2), m.
    fn eccentricity(&self) -> f64 {
        self.r_stator_m - self.r_rotor_m
    }

    /// β(α) = α − asin(ex·sin α / R_S) (eq. 3), rad.
    pub fn beta(&self, alpha: f64) -> f64 {
        alpha - (self.eccentricity() * alpha.sin() / self.r_stator_m).asin()
    }

    /// Volume swept from the sealing line up to angle α (eq. 4), m³:
    /// V_α = L/2 · (R_S²·β − R_R²·α − ex·R_S·sin β).
    fn v_alpha(&self, alpha: f64) -> f64 {
        let beta = self.beta(alpha);
        let (rs, rr) = (self.r_stator_m, self.r_rotor_m);
        0.5 * self.length_m
            * (rs * rs * beta - rr * rr * alpha - self.eccentricity() * rs * beta.sin())
    }

    /// Working-compartment volume V_w(α) between the vane at α and the vane at α − γ (eq. 5), m³.
    /// Defined for 0 ≤ α ≤ 2π + γ.
    pub(crate) fn v_working(&self, alpha: f64) -> f64 {
        let gamma = self.gamma();
        let two_pi = 2.0 * PI;
        if alpha <= gamma {
            self.v_alpha(alpha)
        } else if alpha <= two_pi {
            self.v_alpha(alpha) - self.v_alpha(alpha - gamma)
        } else {
            self.v_alpha(two_pi) - self.v_alpha(alpha - gamma)
        }
    }

    /// Angle of the largest compartment, α = π + γ/2 (by symmetry of V_w about it).
    #[cfg(test)]
    fn alpha_max_volume(&self) -> f64 {
        PI + 0.5 * self.gamma()
    }

    /// Angle on the rising flank (γ ≤ α ≤ π + γ/2) at which V_w reaches `volume_m3`,
    /// found by bisection (V_w rises monotonically there). `None` if out of reach.
    #[cfg(test)]
    pub(crate) fn alpha_at_volume(&self, volume_m3: f64) -> Option<f64> {
        let (mut lo, mut hi) = (self.gamma(), self.alpha_max_volume());
        if volume_m3 < self.v_working(lo) || volume_m3 > self.v_working(hi) {
            return None;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if self.v_working(mid) < volume_m3 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(0.5 * (lo + hi))
    }

    /// V_fill, V_exp, V_d, ε and V_disp,nom from the port timing (eqs. 5–7).
    pub(crate) fn derived_volumes(&self, timing: &PortTiming) -> DerivedVolumes {
        let v_dead_m3 = self.v_working(timing.alpha_dead_rad);
        let v_fill_m3 = self.v_working(timing.alpha_fill_rad);
        let v_exp_m3 = self.v_working(timing.alpha_exp_rad);
        DerivedVolumes {
            v_dead_m3,
            v_fill_m3,
            v_exp_m3,
            eps: v_exp_m3 / v_fill_m3,
            v_disp_m3: f64::from(self.vanes) * v_fill_m3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn full_turn_volume_is_annulus() {
        let g = VaneGeometry::ar034_11();
        let annulus = PI * g.length_m * (g.r_stator_m.powi(2) - g.r_rotor_m.powi(2));
        assert!((g.v_alpha(2.0 * PI) - annulus).abs() < 1e-15);
    }

    #[test]
    fn ar034_largest_compartment_and_port_angles() {
        let g = VaneGeometry::ar034_11();
        let v_max = g.v_working(g.alpha_max_volume());
        assert!((v_max - 1.00e-6).abs() < 0.03e-6, "v_max = {v_max:e}");
        // The compartment is largest at π + γ/2: a little either side is smaller.
        assert!(g.v_working(g.alpha_max_volume() - 0.05) < v_max);
        assert!(g.v_working(g.alpha_max_volume() + 0.05) < v_max);
        let v_fill = 3.8e-6 / 5.0;
        let a_fill = g.alpha_at_volume(v_fill).unwrap().to_degrees();
        assert!((a_fill - 162.0).abs() < 2.0, "fill angle {a_fill}");
        let a_exp = g.alpha_at_volume(1.071 * v_fill).unwrap().to_degrees();
        assert!((a_exp - 169.0).abs() < 2.0, "expansion angle {a_exp}");
    }

    #[test]
    fn compartments_sum_to_annulus() {
        // With vanes at a0 + iγ, the chambers (the one cut by the sealing line counted as its
        // two halves, eq. 5's first and last branch) together fill the crescent.
        let g = VaneGeometry::ar034_11();
        let gamma = g.gamma();
        for k in 0..7 {
            let a0 = 0.1 + 0.13 * f64::from(k);
            let total: f64 = (0..=g.vanes)
                .map(|i| g.v_working(a0 + f64::from(i) * gamma))
                .sum();
            assert!(
                (total - g.v_alpha(2.0 * PI)).abs() < 1e-12,
                "total {total:e}"
            );
        }
    }

    #[test]
    fn derived_volumes_reproduce_appendix() {
        let g = VaneGeometry::ar034_11();
        let v_fill = 3.8e-6 / 5.0;
        let timing = PortTiming {
            alpha_dead_rad: 0.5 * g.gamma(),
            alpha_fill_rad: g.alpha_at_volume(v_fill).unwrap(),
            alpha_exp_rad: g.alpha_at_volume(1.071 * v_fill).unwrap(),
        };
        let d = g.derived_volumes(&timing);
        assert!((d.v_disp_m3 - 3.8e-6).abs() < 1e-12);
        assert!((d.eps - 1.071).abs() < 1e-9);
        assert!(d.v_dead_m3 > 0.0 && d.v_dead_m3 < d.v_fill_m3);
    }
}
