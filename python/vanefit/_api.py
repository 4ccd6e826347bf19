"""The implementation of the package :mod:`vanefit` re-exports (``vanefit.__all__``): kept
in a module of its own so that the package's namespace holds only the public names, not the
typing helpers and modules this one imports."""


from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import DataError, ParameterError, VanefitError, __version__
from .progress import Progress, fit_progress, diagnose_progress, predict_progress
from .results import Diagnosis, Fit, FitStatistics, Plan, Prediction, Samples, StudyResult

__all__ = [
    "Dataset",
    "Fit",
    "FitStatistics",
    "Diagnosis",
    "Prediction",
    "Samples",
    "Plan",
    "StudyResult",
    "Likelihood",
    "chain_diagnostics",
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
    "export_fmu",
    "diagnose",
    "predict",
    "plan",
    "control",
    "CONTROL_STUDIES",
    "synth",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]
#: Parameters: ``None`` (the dataset's nominal motor), a :class:`Fit`, a fit file's path,
#: or a dict ``{name: SI value}`` overriding the nominal motor.
Params = Union[None, Fit, PathLike, Mapping[str, Any]]
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
        cell is NaN); ``pandas.DataFrame(ds.recording(file))`` is the table."""
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


def read_fit(path: PathLike) -> Fit:
    """A fit file (``vanefit.fit/1``), read and checked: :meth:`Fit.read`."""
    return Fit.read(path)


def _fit_source(params: Union[Fit, PathLike, Mapping[str, Any]]) -> Tuple[str, Optional[str]]:
    """(path, text) of a fit for the Rust side: a file is read there; a Fit in memory goes
    as its text (its path, if any, names it in messages). No temporary files."""
    if isinstance(params, Fit):
        return params.path or "<fit>", params.to_json()
    if isinstance(params, (str, os.PathLike)):
        return os.fspath(params), None
    if isinstance(params, Mapping):
        return "<fit>", json.dumps(params)
    raise ParameterError(
        f"fit: expected a vanefit.Fit or a fit file's path, got {type(params).__name__}"
    )


def _split_params(params: Params) -> Tuple[Optional[str], Optional[str], List[Tuple[str, float]]]:
    """(fit path or None, fit text or None, overrides) for the Rust side."""
    if params is None:
        return None, None, []
    if isinstance(params, (Fit, str, os.PathLike)):
        return (*_fit_source(params), [])
    if isinstance(params, Mapping):
        if params.get("format") == "vanefit.fit/1" or isinstance(params.get("parameters"), Mapping):
            # A fit document as a dict: checked by the same reader as a file.
            return (*_fit_source(params), [])
        overrides = []
        for name, v in params.items():
            try:
                overrides.append((str(name), float(v)))
            except (TypeError, ValueError):
                raise ParameterError(f"parameter {name!r}: {v!r} is not a number") from None
        return None, None, overrides
    raise ParameterError(
        "params: expected None, a vanefit.Fit, a fit file path or a dict of values, "
        f"got {type(params).__name__}"
    )


def simulate(ds: Dataset, params: Params = None) -> Dict[str, Table]:
    """Every experiment simulated, by recording file: the recording's input columns as
    recorded, then each simulated output under the recording's column name and unit, same
    rows (what ``vanefit simulate`` writes, at full precision)."""
    path, text, overrides = _split_params(params)
    tables = _core.simulate(ds._core, path, text, overrides)
    return {file: {name: np.asarray(v, dtype=float) for name, v in cols} for file, cols in tables}


def cost(ds: Dataset, params: Params = None) -> Dict[str, Any]:
    """The cost J that :func:`fit`'s multi-start minimises (docs/model.md), with each
    channel's term: ``{"cost", "chi2", "n_points", "failed", "channels": [...]}``. Its
    ``chi2`` is the cost's own: the simulation against each channel's reference polynomial,
    in units of the polynomial's residual σ. It is not the fit's χ²
    (:attr:`FitStatistics.chi2`: the recorded rows against the data's noise) nor
    ``likelihood_chi2`` (what the estimate maximises; see :class:`Likelihood`)."""
    path, text, overrides = _split_params(params)
    return json.loads(_core.cost(ds._core, path, text, overrides))


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
    resume: bool = False,
    progress: Progress = None,
    handoff: bool = True,
) -> Fit:
    """Fits the dataset exactly as ``vanefit fit`` does (multi-start Nelder–Mead on J, the
    estimate at the likelihood's maximum, 95 % intervals), with the GIL released.

    ``progress``: ``True`` for a tqdm bar over the starts, or a callable
    ``progress(done, total, best_cost)`` called when the run begins (``done`` = starts
    already finished, ``best_cost`` = inf) and after every start; an exception it raises
    stops the fit at its next round and is raised. Ctrl-C does the same with
    ``KeyboardInterrupt``.

    ``out``: also write the fit file there (byte for byte what ``vanefit fit --no-plots``
    writes) and record every finished start in ``<out>.starts.jsonl``; ``resume=True``
    continues an interrupted fit from that file.

    ``handoff``: after a first round of Nelder–Mead each start goes on by least squares
    (Levenberg–Marquardt), which usually ends it in the second round; ``False`` runs
    Nelder–Mead alone, round after round.

    Returns a :class:`Fit` (``.parameters``, ``.starts``, ``.statistics``, ``.profiles``,
    ``.plot``)."""
    if isinstance(ds, (str, os.PathLike)):
        ds = load_dataset(ds)
    with fit_progress(progress) as callback:
        text, starts_json = _core.fit(
            ds.path,
            int(starts),
            int(seed),
            None if threads is None else int(threads),
            [str(e) for e in effects or []],
            None if estimate is None else [str(n) for n in estimate],
            uncertainty,
            int(max_iters),
            None if out is None else os.fspath(out),
            bool(resume),
            callback,
            bool(handoff),
        )
    return Fit(text, starts=json.loads(starts_json), path=out)


class Likelihood:
    """The likelihood a fit's estimate and intervals were measured on, rebuilt from its fit
    file: χ²(x) over the estimated parameters ``names`` (SI values). With ``priors`` (the
    default) χ² includes the fit's motor prior, χ²_prior = Σ((ln v − ln m)/σ)² over the
    parameters the fit file's ``statistics.prior`` lists (:attr:`prior_terms`;
    docs/estimation.md, "Priors"): the objective the fit minimised, whose value at ``x_hat``
    is ``statistics.likelihood_chi2`` + ``statistics.prior_chi2``. ``priors=False`` gives
    the likelihood alone (``likelihood_chi2`` at ``x_hat``). A 95 % profile interval ends
    where χ² rises by ``threshold``. Calling the object gives χ² or, where ``x`` is invalid
    or the simulation fails, a large finite penalty (for optimizers)."""

    def __init__(self, ds: Dataset, fit: Union[Fit, PathLike], priors: bool = True):
        path, text = _fit_source(fit)
        self._core = _core.PyLikelihood(ds._core, path, text, bool(priors))

    @property
    def priors(self) -> bool:
        """Whether the motor prior is part of χ², the residuals and :meth:`log_posterior`."""
        return self._core.priors

    @property
    def prior_terms(self) -> List[Dict[str, Any]]:
        """The fit's motor prior of the estimated parameters: ``parameter``, ``median`` (SI),
        ``sd_ln`` (σ of ln v), ``size_exponent`` (k of the size law the median follows
        where the displacement is estimated too; 0 otherwise). Empty for a fit made with
        ``--priors none``."""
        return [
            {"parameter": n, "median": m, "sd_ln": s, "size_exponent": k}
            for n, m, s, k in self._core.prior_terms
        ]

    def prior_chi2(self, x: Sequence[float]) -> float:
        """χ²_prior of the motor prior at ``x`` (SI), whether or not :attr:`priors` is on."""
        return self._core.prior_chi2([float(v) for v in x])

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
        """χ² at the estimate as the fit file states it (``likelihood_chi2``, plus
        ``prior_chi2`` with :attr:`priors`)."""
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
        nuisance prior (β̂/τ), then with :attr:`priors` one per motor prior term
        ((ln v − ln m)/σ, in :attr:`prior_terms`' order). For least-squares optimizers (pyPESTO's ``res``, SciPy's
        ``least_squares``). Raises like :meth:`chi2`."""
        # The core hands the values over as bytes (little-endian f64): read in place, no
        # list of floats in between.
        return np.frombuffer(self._core.residuals([float(v) for v in x]), dtype="<f8")

    def breakdown(self, x: Sequence[float]) -> Dict[str, Any]:
        """χ² at ``x`` split into the rows' part (``chi2_data``), the nuisance priors' part
        (``chi2_prior``; ``chi2`` is their sum, the likelihood's) and the motor prior's
        (``chi2_motor_prior``; ``objective`` = ``chi2`` + it, whatever :attr:`priors`), with
        every compared row (``channels``: file, column, rows, data, sigma, simulated,
        residuals), the profiled nuisances (label, value, prior_sd) and the motor prior's
        terms (``motor_prior``: parameter, median, sd_ln, size_exponent, residual)."""
        b = json.loads(self._core.breakdown([float(v) for v in x]))
        for c in b["channels"]:
            for k in ("rows", "data", "simulated", "residuals"):
                c[k] = np.asarray(c[k])
        return b

    def log_posterior(self, x: Sequence[float]) -> float:
        """ln p at sampling coordinates ``x`` (ln θ of a log-scale parameter, θ otherwise):
        −½·(χ² − χ²_min)/s² of the likelihood (s² = ``threshold``/χ²₁(0.95)), plus with
        :attr:`priors` the motor prior −½·(χ²_prior − χ²_prior(x̂)) (a Gaussian in ln v, no
        Jacobian: ``x`` is ln v), with a prior flat in ``x`` within the search bounds; −inf
        outside them or where the simulation fails. 0 at the estimate. The density
        ``vanefit predict --bands samples`` samples; a callable for emcee."""
        return self._core.log_posterior([float(v) for v in x])

    def to_coords(self, values: Sequence[float]) -> np.ndarray:
        """Sampling coordinates of SI values."""
        return np.asarray(self._core.to_coords([float(v) for v in values]))

    def to_values(self, x: Sequence[float]) -> np.ndarray:
        """SI values at sampling coordinates."""
        return np.asarray(self._core.to_values([float(v) for v in x]))

    def sample(
        self, starts: Any, steps: int, burn_in: int = 0, seed: int = 1
    ) -> Dict[str, np.ndarray]:
        """Runs vanefit's affine-invariant ensemble sampler (the stretch move, as emcee) on
        :meth:`log_posterior` from ``starts`` (walkers × parameters, sampling coordinates).
        Returns a :class:`Samples` dict: ``chain`` (steps × walkers × parameters, emcee's
        ``get_chain()`` layout, sampling coordinates), ``log_prob`` (steps × walkers),
        ``acceptance`` (per walker) and ``names``; ``.to_arviz()`` gives them as an
        ``arviz.InferenceData``. The same seed gives the same chains whatever the thread
        count."""
        x0 = [[float(v) for v in row] for row in np.asarray(starts, dtype=float)]
        chains, lp, acc = self._core.sample(x0, int(steps), int(burn_in), int(seed))
        return Samples(
            chain=np.transpose(np.asarray(chains), (1, 0, 2)),
            log_prob=np.asarray(lp).T,
            acceptance=np.asarray(acc),
            names=self.names,
            units="coords",
            sampler="ensemble",
        )


def chain_diagnostics(chains: Any) -> Dict[str, np.ndarray]:
    """vanefit's convergence diagnostics of ``chains`` (chain × draw × parameter): the
    rank-normalised split-R̂, bulk and tail effective sample sizes (Vehtari et al. 2021), as
    ``predict.md`` and ``bands.json`` report them. For an ensemble, each walker is a chain."""
    a = np.asarray(chains, dtype=float)
    d = np.asarray(_core.chain_diagnostics(a.tolist()))
    return {"rhat": d[:, 0], "ess_bulk": d[:, 1], "ess_tail": d[:, 2]}


def likelihood(ds: Dataset, fit: Union[Fit, PathLike], priors: bool = True) -> Likelihood:
    """The :class:`Likelihood` of ``fit`` (a :class:`Fit` or a fit file's path) on ``ds``
    (with the fit's motor prior unless ``priors=False``)."""
    return Likelihood(ds, fit, priors)


def _find_dataset(fit_path: str, text: Optional[str]) -> str:
    """The fit's dataset folder by the rule ``vanefit predict`` follows (the fit file's
    ``dataset_path``, else ``measurements/<name>`` beside the fit file's folder or in the
    current folder); :class:`DataError` saying where it looked when it is not found."""
    found, said = _core.find_dataset(fit_path, text)
    if found is None:
        raise DataError(f"{fit_path}: {said}; name it with dataset=")
    return found


def export_petab(
    fit: Union[Fit, PathLike], out: PathLike, dataset: Optional[Union[Dataset, PathLike]] = None
) -> Dict[str, Any]:
    """Writes the fit as a PEtab v1 problem into ``out`` (as ``vanefit export-petab``):
    ``parameters.tsv``, ``observables.tsv``, ``measurements.tsv``, ``conditions.tsv``,
    ``model.xml`` (SBML declaring the model's symbols; the dynamics are vanefit's),
    ``problem.yaml`` and ``vanefit_export.json``. ``dataset``: the fit's dataset (default:
    ``measurements/<name>`` beside the fit file's folder, or in the current folder).
    Returns the summary (``measurements``, ``observables``, ``conditions``, ``chi2_rows``,
    ``chi2_priors``, ``chi2`` = their sum (the likelihood's), ``chi2_motor_priors``,
    ``objective`` = all three (the fit's)) with ``yaml``, the problem file's path. See
    :mod:`vanefit.petab` to evaluate the tables with vanefit's simulation."""
    path, text = _fit_source(fit)
    if isinstance(dataset, Dataset):
        dataset = dataset.path
    if dataset is None:
        dataset = _find_dataset(path, text)
    if text is not None and path == "<fit>":
        # A fit held in memory goes into the export beside its tables, so that
        # vanefit_export.json names a file that vanefit.petab can rebuild it from.
        Path(out).mkdir(parents=True, exist_ok=True)
        path, text = os.fspath(Path(out) / "fit.json"), None
        Path(path).write_text(fit.to_json() if isinstance(fit, Fit) else json.dumps(fit))
    summary = json.loads(_core.export_petab(path, text, os.fspath(dataset), os.fspath(out)))
    summary["chi2"] = summary["chi2_rows"] + summary["chi2_priors"]
    summary["yaml"] = os.fspath(Path(out) / "problem.yaml")
    return summary


def export_fmu(
    fit: Union[Fit, PathLike], out: PathLike, binary: Optional[PathLike] = None
) -> Dict[str, Any]:
    """Writes the fitted motor as an FMU (FMI 2.0, model exchange and co-simulation, linux64)
    to the file ``out``, as ``vanefit export-fmu`` (docs/fmu.md). ``fit``: a :class:`Fit`
    (held in memory or read from a file) or a fit file's path. ``binary``: the FMU's shared
    library ``libvanefit_fmu.so`` (default: ``$VANEFIT_FMU_BINARY``, else the one
    ``cargo build --release`` left in the target folder of the source tree this package was
    built from). Returns ``variables``, ``model_parameters``, ``bytes``, ``guid``,
    ``binary`` (the library packed) and ``path`` (the FMU). A fit with an effect the FMU
    cannot carry (``sensor_lag``, ``valve_dynamics``) raises :class:`ParameterError`."""
    path, text = _fit_source(fit)
    summary = json.loads(_core.export_fmu(
        path, text, os.fspath(out), None if binary is None else os.fspath(binary)
    ))
    summary["path"] = os.fspath(out)
    return summary

def diagnose(
    ds: Dataset,
    starts: int = 4,
    seed: int = 1,
    threads: Optional[int] = None,
    out: Optional[PathLike] = None,
    progress: Progress = None,
) -> Diagnosis:
    """Diagnoses the dataset as ``vanefit diagnose`` does: where the base model misses,
    which missing physics explains it, the refit. Returns a :class:`Diagnosis`
    (``.locations``, ``.candidates``, ``.selected``, ``.extended_fit``, ``.summary``,
    ``.plot``). ``progress``: ``True`` for a tqdm line of the phases, or a callable
    ``progress(elapsed_s, message)`` called at every phase; ``out`` also writes the report,
    its plots and the JSON there. The diagnosis runs with the GIL released; Ctrl-C is
    raised when it returns."""
    if isinstance(ds, (str, os.PathLike)):
        ds = load_dataset(ds)
    with diagnose_progress(progress) as callback:
        text, extended, summary = _core.diagnose(
            ds._core,
            int(starts),
            int(seed),
            None if threads is None else int(threads),
            None if out is None else os.fspath(out),
            callback,
        )
    return Diagnosis(text, extended, summary)


def predict(
    fit: Union[Fit, PathLike],
    pressures: Optional[Sequence[float]] = None,
    unit: str = "bar_g",
    reference: Optional[float] = None,
    inlet_nozzle: Optional[float] = None,
    outlet_nozzle: Optional[float] = None,
    speed_grid_rpm: float = 1.0,
    curve_points: int = 41,
    fixed_spread: Optional[float] = None,
    out: Optional[PathLike] = None,
    data: Optional[Union[Dataset, PathLike]] = None,
    bands: str = "auto",
    steps: Optional[int] = None,
    burn_in: Optional[int] = None,
    draws: Optional[int] = None,
    seed: Optional[int] = None,
    progress: Progress = None,
) -> Prediction:
    """The fitted motor at other supply pressures (in ``unit``: ``bar_g``, ``pa``, ``mpa``,
    ...; default 3, 4, 5, 6, 7 bar g) or behind a nozzle (sonic conductance, m³/(s·Pa)), as
    ``vanefit predict``: a :class:`Prediction` with the DataFrames ``catalogue``,
    ``factors`` and ``curves`` (the command's columns and numbers, 95 % bands as
    ``_lo``/``_hi``), its ``notes`` and ``report``. ``fit``: a :class:`Fit` or a fit file's
    path. ``reference``: the correction factors' reference pressure (default 6.3 bar g).
    ``out``: also write the command's files (CSV, ``predict.md``, SVG figures) there.

    ``bands``: ``"auto"`` (default: posterior samples of the fit's dataset when they
    converged, R̂ < 1.01 and ESS ≥ 400, else the delta method), ``"delta"`` (instant) or
    ``"samples"`` (the samples, converged or not). ``data``: the fit's dataset (a
    :class:`Dataset` or its folder); by default the one the fit file records
    (``dataset_path``), else ``measurements/<name>`` beside the fit file's folder or in the
    current folder. ``steps``, ``burn_in``, ``draws``, ``seed``: the sampler's (defaults
    as ``vanefit predict``). Which method made the bands and why: ``.method``, ``.bands``;
    the samples' summary ``.posterior`` and, when samples were drawn, ``.samples`` and
    ``.to_arviz()`` (SI values). ``progress``: ``True`` for a tqdm bar, or a callable
    ``progress(stage, done, total)`` at each tenth of the sampling."""
    path, text = _fit_source(fit)
    if isinstance(data, Dataset):
        data = data.path
    with predict_progress(progress) as callback:
        doc, kept = _core.predict(
            path, text,
            None if pressures is None else [float(p) for p in pressures],
            str(unit),
            None if reference is None else float(reference),
            None if inlet_nozzle is None else float(inlet_nozzle),
            None if outlet_nozzle is None else float(outlet_nozzle),
            float(speed_grid_rpm),
            int(curve_points),
            None if fixed_spread is None else float(fixed_spread),
            None if out is None else os.fspath(out),
            None if data is None else os.fspath(data),
            str(bands),
            None if steps is None else int(steps),
            None if burn_in is None else int(burn_in),
            None if draws is None else int(draws),
            None if seed is None else int(seed),
            None,
            callback,
        )
    doc = json.loads(doc)
    samples = None
    if kept is not None:
        values, lp, (walkers, steps_kept, d), acceptance = kept
        chain = np.frombuffer(values, dtype="<f8").reshape(walkers, steps_kept, d)
        samples = Samples(
            chain=np.transpose(chain, (1, 0, 2)),
            log_prob=np.frombuffer(lp, dtype="<f8").reshape(walkers, steps_kept).T,
            acceptance=np.asarray(acceptance),
            names=list(doc["sampled"]),
            units="SI",
            sampler=doc["bands"]["sampling"]["sampler"],
        )
    return Prediction(doc, samples)


def plan(
    fit: Union[Fit, PathLike],
    pressures: Sequence[float],
    unit: str = "bar_g",
    speeds: Optional[Sequence[float]] = None,
    candidates: Optional[Sequence[str]] = None,
    costs: Optional[Mapping[str, float]] = None,
    fixed_spread: Optional[float] = None,
    top: int = 3,
    out: Optional[PathLike] = None,
) -> Plan:
    """Which measurement next, as ``vanefit plan`` (docs/plan.md): the candidate
    measurements ranked by how much they are expected to shrink the 95 % bands at the
    operating ``pressures`` (in ``unit``) and, given, ``speeds`` (rpm), per hour of rig
    time. ``candidates``: the kinds weighed (``key_figures``, ``stall_torque``,
    ``air_flow``, ``datasheet``, ``pressure_ramp``, ``outlet_throttle``, ``load_step``;
    default all); ``costs``: rig hours by kind, e.g. ``{"datasheet": 3}``; ``top``: how
    many are detailed in the report. Returns a :class:`Plan` (``ranking`` DataFrame, the
    ``plan.json`` document, ``report``). ``out``: also write ``plan.md`` and
    ``plan.json`` there."""
    path, text = _fit_source(fit)
    return Plan(json.loads(_core.plan(
        path, text,
        [float(p) for p in pressures],
        str(unit),
        None if speeds is None else [float(w) for w in speeds],
        None if candidates is None else [str(c) for c in candidates],
        None if costs is None else [(str(k), float(v)) for k, v in costs.items()],
        None if fixed_spread is None else float(fixed_spread),
        int(top),
        None if out is None else os.fspath(out),
    )))


_MOTOR = {"effects": None, "brake_nm_s_rad": None}
_VALVE = {"valve_tau_s": None, "valve_u_max_v": 10.0, "valve_p_max_bar_g": 6.0}
_PI = {"ts_ms": 1.0, "speed_unit_rpm": 1000.0, "anti_windup": "conditional"}
_GAINS = {"kp": 0.85, "ki": 4.0}
_THROTTLE = {"p_supply_mpa": 0.73, "c_min_m3_s_pa": 3e-10, "c_max_m3_s_pa": 1e-7, "points": 40,
             "curves_m3_s_pa": "none,1e-8,4e-9,2e-9,1e-9"}

#: Every control study's options with their defaults (those of ``vanefit control <study>``;
#: a test compares them with the command's ``--help``). ``None``: the study's or the
#: motor's own (``valve_tau_s``: the parameter set's ``valve_tau``; ``brake_nm_s_rad``:
#: 1e-4 N·m·s/rad, none for ``min-speed``; ``effects``: the fit's).
CONTROL_STUDIES: Dict[str, Dict[str, Any]] = {
    "throttle-inlet": {**_MOTOR, **_THROTTLE},
    "throttle-outlet": {**_MOTOR, **_THROTTLE},
    "bode": {**_MOTOR, **_VALVE, "p_mean_mpa": 0.35, "f_min_hz": 0.01, "f_max_hz": 100.0,
             "points": 200},
    "step": {**_MOTOR, **_VALVE, **_PI, **_GAINS, "from_rpm": 3000.0, "to_rpm": 4500.0,
             "t_step_s": 0.5, "duration_s": 8.0},
    "disturbance": {**_MOTOR, **_VALVE, **_PI, **_GAINS, "rpm": 4000.0, "load_step_nm": 0.03,
                    "t_step_s": 0.5, "duration_s": 8.0},
    "min-speed": {**_MOTOR, **_VALVE, **_PI, **_GAINS, "p_max_mpa": 0.73, "ramp_s": 60.0,
                  "factor": 0.8, "floor_rpm": None, "stage_s": 5.0},
    "design": {**_MOTOR, **_VALVE, **_PI, "pm_deg": 60.0, "crossover_hz": None,
               "p_mean_mpa": 0.35, "step_rpm": 300.0, "duration_s": 5.0},
}


def control(
    study: str,
    params: Optional[Union[Fit, PathLike]] = None,
    out: Optional[PathLike] = None,
    **options: Any,
) -> StudyResult:
    """A speed-control study of paper §5 as ``vanefit control <study>`` (``bode``, ``step``,
    ``disturbance``, ``design``, ``throttle-inlet``, ``throttle-outlet``, ``min-speed``) on
    the motor of a fit (a :class:`Fit` or a fit file's path; default: the AR034 motor).
    ``options`` are the study's options by name (``kp=..., ki=..., pm_deg=60,
    p_mean_mpa=0.35``; every study's, with defaults: :data:`CONTROL_STUDIES`). Returns a
    :class:`StudyResult`: every table the study writes (DataFrames in ``result.tables``, or
    ``result["step"]``) and its JSON summaries (``result["design"]``); ``out`` also writes
    its files and figures there. Runs with the GIL released."""
    if study not in CONTROL_STUDIES:
        raise ParameterError(f"study {study!r}: one of {', '.join(CONTROL_STUDIES)}")
    known = CONTROL_STUDIES[study]
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise ParameterError(
            f"{study}: no option {', '.join(unknown)}; its options are {', '.join(known)}"
        )
    given = {**known, **options}
    if isinstance(given["effects"], (list, tuple)):
        given["effects"] = ",".join(given["effects"])
    path, text = (None, None) if params is None else _fit_source(params)
    tables, summaries = _core.control(
        study, path, text, json.dumps(given), None if out is None else os.fspath(out)
    )
    return StudyResult(
        study,
        {name: dict(cols) for name, cols in tables},
        {name: json.loads(doc) for name, doc in summaries},
        None if out is None else os.fspath(out),
    )


def synth(
    out: PathLike,
    params: Optional[Union[Fit, PathLike]] = None,
    effects: Optional[Sequence[str]] = None,
    noise: float = 1.0,
    seed: int = 1,
    catalogue: bool = False,
    pressures_bar_g: Sequence[float] = (6.3,),
) -> Dataset:
    """Writes a synthetic dataset into ``out`` (the three reference experiments with typical
    sensor noise times ``noise``, and ``truth.json``) from the motor of a fit (default: the
    AR034 motor) with the catalogued ``effects`` switched on (default: the fit's), as
    ``vanefit synth``, and loads it. ``catalogue=True`` writes catalogue pages at
    ``pressures_bar_g`` instead of rig recordings."""
    path, text = (None, None) if params is None else _fit_source(params)
    _core.synth(
        os.fspath(out), path, text,
        None if effects is None else [str(e) for e in effects],
        float(noise), int(seed), bool(catalogue), [float(p) for p in pressures_bar_g],
    )
    return load_dataset(out)

