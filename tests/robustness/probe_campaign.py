"""Probe campaign: every command of ``vesicle-tube`` fed unusual and invalid inputs.

Runs each probe as a separate process (the installed console script) with a wall-time bound
(60 s by default), and checks the command-line contract of :mod:`correlations.cli.contract`:

* exit 0: finite numbers only (strict JSON with ``--json``; no ``nan``/``inf`` in a table);
* exit 2: exactly one line on stderr, naming an option or parameter, nothing on stdout;
* exit 1: a solver message; a failed solve reports no physical numbers (JSON probes);
* never a Python traceback, never a hang (the bound), peak memory measured per probe;
* exit 0: no value outside :data:`lubrication.checks.OUTPUT_BOUNDS` without an UNPHYSICAL flag
  ("silent bad result", JSON probes).

The file probes (group ``files``, :mod:`file_probes`) aim at the commands that read or write
files. Each runs in its own sandbox folder (its working directory, made and filled just before
the run, removed after), under a 2 GiB data-size limit (``/dev/zero`` read whole stops there),
and is also judged on:

* files not ours touched: a file of the sandbox that existed before the run (the user's) is
  changed or removed, unless the probe names it as an output it may rewrite;
* a temporary file (``.*.tmp``) left behind;
* peak memory above :data:`MAX_MB`;
* an exit-2 line that names no option (``--...``), no FILE/DIR argument and no column (of a
  ``check`` input).

Usage::

    python tests/robustness/probe_campaign.py [--workers 2] [--timeout 60] [--only TEXT]
        [--group all|base|files] [--report FILE.md]

Prints a summary table and writes the per-probe report (atomically; default
docs/probe-campaign.md, or docs/probe-campaign-files.md for ``--group files``). Not a test: it
takes several minutes; the fuzzing suite (tests/robustness/test_fuzz_cli.py) keeps the contract
in the default test suite.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import re
import select
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from fnmatch import fnmatchcase
from pathlib import Path

from correlations.cli.contract import one_line
from lubrication.checks import OUTPUT_BOUNDS, check_output

ROOT = Path(__file__).resolve().parents[2]

# Keys that are physical results of a solve: null when the solve failed.
PHYSICAL_KEYS = ("V_over_U", "dp_plus_R0", "dp_plus_R", "film_min", "film", "ell", "tension_max",
                 "tension_front", "drag_K", "length", "wall_shear_max")

BAD_FLOATS = ("nan", "inf", "-inf", "1e308", "-1", "0", "1e-320", "abc", "")
NON_FINITE = re.compile(r"(?<![\w-])(-?inf(inity)?|nan)(?![\w-])", re.IGNORECASE)
# Ca_B = inf names the high-Ca lubrication model: a model, not a computed number
MODEL_NAMES = re.compile(r"Ca_B = inf|inf \(high-Ca model\)")

# Result keys checked against OUTPUT_BOUNDS (a number, or a {"value": number} quantity), with
# the quantity whose bound applies; subtrees that echo the user's input or hold error
# estimates and units are not results.
BOUNDED = {**{q: q for q in OUTPUT_BOUNDS}, "dp_plus_R": "dp_plus_R0", "film_min": "film"}
NOT_RESULTS = {"inputs", "values", "uncertainties", "cells", "parameters", "grid", "units",
               "checks", "error_estimate", "errors"}

#: Peak memory a file probe may use [MB] (the contract's bound on a command's work).
MAX_MB = 500.0
#: Data-size limit of a file probe's process [bytes]: a runaway read stops there.
DATA_LIMIT = 2 * 2**30


@dataclass
class Probe:
    """One command line and the exit codes the contract allows for it. The fields after
    ``files`` serve the file probes (:mod:`file_probes`)."""

    argv: list
    allowed: tuple = (0, 1, 2)
    why: str = ""
    files: list = field(default_factory=list)    # paths the probe may write (must be complete)
    group: str = "base"
    sandbox: Path | None = None     # own folder and working directory, made before, removed after
    setup: Callable | None = None   # setup(sandbox): writes the files the probe reads
    may_change: tuple = ()          # sandbox-relative globs of files the command may rewrite
    env: dict | None = None         # environment variables set for the run
    stdout: str | None = None       # file the command's stdout goes to (e.g. /dev/full)
    post: Callable | None = None    # post(sandbox, outcome) -> extra problems
    run: Callable | None = None     # run(probe, timeout) -> Outcome: a scenario of processes
    skip: str = ""                  # why the probe cannot run on this machine
    max_mb: float | None = None     # peak memory bound [MB]


def exe() -> str:
    """The console script: on the PATH, else beside this Python."""
    return shutil.which("vesicle-tube") or str(Path(sys.executable).with_name("vesicle-tube"))


def _value_probes(base: list, option: str, values=BAD_FLOATS, valid_codes=None) -> list:
    """``base`` with ``option`` set to each bad value; nan/inf/strings must give exit 2."""
    out = []
    for v in values:
        codes = (2,) if v in ("nan", "inf", "-inf", "abc", "") else (valid_codes or (0, 1, 2))
        out.append(Probe(base + [option, v], codes, f"{option} {v!r}"))
    return out


def probes(tmp: Path) -> list[Probe]:
    """The campaign: at least 200 command lines across every command (group ``base``), then
    the file probes of :mod:`file_probes` (group ``files``)."""
    P = []
    # --- geometry
    P += [Probe(["geometry", "--nu", "0.6", "--lam", "1.9"], (0,)),
          Probe(["geometry", "--volume-fl", "90", "--area-um2", "135", "--diameter-um", "4"], (0,)),
          Probe(["geometry", "--nu", "0.6", "--lam", "1e200"], (0, 2), "overflow of nu_c"),
          Probe(["geometry"], (2,), "missing inputs"),
          Probe(["geometry", "--nu", "0.6", "--volume-fl", "90"], (2,), "conflicting options"),
          Probe(["geometry", "--volume-fl", "90", "--area-um2", "20"], (2,), "area below sphere"),
          Probe(["geometry", "--nu", "1", "--lam", "1"], (0, 2), "sphere at lam = 1")]
    P += _value_probes(["geometry", "--lam", "1.2"], "--nu")
    P += _value_probes(["geometry", "--nu", "0.8"], "--lam")
    P += _value_probes(["geometry", "--area-um2", "135", "--diameter-um", "4"], "--volume-fl")
    P += _value_probes(["geometry", "--volume-fl", "90", "--diameter-um", "4"], "--area-um2")
    P += _value_probes(["geometry", "--volume-fl", "90", "--area-um2", "135"], "--diameter-um")
    # --- estimate (physical and dimensionless)
    P += [Probe(["estimate"], (0,), "defaults"),
          Probe(["estimate", "--json"], (0,), "defaults, JSON"),
          Probe(["estimate", "--nu", "0.9", "--lam", "1.25"], (0,)),
          Probe(["estimate", "--nu", "0.9"], (2,), "--nu without --lam"),
          Probe(["estimate", "--nu", "0.9", "--lam", "1.0", "--volume-fl", "90"], (2,)),
          Probe(["estimate", "--ca-b", "50"], (2,), "--ca-b with physical inputs"),
          Probe(["estimate", "--velocity-mm-s", "1e308"], (0, 2), "Ca_B overflow"),
          Probe(["estimate", "--diameter-um", "2"], (0, 2), "cannot pass"),
          Probe(["estimate", "--diameter-um", "2", "--hematocrit", "0.3"], (0, 2)),
          Probe(["estimate", "--diameter-um", "3", "--hematocrit", "0.3", "--json"], (0,)),
          Probe(["estimate", "--hematocrit", "45"], (2,), "percentage"),
          Probe(["estimate", "--hematocrit", "0.3", "--hematocrit-kind", "volume"], (2,)),
          Probe(["estimate", "--solver", "magic"], (2,)),
          Probe(["estimate", "--extrapolate", "--json"], (0,)),
          Probe(["estimate", "--nu", "0.9", "--lam", "1.0", "--solver", "lubrication", "--json"],
                (0, 1)),
          Probe(["estimate", "--plot", str(tmp / "est.bad")], (2,), "unknown plot format"),
          Probe(["estimate", "--plot", str(tmp / "nofolder" / "est.png")], (2,)),
          Probe(["estimate", "--plot", str(tmp)], (2,), "plot path is a folder"),
          Probe(["estimate", "--plot", str(tmp / "est.png")], (0,), files=[tmp / "est.png"]),
          Probe(["estimate", "--plot", str(tmp / "est.svg")], (0,), files=[tmp / "est.svg"])]
    for opt in ("--volume-fl", "--area-um2", "--diameter-um", "--velocity-mm-s",
                "--plasma-viscosity-mpas", "--bending-modulus-j", "--hematocrit"):
        P += _value_probes(["estimate"], opt)
    for opt, other in (("--nu", ["--lam", "1.0"]), ("--lam", ["--nu", "0.9"])):
        P += _value_probes(["estimate"] + other, opt)
    P += _value_probes(["estimate", "--nu", "0.9", "--lam", "1.0"], "--ca-b")
    # --- viscosity and Fahraeus
    P += [Probe(["viscosity", "--diameter-um", "6", "--hematocrit", "0.45"], (0,)),
          Probe(["viscosity", "--diameter-um", "2", "--hematocrit", "0.45"], (0, 2),
                "H_T > H_D from the Fahraeus fit"),
          Probe(["viscosity", "--diameter-um", "3", "--hematocrit", "0.45", "--law",
                 "single-file"], (0,)),
          Probe(["viscosity", "--diameter-um", "20", "--hematocrit", "0.45", "--law",
                 "single-file"], (0, 2)),
          Probe(["viscosity", "--diameter-um", "6"], (2,), "missing --hematocrit"),
          Probe(["viscosity", "--diameter-um", "6", "--hematocrit", "0.45", "--law", "x"], (2,)),
          Probe(["viscosity", "--diameter-um", "6", "--hematocrit", "0.45", "--plot",
                 str(tmp / "v.bad")], (2,)),
          Probe(["viscosity", "--diameter-um", "6", "--hematocrit", "0.45", "--plot",
                 str(tmp / "v.pdf")], (0,), files=[tmp / "v.pdf"])]
    for law in ("pries1992", "pries1994", "pries2005"):
        P += _value_probes(["viscosity", "--hematocrit", "0.45", "--law", law], "--diameter-um",
                           ("nan", "1e308", "0", "-5", "1e-320", "2.5", "2.8"))
        P += _value_probes(["viscosity", "--diameter-um", "6", "--law", law], "--hematocrit",
                           ("nan", "-0.1", "1", "45", "0", "0.99"))
    P += [Probe(["fahraeus", "--diameter-um", "10", "--discharge-hematocrit", "0.45"], (0,)),
          Probe(["fahraeus", "--diameter-um", "10"], (2,)),
          Probe(["fahraeus", "--diameter-um", "10", "--discharge-hematocrit", "0.4",
                 "--tube-hematocrit", "0.3"], (2,))]
    P += _value_probes(["fahraeus", "--discharge-hematocrit", "0.45"], "--diameter-um")
    P += _value_probes(["fahraeus", "--diameter-um", "2.8"], "--tube-hematocrit")
    P += _value_probes(["fahraeus", "--diameter-um", "2"], "--discharge-hematocrit")
    # --- lubrication
    lub = ["lubrication", "--nu", "0.9"]
    P += [Probe(lub + ["--lam-ratio", "0.99"], (0,)),
          Probe(lub + ["--lam-ratio", "0.99", "--ca-b", "50", "--json"], (0,)),
          Probe(lub + ["--lam-ratio", "1e-3"], (1, 2), "tiny confinement"),
          Probe(lub + ["--lam-ratio", "1e-3", "--ca-b", "50", "--json"], (0, 1, 2)),
          Probe(lub + ["--lam-ratio", "0.3", "--json"], (1, 2), "high-Ca below its range"),
          Probe(lub + ["--lam-ratio", "1"], (2,), "lam = lam_c"),
          Probe(lub + ["--lam", "5"], (2,), "lam > lam_c"),
          Probe(lub, (2,), "missing --lam"),
          Probe(lub + ["--lam", "1", "--lam-ratio", "0.9"], (2,)),
          Probe(lub + ["--sweep", "--points", "1000000"], (2,), "absurd sweep"),
          Probe(lub + ["--sweep", "--points", "1"], (2,)),
          Probe(lub + ["--sweep", "--from", "0.9", "--to", "0.99", "--points", "3", "--ca-b",
                       "50", "--json"], (0, 1)),
          Probe(lub + ["--sweep", "--from", "0.9", "--to", "0.99", "--points", "3", "--plot",
                       str(tmp / "sw.bad")], (2,)),
          Probe(lub + ["--lam-ratio", "0.99", "--out", str(tmp / "est.png")], (2,),
                "--out is a file"),
          Probe(lub + ["--lam-ratio", "0.99", "--out", "/proc/vesicle"], (2,),
                "--out not writable"),
          Probe(lub + ["--lam-ratio", "0.99", "--out", str(tmp / "lub"), "--plot",
                       str(tmp / "lub.png")], (0,), files=[tmp / "lub.png"])]
    P += _value_probes(lub, "--lam-ratio")
    P += _value_probes(["lubrication", "--lam-ratio", "0.99"], "--nu")
    P += _value_probes(lub + ["--lam-ratio", "0.99"], "--ca-b",
                       ("nan", "-inf", "abc", "", "-1", "0", "1e-320", "1e308"))
    P += _value_probes(lub + ["--sweep"], "--points", ("nan", "abc", "", "-1", "0", "1e308"))
    P += _value_probes(lub + ["--sweep", "--points", "3"], "--from",
                       ("nan", "inf", "-1", "0", "2"))
    # --- BEM sphere, drop, vesicle, vesicle-sweep
    P += [Probe(["bem", "sphere", "--lam", "0.5"], (0,)),
          Probe(["bem", "sphere", "--lam", "1e-300"], (0, 2), "tiny sphere"),
          Probe(["bem", "sphere", "--lam", "0.99"], (0, 1, 2), "near contact"),
          Probe(["bem", "sphere", "--lam", "0.999999"], (0, 1, 2), "near contact"),
          Probe(["bem", "sphere", "--lam", "1"], (2,)),
          Probe(["bem", "sphere", "--lam", "0.5", "--panels", "100000000"], (2,)),
          Probe(["bem", "sphere", "--lam", "0.5", "--plot", str(tmp / "s.bad")], (2,)),
          Probe(["bem", "drop", "--lam", "0.8", "--ca", "1e-300"], (0, 1, 2), "vanishing Ca"),
          Probe(["bem", "drop", "--lam", "0.5", "--ca", "0.1", "--json"], (0, 1)),
          Probe(["bem", "drop", "--lam", "0.8", "--ca", "100", "--json"], (0, 1, 2)),
          Probe(["bem", "drop", "--lam", "0.999", "--ca", "0.1", "--json"], (0, 1, 2)),
          Probe(["bem", "drop", "--lam", "0.5", "--ca", "0.1", "--modes", "100000"], (2,)),
          Probe(["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--ca-b", "1e308", "--json"],
                (1, 2), "huge Ca_B"),
          Probe(["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--json"], (0, 1)),
          Probe(["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--max-time", "0.05", "--json"],
                (1,), "time limit"),
          Probe(["bem", "vesicle", "--nu", "0.9", "--lam", "5"], (2,)),
          Probe(["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--modes", "100000"], (2,)),
          Probe(["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--plot",
                 str(tmp / "p.bad")], (2,)),
          Probe(["bem", "vesicle-sweep", "--nu", "0.9", "--lam-ratio", "0.5", "0.75", "1e6"],
                (2,), "absurd sweep"),
          Probe(["bem", "vesicle-sweep", "--nu", "0.9", "--lam-ratio", "0.5", "0.75", "2.5"],
                (2,)),
          Probe(["bem", "vesicle-sweep", "--nu", "0.9", "--lam-ratio", "0.5", "0.75", "3",
                 "--plot", str(tmp / "p.bad")], (2,), "bad plot format before minutes of work"),
          Probe(["bem", "vesicle-sweep", "--nu", "0.9", "--lam-ratio", "0.5", "0.75", "3",
                 "--out", str(tmp / "est.png")], (2,))]
    P += _value_probes(["bem", "sphere"], "--lam", ("nan", "inf", "-1", "0", "1e308", "abc"))
    P += _value_probes(["bem", "sphere", "--lam", "0.5"], "--tol",
                       ("nan", "inf", "-1", "0", "1e308", "1e-320"))
    P += _value_probes(["bem", "drop", "--ca", "0.1"], "--lam",
                       ("nan", "inf", "-1", "0", "1", "1e308", "1e-320"))
    P += _value_probes(["bem", "drop", "--lam", "0.5"], "--ca",
                       ("nan", "inf", "-1", "0", "1e308", "1e-320"))
    P += _value_probes(["bem", "drop", "--lam", "0.5", "--ca", "0.1"], "--tol",
                       ("nan", "-1", "0", "1e308"))
    ves = ["bem", "vesicle", "--nu", "0.9"]
    P += _value_probes(ves + ["--lam", "1.0"], "--ca-b", ("nan", "inf", "-1", "0", "1e-320"))
    P += _value_probes(ves, "--lam", ("nan", "inf", "-1", "0", "1e308"))
    P += _value_probes(["bem", "vesicle", "--lam", "1.0"], "--nu",
                       ("nan", "inf", "-1", "0", "1", "1e308"))
    P += _value_probes(ves + ["--lam", "1.0"], "--tol", ("nan", "-1", "0", "1e308"))
    P += _value_probes(ves + ["--lam", "1.0"], "--residual-tol", ("nan", "-1", "0"))
    P += _value_probes(ves + ["--lam", "1.0"], "--max-modes", ("-1", "0", "1e308", "abc"))
    P += _value_probes(ves + ["--lam", "1.0"], "--max-time", ("nan", "inf", "-1", "0"))
    # --- the top level
    P += [Probe([], (2,), "no command"), Probe(["frobnicate"], (2,), "unknown command"),
          Probe(["--help"], (0,)), Probe(["estimate", "--help"], (0,)),
          Probe(["bem"], (2,)), Probe(["bem", "sphere"], (2,)),
          Probe(["estimate", "--json", "--json"], (0,))]
    import file_probes  # lazy: it imports this module (its Probe), so not at the top
    return P + file_probes.probes(tmp / "files")


@dataclass
class Outcome:
    probe: Probe
    code: int | None
    seconds: float
    peak_mb: float
    stdout: str
    stderr: str
    problems: list
    skipped: bool = False


def _tree_peak_mb(pid: int) -> float:
    """Largest peak resident memory (VmHWM) [MB] of process ``pid`` and its descendants: read
    before a hung probe is killed, since its /usr/bin/time dies with it."""
    peak, todo = float("nan"), [pid]
    while todo:
        proc = Path("/proc") / str(todo.pop())
        try:
            for line in (proc / "status").read_text().splitlines():
                if line.startswith("VmHWM:"):
                    mb = float(line.split()[1]) / 1024.0
                    peak = mb if math.isnan(peak) else max(peak, mb)
            for task in (proc / "task").iterdir():
                todo += [int(c) for c in (task / "children").read_text().split()]
        except (OSError, ValueError):
            continue
    return peak


class Running:
    """A probe's command line started as the campaign runs it: its own process group, under
    GNU ``/usr/bin/time`` (peak memory; NaN where it is missing); a file probe also in its
    sandbox, with its environment and stdout, stdin closed and the data-size limit
    :data:`DATA_LIMIT`. ``argv`` replaces the probe's own (a step of a scenario)."""

    def __init__(self, probe: Probe, argv: list | None = None):
        self.probe, self.argv = probe, probe.argv if argv is None else argv
        fd, self.log = tempfile.mkstemp(suffix=".time")
        os.close(fd)
        timer = (["/usr/bin/time", "-f", "%M", "-o", self.log]
                 if Path("/usr/bin/time").exists() else [])
        boxed = probe.sandbox is not None
        limit = ["prlimit", f"--data={DATA_LIMIT}"] if boxed and shutil.which("prlimit") else []
        env = None if probe.env is None else {**os.environ, **probe.env}
        # closed by finish(): the file outlives this method
        self.sink = open(probe.stdout, "w") if probe.stdout else None  # noqa: SIM115
        self.t0 = time.perf_counter()
        self.proc = subprocess.Popen(timer + limit + [exe()] + self.argv,
                                     stdout=self.sink or subprocess.PIPE, stderr=subprocess.PIPE,
                                     stdin=subprocess.DEVNULL if boxed else None,
                                     text=True, encoding="utf-8", errors="replace",
                                     start_new_session=True, cwd=probe.sandbox, env=env)

    def finish(self, timeout: float) -> Outcome:
        """Wait at most ``timeout`` seconds from the start; kill the process group beyond."""
        left = max(0.1, timeout - (time.perf_counter() - self.t0))
        hung_peak = None
        try:
            out, err = self.proc.communicate(timeout=left)
            code = self.proc.returncode
        except subprocess.TimeoutExpired:
            hung_peak = _tree_peak_mb(self.proc.pid)
            os.killpg(self.proc.pid, signal.SIGKILL)
            out, err = self.proc.communicate()
            code = None
        seconds = time.perf_counter() - self.t0
        if self.sink is not None:
            self.sink.close()
        try:
            peak = float(Path(self.log).read_text().strip().splitlines()[-1]) / 1024.0
        except (ValueError, IndexError, OSError):
            peak = float("nan") if hung_peak is None else hung_peak
        os.unlink(self.log)
        # /usr/bin/time reports "Command exited with non-zero status N" on stderr
        err = "\n".join(line for line in err.splitlines()
                        if not line.startswith("Command exited with non-zero status")
                        and not line.startswith("Command terminated by signal"))
        return Outcome(self.probe, code, seconds, peak, out or "", err, [])


