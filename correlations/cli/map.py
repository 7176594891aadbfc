"""``vesicle-tube map build | pack | query``: the solution map on the command line.

Follows :mod:`correlations.cli.contract` (table or ``--json``; exit 0 ok, 2 invalid input with one
line naming the option or file, 130 interrupted). Light at start: the build (with the solvers
and Dask) loads only inside ``map build``.

``map build`` checks every grid value and solver option with the ranges of ``bem vesicle`` and
``lubrication`` before ``--out`` is touched (:func:`correlations.map_build.check_build`), and
exits 2 at once when another build is writing into ``--out``. ``map pack`` names ``DIR`` or
``--out`` in every error, refuses a folder without a converged point (a map of holes answers
no query) and reports the points the pack rejected as unphysical.
"""

from __future__ import annotations

import fnmatch
import os
import sys
from pathlib import Path

from lubrication.checks import InvalidParameterError, check_positive, check_range
from lubrication.geometry import critical_confinement
from correlations.cli.contract import (EXIT_INTERRUPTED, Parser, UsageError, add_map_option,
                                      check_output_dir, check_targets, finite_float,
                                      format_rows, format_value, is_interrupt, options_named,
                                      positive_int, short_path)
from correlations.files import read_json
from correlations.solution_map import (POINT_GLOB, load_map, outside_reason, pack_map,
                                       query_map, read_points)

__all__ = ["add_map_parser"]

# The option a user types for each parameter name of the library (map build: the build's
# names of the solver options, correlations.map_build.BuildInputError).
OPTIONS = {"nu": "--nu", "lam_ratio": "--lam-ratio", "ca_b": "--ca-b", "methods": "--methods",
           "out": "--out", "scheduler": "--scheduler", "max_time": "--max-time",
           "workers": "--workers", "bem_n_modes": "--bem-n-modes",
           "bem_max_modes": "--bem-max-modes", "bem_tol": "--bem-tol",
           "bem_residual_tol": "--bem-residual-tol", "lubrication_tol": "--lubrication-tol",
           "map": "--map"}

UNITS = {"V_over_U": "-", "dp_plus_R0": "eta U/R0", "ell": "R", "film_min": "R",
         "tension_max": "eta U", "tension_front": "eta U", "wall_shear_max": "eta U/R",
         "curvature_rear": "1/R", "shape_class": ""}


def _named(args, **renamed):
    return options_named({**OPTIONS, **renamed}, args)


def _progress(state) -> None:
    eta = state["eta_s"]
    eta = "?" if eta is None else (f"{eta:.0f} s" if eta < 120 else f"{eta / 60:.1f} min")
    print(f"map build: {state['done']}/{state['total']} points ({state['failed']} failed), "
          f"{state['running']} lines running, ETA {eta}", file=sys.stderr, flush=True)


