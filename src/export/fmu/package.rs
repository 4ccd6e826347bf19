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

/// The source tree vanefit was compiled from (the clone that `cargo build` or `cargo install
/// --path .` ran in): its `target/` is where that clone's build left the shared library.
const SOURCE_DIR: &str = env!("CARGO_MANIFEST_DIR");

/// Where a build leaves the shared library in a target folder `target`: its `release/`
/// folder (`cargo build --release`, whose default members include `fmu/`) and `release/deps/`
/// (`cargo test --release --workspace`).
fn in_target(target: &Path) -> [PathBuf; 2] {
    let release = target.join("release");
    [
        release.join(BINARY_FILE),
        release.join("deps").join(BINARY_FILE),
    ]
}

/// Where the shared library is looked for without `--binary` or `$VANEFIT_FMU_BINARY`:
/// beside the running executable (`dir`, its `deps/`, one folder up: `cargo build` leaves
/// both in `target/release/`; a test binary runs from `target/release/deps/`), then in the
/// target folder of the source tree vanefit was compiled from (`$CARGO_TARGET_DIR` when set,
/// else `<source>/target`): an executable that `cargo install --path .` copied to
/// `~/.cargo/bin`, or the Python extension, finds there what `cargo build --release` built.
pub fn binary_candidates(exe: Option<&Path>, cargo_target_dir: Option<&Path>) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = Vec::new();
    if let Some(dir) = exe.and_then(Path::parent) {
        out.push(dir.join(BINARY_FILE));
        out.push(dir.join("deps").join(BINARY_FILE));
        out.extend(dir.parent().map(|d| d.join(BINARY_FILE)));
    }
    let source_target = Path::new(SOURCE_DIR).join("target");
    for target in cargo_target_dir
        .into_iter()
        .chain([source_target.as_path()])
    {
        for p in in_target(target) {
            if !out.contains(&p) {
                out.push(p);
            }
        }
    }
    out
}

/// The shared library: `$VANEFIT_FMU_BINARY` when set (it must exist), else the newest
/// `libvanefit_fmu.so` among `binary_candidates` (with `$CARGO_TARGET_DIR`). The newest,
/// because `cargo build` and `cargo test` each update only their own copy.
pub fn find_binary(env_value: Option<PathBuf>, exe: Option<&Path>) -> Result<PathBuf, FmuError> {
    let candidates: Vec<PathBuf> = match env_value {
        Some(p) => vec![p],
        None => {
            let cargo_target = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from);
            binary_candidates(exe, cargo_target.as_deref())
        }
    };
    let modified = |p: &PathBuf| std::fs::metadata(p).and_then(|m| m.modified()).ok();
    candidates
        .iter()
        .filter(|p| p.is_file())
        .max_by_key(|p| modified(p))
        .cloned()
        .ok_or_else(|| FmuError::NoBinary {
            name: BINARY_FILE.into(),
            tried: candidates
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
            tree: SOURCE_DIR,
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
    write_fmu_of(fit_path, &read(fit_path)?, binary, out)
}

/// As [`write_fmu`], with the fit file's bytes `fit_text` given (a fit held in memory:
/// `fit_path` then only names it in messages). The FMU packs these bytes, and its GUID is
/// their hash.
pub fn write_fmu_of(
    fit_path: &Path,
    fit_text: &[u8],
    binary: &Path,
    out: &Path,
) -> Result<FmuSummary, FmuError> {
    let fit = FitFile::parse(fit_path, &String::from_utf8_lossy(fit_text))?;
    let id = guid(fit_text);
    let description = model_description(&fit, &id)?;
    let vars = variables(&fit)?;
    let model_parameters = super::variables::model_parameters(&fit)?.len();
    let bytes = archive(&description, &read(binary)?, fit_text)?;
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
