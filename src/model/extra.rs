//! Terms outside the catalog (docs/model.md, "Missing-physics catalog", last paragraph:
//! "uncatalogued"): `coefficient · pressure(x) · speed(ω)` added to one balance of the
//! motor, or carried along a leak path between two volumes (or a volume and atmosphere), so
//! that the mass one balance loses the other gains. `vanefit diagnose` finds them; fit
//! files carry them in `model.discovered`, and every command that reads a fit file applies
//! them.
//!
//! # Leak paths
//!
//! A term whose balance is [`BalanceId::Path`] is a mass flow, kg/s, from the path's
//! `from` chamber to its `to` chamber: it leaves `from`'s mass balance and enters `to`'s
//! (atmosphere has none), so mass stays conserved. Its pressure factor is then a flow law of
//! Δp = p_from − p_to ([`PressureFactor::Laminar`], [`PressureFactor::CompressibleLaminar`],
//! [`PressureFactor::Turbulent`], [`PressureFactor::Quadratic`], [`PressureFactor::Orifice`],
//! [`PressureFactor::Iso6358`]; formulas and sources in docs/diagnosis.md, "Term library");
//! any other pressure factor
//! is taken as is (the flow from→to is coefficient·factor·speed). A flow law on a
//! one-balance term has no Δp and contributes nothing; fit files refuse it.

use crate::model::effects::Category;
use crate::model::nozzle;
use crate::numerics::ode::State;
use PressureFactor as P;
use SpeedFactor as W;

/// The balance a discovered term enters (docs/model.md, "Missing-physics catalog":
/// uncatalogued mismatches).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum BalanceId {
    /// The torque balance: the term is a loss torque, N·m, added to the friction torque
    /// (so it also lowers the shaft torque a datasheet measures).
    Torque,
    /// Mass balance of V_1: the term is a mass flow INTO V_1, kg/s (negative: a leak out).
    Mass1,
    /// Mass balance of V_2, kg/s into V_2.
    Mass2,
    /// Mass balance of V_e, kg/s into V_e.
    MassE,
    /// Not one balance but a leak path: the term is a mass flow, kg/s, out of the path's
    /// `from` chamber and into its `to` chamber (see the module documentation).
    Path(LeakPath),
}

/// Where the four balances sit in the accumulator of
/// [`crate::model::effects::Term::add_to_balances`] (and of [`ExtraTerm::add_to`]).
pub mod slot {
    /// The torque balance (a loss torque, N·m).
    pub(crate) const TORQUE: usize = 0;
    /// Mass into V_1, kg/s.
    pub(crate) const MASS1: usize = 1;
    /// Mass into V_2, kg/s.
    pub(crate) const MASS2: usize = 2;
    /// Mass into V_e, kg/s.
    pub(crate) const MASSE: usize = 3;
}

impl BalanceId {
    /// The balance's place in the accumulator of
    /// [`crate::model::effects::Term::add_to_balances`] (`None` for a path, which acts on
    /// two).
    pub fn slot(self) -> Option<usize> {
        match self {
            BalanceId::Torque => Some(slot::TORQUE),
            BalanceId::Mass1 => Some(slot::MASS1),
            BalanceId::Mass2 => Some(slot::MASS2),
            BalanceId::MassE => Some(slot::MASSE),
            BalanceId::Path(_) => None,
        }
    }
}

/// A chamber at one end of a leak path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Chamber {
    /// V_1, the inlet compartment (port 1 side).
    V1,
    /// V_2, the outlet compartment (port 2 side).
    V2,
    /// V_e, the exhaust compartment.
    Ve,
    /// The atmosphere (no balance, pressure p_atm).
    Atm,
}

impl Chamber {
    /// Every chamber.
    pub const ALL: [Chamber; 4] = [Chamber::V1, Chamber::V2, Chamber::Ve, Chamber::Atm];

    /// Its pressure at state x, Pa.
    pub fn pressure(self, x: &State, p_atm_pa: f64) -> f64 {
        match self {
            Chamber::V1 => x[0],
            Chamber::V2 => x[1],
            Chamber::Ve => x[2],
            Chamber::Atm => p_atm_pa,
        }
    }

