//! The written results of `vanefit control <study>`: CSV tables and SVG figures, one file per
//! study here, and the one-line descriptions of valve, load and controller that the figures
//! and the printed summaries share.
//!
//! CSV columns carry their unit in the name, as the data files do (docs/formats.md, "CSV
//! recordings"): speeds in rpm, pressures in MPa absolute, conductances in m3/(s*Pa) (and
//! in dm3/(s*bar), the catalogues' unit, in an extra last column), torques in N*m, flows in
//! g/s, commands in V. Every file is written atomically; the caller hears of each one
//! written (the command line prints `wrote <path>`).

pub mod bode;
pub mod closed_loop;
pub mod design;
pub mod min_speed;
pub mod throttle;

use crate::control::closed_loop::{PiController, Trace, Valve, ValveDynamics};
use crate::control::rpm;
use crate::model::motor::Load;
use crate::report::plot::{Chart, Figure, Legend, PlotError, Series};
use std::path::{Path, PathBuf};

/// Why a study's results could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ControlReportError {
    /// A file could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// The output folder of a study and who hears of each file written — or, made by
/// `Writer::in_memory`, a list that keeps the tables and summaries as text.
pub struct Writer<'a> {
    sink: Sink<'a>,
}

/// Where a [`Writer`] puts what it writes.
enum Sink<'a> {
    /// Files in a folder; the callback hears of each.
    Folder(&'a Path, &'a mut dyn FnMut(&Path)),
    /// (file name, text) of the CSV tables and JSON summaries; no figure is drawn.
    Memory(&'a mut Vec<(String, String)>),
}

impl<'a> Writer<'a> {
    /// Writes into `dir` (which exists), calling `on_written` with the path of every file
    /// once it is in place.
    pub fn new(dir: &'a Path, on_written: &'a mut dyn FnMut(&Path)) -> Self {
        Self {
            sink: Sink::Folder(dir, on_written),
        }
    }

    /// Writes nothing: keeps each CSV table and JSON summary as (file name, text) in
    /// `files`, the same text a folder would get, and skips the figures (for callers that
    /// read the results in memory, such as the Python package).
    fn in_memory(files: &'a mut Vec<(String, String)>) -> Self {
        Self {
            sink: Sink::Memory(files),
        }
    }

    /// Writes `bytes` to the file `name` atomically.
    fn bytes(&mut self, name: &str, bytes: &[u8]) -> Result<(), ControlReportError> {
        let (dir, on_written) = match &mut self.sink {
            Sink::Folder(dir, on_written) => (*dir, on_written),
            Sink::Memory(files) => {
                files.push((
                    name.to_string(),
                    String::from_utf8_lossy(bytes).into_owned(),
                ));
                return Ok(());
            }
        };
        let path = dir.join(name);
        crate::io::write_atomic(&path, bytes).map_err(|source| ControlReportError::Write {
            path: path.clone(),
            source,
        })?;
        (on_written)(&path);
        Ok(())
    }

    /// Writes a CSV table.
    fn csv(&mut self, name: &str, t: &Table) -> Result<(), ControlReportError> {
        self.bytes(name, t.text().as_bytes())
    }

    /// Writes a JSON document (pretty-printed).
    fn json(&mut self, name: &str, v: &serde_json::Value) -> Result<(), ControlReportError> {
        let text = serde_json::to_string_pretty(v).unwrap_or_default() + "\n";
        self.bytes(name, text.as_bytes())
    }

    /// Writes a figure as SVG (in memory: not drawn).
    fn figure(&mut self, name: &str, fig: &Figure) -> Result<(), ControlReportError> {
        if let Sink::Memory(_) = self.sink {
            return Ok(());
        }
        let svg = fig.to_svg()?;
        self.bytes(name, svg.as_bytes())
    }
}

/// Which shaft a geared motor's study is at, as `shaft.json` says it: the motor's, with
/// the gearbox that relates it to the output (docs/formats.md, "Geared motors").
pub fn shaft_json(g: &crate::model::gear::Gear) -> serde_json::Value {
    serde_json::json!({
        "shaft": "motor",
        "gear_ratio": g.ratio,
        "gear_efficiency": g.efficiency,
        "gear_efficiency_printed": g.efficiency_printed,
        "note": shaft_note(g),
    })
}

/// One line for people: the study's speeds, torques and brake are the motor shaft's.
pub fn shaft_note(g: &crate::model::gear::Gear) -> String {
    format!(
        "geared motor: every speed, torque and load of this study is at the MOTOR shaft; the gearbox's output turns {} times slower with η·G = {:.4} times the torque ({})",
        g.ratio,
        g.efficiency * g.ratio,
        g.describe()
    )
}

/// Writes `shaft.json` ([`shaft_json`]) into `dir`, for a geared motor's study.
pub fn write_shaft(
    g: &crate::model::gear::Gear,
    dir: &Path,
    on_written: &mut dyn FnMut(&Path),
) -> Result<(), ControlReportError> {
    Writer::new(dir, on_written).json("shaft.json", &shaft_json(g))
}

/// The CSV tables and JSON summaries a study's `write` (e.g. [`bode::write`]) would write,
/// as (file name, text), without writing anything or drawing the figures.
pub fn texts<R>(
    r: &R,
    write: fn(&mut Writer, &R) -> Result<(), ControlReportError>,
) -> Result<Vec<(String, String)>, ControlReportError> {
    let mut files = Vec::new();
    write(&mut Writer::in_memory(&mut files), r)?;
    Ok(files)
}

