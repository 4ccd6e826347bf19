"""Figures of vanefit's results, drawn with matplotlib.

Every function takes the package's results (a :class:`vanefit.Fit`, a
:class:`vanefit.Diagnosis`, a :class:`vanefit.Dataset`, the tables of a
:class:`vanefit.StudyResult`; the result objects' ``.plot`` calls these) and returns a :class:`matplotlib.figure.Figure`; nothing is shown or saved (call
``fig.savefig(path)`` or let a notebook display it). matplotlib is imported only when a
function is called, so ``import vanefit`` needs numpy alone.

Units on the axes are those an engineer reads on a rig or a catalogue, never bare SI
exponents: sonic conductances in dm³/(s·bar) (1 dm³/(s·bar) = 1e-8 m³/(s·Pa)), torques in
mN·m, flows in g/s, speeds in rpm, pressures in MPa absolute.

Figures:

* :func:`waterfall` — the sorted final cost J of every start of a multi-start fit;
* :func:`parameters` — every estimated parameter at the end of every start (pyPESTO's
  parameters plot), with the estimate and its 95 % interval;
* :func:`profiles` — each parameter's likelihood profile Δχ² with the 95 % threshold;
* :func:`overlay` — recorded against simulated channels of every experiment, for one or
  several parameter sets;
* :func:`residuals` — recorded minus simulated against each experiment's abscissa, with
  a running mean that shows the systematic part and the channel's noise σ as a band;
* :func:`candidates` — the diagnosis's candidate explanations ranked by ΔBIC;
* :func:`bode` — magnitude and phase of the frequency responses of ``control("bode")`` or
  the open loops of ``control("design")``;
* :func:`closed_loop` — time responses of ``control("step")``, ``"disturbance"`` or the
  design check: speed with its set-point, valve command, port-1 pressure, load torque.
"""

from __future__ import annotations

import math
import re
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

__all__ = [
    "PARAMETER_WORDS",
    "display_unit",
    "column_label",
    "waterfall",
    "parameters",
    "profiles",
    "overlay",
    "residuals",
    "candidates",
    "bode",
    "closed_loop",
]

# ---------------------------------------------------------------------------------------
# Units

#: Fit-file unit → (factor from SI, unit shown). Values are multiplied by the factor.
_DISPLAY_UNITS: Dict[str, Tuple[float, str]] = {
    "m3/(s*Pa)": (1e8, "dm³/(s·bar)"),
    "N*m": (1e3, "mN·m"),
    "N*m*s/rad": (1e6, "µN·m·s/rad"),
    "N*m*s2/rad2": (1e9, "nN·m·s²/rad²"),
    "N*m/Pa": (1e8, "mN·m/bar"),
    "m3": (1e6, "cm³"),
    "kg*m2": (1e4, "kg·cm²"),
    "rad/s": (60.0 / (2.0 * math.pi), "rpm"),
    "s": (1.0, "s"),
    "1": (1.0, "–"),
}


#: Parameter id → short words (docs/model.md, "Parameters").
PARAMETER_WORDS: Dict[str, str] = {
    "c_in1": "inlet port",
    "c_out2": "outlet port",
    "c_ext": "exhaust port",
    "c_1e": "leak inlet side → exhaust",
    "c_2e": "leak outlet side → exhaust",
    "c_12": "leak inlet → outlet side",
    "b_crit": "critical pressure ratio",
    "v_disp": "displacement",
    "eps": "expansion ratio",
    "v_dead": "dead volume",
    "n_poly": "polytropic index",
    "vol1": "chamber-1 volume",
    "vol2": "chamber-2 volume",
    "vole": "exhaust-chamber volume",
    "inertia": "inertia",
    "t_coulomb": "Coulomb friction",
    "visc": "viscous friction",
    "w_reg": "friction regularisation",
    "t_static": "static friction",
    "w_stribeck": "Stribeck speed",
    "c_w2": "speed-squared friction",
    "g_seal": "extra leakage at standstill",
    "w_seal": "vane-sealing speed",
    "v_carry": "carried-back volume",
    "w_fill": "filling speed",
    "k_fric_p": "pressure-dependent friction",
    "tau_sensor": "sensor lag",
    "valve_tau": "valve time constant",
    "valve_zeta": "valve damping",
}


def display_unit(unit: str) -> Tuple[float, str]:
    """``(factor, label)`` turning a value in the fit file's SI ``unit`` (``"m3/(s*Pa)"``,
    ``"N*m"``, ...) into the unit an engineer reads (dm³/(s·bar), mN·m, ...): shown value =
    SI value × factor. Unknown units are shown as they are (factor 1)."""
    return _DISPLAY_UNITS.get(unit, (1.0, unit))


