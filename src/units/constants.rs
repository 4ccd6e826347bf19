//! Physical constants fixed by SPEC §1 (SI units).

/// Specific gas constant of air, R = 287 J/(kg·K).
pub const R_AIR: f64 = 287.0;
/// Reference temperature T0 = 293.15 K (isothermal model, ISO 6358 reference).
pub const T0_K: f64 = 293.15;
/// R·T0 in J/kg; converts p·V to mass: m = p·V/(R·T0).
pub const RT0: f64 = R_AIR * T0_K;
/// ISO 6358 reference density ρ0 = 1.185 kg/m³.
pub const RHO0_KG_M3: f64 = 1.185;
/// Standard atmosphere, used unless the rig file gives its own p_atm.
pub const P_ATM_PA: f64 = 101_325.0;
/// Speed scale of the forward/reverse torque blend (SPEC §1.2), rad/s.
pub const OMEGA_BLEND_RAD_S: f64 = 1.0;
