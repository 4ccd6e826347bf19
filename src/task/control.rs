//! `control` as a task: a [`ControlStudy`] (the motor and its load, the loop, the study's
//! own options, all unchecked) → [`ControlStudy::check`] → [`CheckedStudy`] →
//! [`CheckedStudy::run`] → [`StudyResult`], written by [`write_study`]. The studies are
//! those of paper §5: throttling, frequency response, step and disturbance responses, the
//! lowest steady speed and a PI design.

use crate::control::closed_loop::Loop;
use crate::control::study::bode::{self, BodeOptions, BodeSettings, BodeStudy};
use crate::control::study::design::{self, DesignOptions, DesignSettings, DesignStudy};
use crate::control::study::disturbance::{
    self, DisturbanceOptions, DisturbanceSettings, DisturbanceStudy,
};
use crate::control::study::min_speed::{self, MinSpeedOptions, MinSpeedSettings, MinSpeedStudy};
use crate::control::study::step::{self, StepOptions, StepSettings, StepStudy};
use crate::control::study::throttle::{self, ThrottleOptions, ThrottleSettings, ThrottleStudy};
use crate::control::study::{LoopOptions, MotorOptions, Plant};
use crate::control::ControlError;
use crate::report::control::{ControlReportError, Writer};
use std::path::Path;

/// Which study, with its own options (unchecked).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Study {
    /// Steady speed against a throttle's conductance, and torque-speed curves for several
    /// throttles (paper Figs. 14, 15); the port is in the options.
    Throttle(ThrottleOptions),
    /// Frequency response supply pressure → speed about an operating point (Figs. 16, 17).
    Bode(BodeOptions),
    /// Closed-loop response to a set-point step (Fig. 19).
    Step(LoopOptions, StepOptions),
    /// Closed-loop rejection of a load-torque step (Fig. 20).
    Disturbance(LoopOptions, DisturbanceOptions),
    /// Lowest steady speed without and with control.
    MinSpeed(LoopOptions, MinSpeedOptions),
    /// PI gains for a phase margin or crossover, checked by simulation (the loop's gains
    /// are not used).
    Design(LoopOptions, DesignOptions),
}

/// A control study as given (unchecked): the motor and its load, and the study.
#[derive(Debug, Clone, PartialEq)]
pub struct ControlStudy {
    /// The motor (fit file, effects) and the brake on its shaft.
    pub motor: MotorOptions,
    /// The study and its options.
    pub study: Study,
}

impl ControlStudy {
    /// The study's name: `throttle-inlet`, `throttle-outlet`, `bode`, `step`,
    /// `disturbance`, `min-speed` or `design` (the command line's, and the default output
    /// folder's `control-<name>`).
    pub fn name(&self) -> String {
        match &self.study {
            Study::Throttle(o) => format!("throttle-{}", o.port.name()),
            Study::Bode(_) => "bode".into(),
            Study::Step(..) => "step".into(),
            Study::Disturbance(..) => "disturbance".into(),
            Study::MinSpeed(..) => "min-speed".into(),
            Study::Design(..) => "design".into(),
        }
    }

    /// The brake when none is given, N·m·s/rad: 1e-4, but none for `min-speed` (the
    /// paper reports it without load).
    pub fn default_brake_nm_s_rad(&self) -> f64 {
        match self.study {
            Study::MinSpeed(..) => 0.0,
            _ => 1e-4,
        }
    }

    /// Reads the fit file and checks the motor and its load only (the plant every study
    /// runs on).
    pub fn check_plant(&self) -> Result<Plant, ControlError> {
        self.motor.check(self.default_brake_nm_s_rad())
    }

    /// Checks everything: the plant ([`ControlStudy::check_plant`]), then the loop, then
    /// the study's options.
    pub fn check(&self) -> Result<CheckedStudy, ControlError> {
        let plant = self.check_plant()?;
        self.check_on(plant)
    }

    /// Checks the loop and the study's options on a checked plant.
    pub fn check_on(&self, plant: Plant) -> Result<CheckedStudy, ControlError> {
        let settings = match &self.study {
            Study::Throttle(o) => Settings::Throttle(o.check()?),
            Study::Bode(o) => Settings::Bode(o.check(plant.motor())?),
            Study::Step(l, o) => Settings::Step(l.check(&plant)?, o.check()?),
            Study::Disturbance(l, o) => Settings::Disturbance(l.check(&plant)?, o.check()?),
            Study::MinSpeed(l, o) => {
                let lp = l.check(&plant)?;
                Settings::MinSpeed(lp, o.check(plant.motor())?)
            }
            Study::Design(l, o) => Settings::Design(l.check(&plant)?, o.check()?),
        };
        Ok(CheckedStudy { plant, settings })
    }
}

