//! `vanefit plan <fit.json>` (docs/cli.md, "plan"; docs/plan.md): candidate measurements
//! ranked by how much they are expected to shrink the 95 % bands at the user's operating
//! points; the work is `vanefit::plan::plan`, this parses, prints the ranking and writes
//! `plan.md` and `plan.json`.
//!
//! Every bad input (fit file, pressure or speed list, costs) is refused with a message that
//! names the file or option, exit status 1, before anything is written.

use crate::cli::predict::{pressure_list, pressure_suffixes, Progress};
use crate::cli::Failure;
use clap::builder::PossibleValuesParser;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use vanefit::data::FitFile;
use vanefit::plan::{CandidateKind, PlanError, PlanOptions, DEFAULT_TOP};
use vanefit::report::plan::{ranking_markdown, write};
use vanefit::report::predict::PressureDisplay;
use vanefit::task::{fit_atmosphere_pa, pressure_unit, source_name, Opt};
use vanefit::units::Unit;

/// `vanefit plan` arguments. Values may start with a minus sign, so that a negative number
/// is refused with its option named (status 1), not as a usage error.
#[derive(Args, Debug, Clone)]
pub(crate) struct PlanArgs {
    /// Fit file (vanefit.fit/1).
    pub(crate) fit: PathBuf,
    /// The operating supply pressures, comma-separated, in --unit.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) pressures: String,
    /// The operating shaft speeds, rpm, comma-separated (the output shaft's for a geared
    /// motor): the bands of torque, power and air there. Omitted: the catalogue figures
    /// at each pressure (max. power, free speed, stall torque, air at max. power).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) speeds: Option<String>,
    /// Pressure unit of --pressures and the outputs: a unit suffix of p_port1 columns.
    #[arg(long, default_value = "bar_g", value_parser = PossibleValuesParser::new(pressure_suffixes()))]
    pub(crate) unit: String,
    /// Rig time of candidate kinds, hours, overriding the defaults: name=hours,… with
    /// names key_figures, stall_torque, air_flow, datasheet, pressure_ramp,
    /// outlet_throttle, load_step.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) costs: Option<String>,
    /// As predict's: take the parameters the fit held fixed or could not identify as
    /// uncertain within this factor (95 %).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) fixed_spread: Option<f64>,
    /// The kinds of candidate weighed, comma-separated (default all): key_figures,
    /// stall_torque, air_flow, datasheet, pressure_ramp, outlet_throttle, load_step.
    #[arg(long)]
    pub(crate) candidates: Option<String>,
    /// Candidates detailed (bands before and after, rig settings).
    #[arg(long, default_value_t = DEFAULT_TOP)]
    pub(crate) top: usize,
    /// Output folder (created): plan.md and plan.json.
    #[arg(long, default_value = "plan")]
    pub(crate) out: PathBuf,
}

/// `--speeds`: a comma-separated list of rpm, each ≥ 0, in rad/s.
fn speed_list(list: &str) -> Result<Vec<f64>, Failure> {
    let items: Vec<&str> = list.split(',').map(str::trim).collect();
    items
        .iter()
        .map(|s| match s.parse::<f64>() {
            Ok(v) if v.is_finite() && v >= 0.0 => Ok(Unit::Rpm.to_si(v, 0.0)),
            _ => Err(Failure(format!(
                "--speeds '{list}': '{s}' is not a speed ≥ 0 in rpm (e.g. --speeds 500,1000)"
            ))),
        })
        .collect()
}

/// `--candidates`: kind names, each known.
fn kind_list(list: &str) -> Result<Vec<CandidateKind>, Failure> {
    let names: Vec<&str> = CandidateKind::ALL.iter().map(|k| k.name()).collect();
    list.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|n| {
            CandidateKind::from_name(n).ok_or_else(|| {
                Failure(format!(
                    "--candidates '{list}': no candidate '{n}' (one of {})",
                    names.join(", ")
                ))
            })
        })
        .collect()
}

