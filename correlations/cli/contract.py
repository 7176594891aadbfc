"""The command-line contract every ``vesicle-tube`` command follows, in one place.

``vesicle-tube COMMAND [options] [--json]``: people get a table with units, ``--json`` prints one
strict JSON object on stdout (no NaN, no Infinity). Exit status:

* 0 success, every number finite (``check``: no row failed; warnings allowed). A converged solve
  whose number breaks a physical bound (:data:`lubrication.checks.OUTPUT_BOUNDS`, e.g. dp+ < 0
  from the lubrication model of a short vesicle) is still 0: the number is the model's own
  answer, flagged (``"unphysical"`` in the JSON, ``warning: UNPHYSICAL ...`` on stderr and a
  line under the table) as a model used beyond its meaning; 1 is kept for work that could not
  be completed;
* 2 invalid input: one line on stderr naming the option, its value and the valid range, printed
  before any expensive work (numbers, counts with their maximum, combinations, output folders
  and files: writable, not a folder where a file goes, names and paths within the file
  system's limits, plot formats);
* 1 the work could not be completed (:data:`EXIT_NOT_CONVERGED`, the same code as
  :data:`EXIT_NOT_WRITTEN`):

  - a solver did not converge or stopped at its resource limit: a message on stderr; with
    ``--json`` the object is still printed with ``"converged": false`` and without the
    physical numbers of the failed solve; for ``check``, a row failed a check
    (:data:`EXIT_CHECK_FAILED`, the table or ``--json`` printed as usual);
  - a result file (``--out``, ``--plot``, ``--report``) could not be written at the end of the
    work (full disk, permission, a folder where the file goes): one line per file on stderr
    naming it and the system's reason; the result is still printed, its JSON listing the file
    under ``"not_written"``; every file is complete or absent (no temporary file is left);
  - stdout could not be written (a full disk, an I/O error): one line on stderr,
    ``cannot write the output: <reason>``;

* 130 interrupted (Ctrl-C): one line naming the files already written (each complete);
* 141 stdout closed early (``... | head``): quiet.

Text a stream cannot encode (``PYTHONIOENCODING=ascii``, a C locale) is written with ASCII
spellings (µm as um, ν as nu, Δp⁺ as dp+, :data:`ASCII_SPELLINGS`; other characters as
``\\u`` escapes), and ``--json`` is then written ASCII-only (the same JSON, with ``\\u``
escapes). Messages that stderr cannot take (a full disk) are dropped; the exit status still
tells.

Every command module of :mod:`correlations.cli` uses it; the physics libraries know nothing of
it (they raise :class:`lubrication.checks.InvalidParameterError` and
:class:`lubrication.io.WriteError` and return results, and the command modules turn those into
the messages and exit codes here).
"""

from __future__ import annotations

import argparse
import codecs
import contextlib
import json
import math
import os
import re
import sys
import tempfile
import unicodedata
from pathlib import Path

from lubrication import io
from lubrication.checks import InvalidParameterError

from correlations.files import UnreadableFile
from correlations.formatting import format_value, format_value_error, one_line, short_path

EXIT_OK, EXIT_NOT_CONVERGED, EXIT_INVALID = 0, 1, 2
EXIT_CHECK_FAILED = 1       # vesicle-tube check: a row failed (module docstring)
EXIT_NOT_WRITTEN = 1        # the output or a result file could not be written (module docstring)
EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 130, 141

__all__ = ["EXIT_OK", "EXIT_NOT_CONVERGED", "EXIT_INVALID", "EXIT_INTERRUPTED",
           "EXIT_BROKEN_PIPE", "EXIT_CHECK_FAILED", "EXIT_NOT_WRITTEN", "UsageError", "Parser",
           "format_rows", "format_value", "format_value_error", "REPORT_FORMATS",
           "MAX_OUTPUT_NAME", "check_report_path", "check_output_dir", "check_targets",
           "check_plot_path", "save_plot", "saved", "not_written_message", "non_finite_keys", "dump_json",
           "finite_float", "positive_int", "add_max_time_option", "add_map_option", "one_line",
           "short_path", "options_named", "is_interrupt", "interrupted_message",
           "ASCII_SPELLINGS", "command_streams", "output_failed", "os_error_message"]


