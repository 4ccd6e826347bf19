//! The motor model (docs/model.md; paper §2): geometry, polytropic cycle, nozzles,
//! friction, the missing-physics catalog, parameters, the motor as parameters → state
//! derivatives, and the analytic Jacobian of the base model.
//!
//! The parameters' files import one way: `params` (the registry assembled from the base
//! model's parameters and the effects', and a motor's values) imports `effects/` (the
//! catalog, each effect with its own parameters) and `spec` (what a parameter and an
//! effect handle are, and the base model's parameter table); `effects/` imports `spec`.

pub(crate) mod effects;
pub(crate) mod extra;
pub(crate) mod friction;
pub(crate) mod gear;
pub(crate) mod geometry;
pub(crate) mod jacobian;
pub(crate) mod motor;
pub(crate) mod nozzle;
pub(crate) mod params;
pub(crate) mod spec;
#[cfg(test)]
pub(crate) mod testing;
pub(crate) mod thermo;

pub use effects::{
    CatalogEffect, Category, Effect, EffectSet, ShowsIn, SupplyValve, Term, UnknownEffect,
};
pub use gear::Gear;
pub use geometry::{PortTiming, VaneGeometry};
pub use jacobian::BoundaryRate;
pub use motor::{
    idx, Balance, BalanceId, Boundary, Chamber, ExtraTerm, LeakPath, Load, Motor, PressureFactor,
    SpeedFactor, State, ThrottleSide, N_STATES,
};
pub use nozzle::{psi, Nozzle, R_LAMINAR};
pub use params::{
    page_prior_extra, spec, Estimated, MotorParams, OffValue, ParamError, ParamId, ParamSpec,
    ParamValues, DEFAULT_ESTIMATED, DEFAULT_ESTIMATED_IDS, PARAMS,
};
pub use thermo::{Cycle, DisplacementFlows};
