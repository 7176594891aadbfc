"""The default BEM vesicle solve over the whole passable domain: converged fraction, time, and
the estimate's error against it.

Run with ``python tests/benchmarks/vesicle_domain.py [--points 100] [--seed 20261207]
[--json FILE]``. The points are drawn at random, as a new user would pick them: ν uniform in
[0.6, 0.98], λ/λc uniform in [0.2, 0.98], Ca_B log-uniform in [5, 500] (``--seed`` draws
others; the default seed is fixed here). Each is solved by :func:`bem.vesicle.solve_vesicle`
with its default options, one after the other, at the default thread count; the time is the
solve's wall time. The shipped solution map (the estimate's source) is queried at the same
point and its value compared with the direct solve: the relative error, and whether the map's
error bar covers it, for V/U, Δp⁺, ℓ and the minimum film.

Reported: the converged fraction, the time quantiles (median, 95th percentile, maximum), every
failure with its message, the bistable points found, and per quantity the coverage of the error
bar and the worst relative error. Results go point by point to the JSON file (atomic writes;
default ``docs/data/vesicle_domain.json`` for the default seed, ``vesicle_domain_seed<S>.json``
for another), with the solver's commit (the last commit that changed bem/ or lubrication/); a
rerun keeps the points already solved by the same solver commit, unless that code has
uncommitted changes. Targets (the solver's acceptance): converged ≥ 98 %, median ≤ 10 s, 95th
percentile ≤ 60 s, coverage ≥ 90 %. Not a test (minutes to an hour on 2 cores);
tests/bem/test_vesicle_domain.py runs a few points at a loose tolerance.
"""

from __future__ import annotations

import argparse
import json
import math
import random
import statistics
import subprocess
import sys
import time
from pathlib import Path

from bem.vesicle import solve_vesicle
from correlations.solution_map import load_map, query_map
from lubrication.io import provenance, write_json

DEFAULT_SEED = 20261207
DOMAIN = {"nu": (0.6, 0.98), "lam_ratio": (0.2, 0.98), "ca_b": (5.0, 500.0)}
QUANTITIES = ("V_over_U", "dp_plus_R0", "ell", "film_min")
TARGETS = {"converged": 0.98, "median_s": 10.0, "p95_s": 60.0, "covered": 0.9}
DATA = Path(__file__).resolve().parents[2] / "docs" / "data"


def draw(n: int, seed: int = DEFAULT_SEED) -> list[tuple[float, float, float]]:
    """``n`` random points (ν, λ/λc, Ca_B) of the domain (module docstring), 4 significant
    digits each."""
    rng = random.Random(seed)
    lo, hi = DOMAIN["ca_b"]
    return [(round(rng.uniform(*DOMAIN["nu"]), 4), round(rng.uniform(*DOMAIN["lam_ratio"]), 4),
             round(math.exp(rng.uniform(math.log(lo), math.log(hi))), 2)) for _ in range(n)]


def solve_point(nu: float, r: float, ca: float, **options) -> dict:
    """The direct solve at one point (``options`` of solve_vesicle) and the map's values there."""
    t0 = time.perf_counter()
    res = solve_vesicle(nu, lam_ratio=r, ca_b=ca, **options)
    seconds = time.perf_counter() - t0
    d = res.to_dict(shape=False)
    q = query_map(nu, r, ca)
    return {"point": [nu, r, ca], "seconds": round(seconds, 2), "success": bool(res.success),
            "status": res.status.value, "message": res.message, "seed": res.seed,
            "failed_starts": res.failed_starts, "other_branch": res.other_branch,
            "shape_class": d.get("shape_class"), "bie_solves": res.bie_solves,
            "direct": {k: d.get(k) for k in QUANTITIES},
            "map": {k: {"value": q.quantities[k].value, "error": q.quantities[k].error}
                    for k in QUANTITIES}}


