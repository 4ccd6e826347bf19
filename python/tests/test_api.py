"""The Python package against the command line: same cost, same fit for the same seed,
same simulation, the documented exceptions with the CLI's located messages."""

import json
import math
import os

import numpy as np
import pandas as pd
import pytest

import vanefit
from conftest import DATASET, ROOT, run_cli


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


@pytest.fixture(scope="module")
def cli_fit_without_prior(tmp_path_factory):
    """The short CLI fit of the `cli_fit` fixture without the motor prior: its file's cost is
    then J alone (with the prior it adds χ²_prior/n, which `vanefit.cost` does not)."""
    out = tmp_path_factory.mktemp("cli_no_prior") / "fit.json"
    run_cli("fit", DATASET, "--starts", 3, "--seed", 5, "--max-iters", 150, "--priors", "none",
            "--uncertainty", "curvature", "--no-plots", "--out", out)
    return out


def test_cost_equals_the_cli_fit_files_cost(ds, cli_fit_without_prior):
    cli_fit = cli_fit_without_prior
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
    assert isinstance(py, vanefit.Fit) and py.path == str(out)
    cli = json.loads(cli_fit.read_text())
    doc = py.document
    for k in ("parameters", "cost", "statistics", "covariance", "starts", "seed", "conditions"):
        assert doc[k] == cli[k], k
    # Both record the dataset's folder relative to their own (what predict samples on).
    for path, d in ((out, doc), (cli_fit, cli)):
        assert (path.parent / d["dataset_path"]).resolve() == DATASET.resolve()
    # What Python wrote is the fit's own text, and it reads back as the same fit.
    assert out.read_text() == py.to_json()
    assert vanefit.Fit.read(out).document == doc
    # The run begins (0 done, no best yet), then every start once.
    assert [c[0] for c in calls] == [0, 1, 2, 3] and all(c[1] == 3 for c in calls)
    assert calls[0][2] == math.inf
    bests = [c[2] for c in calls[1:]]
    assert bests == sorted(bests, reverse=True)
    starts = py.starts
    assert len(starts) == 3 and set(starts["ending"]) <= {"converged", "budget", "stopped_early", "joined"}
    assert set(py.estimated) <= set(starts.columns)
    assert starts["cost"].min() == pytest.approx(py.statistics.best_start_cost, rel=1e-12)


def test_fit_file_reads_and_writes_byte_for_byte(cli_fit, tmp_path):
    """A fit file the command line wrote: read, shown as tables, written back unchanged."""
    f = vanefit.Fit.read(cli_fit)
    assert f.to_json() == cli_fit.read_text()
    f.write(tmp_path / "copy.json")
    assert (tmp_path / "copy.json").read_bytes() == cli_fit.read_bytes()
    doc = json.loads(cli_fit.read_text())
    p = f.parameters
    assert list(p.index) == list(doc["parameters"])
    assert list(p.columns) == ["value", "lower", "upper", "unit", "estimated", "identifiable", "meaning"]
    for name, entry in doc["parameters"].items():
        assert p.loc[name, "value"] == entry["value"] and p.loc[name, "unit"] == entry["unit"]
        if entry.get("ci95"):
            assert [p.loc[name, "lower"], p.loc[name, "upper"]] == entry["ci95"]
        else:
            assert np.isnan(p.loc[name, "lower"])
    assert p.loc["c_in1", "meaning"] == "inlet port"
    s = f.statistics
    assert s.chi2 == doc["statistics"]["chi2"] and s.dof == doc["statistics"]["dof"]
    assert s.cost == doc["cost"] and s.noise_ratio == doc["statistics"]["noise_ratio"]
    assert f"chi2 {s.chi2:.1f}" in str(s)
    assert f.starts.empty and not f.has_starts
    # A file that is no fit file is refused with its name and line.
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "vanefit.fit/1", "parameters": 3}')
    with pytest.raises(vanefit.DataError, match="bad.json"):
        vanefit.Fit.read(bad)
    with pytest.raises(vanefit.DataError):
        vanefit.Fit.from_json('{"format": "vanefit.fit/2"}')