    /// Its mass balance's slot (`None` for the atmosphere).
    pub fn slot(self) -> Option<usize> {
        match self {
            Chamber::V1 => Some(slot::MASS1),
            Chamber::V2 => Some(slot::MASS2),
            Chamber::Ve => Some(slot::MASSE),
            Chamber::Atm => None,
        }
    }

    /// Id in files (`v1`, `v2`, `ve`, `atm`) and symbol in formulas (`p1`, `p2`, `pe`,
    /// `p_atm`).
    pub fn id(self) -> (&'static str, &'static str) {
        match self {
            Chamber::V1 => ("v1", "p1"),
            Chamber::V2 => ("v2", "p2"),
            Chamber::Ve => ("ve", "pe"),
            Chamber::Atm => ("atm", "p_atm"),
        }
    }

    /// The chamber in words.
    pub fn words(self) -> &'static str {
        match self {
            Chamber::V1 => "the inlet compartment (V1)",
            Chamber::V2 => "the outlet compartment (V2)",
            Chamber::Ve => "the exhaust (Ve)",
            Chamber::Atm => "the atmosphere",
        }
    }
}

/// A leak path: mass flows from `from` to `to` (a negative flow goes back).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct LeakPath {
    /// The chamber the flow leaves.
    pub from: Chamber,
    /// The chamber the flow enters.
    pub to: Chamber,
}

impl LeakPath {
    /// The paths searched by the diagnosis: between the three volumes, and from each
    /// volume to atmosphere.
    pub const ALL: [LeakPath; 6] = [
        LeakPath::new(Chamber::V1, Chamber::Ve),
        LeakPath::new(Chamber::V2, Chamber::Ve),
        LeakPath::new(Chamber::V1, Chamber::V2),
        LeakPath::new(Chamber::V1, Chamber::Atm),
        LeakPath::new(Chamber::V2, Chamber::Atm),
        LeakPath::new(Chamber::Ve, Chamber::Atm),
    ];

    /// The path from `from` to `to`.
    pub const fn new(from: Chamber, to: Chamber) -> Self {
        Self { from, to }
    }

    /// The category (docs/model.md, "Missing-physics catalog") of a leak along this path:
    /// between two volumes `internal_leakage`; from V_1 to atmosphere (the supply side)
    /// `inlet_flow`; from V_2 or V_e to atmosphere `outlet_flow`.
    pub fn category(self) -> Category {
        use Chamber::*;
        match (self.from, self.to) {
            (Atm, Atm) => Category::OutletFlow,
            (V1, Atm) | (Atm, V1) => Category::InletFlow,
            (_, Atm) | (Atm, _) => Category::OutletFlow,
            _ => Category::InternalLeakage,
        }
    }
}

/// Stribeck speed of [`SpeedFactor::StribeckExp`], rad/s (a start-up in a ramp shows
/// Stribeck speeds of 1–200 rad/s; the catalog's `breakaway_friction` fits its own).
pub const STRIBECK_EXP_RAD_S: f64 = 10.0;

/// Pressure below which the orifice law √Δp turns laminar (finite slope at Δp = 0), Pa.
const ORIFICE_LAMINAR_PA: f64 = 1e3;

