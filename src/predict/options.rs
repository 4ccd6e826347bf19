//! What a prediction is asked for: supply pressures, the reference pressure of the
//! correction factors, an optional extra nozzle, the speed grid of the maximum power and the
//! number of points of each curve. SI throughout; the command line converts.

use super::PredictError;
use crate::sim::operating_point::Conditions;
use crate::units::Unit;
use std::f64::consts::PI;

/// Supply pressures predicted unless others are asked for, bar gauge.
const DEFAULT_PRESSURES_BAR_G: [f64; 5] = [3.0, 4.0, 5.0, 6.0, 7.0];
/// The reference pressure of the correction factors unless another is asked for, bar gauge:
/// 6.3 bar g, the nominal pressure of pneumatic catalogues (ISO 8778's 6.3 bar working
/// pressure).
const DEFAULT_REFERENCE_BAR_G: f64 = 6.3;
/// Speed grid of the maximum power unless another is asked for: 1 rpm, in rad/s.
const DEFAULT_SPEED_GRID_RAD_S: f64 = PI / 30.0;
/// Points of each curve from standstill to the free speed unless another number is asked.
pub const DEFAULT_CURVE_POINTS: usize = 41;

/// Where the extra nozzle sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NozzlePort {
    /// In series in front of port 1 (inlet throttling, paper §5.1, Figs. 14–15).
    Inlet,
    /// In series behind port 2 (outlet throttling).
    Outlet,
}

impl NozzlePort {
    /// `inlet` or `outlet`.
    pub fn name(self) -> &'static str {
        match self {
            NozzlePort::Inlet => "inlet",
            NozzlePort::Outlet => "outlet",
        }
    }
}

/// An extra ISO 6358 nozzle in series with the motor (the motor's critical ratio b).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nozzle {
    /// Where it sits.
    pub port: NozzlePort,
    /// Its sonic conductance C, m³/(s·Pa). A sharp-edged orifice of diameter d passes
    /// C ≈ C_d·(π/4)·d²·√(κ/(R·T0))·(2/(κ+1))^((κ+1)/(2(κ−1)))/ρ0 ≈ 1.99e-3·C_d·(π/4)·d²
    /// (d in m): a 2 mm orifice with C_d ≈ 0.8 is ≈ 5e-9 m³/(s·Pa).
    pub c_m3_s_pa: f64,
}

/// What to predict.
#[derive(Debug, Clone, PartialEq)]
pub struct PredictOptions {
    /// Supply pressures, Pa absolute, in the order to report them.
    pub pressures_pa: Vec<f64>,
    /// Supply pressure that the correction factors are relative to, Pa absolute.
    pub reference_pa: f64,
    /// Atmosphere, Pa absolute (port 2 and the exhaust discharge to it).
    pub p_atm_pa: f64,
    /// An extra nozzle at the inlet or the outlet (`None`: the motor alone).
    pub nozzle: Option<Nozzle>,
    /// The spacing Δ of the speeds k·Δ on which the maximum power is exact, rad/s.
    pub speed_grid_rad_s: f64,
    /// Points of each torque, power and air curve, from standstill to the free speed (≥ 2).
    pub curve_points: usize,
    /// Factor F > 1 within which the parameters a fit could estimate but held fixed (or
    /// could not identify) are taken as uncertain, 95 %: ln θ ~ N(ln θ̂, (ln F/1.96)²),
    /// independent (`None`: such parameters are taken as exact and the band says so).
    pub fixed_spread: Option<f64>,
}

impl PredictOptions {
    /// The defaults at atmosphere `p_atm_pa`: 3 to 7 bar g, reference 6.3 bar g, no nozzle,
    /// a 1 rpm grid, 41 curve points.
    pub fn new(p_atm_pa: f64) -> Self {
        Self {
            pressures_pa: DEFAULT_PRESSURES_BAR_G
                .iter()
                .map(|p| Unit::BarG.to_si(*p, p_atm_pa))
                .collect(),
            reference_pa: Unit::BarG.to_si(DEFAULT_REFERENCE_BAR_G, p_atm_pa),
            p_atm_pa,
            nozzle: None,
            speed_grid_rad_s: DEFAULT_SPEED_GRID_RAD_S,
            curve_points: DEFAULT_CURVE_POINTS,
            fixed_spread: None,
        }
    }

    /// Refuses what cannot be predicted: no pressure, a pressure or atmosphere that is not a
    /// positive number, a nozzle that is not, a grid that is not, fewer than two curve points.
    pub fn check(&self) -> Result<(), PredictError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if self.pressures_pa.is_empty() {
            return Err(PredictError::NoPressures);
        }
        let all = self
            .pressures_pa
            .iter()
            .chain([&self.reference_pa, &self.p_atm_pa]);
        if let Some(p) = all.copied().find(|p| !positive(*p)) {
            return Err(PredictError::BadPressure(p));
        }
        if let Some(n) = self.nozzle.filter(|n| !positive(n.c_m3_s_pa)) {
            return Err(PredictError::BadNozzle(n.c_m3_s_pa));
        }
        if !positive(self.speed_grid_rad_s) {
            return Err(PredictError::BadGrid(self.speed_grid_rad_s));
        }
        if self.curve_points < 2 {
            return Err(PredictError::BadCurvePoints(self.curve_points));
        }
        if let Some(f) = self.fixed_spread.filter(|f| !(f.is_finite() && *f > 1.0)) {
            return Err(PredictError::BadSpread(f));
        }
        Ok(())
    }

    /// The motor's conditions at supply `p_supply_pa`, with the nozzle fitted.
    pub fn conditions(&self, p_supply_pa: f64) -> Conditions {
        let c = self.nozzle.map(|n| (n.port, n.c_m3_s_pa));
        Conditions {
            p_supply_pa,
            p_atm_pa: self.p_atm_pa,
            c_inlet_m3_s_pa: c.filter(|n| n.0 == NozzlePort::Inlet).map(|n| n.1),
            c_outlet_m3_s_pa: c.filter(|n| n.0 == NozzlePort::Outlet).map(|n| n.1),
        }
    }
}
