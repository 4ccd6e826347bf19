"""PEtab problems written by ``vanefit export-petab``, evaluated with vanefit's simulation.

A vanefit PEtab export declares the model's symbols in SBML but not its dynamics: the
simulated outputs come from vanefit. :func:`simulation_table` gives PEtab's simulation table
(the measurement table with a ``simulation`` column) at the fit, by evaluating every
observable's formula with the ``petab`` library's own parser on vanefit's simulated rows,
the nuisance parameters' nominal values and each row's ``observableParameters``;
:func:`chi2` then lets ``petab.calculate_chi2`` compute χ² from the tables.

Needs the optional packages ``petab``, ``pandas`` and ``sympy``
(``pip install petab``)."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Dict, Optional, Union

import numpy as np

PathLike = Union[str, "os.PathLike[str]"]


def _problem(problem_yaml: PathLike):
    from petab import v1 as petab

    return petab.Problem.from_yaml(os.fspath(problem_yaml))


def _summary(problem_yaml: PathLike) -> Dict[str, Any]:
    return json.loads((Path(problem_yaml).parent / "vanefit_export.json").read_text())


def simulation_table(
    problem_yaml: PathLike,
    dataset: Optional[PathLike] = None,
    fit: Optional[PathLike] = None,
):
    """PEtab's simulation table of an exported problem at the fit: the measurement table
    with ``measurement`` replaced by the simulated observable under column ``simulation``.

    ``dataset``/``fit``: where the dataset and fit file are, if not where
    ``vanefit_export.json`` says (paths there are as given on the command line, relative to
    the folder it was run in)."""
    return _simulation_table(_problem(problem_yaml), problem_yaml, dataset, fit)


def _simulation_table(problem, problem_yaml: PathLike, dataset, fit):
    """:func:`simulation_table` of an already loaded problem."""
    import sympy
    from petab.v1.math import sympify_petab

    from . import Likelihood, load_dataset

    summary = _summary(problem_yaml)
    ds = load_dataset(dataset if dataset is not None else summary["dataset"])
    lik = Likelihood(ds, fit if fit is not None else summary["fit"])
    rows = lik.breakdown(lik.x_hat)
    observables = problem.observable_df
    by_name = {name: oid for oid, name in observables["observableName"].items()}
    nominal = problem.parameter_df["nominalValue"].astype(float).to_dict()
    m = problem.measurement_df.copy()
    sim = np.full(len(m), np.nan)
    for channel in rows["channels"]:
        oid = by_name[f"{channel['file']} {channel['column']}"]
        where = np.flatnonzero((m["observableId"] == oid).to_numpy())
        if len(where) != len(channel["rows"]) or not np.array_equal(
            m["measurement"].to_numpy()[where], channel["data"]
        ):
            raise ValueError(
                f"observable {oid}: the measurement table does not hold the fit's rows"
            )
        expr = sympify_petab(observables.loc[oid, "observableFormula"])
        values = {}
        for sym in expr.free_symbols:
            name = str(sym)
            if name.startswith("observableParameter"):
                k = int(name[len("observableParameter") :].split("_", 1)[0]) - 1
                cells = m["observableParameters"].to_numpy()[where]
                values[sym] = np.array([float(str(c).split(";")[k]) for c in cells])
            elif name in nominal:
                values[sym] = nominal[name]
            else:
                # The model output: vanefit's simulated rows.
                values[sym] = np.asarray(channel["simulated"], dtype=float)
        f = sympy.lambdify(list(values), expr, modules="numpy")
        sim[where] = np.broadcast_to(f(*values.values()), where.shape)
    if np.isnan(sim).any():
        raise ValueError("some measurements belong to no channel the fit compares")
    out = m.rename(columns={"measurement": "simulation"})
    out["simulation"] = sim
    return out


def prior_chi2(problem_yaml: PathLike) -> float:
    """Σ((nominal − mean)/sd)² over the parameters' ``objectivePrior`` at their nominal
    values, each on its own scale: the priors' part of χ² (−2 ln of the prior densities up
    to their constants), which ``petab.calculate_chi2`` (measurements only) does not count.
    The nuisances' ``normal`` priors and the motor prior's ``parameterScaleNormal`` ones
    (docs/python.md, "The motor prior in PEtab")."""
    return _prior_chi2(_problem(problem_yaml).parameter_df)


def _prior_term(kind: str, parameters: str, value: float, scale: str) -> float:
    """((x − μ)/σ)² of one objective prior at ``value`` (linear), x on the prior's scale:
    the value itself (``normal``), its natural log (``logNormal``, whose parameters are
    those of ln x) or its value on ``parameterScale`` (``parameterScaleNormal``)."""
    mean, sd = (float(v) for v in str(parameters).split(";"))
    if kind == "normal":
        x = value
    elif kind == "logNormal":
        x = np.log(value)
    elif kind == "parameterScaleNormal":
        x = {"lin": value, "log": np.log(value), "log10": np.log10(value)}[scale]
    else:
        raise ValueError(f"objectivePriorType {kind!r}: not one vanefit exports")
    return ((x - mean) / sd) ** 2


def _prior_chi2(p, kinds: Optional[tuple] = None) -> float:
    """:func:`prior_chi2` of a loaded parameter table (only the prior types ``kinds`` if
    given)."""
    total = 0.0
    if "objectivePriorType" not in p:
        return total
    for _, row in p.iterrows():
        kind = row.get("objectivePriorType")
        if not isinstance(kind, str) or not kind or (kinds and kind not in kinds):
            continue
        total += _prior_term(
            kind,
            row["objectivePriorParameters"],
            float(row["nominalValue"]),
            str(row.get("parameterScale", "lin")),
        )
    return total


def _noise_parameter_rows(problem):
    """The rows of the parameter table that the noise model can name: the parameters in the
    observables' ``noiseFormula`` and in the measurements' ``noiseParameters``.
    ``petab.calculate_chi2`` reads the parameter table only to evaluate each row's noise
    formula, and for every row it puts each parameter of the table into a sympy
    substitution (``petab.v1.calculate.evaluate_noise_formula``). vanefit's noise formulas
    are constants, so none is needed, and the same χ² comes out bit for bit in less time
    (the shipped fit's export, 3 795 rows, 17 parameters: 16.0 → 13.9 s of one core)."""
    from petab.v1.math import sympify_petab

    names = set()
    for formula in problem.observable_df.get("noiseFormula", []):
        names |= {str(sym) for sym in sympify_petab(formula).free_symbols}
    if "noiseParameters" in problem.measurement_df:
        for cell in problem.measurement_df["noiseParameters"].dropna():
            names |= {part.strip() for part in str(cell).split(";")}
    table = problem.parameter_df
    return table.loc[[name for name in table.index if name in names]]


def chi2(
    problem_yaml: PathLike,
    dataset: Optional[PathLike] = None,
    fit: Optional[PathLike] = None,
) -> Dict[str, float]:
    """χ² of the exported problem at the fit as PEtab computes it: ``rows``
    (``petab.calculate_chi2`` on the tables with :func:`simulation_table`), ``priors`` (the
    nuisances' ``normal`` priors), ``motor_priors`` (the motor prior's
    ``parameterScaleNormal``/``logNormal`` terms) and ``total`` = all three, the fit's
    objective: ``statistics.likelihood_chi2`` + ``statistics.prior_chi2`` of the fit file
    (``likelihood`` = rows + priors is ``likelihood_chi2`` alone)."""
    from petab import v1 as petab

    problem = _problem(problem_yaml)
    sim = _simulation_table(problem, problem_yaml, dataset, fit)
    rows = float(
        petab.calculate_chi2(
            problem.measurement_df,
            sim,
            problem.observable_df,
            _noise_parameter_rows(problem),
        )
    )
    priors = _prior_chi2(problem.parameter_df, ("normal",))
    motor = _prior_chi2(problem.parameter_df, ("parameterScaleNormal", "logNormal"))
    return {
        "rows": rows,
        "priors": priors,
        "motor_priors": motor,
        "likelihood": rows + priors,
        "total": rows + priors + motor,
    }
