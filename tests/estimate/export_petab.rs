//! `vanefit export-petab` (docs/formats.md, "Contracts added later") and the profile paths
//! of the fit file.
//!
//! The PEtab tables are read back here as plain TSV, independently of the exporter: every
//! compared row is present once with its recorded value, every observable's formula names
//! only symbols that the model, the parameter table or its own per-row parameters define,
//! the nuisances' nominal values reproduce the fit's χ² when the residuals are recomputed
//! from the tables and the simulated rows, the motor priors' `parameterScaleNormal` terms at
//! the nominal values add the fit's `prior_chi2` (so the tables' total is the fit's
//! objective, for a rig fit and a catalogue-page fit), and bad input is refused with exit
//! status 1.
//! (The PEtab library's own linter and χ² are run on the same export by the Python tests.)

use crate::common;
use common::{stderr, vanefit, vanefit_in, DATASET};

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use vanefit::data::Dataset;
use vanefit::data::FitFile;
use vanefit::estimate::FitLikelihood;

/// The shipped catalogue page (one supply pressure, no dead volume).
const CATALOGUE: &str = "measurements/ar034-synthetic-catalogue";

/// A fit of the shipped dataset by the CLI with profile intervals (few starts: seconds).
fn profile_fit(dir: &Path) -> std::path::PathBuf {
    fit_of(dir, DATASET)
}

/// A fit of `dataset` by the CLI with its default prior and profile intervals.
fn fit_of(dir: &Path, dataset: &str) -> std::path::PathBuf {
    let out = dir.join("fit.json");
    let o = vanefit(&[
        "fit",
        dataset,
        "--starts",
        "6",
        "--seed",
        "2",
        "--no-plots",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    out
}

/// A TSV file as (header, rows of cells).
fn tsv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let split = |l: &str| l.split('\t').map(str::to_string).collect::<Vec<_>>();
    let header = split(lines.next().unwrap());
    let rows: Vec<Vec<String>> = lines.map(split).collect();
    for r in &rows {
        assert_eq!(
            r.len(),
            header.len(),
            "{}: ragged row {r:?}",
            path.display()
        );
    }
    (header, rows)
}

fn column<'a>(t: &'a (Vec<String>, Vec<Vec<String>>), name: &str) -> Vec<&'a str> {
    let j = t.0.iter().position(|h| h == name).unwrap_or_else(|| {
        panic!("no column {name} in {:?}", t.0);
    });
    t.1.iter().map(|r| r[j].as_str()).collect()
}

fn is_petab_id(s: &str) -> bool {
    let mut c = s.chars();
    c.next()
        .is_some_and(|f| f.is_ascii_alphabetic() || f == '_')
        && c.all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
}

#[test]
fn the_tables_hold_the_fits_likelihood() {
    let dir = tempfile::tempdir().unwrap();
    let fit_path = profile_fit(dir.path());
    check_export(dir.path(), &fit_path, DATASET);
}

/// A page fit estimates every default parameter, most resting on their prior: the table
/// carries each one's prior, and the tables' χ² is the fit's objective.
#[test]
fn a_page_fits_tables_carry_its_motor_prior() {
    let dir = tempfile::tempdir().unwrap();
    let fit_path = fit_of(dir.path(), CATALOGUE);
    let fit = FitFile::read(&fit_path).unwrap();
    let stats = fit.statistics.as_ref().unwrap();
    assert!(stats.prior.len() >= 8, "{:?}", stats.prior);
    let prior_chi2 = stats.prior_chi2.unwrap();
    assert!(prior_chi2 > 0.0);
    let motor = check_export(dir.path(), &fit_path, CATALOGUE);
    assert!(
        ((motor - prior_chi2) / prior_chi2).abs() < 1e-9,
        "{motor} vs {prior_chi2}"
    );
}

