"""Type stubs of the compiled extension ``vanefit._core`` (pyo3), checked against the built
module by mypy's stubtest (python/tests/test_stubs.py). Users call the wrappers in
:mod:`vanefit`; these are the raw functions they use. Paths are ``str`` or ``os.PathLike``;
a fit held in memory goes as ``fit_text`` (its path then only names it in messages); values
are SI unless a column name says otherwise; JSON documents are returned as ``str``."""

import os
from typing import Any, Callable, List, Optional, Sequence, Tuple, Union, final

_Path = Union[str, "os.PathLike[str]"]
_Columns = List[Tuple[str, List[float]]]

__version__: str
__all__ = [
    "VanefitError",
    "DataError",
    "ParameterError",
    "PyDataset",
    "PyLikelihood",
    "load_dataset",
    "nominal_parameters",
    "read_fit",
    "simulate",
    "cost",
    "fit",
    "diagnose",
    "predict",
    "find_dataset",
    "plan",
    "export_petab",
    "export_fmu",
    "synth",
    "control",
    "chain_diagnostics",
    "__version__",
]

class VanefitError(Exception):
    """Anything vanefit refuses or fails at."""

class DataError(VanefitError):
    """A dataset, recording or fit file that cannot be read or used; the message names the
    file, line and column."""

class ParameterError(VanefitError):
    """A bad option, parameter name or parameter value; the message names it."""

@final
class PyDataset:
    """A dataset read and checked (rig.toml and its recordings)."""

    @property
    def name(self) -> str: ...
    @property
    def path(self) -> str: ...
    def experiments_json(self) -> str: ...
    def recording(self, file: str) -> _Columns: ...

@final
class PyLikelihood:
    """A fit's likelihood rebuilt from its fit file, over the estimated parameters (SI)."""

    def __new__(
        cls, ds: PyDataset, fit: _Path, fit_text: Optional[str] = None, priors: bool = True
    ) -> "PyLikelihood": ...
    @property
    def priors(self) -> bool: ...
    @property
    def prior_terms(self) -> List[Tuple[str, float, float, float]]: ...
    def prior_chi2(self, x: Sequence[float]) -> float: ...
    @property
    def names(self) -> List[str]: ...
    @property
    def bounds(self) -> List[Tuple[float, float]]: ...
    @property
    def log_scale(self) -> List[bool]: ...
    @property
    def estimate(self) -> List[float]: ...
    @property
    def chi2_min(self) -> float: ...
    @property
    def threshold(self) -> float: ...
    def chi2(self, x: Sequence[float]) -> float: ...
    def residuals(self, x: Sequence[float]) -> bytearray: ...
    def chi2_or_penalty(self, x: Sequence[float]) -> float: ...
    def breakdown(self, x: Sequence[float]) -> str: ...
    def log_posterior(self, x: Sequence[float]) -> float: ...
    def to_coords(self, values: Sequence[float]) -> List[float]: ...
    def to_values(self, x: Sequence[float]) -> List[float]: ...
    def sample(
        self, starts: Sequence[Sequence[float]], steps: int, burn_in: int = 0, seed: int = 1
    ) -> Tuple[List[List[List[float]]], List[List[float]], List[float]]: ...

def load_dataset(path: _Path) -> PyDataset: ...
def nominal_parameters(ds: PyDataset) -> List[Tuple[str, float]]: ...
def read_fit(path: _Path, text: Optional[str] = None) -> str: ...
def simulate(
    ds: PyDataset,
    fit: Optional[_Path] = None,
    fit_text: Optional[str] = None,
    overrides: Sequence[Tuple[str, float]] = ...,
) -> List[Tuple[str, _Columns]]: ...
def cost(
    ds: PyDataset,
    fit: Optional[_Path] = None,
    fit_text: Optional[str] = None,
    overrides: Sequence[Tuple[str, float]] = ...,
) -> str: ...
def fit(
    dataset: _Path,
    starts: int,
    seed: int,
    threads: Optional[int],
    effects: Sequence[str],
    estimate: Optional[Sequence[str]],
    uncertainty: str,
    max_iters: int,
    out: Optional[_Path],
    resume: bool,
    progress: Optional[Callable[[int, int, float], Any]],
    handoff: bool = ...,
) -> Tuple[str, str]: ...
def diagnose(
    ds: PyDataset,
    starts: int,
    seed: int,
    threads: Optional[int],
    out: Optional[_Path],
    progress: Optional[Callable[[float, str], Any]],
) -> Tuple[str, str, str]: ...
def predict(
    fit: _Path,
    fit_text: Optional[str],
    pressures: Optional[Sequence[float]],
    unit: str,
    reference: Optional[float],
    inlet_nozzle: Optional[float],
    outlet_nozzle: Optional[float],
    speed_grid_rpm: float,
    curve_points: int,
    fixed_spread: Optional[float],
    out: Optional[_Path],
    data: Optional[_Path] = None,
    bands: Optional[str] = None,
    steps: Optional[int] = None,
    burn_in: Optional[int] = None,
    draws: Optional[int] = None,
    seed: Optional[int] = None,
    walkers: Optional[int] = None,
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Tuple[str, Optional[Tuple[bytearray, bytearray, Tuple[int, int, int], List[float]]]]: ...
def find_dataset(fit: _Path, fit_text: Optional[str]) -> Tuple[Optional[str], str]: ...
def plan(
    fit: _Path,
    fit_text: Optional[str],
    pressures: Sequence[float],
    unit: str,
    speeds_rpm: Optional[Sequence[float]],
    candidates: Optional[Sequence[str]],
    costs: Optional[Sequence[Tuple[str, float]]],
    fixed_spread: Optional[float],
    top: int,
    out: Optional[_Path],
) -> str: ...
def export_petab(fit: _Path, fit_text: Optional[str], dataset: _Path, out: _Path) -> str: ...
def export_fmu(fit: _Path, fit_text: Optional[str], out: _Path, binary: Optional[_Path]) -> str: ...
def synth(
    out: _Path,
    fit: Optional[_Path],
    fit_text: Optional[str],
    effects: Optional[Sequence[str]],
    noise: float,
    seed: int,
    catalogue: bool,
    pressures_bar_g: Sequence[float],
) -> None: ...
def control(
    study: str,
    fit: Optional[_Path],
    fit_text: Optional[str],
    options: str,
    out: Optional[_Path],
) -> Tuple[List[Tuple[str, _Columns]], List[Tuple[str, str]]]: ...
def chain_diagnostics(chains: Sequence[Sequence[Sequence[float]]]) -> List[Tuple[float, float, float]]: ...
