"""The wheel, installed as a user installs it, works like the source tree.

The wheel is built from a copy of this source tree (setuptools writes ``build/`` and
``*.egg-info`` into the tree it builds, and would package stale files of an old ``build/lib``),
installed into a fresh virtual environment outside the checkout with its dependencies from the
package index, pinned to the versions of the environment running these tests (so that both sides
compute with the same libraries and their numbers can be compared exactly). Then, each from a
working folder of its own outside the checkout, two sides run the same commands: the wheel's
environment, and the checkout's environment (the editable install) importing the packages from
that same copy (``PYTHONPATH``), so that a file saved in the checkout while the test runs does
not make the two sides run different code. The commands: every command of README.md's
command-line block with ``--json`` (added where the line has none: the same computation, its
numbers on stdout), ``map query`` and ``map pack`` of the installed build folder (README.md,
"Solution map") and README.md's Python block. Compared: the exit code, the JSON on stdout, the
files written (the same names; JSON files equal; CSV and Markdown files, the figures' verdicts
and the check report among them, equal as text), after removing what names the run rather than
its result: :data:`VOLATILE_KEYS` (objects and CSV columns), the installation's and the working
folder's paths, commit hashes and dates. Figures and plots (PNG) are compared by name only. The
two sides run side by side (a command's pair at a time, one per core).

Slow (a wheel build, an environment install, the README block on both sides: minutes), except
:func:`test_wheel_ships_every_file_of_the_packages` (a wheel build: seconds), which CI runs too.
"""

import csv
import difflib
import io
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import time
import zipfile
from concurrent.futures import ThreadPoolExecutor
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("lubrication", "bem", "correlations")
#: what a source copy leaves out: version control, environments, build products and caches
NOT_SOURCE = (".git", ".venv", "build", "dist", "*.egg-info", "__pycache__", ".hypothesis",
              ".ruff_cache", ".benchmarks", ".pytest_cache")
#: JSON keys and CSV columns that name the run (library versions, commit, date) or time it, not
#: its result; "sha256" is a figures cache file's checksum of its own content, timings included
VOLATILE_KEYS = {"provenance", "seconds", "timings", "runtime", "sha256"}
#: a command's time limit: the slowest README command, figures, takes 80 s to 2 min
COMMAND_TIMEOUT = 900

#: Echoes the value of each expression statement of README.md's Python block, as the
#: interpreter does at its prompt (the block is written for it: ``critical_confinement(0.6)``).
PYTHON_BLOCK_RUNNER = """
import ast, sys
ns = {}
for node in ast.parse(open(sys.argv[1], encoding="utf-8").read()).body:
    if isinstance(node, ast.Expr):
        print(repr(eval(compile(ast.Expression(node.value), "README", "eval"), ns)))
    else:
        exec(compile(ast.Module([node], []), "README", "exec"), ns)
"""


# --------------------------------------------------------------------------- building

@pytest.fixture(scope="module")
def source(tmp_path_factory) -> Path:
    """A copy of the source tree (module docstring)."""
    src = tmp_path_factory.mktemp("source") / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(*NOT_SOURCE))
    return src


@pytest.fixture(scope="module")
def wheel(source, tmp_path_factory) -> Path:
    """The wheel built by pip from the copy of the source tree."""
    tmp = tmp_path_factory.mktemp("wheel")
    _run_or_fail([sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet",
                  "--disable-pip-version-check", "--wheel-dir", str(tmp / "dist"), str(source)])
    (path,) = (tmp / "dist").glob("vesicle_tube-*.whl")
    print(f"\nwheel {path.name}: {path.stat().st_size / 1e6:.2f} MB")
    return path


def _run_or_fail(argv: list[str], **kwargs) -> subprocess.CompletedProcess:
    """``argv`` run to completion in the clean environment; a failure fails the test with the
    command and the end of its output."""
    proc = subprocess.run(argv, capture_output=True, text=True, check=False,
                          env=kwargs.pop("env", None) or _clean_env(), **kwargs)
    if proc.returncode:
        pytest.fail(f"{shlex.join(argv)} exited {proc.returncode}:\n{proc.stdout[-2000:]}"
                    f"{proc.stderr[-2000:]}")
    return proc


