"""The layering rules of docs/architecture.md §1, read from the source (no import needed).

* ``lubrication`` and ``bem`` are libraries: no module imports argparse, calls ``print`` or
  ``sys.exit`` (the command line is ``correlations.cli``);
* no module of the three packages imports another module's private (underscored) name: what
  two modules share is public;
* ``lubrication`` imports neither ``bem`` nor ``correlations``, ``bem`` not ``correlations``;
* an import inside a function says why it is not at module level (``# lazy: <reason>``).
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


def _function_imports(node, in_function=False):
    """Every import statement inside a function body (nested functions included)."""
    for child in ast.iter_child_nodes(node):
        if in_function and isinstance(child, (ast.Import, ast.ImportFrom)):
            yield child
        yield from _function_imports(
            child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)))


def test_every_import_inside_a_function_says_why():
    """Imports are at module level, except those that keep a heavy module (numba, matplotlib,
    dask, a scipy submodule, a library the command does not need) off a fast path
    (``vesicle-tube estimate``'s start-up, the input checks before numba, ``import bem``): each
    of those says why on its first line, ``# lazy: <reason>``."""
    found = []
    for path, tree in _modules(*PACKAGES):
        lines = (ROOT / path).read_text().splitlines()
        for node in _function_imports(tree):
            line = lines[node.lineno - 1]
            if "# lazy:" in line:
                continue
            found.append(f"{path}:{node.lineno}: {line.strip()}")
    assert not found, "imports inside functions without '# lazy: <reason>':\n" + "\n".join(found)
