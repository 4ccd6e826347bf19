"""The Python package against the command line: same cost, same fit for the same seed,
same simulation, the documented exceptions with the CLI's located messages."""

import json
import math

import numpy as np
import pandas as pd
import pytest

import vanefit
from conftest import DATASET, run_cli


@pytest.fixture(scope="module")
def ds():
    return vanefit.load_dataset(DATASET)


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def test_dataset_reads_as_written(ds):
    assert ds.name == "ar034-synthetic"
    assert [e["file"] for e in ds.experiments] == ["datasheet.csv", "ramp.csv", "throttle.csv"]
    ramp = ds.recording("ramp.csv")
    csv = pd.read_csv(DATASET / "ramp.csv")
    assert list(ramp) == list(csv.columns)
    for c in csv.columns:
        np.testing.assert_array_equal(ramp[c], csv[c].to_numpy(dtype=float))
    with pytest.raises(vanefit.ParameterError, match="no such recording"):
        ds.recording("nope.csv")


def test_cost_equals_the_cli_fit_files_cost(ds, cli_fit):
    doc = json.loads(cli_fit.read_text())
    c = vanefit.cost(ds, cli_fit)
    assert rel(c["cost"], doc["cost"]) < 1e-12, (c["cost"], doc["cost"])
    assert c["n_points"] == sum(ch["n"] for ch in c["channels"])
    # J is the weighted sum of its channel terms.
    assert rel(sum(ch["cost"] for ch in c["channels"]), c["cost"]) < 1e-12
    # The same parameters given as a dict give the same cost.
    values = {k: v["value"] for k, v in doc["parameters"].items()}
    assert rel(vanefit.cost(ds, values)["cost"], doc["cost"]) < 1e-12
    # ... and another motor another cost.
    values["c_in1"] *= 1.2
    assert vanefit.cost(ds, values)["cost"] > doc["cost"] * 1.01


def test_fit_from_python_equals_the_cli_fit(ds, cli_fit, tmp_path):
    calls = []
    out = tmp_path / "py.json"
    py = vanefit.fit(ds, starts=3, seed=5, max_iters=150, uncertainty="curvature",
                     out=out, progress=lambda done, total, best: calls.append((done, total, best)))
    cli = json.loads(cli_fit.read_text())
    for k in ("parameters", "cost", "statistics", "covariance", "starts", "seed", "conditions"):
        assert py[k] == cli[k], k
    assert json.loads(out.read_text())["parameters"] == cli["parameters"]
    assert [c[0] for c in calls] == [1, 2, 3] and all(c[1] == 3 for c in calls)
    bests = [c[2] for c in calls]
    assert bests == sorted(bests, reverse=True)
    starts = pd.DataFrame(py["start_results"])
    assert len(starts) == 3 and set(starts["ending"]) <= {"converged", "budget", "stopped_early", "joined"}
    assert min(starts["cost"]) == pytest.approx(py["statistics"]["best_start_cost"], rel=1e-12)


def test_thread_count_does_not_change_the_fit(ds):
    one = vanefit.fit(ds, starts=2, seed=9, max_iters=80, uncertainty="none", threads=1)
    two = vanefit.fit(ds, starts=2, seed=9, max_iters=80, uncertainty="none", threads=2)
    assert one["parameters"] == two["parameters"] and one["cost"] == two["cost"]


def test_simulate_equals_the_cli_simulation(ds, cli_fit, tmp_path):
    run_cli("simulate", DATASET, "--params", cli_fit, "--out", tmp_path)
    sim = vanefit.simulate(ds, cli_fit)
    assert set(sim) == {"datasheet.csv", "ramp.csv", "throttle.csv"}
    for file, table in sim.items():
        csv = pd.read_csv(tmp_path / file)
        assert list(table) == list(csv.columns)
        for c in csv.columns:
            # The CLI prints 7 significant digits.
            np.testing.assert_allclose(table[c], csv[c].to_numpy(dtype=float), rtol=1e-6, atol=0)
        assert len(pd.DataFrame(table)) == len(csv)


def test_likelihood_is_the_fits_own(ds, cli_fit):
    doc = json.loads(cli_fit.read_text())
    lik = vanefit.likelihood(ds, cli_fit)
    est = [n for n, p in doc["parameters"].items() if p["estimated"]]
    assert lik.names == est
    x = lik.x_hat
    assert rel(lik.chi2(x), doc["statistics"]["likelihood_chi2"]) < 1e-9
    assert lik.chi2_min == doc["statistics"]["likelihood_chi2"]
    assert lik.threshold == doc["statistics"]["profile_threshold"]
    b = lik.breakdown(x)
    assert rel(b["chi2_data"] + b["chi2_prior"], lik.chi2(x)) < 1e-12
    assert sum(len(c["rows"]) for c in b["channels"]) == doc["statistics"]["n_points"]
    assert np.all(lik.lower < x) and np.all(x < lik.upper)
    y = x.copy()
    y[0] *= 1.01
    assert lik(y) > lik(x)
    y[0] = -1.0
    assert math.isfinite(lik(y)) and lik(y) > 1e6
    with pytest.raises(vanefit.ParameterError):
        lik.chi2(y)
    with pytest.raises(vanefit.ParameterError, match="parameter values given"):
        lik.chi2(x[:2])


