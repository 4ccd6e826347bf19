//! Numerical methods that know nothing of motors: stiff integration, the 4×4 LU behind it
//! and the steady-state Newton, and roots and minima of functions of one variable.

pub(crate) mod lu;
pub(crate) mod normal;
pub(crate) mod ode;
pub(crate) mod rodas;
pub(crate) mod scalar;

#[cfg(feature = "bdf")]
pub use ode::{BdfError, DiffsolBdf};
pub use ode::{Jacobian, Kinks, Rhs, Slopes, SolveError, State, StiffSolver, Tolerances};
pub use rodas::Rodas4;

/// The stiff solver every simulation uses unless it asks for another: Rodas4 (see
/// `rodas` for why, and `examples/solver_accuracy.rs` for the measurements behind it).
pub type DefaultSolver = rodas::Rodas4;

pub(crate) mod quasi_steady;
pub use quasi_steady::QuasiSteady;
