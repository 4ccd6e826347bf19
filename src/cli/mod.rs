//! Command line (SPEC §6). Exit status: 0 success, 1 bad input or failed work, 2 bad usage
//! (clap reports usage errors with status 2 itself).

pub mod batch;
pub mod catalogue;
pub mod control;
pub mod diagnose;
pub mod export;
pub mod fit;
pub mod predict;

use crate::data::dataset::{Dataset, Kind};
use crate::data::fitfile::FitFile;
use crate::data::synth::{synthesize, write_dataset, SensorNoise, SynthPlan};
use crate::io::say;
use crate::model::effects::EffectSet;
use crate::model::motor::Motor;
use crate::model::params::MotorParams;
use crate::numerics::DefaultSolver;
use crate::sim::experiment::Experiment;
use crate::units::Quantity;
use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};

#[derive(Parser, Debug)]
#[command(
    name = "vanefit",
    version,
    about = "Estimate pneumatic vane motor parameters and find missing physics"
)]
/// The parsed command line.
pub struct Cli {
    #[command(subcommand)]
    /// The command to run.
    pub command: Command,
}

#[derive(Subcommand, Debug)]
/// The commands of SPEC §6.
pub enum Command {
    /// Validate a dataset and print a summary.
    Check {
        /// Dataset folder (rig.toml and recordings).
        dataset: PathBuf,
    },
    /// Simulate every experiment of a dataset under a parameter set.
    Simulate {
        /// Dataset folder (rig.toml and recordings).
        dataset: PathBuf,
        /// Fit file (vanefit.fit/1); omitted: the default motor.
        #[arg(long)]
        params: Option<PathBuf>,
        /// Output folder: one CSV per recording, same rows and column names.
        #[arg(long)]
        out: PathBuf,
    },
    /// Estimate parameters from a dataset (multi-start Nelder-Mead) and export a fit file.
    Fit(crate::cli::fit::FitArgs),
    /// Write a synthetic dataset from the simulator.
    Synth {
        /// Folder to write the dataset to.
        out_dataset: PathBuf,
        /// Fit file with the true parameters; omitted: the default motor.
        #[arg(long)]
        params: Option<PathBuf>,
        /// Effects to switch on (comma-separated ids), overriding the fit file's.
        #[arg(long, value_parser = crate::task::effects_arg)]
        effects: Option<String>,
        /// Sensor noise as a multiple of a typical rig's (0 for none).
        #[arg(long, default_value_t = 1.0)]
        noise: f64,
        /// Seed of the noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Write catalogue pages (curves and key figures, printed to 3 digits) instead of
        /// rig recordings.
        #[arg(long)]
        catalogue: bool,
        /// Supply pressures of the catalogue pages, bar(g), comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "6.3")]
        pressures: Vec<f64>,
    },
    /// Find the physics the model leaves out: locate, explain, model, refit (SPEC §5, §6).
    Diagnose(crate::cli::diagnose::DiagnoseArgs),
    /// Speed-control studies (paper section 5): throttling, frequency response, closed loop.
    Control(crate::cli::control::ControlArgs),
    /// Predict the fitted motor at other supply pressures or with an extra nozzle:
    /// catalogue figures, correction factors and curves with 95% bands (SPEC section 7).
    #[command(allow_negative_numbers = true)]
    Predict(crate::cli::predict::PredictArgs),
    /// Export a fit as a PEtab v1 problem: parameter, observable, measurement and condition
    /// tables, an SBML document declaring the model's symbols, and the problem YAML.
    ExportPetab(crate::cli::export::ExportPetabArgs),
    /// Run a manifest's fleet of datasets (fit, diagnose, predict) in resumable shards,
    /// here or on Slurm (SPEC section 7).
    Batch(crate::cli::batch::BatchArgs),
    /// Merge a batch folder into summary.csv, summary.md and fleet.svg (SPEC section 7).
    Merge(crate::cli::batch::MergeArgs),
}

/// A failure to report: message for stderr, exit status 1.
#[derive(Debug)]
pub struct Failure(pub String);

impl<E: std::error::Error> From<E> for Failure {
    fn from(e: E) -> Self {
        Failure(e.to_string())
    }
}

