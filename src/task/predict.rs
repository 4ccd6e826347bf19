//! `predict` as a task (issue 12, SPEC §7): the options of `vanefit predict`, checked, and
//! the prediction with the files it leaves (`catalogue.csv`, `factors.csv`, `curves.csv`,
//! `predict.md`, SVG figures), called by the command line and by `batch` alike.
//!
//! Every bad input (fit file, pressure list, unit, nozzle) is refused with a message that
//! names the file or option, exit status 1, before anything is written.

use crate::data::fitfile::{FitFile, FitFileError};
use crate::predict::Prediction;
use crate::predict::{predict, Nozzle, NozzlePort, PredictError, PredictOptions};
use crate::report::predict::{write, PredictReportError, PressureDisplay};
use crate::units::constants::P_ATM_PA;
use crate::units::{Quantity, Unit};
use clap::Args;
use std::path::{Path, PathBuf};

/// `vanefit predict` arguments. Values may start with a minus sign (`-1e-9`), so that a
/// negative number is refused with its option named (status 1), not as a usage error.
#[derive(Args, Debug, Clone)]
pub struct PredictArgs {
    /// Fit file (vanefit.fit/1).
    pub fit: PathBuf,
    /// Supply pressures, comma-separated, in --unit (default 3,4,5,6,7 bar g).
    #[arg(long, allow_hyphen_values = true)]
    pub pressures: Option<String>,
    /// Pressure unit of --pressures, --reference and the outputs: a unit suffix of
    /// p_port1 columns (bar_g, bar_abs, mpa, kpa, pa, ...).
    #[arg(long, default_value = "bar_g")]
    pub unit: String,
    /// Reference pressure of the correction factors, in --unit (default 6.3 bar g).
    #[arg(long, allow_hyphen_values = true)]
    pub reference: Option<f64>,
    /// Extra nozzle in series in front of port 1: its sonic conductance C, m3/(s*Pa) (a
    /// sharp-edged 2 mm orifice is about 5e-9).
    #[arg(long, allow_hyphen_values = true)]
    pub inlet_nozzle: Option<f64>,
    /// Extra nozzle in series behind port 2: its sonic conductance C, m3/(s*Pa).
    #[arg(long, allow_hyphen_values = true)]
    pub outlet_nozzle: Option<f64>,
    /// Speed grid on which the maximum power is exact, rpm.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub speed_grid_rpm: f64,
    /// Points of each curve from standstill to the free speed.
    #[arg(long, default_value_t = crate::predict::options::DEFAULT_CURVE_POINTS)]
    pub curve_points: usize,
    /// Take the parameters a fit could estimate but held fixed or could not identify as
    /// uncertain within this factor (95 %), so that the bands include them (e.g. 1.5 for a
    /// catalogue fit's defaults).
    #[arg(long)]
    pub fixed_spread: Option<f64>,
    /// Output folder (created).
    #[arg(long, default_value = "predict")]
    pub out: PathBuf,
}