#: Recording column suffix → (factor, unit shown); longest suffixes first.
_COLUMN_UNITS: List[Tuple[str, float, str]] = [
    ("_m3_s_pa", 1e8, "dm³/(s·bar)"),
    ("_dm3_s_bar", 1.0, "dm³/(s·bar)"),
    ("_l_min_anr", 1.0, "l/min ANR"),
    ("_l_s_anr", 1.0, "l/s ANR"),
    ("_rpm_per_bar", 1.0, "rpm/bar"),
    ("_rpm_per_v", 1.0, "rpm/V"),
    ("_bar_g", 1.0, "bar(g)"),
    ("_psi_g", 1.0, "psi(g)"),
    ("_rad_s", 1.0, "rad/s"),
    ("_kg_s", 1.0, "kg/s"),
    ("_g_s", 1.0, "g/s"),
    ("_rpm", 1.0, "rpm"),
    ("_nm", 1e3, "mN·m"),
    ("_mpa", 1.0, "MPa abs."),
    ("_pa", 1e-6, "MPa abs."),
    ("_hz", 1.0, "Hz"),
    ("_deg", 1.0, "°"),
    ("_w", 1.0, "W"),
    ("_v", 1.0, "V"),
    ("_s", 1.0, "s"),
]

#: Recording column stem → what it is, in words.
_COLUMN_WORDS: Dict[str, str] = {
    "t": "time",
    "speed": "speed",
    "torque": "shaft torque",
    "power": "shaft power",
    "flow1": "port-1 flow (in)",
    "flow2": "port-2 flow (out)",
    "p_port1": "port-1 pressure",
    "p_port2": "port-2 pressure",
    "c_port2": "port-2 throttle",
    "c_port1": "port-1 throttle",
    "setpoint": "set-point",
    "command": "valve command",
    "p_valve": "valve pressure",
    "p1": "port-1 pressure",
    "load": "load torque",
    "integral": "integral part",
}


def column_label(column: str) -> Tuple[str, float]:
    """``(axis label, factor)`` of a recording or table column named with its unit, as in
    the CSV files (``speed_rpm`` → ``"speed / rpm"``, ``torque_nm`` → ``"shaft torque /
    mN·m"`` with factor 1000, ``c_port2_m3_s_pa`` → ``"port-2 throttle / dm³/(s·bar)"``
    with factor 1e8): plot ``values * factor`` against the label."""
    for suffix, factor, unit in _COLUMN_UNITS:
        if column.endswith(suffix) and len(column) > len(suffix):
            stem = column[: -len(suffix)]
            return f"{_COLUMN_WORDS.get(stem, stem)} / {unit}", factor
    return column, 1.0


# ---------------------------------------------------------------------------------------
# Helpers


def _plt():
    """matplotlib's pyplot, imported on first use."""
    import matplotlib.pyplot as plt

    return plt


def _document(result: Any) -> Mapping[str, Any]:
    """The dict a figure draws: a :class:`vanefit.Fit` as its file with the starts
    (``start_results``), a :class:`vanefit.Diagnosis` as its ``diagnosis.json``; a dict as
    it is."""
    if hasattr(result, "_plot_document"):
        return result._plot_document()
    if hasattr(result, "document"):
        return result.document
    return result


def _start_results(fit: Mapping[str, Any]) -> List[Dict[str, Any]]:
    starts = fit.get("start_results")
    if not starts:
        raise ValueError(
            "this fit has no 'start_results': pass the Fit returned by vanefit.fit(...) "
            "(a fit file read with Fit.read holds only the estimate)"
        )
    return list(starts)


def _estimated(fit: Mapping[str, Any]) -> List[str]:
    return [n for n, p in fit["parameters"].items() if p.get("estimated")]


def _grid(n: int, ncols: int, width: float = 3.6, height: float = 2.9):
    """A figure with n panels on a grid of at most ncols columns; unused panels removed."""
    plt = _plt()
    ncols = max(1, min(ncols, n))
    nrows = max(1, math.ceil(n / ncols))
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(width * ncols, height * nrows), squeeze=False
    )
    flat = list(axes.ravel())
    for ax in flat[n:]:
        ax.remove()
    return fig, flat[:n]


def _log_x(ax) -> None:
    """A log x axis labelled with plain numbers at 1, 2, 5 × 10^k (a conductance axis
    spans about one decade, where matplotlib's default labels overlap)."""
    from matplotlib import ticker

    ax.set_xscale("log")
    ax.xaxis.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(ticker.NullFormatter())


def _figure_legend(fig, axes, ncol: Optional[int] = None) -> None:
    """One legend above the panels (collected from all of them, each label once), so that
    no legend covers data."""
    seen: Dict[str, Any] = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if not lab.startswith("_") and lab not in seen:
                seen[lab] = h
    if seen:
        fig.legend(list(seen.values()), list(seen), loc="upper center",
                   ncol=ncol or min(len(seen), 3), fontsize=8.5, frameon=False,
                   bbox_to_anchor=(0.5, 1.0))


def _fmt(v: float, digits: int = 4) -> str:
    """A number with ``digits`` significant digits, without exponent where it is short."""
    if v is None or not np.isfinite(v):
        return "–"
    return f"{v:.{digits}g}"


