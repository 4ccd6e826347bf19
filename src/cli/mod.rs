//! Command line (docs/cli.md). Exit status: 0 success, 1 bad input or failed work, 2 bad usage
//! (clap reports usage errors with status 2 itself).
//!
//! Part of the `vanefit` binary, not of the library: it parses the command line, converts
//! it to the library's typed options, calls the task and prints what it did.

/// `println!` that survives a closed stdout (`vanefit::io::say_line`).
macro_rules! say {
    () => {
        vanefit::io::say_line(format_args!(""))
    };
    ($($arg:tt)*) => {
        vanefit::io::say_line(format_args!($($arg)*))
    };
}

pub(crate) mod batch;
pub(crate) mod catalogue;
pub(crate) mod control;
pub(crate) mod diagnose;
pub(crate) mod export;
pub(crate) mod fit;
pub(crate) mod plan;
pub(crate) mod predict;

use clap::{Parser, Subcommand};
use std::path::{Path, PathBuf};
use vanefit::control::ControlError;
use vanefit::data::FitFile;
use vanefit::data::{Dataset, Kind};
use vanefit::model::EffectSet;
use vanefit::task::{motor_for, simulated_tables, write_table};
use vanefit::task::{synth_motor, write_synthetic, SynthOptions};
use vanefit::task::{ExportError, FitError, Opt, OptionError, PredictTaskError};

#[derive(Parser, Debug)]
#[command(
    name = "vanefit",
    version,
    about = "Estimate pneumatic vane motor parameters and find missing physics"
)]
/// The parsed command line.
pub(crate) struct Cli {
    #[command(subcommand)]
    /// The command to run.
    pub(crate) command: Command,
}

#[derive(Subcommand, Debug)]
/// The commands (docs/cli.md, "Synopsis").
pub(crate) enum Command {
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
        #[arg(
            long,
            value_parser = crate::cli::effects_arg,
            help = effects_help("Effects to switch on, overriding the fit file's")
        )]
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
    /// Find the physics the model leaves out: locate, explain, model, refit.
    Diagnose(crate::cli::diagnose::DiagnoseArgs),
    /// Speed-control studies (paper section 5): throttling, frequency response, closed loop.
    Control(crate::cli::control::ControlArgs),
    /// Predict the fitted motor at other supply pressures or with an extra nozzle:
    /// catalogue figures, correction factors and curves with 95% bands.
    #[command(allow_negative_numbers = true)]
    Predict(crate::cli::predict::PredictArgs),
    /// Which measurement next: candidate measurements ranked by how much they are expected
    /// to shrink the 95% bands at the given operating points, per hour of rig time.
    #[command(allow_negative_numbers = true)]
    Plan(crate::cli::plan::PlanArgs),
    /// Export a fit as a PEtab v1 problem: parameter, observable, measurement and condition
    /// tables, an SBML document declaring the model's symbols, and the problem YAML.
    ExportPetab(crate::cli::export::ExportPetabArgs),
    /// Export a fit as an FMU (FMI 2.0, model exchange and co-simulation) for system
    /// simulators: OpenModelica, Dymola, Simulink, FMPy.
    ExportFmu(crate::cli::export::ExportFmuArgs),
    /// Run a manifest's fleet of datasets (fit, diagnose, predict) in resumable shards,
    /// here or on Slurm.
    Batch(crate::cli::batch::BatchArgs),
    /// Merge a batch folder into summary.csv, summary.md and fleet.svg.
    Merge(crate::cli::batch::MergeArgs),
}

/// Options every computing command that starts from random points takes (`fit`,
/// `diagnose`): the seed of the start designs and the worker threads. Results depend on the
/// seed, never on the thread count.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct RunArgs {
    /// Seed of the start designs; a seed gives the same result whatever the thread count.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Worker threads (default: one per core).
    #[arg(long, value_parser = crate::cli::at_least_one)]
    pub(crate) threads: Option<usize>,
}

/// A failure to report: message for stderr, exit status 1.
#[derive(Debug)]
pub(crate) struct Failure(pub String);

impl<E: std::error::Error> From<E> for Failure {
    /// The error's message as it is. Errors that name options are converted where they
    /// arise, naming them by their flags ([`Failure::option`], [`Failure::control`] and
    /// the like).
    fn from(e: E) -> Self {
        Failure(e.to_string())
    }
}