def test_profiles_are_dataframes(profile_fit):
    f = vanefit.Fit.read(profile_fit)
    doc = json.loads(profile_fit.read_text())
    assert set(f.profiles) == set(doc["profiles"]) == set(f.estimated)
    for name, table in f.profiles.items():
        assert list(table.columns) == ["value", "delta_chi2"]
        np.testing.assert_array_equal(table["value"], doc["profiles"][name]["value"])
        assert table["delta_chi2"].min() == 0.0
    cov = f.covariance
    assert cov is None or list(cov.index) == doc["covariance"]["parameters"]


def test_thread_count_does_not_change_the_fit(ds):
    one = vanefit.fit(ds, starts=2, seed=9, max_iters=80, uncertainty="none", threads=1)
    two = vanefit.fit(ds, starts=2, seed=9, max_iters=80, uncertainty="none", threads=2)
    assert one.document["parameters"] == two.document["parameters"] and one.cost == two.cost


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
    # The same from the Fit object in memory.
    assert vanefit.likelihood(ds, vanefit.Fit.read(cli_fit)).chi2_min == lik.chi2_min
    est = [n for n, p in doc["parameters"].items() if p["estimated"]]
    assert lik.names == est
    x = lik.x_hat
    # By default the fit's objective: the likelihood plus the motor prior it was made with.
    st = doc["statistics"]
    objective = st["likelihood_chi2"] + st["prior_chi2"]
    assert lik.priors and st["prior_chi2"] > 0
    assert rel(lik.chi2(x), objective) < 1e-9
    assert rel(lik.chi2_min, objective) < 1e-15
    alone = vanefit.likelihood(ds, cli_fit, priors=False)
    assert rel(alone.chi2(x), st["likelihood_chi2"]) < 1e-9
    assert alone.chi2_min == st["likelihood_chi2"]
    assert rel(lik.prior_chi2(x), st["prior_chi2"]) < 1e-9
    assert lik.threshold == doc["statistics"]["profile_threshold"]
    b = lik.breakdown(x)
    assert rel(b["chi2_data"] + b["chi2_prior"], alone.chi2(x)) < 1e-12
    assert rel(b["objective"], lik.chi2(x)) < 1e-12
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


def test_a_failing_progress_callback_stops_the_fit_and_is_raised(ds):
    calls = []

    def progress(done, total, best):
        calls.append(done)
        raise RuntimeError("callback failed")

    with pytest.raises(RuntimeError, match="callback failed"):
        vanefit.fit(ds, starts=2, seed=3, max_iters=40, uncertainty="none", progress=progress)
    assert calls == [0]  # called once, when the run began; never again
    with pytest.raises(vanefit.ParameterError, match="progress"):
        vanefit.fit(ds, starts=1, progress="yes")


def test_progress_true_draws_a_tqdm_bar(ds, capsys):
    vanefit.fit(ds, starts=2, seed=3, max_iters=40, uncertainty="none", progress=True)
    err = capsys.readouterr().err
    assert "fit" in err and "2/2" in err, err


def _starts_recorded(out):
    """Finished starts in a fit's starts file (its first line is the run's header)."""
    side = out.with_suffix(".starts.jsonl")
    return len(side.read_text().splitlines()) - 1