# ---------------------------------------------------------------------------------------
# Multi-start fits

_ENDING_STYLE = {
    "converged": ("o", "tab:green", "converged"),
    "joined": ("D", "tab:blue", "joined a better start"),
    "stopped_early": ("v", "tab:orange", "stopped early (no hope)"),
    "budget": ("x", "tab:red", "iteration budget used up"),
}


def waterfall(fit: Mapping[str, Any], rtol: float = 1e-3):
    """The waterfall plot: every start's final cost J (dimensionless, lower is better),
    sorted, on a log axis, marked by how the start ended.

    A flat floor reached by many starts on the left means the best minimum was found
    reliably; further steps are other local minima. Starts within ``rtol`` (relative) of
    the best count as reaching it (the title says how many). Needs the dict returned by
    :func:`vanefit.fit` (its ``start_results``)."""
    fit = _document(fit)
    plt = _plt()
    starts = sorted(_start_results(fit), key=lambda s: s["cost"])
    costs = np.array([max(s["cost"], 1e-12) for s in starts])
    best = costs[0]
    n_best = int(np.sum(costs <= best * (1 + rtol)))
    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    ax.plot(np.arange(1, len(costs) + 1), costs, "-", color="0.75", lw=1, zorder=1)
    for ending, (marker, colour, words) in _ENDING_STYLE.items():
        idx = [i for i, s in enumerate(starts) if s["ending"] == ending]
        if idx:
            ax.plot(
                np.array(idx) + 1, costs[idx], marker, color=colour, ms=6, ls="none",
                label=f"{words} ({len(idx)})", zorder=2,
            )
    others = [i for i, s in enumerate(starts) if s["ending"] not in _ENDING_STYLE]
    if others:
        ax.plot(np.array(others) + 1, costs[others], "s", color="0.3", ls="none",
                label="other", zorder=2)
    ax.axhline(best, color="k", lw=0.8, ls=":", zorder=0)
    ax.set_yscale("log")
    ax.set_xlabel("start, sorted by final cost")
    ax.set_ylabel("final cost J (1 per channel = off by one noise σ)")
    ax.set_title(
        f"Waterfall: {n_best} of {len(costs)} starts reach the best J = {_fmt(best, 5)}"
    )
    ax.set_xlim(0.5, len(costs) + 0.5)
    ax.xaxis.get_major_locator().set_params(integer=True)
    ax.legend(loc="upper left", fontsize=8, framealpha=0.9)
    ax.grid(True, which="major", alpha=0.3)
    fig.tight_layout()
    return fig


def parameters(fit: Mapping[str, Any], names: Optional[Sequence[str]] = None,
               relative: bool = True):
    """Every estimated parameter at the end of every start, pyPESTO's parameters plot.

    One row per parameter; each start is a line across the rows, at log10(value /
    estimate) — decades away from the estimate, so parameters of very different size
    (conductances ~1e-9 m³/(s·Pa), friction ~0.02 N·m) share one axis. Lines are coloured
    by the start's rank in final cost (dark = best, drawn on top). The estimate sits at 0
    (black diamond) with its 95 % interval as a black bar; the right-hand labels give the
    estimate and interval in engineering units. Starts whose lines collapse onto 0 agree
    with the estimate; a parameter whose lines scatter among the good starts is poorly
    determined. ``relative=False`` plots log10 of the SI values themselves (pyPESTO's own
    axis; parameters of different size then sit decades apart). Needs the dict returned by
    :func:`vanefit.fit`."""
    fit = _document(fit)
    plt = _plt()
    from matplotlib import cm, colors

    starts = sorted(_start_results(fit), key=lambda s: s["cost"])
    names = list(names or _estimated(fit))
    est = {n: fit["parameters"][n]["value"] for n in names}
    y = np.arange(len(names))[::-1]  # first parameter on top
    height = 0.5 * len(names) + 2.2
    fig = plt.figure(figsize=(11.0, height))
    # Room on the right for the estimates in words, below for the colour bar.
    bottom = 1.45 / height
    ax = fig.add_axes((0.17, bottom, 0.45, 1.0 - bottom - 0.75 / height))
    cax = fig.add_axes((0.17, 0.5 / height, 0.45, 0.12 / height))
    cmap = plt.get_cmap("viridis")
    norm = colors.Normalize(vmin=1, vmax=max(len(starts), 2))

    def decades(v: float, e: float) -> float:
        if v is None or e is None or v <= 0 or e <= 0:
            return np.nan
        return math.log10(v / e) if relative else math.log10(v)

    for rank in range(len(starts), 0, -1):  # worst first, best on top
        s = starts[rank - 1]
        x = [decades(s["parameters"].get(n), est[n]) for n in names]
        ax.plot(x, y, "-o", color=cmap(norm(rank)), lw=1.2, ms=3.5, alpha=0.85)
    for yi, n in zip(y, names):
        ci = fit["parameters"][n].get("ci95")
        if ci and all(c is not None for c in ci):
            lo, hi = decades(ci[0], est[n]), decades(ci[1], est[n])
            ax.plot([lo, hi], [yi, yi], "-", color="k", lw=5, solid_capstyle="butt", zorder=5)
    ax.plot([decades(est[n], est[n]) for n in names], y, "D", color="k", ms=6, zorder=6,
            label="estimate")
    ax.plot([], [], "-", color="k", lw=5, label="95 % interval")
    if relative:
        ax.axvline(0.0, color="k", lw=0.6, zorder=0)
    ax.set_yticks(y)
    ax.set_yticklabels([f"{n}\n{PARAMETER_WORDS.get(n, '')}".rstrip() for n in names],
                       fontsize=8.5)
    ax.set_ylim(-0.6, len(names) - 0.4)
    ax.set_xlabel("log10(value at the end of the start / estimate)  [decades]" if relative
                  else "log10(value at the end of the start / SI unit)")
    ax.grid(True, axis="x", alpha=0.3)
    # Estimate and interval in engineering units on the right.
    right = ax.twinx()
    right.set_ylim(ax.get_ylim())
    right.set_yticks(y)
    labels = []
    for n in names:
        p = fit["parameters"][n]
        f, u = display_unit(p.get("unit", ""))
        ci = p.get("ci95")
        iv = (
            f"  [{_fmt(ci[0] * f)}, {_fmt(ci[1] * f)}]"
            if ci and all(c is not None for c in ci)
            else "  (no interval)"
        )
        labels.append(f"{_fmt(p['value'] * f)}{iv} {u}")
    right.set_yticklabels(labels, fontsize=8.5)
    right.tick_params(length=0)
    bar = fig.colorbar(cm.ScalarMappable(norm=norm, cmap=cmap), cax=cax,
                       orientation="horizontal")
    bar.set_label("start's rank by final cost J (1 = best, drawn on top)", fontsize=9)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=2, fontsize=8,
              frameon=False)
    fig.suptitle("Parameters at the end of every start; estimate [95 % interval] on the right",
                 x=0.17, ha="left",
                 y=1.0 - 0.12 / height, fontsize=11)
    return fig