class UsageError(Exception):
    """Options given in a combination or with a value the command does not accept (exit 2)."""


_NEGATIVE_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$",
                              re.IGNORECASE)


class Parser(argparse.ArgumentParser):
    """argparse with the contract's one-line error and exit status 2, and a help text whose
    failed write (stdout on a full disk) raises, as every output of the command line does,
    instead of being dropped."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # argparse takes "-1e5" and "-inf" for options (its pattern of a negative number has
        # no exponent), so "--nu -1e5" would fail as "expected one argument" instead of
        # reaching the option's check: every negative number is a value here
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message):
        self.exit(EXIT_INVALID, f"{one_line(self.prog)}: error: {one_line(message)}\n")

    def print_help(self, file=None):
        file = sys.stdout if file is None else file
        file.write(self.format_help())
        file.flush()


# --------------------------------------------------------------------------- option names

@contextlib.contextmanager
def options_named(options: dict, args=None):
    """Re-raise an :class:`~lubrication.checks.InvalidParameterError` of the library as a
    :class:`UsageError` that starts with the command-line option behind the parameter
    (``options``: parameter name -> option, e.g. ``{"velocity_mm_s": "--velocity-mm-s"}``),
    marked "(default)" when ``args`` shows the user did not type it. Parameters not in
    ``options`` propagate unchanged (their message names the parameter). A file's error
    (:class:`~correlations.files.UnreadableFile`, "name path: reason") takes the option in
    the place of the parameter's name."""
    try:
        yield
    except InvalidParameterError as exc:
        option = options.get(exc.name)
        if option is None:
            raise
        dest = option.lstrip("-").replace("-", "_")
        default = args is not None and getattr(args, dest, None) is None
        option += " (default)" if default else ""
        if isinstance(exc, UnreadableFile):
            raise UsageError(f"{option} {exc.detail}") from None
        raise UsageError(f"{option}: {exc}") from None


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


def positive_int(text: str, minimum: int = 1, maximum: int | None = None,
                 reason: str = "") -> int:
    """argparse type: an integer ``minimum <= value <= maximum`` (no upper bound when
    ``maximum`` is None; ``reason`` says where the maximum comes from); bind the bounds with
    :func:`functools.partial`. A number with more digits than Python converts is above any
    maximum."""
    shown = repr(short_path(text, 40))
    too_large = (f"{shown}: must be at most {maximum}" + (f" ({reason})" if reason else "")
                 if maximum is not None else "")
    try:
        value = int(text)
    except ValueError:
        if too_large and text.strip().lstrip("+-").isdecimal():    # too many digits
            raise argparse.ArgumentTypeError(too_large) from None
        raise argparse.ArgumentTypeError(f"{shown} is not an integer") from None
    if value < minimum:
        raise argparse.ArgumentTypeError(f"{shown}: must be an integer, at least {minimum}")
    if maximum is not None and value > maximum:
        raise argparse.ArgumentTypeError(too_large)
    return value


# --------------------------------------------------------------------------- output paths

#: The longest name [bytes] of a file a command writes into an output folder (``--out DIR``):
#: the longest stem, ``lubrication_nu<nu>_lam<lam>_bending_caB<ca_b>_failed.json``
#: (lubrication/results.py), has 77 bytes with numbers of 13 characters (``-1.23457e-100``), the
#: others fewer (bem/results.py, bem/sweep.py, the map's point files); 100 leaves room.
MAX_OUTPUT_NAME = 100