impl Failure {
    /// A bad option of a task, named by its flag.
    pub(crate) fn option(e: OptionError) -> Self {
        Failure(e.message_with(&flag))
    }

    /// A failed fit, a bad option named by its flag.
    pub(crate) fn fit(e: FitError) -> Self {
        match e {
            FitError::Option(o) => Self::option(o),
            e => e.into(),
        }
    }

    /// A failed prediction, the options it names named by their flags.
    pub(crate) fn predict(e: PredictTaskError) -> Self {
        Failure(e.message_with(&flag))
    }

    /// A failed export, the option it names named by its flag.
    pub(crate) fn export(e: ExportError) -> Self {
        Failure(e.message_with(&flag))
    }

    /// A failed control study, the options it names named by their flags
    /// (`cli::control::flag`).
    pub(crate) fn control(e: ControlError) -> Self {
        Failure(e.message_with(&crate::cli::control::flag))
    }
}

/// The flag that sets a task's option ([`Opt::flag`]).
pub(crate) fn flag(o: Opt) -> &'static str {
    o.flag()
}

/// Clap value parser of `--effects`: the list as given once every id in it is known, so an
/// unknown id is bad usage (exit status 2, reported by clap with the known ids) rather than
/// a failed run.
pub(crate) fn effects_arg(list: &str) -> Result<String, vanefit::model::UnknownEffect> {
    EffectSet::parse_list(list).map(|_| list.to_string())
}

/// The help of an `--effects` option: `what`, then the ids of the effect catalog (so that
/// `--help` lists every effect that can be switched on).
pub(crate) fn effects_help(what: &str) -> String {
    let ids: Vec<&str> = vanefit::Effect::ALL.iter().map(|e| e.id()).collect();
    format!("{what}: comma-separated ids of {}", ids.join(", "))
}

/// A count option given as 0 or not as a whole number.
#[derive(Debug, thiserror::Error)]
#[error("'{0}' is not a whole number of at least 1")]
pub(crate) struct CountError(String);

/// Clap value parser of a count that must be at least 1 (`--starts`, `--threads`): 0 is bad
/// usage, exit status 2.
pub(crate) fn at_least_one(given: &str) -> Result<usize, CountError> {
    match given.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(CountError(given.to_string())),
    }
}

/// Runs a parsed command.
pub(crate) fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Check { dataset } => check(&dataset),
        Command::Fit(args) => crate::cli::fit::run(&args),
        Command::Simulate {
            dataset,
            params,
            out,
        } => simulate(&dataset, params.as_deref(), &out),
        Command::Synth {
            out_dataset,
            params,
            effects,
            noise,
            seed,
            catalogue,
            pressures,
        } => {
            let options = SynthOptions {
                effects: effects.as_deref().map(EffectSet::parse_list).transpose()?,
                noise,
                seed,
                catalogue,
                pressures_bar_g: pressures,
            };
            synth(&out_dataset, params.as_deref(), &options)
        }
        Command::Control(args) => crate::cli::control::run(args),
        Command::Diagnose(args) => crate::cli::diagnose::run(&args),
        Command::Predict(args) => crate::cli::predict::run(&args),
        Command::Plan(args) => crate::cli::plan::run(&args),
        Command::ExportPetab(args) => crate::cli::export::run(&args),
        Command::ExportFmu(args) => crate::cli::export::run_fmu(&args),
        Command::Batch(args) => crate::cli::batch::run(&args),
        Command::Merge(args) => crate::cli::batch::merge(&args),
    }
}