def profiles(fit: Mapping[str, Any], names: Optional[Sequence[str]] = None, ncols: int = 4):
    """Each estimated parameter's likelihood profile: Δχ² (the rise of χ² when the
    parameter is held at a value and every other parameter re-optimised) against that
    value, in engineering units.

    The dashed line is the threshold ``statistics.profile_threshold`` (χ²₁(0.95) = 3.84,
    times the squared noise ratio when the model misses); where the profile crosses it are
    the ends of the 95 % interval (dotted lines, the fit's ``ci95``). A narrow, steep
    valley is a well-determined parameter; a profile that stays below the threshold on one
    side is not identifiable there. The axis shows Δχ² up to three thresholds (the search's
    far points rise into the thousands). Needs a fit with ``uncertainty="profile"``."""
    fit = _document(fit)
    profs = fit.get("profiles") or {}
    if not profs:
        raise ValueError("this fit has no profiles: fit with uncertainty='profile'")
    names = [n for n in (names or list(profs)) if n in profs]
    threshold = (fit.get("statistics") or {}).get("profile_threshold") or 3.841458820694124
    cap = 3.0 * threshold
    fig, axes = _grid(len(names), ncols)
    for ax, n in zip(axes, names):
        p = fit["parameters"][n]
        f, u = display_unit(p.get("unit", ""))
        v = np.asarray(profs[n]["value"], dtype=float) * f
        d = np.asarray(profs[n]["delta_chi2"], dtype=float)
        ax.plot(v, d, "-o", color="tab:blue", ms=3, lw=1.5, label="profile")
        ax.axhline(threshold, color="tab:red", ls="--", lw=1,
                   label=f"95 % threshold Δχ² = {threshold:.2f}")
        ci = p.get("ci95")
        if ci and all(c is not None for c in ci):
            for c in ci:
                ax.axvline(c * f, color="tab:red", ls=":", lw=1)
            ax.plot([], [], ":", color="tab:red", label="95 % interval ends")
        ax.plot([p["value"] * f], [0.0], "D", color="k", ms=5, label="estimate", zorder=5)
        inside = v[d <= cap]
        xs = np.concatenate([inside, [p["value"] * f]] + ([np.asarray(ci) * f] if ci and all(
            c is not None for c in ci) else []))
        lo, hi = float(np.min(xs)), float(np.max(xs))
        pad = 0.08 * (hi - lo) if hi > lo else 0.01 * abs(hi) or 1.0
        ax.set_xlim(lo - pad, hi + pad)
        ax.set_ylim(0.0, cap)
        ax.ticklabel_format(axis="x", useOffset=False)
        ax.xaxis.get_major_locator().set_params(nbins=4)
        ax.set_xlabel(f"{n} / {u}")
        ax.set_ylabel("Δχ²")
        ax.set_title(f"{n}: {PARAMETER_WORDS.get(n, '')}".rstrip(": "), fontsize=10)
        ax.grid(True, alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=len(labels), fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, 1.0))
    fig.tight_layout(rect=(0, 0, 1, 0.95))
    return fig


