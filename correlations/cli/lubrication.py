"""``vesicle-tube lubrication``: one steady solution or a sweep over lam/lam_c.

Follows the CLI contract of :mod:`correlations.cli.contract` (table or ``--json``; exit 0 ok, 2
invalid input, 1 not converged or out of time, with the JSON still printed and every physical
value of a failed solve null; whether a solve converged is read from its status, written as
``"status"`` beside ``"converged"``). Every option is checked before any solve, and the
messages name the option as it was typed (``--lam-ratio``, not the library's ``lam_ratio``):
the lubrication model's own range checks (:func:`lubrication.solve.check_inputs`) run with the
option names.

Units: the table's "unit" column gives the unit the value is expressed in ("-" for a pure
number), e.g. dp+ in eta U/R0, lengths in R, tensions in eta U; the JSON holds the same numbers
under the keys of :class:`lubrication.results.LubricationResult` and the units under "units".
``"ca_b": null`` with ``"model": "high-Ca"`` stands for Ca_B = inf (strict JSON has no
infinity).

scipy is imported only when the command runs, so registering the command costs nothing at
start-up.
"""

from __future__ import annotations

import csv
import functools
import math
from pathlib import Path

import numpy as np

from lubrication import plotting
from lubrication.checks import check_positive
from correlations.cli.contract import (UsageError, add_max_time_option, finite_float, format_rows,
                                      format_value, positive_int, save_plot, saved)
from lubrication.io import atomic_write, clean_json, make_folder

#: Option names of the inputs, for the messages of the library's checks.
OPTION_NAMES = {"nu": "--nu", "lam": "--lam", "lam_ratio": "--lam-ratio", "ca_b": "--ca-b"}

# The row tables below are alike in shape on purpose: data of one format, not repeated logic.
#: Rows of the single-point table: (key, quantity, unit, method). Unit "-": a pure number.
INPUT_ROWS = (
    ("nu", "reduced volume nu", "-", "input"),
    ("lam", "confinement lam = R0/R", "-", "input"),
    ("lam_ratio", "lam/lam_c", "-", "input"),
    ("lam_c", "critical confinement lam_c", "-", "geometry (Chen et al. 2020 §IV.A)"),
    ("delta", "clearance delta = 1 - lam/lam_c", "-", "geometry (Chen et al. 2020 §IV.A)"),
    ("ca_b", "bending capillary number Ca_B = eta U R0^2/kappa", "-", "input"),
    ("model", "model", "", "input"),
)
RESULT_ROWS = (
    ("V_over_U", "speed V/U", "-"),
    ("Q", "Q = 1 - U/V", "-"),
    ("dp_plus_R0", "extra pressure drop dp+", "eta U/R0"),
    ("dp_plus_R", "extra pressure drop dp+", "eta U/R"),
    ("ell", "length L", "R"),
    ("film_min", "thinnest film h_min", "R"),
    ("tension_front", "front tension", "eta U"),
    ("tension_rear", "rear tension", "eta U"),
    ("tension_max", "largest tension", "eta U"),
    ("curvature_front", "front pole curvature (< 0 convex)", "1/R"),
    ("curvature_rear", "rear pole curvature (< 0 convex)", "1/R"),
    ("shape_class", "shape", ""),
)
DIAGNOSTIC_ROWS = (
    ("force_balance_residual", "net axial force / pressure force", "-"),
    ("area_error", "relative area error", "-"),
    ("volume_error", "relative volume error", "-"),
    ("max_residual", "largest collocation residual", "-"),
    ("n_nodes", "mesh nodes", ""),
)
#: Units of the JSON keys ("-": a pure number).
UNITS = {key: unit for key, _, unit, *_ in INPUT_ROWS + RESULT_ROWS + DIAGNOSTIC_ROWS if unit}

#: Columns of the sweep CSV and JSON points.
SWEEP_COLUMNS = ("lam_ratio", "lam", "delta", "V_over_U", "dp_plus_R0", "dp_plus_R", "ell",
                 "film_min", "tension_front", "tension_max", "shape_class", "converged", "message")