/// Runs a parsed command.
pub fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Check { dataset } => check(&dataset),
        Command::Fit(args) => Ok(crate::cli::fit::run(&args)?),
        Command::Simulate {
            dataset,
            params,
            out,
        } => simulate(&dataset, params.as_deref(), &out),
        Command::Synth {
            out_dataset,
            params,
            effects,
            catalogue: true,
            pressures,
            ..
        } => synth_catalogue(
            &out_dataset,
            params.as_deref(),
            effects.as_deref(),
            &pressures,
        ),
        Command::Synth {
            out_dataset,
            params,
            effects,
            noise,
            seed,
            ..
        } => synth(
            &out_dataset,
            params.as_deref(),
            effects.as_deref(),
            noise,
            seed,
        ),
        Command::Control(args) => crate::cli::control::run(args),
        Command::Diagnose(args) => crate::cli::diagnose::run(&args),
        Command::Predict(args) => Ok(crate::cli::predict::run(&args)?),
        Command::ExportPetab(args) => crate::cli::export::run(&args),
        Command::Batch(args) => crate::cli::batch::run(&args),
        Command::Merge(args) => crate::cli::batch::merge(&args),
    }
}

fn check(dir: &Path) -> Result<(), Failure> {
    let mut ds = Dataset::load(dir)?;
    // From here `check` prints values, not cells as written (except a catalogue's few
    // points): a recording's text, as large again as its values, is freed before the
    // references are fitted, when memory peaks (issue 15: a 100 MB recording in 500 MB).
    for ex in ds
        .experiments
        .iter_mut()
        .filter(|ex| ex.kind != Kind::Catalogue)
    {
        for c in &mut ex.recording.columns {
            c.raw = crate::data::dataset::Cells::new();
        }
    }
    // Every reference is fitted before anything is printed: a channel that cannot give one
    // refuses the dataset like any other bad input.
    let references = ds
        .experiments
        .iter()
        .map(|ex| {
            crate::objective::reference::experiment_references(
                ex,
                &crate::objective::reference::FitOptions::default(),
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    say!(
        "dataset {} ({}): motor {}, p_atm {:.0} Pa, {} experiment(s)",
        ds.name,
        if ds.synthetic {
            "synthetic"
        } else {
            "measured"
        },
        ds.motor.name.as_deref().unwrap_or("unnamed"),
        ds.p_atm_pa,
        ds.experiments.len()
    );
    for (ex, refs) in ds.experiments.iter().zip(&references) {
        say!(
            "  {} {} ({} rows)",
            ex.kind.id(),
            ex.file,
            ex.recording.rows()
        );
        for c in &ex.recording.columns {
            let (lo, hi) =
                c.si.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                        (a.min(*v), b.max(*v))
                    });
            let to = |v: f64| c.unit.from_si(v, ds.p_atm_pa);
            say!(
                "    {:<20} {:>13} .. {:<13} [{}]",
                c.name,
                num(to(lo)),
                num(to(hi)),
                c.unit.suffix()
            );
        }
        catalogue::print(ex, ds.p_atm_pa);
        for r in refs {
            print_reference(r, ds.p_atm_pa);
        }
    }
    Ok(())
}

/// One reference response for `check`: channel, degree, R², σ in the column's unit, valid
/// range in the abscissa column's unit, and its pieces when the data jump.
fn print_reference(r: &crate::objective::reference::ChannelReference, p_atm_pa: f64) {
    let a = &r.abscissa;
    let fit = &r.reference;
    let x_name = if a.log10 {
        format!("log10 {}", a.column)
    } else {
        a.column.clone()
    };
    let sigma = num(r.display_difference(fit.sigma(), p_atm_pa));
    let floor = if fit.sigma() > fit.sigma_residual() {
        " (resolution floor)"
    } else {
        ""
    };
    let range = |lo: f64, hi: f64| {
        let (u, v) = (a.display(lo, p_atm_pa), a.display(hi, p_atm_pa));
        format!("{} .. {} {}", num(u), num(v), a.unit.suffix())
    };
    let pieces = fit.pieces();
    let (lo, hi) = fit.range();
    let degree = if pieces.len() == 1 {
        format!("degree {}", pieces[0].degree)
    } else {
        format!("{} pieces", pieces.len())
    };
    say!(
        "    reference {} vs {x_name}: {degree}, R² {:.5}, σ {sigma} {}{floor}, {} points, {}",
        r.column,
        fit.r_squared(),
        r.unit.suffix(),
        fit.n_fitted(),
        range(lo, hi)
    );
    if pieces.len() > 1 {
        for (k, p) in pieces.iter().enumerate() {
            say!(
                "      piece {}: degree {}, {} points, {}",
                k + 1,
                p.degree,
                p.n,
                range(p.x_min, p.x_max)
            );
        }
    }
}

/// A number for people: fixed point in the usual range, scientific otherwise.
fn num(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e6) {
        format!("{v:.4e}")
    } else {
        format!("{v:.5}")
    }
}

