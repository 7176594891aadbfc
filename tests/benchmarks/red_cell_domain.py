"""The default BEM red-cell solve at random points of its domain: how many converge, and how long.

Run with ``python tests/benchmarks/red_cell_domain.py [--seed 1] [--points 12] [--max-time 300]
[--json FILE]``; writes ``docs/data/red_cell_domain.json`` by default (one row per point,
stored after each). Not a test: timings depend on the machine and its load.

Points: ν uniform in 0.55-0.70 (the biconcave reference needs ν ≤ 0.743), λ/λc uniform in
0.3-0.97, Ca_B log-uniform in 10^0.5-10^3, Ca_S = ηU/G_s log-uniform in 10^-1.7-10^0.3 (0.02-2,
0.1-10 mm/s at G_s = 6 µN/m), drawn in that order from ``random.Random(seed)``; each solved by
``solve_vesicle(nu, lam_ratio=..., ca_b=..., ca_s=..., max_time=...)`` with every other option
at its default (Evans-Fung reference).
"""

from __future__ import annotations

import argparse
import random
import time
from pathlib import Path

from lubrication.io import provenance, write_json

OUT = Path(__file__).resolve().parents[2] / "docs" / "data" / "red_cell_domain.json"


def draw(rng: random.Random) -> tuple[float, float, float, float]:
    """(nu, lam/lam_c, Ca_B, Ca_S) of one point."""
    nu, q = rng.uniform(0.55, 0.70), rng.uniform(0.3, 0.97)
    return nu, q, 10 ** rng.uniform(0.5, 3), 10 ** rng.uniform(-1.7, 0.3)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--points", type=int, default=12)
    p.add_argument("--max-time", type=float, default=300.0)
    p.add_argument("--json", type=Path, default=OUT)
    args = p.parse_args(argv)
    from bem.vesicle import solve_vesicle  # lazy: numba
    rng, rows = random.Random(args.seed), []
    for _ in range(args.points):
        nu, q, ca_b, ca_s = draw(rng)
        t0 = time.perf_counter()
        r = solve_vesicle(nu, lam_ratio=q, ca_b=ca_b, ca_s=ca_s, max_time=args.max_time)
        rows.append({"nu": nu, "lam_ratio": q, "ca_b": ca_b, "ca_s": ca_s,
                     "converged": r.success, "seconds": time.perf_counter() - t0,
                     "V_over_U": r.V_over_U if r.success else None,
                     "dp_plus_R0": r.dp_plus_R0 if r.success else None,
                     "seed": r.seed, "message": r.message})
        write_json(args.json, {"seed": args.seed, "max_time": args.max_time, "rows": rows,
                               "provenance": provenance()})
        print(f"({nu:.4f}, {q:.4f}, {ca_b:.4g}, {ca_s:.4g}): "
              f"{'converged' if r.success else 'FAILED'} in {rows[-1]['seconds']:.0f} s",
              flush=True)
    ok = sum(r["converged"] for r in rows)
    times = sorted(r["seconds"] for r in rows)
    print(f"{ok}/{len(rows)} converged; median {times[len(times) // 2]:.0f} s, "
          f"max {times[-1]:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
