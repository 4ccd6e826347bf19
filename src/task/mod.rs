//! The work of one command as a library function (options in, files out): `fit`,
//! `diagnose` and `predict` of a single dataset. The command line calls these for one
//! dataset and `batch` for every unit of a fleet, so a unit of a batch leaves exactly the
//! files, and the numbers, the command would.

pub mod diagnose;
pub mod fit;
pub mod predict;
