"""Would more levels bring a default solve's error estimate within 10 times of its true error?

Run with ``python tests/benchmarks/estimate_floor.py [--cases 0.8:1.0,0.7:1.2,0.7:1.5] [--extra 2]
[--json FILE]`` after ``default_cases.py`` (its JSON gives each case's default fine level N and
the mode-converged reference). For each case the default ladder is continued past its stop
(tolerances 1e-12, ``max_modes`` = N + 8, N + 16, ...: the same density and levels up to N, then
one more level each) and each stop's value, error estimate and true error are tabulated. The
cases are those whose default estimate is more than 10 times the true error, and (0.7, 1.5), whose
estimate is within 10 times, as a control; where the true error
is at the levels' own floor (not geometric in the modes) no further level helps. Not a test:
seconds per solve (2 cores).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from default_cases import KEYS

from bem.vesicle import MAX_MODES, solve_vesicle
from lubrication.io import provenance, write_json

DEFAULT_CASES = Path(__file__).resolve().parents[2] / "docs" / "data" / "default_cases.json"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default="0.8:1.0,0.7:1.2,0.7:1.5",
                    help="nu:lam cases of default_cases (the last a control)")
    ap.add_argument("--extra", type=int, default=2, help="levels past the default stop (1-3)")
    ap.add_argument("--defaults", default=str(DEFAULT_CASES), help="default_cases.py JSON")
    ap.add_argument("--json", help="write the rows to this JSON file")
    args = ap.parse_args()
    if not 1 <= args.extra <= 3:
        ap.error(f"--extra must be 1, 2 or 3 levels, got {args.extra}")
    rows = {r["case"]: r for r in json.loads(Path(args.defaults).read_text())["rows"]}
    cases = args.cases.split(",")
    unknown = [c for c in cases if c not in rows or rows[c]["keys"]["V_over_U"]["reference"] is None]
    if unknown:
        ap.error(f"--cases: no reference in {args.defaults} for {', '.join(unknown)}")
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    out = []
    print(f"{'case':>8} {'modes':>5} {'key':>11} {'value':>17} {'estimate':>9} {'true err':>9} "
          f"{'ratio':>6}", flush=True)
    for case in cases:
        row = rows[case]
        nu, lam = (float(s) for s in case.split(":"))
        for m in range(row["modes"], row["modes"] + 8 * args.extra + 1, 8):
            if m > MAX_MODES:
                break
            res = solve_vesicle(nu, lam, **({} if m == row["modes"] else
                                            {"tol": 1e-12, "tension_tol": 1e-12, "max_modes": m}))
            stop = {"case": case, "modes": int(res.panels.get("modes") or 0),
                    "residual": res.residual, "keys": {}}
            for k in KEYS:
                value, est = getattr(res, k), res.error_estimate[k]
                true = abs(value - row["keys"][k]["reference"])
                stop["keys"][k] = {"value": value, "estimate": est, "true_error": true,
                                   "ratio": est / true if true else float("inf")}
                print(f"{case:>8} {stop['modes']:5d} {k:>11} {value:17.12g} {est:9.2e} "
                      f"{true:9.2e} {stop['keys'][k]['ratio']:6.2f}", flush=True)
            out.append(stop)
            if args.json:
                write_json(Path(args.json), {"rows": out, "references": Path(args.defaults).name,
                                             "provenance": provenance()}, indent=1, sort_keys=False)


if __name__ == "__main__":
    main()
