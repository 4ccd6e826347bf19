//! `min-speed` (paper §5.2: 2900 rpm without control, 365 rpm with): the lowest steady speed
//! without control (start-up on a pressure ramp) and with control (a set-point staircase).

use super::{absolute_pressure_mpa, positive, Plant};
use crate::control::closed_loop::Loop;
use crate::control::error::{ControlError, SettingsError};
use crate::control::min_speed::{
    closed_loop_min_speed, lowest_running_speed_rad_s, open_loop_start, ramp_simulation,
    ControlledMin, StartUp, HOLD_WINDOW_S,
};
use crate::control::option::ControlOpt;
use crate::control::{rpm, RAD_S_PER_RPM};
use crate::model::motor::Motor;
use crate::units::constants::P_ATM_PA;

/// Speeds of the open-loop start-up analysis.
const START_UP_POINTS: usize = 150;
/// Samples of the simulated pressure ramp.
const RAMP_POINTS: usize = 600;

/// The options of `min-speed` as given (unchecked).
#[derive(Debug, Clone, PartialEq)]
pub struct MinSpeedOptions {
    /// Top of the pressure ramp (`--p-max-mpa`), MPa absolute.
    pub p_max_mpa: f64,
    /// Duration of the simulated ramp (`--ramp-s`), s.
    pub ramp_s: f64,
    /// Ratio of successive set-points of the staircase (`--factor`), in (0, 1).
    pub factor: f64,
    /// Lowest set-point tried (`--floor-rpm`), rpm; `None`: the motor's lowest running
    /// speed.
    pub floor_rpm: Option<f64>,
    /// Duration of each stage of the staircase (`--stage-s`), s.
    pub stage_s: f64,
}

impl MinSpeedOptions {
    /// Checks every option; the default floor is the motor's.
    pub fn check(&self, motor: &Motor) -> Result<MinSpeedSettings, SettingsError> {
        let p_max_mpa = absolute_pressure_mpa(ControlOpt::MinSpeedPMax, self.p_max_mpa)?;
        let ramp_s = positive(ControlOpt::MinSpeedRamp, self.ramp_s)?;
        if !(self.factor > 0.0 && self.factor < 1.0) {
            return Err(SettingsError::Factor(self.factor));
        }
        let floor_rad_s = match self.floor_rpm {
            Some(f) => positive(ControlOpt::MinSpeedFloor, f)? * RAD_S_PER_RPM,
            None => lowest_running_speed_rad_s(motor),
        };
        let stage_s = positive(ControlOpt::MinSpeedStage, self.stage_s)?;
        if stage_s <= HOLD_WINDOW_S + 1.0 {
            return Err(SettingsError::StageTooShort(stage_s));
        }
        Ok(MinSpeedSettings {
            p_max_mpa,
            ramp_s,
            factor: self.factor,
            floor_rad_s,
            stage_s,
        })
    }
}

/// The checked settings of `min-speed`.
#[derive(Debug, Clone, PartialEq)]
pub struct MinSpeedSettings {
    p_max_mpa: f64,
    ramp_s: f64,
    factor: f64,
    floor_rad_s: f64,
    stage_s: f64,
}

impl MinSpeedSettings {
    /// Top of the pressure ramp, MPa absolute, as given.
    pub fn p_max_mpa(&self) -> f64 {
        self.p_max_mpa
    }

    /// Top of the pressure ramp, Pa absolute.
    pub(crate) fn p_max_pa(&self) -> f64 {
        self.p_max_mpa * 1e6
    }

    /// Duration of the simulated ramp, s.
    pub fn ramp_s(&self) -> f64 {
        self.ramp_s
    }

    /// Ratio of successive set-points.
    pub fn factor(&self) -> f64 {
        self.factor
    }

    /// Lowest set-point tried, rad/s.
    pub fn floor_rad_s(&self) -> f64 {
        self.floor_rad_s
    }

    /// Duration of each stage, s.
    pub fn stage_s(&self) -> f64 {
        self.stage_s
    }
}

/// The results of `min-speed`.
#[derive(Debug, Clone, PartialEq)]
pub struct MinSpeedStudy {
    /// The settings it was run with.
    pub settings: MinSpeedSettings,
    /// The loop.
    pub lp: Loop,
    /// The open-loop start-up analysis (steady states along the ramp).
    pub open: StartUp,
    /// The simulated ramp: (supply Pa absolute, speed rad/s).
    pub ramp: Vec<(f64, f64)>,
    /// The staircase with control.
    pub controlled: ControlledMin,
    /// Speed the staircase starts from, rad/s: 1.25 × the open-loop minimum, at least
    /// 1000 rpm.
    pub start_rad_s: f64,
}

/// Runs `min-speed` on the plant with the loop `lp`.
pub fn study(
    plant: &Plant,
    lp: &Loop,
    s: &MinSpeedSettings,
) -> Result<MinSpeedStudy, ControlError> {
    let m = plant.motor();
    let p_max = s.p_max_pa();
    let open = open_loop_start(m, lp.load, P_ATM_PA, p_max, START_UP_POINTS)?;
    let ramp = ramp_simulation(m, lp.load, P_ATM_PA, p_max, s.ramp_s, RAMP_POINTS)?;
    // Start the loop settled well above the open-loop minimum (where it runs open loop).
    let w_start = (1.25 * open.w_min_rad_s).max(1000.0 * RAD_S_PER_RPM);
    let controlled = closed_loop_min_speed(m, lp, w_start, s.factor, s.floor_rad_s, s.stage_s)
        .map_err(|e| ControlError::StaircaseStart {
            start_rpm: rpm(w_start),
            source: Box::new(e),
        })?;
    Ok(MinSpeedStudy {
        settings: s.clone(),
        lp: *lp,
        open,
        ramp,
        controlled,
        start_rad_s: w_start,
    })
}
