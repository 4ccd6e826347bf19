//! `throttle-inlet` / `throttle-outlet` (paper §5.1, Figs. 14, 15): steady speed against
//! the conductance of a throttle at constant supply pressure, and torque–speed curves for
//! several throttles.

use super::{absolute_pressure_mpa, positive, Plant};
use crate::control::error::{ControlError, SettingsError};
use crate::control::option::ControlOpt;
use crate::control::throttle::{
    conductance_grid, speed_vs_conductance, torque_speed, Port, ThrottlePoint, TorquePoint,
};
use crate::model::motor::{idx, Load};
use crate::sim::steady;
use crate::units::constants::P_ATM_PA;

/// Number of speeds on each torque–speed curve.
const CURVE_POINTS: usize = 60;

/// The options of a throttling study as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct ThrottleOptions {
    /// Where the throttle sits.
    pub port: Port,
    /// Constant supply pressure (`--p-supply-mpa`), MPa absolute.
    pub p_supply_mpa: f64,
    /// Smallest conductance (`--c-min-m3-s-pa`), m3/(s·Pa).
    pub c_min_m3_s_pa: f64,
    /// Largest conductance (`--c-max-m3-s-pa`), m3/(s·Pa).
    pub c_max_m3_s_pa: f64,
    /// Number of conductances, log-spaced (`--points`).
    pub points: usize,
    /// Throttles of the torque–speed curves (`--curves-m3-s-pa`): comma-separated
    /// conductances, `none` for no throttle.
    pub curves_m3_s_pa: String,
}

impl ThrottleOptions {
    /// Checks every option.
    pub fn check(&self) -> Result<ThrottleSettings, SettingsError> {
        let p_supply_mpa = absolute_pressure_mpa(ControlOpt::ThrottlePSupply, self.p_supply_mpa)?;
        let c_min = positive(ControlOpt::ThrottleCMin, self.c_min_m3_s_pa)?;
        let c_max = positive(ControlOpt::ThrottleCMax, self.c_max_m3_s_pa)?;
        if c_max <= c_min {
            return Err(SettingsError::EmptyRange {
                option: ControlOpt::ThrottleCMax,
                value: c_max,
                lower: ControlOpt::ThrottleCMin,
            });
        }
        if self.points < 2 {
            return Err(SettingsError::TooFewPoints {
                option: ControlOpt::ThrottlePoints,
                value: self.points,
                min: 2,
            });
        }
        Ok(ThrottleSettings {
            port: self.port,
            p_supply_mpa,
            c_min,
            c_max,
            points: self.points,
            curves: parse_curves(&self.curves_m3_s_pa)?,
        })
    }
}

/// `--curves-m3-s-pa`: conductances > 0 or `none` (`None`), at least one.
fn parse_curves(list: &str) -> Result<Vec<Option<f64>>, SettingsError> {
    let mut out = Vec::new();
    for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        if item == "none" {
            out.push(None);
        } else {
            let v: f64 = item
                .parse()
                .map_err(|_| SettingsError::NotAConductance(item.to_string()))?;
            out.push(Some(positive(ControlOpt::ThrottleCurves, v)?));
        }
    }
    if out.is_empty() {
        return Err(SettingsError::NoCurves(list.to_string()));
    }
    Ok(out)
}

/// The checked settings of a throttling study.
#[derive(Debug, Clone, PartialEq)]
pub struct ThrottleSettings {
    port: Port,
    p_supply_mpa: f64,
    c_min: f64,
    c_max: f64,
    points: usize,
    curves: Vec<Option<f64>>,
}

impl ThrottleSettings {
    /// Where the throttle sits.
    pub fn port(&self) -> Port {
        self.port
    }

    /// Supply pressure, MPa absolute, as given.
    pub fn p_supply_mpa(&self) -> f64 {
        self.p_supply_mpa
    }

    /// Supply pressure, Pa absolute.
    pub fn p_supply_pa(&self) -> f64 {
        self.p_supply_mpa * 1e6
    }

    /// Conductances of the speed curve, m3/(s·Pa), log-spaced from the smallest.
    pub(crate) fn conductances(&self) -> Vec<f64> {
        conductance_grid(self.c_min, self.c_max, self.points)
    }

    /// Throttles of the torque–speed curves (`None`: no throttle).
    pub fn curves(&self) -> &[Option<f64>] {
        &self.curves
    }
}

/// One torque–speed curve.
#[derive(Debug, Clone, PartialEq)]
pub struct TorqueCurve {
    /// Throttle conductance, m3/(s·Pa); `None`: no throttle.
    pub c_m3_s_pa: Option<f64>,
    /// Shaft torque against imposed speed, ascending in speed.
    pub points: Vec<TorquePoint>,
}

/// The results of a throttling study.
#[derive(Debug, Clone, PartialEq)]
pub struct ThrottleStudy {
    /// The settings it was run with.
    pub settings: ThrottleSettings,
    /// The load on the shaft of the speed curve.
    pub load: Load,
    /// Steady state against conductance, as `ThrottleSettings::conductances` (Fig. 14).
    pub speed: Vec<ThrottlePoint>,
    /// Torque–speed curves up to 1.02 × the unthrottled free speed (Fig. 15).
    pub curves: Vec<TorqueCurve>,
    /// Free speed without throttle and without load, rad/s.
    pub free_speed_rad_s: f64,
}

/// Runs a throttling study on the plant.
pub fn study(plant: &Plant, s: &ThrottleSettings) -> Result<ThrottleStudy, ControlError> {
    let m = plant.motor();
    let port = s.port;
    let p_supply = s.p_supply_pa();
    let speed = speed_vs_conductance(m, port, p_supply, P_ATM_PA, plant.load(), &s.conductances())?;
    // Torque-speed curves up to the unthrottled free speed.
    let bc = port.boundary(p_supply, P_ATM_PA, Load::None, None);
    let free = steady::free(m, &bc, &steady::initial_guess(&bc))?;
    let w_max = 1.02 * free[idx::OMEGA];
    let curves = s
        .curves
        .iter()
        .map(|c| {
            Ok(TorqueCurve {
                c_m3_s_pa: *c,
                points: torque_speed(m, port, p_supply, P_ATM_PA, *c, w_max, CURVE_POINTS)?,
            })
        })
        .collect::<Result<_, ControlError>>()?;
    Ok(ThrottleStudy {
        settings: s.clone(),
        load: plant.load(),
        speed,
        curves,
        free_speed_rad_s: free[idx::OMEGA],
    })
}