def cmd_map_build(args):
    from correlations.map_build import (  # lazy: the solvers and scipy off the estimate's start-up
        DEFAULT_GRID, METHODS, build_map, make_grid)
    out = Path(args.out)
    check_targets("--out", files=[out / "build.json"]
                  + ([] if args.no_pack else [out / "solution_map.json"]))
    grid_given = any(v is not None for v in (args.nu, args.lam_ratio, args.lam_ratio_bem,
                                             args.lam_ratio_lubrication, args.ca_b, args.methods))
    # a list of lam/lam_c comes from --lam-ratio-<method>, else from --lam-ratio
    ratio_options = {f"lam_ratio_{m}": (f"--lam-ratio-{m}" if getattr(args, f"lam_ratio_{m}")
                                        is not None else "--lam-ratio") for m in METHODS}
    # a file of the build folder that cannot be read (the pack at the end) is one of --out
    with _named(args, folder="--out", **ratio_options):
        grid = None
        if grid_given:
            ratios = args.lam_ratio
            if args.lam_ratio_bem is not None or args.lam_ratio_lubrication is not None:
                ratios = {m: (given if given is not None else
                              (args.lam_ratio or DEFAULT_GRID["lam_ratio"][m]))
                          for m, given in (("bem", args.lam_ratio_bem),
                                           ("lubrication", args.lam_ratio_lubrication))}
            try:
                grid = make_grid(args.nu, ratios, args.ca_b, args.methods)
            except InvalidParameterError as exc:
                if exc.name != "grid":
                    raise
                raise UsageError(f"--nu, --lam-ratio, --ca-b: {exc}") from None
        options = {"bem": {k: v for k, v in (("n_modes", args.bem_n_modes),
                                             ("max_modes", args.bem_max_modes),
                                             ("tol", args.bem_tol),
                                             ("residual_tol", args.bem_residual_tol))
                           if v is not None},
                   "lubrication": ({"tol": args.lubrication_tol}
                                   if args.lubrication_tol is not None else {})}
        try:
            out = build_map(args.out, grid, options=options, workers=args.workers,
                            scheduler=args.scheduler, max_time=args.max_time,
                            retry_failed=args.retry_failed, progress=_progress,
                            pack=not args.no_pack)
        except (KeyboardInterrupt, SystemError) as exc:     # SystemError: see is_interrupt
            if not is_interrupt(exc):
                raise
            n = sum(not p.name.startswith(".") for p in Path(args.out).glob(POINT_GLOB))
            print(f"vesicle-tube map build: interrupted; {n} points stored in {args.out} (every "
                  "file complete); run the same command again to resume", file=sys.stderr)
            raise SystemExit(EXIT_INTERRUPTED) from None
    out = {"command": "map build", "converged": not (out["errors"] or out["timed_out"]),
           "out": str(args.out), **out}
    problems = list(out["errors"])  # a line task crashed (a failed point is a stored hole)
    if out["timed_out"]:            # --max-time reached: exit 1, as for every command
        n = out["timed_out"]
        problems.append(f"{n} point{'s' if n != 1 else ''} stopped at --max-time "
                        f"{args.max_time:g} s (stored as failed; rerun with --retry-failed and "
                        "a larger budget)")
    if problems:
        out["message"] = "; ".join(problems)
    if out["failed"]:
        out["warnings"] = [f"{out['failed']} points failed (holes of the map, with their "
                           "reasons in the packed file)"]
    rows = [(k, out[k], "", "", "") for k in ("total", "done", "new", "failed", "missing")]
    rows += [("seconds", out["seconds"], "s", "", ""), ("map", out["map"], "", "", "")]
    return out, format_rows(rows, f"Solution map build in {args.out}")


def coverage_summary(data: dict) -> dict:
    """Counts of the packed map: converged points per method, the BEM grid nodes answered by
    lubrication instead, and the nodes where no method converged (with the BEM reason)."""
    cols, grid = data["columns"], data["grid"]
    have = {(m, nu, r, ca) for m, nu, r, ca in zip(cols["method"], cols["nu"],
                                                   cols["lam_ratio"], cols["ca_b"])}
    reason = {(h["nu"], h["lam_ratio"], h["ca_b"]): h["reason"] for h in data["holes"]
              if h["method"] == "bem"}
    nodes = [(nu, r, ca) for nu in grid["nu"] for ca in grid["ca_b"]
             for r in sorted({r for rs in grid["lam_ratio"].values() for r in rs})]
    bem_grid = set(grid["lam_ratio"].get("bem", []))
    return {"grid": {"nu": len(grid["nu"]), "ca_b": grid["ca_b"], "nodes": len(nodes),
                     "lam_ratio": {m: len(v) for m, v in grid["lam_ratio"].items()}},
            "points": {m: sum(k[0] == m for k in have) for m in grid["methods"]},
            "bem_nodes": sum(1 for nu, r, ca in nodes if r in bem_grid),
            "lubrication_for_bem": [[nu, r, ca] for nu, r, ca in nodes if r in bem_grid
                                    and ("bem", nu, r, ca) not in have
                                    and ("lubrication", nu, r, ca) in have],
            "holes": [{"nu": nu, "lam_ratio": r, "ca_b": ca,
                       "reason": reason.get((nu, r, ca), "not computed")}
                      for nu, r, ca in nodes if not any((m, nu, r, ca) in have
                                                        for m in grid["methods"])]}


