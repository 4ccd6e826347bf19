//! Terms outside the catalog (SPEC §5, "uncatalogued"): `coefficient · pressure(x) · speed(ω)`
//! added to one balance of the motor. `vanefit diagnose` finds them; fit files carry them in
//! `model.discovered`, and every command that reads a fit file applies them.

use crate::model::effects::{Category, Term};
use crate::model::params::MotorParams;
use crate::numerics::ode::State;
use PressureFactor as P;
use SpeedFactor as W;

/// The balance a discovered term enters (SPEC §5, uncatalogued mismatches).
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
}

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
}

impl PressureFactor {
    /// Every pressure factor.
    pub const ALL: [PressureFactor; 10] = [
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
    ];
}

impl SpeedFactor {
    /// Every speed factor.
    pub const ALL: [SpeedFactor; 5] = [W::One, W::Omega, W::AbsOmega, W::OmegaAbsOmega, W::Sign];
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
    /// The feature pressure(x)·speed(ω) at state x (SI).
    pub fn feature(&self, x: &State, p_atm_pa: f64, w_reg: f64) -> f64 {
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
        };
        let w = match self.speed {
            SpeedFactor::One => 1.0,
            SpeedFactor::Omega => omega,
            SpeedFactor::AbsOmega => omega.abs(),
            SpeedFactor::OmegaAbsOmega => omega * omega.abs(),
            SpeedFactor::Sign => (omega / w_reg).tanh(),
        };
        self.coefficient * p * w
    }
}

impl Term for ExtraTerm {
    /// coefficient·feature(x) added to its balance (the catalog effects' hook).
    fn add_to_balances(
        &self,
        _own: &[f64],
        params: &MotorParams,
        x: &State,
        p_atm_pa: f64,
        acc: &mut [f64; 4],
    ) {
        acc[self.balance as usize] += self.feature(x, p_atm_pa, params.w_reg());
    }
}

/// The SPEC §5 category of a discovered term: torque → torque_loss; a mass term driven by a
/// pressure difference between two chambers → internal_leakage; other mass terms at V_1 →
/// inlet_flow, at V_2 or V_e → outlet_flow.
pub fn category(t: &ExtraTerm) -> Category {
    match t.balance {
        BalanceId::Torque => Category::TorqueLoss,
        _ if matches!(t.pressure, P::P1MinusPe | P::P2MinusPe | P::P1MinusP2) => {
            Category::InternalLeakage
        }
        BalanceId::Mass1 => Category::InletFlow,
        BalanceId::Mass2 | BalanceId::MassE => Category::OutletFlow,
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
    }
}

fn speed_symbol(w: W) -> (&'static str, &'static str) {
    match w {
        W::One => ("", ""),
        W::Omega => ("omega", "rad/s"),
        W::AbsOmega => ("|omega|", "rad/s"),
        W::OmegaAbsOmega => ("omega*|omega|", "rad2/s2"),
        W::Sign => ("tanh(omega/w_reg)", ""),
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
    }
}

/// The feature as a product of symbols, e.g. `p2*omega`.
pub fn feature_name(t: &ExtraTerm) -> String {
    let (p, _) = pressure_symbol(t.pressure);
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
    let (_, pu) = pressure_symbol(t.pressure);
    let (_, wu) = speed_symbol(t.speed);
    let den: Vec<&str> = [pu, wu].into_iter().filter(|s| !s.is_empty()).collect();
    if den.is_empty() {
        num.into()
    } else {
        format!("{num}/({})", den.join("*"))
    }
}

/// The balance's symbol in a formula.
pub fn balance_symbol(b: BalanceId) -> &'static str {
    match b {
        BalanceId::Torque => "T_loss",
        BalanceId::Mass1 => "dm1/dt",
        BalanceId::Mass2 => "dm2/dt",
        BalanceId::MassE => "dme/dt",
    }
}

/// The balance's name in reports and JSON.
pub fn balance_name(b: BalanceId) -> &'static str {
    match b {
        BalanceId::Torque => "torque",
        BalanceId::Mass1 => "mass_v1",
        BalanceId::Mass2 => "mass_v2",
        BalanceId::MassE => "mass_ve",
    }
}

/// A term as a formula with its coefficient, e.g.
/// `T_loss += 1.2e-10 N*m/(Pa*rad/s) * p2*omega`.
pub fn formula(t: &ExtraTerm) -> String {
    format!(
        "{} += {:.4e} {} * {}",
        balance_symbol(t.balance),
        t.coefficient,
        coefficient_unit(t),
        feature_name(t)
    )
}