/// `--costs`: `name=hours` pairs, each name a candidate kind, each cost a positive number.
fn cost_list(list: &str) -> Result<Vec<(CandidateKind, f64)>, Failure> {
    let names: Vec<&str> = CandidateKind::ALL.iter().map(|k| k.name()).collect();
    list.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|item| {
            let fail = |why: String| Failure(format!("--costs '{list}': '{item}': {why}"));
            let (name, hours) = item
                .split_once('=')
                .ok_or_else(|| fail("write name=hours, e.g. datasheet=3".into()))?;
            let kind = CandidateKind::from_name(name.trim()).ok_or_else(|| {
                fail(format!(
                    "no candidate '{}' (one of {})",
                    name.trim(),
                    names.join(", ")
                ))
            })?;
            match hours.trim().parse::<f64>() {
                Ok(h) if h.is_finite() && h > 0.0 => Ok((kind, h)),
                _ => Err(fail(format!(
                    "'{}' is not a positive number of hours",
                    hours.trim()
                ))),
            }
        })
        .collect()
}

impl PlanArgs {
    /// The library's options (lists parsed, pressures in SI), and how pressures are shown.
    fn options(&self, p_atm_pa: f64) -> Result<(PlanOptions, PressureDisplay), Failure> {
        let unit = pressure_unit(Opt::PredictUnit, &self.unit).map_err(Failure::option)?;
        let pressures = pressure_list(&self.pressures).map_err(Failure::option)?;
        let mut o = PlanOptions::new(
            pressures.iter().map(|p| unit.to_si(*p, p_atm_pa)).collect(),
            p_atm_pa,
        );
        o.speeds_rad_s = self.speeds.as_deref().map(speed_list).transpose()?;
        o.costs_h = self
            .costs
            .as_deref()
            .map(cost_list)
            .transpose()?
            .unwrap_or_default();
        o.fixed_spread = self.fixed_spread;
        o.top = self.top;
        o.kinds = self.candidates.as_deref().map(kind_list).transpose()?;
        o.check().map_err(|e| self.refused(e, unit, p_atm_pa))?;
        Ok((o, PressureDisplay { unit, p_atm_pa }))
    }

    /// A refused option, named by its flag.
    fn refused(&self, e: PlanError, unit: Unit, p_atm_pa: f64) -> Failure {
        match e {
            PlanError::NoPressures => Failure("--pressures: give at least one pressure".into()),
            PlanError::BadPressure(p) => Failure(format!(
                "--pressures '{}': {} {} is not a pressure above atmosphere",
                self.pressures,
                unit.from_si(p, p_atm_pa),
                self.unit
            )),
            PlanError::BadSpeed(_) => {
                Failure("--speeds: give at least one speed ≥ 0 in rpm".into())
            }
            PlanError::BadSpread(f) => Failure(format!("--fixed-spread {f}: not a factor > 1")),
            PlanError::BadTop => {
                Failure(format!("--top {}: detail at least 1 candidate", self.top))
            }
            PlanError::NoKinds => Failure("--candidates: name at least one kind".into()),
            e => Failure(e.to_string()),
        }
    }
}

/// Runs `vanefit plan`.
pub(crate) fn run(args: &PlanArgs) -> Result<(), Failure> {
    let t0 = Instant::now();
    vanefit::io::check_dir(&args.out).map_err(|e| Failure(format!("--out {e}")))?;
    let fit = FitFile::read(&args.fit)?;
    let (options, display) = args.options(fit_atmosphere_pa(&fit))?;
    let bar = Progress::default();
    let plan = vanefit::plan::plan(&fit, &options, &|what, done, total| {
        bar.tell(what, done, total)
    })
    .map_err(|e| Failure(format!("{}: {e}", args.fit.display())))?;
    let source = source_name(&args.fit, &fit);
    std::fs::create_dir_all(&args.out)
        .map_err(|e| Failure(format!("--out {}: {e}", args.out.display())))?;
    let written = write(&plan, &display, &source, &args.out)?;
    say!("which measurement next, from {source}\n");
    say!("{}", ranking_markdown(&plan, &display));
    for n in vanefit::report::plan::notes(&plan) {
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