def _check_lengths(option: str, path, extra: int) -> None:
    """Every name in ``path`` fits the file system's name limit and the absolute path, plus
    ``extra`` bytes of what the command writes below or beside it, its path limit
    (:func:`lubrication.io.path_limits`); otherwise a :class:`UsageError` naming the option."""
    absolute = os.path.abspath(path)
    name_max, path_max = io.path_limits(absolute)
    for part in Path(absolute).parts:
        size = len(os.fsencode(part))
        if size > name_max:
            raise UsageError(f"{option} {short_path(path)}: the name {short_path(part, 40)!r} "
                             f"has {size} bytes; the file system allows {name_max} bytes per "
                             "name (PC_NAME_MAX)")
    size = len(os.fsencode(absolute))
    if size + extra > path_max - 1:
        raise UsageError(f"{option} {short_path(path)}: the path is too long: {size} bytes, "
                         f"{extra} more for the files written there, where the file system "
                         f"allows {path_max - 1} bytes (PC_PATH_MAX)")


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
        raise UsageError(f"{option} {what}: {short_path(probe)!r} is a file, not a folder")
    try:
        os.rmdir(tempfile.mkdtemp(prefix=".vesicle-tube-", dir=probe))
    except OSError as exc:
        raise UsageError(f"{option} {what}: cannot write in the folder {short_path(probe)!r} "
                         f"({exc.strerror or exc})") from None


@contextlib.contextmanager
def _looked_up(option: str, path):
    """A failure to look ``path`` up (permission on a parent, a loop of links) as a
    :class:`UsageError` naming the option."""
    try:
        yield
    except OSError as exc:
        raise UsageError(f"{option} {short_path(path)}: {exc.strerror or exc}") from None


def check_targets(option: str, files=(), folders=()) -> None:
    """Check, before any work, the fixed names a command writes under an output option:
    none of ``files`` is a folder and none of ``folders`` is a file (a :class:`UsageError`
    naming the option), so that a result is not computed only to fail at its last write."""
    for path in map(Path, files):
        if path.is_dir():
            raise UsageError(f"{option}: {short_path(path)} is a folder where this command "
                             "writes a file; move it away or choose another output")
    for path in map(Path, folders):
        if path.exists() and not path.is_dir():
            raise UsageError(f"{option}: {short_path(path)} is a file where this command "
                             "keeps a folder; move it away or choose another output")


def check_output_dir(option: str, path) -> Path:
    """Check an output folder option (``--out DIR``) before any work: its names and length
    leave room for the files written in it (:data:`MAX_OUTPUT_NAME`, within the file system's
    limits), and it is a folder or can be created in a writable parent. Returns it as a
    :class:`~pathlib.Path`. Which files a command writes there depends on its results; a
    folder found in the place of one of them is reported when it is written (exit 1)."""
    if path is None:
        return None
    if str(path).strip() == "":
        raise UsageError(f"{option}: the folder name is empty")
    name_max = io.path_limits(path)[0]
    if MAX_OUTPUT_NAME > name_max:
        raise UsageError(f"{option} {short_path(path)}: the file system allows names of "
                         f"{name_max} bytes; the files written there have up to "
                         f"{MAX_OUTPUT_NAME}")
    _check_lengths(option, path, 1 + MAX_OUTPUT_NAME + io.TEMPORARY_EXTRA)
    folder = Path(path)
    with _looked_up(option, path):
        if folder.exists() and not folder.is_dir():
            raise UsageError(f"{option} {short_path(path)}: this is a file, not a folder")
        _writable_folder(option, folder, short_path(path))
    return folder


def _plot_formats() -> dict:
    """The file formats matplotlib can write, ``{extension: description}``."""
    from matplotlib.backend_bases import FigureCanvasBase  # lazy: matplotlib
    return FigureCanvasBase.get_supported_filetypes()


