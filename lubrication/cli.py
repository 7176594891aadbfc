"""``vesicle-tube lubrication``: one steady solution or a sweep over lam/lam_c.

Follows the CLI contract of :mod:`lubrication.cli_contract` (table or ``--json``; exit 0 ok, 2 invalid
input, 1 not converged with the JSON still printed). scipy is imported only when the command
runs, so registering the command costs nothing at start-up.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

#: Scalars of a single solution shown in the table, with their units.
ROWS = (("nu", "-"), ("lam", "-"), ("lam_c", "-"), ("delta", "-"), ("ca_b", "-"), ("model", ""),
        ("V_over_U", "-"), ("Q", "-"), ("dp_plus_R0", "dp+ R0/(eta U)"), ("dp_plus_R", "dp+ R/(eta U)"),
        ("ell", "L/R"), ("film_min", "h/R"), ("tension_front", "eta U"), ("tension_rear", "eta U"),
        ("tension_max", "eta U"), ("curvature_front", "1/R"), ("curvature_rear", "1/R"),
        ("shape_class", ""), ("force_balance_residual", "-"), ("area_error", "-"),
        ("volume_error", "-"), ("n_nodes", ""))

#: Columns of the sweep CSV.
SWEEP_COLUMNS = ("lam_ratio", "lam", "delta", "V_over_U", "dp_plus_R0", "dp_plus_R", "ell",
                 "film_min", "tension_front", "tension_max", "shape_class", "converged", "message")


def ca_b_type(text: str) -> float:
    """argparse type of ``--ca-b``: a positive number or ``inf`` (high-Ca model)."""
    return math.inf if text.strip().lower() in ("inf", "infinity") else float(text)


def add_parser(sub) -> None:
    """Register ``lubrication`` on the subparsers of the main CLI."""
    p = sub.add_parser("lubrication", help="lubrication (parallel-flow) model of a vesicle in a tube")
    p.add_argument("--nu", type=float, required=True, help="reduced volume, 0 < nu < 1 [-]")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--lam", type=float, help="confinement R0/R [-]")
    g.add_argument("--lam-ratio", type=float, help="lam/lam_c, in (0, 1) [-]")
    p.add_argument("--ca-b", type=ca_b_type, default=math.inf,
                   help="bending capillary number eta U R0^2/kappa [-], or inf for the high-Ca "
                        "model (default inf)")
    p.add_argument("--sweep", action="store_true",
                   help="sweep lam/lam_c from --from to --to (warm-started continuation)")
    p.add_argument("--from", dest="ratio_from", type=float, default=0.5,
                   help="smallest lam/lam_c of the sweep (default 0.5)")
    p.add_argument("--to", dest="ratio_to", type=float, default=0.999,
                   help="largest lam/lam_c of the sweep (default 0.999)")
    p.add_argument("--points", type=int, default=50, help="number of sweep points (default 50)")
    p.add_argument("--out", metavar="DIR", help="write the result(s): JSON + CSV (atomic)")
    p.add_argument("--plot", metavar="FILE", help="PNG: the shape, or V/U, dp+, film, length vs lam")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=cmd_lubrication)


def cmd_lubrication(args):
    from lubrication.cli_contract import UsageError, format_rows
    if args.sweep:
        if args.lam is not None or args.lam_ratio is not None:
            raise UsageError("--sweep takes --from/--to/--points, not --lam or --lam-ratio")
        return _sweep(args)
    if args.lam is None and args.lam_ratio is None:
        raise UsageError("give --lam LAM or --lam-ratio R (or --sweep)")
    from .solve import solve_lubrication
    res = solve_lubrication(args.nu, args.lam, lam_ratio=args.lam_ratio, ca_b=args.ca_b)
    out = {"command": "lubrication", **res.to_dict()}
    if args.out:
        paths = res.save(args.out)
        out["files"] = [str(p) for p in paths]
    if args.plot and res.success:
        from lubrication.cli_contract import save_plot
        from .plotting import plot_shape
        save_plot(plot_shape(res), args.plot)
    rows = [(k, out.get(k), unit, "lubrication model", "") for k, unit in ROWS]
    title = (f"Lubrication model ({res.model}): "
             + ("converged" if res.success else "NOT CONVERGED") + f" - {res.message}")
    return out, format_rows(rows, title)


def _sweep(args):
    import numpy as np

    from lubrication.cli_contract import UsageError, format_rows
    from .solve import sweep_lubrication
    if args.points < 2:
        raise UsageError(f"--points {args.points}: a sweep needs at least 2 points")
    ratios = np.linspace(args.ratio_from, args.ratio_to, args.points)
    results = sweep_lubrication(args.nu, ratios, ca_b=args.ca_b, progress=not args.json)
    table = [{k: _column(r, k) for k in SWEEP_COLUMNS} for r in results]
    converged = all(r.success for r in results)
    out = {"command": "lubrication", "sweep": True, "nu": results[0].nu, "lam_c": results[0].lam_c,
           "ca_b": "inf" if math.isinf(args.ca_b) else args.ca_b, "model": results[0].model,
           "converged": converged, "n_converged": sum(r.success for r in results),
           "lowest_converged_lam_ratio": min((r.lam_ratio for r in results if r.success), default=None),
           "points": table}
    if args.out:
        out["files"] = [str(_write_sweep_csv(Path(args.out), results, table))]
    if args.plot:
        from lubrication.cli_contract import save_plot
        from .plotting import plot_sweep
        save_plot(plot_sweep(results), args.plot)
    rows = [(f"lam/lam_c = {t['lam_ratio']:.4f}", t["V_over_U"], "V/U",
             f"dp+R0/(eta U) = {t['dp_plus_R0']:.4g}, h/R = {t['film_min']:.3g}, L/R = {t['ell']:.3g}"
             if t["converged"] else "", "" if t["converged"] else "NOT CONVERGED") for t in table]
    title = (f"Lubrication sweep, nu = {args.nu:g}, model {results[0].model}: "
             f"{out['n_converged']}/{len(results)} points converged")
    return out, format_rows(rows, title)


def _column(res, key):
    if key == "converged":
        return bool(res.success)
    value = getattr(res, key)
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _write_sweep_csv(directory: Path, results, table) -> Path:
    """One row per point, written atomically (temporary file, then rename)."""
    from .io import atomic_write
    directory.mkdir(parents=True, exist_ok=True)
    r0 = results[0]
    path = directory / f"lubrication_sweep_nu{r0.nu:.4g}_{r0.model}" \
                       f"{'' if r0.model == 'high-Ca' else f'_caB{r0.ca_b:.4g}'}.csv"

    def write(f):
        w = csv.DictWriter(f, fieldnames=SWEEP_COLUMNS)
        w.writeheader()
        w.writerows(table)

    atomic_write(path, write)
    return path