fn check(dir: &Path) -> Result<(), Failure> {
    let mut ds = Dataset::load(dir)?;
    // From here `check` prints values, not cells as written (except a catalogue's few
    // points): a recording's text, as large again as its values, is freed before the
    // references are fitted, when memory peaks (a 100 MB recording is checked in 500 MB).
    for ex in ds
        .experiments
        .iter_mut()
        .filter(|ex| ex.kind != Kind::Catalogue)
    {
        for c in &mut ex.recording.columns {
            c.raw = vanefit::data::Cells::new();
        }
    }
    // Every reference is fitted before anything is printed: a channel that cannot give one
    // refuses the dataset like any other bad input.
    let references = ds
        .experiments
        .iter()
        .map(|ex| {
            vanefit::objective::experiment_references(
                ex,
                &vanefit::objective::ReferenceOptions::default(),
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
    if let Ok(lines) = ds.motor.assumed() {
        say!("  the motor a fit will use ([motor] in rig.toml):");
        for l in lines {
            say!("    {l}");
        }
    }
    if let Some(g) = ds.gear() {
        say!(
            "    {}{}",
            g.describe(),
            if g.efficiency_printed {
                ""
            } else {
                "  ASSUMED (gear_efficiency not given)"
            }
        );
        say!("    the pages' figures are the gearbox's OUTPUT shaft's; they are fitted at the motor shaft (speed × G, torque ÷ η·G, power ÷ η)");
    }
    // A page without its displacement: the size a fit starts from, estimated from the page.
    if let Ok(Some(e)) = vanefit::task::page_displacement_of(&ds) {
        say!("    {}", vanefit::task::displacement_first_line(&e));
    }
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
                "    {:<20} {:>13} .. {:<13} [{}]{}",
                c.name,
                num(to(lo)),
                num(to(hi)),
                c.unit.symbol(),
                if ds.gear().is_some() {
                    " at the motor shaft"
                } else {
                    ""
                }
            );
        }
        catalogue::print(ex, ds.p_atm_pa);
        print_page_warnings(&ds, ex);
        for r in refs {
            print_reference(r, ds.p_atm_pa);
        }
    }
    Ok(())
}

