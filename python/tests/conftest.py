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
# CI runs these tests on both cores (`pytest -n 2 --dist loadgroup`, .ci/run). A fixture is
# made once per worker that needs it, and tests are handed to workers one by one; so tests
# that share an expensive module fixture go to one worker together (an xdist group), and the
# timing-dependent Ctrl-C tests run one after the other on one worker. Without xdist the marks
# do nothing (the longest groups only run first).

# Fixture name → group: the tests that use it run on one worker, which makes it once.
SHARED_FIXTURE_GROUPS = {
    "pesto": "pesto",  # pyPESTO's multi-start and profiles (≈ 45 s)
    "runs": "sampler-runs",  # both samplers on the catalogue likelihood
    "page_runs": "sampler-page",  # both samplers on the page posterior (≈ 75 s)
    "fmus": "fmu",  # two FMUs exported and simulated
    "tiny_fit": "plot-fit",  # a fit with profiles for the plots
    "posterior": "sampler-runs",  # the catalogue fit the samplers start from
}
# The longest groups are handed out first (CI passes --no-loadscope-reorder, so that xdist
# keeps this order): started last, one of them would keep a worker busy alone at the end.
FIRST = ["sampler-page", "pesto"]
# Tests that measure how long something takes (the Ctrl-C tests: a KeyboardInterrupt within a
# round, a SIGINT answered within 30 s): one worker, one after the other.
TIMING_TESTS = {
    "test_keyboard_interrupt_stops_the_fit_and_it_resumes",
    "test_ctrl_c_interrupts_a_running_fit",
}


def pytest_configure(config):
    # Registered here too, so that the mark is known when pytest-xdist is not installed.
    config.addinivalue_line("markers", "xdist_group(name): run on one xdist worker together")


def pytest_collection_modifyitems(config, items):
    for item in items:
        group = None
        if item.originalname in TIMING_TESTS:
            group = "interrupt"
        params = getattr(getattr(item, "callspec", None), "params", {})
        if "export" in params:
            # test_petab's module fixture, one export per fit: the tests of one fit together.
            group = f"petab-{params['export']}"
        for name, g in SHARED_FIXTURE_GROUPS.items():
            if group is None and name in item.fixturenames:
                group = g
        if group is not None:
            item.add_marker(pytest.mark.xdist_group(group))
        item.stash[_GROUP] = group
    # A stable sort: within a group, and for the rest, the collection's order.
    rank = {g: i for i, g in enumerate(FIRST)}
    items.sort(key=lambda it: rank.get(it.stash[_GROUP], len(FIRST)))


_GROUP = pytest.StashKey[object]()