/// The pressure factor of a discovered term's feature (Pa, or 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PressureFactor {
    /// 1 (no pressure factor).
    One,
    /// p_1, Pa.
    P1,
    /// p_2, Pa.
    P2,
    /// p_e, Pa.
    Pe,
    /// Gauge pressure p_1 − p_atm, Pa.
    P1Gauge,
    /// Gauge pressure p_2 − p_atm, Pa.
    P2Gauge,
    /// Gauge pressure p_e − p_atm, Pa.
    PeGauge,
    /// p_1 − p_e, Pa.
    P1MinusPe,
    /// p_2 − p_e, Pa.
    P2MinusPe,
    /// p_1 − p_2, Pa.
    P1MinusP2,
    /// (p_1 − p_e) + (p_2 − p_e), Pa: the normal load of vanes pressed by both chambers
    /// (pressure-loaded Coulomb friction T = k·(p_1 + p_2 − 2·p_e)·tanh(ω/ω_reg), the
    /// Coulomb force F_C = F_pr + f·(p_A + p_B) of seal friction; docs/diagnosis.md,
    /// "Term library").
    ChamberSum,
    /// |T_air|, N·m: the magnitude of the air torque on the rotor at the state, the ideal
    /// motor's torque T of J·dω/dt = T − T_f − T_load
    /// ([`crate::model::motor::Motor::air_torque_nm`]). Times `sign` it is load-dependent
    /// Coulomb friction T = k·|T_air|·tanh(ω/ω_reg), k dimensionless: vanes and bearings
    /// loaded by the torque they transmit (docs/diagnosis.md, "Term library"). A torque,
    /// so only the torque balance takes it.
    AirTorque,
    /// Flow law of a leak path: Δp = p_from − p_to, Pa (laminar).
    Laminar,
    /// Flow law of a leak path: Δp·|Δp|, Pa² (grows with the square of the difference): a
    /// gap that the pressure opens. Not a textbook law of a fixed gap; the first-order
    /// correction of a laminar gap whose height grows with Δp (ṁ ∝ h³·Δp with
    /// h = h_0·(1 + Δp/p_d) gives Δp + 3·Δp²/p_d + …), the "elastic leak" of a seal lifted
    /// by the pressure (docs/diagnosis.md, "Term library").
    Quadratic,
    /// Flow law of a leak path: p_from² − p_to², Pa² (isothermal compressible laminar gap
    /// flow, ṁ = h³·w·(p_a² − p_b²)/(24·μ·L·R·T): Poiseuille flow at the mean density).
    CompressibleLaminar,
    /// Flow law of a leak path: sign(Δp)·|Δp|^(4/7), Pa^(4/7) (turbulent gap flow with
    /// Blasius's friction factor λ ∝ Re^(−1/4); linear below p_r = `ORIFICE_LAMINAR_PA`).
    Turbulent,
    /// Flow law of a leak path: Δp·(Δp² + p_r²)^(−1/4) ≈ sign(Δp)·√|Δp|, √Pa (a sharp
    /// orifice; laminar below p_r = `ORIFICE_LAMINAR_PA`).
    Orifice,
    /// Flow law of a leak path: ISO 6358 (b = 0.5) with the coefficient as sonic
    /// conductance: ρ0·p_u·ψ(p_d/p_u), kg/(s·m³/(s·Pa)), reverse flow by symmetry.
    Iso6358,
}

/// The speed factor of a discovered term's feature.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum SpeedFactor {
    /// 1 (no speed factor).
    One,
    /// ω, rad/s.
    Omega,
    /// |ω|, rad/s.
    AbsOmega,
    /// ω·|ω|, (rad/s)².
    OmegaAbsOmega,
    /// tanh(ω/ω_reg), 1: a Coulomb-like sign with the friction's regularisation.
    Sign,
    /// ω·|ω|^(1/2), (rad/s)^1.5: a viscous loss growing faster than ω (mixed lubrication).
    OmegaPow15,
    /// exp(−|ω|/ω_s)·tanh(ω/ω_reg), 1, ω_s = `STRIBECK_EXP_RAD_S`: the exponential
    /// Stribeck curve's excess over Coulomb friction.
    StribeckExp,
}

impl PressureFactor {
    /// The flow laws of a leak path.
    pub const LAWS: [PressureFactor; 6] = [
        P::Laminar,
        P::CompressibleLaminar,
        P::Turbulent,
        P::Quadratic,
        P::Orifice,
        P::Iso6358,
    ];

    /// Whether this is a flow law of a leak path.
    pub(crate) fn is_law(self) -> bool {
        Self::LAWS.contains(&self)
    }

