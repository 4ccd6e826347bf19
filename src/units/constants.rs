//! Physical constants of the model (docs/model.md, "Constants"; SI units).

/// Specific gas constant of air, R = 287 J/(kg·K).
const R_AIR: f64 = 287.0;
/// Reference temperature T0 = 293.15 K (isothermal model, ISO 6358 reference).
pub const T0_K: f64 = 293.15;
/// R·T0 in J/kg; converts p·V to mass: m = p·V/(R·T0).
pub(crate) const RT0: f64 = R_AIR * T0_K;
/// ISO 6358 reference density ρ0 = 1.185 kg/m³.
pub const RHO0_KG_M3: f64 = 1.185;
/// Standard atmosphere, used unless the rig file gives its own p_atm.
pub const P_ATM_PA: f64 = 101_325.0;
/// Speed scale of the forward/reverse torque blend (docs/model.md, "Cycle work and
/// torque"), rad/s.
pub const OMEGA_BLEND_RAD_S: f64 = 1.0;

/// Specific gas constant of dry air for converting volume flows at stated reference
/// conditions to mass (ISO 2533 value), J/(kg·K). The model itself uses [`R_AIR`]
/// (docs/model.md, "Constants"); this one only turns a catalogue's "l/s at 1 bar, 20 °C"
/// into kg/s.
const R_DRY_AIR: f64 = 287.052_87;
/// Free air (ISO 1217 reference inlet conditions, which compressor and air-motor
/// catalogues quote "free air" at): 100 kPa, 20 °C, dry: ρ = p/(R·T) ≈ 1.18836 kg/m³.
pub(crate) const RHO_FREE_AIR_KG_M3: f64 = 100_000.0 / (R_DRY_AIR * 293.15);
/// Normal conditions of DIN 1343 (Nl, Nm³): 101.325 kPa, 0 °C, dry: ρ ≈ 1.29228 kg/m³.
pub(crate) const RHO_NORMAL_KG_M3: f64 = 101_325.0 / (R_DRY_AIR * 273.15);
/// US "standard air" of scfm (ASME/ANSI): 0.075 lb/ft³ by definition (14.7 psia, 68 °F,
/// 36 % relative humidity), = 0.075·0.45359237 kg / 0.028316846592 m³ ≈ 1.20137 kg/m³.
pub(crate) const RHO_SCFM_KG_M3: f64 = 0.075 * LB_KG / FT3_M3;
/// One avoirdupois pound, kg (exact by definition).
const LB_KG: f64 = 0.453_592_37;
/// One foot, m (exact by definition).
pub(crate) const FT_M: f64 = 0.3048;
/// One inch, m (exact by definition).
pub(crate) const IN_M: f64 = 0.0254;
/// One cubic foot, m³ (exact: 0.3048³).
pub(crate) const FT3_M3: f64 = 0.028_316_846_592;
/// Standard gravity, m/s² (exact by definition; defines the pound-force).
pub(crate) const G_N: f64 = 9.806_65;
/// One pound-force, N (exact: lb·g_n = 4.4482216152605 N).
pub(crate) const LBF_N: f64 = LB_KG * G_N;
/// One pound-force per square inch, Pa (≈ 6894.757 Pa).
pub(crate) const PSI_PA: f64 = LBF_N / (IN_M * IN_M);
/// One mechanical horsepower, W (550 ft·lbf/s ≈ 745.700 W).
pub(crate) const HP_W: f64 = 550.0 * FT_M * LBF_N;
