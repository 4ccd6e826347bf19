//! The fuzzed entry points, shared by the fuzz targets (`fuzz_targets/*.rs`) and by the
//! corpus replay of the test suite (`tests/hardening/fuzz_corpus.rs`), so a crash the fuzzer finds
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
        vanefit::data::Recording::parse(path, &text, p_atm)
    } else {
        vanefit::data::Recording::parse_sparse(path, &text, p_atm)
    };
    if let Ok(rec) = read {
        for c in &rec.columns {
            assert_eq!(c.si.len(), rec.rows());
        }
    } else if let Err(e) = read {
        assert!(e.to_string().starts_with("fuzz.csv"), "{e}");
    }
}

/// A temporary folder holding the shipped recordings (and catalogue pages), beside which
/// each input is read as rig.toml text. The recordings keep their first 120 rows: enough
/// for every check of a dataset (the recording parser has its own target), and reading them
/// for every input that gets that far stays cheap.
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
                    let text = std::fs::read_to_string(e.path()).unwrap();
                    let head: Vec<&str> = text.lines().take(121).collect();
                    std::fs::write(dir.join(e.file_name()), head.join("\n") + "\n").unwrap();
                }
            }
        }
        dir
    })
}

/// Whether an input names system folders whose files are endless or huge (`/dev/zero`,
/// `/proc/kcore`): reading them is slow, not wrong, and would stall the fuzzer.
fn names_system_files(text: &str) -> bool {
    ["/dev", "/proc", "/sys"].iter().any(|p| text.contains(p))
}

/// A rig.toml beside the shipped recordings: loaded (and its nominal motor built) or
/// refused, with a message naming rig.toml.
pub fn rig(data: &[u8]) {
    let text = text(data);
    if names_system_files(&text) {
        return;
    }
    let dir = rig_dir();
    match vanefit::data::Dataset::from_rig_text(dir, &text) {
        Ok(ds) => {
            let _ = ds.nominal_params();
        }
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// A fit file (vanefit.fit/1).
pub fn fit_file(data: &[u8]) {
    let _ = vanefit::data::FitFile::parse(Path::new("fuzz.json"), &text(data));
}

/// A batch manifest, in a folder of its own with two (empty) dataset folders under
/// `measurements/`, against which its dataset globs resolve. The manifest reader refuses
/// globs that could leave that folder (absolute, `..`, `.?`) before walking, so no input
/// walks the machine's file system (the fuzzer once found `"/*/////*/.?/*/?O…"`, a
/// 13-second walk, and `.?/`, a walk of all of /tmp, which this target had to skip).
pub fn manifest(data: &[u8]) {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| {
        let dir =
            std::env::temp_dir().join(format!("vanefit-fuzz-manifest-{}", std::process::id()));
        for d in ["a", "b"] {
            std::fs::create_dir_all(dir.join("measurements").join(d)).unwrap();
        }
        dir
    });
    let text = text(data);
    let path = dir.join("manifest.toml");
    let shown = Path::new("manifest.toml");
    if let Err(e) = vanefit::batch::Manifest::parse(&path, shown, &text) {
        assert!(e.to_string().starts_with("manifest.toml"), "{e}");
    }
}

/// The files `merge` reads back from a batch folder (a user may have edited or truncated
/// them), separated by NUL bytes: `batch.json`, then each unit's `status.json`, `fit.json`
/// and `diagnosis.json` (every unit gets the same). Without a usable `batch.json`, a batch
/// of a fit and a diagnosis of one dataset stands in, so that the other files are still
/// read. The summary is made in memory, the fleet plot drawn to a string.
pub fn batch_files(data: &[u8]) {
    use vanefit::batch::{summarize, BatchRecord};
    let mut parts = data.split(|b| *b == 0).map(text);
    let batch = parts.next().unwrap_or_default();
    let files: Vec<String> = parts.take(3).collect();
    let out = Path::new("/fuzz-batch");
    let record = BatchRecord::parse(out, &batch)
        .ok()
        .filter(|r| r.units.len() <= 16)
        .unwrap_or_else(|| {
            BatchRecord::parse(
                out,
                r#"{"format": "vanefit.batch/1", "manifest": "/m.toml", "settings": {},
                "units": [{"dataset": "d", "path": "/d", "task": "fit", "group": 0},
                          {"dataset": "d", "path": "/d", "task": "diagnose", "group": 0}]}"#,
            )
            .expect("the stand-in batch record")
        });
    let read = |p: &Path| -> std::io::Result<String> {
        let k = match p.file_name().and_then(|n| n.to_str()) {
            Some("status.json") => 0,
            Some("fit.json") => 1,
            Some("diagnosis.json") => 2,
            _ => 3,
        };
        files
            .get(k)
            .cloned()
            .ok_or_else(|| std::io::Error::from(std::io::ErrorKind::NotFound))
    };
    let summary = summarize(out, &record, &read);
    assert!(summary.csv.starts_with("dataset,task,status,message,cost"));
    if let Some(fig) = summary.fleet {
        let _ = fig.to_svg();
    }
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
    if let Ok((si, _, _)) = vanefit::data::parse_value(&text(rest), q, 101_325.0) {
        assert!(si.is_finite(), "{si}");
    }
}
