"""Default-option BEM vesicle solves against mode-converged values: is the error estimate honest?

Run with ``python tests/benchmarks/default_cases.py [--cases 0.8:1.0,0.7:r0.95] [--json FILE]``
(``r`` marks lam/lam_c instead of lam). For each case the default
:func:`bem.vesicle.solve_vesicle` (Ca_B = 50) is run, then ``mode_convergence``
(``vesicle_modes.py``) solves its shape again at N + 8, N + 16, N + 24 modes (N the default's
fine level) on the density built on the default shape; the last of those, extrapolated with its
own contraction ratio, is the reference. The table gives, per output, the default's value, its
error estimate, the true error (against the reference) and their ratio: honest means
1 <= ratio <= 10. Not a test: minutes per case (2 cores).

The seven cases are the default-option failures of the solver before its consistent ladder:
(0.8, 1.0), (0.7, 1.2), (0.6, 1.5), (0.7, 1.5), (0.9, 0.98 lam_c), (0.7, 0.95 lam_c),
(0.6, 1.94).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from bem.vesicle import MAX_MODES, solve_vesicle
from lubrication.io import provenance, write_json
from vesicle_modes import mode_convergence

SEVEN = "0.8:1.0,0.7:1.2,0.6:1.5,0.7:1.5,0.9:r0.98,0.7:r0.95,0.6:1.94"
KEYS = ("V_over_U", "dp_plus_R0", "tension_max")


def _case(text: str) -> tuple[float, dict]:
    nu, lam = text.split(":")
    return float(nu), ({"lam_ratio": float(lam[1:])} if lam.startswith("r")
                       else {"lam": float(lam)})


def reference(rows: list[dict], key: str) -> float:
    """Last level plus the tail of its geometric contraction (the ratio of its last two
    differences, at most 0.9)."""
    q = [r[key] for r in rows]
    d1, d2 = q[-2] - q[-3], q[-1] - q[-2]
    rho = min(abs(d2 / d1), 0.9) if d1 else 0.0
    return q[-1] + d2 * rho / (1.0 - rho)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=SEVEN, help=f"nu:lam or nu:r<lam/lam_c> list ({SEVEN})")
    ap.add_argument("--json", help="write the rows to this JSON file")
    args = ap.parse_args()
    out = []
    print(f"{'case':>12} {'s':>6} {'BIE':>5} {'conv':>5} {'modes':>5} {'key':>11} "
          f"{'value':>13} {'estimate':>9} {'true err':>9} {'ratio':>6}", flush=True)
    for text in args.cases.split(","):
        nu, where = _case(text)
        t0 = time.perf_counter()
        res = solve_vesicle(nu, **where)
        seconds = time.perf_counter() - t0
        n = int(res.panels.get("modes") or 0)
        levels = [m for m in (n + 8, n + 16, n + 24) if m <= MAX_MODES]
        rows = (mode_convergence(res, levels) if res.modes.size and len(levels) == 3 else [])
        row = {"case": text, "nu": nu, "lam": res.lam, "seconds": seconds,
               "bie_solves": res.bie_solves, "success": res.success, "message": res.message,
               "modes": n, "residual": res.residual, "levels": rows, "keys": {}}
        # the last three levels of the default ladder (consistent: the solver stops on three)
        last3 = [dict(zip(("modes", "residual", *KEYS), lv)) for lv in res.refinement[-3:]]
        for k in KEYS:
            ref = reference(rows, k) if rows else float("nan")
            true = abs(getattr(res, k) - ref)
            est = res.error_estimate.get(k, float("nan"))
            q = [lv[k] for lv in last3]
            d1, d2 = (abs(q[1] - q[0]), abs(q[2] - q[1])) if len(q) == 3 else (math.nan,) * 2
            row["keys"][k] = {"value": getattr(res, k), "estimate": est, "reference": ref,
                              "true_error": true, "ratio": est / true if true else float("inf"),
                              "contraction": d2 / d1 if d1 else math.nan,
                              "error_over_last_difference": true / d2 if d2 else math.nan}
            print(f"{text:>12} {seconds:6.0f} {res.bie_solves:5d} {res.success!s:>5} {n:5d} "
                  f"{k:>11} {getattr(res, k):13.8g} {est:9.2e} {true:9.2e} "
                  f"{row['keys'][k]['ratio']:6.1f}", flush=True)
        if not res.success:
            print(f"{'':>12} not converged: {res.message}", flush=True)
        out.append(row)
        if args.json:
            write_json(Path(args.json), {"rows": out, "provenance": provenance()}, indent=1,
                       sort_keys=False)


if __name__ == "__main__":
    main()
