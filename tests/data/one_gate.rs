//! One gate for values: `check` refuses every value that `fit`, `simulate`,
//! `diagnose` or `export-petab --dataset` would refuse, with the same located message, and
//! exit status 1.
//!
//! Each case spoils one value of the shipped dataset (in rig.toml or in one cell of a
//! recording), as a spreadsheet slip or a data logger's sentinel would, and runs every
//! command that loads a dataset on it. Before the gate, a displacement of 1e30 m³ passed
//! `check` and made `fit` exit 0 with a cost of 6e75, and a port pressure of 1e30 MPa in
//! one row was simulated into flows of 1e29 g/s.

use crate::common;

use common::{stderr, vanefit, DATASET};
use std::path::Path;

/// Where a case puts its bad value.
enum Spoil {
    /// Replace text in rig.toml (every occurrence).
    Rig(&'static str, &'static str),
    /// Set one cell of a recording: file, data row (0-based), column (0-based), text.
    Cell(&'static str, usize, usize, &'static str),
    /// Set one cell of a recording's last row.
    LastCell(&'static str, usize, &'static str),
}

const CASES: &[(&str, Spoil)] = &[
    (
        "displacement of 1e30 m³",
        Spoil::Rig("displacement_m3 = 3.8e-6", "displacement_m3 = 1e30"),
    ),
    (
        "negative displacement",
        Spoil::Rig("displacement_m3 = 3.8e-6", "displacement_m3 = -3.8e-6"),
    ),
    (
        "expansion ratio below one",
        Spoil::Rig("expansion_ratio = 1.071", "expansion_ratio = 0.5"),
    ),
    ("one vane", Spoil::Rig("vanes = 5", "vanes = 1")),
    (
        "supply below atmosphere",
        Spoil::Rig("p_supply_mpa = 0.73", "p_supply_mpa = 0.05"),
    ),
    (
        "negative brake",
        Spoil::Rig("c_nm_s_rad = 1e-4", "c_nm_s_rad = -1e-4"),
    ),
    (
        "zero temperature",
        Spoil::Rig("temperature_k = 293.15", "temperature_k = 0"),
    ),
    (
        "speed of 1e30 rpm",
        Spoil::Cell("datasheet.csv", 1, 0, "1e30"),
    ),
    (
        "torque not a number",
        Spoil::Cell("datasheet.csv", 2, 1, "nan"),
    ),
    (
        "port pressure of 1e30 MPa",
        Spoil::Cell("ramp.csv", 1, 1, "1e30"),
    ),
    (
        "negative port pressure",
        Spoil::Cell("ramp.csv", 1, 1, "-2"),
    ),
    ("flow of 1e30 g/s", Spoil::Cell("ramp.csv", 2, 2, "1e30")),
    ("last time 1e30 s", Spoil::LastCell("ramp.csv", 0, "1e30")),
    (
        "negative throttle conductance",
        Spoil::Cell("throttle.csv", 1, 1, "-1e-8"),
    ),
    (
        "throttle conductance of 1 m³/(s·Pa)",
        Spoil::Cell("throttle.csv", 1, 1, "1"),
    ),
    (
        "speed of -1e30 rpm",
        Spoil::Cell("throttle.csv", 5, 4, "-1e30"),
    ),
];

/// A copy of the shipped dataset in `dir` with one value spoiled.
fn spoiled(dir: &Path, spoil: &Spoil) {
    std::fs::create_dir_all(dir).unwrap();
    for e in std::fs::read_dir(DATASET).unwrap().flatten() {
        std::fs::copy(e.path(), dir.join(e.file_name())).unwrap();
    }
    let set_cell = |file: &str, row: Option<usize>, col: usize, text: &str| {
        let path = dir.join(file);
        let body = std::fs::read_to_string(&path).unwrap();
        let mut lines: Vec<String> = body.lines().map(str::to_string).collect();
        let line = row.map_or(lines.len() - 1, |r| r + 1);
        let mut cells: Vec<&str> = lines[line].split(',').collect();
        cells[col] = text;
        lines[line] = cells.join(",");
        std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    };
    match *spoil {
        Spoil::Rig(from, to) => {
            let path = dir.join("rig.toml");
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(text.contains(from), "{from}");
            std::fs::write(&path, text.replace(from, to)).unwrap();
        }
        Spoil::Cell(file, row, col, text) => set_cell(file, Some(row), col, text),
        Spoil::LastCell(file, col, text) => set_cell(file, None, col, text),
    }
}

/// The exit status and the `error:` line of a run.
fn outcome(args: &[&str]) -> (Option<i32>, String) {
    let o = vanefit(args);
    let err = stderr(&o)
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or("")
        .to_string();
    (o.status.code(), err)
}

#[test]
fn check_refuses_what_fit_and_simulate_refuse_with_the_same_message() {
    let tmp = tempfile::tempdir().unwrap();
    for (k, (what, spoil)) in CASES.iter().enumerate() {
        let dir = tmp.path().join(format!("case{k}"));
        spoiled(&dir, spoil);
        let ds = dir.to_str().unwrap();
        let out = |name: &str| dir.join(name).to_str().unwrap().to_string();
        let check = outcome(&["check", ds]);
        assert_eq!(check.0, Some(1), "{what}: check must refuse it");
        // Located: file:line:column, in rig.toml or the recording.
        let located = regex_free_location(&check.1);
        assert!(located, "{what}: not located: {}", check.1);
        let runs = [
            ("simulate", outcome(&["simulate", ds, "--out", &out("sim")])),
            (
                "fit",
                outcome(&[
                    "fit",
                    ds,
                    "--starts",
                    "2",
                    "--uncertainty",
                    "none",
                    "--threads",
                    "1",
                    "--out",
                    &out("fit.json"),
                ]),
            ),
            (
                "diagnose",
                outcome(&["diagnose", ds, "--out", &out("diag")]),
            ),
        ];
        for (command, (code, err)) in runs {
            assert_eq!(code, Some(1), "{what}: {command} must refuse it too");
            assert_eq!(err, check.1, "{what}: {command} says otherwise than check");
        }
        // Nothing was written for a refused dataset.
        for name in ["sim", "fit.json", "diag"] {
            assert!(!dir.join(name).exists(), "{what}: {name} written");
        }
    }
}

/// `error: <path>:<line>:<column> …`: the message names a line and a column.
fn regex_free_location(line: &str) -> bool {
    let Some(rest) = line.strip_prefix("error: ") else {
        return false;
    };
    let head = rest.split(' ').next().unwrap_or("");
    let parts: Vec<&str> = head.trim_end_matches(':').rsplitn(3, ':').collect();
    parts.len() == 3 && parts[0].parse::<u32>().is_ok() && parts[1].parse::<u32>().is_ok()
}

/// The unspoiled dataset passes the same gate (the limits are not so tight that they
/// refuse a real recording), and `simulate` on it writes no value the gate would refuse.
#[test]
fn the_shipped_datasets_pass_the_gate_and_their_simulations_too() {
    for ds in [DATASET, "measurements/ar034-synthetic-catalogue"] {
        let (code, err) = outcome(&["check", ds]);
        assert_eq!(code, Some(0), "{ds}: {err}");
    }
    let tmp = tempfile::tempdir().unwrap();
    let sim = tmp.path().join("sim");
    let (code, err) = outcome(&["simulate", DATASET, "--out", sim.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    // The simulated recordings, put in place of the measured ones, are a dataset too.
    std::fs::copy(Path::new(DATASET).join("rig.toml"), sim.join("rig.toml")).unwrap();
    let (code, err) = outcome(&["check", sim.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
}
