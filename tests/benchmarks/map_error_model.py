"""The distribution of the solution map's error in units of its own error bar, for the
likelihood of ``vesicle-tube infer``'s posterior (correlations.infer.MAP_ERROR_MODEL).

Data: direct BEM solves against the map's V/U and ℓ at the same (ν, λ/λc, Ca_B), from two
independent samples: docs/data/map_offgrid.json (tests/benchmarks/map_offgrid.py: points off the
map's nodes, λ/λc ≤ 0.95) and the converged points of docs/data/infer_truth.json
(tests/benchmarks/infer_truth.py: uniform over the map's whole domain, λ/λc up to 0.98, nodes
not avoided). Each residual (map − direct) is divided by the map's error bar at that point; the
V/U and ℓ residuals are pooled. A single Gaussian fits them poorly (most errors are a tenth of
the bar, a few reach twice it), so a mixture of two zero-mean Gaussians (weight, width in bars)
is fitted by maximum likelihood (Nelder-Mead on the weight's logit and the widths' logs).

``--fold K --folds N`` leaves out the truth points whose index is K modulo N: the model the
calibration (tests/benchmarks/infer_calibration.py) uses for those points, so that no point is
judged by a model fitted to its own error. Prints the quantiles of |error|/bar, both fits and
their log-likelihoods. Seconds. Run: ``.venv/bin/python tests/benchmarks/map_error_model.py``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

DATA = Path(__file__).resolve().parents[2] / "docs" / "data"
OFFGRID = DATA / "map_offgrid.json"
TRUTH = DATA / "infer_truth.json"
QUANTITIES = ("V_over_U", "ell")


def offgrid_residuals(path=OFFGRID) -> list[float]:
    data = json.loads(Path(path).read_text())
    out = []
    for q in QUANTITIES:
        for p in data["points"]:
            m = p["map"][q]
            if p["direct"].get("success") and m["value"] is not None and m["error"]:
                out.append((m["value"] - p["direct"][q]) / m["error"])
    return out


def truth_residuals(path=TRUTH, leave_out=None) -> list[float]:
    """Residuals at the converged truth points; ``leave_out(index)`` True drops a point."""
    from correlations.solution_map import load_map, query_map
    m = load_map()
    out = []
    for p in json.loads(Path(path).read_text())["points"]:
        if not p["success"] or (leave_out is not None and leave_out(p["index"])):
            continue
        q = query_map(p["nu"], p["lam_ratio"], p["ca_b"], map=m)
        for k in QUANTITIES:
            v = q.quantities[k]
            if v.value is not None and v.error:
                out.append((v.value - p[k]) / v.error)
    return out


def residuals(fold: int | None = None, folds: int = 2) -> np.ndarray:
    """Both samples' residuals; with ``fold``, the truth points of that fold left out."""
    leave_out = None if fold is None else (lambda i: i % folds == fold)
    return np.array(offgrid_residuals() + truth_residuals(leave_out=leave_out))


def fit_mixture(z: np.ndarray) -> tuple:
    """((1 - w, s1), (w, s2)) maximising the likelihood of z, and that log-likelihood."""
    from scipy.optimize import minimize

    def nll(t):
        w, s1, s2 = 1 / (1 + math.exp(-t[0])), math.exp(t[1]), math.exp(t[2])
        pdf = ((1 - w) * np.exp(-0.5 * (z / s1)**2) / s1 + w * np.exp(-0.5 * (z / s2)**2) / s2)
        return -float(np.sum(np.log(pdf / math.sqrt(2 * math.pi))))

    r = minimize(nll, [math.log(0.1 / 0.9), math.log(0.1), math.log(0.4)], method="Nelder-Mead")
    w, s1, s2 = 1 / (1 + math.exp(-r.x[0])), math.exp(r.x[1]), math.exp(r.x[2])
    return ((1 - w, s1), (w, s2)), -r.fun


def error_model(fold: int | None = None, folds: int = 2) -> tuple:
    """The fitted mixture, rounded as MAP_ERROR_MODEL stores it (two decimals)."""
    (a, b), _ = fit_mixture(residuals(fold, folds))
    return tuple((round(w, 2), round(s, 2)) for w, s in (a, b))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fold", type=int, help="leave out the truth points of this fold")
    ap.add_argument("--folds", type=int, default=2, help="number of folds (default 2)")
    args = ap.parse_args(argv)
    z = residuals(args.fold, args.folds)
    q = np.quantile(np.abs(z), [0.5, 0.68, 0.95])
    print(f"{z.size} residuals (V/U and ell) in units of the map's error bar: |error|/bar "
          f"50 % {q[0]:.3f}, 68 % {q[1]:.3f}, 95 % {q[2]:.3f}, max {np.abs(z).max():.3f}")
    sd = float(np.std(z))
    single = float(np.sum(-0.5 * (z / sd)**2 - math.log(sd * math.sqrt(2 * math.pi))))
    print(f"one Gaussian: sd {sd:.3f} bar, log-likelihood {single:.1f}")
    (a, b), loglik = fit_mixture(z)
    print(f"two Gaussians: weight {a[0]:.3f} sd {a[1]:.3f} bar + weight {b[0]:.3f} sd "
          f"{b[1]:.3f} bar, log-likelihood {loglik:.1f}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_store import run_script
    run_script(main)