def _run_measured(probe: Probe, timeout: float) -> Outcome:
    """Run one probe's command line to its end or the bound (see :class:`Running`)."""
    return Running(probe).finish(timeout)


def out_of_bounds(obj, where: str = "") -> list[str]:
    """``key = value`` of every result number of a JSON object outside
    :data:`lubrication.checks.OUTPUT_BOUNDS` (keys of :data:`BOUNDED`; the subtrees of
    :data:`NOT_RESULTS` skipped)."""
    found = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k in NOT_RESULTS:
                continue
            value = v.get("value") if isinstance(v, dict) and k in BOUNDED else v
            number = isinstance(value, (int, float)) and not isinstance(value, bool)
            if k in BOUNDED and number and check_output(BOUNDED[k], float(value), {}):
                found.append(f"{where}{k} = {value:.6g}")
            found += out_of_bounds(v, f"{where}{k}.")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            found += out_of_bounds(v, f"{where}{i}.")
    return found


def _strict_json(text: str):
    return json.loads(text, parse_constant=lambda c: (_ for _ in ()).throw(ValueError(c)))


def judge(o: Outcome) -> Outcome:
    p = o.problems
    if o.code is None:
        p.append("hang")
        return o
    if "Traceback" in o.stderr:
        p.append("traceback")
    if o.code not in (0, 1, 2):
        p.append(f"exit {o.code}")
    elif o.code not in o.probe.allowed:
        p.append(f"exit {o.code} not in {o.probe.allowed}")
    # stdout sent to a file (/dev/full) is not seen
    is_json = "--json" in o.probe.argv and o.probe.stdout is None
    if o.code in (0, 1) and "--help" not in o.probe.argv:
        obj = None
        if is_json:
            try:
                obj = _strict_json(o.stdout)
            except ValueError:
                p.append("silent nan/inf" if NON_FINITE.search(o.stdout) else "bad JSON")
            # exit 1 for a result file not written: the solve's numbers are good
            if o.code == 1 and isinstance(obj, dict) and not obj.get("not_written"):
                numbers = [k for k in PHYSICAL_KEYS if obj.get(k) is not None]
                if numbers:
                    p.append("numbers from a failed solve: " + ", ".join(numbers))
        elif o.code == 0 and o.probe.stdout is None \
                and NON_FINITE.search(MODEL_NAMES.sub("", o.stdout)):
            p.append("silent nan/inf")
        bad = out_of_bounds(obj) if o.code == 0 else []
        if bad and not (isinstance(obj, dict) and obj.get("unphysical")) \
                and "UNPHYSICAL" not in o.stdout + o.stderr:
            p.append("silent bad result: " + ", ".join(bad[:3]))
    if o.code == 2:
        lines = [line for line in o.stderr.splitlines() if line.strip()]
        if len(lines) != 1 or "error" not in lines[0]:
            p.append(f"exit 2 with {len(lines)} stderr lines")
        elif o.probe.group == "files":
            names = {a.split("=")[0] for a in o.probe.argv if a.startswith("--")}
            # check names the row and column of a bad cell
            if not any(n in lines[0] for n in names | {"FILE", "DIR", "column"}):
                p.append("exit 2 line names no option")
        if o.stdout.strip():
            p.append("exit 2 with output on stdout")
    if o.code == 0:
        for f in o.probe.files:
            if not Path(f).is_file() or Path(f).stat().st_size == 0:
                p.append(f"file {f} missing")
    if o.probe.max_mb is not None and o.peak_mb > o.probe.max_mb:
        p.append(f"peak memory {o.peak_mb:.0f} MB > {o.probe.max_mb:g} MB")
    return o


