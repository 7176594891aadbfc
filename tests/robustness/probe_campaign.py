"""Probe campaign: every command of ``vesicle-tube`` fed unusual and invalid inputs.

Runs each probe as a separate process (the installed console script) with a wall-time bound
(60 s by default), and checks the command-line contract of :mod:`correlations.cli.contract`:

* exit 0: finite numbers only (strict JSON with ``--json``; no ``nan``/``inf`` in a table);
* exit 2: exactly one line on stderr, naming an option or parameter, nothing on stdout;
* exit 1: a solver message; a failed solve reports no physical numbers (JSON probes);
* never a Python traceback, never a hang (the bound), peak memory measured per probe.

Usage::

    python tests/robustness/probe_campaign.py [--workers 2] [--timeout 60] [--only TEXT]
        [--report docs/probe-campaign.md]

Prints a summary table and writes the per-probe report (atomically). Not a test: it takes
several minutes; the fuzzing suite (tests/robustness/test_fuzz_cli.py) keeps the contract in
the default test suite.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# Keys that are physical results of a solve: null when the solve failed.
PHYSICAL_KEYS = ("V_over_U", "dp_plus_R0", "dp_plus_R", "film_min", "film", "ell", "tension_max",
                 "tension_front", "drag_K", "length", "wall_shear_max")

BAD_FLOATS = ("nan", "inf", "-inf", "1e308", "-1", "0", "1e-320", "abc", "")
NON_FINITE = re.compile(r"(?<![\w-])(-?inf(inity)?|nan)(?![\w-])", re.IGNORECASE)
# Ca_B = inf names the high-Ca lubrication model: a model, not a computed number
MODEL_NAMES = re.compile(r"Ca_B = inf|inf \(high-Ca model\)")


@dataclass
class Probe:
    """One command line and the exit codes the contract allows for it."""

    argv: list
    allowed: tuple = (0, 1, 2)
    why: str = ""
    files: list = field(default_factory=list)    # paths the probe may write (must be complete)


def _exe() -> str:
    exe = shutil.which("vesicle-tube") or str(Path(sys.executable).with_name("vesicle-tube"))
    return exe


def _value_probes(base: list, option: str, values=BAD_FLOATS, valid_codes=None) -> list:
    """``base`` with ``option`` set to each bad value; nan/inf/strings must give exit 2."""
    out = []
    for v in values:
        codes = (2,) if v in ("nan", "inf", "-inf", "abc", "") else (valid_codes or (0, 1, 2))
        out.append(Probe(base + [option, v], codes, f"{option} {v!r}"))
    return out


def probes(tmp: Path) -> list[Probe]:
    """The campaign: at least 200 command lines across every command."""
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
    return P


@dataclass
class Outcome:
    probe: Probe
    code: int | None
    seconds: float
    peak_mb: float
    stdout: str
    stderr: str
    problems: list


def _run_measured(probe: Probe, timeout: float) -> Outcome:
    """Run one probe in its own process group, killed at the bound; the peak resident memory
    comes from GNU ``/usr/bin/time`` (NaN where it is missing)."""
    fd, log = tempfile.mkstemp(suffix=".time")
    os.close(fd)
    timer = ["/usr/bin/time", "-f", "%M", "-o", log] if Path("/usr/bin/time").exists() else []
    t0 = time.perf_counter()
    proc = subprocess.Popen(timer + [_exe()] + probe.argv, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
        code = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        code = None
    seconds = time.perf_counter() - t0
    try:
        peak = float(Path(log).read_text().strip().splitlines()[-1]) / 1024.0
    except (ValueError, IndexError):
        peak = float("nan")
    os.unlink(log)
    # /usr/bin/time reports "Command exited with non-zero status N" on stderr
    err = "\n".join(line for line in err.splitlines()
                    if not line.startswith("Command exited with non-zero status")
                    and not line.startswith("Command terminated by signal"))
    return Outcome(probe, code, seconds, peak, out, err, [])


def _judge(o: Outcome) -> Outcome:
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
    is_json = "--json" in o.probe.argv
    if o.code in (0, 1) and "--help" not in o.probe.argv:
        if is_json:
            try:
                obj = json.loads(o.stdout, parse_constant=lambda c: (_ for _ in ()).throw(
                    ValueError(c)))
            except ValueError:
                p.append("silent nan/inf" if NON_FINITE.search(o.stdout) else "bad JSON")
                obj = None
            if o.code == 1 and isinstance(obj, dict):
                numbers = [k for k in PHYSICAL_KEYS if obj.get(k) is not None]
                if numbers:
                    p.append("numbers from a failed solve: " + ", ".join(numbers))
        elif o.code == 0 and NON_FINITE.search(MODEL_NAMES.sub("", o.stdout)):
            p.append("silent nan/inf")
    if o.code == 2:
        lines = [line for line in o.stderr.splitlines() if line.strip()]
        if len(lines) != 1 or "error" not in lines[0]:
            p.append(f"exit 2 with {len(lines)} stderr lines")
        if o.stdout.strip():
            p.append("exit 2 with output on stdout")
    if o.code == 0:
        for f in o.probe.files:
            if not Path(f).is_file() or Path(f).stat().st_size == 0:
                p.append(f"file {f} missing")
    return o


def _pipe_probe(argv: list, timeout: float) -> Outcome:
    """``vesicle-tube ... | head -1``: the reader closes the pipe after one line."""
    t0 = time.perf_counter()
    proc = subprocess.Popen([_exe()] + argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--workers", type=int, default=2, help="probes run at once (default 2)")
    ap.add_argument("--timeout", type=float, default=60.0, help="bound per probe [s]")
    ap.add_argument("--only", default="", help="run the probes whose command line contains this")
    ap.add_argument("--report", default=str(ROOT / "docs" / "probe-campaign.md"),
                    help="Markdown report to write (atomic)")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from lubrication.io import atomic_write

    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        todo = [p for p in probes(tmp) if a.only in " ".join(p.argv)]
        print(f"{len(todo)} probes, {a.workers} at a time, bound {a.timeout:g} s each",
              file=sys.stderr)
        t0 = time.perf_counter()
        done = []
        with ThreadPoolExecutor(a.workers) as pool:
            for k, o in enumerate(pool.map(lambda p: _judge(_run_measured(p, a.timeout)), todo)):
                done.append(o)
                flag = "; ".join(o.problems) or "ok"
                print(f"[{k + 1}/{len(todo)}] exit {o.code} {o.seconds:5.1f} s "
                      f"{o.peak_mb:6.0f} MB  {' '.join(o.probe.argv)[:90]}  {flag}",
                      file=sys.stderr, flush=True)
        if not a.only:
            done += [_pipe_probe(["estimate"], a.timeout),
                     _pipe_probe(["geometry", "--nu", "0.6", "--lam", "1.9", "--json"], a.timeout),
                     _pipe_probe(["viscosity", "--diameter-um", "6", "--hematocrit", "0.45"],
                                 a.timeout)]
        wall = time.perf_counter() - t0
    counts = {
        "probes": len(done),
        "tracebacks": sum("traceback" in o.problems for o in done),
        "silent NaN/inf": sum("silent nan/inf" in o.problems for o in done),
        "numbers from failed solves": sum(any(x.startswith("numbers") for x in o.problems)
                                          for o in done),
        "hangs (> bound)": sum("hang" in o.problems for o in done),
        "contract violations (any problem)": sum(bool(o.problems) for o in done),
    }
    worst = max(done, key=lambda o: o.peak_mb if o.peak_mb == o.peak_mb else 0)
    by_code = {c: sum(o.code == c for o in done) for c in sorted({o.code for o in done},
                                                                 key=lambda c: (c is None, c))}
    lines = ["# Probe campaign of the command line", "",
             "Written by `python tests/robustness/probe_campaign.py` (the contract is in "
             "`correlations/cli/contract.py`). Each probe is one process, bounded at "
             f"{a.timeout:g} s; {a.workers} ran at a time on this machine ({os.cpu_count()} "
             f"cores); the campaign took {wall:.0f} s.", "", "| count | value |", "|---|---|"]
    lines += [f"| {k} | {v} |" for k, v in counts.items()]
    lines += [f"| exit {c} | {n} |" for c, n in by_code.items()]
    lines += [f"| worst peak memory | {worst.peak_mb:.0f} MB (`{' '.join(worst.probe.argv)}`) |",
              "", "| # | command line | exit | allowed | time [s] | peak [MB] | problems |",
              "|---|---|---|---|---|---|---|"]
    for k, o in enumerate(done, 1):
        cmd = " ".join(x if x else "''" for x in o.probe.argv).replace(str(Path(tempfile.gettempdir())), "$TMP")
        cmd = re.sub(r"\$TMP/tmp\w+", "$TMP", cmd).replace("|", "\\|")
        lines.append(f"| {k} | `{cmd}` | {o.code} | {','.join(map(str, o.probe.allowed))} | "
                     f"{o.seconds:.1f} | {o.peak_mb:.0f} | {'; '.join(o.problems) or 'ok'} |")
    atomic_write(a.report, lambda f: f.write("\n".join(lines) + "\n"))
    for k, v in counts.items():
        print(f"{k:38s} {v}")
    print(f"{'worst peak memory':38s} {worst.peak_mb:.0f} MB ({' '.join(worst.probe.argv)})")
    print(f"report written to {a.report}")
    return 0 if counts["contract violations (any problem)"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
