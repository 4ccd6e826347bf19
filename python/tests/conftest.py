"""Shared fixtures: the repository, the command-line binary, and one short fit made by the
command line (the reference the Python side is compared with)."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DATASET = ROOT / "measurements" / "ar034-synthetic"


def vanefit_bin() -> str:
    """The CLI binary: $VANEFIT_BIN, or the release build of this checkout."""
    return os.environ.get("VANEFIT_BIN", str(ROOT / "target" / "release" / "vanefit"))


def run_cli(*args, check=True):
    """Runs the CLI from the repository root; returns the CompletedProcess."""
    p = subprocess.run(
        [vanefit_bin(), *map(str, args)], cwd=ROOT, capture_output=True, text=True
    )
    if check and p.returncode != 0:
        raise AssertionError(f"vanefit {' '.join(map(str, args))} failed:\n{p.stderr}")
    return p


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def cli_fit(tmp_path_factory) -> Path:
    """A short fit of the shipped dataset by the CLI (3 starts, curvature intervals)."""
    out = tmp_path_factory.mktemp("cli") / "fit.json"
    run_cli("fit", DATASET, "--starts", 3, "--seed", 5, "--max-iters", 150,
            "--uncertainty", "curvature", "--no-plots", "--out", out)
    assert json.loads(out.read_text())["statistics"]["likelihood_chi2"] > 0
    return out


@pytest.fixture(scope="session")
def profile_fit(tmp_path_factory) -> Path:
    """A full fit of the shipped dataset by the CLI (16 starts, profile-likelihood
    intervals): the reference for pyPESTO's optimum and profiles."""
    out = tmp_path_factory.mktemp("cli_profile") / "fit.json"
    run_cli("fit", DATASET, "--starts", 16, "--seed", 1, "--no-plots", "--out", out)
    doc = json.loads(out.read_text())
    assert doc["statistics"]["uncertainty"] == "profile"
    return out


CATALOGUE = ROOT / "measurements" / "ar034-synthetic-catalogue"


@pytest.fixture(scope="session")
def page_fit(tmp_path_factory) -> Path:
    """A fit of the shipped catalogue page by the CLI with its default motor prior (every
    default parameter estimated; what the page cannot pin rests on its prior)."""
    out = tmp_path_factory.mktemp("cli_page") / "fit.json"
    run_cli("fit", CATALOGUE, "--starts", 16, "--seed", 1, "--no-plots", "--out", out)
    doc = json.loads(out.read_text())
    assert doc["statistics"]["prior_chi2"] > 0
    return out


# --- running on several workers (pytest-xdist) ---------------------------------------------
# CI runs these tests on both cores (`pytest -n 2 --dist loadfile`, .ci/run): a file's tests
# run on one worker, so that a module fixture (pyPESTO's multi-start, the samplers' runs, the
# FMUs, each PEtab export) is made once, and the timing-dependent Ctrl-C tests of test_api.py
# run one after the other. (xdist's own groups, `--dist loadgroup`, were tried first: the
# worker names a test's group in its collection hook, which ran before this file's marks in
# pytest-xdist 3.8, so the groups never formed.) The files with the longest tests are handed
# out first (CI passes --no-loadscope-reorder, so that xdist keeps this order): started last,
# one of them would keep a worker busy alone at the end. Without xdist only the order changes.
LONGEST_FIRST = ["test_sampler.py", "test_pesto.py", "test_petab.py", "test_notebooks.py"]


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    # A stable sort: each file's tests stay together and in their order.
    items.sort(key=lambda it: rank.get(it.path.name, len(LONGEST_FIRST)))
