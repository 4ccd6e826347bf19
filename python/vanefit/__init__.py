"""vanefit from Python: pneumatic vane motors simulated, fitted, diagnosed and predicted.

Every function runs the same Rust code as the ``vanefit`` command line, so a seed gives the
same fit in both and a bad file gets the same located message. Results are plain Python
objects: dicts whose tables are dicts of numpy arrays (``pandas.DataFrame(table)`` reads
them directly). Values are SI unless a name says otherwise (column names carry their unit,
as in the recordings: ``speed_rpm``, ``flow1_g_s``, ``p_port1_mpa``).

Errors: :class:`DataError` (a dataset, recording or fit file that cannot be read or used;
the message names file, line and column), :class:`ParameterError` (a bad option, parameter
name or value), both subclasses of :class:`VanefitError`.

Example::

    import vanefit, pandas as pd
    ds = vanefit.load_dataset("measurements/ar034-synthetic")
    fit = vanefit.fit(ds, starts=16, seed=1, progress=lambda done, total, best: None)
    pd.DataFrame(vanefit.simulate(ds, fit)["ramp.csv"])
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import tempfile
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import DataError, ParameterError, VanefitError, __version__

__all__ = [
    "Dataset",
    "Likelihood",
    "DataError",
    "ParameterError",
    "VanefitError",
    "load_dataset",
    "default_parameters",
    "read_fit",
    "simulate",
    "cost",
    "fit",
    "likelihood",
    "export_petab",
    "diagnose",
    "predict",
    "control",
    "synth",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]
#: Parameters: ``None`` (the dataset's nominal motor), a fit file's path, a fit document
#: (a result of :func:`fit`, :func:`read_fit`, or a diagnosis' ``extended_fit``), or a dict
#: ``{name: SI value}`` overriding the nominal motor.
Params = Union[None, PathLike, Mapping[str, Any]]
Table = Dict[str, np.ndarray]


class Dataset:
    """A dataset read and checked by vanefit: ``rig.toml`` and its recordings."""

    def __init__(self, core: Any):
        self._core = core

    @property
    def name(self) -> str:
        """The dataset's name."""
        return self._core.name

    @property
    def path(self) -> str:
        """The folder it was read from."""
        return self._core.path

    @property
    def experiments(self) -> List[Dict[str, Any]]:
        """One dict per experiment: ``file``, ``kind``, ``columns`` (names with units)."""
        return json.loads(self._core.experiments_json())

    def recording(self, file: str) -> Table:
        """A recording's columns as written (name with unit → values in that unit; an empty
        cell is NaN)."""
        return {name: np.asarray(v, dtype=float) for name, v in self._core.recording(file)}

    def __repr__(self) -> str:
        files = ", ".join(e["file"] for e in self.experiments)
        return f"vanefit.Dataset({self.name!r} at {self.path!r}: {files})"


def load_dataset(path: PathLike) -> Dataset:
    """Reads and checks a dataset folder; :class:`DataError` names file, line and column."""
    return Dataset(_core.load_dataset(os.fspath(path)))


def default_parameters(ds: Dataset) -> Dict[str, float]:
    """The dataset's nominal motor: every parameter's SI value by name."""
    return dict(_core.nominal_parameters(ds._core))


def read_fit(path: PathLike) -> Dict[str, Any]:
    """A fit file (``vanefit.fit/1``), read and checked, as a dict."""
    return json.loads(_core.read_fit(os.fspath(path)))


_DOCUMENT_KEYS = ("start_results", "out", "summary")


class _FitDocument(str):
    """The path of a fit document written to a temporary file for one call."""


def _fit_document_file(doc: Mapping[str, Any]) -> str:
    """Writes a fit document (without the Python-only keys) to a temporary file; the
    caller removes it (:func:`_params`)."""
    clean = {k: v for k, v in doc.items() if k not in _DOCUMENT_KEYS}
    fd, path = tempfile.mkstemp(prefix="vanefit-fit-", suffix=".json")
    with os.fdopen(fd, "w") as f:
        json.dump(clean, f)
    return _FitDocument(path)


@contextlib.contextmanager
def _params(params: Params):
    """(fit file path or None, overrides) for the Rust side, for the duration of a call."""
    path, overrides = _split_params(params)
    try:
        yield path, overrides
    finally:
        if isinstance(path, _FitDocument):
            os.remove(path)