# --------------------------------------------------------------------------- sandboxes

def snapshot(folder: Path) -> dict:
    """Every entry under ``folder`` (symbolic links not followed): a file as its size,
    modification time and content hash (files above 16 MB: size and time), a folder, a link
    with its target, or another kind (FIFO, socket) by its type."""
    out = {}
    for dirpath, dirnames, filenames in os.walk(folder):
        for name in dirnames + filenames:
            path = Path(dirpath, name)
            try:
                st = os.lstat(path)
                if stat.S_ISREG(st.st_mode):
                    digest = (hashlib.sha1(path.read_bytes()).hexdigest()
                              if st.st_size <= 16 * 2**20 else None)
                    entry = ("file", st.st_size, st.st_mtime_ns, digest)
                elif stat.S_ISLNK(st.st_mode):
                    entry = ("link", os.readlink(path))
                else:
                    entry = (stat.S_IFMT(st.st_mode),)
            except OSError:
                continue
            out[str(path.relative_to(folder))] = entry
    return out


def _sandbox_problems(probe: Probe, before: dict, after: dict) -> list[str]:
    """Files of the user (in the sandbox before the run) that the run removed or changed,
    besides the probe's ``may_change``; temporaries the run left."""
    def ours(rel):
        return any(fnmatchcase(rel, g) for g in probe.may_change)
    removed = sorted(r for r in before if r not in after and not ours(r))
    changed = sorted(r for r in before if r in after and after[r] != before[r] and not ours(r))
    left = sorted(r for r in after if r not in before and Path(r).name.startswith(".")
                  and (r.endswith(".tmp") or Path(r).name.startswith(".vesicle-tube-")))
    problems = []
    for what, names in (("user file removed", removed), ("user file changed", changed),
                        ("temporary left behind", left)):
        if names:
            more = f" (+{len(names) - 3})" if len(names) > 3 else ""
            problems.append(f"{what}: {', '.join(names[:3])}{more}")
    return problems