# ---------------------------------------------------------------------------------------
# Recorded against simulated

#: The abscissa of each experiment kind (the first column of the recording that starts so).
_ABSCISSA = {
    "datasheet": ("speed",),
    "catalogue": ("speed",),
    "pressure_ramp": ("p_port1",),
    "outlet_throttle": ("c_port2",),
}


def _abscissa(experiment: Mapping[str, Any], columns: Sequence[str],
              x: Optional[Union[str, Mapping[str, str]]]) -> str:
    if isinstance(x, str) and x in columns:
        return x
    if isinstance(x, Mapping) and experiment["file"] in x:
        return x[experiment["file"]]
    for stem in _ABSCISSA.get(experiment["kind"], ()):
        for c in columns:
            if c.startswith(stem + "_"):
                return c
    return "t_s" if "t_s" in columns else columns[0]


def _models(params: Any, labels: Optional[Sequence[str]]) -> Tuple[List[Any], List[str]]:
    models = list(params) if isinstance(params, list) else [params]
    if labels is None:
        labels = ["simulated"] if len(models) == 1 else [f"model {i + 1}" for i in range(len(models))]
    if len(labels) != len(models):
        raise ValueError(f"{len(labels)} labels for {len(models)} parameter sets")
    return models, list(labels)


def _channels(ds, sims: List[Dict[str, Dict[str, np.ndarray]]], x: Any):
    """(experiment, recording, abscissa, [output columns]) for every experiment."""
    out = []
    for e in ds.experiments:
        rec = ds.recording(e["file"])
        cols = list(rec)
        xcol = _abscissa(e, cols, x)
        inputs = {"t_s", xcol}
        chans = [c for c in cols if c not in inputs and all(c in s[e["file"]] for s in sims)]
        out.append((e, rec, xcol, chans))
    return out


_SIM_COLOURS = ["tab:red", "tab:blue", "tab:green", "tab:purple"]


def overlay(ds, params: Any = None, labels: Optional[Sequence[str]] = None,
            x: Optional[Union[str, Mapping[str, str]]] = None):
    """Recorded (grey dots) against simulated (lines) for every experiment (a row) and
    channel (a panel), in the recording's units against the experiment's abscissa: speed
    for a datasheet, port-1 pressure for the pressure ramp, the port-2 throttle's
    conductance (log axis) for the outlet throttle.

    ``params`` is anything :func:`vanefit.simulate` takes (a fit file's path, a fit dict
    written with ``out=``, a dict of values, None for the nominal motor) or a *list* of
    them to compare several models, named by ``labels``. ``x`` overrides the abscissa: a
    column name, or ``{file: column}``."""
    import vanefit

    plt = _plt()
    models, labels = _models(params, labels)
    sims = [vanefit.simulate(ds, m) for m in models]
    rows = _channels(ds, sims, x)
    ncols = max(len(r[3]) for r in rows)
    fig, axes = plt.subplots(len(rows), ncols, figsize=(3.7 * ncols, 2.9 * len(rows)),
                             squeeze=False)
    for i, (e, rec, xcol, chans) in enumerate(rows):
        xl, xf = column_label(xcol)
        for j in range(ncols):
            ax = axes[i, j]
            if j >= len(chans):
                ax.remove()
                continue
            c = chans[j]
            yl, yf = column_label(c)
            steady = e["kind"] in ("datasheet", "catalogue")
            ax.plot(rec[xcol] * xf, rec[c] * yf, "o" if steady else ".", color="0.45",
                    ms=4 if steady else 2.5, label="recorded", zorder=1)
            for k, (sim, lab) in enumerate(zip(sims, labels)):
                t = sim[e["file"]]
                ax.plot(t[xcol] * xf, t[c] * yf, "-", color=_SIM_COLOURS[k % 4], lw=1.6,
                        label=lab, zorder=2 + k, alpha=0.9)
            if xcol.startswith("c_port"):
                _log_x(ax)
            ax.set_xlabel(xl)
            ax.set_ylabel(yl)
            ax.set_title(f"{e['file']}: {yl.split(' / ')[0]}", fontsize=9)
            ax.grid(True, alpha=0.3)
    _figure_legend(fig, [a for a in axes.ravel() if a.figure is fig])
    fig.tight_layout(rect=(0, 0, 1, 1.0 - 0.35 / fig.get_figheight()))
    return fig


def _noise_sigma(y: np.ndarray) -> float:
    """A channel's noise σ from its second differences (robust: median absolute
    deviation), as vanefit estimates it: for white noise, Var(Δ²y) = 6σ²."""
    d2 = np.diff(y[np.isfinite(y)], 2)
    if d2.size < 3:
        return float("nan")
    mad = np.median(np.abs(d2 - np.median(d2)))
    return float(1.4826 * mad / math.sqrt(6.0))