def _split_params(params: Params) -> Tuple[Optional[str], List[Tuple[str, float]]]:
    """(fit file path or None, overrides) for the Rust side."""
    if params is None:
        return None, []
    if isinstance(params, (str, os.PathLike)):
        return os.fspath(params), []
    if isinstance(params, Mapping):
        if params.get("out") is not None and isinstance(params.get("parameters"), Mapping):
            return os.fspath(params["out"]), []
        if params.get("format") == "vanefit.fit/1" or isinstance(params.get("parameters"), Mapping):
            # A fit document in memory (read_fit, fit without out, a diagnosis'
            # extended_fit): checked by the same reader as a file.
            return _fit_document_file(params), []
        overrides = []
        for name, v in params.items():
            try:
                overrides.append((str(name), float(v)))
            except (TypeError, ValueError):
                raise ParameterError(f"parameter {name!r}: {v!r} is not a number") from None
        return None, overrides
    raise ParameterError(
        f"params: expected None, a fit file path or a dict of values, got {type(params).__name__}"
    )


def simulate(ds: Dataset, params: Params = None) -> Dict[str, Table]:
    """Every experiment simulated, by recording file: the recording's input columns as
    recorded, then each simulated output under the recording's column name and unit, same
    rows (what ``vanefit simulate`` writes, at full precision)."""
    with _params(params) as (fit_path, overrides):
        tables = _core.simulate(ds._core, fit_path, overrides)
    return {file: {name: np.asarray(v, dtype=float) for name, v in cols} for file, cols in tables}


def cost(ds: Dataset, params: Params = None) -> Dict[str, Any]:
    """The cost J that :func:`fit`'s multi-start minimises (SPEC §2), with each channel's
    term: ``{"cost", "chi2", "n_points", "failed", "channels": [...]}``. Its ``chi2`` is the
    cost's own: the simulation against each channel's reference polynomial, in units of
    the polynomial's residual σ. It is not the fit file's ``statistics.chi2`` (the recorded
    rows against the data's noise) nor ``likelihood_chi2`` (what the estimate maximises;
    see :class:`Likelihood`)."""
    with _params(params) as (fit_path, overrides):
        return json.loads(_core.cost(ds._core, fit_path, overrides))


def fit(
    ds: Dataset,
    starts: int = 32,
    seed: int = 1,
    threads: Optional[int] = None,
    estimate: Optional[Sequence[str]] = None,
    effects: Optional[Sequence[str]] = None,
    uncertainty: str = "profile",
    max_iters: int = 3000,
    out: Optional[PathLike] = None,
    progress: Optional[Callable[[int, int, float], Any]] = None,
) -> Dict[str, Any]:
    """Fits the dataset exactly as ``vanefit fit`` does (multi-start Nelder–Mead on J, the
    estimate at the likelihood's maximum, 95 % intervals), with the GIL released.

    ``progress(done, total, best_cost)`` is called after every start. ``out``: also write
    the fit file and its starts file there, as the command line does.

    Returns the fit file as a dict (``parameters``, ``statistics``, ``covariance``,
    ``profiles``, ...) plus ``start_results`` (every start: ``index``, ``cost``, ``ending``,
    ``parameters``) and ``out``."""
    doc = json.loads(
        _core.fit(
            ds.path,
            int(starts),
            int(seed),
            None if threads is None else int(threads),
            ",".join(effects or []),
            None if estimate is None else ",".join(estimate),
            uncertainty,
            int(max_iters),
            None if out is None else os.fspath(out),
            progress,
        )
    )
    doc["out"] = None if out is None else os.fspath(out)
    return doc


