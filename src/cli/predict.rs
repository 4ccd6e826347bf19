//! `vanefit predict <fit.json>` (issue 12, SPEC §7): what the fitted motor does at other
//! supply pressures or with an extra nozzle, with 95 % bands; the work is
//! `vanefit::task::predict` (shared with `batch`), this parses and prints the tables.
//!
//! Every bad input (fit file, pressure list, unit, nozzle) is refused with a message that
//! names the file or option, exit status 1, before anything is written.

use crate::cli::Failure;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use vanefit::data::fitfile::FitFile;
use vanefit::report::predict::{notes, tables_markdown};
use vanefit::task::predict::{
    fit_atmosphere_pa, predict, pressure_unit, source_name, write_prediction, PredictOptions,
};
use vanefit::task::OptionError;

/// `vanefit predict` arguments. Values may start with a minus sign (`-1e-9`), so that a
/// negative number is refused with its option named (status 1), not as a usage error.
#[derive(Args, Debug, Clone)]
pub(crate) struct PredictArgs {
    /// Fit file (vanefit.fit/1).
    pub(crate) fit: PathBuf,
    /// Supply pressures, comma-separated, in --unit (default 3,4,5,6,7 bar g).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) pressures: Option<String>,
    /// Pressure unit of --pressures, --reference and the outputs: a unit suffix of
    /// p_port1 columns (bar_g, bar_abs, mpa, kpa, pa, ...).
    #[arg(long, default_value = "bar_g")]
    pub(crate) unit: String,
    /// Reference pressure of the correction factors, in --unit (default 6.3 bar g).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) reference: Option<f64>,
    /// Extra nozzle in series in front of port 1: its sonic conductance C, m3/(s*Pa) (a
    /// sharp-edged 2 mm orifice is about 5e-9).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) inlet_nozzle: Option<f64>,
    /// Extra nozzle in series behind port 2: its sonic conductance C, m3/(s*Pa).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) outlet_nozzle: Option<f64>,
    /// Speed grid on which the maximum power is exact, rpm.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub(crate) speed_grid_rpm: f64,
    /// Points of each curve from standstill to the free speed.
    #[arg(long, default_value_t = vanefit::predict::options::DEFAULT_CURVE_POINTS)]
    pub(crate) curve_points: usize,
    /// Take the parameters a fit could estimate but held fixed or could not identify as
    /// uncertain within this factor (95 %), so that the bands include them (e.g. 1.5 for a
    /// catalogue fit's defaults).
    #[arg(long)]
    pub(crate) fixed_spread: Option<f64>,
    /// Output folder (created).
    #[arg(long, default_value = "predict")]
    pub(crate) out: PathBuf,
}

/// `--pressures`: a comma-separated list of numbers, at least one.
fn pressure_list(list: &str) -> Result<Vec<f64>, OptionError> {
    let fail =
        |why: String| OptionError::new("PredictOptions.pressures", format!(" '{list}': {why}"));
    let items: Vec<&str> = list.split(',').map(str::trim).collect();
    if items.iter().all(|s| s.is_empty()) {
        return Err(fail("give at least one pressure, e.g. 3,4,5".into()));
    }
    items
        .iter()
        .map(|s| {
            s.parse()
                .map_err(|_| fail(format!("'{s}' is not a number")))
        })
        .collect()
}

impl PredictArgs {
    /// The library's options (the unit and the pressure list parsed).
    pub(crate) fn options(&self) -> Result<PredictOptions, OptionError> {
        Ok(PredictOptions {
            unit: pressure_unit("PredictOptions.unit", &self.unit)?,
            pressures: self.pressures.as_deref().map(pressure_list).transpose()?,
            reference: self.reference,
            inlet_nozzle_m3_s_pa: self.inlet_nozzle,
            outlet_nozzle_m3_s_pa: self.outlet_nozzle,
            speed_grid_rpm: self.speed_grid_rpm,
            curve_points: self.curve_points,
            fixed_spread: self.fixed_spread,
        })
    }
}

/// Runs `vanefit predict`.
pub(crate) fn run(args: &PredictArgs) -> Result<(), Failure> {
    let t0 = Instant::now();
    vanefit::io::out::check_dir(&args.out).map_err(|e| Failure(format!("--out {e}")))?;
    let fit = FitFile::read(&args.fit)?;
    let settings = args.options()?.check(fit_atmosphere_pa(&fit))?;
    let prediction = predict(&fit, &settings)?;
    let source = source_name(&args.fit, &fit);
    let written = write_prediction(&prediction, &settings, &source, &args.out)?;
    let display = settings.display();
    say!("prediction from {source}\n");
    say!("{}", tables_markdown(&prediction, display));
    for n in notes(&prediction, display) {
        say!("- {n}");
    }
    let written: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    say!(
        "\nwrote {} ({:.2} s)",
        written.join(", "),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
