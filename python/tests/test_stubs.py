"""The type stubs describe the compiled module as it is: every public name of
``vanefit._core`` is in ``_core.pyi`` with the same members, and nothing more."""

import ast
import inspect
from pathlib import Path

import vanefit
from vanefit import _core

STUB = Path(vanefit.__file__).with_name("_core.pyi")


def stub_names():
    tree = ast.parse(STUB.read_text())
    top, members = set(), {}
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            top.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            top.add(node.target.id)
        if isinstance(node, ast.ClassDef):
            members[node.name] = {
                n.name for n in node.body if isinstance(n, ast.FunctionDef) and not n.name.startswith("__")
            }
    return top, members


def test_stub_lists_every_public_name_of_the_extension():
    top, members = stub_names()
    runtime = {n for n in dir(_core) if not n.startswith("_")} | {"__version__"}
    assert top - {"_Path", "_Columns"} == runtime
    for cls, names in members.items():
        obj = getattr(_core, cls)
        public = {n for n, _ in inspect.getmembers(obj) if not n.startswith("_")}
        if issubclass(obj, BaseException):
            continue
        assert names == public, cls


def test_package_ships_its_typing_marker():
    assert Path(vanefit.__file__).with_name("py.typed").is_file()
