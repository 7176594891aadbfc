"""Mode convergence of a steady BEM vesicle at a fixed parametrisation density (prints a table).

Run with ``python tests/benchmarks/vesicle_modes.py [--nu 0.6] [--lam 1.94] [--modes 56,64,72,80]
[--json FILE]``. The default solve (:func:`bem.vesicle.solve_vesicle`) gives the shape; the
density is re-built on it once and every level of ``--modes`` is solved to its least-squares
minimum with that density (:func:`bem.vesicle.mode_convergence`). The ratios are the observed
contraction of the successive differences per level (a constant ratio rho < 1: geometric
convergence, remaining error ~ rho/(1 - rho) times the last difference). The steady solver's
validation asks for the observed order at (0.6, 1.94); about 5 min for the default solve and
2-4 min per level on 2 cores.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from bem.vesicle import mode_convergence, solve_vesicle
from lubrication.io import provenance, write_json


def _fmt(row: dict) -> str:
    ratios = " ".join(f"{row.get('ratio_' + k, float('nan')):7.3f}"
                      for k in ("V_over_U", "dp_plus_R0", "tension_max"))
    return (f"{row['modes']:5d} {row['V_over_U']:11.7f} {row['dp_plus_R0']:11.5f} "
            f"{row['tension_max']:9.3f} {row['residual']:9.2e} {ratios} "
            f"{row['evaluations']:6d} {row['seconds']:7.1f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nu", type=float, default=0.6, help="reduced volume (default 0.6)")
    ap.add_argument("--lam", type=float, default=1.94, help="confinement R0/R (default 1.94)")
    ap.add_argument("--lam-ratio", type=float, help="lam/lam_c instead of --lam")
    ap.add_argument("--ca-b", type=float, default=50.0, help="Ca_B = eta U R0^2/kappa (50)")
    ap.add_argument("--modes", default="56,64,72,80", help="levels, comma separated")
    ap.add_argument("--json", help="write parameters and rows to this JSON file")
    args = ap.parse_args()
    modes = [int(m) for m in args.modes.split(",")]
    t0 = time.perf_counter()
    lam = None if args.lam_ratio else args.lam
    base = solve_vesicle(args.nu, lam, lam_ratio=args.lam_ratio, ca_b=args.ca_b)
    print(f"  {base.message} ({base.bie_solves} BIE solves)", flush=True)
    print(f"default solve: {base.panels.get('modes')} modes, V/U {base.V_over_U:.7f}, "
          f"dp+R0 {base.dp_plus_R0:.5f}, g_max {base.tension_max:.3f}, residual "
          f"{base.residual:.1e}, {time.perf_counter() - t0:.0f} s", flush=True)
    print(f"{'modes':>5} {'V/U':>11} {'dp+R0/(eU)':>11} {'g_max':>9} {'residual':>9} "
          f"{'rho V':>7} {'rho dp':>7} {'rho g':>7} {'evals':>6} {'s':>7}", flush=True)
    rows = mode_convergence(base, modes, progress=lambda r: print(_fmt(r), flush=True))
    if args.json:
        out = Path(args.json)
        doc = {"nu": args.nu, "lam": base.lam, "ca_b": args.ca_b, "modes": modes,
               "density": "bend, built on the default solve's shape", "rows": rows,
               "default_solve": base.to_dict(shape=False),
               "default_levels": base.refinement, "default_seconds": time.perf_counter() - t0,
               "provenance": provenance()}
        write_json(out, doc, indent=1, sort_keys=False)


if __name__ == "__main__":
    main()
