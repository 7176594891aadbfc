"""Error bars of the red-cell slice of the map against direct BEM solves off its grid.

Run with ``python tests/benchmarks/rbc_slice_coverage.py [--map FILE]``: by default it packs
the build folder ``docs/data/rbc_slice_build`` (:func:`correlations.solution_map.pack_map`,
into a temporary file) and queries it at every converged red-cell point of
``docs/data/rbc_shear_bem.json`` (the default cell, ν = 0.610, in 4-8 µm tubes: off the slice's
ν and λ/λc grid lines; their velocities 0.1-2 mm/s are on its Ca_B lines, 4 and 8 mm/s between
them). For each quantity it prints how often |map − direct| ≤ the map's error bar (the target
of the red-cell estimate: ≥ 90 % of ≥ 20 points) and the largest ratio |map − direct|/bar.
Points where the map has no value (outside its box, a hole) are counted apart. Then the share
of ``--random N`` (default 4000) uniform random points of the map's box (log-uniform in Ca_B)
where the map answers Δp⁺, overall and per ν interval. Not a test.
"""

from __future__ import annotations

import argparse
import json
import math
import random
import tempfile
from pathlib import Path

from correlations.solution_map import load_map, pack_map, query_map, query_map_many

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "docs" / "data" / "rbc_slice_build"
DIRECT = ROOT / "docs" / "data" / "rbc_shear_bem.json"
QUANTITIES = ("V_over_U", "dp_plus_R0", "ell", "film_min")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--map", type=Path, help="a packed red-cell map (default: pack the build)")
    p.add_argument("--random", type=int, default=4000, metavar="N",
                   help="random points of the box for the answered share (default 4000)")
    args = p.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        path = args.map or pack_map(BUILD, Path(tmp) / "rbc_slice_map.json")
        m = load_map(path)
    rows = [r for k, r in json.loads(DIRECT.read_text())["rows"].items()
            if k.startswith("red cell") and r["success"]]
    nu = json.loads(DIRECT.read_text())["parameters"]["nu"]
    stats = {q: {"covered": 0, "answered": 0, "worst": 0.0} for q in QUANTITIES}
    missing = 0
    print(f"{'d [um]':>6} {'U':>5} {'lam/lam_c':>9}  " + "  ".join(f"{q:>22}" for q in QUANTITIES))
    for r in sorted(rows, key=lambda r: (r["diameter_um"], r["U_mm_s"])):
        res = query_map(nu, r["lam_ratio"], r["ca_b"], m)
        cells = []
        for q in QUANTITIES:
            v = res.quantities[q]
            if v.value is None or v.error is None:
                cells.append(f"{'—':>22}")
                continue
            s = stats[q]
            s["answered"] += 1
            ratio = abs(v.value - r[q]) / v.error if v.error > 0 else float("inf")
            s["covered"] += ratio <= 1.0
            s["worst"] = max(s["worst"], ratio)
            cells.append(f"{v.value:>9.4g}±{v.error:<7.2g}{ratio:>5.2f}")
        missing += all(c.strip() == "—" for c in cells)
        print(f"{r['diameter_um']:>6g} {r['U_mm_s']:>5g} {r['lam_ratio']:>9.4f}  " + "  ".join(cells))
    print(f"\n{len(rows)} direct solves; {missing} without any map value")
    for q, s in stats.items():
        share = s["covered"] / s["answered"] if s["answered"] else float("nan")
        print(f"{q:>12}: bar covers {s['covered']}/{s['answered']} ({share:.0%}), worst "
              f"|map - direct|/bar = {s['worst']:.2f}")
    answered_share(m, args.random)
    return 0


def answered_share(m, n: int, seed: int = 7) -> None:
    """Print where map ``m`` answers Δp⁺ among ``n`` random points of its box."""
    rng = random.Random(seed)
    lo, hi = math.log(m.cas[0]), math.log(m.cas[-1])
    pts = [(rng.uniform(m.nus[0], m.nus[-1]), rng.uniform(m.ratios[0], m.ratios[-1]),
            math.exp(rng.uniform(lo, hi))) for _ in range(n)]
    ok = [r.quantities["dp_plus_R0"].value is not None
          for r in query_map_many(*zip(*pts), map=m, names=("V_over_U", "dp_plus_R0"))]
    print(f"\nthe map answers at {sum(ok) / n:.1%} of {n} random points of its box")
    for a, b in zip(m.nus, m.nus[1:]):
        inside = [o for p, o in zip(pts, ok) if a <= p[0] < b]
        print(f"  nu {a:g}-{b:g}: {sum(inside) / max(len(inside), 1):.1%}")


if __name__ == "__main__":
    raise SystemExit(main())
