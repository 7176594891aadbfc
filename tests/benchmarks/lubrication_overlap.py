"""Where is the lubrication model accurate? BEM against lubrication in the map's overlap.

Run with ``python tests/benchmarks/lubrication_overlap.py [--build DIR] [--json FILE]``.
Reads the converged points of a map build folder (default: the committed one,
``correlations/data/solution_map_build``) and prints, for every (ν, Ca_B) and every λ/λc
where both the BEM and the lubrication solver converged, the relative difference
(lubrication − BEM)/BEM of V/U, Δp⁺R0/(ηU), ℓ, minimum film and γ_max; then, per δ = 1 − λ/λc,
the largest |difference| over all lines. The lubrication row of the estimate's method table
takes its validity range from this table (:data:`correlations.registry.LUBRICATION_RANGE`).
Not a test: it reads stored results, no solver runs.
"""

from __future__ import annotations

import argparse
import collections
from pathlib import Path

from correlations.solution_map import read_points
from lubrication.io import write_json

BUILD = Path(__file__).resolve().parents[2] / "correlations" / "data" / "solution_map_build"
KEYS = ("V_over_U", "dp_plus_R0", "ell", "film_min", "tension_max")


def overlap(folder) -> list[dict]:
    """One row per (ν, Ca_B, λ/λc) with both methods converged: the relative differences."""
    pts = {(p["method"], p["nu"], p["lam_ratio"], p["ca_b"]): p
           for p in read_points(folder) if p["success"]}
    rows = []
    for (method, nu, r, ca), b in sorted(pts.items(), key=lambda kv: (kv[0][3], -kv[0][1],
                                                                      kv[0][2])):
        lub = pts.get(("lubrication", nu, r, ca))
        if method == "bem" and lub is not None:
            rows.append({"nu": nu, "ca_b": ca, "lam_ratio": r,
                         **{q: (lub[q] - b[q]) / b[q] for q in KEYS}})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=str(BUILD), help="map build folder")
    ap.add_argument("--json", help="write the rows and the summary to this file")
    args = ap.parse_args(argv)
    if not Path(args.build).is_dir():
        ap.error(f"--build: {args.build} is not a folder")
    rows = overlap(args.build)
    print(f"{'Ca_B':>5} {'nu':>5} {'r':>5} " + " ".join(f"{k:>12}" for k in KEYS))
    for row in rows:
        print(f"{row['ca_b']:5g} {row['nu']:5g} {row['lam_ratio']:5g} "
              + " ".join(f"{row[k]:+12.2%}" for k in KEYS))
    worst = collections.defaultdict(dict)
    for row in rows:
        delta = round(1.0 - row["lam_ratio"], 6)
        for k in KEYS:
            worst[delta][k] = max(worst[delta].get(k, 0.0), abs(row[k]))
    print(f"\nlargest |lubrication - BEM| / BEM over {len(rows)} points:")
    print(f"{'delta':>6} " + " ".join(f"{k:>12}" for k in KEYS))
    for delta in sorted(worst):
        print(f"{delta:6g} " + " ".join(f"{worst[delta][k]:12.2%}" for k in KEYS))
    if args.json:
        write_json(args.json, {"build": args.build, "rows": rows,
                               "worst": {str(d): w for d, w in sorted(worst.items())}},
                   indent=1, sort_keys=False)
    return 0


if __name__ == "__main__":
    from bench_store import run_script

    run_script(main)
