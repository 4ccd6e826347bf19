//! The motor model (docs/model.md; paper §2): geometry, polytropic cycle, nozzles,
//! friction, the missing-physics catalog, parameters, the motor as parameters → state
//! derivatives, and the analytic Jacobian of the base model.

pub mod effects;
pub mod extra;
pub mod friction;
pub mod geometry;
pub mod jacobian;
pub mod motor;
pub mod nozzle;
pub mod params;
pub(crate) mod thermo;
