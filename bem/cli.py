"""``vesicle-tube bem ...``: the boundary element solvers on the command line.

Registered by :func:`correlations.cli.build_parser` through :func:`add_bem_parser`; the contract
is the one of :mod:`lubrication.cli_contract` (table for people, one JSON object with ``--json``, exit
0 / 2 invalid input with one line on stderr / 1 not converged with the JSON still printed and
``"converged": false``). This module imports only the standard library at import time: numba,
numpy and matplotlib load inside the command functions, so that ``vesicle-tube estimate`` stays
fast.

Units: R = 1, U the mean velocity, eta the viscosity; lam = a/R (sphere) or R0/R (drop, R0 the
radius of the sphere of equal volume), Ca = eta U / gamma.
"""

from __future__ import annotations

import logging
import math
import sys

__all__ = ["add_bem_parser", "cmd_bem_drop", "cmd_bem_sphere", "cmd_bem_vesicle",
           "cmd_bem_vesicle_sweep"]


def cmd_bem_sphere(args):
    """Free rigid sphere of radius lam R on the axis of Poiseuille flow."""
    from lubrication.cli_contract import format_rows

    from .solve import solve_sphere
    res = solve_sphere(args.lam, panels=args.panels, tol=args.tol)
    out = {"command": "bem", "subcommand": "sphere"}
    out.update(res.to_dict())
    out["converged"] = bool(res.converged)
    out["error_estimate"] = {"V_over_U": res.V_over_U_err, "dp_plus_R": res.dp_plus_R_err,
                             "dp_plus_R0": res.dp_plus_R_err * res.lam, "drag_K": res.drag_K_err}
    method = f"BEM, {res.panels['body']} panels x {res.panels['order']} nodes"
    rows = [("confinement a/R", res.lam, "-", "input", ""),
            ("speed V/U", res.V_over_U, "-", method, f"± {res.V_over_U_err:.1e}"),
            ("extra pressure drop dp+ R/(eta U)", res.dp_plus_R, "-", method,
             f"± {res.dp_plus_R_err:.1e}"),
            ("extra pressure drop dp+ a/(eta U)", res.dp_plus_R0, "-", method, ""),
            ("quiescent-tube drag K = F/(6 pi eta a V)", res.drag_K, "-", method,
             f"± {res.drag_K_err:.1e}"),
            ("converged", res.converged, "", "", "" if res.converged else res.message)]
    _plot_shape(res, args)
    return out, format_rows(rows, f"Rigid sphere on the axis of Poiseuille flow (BEM), "
                                  f"a/R = {res.lam:g}")


def _shape_result_json(res, subcommand: str, args) -> dict:
    """JSON object of a drop/vesicle result; with --out the files are written and listed."""
    out = {"command": "bem", "subcommand": subcommand, **res.to_dict(shape=False),
           "converged": bool(res.success)}
    if args.out:
        out["files"] = [str(p) for p in res.save(args.out)]
    return out


def _plot_shape(res, args) -> None:
    """--plot FILE: the body's shape in the tube."""
    if args.plot:
        from lubrication.cli_contract import save_plot

        from .plotting import plot_shape
        save_plot(plot_shape(res), args.plot)


def _method_and_error(res):
    """Method label (modes and panels) and ``pm(key)`` -> "± error" of a drop/vesicle result."""
    p, err = res.panels, res.error_estimate
    method = (f"BEM, {p.get('modes', '?')} modes, {p.get('drop', '?')}+{p.get('wall', '?')} "
              f"panels" if p else "BEM")

    def pm(key):
        v = err.get(key)
        return f"± {v:.1e}" if v is not None and math.isfinite(v) else ""
    return method, pm