def _running_mean(y: np.ndarray, window: int) -> np.ndarray:
    if window <= 1 or y.size < window:
        return y
    k = np.ones(window) / window
    num = np.convolve(np.nan_to_num(y), k, mode="same")
    den = np.convolve(np.isfinite(y).astype(float), k, mode="same")
    return num / np.maximum(den, 1e-12)


def residuals(ds, params: Any = None, labels: Optional[Sequence[str]] = None,
              x: Optional[Union[str, Mapping[str, str]]] = None, window: int = 31,
              experiments: Optional[Sequence[str]] = None):
    """Recorded minus simulated for every experiment (a row) and channel (a panel), in
    the recording's units against the experiment's abscissa (as :func:`overlay`).

    For a transient recording the raw residuals are faint dots and a running mean over
    ``window`` rows is the line: what a model misses systematically stands out of the
    noise as a line that wanders away from 0. The grey band is ±2 σ of the channel's
    noise, estimated from the recording's second differences (a steady-state datasheet has
    too few rows for that and gets none). ``params``/``labels``: one parameter set or a
    list of them (e.g. the base model and the model the diagnosis extended), as
    :func:`overlay`. ``experiments``: only these recording files."""
    import vanefit

    plt = _plt()
    models, labels = _models(params, labels)
    sims = [vanefit.simulate(ds, m) for m in models]
    rows = [r for r in _channels(ds, sims, x)
            if experiments is None or r[0]["file"] in experiments]
    ncols = max(len(r[3]) for r in rows)
    fig, axes = plt.subplots(len(rows), ncols, figsize=(3.7 * ncols, 2.8 * len(rows)),
                             squeeze=False)
    for i, (e, rec, xcol, chans) in enumerate(rows):
        xl, xf = column_label(xcol)
        steady = e["kind"] in ("datasheet", "catalogue")
        for j in range(ncols):
            ax = axes[i, j]
            if j >= len(chans):
                ax.remove()
                continue
            c = chans[j]
            yl, yf = column_label(c)
            xv = rec[xcol] * xf
            order = np.argsort(xv, kind="stable") if steady else np.arange(xv.size)
            if not steady:
                s = _noise_sigma(rec[c]) * yf
                if np.isfinite(s):
                    ax.axhspan(-2 * s, 2 * s, color="0.88", zorder=0,
                               label="±2σ of the recording's noise")
            ax.axhline(0.0, color="k", lw=0.7, zorder=1)
            for k, (sim, lab) in enumerate(zip(sims, labels)):
                r = (rec[c] - sim[e["file"]][c]) * yf
                col = _SIM_COLOURS[k % 4]
                if steady:
                    ax.plot(xv[order], r[order], "-o", color=col, ms=3.5, lw=1, label=lab)
                else:
                    ax.plot(xv, r, ".", color=col, ms=1.5, alpha=0.25, zorder=2)
                    ax.plot(xv, _running_mean(r, window), "-", color=col, lw=1.8, label=lab,
                            zorder=3)
            if xcol.startswith("c_port"):
                _log_x(ax)
            ax.set_xlabel(xl)
            ax.set_ylabel(f"recorded − simulated / {yl.split(' / ')[-1]}")
            ax.set_title(f"{e['file']}: {yl.split(' / ')[0]}", fontsize=9)
            ax.grid(True, alpha=0.3)
            if not steady:
                # Scale to the running means and the band, not to single noisy rows.
                lines = [_running_mean((rec[c] - sim[e["file"]][c]) * yf, window)
                         for sim in sims]
                s = _noise_sigma(rec[c]) * yf
                m = max([np.nanmax(np.abs(l[window:-window] if l.size > 2 * window else l))
                         for l in lines] + [2 * s if np.isfinite(s) else 0.0])
                if np.isfinite(m) and m > 0:
                    ax.set_ylim(-1.6 * m, 1.6 * m)
    _figure_legend(fig, [a for a in axes.ravel() if a.figure is fig])
    fig.tight_layout(rect=(0, 0, 1, 1.0 - 0.35 / fig.get_figheight()))
    return fig


