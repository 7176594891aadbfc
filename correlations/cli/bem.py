"""``vesicle-tube bem ...``: the boundary element solvers on the command line.

Registered by :func:`correlations.cli.build_parser` through :func:`add_bem_parser`; the contract
is the one of :mod:`correlations.cli.contract` (table for people, one JSON object with ``--json``, exit
0 / 2 invalid input with one line on stderr / 1 not converged with the JSON still printed and
``"converged": false``); the JSON holds the solve's ``"status"``
(:class:`lubrication.results.Status`) beside ``"converged"``. The
``bem`` package loads inside the command functions (and with it scipy, numba at the first solve
and matplotlib for a plot), so that ``vesicle-tube estimate``, which registers these commands,
stays fast.

Units: R = 1, U the mean velocity, eta the viscosity; lam = a/R (sphere) or R0/R (drop, R0 the
radius of the sphere of equal volume), Ca = eta U / gamma. In the tables the "unit" column
gives the unit or scale of each value ("-" dimensionless, "R", "1/R", "U", "eta U",
"eta U/R0", "s"); the pressure drop of a vesicle is dp+ in units of eta U/R0 (Chen et al.
2020), as in the plot title.

Every option is checked before any BEM work (and before numba loads) by the solver itself
(``check_*_inputs``, called first); a value outside its range or outside the solver's resource envelope is
exit 2 with one line naming the option. A solve that fails prints "—" (JSON null) for every
physical number.
"""

from __future__ import annotations

import functools
import logging
import math
import sys

import numpy as np

from lubrication.io import clean_json
from correlations.cli.contract import (Parser, UsageError, add_max_time_option, finite_float,
                                      format_rows, format_value, options_named, positive_int,
                                      save_plot, saved)

__all__ = ["add_bem_parser", "cmd_bem_drop", "cmd_bem_sphere", "cmd_bem_vesicle",
           "cmd_bem_vesicle_sweep"]


#: API parameter -> command-line option, for the messages of invalid input
_OPTIONS = {"lam": "--lam", "lam_ratio": "--lam-ratio", "lams": "--lam", "lam_ratios":
            "--lam-ratio", "ca": "--ca", "ca_b": "--ca-b", "nu": "--nu", "panels": "--panels",
            "tol": "--tol", "tension_tol": "--tension-tol", "residual_tol": "--residual-tol",
            "n_modes": "--modes", "ca_s": "--ca-s", "reference": "--reference",
            "max_modes": "--max-modes", "max_time": "--max-time"}


# The counts' ranges of the solvers' resource envelopes, written out so that registering the
# commands does not import bem (tests/test_cli.py checks they are the solvers' own): each
# maximum is what one level of the solver may cost in memory and time (module docstrings of
# bem/solve.py, bem/drop.py, bem/vesicle.py). Both are checked as the option is parsed (but the
# minimum of --max-modes, which depends on --modes) and again by the solver's input check.
#: Sphere panels: a mesh has at most bem.solve.MAX_UNKNOWNS = 4000 unknowns (dense system
#: ~0.55 GB, one LU ~1.5 s); 51 panels fit at the smallest sphere, a/R = 0.001, fewer as a/R grows.
SPHERE_PANELS = (3, 51, "a mesh has at most 4000 unknowns, ~0.55 GB")
#: Drop shape modes (bem.drop.MAX_MODES): 64 modes make 22 drop panels, ~0.2 GB of operators.
DROP_MODES = (6, 64, "22 drop panels and ~0.2 GB of operators at 64")
#: Vesicle shape modes (bem.vesicle.MAX_MODES): a level of 152 modes costs ~6 s on 2 cores
#: and ~1 GB; the automatic refinement's largest level starts at 24.
VESICLE_MODES = (8, 160, "a level costs ~6 s on 2 cores and ~1 GB at 152")
VESICLE_MAX_MODES = (24,) + VESICLE_MODES[1:]


def _count(bounds, minimum: bool = True):
    """argparse type of a count of ``bounds`` = (minimum, maximum, reason of the maximum); with
    ``minimum`` False only the maximum (a minimum that depends on other options is left to the
    solver's check)."""
    return functools.partial(positive_int, minimum=bounds[0] if minimum else 1,
                             maximum=bounds[1], reason=bounds[2])


