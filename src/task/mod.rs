//! The work of one command as a library function (options in, files out): `fit`,
//! `diagnose` and `predict` of a single dataset. The command line calls these for one
//! dataset and `batch` for every unit of a fleet, so a unit of a batch leaves exactly the
//! files, and the numbers, the command would.

pub mod diagnose;
pub mod fit;
pub mod predict;

/// Clap value parser of `--effects`: the list as given once every id in it is known, so an
/// unknown id is bad usage (exit status 2, reported by clap with the known ids) rather than
/// a failed run.
pub fn effects_arg(list: &str) -> Result<String, crate::model::effects::UnknownEffect> {
    crate::model::effects::EffectSet::parse_list(list).map(|_| list.to_string())
}

/// A count option given as 0 or not as a whole number.
#[derive(Debug, thiserror::Error)]
#[error("'{0}' is not a whole number of at least 1")]
pub struct CountError(String);

/// Clap value parser of a count that must be at least 1 (`--starts`, `--threads`): 0 is bad
/// usage, exit status 2.
pub fn at_least_one(given: &str) -> Result<usize, CountError> {
    match given.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(CountError(given.to_string())),
    }
}
