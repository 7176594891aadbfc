"""The layering rules of docs/architecture.md §1, read from the source (no import needed).

* ``lubrication`` and ``bem`` are libraries: no module imports argparse, calls ``print`` or
  ``sys.exit`` (the command line is ``correlations.cli``);
* no module of the three packages imports another module's private (underscored) name: what
  two modules share is public;
* ``lubrication`` imports neither ``bem`` nor ``correlations``, ``bem`` not ``correlations``.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("lubrication", "bem", "correlations")


def _modules(*packages):
    for package in packages:
        for path in sorted((ROOT / package).rglob("*.py")):
            yield path.relative_to(ROOT), ast.parse(path.read_text(), str(path))


def _imported(tree):
    """(module, name) of every import; name None for ``import module``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                yield a.name, None
        elif isinstance(node, ast.ImportFrom):
            for a in node.names:
                yield ("." * node.level) + (node.module or ""), a.name


@pytest.mark.parametrize("package", ["lubrication", "bem"])
def test_libraries_have_no_command_line(package):
    found = []
    for path, tree in _modules(package):
        for module, _ in _imported(tree):
            if module.split(".")[0] == "argparse":
                found.append(f"{path}: imports argparse")
        for node in ast.walk(tree):
            if isinstance(node, ast.Call):
                f = node.func
                if isinstance(f, ast.Name) and f.id == "print":
                    found.append(f"{path}:{node.lineno}: print()")
                if (isinstance(f, ast.Attribute) and f.attr == "exit"
                        and isinstance(f.value, ast.Name) and f.value.id == "sys"):
                    found.append(f"{path}:{node.lineno}: sys.exit()")
    assert not found, found


def test_no_module_imports_another_modules_private_names():
    found = [f"{path}: from {module} import {name}"
             for path, tree in _modules(*PACKAGES) for module, name in _imported(tree)
             if name and name.startswith("_") and not name.startswith("__")]
    assert not found, found


@pytest.mark.parametrize("package, forbidden", [("lubrication", ("bem", "correlations")),
                                                ("bem", ("correlations",))])
def test_dependencies_point_one_way(package, forbidden):
    found = [f"{path}: {module}" for path, tree in _modules(package)
             for module, _ in _imported(tree) if module.split(".")[0] in forbidden]
    assert not found, found