def _range(bounds) -> str:
    """"LO to HI (REASON)" for a help text."""
    return f"{bounds[0]} to {bounds[1]} ({bounds[2]})"


def _options_named():
    """Input-check errors name the option (:func:`correlations.cli.contract.options_named`)."""
    return options_named(_OPTIONS)


def cmd_bem_sphere(args):
    """Free rigid sphere of radius lam R on the axis of Poiseuille flow."""
    from bem.solve import solve_sphere  # lazy: bem off the estimate's start-up
    with _options_named():           # the solver checks its inputs before any BEM work
        res = solve_sphere(args.lam, panels=args.panels, tol=args.tol, max_time=args.max_time)
    ok = res.success
    out = {"command": "bem", "subcommand": "sphere", **res.to_dict()}
    errors = {"V_over_U": res.V_over_U_err, "dp_plus_R": res.dp_plus_R_err,
              "dp_plus_R0": res.dp_plus_R_err * res.lam, "drag_K": res.drag_K_err}
    out["error_estimate"] = clean_json(errors)
    for key in ("V_over_U_err", "dp_plus_R_err", "drag_K_err"):
        out.pop(key, None)
    method = f"BEM, {res.panels['body']} panels x {res.panels['order']} nodes"

    def pm(err):
        return f"± {err:.1e}" if ok and math.isfinite(err) else ""
    rows = [("confinement a/R", res.lam, "-", "input", ""),
            ("speed V", out["V_over_U"], "U", method, pm(res.V_over_U_err)),
            ("extra pressure drop dp+", out["dp_plus_R"], "eta U/R", method,
             pm(res.dp_plus_R_err)),
            ("extra pressure drop dp+", out["dp_plus_R0"], "eta U/a", method, ""),
            ("quiescent-tube drag K = F/(6 pi eta a V)", out["drag_K"], "-", method,
             pm(res.drag_K_err)),
            ("time", res.timings.get("total_s"), "s", "", ""),
            ("converged", ok, "", "", "" if ok else res.message)]
    _plot_shape(res, args, out)
    return out, format_rows(rows, f"Rigid sphere on the axis of Poiseuille flow (BEM), "
                                  f"a/R = {res.lam:g}")


def _shape_result_json(res, subcommand: str, args) -> dict:
    """JSON object of a drop/vesicle result; with --out the files are written and listed
    (physical fields null and no profile rows when the solve failed)."""
    out = {"command": "bem", "subcommand": subcommand, **res.to_dict(shape=False)}
    if args.out:
        files = saved(out, "--out", lambda: res.save(args.out))
        if files is not None:
            out["files"] = [str(p) for p in files]
    return out


def _plot_shape(res, args, out: dict) -> None:
    """--plot FILE: the body's shape in the tube (a failed write recorded in ``out``)."""
    if args.plot:
        from bem.plotting import plot_shape  # lazy: bem off the estimate's start-up
        saved(out, "--plot", lambda: save_plot(plot_shape(res), args.plot))


def _method_and_error(res):
    """Method label (modes and panels) and ``pm(key)`` -> "± error" of a drop/vesicle result."""
    p, err = res.panels, res.error_estimate
    method = (f"BEM, {p.get('modes', '?')} modes, {p.get('drop', '?')}+{p.get('wall', '?')} "
              f"panels" if p else "BEM")

    def pm(key):
        v = err.get(key)
        return f"± {v:.1e}" if res.success and v is not None and math.isfinite(v) else ""
    return method, pm


