"""The distribution of the solution map's error in units of its own error bar, for the
likelihood of ``vesicle-tube infer``'s posterior (correlations.infer.MAP_ERROR_MODEL).

Data: docs/data/map_offgrid.json (tests/benchmarks/map_offgrid.py): direct BEM solves at random
points off the map's nodes against the map's V/U and ℓ there. Each residual (map − direct) is
divided by the map's error bar at that point; the V/U and ℓ residuals are pooled. A single
Gaussian fits them poorly (most errors are a tenth of the bar, a few reach the bar), so a
mixture of two zero-mean Gaussians (weight, width in bars) is fitted by maximum likelihood
(Nelder-Mead on the weight's logit and the widths' logs). Prints the quantiles of |error|/bar,
both fits and their log-likelihoods. Seconds. Run:
``.venv/bin/python tests/benchmarks/map_error_model.py``.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

OFFGRID = Path(__file__).resolve().parents[2] / "docs" / "data" / "map_offgrid.json"


def residuals(path=OFFGRID) -> np.ndarray:
    data = json.loads(Path(path).read_text())
    out = []
    for q in ("V_over_U", "ell"):
        for p in data["points"]:
            m = p["map"][q]
            if p["direct"].get("success") and m["value"] is not None and m["error"]:
                out.append((m["value"] - p["direct"][q]) / m["error"])
    return np.array(out)


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


def main() -> int:
    z = residuals()
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
