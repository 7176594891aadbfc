"""``vesicle-tube check FILE``: the consistency check on the command line, and its report.

Follows :mod:`correlations.cli.contract`: a table (one line per check) or ``--json`` (one object
with a ``rows`` list, each row with its ``verdict`` and its ``checks``); exit 0 when no row
fails (warnings allowed), 1 when a row fails (``"converged": false`` and one line on stderr
with the number of failed rows and the first failure), 2 for unreadable input (one line naming
the row and column, before any row is checked), 130 on Ctrl-C. ``--report FILE.md|FILE.html``
writes a report with a figure of the rows over the references (Markdown: the figure beside it
as ``FILE.png``; HTML: embedded); its path and format are checked before any work.

Any number of rows is checked in bounded memory (:func:`correlations.check.check_summary`): the
table, the JSON ``rows`` and the report list at most ``--listed-rows`` rows (default
:data:`correlations.check.MAX_LISTED_ROWS`: failing rows first, then rows with warnings, then
passing rows, each in file order); the verdict counts (and ``rows_total``, ``rows_omitted``)
cover every row. A million-row table would be gigabytes of output that no one reads; the rows
that need attention come first. Light at start: the check (with the solvers it calls) and
matplotlib load only inside the command.
"""

from __future__ import annotations

import base64
import html
import io
import sys
import time
from pathlib import Path

from lubrication.io import atomic_write
from correlations.cli.contract import add_map_option, check_targets, options_named, positive_int
from correlations.plotting import plot_check

__all__ = ["add_check_parser", "cmd_check", "write_report"]

#: Default of ``--listed-rows`` (the same as correlations.check.MAX_LISTED_ROWS, which is not
#: imported at start-up).
LISTED_ROWS = 1000


def cmd_check(args):
    from correlations.check import (  # lazy: correlations.check off the estimate's start-up
        check_summary)
    if args.report and Path(args.report).suffix.lower() in (".md", ".markdown"):
        check_targets("--report", files=[Path(args.report).with_suffix(".png")])
    with options_named({"map": "--map"}, args):
        report = check_summary(args.file, bem=not args.no_bem, solution_map=args.map,
                               keep=args.listed_rows, progress=_progress())
    failed = report.counts["fail"]
    # "converged" as the contract pairs it with the exit status: false when a row failed (exit 1)
    out = {"command": "check", "converged": not failed, **report.to_dict()}
    if args.report:
        write_report(report, args.report)
    if failed:
        first = report.failure_lines(1)
        print(f"vesicle-tube check: {failed} of {report.n_rows} rows failed a check"
              + (f"; the first: {first[0]}" if first else ""), file=sys.stderr)
    return out, report.format_table()


def _progress():
    """On a terminal, a line on stderr every 5 s of a long check (rows read, rate); None when
    stderr is a pipe or a file, whose readers want one message or none."""
    if not sys.stderr.isatty():
        return None
    start = last = time.monotonic()

    def report(n: int) -> None:
        nonlocal last
        now = time.monotonic()
        if now - last >= 5.0:
            last = now
            print(f"vesicle-tube check: {n} rows read ({n / (now - start):.0f} rows/s)",
                  file=sys.stderr, flush=True)
    return report


# --------------------------------------------------------------------------- the report

def _blocks(report, figure: str) -> list:
    """The report as blocks (``("h1"|"h2"|"p", text)``, ``("table", head, rows)``,
    ``("ul", items)``, ``("img", name)``), rendered by :func:`_markdown` or :func:`_html`."""
    from correlations.check import (  # lazy: correlations.check off the estimate's start-up
        TOLERANCE_RULE, format_cell)
    counts = ", ".join(f"{n} {v}" for v, n in report.counts.items())
    prov = report.provenance
    blocks = [("h1", f"Consistency check of {report.source}"),
              ("p", f"Verdict: {report.verdict.value.upper()} ({counts} rows). Solution map: "
                    f"{report.map_source}. vesicle-tube {prov.get('vesicle-tube', '?')}, "
                    f"commit {prov.get('git_commit', '?')}, {prov.get('date', '')}."),
              ("p", "Rule: " + TOLERANCE_RULE)]
    if report.assumptions:
        blocks.append(("ul", [f"Assumption: {a}" for a in report.assumptions]))
    if report.omitted:
        blocks.append(("p", (f"Listed: {report.listing()}. The rows, the figure, the checks "
                             "and the notes below are those of the rows listed.")))
    blocks += [("h2", "Rows"),
               ("table", ("row", "name", "kind", "verdict", "checks not passed"),
                [(r.row.index, r.row.name, r.row.kind, r.verdict.value,
                  "; ".join(f"{c.name} ({c.verdict.value})" for c in r.checks
                            if c.verdict.value != "pass")) for r in report.rows]),
               ("h2", "Figure"), ("img", figure),
               ("h2", "Checks"),
               ("table", ("row", "check", "verdict", "value", "reference", "deviation",
                          "tolerance", "reference used", "why valid here"),
                [(r.row.index, c.name, c.verdict.value, *(format_cell(x) for x in (
                    c.value, c.reference, c.deviation, c.tolerance)), c.source,
                  c.why + (f" ({c.note})" if c.note else ""))
                 for r in report.rows for c in r.checks])]
    notes = [f"row {r.row.index}: {n}" for r in report.rows for n in r.notes]
    if notes:
        blocks += [("h2", "Notes"), ("ul", notes)]
    return blocks


