"""The solution map against direct solves at off-grid points: interpolation error and error-bar
coverage.

Run with ``python tests/benchmarks/map_offgrid.py [--map FILE] [--json FILE] [--points N]``.
The points are a fixed pseudo-random sample (seed 2026) of (ν, λ/λc, Ca_B) inside the map's
box, ν in [0.6, 0.98], λ/λc in [0.2, 0.95], log-uniform Ca_B in [5, 500] (or the Ca_B values
given with ``--ca-b``, or the range given with ``--ca-b-range``), none on a node of the map's
grid (each coordinate at least 0.2 of a grid step from the nearest node; a finer grid thus
draws new points where old ones now lie near a node). Each is solved directly by the BEM at
its default options (Ca_B given; the default solve starts from the nearest stored shapes of the
seed bank, :mod:`bem.seed_bank`) and compared with :func:`query_map` at the same point. For a
red-cell map (:attr:`~correlations.solution_map.SolutionMap.membrane`) ν is drawn over the
map's ν range and each point is the red cell of the map's shear ratio β, Ca_S = Ca_B/β (``python
tests/benchmarks/map_offgrid.py --map correlations/data/rbc_slice_map.json --json
docs/data/rbc_slice_offgrid.json --points 24 --ca-b-range 4.6372 463.7179``).

Acceptance targets (relative, |map − direct| / |direct|): V/U 0.2 %, Δp⁺ and ℓ 2 %, minimum
film 5 %; the reported error bar ``error`` should cover |map − direct| at ≥ 90 % of points.
The statistics are kept in two groups: points whose grid cell has one shape class at all its
neighbouring points (``summary``; the targets are judged there), and points where the
neighbouring points differ in shape class (``summary_branch_change``: the map's shape class is
None). In the second group the cell holds a bullet–parachute transition or, at small λ/λc, the
end of the elongated or the parachute branch, two steady states that coexist
(tests/benchmarks/map_bistability.py); interpolation across them has no accuracy to claim, only
its error bar. Direct solves that do not converge, and map queries that return None (next to a
hole), are listed and left out of the statistics. Results are stored point by point in the JSON
file (atomic writes; a rerun skips the points already solved, and with ``--retry-failed`` solves
again those that did not converge). Not a test: a BEM solve takes 3–60 s per point on 2 cores.
"""

from __future__ import annotations

import argparse
import json
import math
import random
import statistics
import time
from pathlib import Path

from bem.vesicle import solve_vesicle
from correlations.solution_map import load_map, query_map
from lubrication.io import write_json

TARGETS = {"V_over_U": 2e-3, "dp_plus_R0": 2e-2, "ell": 2e-2, "film_min": 5e-2}
COVERAGE_TARGET = 0.9


def _off(value: float, nodes: list[float], log: bool = False) -> bool:
    """True if ``value`` is at least 0.2 of the local grid step from every node."""
    f = math.log if log else (lambda v: v)
    xs = sorted(f(n) for n in nodes)
    x = f(value)
    i = min(range(len(xs)), key=lambda k: abs(xs[k] - x))
    step = min(abs(xs[j] - xs[i]) for j in (i - 1, i + 1) if 0 <= j < len(xs))
    return abs(x - xs[i]) >= 0.2 * step


def sample(n: int, grid: dict, ca_b: list[float] | None = None, seed: int = 2026,
           nu_range=(0.6, 0.98), ca_b_range=(5.0, 500.0)) -> list[tuple]:
    """``n`` points (ν, λ/λc, Ca_B) of the BEM box, each off the nodes of ``grid`` (the map's
    grid: its ν, its BEM λ/λc, its Ca_B)."""
    rng, out = random.Random(seed), []
    lo, hi = (math.log(c) for c in ca_b_range)
    while len(out) < n:
        nu = round(rng.uniform(*nu_range), 4)
        r = round(rng.uniform(0.2, 0.95), 4)
        ca = rng.choice(ca_b) if ca_b else round(math.exp(rng.uniform(lo, hi)), 2)
        if (_off(nu, grid["nu"]) and _off(r, grid["lam_ratio"]["bem"])
                and (ca_b or _off(ca, grid["ca_b"], log=True))):
            out.append((nu, r, ca))
    return out


def _direct(nu: float, r: float, ca: float, shear_ratio: float | None = None) -> dict:
    """The default solve at one point (a red cell of shear ratio β = Ca_B/Ca_S if given)."""
    t0 = time.perf_counter()
    red_cell = {} if shear_ratio is None else {"ca_s": ca / shear_ratio, "max_time": 900.0}
    res = solve_vesicle(nu, lam_ratio=r, ca_b=ca, **red_cell)   # the red-cell build's time cap
    d = res.to_dict(shape=False)
    return {"success": bool(res.success), "message": res.message, "seed": res.seed,
            "seconds": round(time.perf_counter() - t0, 1),
            "bie_solves": res.bie_solves, "shape_class": d.get("shape_class"),
            **{q: d.get(q) for q in TARGETS}}


def branch_change(row: dict) -> bool:
    """True where the map's neighbouring points differ in shape class (module docstring)."""
    return row["map"]["shape_class"] is None