def cmd_bem_drop(args):
    """Steady clean drop (viscosity ratio 1, constant tension) on the axis."""
    from lubrication.cli_contract import format_rows

    from .drop import solve_drop
    res = solve_drop(args.lam, args.ca, n_modes=args.modes, tol=args.tol)
    out = _shape_result_json(res, "drop", args)
    method, pm = _method_and_error(res)

    rows = [("confinement lam = R0/R", res.lam, "-", "input", ""),
            ("capillary number Ca = eta U/gamma", res.ca, "-", "input", ""),
            ("speed V/U", res.V_over_U, "-", method, pm("V_over_U")),
            ("extra pressure drop dp+ R/(eta U)", res.dp_plus_R, "-", method, pm("dp_plus_R")),
            ("extra pressure drop dp+ R0/(eta U)", res.dp_plus_R0, "-", method, pm("dp_plus_R0")),
            ("drop length L/R", res.length, "-", method, ""),
            ("smallest gap 1 - max r/R", res.film, "-", method, ""),
            ("front curvature", res.curvature_front, "1/R", method, ""),
            ("rear curvature", res.curvature_rear, "1/R", method, ""),
            ("steady residual max|u.n - V n_x|", res.residual, "U", method, ""),
            ("volume error", res.volume_error, "-", "panel quadrature", ""),
            ("time", res.timings.get("total_s"), "s", "", ""),
            ("converged", res.success, "", "", "" if res.success else res.message)]
    _plot_shape(res, args)
    return out, format_rows(rows, f"Clean drop, viscosity ratio 1, on the axis of Poiseuille "
                                  f"flow (BEM): lam = {res.lam:g}, Ca = {res.ca:g}")


def cmd_bem_vesicle(args):
    """Steady vesicle (inextensible bending membrane, viscosity ratio 1) on the axis."""
    from lubrication.cli_contract import format_rows

    from .vesicle import solve_vesicle
    res = solve_vesicle(args.nu, args.lam, lam_ratio=args.lam_ratio, ca_b=args.ca_b,
                        n_modes=args.modes, tol=args.tol, residual_tol=args.residual_tol,
                        max_modes=args.max_modes)
    out = _shape_result_json(res, "vesicle", args)
    method, pm = _method_and_error(res)

    rows = [("reduced volume nu", res.nu, "-", "input", ""),
            ("confinement lam = R0/R", res.lam, "-", "input", f"lam/lam_c = {res.lam_ratio:.4g}"),
            ("bending capillary number Ca_B = eta U R0^2/kappa", res.ca_b, "-", "input", ""),
            ("speed V/U", res.V_over_U, "-", method, pm("V_over_U")),
            ("extra pressure drop dp+ R0/(eta U)", res.dp_plus_R0, "-", method, pm("dp_plus_R0")),
            ("length L/R", res.ell, "-", method, ""),
            ("smallest gap h/R", res.film_min, "-", method, ""),
            ("largest tension gamma_max/(eta U)", res.tension_max, "-", method,
             pm("tension_max")),
            ("largest wall shear stress tau_w R/(eta U) = shear rate R/U", res.wall_shear_max,
             "-", method, "Poiseuille: 4"),
            ("rear / front curvature (neg. convex)",
             f"{res.curvature_rear:.4g} / {res.curvature_front:.4g}", "1/R", method, ""),
            ("shape class", res.shape_class, "", method, ""),
            ("steady residual max|u - V e_x|", res.residual, "U", method, ""),
            ("volume / area error", f"{res.volume_error:.1e} / {res.area_error:.1e}", "-",
             "panel quadrature", ""),
            ("time", res.timings.get("total_s"), "s", "", ""),
            ("converged", res.success, "", "", "" if res.success else res.message)]
    _plot_shape(res, args)
    return out, format_rows(rows, f"Vesicle, viscosity ratio 1, on the axis of Poiseuille flow "
                                  f"(BEM): nu = {res.nu:g}, lam = {res.lam:g}, "
                                  f"Ca_B = {res.ca_b:g}")