def test_keyboard_interrupt_stops_the_fit_and_it_resumes(ds, tmp_path):
    """Ctrl-C (here: KeyboardInterrupt raised by the callback once a start has finished)
    stops the fit at its next round; the finished starts are in the starts file and the
    fit resumes from them to the fit an uninterrupted run makes."""
    out = tmp_path / "fit.json"
    # Nelder–Mead alone: with the hand-over every start ends in the second round, together,
    # and there would be no later round left to stop.
    opts = dict(starts=6, seed=11, max_iters=600, uncertainty="none", threads=1, handoff=False)

    def interrupt(done, total, best):
        if done >= 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        vanefit.fit(ds, out=out, progress=interrupt, **opts)
    assert not out.exists()
    done = _starts_recorded(out)
    assert 1 <= done < 6
    seen = []
    resumed = vanefit.fit(ds, out=out, resume=True, progress=lambda d, t, b: seen.append(d), **opts)
    assert seen[0] == done and seen[-1] == 6
    whole = vanefit.fit(ds, **opts)
    assert resumed.document["parameters"] == whole.document["parameters"]
    with pytest.raises(vanefit.ParameterError, match="resume"):
        vanefit.fit(ds, resume=True, **opts)


SIGINT_CHILD = """
import sys, vanefit
ds = vanefit.load_dataset(sys.argv[1])
def progress(done, total, best):
    if done >= 1:
        open(sys.argv[3], "w").close()
try:
    vanefit.fit(ds, starts=6, seed=2, max_iters=3000, uncertainty="none", threads=1,
                out=sys.argv[2], progress=progress, handoff=False)
except KeyboardInterrupt:
    print("interrupted")
    sys.exit(0)
print("finished")
"""