    /// Every pressure factor.
    pub const ALL: [PressureFactor; 18] = [
        P::One,
        P::P1,
        P::P2,
        P::Pe,
        P::P1Gauge,
        P::P2Gauge,
        P::PeGauge,
        P::P1MinusPe,
        P::P2MinusPe,
        P::P1MinusP2,
        P::ChamberSum,
        P::AirTorque,
        P::Laminar,
        P::Quadratic,
        P::Orifice,
        P::Iso6358,
        P::CompressibleLaminar,
        P::Turbulent,
    ];
}

impl SpeedFactor {
    /// Every speed factor.
    pub const ALL: [SpeedFactor; 7] = [
        W::One,
        W::Omega,
        W::AbsOmega,
        W::OmegaAbsOmega,
        W::Sign,
        W::OmegaPow15,
        W::StribeckExp,
    ];
}

/// A term outside the catalog: `coefficient · pressure(x) · speed(ω)` added to one balance.
/// The coefficient is SI: (N·m or kg/s) per unit of the feature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtraTerm {
    /// The balance the term enters.
    pub balance: BalanceId,
    /// Its pressure factor.
    pub pressure: PressureFactor,
    /// Its speed factor.
    pub speed: SpeedFactor,
    /// The coefficient, SI per unit of the feature ([`coefficient_unit`]).
    pub coefficient: f64,
}

impl ExtraTerm {
    /// The feature pressure(x)·speed(ω) at state x (SI), times the coefficient: the loss
    /// torque or the mass flow into the balance, or along the path from→to. `t_air_nm` is
    /// the air torque at x, N·m ([`crate::model::motor::Motor::air_torque_nm`]; only
    /// [`PressureFactor::AirTorque`] reads it).
    pub fn feature(&self, x: &State, p_atm_pa: f64, w_reg: f64, t_air_nm: f64) -> f64 {
        let [p1, p2, pe, omega] = *x;
        let p = match self.pressure {
            PressureFactor::One => 1.0,
            PressureFactor::P1 => p1,
            PressureFactor::P2 => p2,
            PressureFactor::Pe => pe,
            PressureFactor::P1Gauge => p1 - p_atm_pa,
            PressureFactor::P2Gauge => p2 - p_atm_pa,
            PressureFactor::PeGauge => pe - p_atm_pa,
            PressureFactor::P1MinusPe => p1 - pe,
            PressureFactor::P2MinusPe => p2 - pe,
            PressureFactor::P1MinusP2 => p1 - p2,
            PressureFactor::ChamberSum => p1 + p2 - 2.0 * pe,
            PressureFactor::AirTorque => t_air_nm.abs(),
            law => match self.balance {
                BalanceId::Path(path) => flow_law(
                    law,
                    path.from.pressure(x, p_atm_pa),
                    path.to.pressure(x, p_atm_pa),
                ),
                _ => 0.0,
            },
        };
        let w = match self.speed {
            SpeedFactor::One => 1.0,
            SpeedFactor::Omega => omega,
            SpeedFactor::AbsOmega => omega.abs(),
            SpeedFactor::OmegaAbsOmega => omega * omega.abs(),
            SpeedFactor::Sign => (omega / w_reg).tanh(),
            SpeedFactor::OmegaPow15 => omega * omega.abs().sqrt(),
            SpeedFactor::StribeckExp => {
                (-omega.abs() / STRIBECK_EXP_RAD_S).exp() * (omega / w_reg).tanh()
            }
        };
        self.coefficient * p * w
    }

    /// A leak along `path` by flow `law`, scaled by `speed`.
    pub fn leak(path: LeakPath, law: PressureFactor, speed: SpeedFactor, coefficient: f64) -> Self {
        Self {
            balance: BalanceId::Path(path),
            pressure: law,
            speed,
            coefficient,
        }
    }
}

