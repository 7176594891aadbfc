"""Speed of one solution-map point query (:func:`correlations.solution_map.query_map`) at
distinct random points of the shipped map, and the throughput of ``vesicle-tube check --no-bem``
on a file of distinct rows (one map query per row), for the working tree and for an earlier
revision of ``correlations/solution_map.py`` (``--before``, default the revision before the
query computed its stencil once for the eight quantities). Target: a query at least 10x faster
than before (<= 0.4 ms on the machine where it took 4 ms). Not a test: timings depend on the
machine (and on what else runs on it: the load average is printed).

The earlier revision is read with ``git show REV:correlations/solution_map.py`` and imported in
its place (in this process as a module of its own; for ``check`` in a child process, as
``correlations.solution_map`` before the command line is imported), so both run against the same
map file and the same rest of the package.

Points: ν uniform in 0.6-0.98, λ/λc uniform in 0.2-0.9999, Ca_B log-uniform in 5-500 (the
box of the shipped map; some land next to holes, where the query stops early). Rows of the
check file: ``name,nu,lam,ca_b,V_over_U,dp_plus_R0`` with ν in 0.6-0.95, λ/λc in 0.5-0.99
(λ = λ/λc · λc(ν), :func:`lubrication.geometry.critical_confinement`), Ca_B in 5-400
log-uniform, V/U = 1 + δ and Δp⁺R0/(ηU) = 4λ(λc²ν^(-2/3) − 1)/δ (the near-critical
asymptotics of Chen et al. 2020, eq:vel2 and eq:asmyp2: plausible values; the verdicts do not
matter here).

``--write-reference`` instead writes the reference of the equality test of
tests/correlations/test_solution_map.py: the earlier revision's full answers (every field of every
:class:`~correlations.solution_map.MapValue`, the rows included) at :func:`reference_points`.

Run with ``python tests/benchmarks/map_query_speed.py [--before REV] [--points 2000]
[--rows 5000] [--skip-check] [--write-reference]``.
"""

from __future__ import annotations

import argparse
import csv
import hashlib
import importlib.util
import json
import math
import os
import platform
import random
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: the revision of correlations/solution_map.py before the query computed its stencil once
BEFORE = "12889ff"
REFERENCE = ROOT / "tests" / "correlations" / "data" / "solution_map_queries.json"
SHIPPED_MAP = ROOT / "correlations" / "data" / "solution_map.json"
TARGET_SPEEDUP = 10.0


def implementation(rev: str | None):
    """The module correlations.solution_map of the working tree (``rev`` None) or of git
    revision ``rev``, imported as a module of its own (relative imports resolve in
    ``correlations``)."""
    if rev is None:
        import correlations.solution_map as current   # lazy: the module under test
        return current
    source = subprocess.run(["git", "show", f"{rev}:correlations/solution_map.py"], cwd=ROOT,
                            check=True, capture_output=True, text=True).stdout
    name = f"correlations._solution_map_{rev}"
    with tempfile.TemporaryDirectory(prefix="map-query-speed-") as folder:
        path = Path(folder) / "solution_map.py"
        path.write_text(source, encoding="utf-8")
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module      # dataclasses look their module up while it executes
        spec.loader.exec_module(module)
    module.DEFAULT_MAP = SHIPPED_MAP       # its own would point into the temporary folder
    return module


def random_points(n: int, seed: int = 1) -> list[tuple[float, float, float]]:
    """``n`` distinct random points in the box of the shipped map (module docstring)."""
    rng = random.Random(seed)
    return [(rng.uniform(0.6, 0.98), rng.uniform(0.2, 0.9999), 5.0 * 100.0 ** rng.random())
            for _ in range(n)]


def ms_per_query(module, points) -> float:
    """Mean wall time of ``module.query_map`` over ``points`` [ms], the map loaded first."""
    m = module.load_map()
    module.query_map(*points[0], map=m)        # the per-map caches of the first query
    t0 = time.perf_counter()
    for p in points:
        module.query_map(*p, map=m)
    return 1e3 * (time.perf_counter() - t0) / len(points)


def write_check_rows(path: Path, n: int, seed: int = 2) -> None:
    """``n`` rows of distinct points (module docstring) as CSV at ``path``."""
    from lubrication.geometry import critical_confinement   # lazy: only the check rows need it
    rng = random.Random(seed)
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f)
        writer.writerow(["name", "nu", "lam", "ca_b", "V_over_U", "dp_plus_R0"])
        for i in range(n):
            nu, ratio = rng.uniform(0.6, 0.95), rng.uniform(0.5, 0.99)
            ca_b = 5.0 * 80.0 ** rng.random()
            lam_c = float(critical_confinement(nu))
            lam, delta = ratio * lam_c, 1.0 - ratio
            dp = 4.0 * lam * (lam_c**2 * nu ** (-2.0 / 3.0) - 1.0) / delta
            writer.writerow([f"r{i}", f"{nu:.12g}", f"{lam:.12g}", f"{ca_b:.12g}",
                             f"{1.0 + delta:.10g}", f"{dp:.10g}"])


