"""Throughput and peak memory of ``vesicle-tube check`` on large CSV files of rows that need no
solver; targets: at least 20 000 rows/s and at most 500 MB peak memory for 10^6 rows, plain,
``--json`` and ``--report``.

Rows: vesicle rows at 16 cases inside the shipped solution map (ν 0.7 and 0.9, Ca_B 50, eight
λ/λc from 0.3 to 0.99), each row with the map's V/U, Δp⁺R0/(ηU), ℓ, h/R moved by a random
fraction (±0.4) of the map's error bar, that error bar as its ``*_err`` columns, and the map's
shape class, so that every check of a vesicle row runs (bounds, map references, Chen et al.'s
film scaling near λc, the shape's volume and area, the shape class, the series trends); one
row in 1000 has a negative Δp⁺ and fails. The references come from the map's interpolation,
no solver; the 16 cases are few enough for the map query cache, as in a file of repeated runs
(a file of distinct points costs one map query per row, about 3.5 ms, whatever the check).

Each run is its own process (the installed console script) with its stdout written to a file;
time is wall time including the interpreter's start, peak memory is the process's maximum
resident set size (``os.wait4``); CPU time (user + system) is given beside it, since wall time
depends on what else runs on the machine. A run is stopped (and marked so) past ``--timeout``
seconds or ``--max-rss-mb`` of resident memory. Not a test: timings depend on the machine. Run
with
``python tests/benchmarks/check_throughput.py [--rows 100000 1000000] [--modes plain json
report]``.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

TARGET_ROWS_PER_S = 20_000
TARGET_PEAK_MB = 500.0
QUANTITIES = ("V_over_U", "dp_plus_R0", "ell", "film_min")
COLUMNS = ("name", "nu", "lam", "ca_b", *QUANTITIES, *(f"{q}_err" for q in QUANTITIES),
           "shape_class")
#: The cases of the rows: (nu, lam/lam_c) at Ca_B 50 (the map's default, one query per case).
CASES = [(nu, ratio) for nu in (0.7, 0.9)
         for ratio in (0.3, 0.5, 0.7, 0.8, 0.9, 0.95, 0.98, 0.99)]
CA_B = 50.0
#: One row in this many is corrupted (negative dp+: a failure).
FAIL_EVERY = 1000
MODES = {"plain": [], "json": ["--json"], "report": ["--report", "{folder}/report.md"]}


def _exe() -> str:
    return shutil.which("vesicle-tube") or str(Path(sys.executable).with_name("vesicle-tube"))


def case_values() -> list[dict]:
    """The map's values and error bars at :data:`CASES`."""
    from correlations.solution_map import load_map, query_map
    from lubrication.geometry import critical_confinement
    m, out = load_map(), []
    for nu, ratio in CASES:
        q = query_map(nu, ratio, CA_B, m).quantities
        missing = [k for k in QUANTITIES if q[k].value is None or q[k].error is None]
        if missing or q["shape_class"].value is None:
            raise SystemExit(f"the shipped map has no {missing or 'shape class'} at nu={nu}, "
                             f"lam/lam_c={ratio}")
        out.append({"nu": nu, "lam": ratio * float(critical_confinement(nu)), "ca_b": CA_B,
                    "shape_class": q["shape_class"].value,
                    **{k: (q[k].value, q[k].error) for k in QUANTITIES}})
    return out


def write_rows(path: Path, n: int, cases: list[dict], seed: int = 1) -> None:
    """``n`` rows (module docstring) as CSV at ``path``."""
    rng = random.Random(seed)
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        for i in range(1, n + 1):
            c = cases[i % len(cases)]
            values = {k: c[k][0] + rng.uniform(-0.4, 0.4) * c[k][1] for k in QUANTITIES}
            if i % FAIL_EVERY == 0:
                values["dp_plus_R0"] = -values["dp_plus_R0"]
            writer.writerow([f"r{i}", c["nu"], f"{c['lam']:.12g}", c["ca_b"],
                             *(f"{values[k]:.10g}" for k in QUANTITIES),
                             *(f"{c[k][1]:.3g}" for k in QUANTITIES), c["shape_class"]])


