"""The type stubs describe the compiled module as it is: mypy's stubtest imports the built
``vanefit._core`` and compares every function, class, method and signature with
``_core.pyi`` (a name missing on either side, a parameter renamed, reordered or given another
default fails)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import vanefit

STUB = Path(vanefit.__file__).with_name("_core.pyi")


def test_stubtest_finds_the_stub_equal_to_the_built_module(tmp_path):
    pytest.importorskip("mypy")
    # From an empty folder, so that what is checked is the installed package. (A stub
    # with a renamed parameter, a missing function or a constructor written as __init__
    # instead of __new__ makes stubtest report it and exit 1.)
    p = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "vanefit._core"],
        cwd=tmp_path, capture_output=True, text=True,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    assert "Success" in p.stdout, p.stdout


def test_package_ships_its_stub_and_typing_marker():
    assert STUB.is_file()
    assert Path(vanefit.__file__).with_name("py.typed").is_file()


@pytest.mark.skipif(os.environ.get("VANEFIT_INSTALLED") != "1",
                    reason="CI installs the wheel and sets VANEFIT_INSTALLED=1")
def test_the_tests_run_on_the_installed_wheel():
    """CI tests the wheel as installed in its virtual environment, not the source tree."""
    here = Path(vanefit.__file__).resolve()
    assert Path(sys.prefix).resolve() in here.parents, here
    assert "site-packages" in here.parts, here
