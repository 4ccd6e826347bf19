//! The reference experiments (docs/model.md, "Reference experiments") as first-class types:
//! each knows its inputs (from the rig and its recording) and simulates the channels that
//! were measured, one value per row.
//!
//! Every experiment kind lives in its own file and implements [`ExperimentKind`]: its id
//! (as rig.toml writes it), the inputs it reads from a recording and how they are checked,
//! the channels it measures, its abscissa, whether it is transient, and how it builds the
//! [`Drive`] that simulates it. Adding a kind is its file plus one line in the
//! `registry!` below (which also adds the [`Kind`] variant that rig.toml names).

use crate::model::motor::{Load, Motor};
use crate::numerics::ode::{SolveError, StiffSolver};
use crate::sim::recording::{ExperimentData, MissingColumn};
use crate::sim::steady::SteadyError;
use crate::units::Quantity;
use serde::Deserialize;
use std::fmt;
use std::sync::Arc;

mod transient;

/// Why a simulation failed. Every variant but [`SimError::FreeSpeed`] names its
/// experiment by its recording's file name as given in rig.toml.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// A channel the experiment needs is not in its recording.
    #[error("simulating {experiment}: {source}")]
    MissingColumn {
        /// Recording file name as given in rig.toml.
        experiment: String,
        /// The missing column.
        source: MissingColumn,
    },
    /// A catalogue without its supply pressure.
    #[error("simulating {experiment}: a catalogue needs its supply pressure")]
    CatalogueWithoutSupply {
        /// Recording file name as given in rig.toml.
        experiment: String,
    },
    /// A transient without a supply pressure (neither in rig.toml nor recorded).
    #[error("simulating {experiment}: no supply pressure")]
    NoSupply {
        /// Recording file name as given in rig.toml.
        experiment: String,
    },
    /// No steady state at a point of a steady sweep.
    #[error("simulating {experiment}: {source}")]
    Steady {
        /// Recording file name as given in rig.toml.
        experiment: String,
        /// The steady solver's error.
        source: SteadyError,
    },
    /// No steady state at a row of a recording (1-based).
    #[error("simulating {experiment}: row {row}: {source}")]
    SteadyRow {
        /// Recording file name as given in rig.toml.
        experiment: String,
        /// The row, counted from 1.
        row: usize,
        /// The steady solver's error.
        source: SteadyError,
    },
    /// No steady state to start a transient from.
    #[error("simulating {experiment}: initial state: {source}")]
    InitialState {
        /// Recording file name as given in rig.toml.
        experiment: String,
        /// The steady solver's error.
        source: SteadyError,
    },
    /// The integration of a transient failed.
    #[error("simulating {experiment}: {source}")]
    Solve {
        /// Recording file name as given in rig.toml.
        experiment: String,
        /// The integrator's error.
        source: SolveError,
    },
    /// The simulation gives no values for a channel of the recording.
    #[error("simulating {experiment}: the simulation gives no {column}")]
    NoChannel {
        /// Recording file name as given in rig.toml.
        experiment: String,
        /// The recorded column's name.
        column: String,
    },
    /// A catalogue page prints its max power at a speed, and the model's power is not
    /// concave there (no maximum to place at that speed).
    #[error("simulating {experiment}: the model's power has no maximum near the printed speed at max power ({speed_rpm:.0} rpm)")]
    NoPowerPeak {
        /// Recording file name as given in rig.toml.
        experiment: String,
        /// The printed speed at max power, rpm.
        speed_rpm: f64,
    },
    /// No free-running speed (of a synthetic dataset's motor).
    #[error("simulating free speed: {0}")]
    FreeSpeed(#[source] SteadyError),
}

impl SimError {
    /// The recording file name of the experiment (as given in rig.toml); `free speed` for
    /// [`SimError::FreeSpeed`].
    pub fn experiment(&self) -> &str {
        match self {
            Self::MissingColumn { experiment, .. }
            | Self::CatalogueWithoutSupply { experiment }
            | Self::NoSupply { experiment }
            | Self::Steady { experiment, .. }
            | Self::SteadyRow { experiment, .. }
            | Self::InitialState { experiment, .. }
            | Self::Solve { experiment, .. }
            | Self::NoChannel { experiment, .. }
            | Self::NoPowerPeak { experiment, .. } => experiment,
            Self::FreeSpeed(_) => "free speed",
        }
    }
}

/// Simulated channels of one experiment, SI, one value per recorded row.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulated {
    /// Each channel with its values, SI, in the kind's channel order.
    pub outputs: Vec<(Quantity, Vec<f64>)>,
}

impl Simulated {
    /// The values of one channel (`None` if the kind does not simulate it).
    pub fn channel(&self, q: Quantity) -> Option<&[f64]> {
        self.outputs
            .iter()
            .find(|(k, _)| *k == q)
            .map(|(_, v)| v.as_slice())
    }
}

/// A check of a recording's inputs, run in order by the data layer (which words the
/// errors).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum InputCheck {
    /// The column must be present.
    Column(Quantity),
    /// The column must span at least this fraction of its largest magnitude.
    Spans(Quantity, f64),
    /// A supply pressure must be given: `p_supply_mpa` in rig.toml or a p_port1 column.
    Supply,
    /// Every value of the column must be > 0; `what` names it in the error.
    Positive(Quantity, &'static str),
}

/// The abscissa of an experiment kind's reference responses: a recorded column, possibly
/// on a log10 scale.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbscissaSpec {
    /// The quantity of the column.
    pub quantity: Quantity,
    /// The abscissa is log10 of the SI value.
    pub log10: bool,
}