def coverage(data: dict) -> str:
    """The packed map's coverage as text: per Ca_B a ν × λ/λc table with B (BEM point),
    L (lubrication point only) or . (hole), then every hole where no method converged, with
    its reasons."""
    cols, grid = data["columns"], data["grid"]
    have = {(m, nu, r, ca) for m, nu, r, ca in zip(cols["method"], cols["nu"],
                                                   cols["lam_ratio"], cols["ca_b"])}
    ratios = sorted({r for rs in grid["lam_ratio"].values() for r in rs})
    reasons: dict = {}
    for h in data["holes"]:
        reasons.setdefault((h["nu"], h["lam_ratio"], h["ca_b"]), []).append(
            f"{h['method']}: {h['reason']}")
    lines, holes = [], []
    for ca in grid["ca_b"]:
        lines.append(f"Ca_B = {ca:g}   (B: BEM, L: lubrication, .: hole)")
        lines.append("  nu \\ lam/lam_c " + "".join(f"{r:<6g}" for r in ratios))
        for nu in reversed(grid["nu"]):
            cells = []
            for r in ratios:
                cell = ("B" if ("bem", nu, r, ca) in have else
                        "L" if ("lubrication", nu, r, ca) in have else ".")
                if cell == "." and any(r in grid["lam_ratio"][m] for m in grid["methods"]):
                    holes.append(f"  (nu={nu:g}, lam/lam_c={r:g}, Ca_B={ca:g}): "
                                 + "; ".join(reasons.get((nu, r, ca), ["not computed"])))
                cells.append(f"{cell:<6}")
            lines.append(f"  {nu:<16g}" + "".join(cells))
    lines.append(f"holes (no method converged): {len(holes)}")
    return "\n".join(lines + holes)


def _check_pack_target(target: str, folder: str) -> None:
    """``map pack --out FILE`` before any work: a file name (not empty, not a folder, not a
    device), in an existing writable folder, and not a file of the build folder ``folder``
    (its ``build.json`` or a point file)."""
    if target.strip() == "":
        raise UsageError("--out: the file name is empty")
    p, name = Path(target), short_path(target)
    try:
        if p.is_dir() or target.endswith(os.sep):
            raise UsageError(f"--out {name}: this is a folder; give a file name, e.g. "
                             f"{os.path.join(name, 'solution_map.json')}")
        if p.exists() and not p.is_file():
            raise UsageError(f"--out {name}: not a regular file (a device, FIFO or socket)")
        if p.parent.exists() and not p.parent.is_dir():
            raise UsageError(f"--out {name}: {short_path(p.parent)!r} is a file, not a folder")
        if not p.parent.is_dir():
            raise UsageError(f"--out {name}: the folder {short_path(p.parent)!r} does not "
                             "exist")
        if p.parent.resolve() == Path(folder).resolve() and (
                p.name == "build.json" or fnmatch.fnmatchcase(p.name, POINT_GLOB)):
            raise UsageError(f"--out {name}: a file of the build folder DIR; give another "
                             "name, e.g. the default DIR/solution_map.json")
    except OSError as exc:          # a name too long, a loop of links, no permission
        raise UsageError(f"--out {name}: {exc.strerror or exc}") from None
    check_output_dir("--out", str(p.parent))


def _check_build_folder(folder: str) -> None:
    """``map pack DIR`` before any work: a folder with a ``build.json``."""
    if str(folder).strip() == "":
        raise UsageError("DIR: the folder name is empty")
    p, name = Path(folder), short_path(folder)
    try:
        if not p.exists():
            raise UsageError(f"DIR {name}: no such folder")
        if not p.is_dir():
            raise UsageError(f"DIR {name}: this is a file; give the build folder of "
                             "'vesicle-tube map build'")
        if not (p / "build.json").is_file():
            raise UsageError(f"DIR {name}: not a build folder of 'vesicle-tube map build' "
                             "(no build.json)")
    except OSError as exc:          # a name too long, a loop of links, no permission
        raise UsageError(f"DIR {name}: {exc.strerror or exc}") from None


