//! Everything a typical program needs, in one `use vanefit::prelude::*;`: the tasks, their
//! options and settings, their results and errors, the observers, and the model types the
//! results are made of.

pub use crate::batch::{BatchOptions, BatchSettings, Manifest};
pub use crate::data::dataset::Dataset;
pub use crate::data::fitfile::FitFile;
pub use crate::diagnose::{DiagnoseObserver, Diagnosis};
pub use crate::estimate::fit::UncertaintyMethod;
pub use crate::estimate::multistart::Silent;
pub use crate::estimate::RunObserver;
pub use crate::model::effects::{Effect, EffectSet};
pub use crate::model::motor::Motor;
pub use crate::model::params::MotorParams;
pub use crate::predict::Prediction;
pub use crate::task::control::{ControlStudy, Study, StudyResult};
pub use crate::task::diagnose::{DiagnoseOptions, DiagnoseSettings, DiagnoseTaskError, Effort};
pub use crate::task::fit::{Fit, FitError, FitObserver, FitOptions, FitSettings, ParamRange};
pub use crate::task::predict::{PredictOptions, PredictSettings, PredictTaskError};
pub use crate::task::synth::{SynthOptions, SynthSettings};
pub use crate::task::OptionError;
pub use crate::units::Unit;