/// One reference response for `check`: channel, degree, R², σ in the column's unit, valid
/// range in the abscissa column's unit, and its pieces when the data jump.
fn print_reference(r: &vanefit::objective::ChannelReference, p_atm_pa: f64) {
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
        format!("{} .. {} {}", num(u), num(v), a.unit.symbol())
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
        r.unit.symbol(),
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

fn simulate(dir: &Path, params: Option<&Path>, out: &Path) -> Result<(), Failure> {
    let ds = Dataset::load(dir)?;
    let fit = params.map(FitFile::read).transpose()?;
    let motor = motor_for(&ds, fit.as_ref())?;
    let _lock = vanefit::io::prepare_dir(out)?;
    for table in simulated_tables(&ds, &motor)? {
        let path = write_table(&table, out)?;
        say!("wrote {}", path.display());
    }
    Ok(())
}

/// `vanefit synth`: a synthetic dataset (rig recordings, or with `--catalogue` catalogue
/// pages at `--pressures`, bar(g)) and its truth file.
fn synth(out: &Path, params: Option<&Path>, options: &SynthOptions) -> Result<(), Failure> {
    let settings = options.check().map_err(Failure::option)?;
    let fit = params.map(FitFile::read).transpose()?;
    let name = out.file_name().unwrap_or_default().to_string_lossy();
    let (motor, truth) = synth_motor(&name, fit.as_ref(), &settings);
    let _lock = vanefit::io::prepare_dir(out)?;
    let written = write_synthetic(out, &motor, &truth, &settings)?;
    if written.catalogue {
        say!(
            "wrote catalogue {} ({} page(s), truth in truth.json)",
            out.display(),
            written.count
        );
    } else {
        say!(
            "wrote dataset {} ({} experiments, truth in truth.json)",
            out.display(),
            written.count
        );
    }
    Ok(())
}

/// The warnings of a catalogue page (maker rules, figures against the page's own curves),
/// each at its rig.toml line, on stderr (`check` and `fit`).
pub(crate) fn print_page_warnings(ds: &Dataset, ex: &vanefit::sim::ExperimentData) {
    for w in vanefit::data::page_warnings(ex) {
        let at = w.line.map_or(String::new(), |l| format!(":{l}"));
        eprintln!(
            "warning: {}{at} (key '{}'): {}",
            ds.dir.join("rig.toml").display(),
            w.key,
            w.message
        );
    }
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::{CommandFactory, Parser};

    /// Every option of the control studies has a flag of a control study (none is shown as
    /// its field), and a bad option's message names its options by their flags.
    #[test]
    fn every_control_option_has_a_flag() {
        use vanefit::control::{ControlError, ControlOpt, SettingsError};
        let mut cmd = Cli::command();
        let control = cmd.find_subcommand_mut("control").unwrap();
        let longs: Vec<String> = control
            .get_subcommands()
            .flat_map(|s| s.get_arguments())
            .filter_map(|a| a.get_long())
            .map(|l| format!("--{l}"))
            .collect();
        for o in ControlOpt::ALL {
            let f = crate::cli::control::flag(*o);
            assert!(longs.iter().any(|l| l == f), "{o}: {f}");
        }
        let e = ControlError::Settings(SettingsError::StepAfterEnd {
            option: ControlOpt::StepTStep,
            value: 9.0,
            end: ControlOpt::StepDuration,
        });
        assert_eq!(
            e.to_string(),
            "StepOptions.t_step_s 9: must be before StepOptions.duration_s"
        );
        assert_eq!(
            super::Failure::control(e).0,
            "--t-step-s 9: must be before --duration-s"
        );
    }

    /// Every option of the tasks has a flag of its own (none is shown as its field), and
    /// a bad option's message names it by its flag.
    #[test]
    fn every_task_option_has_a_flag() {
        for o in vanefit::task::Opt::ALL {
            let f = super::flag(*o);
            assert!(f.starts_with("--") && f != o.field(), "{o}: {f}");
        }
        let e = vanefit::task::OptionError::pair(
            vanefit::task::Opt::PredictInletNozzle,
            vanefit::task::Opt::PredictOutletNozzle,
            ": give one extra nozzle, not both",
        );
        assert_eq!(
            super::Failure::option(e).0,
            "--inlet-nozzle and --outlet-nozzle: give one extra nozzle, not both"
        );
    }

    /// The help of a subcommand, as `vanefit <path> --help` prints it.
    fn help(path: &[&str]) -> String {
        let mut cmd = Cli::command();
        let mut sub = &mut cmd;
        for name in path {
            sub = sub.find_subcommand_mut(name).unwrap();
        }
        sub.render_long_help().to_string()
    }

    /// Every enumerated option refuses an unknown value as bad usage (exit status 2), before
    /// anything runs: `--unit`, `--uncertainty`, `--anti-windup`, `--effects`, `--shard`.
    #[test]
    fn unknown_choices_are_usage_errors() {
        let cases: [&[&str]; 5] = [
            &["predict", "fit.json", "--unit", "bar"],
            &["fit", "d", "--out", "f.json", "--uncertainty", "exact"],
            &["control", "step", "--anti-windup", "sometimes"],
            &["synth", "d", "--effects", "warp"],
            &["batch", "m.toml", "--out", "b", "--shard", "3/2"],
        ];
        for args in cases {
            let all: Vec<&str> = ["vanefit"].iter().chain(args).copied().collect();
            let e = Cli::try_parse_from(all).unwrap_err();
            assert_eq!(e.exit_code(), 2, "{args:?}: {e}");
        }
        assert!(help(&["predict"]).contains("bar_g"));
    }

    /// No help text cites a document the user does not have (the specification, an issue):
    /// it says the thing, and docs/ holds the references.
    #[test]
    fn help_cites_no_spec_or_issue() {
        fn walk(cmd: &mut clap::Command, path: &str, bad: &mut Vec<String>) {
            let text = cmd.render_long_help().to_string();
            for needle in ["SPEC", "issue "] {
                if text.contains(needle) {
                    bad.push(format!("{path}: {needle}"));
                }
            }
            for sub in cmd.get_subcommands_mut() {
                let name = format!("{path} {}", sub.get_name());
                walk(sub, &name, bad);
            }
        }
        let mut bad = Vec::new();
        walk(&mut Cli::command(), "vanefit", &mut bad);
        assert!(bad.is_empty(), "{bad:?}");
    }

    /// Every `--effects` help lists every effect of the catalog by id.
    #[test]
    fn effects_help_lists_every_effect_id() {
        for path in [&["fit"][..], &["synth"], &["control", "step"]] {
            let text = help(path);
            for e in vanefit::Effect::ALL {
                assert!(text.contains(e.id()), "{path:?} --help lacks {}", e.id());
            }
        }
    }
}
