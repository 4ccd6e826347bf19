//! The local optimizers and the multi-start over them: restarted Nelder–Mead through argmin
//! (`nelder_mead`), Levenberg–Marquardt on residuals (`least_squares`), both behind one
//! trait (`local`), the checked run settings (`settings`) and the multi-start runner with
//! its observer (`multistart`).

pub(crate) mod least_squares;
pub(crate) mod local;
pub mod multistart;
pub(crate) mod nelder_mead;
pub(crate) mod settings;
