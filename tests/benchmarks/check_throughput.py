"""Throughput and peak memory of ``vesicle-tube check`` on large CSV files of rows that need no
solver; targets: at least 20 000 rows/s and at most 500 MB peak memory for 10^6 rows, plain,
``--json`` and ``--report``.

Rows (two kinds of file, both needing no solver):

* repeated cases (default): vesicle rows at 16 cases inside the shipped solution map (ν 0.7
  and 0.9, Ca_B 50, eight λ/λc from 0.3 to 0.99), as in a file of repeated runs;
* ``--distinct``: every row at its own point, drawn with a fixed seed: 80 % vesicle rows
  inside the map's box (ν 0.6-0.98, λ/λc = 1 − 10^U(−4, −0.1), Ca_B log-uniform in 5-10⁴,
  above the map's largest Ca_B by its clamp), each needing its own map query, and 20 %
  closed-form rows outside the map (ν 0.985-0.999: near λc the near-critical laws, at
  λ ≤ 0.5 and Ca_B ≥ 50 the small-sphere laws).

Each vesicle row inside the map has the map's V/U, Δp⁺R0/(ηU), ℓ, h/R moved by a random
fraction (±0.4) of the map's error bar, that error bar as its ``*_err`` columns, and the map's
shape class, so that every check of a vesicle row runs (bounds, map references, Chen et al.'s
film scaling near λc, the shape's volume and area, the shape class, the series trends); a
closed-form row has the law's V/U and Δp⁺ moved likewise within the law's error. One row in
1000 has a negative Δp⁺ and fails.

Each run is its own process (the installed console script) with its stdout written to a file;
time is wall time including the interpreter's start, peak memory is the process's maximum
resident set size (``os.wait4``) and, beside it, the peak of the resident memory of the process
and its worker processes summed (sampled; shared pages counted in each); CPU time (user +
system, the workers' included) is given beside the time, since wall time depends on what else
runs on the machine. A run is stopped (and marked so) past ``--timeout``
seconds or ``--max-rss-mb`` of resident memory. Not a test: timings depend on the machine. Run
with
``python tests/benchmarks/check_throughput.py [--rows 100000 1000000] [--modes plain json
report] [--distinct]``. The table is printed and stored under ``throughput`` in
``docs/data/bench_check.json`` (one entry per kind of file, with the machine and its load),
beside what ``tests/benchmarks/bench_check.py`` stores there.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import csv
import json
import math
import multiprocessing
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
#: Distinct rows: the share of closed-form rows (outside the map) and the ranges drawn.
CLOSED_FORM_SHARE = 0.2
NU_MAP, NU_CLOSED = (0.6, 0.98), (0.985, 0.999)
CA_B_RANGE = (5.0, 1e4)
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


def _map_rows(rng, n: int, m) -> list[list]:
    """Up to ``n`` vesicle rows at random points inside map ``m`` (points where the map has
    no value or no shape class are left out)."""
    from correlations.solution_map import query_map_many
    from lubrication.geometry import critical_confinement
    nu = [rng.uniform(*NU_MAP) for _ in range(n)]
    ratio = [1.0 - 10 ** rng.uniform(-4.0, -0.1) for _ in range(n)]
    ca_b = [10 ** rng.uniform(*map(math.log10, CA_B_RANGE)) for _ in range(n)]
    lam = (critical_confinement(nu) * ratio).tolist()
    rows = []
    for q, l in zip(query_map_many(nu, ratio, ca_b, m, QUANTITIES), lam):
        v = q.quantities
        if any(v[k].value is None or v[k].error is None for k in QUANTITIES) \
                or v["shape_class"].value is None:
            continue
        values = {k: v[k].value + rng.uniform(-0.4, 0.4) * v[k].error for k in QUANTITIES}
        rows.append([f"{q.nu:.10g}", f"{l:.12g}", f"{q.ca_b:.6g}",
                     *(f"{values[k]:.10g}" for k in QUANTITIES),
                     *(f"{v[k].error:.3g}" for k in QUANTITIES), v["shape_class"].value])
    return rows


def _closed_form_row(rng) -> list:
    """A vesicle row outside the map (ν above its range) with the near-critical or the
    small-sphere law's V/U and Δp⁺."""
    from correlations.check import near_critical_reference, small_object_reference
    from lubrication.geometry import critical_confinement
    nu = rng.uniform(*NU_CLOSED)
    lam_c = float(critical_confinement(nu))
    if rng.random() < 0.5:
        lam, ca_b = lam_c * (1.0 - 10 ** rng.uniform(-4.0, -1.05)), 10 ** rng.uniform(0.7, 4)
        refs = [near_critical_reference(nu, lam, k) for k in QUANTITIES[:2]]
    else:
        lam, ca_b = rng.uniform(0.1, 0.5), 10 ** rng.uniform(1.7, 4)
        refs = [small_object_reference("vesicle", lam, k, nu, None, ca_b)
                for k in QUANTITIES[:2]]
    values = [r.value + rng.uniform(-0.4, 0.4) * r.error for r in refs]
    return [f"{nu:.10g}", f"{lam:.12g}", f"{ca_b:.6g}", *(f"{v:.10g}" for v in values), "", "",
            *(f"{r.error:.3g}" for r in refs), "", "", ""]


