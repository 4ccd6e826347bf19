//! Import hardening: every refused case names the file, the line and the column,
//! and no input whatsoever makes the import panic (property tests on malformed CSV and
//! rig.toml text).

use proptest::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use vanefit::data::{DataError, Dataset, Recording};

const SHIPPED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/measurements/ar034-synthetic");

/// A copy of the shipped dataset in a temporary folder, with `edit` applied to one file.
fn dataset_with(file: &str, edit: impl FnOnce(String) -> Option<String>) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for entry in std::fs::read_dir(SHIPPED).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, dir.path().join(path.file_name().unwrap())).unwrap();
    }
    let target = dir.path().join(file);
    let text = std::fs::read_to_string(&target).unwrap_or_default();
    match edit(text) {
        Some(t) => std::fs::write(&target, t).unwrap(),
        None => std::fs::remove_file(&target).unwrap(),
    }
    dir
}

fn load_error(dir: &tempfile::TempDir) -> DataError {
    Dataset::load(dir.path()).expect_err("must be refused")
}

fn file_name(e: &DataError) -> String {
    e.file.file_name().unwrap().to_string_lossy().into_owned()
}

/// Replaces one field (1-based line and column) of CSV text.
fn set_field(text: &str, line: usize, col: usize, value: &str) -> String {
    text.lines()
        .enumerate()
        .map(|(i, l)| {
            if i + 1 == line {
                let mut f: Vec<&str> = l.split(',').collect();
                f[col - 1] = value;
                f.join(",")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

#[test]
fn shipped_dataset_loads() {
    let ds = Dataset::load(Path::new(SHIPPED)).unwrap();
    assert_eq!(ds.experiments.len(), 3);
}

#[test]
fn missing_recording_is_located_in_rig_toml() {
    let dir = dataset_with("ramp.csv", |_| None);
    let e = load_error(&dir);
    assert_eq!(file_name(&e), "rig.toml");
    assert_eq!(e.line, Some(22), "{e}");
    assert_eq!(e.column.as_ref().map(|c| c.1.as_str()), Some("file"));
    assert!(e.message.contains("'ramp.csv' not found"), "{e}");
}

#[test]
fn missing_rig_and_missing_folder_are_named() {
    let dir = dataset_with("rig.toml", |_| None);
    let e = load_error(&dir);
    assert_eq!(file_name(&e), "rig.toml");
    assert!(e.message.contains("cannot read"), "{e}");
    let e = Dataset::load(&dir.path().join("nowhere")).unwrap_err();
    assert!(e.to_string().contains("nowhere"), "{e}");
}

#[test]
fn empty_file_is_refused() {
    let dir = dataset_with("throttle.csv", |_| Some(String::new()));
    let e = load_error(&dir);
    assert_eq!((file_name(&e).as_str(), e.line), ("throttle.csv", Some(1)));
    assert!(e.message.contains("empty"), "{e}");
    let dir = dataset_with("throttle.csv", |t| {
        Some(t.lines().next().unwrap().to_string())
    });
    let e = load_error(&dir);
    assert!(e.message.contains("no data rows"), "{e}");
}

#[test]
fn missing_column_is_named() {
    // The ramp without its p_port1 column.
    let dir = dataset_with("ramp.csv", |t| {
        Some(
            t.lines()
                .map(|l| {
                    let f: Vec<&str> = l.split(',').collect();
                    [&f[..1], &f[2..]].concat().join(",")
                })
                .collect::<Vec<_>>()
                .join("\n"),
        )
    });
    let e = load_error(&dir);
    assert_eq!((file_name(&e).as_str(), e.line), ("ramp.csv", Some(1)));
    assert!(e.message.contains("p_port1"), "{e}");
}

#[test]
fn unknown_column_and_unknown_unit_are_located() {
    let dir = dataset_with("ramp.csv", |t| Some(t.replacen("flow2_g_s", "temp_k", 1)));
    let e = load_error(&dir);
    assert_eq!(e.line, Some(1));
    assert_eq!(e.column, Some((4, "temp_k".to_string())));
    assert!(e.message.contains("unknown column"), "{e}");
    let dir = dataset_with("ramp.csv", |t| {
        Some(t.replacen("flow2_g_s", "flow2_furlongs", 1))
    });
    let e = load_error(&dir);
    assert_eq!(e.column, Some((4, "flow2_furlongs".to_string())));
    assert!(e.message.contains("unknown unit 'furlongs'"), "{e}");
    assert!(e.message.contains("l_min_anr"), "{e}");
}

#[test]
fn text_and_nan_in_a_number_field_are_located() {
    for bad in ["abc", "NaN", "inf", "", "1,5e0", "1e999"] {
        let dir = dataset_with("throttle.csv", |t| Some(set_field(&t, 40, 3, bad)));
        let e = load_error(&dir);
        assert_eq!(file_name(&e), "throttle.csv");
        assert_eq!(e.line, Some(40), "{bad:?}: {e}");
        if !bad.contains(',') {
            assert_eq!(e.column, Some((3, "flow1_g_s".to_string())), "{bad:?}: {e}");
        }
    }
}

#[test]
fn time_going_backwards_is_located() {
    let dir = dataset_with("ramp.csv", |t| Some(set_field(&t, 100, 1, "5.0")));
    let e = load_error(&dir);
    assert_eq!(e.line, Some(100), "{e}");
    assert_eq!(e.column, Some((1, "t_s".to_string())));
    assert!(e.message.contains("time does not increase"), "{e}");
}

#[test]
fn ramp_that_does_not_span_is_refused() {
    let dir = dataset_with("ramp.csv", |t| {
        let mut out = String::new();
        for (i, l) in t.lines().enumerate() {
            if i == 0 {
                out += l;
            } else {
                let f: Vec<&str> = l.split(',').collect();
                out += &format!("{},0.73,{}", f[0], f[2..].join(","));
            }
            out.push('\n');
        }
        Some(out)
    });
    let e = load_error(&dir);
    assert_eq!(file_name(&e), "ramp.csv");
    assert_eq!(e.line, Some(602), "{e}");
    assert_eq!(e.column, Some((2, "p_port1_mpa".to_string())));
    assert!(e.message.contains("does not span"), "{e}");
}

#[test]
fn rig_errors_are_located_at_their_key() {
    let dir = dataset_with("rig.toml", |t| {
        Some(t.replace("p_supply_mpa = 0.73\nload", "p_supply_mpa = 73\nload"))
    });
    let e = load_error(&dir);
    assert_eq!(
        (file_name(&e).as_str(), e.line),
        ("rig.toml", Some(28)),
        "{e}"
    );
    assert_eq!(e.column, Some((1, "p_supply_mpa".to_string())));
    let dir = dataset_with("rig.toml", |t| {
        Some(t.replace(
            "file = \"ramp.csv\"",
            "file = \"ramp.csv\"\nweights = { flwo1 = 2.0 }",
        ))
    });
    let e = load_error(&dir);
    assert_eq!(e.line, Some(23), "{e}");
    assert_eq!(e.column, Some((13, "flwo1".to_string())));
    assert!(e.message.contains("not a channel"), "{e}");
    let dir = dataset_with("rig.toml", |t| {
        Some(t.replace("vanes = 5", "vanes = \"five\""))
    });
    let e = load_error(&dir);
    assert_eq!(e.line, Some(7), "{e}");
    let dir = dataset_with("rig.toml", |t| {
        Some(t.replace("kind = \"datasheet\"", "kind = \"datashet\""))
    });
    let e = load_error(&dir);
    assert_eq!(e.line, Some(16), "{e}");
}

#[test]
fn check_command_exits_1_with_a_located_message() {
    let dir = dataset_with("datasheet.csv", |t| Some(set_field(&t, 7, 2, "0,25")));
    let out = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .arg("check")
        .arg(dir.path())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("datasheet.csv:7"), "{err}");
    assert!(out.stdout.is_empty(), "nothing printed before the refusal");
    let ok = Command::new(env!("CARGO_BIN_EXE_vanefit"))
        .arg("check")
        .arg(SHIPPED)
        .output()
        .unwrap();
    assert_eq!(ok.status.code(), Some(0));
    let text = String::from_utf8_lossy(&ok.stdout);
    assert!(
        text.contains("reference speed_rpm vs p_port1_mpa"),
        "{text}"
    );
    assert!(
        text.contains("reference flow1_g_s vs log10 c_port2_m3_s_pa"),
        "{text}"
    );
}

// ---------------------------------------------------------------------------------------
// Property tests: no input makes the import panic, and every refusal is located.

const VALID_CSV: &str = "t_s,p_port1_bar_g,flow1_l_min_anr,flow2_kg_s,speed_rpm\n\
0.0,0.0,0.0,0.0,0\n\
0.1,0.5,10.5,1e-4,100\n\
0.2,1.0,20.25,2e-4,200\n\
0.3,1.5,30.0,3e-4,300\n\
0.4,2.0,40.0,4e-4,400\n";

fn parse(text: &str) -> Result<Recording, DataError> {
    Recording::parse(Path::new("p.csv"), text, 101_325.0)
}

fn assert_located(e: &DataError, text: &str) {
    let lines = text.lines().count().max(1) as u64;
    let line = e.line.expect("every CSV refusal names a line");
    assert!(
        line >= 1 && line <= lines + 1,
        "line {line} of {lines}: {e}"
    );
    if let Some((c, _)) = &e.column {
        assert!(*c >= 1);
    }
    assert!(e.to_string().starts_with("p.csv:"), "{e}");
}

/// Text fragments that break CSV files in practice.
fn junk() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("".to_string()),
        Just("NaN".to_string()),
        Just("-inf".to_string()),
        Just("1e999".to_string()),
        Just("\"".to_string()),
        Just("\"1,0\"".to_string()),
        Just(",".to_string()),
        Just("\n".to_string()),
        Just("\r\n".to_string()),
        Just("0,5".to_string()),
        Just("\u{feff}".to_string()),
        Just("١٢".to_string()),
        Just("µ".to_string()),
        Just("-0".to_string()),
        Just("t_s".to_string()),
        Just("flow1_cfm".to_string()),
        "[ -~]{0,6}",
        any::<String>(),
        any::<f64>().prop_map(|v| v.to_string()),
    ]
}

/// One edit of a text at a (char-boundary) position: insert, replace a span, or truncate.
fn mutate(text: &str, kind: u8, at: usize, len: usize, piece: &str) -> String {
    let b: Vec<usize> = text
        .char_indices()
        .map(|(i, _)| i)
        .chain([text.len()])
        .collect();
    let i = b[at % b.len()];
    let j = b[((at % b.len()) + len).min(b.len() - 1)];
    match kind % 3 {
        0 => format!("{}{piece}{}", &text[..i], &text[i..]),
        1 => format!("{}{piece}{}", &text[..i], &text[j..]),
        _ => text[..i].to_string(),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_text_never_panics(text in any::<String>()) {
        if let Err(e) = parse(&text) {
            assert_located(&e, &text);
        }
    }

    #[test]
    fn mutated_csv_is_read_or_refused_with_a_location(
        edits in prop::collection::vec((any::<u8>(), any::<usize>(), 0usize..12, junk()), 1..4)
    ) {
        let mut text = VALID_CSV.to_string();
        for (kind, at, len, piece) in &edits {
            text = mutate(&text, *kind, *at, *len, piece);
        }
        match parse(&text) {
            Ok(rec) => {
                // Whatever was accepted is finite, rectangular and in increasing time.
                for c in &rec.columns {
                    prop_assert_eq!(c.si.len(), rec.rows());
                    prop_assert!(c.si.iter().all(|v| v.is_finite()));
                }
                if let Some(t) = rec.column(vanefit::units::Quantity::Time) {
                    prop_assert!(t.si.windows(2).all(|w| w[1] > w[0]));
                }
            }
            Err(e) => assert_located(&e, &text),
        }
    }

    #[test]
    fn column_names_never_panic(name in any::<String>()) {
        let _ = vanefit::units::parse_column(&name);
    }
}

/// A folder with valid recordings and the given rig.toml text.
fn rig_dataset(rig: &str) -> tempfile::TempDir {
    dataset_with("rig.toml", |_| Some(rig.to_string()))
}

fn shipped_rig() -> String {
    std::fs::read_to_string(PathBuf::from(SHIPPED).join("rig.toml")).unwrap()
}

/// rig.toml fragments: keys and values that are wrong in type, range or name.
fn rig_junk() -> impl Strategy<Value = String> {
    prop_oneof![
        Just("nan".to_string()),
        Just("-1".to_string()),
        Just("1e400".to_string()),
        Just("\"x\"".to_string()),
        Just("[[experiment]]\n".to_string()),
        Just("[motor]\n".to_string()),
        Just("weights = { speed = -1 }\n".to_string()),
        Just("load = { kind = \"torque\", t_nm = inf }\n".to_string()),
        Just("file = \"../ramp.csv\"\n".to_string()),
        Just("file = \"\"\n".to_string()),
        Just("=".to_string()),
        Just("\"".to_string()),
        Just("é".to_string()),
        "[ -~]{0,8}",
        any::<String>(),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn mutated_rig_is_read_or_refused_with_a_location(
        edits in prop::collection::vec((any::<u8>(), any::<usize>(), 0usize..16, rig_junk()), 1..3)
    ) {
        let mut text = shipped_rig();
        for (kind, at, len, piece) in &edits {
            text = mutate(&text, *kind, *at, *len, piece);
        }
        let dir = rig_dataset(&text);
        if let Err(e) = Dataset::load(dir.path()) {
            // Errors in rig.toml itself carry a line; errors in a recording name it.
            let name = file_name(&e);
            if name == "rig.toml" {
                prop_assert!(e.line.is_some(), "{}\n---\n{}", e, text);
            }
            prop_assert!(e.to_string().contains(&name));
        }
    }
}

#[test]
fn motor_given_by_geometry_loads_and_bad_motor_keys_are_located() {
    // The appendix geometry with port angles for V_fill = 0.76 cm³, ε = 1.071: the rig's
    // nominal motor gets v_disp and eps from paper eqs. 1–7.
    let geometry = "[motor]\nname = \"AR034-11\"\nvanes = 5\nlength_m = 0.032\n\
                    r_stator_m = 0.009\nr_rotor_m = 0.00755\nalpha_dead_deg = 36\n\
                    alpha_fill_deg = 162.0\nalpha_exp_deg = 169.0\n";
    let dir = dataset_with("rig.toml", |t| {
        let start = t.find("[motor]").unwrap();
        let end = t.find("[conditions]").unwrap();
        Some(format!("{}{geometry}\n{}", &t[..start], &t[end..]))
    });
    let ds = Dataset::load(dir.path()).unwrap();
    let p = ds.nominal_params().unwrap();
    assert!(
        (p.v_disp() - 3.8e-6).abs() < 0.1e-6,
        "v_disp {}",
        p.v_disp()
    );
    assert!(p.eps() > 1.0 && p.eps() < 1.2, "eps {}", p.eps());

    // A negative displacement is refused by `check` itself, at its key.
    let dir = dataset_with("rig.toml", |t| {
        Some(t.replace("displacement_m3 = 3.8e-6", "displacement_m3 = -3.8e-6"))
    });
    let e = load_error(&dir);
    let text = std::fs::read_to_string(dir.path().join("rig.toml")).unwrap();
    let line = text
        .lines()
        .position(|l| l.starts_with("displacement_m3"))
        .unwrap() as u64
        + 1;
    assert_eq!(e.line, Some(line), "{e}");
    assert_eq!(
        e.column.as_ref().map(|c| c.1.as_str()),
        Some("displacement_m3")
    );
    assert!(e.to_string().contains("v_disp"), "{e}");

    // An expansion ratio below 1 likewise.
    let dir = dataset_with("rig.toml", |t| {
        Some(t.replace("expansion_ratio = 1.071", "expansion_ratio = 0.5"))
    });
    let e = load_error(&dir);
    assert_eq!(
        e.column.as_ref().map(|c| c.1.as_str()),
        Some("expansion_ratio"),
        "{e}"
    );
}
