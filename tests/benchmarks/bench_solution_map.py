"""Benchmark of the solution map at the size of the default grid: pack time, packed file size
and query cost (target: a query <= 50 ms after import). Not a test: timings depend on the
machine.

The map is synthetic (a smooth function stored as converged points on every node of
correlations.map_build.DEFAULT_GRID), so no solver runs. Run with
``python tests/benchmarks/bench_solution_map.py``.
"""

from __future__ import annotations

import json
import math
import random
import statistics
import sys
import tempfile
import time
from pathlib import Path

QUERY_TARGET_MS = 50.0


def _value(q, nu, r, ca):
    """A smooth stand-in with the near-critical powers of delta of the real quantities."""
    from correlations.solution_map import TRANSFORMS
    d = 1.0 - r
    g = 0.3 * math.sin(2 * nu) - 0.4 * math.sqrt(d) + 0.1 * math.log(ca)
    t = TRANSFORMS[q]
    return (g if not t["log"] else math.exp(g)) / d ** t["power"] + t["offset"]


def make_folder(folder: Path) -> None:
    from correlations.map_build import DEFAULT_GRID, make_grid
    from correlations.solution_map import POINT_FORMAT, QUANTITIES, point_filename
    grid = make_grid()
    (folder / "build.json").write_text(json.dumps({"grid": grid, "parameters": {},
                                                   "provenance": {"benchmark": True}}))
    for m in grid["methods"]:
        for nu in grid["nu"]:
            for ca in grid["ca_b"]:
                for r in DEFAULT_GRID["lam_ratio"][m]:
                    rec = {"format": POINT_FORMAT, "method": m, "nu": nu, "lam_ratio": r,
                           "ca_b": ca, "success": True, "message": "", "shape_class": "bullet",
                           "error_estimate": {q: 1e-6 for q in ("V_over_U", "dp_plus_R0")},
                           "residual": 1e-6, "bie_solves": 50, "seconds": 60.0,
                           **{q: _value(q, nu, r, ca) for q in QUANTITIES}}
                    (folder / point_filename(m, nu, r, ca)).write_text(json.dumps(rec))


def main() -> int:
    from correlations.solution_map import load_map, pack_map, query_map
    folder = Path(tempfile.mkdtemp(prefix="bench-map-"))
    make_folder(folder)
    t0 = time.perf_counter()
    path = pack_map(folder)
    pack_s = time.perf_counter() - t0
    m = load_map(path)
    rng = random.Random(1)
    points = [(rng.uniform(0.6, 0.98), 1 - rng.uniform(1e-4, 0.8), rng.uniform(5, 500))
              for _ in range(200)]
    times = []
    for p in points:
        t0 = time.perf_counter()
        query_map(*p, m)
        times.append(1e3 * (time.perf_counter() - t0))
    med, worst = statistics.median(times), max(times)
    print(f"points {len(m.columns['nu'])}, pack {pack_s:.1f} s, file {path.stat().st_size / 1e3:.0f} kB")
    print(f"query: median {med:.1f} ms, max {worst:.1f} ms over {len(times)} random queries "
          f"(target <= {QUERY_TARGET_MS:g} ms): {'ok' if worst <= QUERY_TARGET_MS else 'SLOW'}")
    return 0 if worst <= QUERY_TARGET_MS else 1


if __name__ == "__main__":
    sys.exit(main())
