//! Replays every committed fuzz corpus file (`fuzz/corpus/<target>/`) through the entry point its
//! fuzz target calls (`fuzz/entries.rs`, shared with the targets): none may panic. The cheap CI
//! half of the fuzzing (the other is `.ci/fuzz.sh`); a crash the fuzzer finds is added to the
//! corpus (or as a test here) and stays fixed.

#[path = "../../fuzz/entries.rs"]
mod entries;

use std::path::Path;

/// Every file of `fuzz/corpus/<target>`, through `entry`; returns how many.
fn replay(target: &str, entry: fn(&[u8])) -> usize {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap().flatten() {
        let bytes = std::fs::read(e.path()).unwrap();
        let name = e.path().display().to_string();
        let r = std::panic::catch_unwind(|| entry(&bytes));
        assert!(r.is_ok(), "{name} panics in the {target} parser");
        n += 1;
    }
    n
}

#[test]
fn every_corpus_file_is_read_or_refused_without_a_panic() {
    for (target, entry) in [
        ("recording", entries::recording as fn(&[u8])),
        ("rig", entries::rig),
        ("fitfile", entries::fit_file),
        ("manifest", entries::manifest),
        ("catalogue_value", entries::catalogue_value),
        ("batch_files", entries::batch_files),
    ] {
        assert!(replay(target, entry) > 0, "{target}: empty corpus");
    }
}

/// Regression inputs: the shapes spreadsheets and loggers produce that once misbehaved,
/// through the same entry points.
#[test]
fn odd_inputs_are_refused_without_a_panic() {
    for text in [
        "\u{feff}t_s;p_port1_mpa\r\n0;1\r\n",
        "t_s,p_port1_mpa\n0,0,1\n",
        "t_s,t_s\n0,0\n",
        "\r\n\r\n",
        ",,,\n,,,\n",
    ] {
        let mut bytes = vec![0u8];
        bytes.extend(text.as_bytes());
        entries::recording(&bytes);
        bytes[0] = 1;
        entries::recording(&bytes);
    }
    entries::fit_file(b"{\"format\": \"vanefit.fit/1\", \"parameters\": {\"c_in1\": 1e999}}");
    entries::catalogue_value(b"\x001e999 rpm");
    entries::rig(b"[motor]\nvanes = 0\n");
}