#: Columns of the human sweep table: (key, header, unit, format).
SWEEP_TABLE = (("lam_ratio", "lam/lam_c", "-", ".4f"), ("lam", "lam", "-", ".4f"),
               ("V_over_U", "V/U", "-", ".5g"), ("dp_plus_R0", "dp+", "eta U/R0", ".4g"),
               ("film_min", "h_min", "R", ".4g"), ("ell", "L", "R", ".4g"),
               ("tension_max", "max tension", "eta U", ".4g"), ("shape_class", "shape", "", ""))

#: Default lowest lam/lam_c of a sweep (raised to the model's lowest where that is higher).
SWEEP_FROM = 0.5
SWEEP_TO = 0.999
SWEEP_POINTS = 50
#: Points of a sweep, 2 to lubrication.solve.MAX_SWEEP_POINTS (whose comment gives the reason,
#: also in the help of --points; tests/test_cli.py checks they agree).
SWEEP_POINTS_RANGE = (2, 2000)


def ca_b_type(text: str) -> float:
    """argparse type of ``--ca-b``: a finite number or ``inf`` (the high-Ca model)."""
    if text.strip().lower() in ("inf", "+inf", "infinity", "+infinity"):
        return math.inf
    return finite_float(text)


def add_parser(sub) -> None:
    """Register ``lubrication`` on the subparsers of the main CLI.

    The ranges in the help are those of :mod:`lubrication.solve` (NU_RANGE, MIN_LAM_RATIO,
    CA_B_RANGE, HIGH_CA_BRANCH_END, MAX_SWEEP_POINTS), written out so that registering the
    command does not import scipy; tests/lubrication/test_lubrication_cli.py checks they agree.
    """
    p = sub.add_parser(
        "lubrication", help="lubrication (parallel-flow) model of a vesicle in a tube",
        description="Steady vesicle in a tube by the lubrication model (Secomb et al. 1986; "
                    "Barakat & Shaqfeh 2018b). The default high-Ca model (--ca-b inf) has "
                    "solutions only above a lam/lam_c that depends on nu (0.908 at nu = 0.6, "
                    "0.738 at 0.8, 0.597 at 0.9, 0.345 at 0.98): below it give a finite --ca-b, "
                    "e.g. --ca-b 50 (Chen et al. 2020).")
    p.add_argument("--nu", type=finite_float, required=True,
                   help="reduced volume, 0.3 <= nu < 1 [-]")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--lam", type=finite_float, help="confinement R0/R, below lam_c(nu) [-]")
    g.add_argument("--lam-ratio", type=finite_float,
                   help="lam/lam_c, 0.1 <= lam/lam_c < 1, and for the high-Ca "
                        "model above the end of its branch (see above) [-]")
    p.add_argument("--ca-b", type=ca_b_type, default=math.inf,
                   help="bending capillary number eta U R0^2/kappa, 0.01 to 1e5 [-], or inf "
                        "(default) for the high-Ca model, which "
                        "has no solution below a nu-dependent lam/lam_c (see above)")
    p.add_argument("--sweep", action="store_true",
                   help="sweep lam/lam_c from --from to --to (warm-started continuation)")
    p.add_argument("--from", dest="ratio_from", type=finite_float, default=None,
                   help=f"smallest lam/lam_c of the sweep [-] (default {SWEEP_FROM:g}, or the "
                        "lowest of the high-Ca model, rounded up, where that is higher)")
    p.add_argument("--to", dest="ratio_to", type=finite_float, default=None,
                   help=f"largest lam/lam_c of the sweep, below 1 [-] (default {SWEEP_TO:g})")
    lo, hi = SWEEP_POINTS_RANGE
    why = ("at 2000 they are 5e-4 in lam/lam_c apart, the continuation's smallest step, and "
           "take 10-30 min")
    p.add_argument("--points", type=functools.partial(positive_int, minimum=lo, maximum=hi,
                                                      reason=why),
                   default=None,
                   help=f"number of sweep points, {lo} to {hi} ({why}) (default {SWEEP_POINTS})")
    add_max_time_option(p)
    p.add_argument("--out", metavar="DIR", help="write the result(s): JSON + CSV (atomic)")
    p.add_argument("--plot", metavar="FILE", help="figure: the shape, or V/U, dp+, film, "
                                                  "length vs lam (format from the extension)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=cmd_lubrication)


def _check_max_time(args) -> float | None:
    if args.max_time is None:
        return None
    return float(check_positive("--max-time", args.max_time, reason="wall-time budget [s]"))


def cmd_lubrication(args):
    if args.sweep:
        if args.lam is not None or args.lam_ratio is not None:
            raise UsageError("--sweep takes --from/--to/--points, not --lam or --lam-ratio")
        return _sweep(args)
    given = [o for o, v in (("--from", args.ratio_from), ("--to", args.ratio_to),
                            ("--points", args.points)) if v is not None]
    if given:
        raise UsageError(f"{', '.join(given)} go(es) with --sweep")
    if args.lam is None and args.lam_ratio is None:
        raise UsageError("give --lam LAM or --lam-ratio R (or --sweep)")
    from lubrication.solve import (  # lazy: scipy.integrate off the estimate's start-up
        check_inputs, solve_lubrication)
    check_inputs(args.nu, args.lam, args.lam_ratio, args.ca_b, names=OPTION_NAMES)
    max_time = _check_max_time(args)
    res = solve_lubrication(args.nu, args.lam, lam_ratio=args.lam_ratio, ca_b=args.ca_b,
                            max_time=max_time)
    ok = res.success
    out = {"command": "lubrication", **res.to_dict(), "units": UNITS}
    notes = []
    if args.out:
        files = saved(out, "--out", lambda: res.save(args.out))
        if files is not None:
            out["files"] = [str(p) for p in files]
            if not ok:
                notes.append("not converged: only the JSON was written (no profiles)")
    if args.plot:
        notes += _plot(ok, "shape", res, args.plot, "not converged", out)
    title = (f"Lubrication, {_model_label(res.model, res.ca_b)}: "
             + ("converged" if ok else "NOT CONVERGED") + f" - {res.message}")
    return out, "\n".join([format_rows(_single_rows(out, ok), title)] + notes)


def _plot(ok: bool, kind: str, what, path, failed: str, out: dict) -> list[str]:
    """Draw ``what`` (a result for ``kind`` "shape", results for "sweep") to ``path`` when
    ``ok`` (a failed write recorded in ``out``); else the note that says why no figure was
    written."""
    if not ok:
        return [f"{failed}: no figure written to {path}"]
    draw = plotting.plot_shape if kind == "shape" else plotting.plot_sweep
    saved(out, "--plot", lambda: save_plot(draw(what), path))
    return []


def _model_label(model: str, ca_b: float) -> str:
    return "high-Ca model, Ca_B = inf" if model == "high-Ca" else f"bending model, Ca_B = {ca_b:g}"


def _single_rows(out: dict, success: bool) -> list:
    rows = []
    for key, label, unit, method in INPUT_ROWS:
        value = out.get(key)
        if key == "ca_b" and value is None:
            value = "inf (high-Ca model)"
        rows.append((label, value, unit, method, ""))
    for key, label, unit in RESULT_ROWS:
        rows.append((label, out.get(key) if success else None, unit, "lubrication model",
                     "" if success else "no value: not converged"))
    for key, label, unit in DIAGNOSTIC_ROWS:
        rows.append((label, out.get(key), unit, "diagnostic", ""))
    return rows


# --------------------------------------------------------------------------- sweep
def _sweep_ratios(args):
    """Checked (from, to, points) of a sweep; the defaults follow the model's range."""
    from lubrication.solve import (  # lazy: scipy.integrate off the estimate's start-up
        check_inputs, lowest_lam_ratio)
    nu = check_inputs(args.nu, lam_ratio=SWEEP_TO, ca_b=args.ca_b, names=OPTION_NAMES)[0]
    ratio_from, ratio_to = args.ratio_from, args.ratio_to
    if ratio_from is None:
        lowest = lowest_lam_ratio(nu, args.ca_b)
        # 0.005 above the measured end of the high-Ca branch, rounded up to 0.01
        ratio_from = max(SWEEP_FROM, math.ceil((lowest + 0.005) * 100.0) / 100.0)
    if ratio_to is None:
        ratio_to = SWEEP_TO
    for option, value in (("--from", ratio_from), ("--to", ratio_to)):
        check_inputs(nu, lam_ratio=value, ca_b=args.ca_b, names=dict(OPTION_NAMES,
                                                                     lam_ratio=option))
    if not ratio_from < ratio_to:
        raise UsageError(f"--from {ratio_from:g} --to {ratio_to:g}: --from must be below --to")
    points = SWEEP_POINTS if args.points is None else args.points    # checked by its type
    return nu, ratio_from, ratio_to, points


def _sweep(args):
    from lubrication.solve import (  # lazy: scipy.integrate off the estimate's start-up
        sweep_lubrication)
    nu, ratio_from, ratio_to, points = _sweep_ratios(args)
    max_time = _check_max_time(args)
    ratios = np.linspace(ratio_from, ratio_to, points)
    results = sweep_lubrication(nu, ratios, ca_b=args.ca_b, progress=not args.json,
                                max_time=max_time)
    table = [{k: _column(r, k) for k in SWEEP_COLUMNS} for r in results]
    n_ok = sum(r.success for r in results)
    converged = n_ok == len(results)
    r0 = results[0]
    failed = [r for r in results if not r.success]
    first = min(failed, key=lambda r: r.lam_ratio) if failed else None
    message = ("all points converged" if converged else
               f"{len(failed)} of {len(results)} points did not converge; at the lowest of them, "
               f"lam/lam_c = {first.lam_ratio:.6g}: {first.message}")
    out = {"command": "lubrication", "sweep": True, "nu": r0.nu, "lam_c": r0.lam_c,
           "ca_b": clean_json(r0.ca_b), "model": r0.model,
           "converged": converged, "message": message, "n_points": len(results),
           "n_converged": n_ok, "max_time": max_time,
           "lowest_converged_lam_ratio": min((r.lam_ratio for r in results if r.success),
                                             default=None),
           "units": {k: UNITS[k] for k in SWEEP_COLUMNS if k in UNITS}, "points": table}
    notes = []
    if args.out:
        path = saved(out, "--out", lambda: _write_sweep_csv(Path(args.out), results, table))
        if path is not None:
            out["files"] = [str(path)]
    if args.plot:
        notes += _plot(n_ok, "sweep", results, args.plot, "no point converged", out)
    title = (f"Lubrication sweep: nu = {r0.nu:g}, lam_c = {r0.lam_c:.6g}, "
             f"{_model_label(r0.model, r0.ca_b)}: {n_ok}/{len(results)} points converged")
    if failed:
        notes.append(message)
    return out, "\n".join([_sweep_table(table, title)] + notes)


def _sweep_table(table, title: str) -> str:
    """Fixed-width table, one row per point, one column per quantity (unit in the header)."""
    head = [f"{h} [{u}]" if u else h for _, h, u, _ in SWEEP_TABLE] + ["status"]
    body = []
    for t in table:
        cells = []
        for key, _, _, fmt in SWEEP_TABLE:
            value = t[key]
            cells.append(format(value, fmt) if isinstance(value, float) and fmt
                         else format_value(value if value != "" else None))
        cells.append("converged" if t["converged"] else "NOT CONVERGED")
        body.append(cells)
    widths = [max(len(r[i]) for r in [head] + body) for i in range(len(head))]
    lines = [title, "  ".join(h.rjust(w) for h, w in zip(head, widths)),
             "  ".join("-" * w for w in widths)]
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in body]
    return "\n".join(lines)


def _column(res, key):
    if key == "converged":
        return res.success
    value = getattr(res, key)
    if key not in ("lam_ratio", "lam", "delta", "message") and not res.success:
        return None             # no physical numbers from a failed solve
    return clean_json(value)


def _write_sweep_csv(directory: Path, results, table) -> Path:
    """One row per point, written atomically (temporary file, then rename)."""
    make_folder(directory)
    r0 = results[0]
    path = directory / f"lubrication_sweep_nu{r0.nu:.4g}_{r0.model}" \
                       f"{'' if r0.model == 'high-Ca' else f'_caB{r0.ca_b:.4g}'}.csv"

    def write(f):
        w = csv.DictWriter(f, fieldnames=SWEEP_COLUMNS)
        w.writeheader()
        w.writerows(table)

    atomic_write(path, write)
    return path
