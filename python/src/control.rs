//! Control studies: the library's typed `ControlStudy` (motor, loop, study options) built
//! from the options Python gives by name, checked and run with the GIL released. The tables
//! come back as the CSV text and JSON the command writes (read in memory, nothing written
//! unless a folder is given).

use crate::errors::{param_err, DataError, ParameterError, VanefitError};
use pyo3::prelude::*;
use serde_json::{Map, Value};
use std::path::PathBuf;
use vanefit::control::BodeOptions;
use vanefit::control::DesignOptions;
use vanefit::control::DisturbanceOptions;
use vanefit::control::MinSpeedOptions;
use vanefit::control::Port;
use vanefit::control::StepOptions;
use vanefit::control::ThrottleOptions;
use vanefit::control::{ControlError, ControlOpt};
use vanefit::control::{GainOptions, LoopOptions, MotorOptions, PiOptions, ValveOptions};
use vanefit::report::control as rc;
use vanefit::report::control::ControlReportError;
use vanefit::task::{ControlStudy, Study, StudyResult};

/// A study's CSV tables and JSON summaries as (file name, text), the text its files get.
fn texts(r: &StudyResult) -> Result<Vec<(String, String)>, ControlReportError> {
    match r {
        StudyResult::Throttle(r) => rc::texts(r, rc::throttle::write),
        StudyResult::Bode(r) => rc::texts(r, rc::bode::write),
        StudyResult::Step(r) => rc::texts(r, rc::closed_loop::write_step),
        StudyResult::Disturbance(r) => rc::texts(r, rc::closed_loop::write_disturbance),
        StudyResult::MinSpeed(r) => rc::texts(r, rc::min_speed::write),
        StudyResult::Design(r) => rc::texts(r, rc::design::write),
        _ => Ok(Vec::new()),
    }
}

/// The options by name (every one given: the Python side fills in the defaults).
struct Options(Map<String, Value>);

impl Options {
    fn value(&self, name: &str) -> PyResult<&Value> {
        self.0
            .get(name)
            .ok_or_else(|| ParameterError::new_err(format!("{name}: missing")))
    }

    fn f64(&self, name: &str) -> PyResult<f64> {
        self.value(name)?
            .as_f64()
            .ok_or_else(|| ParameterError::new_err(format!("{name}: must be a number")))
    }

    fn opt_f64(&self, name: &str) -> PyResult<Option<f64>> {
        match self.0.get(name) {
            None | Some(Value::Null) => Ok(None),
            Some(_) => self.f64(name).map(Some),
        }
    }

    fn usize(&self, name: &str) -> PyResult<usize> {
        self.value(name)?
            .as_u64()
            .map(|v| v as usize)
            .ok_or_else(|| ParameterError::new_err(format!("{name}: must be a whole number >= 0")))
    }

    fn text(&self, name: &str) -> PyResult<String> {
        self.value(name)?
            .as_str()
            .map(str::to_string)
            .ok_or_else(|| ParameterError::new_err(format!("{name}: must be text")))
    }

    fn valve(&self) -> PyResult<ValveOptions> {
        Ok(ValveOptions {
            tau_s: self.opt_f64("valve_tau_s")?,
            u_max_v: self.f64("valve_u_max_v")?,
            p_max_bar_g: self.f64("valve_p_max_bar_g")?,
        })
    }

    fn control_loop(&self, gains: bool) -> PyResult<LoopOptions> {
        Ok(LoopOptions {
            valve: self.valve()?,
            pi: PiOptions {
                ts_ms: self.f64("ts_ms")?,
                speed_unit_rpm: self.f64("speed_unit_rpm")?,
                anti_windup: self.text("anti_windup")?,
            },
            gains: if gains {
                Some(GainOptions {
                    kp: self.f64("kp")?,
                    ki: self.f64("ki")?,
                })
            } else {
                None
            },
        })
    }

    fn throttle(&self, port: Port) -> PyResult<Study> {
        Ok(Study::Throttle(ThrottleOptions {
            port,
            p_supply_mpa: self.f64("p_supply_mpa")?,
            c_min_m3_s_pa: self.f64("c_min_m3_s_pa")?,
            c_max_m3_s_pa: self.f64("c_max_m3_s_pa")?,
            points: self.usize("points")?,
            curves_m3_s_pa: self.text("curves_m3_s_pa")?,
        }))
    }