/// What the simulation of one experiment needs besides its drive.
#[derive(Debug, Clone, Copy)]
pub struct Setting<'a> {
    /// Recording file name as given in rig.toml (for errors).
    pub file: &'a str,
    /// Load on the shaft.
    pub load: Load,
    /// Atmosphere, Pa.
    pub p_atm_pa: f64,
}

impl Setting<'_> {
    /// This experiment's failure to find a steady state (of a sweep).
    pub fn steady_failed(&self, source: SteadyError) -> SimError {
        SimError::Steady {
            experiment: self.file.to_string(),
            source,
        }
    }
}

/// How an experiment drives the motor, built from its recording: simulates every row.
pub trait Drive: fmt::Debug + Send + Sync {
    /// The abscissa of each recorded row, SI, as the reference responses use it (for
    /// transient experiments the smoothed input that drove the simulation).
    fn abscissa(&self) -> Vec<f64>;
    /// The measured channels simulated at every row.
    fn simulate(
        &self,
        setting: &Setting<'_>,
        motor: &Motor,
        solver: &dyn StiffSolver,
    ) -> Result<Simulated, SimError>;
}

/// An experiment kind (docs/model.md, "Reference experiments").
pub trait ExperimentKind: Sync {
    /// The id in rig.toml and reports.
    fn id(&self) -> &'static str;
    /// The inputs it reads from a recording (and rig.toml), as checks run in order.
    fn inputs(&self) -> &'static [InputCheck];
    /// The measured output channels, in the simulator's order.
    fn channels(&self) -> &'static [Quantity];
    /// The abscissa of its reference responses.
    fn abscissa(&self) -> AbscissaSpec;
    /// Whether it is a transient (time-driven) experiment.
    fn is_transient(&self) -> bool;
    /// Its drive, from a recording that passed the checks of [`ExperimentKind::inputs`].
    fn build(&self, data: &ExperimentData) -> Result<Arc<dyn Drive>, SimError>;
}

/// One line per kind: `file::Type;` declares the module `file` (which must define the unit
/// struct `Type` implementing [`ExperimentKind`]) and the variant `Kind::Type`, whose
/// snake_case name is the id in rig.toml.
macro_rules! registry {
    ($( $file:ident :: $ty:ident ; )*) => {
        $( pub mod $file; )*

        /// The experiment kinds (docs/model.md, "Reference experiments"; rig.toml `kind =
        /// "…"`).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Deserialize, PartialOrd, Ord)]
        #[serde(rename_all = "snake_case")]
        #[non_exhaustive]
        pub enum Kind {
            $(
                #[doc = concat!("The `", stringify!($file), "` experiment (rig.toml `kind`).")]
                $ty,
            )*
        }

        impl Kind {
            /// Every kind, in registry order.
            pub const ALL: &'static [Kind] = &[$( Kind::$ty, )*];

            /// The kind's definition.
            pub fn model(self) -> &'static dyn ExperimentKind {
                match self {
                    $( Kind::$ty => &$file::$ty, )*
                }
            }
        }
    };
}

registry! {
    datasheet::Datasheet;
    pressure_ramp::PressureRamp;
    outlet_throttle::OutletThrottle;
    catalogue::Catalogue;
}

impl Kind {
    /// The id in rig.toml and reports.
    pub fn id(self) -> &'static str {
        self.model().id()
    }

    /// The measured output channels of the kind, in the simulator's order.
    pub fn channels(self) -> &'static [Quantity] {
        self.model().channels()
    }

    /// Whether the kind is a transient (time-driven) experiment.
    pub(crate) fn is_transient(self) -> bool {
        self.model().is_transient()
    }
}

/// A reference experiment ready to simulate.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// The kind.
    pub kind: Kind,
    /// Recording file name as given in rig.toml.
    pub file: String,
    /// Load on the shaft.
    pub load: Load,
    /// Atmosphere, Pa.
    pub p_atm_pa: f64,
    drive: Arc<dyn Drive>,
}

impl Experiment {
    /// Builds the experiment's inputs from its recording (validated by `dataset`).
    pub fn new(data: &ExperimentData, p_atm_pa: f64) -> Result<Self, SimError> {
        Ok(Self {
            kind: data.kind,
            file: data.file.clone(),
            load: data.load,
            p_atm_pa,
            drive: data.kind.model().build(data)?,
        })
    }

    /// The abscissa of each recorded row, SI, as the reference responses use it: imposed
    /// speed (rad/s) for the datasheet, port-1 pressure (Pa) for the pressure ramp, log10 of
    /// the port-2 conductance (log10 m³/(s·Pa)) for the outlet throttle. For transient
    /// experiments it is the smoothed input that drove the simulation, not the noisy samples.
    pub fn abscissa(&self) -> Vec<f64> {
        self.drive.abscissa()
    }

    /// Simulates every row of the recording.
    pub fn simulate(&self, motor: &Motor, solver: &dyn StiffSolver) -> Result<Simulated, SimError> {
        let setting = Setting {
            file: &self.file,
            load: self.load,
            p_atm_pa: self.p_atm_pa,
        };
        self.drive.simulate(&setting, motor, solver)
    }
}

/// The error of a missing column while building an experiment from `data`.
fn missing(data: &ExperimentData) -> impl Fn(MissingColumn) -> SimError + '_ {
    |source: MissingColumn| SimError::MissingColumn {
        experiment: data.file.clone(),
        source,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_the_rig_file_names() {
        #[derive(Deserialize)]
        struct K {
            kind: Kind,
        }
        for k in Kind::ALL {
            let parsed: K = toml::from_str(&format!("kind = \"{}\"", k.id())).unwrap();
            assert_eq!(parsed.kind, *k);
        }
    }
}