def candidates(diagnosis: Mapping[str, Any], select_below: float = -10.0):
    """The diagnosis's ranking: each candidate explanation's ΔBIC against the base model
    (BIC = χ² + k·ln n; negative = better, the bar's length), best at the top, on a
    symmetric-log axis (ΔBIC spans from a few units to thousands). A candidate is only
    selected when it beats every simpler model by ΔBIC < ``select_below`` (−10, the
    dashed line); the selected ones are dark. ``diagnosis`` is the dict of
    :func:`vanefit.diagnose`."""
    diagnosis = _document(diagnosis)
    plt = _plt()
    cands = sorted(diagnosis.get("candidates") or [], key=lambda c: c["delta_bic"])
    if not cands:
        raise ValueError("the diagnosis lists no candidates (no mismatch was found)")
    chosen = {s.get("effect") for s in diagnosis.get("selected") or []}
    names = [c["effect"] for c in cands]
    dbic = np.array([c["delta_bic"] for c in cands], dtype=float)
    fig, ax = plt.subplots(figsize=(7.2, 0.42 * len(cands) + 1.4))
    y = np.arange(len(cands))[::-1]
    colours = ["tab:blue" if n in chosen else "lightsteelblue" for n in names]
    ax.barh(y, dbic, color=colours, edgecolor="0.3", lw=0.6)
    ax.axvline(select_below, color="tab:red", ls="--", lw=1,
               label=f"selection threshold ΔBIC = {select_below:g}")
    ax.axvline(0.0, color="k", lw=0.8)
    ax.set_xscale("symlog", linthresh=10.0)
    ax.set_yticks(y)
    ax.set_yticklabels(names, fontsize=9)
    for yi, v in zip(y, dbic):
        ax.text(v, yi, f" {v:.0f} ", va="center", ha="right" if v < 0 else "left", fontsize=8)
    lo = min(dbic.min(), select_below)
    hi = max(dbic.max(), 10.0)
    ax.set_xlim(lo * 3 if lo < 0 else -30, hi * 3 if hi > 0 else 30)
    ax.set_xlabel("ΔBIC against the base model (negative = better explanation)")
    ax.set_title("Candidate explanations (dark: selected)", fontsize=10)
    ax.grid(True, axis="x", alpha=0.3)
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    return fig


# ---------------------------------------------------------------------------------------
# Speed control


def _bode_pairs(table: Mapping[str, np.ndarray]) -> List[Tuple[str, str, str, str]]:
    """(name, magnitude column, phase column, unit) for every ``<name>_mag[_unit]`` column
    with a ``<name>_phase_deg`` partner."""
    pairs = []
    for c in table:
        m = re.match(r"^(.*?)_mag(?:_(.*))?$", c)
        if m and f"{m.group(1)}_phase_deg" in table:
            unit = (m.group(2) or "").replace("_per_", "/").replace("/v", "/V")
            pairs.append((m.group(1), c, f"{m.group(1)}_phase_deg", unit))
    return pairs


_SERIES_WORDS = {
    "motor": "motor (linearised)",
    "fit": "two-lag fit",
    "valve_motor": "valve + motor",
    "designed": "designed PI",
    "paper": "paper's PI (0.85, 4)",
}


def bode(table: Mapping[str, np.ndarray], series: Optional[Sequence[str]] = None,
         margins: Optional[Mapping[str, Mapping[str, Any]]] = None,
         title: Optional[str] = None):
    """Bode diagram (magnitude over phase, frequency in Hz on a log axis) of every
    ``<name>_mag``/``<name>_phase_deg`` pair of a table: ``control("bode")["bode"]``
    (supply pressure → speed in rpm/bar, its two-lag fit, and valve + motor command →
    speed in rpm/V) or ``control("design")["design_open_loop"]`` (the open loops, a
    dimensionless loop gain, shown in dB with the 0 dB line).

    ``series`` picks pairs by name (``"motor"``, ``"fit"``, ``"designed"``, ...).
    ``margins`` (``{label: design["designed"], ...}``) marks each loop's crossover
    (``crossover_rad_s``) and phase margin (``phase_margin_deg``) on open-loop plots."""
    plt = _plt()
    pairs = [p for p in _bode_pairs(table) if series is None or p[0] in series]
    if not pairs:
        raise ValueError(f"no <name>_mag / <name>_phase_deg columns among {list(table)}")
    f = np.asarray(table["f_hz"], dtype=float)
    loop = all(unit == "" for _, _, _, unit in pairs)
    fig, (am, ap) = plt.subplots(2, 1, figsize=(7.2, 6.2), sharex=True,
                                 gridspec_kw={"height_ratios": [3, 2]})
    # One magnitude axis per unit (rpm/bar and rpm/V on twin axes).
    units = list(dict.fromkeys(u for _, _, _, u in pairs))
    axes_by_unit = {units[0]: am}
    if len(units) > 1:
        axes_by_unit[units[1]] = am.twinx()
    styles = ["-", "--", "-.", ":"]
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:purple"]
    handles = []
    for k, (name, mcol, pcol, unit) in enumerate(pairs):
        a = axes_by_unit.get(unit, am)
        mag = np.asarray(table[mcol], dtype=float)
        label = _SERIES_WORDS.get(name, name) + (
            f" [{unit}{', right axis' if unit != units[0] else ''}]" if len(units) > 1 else ""
        )
        st = dict(color=colours[k % 4], ls=styles[k % 4] if name == "fit" else "-", lw=1.6)
        if loop:
            (h,) = a.semilogx(f, 20 * np.log10(mag), label=label, **st)
        else:
            (h,) = a.loglog(f, mag, label=label, **st)
        handles.append(h)
        ap.semilogx(f, np.asarray(table[pcol], dtype=float), **st)
    if loop:
        am.axhline(0.0, color="k", lw=0.8)
        am.set_ylabel("open-loop gain / dB")
        ap.axhline(-180.0, color="k", lw=0.8)
    else:
        for unit, a in axes_by_unit.items():
            side = " (right axis)" if a is not am else ""
            a.set_ylabel(f"|speed / input| / {unit}{side}")
    if margins:
        notes = []
        for k, (lab, m) in enumerate(margins.items()):
            wc = m.get("crossover_rad_s")
            pm = m.get("phase_margin_deg")
            if wc:
                fc = wc / (2 * math.pi)
                for a in (am, ap):
                    a.axvline(fc, color=colours[k % 4], ls=":", lw=1)
                if pm is not None:
                    ap.annotate("", xy=(fc, -180.0 + pm), xytext=(fc, -180.0),
                                arrowprops=dict(arrowstyle="<->", color=colours[k % 4]))
                    gm = m.get("gain_margin_db")
                    notes.append((f"{lab}: crossover {fc:.2f} Hz, phase margin {pm:.0f}°"
                                  + (f", gain margin {gm:.0f} dB" if gm is not None else ""),
                                  colours[k % 4]))
        for k, (text, colour) in enumerate(notes):
            ap.text(0.02, 0.06 + 0.11 * (len(notes) - 1 - k), text, color=colour, fontsize=8,
                    transform=ap.transAxes, va="bottom",
                    bbox=dict(facecolor="white", edgecolor="none", alpha=0.8, pad=1))
    ap.set_xlabel("frequency / Hz")
    ap.set_ylabel("phase / °")
    for a in (am, ap):
        a.grid(True, which="both", alpha=0.3)
    am.legend(handles=handles, fontsize=8, loc="lower left")
    if title:
        am.set_title(title)
    fig.tight_layout()
    return fig