/// A flow law of Δp = `p_from` − `p_to` (see [`PressureFactor`]); 0 for any other factor.
pub(crate) fn flow_law(law: PressureFactor, p_from: f64, p_to: f64) -> f64 {
    let dp = p_from - p_to;
    match law {
        P::Laminar => dp,
        P::Quadratic => dp * dp.abs(),
        P::CompressibleLaminar => p_from * p_from - p_to * p_to,
        P::Turbulent => {
            // |Δp|^(4/7), continued linearly below p_r (the gap turns laminar).
            let a = dp.abs().max(ORIFICE_LAMINAR_PA);
            dp * a.powf(4.0 / 7.0 - 1.0)
        }
        P::Orifice => dp * (dp * dp + ORIFICE_LAMINAR_PA * ORIFICE_LAMINAR_PA).powf(-0.25),
        P::Iso6358 => {
            let (pu, pd, sign) = if dp >= 0.0 {
                (p_from, p_to, 1.0)
            } else {
                (p_to, p_from, -1.0)
            };
            if pu <= 0.0 {
                return 0.0;
            }
            sign * crate::units::constants::RHO0_KG_M3 * pu * nozzle::psi((pd / pu).max(0.0), 0.5)
        }
        _ => 0.0,
    }
}

impl ExtraTerm {
    /// coefficient·feature(x) added to its balance in `acc` (the slots of [`slot`], as the
    /// catalog effects' [`crate::model::effects::Term::add_to_balances`]); along a path,
    /// taken from `from`'s balance and given to `to`'s. `t_air_nm`: the air torque at x,
    /// N·m, which the motor has already computed for its torque equation.
    pub(crate) fn add_to(
        &self,
        x: &State,
        p_atm_pa: f64,
        w_reg: f64,
        t_air_nm: f64,
        acc: &mut [f64; 4],
    ) {
        let f = self.feature(x, p_atm_pa, w_reg, t_air_nm);
        match self.balance {
            BalanceId::Path(path) => {
                if let Some(i) = path.from.slot() {
                    acc[i] -= f;
                }
                if let Some(i) = path.to.slot() {
                    acc[i] += f;
                }
            }
            b => acc[b.slot().expect("a balance")] += f,
        }
    }
}

/// The category (docs/model.md, "Missing-physics catalog") of a discovered term: torque →
/// torque_loss; a leak path by its path ([`LeakPath::category`]); a one-balance mass term
/// driven by a pressure difference between two chambers → internal_leakage; other mass
/// terms at V_1 → inlet_flow, at V_2 or V_e → outlet_flow.
pub fn category(t: &ExtraTerm) -> Category {
    match t.balance {
        BalanceId::Torque => Category::TorqueLoss,
        BalanceId::Path(path) => path.category(),
        _ if matches!(t.pressure, P::P1MinusPe | P::P2MinusPe | P::P1MinusP2) => {
            Category::InternalLeakage
        }
        BalanceId::Mass1 => Category::InletFlow,
        BalanceId::Mass2 | BalanceId::MassE => Category::OutletFlow,
    }
}

/// A discovered term in words, e.g. "a leak from the inlet compartment (V1) to the exhaust
/// (Ve) that grows with the square of the pressure difference".
pub fn describe(t: &ExtraTerm) -> String {
    let speed = match t.speed {
        W::One => "",
        W::Omega => ", proportional to the speed",
        W::AbsOmega => ", proportional to the speed's magnitude",
        W::OmegaAbsOmega => ", growing with the square of the speed",
        W::Sign => ", of constant size while turning (Coulomb-like)",
        W::OmegaPow15 => ", growing with the speed to the power 1.5",
        W::StribeckExp => ", largest at start-up and decaying with the speed (Stribeck)",
    };
    match t.balance {
        BalanceId::Path(path) => {
            let law = match t.pressure {
                P::Laminar => "that grows in proportion to the pressure difference (laminar)",
                P::Quadratic => {
                    "that grows with the square of the pressure difference (a gap the pressure opens)"
                }
                P::CompressibleLaminar => {
                    "that grows with the difference of the squared pressures (compressible laminar)"
                }
                P::Turbulent => {
                    "that grows with the pressure difference to the power 4/7 (turbulent)"
                }
                P::Orifice => {
                    "that grows with the square root of the pressure difference (orifice)"
                }
                P::Iso6358 => "through an ISO 6358 restriction (choked at large pressure ratios)",
                _ => "driven by",
            };
            let what = if t.pressure.is_law() {
                law.to_string()
            } else {
                format!("{law} {}", feature_name(t))
            };
            format!(
                "a leak from {} to {} {what}{speed}",
                path.from.words(),
                path.to.words()
            )
        }
        BalanceId::Torque if t.pressure == P::AirTorque => format!(
            "a loss torque proportional to the magnitude of the air torque (load-dependent \
             friction){speed}"
        ),
        BalanceId::Torque => format!("a loss torque proportional to {}", feature_name(t)),
        b => format!(
            "a mass flow into {} proportional to {}",
            match b {
                BalanceId::Mass1 => Chamber::V1.words(),
                BalanceId::Mass2 => Chamber::V2.words(),
                _ => Chamber::Ve.words(),
            },
            feature_name(t)
        ),
    }
}

