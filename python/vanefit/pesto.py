"""A fit's likelihood as a pyPESTO problem: pyPESTO's multi-start, optimizers, profiles and
plots on vanefit's χ².

pyPESTO minimises a negative log-likelihood; here it is χ²/2 (Gaussian rows and the
nuisances' priors; :class:`vanefit.Likelihood`), given both as a function and as residuals
(so least-squares optimizers such as SciPy's ``ls_trf`` apply). Parameters are pyPESTO's on
vanefit's search scale: log10 of the SI value for conductances and friction (``log_scale``),
the SI value otherwise, with vanefit's search bounds. A profile's likelihood ratio is then
exp(−Δχ²/2), so vanefit's 95 % interval is where it falls below
:func:`confidence_ratio` = exp(−threshold/2).

Needs the optional package ``pypesto`` (``pip install pypesto``)."""

from __future__ import annotations

from typing import Dict, Optional, Sequence, Tuple

import numpy as np

from . import Likelihood, VanefitError

#: Residual given where vanefit cannot simulate (every row 10³ σ off): far worse than any
#: fit, but finite, so that optimizers step back instead of stopping on NaN.
FAILED_RESIDUAL = 1e3


def to_si(lik: Likelihood, x: Sequence[float]) -> np.ndarray:
    """pyPESTO coordinates → SI values."""
    x = np.asarray(x, dtype=float)
    return np.where(lik.log_scale, 10.0**x, x)


def from_si(lik: Likelihood, values: Sequence[float]) -> np.ndarray:
    """SI values → pyPESTO coordinates."""
    v = np.asarray(values, dtype=float)
    return np.where(lik.log_scale, np.log10(np.where(lik.log_scale, v, 1.0)), v)


def objective(lik: Likelihood, delta: float = 1e-4):
    """The pyPESTO objective of χ²/2 with its residuals; gradient and residual
    sensitivities by central finite differences of step ``delta`` (in pyPESTO's
    coordinates: 1e-4, a 0.023 % change of a log-scale value, is far above the ODE
    solver's jitter — at 1e-5 the residuals' differences are noisy enough to stop
    least-squares optimizers short of the minimum — and far below the curvature's scale)."""
    import pypesto

    n_res = len(lik.residuals(lik.x_hat))

    def fun(x):
        return 0.5 * lik(to_si(lik, x))

    def res(x):
        try:
            return lik.residuals(to_si(lik, x))
        except VanefitError:
            return np.full(n_res, FAILED_RESIDUAL)

    return pypesto.FD(
        pypesto.Objective(fun=fun, res=res, x_names=lik.names),
        grad=True,
        sres=True,
        delta_fun=delta,
        delta_res=delta,
        x_names=lik.names,
    )


def problem(lik: Likelihood, delta: float = 1e-4):
    """The pyPESTO problem: :func:`objective` within vanefit's search bounds."""
    import pypesto

    scales = ["log10" if s else "lin" for s in lik.log_scale]
    return pypesto.Problem(
        objective(lik, delta),
        lb=from_si(lik, lik.lower),
        ub=from_si(lik, lik.upper),
        x_names=lik.names,
        x_scales=scales,
    )


def confidence_ratio(lik: Likelihood) -> float:
    """The profile likelihood ratio that bounds vanefit's 95 % interval, exp(−threshold/2)
    (pyPESTO's ``chi2_quantile_to_ratio(0.95)`` when the fit widened no noise)."""
    return float(np.exp(-lik.threshold / 2.0))


def profile_options(step: float = 2e-4):
    """Profile steps for vanefit's parameters: a recording pins a conductance to a fraction
    of a percent, far below pyPESTO's default steps (a hundredth of a decade and more), so
    the steps are absolute in log10 and small: ``step`` to start, a tenth of it at least,
    ten times at most."""
    from pypesto.profile import ProfileOptions

    return ProfileOptions(
        default_step_size_absolute=step,
        min_step_size_absolute=step / 10.0,
        max_step_size_absolute=step * 10.0,
        default_step_size_relative=0.0,
        min_step_size_relative=0.0,
        max_step_size_relative=0.0,
        step_size_precheck_mode="off",
    )


def intervals(
    lik: Likelihood, result, profile_list: int = 0
) -> Dict[str, Tuple[float, float]]:
    """95 % intervals (SI) of every profiled parameter of a pyPESTO result, where the
    profile's likelihood ratio crosses :func:`confidence_ratio` (linear interpolation,
    ``pypesto.profile.calculate_approximate_ci``)."""
    from pypesto.profile import calculate_approximate_ci

    out = {}
    ratio = confidence_ratio(lik)
    for i, prof in enumerate(result.profile_result.list[profile_list]):
        if prof is None:
            continue
        xs = prof.x_path[i, :]
        lo, hi = calculate_approximate_ci(xs, prof.ratio_path, ratio)
        lo_si, hi_si = (10.0**lo, 10.0**hi) if lik.log_scale[i] else (lo, hi)
        out[lik.names[i]] = (float(lo_si), float(hi_si))
    return out


def multistart(
    lik: Likelihood,
    n_starts: int = 20,
    seed: int = 1,
    optimizer=None,
    x_guesses: Optional[Sequence[Sequence[float]]] = None,
):
    """pyPESTO's multi-start on the likelihood (default optimizer SciPy's ``ls_trf`` on the
    residuals), start points uniform in the bounds from ``seed``. Returns the pyPESTO
    result (``result.optimize_result``, best first)."""
    import pypesto
    import pypesto.optimize as optimize

    prob = problem(lik)
    if x_guesses is not None:
        prob.set_x_guesses(np.asarray(x_guesses, dtype=float))
    np.random.seed(seed)
    return optimize.minimize(
        prob,
        optimizer=optimizer or optimize.ScipyOptimizer(method="ls_trf"),
        n_starts=n_starts,
        engine=pypesto.engine.SingleCoreEngine(),
        progress_bar=False,
    )