def cmd_map_pack(args):
    target = args.pack_out
    _check_build_folder(args.folder)
    if target is not None:
        _check_pack_target(target, args.folder)
    # every file read comes from DIR (build.json, the point files); args=None: DIR is never
    # a default
    with options_named({"folder": "DIR", "map": "DIR", "out": "DIR"}):
        points = read_points(args.folder)        # each point file checked before any writing
        if not any(p["success"] for p in points):
            stored = f"its {len(points)} points all failed" if points else "no point stored"
            raise UsageError(f"DIR {args.folder}: no converged point to pack ({stored}); a "
                             "map of holes answers no query: build it first ('vesicle-tube map "
                             f"build --out {args.folder}')")
        packed = pack_map(args.folder, target, points)
    path = Path(packed)
    data = read_json(path, name="--out" if target is not None else "DIR",
                     what="the packed map just written")
    out = {"command": "map pack", "converged": True, "map": str(path),
           "points": len(data["columns"]["nu"]), "holes": len(data["holes"]),
           "rejected": len(data.get("rejected", [])), "bytes": path.stat().st_size,
           "coverage": coverage_summary(data)}
    if out["rejected"]:
        out["warnings"] = [f"{out['rejected']} converged points rejected as unphysical (holes "
                           f"of the map; each with its reason under 'rejected' in {path})"
                           + ("; the map has no node left: 'map query' refuses it"
                              if not out["points"] else "")]
    rows = [(k, out[k], "", "", "") for k in ("map", "points", "holes", "rejected", "bytes")]
    return out, format_rows(rows, f"Packed {args.folder}") + "\n\n" + coverage(data)


def cmd_map_query(args):
    if (args.lam is None) == (args.lam_ratio is None):
        raise UsageError("give exactly one of --lam LAM, --lam-ratio RATIO")
    with _named(args, lam_ratio="--lam" if args.lam is not None else "--lam-ratio"):
        nu = float(check_range("nu", args.nu, 0.0, 1.0, lo_open=True))
        check_positive("ca_b", args.ca_b)
        if args.lam is not None:
            lam_c = float(critical_confinement(nu))
            lam = float(check_positive("lam", args.lam))
            if lam >= lam_c:
                raise UsageError(f"--lam {lam:g}: lam >= lam_c = {lam_c:.6g} for nu={nu:g}; the "
                                 "vesicle cannot pass the tube intact")
            ratio = lam / lam_c
        else:
            ratio = float(check_range("lam_ratio", args.lam_ratio, 0.0, 1.0, lo_open=True,
                                      hi_open=True,
                                      reason="lam/lam_c >= 1: the vesicle cannot pass"))
        m = load_map(args.map)
        reason = outside_reason(m, nu, ratio, args.ca_b)
        if reason:
            option = reason.split("=")[0]
            option = {"nu": "--nu", "lam_ratio": "--lam" if args.lam is not None else
                      "--lam-ratio", "ca_b": "--ca-b"}[option]
            raise UsageError(f"{option}: query outside the map {m.source}: {reason}")
        res = query_map(nu, ratio, args.ca_b, m)
    quantities = {k: v.to_dict() for k, v in res.quantities.items()}
    out = {"command": "map query", "converged": True, **res.to_dict(),
           **{k: v["value"] for k, v in quantities.items()}}
    rows, notes = [], []
    for k, q in quantities.items():
        if q["note"] and q["note"] not in notes:
            notes.append(q["note"])
        flag = f"note {notes.index(q['note']) + 1}" if q["note"] else ""
        if q["value"] is not None and q["error"] is not None:
            parts = ", ".join(f"{name} {format_value(q[f'{name}_error'])}"
                              for name in ("interpolation", "solver", "model"))
            flag = f"+- {format_value(q['error'])} ({parts}) {flag}".rstrip()
        rows.append((k, q["value"], UNITS.get(k, "-"), "+".join(q["methods"]), flag))
    title = (f"Solution map at nu={nu:g}, lam/lam_c={ratio:.6g}, Ca_B={args.ca_b:g} "
             f"({res.source})")
    if res.membrane is not None:        # never read as a vesicle's answer
        beta = res.membrane["shear_ratio"]
        title += (f"\nRED-CELL map: shear ratio beta = G_s R0^2/kappa = {beta:.6g} "
                  f"(Ca_S = Ca_B/beta = {args.ca_b / beta:.4g}), stress-free shape "
                  f"{res.membrane['reference']}; not a vesicle's answer")
    return out, "\n".join([format_rows(rows, title)]
                          + [f"note {i}: {n}" for i, n in enumerate(notes, 1)])