/// The law's symbol on a path, e.g. `(p1 - pe)*|p1 - pe|`, and its unit.
fn law_symbol(law: P, path: LeakPath) -> (String, &'static str) {
    let (a, b) = (path.from.id().1, path.to.id().1);
    let dp = format!("({a} - {b})");
    match law {
        P::Laminar => (dp, "Pa"),
        P::Quadratic => (format!("{dp}*|{dp}|"), "Pa2"),
        P::CompressibleLaminar => (format!("({a}^2 - {b}^2)"), "Pa2"),
        P::Turbulent => (format!("{dp}^(4/7)"), "Pa^(4/7)"),
        P::Orifice => (format!("sqrt{dp}"), "Pa^0.5"),
        P::Iso6358 => (format!("iso6358({a}, {b})"), "kg/m3*Pa"),
        _ => (String::new(), ""),
    }
}

fn pressure_symbol(p: P) -> (&'static str, &'static str) {
    match p {
        P::One => ("", ""),
        P::P1 => ("p1", "Pa"),
        P::P2 => ("p2", "Pa"),
        P::Pe => ("pe", "Pa"),
        P::P1Gauge => ("(p1 - p_atm)", "Pa"),
        P::P2Gauge => ("(p2 - p_atm)", "Pa"),
        P::PeGauge => ("(pe - p_atm)", "Pa"),
        P::P1MinusPe => ("(p1 - pe)", "Pa"),
        P::P2MinusPe => ("(p2 - pe)", "Pa"),
        P::P1MinusP2 => ("(p1 - p2)", "Pa"),
        P::ChamberSum => ("(p1 + p2 - 2*pe)", "Pa"),
        P::AirTorque => ("|T_air|", "N*m"),
        P::Laminar => ("dp", "Pa"),
        P::Quadratic => ("dp*|dp|", "Pa2"),
        P::CompressibleLaminar => ("(pa^2 - pb^2)", "Pa2"),
        P::Turbulent => ("dp^(4/7)", "Pa^(4/7)"),
        P::Orifice => ("sqrt(dp)", "Pa^0.5"),
        P::Iso6358 => ("iso6358", "kg/m3*Pa"),
    }
}

fn speed_symbol(w: W) -> (&'static str, &'static str) {
    match w {
        W::One => ("", ""),
        W::Omega => ("omega", "rad/s"),
        W::AbsOmega => ("|omega|", "rad/s"),
        W::OmegaAbsOmega => ("omega*|omega|", "rad2/s2"),
        W::Sign => ("tanh(omega/w_reg)", ""),
        W::OmegaPow15 => ("omega*|omega|^0.5", "(rad/s)^1.5"),
        W::StribeckExp => ("exp(-|omega|/10)*tanh(omega/w_reg)", ""),
    }
}

/// Id of a pressure factor in files.
pub fn pressure_id(p: P) -> &'static str {
    match p {
        P::One => "one",
        P::P1 => "p1",
        P::P2 => "p2",
        P::Pe => "pe",
        P::P1Gauge => "p1_gauge",
        P::P2Gauge => "p2_gauge",
        P::PeGauge => "pe_gauge",
        P::P1MinusPe => "p1_minus_pe",
        P::P2MinusPe => "p2_minus_pe",
        P::P1MinusP2 => "p1_minus_p2",
        P::ChamberSum => "p1_plus_p2_minus_2pe",
        P::AirTorque => "air_torque",
        P::Laminar => "laminar",
        P::Quadratic => "quadratic",
        P::CompressibleLaminar => "compressible_laminar",
        P::Turbulent => "turbulent",
        P::Orifice => "orifice",
        P::Iso6358 => "iso6358",
    }
}