def cmd_bem_drop(args):
    """Steady clean drop (viscosity ratio 1, constant tension) on the axis."""
    from bem.drop import solve_drop  # lazy: bem and scipy.linalg off the estimate's start-up
    with _options_named():           # the solver checks its inputs before any BEM work
        res = solve_drop(args.lam, args.ca, n_modes=args.modes, tol=args.tol,
                         max_time=args.max_time)
    out = _shape_result_json(res, "drop", args)
    method, pm = _method_and_error(res)
    ok = res.success
    # physical numbers from out: the result's to_dict gives None for them after a failed solve
    rows = [("confinement lam = R0/R", res.lam, "-", "input", ""),
            ("capillary number Ca = eta U/gamma", res.ca, "-", "input", ""),
            ("speed V", out["V_over_U"], "U", method, pm("V_over_U")),
            ("extra pressure drop dp+", out["dp_plus_R"], "eta U/R", method,
             pm("dp_plus_R")),
            ("extra pressure drop dp+", out["dp_plus_R0"], "eta U/R0", method,
             pm("dp_plus_R0")),
            ("drop length L", out["length"], "R", method, ""),
            ("smallest gap 1 - max r", out["film"], "R", method, ""),
            ("front curvature", out["curvature_front"], "1/R", method, ""),
            ("rear curvature", out["curvature_rear"], "1/R", method, ""),
            ("steady residual max|u.n - V n_x|", res.residual, "U", method, ""),
            ("volume error", res.volume_error, "-", "panel quadrature", ""),
            ("time", res.timings.get("total_s"), "s", "", ""),
            ("converged", ok, "", "", "" if ok else res.message)]
    _plot_shape(res, args, out)
    return out, format_rows(rows, f"Clean drop, viscosity ratio 1, on the axis of Poiseuille "
                                  f"flow (BEM): lam = {res.lam:g}, Ca = {res.ca:g}")


def _vesicle_solver_options(args) -> dict:
    return {"n_modes": args.modes, "tol": args.tol, "tension_tol": args.tension_tol,
            "residual_tol": args.residual_tol,
            "max_modes": args.max_modes}


def _other_branch(res) -> str:
    """Note of the shape-class row where a second steady state exists (a bistable point)."""
    other = res.other_branch if res.success else {}
    if not other:
        return ""
    return (f"bistable: a {other['shape_class']} also exists (V/U {other['V_over_U']:.5g}); "
            f"--branch {other['shape_class']}")


def cmd_bem_vesicle(args):
    """Steady vesicle (inextensible bending membrane, viscosity ratio 1) on the axis."""
    from bem.vesicle import solve_vesicle  # lazy: bem and scipy off the estimate's start-up
    with _options_named():           # the solver checks its inputs before any BEM work
        res = solve_vesicle(args.nu, args.lam, lam_ratio=args.lam_ratio, ca_b=args.ca_b,
                            branch=args.branch, seed_bank=args.seed_bank,
                            ca_s=args.ca_s, reference=args.reference,
                            max_time=args.max_time, **_vesicle_solver_options(args))
    out = _shape_result_json(res, "vesicle", args)
    method, pm = _method_and_error(res)
    ok = res.success
    # physical numbers from out: the result's to_dict gives None for them after a failed solve
    start, _, where = res.seed.partition(" (")       # "seed bank (its point)" and the like
    curv = (f"{res.curvature_rear:.4g} / {res.curvature_front:.4g}" if ok else None)
    rows = [("reduced volume nu", res.nu, "-", "input", ""),
            ("confinement lam = R0/R", res.lam, "-", "input", f"lam/lam_c = {res.lam_ratio:.4g}"),
            ("bending capillary number Ca_B = eta U R0^2/kappa", res.ca_b, "-", "input", ""),
            *([("shear capillary number Ca_S = eta U/G_s", res.ca_s, "-", "input",
                f"stress-free shape: {res.reference}")] if res.reference else []),
            ("speed V", out["V_over_U"], "U", method, pm("V_over_U")),
            ("extra pressure drop dp+", out["dp_plus_R0"], "eta U/R0", method,
             pm("dp_plus_R0")),
            ("length L (front pole to rearmost point)", out["ell"], "R", method, ""),
            ("smallest gap h", out["film_min"], "R", method, ""),
            ("largest tension gamma_max", out["tension_max"], "eta U", method,
             pm("tension_max")),
            ("largest wall shear stress tau_w (= shear rate x eta)", out["wall_shear_max"],
             "eta U/R", method, "Poiseuille: 4"),
            ("rear / front curvature (neg. convex)", curv, "1/R", method, ""),
            ("shape class", out["shape_class"] or None, "", method, _other_branch(res)),
            ("converged from", start or None, "", "", where.strip(" ()")),
            ("steady residual max|u - V e_x|", res.residual, "U", method, ""),
            ("volume / area error", f"{res.volume_error:.1e} / {res.area_error:.1e}"
             if math.isfinite(res.volume_error) else None, "-", "panel quadrature", ""),
            ("time", res.timings.get("total_s"), "s", "", ""),
            ("converged", ok, "", "", "" if ok else res.message)]
    _plot_shape(res, args, out)
    return out, format_rows(rows, f"Vesicle, viscosity ratio 1, on the axis of Poiseuille flow "
                                  f"(BEM): nu = {res.nu:g}, lam = {res.lam:g}, "
                                  f"Ca_B = {res.ca_b:g}")


