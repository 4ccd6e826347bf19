//! Everything a typical program needs, in one `use vanefit::prelude::*;`: the tasks, their
//! options and settings, their results and errors, the observers, and the model types the
//! results are made of.

pub use crate::batch::{BatchOptions, BatchSettings, Manifest};
pub use crate::data::{Dataset, FitFile};
pub use crate::diagnose::{DiagnoseObserver, Diagnosis};
pub use crate::estimate::{RunObserver, Silent, UncertaintyMethod};
pub use crate::model::{Effect, EffectSet, Motor, MotorParams};
pub use crate::predict::Prediction;
pub use crate::task::{
    ControlStudy, DiagnoseOptions, DiagnoseSettings, DiagnoseTaskError, Effort, Fit, FitError,
    FitObserver, FitOptions, FitSettings, Opt, OptionError, ParamRange, PredictOptions,
    PredictSettings, PredictTaskError, Study, StudyResult, SynthOptions, SynthSettings,
};
pub use crate::units::Unit;