/// Parameters for a dataset: the fit file's, or else the rig's nominal motor.
pub fn params_for(
    ds: &Dataset,
    fit: Option<&FitFile>,
) -> Result<(MotorParams, EffectSet), Failure> {
    if let Some(f) = fit {
        return Ok((f.params.clone(), f.effects.clone()));
    }
    Ok((ds.nominal_params()?, EffectSet::empty()))
}

/// One column of a simulated recording: the recording's column name (with its unit) and
/// the values in that unit; `raw` holds an input column's cells exactly as recorded.
#[derive(Debug, Clone)]
pub struct SimulatedColumn {
    /// The recording's column name, unit included.
    pub name: String,
    /// Values in the column's unit (an input's as recorded, NaN for an empty cell).
    pub values: Vec<f64>,
    /// An input column's cells as recorded (`None` for a simulated output).
    pub raw: Option<crate::data::dataset::Cells>,
}

/// A recording simulated as `vanefit simulate` writes it: the inputs as recorded, then
/// every simulated output that the recording has, in the recording's units, same rows.
#[derive(Debug, Clone)]
pub struct SimulatedTable {
    /// The recording's file name.
    pub file: String,
    /// Inputs first, then outputs.
    pub columns: Vec<SimulatedColumn>,
}

/// The motor of a dataset under an optional fit file (its parameters, effects and
/// discovered terms; without one the rig's nominal motor).
pub fn motor_for(ds: &Dataset, fit: Option<&FitFile>) -> Result<Motor, Failure> {
    let (p, effects) = params_for(ds, fit)?;
    let extra = fit.map(|f| f.extra.clone()).unwrap_or_default();
    Ok(Motor::new(p, effects).with_extra(&extra))
}

/// Every experiment of `ds` simulated with `motor` (the tables `vanefit simulate` writes).
pub fn simulated_tables(ds: &Dataset, motor: &Motor) -> Result<Vec<SimulatedTable>, Failure> {
    let solver = DefaultSolver::default();
    let mut out = Vec::new();
    for data in &ds.experiments {
        let sim = Experiment::new(data, ds.p_atm_pa)?.simulate(motor, &solver)?;
        let rec = &data.recording;
        let inputs: &[Quantity] = match data.kind {
            Kind::Datasheet | Kind::Catalogue => {
                &[Quantity::Time, Quantity::Speed, Quantity::PPort1]
            }
            _ => &[Quantity::Time, Quantity::PPort1, Quantity::CPort2],
        };
        let mut columns: Vec<SimulatedColumn> = rec
            .columns
            .iter()
            .filter(|c| inputs.contains(&c.quantity))
            .map(|c| SimulatedColumn {
                name: c.name.clone(),
                values: c
                    .raw
                    .iter()
                    .map(|v| v.trim().parse().unwrap_or(f64::NAN))
                    .collect(),
                raw: Some(c.raw.clone()),
            })
            .collect();
        for c in rec.columns.iter().filter(|c| !inputs.contains(&c.quantity)) {
            if let Some(v) = sim.channel(c.quantity) {
                columns.push(SimulatedColumn {
                    name: c.name.clone(),
                    values: v.iter().map(|x| c.unit.from_si(*x, ds.p_atm_pa)).collect(),
                    raw: None,
                });
            }
        }
        out.push(SimulatedTable {
            file: data.file.clone(),
            columns,
        });
    }
    Ok(out)
}