#: A child process running the command line with revision ``rev`` of solution_map.py in place of
#: the working tree's (which is never imported there).
_CHILD = """
import sys
sys.path.insert(0, {bench!r})
import correlations
import map_query_speed
module = map_query_speed.implementation({rev!r})
sys.modules["correlations.solution_map"] = correlations.solution_map = module
from correlations.cli import main
sys.exit(main(sys.argv[1:]))
"""


def check_rows_per_s(rev: str | None, csv_path: Path, rows: int) -> tuple[float, int]:
    """Rows per second of ``vesicle-tube check --no-bem --json`` on ``csv_path`` (wall time of
    the whole process, the interpreter's start included), and its exit code."""
    argv = ([shutil.which("vesicle-tube") or str(Path(sys.executable).with_name("vesicle-tube"))]
            if rev is None else
            [sys.executable, "-c", _CHILD.format(bench=str(Path(__file__).parent), rev=rev)])
    t0 = time.perf_counter()
    proc = subprocess.run([*argv, "check", "--no-bem", "--json", str(csv_path)], cwd=ROOT,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                          check=False)
    seconds = time.perf_counter() - t0
    if proc.returncode not in (0, 1):
        raise SystemExit(f"check failed (exit {proc.returncode}): {proc.stderr.strip()}")
    return rows / seconds, proc.returncode


# ----------------------------------------------------------------------------- reference

def reference_points(m, seed: int = 3) -> list[tuple[float, float, float]]:
    """About 2400 query points of map ``m`` for the equality test: uniform in λ/λc and in δ^½
    (dense near λc) over the map's box, on grid nodes (on all three axes, on one or two, and
    within the on-node tolerance), next to every hole, at Ca_B above the largest node (clamped,
    up to and past 1e4), at λ/λc near 1 and at the box's edges, and outside the box."""
    rng = random.Random(seed)
    nus, ratios, cas = m.nus, m.ratios, m.cas

    def nu_():
        return rng.uniform(nus[0], nus[-1])

    def ca_():
        return cas[0] * (cas[-1] / cas[0]) ** rng.random()

    def ratio_():
        return rng.uniform(ratios[0], ratios[-1])

    def near(values, v, spread):
        """A value within ``spread`` grid steps of node ``v`` (inside the grid's range)."""
        i = values.index(v)
        lo, hi = values[max(i - 1, 0)], values[min(i + 1, len(values) - 1)]
        return min(max(v + rng.uniform(-spread, spread) * (hi - lo) / 2, values[0]), values[-1])

    x_lo, x_hi = math.sqrt(1.0 - ratios[-1]), math.sqrt(1.0 - ratios[0])
    points = [(nu_(), ratio_(), ca_()) for _ in range(800)]
    points += [(nu_(), 1.0 - rng.uniform(x_lo, x_hi) ** 2, ca_()) for _ in range(700)]
    points += [(rng.choice(nus), rng.choice(ratios), rng.choice(cas)) for _ in range(200)]
    for _ in range(200):
        p = [nu_(), ratio_(), ca_()]
        for axis in rng.sample(range(3), rng.choice((1, 2))):
            p[axis] = rng.choice((nus, ratios, cas)[axis])
            if rng.random() < 0.3:                 # on the node within its tolerance
                p[axis] *= 1.0 + rng.choice((-1, 1)) * 1e-13
        points.append(tuple(p))
    for h in m.holes:
        for _ in range(3):
            points.append((near(nus, h["nu"], 1.2), near(ratios, h["lam_ratio"], 1.2),
                           near(cas, h["ca_b"], 1.2)))
    for _ in range(120):
        ca = rng.choice((cas[-1] * (1 + 1e-13), cas[-1] * 1.0001, 1e4, 1e4 * (1 + 1e-13),
                         cas[-1] * (1e4 / cas[-1]) ** rng.random()))
        nu = rng.choice((nu_(), rng.choice(nus)))
        points.append((nu, rng.choice((ratio_(), rng.choice(ratios))), ca))
    points += [(nu_(), rng.uniform(0.99, ratios[-1]), ca_()) for _ in range(120)]
    points += [(rng.choice((nus[0], nus[-1], nu_())), rng.choice((ratios[0], ratios[-1])),
                rng.choice((cas[0], cas[-1], ca_()))) for _ in range(40)]
    for _ in range(80):
        p = [nu_(), ratio_(), ca_()]
        axis = rng.randrange(3)
        p[axis] = rng.choice(([rng.uniform(0.4, nus[0] * (1 - 1e-9)),
                               rng.uniform(nus[-1] * (1 + 1e-9), 1.0)],
                              [rng.uniform(0.01, ratios[0] * (1 - 1e-9)),
                               rng.uniform(ratios[-1] * (1 + 1e-9), 0.999999999)],
                              [rng.uniform(0.1, cas[0] * (1 - 1e-9)),
                               rng.uniform(1e4 * (1 + 1e-9), 1e6)])[axis])
        points.append(tuple(p))
    return points


