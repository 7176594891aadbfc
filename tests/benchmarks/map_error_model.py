"""The distribution of the solution map's error in units of its own error bar, for the
likelihood of ``vesicle-tube infer``'s posterior (correlations.infer.MAP_ERROR_MODEL).

Data: direct BEM solves against the map's V/U and ℓ at the same (ν, λ/λc, Ca_B), from two
independent samples: docs/data/map_offgrid.json (tests/benchmarks/map_offgrid.py: points off the
map's nodes, λ/λc ≤ 0.95) and the converged points of docs/data/infer_truth.json
(tests/benchmarks/infer_truth.py: uniform over the map's whole domain, λ/λc up to 0.98, nodes
not avoided). Each residual (map − direct) is divided by the map's error bar at that point. A
single Gaussian fits them poorly (most errors are a tenth of the bar, a few reach twice it),
and the errors of V/U and ℓ at one point are large or small together (|z_V| and |z_ℓ| are
correlated; both above 0.3 bar at about five times the rate independence gives), so the model
is a mixture over points: with weight w_b a "poor" point whose two errors are independent
Gaussians of width s_b, else a "good" point whose errors are each a mixture of two Gaussians
(weight q of width s_2, else s_1). Its five parameters are fitted by maximum likelihood
(Nelder-Mead on logits and logs, from three starts); the script prints it against the
per-value mixture of two Gaussians (the same for V/U and ℓ, independent), whose fit it beats
by about 34 in log-likelihood with three parameters more.

``--fold K --folds N`` leaves out the truth points whose index is K modulo N: the model the
calibration (tests/benchmarks/infer_calibration.py) uses for those points, so that no point is
judged by a model fitted to its own error. Prints the quantiles of |error|/bar, the fits and
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


def offgrid_residuals(path=OFFGRID) -> list[list]:
    """Per off-grid point, its (V/U, ℓ) residuals in bars (NaN where the map has no value)."""
    out = []
    for p in json.loads(Path(path).read_text())["points"]:
        if p["direct"].get("success"):
            m = p["map"]
            out.append([(m[q]["value"] - p["direct"][q]) / m[q]["error"]
                        if m[q]["value"] is not None and m[q]["error"] else math.nan
                        for q in QUANTITIES])
    return out


def truth_residuals(path=TRUTH, leave_out=None) -> list[list]:
    """Per converged truth point, its (V/U, ℓ) residuals in bars; ``leave_out(index)`` True
    drops a point."""
    from correlations.solution_map import load_map, query_map
    m = load_map()
    out = []
    for p in json.loads(Path(path).read_text())["points"]:
        if not p["success"] or (leave_out is not None and leave_out(p["index"])):
            continue
        q = query_map(p["nu"], p["lam_ratio"], p["ca_b"], map=m).quantities
        out.append([(q[k].value - p[k]) / q[k].error if q[k].value is not None and q[k].error
                    else math.nan for k in QUANTITIES])
    return out


def residuals(fold: int | None = None, folds: int = 2) -> np.ndarray:
    """Both samples' residuals, one row (V/U, ℓ) per point, rows without a value dropped;
    with ``fold``, the truth points of that fold left out."""
    leave_out = None if fold is None else (lambda i: i % folds == fold)
    z = np.array(offgrid_residuals() + truth_residuals(leave_out=leave_out))
    return z[np.isfinite(z).any(axis=1)]


def log_likelihood(z: np.ndarray, model) -> float:
    """Log-likelihood of the residual rows ``z`` (NaN: no value, left out) under an error model
    of correlations.posterior: ((class weight, ((weight, sd), ...)), ...)."""
    ok = np.isfinite(z)
    zz = np.where(ok, z, 0.0)
    total = 0.0
    for weight, parts in model:
        value = sum(w * np.exp(-0.5 * (zz / s)**2) / (s * math.sqrt(2 * math.pi))
                    for w, s in parts)
        total = total + weight * np.where(ok, value, 1.0).prod(axis=1)
    return float(np.sum(np.log(total)))


def _logit(p: float) -> float:
    return math.log(p / (1 - p))


def _sigmoid(t: float) -> float:
    return 1 / (1 + math.exp(-t))


def two_level(t) -> tuple:
    """The model of the module docstring from its parameters (logit w_b, logit q, log s_1,
    log s_2, log s_b)."""
    wb, q = _sigmoid(t[0]), _sigmoid(t[1])
    s1, s2, sb = np.exp(t[2:5])
    return ((1 - wb, ((1 - q, s1), (q, s2))), (wb, ((1.0, sb),)))


def per_value(t) -> tuple:
    """The per-value mixture of two Gaussians (logit q, log s_1, log s_2), one class."""
    q = _sigmoid(t[0])
    return ((1.0, ((1 - q, math.exp(t[1])), (q, math.exp(t[2])))),)


def fit(z: np.ndarray, family, starts) -> tuple:
    """The model of ``family`` maximising :func:`log_likelihood` over the ``starts``, and its
    log-likelihood."""
    from scipy.optimize import minimize
    best = min((minimize(lambda t: -log_likelihood(z, family(t)), t0, method="Nelder-Mead",
                         options={"maxiter": 20000, "maxfev": 20000}) for t0 in starts),
               key=lambda r: r.fun)
    return family(best.x), -best.fun


TWO_LEVEL_STARTS = [[_logit(0.05), _logit(0.2), math.log(0.05), math.log(0.2), math.log(0.7)],
                    [_logit(0.12), _logit(0.3), math.log(0.1), math.log(0.3), math.log(1.0)],
                    [_logit(0.03), _logit(0.1), math.log(0.08), math.log(0.5), math.log(1.2)]]
PER_VALUE_STARTS = [[_logit(0.1), math.log(0.1), math.log(0.4)]]


def _rounded(model) -> tuple:
    return tuple((round(float(weight), 3), tuple((round(float(w), 3), round(float(s), 3))
                                                 for w, s in parts))
                 for weight, parts in model)


def error_model(fold: int | None = None, folds: int = 2) -> tuple:
    """The fitted two-level model, rounded as MAP_ERROR_MODEL stores it (three decimals)."""
    return _rounded(fit(residuals(fold, folds), two_level, TWO_LEVEL_STARTS)[0])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fold", type=int, help="leave out the truth points of this fold")
    ap.add_argument("--folds", type=int, default=2, help="number of folds (default 2)")
    args = ap.parse_args(argv)
    z = residuals(args.fold, args.folds)
    flat = np.abs(z[np.isfinite(z)])
    q = np.quantile(flat, [0.5, 0.68, 0.95])
    both = np.isfinite(z).all(axis=1)
    big = np.abs(z[both]) > 0.3
    print(f"{len(z)} points, {flat.size} residuals (V/U and ell) in units of the map's error "
          f"bar: |error|/bar 50 % {q[0]:.3f}, 68 % {q[1]:.3f}, 95 % {q[2]:.3f}, max "
          f"{flat.max():.3f}")
    print(f"both above 0.3 bar at {big.all(axis=1).mean():.1%} of the {both.sum()} points "
          f"with both; independence gives {big[:, 0].mean() * big[:, 1].mean():.1%}")
    sd = float(np.std(flat))
    print(f"one Gaussian: sd {sd:.3f} bar, log-likelihood "
          f"{log_likelihood(z, ((1.0, ((1.0, sd),)),)):.1f}")
    for name, family, starts in (("per value", per_value, PER_VALUE_STARTS),
                                 ("two-level", two_level, TWO_LEVEL_STARTS)):
        model, loglik = fit(z, family, starts)
        print(f"{name}: {_rounded(model)}, log-likelihood {loglik:.1f}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from bench_store import run_script
    run_script(main)
