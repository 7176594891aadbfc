"""Cost of ONE BEM evaluation of the steady vesicle operator, this tree against a baseline
revision (prints a table; not a test: timings depend on the machine and its load).

Run with ``python tests/benchmarks/bench_evaluation.py [--baseline REV] [--rounds 2]
[--threads 1]``.

Shapes (fixed, so that only the operator is compared): the lubrication seed
(:func:`bem.vesicle.lubrication_seed`, Ca_B = 50) at (ν, λ) = (0.9, 1.0) with 32 modes (uniform
density), (0.61, 1.39) with 40 modes and (0.6, 1.94) with 64 modes ("bend" density), each
evaluated by ``VesicleOperator(nu, lam, 50, vesicle_discretisation(N), seed)`` at
``op.curve(seed.modes)``. The seeds are made once, here, and handed to both sides.

The baseline (default: the last commit before the quadrature speed-ups) is exported with
``git archive`` to a temporary directory; each side runs in its own interpreter (numba compiled
and warm before timing, single-threaded BLAS as in the solver, numba's default threads) and
reports, per shape, the minimum of ``--repeats`` evaluation times and the outputs V/U,
Δp⁺R0/(ηU), γ_max (max of the tension on 401 points) and the residual. The two sides take turns
for ``--rounds`` rounds (A/B under the same load) and the minima over the rounds are printed.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: the last commit before the quadrature speed-ups (fixed self-panel rule, ring Stokeslet)
BASELINE = "0e10f54"

SHAPES = [(0.9, 1.0, 32, "uniform"), (0.61, 1.39, 40, "bend"), (0.6, 1.94, 64, "bend")]
CA_B = 50.0

_CHILD = r"""
import json, math, pickle, sys, time
import numpy as np
from bem.membrane import tension_profile
from bem.threads import single_threaded_blas
from bem.vesicle import VesicleOperator, vesicle_discretisation
shapes, seeds, repeats, CA_B = pickle.load(open(sys.argv[1], "rb"))
rows = []
for (nu, lam, n, _), seed in zip(shapes, seeds):
    op = VesicleOperator(nu, lam, CA_B, vesicle_discretisation(n), seed)
    curve = op.curve(seed.modes)
    with single_threaded_blas():
        st = op.evaluate(curve)                      # compiles numba on the first shape
        best = math.inf
        for _ in range(repeats):
            t0 = time.perf_counter()
            op.evaluate(curve)
            best = min(best, time.perf_counter() - t0)
    gmax = float(np.max(tension_profile(curve, st["g"], np.linspace(0.0, 1.0, 401))[0]))
    rows.append({"modes": n, "panels": op.disc.n_panels, "eval_s": best, "V": st["V"],
                 "dp": st["dp"] * lam, "gmax": gmax, "residual": st["residual"]})
print(json.dumps(rows))
"""


def make_seeds() -> list:
    sys.path.insert(0, str(ROOT))
    from bem.vesicle import lubrication_seed
    return [lubrication_seed(nu, lam, CA_B, n, dens)[0] for nu, lam, n, dens in SHAPES]


def export(rev: str, into: str) -> str:
    """``git archive`` of ``rev`` unpacked into ``into``; returns the directory."""
    os.makedirs(into, exist_ok=True)
    archive = subprocess.run(["git", "archive", rev], cwd=ROOT, check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", into], input=archive, check=True)
    return into


def run_side(path: str, seeds_file: str, threads: int | None) -> list:
    env = dict(os.environ, PYTHONPATH=path)
    if threads:
        env["NUMBA_NUM_THREADS"] = str(threads)
    out = subprocess.run([sys.executable, "-c", _CHILD, seeds_file], cwd=path, env=env,
                         check=True, capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default=BASELINE,
                    help=f"git revision to compare with (default {BASELINE})")
    ap.add_argument("--repeats", type=int, default=5,
                    help="evaluations timed per shape and round; the minimum is kept (default 5)")
    ap.add_argument("--rounds", type=int, default=2,
                    help="alternating baseline/current rounds (default 2)")
    ap.add_argument("--threads", type=int, default=None,
                    help="numba threads of both sides (default: numba's, one per core); on a "
                         "loaded machine one thread gives the steadier comparison")
    ap.add_argument("--json", help="also write the rows to this JSON file")
    args = ap.parse_args(argv)
    seeds = make_seeds()
    with tempfile.TemporaryDirectory() as tmp:
        seeds_file = os.path.join(tmp, "seeds.pkl")
        with open(seeds_file, "wb") as fh:
            pickle.dump((SHAPES, seeds, args.repeats, CA_B), fh)
        base_dir = export(args.baseline, os.path.join(tmp, "base"))
        sides = {"before": base_dir, "after": str(ROOT)}
        best = {}
        for _ in range(args.rounds):
            for name, path in sides.items():
                for i, row in enumerate(run_side(path, seeds_file, args.threads)):
                    old = best.get((name, i))
                    if old is None or row["eval_s"] < old["eval_s"]:
                        best[(name, i)] = row
    print(f"one VesicleOperator.evaluate, Ca_B = {CA_B:g}; before = {args.baseline}, after = "
          f"this tree; min of {args.repeats} x {args.rounds} rounds; numba threads "
          f"{args.threads or 'default'}; "
          f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print(f"{'nu':>5} {'lam':>5} {'N':>3} {'panels':>6} {'before ms':>9} {'after ms':>9} "
          f"{'speed-up':>8} {'dV/U':>8} {'d dp':>8} {'d g_max':>8} {'d res':>8}")
    rows = []
    for i, (nu, lam, n, _) in enumerate(SHAPES):
        b, a = best[("before", i)], best[("after", i)]
        rel = {k: abs(a[k] / b[k] - 1.0) for k in ("V", "dp", "gmax")}
        dres = abs(a["residual"] - b["residual"])
        rows.append({"nu": nu, "lam": lam, "before": b, "after": a, "rel": rel, "dres": dres})
        print(f"{nu:5.2f} {lam:5.2f} {n:3d} {a['panels']:6d} {b['eval_s'] * 1e3:9.1f} "
              f"{a['eval_s'] * 1e3:9.1f} {b['eval_s'] / a['eval_s']:8.2f} {rel['V']:8.1e} "
              f"{rel['dp']:8.1e} {rel['gmax']:8.1e} {dres:8.1e}")
    print("d: relative change of V/U, dp+R0/(eta U), gamma_max; absolute change of the residual")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