def _check_file_path(option: str, path, what: str, formats, example: str,
                     optional_extension: bool) -> Path:
    """An output file option checked before any work: its extension is one of ``formats``
    (none allowed when ``optional_extension``), its name and path fit the file system's limits
    (with its temporary file), it is not a folder, and its folder exists and is writable."""
    if path is None:
        return None
    if str(path).strip() == "":
        raise UsageError(f"{option}: the file name is empty")
    p = Path(path)
    ext = p.suffix.lstrip(".").lower()
    if (ext or not optional_extension) and ext not in formats:
        raise UsageError(f"{option} {short_path(path)}: unknown {what} format {ext!r}; valid: "
                         + ", ".join(sorted(formats)))
    _check_lengths(option, path, io.TEMPORARY_EXTRA)
    with _looked_up(option, path):
        if p.is_dir() or str(path).endswith(os.sep):
            raise UsageError(f"{option} {short_path(path)}: this is a folder; give a file "
                             f"name, e.g. {os.path.join(short_path(path), example)}")
        if not p.parent.is_dir():
            raise UsageError(f"{option} {short_path(path)}: the folder "
                             f"{short_path(p.parent)!r} does not exist")
        _writable_folder(option, p.parent, short_path(path))
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
    """Write the figure of ``ax`` to ``path`` atomically (PNG when there is no extension);
    :class:`lubrication.io.WriteError` if it cannot be written."""
    import matplotlib.pyplot as plt  # lazy: matplotlib
    ext = Path(path).suffix.lstrip(".").lower() or "png"
    try:
        io.atomic_write(path, lambda f: ax.figure.savefig(f, format=ext, dpi=150,
                                                          bbox_inches="tight"), binary=True)
    finally:
        plt.close(ax.figure)
    return Path(path)


def saved(out: dict, option: str, save):
    """``save()`` (the writer of the files of output option ``option``) and what it returns; a
    file it cannot write (:class:`lubrication.io.WriteError`) is recorded in
    ``out["not_written"]`` (option, file, reason, and the files of this save written before
    it) and None returned, so that the command still prints the result it computed, then
    exits 1 naming the file (:func:`not_written_message`)."""
    before = set(io.written_files())
    try:
        return save()
    except io.WriteError as exc:
        out.setdefault("not_written", []).append(
            {"option": option, "file": exc.filename, "reason": exc.strerror,
             "written": [str(p) for p in io.written_files() if p not in before]})
        return None


def not_written_message(entry: dict) -> str:
    """The line of an entry of ``out["not_written"]`` (:func:`saved`): the file, the reason,
    and what of the option's output exists."""
    option, written = entry["option"], entry["written"]
    return (f"{option}: cannot write {short_path(entry['file'])}: {entry['reason']}; the work "
            f"was done and its result is printed, but {option} is incomplete ("
            + (f"written: {', '.join(map(short_path, written))}" if written else
               "none of its files was written") + ")")


def os_error_message(exc: OSError) -> str:
    """One line for an operating-system failure: "cannot write FILE: reason" for a result file
    (:class:`lubrication.io.WriteError`), else the reason and the file it names."""
    reason = exc.strerror or str(exc)
    if isinstance(exc, io.WriteError):
        return f"cannot write {short_path(exc.filename)}: {reason}"
    return f"{short_path(exc.filename)}: {reason}" if exc.filename else one_line(reason)


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


def dump_json(obj, stream=None) -> str:
    """Strict JSON (``allow_nan=False``); the caller has removed non-finite numbers. Characters
    are written as they are, or all non-ASCII ones as ``\\u`` escapes (the same JSON) when
    the encoding of ``stream`` (the stdout it is printed on) cannot write them."""
    text = json.dumps(obj, indent=2, default=_plain, ensure_ascii=False, allow_nan=False)
    try:
        text.encode(getattr(stream, "encoding", None) or "utf-8")
    except (UnicodeEncodeError, LookupError):
        text = json.dumps(obj, indent=2, default=_plain, ensure_ascii=True, allow_nan=False)
    return text


