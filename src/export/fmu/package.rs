//! The `.fmu` archive (a zip): `modelDescription.xml` generated from the fit, the shared
//! library as `binaries/linux64/<modelIdentifier>.so`, and the fit file itself as
//! `resources/fit.json`, which the library reads when instantiated. Written to a temporary
//! file and renamed (`io::write_atomic`).

use super::description::model_description;
use super::variables::{variables, MODEL_IDENTIFIER};
use super::{guid, FmuError, RESOURCE_FIT};
use crate::data::fitfile::FitFile;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The shared library's file name as cargo builds it (`target/release/`).
pub const BINARY_FILE: &str = "libvanefit_fmu.so";

/// Environment variable that names the shared library, overriding the search.
pub const BINARY_ENV: &str = "VANEFIT_FMU_BINARY";

/// What was written.
#[derive(Debug, Clone, PartialEq)]
pub struct FmuSummary {
    /// The archive's size, bytes.
    pub bytes: usize,
    /// Number of variables in `modelDescription.xml`.
    pub variables: usize,
    /// Number of tunable model parameters (base, effects, discovered terms).
    pub model_parameters: usize,
    /// The GUID.
    pub guid: String,
}

/// The shared library: `$VANEFIT_FMU_BINARY` when set (it must exist), else the newest
/// `libvanefit_fmu.so` beside the running executable, in its `deps/` folder (where `cargo
/// test` leaves it) or one folder up (a test binary runs from `target/release/deps/`).
/// The newest, because `cargo build` and `cargo test` each update only their own copy.
pub fn find_binary(env_value: Option<PathBuf>, exe: Option<&Path>) -> Result<PathBuf, FmuError> {
    let candidates: Vec<PathBuf> = match env_value {
        Some(p) => vec![p],
        None => exe
            .and_then(Path::parent)
            .map(|dir| {
                let up = dir.parent().map(|d| d.join(BINARY_FILE));
                [dir.join(BINARY_FILE), dir.join("deps").join(BINARY_FILE)]
                    .into_iter()
                    .chain(up)
                    .collect()
            })
            .unwrap_or_default(),
    };
    let modified = |p: &PathBuf| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    candidates
        .iter()
        .filter(|p| p.is_file())
        .max_by_key(|p| modified(p))
        .cloned()
        .ok_or_else(|| FmuError::NoBinary {
            name: BINARY_FILE.into(),
            tried: if candidates.is_empty() {
                "nowhere: the running executable's folder is unknown".into()
            } else {
                candidates
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            },
            env: BINARY_ENV,
        })
}

fn read(path: &Path) -> Result<Vec<u8>, FmuError> {
    std::fs::read(path).map_err(|source| FmuError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The archive's bytes: description, binary and fit.
fn archive(description: &str, binary: &[u8], fit_text: &[u8]) -> Result<Vec<u8>, FmuError> {
    let zip_err = |e: zip::result::ZipError| FmuError::Zip(e.to_string());
    let io_err = |e: std::io::Error| FmuError::Zip(e.to_string());
    let mut w = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let deflated = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .unix_permissions(0o644);
    let entries: [(String, &[u8]); 3] = [
        ("modelDescription.xml".into(), description.as_bytes()),
        (format!("binaries/linux64/{MODEL_IDENTIFIER}.so"), binary),
        (format!("resources/{RESOURCE_FIT}"), fit_text),
    ];
    for (name, bytes) in entries {
        w.start_file(name, deflated).map_err(zip_err)?;
        w.write_all(bytes).map_err(io_err)?;
    }
    Ok(w.finish().map_err(zip_err)?.into_inner())
}

/// Writes the FMU of the fit file at `fit_path` with the shared library at `binary` to
/// `out` (temporary file, then rename). Refuses a fit the FMU cannot represent.
pub fn write_fmu(fit_path: &Path, binary: &Path, out: &Path) -> Result<FmuSummary, FmuError> {
    let fit_text = read(fit_path)?;
    let fit = FitFile::parse(fit_path, &String::from_utf8_lossy(&fit_text))?;
    let id = guid(&fit_text);
    let description = model_description(&fit, &id)?;
    let vars = variables(&fit)?;
    let model_parameters = super::variables::model_parameters(&fit)?.len();
    let bytes = archive(&description, &read(binary)?, &fit_text)?;
    crate::io::write_atomic(out, &bytes).map_err(|source| FmuError::Io {
        path: out.to_path_buf(),
        source,
    })?;
    Ok(FmuSummary {
        bytes: bytes.len(),
        variables: vars.len(),
        model_parameters,
        guid: id,
    })
}
