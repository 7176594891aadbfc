"""Direct BEM vesicle solves at random points of the solution map's domain: a reference
dataset to calibrate the inverse estimate ``vesicle-tube infer`` (correlations/infer.py).

Run with ``python tests/benchmarks/infer_truth.py [--points N] [--seed S] [--out FILE]
[--max-time SECONDS]`` (defaults 128 points, seed 2027, docs/data/infer_truth.json, 240 s);
on 2 shared cores, e.g. ``NUMBA_NUM_THREADS=1 nice -n 10 .venv/bin/python
tests/benchmarks/infer_truth.py``.

Sampling: ``numpy.random.default_rng(seed)`` draws, point after point, ν uniform, λ/λc uniform
and log Ca_B uniform over the ranges of the shipped map's grid (:func:`map_ranges`: the map's
ν nodes, its BEM λ/λc nodes, its Ca_B nodes, read from correlations/data/solution_map.json, not
written here; they are stored in the output). ν and λ/λc are rounded to 4 decimals, Ca_B to 4
significant digits (the rounded values are the inputs solved). The draw of point i does not
depend on N, so a larger ``--points`` extends a finished file. The points need not be off the
map's nodes (unlike tests/benchmarks/map_offgrid.py, whose Python-``random`` draw is in a fixed
box and skips points near nodes).

Solves: each point by :func:`bem.vesicle.solve_vesicle` (λ given as λ/λc) at its default
options, as ``vesicle-tube bem vesicle`` calls it, with ``max_time`` per attempt. A failed
default solve is retried once (not after a time-out, whose retry would only spend the budget
again) with ``max_modes`` = MAX_MODES and the solver's own seeding path flipped: above
NEAR_CRITICAL the default ``continuation`` reversed, below it the default ``valley`` reversed.
The retry starts from the solver's own seeds, never from a map or map-build shape: the
results are independent of the map. Each point records the options of every attempt and of the
one that produced its numbers; a point whose attempts all failed records no numbers, only
``success`` false and the messages.

Per point: index (from 0; the progress lines count from 1), ν, λ, λc, λ/λc, Ca_B, success,
V/U, ℓ = L/R (full axial length), Δp⁺R0/(ηU), minimum film h/R, the solver's error estimates
(absolute, of V/U, Δp⁺R0/(ηU), γ_max) and steady residual, shape class, modes, BIE solves,
seconds, options and provenance (git commit, package versions, date, and the solver sources
modified against that commit at the start of the run). The file is written atomically after
every point and the run resumes: points already in the file (success or failure) are not
solved again; a file drawn with another seed or other ranges is refused. Progress goes to
stderr, one line per point. Not a test: seconds to minutes per point.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "data" / "infer_truth.json"
SEED = 2027
POINTS = 128
MAX_TIME_S = 240.0
#: outputs recorded from a converged solve (names of :class:`bem.results.VesicleResult`)
OUTPUTS = ("V_over_U", "ell", "dp_plus_R0", "film_min")
DESCRIPTION = ("steady vesicles solved directly by the BEM (bem.vesicle.solve_vesicle, not the "
               "solution map) at random points of the map's domain; reference for calibrating "
               "vesicle-tube infer")


def map_ranges(m) -> dict:
    """The sampling box of the map ``m``: [min, max] of its ν nodes, of its BEM λ/λc nodes and
    of its Ca_B nodes (its BEM domain; the lubrication-only λ/λc nodes above lie outside)."""
    grid = m.grid
    if "bem" not in grid.get("methods", ()):
        raise ValueError(f"the map {m.source!r} has no BEM grid")
    nus = [float(v) for v in grid["nu"]]
    ratios = [float(v) for v in grid["lam_ratio"]["bem"]]
    cas = [float(v) for v in grid["ca_b"]]
    return {"nu": [min(nus), max(nus)], "lam_ratio": [min(ratios), max(ratios)],
            "ca_b": [min(cas), max(cas)]}


def draw(n: int, ranges: dict, seed: int) -> list[tuple[float, float, float]]:
    """``n`` points (ν, λ/λc, Ca_B): ν and λ/λc uniform, Ca_B log-uniform in ``ranges``,
    from ``numpy.random.default_rng(seed)``, three draws per point in that order (point i is
    the same for every n > i); rounded as the module docstring says."""
    rng = np.random.default_rng(seed)
    (n0, n1), (r0, r1), (c0, c1) = ranges["nu"], ranges["lam_ratio"], ranges["ca_b"]
    out = []
    for _ in range(n):
        nu = round(float(rng.uniform(n0, n1)), 4)
        r = round(float(rng.uniform(r0, r1)), 4)
        ca = float(f"{math.exp(rng.uniform(math.log(c0), math.log(c1))):.4g}")
        out.append((nu, r, ca))
    return out


def retry_options(nu: float, lam_ratio: float) -> dict:
    """Options of the one retry (module docstring): the most modes and the default seeding path
    reversed (continuation above NEAR_CRITICAL, valley below), both defaults as
    :func:`bem.vesicle.solve_vesicle` derives them."""
    from bem.vesicle import MAX_MODES, NEAR_CRITICAL
    from bem.vesicle.ladder import LONG_VESICLE, RUNG_MAX_LENGTH
    from lubrication.geometry import critical_length
    ell = float(critical_length(nu)) * lam_ratio        # the solver's estimated length
    if lam_ratio > NEAR_CRITICAL:
        return {"max_modes": MAX_MODES, "continuation": not ell <= RUNG_MAX_LENGTH}
    return {"max_modes": MAX_MODES, "valley": not ell > LONG_VESICLE}


def _attempt(nu: float, r: float, ca: float, options: dict, max_time: float):
    """One solve: (result or None, record of the attempt)."""
    from bem.vesicle import solve_vesicle
    t0 = time.perf_counter()
    try:
        res = solve_vesicle(nu, lam_ratio=r, ca_b=ca, max_time=max_time, **options)
    except Exception as exc:          # a raised error is a failed point, not the end of the run
        return None, {"options": options, "success": False, "seconds":
                      round(time.perf_counter() - t0, 1),
                      "message": f"{type(exc).__name__}: {exc}"}
    return res, {"options": options, "success": bool(res.success), "status": res.status.value,
                 "seconds": round(time.perf_counter() - t0, 1), "message": res.message,
                 "modes": int(res.modes.size), "bie_solves": res.bie_solves}


def _modified_sources() -> list[str]:
    """Solver sources (bem/, lubrication/, correlations/) modified or untracked against the
    git commit, as ``git status --porcelain`` lists them ([] outside a checkout)."""
    try:
        git = subprocess.run(["git", "status", "--porcelain", "--", "bem", "lubrication",
                              "correlations"], cwd=ROOT, capture_output=True, text=True,
                             timeout=10, check=False)
    except (OSError, subprocess.SubprocessError):
        return []
    return [line.strip() for line in git.stdout.splitlines() if line.strip()]


def solve_point(index: int, nu: float, r: float, ca: float, max_time: float,
                run_provenance: dict) -> dict:
    """The record of point ``index``: the default solve, one retry if it failed (not after a
    time-out), numbers only from a converged attempt."""
    from lubrication.geometry import critical_confinement
    from lubrication.io import clean_json, provenance
    from lubrication.results import Status, status_of
    attempts = []
    res, rec = _attempt(nu, r, ca, {}, max_time)
    attempts.append(rec)
    if not rec["success"]:
        if status_of(rec) is Status.TIME_LIMIT:
            rec["retry"] = "none: the default solve stopped at the time limit"
        else:
            res, rec = _attempt(nu, r, ca, retry_options(nu, r), max_time)
            attempts.append(rec)
    ok = bool(rec["success"])
    lam_c = float(critical_confinement(nu))
    row = {"index": index, "nu": nu, "lam": r * lam_c, "lam_c": lam_c, "lam_ratio": r,
           "ca_b": ca, "success": ok, "max_time_s": max_time}
    if ok:
        d = res.to_dict(shape=False)
        row.update({q: d[q] for q in OUTPUTS})
        row["error_estimate"] = clean_json(dict(res.error_estimate))
        row.update({"residual": d["residual"], "shape_class": d["shape_class"],
                    "modes": int(res.modes.size), "seed": res.seed})
    else:
        row.update(dict.fromkeys(OUTPUTS))
        row.update({"error_estimate": None, "residual": None, "shape_class": None,
                    "modes": None, "seed": None})
    row.update({"message": rec["message"], "options": rec["options"] if ok else None,
                "attempts": attempts,
                "seconds": round(sum(a["seconds"] for a in attempts), 1),
                "bie_solves": sum(a.get("bie_solves", 0) for a in attempts),
                "provenance": {**provenance(), "source_modified_at_run_start":
                               run_provenance["source_modified"]}})
    return row


def _progress(row: dict, n: int) -> str:
    head = (f"[{row['index'] + 1:3d}/{n}] nu={row['nu']:.4f} lam/lam_c={row['lam_ratio']:.4f} "
            f"Ca_B={row['ca_b']:<7g}")
    if row["success"]:
        how = "default" if not row["options"] else "retry " + json.dumps(row["options"])
        out = (f"ok  V/U={row['V_over_U']:.6f} ell={row['ell']:.4f} "
               f"dp+R0={row['dp_plus_R0']:.5g} film={row['film_min']:.3e} "
               f"({how}, {row['modes']} modes)")
    else:
        out = "FAILED  " + " | ".join(a["message"] for a in row["attempts"])
    return f"{head}  {out}  {row['seconds']:.1f} s"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=POINTS,
                    help=f"number of random points (default {POINTS})")
    ap.add_argument("--seed", type=int, default=SEED,
                    help=f"seed of numpy.random.default_rng (default {SEED})")
    ap.add_argument("--out", default=str(OUT), help="results file (default docs/data/"
                    "infer_truth.json); an existing one is resumed")
    ap.add_argument("--max-time", type=float, default=MAX_TIME_S, dest="max_time",
                    help=f"time limit of each solve attempt [s] (default {MAX_TIME_S:g})")
    args = ap.parse_args(argv)
    if args.points < 1:
        ap.error(f"--points must be >= 1, got {args.points}")
    if args.seed < 0:
        ap.error(f"--seed must be >= 0, got {args.seed}")
    if not (math.isfinite(args.max_time) and args.max_time > 0):
        ap.error(f"--max-time must be a positive number of seconds, got {args.max_time}")
    out_path = Path(args.out)
    if not out_path.parent.is_dir():
        ap.error(f"--out: folder {out_path.parent} does not exist")

    from correlations.solution_map import load_map
    from lubrication.io import provenance, write_json
    m = load_map()
    ranges = map_ranges(m)
    sampling = {"generator": "numpy.random.default_rng", "seed": args.seed,
                "ranges": ranges, "source": f"grid of the shipped map ({m.source})",
                "laws": {"nu": "uniform", "lam_ratio": "uniform", "ca_b": "log-uniform"},
                "rounding": "nu, lam_ratio to 4 decimals; ca_b to 4 significant digits"}
    done: dict[int, dict] = {}
    if out_path.exists():
        try:
            old = json.loads(out_path.read_text())
            old_sampling = old["sampling"]
            rows = old["points"]
        except (ValueError, KeyError, TypeError) as exc:
            ap.error(f"--out: {out_path} is not a results file of this script ({exc})")
        if (old_sampling.get("seed") != args.seed
                or old_sampling.get("ranges") != json.loads(json.dumps(ranges))):
            ap.error(f"--out: {out_path} was drawn with seed {old_sampling.get('seed')} and "
                     f"ranges {old_sampling.get('ranges')}, not seed {args.seed} and ranges "
                     f"{ranges}: choose another file")
        done = {int(p["index"]): p for p in rows}
    points = draw(max(args.points, max(done, default=-1) + 1), ranges, args.seed)
    for i, p in done.items():
        if (p["nu"], p["lam_ratio"], p["ca_b"]) != points[i]:
            ap.error(f"--out: point {i} of {out_path} is not the draw's {points[i]}")

    run_prov = {"source_modified": _modified_sources()}
    solver = {"function": "bem.vesicle.solve_vesicle", "called_as": "solve_vesicle(nu, "
              "lam_ratio=lam_ratio, ca_b=ca_b, max_time=max_time, **options)",
              "default_options": {}, "max_time_s_per_attempt": args.max_time,
              "retry": "once after a failed default solve that did not time out: max_modes "
                       "MAX_MODES and the default continuation (lam_ratio > NEAR_CRITICAL) or "
                       "valley (below) reversed; the options of each result are in 'options'"}
    units = {"V_over_U": "V/U [-]", "ell": "L/R, full axial length [-]",
             "dp_plus_R0": "dp+ R0/(eta U) [-]", "film_min": "smallest gap h/R [-]",
             "error_estimate": "absolute estimated discretisation errors of the solver",
             "residual": "steady residual max|u - V e_x| [U]", "seconds": "wall time [s]"}

    def save() -> None:
        rows = [done[i] for i in sorted(done)]
        ok = sum(r["success"] for r in rows)
        write_json(out_path, {
            "description": DESCRIPTION,
            "script": "tests/benchmarks/infer_truth.py", "sampling": sampling,
            "solver": solver, "units": units,
            "summary": {"points": len(rows), "success": ok, "failed": len(rows) - ok,
                        "seconds": round(sum(r["seconds"] for r in rows), 1)},
            "provenance": provenance(), "points": rows}, indent=1, sort_keys=False)

    def stop(signum, frame):
        raise KeyboardInterrupt
    # a SIGTERM ends the run like Ctrl-C: the file holds every point finished before it
    signal.signal(signal.SIGTERM, stop)
    print(f"infer_truth: {args.points} points, seed {args.seed}; nu {ranges['nu']}, lam/lam_c "
          f"{ranges['lam_ratio']}, Ca_B {ranges['ca_b']} (log); {len(done)} already in "
          f"{out_path}", file=sys.stderr, flush=True)
    t_run = time.perf_counter()
    for i, (nu, r, ca) in enumerate(points[:args.points]):
        if i in done:
            continue
        done[i] = solve_point(i, nu, r, ca, args.max_time, run_prov)
        save()
        print(_progress(done[i], args.points), file=sys.stderr, flush=True)
    if not out_path.exists():
        save()
    rows = [done[i] for i in range(args.points)]
    ok = sum(r["success"] for r in rows)
    print(f"infer_truth: {ok} of {len(rows)} points converged, {len(rows) - ok} failed; "
          f"this run {time.perf_counter() - t_run:.0f} s", file=sys.stderr, flush=True)
    return 0


if __name__ == "__main__":
    from bench_store import run_script

    run_script(main)
