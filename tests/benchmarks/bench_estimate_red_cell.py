"""Time per call of the red-cell estimate after import, answered from the red-cell map.

Target: <= 50 ms per ``estimate()`` (the engineering estimate is instant). The first call reads
the map file; the others query it (each a new case: the velocity changes, so neither the map
query's cache nor the estimate's is hit). Prints a table::

    python tests/benchmarks/bench_estimate_red_cell.py                 # the shipped red-cell map
    python tests/benchmarks/bench_estimate_red_cell.py --map FILE      # another packed slice

Without a red-cell map (none shipped, no --map) it times the estimate that says so.
"""

from __future__ import annotations

import argparse
import statistics
import time

from correlations.estimate import estimate
from correlations.solution_map import RED_CELL_MAP

TARGET_MS = 50.0


def bench(solution_map=None, calls: int = 50) -> dict:
    """Wall times [ms]: the first call, then ``calls`` calls of new cases (red cell and, for
    comparison, vesicle), and how the red cell's V/U was answered."""
    t = time.perf_counter()
    first = estimate(solution_map=solution_map)
    first_ms = (time.perf_counter() - t) * 1e3
    out = {"first": first_ms, "method": first.quantities["V_over_U"].method
           or first.quantities["V_over_U"].note}
    for membrane, kw in (("red-cell", {"solution_map": solution_map}), ("vesicle", {})):
        times = []
        for k in range(calls):
            t = time.perf_counter()
            estimate(velocity_mm_s=0.9 + 0.004 * k, hematocrit=0.3, membrane=membrane, **kw)
            times.append((time.perf_counter() - t) * 1e3)
        out[membrane] = times
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--map", help=f"packed red-cell map (default {RED_CELL_MAP})")
    p.add_argument("--calls", type=int, default=50)
    args = p.parse_args(argv)
    r = bench(args.map, args.calls)
    print(f"red-cell map: {args.map or RED_CELL_MAP}; V/U at the default cell: {r['method']}")
    print(f"{'estimate()':28s} {'median [ms]':>12s} {'max [ms]':>10s} {'target [ms]':>12s}")
    print(f"{'first call (reads the map)':28s} {r['first']:12.2f} {r['first']:10.2f} {'-':>12s}")
    ok = True
    for membrane in ("red-cell", "vesicle"):
        times = r[membrane]
        med = statistics.median(times)
        ok &= med <= TARGET_MS
        print(f"{membrane + ', new case':28s} {med:12.2f} {max(times):10.2f} {TARGET_MS:12.0f}")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