/// A study's checked settings.
#[derive(Debug, Clone)]
enum Settings {
    Throttle(ThrottleSettings),
    Bode(BodeSettings),
    Step(Loop, StepSettings),
    Disturbance(Loop, DisturbanceSettings),
    MinSpeed(Loop, MinSpeedSettings),
    Design(Loop, DesignSettings),
}

/// A checked [`ControlStudy`], ready to run (private fields).
#[derive(Debug, Clone)]
pub struct CheckedStudy {
    plant: Plant,
    settings: Settings,
}

impl CheckedStudy {
    /// The motor and its load.
    pub fn plant(&self) -> &Plant {
        &self.plant
    }

    /// Runs the study.
    pub fn run(&self) -> Result<StudyResult, ControlError> {
        let p = &self.plant;
        Ok(match &self.settings {
            Settings::Throttle(s) => StudyResult::Throttle(throttle::study(p, s)?),
            Settings::Bode(s) => StudyResult::Bode(bode::study(p, s)?),
            Settings::Step(l, s) => StudyResult::Step(step::study(p, l, s)?),
            Settings::Disturbance(l, s) => StudyResult::Disturbance(disturbance::study(p, l, s)?),
            Settings::MinSpeed(l, s) => StudyResult::MinSpeed(min_speed::study(p, l, s)?),
            Settings::Design(l, s) => StudyResult::Design(design::study(p, l, s)?),
        })
    }
}

/// The result of a control study (each holds its settings, its numbers and its traces).
// One value per study run, matched by its users: boxing the larger variants would save a few
// hundred bytes once and cost every match a dereference.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum StudyResult {
    /// Throttling.
    Throttle(ThrottleStudy),
    /// Frequency response.
    Bode(BodeStudy),
    /// Set-point step.
    Step(StepStudy),
    /// Load-torque step.
    Disturbance(DisturbanceStudy),
    /// Lowest steady speed.
    MinSpeed(MinSpeedStudy),
    /// PI design.
    Design(DesignStudy),
}

/// Checks and runs a study (a fit file is read when the motor options name one).
pub fn run_study(study: &ControlStudy) -> Result<StudyResult, ControlError> {
    study.check()?.run()
}

/// Writes a study's CSV tables, JSON summary and SVG figures into the folder `out`
/// (atomically), calling `on_written` with each file's path.
pub fn write_study(
    r: &StudyResult,
    out: &Path,
    on_written: &mut dyn FnMut(&Path),
) -> Result<(), ControlReportError> {
    use crate::report::control as rc;
    let w = &mut Writer::new(out, on_written);
    match r {
        StudyResult::Throttle(r) => rc::throttle::write(w, r),
        StudyResult::Bode(r) => rc::bode::write(w, r),
        StudyResult::Step(r) => rc::closed_loop::write_step(w, r),
        StudyResult::Disturbance(r) => rc::closed_loop::write_disturbance(w, r),
        StudyResult::MinSpeed(r) => rc::min_speed::write(w, r),
        StudyResult::Design(r) => rc::design::write(w, r),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::study::step::StepOptions;
    use crate::control::study::throttle::ThrottleOptions;
    use crate::control::study::GainOptions;
    use crate::control::throttle::Port;

    fn message(study: Study) -> String {
        let s = ControlStudy {
            motor: MotorOptions::default(),
            study,
        };
        s.check().unwrap_err().to_string()
    }

    /// The library names a bad option by its field (`ThrottleOptions.points`), never by a
    /// command-line flag: the command line and Python name it their own way.
    #[test]
    fn bad_options_name_the_field() {
        let throttle = Study::Throttle(ThrottleOptions {
            port: Port::Inlet,
            p_supply_mpa: 0.73,
            c_min_m3_s_pa: 3e-10,
            c_max_m3_s_pa: 1e-7,
            points: 1,
            curves_m3_s_pa: "none".into(),
        });
        assert_eq!(
            message(throttle),
            "ThrottleOptions.points 1: must be at least 2"
        );
        let step = StepOptions {
            from_rpm: 3000.0,
            to_rpm: 4500.0,
            t_step_s: 9.0,
            duration_s: 8.0,
        };
        assert_eq!(
            message(Study::Step(LoopOptions::default(), step.clone())),
            "StepOptions.t_step_s 9: must be before StepOptions.duration_s"
        );
        let mut lp = LoopOptions::default();
        lp.pi.anti_windup = "back-calculation".into();
        lp.gains = Some(GainOptions { kp: 0.0, ki: 4.0 });
        let m = message(Study::Step(
            lp,
            StepOptions {
                t_step_s: 0.5,
                ..step
            },
        ));
        assert!(
            m.starts_with("PiOptions.anti_windup back-calculation needs GainOptions.kp"),
            "{m}"
        );
        assert!(!m.contains("--"), "{m}");
    }
}