def _clean_env(pythonpath=None) -> dict:
    """This process's environment without what would point Python at the checkout (or with
    ``pythonpath`` first on the import path), and with matplotlib's file-only backend."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "VIRTUAL_ENV")}
    env["MPLBACKEND"] = "Agg"
    if pythonpath is not None:
        env["PYTHONPATH"] = str(pythonpath)
    return env


def _tracked_package_files() -> list[str]:
    """The files of the three packages under version control that exist in the working tree."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout: the package files under version control are unknown")
    out = subprocess.run(["git", "ls-files", "-z", "--", *PACKAGES], cwd=ROOT, check=True,
                         capture_output=True).stdout.decode()
    return [name for name in out.split("\0") if name and (ROOT / name).is_file()]


@pytest.mark.slow
@pytest.mark.ci
def test_wheel_ships_every_file_of_the_packages(wheel):
    """Every file of lubrication/, bem/ and correlations/ under version control (the modules,
    the packed solution map, the map's build folder with the BEM shapes that ``figures`` draws)
    is in the wheel."""
    shipped = set(zipfile.ZipFile(wheel).namelist())
    missing = [name for name in _tracked_package_files() if name not in shipped]
    assert not missing, (f"{len(missing)} file(s) of the packages are not in {wheel.name} "
                         f"(pyproject.toml [tool.setuptools]): {missing[:20]}")


# --------------------------------------------------------------------------- installing

@pytest.fixture(scope="module")
def wheel_env(wheel, tmp_path_factory) -> Path:
    """A fresh virtual environment outside the checkout with the wheel installed (dependencies
    from the package index, at the versions installed here); returns its bin folder."""
    tmp = tmp_path_factory.mktemp("venv")
    venv = tmp / "venv"
    _run_or_fail([sys.executable, "-m", "venv", str(venv)])
    pins = sorted({f"{d.metadata['Name']}=={d.version}" for d in metadata.distributions()
                   if d.metadata["Name"] and d.metadata["Name"].lower() != "vesicle-tube"})
    constraints = tmp / "constraints.txt"
    constraints.write_text("\n".join(pins) + "\n", encoding="utf-8")
    t0 = time.perf_counter()
    _run_or_fail([str(venv / "bin" / "python"), "-m", "pip", "install", "--quiet",
                  "--disable-pip-version-check", "--constraint", str(constraints), str(wheel)])
    print(f"installed {wheel.name} and its dependencies in {time.perf_counter() - t0:.0f} s")
    return venv / "bin"


def _package_site(bin_dir: Path, cwd: Path, env: dict) -> Path:
    """The folder the ``correlations`` package is imported from by ``bin_dir``'s Python, run
    in ``cwd`` with ``env`` (the source copy, or site-packages for the wheel)."""
    code = "import correlations, pathlib; print(pathlib.Path(correlations.__file__).parents[1])"
    return Path(_run_or_fail([str(bin_dir / "python"), "-c", code], cwd=cwd, env=env)
                .stdout.strip())


# --------------------------------------------------------------------------- the commands

def _readme_block(heading: str, language: str) -> str:
    """The first ``language`` code block after the README heading ``heading``."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    start = text.index(f"\n## {heading}\n")
    block = re.search(rf"```{language}\n(.*?)```", text[start:], re.DOTALL)
    return block.group(1)


def _readme_commands() -> list[list[str]]:
    """The argument lists of README.md's command-line block (comments removed)."""
    commands = [shlex.split(line, comments=True)
                for line in _readme_block("Command line", "sh").splitlines()
                if line.startswith("vesicle-tube ")]
    return [argv[1:] for argv in commands]


#: the installation's folder of the packages, in :func:`_commands`
SITE = "{site}"


def _commands() -> list[list[str]]:
    """Every command compared, with ``--json``: README.md's command-line block, ``map query``
    and ``map pack`` of the installed build folder (README.md, "Solution map")."""
    commands = _readme_commands() + [
        ["map", "query", "--nu", "0.92", "--lam-ratio", "0.96", "--ca-b", "50"],
        ["map", "pack", f"{SITE}/correlations/data/solution_map_build", "--out", "packed.json"]]
    return [argv if "--json" in argv else [*argv, "--json"] for argv in commands]


# --------------------------------------------------------------------------- comparing