def test_ctrl_c_interrupts_a_running_fit(tmp_path):
    """A real SIGINT to a process in the middle of a fit (the GIL released, the work on
    vanefit's threads) raises KeyboardInterrupt within a round and leaves the finished
    starts on disk."""
    import signal
    import subprocess
    import sys
    import time

    out, marker = tmp_path / "fit.json", tmp_path / "one-start-done"
    child = subprocess.Popen([sys.executable, "-c", SIGINT_CHILD, str(DATASET), str(out), str(marker)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.time()
    while not marker.exists() and child.poll() is None and time.time() - t0 < 120:
        time.sleep(0.05)
    assert marker.exists(), child.communicate()
    child.send_signal(signal.SIGINT)
    stdout, stderr = child.communicate(timeout=600)
    assert child.returncode == 0 and stdout.strip() == "interrupted", (stdout, stderr)
    # Stopped within the run, judged by what it recorded rather than by the clock (a busy
    # machine stretches the wall time): some of its 6 starts finished, not all.
    assert not out.exists() and 1 <= _starts_recorded(out) < 6


def _tempdir_entries():
    import tempfile

    return set(os.listdir(tempfile.gettempdir()))


@pytest.fixture
def private_tmp(tmp_path_factory, monkeypatch):
    """A temporary folder of this test's own, for Python (tempfile) and for the Rust side
    (TMPDIR): the machine's /tmp is shared with whatever else runs, so only a folder of the
    test's own shows what the package left behind."""
    import tempfile

    d = tmp_path_factory.mktemp("private-tmp")
    monkeypatch.setenv("TMPDIR", str(d))
    monkeypatch.setattr(tempfile, "tempdir", str(d))
    return d


def test_predict_control_and_synth_tables(cli_fit, tmp_path, capfd, private_tmp):
    before = _tempdir_entries()
    assert before == set()
    fit = vanefit.Fit.read(cli_fit)
    p = vanefit.predict(fit, pressures=[4, 6.3], bands="delta")
    assert isinstance(p, vanefit.Prediction)
    cat = p.catalogue
    assert len(cat) == 2 and cat["free_speed_rpm"].iloc[1] > cat["free_speed_rpm"].iloc[0]
    assert len(p.factors) == 2 and len(p.curves) > 2 and p.notes and p.unit == "bar_g"
    # With out=, the command's files, and the tables are the files' own.
    q = vanefit.predict(cli_fit, pressures=[4, 6.3], out=tmp_path / "pred", bands="delta")
    for name in ("catalogue", "factors", "curves"):
        assert (tmp_path / "pred" / f"{name}.csv").read_text() == q.csv(name) == p.csv(name)
    assert (tmp_path / "pred" / "predict.md").is_file()
    with pytest.raises(vanefit.ParameterError, match="unit"):
        vanefit.predict(fit, unit="furlongs")
    d = vanefit.control("design", params=fit, pm_deg=55)
    assert isinstance(d, vanefit.StudyResult)
    assert abs(d["design"]["designed"]["phase_margin_deg"] - 55) < 0.5
    assert len(d["design_step"]["speed_rpm"]) > 100
    assert len(d.tables["design_step"]) == len(d["design_step"]["speed_rpm"])
    with pytest.raises(vanefit.ParameterError, match="kp"):
        vanefit.control("bode", kp=1.0)
    new = vanefit.synth(tmp_path / "synth", params=fit, noise=0.0, seed=4)
    assert [e["kind"] for e in new.experiments] == ["datasheet", "pressure_ramp", "outlet_throttle"]
    # Noise-free data of the fitted motor: the fit's parameters simulate what was written.
    sim, rec = vanefit.simulate(new, fit)["ramp.csv"], new.recording("ramp.csv")
    for c in ("speed_rpm", "flow1_g_s"):
        np.testing.assert_allclose(sim[c], rec[c], rtol=1e-4, atol=1e-3 * np.abs(rec[c]).max())
    # Nothing printed, nothing left in the temporary folder.
    captured = capfd.readouterr()
    assert captured.out == "", captured.out
    assert _tempdir_entries() == before


def test_fits_in_memory_are_parameters(ds, cli_fit, private_tmp):
    """A Fit held in memory simulates and costs like its file, without temporary files."""
    before = _tempdir_entries()
    assert before == set()
    fit = vanefit.Fit.from_json(cli_fit.read_text())
    assert fit.path is None
    assert vanefit.cost(ds, fit)["cost"] == vanefit.cost(ds, cli_fit)["cost"]
    a, b = vanefit.simulate(ds, fit), vanefit.simulate(ds, cli_fit)
    for file in a:
        for col in a[file]:
            np.testing.assert_array_equal(a[file][col], b[file][col])
    assert _tempdir_entries() == before
    # A malformed document is refused like a malformed file.
    bad = dict(fit.document, parameters={"c_in1": {"value": "x"}})
    with pytest.raises(vanefit.DataError, match="c_in1"):
        vanefit.cost(ds, bad)


@pytest.mark.parametrize("study", sorted(vanefit.CONTROL_STUDIES))
def test_control_options_are_the_commands(study):
    """Every option of `vanefit control <study>` (but --params, --out) is an option of
    vanefit.control with the same default, and no other."""
    import re

    text = run_cli("control", study, "--help").stdout
    cli, current = {}, None
    for line in text.splitlines():
        m = re.match(r"\s+--([a-z0-9-]+)(?: <[A-Z0-9_]+>)?", line)
        if m:
            current = m.group(1).replace("-", "_")
            cli[current] = None
        d = re.search(r"\[default: ([^\]]+)\]", line)
        if d and current:
            cli[current] = d.group(1)
    for name in ("params", "out", "help"):
        cli.pop(name, None)
    ours = vanefit.CONTROL_STUDIES[study]
    assert set(cli) == set(ours)
    for name, default in cli.items():
        if default is None:
            assert ours[name] is None, name
        elif isinstance(ours[name], str):
            assert ours[name] == default, name
        else:
            assert ours[name] == pytest.approx(float(default), rel=1e-12), name


def test_control_takes_a_fit_in_memory_as_its_signature_says(tmp_path):
    """control(study, fit) with a Fit held in memory (no file behind it) runs the study on
    that fit's motor: the same tables as with the fit file's path."""
    fit_file = ROOT / "fits" / "ar034-synthetic.json"
    in_memory = vanefit.Fit.from_json(fit_file.read_text())
    assert in_memory.path is None
    options = dict(kp=1.2, ki=5.0, duration_s=1.0)
    from_memory = vanefit.control("step", in_memory, **options)
    from_path = vanefit.control("step", fit_file, **options)
    assert list(from_memory.tables) == list(from_path.tables)
    for name in from_path.tables:
        pd.testing.assert_frame_equal(from_memory.tables[name], from_path.tables[name])
    # and the motor is the fit's, not the default one
    default = vanefit.control("step", **options)
    assert not from_memory.tables["step"].equals(default.tables["step"])


def test_the_namespace_is_the_public_api():
    """The package exposes its API (__all__) and its submodules, not the typing helpers,
    numpy or json that its implementation imports."""
    import types

    public = {n for n in dir(vanefit) if not n.startswith("_")}
    modules = {n for n in public if isinstance(getattr(vanefit, n), types.ModuleType)}
    assert public - modules == set(vanefit.__all__) - {"__version__"}
    for helper in ["Any", "Dict", "List", "Optional", "Union", "Mapping", "np", "json", "os"]:
        assert not hasattr(vanefit, helper), helper
    assert callable(vanefit.export_fmu)


def test_control_files_and_tables_are_the_commands(tmp_path):
    """A study run from Python writes the command's files byte for byte, and its tables in
    memory are those files' numbers."""
    r = vanefit.control("bode", out=tmp_path / "py", points=40, p_mean_mpa=0.4)
    run_cli("control", "bode", "--points", 40, "--p-mean-mpa", 0.4, "--out", tmp_path / "cli")
    py_files = sorted(p.name for p in (tmp_path / "py").iterdir() if not p.name.startswith("."))
    cli_files = sorted(p.name for p in (tmp_path / "cli").iterdir() if not p.name.startswith("."))
    assert py_files == cli_files and any(n.endswith(".svg") for n in py_files)
    for name in cli_files:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    table = pd.read_csv(tmp_path / "cli" / "bode.csv")
    assert list(r.tables["bode"].columns) == list(table.columns)
    np.testing.assert_array_equal(r.tables["bode"].to_numpy(), table.to_numpy())
    assert r["bode_fit"] == json.loads((tmp_path / "cli" / "bode_fit.json").read_text())
    with pytest.raises(vanefit.ParameterError, match="pm_deg"):
        vanefit.control("step", pm_deg=50)
    with pytest.raises(vanefit.ParameterError, match="study"):
        vanefit.control("nope")


def test_plan_ranks_as_the_command_and_names_bad_keywords(cli_fit, tmp_path):
    """vanefit.plan is `vanefit plan`: the same plan.json, ranked by V per hour, a stall
    torque alone when asked, at the asked cost; bad keywords are named."""
    p = vanefit.plan(cli_fit, pressures=[3, 4, 5], out=tmp_path / "plan")
    assert isinstance(p, vanefit.Plan)
    assert (tmp_path / "plan" / "plan.md").read_text() == p.report
    r = p.ranking
    assert len(r) == len(p.doc["ranked"]) and list(r["v_per_hour"]) == sorted(r["v_per_hour"], reverse=True)
    assert (r["v_per_hour"] - r["v_reduction"] / r["cost_h"]).abs().max() < 1e-12
    run_cli("plan", cli_fit, "--pressures", "3,4,5", "--out", tmp_path / "cli")
    cli = json.loads((tmp_path / "cli" / "plan.json").read_text())
    assert cli["ranked"] == p.doc["ranked"]
    only = vanefit.plan(cli_fit, pressures=[4], candidates=["stall_torque"], costs={"stall_torque": 2})
    assert [c["kind"] for c in only.doc["ranked"]] == ["stall_torque"]
    assert only.doc["ranked"][0]["cost_h"] == 2
    for kw, bad in [("pressures", {"pressures": [-2]}), ("speeds", {"speeds": [-5]}),
                    ("costs", {"costs": {"datasheet": 0}}), ("candidates", {"candidates": ["x"]}),
                    ("top", {"top": 0})]:
        args = {"pressures": [3], **bad}
        with pytest.raises(vanefit.ParameterError, match=kw):
            vanefit.plan(cli_fit, **args)
