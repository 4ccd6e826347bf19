"""The notebooks in `notebooks/` run headless without an error and are committed with their
outputs stripped; the figures of `vanefit.plot` are drawn from plain results."""

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import vanefit
from conftest import DATASET, ROOT

NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


def test_there_are_the_three_notebooks_of_the_issue():
    names = [p.name for p in NOTEBOOKS]
    for prefix in ("01_", "02_", "03_"):
        assert any(n.startswith(prefix) for n in names), names


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_is_committed_without_outputs(path):
    nb = json.loads(path.read_text())
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "code":
            continue
        assert cell.get("outputs") == [], f"{path.name} cell {i} has outputs"
        assert cell.get("execution_count") is None, f"{path.name} cell {i} has an execution count"
    # Nothing a run leaves behind in the notebook's metadata either.
    assert "widgets" not in nb.get("metadata", {})


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_uses_only_the_public_api(path):
    """No `vanefit._core`, no private name (`x._y`) of anything: what a notebook shows a user
    can do, a user can do."""
    import ast

    nb = json.loads(path.read_text())
    for i, cell in enumerate(nb["cells"]):
        if cell["cell_type"] != "code":
            continue
        tree = ast.parse("".join(cell["source"]))
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute):
                private = node.attr.startswith("_") and not (
                    node.attr.startswith("__") and node.attr.endswith("__"))
                assert not private, f"{path.name} cell {i}: .{node.attr}"
            if isinstance(node, ast.ImportFrom):
                assert not (node.module or "").startswith("vanefit._"), f"{path.name} cell {i}"
                assert all(not a.name.startswith("_") for a in node.names), f"{path.name} cell {i}"
            if isinstance(node, ast.Import):
                assert all(not a.name.startswith("vanefit._") for a in node.names), f"{path.name} cell {i}"