class Likelihood:
    """The likelihood a fit's estimate and intervals were measured on, rebuilt from its fit
    file: χ²(x) over the estimated parameters ``names`` (SI values). At ``x_hat`` it is the
    fit file's ``statistics.likelihood_chi2``; a 95 % profile interval ends where it rises
    by ``threshold``. Calling the object gives χ² or, where ``x`` is invalid or the
    simulation fails, a large finite penalty (for optimizers)."""

    def __init__(self, ds: Dataset, fit: PathLike):
        self._core = _core.PyLikelihood(ds._core, os.fspath(fit))

    @property
    def names(self) -> List[str]:
        """Estimated parameters, in the fit file's order."""
        return list(self._core.names)

    @property
    def lower(self) -> np.ndarray:
        """Default search bounds, lower, SI."""
        return np.array([b[0] for b in self._core.bounds])

    @property
    def upper(self) -> np.ndarray:
        """Default search bounds, upper, SI."""
        return np.array([b[1] for b in self._core.bounds])

    @property
    def log_scale(self) -> np.ndarray:
        """Whether each parameter is searched on a log scale."""
        return np.array(self._core.log_scale, dtype=bool)

    @property
    def x_hat(self) -> np.ndarray:
        """The fit's estimate, SI."""
        return np.array(self._core.estimate)

    @property
    def chi2_min(self) -> float:
        """χ² at the estimate as the fit file states it."""
        return self._core.chi2_min

    @property
    def threshold(self) -> float:
        """Rise of χ² bounding a 95 % profile interval (χ²₁(0.95)·s²)."""
        return self._core.threshold

    def chi2(self, x: Sequence[float]) -> float:
        """χ² at ``x`` (SI); :class:`ParameterError` for a bad vector,
        :class:`VanefitError` if the simulation fails."""
        return self._core.chi2([float(v) for v in x])

    def __call__(self, x: Sequence[float]) -> float:
        return self._core.chi2_or_penalty([float(v) for v in x])

    def residuals(self, x: Sequence[float]) -> np.ndarray:
        """The residual vector at ``x`` (SI) whose squares sum to :meth:`chi2`: every compared
        row, (simulated − recorded)/σ after the nuisances' correction, then one row per
        nuisance prior (β̂/τ). For least-squares optimizers (pyPESTO's ``res``, SciPy's
        ``least_squares``). Raises like :meth:`chi2`."""
        return np.asarray(self._core.residuals([float(v) for v in x]))

    def breakdown(self, x: Sequence[float]) -> Dict[str, Any]:
        """χ² at ``x`` split into the rows' part and the nuisance priors' part, with every
        compared row (``channels``: file, column, rows, data, sigma, simulated, residuals)
        and the profiled nuisances (label, value, prior_sd)."""
        b = json.loads(self._core.breakdown([float(v) for v in x]))
        for c in b["channels"]:
            for k in ("rows", "data", "simulated", "residuals"):
                c[k] = np.asarray(c[k])
        return b


def likelihood(ds: Dataset, fit: PathLike) -> Likelihood:
    """The :class:`Likelihood` of the fit file ``fit`` on ``ds``."""
    return Likelihood(ds, fit)


def export_petab(
    fit: PathLike, out: PathLike, dataset: Optional[PathLike] = None
) -> Dict[str, Any]:
    """Writes the fit as a PEtab v1 problem into ``out`` (as ``vanefit export-petab``):
    ``parameters.tsv``, ``observables.tsv``, ``measurements.tsv``, ``conditions.tsv``,
    ``model.xml`` (SBML declaring the model's symbols; the dynamics are vanefit's),
    ``problem.yaml`` and ``vanefit_export.json``. ``dataset``: the fit's dataset folder
    (default: ``measurements/<name>`` beside the fit file's folder). Returns
    ``vanefit_export.json`` as a dict (χ² of the tables at the fit, split into the rows and
    the nuisance priors) with ``yaml``, the problem file's path. See :mod:`vanefit.petab` to
    evaluate the tables with vanefit's simulation."""
    args = ["export-petab", os.fspath(fit), "--out", os.fspath(out)]
    if dataset is not None:
        args += ["--dataset", os.fspath(dataset)]
    _core.run_command(args, 1)
    summary = json.loads((Path(out) / "vanefit_export.json").read_text())
    summary["yaml"] = os.fspath(Path(out) / "problem.yaml")
    return summary


def diagnose(
    ds: Dataset,
    starts: int = 4,
    seed: int = 1,
    threads: Optional[int] = None,
    out: Optional[PathLike] = None,
    progress: Optional[Callable[[float, str], Any]] = None,
) -> Dict[str, Any]:
    """Diagnoses the dataset as ``vanefit diagnose`` does: where the base model misses,
    which missing physics explains it, the refit. Returns the diagnosis (``diagnosis.json``)
    as a dict plus ``summary`` (the printed paragraph) and ``extended_fit`` (the chosen
    model as a fit file). ``progress(elapsed_s, message)`` is called at every phase; ``out``
    also writes the report, its plots and the JSON there."""
    return json.loads(
        _core.diagnose(
            ds._core,
            int(starts),
            int(seed),
            None if threads is None else int(threads),
            None if out is None else os.fspath(out),
            progress,
        )
    )