def solver_commit() -> str | None:
    """The last commit that changed the solver's code (bem/, lubrication/), or None when that
    code has uncommitted changes or git is not available."""
    root = Path(__file__).resolve().parents[2]
    try:
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "bem", "lubrication"],
                               cwd=root, capture_output=True, text=True, check=True).stdout
        last = subprocess.run(["git", "log", "-1", "--format=%H", "--", "bem", "lubrication"],
                              cwd=root, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    return None if dirty.strip() else last.strip() or None


def quantile(xs: list[float], p: float) -> float:
    """The p-quantile of ``xs`` (linear between order statistics)."""
    xs = sorted(xs)
    k = (len(xs) - 1) * p
    i = math.floor(k)
    return xs[i] + (xs[min(i + 1, len(xs) - 1)] - xs[i]) * (k - i)


def summarise(rows: list[dict]) -> dict:
    """Converged fraction, time quantiles and, per quantity over the converged points with a map
    value, the coverage of the map's error bar and the worst relative error."""
    times = [r["seconds"] for r in rows]
    ok = [r for r in rows if r["success"]]
    out = {"points": len(rows), "converged": len(ok) / len(rows) if rows else math.nan,
           "median_s": statistics.median(times) if times else math.nan,
           "p95_s": quantile(times, 0.95) if times else math.nan,
           "max_s": max(times, default=math.nan),
           "bistable": [r["point"] for r in ok if r["other_branch"]],
           "failures": [{"point": r["point"], "status": r["status"], "message": r["message"]}
                        for r in rows if not r["success"]], "estimate": {}}
    out["bistable_points"], out["failed_points"] = len(out["bistable"]), len(out["failures"])
    for k in QUANTITIES:
        pairs = [(r["map"][k], r["direct"][k]) for r in ok
                 if r["map"][k]["value"] is not None and r["direct"][k] is not None]
        if not pairs:
            continue
        errors = [abs(m["value"] - d) for m, d in pairs]
        out["estimate"][k] = {
            "points": len(pairs),
            "covered": sum(m["error"] is not None and m["error"] >= e
                           for (m, _), e in zip(pairs, errors)) / len(pairs),
            "worst_relative_error": max(e / abs(d) for (_, d), e in zip(pairs, errors))}
    return out


def print_summary(s: dict, out=sys.stdout) -> bool:
    """Print the summary against :data:`TARGETS`; True if every target is met."""
    met = (s["converged"] >= TARGETS["converged"] and s["median_s"] <= TARGETS["median_s"]
           and s["p95_s"] <= TARGETS["p95_s"])
    print(f"\n{s['points']} points: converged {s['converged']:.1%} (target "
          f"{TARGETS['converged']:.0%}); time median {s['median_s']:.1f} s (target "
          f"{TARGETS['median_s']:g}), 95th percentile {s['p95_s']:.1f} s (target "
          f"{TARGETS['p95_s']:g}), max {s['max_s']:.1f} s", file=out)
    for f in s["failures"]:
        print(f"  not converged at {tuple(f['point'])}: {f['status']}: {f['message']}", file=out)
    print(f"bistable points found: {len(s['bistable'])} {s['bistable']}", file=out)
    print(f"{'estimate':>11} {'points':>6} {'covered':>8} {'worst rel err':>13}", file=out)
    for k, e in s["estimate"].items():
        met &= e["covered"] >= TARGETS["covered"]
        print(f"{k:>11} {e['points']:6d} {e['covered']:8.0%} {e['worst_relative_error']:13.2e}",
              file=out)
    return met


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=100, help="number of points (default 100)")
    ap.add_argument("--seed", type=int, default=DEFAULT_SEED,
                    help=f"random seed of the draw (default {DEFAULT_SEED})")
    ap.add_argument("--json", help="results file (default docs/data/vesicle_domain[_seedS].json)")
    args = ap.parse_args(argv)
    if args.points < 1:
        ap.error(f"--points must be >= 1, got {args.points}")
    path = Path(args.json) if args.json else DATA / (
        "vesicle_domain.json" if args.seed == DEFAULT_SEED
        else f"vesicle_domain_seed{args.seed}.json")
    if not path.parent.is_dir():
        ap.error(f"--json: folder {path.parent} does not exist")
    load_map()
    commit = solver_commit()
    old = {}
    if path.exists():
        data = json.loads(path.read_text())
        if commit is not None and data.get("git_commit") == commit:
            old = {tuple(r["point"]): r for r in data.get("rows", [])}
    rows = []

    def save(**more) -> None:
        write_json(path, {"seed": args.seed, "domain": DOMAIN, "git_commit": commit, **more,
                          "rows": rows}, indent=1, sort_keys=False)

    print(f"{'nu':>6} {'r':>6} {'Ca_B':>7} {'s':>6} {'status':>14} {'class':>9}  seed", flush=True)
    for point in draw(args.points, args.seed):
        row = old.get(point) or solve_point(*point)
        rows.append(row)
        save()
        print(f"{point[0]:6.4f} {point[1]:6.4f} {point[2]:7.2f} {row['seconds']:6.1f} "
              f"{row['status']:>14} {row['shape_class'] or '-':>9}  {row['seed']}", flush=True)
    summary = summarise(rows)
    save(provenance=provenance(), machine=machine(), summary=summary)
    return 0 if print_summary(summary) else 1


if __name__ == "__main__":
    from bench_store import machine, run_script

    run_script(main)