/// Exports `fit_path` and checks its tables against the fit (module documentation);
/// returns the motor priors' χ² at the nominal values.
fn check_export(dir: &Path, fit_path: &Path, dataset: &str) -> f64 {
    let out = dir.join("petab");
    let o = vanefit(&[
        "export-petab",
        fit_path.to_str().unwrap(),
        "--dataset",
        dataset,
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "parameters.tsv",
        "observables.tsv",
        "measurements.tsv",
        "conditions.tsv",
        "model.xml",
        "problem.yaml",
        "vanefit_export.json",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");

    let params = tsv(&out.join("parameters.tsv"));
    let obs = tsv(&out.join("observables.tsv"));
    let meas = tsv(&out.join("measurements.tsv"));
    let cond = tsv(&out.join("conditions.tsv"));
    let model = std::fs::read_to_string(out.join("model.xml")).unwrap();

    // Every id is a PEtab identifier; every measurement's condition and observable exist.
    let obs_ids = column(&obs, "observableId");
    let cond_ids: BTreeSet<&str> = column(&cond, "conditionId").into_iter().collect();
    for id in obs_ids.iter().chain(cond_ids.iter()) {
        assert!(is_petab_id(id), "{id}");
    }
    for (o, c) in column(&meas, "observableId")
        .iter()
        .zip(column(&meas, "simulationConditionId"))
    {
        assert!(obs_ids.contains(o) && cond_ids.contains(c), "{o} {c}");
    }

    // Formulas name only what the model, the parameter table or their own per-row
    // parameters define.
    let declared: BTreeSet<String> = model
        .split("<parameter id=\"")
        .skip(1)
        .map(|s| s.split('"').next().unwrap().to_string())
        .collect();
    let table: BTreeMap<&str, usize> = column(&params, "parameterId")
        .into_iter()
        .enumerate()
        .map(|(i, p)| (p, i))
        .collect();
    for (id, f) in obs_ids.iter().zip(column(&obs, "observableFormula")) {
        for token in f.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_')) {
            if token.is_empty() || token.parse::<f64>().is_ok() {
                continue;
            }
            let per_row = token.starts_with("observableParameter") && token.ends_with(id);
            assert!(
                per_row || declared.contains(token) || table.contains_key(token),
                "{id}: '{token}' is defined nowhere"
            );
        }
    }

    // The estimated parameters carry the fit's values; nuisance priors are N(0, τ²), τ > 0.
    let fit = FitFile::read(fit_path).unwrap();
    let nominal = column(&params, "nominalValue");
    for name in &fit.estimated {
        let v: f64 = nominal[table[name.as_str()]].parse().unwrap();
        assert_eq!(v, fit.params.get(name).unwrap(), "{name}");
    }
    let priors = column(&params, "objectivePriorParameters");
    let scales = column(&params, "parameterScale");
    let ids = column(&params, "parameterId");
    let stats = fit.statistics.clone().unwrap();
    let mut chi2_priors = 0.0;
    let mut chi2_motor = 0.0;
    for (i, kind) in column(&params, "objectivePriorType").iter().enumerate() {
        let (m, s) = match priors[i].split_once(';') {
            Some((m, s)) => (m.parse::<f64>().unwrap(), s.parse::<f64>().unwrap()),
            None => {
                // No prior: only a parameter the fit file states none for.
                assert!(kind.is_empty(), "{}: {kind} without parameters", ids[i]);
                assert!(
                    stats.prior.iter().all(|e| e.parameter != ids[i]),
                    "{}",
                    ids[i]
                );
                continue;
            }
        };
        let v: f64 = nominal[i].parse().unwrap();
        match *kind {
            "normal" => {
                assert!(m == 0.0 && s > 0.0);
                chi2_priors += (v / s).powi(2);
            }
            "parameterScaleNormal" => {
                // log10 of the fit file's median, σ of ln v / ln 10, on the log10 scale.
                assert_eq!(scales[i], "log10", "{}", ids[i]);
                let e = stats.prior.iter().find(|e| e.parameter == ids[i]).unwrap();
                assert!((m - e.median.log10()).abs() < 1e-12, "{}", ids[i]);
                assert!((s * std::f64::consts::LN_10 / e.sd_ln - 1.0).abs() < 1e-12);
                chi2_motor += ((v.log10() - m) / s).powi(2);
            }
            "logNormal" => {
                // A parameter searched on a linear scale (b_crit): ln of the median, σ of ln v.
                assert_eq!(scales[i], "lin", "{}", ids[i]);
                let e = stats.prior.iter().find(|e| e.parameter == ids[i]).unwrap();
                assert!((m - e.median.ln()).abs() < 1e-12, "{}", ids[i]);
                assert!((s / e.sd_ln - 1.0).abs() < 1e-12);
                chi2_motor += ((v.ln() - m) / s).powi(2);
            }
            other => panic!("{}: unexpected prior {other}", ids[i]),
        }
    }
    // Every prior the fit file states is in the table.
    for e in &stats.prior {
        let i = table[e.parameter.as_str()];
        let want = if scales[i] == "log10" {
            "parameterScaleNormal"
        } else {
            "logNormal"
        };
        assert_eq!(
            column(&params, "objectivePriorType")[i],
            want,
            "{}",
            e.parameter
        );
    }

    // χ² recomputed from the tables and the simulated rows equals the fit's.
    let ds = Dataset::load(Path::new(dataset)).unwrap();
    let lik = FitLikelihood::from_fit(&ds, &fit).unwrap();
    let b = lik.breakdown(&lik.estimate()).unwrap();
    let values: Vec<f64> = column(&meas, "measurement")
        .iter()
        .map(|v| v.parse().unwrap())
        .collect();
    let mut chi2_rows = 0.0;
    for c in &b.channels {
        let name = format!("{} {}", c.file, c.column);
        let k = column(&obs, "observableName")
            .iter()
            .position(|n| *n == name)
            .unwrap();
        let id = obs_ids[k];
        let sigma: f64 = column(&obs, "noiseFormula")[k].parse().unwrap();
        let formula = column(&obs, "observableFormula")[k];
        let rows: Vec<usize> = column(&meas, "observableId")
            .iter()
            .enumerate()
            .filter(|(_, o)| **o == id)
            .map(|(i, _)| i)
            .collect();
        assert_eq!(rows.len(), c.rows.len(), "{name}");
        let extra = column(&meas, "observableParameters");
        for (n, &i) in rows.iter().enumerate() {
            assert_eq!(values[i], c.data[n]);
            // y_model + Σ β_k·a_k: the plain offsets, then the per-row terms in order.
            let mut y = c.simulated[n];
            let mut per_row = extra[i].split(';').filter(|s| !s.is_empty());
            for term in formula.split(" + ").skip(1) {
                let (beta_id, scaled) = match term.split_once(" * ") {
                    Some((p, _)) => (p, per_row.next().unwrap().parse::<f64>().unwrap()),
                    None => (term, 1.0),
                };
                let beta: f64 = nominal[table[beta_id]].parse().unwrap();
                y += beta * scaled;
            }
            chi2_rows += ((values[i] - y) / sigma).powi(2);
        }
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("vanefit_export.json")).unwrap())
            .unwrap();
    // A page's power-peak term is no table's (the export says so); the summary states it
    // where a page has one.
    let peaks = summary["chi2_power_peaks"].as_f64().unwrap_or(0.0);
    let want = stats.likelihood_chi2.unwrap();
    let got = chi2_rows + chi2_priors + peaks;
    assert!(
        ((got - want) / want).abs() < 1e-9,
        "tables' chi2 {got} vs fit's {want}"
    );
    // With the motor priors: the fit's objective, as the summary states it.
    let objective = want + stats.prior_chi2.unwrap_or(0.0);
    let total = got + chi2_motor;
    assert!(
        ((total - objective) / objective).abs() < 1e-9,
        "tables' objective {total} vs fit's {objective}"
    );
    let stated = summary["objective"].as_f64().unwrap();
    assert!(((stated - objective) / objective).abs() < 1e-9, "{stated}");
    chi2_motor
}