/// Id of a speed factor in files.
pub fn speed_id(w: W) -> &'static str {
    match w {
        W::One => "one",
        W::Omega => "omega",
        W::AbsOmega => "abs_omega",
        W::OmegaAbsOmega => "omega_abs_omega",
        W::Sign => "sign",
        W::OmegaPow15 => "omega_pow_1_5",
        W::StribeckExp => "stribeck_exp",
    }
}

/// The feature as a product of symbols, e.g. `p2*omega`.
pub fn feature_name(t: &ExtraTerm) -> String {
    let (p, _) = factor_symbol(t);
    let p = p.as_str();
    let (w, _) = speed_symbol(t.speed);
    match (p.is_empty(), w.is_empty()) {
        (true, true) => "1".into(),
        (true, false) => w.into(),
        (false, true) => p.into(),
        (false, false) => format!("{p}*{w}"),
    }
}

/// The SI unit of a term's coefficient.
pub fn coefficient_unit(t: &ExtraTerm) -> String {
    let num = match t.balance {
        BalanceId::Torque => "N*m",
        _ => "kg/s",
    };
    let (_, pu) = factor_symbol(t);
    let (_, wu) = speed_symbol(t.speed);
    let den: Vec<&str> = [pu, wu].into_iter().filter(|s| !s.is_empty()).collect();
    // A torque per torque (load-dependent friction's fraction of the air torque) is a pure
    // number.
    if den == [num] {
        "1".into()
    } else if den.is_empty() {
        num.into()
    } else {
        format!("{num}/({})", den.join("*"))
    }
}

/// The pressure factor's symbol and unit, a path's flow law written out.
fn factor_symbol(t: &ExtraTerm) -> (String, &'static str) {
    match t.balance {
        BalanceId::Path(path) if t.pressure.is_law() => law_symbol(t.pressure, path),
        _ => {
            let (s, u) = pressure_symbol(t.pressure);
            (s.to_string(), u)
        }
    }
}

/// The balance's symbol in a formula (a path: `m_dot(v1->ve)`).
pub fn balance_symbol(b: BalanceId) -> String {
    let s = match b {
        BalanceId::Path(path) => return format!("m_dot({}->{})", path.from.id().0, path.to.id().0),
        BalanceId::Torque => "T_loss",
        BalanceId::Mass1 => "dm1/dt",
        BalanceId::Mass2 => "dm2/dt",
        BalanceId::MassE => "dme/dt",
    };
    s.to_string()
}

/// The balance's name in reports and JSON (`leak_path` for a path).
pub fn balance_name(b: BalanceId) -> &'static str {
    match b {
        BalanceId::Path(_) => "leak_path",
        BalanceId::Torque => "torque",
        BalanceId::Mass1 => "mass_v1",
        BalanceId::Mass2 => "mass_v2",
        BalanceId::MassE => "mass_ve",
    }
}

/// A term as a formula with its coefficient, e.g.
/// `T_loss += 1.2e-10 N*m/(Pa*rad/s) * p2*omega` (a pure number's unit left out:
/// `T_loss += 6.6e-2 * |T_air|*tanh(omega/w_reg)`).
pub fn formula(t: &ExtraTerm) -> String {
    let op = if matches!(t.balance, BalanceId::Path(_)) {
        "="
    } else {
        "+="
    };
    let unit = coefficient_unit(t);
    let unit = if unit == "1" {
        String::new()
    } else {
        format!(" {unit}")
    };
    format!(
        "{} {op} {:.4e}{unit} * {}",
        balance_symbol(t.balance),
        t.coefficient,
        feature_name(t)
    )
}
