"""`vanefit export-petab` checked by the PEtab community's own tools: the real `petablint`
on the export, and `petab.calculate_chi2` on the exported tables with vanefit's simulation
plus the priors the parameter table states (the nuisances' and the motor's) against the
fit's own objective, for a rig fit and a catalogue-page fit."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import vanefit
import vanefit.petab as vpetab
from conftest import CATALOGUE, DATASET, run_cli, vanefit_bin


def petablint(yaml: Path) -> subprocess.CompletedProcess:
    """The linter as users run it (the console script of the `petab` package)."""
    exe = Path(sys.executable).with_name("petablint")
    return subprocess.run([str(exe), "-v", str(yaml)], capture_output=True, text=True)


@pytest.fixture(scope="module", params=["cli_fit", "profile_fit", "page_fit"])
def export(request, tmp_path_factory):
    """The fits exported by the command line: (fit file, export folder, dataset)."""
    fit = request.getfixturevalue(request.param)
    dataset = CATALOGUE if request.param == "page_fit" else DATASET
    out = tmp_path_factory.mktemp("petab")
    p = run_cli("export-petab", fit, "--dataset", dataset, "--out", out)
    assert "measurements" in p.stdout
    return fit, out, dataset


def test_petablint_accepts_the_export(export):
    _, out, _ = export
    p = petablint(out / "problem.yaml")
    text = p.stdout + p.stderr
    assert p.returncode == 0, text
    assert "PEtab format check completed successfully" in text, text
    # The model was checked too, not skipped.
    assert "Checking model" in text and "Model not available" not in text, text


def test_petab_chi2_with_vanefits_simulation_is_the_fits_objective(export):
    fit, out, dataset = export
    doc = json.loads(Path(fit).read_text())
    want = doc["statistics"]["likelihood_chi2"]
    motor = doc["statistics"]["prior_chi2"]
    assert motor > 0, "every fit made with default options carries the motor prior"
    got = vpetab.chi2(out / "problem.yaml")
    summary = json.loads((out / "vanefit_export.json").read_text())
    # A page's power-peak term is no PEtab table's: the export's summary states it apart
    # (`chi2_power_peaks`, where a page has one).
    peaks = summary.get("chi2_power_peaks", 0.0)
    # Rows + nuisance priors (+ peaks): the likelihood; + the motor prior: the objective.
    assert abs(got["likelihood"] + peaks - want) <= 1e-9 * want, (got, peaks, want)
    assert abs(got["motor_priors"] - motor) <= 1e-9 * motor, (got, motor)
    total = want + motor
    assert abs(got["total"] + peaks - total) <= 1e-9 * total, (got, peaks, want, motor)
    # The rows' part is petab's own calculate_chi2; the nuisances' priors are the rest.
    ds = vanefit.load_dataset(dataset)
    lik = vanefit.Likelihood(ds, fit)
    b = lik.breakdown(np.array([doc["parameters"][n]["value"] for n in lik.names]))
    assert abs(got["rows"] - b["chi2_data"]) <= 1e-9 * b["chi2_data"]
    assert abs(got["priors"] - b["chi2_prior"]) <= 1e-9 * max(b["chi2_prior"], 1e-12)
    assert abs(b["objective"] - (want + motor)) <= 1e-9 * (want + motor)
    assert abs(summary["chi2"] - want) <= 1e-9 * want
    assert abs(summary["objective"] - (want + motor)) <= 1e-9 * (want + motor)


def test_motor_priors_are_the_fit_files_as_petab_reads_them(export):
    """Each prior of the fit file is in the parameter table, and petab's own Prior
    (parsed from the table row) has −ln p = ½((ln v − ln m)/σ)² + its normalisation and
    Jacobian: the table says what the fit file says, on the scale PEtab reads it."""
    from petab.v1.priors import Prior

    fit, out, _ = export
    doc = json.loads(Path(fit).read_text())
    table = pd.read_csv(out / "parameters.tsv", sep="\t").set_index("parameterId")
    entries = doc["statistics"]["prior"]
    assert entries
    for e in entries:
        row = table.loc[e["parameter"]].to_dict()
        kind = "parameterScaleNormal" if row["parameterScale"] == "log10" else "logNormal"
        assert row["objectivePriorType"] == kind, (e, row)
        prior = Prior.from_par_dict(row, "objective", _bounds_truncate=False)
        v = float(row["nominalValue"])
        z2 = ((np.log(v) - np.log(e["median"])) / e["sd_ln"]) ** 2
        # Both kinds are, to petab, a log-normal density of the linear value v: the
        # normal density of log10 v (or ln v) times its Jacobian 1/(v·ln 10) (1/v).
        sd = float(row["objectivePriorParameters"].split(";")[1])
        jac = np.log(v * np.log(10)) if kind == "parameterScaleNormal" else np.log(v)
        const = np.log(sd * np.sqrt(2 * np.pi)) + jac
        assert prior.neglogprior(v) - const == pytest.approx(0.5 * z2, rel=1e-9, abs=1e-12), e
    # Parameters without a fit-file prior carry none (the nuisances' are normal).
    others = table[~table.index.isin([e["parameter"] for e in entries])]
    assert set(others["objectivePriorType"].dropna()) <= {"normal"}


def test_tables_hold_every_compared_row_with_its_noise(export):
    fit, out, dataset = export
    if dataset != DATASET:
        pytest.skip("the rig dataset's recordings are checked row by row")
    m = pd.read_csv(out / "measurements.tsv", sep="\t")
    obs = pd.read_csv(out / "observables.tsv", sep="\t").set_index("observableId")
    cond = pd.read_csv(out / "conditions.tsv", sep="\t").set_index("conditionId")
    ds = vanefit.load_dataset(DATASET)
    lik = vanefit.Likelihood(ds, fit)
    b = lik.breakdown(lik.x_hat)
    assert len(m) == sum(len(c["rows"]) for c in b["channels"])
    for c in b["channels"]:
        row = obs[obs["observableName"] == f"{c['file']} {c['column']}"]
        assert len(row) == 1
        assert float(row["noiseFormula"].iloc[0]) == c["sigma"]
        sel = m[m["observableId"] == row.index[0]]
        np.testing.assert_array_equal(sel["measurement"].to_numpy(), c["data"])
    # Steady-state rows are at steady state, one condition per datasheet row with its speed.
    steady = m[m["datasetId"] == "datasheet"]
    assert np.isinf(steady["time"]).all()
    rec = ds.recording("datasheet.csv")
    for cid in steady["simulationConditionId"].unique():
        r = int(cid.rsplit("_r", 1)[1])
        assert cond.loc[cid, "omega_rad_s"] == pytest.approx(rec["speed_rpm"][r] * np.pi / 30, rel=1e-12)
    # Transient rows at their recorded times.
    ramp = m[m["datasetId"] == "ramp"]
    assert set(ramp["time"]) <= set(ds.recording("ramp.csv")["t_s"])


def test_the_export_from_python_equals_the_clis(export, tmp_path):
    fit, out, dataset = export
    s = vanefit.export_petab(fit, tmp_path / "py", dataset=dataset)
    assert Path(s["yaml"]).is_file()
    for name in ("parameters.tsv", "observables.tsv", "measurements.tsv", "conditions.tsv", "model.xml"):
        assert (tmp_path / "py" / name).read_text() == (out / name).read_text(), name


def test_export_errors_name_the_file_or_option(tmp_path, cli_fit):
    # A fit file whose dataset cannot be found: says where it looked and what to give.
    lone = tmp_path / "lone" / "fit.json"
    lone.parent.mkdir()
    lone.write_text(Path(cli_fit).read_text())
    p = subprocess.run([vanefit_bin(), "export-petab", str(lone), "--out", str(tmp_path / "x")],
                       cwd=tmp_path, capture_output=True, text=True)
    assert p.returncode == 1 and "--dataset" in p.stderr, p.stderr
    assert not (tmp_path / "x").exists()
    # A file that is no fit file.
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "vanefit.fit/1", "parameters": {"c_in1": {"value": "x"}}}\n')
    p = run_cli("export-petab", bad, "--dataset", DATASET, "--out", tmp_path / "y", check=False)
    assert p.returncode == 1 and str(bad) in p.stderr and ":1:" in p.stderr, p.stderr
    with pytest.raises(vanefit.DataError, match="dataset="):
        here = os.getcwd()
        os.chdir(tmp_path)
        try:
            vanefit.export_petab(lone, tmp_path / "z")
        finally:
            os.chdir(here)
