"""The command-line contract every ``vesicle-tube`` command follows, in one place.

``vesicle-tube COMMAND [options] [--json]``: people get a table with units, ``--json`` prints one
strict JSON object on stdout (no NaN, no Infinity). Exit status:

* 0 success, every number finite (``check``: no row failed; warnings allowed);
* 2 invalid input: one line on stderr naming the option, its value and the valid range, printed
  before any expensive work (numbers, combinations, output folders and plot formats included);
* 1 a solver did not converge or stopped at its resource limit: a message on stderr; with
  ``--json`` the object is still printed with ``"converged": false`` and without the physical
  numbers of the failed solve; for ``check``, a row failed a check (:data:`EXIT_CHECK_FAILED`,
  the table or ``--json`` printed as usual);
* 130 interrupted (Ctrl-C): one line naming the files already written (each complete);
* 141 stdout closed early (``... | head``): quiet.

Every command module of :mod:`correlations.cli` uses it; the physics libraries know nothing of
it (they raise :class:`lubrication.checks.InvalidParameterError` and return results, and the
command modules turn those into the messages and exit codes here).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import sys
import tempfile
from pathlib import Path

from lubrication import io
from lubrication.checks import InvalidParameterError

from correlations.formatting import format_value, format_value_error

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_INVALID = 0, 1, 2
EXIT_CHECK_FAILED = 1       # vesicle-tube check: a row failed (module docstring)
EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 130, 141

__all__ = ["EXIT_OK", "EXIT_NOT_CONVERGED", "EXIT_INVALID", "EXIT_INTERRUPTED",
           "EXIT_BROKEN_PIPE", "EXIT_CHECK_FAILED", "UsageError", "Parser", "format_rows",
           "format_value", "format_value_error", "REPORT_FORMATS", "check_report_path",
           "check_output_dir", "check_plot_path", "save_plot", "non_finite_keys", "dump_json",
           "finite_float", "positive_int", "add_max_time_option", "add_map_option", "one_line",
           "options_named", "is_interrupt", "interrupted_message"]


class UsageError(Exception):
    """Options given in a combination or with a value the command does not accept (exit 2)."""


def one_line(text: str) -> str:
    """``text`` with every character that is not printable (newlines, control characters a
    user may have typed) written as an escape, so that a message stays one line."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))


class Parser(argparse.ArgumentParser):
    """argparse with the contract's one-line error and exit status 2."""

    def error(self, message):
        self.exit(EXIT_INVALID, f"{one_line(self.prog)}: error: {one_line(message)}\n")


# --------------------------------------------------------------------------- option names

@contextlib.contextmanager
def options_named(options: dict, args=None):
    """Re-raise an :class:`~lubrication.checks.InvalidParameterError` of the library as a
    :class:`UsageError` that starts with the command-line option behind the parameter
    (``options``: parameter name -> option, e.g. ``{"velocity_mm_s": "--velocity-mm-s"}``),
    marked "(default)" when ``args`` shows the user did not type it. Parameters not in
    ``options`` propagate unchanged (their message names the parameter)."""
    try:
        yield
    except InvalidParameterError as exc:
        option = options.get(exc.name)
        if option is None:
            raise
        dest = option.lstrip("-").replace("-", "_")
        default = args is not None and getattr(args, dest, None) is None
        raise UsageError(f"{option}{' (default)' if default else ''}: {exc}") from None


# --------------------------------------------------------------------------- option types

def add_map_option(parser, what: str = "packed solution map") -> None:
    """``--map FILE``: ``what``, in place of the shipped map (``check``, ``infer``, ``figures``,
    ``map query``)."""
    parser.add_argument("--map", metavar="FILE",
                        help=f"{what} (default: the shipped correlations/data/solution_map.json)")


