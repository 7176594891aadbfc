"""``vesicle-tube figures --out DIR``: the quantitative figures of Chen et al. (2020) regenerated
from our solvers and solution map, with the paper's statements checked.

Follows :mod:`correlations.cli.contract`: a table (one line per figure) or ``--json``; exit 0
when the figures were written (disagreements with the paper are results, not errors), 2 for
bad input (``--out``, ``--format``, ``--only``, checked before any work), 130 on Ctrl-C (the
figures, cache files and solves finished before it are complete and kept). Writes
``DIR/<figure>.<format>``, ``DIR/figures.json``, ``DIR/figures.md`` and ``DIR/cache/``;
progress goes to stderr, one line per figure. Light at start: matplotlib and the solvers load
only when a figure is drawn or solved (inside :mod:`correlations.figures`).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from lubrication.io import atomic_write, provenance, write_json
from correlations.cli.contract import (UsageError, add_map_option, check_targets, finite_float,
                                      options_named, short_path)
from correlations.figures import FIGURES, FigureContext, make_figure, render_markdown

__all__ = ["add_figures_parser", "cmd_figures", "FORMATS"]

#: figure file formats offered (matplotlib writes each without extra dependencies)
FORMATS = ("png", "pdf", "svg")


def _progress(text: str) -> None:
    print(f"figures: {text}", file=sys.stderr, flush=True)


def cmd_figures(args):
    if not args.bem_max_time > 0:
        raise UsageError(f"--bem-max-time {args.bem_max_time:g}: must be > 0 [s]")
    names = list(dict.fromkeys(args.only or FIGURES))
    out = Path(args.out)
    check_targets("--out", files=[out / "figures.json", out / "figures.md"]
                  + [out / f"{name}.{args.format}" for name in names], folders=[out / "cache"])
    if args.build is not None and not (Path(args.build) / "build.json").is_file():
        raise UsageError(f"--build {short_path(args.build)}: not a build folder of "
                         "'vesicle-tube map build' (no build.json)")
    with options_named({"map": "--map", "build": "--build"}, args):
        ctx = FigureContext(args.out, map_path=args.map, build=args.build,
                            bem_max_time=args.bem_max_time, progress=_progress)
    ctx.out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    records = []
    for i, name in enumerate(names, 1):
        _progress(f"[{i}/{len(names)}] {name}: {FIGURES[name][0]} ...")
        rec = make_figure(ctx, name, args.format)
        records.append(rec)
        n = {v: sum(s["verdict"] == v for s in rec["statements"])
             for v in ("agree", "disagree", "not checked")}
        _progress(f"[{i}/{len(names)}] {name}: {rec['seconds']:.1f} s"
                  f"{' (cache)' if rec['cached'] else ''}, {n['agree']} agree, "
                  f"{n['disagree']} disagree, {n['not checked']} not checked")
    seconds = time.perf_counter() - t0
    statements = [s for r in records for s in r["statements"]]
    counts = {v: sum(s["verdict"] == v for s in statements)
              for v in ("agree", "disagree", "not checked")}
    out = {"command": "figures", "converged": True, "out": str(ctx.out), "format": args.format,
           "figures": [{k: r[k] for k in ("name", "caption", "file", "cached")}
                       for r in records], "counts": counts, "statements": statements,
           "inputs": ctx.fingerprint, "provenance": provenance()}
    write_json(ctx.out / "figures.json", out)
    header = (f"Solution map {ctx.map_path.name} (created "
              f"{ctx.map.provenance.get('created', '?')}, commit "
              f"{str(ctx.map.provenance.get('git_commit', '?'))[:12]}); tolerances and rules: "
              "correlations/figures.py.")
    atomic_write(ctx.out / "figures.md", lambda f: f.write(render_markdown(records, header)))
    out["seconds"] = seconds
    width = max(len(r["name"]) for r in records)
    lines = [f"Chen et al. (2020) figures in {ctx.out}"]
    for r in records:
        n = {v: sum(s["verdict"] == v for s in r["statements"])
             for v in ("agree", "disagree", "not checked")}
        lines.append(f"  {r['name']:<{width}}  {Path(r['file']).name:<{width + 4}}  "
                     f"{n['agree']:>2} agree  {n['disagree']:>2} disagree  "
                     f"{n['not checked']:>2} not checked{'  (cache)' if r['cached'] else ''}")
    lines.append(f"statements: {counts['agree']} agree, {counts['disagree']} disagree, "
                 f"{counts['not checked']} not checked; table: {ctx.out / 'figures.md'}")
    human = "\n".join(lines)
    return out, human


def add_figures_parser(subparsers) -> None:
    """Add ``figures`` to the subcommands."""
    p = subparsers.add_parser(
        "figures", help="regenerate the figures of Chen et al. (2020) from our solvers and "
                        "solution map and check the paper's statements")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: one file per figure, figures.json, figures.md and "
                        "cache/ (created if missing)")
    p.add_argument("--format", choices=FORMATS, default="png",
                   help="figure file format (default png)")
    p.add_argument("--only", nargs="+", choices=list(FIGURES), metavar="NAME",
                   help="draw only these figures; names: " + ", ".join(FIGURES))
    add_map_option(p)
    p.add_argument("--build", metavar="DIR",
                   help="build folder whose stored BEM shapes the shape and tension figures "
                        "use (default: the shipped correlations/data/solution_map_build)")
    p.add_argument("--bem-max-time", type=finite_float, default=900.0, metavar="SECONDS",
                   help="wall-time budget of each BEM solve (not converged beyond it) [s] "
                        "(default 900)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=cmd_figures)