#: Files of "the user" in every sandbox: they must survive every probe.
CANARIES = {"user-notes.txt": "my notes\n", ".user-draft.tmp": "draft of the user\n"}


def run_probe(probe: Probe, timeout: float) -> Outcome:
    """Run and judge one probe; a file probe in its sandbox (made, filled by ``setup``,
    snapshot before and after, then removed)."""
    if probe.skip:
        return Outcome(probe, None, 0.0, float("nan"), "", "", [], skipped=True)
    if probe.sandbox is None:
        return judge(_run_measured(probe, timeout))
    box = probe.sandbox
    try:
        box.mkdir(parents=True)
        for name, text in CANARIES.items():
            (box / name).write_text(text)
        if probe.setup is not None:
            probe.setup(box)
    except Exception as exc:     # noqa: BLE001 - reported as the probe's problem
        shutil.rmtree(box, ignore_errors=True)
        return Outcome(probe, None, 0.0, float("nan"), "", "",
                       [f"setup failed: {type(exc).__name__}: {one_line(exc)}"])
    try:
        before = snapshot(box)
        # a scenario judges its own runs
        o = probe.run(probe, timeout) if probe.run else judge(_run_measured(probe, timeout))
        if probe.post is not None and o.code is not None:
            o.problems += probe.post(box, o)
        o.problems += _sandbox_problems(probe, before, snapshot(box))
    finally:
        shutil.rmtree(box, ignore_errors=True)
    return o