def test_bad_datasets_raise_data_error_with_the_clis_message(tmp_path):
    bad = tmp_path / "bad"
    bad.mkdir()
    for f in ("datasheet.csv", "ramp.csv", "throttle.csv"):
        (bad / f).write_text((DATASET / f).read_text())
    rig = (DATASET / "rig.toml").read_text()
    (bad / "rig.toml").write_text(rig.replace("vanes = 5", "vanes = \"five\""))
    cli = run_cli("check", bad, check=False)
    assert cli.returncode == 1
    with pytest.raises(vanefit.DataError) as e:
        vanefit.load_dataset(bad)
    assert str(e.value) in cli.stderr
    assert "rig.toml" in str(e.value) and ":" in str(e.value)

    (bad / "rig.toml").write_text(rig)
    lines = (DATASET / "ramp.csv").read_text().splitlines()
    cells = lines[5].split(",")
    cells[2] = "abc"
    lines[5] = ",".join(cells)
    (bad / "ramp.csv").write_text("\n".join(lines) + "\n")
    cli = run_cli("check", bad, check=False)
    with pytest.raises(vanefit.DataError) as e:
        vanefit.load_dataset(bad)
    assert str(e.value) in cli.stderr
    assert "ramp.csv:6:" in str(e.value), str(e.value)


def test_bad_parameters_raise_parameter_error(ds, tmp_path):
    with pytest.raises(vanefit.ParameterError, match="c_nope"):
        vanefit.cost(ds, {"c_nope": 1e-9})
    with pytest.raises(vanefit.ParameterError, match="c_in1"):
        vanefit.simulate(ds, {"c_in1": -1e-9})
    with pytest.raises(vanefit.ParameterError):
        vanefit.cost(ds, {"c_in1": "many"})
    with pytest.raises(vanefit.ParameterError, match="starts"):
        vanefit.fit(ds, starts=0)
    with pytest.raises(vanefit.ParameterError, match="uncertainty"):
        vanefit.fit(ds, starts=1, uncertainty="maybe")
    with pytest.raises(vanefit.ParameterError, match="nope"):
        vanefit.fit(ds, starts=1, estimate=["nope"])
    with pytest.raises(vanefit.DataError):
        vanefit.read_fit(tmp_path / "missing.json")
    (tmp_path / "broken.json").write_text('{"format": "vanefit.fit/1", "parameters": 3}')
    with pytest.raises(vanefit.DataError, match="broken.json"):
        vanefit.read_fit(tmp_path / "broken.json")


def test_a_failing_progress_callback_is_raised_after_the_fit(ds):
    calls = []

    def progress(done, total, best):
        calls.append(done)
        raise RuntimeError("callback failed")

    with pytest.raises(RuntimeError, match="callback failed"):
        vanefit.fit(ds, starts=2, seed=3, max_iters=40, uncertainty="none", progress=progress)
    assert calls == [1]


def test_predict_control_and_synth_tables(cli_fit, tmp_path):
    p = vanefit.predict(cli_fit, pressures=[4, 6.3], out=tmp_path / "pred")
    cat = pd.DataFrame(p["catalogue"])
    assert len(cat) == 2 and cat["free_speed_rpm"].iloc[1] > cat["free_speed_rpm"].iloc[0]
    assert {"factors", "curves"} <= set(p)
    with pytest.raises(vanefit.ParameterError, match="unit"):
        vanefit.predict(cli_fit, unit="furlongs")
    d = vanefit.control("design", params=cli_fit, pm_deg=55)
    assert abs(d["design"]["designed"]["phase_margin_deg"] - 55) < 0.5
    assert len(d["design_step"]["speed_rpm"]) > 100
    with pytest.raises(vanefit.ParameterError, match="--kp"):
        vanefit.control("bode", kp=1.0)
    new = vanefit.synth(tmp_path / "synth", params=cli_fit, noise=0.0, seed=4)
    assert [e["kind"] for e in new.experiments] == ["datasheet", "pressure_ramp", "outlet_throttle"]
    # Noise-free data of the fitted motor: the fit's parameters simulate what was written.
    sim, rec = vanefit.simulate(new, cli_fit)["ramp.csv"], new.recording("ramp.csv")
    for c in ("speed_rpm", "flow1_g_s"):
        np.testing.assert_allclose(sim[c], rec[c], rtol=1e-4, atol=1e-3 * np.abs(rec[c]).max())


def test_fit_documents_in_memory_are_parameters(ds, cli_fit, tmp_path):
    """A fit read into memory (or returned without a file) simulates and costs like its file,
    and the temporary file it goes through is removed."""
    import glob
    import tempfile

    doc = vanefit.read_fit(cli_fit)
    before = set(glob.glob(f"{tempfile.gettempdir()}/vanefit-fit-*"))
    assert vanefit.cost(ds, doc)["cost"] == vanefit.cost(ds, cli_fit)["cost"]
    a, b = vanefit.simulate(ds, doc), vanefit.simulate(ds, cli_fit)
    for file in a:
        for col in a[file]:
            np.testing.assert_array_equal(a[file][col], b[file][col])
    assert set(glob.glob(f"{tempfile.gettempdir()}/vanefit-fit-*")) == before
    # A malformed document is refused like a malformed file.
    bad = dict(doc, parameters={"c_in1": {"value": "x"}})
    with pytest.raises(vanefit.DataError, match="c_in1"):
        vanefit.cost(ds, bad)
