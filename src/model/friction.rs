//! Friction torque of rotor, vanes and bearings (docs/model.md, "Mechanics and friction"
//! and "Missing-physics catalog"), N·m.
//!
//! Base model: T_f = T_c·tanh(ω/ω_reg) + d·ω (regularised Coulomb plus viscous).
//! The tanh regularisation replaces the discontinuous sign function so that the ODE has a
//! finite Jacobian at standstill; ω_reg = 0.2 rad/s is well below any speed of interest.

/// Regularised Coulomb plus viscous friction, N·m.
#[cfg(test)]
fn coulomb_viscous(omega: f64, t_coulomb_nm: f64, visc_nm_s_rad: f64, w_reg: f64) -> f64 {
    t_coulomb_nm * (omega / w_reg).tanh() + visc_nm_s_rad * omega
}

/// Magnitude of the dry part of Stribeck friction, T_c + (T_s − T_c)·exp(−(ω/ω_s)²), N·m.
pub(crate) fn stribeck_dry(
    omega: f64,
    t_coulomb_nm: f64,
    t_static_nm: f64,
    w_stribeck: f64,
) -> f64 {
    t_coulomb_nm + (t_static_nm - t_coulomb_nm) * (-(omega / w_stribeck).powi(2)).exp()
}

/// Stribeck breakaway friction (`breakaway_friction`; docs/model.md, "Missing-physics
/// catalog"), N·m: T_f = (T_c + (T_s − T_c)·exp(−(ω/ω_s)²))·tanh(ω/ω_reg) + d·ω.
#[cfg(test)]
fn stribeck(
    omega: f64,
    t_coulomb_nm: f64,
    t_static_nm: f64,
    w_stribeck: f64,
    visc_nm_s_rad: f64,
    w_reg: f64,
) -> f64 {
    stribeck_dry(omega, t_coulomb_nm, t_static_nm, w_stribeck) * (omega / w_reg).tanh()
        + visc_nm_s_rad * omega
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn friction_is_odd_and_saturates_at_coulomb() {
        for w in [0.01, 0.3, 10.0, 900.0] {
            let f = coulomb_viscous(w, 0.02, 6e-5, 0.2);
            assert_eq!(f, -coulomb_viscous(-w, 0.02, 6e-5, 0.2));
        }
        assert!((coulomb_viscous(100.0, 0.02, 0.0, 0.2) - 0.02).abs() < 1e-15);
    }

    #[test]
    fn stribeck_reduces_to_coulomb_when_static_equals_coulomb() {
        for w in [0.05, 1.0, 50.0] {
            let a = stribeck(w, 0.02, 0.02, 5.0, 6e-5, 0.2);
            assert!((a - coulomb_viscous(w, 0.02, 6e-5, 0.2)).abs() < 1e-15);
        }
        // Far above ω_s the static excess has decayed away.
        let fast = stribeck(200.0, 0.02, 0.05, 5.0, 6e-5, 0.2);
        assert!((fast - coulomb_viscous(200.0, 0.02, 6e-5, 0.2)).abs() < 1e-12);
    }
}