def _rss_mb(pid: int) -> float:
    """Resident memory of process ``pid`` now [MB] (Linux; 0 elsewhere)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def run(argv: list[str], stdout: Path, timeout: float, max_rss_mb: float) -> dict:
    """Run ``argv`` with its stdout to ``stdout``: exit code, wall time [s], peak RSS [MB],
    stderr's last line, and why it was stopped ("" when it ended by itself)."""
    stopped = []
    with stdout.open("wb") as out:
        t0 = time.perf_counter()
        proc = subprocess.Popen(argv, stdout=out, stderr=subprocess.PIPE)
        err = []
        reader = threading.Thread(target=lambda: err.append(proc.stderr.read()), daemon=True)
        reader.start()

        def watch():
            while proc.returncode is None:
                elapsed, rss = time.perf_counter() - t0, _rss_mb(proc.pid)
                if elapsed > timeout or rss > max_rss_mb:
                    stopped.append(f"stopped at {elapsed:.0f} s, {rss:.0f} MB")
                    proc.send_signal(signal.SIGKILL)
                    return
                time.sleep(0.2)
        watchdog = threading.Thread(target=watch, daemon=True)
        watchdog.start()
        _, status, usage = os.wait4(proc.pid, 0)
        seconds = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        reader.join(timeout=5)
    scale = 1024 if sys.platform != "darwin" else 2**20       # ru_maxrss: kB on Linux
    lines = b"".join(err).decode(errors="replace").strip().splitlines()
    return {"code": proc.returncode, "seconds": seconds, "cpu": usage.ru_utime + usage.ru_stime,
            "peak_mb": usage.ru_maxrss / scale,
            "stderr": lines[-1] if lines else "", "stopped": stopped[0] if stopped else ""}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rows", type=int, nargs="+", default=[100_000, 1_000_000])
    p.add_argument("--modes", nargs="+", choices=MODES, default=list(MODES))
    p.add_argument("--timeout", type=float, default=600.0, help="stop a run after [s]")
    p.add_argument("--max-rss-mb", type=float, default=4000.0,
                   help="stop a run above this resident memory [MB]")
    p.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = p.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="check-throughput-"))
    cases = case_values()
    load = os.getloadavg()
    results = []
    try:
        for n in args.rows:
            path = folder / f"rows_{n}.csv"
            t0 = time.perf_counter()
            write_rows(path, n, cases)
            print(f"{n} rows written to {path} ({path.stat().st_size / 2**20:.1f} MB) in "
                  f"{time.perf_counter() - t0:.1f} s", flush=True)
            for mode in args.modes:
                extra = [a.format(folder=folder) for a in MODES[mode]]
                out = folder / f"out_{n}_{mode}.txt"
                r = run([_exe(), "check", str(path), *extra], out, args.timeout,
                        args.max_rss_mb)
                r.update(rows=n, mode=mode, out_mb=out.stat().st_size / 2**20)
                if mode == "json" and not r["stopped"] and r["out_mb"] < 200:
                    try:
                        json.loads(out.read_text(encoding="utf-8"))
                    except ValueError as exc:
                        r["stopped"] = f"stdout is not one JSON object: {exc}"
                out.unlink()
                results.append(r)
                print(f"  {mode}: exit {r['code']}, {r['seconds']:.1f} s, "
                      f"{r['peak_mb']:.0f} MB {r['stopped']}", flush=True)
    finally:
        if args.keep:
            print(f"kept {folder}")
        else:
            shutil.rmtree(folder, ignore_errors=True)
    print(f"\nvesicle-tube check, rows needing no solver (targets: >= {TARGET_ROWS_PER_S} rows/s, "
          f"<= {TARGET_PEAK_MB:g} MB); load average (1 min) {load[0]:.1f} before, "
          f"{os.getloadavg()[0]:.1f} after, on {os.cpu_count()} cores")
    head = ("rows", "mode", "exit", "time [s]", "rows/s", "CPU [s]", "rows/CPU s",
            "peak RSS [MB]", "stdout [MB]", "")
    table = [head] + [(str(r["rows"]), r["mode"], str(r["code"]), f"{r['seconds']:.1f}",
                       "-" if r["stopped"] else f"{r['rows'] / r['seconds']:.0f}",
                       f"{r['cpu']:.1f}", "-" if r["stopped"] else f"{r['rows'] / r['cpu']:.0f}",
                       f"{r['peak_mb']:.0f}", f"{r['out_mb']:.1f}",
                       r["stopped"] or r["stderr"][:90]) for r in results]
    widths = [max(len(line[i]) for line in table) for i in range(len(head))]
    for line in table:
        print("  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip())
    ok = all(not r["stopped"] and r["rows"] / r["seconds"] >= TARGET_ROWS_PER_S
             and r["peak_mb"] <= TARGET_PEAK_MB for r in results if r["rows"] >= 100_000)
    print("targets met" if ok else "targets NOT met")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