def _sweep_values(args):
    """The confinements of ``--lam A B N`` or ``--lam-ratio A B N`` (N points, A to B)."""
    from bem.sweep import MAX_POINTS  # lazy: bem and scipy off the estimate's start-up
    option, (a, b, n) = (("--lam", args.lam) if args.lam is not None
                         else ("--lam-ratio", args.lam_ratio))
    if not (math.isfinite(n) and n.is_integer() and n >= 2):
        raise UsageError(f"{option} {a:g} {b:g} {n:g}: N, the number of points, must be an "
                         "integer >= 2")
    if n > MAX_POINTS:
        raise UsageError(f"{option} {a:g} {b:g} {n:g}: at most N = {MAX_POINTS} points (each "
                         "point is a full vesicle solve, seconds to minutes)")
    return {"lams" if option == "--lam" else "lam_ratios": np.linspace(a, b, int(n))}


#: columns of the sweep table: (key, header, format)
_SWEEP_TABLE = (("lam", "lam=R0/R", ".5g"), ("lam_ratio", "lam/lam_c", ".4f"),
                ("V_over_U", "V/U", ".5g"), ("dp_plus_R0", "dp+ R0/(eta U)", ".4g"),
                ("film_min", "h/R", ".3g"), ("ell", "L/R", ".4g"),
                ("shape_class", "shape", ""), ("runtime", "time [s]", ".0f"),
                ("converged", "converged", ""))


def _sweep_text(table, title: str) -> str:
    """One row per point, labelled columns; "—" for missing values."""
    cells = [[h for _, h, _ in _SWEEP_TABLE]]
    for t in table:
        row = []
        for key, _, fmt in _SWEEP_TABLE:
            v = t.get(key)
            row.append(format(v, fmt) if fmt and isinstance(v, float) and math.isfinite(v)
                       else format_value(v))
        cells.append(row)
    widths = [max(len(r[i]) for r in cells) for i in range(len(_SWEEP_TABLE))]
    lines = [title]
    for k, r in enumerate(cells):
        lines.append("  ".join(c.rjust(w) for c, w in zip(r, widths)))
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    failed = [t for t in table if not t["converged"]]
    lines += [f"lam = {t['lam']:.5g}: NOT CONVERGED: {t['message']}" for t in failed]
    return "\n".join(lines)


def cmd_bem_vesicle_sweep(args):
    """Steady vesicles over a range of confinements at fixed nu (continuation in lam)."""
    from bem.sweep import (  # lazy: bem and scipy off the estimate's start-up
        confinements, save_sweep, sweep_table, sweep_vesicle)
    from bem.vesicle import check_vesicle_inputs  # lazy: bem and scipy off the estimate's start-up
    points = _sweep_values(args)
    solver = _vesicle_solver_options(args)
    with _options_named():
        _, lams, _, _ = confinements(args.nu, points.get("lams"), points.get("lam_ratios"),
                                      args.ca_b)
        check_vesicle_inputs(args.nu, float(lams[0]), ca_b=args.ca_b, max_time=args.max_time,
                             **solver)
    done, partial_save = [], {}

    def report(i, n, res, seconds):
        """With --out the points so far (saved first: an interrupted sweep keeps its finished
        points; after a failed write the sweep goes on without, and the final save decides),
        then one line per point on stderr (not with --json)."""
        done.append(res)
        if args.out and i < n and "not_written" not in partial_save:
            saved(partial_save, "--out", lambda: save_sweep(
                args.out, sorted(done, key=lambda r: r.lam), solver, profiles=False,
                complete=False))
        if not args.json:
            print(f"point {i}/{n}: lam = {res.lam:.6g} (lam/lam_c = {res.lam_ratio:.4f}) "
                  f"{'converged' if res.success else 'NOT CONVERGED'} in {seconds:.1f} s",
                  file=sys.stderr, flush=True)

    results = sweep_vesicle(args.nu, **points, ca_b=args.ca_b, progress=report,
                            max_time=args.max_time, **solver)
    table = sweep_table(results)
    r0 = results[0]
    out = {"command": "bem", "subcommand": "vesicle-sweep", "nu": r0.nu, "lam_c": r0.lam_c,
           "ca_b": r0.ca_b, "parameters": solver,
           "converged": all(r.success for r in results), "n_points": len(results),
           "n_converged": sum(r.success for r in results),
           "points": table}
    if not out["converged"]:
        out["message"] = f"{len(results) - out['n_converged']} of {len(results)} points did " \
                         "not converge"
    if args.out:
        files = saved(out, "--out", lambda: save_sweep(args.out, results, solver))
        if files is not None:
            out["files"] = [str(p) for p in files]
    if args.plot:
        from bem.plotting import plot_vesicle_sweep  # lazy: bem off the estimate's start-up
        saved(out, "--plot", lambda: save_plot(plot_vesicle_sweep(results), args.plot))
    title = (f"Vesicle sweep (BEM), nu = {r0.nu:g}, lam_c = {r0.lam_c:.4g}, Ca_B = "
             f"{r0.ca_b:g}: {out['n_converged']}/{len(results)} points converged; "
             "V/U speed over the mean velocity, dp+ extra pressure drop, h/R smallest gap, "
             "L/R length")
    return out, _sweep_text(table, title)