    /// The study named `name` with its options.
    fn study(&self, name: &str) -> PyResult<Study> {
        Ok(match name {
            "throttle-inlet" => self.throttle(Port::Inlet)?,
            "throttle-outlet" => self.throttle(Port::Outlet)?,
            "bode" => Study::Bode(BodeOptions {
                p_mean_mpa: self.f64("p_mean_mpa")?,
                f_min_hz: self.f64("f_min_hz")?,
                f_max_hz: self.f64("f_max_hz")?,
                points: self.usize("points")?,
                valve: self.valve()?,
            }),
            "step" => Study::Step(
                self.control_loop(true)?,
                StepOptions {
                    from_rpm: self.f64("from_rpm")?,
                    to_rpm: self.f64("to_rpm")?,
                    t_step_s: self.f64("t_step_s")?,
                    duration_s: self.f64("duration_s")?,
                },
            ),
            "disturbance" => Study::Disturbance(
                self.control_loop(true)?,
                DisturbanceOptions {
                    rpm: self.f64("rpm")?,
                    load_step_nm: self.f64("load_step_nm")?,
                    t_step_s: self.f64("t_step_s")?,
                    duration_s: self.f64("duration_s")?,
                },
            ),
            "min-speed" => Study::MinSpeed(
                self.control_loop(true)?,
                MinSpeedOptions {
                    p_max_mpa: self.f64("p_max_mpa")?,
                    ramp_s: self.f64("ramp_s")?,
                    factor: self.f64("factor")?,
                    floor_rpm: self.opt_f64("floor_rpm")?,
                    stage_s: self.f64("stage_s")?,
                },
            ),
            "design" => Study::Design(
                self.control_loop(false)?,
                DesignOptions {
                    pm_deg: self.f64("pm_deg")?,
                    crossover_hz: self.opt_f64("crossover_hz")?,
                    p_mean_mpa: self.f64("p_mean_mpa")?,
                    step_rpm: self.f64("step_rpm")?,
                    duration_s: self.f64("duration_s")?,
                },
            ),
            other => {
                return Err(ParameterError::new_err(format!(
                    "study '{other}': one of throttle-inlet, throttle-outlet, bode, step, \
                     disturbance, min-speed, design"
                )))
            }
        })
    }
}

/// A study's tables: (name, [(column, values)]).
type Tables = Vec<(String, Vec<(String, Vec<f64>)>)>;

/// A CSV table the study wrote, as columns of numbers.
fn columns(text: &str) -> Vec<(String, Vec<f64>)> {
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or_default().split(',').collect();
    let mut cols: Vec<(String, Vec<f64>)> =
        header.iter().map(|h| (h.to_string(), Vec::new())).collect();
    for line in lines {
        for (c, cell) in cols.iter_mut().zip(line.split(',')) {
            c.1.push(cell.trim().parse().unwrap_or(f64::NAN));
        }
    }
    cols
}

/// Runs the control study `study` (`throttle-inlet`, `throttle-outlet`, `bode`, `step`,
/// `disturbance`, `min-speed`, `design`) on the motor of the fit file `fit`, or of the
/// fit-file text `fit_text` (a fit held in memory; `fit` then only names it) (neither: the
/// default motor) with `options` (JSON: every option by name). Returns its tables (CSV
/// text read into columns, by file stem) and its JSON summaries (text, by file stem);
/// writes its files and figures into `out` when given.
#[pyfunction]
#[pyo3(signature = (study, fit, fit_text, options, out))]
pub fn control(
    py: Python<'_>,
    study: &str,
    fit: Option<PathBuf>,
    fit_text: Option<String>,
    options: &str,
    out: Option<PathBuf>,
) -> PyResult<(Tables, Vec<(String, String)>)> {
    let map: Map<String, Value> = serde_json::from_str(options).map_err(param_err)?;
    let o = Options(map);
    let study = ControlStudy {
        motor: MotorOptions {
            params: fit,
            params_text: fit_text,
            effects: o
                .0
                .get("effects")
                .and_then(Value::as_str)
                .map(str::to_string),
            brake_nm_s_rad: o.opt_f64("brake_nm_s_rad")?,
        },
        study: o.study(study)?,
    };
    let checked = study.check().map_err(control_err)?;
    let _lock = match &out {
        Some(dir) => {
            Some(vanefit::io::prepare_dir(dir).map_err(|e| param_err(format!("out {e}")))?)
        }
        None => None,
    };
    let result = py.detach(|| checked.run()).map_err(control_err)?;
    let report_err = |e: ControlReportError| VanefitError::new_err(e.to_string());
    if let Some(dir) = &out {
        vanefit::task::write_study(&result, dir, &mut |_| {}).map_err(report_err)?;
    }
    let texts = texts(&result).map_err(report_err)?;
    if let StudyResult::Design(r) = &result {
        // As the command: the results are there to look at, then the failed check.
        r.check_settled().map_err(control_err)?;
    }
    let mut tables = Vec::new();
    let mut summaries = Vec::new();
    for (name, text) in texts {
        match name.rsplit_once('.') {
            Some((stem, "csv")) => tables.push((stem.to_string(), columns(&text))),
            Some((stem, "json")) => summaries.push((stem.to_string(), text)),
            _ => {}
        }
    }
    Ok((tables, summaries))
}

/// A study's error as the exception Python users catch: a fit file that cannot be read is
/// a DataError, a bad option a ParameterError, a study that fails a VanefitError. Options
/// are named as the Python keywords ([`keyword`]).
fn control_err(e: ControlError) -> PyErr {
    let message = e.message_with(&keyword);
    match e {
        ControlError::FitFile(_) => DataError::new_err(message),
        ControlError::Settings(_) | ControlError::SetPoint { .. } => {
            ParameterError::new_err(message)
        }
        _ => VanefitError::new_err(message),
    }
}

/// The keyword of `control()` that sets a control study's option: the field's name
/// (`from_rpm` for `StepOptions.from_rpm`), `valve_` before the valve's, and `fit` for the
/// fit file.
fn keyword(o: ControlOpt) -> &'static str {
    match o {
        ControlOpt::MotorParams => "fit",
        ControlOpt::ValveTau => "valve_tau_s",
        ControlOpt::ValveUMax => "valve_u_max_v",
        ControlOpt::ValvePMax => "valve_p_max_bar_g",
        other => other.name(),
    }
}