#[test]
fn export_refuses_bad_input_with_exit_status_1() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A missing fit file: named.
    let o = vanefit_in(&["export-petab", "nope.json", "--out", "x"], d);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("nope.json"));
    // A fit file of plain parameters (no statistics): says it was not written by a fit.
    std::fs::write(
        d.join("plain.json"),
        "{\"format\": \"vanefit.fit/1\", \"dataset\": \"ar034-synthetic\", \"parameters\": {\"c_in1\": 7e-9}}\n",
    )
    .unwrap();
    let ds = std::fs::canonicalize(DATASET).unwrap();
    let o = vanefit_in(
        &[
            "export-petab",
            "plain.json",
            "--dataset",
            ds.to_str().unwrap(),
            "--out",
            "y",
        ],
        d,
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("vanefit fit"));
    assert!(!d.join("y").exists(), "nothing written on failure");
    // --out naming a file.
    std::fs::write(d.join("afile"), "x").unwrap();
    let o = vanefit_in(&["export-petab", "plain.json", "--out", "afile"], d);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--out afile"));
}

/// Without `--dataset`, the export finds the dataset the fit file records (`dataset_path`)
/// as `predict` does, also where no `measurements/` folder would lead to it; a recorded path
/// that no longer holds the dataset is an error naming `--dataset`, exit status 1.
#[test]
fn export_finds_the_dataset_the_fit_file_records() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let data = d.join("rig-logs").join("ar034-synthetic-catalogue");
    std::fs::create_dir_all(&data).unwrap();
    for entry in std::fs::read_dir(CATALOGUE).unwrap() {
        let entry = entry.unwrap();
        std::fs::copy(entry.path(), data.join(entry.file_name())).unwrap();
    }
    std::fs::create_dir_all(d.join("fits").join("page")).unwrap();
    let fit = d.join("fits").join("page").join("fit.json");
    let o = vanefit(&[
        "fit",
        data.to_str().unwrap(),
        "--starts",
        "2",
        "--no-plots",
        "--out",
        fit.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = vanefit_in(&["export-petab", "fits/page/fit.json", "--out", "petab"], d);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(d.join("petab").join("problem.yaml").is_file());
    // The recorded folder gone: refused, naming the option that names a dataset.
    std::fs::rename(&data, d.join("moved")).unwrap();
    let o = vanefit_in(
        &["export-petab", "fits/page/fit.json", "--out", "petab2"],
        d,
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--dataset"), "{}", stderr(&o));
    assert!(stderr(&o).contains("dataset_path"), "{}", stderr(&o));
}

#[test]
fn fit_file_profiles_round_trip_and_bad_ones_are_located() {
    let good = r#"{
  "format": "vanefit.fit/1",
  "parameters": { "c_in1": { "value": 7e-9, "estimated": true } },
  "profiles": {
    "c_in1": { "value": [6.9e-9, 7e-9, 7.1e-9], "delta_chi2": [4.1, 0.0, 3.9] }
  }
}
"#;
    let f = FitFile::parse(Path::new("p.json"), good).unwrap();
    assert_eq!(f.profiles.len(), 1);
    assert_eq!(f.profiles[0].parameter, "c_in1");
    assert_eq!(f.profiles[0].delta_chi2, vec![4.1, 0.0, 3.9]);
    let again = FitFile::parse(Path::new("q.json"), &f.to_json().to_string()).unwrap();
    assert_eq!(again.profiles, f.profiles);
    for (bad, says) in [
        (
            good.replace("[4.1, 0.0, 3.9]", "[4.1, 0.0]"),
            "2 delta_chi2",
        ),
        (
            good.replace("[6.9e-9, 7e-9, 7.1e-9]", "[7.1e-9, 7e-9, 6.9e-9]"),
            "increasing",
        ),
        (good.replace("\"delta_chi2\"", "\"chi2\""), "delta_chi2"),
    ] {
        let e = FitFile::parse(Path::new("p.json"), &bad).unwrap_err();
        assert_eq!(e.line, Some(5), "{e}");
        assert!(e.to_string().contains(says), "{e}");
    }
}

#[test]
fn a_fit_draws_its_profiles_and_its_parameters_across_starts() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("f.json");
    let o = vanefit(&[
        "fit",
        DATASET,
        "--starts",
        "3",
        "--seed",
        "4",
        "--estimate",
        "c_in1,c_ext,t_coulomb",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let profiles = doc["profiles"].as_object().unwrap();
    assert_eq!(
        profiles.keys().collect::<Vec<_>>(),
        ["c_in1", "c_ext", "t_coulomb"]
    );
    let report = std::fs::read_to_string(dir.path().join("f.report.md")).unwrap();
    for (file, what) in [
        ("f.profiles.svg", "Δχ²"),
        ("f.parameters.svg", "start (by final cost)"),
    ] {
        let svg = std::fs::read_to_string(dir.path().join(file)).unwrap();
        assert!(svg.contains(what), "{file}");
        for p in ["c_in1", "c_ext", "t_coulomb"] {
            assert!(svg.contains(p), "{file} lacks {p}");
        }
        assert!(report.contains(file), "the report does not show {file}");
    }
    // Each path holds the estimate at Δχ² = 0 and rises past the threshold on both sides.
    let t = doc["statistics"]["profile_threshold"].as_f64().unwrap();
    for (name, p) in profiles {
        let d: Vec<f64> = p["delta_chi2"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let i = d
            .iter()
            .position(|v| *v == 0.0)
            .expect("estimate on the path");
        assert!(d[..i].iter().any(|v| *v > t), "{name}: no rise below");
        assert!(d[i + 1..].iter().any(|v| *v > t), "{name}: no rise above");
    }
}