def _vesicle_options(p, sweep: bool) -> None:
    """Inputs and refinement options of ``bem vesicle`` (one lam) and ``vesicle-sweep``
    (``--lam A B N``)."""
    p.add_argument("--nu", type=finite_float, required=True, help="reduced volume, 0 < nu < 1 [-]")
    g = p.add_mutually_exclusive_group(required=True)
    many = {"nargs": 3, "metavar": ("A", "B", "N")} if sweep else {}
    points = ("N values (2 to 100: each point is a full vesicle solve, seconds to minutes) "
              "from A to B of the " if sweep else "")
    g.add_argument("--lam", type=finite_float, **many,
                   help=points + "confinement R0/R, 0 < lam < lam_c(nu) [-]")
    g.add_argument("--lam-ratio", type=finite_float, dest="lam_ratio", **many,
                   help=points + "confinement over critical lam/lam_c, 0 < ratio < 1 [-]")
    p.add_argument("--ca-b", type=finite_float, default=50.0, dest="ca_b",
                   help="bending capillary number eta U R0^2/kappa, 0.01 to 1e5 (default 50) [-]")
    p.add_argument("--n-modes", "--modes", type=_count(VESICLE_MODES), dest="modes",
                   help=f"shape modes of the fine mesh, {_range(VESICLE_MODES)} "
                        "(default: automatic refinement)")
    p.add_argument("--tol", type=finite_float, default=1e-4,
                   help="relative tolerance of the estimated discretisation error of V/U and "
                        "dp+, 1e-12 to 0.5 (default 1e-4) [-]")
    p.add_argument("--tension-tol", type=finite_float, default=1e-2, dest="tension_tol",
                   help="relative tolerance of the estimated error of gamma_max, 1e-12 to 0.5 "
                        "(default 1e-2) [-]")
    p.add_argument("--residual-tol", type=finite_float, default=1e-3, dest="residual_tol",
                   help="tolerance of the steady residual max|u - V e_x|, 1e-14 to 10 "
                        "(default 1e-3) [U]")
    # its minimum is 24 for the automatic refinement, 8 with --modes: the solver checks it
    p.add_argument("--max-modes", type=_count(VESICLE_MAX_MODES, minimum=False), default=None,
                   dest="max_modes",
                   help=f"largest number of shape modes of the automatic refinement, "
                        f"{_range(VESICLE_MAX_MODES)} "
                        "(default 80, or for a long vesicle 40 more than the level where its "
                        "density is re-built, ~6 per tube radius of length)")
    if not sweep:
        p.add_argument("--branch", choices=("parachute", "bullet"), default=None,
                       help="shape class to return where two steady states coexist (default: "
                            "the state reached from the nearest stored shape; a second one "
                            "found is reported)")
        p.add_argument("--no-seed-bank", action="store_false", dest="seed_bank",
                       help="start from the solver's own model seeds only (lubrication shape, "
                            "continuation), not from the stored converged shapes")
        p.add_argument("--ca-s", type=finite_float, default=None, dest="ca_s",
                       help="shear capillary number eta U/G_s of a red-cell membrane (in-plane "
                            "shear elasticity, Evans 1973), 0.01 to 1e4 (default: none, a "
                            "vesicle) [-]")
        p.add_argument("--reference", choices=("biconcave", "spheroid"), default="biconcave",
                       help="stress-free shape of the red-cell membrane with --ca-s: the "
                            "Evans-Fung disc (default, nu <= 0.743) or an oblate spheroid")
    add_max_time_option(p)