/// Why `vanefit predict` failed (exit status 1).
#[derive(Debug, thiserror::Error)]
pub enum PredictCommandError {
    /// `--out` cannot be a folder (a file, or a parent that is a file).
    #[error("--out {0}")]
    Output(#[from] crate::io::out::OutputError),
    /// The fit file cannot be read.
    #[error(transparent)]
    FitFile(#[from] FitFileError),
    /// `--unit` names no pressure unit.
    #[error("--unit '{given}': not a pressure unit; use one of {known}")]
    Unit {
        /// What was given.
        given: String,
        /// The accepted suffixes.
        known: String,
    },
    /// `--pressures` or `--reference` is not a list of positive absolute pressures.
    #[error("{option} '{given}': {why}")]
    Pressure {
        /// `--pressures` or `--reference`.
        option: &'static str,
        /// What was given.
        given: String,
        /// What is wrong.
        why: String,
    },
    /// Both nozzles were given.
    #[error("--inlet-nozzle and --outlet-nozzle: give one extra nozzle, not both")]
    BothNozzles,
    /// A nozzle's conductance is not positive.
    #[error("--{option} {value}: the conductance must be a positive number of m3/(s*Pa)")]
    Nozzle {
        /// `inlet-nozzle` or `outlet-nozzle`.
        option: &'static str,
        /// What was given.
        value: f64,
    },
    /// `--speed-grid-rpm` or `--curve-points` out of range.
    #[error("--{option} {value}: {why}")]
    Setting {
        /// The option.
        option: &'static str,
        /// What was given.
        value: String,
        /// What is needed.
        why: &'static str,
    },
    /// The prediction failed.
    #[error("{0}")]
    Predict(String),
    /// The output folder cannot be made.
    #[error("{}: cannot create: {source}", path.display())]
    CreateDir {
        /// The folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The results cannot be written.
    #[error(transparent)]
    Report(#[from] PredictReportError),
}

/// The pressure unit named by its column suffix among those of `p_port1` columns.
fn pressure_unit(suffix: &str) -> Result<Unit, PredictCommandError> {
    let units = Quantity::PPort1.units();
    units
        .iter()
        .find(|u| u.suffix() == suffix.trim())
        .copied()
        .ok_or_else(|| PredictCommandError::Unit {
            given: suffix.to_string(),
            known: units
                .iter()
                .map(|u| u.suffix())
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// A pressure in `unit` as an absolute pressure, Pa, that must be positive.
fn absolute(
    option: &'static str,
    text: &str,
    v: f64,
    unit: Unit,
    p_atm_pa: f64,
) -> Result<f64, PredictCommandError> {
    let p = unit.to_si(v, p_atm_pa);
    if p.is_finite() && p > 0.0 {
        return Ok(p);
    }
    Err(PredictCommandError::Pressure {
        option,
        given: text.to_string(),
        why: format!(
            "{} {} is not a positive absolute pressure ({p} Pa)",
            v,
            unit.suffix()
        ),
    })
}

/// `--pressures`: a comma-separated list of numbers in `unit`, at least one.
fn pressures(list: &str, unit: Unit, p_atm_pa: f64) -> Result<Vec<f64>, PredictCommandError> {
    let fail = |why: String| PredictCommandError::Pressure {
        option: "--pressures",
        given: list.to_string(),
        why,
    };
    let items: Vec<&str> = list.split(',').map(str::trim).collect();
    if items.iter().all(|s| s.is_empty()) {
        return Err(fail("give at least one pressure, e.g. 3,4,5".into()));
    }
    items
        .iter()
        .map(|s| {
            let v: f64 = s
                .parse()
                .map_err(|_| fail(format!("'{s}' is not a number")))?;
            absolute("--pressures", list, v, unit, p_atm_pa)
        })
        .collect()
}

/// The prediction's options from the arguments (the fit file gives the atmosphere).
pub fn options(
    args: &PredictArgs,
    fit: &FitFile,
) -> Result<(PredictOptions, Unit), PredictCommandError> {
    let p_atm_pa = fit.conditions.map_or(P_ATM_PA, |c| c.p_atm_pa);
    let unit = pressure_unit(&args.unit)?;
    let mut o = PredictOptions::new(p_atm_pa);
    if let Some(list) = &args.pressures {
        o.pressures_pa = pressures(list, unit, p_atm_pa)?;
    }
    if let Some(r) = args.reference {
        o.reference_pa = absolute("--reference", &r.to_string(), r, unit, p_atm_pa)?;
    }
    let nozzle = |option: &'static str, port: NozzlePort, c: Option<f64>| match c {
        Some(v) if !(v.is_finite() && v > 0.0) => {
            Err(PredictCommandError::Nozzle { option, value: v })
        }
        Some(v) => Ok(Some(Nozzle { port, c_m3_s_pa: v })),
        None => Ok(None),
    };
    let inlet = nozzle("inlet-nozzle", NozzlePort::Inlet, args.inlet_nozzle)?;
    let outlet = nozzle("outlet-nozzle", NozzlePort::Outlet, args.outlet_nozzle)?;
    if inlet.is_some() && outlet.is_some() {
        return Err(PredictCommandError::BothNozzles);
    }
    o.nozzle = inlet.or(outlet);
    let grid = args.speed_grid_rpm;
    if !(grid.is_finite() && grid > 0.0) {
        return Err(PredictCommandError::Setting {
            option: "speed-grid-rpm",
            value: grid.to_string(),
            why: "must be a positive number of rpm",
        });
    }
    o.speed_grid_rad_s = Unit::Rpm.to_si(grid, p_atm_pa);
    if args.curve_points < 2 {
        return Err(PredictCommandError::Setting {
            option: "curve-points",
            value: args.curve_points.to_string(),
            why: "a curve needs at least 2 points",
        });
    }
    o.curve_points = args.curve_points;
    if let Some(f) = args.fixed_spread {
        if !(f.is_finite() && f > 1.0) {
            return Err(PredictCommandError::Setting {
                option: "fixed-spread",
                value: f.to_string(),
                why: "must be a factor > 1",
            });
        }
    }
    o.fixed_spread = args.fixed_spread;
    Ok((o, unit))
}

/// A prediction's failure in the asked unit (naming --reference when the reference
/// pressure is the one that failed, since every factor needs it).
fn failed(e: PredictError, display: &PressureDisplay, reference_pa: f64) -> PredictCommandError {
    PredictCommandError::Predict(match e {
        PredictError::AtPressure {
            p_supply_pa,
            source,
        } => format!(
            "at {} {} ({p_supply_pa:.0} Pa abs.{}): {source}",
            display.text(p_supply_pa),
            display.label(),
            if p_supply_pa == reference_pa {
                ", the --reference pressure of the factors"
            } else {
                ""
            }
        ),
        other => other.to_string(),
    })
}

/// A finished prediction and what it wrote.
pub struct Predicted {
    /// The prediction.
    pub prediction: Prediction,
    /// The pressure unit of the tables.
    pub display: PressureDisplay,
    /// The fit file and its dataset, as titles name them.
    pub source: String,
    /// The files written.
    pub written: Vec<PathBuf>,
}

/// Reads the fit file, checks the options, predicts and writes the results into
/// `args.out`; nothing is written when an input is bad.
pub fn predict_to(args: &PredictArgs) -> Result<Predicted, PredictCommandError> {
    let fit = FitFile::read(&args.fit)?;
    let (options, unit) = options(args, &fit)?;
    let display = PressureDisplay {
        unit,
        p_atm_pa: options.p_atm_pa,
    };
    let prediction =
        predict(&fit, &options).map_err(|e| failed(e, &display, options.reference_pa))?;
    std::fs::create_dir_all(&args.out).map_err(|source| PredictCommandError::CreateDir {
        path: args.out.clone(),
        source,
    })?;
    let source = source_name(&args.fit, &fit);
    let mut written = Vec::new();
    write(
        &prediction,
        &display,
        &source,
        &args.out,
        &mut |p: &Path| written.push(p.to_path_buf()),
    )?;
    Ok(Predicted {
        prediction,
        display,
        source,
        written,
    })
}

/// The fit file and its dataset, for titles.
fn source_name(path: &Path, fit: &FitFile) -> String {
    if fit.dataset.is_empty() {
        path.display().to_string()
    } else {
        format!("{} (fit of dataset {})", path.display(), fit.dataset)
    }
}
