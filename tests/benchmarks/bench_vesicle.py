"""Benchmark of the steady BEM vesicle solver: prints a table (not a test; timings depend on the
machine and its load).

Run with ``python tests/benchmarks/bench_vesicle.py [--cases short,rbc,long,sweep] [--repeats 3]
[--json FILE]`` (``make benchmark`` runs every case three times). Each run is a fresh
interpreter (numba cache warm, compiled by a small solve before the clock starts), one at a
time, so that its peak resident memory (``ru_maxrss``) is its own; ``threads`` records numba's
thread count, which also bounds the concurrent Jacobian evaluations of the solver. The table
gives the minimum and median wall time of the runs, the number of boundary-integral solves
(BEM evaluations, continuation rungs included; the same in every run) beside the 10^4-10^5
semi-implicit time steps of Chen et al. 2020 (one BIE solve each), and the solution with its
error estimate.
Each case run is stored under ``cases/<case>`` of ``docs/data/bench_vesicle.json`` with its
parameters, runs and the machine (``tests/benchmarks/bench_store.py``); cases run separately
accumulate there, a new run of a case replaces only that case.

Cases and targets (2-core machine, default options, Ca_B = 50):

* short: (nu, lam) = (0.9, 1.0), <= 4 s;
* rbc: (0.61, 1.39), the red blood cell in a 4 um capillary, <= 15 s;
* long: (0.6, 1.94), lam/lam_c = 0.98, <= 60 s;
* sweep: 10 points at nu = 0.8, lam/lam_c = 0.3 ... 0.95, by continuation
  (:func:`bem.sweep.sweep_vesicle`), <= 60 s in all.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

CASES = {"short": (0.9, 1.0, 4.0), "rbc": (0.61, 1.39, 15.0), "long": (0.6, 1.94, 60.0),
         "sweep": (0.8, None, 60.0)}

_CHILD = """
import json, resource, time
import numba
import numpy as np
from bem.sweep import sweep_vesicle
from bem.vesicle import solve_vesicle
solve_vesicle(0.98, 0.3, n_modes=8, tol=0.5, residual_tol=10)      # compile / warm the cache
t = time.perf_counter()
if {lam!r} is None:
    out = sweep_vesicle({nu}, lam_ratios=list(np.linspace(0.3, 0.95, 10)))
else:
    out = [solve_vesicle({nu}, {lam})]
wall = time.perf_counter() - t
r = out[-1]
print(json.dumps({{"wall_s": wall, "bie_solves": sum(p.bie_solves for p in out),
                  "converged": sum(bool(p.success) for p in out), "points": len(out),
                  "lam_ratio": r.lam_ratio, "V_over_U": r.V_over_U, "dp_plus_R0": r.dp_plus_R0,
                  "tension_max": r.tension_max, "residual": r.residual,
                  "error": r.error_estimate, "modes": r.panels.get("modes"),
                  "messages": [p.message for p in out if not p.success],
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                  "threads": numba.get_num_threads()}}))
"""


def run_case(nu: float, lam: float | None) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD.format(nu=nu, lam=lam)], cwd=ROOT,
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="short,rbc,long,sweep",
                    help="comma-separated subset of " + ", ".join(CASES))
    ap.add_argument("--repeats", type=int, default=3, help="runs per case (default 3)")
    ap.add_argument("--json", help="also write the rows to this JSON file")
    args = ap.parse_args()
    names = [c.strip() for c in args.cases.split(",") if c.strip()]
    unknown = [c for c in names if c not in CASES]
    if unknown or args.repeats < 1:
        ap.error(f"--cases must be from {', '.join(CASES)} and --repeats >= 1")
    from bench_store import DATA
    if args.json and Path(args.json).resolve() == (DATA / "bench_vesicle.json").resolve():
        ap.error(f"--json {args.json}: the benchmark's own store (written in any case, in its "
                 "own format); give another file for the rows")
    rows = []
    print(f"{'case':>6} {'nu':>5} {'lam/lc':>6} {'min s':>7} {'median s':>8} {'target':>6} "
          f"{'BIE':>6} {'conv':>5} {'modes':>5} {'V/U':>10} {'dp+R0':>9} {'g_max':>8} "
          f"{'residual':>8} {'peak MB':>7}", flush=True)
    from bench_store import machine, store
    for name in names:
        nu, lam, target = CASES[name]
        load_before = os.getloadavg()
        runs = [run_case(nu, lam) for _ in range(args.repeats)]
        walls = [r["wall_s"] for r in runs]
        r = runs[-1]
        row = {"case": name, "nu": nu, "lam": lam, "target_s": target, "min_s": min(walls),
               "median_s": statistics.median(walls), "runs_s": walls, **r}
        rows.append(row)
        print(f"{name:>6} {nu:5.2f} {r['lam_ratio']:6.3f} {row['min_s']:7.1f} "
              f"{row['median_s']:8.1f} {target:6.0f} {r['bie_solves']:6d} "
              f"{r['converged']:>2d}/{r['points']:<2d} {r['modes']!s:>5} "
              f"{r['V_over_U']:10.6f} {r['dp_plus_R0']:9.4g} {r['tension_max']:8.4g} "
              f"{r['residual']:8.1e} {r['peak_rss_mb']:7.0f}", flush=True)
        for m in r["messages"]:
            print(f"       not converged: {m}")
        store("vesicle", {"cases": {name: {**row, "repeats": args.repeats, "ca_b": 50.0}},
                          "machine": machine(load_before)}, merge="cases")
    print("BIE: boundary-integral solves (Chen et al. 2020: 1e4-1e5 time steps, one each); "
          "sweep row: totals over its 10 points, solution of the last one")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
