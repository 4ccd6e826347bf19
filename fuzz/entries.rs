//! The fuzzed entry points, shared by the fuzz targets (`fuzz_targets/*.rs`) and by the
//! corpus replay of the test suite (`tests/fuzz_corpus.rs`), so a crash the fuzzer finds
//! fails `cargo test` once its input is in the corpus. Each takes arbitrary bytes and must
//! return (read or refused) without a panic.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The shipped datasets' folder (this file is compiled in the fuzz crate and in vanefit's
/// tests, one folder apart).
fn measurements() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    [here.join("measurements"), here.join("../measurements")]
        .into_iter()
        .find(|p| p.is_dir())
        .expect("the shipped measurements folder")
}

/// Text of the input, lossily: the parsers take text (files are read as UTF-8 and refused
/// with a located message otherwise).
fn text(data: &[u8]) -> String {
    String::from_utf8_lossy(data).into_owned()
}

/// A CSV recording: the first byte picks dense (rig) or sparse (catalogue) reading and
/// the atmospheric pressure; the rest is the file.
pub fn recording(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let text = text(rest);
    let p_atm = if mode & 2 == 0 { 101_325.0 } else { 90_000.0 };
    let path = Path::new("fuzz.csv");
    let read = if mode & 1 == 0 {
        vanefit::data::dataset::Recording::parse(path, &text, p_atm)
    } else {
        vanefit::data::dataset::Recording::parse_sparse(path, &text, p_atm)
    };
    if let Ok(rec) = read {
        for c in &rec.columns {
            assert_eq!(c.si.len(), rec.rows());
        }
    } else if let Err(e) = read {
        assert!(e.to_string().starts_with("fuzz.csv"), "{e}");
    }
}

/// A temporary folder holding the shipped recordings (and catalogue pages), into which
/// each input is written as rig.toml.
fn rig_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("vanefit-fuzz-rig-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for src in ["ar034-synthetic", "ar034-synthetic-catalogue"] {
            for e in std::fs::read_dir(measurements().join(src))
                .unwrap()
                .flatten()
            {
                if e.path().extension().is_some_and(|x| x == "csv") {
                    std::fs::copy(e.path(), dir.join(e.file_name())).unwrap();
                }
            }
        }
        dir
    })
}

/// A rig.toml beside the shipped recordings: loaded (and its nominal motor built) or
/// refused.
pub fn rig(data: &[u8]) {
    let dir = rig_dir();
    std::fs::write(dir.join("rig.toml"), data).unwrap();
    if let Ok(ds) = vanefit::data::dataset::Dataset::load(dir) {
        let _ = ds.nominal_params();
    }
}

/// A fit file (vanefit.fit/1).
pub fn fit_file(data: &[u8]) {
    let _ = vanefit::data::fitfile::FitFile::parse(Path::new("fuzz.json"), &text(data));
}

/// A batch manifest, in a folder of its own (its dataset globs resolve there).
pub fn manifest(data: &[u8]) {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| {
        let dir =
            std::env::temp_dir().join(format!("vanefit-fuzz-manifest-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("measurements")).unwrap();
        dir
    });
    let path = dir.join("manifest.toml");
    std::fs::write(&path, data).unwrap();
    let _ = vanefit::batch::manifest::Manifest::load(&path);
}

/// A catalogue value ("6.3 bar(g)", "1,450 rpm") of each quantity a catalogue page gives:
/// the first byte picks the quantity.
pub fn catalogue_value(data: &[u8]) {
    use vanefit::units::Quantity;
    let Some((&pick, rest)) = data.split_first() else {
        return;
    };
    let quantities = [
        Quantity::Speed,
        Quantity::Torque,
        Quantity::Power,
        Quantity::Flow1,
        Quantity::PPort1,
    ];
    let q = quantities[pick as usize % quantities.len()];
    if let Ok((si, _, _)) =
        vanefit::data::dataset::catalogue::parse_value(&text(rest), q, 101_325.0)
    {
        assert!(si.is_finite(), "{si}");
    }
}
