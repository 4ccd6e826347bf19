"""`vanefit export-fmu` checked by FMPy (docs/fmu.md): the FMU validates, and FMPy's own
co-simulation loop and model exchange with FMPy's CVode reproduce `vanefit simulate` on the
shipped dataset's pressure ramp and outlet-throttling ramp within 0.1 % of each channel's
range; the same for an extended model (catalog effects and a discovered term), and the
export refuses an effect the FMU cannot represent."""

import csv
import json
import math
import os
import shutil
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, instantiate_fmu, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

from conftest import DATASET, ROOT, run_cli

FIT = ROOT / "fits" / "ar034-synthetic.json"
P_ATM_PA = 101325.0
BRAKE_NM_S_RAD = 1e-4  # rig.toml: load = viscous_brake 1e-4 on both ramps
MAX_KNOTS = 16  # sim::schedule::MAX_KNOTS
DT_S = 0.01  # FMPy's communication / output interval
RAD_S_PER_RPM = 2 * math.pi / 60


def schedule(times, values):
    """vanefit's input schedule (sim::schedule::Schedule::smoothed): bin means of at most
    16 bins joined by a monotone cubic (Fritsch–Carlson), extended linearly. Returns a
    function of time (numpy arrays)."""
    n = min(len(times), len(values))
    per_bin = max(-(-n // MAX_KNOTS), 1)
    t = np.array([np.mean(times[s:s + per_bin]) for s in range(0, n, per_bin)])
    v = np.array([np.mean(values[s:s + per_bin]) for s in range(0, n, per_bin)])
    sec = np.diff(v) / np.diff(t)
    m = np.zeros_like(v)
    m[0], m[-1] = sec[0], sec[-1]
    for k in range(1, len(v) - 1):
        a, b = sec[k - 1], sec[k]
        if a * b > 0:
            h0, h1 = t[k] - t[k - 1], t[k + 1] - t[k]
            w1, w2 = 2 * h1 + h0, h1 + 2 * h0
            m[k] = (w1 + w2) / (w1 / a + w2 / b)

    def at(x):
        x = np.asarray(x, dtype=float)
        k = np.clip(np.searchsorted(t, x, side="right") - 1, 0, len(t) - 2)
        h = t[k + 1] - t[k]
        s = (x - t[k]) / h
        h00, h10 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2
        h01, h11 = s * s * (3 - 2 * s), s * s * (s - 1)
        y = h00 * v[k] + h10 * h * m[k] + h01 * v[k + 1] + h11 * h * m[k + 1]
        y = np.where(x <= t[0], v[0] + m[0] * (x - t[0]), y)
        return np.where(x >= t[-1], v[-1] + m[-1] * (x - t[-1]), y)

    return at


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def inputs_of(experiment):
    """The FMU's inputs for a ramp of the shipped dataset as functions of time, as vanefit
    drives it: the ramp's supply is its recorded port-1 pressure smoothed (held at least at
    half the atmosphere); the throttle's is rig.toml's 0.73 MPa, its port-2 conductance the
    recorded one smoothed in log10. Returns the recorded times and {input name: f(t)}."""
    rec = read_csv(DATASET / f"{experiment}.csv")
    t = rec["t_s"]
    if experiment == "ramp":
        s = schedule(t, rec["p_port1_mpa"] * 1e6)
        return t, {"p_supply": lambda x: np.maximum(s(x), 0.5 * P_ATM_PA)}
    s = schedule(t, np.log10(rec["c_port2_m3_s_pa"]))
    return t, {"p_supply": lambda x: np.full_like(np.asarray(x, dtype=float), 0.73e6),
               "c_throttle2": lambda x: 10 ** s(x)}


def input_table(t, inputs):
    """The inputs sampled every DT_S for FMPy's input table (linear in between)."""
    grid = np.arange(t[0], t[-1] + DT_S / 2, DT_S)
    table = np.zeros(len(grid), dtype=[(n, np.float64) for n in ["time", *inputs]])
    table["time"] = grid
    for n, f in inputs.items():
        table[n] = f(grid)
    return table


OUTPUTS = ["speed", "flow_port1", "flow_port2", "torque_shaft",
           "p_chamber1", "p_chamber2", "p_exhaust"]
# simulate's CSV column → (FMU output, factor from SI to the column's unit)
CHANNELS = {"flow1_g_s": ("flow_port1", 1e3), "flow2_g_s": ("flow_port2", 1e3),
            "speed_rpm": ("speed", 1 / RAD_S_PER_RPM)}


def co_simulate(fmu, t, inputs, start):
    """FMPy's co-simulation interface (`fmpy.fmi2.FMU2Slave`) stepped every DT_S, each
    step given its inputs' values and slopes (`fmi2SetRealInputDerivatives`: the FMU moves
    the inputs along them within the step). FMPy's `simulate_fmu` has the same loop, but
    its `set_input_derivatives` fails for any number of inputs but nine (FMPy 0.3.32 sizes
    the derivatives' buffer 9)."""
    unzipdir = extract(str(fmu), unzipdir=tempfile.mkdtemp())
    md = read_model_description(unzipdir)
    refs = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="motor")
    fmu.instantiate()
    fmu.setupExperiment(startTime=t[0])
    fmu.enterInitializationMode()
    fmu.setReal([refs[n] for n in start], list(start.values()))
    in_vrs = [refs[n] for n in inputs]
    fmu.setReal(in_vrs, [float(f(t[0])) for f in inputs.values()])
    fmu.exitInitializationMode()
    out_vrs = [refs[n] for n in OUTPUTS]
    grid = np.arange(t[0], t[-1] + DT_S / 2, DT_S)
    rows = [fmu.getReal(out_vrs)]
    for a, b in zip(grid[:-1], grid[1:]):
        now = [float(f(a)) for f in inputs.values()]
        slopes = [(float(f(b)) - u) / (b - a) for f, u in zip(inputs.values(), now)]
        fmu.setReal(in_vrs, now)
        fmu.setRealInputDerivatives(in_vrs, [1] * len(in_vrs), slopes)
        fmu.doStep(currentCommunicationPoint=a, communicationStepSize=b - a)
        rows.append(fmu.getReal(out_vrs))
    fmu.terminate()
    fmu.freeInstance()
    shutil.rmtree(unzipdir)
    res = {"time": grid}
    res.update(zip(OUTPUTS, np.array(rows).T))
    return res


def fmpy_run(fmu, experiment, fmi_type):
    """FMPy's simulation of the FMU through a ramp. Co-simulation: [`co_simulate`].
    Model exchange: FMPy's `simulate_fmu` with its CVode, the inputs set to their value at
    every time FMPy sets (each right-hand side), as a tool that connects the FMU's inputs to
    continuous signals does."""
    t, inputs = inputs_of(experiment)
    start = {"c_brake": BRAKE_NM_S_RAD, "p_atm": P_ATM_PA}
    t0 = time.perf_counter()
    if fmi_type == "CoSimulation":
        res = co_simulate(fmu, t, inputs, start)
        return t, res, time.perf_counter() - t0
    unzipdir = extract(str(fmu), unzipdir=tempfile.mkdtemp())
    md = read_model_description(unzipdir)
    inst = instantiate_fmu(unzipdir, md, fmi_type="ModelExchange")
    refs = {v.name: v.valueReference for v in md.modelVariables}
    vrs = [refs[n] for n in inputs]
    set_time = inst.setTime

    def set_time_and_inputs(time_s):
        set_time(time_s)
        inst.setReal(vrs, [float(f(time_s)) for f in inputs.values()])

    inst.setTime = set_time_and_inputs
    start.update({n: float(f(t[0])) for n, f in inputs.items()})
    res = simulate_fmu(unzipdir, start_time=t[0], stop_time=t[-1], fmi_type=fmi_type,
                       solver="CVode", relative_tolerance=1e-8, output_interval=DT_S,
                       output=OUTPUTS, start_values=start, fmu_instance=inst,
                       model_description=md)
    wall = time.perf_counter() - t0
    inst.freeInstance()
    shutil.rmtree(unzipdir)
    return t, res, wall


def agreement(fmu, sim_dir, experiment, fmi_type):
    """Per channel: the largest |FMU − simulate| over the recorded rows as a fraction of
    the channel's range in simulate's output; and FMPy's wall time per simulated second."""
    t, res, wall = fmpy_run(fmu, experiment, fmi_type)
    sim = read_csv(sim_dir / f"{experiment}.csv")
    out = {}
    for col, (name, factor) in CHANNELS.items():
        fmu_rows = np.interp(t, res["time"], res[name]) * factor
        span = np.ptp(sim[col])
        out[col] = float(np.max(np.abs(fmu_rows - sim[col])) / span)
    return out, wall / (t[-1] - t[0])


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """The shipped fit and an extended one (two catalog effects and a discovered torque
    term), each exported as an FMU and simulated by `vanefit simulate`."""
    tmp = tmp_path_factory.mktemp("fmu")
    doc = json.loads(FIT.read_text())
    doc["model"]["effects"] = ["speed_dependent_leakage", "pressure_dependent_friction"]
    doc["parameters"]["g_seal"] = {"value": 3.0, "unit": "1", "estimated": False, "ci95": None}
    doc["parameters"]["w_seal"] = {"value": 300.0, "unit": "rad/s", "estimated": False,
                                   "ci95": None}
    doc["parameters"]["k_fric_p"] = {"value": 3e-8, "unit": "N*m/Pa", "estimated": False,
                                     "ci95": None}
    doc["model"]["discovered"] = [{"balance": "torque", "pressure": "p1_gauge",
                                   "speed": "omega", "coefficient": 3e-11}]
    extended = tmp / "extended.json"
    extended.write_text(json.dumps(doc, indent=1))
    made = {}
    for name, fit in [("fitted", FIT), ("extended", extended)]:
        fmu = tmp / f"{name}.fmu"
        p = run_cli("export-fmu", fit, "--out", fmu)
        assert "wrote" in p.stdout, p.stdout
        sim = tmp / f"sim_{name}"
        run_cli("simulate", DATASET, "--params", fit, "--out", sim)
        made[name] = (fmu, sim)
    return made


@pytest.mark.parametrize("name", ["fitted", "extended"])
def test_fmpy_validates_the_fmu(fmus, name):
    fmu, _ = fmus[name]
    problems = validate_fmu(str(fmu))
    assert problems == [], problems
    md = read_model_description(str(fmu))
    assert md.fmiVersion == "2.0"
    assert md.modelExchange is not None and md.coSimulation is not None
    names = {v.name: v for v in md.modelVariables}
    for n in ["p_supply", "p_back", "t_load", "c_throttle1", "c_throttle2"]:
        assert names[n].causality == "input", n
    for n in OUTPUTS:
        assert names[n].causality == "output", n
    assert len(md.derivatives) == 4
    # Every fitted value is a tunable parameter's start value, with its description.
    if name == "fitted":
        for pid, entry in json.loads(FIT.read_text())["parameters"].items():
            v = names[pid]
            assert v.causality == "parameter" and v.variability == "tunable", pid
            assert float(v.start) == entry["value"], pid
            assert v.description, pid
    else:
        assert {"g_seal", "w_seal", "k_fric_p", "discovered_1"} <= set(names)
    units = {u.name for u in md.unitDefinitions}
    assert {"Pa", "kg/s", "rad/s", "N.m", "m3/(s.Pa)"} <= units
    with zipfile.ZipFile(fmu) as z:
        assert "resources/fit.json" in z.namelist()
        assert "binaries/linux64/vanefit_fmu.so" in z.namelist()


@pytest.mark.parametrize("fmi_type", ["CoSimulation", "ModelExchange"])
@pytest.mark.parametrize("experiment", ["ramp", "throttle"])
@pytest.mark.parametrize("name", ["fitted", "extended"])
def test_fmpy_reproduces_vanefit_simulate(fmus, name, experiment, fmi_type):
    fmu, sim = fmus[name]
    worst, wall_per_s = agreement(fmu, sim, experiment, fmi_type)
    print(f"{name} {experiment} {fmi_type}: " + ", ".join(
        f"{c} {100 * e:.4f} %" for c, e in worst.items())
        + f"; FMPy {wall_per_s * 1e3:.1f} ms per simulated second")
    assert all(e <= 1e-3 for e in worst.values()), worst


def test_the_extended_model_differs_from_the_fitted_one(fmus):
    """The extended FMU's agreement is not the base model's by accident: its simulation
    differs from the fitted one by far more than the 0.1 % tolerance."""
    a = read_csv(fmus["fitted"][1] / "ramp.csv")
    b = read_csv(fmus["extended"][1] / "ramp.csv")
    assert np.max(np.abs(a["speed_rpm"] - b["speed_rpm"])) > 0.01 * np.ptp(a["speed_rpm"])


def test_export_refuses_an_effect_the_fmu_cannot_represent(tmp_path):
    doc = json.loads(FIT.read_text())
    doc["model"]["effects"] = ["sensor_lag"]
    fit = tmp_path / "lag.json"
    fit.write_text(json.dumps(doc))
    p = run_cli("export-fmu", fit, "--out", tmp_path / "lag.fmu", check=False)
    assert p.returncode == 1
    assert "sensor_lag" in p.stderr, p.stderr
    assert not (tmp_path / "lag.fmu").exists()
    assert os.listdir(tmp_path) == ["lag.json"]


def test_python_exports_the_fmu_the_command_exports(fmus, tmp_path):
    """vanefit.export_fmu, from a file's path and from a Fit held in memory, writes the FMU
    the command writes (same entries, same bytes), which FMPy validates."""
    import vanefit

    cli_fmu, _ = fmus["fitted"]
    from_path = vanefit.export_fmu(FIT, tmp_path / "path.fmu")
    in_memory = vanefit.Fit.from_json(FIT.read_text())
    assert in_memory.path is None
    from_memory = vanefit.export_fmu(in_memory, tmp_path / "memory.fmu")
    assert from_path["guid"] == from_memory["guid"]
    assert from_path["variables"] == len(read_model_description(str(cli_fmu)).modelVariables)
    with zipfile.ZipFile(cli_fmu) as want:
        for made in (tmp_path / "path.fmu", tmp_path / "memory.fmu"):
            with zipfile.ZipFile(made) as got:
                assert got.namelist() == want.namelist()
                for name in want.namelist():
                    assert got.read(name) == want.read(name), (made, name)
    assert validate_fmu(str(tmp_path / "memory.fmu")) == []
    doc = json.loads(FIT.read_text())
    doc["model"]["effects"] = ["sensor_lag"]
    with pytest.raises(vanefit.ParameterError, match="sensor_lag"):
        vanefit.export_fmu(vanefit.Fit.from_json(json.dumps(doc)), tmp_path / "lag.fmu")
