"""Speed-up of the map build on a local process pool and on a Dask LocalCluster over the serial
build (2 workers each), on a small BEM grid at the default solver options.

Run with ``python tests/benchmarks/bench_map_build.py`` on an otherwise idle machine. The grid:
ν ∈ {0.95, 0.9} × λ/λc ∈ {0.3, 0.4, 0.5, 0.6} at Ca_B = 50 (4 BEM lines of 2 points). Each
build starts in a fresh temporary folder; the maps are compared (V/U and Δp⁺ equal to the solver
tolerance 1e-4, relative). Not a test: about a minute; the Dask part needs the
``distributed`` extra. The times, with the machine they were taken on, go to
``docs/data/bench_map_build.json`` (``tests/benchmarks/bench_store.py``).
"""

from __future__ import annotations

import json
import os
import tempfile
import time
from pathlib import Path

from correlations.map_build import build_map, make_grid

GRID = make_grid([0.9, 0.95], [0.3, 0.4, 0.5, 0.6], [50.0], ["bem"])


def _timed(folder, **kw) -> tuple[float, dict]:
    t0 = time.perf_counter()
    summary = build_map(folder, GRID, **kw)
    seconds = time.perf_counter() - t0
    if summary["failed"] or summary["missing"]:
        raise SystemExit(f"build in {folder} incomplete: {summary}")
    return seconds, json.loads(Path(summary["map"]).read_text())["columns"]


def main() -> int:
    from bench_store import machine, store
    load_before = os.getloadavg()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        build_map(tmp / "warm", make_grid([0.95], [0.3], [50.0], ["bem"]), workers=1)  # JIT
        rows = [("serial (workers=1)",) + _timed(tmp / "serial", workers=1)]
        rows.append(("process pool (workers=2)",) + _timed(tmp / "pool", workers=2))
        try:
            from dask.distributed import LocalCluster
        except ImportError:
            print("dask.distributed not installed: Dask row skipped (pip install "
                  "'.[distributed]')")
        else:
            with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                              dashboard_address=None) as cluster:
                rows.append(("Dask LocalCluster (2 processes)",)
                            + _timed(tmp / "dask", scheduler=cluster.scheduler_address))
        ref = rows[0][2]
        print(f"{'build':<34} {'s':>7} {'speed-up':>9} {'max rel diff V/U, dp+':>22}")
        builds = {}
        for (name, seconds, cols), key in zip(rows, ("serial", "pool", "dask")):
            diff = max(abs(a - b) / abs(b) for q in ("V_over_U", "dp_plus_R0")
                       for a, b in zip(cols[q], ref[q]))
            print(f"{name:<34} {seconds:7.1f} {rows[0][1] / seconds:8.2f}x {diff:22.1e}")
            builds[key] = {"label": name, "seconds": seconds, "speed_up": rows[0][1] / seconds,
                           "max_rel_diff": diff}
    store("map_build", {"parameters": {"nu": [0.9, 0.95], "lam_ratio": [0.3, 0.4, 0.5, 0.6],
                                       "ca_b": [50.0], "methods": ["bem"], "workers": 2,
                                       "points": len(ref["nu"]), "runs": 1},
                        "builds": builds, "machine": machine(load_before)})
    return 0


if __name__ == "__main__":
    from bench_store import run_script

    run_script(main)
