//! Numerical methods that know nothing of motors: stiff integration, the 4×4 LU behind it
//! and the steady-state Newton, and roots and minima of functions of one variable.

pub mod lu;
pub mod normal;
pub mod ode;
pub mod rodas;
pub(crate) mod scalar;

/// The stiff solver every simulation uses unless it asks for another: Rodas4 (see
/// [`rodas`] for why, and `examples/solver_accuracy.rs` for the measurements behind it).
pub type DefaultSolver = rodas::Rodas4;
