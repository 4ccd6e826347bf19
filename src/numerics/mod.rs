//! Numerical methods that know nothing of motors: stiff integration.

pub mod ode;
