"""The results of vanefit as objects: :class:`Fit`, :class:`Diagnosis`, :class:`Prediction`
and :class:`StudyResult`.

Each holds the document the command line writes (a fit file, ``diagnosis.json``, the
prediction's CSV tables, a control study's tables), byte for byte where it is a file, and
shows it as pandas DataFrames, dataclasses and figures:

* ``fit.parameters`` — one row per parameter (value, lower, upper, unit, estimated,
  identifiable, meaning), ``fit.starts`` — one row per start, ``fit.statistics`` —
  :class:`FitStatistics`, ``fit.profiles`` — one DataFrame per profiled parameter;
* ``fit.plot.waterfall()`` and the other figures of :mod:`vanefit.plot`;
* ``fit.to_json()`` / ``fit.write(path)`` / ``Fit.read(path)`` — the ``vanefit.fit/1`` file,
  exactly as ``vanefit fit`` writes it, so the command line and Python read each other's.

pandas is needed for the tables (imported when a table is asked for), matplotlib for the
figures.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Dict, List, Mapping, Optional, Union

import numpy as np

from . import _core

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd
    from matplotlib.figure import Figure

PathLike = Union[str, "os.PathLike[str]"]

__all__ = [
    "Fit",
    "FitStatistics",
    "Diagnosis",
    "Prediction",
    "Samples",
    "StudyResult",
]


def _pd():
    import pandas as pd

    return pd


def _words() -> Dict[str, str]:
    from .plot import PARAMETER_WORDS

    return PARAMETER_WORDS


@dataclasses.dataclass(frozen=True)
class FitStatistics:
    """How well a fit fits (the fit file's ``statistics`` with ``cost``).

    ``chi2`` is the one χ² the report prints: the recorded rows against the data's own
    noise σ at the estimate, over ``n_points`` rows with ``dof`` = n − k degrees of
    freedom. ``cost`` is J, the multi-start's objective at the estimate (each channel's
    mean squared deviation from its reference polynomial, in units of that polynomial's
    scatter, summed over the channels): it ranks starts, it is not a χ².
    ``likelihood_chi2`` is χ² of the likelihood the estimate maximises and the intervals
    are profiled on (noise widened where a channel's scatter exceeds it, the sensor
    offsets' priors included); a 95 % profile interval ends where it rises by
    ``profile_threshold``."""

    chi2: float
    n_points: int
    dof: int
    chi2_per_dof: Optional[float]
    noise_ratio: float
    noise_ratio_limit: float
    noise_reached: bool
    cost: Optional[float]
    best_start_cost: float
    interval_scale: float
    uncertainty: str
    likelihood_chi2: Optional[float]
    profile_threshold: Optional[float]
    nuisances: Dict[str, float]
    widened_noise: Dict[str, float]

    @classmethod
    def _of(cls, doc: Mapping[str, Any]) -> Optional["FitStatistics"]:
        s = doc.get("statistics")
        if not s:
            return None
        return cls(
            chi2=s["chi2"], n_points=s["n_points"], dof=s["dof"],
            chi2_per_dof=s["chi2_per_dof"], noise_ratio=s["noise_ratio"],
            noise_ratio_limit=s["noise_ratio_limit"], noise_reached=s["noise_reached"],
            cost=doc.get("cost"), best_start_cost=s["best_start_cost"],
            interval_scale=s["interval_scale"], uncertainty=s["uncertainty"],
            likelihood_chi2=s.get("likelihood_chi2"),
            profile_threshold=s.get("profile_threshold"),
            nuisances=dict(s.get("nuisances", {})),
            widened_noise=dict(s.get("widened_noise", {})),
        )

    def __str__(self) -> str:
        verdict = ("the model explains the data to within their noise" if self.noise_reached
                   else "the model misses")
        per_dof = ("undefined" if self.chi2_per_dof is None
                   else f"{self.chi2_per_dof:.3f}")
        return (f"chi2 {self.chi2:.1f} over {self.n_points} rows (dof {self.dof}, "
                f"chi2/dof {per_dof}); noise ratio {self.noise_ratio:.3f} "
                f"(limit {self.noise_ratio_limit:.3f}): {verdict}")


class _Plots:
    """Figures of one result: each method returns a matplotlib Figure (see
    :mod:`vanefit.plot`)."""

    def __init__(self, owner: Any):
        self._owner = owner

    def __repr__(self) -> str:
        names = [n for n in dir(self) if not n.startswith("_")]
        return f"<figures: {', '.join(names)}>"


class FitPlots(_Plots):
    """``fit.plot.waterfall()``, ``.parameters()``, ``.profiles()``, ``.overlay(ds)``,
    ``.residuals(ds)``."""

    def waterfall(self, **kw: Any) -> "Figure":
        """The sorted final cost of every start (:func:`vanefit.plot.waterfall`)."""
        from . import plot

        return plot.waterfall(self._owner, **kw)

    def parameters(self, **kw: Any) -> "Figure":
        """Every estimated parameter at every start's end (:func:`vanefit.plot.parameters`)."""
        from . import plot

        return plot.parameters(self._owner, **kw)

    def profiles(self, **kw: Any) -> "Figure":
        """The likelihood profiles with the 95 % threshold (:func:`vanefit.plot.profiles`)."""
        from . import plot

        return plot.profiles(self._owner, **kw)

    def overlay(self, ds: Any, **kw: Any) -> "Figure":
        """Recorded against simulated on dataset ``ds`` (:func:`vanefit.plot.overlay`)."""
        from . import plot

        return plot.overlay(ds, self._owner, **kw)

    def residuals(self, ds: Any, **kw: Any) -> "Figure":
        """Recorded minus simulated on dataset ``ds`` (:func:`vanefit.plot.residuals`)."""
        from . import plot

        return plot.residuals(ds, self._owner, **kw)


class Fit:
    """A fit: the ``vanefit.fit/1`` file (what ``vanefit fit`` writes, held byte for byte)
    and, when it was made in this session, every start of its multi-start.

    Made by :func:`vanefit.fit`, read by :meth:`Fit.read`; every function that takes
    parameters (:func:`vanefit.simulate`, :func:`vanefit.cost`, :func:`vanefit.predict`,
    ...) takes a Fit."""

    def __init__(self, text: str, starts: Optional[List[Dict[str, Any]]] = None,
                 path: Optional[PathLike] = None):
        self._text = text
        self._doc: Dict[str, Any] = json.loads(text)
        self._starts = starts
        #: The file it was read from or written to (None: held in memory only).
        self.path: Optional[str] = None if path is None else os.fspath(path)

    # -- files ---------------------------------------------------------------------------

    @classmethod
    def read(cls, path: PathLike) -> "Fit":
        """Reads and checks a fit file; :class:`vanefit.DataError` names file and line."""
        return cls(_core.read_fit(os.fspath(path)), path=path)

    @classmethod
    def from_json(cls, text: str) -> "Fit":
        """A fit from fit-file text (checked as a file would be)."""
        return cls(_core.read_fit("<fit>", text))

    def to_json(self) -> str:
        """The fit file's text, exactly as ``vanefit fit`` writes it."""
        return self._text

    def write(self, path: PathLike) -> None:
        """Writes the fit file (the bytes of :meth:`to_json`) and remembers ``path``."""
        Path(path).write_text(self._text)
        self.path = os.fspath(path)

    @property
    def document(self) -> Dict[str, Any]:
        """The fit file as a dict (a copy)."""
        return json.loads(self._text)

    # -- what it says --------------------------------------------------------------------

    @property
    def dataset(self) -> str:
        """Name of the dataset fitted."""
        return self._doc.get("dataset", "")

    @property
    def effects(self) -> List[str]:
        """Catalogued effects of the model (ids)."""
        return list(self._doc.get("model", {}).get("effects", []))

    @property
    def cost(self) -> Optional[float]:
        """J at the estimate (None for a plain parameter file)."""
        return self._doc.get("cost")

    @property
    def seed(self) -> Optional[int]:
        return self._doc.get("seed")

    @property
    def values(self) -> Dict[str, float]:
        """Every parameter's value, SI, by name."""
        return {k: v["value"] for k, v in self._doc["parameters"].items()}

    @property
    def estimated(self) -> List[str]:
        """Names of the estimated parameters, in the file's order."""
        return [k for k, v in self._doc["parameters"].items() if v.get("estimated")]

    @property
    def parameters(self) -> "pd.DataFrame":
        """One row per parameter, indexed by name: ``value`` (SI), ``lower``/``upper`` (the
        95 % interval, NaN where none was computed), ``unit`` (SI), ``estimated``,
        ``identifiable`` (None where not assessed) and ``meaning`` (in words)."""
        words = _words()
        rows = []
        for name, p in self._doc["parameters"].items():
            lo, hi = p.get("ci95") or (np.nan, np.nan)
            rows.append({
                "parameter": name, "value": p["value"], "lower": lo, "upper": hi,
                "unit": p["unit"], "estimated": bool(p.get("estimated")),
                "identifiable": p.get("identifiable"), "meaning": words.get(name, ""),
            })
        return _pd().DataFrame(rows).set_index("parameter")

    @property
    def statistics(self) -> Optional[FitStatistics]:
        """How well it fits (None for a plain parameter file)."""
        return FitStatistics._of(self._doc)

    @property
    def has_starts(self) -> bool:
        """Whether the starts of the multi-start are known (a fit made in this session)."""
        return bool(self._starts)

    @property
    def starts(self) -> "pd.DataFrame":
        """One row per start of the multi-start, indexed by start: ``cost`` (J at its end),
        ``ending``, ``iterations``, ``evaluations``, then each estimated parameter's end
        value (SI). Empty for a fit read from a file (the file keeps the estimate only)."""
        pd = _pd()
        if not self._starts:
            return pd.DataFrame(columns=["cost", "ending", "iterations", "evaluations"])
        rows = [{"start": s["index"], "cost": s["cost"], "ending": s["ending"],
                 "iterations": s["iterations"], "evaluations": s["evaluations"],
                 **s["parameters"]} for s in self._starts]
        return pd.DataFrame(rows).set_index("start")

    @property
    def profiles(self) -> Dict[str, "pd.DataFrame"]:
        """Each profiled parameter's likelihood profile: a DataFrame of ``value`` (SI,
        increasing) and ``delta_chi2`` (the rise of the likelihood's χ² with the others
        re-fitted). Empty without profile intervals."""
        pd = _pd()
        return {name: pd.DataFrame({"value": p["value"], "delta_chi2": p["delta_chi2"]})
                for name, p in self._doc.get("profiles", {}).items()}

    @property
    def covariance(self) -> Optional["pd.DataFrame"]:
        """Covariance of the estimated parameters' logarithms (None if not computed)."""
        c = self._doc.get("covariance")
        if not c:
            return None
        return _pd().DataFrame(c["matrix"], index=c["parameters"], columns=c["parameters"])

    @property
    def plot(self) -> FitPlots:
        """Figures: ``fit.plot.waterfall()``, ``.parameters()``, ``.profiles()``,
        ``.overlay(ds)``, ``.residuals(ds)``."""
        return FitPlots(self)

    def _plot_document(self) -> Dict[str, Any]:
        """The dict :mod:`vanefit.plot` draws: the file plus ``start_results``."""
        doc = self.document
        if self._starts:
            doc["start_results"] = self._starts
        return doc

    def __repr__(self) -> str:
        where = f" at {self.path!r}" if self.path else ""
        s = self.statistics
        how = f": {s}" if s else ""
        return f"vanefit.Fit(dataset {self.dataset!r}{where}, {len(self.estimated)} estimated{how})"


class DiagnosisPlots(_Plots):
    """``diagnosis.plot.candidates()``, ``.residuals(ds)``."""

    def candidates(self, **kw: Any) -> "Figure":
        """The candidates ranked by ΔBIC (:func:`vanefit.plot.candidates`)."""
        from . import plot

        return plot.candidates(self._owner.document, **kw)

    def residuals(self, ds: Any, base: Any = None, **kw: Any) -> "Figure":
        """Residuals of ``base`` (a Fit, optional) and of the extended model on ``ds``."""
        from . import plot

        models = ([base] if base is not None else []) + [self._owner.extended_fit]
        labels = (["base model"] if base is not None else []) + [self._owner.extended_label]
        return plot.residuals(ds, models, labels=labels, **kw)


class Diagnosis:
    """A diagnosis: ``diagnosis.json`` as ``vanefit diagnose`` writes it, the extended
    model as a :class:`Fit`, and the summary paragraph the command prints."""

    def __init__(self, text: str, extended_text: str, summary: str):
        self._text = text
        self._doc: Dict[str, Any] = json.loads(text)
        #: The extended model (the base model with what was selected) as a fit.
        self.extended_fit = Fit(extended_text)
        #: The paragraph ``vanefit diagnose`` prints.
        self.summary = summary

    def to_json(self) -> str:
        """The text of ``diagnosis.json``, exactly as ``vanefit diagnose`` writes it."""
        return self._text

    def write(self, path: PathLike) -> None:
        """Writes ``diagnosis.json`` (the bytes of :meth:`to_json`)."""
        Path(path).write_text(self._text)

    @classmethod
    def read(cls, folder: PathLike) -> "Diagnosis":
        """A diagnosis from the folder ``vanefit diagnose --out`` wrote (``diagnosis.json``,
        ``extended.json``; the summary is not kept there and reads as '')."""
        folder = Path(folder)
        return cls((folder / "diagnosis.json").read_text(),
                   _core.read_fit(os.fspath(folder / "extended.json")), "")

    @property
    def document(self) -> Dict[str, Any]:
        """``diagnosis.json`` as a dict (a copy)."""
        return json.loads(self._text)

    @property
    def baseline(self) -> Dict[str, Any]:
        """The base model's fit: χ², noise ratio, parameters."""
        return dict(self._doc["baseline"])

    @property
    def extended(self) -> Dict[str, Any]:
        """The extended model's fit: χ², noise ratio, parameters."""
        return dict(self._doc["extended"])

    @property
    def mismatch(self) -> Any:
        return self._doc.get("mismatch")

    @property
    def locations(self) -> "pd.DataFrame":
        """Where the base model misses: one row per located range (experiment, channel,
        ``x_from``/``x_to`` in SI, severity in noise σ, ...)."""
        pd = _pd()
        rows = []
        for loc in self._doc.get("locations", []):
            r = dict(loc)
            lo, hi = r.pop("x_range", (np.nan, np.nan))
            rows.append({**r, "x_from": lo, "x_to": hi})
        return pd.DataFrame(rows)

    @property
    def candidates(self) -> "pd.DataFrame":
        """Every candidate explanation, best (lowest ΔBIC) first."""
        pd = _pd()
        df = pd.DataFrame(self._doc.get("candidates", []))
        return df.sort_values("delta_bic").reset_index(drop=True) if "delta_bic" in df else df

    @property
    def selected(self) -> "pd.DataFrame":
        """What was selected: one row per (effect, parameter) with its estimate."""
        rows = [{"effect": s["effect"], "category": s.get("category"), "parameter": k,
                 "estimate": v, "delta_bic": s.get("delta_bic")}
                for s in self._doc.get("selected", [])
                for k, v in (s.get("parameters") or {"": np.nan}).items()]
        return _pd().DataFrame(rows)

    @property
    def selected_effects(self) -> List[str]:
        return [s["effect"] for s in self._doc.get("selected", [])]

    @property
    def extended_label(self) -> str:
        sel = self.selected_effects
        return "+ " + " + ".join(sel) if sel else "extended model"

    @property
    def plot(self) -> DiagnosisPlots:
        """Figures: ``diagnosis.plot.candidates()``, ``.residuals(ds, base=fit)``."""
        return DiagnosisPlots(self)

    def __repr__(self) -> str:
        return (f"vanefit.Diagnosis(selected {self.selected_effects or 'nothing'}; "
                f"noise ratio {self.baseline.get('noise_ratio', float('nan')):.3f} -> "
                f"{self.extended.get('noise_ratio', float('nan')):.3f})")


def _read_csv(text: str) -> "pd.DataFrame":
    return _pd().read_csv(io.StringIO(text))


class Samples(dict):
    """Posterior samples of a fit, as a dict: ``chain`` (steps × walkers × parameters,
    emcee's ``get_chain()`` layout), ``log_prob`` (steps × walkers), ``acceptance`` (per
    walker) and ``names`` (the parameters), with :meth:`to_arviz`. ``units``: ``"SI"`` when
    ``chain`` holds SI values (a prediction's samples), ``"coords"`` when it holds the
    sampler's coordinates (ln θ of a log-scale parameter; :meth:`vanefit.Likelihood.sample`).
    ``sampler``: which sampler drew them (``"ensemble"``, ``"laplace_chains"``,
    ``"transport_chains"``; ``bands.json``'s ``sampling.sampler``)."""

    def to_arviz(self) -> Any:
        """The samples as an ``arviz.InferenceData``: group ``posterior`` with one variable
        per parameter (its name), dims ``chain`` × ``draw`` (each walker is a chain; the
        values as in ``chain``: SI, or the sampler's coordinates), and ``sample_stats``
        with ``lp`` (ln p of each sample) and ``acceptance_rate`` (each walker's over its
        kept steps, repeated over the draws). arviz's ``rhat``/``ess`` of it are those
        vanefit reports for the same chains."""
        import arviz as az

        chain = np.asarray(self["chain"])  # steps × walkers × d
        per_walker = np.transpose(chain, (1, 0, 2))  # walkers × steps × d
        posterior = {n: per_walker[:, :, i] for i, n in enumerate(self["names"])}
        lp = np.asarray(self["log_prob"]).T
        acc = np.repeat(np.asarray(self["acceptance"], dtype=float)[:, None], lp.shape[1], 1)
        return az.from_dict(
            posterior=posterior,
            sample_stats={"lp": lp, "acceptance_rate": acc},
            attrs={
                "units": self.get("units", "SI"),
                "sampler": f"vanefit {self.get('sampler', 'ensemble')}",
            },
        )


class _Reported:
    """A result of a command that writes a markdown report: its notes and the report's text
    (``report``, also what a notebook shows)."""

    _doc: Dict[str, Any]

    @property
    def notes(self) -> List[str]:
        return list(self._doc["notes"])

    @property
    def report(self) -> str:
        """The markdown of the command's report (``predict.md``, ``plan.md``)."""
        return self._doc["report"]

    def _repr_markdown_(self) -> str:
        return self.report


class Prediction(_Reported):
    """A prediction: the tables ``vanefit predict`` writes (``catalogue.csv``,
    ``factors.csv``, ``curves.csv``, same columns and numbers) as DataFrames, its notes and
    its report (``predict.md``); which method made the bands and why (:attr:`bands`,
    :attr:`method`), the posterior summary (:attr:`posterior`) and the samples
    (:attr:`samples`, :meth:`to_arviz`) when any were drawn."""

    def __init__(self, doc: Mapping[str, Any], samples: Optional["Samples"] = None):
        self._doc = dict(doc)
        self._samples = samples

    @property
    def bands(self) -> Dict[str, Any]:
        """``bands.json``: ``method`` (``"samples"`` or ``"delta"``), ``asked``
        (``"auto"``, ``"delta"``, ``"samples"``), ``reason`` (which method and why, one
        sentence), ``dataset`` (``found`` and ``where``, or ``None`` when none was needed),
        ``delta_unreliable`` (what in the fit file speaks against the delta method) and
        ``sampling`` (the posterior summary, or ``None``)."""
        return dict(self._doc["bands"])

    @property
    def method(self) -> str:
        """The method that made the bands: ``"samples"`` or ``"delta"``."""
        return self._doc["bands"]["method"]

    @property
    def posterior(self) -> Optional[Dict[str, Any]]:
        """The posterior samples' summary (walkers, steps, acceptance, ``converged``,
        ``rhat_max``, ``ess_min`` and per parameter its quantiles, R̂ and ESS), whether or
        not they made the bands; ``None`` when none were drawn."""
        return self._doc["bands"]["sampling"]

    @property
    def samples(self) -> Optional["Samples"]:
        """The kept posterior samples (SI values), or ``None`` when none were drawn."""
        return self._samples

    def to_arviz(self) -> Any:
        """The posterior samples as an ``arviz.InferenceData`` (:meth:`Samples.to_arviz`;
        values in SI units); :class:`ValueError` when none were drawn (``bands="delta"``,
        or no dataset)."""
        if self._samples is None:
            raise ValueError(f"no posterior samples: {self._doc['bands']['reason']}")
        return self._samples.to_arviz()

    @property
    def catalogue(self) -> "pd.DataFrame":
        """The catalogue figures at each supply pressure, 95 % bands as ``_lo``/``_hi``."""
        return _read_csv(self._doc["catalogue"])

    @property
    def factors(self) -> "pd.DataFrame":
        """The correction factors against the reference pressure."""
        return _read_csv(self._doc["factors"])

    @property
    def curves(self) -> "pd.DataFrame":
        """Torque, power and air against speed at each pressure, with bands."""
        return _read_csv(self._doc["curves"])


    @property
    def unit(self) -> str:
        """The pressure unit of the tables (a column suffix: ``bar_g``, ``mpa``, ...)."""
        return self._doc["unit"]

    @property
    def files(self) -> List[str]:
        """The files written (with ``out=``)."""
        return list(self._doc["written"])

    def csv(self, table: str) -> str:
        """A table's CSV text exactly as ``vanefit predict`` writes it."""
        return self._doc[table]

    def __repr__(self) -> str:
        return f"vanefit.Prediction({len(self.catalogue)} pressure(s), unit {self.unit})"


class Plan(_Reported):
    """Which measurement next (``vanefit plan``): the candidates ranked, as a DataFrame
    (``ranking``), the whole ``plan.json`` document (``doc``), the notes and the report
    (``plan.md``)."""

    def __init__(self, doc: Mapping[str, Any]):
        self._doc = dict(doc)
        #: What ``plan.json`` holds (SI).
        self.doc: Dict[str, Any] = dict(self._doc["plan"])

    @property
    def ranking(self) -> "pd.DataFrame":
        """One row per candidate, best V per hour first: kind, supply pressure (in the
        plan's unit, empty for a ramp), cost in hours, V (variance removed), V per hour,
        D (nats) and the mean expected shrinkage of the bands."""
        pd = _pd()
        unit = self._doc["unit"]
        rows = []
        for c in self.doc["ranked"]:
            rows.append({
                "kind": c["kind"],
                "p_supply_pa": c["p_supply_pa"],
                "cost_h": c["cost_h"],
                "v_reduction": c["v_reduction"],
                "v_per_hour": c["v_per_hour"],
                "d_gain_nats": c["d_gain_nats"],
                "mean_shrinkage": c["mean_shrinkage"],
            })
        frame = pd.DataFrame(rows)
        frame.attrs["unit"] = unit
        return frame


    @property
    def written(self) -> List[str]:
        """The files written (none without ``out``)."""
        return list(self._doc["written"])

    def __repr__(self) -> str:
        best = self.doc["ranked"][0]["kind"] if self.doc["ranked"] else "nothing"
        return f"vanefit.Plan({len(self.doc['ranked'])} candidates, best {best})"


class StudyResult:
    """A control study's results: each table it writes as a DataFrame (``result["step"]``,
    ``result.tables``), each JSON summary as a dict (``result.summaries``), and the folder
    with its files and figures."""

    def __init__(self, study: str, tables: Mapping[str, Any], summaries: Mapping[str, Any],
                 folder: Optional[str], report: str = ""):
        self.study = study
        self._tables = dict(tables)
        #: The study's JSON summaries by name (``design``, ``bode_fit``, ...).
        self.summaries: Dict[str, Any] = dict(summaries)
        #: Where its files are (None: nothing written).
        self.folder = folder
        #: The study's report in markdown.
        self.report = report

    @property
    def tables(self) -> Dict[str, "pd.DataFrame"]:
        """Every table by name, as DataFrames."""
        pd = _pd()
        return {k: pd.DataFrame(v) for k, v in self._tables.items()}

    def __getitem__(self, name: str) -> Any:
        """A table (as a dict of numpy arrays, which :mod:`vanefit.plot` and pandas read)
        or a summary (a dict) by name."""
        if name in self._tables:
            return {k: np.asarray(v) for k, v in self._tables[name].items()}
        if name in self.summaries:
            return self.summaries[name]
        raise KeyError(f"{name!r}: this {self.study} study has "
                       f"{', '.join(list(self._tables) + list(self.summaries))}")

    def __contains__(self, name: object) -> bool:
        return name in self._tables or name in self.summaries

    def keys(self) -> List[str]:
        return list(self._tables) + list(self.summaries)

    def _repr_markdown_(self) -> str:
        return self.report

    def __repr__(self) -> str:
        return f"vanefit.StudyResult({self.study}: {', '.join(self.keys())})"
