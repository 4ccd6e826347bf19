//! The fitted motor as an FMU (Functional Mock-up Interface 2.0, model exchange and
//! co-simulation; docs/fmu.md): the variable table shared by `modelDescription.xml` and the
//! binary (`variables`), the description itself (`description`), the model behind the C
//! functions (`runtime`, called by the `fmu/` workspace crate, the binary), SI unit
//! definitions (`units`) and the archive (`package`).
//!
//! One binary serves every fit: it reads the fit file packed into the FMU's `resources/`
//! when instantiated, so `vanefit export-fmu` only writes an archive and never compiles.

pub(crate) mod description;
pub(crate) mod package;
pub(crate) mod runtime;
pub(crate) mod units;
pub(crate) mod variables;

pub use package::{find_binary, write_fmu, write_fmu_of, FmuSummary};
pub use runtime::{Inputs, MotorFmu, RuntimeError};
pub use variables::vr;

use std::path::PathBuf;

/// Name of the fit file inside the FMU's `resources/` folder.
pub const RESOURCE_FIT: &str = "fit.json";

/// Why an FMU cannot be made.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FmuError {
    /// The fit has an effect that an FMU of the motor cannot represent.
    #[error("the FMU cannot represent effect '{effect}': {why}")]
    Unrepresentable {
        /// The effect's id.
        effect: String,
        /// Why not.
        why: &'static str,
    },
    /// The fit file cannot be read.
    #[error(transparent)]
    FitFile(#[from] crate::data::fitfile::FitFileError),
    /// The FMU's shared library is not where it was looked for.
    #[error("the FMU binary {name} was not found (looked at {tried}); build it with `cargo build --release` in {tree} (it builds the vanefit-fmu crate beside vanefit), or name it with --binary or {env}")]
    NoBinary {
        /// Its file name.
        name: String,
        /// Where it was looked for.
        tried: String,
        /// The source tree vanefit was compiled from.
        tree: &'static str,
        /// The environment variable that names it.
        env: &'static str,
    },
    /// A file cannot be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// The archive cannot be made.
    #[error("cannot make the FMU archive: {0}")]
    Zip(String),
}

/// The FMU's GUID for a fit file's text: FNV-1a (64 bit) of vanefit's version and the
/// text, so that the binary can check that `modelDescription.xml` and the fit it reads
/// belong together.
pub fn guid(fit_text: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let version = env!("CARGO_PKG_VERSION").as_bytes();
    for b in version.iter().chain([0u8].iter()).chain(fit_text) {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{{vanefit-{h:016x}}}")
}
