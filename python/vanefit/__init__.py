"""vanefit from Python: pneumatic vane motors simulated, fitted, diagnosed and predicted.

Every function calls the same Rust library functions as the ``vanefit`` command line (never
the command line itself), so a seed gives the same fit in both and a bad file gets the same
located message. Results are objects (:class:`Fit`, :class:`Diagnosis`, :class:`Prediction`,
:class:`StudyResult`) whose tables are pandas DataFrames and whose ``.plot`` draws them;
they read and write the files the command line writes, byte for byte. Values are SI unless
a name says otherwise (column names carry their unit, as in the recordings: ``speed_rpm``,
``flow1_g_s``, ``p_port1_mpa``). Nothing is printed and nothing is written unless ``out=``
names where.

Long calls (:func:`fit`, :func:`diagnose`, :func:`predict`) release the GIL and report
progress to ``progress=`` (a callable, or ``True`` for a tqdm bar). Ctrl-C stops a fit at
its next round of starts and raises ``KeyboardInterrupt``; with ``out=`` the finished starts
are in its starts file, and ``fit(..., out=same, resume=True)`` continues from them.

Errors: :class:`DataError` (a dataset, recording or fit file that cannot be read or used;
the message names file, line and column), :class:`ParameterError` (a bad option, parameter
name or value), both subclasses of :class:`VanefitError`.

Example::

    import vanefit
    ds = vanefit.load_dataset("measurements/ar034-synthetic")
    fit = vanefit.fit(ds, starts=16, seed=1, progress=True)
    fit.parameters                      # DataFrame: value, lower, upper, unit, ...
    fit.plot.waterfall()
    vanefit.predict(fit, pressures=[4, 6.3]).catalogue
"""

# The public names only: the implementation (and the typing helpers, numpy, json, ... it
# imports) lives in vanefit._api, so that dir(vanefit) and completion show the API alone.
from ._api import (  # noqa: F401
    Dataset,
    Fit,
    FitStatistics,
    Diagnosis,
    Prediction,
    Samples,
    StudyResult,
    Likelihood,
    chain_diagnostics,
    DataError,
    ParameterError,
    VanefitError,
    load_dataset,
    default_parameters,
    read_fit,
    simulate,
    cost,
    fit,
    likelihood,
    export_petab,
    export_fmu,
    diagnose,
    predict,
    plan,
    Plan,
    control,
    CONTROL_STUDIES,
    synth,
    __version__,
)

# One list of the public names, the implementation's.
from ._api import __all__  # noqa: E402,F401

# Submodules; each imports its optional dependency (matplotlib, petab, pypesto) only when
# one of its functions is called.
from . import pesto, petab, plot  # noqa: E402,F401
