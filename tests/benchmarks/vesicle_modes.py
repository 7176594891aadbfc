"""Mode convergence of a steady BEM vesicle at a fixed parametrisation density (prints a table).

Run with ``python tests/benchmarks/vesicle_modes.py [--nu 0.6] [--lam 1.94] [--modes 56,64,72,80]
[--json FILE]``. The default solve (:func:`bem.vesicle.solve_vesicle`) gives the shape; the
density is re-built on it once and every level of ``--modes`` is solved to its least-squares
minimum with that density (:func:`mode_convergence`, also used by ``default_cases.py`` and
``tests/bem/test_vesicle.py``). The ratios are the observed contraction of the successive
differences per level (a constant ratio rho < 1: geometric
convergence, remaining error ~ rho/(1 - rho) times the last difference). The steady solver's
validation asks for the observed order at (0.6, 1.94); about 5 min for the default solve and
2-4 min per level on 2 cores.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from bem.results import VesicleResult
from bem.shape import fit_curve
from bem.threads import single_threaded_blas
from bem.vesicle import solve_vesicle, vesicle_discretisation
from bem.vesicle.ladder import ESTIMATED_OUTPUTS
from bem.vesicle.level import solve_level
from bem.vesicle.operator import level_outputs
from bem.vesicle.seeds import DENSITIES
from lubrication.checks import InvalidParameterError, check_range
from lubrication.io import provenance, write_json


@single_threaded_blas()
def mode_convergence(result, modes, *, density: str | None = "bend", density_terms: int = 16,
                     xtol: float = 1e-9, max_iter: int = 40, progress=None) -> list[dict]:
    r"""Mesh-convergence study of a steady vesicle at a *fixed* parametrisation density.

    The arc-length density (with it the panel breaks) is part of the discretisation: the
    levels of :func:`bem.vesicle.solve_vesicle` each carry the density of their seed, and a
    long vesicle's default density is built on the lubrication shape, which does not resolve
    the BEM shape's rear film neck (at (0.6, 1.94), 64 modes: residual 2.7e-3 against 7.7e-4
    with the density built on the BEM shape). Here the density is built once on ``result``'s
    shape and every level in ``modes`` (solved in the given order, each started from the
    previous one, the first from ``result``) is a Levenberg–Marquardt minimum with that density
    (:func:`bem.newton.valley_levenberg_marquardt`, full Jacobian budget), so the successive
    differences measure the discretisation error alone.

    Parameters
    ----------
    result : VesicleResult
        A solved vesicle (its shape seeds the first level; its density is re-built on it).
    modes : sequence of int
        Shape modes of the levels (8 to 256 each), e.g. (56, 64, 72, 80).
    density : {"bend", "curvature", "film"} or None
        Density built on ``result``'s shape; None keeps ``result``'s own density.
    density_terms, xtol, max_iter
        As in :func:`bem.vesicle.solve_vesicle`.
    progress : callable, optional
        Called with each finished row (e.g. ``print``).

    Returns
    -------
    list of dict
        One row per level: ``modes``, ``V_over_U``, ``dp_plus_R0``, ``tension_max``,
        ``film_min``, ``ell``, ``residual``, ``evaluations``, ``seconds``, ``success``,
        ``message``; from the third row on ``ratio_<key>`` =
        :math:`|q_k - q_{k-1}|/|q_{k-1} - q_{k-2}|` for V/U, Δp⁺ and γ_max (the observed
        contraction per level: a constant ratio ρ < 1 is geometric (spectral) convergence,
        and the error of the last level is about ρ/(1 - ρ) times its last difference).
    """
    if not isinstance(result, VesicleResult) or result.modes.size == 0:
        raise InvalidParameterError("result", type(result).__name__,
                                    "a VesicleResult with a shape")
    if density is not None and density not in DENSITIES:
        raise InvalidParameterError("density", density, '"bend", "curvature", "film" or None')
    levels = [int(check_range("modes", n, 8, 256)) for n in modes]
    if not levels:
        raise InvalidParameterError("modes", modes, "at least one mode count")
    prev = result.curve()
    dens = prev.density if density is None else \
        DENSITIES[density](prev, int(check_range("density_terms", density_terms, 1, 64)))
    rows = []
    for n in levels:
        seed = fit_curve(prev.sample, 0.0, 1.0, n, density=dens)
        t0 = time.perf_counter()
        st, op, info = solve_level(result.nu, result.lam, result.ca_b,
                                   vesicle_discretisation(n), seed, n, xtol=xtol,
                                   max_iter=max_iter, valley=True)
        out = level_outputs(result.nu, result.lam, op, st)
        keys = (*ESTIMATED_OUTPUTS, "film_min", "ell", "residual")
        row = {"modes": n, **{k: out[k] for k in keys},
               "evaluations": info["evaluations"], "seconds": time.perf_counter() - t0,
               "success": info["success"], "message": info["message"]}
        if len(rows) >= 2:
            for k in ESTIMATED_OUTPUTS:
                d0 = rows[-1][k] - rows[-2][k]
                row[f"ratio_{k}"] = abs(row[k] - rows[-1][k]) / abs(d0) if d0 else math.nan
        rows.append(row)
        prev = st["curve"]
        if progress is not None:
            progress(row)
    return rows


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