def _read_table(path: Path) -> Table:
    """A CSV file as a dict of arrays (numbers as floats, other columns as strings)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    out: Table = {}
    for j, name in enumerate(header):
        cells = [r[j] if j < len(r) else "" for r in body]
        try:
            out[name] = np.array([float(c) if c != "" else np.nan for c in cells])
        except ValueError:
            out[name] = np.array(cells, dtype=object)
    return out


def _option_args(options: Mapping[str, Any]) -> List[str]:
    """``{"p_mean_mpa": 0.35, "anti_windup": "clamp"}`` → ``--p-mean-mpa 0.35 --anti-windup clamp``."""
    args: List[str] = []
    for key, value in options.items():
        if value is None:
            continue
        flag = "--" + key.replace("_", "-")
        if value is True:
            args.append(flag)
        elif value is False:
            continue
        elif isinstance(value, (list, tuple)):
            args += [flag, ",".join(str(v) for v in value)]
        else:
            args += [flag, str(value)]
    return args


def _run_into(out: Optional[PathLike], args: List[str], error: int) -> Path:
    """Runs a command writing into ``out`` (a fresh temporary folder if None)."""
    folder = Path(tempfile.mkdtemp(prefix="vanefit-")) if out is None else Path(out)
    _core.run_command(args + ["--out", os.fspath(folder)], error)
    return folder


def _tables(folder: Path) -> Dict[str, Any]:
    """Every CSV (as a table) and JSON file of a folder, by file stem; ``folder`` too."""
    result: Dict[str, Any] = {"folder": os.fspath(folder)}
    for p in sorted(folder.glob("*.csv")):
        result[p.stem] = _read_table(p)
    for p in sorted(folder.glob("*.json")):
        result[p.stem] = json.loads(p.read_text())
    return result


def predict(
    fit: PathLike,
    pressures: Optional[Sequence[float]] = None,
    unit: str = "bar_g",
    inlet_nozzle: Optional[float] = None,
    outlet_nozzle: Optional[float] = None,
    fixed_spread: Optional[float] = None,
    out: Optional[PathLike] = None,
    **options: Any,
) -> Dict[str, Any]:
    """The fitted motor at other supply pressures (in ``unit``: ``bar_g``, ``pa``, ``mpa``,
    ...) or behind a nozzle (sonic conductance, m³/(s·Pa)), as ``vanefit predict``: tables
    ``catalogue``, ``factors`` and ``curves`` (each a dict of arrays, columns as in the CSV
    files, 95 % bands as ``_lo``/``_hi``) and the ``folder`` with the figures."""
    args = ["predict", os.fspath(fit), "--unit", unit]
    if pressures is not None:
        args += ["--pressures", ",".join(repr(float(p)) for p in pressures)]
    args += _option_args(
        dict(
            inlet_nozzle=inlet_nozzle,
            outlet_nozzle=outlet_nozzle,
            fixed_spread=fixed_spread,
            **options,
        )
    )
    return _tables(_run_into(out, args, 2))


def control(
    study: str,
    params: Optional[PathLike] = None,
    out: Optional[PathLike] = None,
    **options: Any,
) -> Dict[str, Any]:
    """A speed-control study of paper §5 as ``vanefit control <study>`` (``bode``, ``step``,
    ``disturbance``, ``design``, ``throttle-inlet``, ``throttle-outlet``, ``min-speed``) on
    the motor of a fit file (default: the AR034 motor). ``options`` are the command's
    options with underscores (``kp=..., ki=..., pm_deg=60, p_mean_mpa=0.35``). Returns every
    table the study writes (dicts of arrays, by file stem), its JSON summaries and the
    ``folder`` with the figures."""
    args = ["control", study]
    if params is not None:
        args += ["--params", os.fspath(params)]
    return _tables(_run_into(out, args + _option_args(options), 2))


def synth(
    out: PathLike,
    params: Optional[PathLike] = None,
    effects: Optional[Sequence[str]] = None,
    noise: float = 1.0,
    seed: int = 1,
) -> Dataset:
    """Writes a synthetic dataset (the three reference experiments with typical sensor
    noise, and ``truth.json``) from the motor of a fit file (default: the AR034 motor) with
    the catalogued ``effects`` switched on, as ``vanefit synth``, and loads it."""
    args = ["synth", os.fspath(out), "--noise", repr(float(noise)), "--seed", str(int(seed))]
    if params is not None:
        args += ["--params", os.fspath(params)]
    if effects:
        args += ["--effects", ",".join(effects)]
    _core.run_command(args, 1)
    return load_dataset(out)


# Submodules; each imports its optional dependency (matplotlib, petab, pypesto) only when
# one of its functions is called.
from . import pesto, petab, plot  # noqa: E402
