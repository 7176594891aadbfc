"""Benchmark of ``vesicle-tube check``: a 1000-row file of vesicle rows inside the solution map
(no BEM reference needed), target <= 5 s.

Rows: random (nu, lam/lam_c, Ca_B) inside the map (nu 0.6-0.98, lam/lam_c 0.2-0.9999, Ca_B 15,
50, 100 or 300), with the map's own V/U, dp+, ell, h/R (and their error bars as *_err) and
shape class, so that every check runs (bounds, map references, relations, shape class). Timed: ``check_results`` on the
CSV file in this process (the map's query cache cleared before each run; the map file itself
is read once, as in one command), and the command line ``vesicle-tube check FILE --json``
end to end (process start included). The map is the shipped one, or the one packed from the
committed build folder when none is shipped. Not a test: timings depend on the machine. Run
with ``python tests/benchmarks/bench_check.py``; the measurements, with the machine they were
taken on, go to ``docs/data/bench_check.json`` (``tests/benchmarks/bench_store.py``), beside
the ``throughput`` entry of ``tests/benchmarks/check_throughput.py``, which is kept.
"""

from __future__ import annotations

import csv
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TARGET_S = 5.0
ROWS = 1000
QUANTITIES = ("V_over_U", "dp_plus_R0", "ell", "film_min")
COLUMNS = ("nu", "lam", "ca_b", *QUANTITIES, *(f"{q}_err" for q in QUANTITIES), "shape_class")


def solution_map():
    from correlations.solution_map import DEFAULT_MAP, load_map, pack_map
    if DEFAULT_MAP.exists():
        return load_map()
    build = Path(__file__).resolve().parents[2] / "correlations" / "data" / "solution_map_build"
    return load_map(pack_map(build, Path(tempfile.mkdtemp(prefix="bench-check-")) / "map.json"))


def make_rows(m, n: int = ROWS, seed: int = 1) -> list[dict]:
    """``n`` rows with the map's values at random points inside it, each with the map's error
    bar as its stated uncertainty (interpolated values are only that accurate)."""
    from correlations.solution_map import query_map
    from lubrication.geometry import critical_confinement
    rng, rows = random.Random(seed), []
    while len(rows) < n:
        nu, ratio = rng.uniform(0.6, 0.98), 1.0 - 10 ** rng.uniform(-4, -0.1)
        ca_b = rng.choice((15.0, 50.0, 100.0, 300.0))
        q = query_map(nu, ratio, ca_b, m).quantities
        if any(q[k].value is None or q[k].error is None for k in (*QUANTITIES, "shape_class")
               if k != "shape_class") or q["shape_class"].value is None:
            continue
        rows.append({"nu": nu, "lam": ratio * float(critical_confinement(nu)), "ca_b": ca_b,
                     "shape_class": q["shape_class"].value,
                     **{k: q[k].value for k in QUANTITIES},
                     **{f"{k}_err": q[k].error for k in QUANTITIES}})
    return rows


def _relative(path) -> str:
    """``path`` relative to the repository if it lies inside it (stored files name no home)."""
    root = Path(__file__).resolve().parents[2]
    try:
        return str(Path(path).resolve().relative_to(root))
    except ValueError:
        return str(path)


def main() -> int:
    from bench_store import DATA, machine, store
    from correlations import check, registry
    load_before = os.getloadavg()
    m = solution_map()
    folder = Path(tempfile.mkdtemp(prefix="bench-check-"))
    path = folder / "rows.csv"
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(make_rows(m))
    times = []
    for _ in range(5):
        registry.map_query.cache_clear()
        t0 = time.perf_counter()
        report = check.check_results(path, solution_map=m)
        times.append(time.perf_counter() - t0)
    checks = sum(len(r.checks) for r in report.rows)
    wall = []
    for _ in range(3):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "correlations.cli", "check", str(path), "--json",
                        "--map", m.source], capture_output=True, check=False)
        wall.append(time.perf_counter() - t0)
    ok = statistics.median(wall) <= TARGET_S
    print(f"check of {ROWS} rows ({checks} checks; verdicts {report.counts}; map {m.source}):")
    print(f"  check_results in this process: min {min(times):.2f} s, median "
          f"{statistics.median(times):.2f} s over {len(times)} runs")
    print(f"  vesicle-tube check FILE --json, end to end: min {min(wall):.2f} s, median "
          f"{statistics.median(wall):.2f} s over {len(wall)} runs (target <= {TARGET_S:g} s): "
          f"{'ok' if ok else 'SLOW'}")
    previous = DATA / "bench_check.json"      # check_throughput.py's entry is kept
    kept = json.loads(previous.read_text()).get("throughput") if previous.exists() else None
    store("check", {
        **({"throughput": kept} if kept else {}),
        "parameters": {"rows": ROWS, "seed": 1, "map": _relative(m.source),
                       "in_process_runs": len(times), "end_to_end_runs": len(wall)},
        "checks": checks, "verdicts": report.counts,
        "in_process_s": {"runs": times, "min": min(times), "median": statistics.median(times)},
        "end_to_end_s": {"runs": wall, "min": min(wall), "median": statistics.median(wall),
                         "target": TARGET_S},
        "machine": machine(load_before)})
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