#: the fields of a MapValue in the reference, in this order (``rows``: ``to_dict`` omits them)
FIELDS = ("value", "error", "interpolation_error", "solver_error", "model_error", "methods",
          "rows", "note")


def answer(res) -> list:
    """Every field of every :class:`MapValue` of a query, as :data:`FIELDS` lists in JSON types,
    in the order of ``res.quantities``."""
    return [[*(v.to_dict()[f] for f in FIELDS[:5]), list(v.methods), list(v.rows), v.note]
            for v in res.quantities.values()]


def write_reference(rev: str, path: Path = REFERENCE) -> None:
    """The answers of revision ``rev``'s query_map at :func:`reference_points` of the shipped
    map, as JSON at ``path``. To keep the file small (< 2 MB) each point is a list
    ``[nu, lam_ratio, ca_b, answers]`` and the methods, rows and notes of an answer are indices
    into lists of the distinct ones."""
    module = implementation(rev)
    m = module.load_map()
    tables = {"methods": {}, "rows": {}, "note": {}}
    points = []
    for nu, ratio, ca_b in reference_points(m):
        res = module.query_map(nu, ratio, ca_b, map=m)
        out = answer(res)
        for v in out:
            for i, f in enumerate(FIELDS[5:], start=5):
                key = json.dumps(v[i])
                v[i] = tables[f].setdefault(key, len(tables[f]))
        points.append([nu, ratio, ca_b, out])
    digest = hashlib.sha256(Path(module.DEFAULT_MAP).read_bytes()).hexdigest()
    data = {"what": "query_map answers of the shipped map, for the equality test of "
                    "tests/correlations/test_solution_map.py",
            "made_by": f"python tests/benchmarks/map_query_speed.py --write-reference "
                       f"--before {rev} (correlations/solution_map.py of revision {rev})",
            "python": platform.python_version(), "map_sha256": digest,
            "keys": list(res.quantities), "fields": list(FIELDS),
            **{f: [json.loads(k) for k in t] for f, t in tables.items()}, "points": points}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, separators=(",", ":"), allow_nan=False), encoding="utf-8")
    print(f"{len(points)} points written to {path} ({path.stat().st_size / 2**20:.2f} MB)")


# ----------------------------------------------------------------------------- main

def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--before", default=BEFORE, help=f"git revision (default {BEFORE})")
    p.add_argument("--points", type=int, default=2000, help="distinct query points")
    p.add_argument("--rows", type=int, default=5000, help="rows of the check file")
    p.add_argument("--skip-check", action="store_true", help="time the queries only")
    p.add_argument("--write-reference", action="store_true",
                   help=f"write {REFERENCE.relative_to(ROOT)} with --before and stop")
    args = p.parse_args()
    if args.write_reference:
        write_reference(args.before)
        return 0
    load = os.getloadavg()[0]
    points = random_points(args.points)
    before = ms_per_query(implementation(args.before), points)
    after = ms_per_query(implementation(None), points)
    print(f"query_map, {len(points)} distinct random points of the shipped map "
          f"(load average {load:.1f} on {os.cpu_count()} cores):")
    print(f"  before ({args.before}): {before:.3f} ms per query")
    print(f"  after (working tree): {after:.3f} ms per query ({before / after:.1f}x faster; "
          f"target >= {TARGET_SPEEDUP:g}x)")
    if not args.skip_check:
        folder = Path(tempfile.mkdtemp(prefix="map-query-speed-"))
        try:
            path = folder / "rows.csv"
            write_check_rows(path, args.rows)
            print(f"vesicle-tube check --no-bem --json, {args.rows} rows of distinct points "
                  "(wall time of the process):")
            for label, rev in ((f"before ({args.before})", args.before),
                               ("after (working tree)", None)):
                rate, code = check_rows_per_s(rev, path, args.rows)
                print(f"  {label}: {rate:.0f} rows/s (exit {code})")
        finally:
            shutil.rmtree(folder, ignore_errors=True)
    return 0 if before / after >= TARGET_SPEEDUP else 1


if __name__ == "__main__":
    sys.exit(main())