def _sweep_values(args):
    """The confinements of ``--lam A B N`` or ``--lam-ratio A B N`` (N points, A to B)."""
    import numpy as np

    from lubrication.cli_contract import UsageError
    option, (a, b, n) = (("--lam", args.lam) if args.lam is not None
                         else ("--lam-ratio", args.lam_ratio))
    if not (math.isfinite(n) and n.is_integer() and n >= 2):
        raise UsageError(f"{option} {a:g} {b:g} {n:g}: N, the number of points, must be an "
                         "integer >= 2")
    return {"lams" if option == "--lam" else "lam_ratios": np.linspace(a, b, int(n))}


def cmd_bem_vesicle_sweep(args):
    """Steady vesicles over a range of confinements at fixed nu (continuation in lam)."""
    from lubrication.cli_contract import format_rows

    from .sweep import save_sweep, sweep_table, sweep_vesicle
    points = _sweep_values(args)
    solver = {"n_modes": args.modes, "tol": args.tol, "residual_tol": args.residual_tol,
              "max_modes": args.max_modes}
    done = []

    def report(i, n, res, seconds):
        """One line per point on stderr (not with --json); with --out the points so far."""
        done.append(res)
        if not args.json:
            print(f"point {i}/{n}: lam = {res.lam:.6g} (lam/lam_c = {res.lam_ratio:.4f}) "
                  f"{'converged' if res.success else 'NOT CONVERGED'} in {seconds:.1f} s",
                  file=sys.stderr, flush=True)
        if args.out and i < n:          # an interrupted sweep keeps its finished points
            save_sweep(args.out, sorted(done, key=lambda r: r.lam), solver, profiles=False,
                       complete=False)

    results = sweep_vesicle(args.nu, **points, ca_b=args.ca_b, progress=report, **solver)
    table = sweep_table(results)
    r0 = results[0]
    out = {"command": "bem", "subcommand": "vesicle-sweep", "nu": r0.nu, "lam_c": r0.lam_c,
           "ca_b": r0.ca_b, "parameters": solver, "converged": all(r.success for r in results),
           "n_points": len(results), "n_converged": sum(bool(r.success) for r in results),
           "points": table}
    if args.out:
        out["files"] = [str(p) for p in save_sweep(args.out, results, solver)]
    if args.plot:
        from lubrication.cli_contract import save_plot

        from .plotting import plot_vesicle_sweep
        save_plot(plot_vesicle_sweep(results), args.plot)
    rows = [(f"lam = {t['lam']:.5g} (lam/lam_c = {t['lam_ratio']:.4f})", t["V_over_U"], "V/U",
             f"dp+R0/(eta U) = {t['dp_plus_R0']:.4g}, h/R = {t['film_min']:.3g}, "
             f"L/R = {t['ell']:.3g}, {t['shape_class']}, {t['runtime']:.0f} s"
             if t["converged"] else f"{t['runtime']:.0f} s",
             "" if t["converged"] else "NOT CONVERGED") for t in table]
    title = (f"Vesicle sweep (BEM), nu = {r0.nu:g}, Ca_B = {r0.ca_b:g}: "
             f"{out['n_converged']}/{len(results)} points converged")
    return out, format_rows(rows, title)


def _vesicle_options(p, sweep: bool) -> None:
    """Inputs and refinement options of ``bem vesicle`` (one lam) and ``vesicle-sweep``
    (``--lam A B N``)."""
    p.add_argument("--nu", type=float, required=True, help="reduced volume, 0 < nu < 1 [-]")
    g = p.add_mutually_exclusive_group(required=True)
    many = {"nargs": 3, "metavar": ("A", "B", "N")} if sweep else {}
    points = "N values from A to B of the " if sweep else ""
    g.add_argument("--lam", type=float, **many,
                   help=points + "confinement R0/R, 0 < lam < lam_c(nu) [-]")
    g.add_argument("--lam-ratio", type=float, dest="lam_ratio", **many,
                   help=points + "confinement over critical lam/lam_c, 0 < ratio < 1 [-]")
    p.add_argument("--ca-b", type=float, default=50.0, dest="ca_b",
                   help="bending capillary number eta U R0^2/kappa (default 50) [-]")
    p.add_argument("--n-modes", "--modes", type=int, dest="modes",
                   help="shape modes of the fine mesh (default: automatic refinement)")
    p.add_argument("--tol", type=float, default=1e-4,
                   help="relative tolerance of the refinement pair in V/U, dp+ and "
                        "gamma_max (default 1e-4) [-]")
    p.add_argument("--residual-tol", type=float, default=1e-4, dest="residual_tol",
                   help="tolerance of the steady residual max|u - V e_x| (default 1e-4) [U]")
    p.add_argument("--max-modes", type=int, default=None, dest="max_modes",
                   help="largest number of shape modes of the automatic refinement (default "
                        "40, or ~6 per tube radius of length for long vesicles, 64 at "
                        "nu = 0.6 near lam_c; near lam_c use --tol 1e-2 --residual-tol 5e-3)")