def closed_loop(tables: Mapping[str, Mapping[str, np.ndarray]], title: Optional[str] = None,
                t_window: Optional[Tuple[float, float]] = None):
    """Closed-loop time responses of ``control("step")``, ``"disturbance"`` or the design
    check (``design_step``), several runs compared: ``tables`` is ``{label: table}``.

    Panels share the time axis (s): speed (rpm) with the set-point dashed; the valve
    command (V, 0–10 V is the valve's range: a flat top is saturation); the port-1
    pressure (MPa absolute); and, where a run has a load step, the load torque (mN·m: the
    brake's c·ω plus the step). ``t_window`` limits the time axis."""
    plt = _plt()
    tabs = list(tables.items())
    def load_step(t: Mapping[str, np.ndarray]) -> bool:
        # A jump in the load (a load step), not the brake's torque following the speed.
        if "load_nm" not in t:
            return False
        load = np.asarray(t["load_nm"], dtype=float)
        span = np.ptp(load)
        return span > 1e-9 and np.max(np.abs(np.diff(load))) > 0.2 * span

    show_load = any(load_step(t) for _, t in tabs)
    panels = ["speed_rpm", "command_v", "p1_mpa"] + (["load_nm"] if show_load else [])
    heights = [3] + [1.6] * (len(panels) - 1)
    fig, axes = plt.subplots(len(panels), 1, figsize=(7.2, 1.6 * sum(heights) / 1.6 + 0.6),
                             sharex=True, gridspec_kw={"height_ratios": heights})
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:purple"]
    for k, (lab, t) in enumerate(tabs):
        ts = np.asarray(t["t_s"], dtype=float)
        col = colours[k % 4]
        for ax, c in zip(axes, panels):
            if c not in t:
                continue
            _, fac = column_label(c)
            ax.plot(ts, np.asarray(t[c], dtype=float) * fac, color=col, lw=1.5,
                    label=lab if c == "speed_rpm" else None)
    # The set-points, each different one once.
    drawn: List[np.ndarray] = []
    for k, (lab, t) in enumerate(tabs):
        if "setpoint_rpm" not in t:
            continue
        sp = np.asarray(t["setpoint_rpm"], dtype=float)
        if any(d.shape == sp.shape and np.allclose(d, sp) for d in drawn):
            continue
        same = all(np.allclose(np.asarray(u.get("setpoint_rpm", sp)), sp) for _, u in tabs
                   if np.shape(u.get("setpoint_rpm", sp)) == sp.shape)
        axes[0].plot(np.asarray(t["t_s"], dtype=float), sp, "--", lw=1.1,
                     color="k" if same else colours[k % 4],
                     label="set-point" if same else f"{lab}: set-point")
        drawn.append(sp)
    for ax, c in zip(axes, panels):
        ax.set_ylabel(column_label(c)[0].replace(" / ", "\n/ "), fontsize=9)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8, loc="best")
    axes[-1].set_xlabel("time / s")
    if t_window:
        axes[-1].set_xlim(*t_window)
    if title:
        axes[0].set_title(title)
    fig.align_ylabels(axes)
    fig.tight_layout()
    return fig