def summarise(rows: list[dict]) -> dict:
    """Per quantity over the points with a direct solution and a map value: the number of
    points, the median and largest relative error of the map, the fraction within the target,
    the fraction whose error bar covers the error and the median bar/error (stored in the JSON
    as ``summary`` and ``summary_branch_change``, from which docs/validation.md is
    generated)."""
    out = {}
    for q, target in TARGETS.items():
        errs, cover, ratios = [], [], []
        for row in rows:
            mv, d = row["map"][q], row["direct"]
            if d["success"] and mv["value"] is not None and d[q] is not None:
                e = abs(mv["value"] - d[q])
                errs.append(e / abs(d[q]))
                cover.append(mv["error"] is not None and mv["error"] >= e)
                ratios.append((mv["error"] or 0.0) / max(e, 1e-300))
        if errs:
            out[q] = {"points": len(errs), "median_error": statistics.median(errs),
                      "max_error": max(errs), "target": target,
                      "within_target": sum(e <= target for e in errs) / len(errs),
                      "covered": sum(cover) / len(cover),
                      "median_bar_over_error": statistics.median(ratios)}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--map", help="packed map file (default: the shipped map)")
    ap.add_argument("--json", default="docs/data/map_offgrid.json", help="results file")
    ap.add_argument("--points", type=int, default=32, help="number of points (default 32)")
    ap.add_argument("--ca-b", type=float, nargs="+", help="Ca_B values to sample from "
                    "(default: log-uniform in [5, 500])")
    ap.add_argument("--ca-b-range", type=float, nargs=2, metavar=("LO", "HI"),
                    help="log-uniform Ca_B range (default 5 500)")
    ap.add_argument("--retry-failed", action="store_true",
                    help="solve again the stored direct solves that did not converge (e.g. "
                         "after a change of the solver)")
    args = ap.parse_args(argv)
    if args.points < 1:
        ap.error(f"--points must be >= 1, got {args.points}")
    out_path = Path(args.json)
    if not out_path.parent.is_dir():
        ap.error(f"--json: folder {out_path.parent} does not exist")
    m = load_map(args.map)
    source = str(args.map or "shipped map")
    old = json.loads(out_path.read_text()) if out_path.exists() else {}
    done = {tuple(p["point"]): p for p in old.get("points", [])}
    rows = []
    print(f"{'nu':>6} {'r':>6} {'Ca_B':>7} {'s':>5}  " + "  ".join(
        f"{q:>10} {'rel err':>8} {'bar':>8}" for q in TARGETS), flush=True)
    beta = m.membrane["shear_ratio"] if m.membrane else None
    box = {"nu_range": (m.nus[0], m.nus[-1])} if beta else {}
    if args.ca_b_range:
        box["ca_b_range"] = tuple(args.ca_b_range)
    for point in sample(args.points, m.grid, args.ca_b, **box):
        row = done.get(point)
        if row is None or (not row["direct"]["success"]
                           and ("seed" not in row["direct"] or args.retry_failed)):
            row = {"point": list(point), "direct": _direct(*point, shear_ratio=beta)}
        query = query_map(*point, map=m)
        row["map"] = {q: {"value": query.quantities[q].value, "error": query.quantities[q].error,
                          "note": query.quantities[q].note} for q in TARGETS}
        row["map"]["shape_class"] = query.quantities["shape_class"].value
        rows.append(row)
        done[point] = row                          # the file keeps every point solved so far
        write_json(out_path, {"map": source, "targets": TARGETS,
                              "points": list(done.values())}, indent=1, sort_keys=False)
        d = row["direct"]
        cells = []
        for q in TARGETS:
            mv, dv = row["map"][q]["value"], d[q]
            if not d["success"] or mv is None or dv is None:
                cells.append(f"{'—':>10} {'':>8} {'':>8}")
                continue
            cells.append(f"{mv:10.5g} {abs(mv - dv) / abs(dv):8.1e} "
                         f"{(row['map'][q]['error'] or 0) / abs(dv):8.1e}")
        print(f"{point[0]:6.4f} {point[1]:6.4f} {point[2]:7.2f} {d['seconds']:5.0f}  "
              + "  ".join(cells) + ("" if d["success"] else "  direct: not converged"),
              flush=True)
    summary = summarise([r for r in rows if not branch_change(r)])
    changes = summarise([r for r in rows if branch_change(r)])
    write_json(out_path, {"map": source, "targets": TARGETS, "summary": summary,
                          "summary_branch_change": changes, "points": list(done.values())},
               indent=1, sort_keys=False)
    status = 0
    for title, table, judged in (("cells with one shape class (targets apply)", summary, True),
                                 ("cells where the shape class changes", changes, False)):
        print(f"\n{title}:")
        print(f"{'quantity':>11} {'points':>6} {'median rel err':>14} {'max rel err':>11} "
              f"{'target':>7} {'within':>7} {'covered':>8} {'median bar/err':>14}")
        for q, target in TARGETS.items():
            row = table.get(q)
            if row is None:
                print(f"{q:>11} {0:6d} {'—':>11}")
                continue
            ok = row["max_error"] <= target and row["covered"] >= COVERAGE_TARGET
            status |= judged and not ok
            print(f"{q:>11} {row['points']:6d} {row['median_error']:14.2e} "
                  f"{row['max_error']:11.2e} {target:7.0e} {row['within_target']:7.0%} "
                  f"{row['covered']:8.0%} {row['median_bar_over_error']:14.1f}"
                  + ("" if ok or not judged else "  MISSED"))
    left = [r["point"] for r in rows if not r["direct"]["success"]]
    holes = [r["point"] for r in rows if r["direct"]["success"]
             and r["map"]["V_over_U"]["value"] is None]
    print(f"direct solve not converged: {left or 'none'}")
    print(f"map gives no value (hole or outside): {holes or 'none'}")
    return status


if __name__ == "__main__":
    from bench_store import run_script

    run_script(main)
