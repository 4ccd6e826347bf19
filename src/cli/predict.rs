//! `vanefit predict <fit.json>` (docs/cli.md, "predict"): what the fitted motor does at other
//! supply pressures or with an extra nozzle, with 95 % bands; the work is
//! `vanefit::task::predict` (shared with `batch`), this parses and prints the tables.
//!
//! Every bad input (fit file, pressure list, nozzle) is refused with a message that names
//! the file or option, exit status 1, before anything is written; an unknown `--unit` is
//! bad usage (exit status 2).

use crate::cli::Failure;
use clap::builder::PossibleValuesParser;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;
use vanefit::data::FitFile;
use vanefit::predict::{BandChoice, PosteriorData, SamplingOptions};
use vanefit::report::predict::{notes, tables_markdown};
use vanefit::task::{
    fit_atmosphere_pa, predict_located, pressure_unit, source_name, write_prediction,
    PredictOptions,
};

/// Progress of the posterior samples on stderr: a line per tenth of each stage.
#[derive(Default)]
pub(crate) struct Progress {
    t0: std::sync::OnceLock<Instant>,
    last: std::sync::Mutex<(String, usize)>,
}

impl Progress {
    pub(crate) fn tell(&self, what: &str, done: usize, total: usize) {
        let t0 = self.t0.get_or_init(Instant::now);
        let tenth = (10 * done) / total.max(1);
        let mut last = self.last.lock().unwrap_or_else(|p| p.into_inner());
        if last.0 != what || tenth > last.1 {
            *last = (what.to_string(), tenth);
            eprintln!(
                "{what}: {done}/{total} ({:.1} s)",
                t0.elapsed().as_secs_f64()
            );
        }
    }
}
use vanefit::task::{Opt, OptionError};

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
    /// p_port1 columns.
    #[arg(long, default_value = "bar_g", value_parser = PossibleValuesParser::new(pressure_suffixes()))]
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
    #[arg(long, default_value_t = vanefit::predict::DEFAULT_CURVE_POINTS)]
    pub(crate) curve_points: usize,
    /// Take the parameters a fit could estimate but held fixed or could not identify as
    /// uncertain within this factor (95 %), so that the bands include them (e.g. 1.5 for a
    /// catalogue fit's defaults).
    #[arg(long)]
    pub(crate) fixed_spread: Option<f64>,
    /// How the 95 % bands are made: `delta` (linearised about the estimate with the fit's
    /// covariance; instant), `samples` (percentiles of the figures of posterior samples of
    /// the fit's dataset, converged or not) or `auto`: samples when the dataset is at hand
    /// and they converged (every R̂ < 1.01, ESS ≥ 400), else delta; the output says which
    /// and why.
    #[arg(long, default_value = "auto", value_parser = ["auto", "delta", "samples"])]
    pub(crate) bands: String,
    /// The dataset folder the fit was made from, for the posterior samples (default: the
    /// fit file's dataset_path, or for older fit files measurements/<dataset> beside the
    /// fit file's folder or in the current folder).
    #[arg(long)]
    pub(crate) data: Option<PathBuf>,
    /// Chains (≥ 2) or walkers of the posterior sampler (the ensemble needs an even number
    /// ≥ 2 × (estimated parameters + 1); default 8 chains, or max(16, 4 × estimated
    /// parameters) walkers).
    #[arg(long)]
    pub(crate) walkers: Option<usize>,
    /// Kept steps per walker of the posterior sampler.
    #[arg(long, default_value_t = vanefit::predict::DEFAULT_STEPS)]
    pub(crate) steps: usize,
    /// Steps per walker run first and discarded.
    #[arg(long, default_value_t = vanefit::predict::DEFAULT_BURN_IN)]
    pub(crate) burn_in: usize,
    /// Posterior samples propagated through the figures.
    #[arg(long, default_value_t = vanefit::predict::DEFAULT_DRAWS)]
    pub(crate) draws: usize,
    /// Seed of the posterior sampler; a seed gives the same bands whatever the thread count.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Output folder (created).
    #[arg(long, default_value = "predict")]
    pub(crate) out: PathBuf,
}

/// The column suffixes of the pressure units, the values `--unit` accepts.
pub(crate) fn pressure_suffixes() -> Vec<&'static str> {
    vanefit::task::pressure_units()
        .iter()
        .map(|u| u.suffix())
        .collect()
}

/// `--pressures`: a comma-separated list of numbers, at least one.
pub(crate) fn pressure_list(list: &str) -> Result<Vec<f64>, OptionError> {
    let fail = |why: String| OptionError::of(Opt::PredictPressures, format!(" '{list}': {why}"));
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
            unit: pressure_unit(Opt::PredictUnit, &self.unit)?,
            pressures: self.pressures.as_deref().map(pressure_list).transpose()?,
            reference: self.reference,
            inlet_nozzle_m3_s_pa: self.inlet_nozzle,
            outlet_nozzle_m3_s_pa: self.outlet_nozzle,
            speed_grid_rpm: self.speed_grid_rpm,
            curve_points: self.curve_points,
            fixed_spread: self.fixed_spread,
            bands: match self.bands.as_str() {
                "delta" => BandChoice::Delta,
                "samples" => BandChoice::Samples,
                _ => BandChoice::Auto,
            },
            data: self.data.clone(),
            sampling: SamplingOptions {
                walkers: self.walkers,
                steps: self.steps,
                burn_in: self.burn_in,
                draws: self.draws,
                seed: self.seed,
                // The chains are checkpointed beside the outputs (docs/cli.md, "predict").
                checkpoint: Some(self.out.join("samples.checkpoint")),
                ..SamplingOptions::default()
            },
        })
    }
}

/// Runs `vanefit predict`.
pub(crate) fn run(args: &PredictArgs) -> Result<(), Failure> {
    let t0 = Instant::now();
    vanefit::io::check_dir(&args.out).map_err(|e| Failure(format!("--out {e}")))?;
    let fit = FitFile::read(&args.fit)?;
    let settings = args
        .options()
        .and_then(|o| o.check(fit_atmosphere_pa(&fit)))
        .map_err(Failure::option)?;
    for warning in settings.far_extrapolations(&fit) {
        eprintln!("WARNING: {warning}");
    }
    let bar = Progress::default();
    let prediction = predict_located(Some(&args.fit), &fit, &settings, &|what, done, total| {
        bar.tell(what, done, total)
    })
    .map_err(Failure::predict)?;
    let named = !(fit.dataset.is_empty() || fit.estimated.is_empty());
    if let (Some(PosteriorData::Missing(why)), true) = (&prediction.bands.data, named) {
        eprintln!(
            "WARNING: {why}; the bands are delta-method bands (give the dataset with --data)"
        );
    }
    let source = source_name(&args.fit, &fit);
    let written =
        write_prediction(&prediction, &settings, &source, &args.out).map_err(Failure::predict)?;
    let display = settings.display();
    say!("prediction from {source}");
    if let Some(PosteriorData::At(at)) = &prediction.bands.data {
        say!("posterior sampled on the {at}");
    }
    say!("{}\n", prediction.bands.statement());
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