def _pipe_probe(argv: list, timeout: float) -> Outcome:
    """``vesicle-tube ... | head -1``: the reader closes the pipe after one line."""
    t0 = time.perf_counter()
    proc = subprocess.Popen([exe()] + argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)
    problems = []
    ready, _, _ = select.select([proc.stdout], [], [], timeout)
    if ready:
        proc.stdout.readline()
    proc.stdout.close()
    try:
        err = proc.stderr.read().decode()
        code = proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        code, err = None, ""
        problems.append("hang")
    if "Traceback" in err or "BrokenPipe" in err:
        problems.append("traceback")
    return Outcome(Probe(argv + ["| head -1"], (0, 141)), code, time.perf_counter() - t0, 0.0,
                   "", err, problems)


# --------------------------------------------------------------------------- the report

#: Kinds of violation, by the start of the problem's text (a scenario step's "[step] " first).
KINDS = (("hang", "hang"), ("traceback", "traceback"), ("exit 2 with", "exit-2 message"),
         ("exit 2 line", "exit-2 message"), ("exit ", "exit code"),
         ("silent bad", "silent bad result"), ("silent nan", "silent nan/inf"),
         ("bad JSON", "bad JSON"), ("numbers from", "numbers from a failed solve"),
         ("user file", "files not ours touched"), ("temporary", "temporary left behind"),
         ("peak memory", "memory"), ("file ", "output file missing"),
         ("setup", "setup failed"), ("duplicate", "duplicate work"), ("resume", "resume"))


