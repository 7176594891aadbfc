"""Benchmark of the steady BEM vesicle solver: prints a table (not a test; timings depend on the
machine).

Run with ``python tests/benchmarks/bench_vesicle.py [--near] [--json FILE]``. Each case runs in a
fresh interpreter (numba cache warm) so that its peak resident memory (``ru_maxrss``) is its own.
Targets (issue 6, 2-core machine): steady solve at (nu, lam) = (0.9, 1.0) in <= 30 s; at
(0.6, 1.94) in <= 5 min (``--near``, long). The number of boundary-integral solves (BEM
evaluations, continuation rungs included) is printed beside the 10^4-10^5 semi-implicit time
steps of Chen et al. 2020 (one BIE solve each).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

CASES = [(0.9, 1.0)]
NEAR = [(0.6, 1.94)]

_CHILD = """
import json, resource, sys, time
from bem.vesicle import solve_vesicle
solve_vesicle(0.98, 0.3, n_modes=8, tol=0.5, residual_tol=10)      # compile / warm the cache
t = time.perf_counter()
r = solve_vesicle({nu}, {lam})
wall = time.perf_counter() - t
print(json.dumps({{"nu": r.nu, "lam": r.lam, "lam_ratio": r.lam_ratio, "wall_s": wall,
                  "bie_solves": r.bie_solves, "V_over_U": r.V_over_U,
                  "dp_plus_R0": r.dp_plus_R0, "tension_max": r.tension_max,
                  "residual": r.residual, "converged": r.success, "message": r.message,
                  "modes": r.panels.get("modes"), "seed": r.seed,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}}))
"""


def run_case(nu: float, lam: float) -> dict:
    out = subprocess.run([sys.executable, "-c", _CHILD.format(nu=nu, lam=lam)], cwd=ROOT,
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--near", action="store_true", help="also (0.6, 1.94) (minutes)")
    ap.add_argument("--json", help="write the rows to this JSON file")
    args = ap.parse_args()
    cases = CASES + (NEAR if args.near else [])
    rows = []
    print(f"{'nu':>5} {'lam':>5} {'lam/lc':>6} {'wall s':>7} {'BIE solves':>10} "
          f"{'Chen steps':>10} {'modes':>5} {'V/U':>10} {'dp+R0':>9} {'g_max':>8} "
          f"{'residual':>8} {'conv':>5} {'peak MB':>8}")
    for nu, lam in cases:
        r = run_case(nu, lam)
        rows.append(r)
        print(f"{r['nu']:5.2f} {r['lam']:5.2f} {r['lam_ratio']:6.3f} {r['wall_s']:7.1f} "
              f"{r['bie_solves']:10d} {'1e4-1e5':>10} {r['modes']!s:>5} "
              f"{r['V_over_U']:10.6f} {r['dp_plus_R0']:9.4g} {r['tension_max']:8.4g} "
              f"{r['residual']:8.1e} {r['converged']!s:>5} {r['peak_rss_mb']:8.0f}",
              flush=True)
        if not r["converged"]:
            print(f"      not converged: {r['message']}")
    print("targets: (0.9, 1.0) <= 30 s; (0.6, 1.94) <= 300 s (issue 6, 2 cores)")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