def add_bem_parser(subparsers) -> None:
    """Add ``bem sphere``, ``drop``, ``vesicle`` and ``vesicle-sweep`` to the subcommands."""
    from lubrication.cli_contract import Parser
    logging.getLogger("bem").addHandler(logging.NullHandler())
    b = subparsers.add_parser("bem", help="boundary element solvers: rigid sphere, clean drop, vesicle")
    sub = b.add_subparsers(dest="bem_command", required=True, parser_class=Parser)

    s = sub.add_parser("sphere", help="free rigid sphere on the axis of Poiseuille flow")
    s.add_argument("--lam", type=float, required=True, metavar="A_OVER_R",
                   help="sphere radius over tube radius a/R, 0 < a/R < 1 [-]")
    s.add_argument("--panels", type=int, help="sphere panels (default: automatic refinement)")
    s.add_argument("--tol", type=float, default=1e-10,
                   help="relative tolerance of the refinement pair (default 1e-10) [-]")
    s.add_argument("--plot", metavar="FILE", help="write the geometry to FILE (PNG)")
    s.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    s.set_defaults(func=cmd_bem_sphere)

    d = sub.add_parser("drop", help="steady clean drop (viscosity ratio 1) in Poiseuille flow")
    d.add_argument("--lam", type=float, required=True,
                   help="drop volume radius over tube radius R0/R, 0 < lam < 1 [-]")
    d.add_argument("--ca", type=float, required=True,
                   help="capillary number eta U/gamma, U the mean velocity, > 0 [-]")
    d.add_argument("--modes", type=int,
                   help="shape modes of the fine mesh (default: automatic refinement)")
    d.add_argument("--tol", type=float, default=1e-5,
                   help="relative tolerance of the refinement pair in V/U and dp+ "
                        "(default 1e-5) [-]")
    d.add_argument("--out", metavar="DIR", help="save the result as JSON + CSV shape in DIR")
    d.add_argument("--plot", metavar="FILE", help="write the drop shape to FILE (PNG)")
    d.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    d.set_defaults(func=cmd_bem_drop)

    v = sub.add_parser("vesicle", help="steady vesicle (inextensible bending membrane, "
                                       "viscosity ratio 1) in Poiseuille flow")
    _vesicle_options(v, sweep=False)
    v.add_argument("--out", metavar="DIR", help="save the result as JSON + CSV profiles in DIR")
    v.add_argument("--plot", metavar="FILE", help="write the vesicle shape to FILE (PNG)")
    v.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    v.set_defaults(func=cmd_bem_vesicle)

    w = sub.add_parser("vesicle-sweep", help="steady vesicles over a range of confinements "
                                             "(continuation in lam, minutes per point)")
    _vesicle_options(w, sweep=True)
    w.add_argument("--out", metavar="DIR", help="write the sweep CSV + JSON and each point's "
                                                "JSON + CSV profiles to DIR (atomic)")
    w.add_argument("--plot", metavar="FILE", help="write the shapes of all points in the tube "
                                                  "to FILE (PNG)")
    w.add_argument("--json", action="store_true", help="print one JSON object on stdout "
                                                       "(and no progress lines)")
    w.set_defaults(func=cmd_bem_vesicle_sweep)