def add_map_parser(subparsers) -> None:
    """Add ``map build``, ``map pack`` and ``map query`` to the subcommands."""
    p = subparsers.add_parser("map", help="precomputed solution map: build, pack, query")
    sub = p.add_subparsers(dest="map_command", required=True, parser_class=Parser)

    b = sub.add_parser("build", help="solve the grid of the map into a build folder "
                       "(resumes a stopped build)")
    # option lists alike in shape only with the figures command's (a deliberate repeat)
    b.add_argument("--out", required=True, metavar="DIR",
                   help="build folder: build.json, one JSON file per point, solution_map.json")
    b.add_argument("--workers", type=positive_int,
                   help="local worker processes, 1 to the number of cores (default: the number "
                        "of cores; 1: in this process; not with --scheduler)")
    b.add_argument("--scheduler", metavar="ADDRESS",
                   help="address of a Dask distributed scheduler, e.g. tcp://host:8786 "
                        "(needs vesicle-tube[distributed]; workers must see --out)")
    b.add_argument("--max-time", type=finite_float, metavar="SECONDS",
                   help="wall-time budget of each point, > 0; an expired point is stored as "
                        "failed and the build exits 1 [s] (default: no limit)")
    # the ranges below are those of 'bem vesicle' and 'lubrication' (the solvers' checks,
    # correlations.map_build.check_build), written out so that the parser needs no numpy
    b.add_argument("--nu", type=finite_float, nargs="+", help="reduced volumes, 0 < nu < 1 "
                   "(lubrication: 0.3 <= nu < 1) [-] (default 0.6 0.65 ... 0.95 0.98)")
    b.add_argument("--lam-ratio", type=finite_float, nargs="+",
                   help="lam/lam_c of every method, 0 < r < 1 (lubrication: 0.1 <= r < 1) [-] "
                        "(default: BEM 0.2 ... 0.98, lubrication 0.9 ... 0.9999)")
    b.add_argument("--lam-ratio-bem", type=finite_float, nargs="+",
                   help="lam/lam_c of the BEM lines only, 0 < r < 1 [-]")
    b.add_argument("--lam-ratio-lubrication", type=finite_float, nargs="+",
                   help="lam/lam_c of the lubrication lines only, 0.1 <= r < 1 [-]")
    b.add_argument("--ca-b", type=finite_float, nargs="+",
                   help="bending capillary numbers eta U R0^2/kappa, 0.01 to 1e5 [-] "
                        "(default 5 9 15 25 50 150 500); at most 20000 points in all")
    b.add_argument("--methods", nargs="+", choices=("bem", "lubrication"),
                   help="solvers (default both)")
    b.add_argument("--bem-n-modes", type=positive_int,
                   help="BEM shape modes, 8 to 160 (default: automatic refinement)")
    b.add_argument("--bem-max-modes", type=positive_int,
                   help="BEM largest mode count of the refinement, 24 to 160")
    b.add_argument("--bem-tol", type=finite_float,
                   help="BEM relative tolerance of the refinement pair, 1e-12 to 0.5 [-] "
                        "(default 1e-4)")
    b.add_argument("--bem-residual-tol", type=finite_float,
                   help="BEM steady residual tolerance, 1e-14 to 10 [U] (default 1e-3)")
    b.add_argument("--lubrication-tol", type=finite_float,
                   help="lubrication collocation tolerance, 1e-12 to 1e-3 [-] (default 1e-7)")
    b.add_argument("--retry-failed", action="store_true",
                   help="solve again the points stored as failed")
    b.add_argument("--no-pack", action="store_true", help="do not pack at the end")
    b.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    b.set_defaults(func=cmd_map_build)

    k = sub.add_parser("pack", help="pack a build folder into one map file")
    k.add_argument("folder", metavar="DIR", help="build folder of 'map build'")
    k.add_argument("--out", dest="pack_out", metavar="FILE",
                   help="map file to write (default DIR/solution_map.json; the shipped map is "
                        "correlations/data/solution_map.json)")
    k.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    k.set_defaults(func=cmd_map_pack)

    q = sub.add_parser("query", help="every quantity of the map at one point, with error bars")
    q.add_argument("--nu", type=finite_float, required=True, help="reduced volume [-]")
    q.add_argument("--lam", type=finite_float, help="confinement R0/R [-]")
    q.add_argument("--lam-ratio", type=finite_float, help="lam/lam_c, 0 < r < 1 [-]")
    q.add_argument("--ca-b", type=finite_float, required=True,
                   help="bending capillary number eta U R0^2/kappa > 0 [-]")
    add_map_option(q, "packed map")
    q.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    q.set_defaults(func=cmd_map_query)
