"""Calibration of ``vesicle-tube infer``'s uncertainty against direct BEM solutions.

Truth: the converged points of docs/data/infer_truth.json (tests/benchmarks/infer_truth.py:
steady vesicles solved directly by the BEM at random (ν, λ/λc, Ca_B) of the map's domain, not
taken from the map). At each relative precision p (0.1 % and 2 %) every truth's V/U and ℓ are
measured with Gaussian noise of p times their value (numpy default_rng, seed SEED + index), the
measurement's error is stated as p times the measured value, and
:func:`correlations.infer.infer_map` is called at the truth's Ca_B (known, as with η and κ
given) with each uncertainty method. The posterior's model of the map's own error
(correlations.infer.MAP_ERROR_MODEL) is fitted partly to these truths
(tests/benchmarks/map_error_model.py), so each truth is judged by the model fitted without its
own fold (``--folds`` N, default 2: the truths whose index is k modulo N form fold k): a
cross-fitted, out-of-sample calibration of the shipped procedure. A truth is covered at a level when its ν (or λ) lies in
the reported interval: for the posterior its 68 % and 95 % intervals, for the linearisation
value ± error and ± 2 error. Calibrated intervals cover 68 % and 95 % of the truths; the
acceptance is 60-80 % and at least 90 %.

Writes docs/data/infer_calibration.json (parameters, the coverage table, every case with its
intervals and the seconds it took) atomically and prints the table. About 30 minutes.
Run: ``.venv/bin/python tests/benchmarks/infer_calibration.py``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
TRUTH = ROOT / "docs" / "data" / "infer_truth.json"
OUT = ROOT / "docs" / "data" / "infer_calibration.json"
PRECISIONS = (0.001, 0.02)
SEED = 11


def intervals(q, method: str) -> dict:
    """{level: (low, high)} that the method reports for one quantity (for the posterior, its
    linearised fallback's value ± error and ± 2 error where it reports no interval)."""
    if method == "posterior" and q.low is not None:
        return {0.68: (q.low, q.high), 0.95: (q.low95, q.high95)}
    return {0.68: (q.value - q.error, q.value + q.error),
            0.95: (q.value - 2 * q.error, q.value + 2 * q.error)}


def run_case(truth: dict, precision: float, method: str, seed: int) -> dict:
    from correlations.infer import infer_map
    rng = np.random.default_rng(seed)
    vu = truth["V_over_U"] * (1 + precision * rng.standard_normal())
    ell = truth["ell"] * (1 + precision * rng.standard_normal())
    start = time.perf_counter()
    r = infer_map(vu, ell, precision * vu, precision * ell, ca_b=truth["ca_b"],
                  uncertainty=method)
    row = {"index": truth["index"], "nu": truth["nu"], "lam": truth["lam"],
           "lam_ratio": truth["lam_ratio"], "ca_b": truth["ca_b"], "V_over_U": vu, "ell": ell,
           "status": r.status.value, "seconds": time.perf_counter() - start,
           "degenerate": any(n.startswith("degenerate") for n in r.notes)}
    for name in ("nu", "lam"):
        q = r.quantities.get(name) if r.consistent else None
        if q is None or q.error is None:
            row[name + "_intervals"] = None
            row[name + "_covered"] = {"0.68": False, "0.95": False}
            continue
        iv = intervals(q, method)
        row["fallback"] = method == "posterior" and q.low is None
        row[name + "_value"] = q.value
        row[name + "_intervals"] = {str(k): v for k, v in iv.items()}
        row[name + "_covered"] = {str(k): bool(lo <= truth[name] <= hi)
                                  for k, (lo, hi) in iv.items()}
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--truth", default=str(TRUTH), help="truth file (default %(default)s)")
    ap.add_argument("--out", default=str(OUT), help="results file (default %(default)s)")
    from correlations.infer import UNCERTAINTY_METHODS as METHODS
    ap.add_argument("--methods", nargs="+", choices=METHODS, default=list(METHODS),
                    help="uncertainty methods to calibrate (default: all)")
    ap.add_argument("--folds", type=int, default=2,
                    help="folds of the cross-fitted map error model (default 2)")
    args = ap.parse_args(argv)
    if args.folds < 2:
        ap.error(f"--folds: {args.folds} is not >= 2")
    from lubrication.io import provenance, write_json
    out = Path(args.out)
    if not out.parent.is_dir():
        ap.error(f"--out: folder {out.parent} does not exist")
    truths = [p for p in json.loads(Path(args.truth).read_text())["points"] if p["success"]]
    if not truths:
        ap.error(f"--truth: {args.truth} holds no converged point")
    import correlations.infer
    from map_error_model import error_model
    models = {k: error_model(k, args.folds) for k in range(args.folds)}
    print("map error models without each fold:", models, flush=True)

    def judged(t, precision, method):
        correlations.infer.MAP_ERROR_MODEL = models[t["index"] % args.folds]
        return run_case(t, precision, method, SEED + t["index"])

    table, cases = [], []
    for precision in PRECISIONS:
        for method in args.methods:
            rows = [judged(t, precision, method) for t in truths]
            cases += [{"precision": precision, "method": method, **r} for r in rows]
            entry = {"precision": precision, "method": method, "cases": len(rows),
                     "median_s": float(np.median([r["seconds"] for r in rows])),
                     "max_s": float(max(r["seconds"] for r in rows)),
                     "inconsistent": sum(r["status"] != "consistent" for r in rows),
                     "fallback": sum(bool(r.get("fallback")) for r in rows)}
            for name in ("nu", "lam"):
                for level in ("0.68", "0.95"):
                    entry[f"{name}_{level}"] = float(np.mean([r[name + "_covered"][level]
                                                              for r in rows]))
            table.append(entry)
            print(f"p = {precision:.1%}, {method:9s}: nu covered {entry['nu_0.68']:.0%} (68 %), "
                  f"{entry['nu_0.95']:.0%} (95 %); lam {entry['lam_0.68']:.0%}, "
                  f"{entry['lam_0.95']:.0%}; {entry['inconsistent']} inconsistent; median "
                  f"{entry['median_s']:.2f} s, max {entry['max_s']:.2f} s per cell",
                  flush=True)
    truth = Path(args.truth).resolve()
    write_json(out, {"description": __doc__.splitlines()[0],
                     "truth": str(truth.relative_to(ROOT)) if truth.is_relative_to(ROOT)
                     else str(truth),
                     "precisions": PRECISIONS, "methods": args.methods, "seed": SEED,
                     "folds": args.folds,
                     "error_models": {str(k): v for k, v in models.items()},
                     "coverage": table, "cases": cases, "provenance": provenance()},
               indent=1)
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_store import run_script
    run_script(main)
