"""`vanefit export-petab` checked by the PEtab community's own tools: the real `petablint`
on the export, and `petab.calculate_chi2` on the exported tables with vanefit's simulation
against the fit's own χ²."""

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
from conftest import DATASET, run_cli, vanefit_bin


def petablint(yaml: Path) -> subprocess.CompletedProcess:
    """The linter as users run it (the console script of the `petab` package)."""
    exe = Path(sys.executable).with_name("petablint")
    return subprocess.run([str(exe), "-v", str(yaml)], capture_output=True, text=True)


@pytest.fixture(scope="module", params=["cli_fit", "profile_fit"])
def export(request, tmp_path_factory):
    """Both fits exported by the command line: (fit file, export folder)."""
    fit = request.getfixturevalue(request.param)
    out = tmp_path_factory.mktemp("petab")
    p = run_cli("export-petab", fit, "--dataset", DATASET, "--out", out)
    assert "measurements" in p.stdout
    return fit, out


def test_petablint_accepts_the_export(export):
    _, out = export
    p = petablint(out / "problem.yaml")
    text = p.stdout + p.stderr
    assert p.returncode == 0, text
    assert "PEtab format check completed successfully" in text, text
    # The model was checked too, not skipped.
    assert "Checking model" in text and "Model not available" not in text, text


def test_petab_chi2_with_vanefits_simulation_is_the_fits_chi2(export):
    fit, out = export
    doc = json.loads(Path(fit).read_text())
    want = doc["statistics"]["likelihood_chi2"]
    got = vpetab.chi2(out / "problem.yaml")
    assert abs(got["total"] - want) <= 1e-9 * want, (got, want)
    # The rows' part is petab's own calculate_chi2; the nuisances' priors are the rest.
    ds = vanefit.load_dataset(DATASET)
    b = vanefit.Likelihood(ds, fit).breakdown(np.array(
        [doc["parameters"][n]["value"] for n in vanefit.Likelihood(ds, fit).names]))
    assert abs(got["rows"] - b["chi2_data"]) <= 1e-9 * b["chi2_data"]
    assert abs(got["priors"] - b["chi2_prior"]) <= 1e-9 * max(b["chi2_prior"], 1e-12)
    summary = json.loads((out / "vanefit_export.json").read_text())
    assert abs(summary["chi2"] - want) <= 1e-9 * want


def test_tables_hold_every_compared_row_with_its_noise(export):
    fit, out = export
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
    fit, out = export
    s = vanefit.export_petab(fit, tmp_path / "py", dataset=DATASET)
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