# --------------------------------------------------------------------------- streams

#: ASCII spellings of the symbols in the tables and messages, for a stream that cannot encode
#: them (the names the options and JSON keys use: nu, lam, dp+, um); a character not listed is
#: decomposed to ASCII where it can be (é as e), else written as its backslash escape.
ASCII_SPELLINGS = {
    "µ": "u", "μ": "u", "ν": "nu", "λ": "lam", "Δ": "d", "δ": "delta", "γ": "gamma",
    "η": "eta", "κ": "kappa", "ε": "eps", "π": "pi", "σ": "sigma", "τ": "tau", "ρ": "rho",
    "α": "alpha", "β": "beta", "ω": "omega", "Ω": "Omega", "Σ": "Sigma", "ℓ": "ell",
    "⁺": "+", "⁻": "-", "²": "^2", "³": "^3", "±": "+/-", "×": "x", "·": ".", "÷": "/",
    "−": "-", "–": "-", "—": "-", "≤": "<=", "≥": ">=", "≈": "~", "≃": "~", "∼": "~",
    "≲": "<~", "≪": "<<", "∝": "~", "→": "->", "∞": "inf", "√": "sqrt", "°": "deg",
    "§": "sec. ", "…": "...", "æ": "ae", "Æ": "AE", "‘": "'", "’": "'", "“": '"', "”": '"',
}
_ASCII_FALLBACK = "vesicle-tube-ascii"


def _ascii_fallback(error: UnicodeEncodeError):
    """Codec error handler: :data:`ASCII_SPELLINGS`, else the character decomposed to ASCII
    (NFKD), else its backslash escape."""
    out = []
    for c in error.object[error.start:error.end]:
        spelling = ASCII_SPELLINGS.get(c)
        if spelling is None:
            spelling = (unicodedata.normalize("NFKD", c).encode("ascii", "ignore").decode()
                        or c.encode("ascii", "backslashreplace").decode())
        out.append(spelling)
    return "".join(out), error.end


codecs.register_error(_ASCII_FALLBACK, _ascii_fallback)


class _Tolerant:
    """A text stream whose writes never raise: what a stream that cannot be written (stderr on
    a full disk) refuses is dropped, so that a message never turns into a traceback or changes
    the exit status."""

    def __init__(self, stream):
        self._stream = stream

    def write(self, text):
        try:
            return self._stream.write(text)
        except (OSError, ValueError):       # ValueError: the stream was closed
            return len(text)

    def flush(self):
        with contextlib.suppress(OSError, ValueError):
            self._stream.flush()

    def __getattr__(self, name):
        return getattr(self._stream, name)


@contextlib.contextmanager
def command_streams():
    """Standard streams for one command: stdout and stderr write what their encoding cannot
    with the ASCII spellings (module docstring), and stderr never raises (:class:`_Tolerant`);
    stdout still raises, so that a result that cannot be written is reported
    (:func:`output_failed`)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(AttributeError, OSError, ValueError):   # not a TextIOWrapper
            stream.reconfigure(errors=_ASCII_FALLBACK)
    stderr = sys.stderr
    if stderr is not None:
        sys.stderr = _Tolerant(stderr)
    try:
        yield
    finally:
        sys.stderr = stderr


def _discard_stdout() -> None:
    """Point stdout's file descriptor at /dev/null, so that the interpreter's final flush of
    what could not be written succeeds quietly."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):
        pass


def output_failed(prog: str, exc: OSError) -> int:
    """stdout could not be written (a full disk, an I/O error): one line on stderr, exit 1."""
    _discard_stdout()
    print(f"{prog}: error: cannot write the output: {exc.strerror or exc}", file=sys.stderr)
    return EXIT_NOT_WRITTEN


# --------------------------------------------------------------------------- clean exits

def quiet_broken_pipe() -> int:
    """After stdout was closed by the reader: silence the interpreter's final flush."""
    _discard_stdout()
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
