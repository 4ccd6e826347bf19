"""Progress of long calls: ``progress=`` of :func:`vanefit.fit` and :func:`vanefit.diagnose`.

``progress`` is ``None`` (silent), ``True`` (a tqdm bar: a widget in a notebook with
ipywidgets, text otherwise) or a callable, called from the thread that made the call while
the work runs on vanefit's threads (the GIL is taken only for the call):

* fit: ``progress(done, total, best_cost)`` — when the run begins (``done`` = starts
  already finished, e.g. read back on resume; ``best_cost`` = inf) and after every start;
* diagnose: ``progress(elapsed_s, message)`` at every phase;
* predict: ``progress(stage, done, total)`` at each tenth of the posterior sampling
  (``"sampling"``, steps) and of the propagation of its samples (``"propagating"``).

An exception raised by the callable stops a fit at its next round of starts and is raised
by :func:`vanefit.fit`.
"""

from __future__ import annotations

import contextlib
import math
from typing import Any, Callable, Iterator, Optional, Union

#: What ``progress=`` accepts.
Progress = Union[None, bool, Callable[..., Any]]

__all__ = ["Progress", "fit_progress", "diagnose_progress", "predict_progress"]


def _tqdm_class():
    """tqdm's notebook bar when ipywidgets can draw it, its text bar otherwise."""
    try:
        import ipywidgets  # noqa: F401
        from IPython import get_ipython

        if get_ipython() is not None and "IPKernelApp" in get_ipython().config:
            from tqdm.notebook import tqdm

            return tqdm
    except Exception:
        pass
    from tqdm.std import tqdm

    return tqdm


def _check(progress: Progress) -> None:
    if progress is None or isinstance(progress, bool) or callable(progress):
        return
    from ._core import ParameterError

    raise ParameterError(
        f"progress: expected None, True or a callable, got {type(progress).__name__}"
    )


@contextlib.contextmanager
def _progress(
    progress: Progress, desc: str, unit: str, updater: Callable[[Any], Callable[..., Any]]
) -> Iterator[Optional[Callable[..., Any]]]:
    """The callback for ``progress=``: none for ``None``/``False``, the caller's own
    callable, or for ``True`` ``updater(bar)`` on a tqdm bar, closed when the call returns
    (or fails)."""
    _check(progress)
    if not progress:
        yield None
        return
    if callable(progress):
        yield progress
        return
    bar = _tqdm_class()(total=None, desc=desc, unit=unit, leave=True)
    try:
        yield updater(bar)
    finally:
        bar.close()


def fit_progress(
    progress: Progress,
) -> contextlib.AbstractContextManager[Optional[Callable[[int, int, float], Any]]]:
    """The callback of a fit for ``progress=``; a tqdm bar over the starts for ``True``,
    closed when the fit returns (or fails)."""

    def updater(bar: Any) -> Callable[[int, int, float], None]:
        def update(done: int, total: int, best: float) -> None:
            if bar.total != total:
                bar.total = total
            bar.n = done
            if math.isfinite(best):
                bar.set_postfix_str(f"best J {best:.4g}", refresh=False)
            bar.refresh()

        return update

    return _progress(progress, "fit", "start", updater)


def diagnose_progress(
    progress: Progress,
) -> contextlib.AbstractContextManager[Optional[Callable[[float, str], Any]]]:
    """The callback of a diagnosis for ``progress=``; for ``True`` a tqdm line counting
    the phases with the latest message."""

    def updater(bar: Any) -> Callable[[float, str], None]:
        def update(elapsed: float, message: str) -> None:
            bar.update(1)
            bar.set_postfix_str(message[:80], refresh=True)

        return update

    return _progress(progress, "diagnose", "step", updater)


def predict_progress(
    progress: Progress,
) -> contextlib.AbstractContextManager[Optional[Callable[[str, int, int], Any]]]:
    """The callback of a prediction for ``progress=``; for ``True`` a tqdm bar over each
    stage of the posterior sampling (``sampling``, then ``propagating``)."""

    def updater(bar: Any) -> Callable[[str, int, int], None]:
        def update(stage: str, done: int, total: int) -> None:
            if bar.desc != stage:
                bar.set_description_str(stage, refresh=False)
            if bar.total != total:
                bar.total = total
            bar.n = done
            bar.refresh()

        return update

    return _progress(progress, "predict", "step", updater)