def _markdown(blocks) -> str:
    def cell(x) -> str:
        return str(x).replace("|", "\\|").replace("\n", " ")
    lines = []
    for kind, *rest in blocks:
        if kind in ("h1", "h2"):
            lines += [("# " if kind == "h1" else "## ") + rest[0], ""]
        elif kind == "p":
            lines += [rest[0], ""]
        elif kind == "ul":
            lines += [f"- {item}" for item in rest[0]] + [""]
        elif kind == "img":
            lines += [f"![V/U and extra pressure drop of the rows over the references]"
                      f"({rest[0]})", ""]
        else:
            head, rows = rest
            lines += ["| " + " | ".join(map(cell, head)) + " |",
                      "|" + "---|" * len(head)]
            lines += ["| " + " | ".join(map(cell, row)) + " |" for row in rows] + [""]
    return "\n".join(lines)


def _html(blocks, png: bytes) -> str:
    e = html.escape
    parts = ["<!DOCTYPE html>", '<html><head><meta charset="utf-8">',
             f"<title>{e(blocks[0][1])}</title>",
             "<style>body{font-family:sans-serif;max-width:80em;margin:auto}"
             "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #ccc;"
             "padding:2px 6px}</style></head><body>"]
    for kind, *rest in blocks:
        if kind in ("h1", "h2", "p"):
            parts.append(f"<{kind}>{e(rest[0])}</{kind}>")
        elif kind == "ul":
            parts.append("<ul>" + "".join(f"<li>{e(str(i))}</li>" for i in rest[0]) + "</ul>")
        elif kind == "img":
            data = base64.b64encode(png).decode("ascii")
            parts.append(f'<img alt="V/U and extra pressure drop of the rows over the '
                         f'references" src="data:image/png;base64,{data}">')
        else:
            head, rows = rest
            parts.append("<table><tr>" + "".join(f"<th>{e(str(h))}</th>" for h in head)
                         + "</tr>" + "".join("<tr>" + "".join(f"<td>{e(str(c))}</td>"
                                                              for c in row) + "</tr>"
                                             for row in rows) + "</table>")
    return "\n".join(parts + ["</body></html>", ""])


def write_report(report, path) -> Path:
    """Write ``report`` (a :class:`~correlations.check.CheckReport`) as Markdown (``.md``,
    ``.markdown``; the figure beside it as ``<stem>.png``) or HTML (``.html``, ``.htm``; the
    figure embedded), each file atomically. Returns the report's path."""
    import matplotlib.pyplot as plt  # lazy: matplotlib
    path = Path(path)
    ax = plot_check(report)
    buffer = io.BytesIO()
    try:
        ax.figure.savefig(buffer, format="png", dpi=120, bbox_inches="tight")
    finally:
        plt.close(ax.figure)
    png = buffer.getvalue()
    figure = path.with_suffix(".png")
    if path.suffix.lower() in (".html", ".htm"):
        text = _html(_blocks(report, figure.name), png)
    else:
        atomic_write(figure, lambda f: f.write(png), binary=True)
        text = _markdown(_blocks(report, figure.name))
    return atomic_write(path, lambda f: f.write(text))


def add_check_parser(subparsers) -> None:
    """Add ``check`` to the subcommands."""
    p = subparsers.add_parser(
        "check", help="check results (CSV or JSON rows: your V/U, dp+, length, film) against "
                      "the physics and our references")
    p.add_argument("file", metavar="FILE",
                   help="CSV (header row, comma-separated) or JSON (a list of objects or "
                        '{"rows": [...]}); columns: docs/user-guide.md "Checking your results"')
    p.add_argument("--report", metavar="FILE.md|FILE.html",
                   help="also write a report with a figure of the rows over the references "
                        "(Markdown: the figure as FILE.png beside it; HTML: embedded)")
    p.add_argument("--no-bem", action="store_true",
                   help="skip the BEM references of sphere and drop rows (about a second per "
                        "(lam, Ca)); the small-object laws remain where valid")
    add_map_option(p, "packed solution map of the vesicle references")
    p.add_argument("--listed-rows", type=positive_int, default=LISTED_ROWS, metavar="N",
                   help=f"list at most N rows in the table, the JSON and the report (default "
                        f"{LISTED_ROWS}): failing rows first, then rows with warnings, then "
                        "passing rows, each in file order; the verdict counts cover every row "
                        "(memory: a few kB per listed row)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=cmd_check)
