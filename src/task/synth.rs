//! `synth` as a task: a synthetic dataset (rig recordings with sensor noise, or catalogue
//! pages printed to 3 digits) written from a known motor, with its truth file.

use super::simulate::SimulateError;
use super::{Opt, OptionError};
use crate::data::fitfile::FitFile;
use crate::data::synth::{synthesize, write_dataset, SensorNoise, SynthPlan};
use crate::data::synth_catalogue::{write_catalogue, CataloguePlan};
use crate::model::effects::EffectSet;
use crate::model::motor::Motor;
use crate::model::params::MotorParams;
use crate::numerics::DefaultSolver;
use std::path::Path;

/// What a synthetic dataset is made of, as given (unchecked): see [`SynthOptions::check`].
#[derive(Debug, Clone, PartialEq)]
pub struct SynthOptions {
    /// Effects to switch on, overriding the fit file's (`None`: the fit file's).
    pub effects: Option<EffectSet>,
    /// Sensor noise as a multiple of a typical rig's (0 for none); rig recordings only.
    pub noise: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// Write catalogue pages (curves and key figures, 3 digits) instead of rig recordings.
    pub catalogue: bool,
    /// Supply pressures of the catalogue pages, bar(g); catalogue only.
    pub pressures_bar_g: Vec<f64>,
}

impl Default for SynthOptions {
    /// Rig recordings with a typical rig's noise, seed 1 (catalogue: one page at 6.3 bar(g)).
    fn default() -> Self {
        Self {
            effects: None,
            noise: 1.0,
            seed: 1,
            catalogue: false,
            pressures_bar_g: vec![6.3],
        }
    }
}

/// Checked [`SynthOptions`] (private fields: every value is usable).
#[derive(Debug, Clone, PartialEq)]
pub struct SynthSettings(SynthOptions);

impl SynthSettings {
    /// The effects that override the fit file's.
    pub fn effects(&self) -> Option<&EffectSet> {
        self.0.effects.as_ref()
    }
    /// Noise multiple (≥ 0).
    pub fn noise(&self) -> f64 {
        self.0.noise
    }
    /// Seed of the noise.
    pub fn seed(&self) -> u64 {
        self.0.seed
    }
    /// Catalogue pages instead of rig recordings.
    pub fn catalogue(&self) -> bool {
        self.0.catalogue
    }
    /// Supply pressures of the catalogue pages, bar(g), each in (0, 40).
    pub fn pressures_bar_g(&self) -> &[f64] {
        &self.0.pressures_bar_g
    }
}

impl SynthOptions {
    /// Checks the values that are used: the pages' pressures for a catalogue (each in
    /// (0, 40) bar(g)), the noise (≥ 0) for rig recordings.
    pub fn check(&self) -> Result<SynthSettings, OptionError> {
        if self.catalogue {
            if let Some(p) = self
                .pressures_bar_g
                .iter()
                .find(|p| !(p.is_finite() && **p > 0.0 && **p < 40.0))
            {
                return Err(OptionError::of(
                    Opt::SynthPressures,
                    format!(": {p} is not a supply pressure in bar(g) (0 to 40)"),
                ));
            }
        } else if !(self.noise.is_finite() && self.noise >= 0.0) {
            return Err(OptionError::of(
                Opt::SynthNoise,
                format!(" {}: must be a number >= 0", self.noise),
            ));
        }
        Ok(SynthSettings(self.clone()))
    }
}

/// The motor of a synthetic dataset named `name`: the fit file's (or the default motor),
/// its effects overridden by the settings', and its truth file (not yet written).
/// Discovered terms of the fit file act in the synthetic motor as in `simulate`.
pub fn synth_motor(
    name: &str,
    fit: Option<&FitFile>,
    settings: &SynthSettings,
) -> (Motor, FitFile) {
    let (p, mut fx) = match fit {
        Some(f) => (f.params.clone(), f.effects.clone()),
        None => (MotorParams::default(), EffectSet::empty()),
    };
    if let Some(e) = settings.effects() {
        fx = e.clone();
    }
    let extra = fit.map(|f| f.extra.clone()).unwrap_or_default();
    let motor = Motor::new(p, fx.clone()).with_extra(&extra);
    let mut truth = FitFile::from_params(name, motor.params().clone(), fx);
    truth.extra = extra;
    (motor, truth)
}

/// A synthetic dataset written.
#[derive(Debug, Clone, PartialEq)]
pub struct Synthesized {
    /// Experiments (rig recordings) or pages (catalogue) written.
    pub count: usize,
    /// Catalogue pages rather than rig recordings.
    pub catalogue: bool,
}

/// Writes the synthetic dataset of `motor` into the folder `out` (rig.toml, recordings or
/// catalogue pages) and its truth file `truth.json`.
pub fn write_synthetic(
    out: &Path,
    motor: &Motor,
    truth: &FitFile,
    settings: &SynthSettings,
) -> Result<Synthesized, SimulateError> {
    let count = if settings.catalogue() {
        let plan = CataloguePlan {
            pressures_bar_g: settings.pressures_bar_g().to_vec(),
            ..Default::default()
        };
        write_catalogue(out, motor, &plan, "no noise")?.len()
    } else {
        let v_disp_m3 = motor.params().v_disp();
        let plan = SynthPlan::for_motor(v_disp_m3);
        let (noise, seed) = (settings.noise(), settings.seed());
        let experiments = synthesize(
            motor,
            &DefaultSolver::default(),
            &plan,
            &SensorNoise::typical_for(v_disp_m3).scaled(noise),
            seed,
        )?;
        let description = format!("seed {seed}, noise x{noise}.");
        write_dataset(
            out,
            &experiments,
            &plan,
            motor,
            &motor.effects,
            &description,
        )?;
        experiments.len()
    };
    truth
        .write(&out.join("truth.json"))
        .map_err(|source| SimulateError::Write {
            path: out.to_path_buf(),
            source,
        })?;
    Ok(Synthesized {
        count,
        catalogue: settings.catalogue(),
    })
}