def _kernel_name() -> str:
    """The `python3` kernel of this interpreter, installed into its prefix if missing."""
    from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel

    try:
        KernelSpecManager().get_kernel_spec("python3")
    except NoSuchKernel:
        subprocess.run(
            [sys.executable, "-m", "ipykernel", "install", "--prefix", sys.prefix],
            check=True, capture_output=True,
        )
    return "python3"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs_headless(path, capsys, tmp_path, monkeypatch):
    # The notebooks write into tempfile.mkdtemp(); the kernel inherits TMPDIR, so what they
    # write lands in pytest's temporary folder, not in the machine's /tmp.
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb, kernel_name=_kernel_name(), timeout=600,
        resources={"metadata": {"path": str(path.parent)}},
    )
    t0 = time.time()
    client.execute()  # raises CellExecutionError, naming the cell, on any error
    wall = time.time() - t0
    errors = [o for c in nb.cells for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert not errors, errors
    figures = sum("image/png" in o.get("data", {}) for c in nb.cells for o in c.get("outputs", []))
    # The three tutorials draw at least three figures each; the FMU notebook its one loop.
    least = 3 if path.name[:3] in ("01_", "02_", "03_") else 1
    assert figures >= least, f"{path.name} drew {figures} figures"
    with capsys.disabled():
        print(f"\n{path.name}: {wall:.1f} s, {figures} figures")


# --- vanefit.plot on a tiny fit ------------------------------------------------------------

@pytest.fixture(scope="module")
def plt():
    mpl = pytest.importorskip("matplotlib")
    mpl.use("Agg")
    import matplotlib.pyplot as plt

    yield plt
    plt.close("all")


@pytest.fixture(scope="module")
def ds():
    return vanefit.load_dataset(DATASET)


@pytest.fixture(scope="module")
def tiny_fit(ds, tmp_path_factory):
    """Three short starts with profile intervals of two parameters only (a few seconds)."""
    out = tmp_path_factory.mktemp("plot") / "fit.json"
    return vanefit.fit(ds, starts=3, seed=5, max_iters=150, estimate=["c_in1", "t_coulomb"],
                       uncertainty="profile", out=out)


def test_plot_needs_no_matplotlib_to_import():
    code = ("import sys, vanefit, vanefit.plot; "
            "assert 'matplotlib' not in sys.modules, 'matplotlib imported'")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_waterfall_parameters_profiles(plt, tiny_fit):
    from matplotlib.figure import Figure

    from vanefit import plot

    fig = plot.waterfall(tiny_fit)
    assert isinstance(fig, Figure) and len(fig.axes) == 1
    ax = fig.axes[0]
    assert ax.get_yscale() == "log"
    # The sorted costs, every start once.
    ys = np.concatenate([l.get_ydata() for l in ax.lines if l.get_linestyle() == "None"])
    assert sorted(ys) == pytest.approx(sorted(tiny_fit.starts["cost"]))
    # The Fit's own figures are the module's.
    assert len(tiny_fit.plot.waterfall().axes[0].lines) == len(ax.lines)

    fig = plot.parameters(tiny_fit)
    assert isinstance(fig, Figure)
    main = fig.axes[0]
    assert len(main.get_yticks()) == 2  # two estimated parameters
    # One line per start, then the intervals and the estimate.
    start_lines = [l for l in main.lines if len(l.get_xdata()) == 2 and l.get_marker() == "o"]
    assert len(start_lines) == 3

    fig = plot.profiles(tiny_fit)
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    thr = tiny_fit.statistics.profile_threshold
    for ax, name in zip(fig.axes, ["c_in1", "t_coulomb"]):
        assert ax.get_title().startswith(name)
        assert any(np.allclose(l.get_ydata(), thr) for l in ax.lines)  # the threshold
        assert ax.get_ylim()[1] == pytest.approx(3 * thr)
    plt.close("all")


def test_plots_refuse_results_without_what_they_show(plt, tiny_fit):
    from vanefit import plot

    with pytest.raises(ValueError, match="start_results"):
        vanefit.Fit.read(tiny_fit.path).plot.waterfall()
    with pytest.raises(ValueError, match="profile"):
        plot.profiles({**tiny_fit.document, "profiles": {}})


def test_overlay_and_residuals(plt, ds, tiny_fit):
    from vanefit import plot

    fig = plot.overlay(ds, tiny_fit)
    # datasheet: torque, flow1; ramp and throttle: flow1, flow2, speed.
    assert len(fig.axes) == 8
    for ax in fig.axes:
        assert len(ax.lines) == 2  # recorded, simulated
        assert " / " in ax.get_xlabel() and " / " in ax.get_ylabel()
    assert fig.axes[-1].get_xscale() == "log"  # the throttle's conductance
    assert "dm³/(s·bar)" in fig.axes[-1].get_xlabel()

    fig = plot.residuals(ds, [None, tiny_fit], labels=["nominal", "fit"],
                         experiments=["ramp.csv"])
    assert len(fig.axes) == 3
    for ax in fig.axes:
        assert "recorded − simulated" in ax.get_ylabel()
    plt.close("all")


def test_control_plots(plt, tmp_path):
    from vanefit import plot

    bode = vanefit.control("bode", out=tmp_path / "bode", points=40)
    fig = plot.bode(bode["bode"])
    assert len(fig.axes) == 3  # magnitude (rpm/bar), its twin (rpm/V), phase
    assert fig.axes[1].get_xscale() == "log"

    design = vanefit.control("design", out=tmp_path / "design", duration_s=2)
    d = design["design"]
    fig = plot.bode(design["design_open_loop"],
                    margins={"designed": d["designed"], "paper": d["paper"]})
    assert len(fig.axes) == 2
    assert "dB" in fig.axes[0].get_ylabel()

    fig = plot.closed_loop({"designed": design["design_step"],
                            "paper": design["design_step_paper_gains"]})
    assert len(fig.axes) == 3  # speed, command, pressure: no load step
    dist = vanefit.control("disturbance", out=tmp_path / "dist", duration_s=2)
    fig = plot.closed_loop({"PI": dist["disturbance"], "open loop": dist["disturbance_open_loop"]})
    assert len(fig.axes) == 4  # and the load step
    plt.close("all")


def test_candidates_plot(plt):
    from vanefit import plot

    diagnosis = {
        "candidates": [
            {"effect": "breakaway_friction", "delta_bic": -40.0},
            {"effect": "sensor_lag", "delta_bic": 3.0},
            {"effect": "vane_friction_speed_squared", "delta_bic": -2200.0},
        ],
        "selected": [{"effect": "vane_friction_speed_squared"}],
    }
    fig = plot.candidates(diagnosis)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == [
        "vane_friction_speed_squared", "breakaway_friction", "sensor_lag"]
    assert len(ax.patches) == 3
    with pytest.raises(ValueError):
        plot.candidates({"candidates": []})
    plt.close("all")


def test_units_on_the_axes():
    from vanefit.plot import column_label, display_unit

    assert display_unit("m3/(s*Pa)") == (1e8, "dm³/(s·bar)")
    assert display_unit("N*m")[0] == 1e3
    assert display_unit("furlong") == (1.0, "furlong")
    assert column_label("torque_nm") == ("shaft torque / mN·m", 1e3)
    assert column_label("speed_rpm") == ("speed / rpm", 1.0)
    assert column_label("c_port2_m3_s_pa")[1] == 1e8
    assert column_label("p_port1_mpa")[0] == "port-1 pressure / MPa abs."