def finite_float(text: str) -> float:
    """argparse type: a finite real number (``nan``, ``inf`` and overflow are refused here, so
    that the message names the option)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: must be an integer >= 1")
    return value


# --------------------------------------------------------------------------- output paths

def _writable_folder(option: str, folder: Path, what: str) -> None:
    """``folder`` (or, if it does not exist yet, its nearest existing parent) is a folder in
    which files can be created; otherwise a :class:`UsageError` naming the option. Tried for
    real (a temporary folder made and removed): permission bits do not tell for root, for
    read-only file systems or for /proc."""
    probe = folder
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        raise UsageError(f"{option} {what}: {str(probe)!r} is a file, not a folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".vesicle-tube-", dir=probe))
    except OSError as exc:
        raise UsageError(f"{option} {what}: cannot write in the folder {str(probe)!r} "
                         f"({exc.strerror or exc})") from None


def check_output_dir(option: str, path) -> Path:
    """Check an output folder option (``--out DIR``) before any work: it is a folder or can be
    created in a writable parent. Returns it as a :class:`~pathlib.Path`."""
    if path is None:
        return None
    if str(path).strip() == "":
        raise UsageError(f"{option}: the folder name is empty")
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"{option} {path}: this is a file, not a folder")
    _writable_folder(option, folder, str(path))
    return folder


def _plot_formats() -> dict:
    """The file formats matplotlib can write, ``{extension: description}``."""
    from matplotlib.backend_bases import FigureCanvasBase  # lazy: matplotlib
    return FigureCanvasBase.get_supported_filetypes()


def _check_file_path(option: str, path, what: str, formats, example: str,
                     optional_extension: bool) -> Path:
    """An output file option checked before any work: its extension is one of ``formats``
    (none allowed when ``optional_extension``), it is not a folder, and its folder exists and
    is writable."""
    if path is None:
        return None
    if str(path).strip() == "":
        raise UsageError(f"{option}: the file name is empty")
    p = Path(path)
    ext = p.suffix.lstrip(".").lower()
    if (ext or not optional_extension) and ext not in formats:
        raise UsageError(f"{option} {path}: unknown {what} format {ext!r}; valid: "
                         + ", ".join(sorted(formats)))
    if p.is_dir() or str(path).endswith(os.sep):
        raise UsageError(f"{option} {path}: this is a folder; give a file name, e.g. "
                         f"{os.path.join(str(path), example)}")
    if not p.parent.is_dir():
        raise UsageError(f"{option} {path}: the folder {str(p.parent)!r} does not exist")
    _writable_folder(option, p.parent, str(path))
    return p


def check_plot_path(option: str, path) -> Path:
    """Check a figure file option (``--plot FILE``) before any work: its extension is a format
    matplotlib writes (no extension: PNG), it is not a folder, and its folder exists and is
    writable. Returns the path."""
    return _check_file_path(option, path, "figure", _plot_formats() if path else (),
                            "figure.png", optional_extension=True)


#: Formats of a written report, by extension.
REPORT_FORMATS = {"md": "Markdown", "markdown": "Markdown", "html": "HTML", "htm": "HTML"}


def check_report_path(option: str, path) -> Path:
    """Check a report file option (``--report FILE.md|FILE.html``) before any work, as
    :func:`check_plot_path` (the extension is required: one of :data:`REPORT_FORMATS`)."""
    return _check_file_path(option, path, "report", REPORT_FORMATS, "report.md",
                            optional_extension=False)


def save_plot(ax, path) -> Path:
    """Write the figure of ``ax`` to ``path`` atomically (PNG when there is no extension)."""
    import matplotlib.pyplot as plt  # lazy: matplotlib
    ext = Path(path).suffix.lstrip(".").lower() or "png"
    try:
        io.atomic_write(path, lambda f: ax.figure.savefig(f, format=ext, dpi=150,
                                                          bbox_inches="tight"), binary=True)
    finally:
        plt.close(ax.figure)
    return Path(path)


# --------------------------------------------------------------------------- tables and JSON

def format_rows(rows, title: str = "") -> str:
    """Fixed-width table of (quantity, value, scaling or unit, method, flag) rows."""
    head = ("quantity", "value", "unit / scaling", "method", "")
    cells = [head] + [tuple(format_value(c) if i == 1 else ("" if c is None else str(c))
                            for i, c in enumerate(r)) for r in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(4)]
    lines = [title] if title else []
    for k, r in enumerate(cells):
        lines.append("  ".join(c.ljust(w) for c, w in zip(r[:4], widths))
                     + ("  " + r[4] if r[4] else ""))
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines)


def _plain(x):
    """numpy scalars and arrays as Python numbers and lists, anything else (paths) as text."""
    return x.tolist() if hasattr(x, "tolist") else str(x)


def non_finite_keys(obj, prefix: str = "") -> list[str]:
    """Dotted keys of every NaN or infinite number inside a JSON-like object."""
    bad = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            bad += non_finite_keys(v, f"{prefix}{k}.")
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            bad += non_finite_keys(v, f"{prefix}{i}.")
    elif hasattr(obj, "tolist") and not isinstance(obj, (str, bytes)):
        return non_finite_keys(obj.tolist(), prefix)
    elif isinstance(obj, float) and not math.isfinite(obj):
        bad.append(prefix.rstrip(".") or "value")
    return bad


def dump_json(obj) -> str:
    """Strict JSON (``allow_nan=False``); the caller has removed non-finite numbers."""
    return json.dumps(obj, indent=2, default=_plain, ensure_ascii=False, allow_nan=False)


# --------------------------------------------------------------------------- clean exits

def quiet_broken_pipe() -> int:
    """After stdout was closed by the reader: silence the interpreter's final flush."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass
    return EXIT_BROKEN_PIPE


def is_interrupt(exc: BaseException) -> bool:
    """True for a KeyboardInterrupt, or an error raised because of one: a Ctrl-C that lands
    while numba-compiled code calls back into Python surfaces as a SystemError ("returned a
    result with an exception set") whose cause is the KeyboardInterrupt."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def interrupted_message(prog: str) -> str:
    """The one line printed on Ctrl-C: which files (all complete) were written before it."""
    files = io.written_files()
    if files:
        return (f"{prog}: interrupted; complete files written before the interrupt: "
                + ", ".join(map(str, files)))
    return f"{prog}: interrupted; no file was written"


def add_max_time_option(parser, default: float | None = None) -> None:
    """``--max-time SECONDS``: the wall-time budget of a solver command (exit 1 when spent)."""
    parser.add_argument("--max-time", type=finite_float, default=default, dest="max_time",
                        metavar="SECONDS",
                        help="stop the solve after this wall time and report it as not "
                             "converged (exit 1) [s]"
                             + (f" (default {default:g})" if default is not None else
                                " (default: no limit)"))