def problem_kind(text: str) -> str:
    text = re.sub(r"^\[[^]]*\] ", "", text)
    return next((kind for start, kind in KINDS if text.startswith(start)),
                text.split(":")[0])


def command_of(argv: list) -> str:
    """The command (and subcommand) of a command line, e.g. ``map query``."""
    words = [a for a in argv[:2] if not a.startswith("-")]
    if words[:1] in (["map"], ["bem"]):
        return " ".join(words[:2])
    return words[0] if words else "(none)"


def show(argv: list, limit: int = 100) -> str:
    """A command line (or a message, as a list of one) for the report: temporary folders as
    $TMP, arguments longer than ``limit`` elided, control characters escaped."""
    tmp = re.escape(str(Path(tempfile.gettempdir())))
    out = []
    for a in argv:
        a = re.sub(tmp + r"(/tmp\w+)?", "$TMP", a) if a else "''"
        if len(a) > limit:
            a = f"{a[:40]}...<{len(a)} characters>"
        out.append(a.encode("unicode_escape").decode("ascii") if not a.isprintable() else a)
    return " ".join(out)


#: stderr lines that report progress, not the outcome
PROGRESS = re.compile(r"^(\[[^]]*\] )?(map build: \d|figures: |point \d+/\d+: )")


def first_line(stderr: str) -> str:
    """The first stderr line that says what happened: the first error line (with a
    traceback, its last line, the exception), else the first line that is not progress or
    "wrote FILE"."""
    lines = [x for x in stderr.splitlines() if x.strip()]
    if "Traceback" in stderr:
        return f"Traceback ... {lines[-1]}"
    errors = [x for x in lines if "error" in x.lower()]
    rest = [x for x in lines if not PROGRESS.match(x) and not x.startswith("wrote ")]
    return (errors or rest or [""])[0]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2, help="probes run at once (default 2)")
    ap.add_argument("--timeout", type=float, default=60.0, help="bound per probe [s]")
    ap.add_argument("--only", default="",
                    help="run the probes whose command line or name (a file probe's, e.g. "
                         "map-build-twice-at-once) contains this")
    ap.add_argument("--group", choices=("all", "base", "files"), default="all",
                    help="base: the probes of every command; files: the file probes "
                         "(tests/robustness/file_probes.py); all: both (default)")
    ap.add_argument("--report", default=None,
                    help="Markdown report to write (atomic; default docs/probe-campaign.md, "
                         "for --group files docs/probe-campaign-files.md)")
    a = ap.parse_args(argv)
    report = a.report or str(ROOT / "docs" / ("probe-campaign-files.md" if a.group == "files"
                                              else "probe-campaign.md"))
    sys.path.insert(0, str(ROOT))
    from lubrication.io import atomic_write

    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        todo = [p for p in probes(tmp) if a.group in ("all", p.group)
                and (a.only in " ".join(p.argv) or a.only in p.why)]
        print(f"{len(todo)} probes, {a.workers} at a time, bound {a.timeout:g} s each",
              file=sys.stderr)
        t0 = time.perf_counter()
        done = []
        with ThreadPoolExecutor(a.workers) as pool:
            for k, o in enumerate(pool.map(lambda p: run_probe(p, a.timeout), todo)):
                done.append(o)
                flag = ("skipped: " + o.probe.skip if o.skipped
                        else "; ".join(o.problems) or "ok")
                print(f"[{k + 1}/{len(todo)}] exit {o.code} {o.seconds:5.1f} s "
                      f"{o.peak_mb:6.0f} MB  {show(o.probe.argv)[:90]}  {flag[:200]}",
                      file=sys.stderr, flush=True)
        if not a.only and a.group != "files":
            done += [_pipe_probe(["estimate"], a.timeout),
                     _pipe_probe(["geometry", "--nu", "0.6", "--lam", "1.9", "--json"], a.timeout),
                     _pipe_probe(["viscosity", "--diameter-um", "6", "--hematocrit", "0.45"],
                                 a.timeout)]
        wall = time.perf_counter() - t0
    skipped = [o for o in done if o.skipped]
    done = [o for o in done if not o.skipped]
    bad = [o for o in done if o.problems]
    counts = {
        "probes": len(done),
        "tracebacks": sum("traceback" in o.problems for o in done),
        "silent NaN/inf": sum("silent nan/inf" in o.problems for o in done),
        "numbers from failed solves": sum(any(x.startswith("numbers") for x in o.problems)
                                          for o in done),
        "hangs (> bound)": sum("hang" in o.problems for o in done),
        "contract violations (any problem)": len(bad),
        "skipped (cannot run here)": len(skipped),
    }
    kinds = Counter(k for o in bad for k in {problem_kind(x) for x in o.problems})
    measured = [o for o in done if o.peak_mb == o.peak_mb]
    worst = max(measured, key=lambda o: o.peak_mb) if measured else None
    by_code = {c: sum(o.code == c for o in done) for c in sorted({o.code for o in done},
                                                                 key=lambda c: (c is None, c))}
    lines = ["# Probe campaign of the command line", "",
             "Written by `python tests/robustness/probe_campaign.py"
             + (f" --group {a.group}" if a.group != "all" else "") + "` (the contract is in "
             "`correlations/cli/contract.py`). Each probe is one process, bounded at "
             f"{a.timeout:g} s; {a.workers} ran at a time on this machine ({os.cpu_count()} "
             f"cores); the campaign took {wall:.0f} s.", "", "| count | value |", "|---|---|"]
    lines += [f"| {k} | {v} |" for k, v in counts.items()]
    lines += [f"| probes with a violation of kind: {k} | {n} |" for k, n in kinds.most_common()]
    lines += [f"| exit {c} | {n} |" for c, n in by_code.items()]
    if worst is not None:
        lines.append(f"| worst peak memory | {worst.peak_mb:.0f} MB (`{show(worst.probe.argv)}`) |")
    if bad:
        lines += ["", "## Violations by command", ""]
        for cmd in sorted({command_of(o.probe.argv) for o in bad}):
            lines += [f"### {cmd}", "",
                      "| probe | command line | exit | first stderr line | problems |",
                      "|---|---|---|---|---|"]
            for o in bad:
                if command_of(o.probe.argv) == cmd:
                    first = first_line(o.stderr)
                    cells = (show(o.probe.argv), show([first], 300) if first else "",
                             "; ".join(o.problems))
                    cmd_, first, problems = (c.replace("|", "\\|") for c in cells)
                    lines.append(f"| {o.probe.why if o.probe.group == 'files' else ''} | "
                                 f"`{cmd_}` | {o.code} | {first} | {problems} |")
            lines.append("")
    if skipped:
        lines += ["", "## Skipped", ""] + [f"- `{show(o.probe.argv)}`: {o.probe.skip}"
                                           for o in skipped]
    lines += ["", "## Every probe", "",
              "| # | probe | command line | exit | allowed | time [s] | peak [MB] | problems |",
              "|---|---|---|---|---|---|---|---|"]
    for k, o in enumerate(done, 1):
        cmd = show(o.probe.argv).replace("|", "\\|")
        name = o.probe.why if o.probe.group == "files" else ""
        lines.append(f"| {k} | {name} | `{cmd}` | {o.code} | "
                     f"{','.join(map(str, o.probe.allowed))} | "
                     f"{o.seconds:.1f} | {o.peak_mb:.0f} | "
                     f"{'; '.join(o.problems).replace('|', '/') or 'ok'} |")
    atomic_write(report, lambda f: f.write("\n".join(lines) + "\n"))
    for k, v in counts.items():
        print(f"{k:38s} {v}")
    for k, n in kinds.most_common():
        print(f"  {k:36s} {n}")
    if worst is not None:
        print(f"{'worst peak memory':38s} {worst.peak_mb:.0f} MB ({show(worst.probe.argv)})")
    print(f"report written to {report}")
    return 0 if not bad else 1


if __name__ == "__main__":
    import probe_campaign  # lazy: run as the module file_probes imports, not a second copy
    sys.exit(probe_campaign.main())