def _output_options(p, func, *, plot: str, out: str | None = None,
                    json: str = "print one JSON object on stdout") -> None:
    """The output options every ``bem`` command shares, in this order: ``--out DIR`` (if ``out``
    says what it saves), ``--plot FILE`` and ``--json``; then the command ``func``."""
    if out is not None:
        p.add_argument("--out", metavar="DIR", help=out)
    p.add_argument("--plot", metavar="FILE", help=plot)
    p.add_argument("--json", action="store_true", help=json)
    p.set_defaults(func=func)


def add_bem_parser(subparsers) -> None:
    """Add ``bem sphere``, ``drop``, ``vesicle`` and ``vesicle-sweep`` to the subcommands."""
    logging.getLogger("bem").addHandler(logging.NullHandler())
    b = subparsers.add_parser("bem", help="boundary element solvers: rigid sphere, clean drop, vesicle")
    sub = b.add_subparsers(dest="bem_command", required=True, parser_class=Parser)

    s = sub.add_parser("sphere", help="free rigid sphere on the axis of Poiseuille flow")
    s.add_argument("--lam", type=finite_float, required=True, metavar="A_OVER_R",
                   help="sphere radius over tube radius a/R, about 0.05 to 0.996 (smaller and "
                        "nearer contact: refused with the closed-form limits) [-]")
    s.add_argument("--panels", type=_count(SPHERE_PANELS),
                   help=f"sphere panels, {_range(SPHERE_PANELS)}: {SPHERE_PANELS[1]} for "
                        "the smallest sphere, fewer as a/R grows (32 at 0.996) (default: "
                        "automatic refinement)")
    s.add_argument("--tol", type=finite_float, default=1e-8,
                   help="relative tolerance of the refinement pair, 1e-14 to 0.1 "
                        "(default 1e-8) [-]")
    add_max_time_option(s)
    _output_options(s, cmd_bem_sphere, plot="write the geometry to FILE (PNG)")

    d = sub.add_parser("drop", help="steady clean drop (viscosity ratio 1) in Poiseuille flow")
    d.add_argument("--lam", type=finite_float, required=True,
                   help="drop volume radius over tube radius R0/R, about 0.01 to < 1 [-]")
    d.add_argument("--ca", type=finite_float, required=True,
                   help="capillary number eta U/gamma, U the mean velocity, 1e-8 to 100 [-]")
    d.add_argument("--modes", type=_count(DROP_MODES),
                   help=f"shape modes of the fine mesh, {_range(DROP_MODES)} (default: "
                        "automatic refinement)")
    d.add_argument("--tol", type=finite_float, default=1e-5,
                   help="relative tolerance of the refinement pair in V/U and dp+, 1e-12 to "
                        "0.1 (default 1e-5) [-]")
    add_max_time_option(d)
    _output_options(d, cmd_bem_drop, out="save the result as JSON + CSV shape in DIR",
                    plot="write the drop shape to FILE (PNG)")

    v = sub.add_parser("vesicle", help="steady vesicle (inextensible bending membrane, "
                                       "viscosity ratio 1) in Poiseuille flow")
    _vesicle_options(v, sweep=False)
    _output_options(v, cmd_bem_vesicle, out="save the result as JSON + CSV profiles in DIR",
                    plot="write the vesicle shape to FILE (PNG)")

    w = sub.add_parser("vesicle-sweep", help="steady vesicles over a range of confinements "
                                             "(continuation in lam, minutes per point)")
    _vesicle_options(w, sweep=True)
    _output_options(w, cmd_bem_vesicle_sweep,
                    out="write the sweep CSV + JSON and each point's JSON + CSV profiles to DIR "
                        "(atomic)",
                    plot="write the shapes of all points in the tube to FILE (PNG)",
                    json="print one JSON object on stdout (and no progress lines)")