fn simulate(dir: &Path, params: Option<&Path>, out: &Path) -> Result<(), Failure> {
    let ds = Dataset::load(dir)?;
    let fit = params.map(FitFile::read).transpose()?;
    let motor = motor_for(&ds, fit.as_ref())?;
    let _lock = crate::io::out::prepare_dir(out)?;
    for table in simulated_tables(&ds, &motor)? {
        let header: Vec<&str> = table.columns.iter().map(|c| c.name.as_str()).collect();
        let mut text = header.join(",") + "\n";
        // Inputs as recorded, outputs formatted row by row (not gathered first: a column of
        // cells holds at most 4 GiB of text, and the outputs need not be held twice).
        let rows = table.columns.first().map_or(0, |c| c.values.len());
        for r in 0..rows {
            let row: Vec<String> = table
                .columns
                .iter()
                .map(|c| match &c.raw {
                    Some(raw) => raw[r].to_string(),
                    None => format!("{:.6e}", c.values[r]),
                })
                .collect();
            text.push_str(&row.join(","));
            text.push('\n');
        }
        let path = out.join(&table.file);
        crate::io::write_atomic(&path, text.as_bytes())
            .map_err(|e| Failure(format!("{}: {e}", path.display())))?;
        say!("wrote {}", path.display());
    }
    Ok(())
}

/// `vanefit synth --catalogue`: catalogue pages of the motor at `pressures` (bar(g)).
fn synth_catalogue(
    out: &Path,
    params: Option<&Path>,
    effects: Option<&str>,
    pressures: &[f64],
) -> Result<(), Failure> {
    if let Some(p) = pressures
        .iter()
        .find(|p| !(p.is_finite() && **p > 0.0 && **p < 40.0))
    {
        return Err(Failure(format!(
            "--pressures: {p} is not a supply pressure in bar(g) (0 to 40)"
        )));
    }
    let (motor, truth) = synth_motor(out, params, effects)?;
    let _lock = crate::io::out::prepare_dir(out)?;
    let plan = crate::data::synth_catalogue::CataloguePlan {
        pressures_bar_g: pressures.to_vec(),
        ..Default::default()
    };
    let rows = crate::data::synth_catalogue::write_catalogue(out, &motor, &plan, "no noise")?;
    truth
        .write(&out.join("truth.json"))
        .map_err(|e| Failure(format!("{}: {e}", out.display())))?;
    say!(
        "wrote catalogue {} ({} page(s), truth in truth.json)",
        out.display(),
        rows.len()
    );
    Ok(())
}

/// The motor of `synth` (from a fit file or the default, effects overridden) and its truth
/// file.
fn synth_motor(
    out: &Path,
    params: Option<&Path>,
    effects: Option<&str>,
) -> Result<(Motor, FitFile), Failure> {
    let fit = params.map(FitFile::read).transpose()?;
    let (p, mut fx) = match &fit {
        Some(f) => (f.params.clone(), f.effects.clone()),
        None => (MotorParams::default(), EffectSet::empty()),
    };
    if let Some(list) = effects {
        fx = EffectSet::parse_list(list).map_err(|m| Failure(format!("--effects: {m}")))?;
    }
    let extra = fit.as_ref().map(|f| f.extra.clone()).unwrap_or_default();
    let motor = Motor::new(p, fx.clone()).with_extra(&extra);
    let mut truth = FitFile::from_params(
        &out.file_name().unwrap_or_default().to_string_lossy(),
        motor.params.clone(),
        fx,
    );
    truth.extra = extra;
    Ok((motor, truth))
}

fn synth(
    out: &Path,
    params: Option<&Path>,
    effects: Option<&str>,
    noise: f64,
    seed: u64,
) -> Result<(), Failure> {
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(Failure(format!("--noise {noise}: must be a number >= 0")));
    }
    // Discovered terms of the fit file act in the synthetic motor as in `simulate`.
    let (motor, truth) = synth_motor(out, params, effects)?;
    let _lock = crate::io::out::prepare_dir(out)?;
    let plan = SynthPlan::default();
    let experiments = synthesize(
        &motor,
        &DefaultSolver::default(),
        &plan,
        &SensorNoise::typical().scaled(noise),
        seed,
    )?;
    let description = format!("seed {seed}, noise x{noise}.");
    write_dataset(
        out,
        &experiments,
        &plan,
        &motor,
        &motor.effects,
        &description,
    )?;
    truth
        .write(&out.join("truth.json"))
        .map_err(|e| Failure(format!("{}: {e}", out.display())))?;
    say!(
        "wrote dataset {} ({} experiments, truth in truth.json)",
        out.display(),
        experiments.len()
    );
    Ok(())
}