/// A CSV table: header names with units, rows of numbers.
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Table {
    fn new(header: &[&str]) -> Self {
        Self {
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
        }
    }

    fn push(&mut self, row: Vec<f64>) {
        debug_assert_eq!(row.len(), self.header.len());
        self.rows.push(row);
    }

    /// The CSV text; numbers with 7 significant digits.
    fn text(&self) -> String {
        let mut s = self.header.join(",") + "\n";
        for r in &self.rows {
            let cells: Vec<String> = r.iter().map(|v| format!("{v:.6e}")).collect();
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        s
    }
}

/// The valve in words, e.g. `valve first order, tau 0.05 s; 0-10 V -> 0-6 bar gauge`.
pub fn describe_valve(v: &Valve) -> String {
    let dyn_ = match v.dynamics {
        ValveDynamics::FirstOrder { tau_s } => format!("first order, tau {tau_s} s"),
        ValveDynamics::SecondOrder { tau_s, zeta } => {
            format!("second order, tau {tau_s} s, zeta {zeta}")
        }
    };
    format!(
        "valve {dyn_}; 0-{} V -> 0-{} bar gauge",
        v.u_max_v,
        v.p_max_gauge_pa / 1e5
    )
}

/// The load in words, e.g. `brake 1e-4 N*m*s/rad`.
pub fn describe_load(l: &Load) -> String {
    match l {
        Load::None => "no load".into(),
        Load::ViscousBrake { c_nm_s_rad } => format!("brake {c_nm_s_rad:e} N*m*s/rad"),
        Load::Torque { t_nm } => format!("torque {t_nm} N*m"),
        Load::BrakeAndTorque { c_nm_s_rad, t_nm } => {
            format!("brake {c_nm_s_rad:e} N*m*s/rad and torque {t_nm} N*m")
        }
    }
}

/// The controller in words: its transfer function, speed unit, sample time, anti-windup.
pub fn describe_pi(pi: &PiController) -> String {
    format!(
        "PI ({:.4} s + {:.4})/s on error in {} rpm -> V, Ts {} ms, anti-windup {:?}",
        pi.kp,
        pi.ki,
        pi.speed_unit_rpm,
        pi.ts_s * 1e3,
        pi.anti_windup
    )
}

/// A closed-loop trace as a table, one row per controller sample.
fn trace_table(tr: &Trace) -> Table {
    let mut t = Table::new(&[
        "t_s",
        "setpoint_rpm",
        "speed_rpm",
        "command_v",
        "p_valve_mpa",
        "p1_mpa",
        "integral_v",
        "load_nm",
    ]);
    for k in 0..tr.t_s.len() {
        t.push(vec![
            tr.t_s[k],
            rpm(tr.setpoint_rad_s[k]),
            rpm(tr.speed_rad_s[k]),
            tr.command_v[k],
            tr.p_valve_pa[k] / 1e6,
            tr.p1_pa[k] / 1e6,
            tr.integral_v[k],
            tr.load_nm[k],
        ]);
    }
    t
}

/// Fig. 19/20 style panels: speed (and set-point), command, pressures.
fn trace_figure(title: &str, runs: &[(&str, &Trace)]) -> Figure {
    let xy = |tr: &Trace, v: &dyn Fn(usize) -> f64| {
        (0..tr.t_s.len())
            .map(|k| (tr.t_s[k], v(k)))
            .collect::<Vec<_>>()
    };
    let mut speed =
        Chart::new(&format!("{title}: speed"), "t [s]", "speed [rpm]").legend(Legend::Right);
    let mut cmd = Chart::new("valve command y", "t [s]", "command [V]").legend(Legend::Right);
    let mut pres = Chart::new("pressure at the motor inlet", "t [s]", "pressure [MPa abs]")
        .legend(Legend::Right);
    if let Some((_, tr)) = runs.first() {
        speed.series.push(Series::line(
            "set-point",
            xy(tr, &|k| rpm(tr.setpoint_rad_s[k])),
        ));
    }
    for (name, tr) in runs {
        speed
            .series
            .push(Series::line(name, xy(tr, &|k| rpm(tr.speed_rad_s[k]))));
        cmd.series
            .push(Series::line(name, xy(tr, &|k| tr.command_v[k])));
        pres.series.push(Series::line(
            &format!("{name}: valve"),
            xy(tr, &|k| tr.p_valve_pa[k] / 1e6),
        ));
        pres.series.push(Series::line(
            &format!("{name}: V1"),
            xy(tr, &|k| tr.p1_pa[k] / 1e6),
        ));
    }
    Figure::new(vec![speed, cmd, pres], 1)
}

/// Pairs of (x, y) from two columns.
fn pairs(x: &[f64], y: &[f64]) -> Vec<(f64, f64)> {
    x.iter().zip(y).map(|(x, y)| (*x, *y)).collect()
}

#[cfg(test)]
mod shaft_tests {
    use super::*;
    use crate::model::gear::Gear;

    /// A geared study says it is at the motor shaft, with η·G for the output's torque.
    #[test]
    fn a_geared_study_names_the_motor_shaft() {
        let g = Gear::new(4.0, Some(0.9));
        let note = shaft_note(&g);
        assert!(
            note.contains("MOTOR shaft") && note.contains("3.6000"),
            "{note}"
        );
        let doc = shaft_json(&g);
        assert_eq!(doc["shaft"], "motor");
        assert_eq!(doc["gear_ratio"], 4.0);
        let dir = tempfile::tempdir().unwrap();
        let mut seen = Vec::new();
        write_shaft(&g, dir.path(), &mut |p| seen.push(p.to_path_buf())).unwrap();
        assert_eq!(seen, vec![dir.path().join("shaft.json")]);
    }
}