def write_distinct_rows(path: Path, n: int, seed: int = 1) -> None:
    """``n`` rows at distinct points (module docstring) as CSV at ``path``."""
    from correlations.solution_map import load_map
    rng, m, i = random.Random(seed), load_map(), 0
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(COLUMNS)
        while i < n:
            closed = sum(rng.random() < CLOSED_FORM_SHARE for _ in range(min(n - i, 20_000)))
            rows = _map_rows(rng, min(n - i, 20_000) - closed, m)
            rows += [_closed_form_row(rng) for _ in range(closed)]
            rng.shuffle(rows)
            for row in rows[:n - i]:
                i += 1
                if i % FAIL_EVERY == 0:
                    row[4] = f"{-float(row[4]):.10g}"
                writer.writerow([f"r{i}", *row])


def write(path: Path, n: int, distinct: bool) -> None:
    """``n`` rows of either kind (module docstring) as CSV at ``path``."""
    if distinct:
        write_distinct_rows(path, n)
    else:
        write_rows(path, n, case_values())


def _rss_mb(pid: int) -> float:
    """Resident memory of process ``pid`` now [MB] (Linux; 0 elsewhere)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def _tree_rss_mb(pid: int) -> float:
    """Resident memory of process ``pid`` and its child processes (the check's workers) now,
    summed [MB] (Linux; 0 elsewhere). Pages the workers share with their parent (forked) are
    counted in each: an upper bound."""
    try:
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except OSError:
        children = []
    return _rss_mb(pid) + sum(_tree_rss_mb(int(c)) for c in children)


def run(argv: list[str], stdout: Path, timeout: float, max_rss_mb: float) -> dict:
    """Run ``argv`` with its stdout to ``stdout``: exit code, wall time [s], CPU time of the
    process and its workers [s], peak RSS of the process [MB], peak of the summed RSS of the
    process and its workers (sampled every 0.1 s) [MB], stderr's last line, and why it was
    stopped ("" when it ended by itself)."""
    stopped, tree = [], [0.0]
    with stdout.open("wb") as out:
        t0 = time.perf_counter()
        proc = subprocess.Popen(argv, stdout=out, stderr=subprocess.PIPE)
        err = []
        reader = threading.Thread(target=lambda: err.append(proc.stderr.read()), daemon=True)
        reader.start()

        def watch():
            while proc.returncode is None:
                elapsed, rss = time.perf_counter() - t0, _tree_rss_mb(proc.pid)
                tree[0] = max(tree[0], rss)
                if elapsed > timeout or rss > max_rss_mb:
                    stopped.append(f"stopped at {elapsed:.0f} s, {rss:.0f} MB")
                    proc.send_signal(signal.SIGKILL)
                    return
                time.sleep(0.1)
        watchdog = threading.Thread(target=watch, daemon=True)
        watchdog.start()
        _, status, usage = os.wait4(proc.pid, 0)
        seconds = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        reader.join(timeout=5)
    scale = 1024 if sys.platform != "darwin" else 2**20       # ru_maxrss: kB on Linux
    lines = b"".join(err).decode(errors="replace").strip().splitlines()
    return {"code": proc.returncode, "seconds": seconds, "cpu": usage.ru_utime + usage.ru_stime,
            "peak_mb": usage.ru_maxrss / scale, "tree_peak_mb": tree[0],
            "stderr": lines[-1] if lines else "", "stopped": stopped[0] if stopped else ""}


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--rows", type=int, nargs="+", default=[100_000, 1_000_000])
    p.add_argument("--modes", nargs="+", choices=MODES, default=list(MODES))
    p.add_argument("--timeout", type=float, default=600.0, help="stop a run after [s]")
    p.add_argument("--max-rss-mb", type=float, default=4000.0,
                   help="stop a run above this resident memory [MB]")
    p.add_argument("--distinct", action="store_true",
                   help="rows at distinct points (a map query each) and closed-form rows, "
                        "instead of 16 repeated cases")
    p.add_argument("--keep", action="store_true", help="keep the temporary folder")
    args = p.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="check-throughput-"))
    load = os.getloadavg()
    results = []
    try:
        for n in args.rows:
            path = folder / f"rows_{n}.csv"
            t0 = time.perf_counter()
            # in a process of its own: this one stays small, and a command started from it
            # does not count its memory (a child shares its parent's pages until it execs)
            with concurrent.futures.ProcessPoolExecutor(
                    1, mp_context=multiprocessing.get_context("spawn")) as pool:
                pool.submit(write, path, n, args.distinct).result()
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
    kind = "distinct" if args.distinct else "repeated"
    print(f"\nvesicle-tube check, rows needing no solver, {kind} points (targets: >= "
          f"{TARGET_ROWS_PER_S} rows/s, <= {TARGET_PEAK_MB:g} MB); load average (1 min) "
          f"{load[0]:.1f} before, {os.getloadavg()[0]:.1f} after, on {os.cpu_count()} cores")
    head = ("rows", "mode", "exit", "time [s]", "rows/s", "CPU [s]", "rows/CPU s",
            "peak RSS [MB]", "with workers [MB]", "stdout [MB]", "")
    table = [head] + [(str(r["rows"]), r["mode"], str(r["code"]), f"{r['seconds']:.1f}",
                       "-" if r["stopped"] else f"{r['rows'] / r['seconds']:.0f}",
                       f"{r['cpu']:.1f}", "-" if r["stopped"] else f"{r['rows'] / r['cpu']:.0f}",
                       f"{r['peak_mb']:.0f}", f"{r['tree_peak_mb']:.0f}", f"{r['out_mb']:.1f}",
                       r["stopped"] or r["stderr"][:90]) for r in results]
    widths = [max(len(line[i]) for line in table) for i in range(len(head))]
    for line in table:
        print("  ".join(c.ljust(w) for c, w in zip(line, widths)).rstrip())
    ok = all(not r["stopped"] and r["rows"] / r["seconds"] >= TARGET_ROWS_PER_S
             and max(r["peak_mb"], r["tree_peak_mb"]) <= TARGET_PEAK_MB
             for r in results if r["rows"] >= 100_000)
    print("targets met" if ok else "targets NOT met")
    print(f"stored in {save(kind, results, ok, load)}")
    return 0 if ok else 1


def save(kind: str, results: list[dict], ok: bool, load_before) -> Path:
    """Store ``results`` under ``throughput[kind]`` of ``docs/data/bench_check.json`` (the
    other entries and what bench_check.py stores there are kept), with the machine."""
    from bench_store import DATA, machine

    from lubrication.io import provenance, write_json
    path = DATA / "bench_check.json"
    doc = json.loads(path.read_text()) if path.exists() else {}
    doc.setdefault("throughput", {})[kind] = {
        "runs": [{k: r[k] for k in ("rows", "mode", "code", "seconds", "cpu", "peak_mb",
                                    "tree_peak_mb", "out_mb", "stopped")}
                 | {"rows_per_s": None if r["stopped"] else r["rows"] / r["seconds"]}
                 for r in results],
        "targets": {"rows_per_s": TARGET_ROWS_PER_S, "peak_mb": TARGET_PEAK_MB, "met": ok},
        "machine": machine(load_before), "provenance": provenance()}
    return write_json(path, doc, indent=1, sort_keys=False)


if __name__ == "__main__":
    sys.exit(main())