def _masker(site: Path, cwd: Path):
    """A function that replaces, in a text, what names this run rather than its result: the
    package's installation folder, the working folder, commit hashes, dates (ISO 8601) and a
    commit of "unknown" (outside a git checkout)."""
    def mask(text: str) -> str:
        text = text.replace(str(site), "<site>").replace(str(cwd), "<cwd>")
        text = re.sub(r"\b[0-9a-f]{40}\b", "<commit>", text)
        text = re.sub(r"\bcommit (unknown|<commit>)", "commit <commit>", text)
        return re.sub(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d(\.\d+)?([+-]\d\d:\d\d|Z)?", "<date>", text)
    return mask


def _normalised(value, mask):
    """JSON data without :data:`VOLATILE_KEYS`, with every string masked."""
    if isinstance(value, dict):
        return {k: _normalised(v, mask) for k, v in value.items() if k not in VOLATILE_KEYS}
    if isinstance(value, list):
        return [_normalised(v, mask) for v in value]
    return mask(value) if isinstance(value, str) else value


def _flat(value, prefix="") -> dict:
    """{"/key/0/key": leaf} of nested JSON data."""
    if isinstance(value, dict):
        items = value.items()
    elif isinstance(value, list):
        items = enumerate(value)
    else:
        return {prefix or "/": value}
    out = {}
    for k, v in items:
        out.update(_flat(v, f"{prefix}/{k}"))
    return out


def _json_diff(source, wheel, limit=15) -> list[str]:
    """The leaves that differ, as "path: source != wheel" lines (at most ``limit``)."""
    a, b = _flat(source), _flat(wheel)
    missing = object()
    lines = [f"  {k}: source {a.get(k, '(absent)')!r} != wheel {b.get(k, '(absent)')!r}"
             for k in sorted(a.keys() | b.keys()) if a.get(k, missing) != b.get(k, missing)]
    return lines[:limit] + ([f"  ... {len(lines) - limit} more"] if len(lines) > limit else [])


def _text_diff(source: str, wheel: str, limit=15) -> list[str]:
    lines = list(difflib.unified_diff(source.splitlines(), wheel.splitlines(), "source",
                                      "wheel", lineterm="", n=1))
    return [f"  {x}" for x in lines[:limit]] + (["  ..."] if len(lines) > limit else [])


def _csv_rows(text: str) -> list[dict]:
    """The rows of a CSV text without the :data:`VOLATILE_KEYS` columns."""
    return [{k: v for k, v in row.items() if k not in VOLATILE_KEYS}
            for row in csv.DictReader(io.StringIO(text))]


def _parse_json(text: str):
    try:
        return json.loads(text)
    except ValueError:
        return None


class Side:
    """One installation (source or wheel): its bin folder, its environment, its working folder,
    the files its commands wrote (relative path -> the command that last wrote it) and its
    masker."""

    def __init__(self, name: str, bin_dir: Path, cwd: Path, pythonpath=None):
        self.name, self.bin, self.cwd = name, bin_dir, cwd
        self.env = _clean_env(pythonpath)
        cwd.mkdir(parents=True)
        table = ROOT / "docs" / "data" / "chen2020_table1.csv"   # the check example's input
        (cwd / "docs" / "data").mkdir(parents=True)
        shutil.copy(table, cwd / "docs" / "data" / table.name)
        self.site = _package_site(bin_dir, cwd, self.env)
        self.mask = _masker(self.site, cwd)
        self.written: dict[str, str] = {}

    def _snapshot(self) -> dict:
        return {str(p.relative_to(self.cwd)): (p.stat().st_size, p.stat().st_mtime_ns)
                for p in self.cwd.rglob("*") if p.is_file()}

    def run(self, argv: list[str]) -> tuple[subprocess.CompletedProcess, float]:
        """``vesicle-tube argv`` ({site} replaced) in the working folder, and its seconds;
        records the files it wrote."""
        before = self._snapshot()
        t0 = time.perf_counter()
        proc = subprocess.run([str(self.bin / "vesicle-tube"),
                               *(x.replace(SITE, str(self.site)) for x in argv)],
                              cwd=self.cwd, capture_output=True, text=True, env=self.env,
                              stdin=subprocess.DEVNULL, timeout=COMMAND_TIMEOUT, check=False)
        seconds = time.perf_counter() - t0
        for path, stamp in self._snapshot().items():
            if before.get(path) != stamp:
                self.written[path] = shlex.join(["vesicle-tube", *argv])
        return proc, seconds

    def run_python_block(self, code: str) -> subprocess.CompletedProcess:
        script = self.cwd / "readme_python.py"
        script.write_text(code, encoding="utf-8")
        return subprocess.run([str(self.bin / "python"), "-c", PYTHON_BLOCK_RUNNER, str(script)],
                              cwd=self.cwd, capture_output=True, text=True, env=self.env,
                              stdin=subprocess.DEVNULL, timeout=COMMAND_TIMEOUT, check=False)


def _compare_command(argv, a: Side, b: Side, pa, pb) -> list[str]:
    """The differences between the source's (a) and the wheel's (b) run of one command."""
    problems = []
    if pa.returncode != pb.returncode:
        problems.append(f"  exit code: source {pa.returncode} != wheel {pb.returncode}")
    for side, p in ((a, pa), (b, pb)):
        if "Traceback" in p.stderr:
            problems.append(f"  {side.name} printed a traceback:\n{p.stderr[-1500:]}")
    ja, jb = _parse_json(pa.stdout), _parse_json(pb.stdout)
    if ja is None or jb is None:
        problems.append(f"  stdout is not JSON: source {pa.stdout[:200]!r}, "
                        f"wheel {pb.stdout[:200]!r}")
    else:
        diff = _json_diff(_normalised(ja, a.mask), _normalised(jb, b.mask))
        problems += ["  --json output differs:", *diff] if diff else []
    return problems


def _compare_files(a: Side, b: Side) -> list[str]:
    """The differences between the files the two sides wrote, each with its command."""
    problems = []
    for path in sorted(a.written.keys() | b.written.keys()):
        command = a.written.get(path) or b.written.get(path)
        if path not in a.written or path not in b.written:
            where = "source" if path in a.written else "wheel"
            problems.append(f"{command}: {path} written only by the {where}")
            continue
        fa, fb = a.cwd / path, b.cwd / path
        if fa.suffix == ".json":
            diff = _json_diff(_normalised(json.loads(fa.read_text(encoding="utf-8")), a.mask),
                              _normalised(json.loads(fb.read_text(encoding="utf-8")), b.mask))
        elif fa.suffix == ".csv":
            diff = _json_diff(_csv_rows(fa.read_text(encoding="utf-8")),
                              _csv_rows(fb.read_text(encoding="utf-8")))
        elif fa.suffix in (".md", ".txt"):
            ta = a.mask(fa.read_text(encoding="utf-8"))
            tb = b.mask(fb.read_text(encoding="utf-8"))
            diff = _text_diff(ta, tb) if ta != tb else []
        else:
            diff = []                                   # figures and plots: by name only
        if diff:
            problems.append(f"{command}: {path} differs:\n" + "\n".join(diff))
    return problems


@pytest.mark.slow
def test_wheel_commands_match_the_source(source, wheel_env, tmp_path):
    """Each command gives the same exit code, JSON and files from the installed wheel as from
    the source tree (module docstring)."""
    checkout_bin = Path(sys.executable).parent
    assert (checkout_bin / "vesicle-tube").is_file(), "run the tests from the checkout's venv"
    a = Side("source", checkout_bin, tmp_path / "source", pythonpath=source)
    b = Side("wheel", wheel_env, tmp_path / "wheel")
    assert a.site.resolve() == source.resolve(), f"the source side imports from {a.site}"
    assert b.site.resolve().is_relative_to(wheel_env.parent.resolve()), (
        f"the wheel's Python imports correlations from {b.site}, not from its environment")

    problems, timings = [], []
    with ThreadPoolExecutor(2) as pool:
        for argv in _commands():
            (pa, ta), (pb, tb) = pool.map(Side.run, (a, b), (argv, argv))
            timings.append(f"  {ta:6.1f} s {tb:6.1f} s  exit {pa.returncode} {pb.returncode}"
                           f"  {shlex.join(argv)}")
            found = _compare_command(argv, a, b, pa, pb)
            if found:
                problems.append(f"vesicle-tube {shlex.join(argv)}:\n" + "\n".join(found))
    problems += _compare_files(a, b)

    code = _readme_block("Python", "python")
    pa, pb = a.run_python_block(code), b.run_python_block(code)
    if (pa.returncode, pa.stdout) != (pb.returncode, pb.stdout) or pa.returncode:
        problems.append(f"README.md's Python block: exit code source {pa.returncode}, wheel "
                        f"{pb.returncode}; stderr {pa.stderr[-600:]!r}, {pb.stderr[-600:]!r}\n"
                        + "\n".join(_text_diff(pa.stdout, pb.stdout)))
    print("  source   wheel  exit codes  command\n" + "\n".join(timings))
    assert not problems, "the wheel differs from the source:\n" + "\n".join(problems)
