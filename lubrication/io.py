"""Result output shared by every writer of the project: atomic files, strict JSON, provenance.

A result file is written to a temporary file in the target directory and renamed over the target
(:func:`os.replace` is atomic on POSIX), so an interrupted run never leaves a half-written file.
A file that cannot be written (a full disk, no permission, a name too long, a folder where the
file should go) raises :class:`WriteError` naming the target and the operating system's reason;
the temporary file is removed and the target is left as it was.

Non-finite numbers (the one policy of every result file): JSON has no NaN or infinity, so
:func:`clean_json` writes them as ``null`` (Python None), and a CSV cell holding one is left
empty. A non-finite number in a result is either missing (the physical outputs of a failed
solve, an error estimate without a refinement pair) or an infinite parameter whose meaning is
stated beside it (``"ca_b": null`` with ``"model": "high-Ca"``). ``null`` rather than strings
such as ``"NaN"`` or ``"Infinity"``: every strict JSON reader (Python with ``allow_nan=False``,
JavaScript, jq) accepts it, a numeric field stays numeric-or-missing (a string would make every
reader special-case the field, and pandas read the column as text), and the difference between
NaN and infinity is carried by the fields beside it (``converged``, ``message``, ``model``). The
files are then written with ``allow_nan=False``, so that a value this cleaning misses is an
error, never an invalid file.

Provenance (:func:`provenance`): the versions of the package and of its numerical
dependencies, the git commit of the source tree and the date, recorded in every result.
"""

from __future__ import annotations

import contextlib
import csv
import datetime
import errno
import functools
import json
import math
import os
import platform
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import lubrication   # the package's __version__, read at call time (no import-order dependency)

__all__ = ["TEMPORARY_EXTRA", "WriteError", "atomic_write", "temporary_target", "clean_json",
           "forget_written_files", "make_folder", "path_limits", "provenance", "save_json",
           "save_result", "write_json", "written_files"]

# Every file completed by atomic_write in this process, in order: the command line names them
# after a run, and after an interrupt (each of them is complete).
_WRITTEN: list[Path] = []


def written_files() -> list[Path]:
    """The files :func:`atomic_write` has completed in this process (oldest first, no repeats)."""
    return list(dict.fromkeys(_WRITTEN))


def forget_written_files() -> None:
    """Start a new record of written files (called at the start of each command)."""
    _WRITTEN.clear()


class WriteError(OSError):
    """A result file could not be written: ``filename`` is the file, ``strerror`` the operating
    system's reason (``errno`` its code). Nothing was left behind: the target is as it was
    before and the temporary file is removed."""


def _write_error(exc: OSError, path) -> WriteError:
    """``exc`` (raised while writing ``path``) as a :class:`WriteError` naming ``path``."""
    if isinstance(exc, WriteError):
        return exc
    return WriteError(exc.errno, exc.strerror or str(exc), str(path))


def path_limits(folder) -> tuple[int, int]:
    """``(NAME_MAX, PATH_MAX)`` in bytes of the file system holding ``folder`` (or its nearest
    existing parent), by :func:`os.pathconf`; the Linux values 255 and 4096 where the system
    does not tell. PATH_MAX counts the terminating NUL: a path may have PATH_MAX - 1 bytes."""
    folder = Path(os.path.abspath(folder))
    for probe in (folder, *folder.parents):
        try:
            if probe.is_dir():
                break
        except OSError:             # e.g. the name itself is too long to look up
            continue
    limits = []
    for name, default in (("PC_NAME_MAX", 255), ("PC_PATH_MAX", 4096)):
        try:
            limits.append(os.pathconf(probe, name))
        except (OSError, ValueError):
            limits.append(default)
    return limits[0], limits[1]


#: The temporary file of :func:`atomic_write` is ".NAME.XXXXXXXX.tmp" (mkstemp: 8 random
#: characters): this many bytes more than NAME, which is shortened where the file system's name
#: limit needs it (so its path is at most this much longer than the target's).
TEMPORARY_EXTRA = len("." + "." + "XXXXXXXX" + ".tmp")
# mkstemp's random part: 8 characters of [a-z0-9_] (tempfile._RandomNameSequence)
_TEMPORARY = re.compile(r"\.(.+)\.[a-z0-9_]{8}\.tmp")


def temporary_target(name: str) -> str | None:
    """The name of the file whose :func:`atomic_write` temporary ``name`` is
    (``.NAME.XXXXXXXX.tmp`` -> NAME), or None when ``name`` has not that form (a user's
    ``.notes.old.tmp``).

    Examples
    --------
    >>> temporary_target(".build.json.k2x_9ab0.tmp"), temporary_target(".build.json.old.tmp")
    ('build.json', None)
    """
    match = _TEMPORARY.fullmatch(name)
    return match.group(1) if match else None


def _refuse_folder(path: Path) -> None:
    """Raise :class:`WriteError` when ``path`` is an existing folder (EISDIR) or cannot be looked
    up (e.g. its name is too long)."""
    try:
        folder = path.is_dir()
    except OSError as exc:
        raise _write_error(exc, path) from exc
    if folder:
        raise WriteError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))


def atomic_write(path, write, *, binary: bool = False) -> Path:
    """Call ``write(file)`` on a temporary file beside ``path``, then rename it to ``path``.

    The file gets the permissions of a normally created file (0666 minus the umask; mkstemp
    alone would leave 0600). Text files are UTF-8 with untranslated newlines. Returns the path.
    Any operating-system failure (full disk, permission, read-only folder, a name too long, a
    folder at ``path``) raises :class:`WriteError` naming ``path``, after the temporary file
    is removed; ``path`` is then unchanged. The temporary file's name is NAME shortened, where
    needed, so that any name the file system accepts can be written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
    >>> atomic_write(p, lambda f: f.write("ok")).read_text()
    'ok'
    """
    path = Path(path)
    tmp = None
    try:
        _refuse_folder(path)
        room = max(path_limits(path.parent)[0] - TEMPORARY_EXTRA, 0)
        name = os.fsdecode(os.fsencode(path.name)[:room])
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{name}.", suffix=".tmp")
        with (os.fdopen(fd, "wb") if binary else
              os.fdopen(fd, "w", newline="", encoding="utf-8")) as f:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        _WRITTEN.append(path)
    except BaseException as exc:
        if tmp is not None:
            with contextlib.suppress(OSError):      # already gone, or the folder went away
                os.unlink(tmp)
        if isinstance(exc, OSError):
            raise _write_error(exc, path) from exc
        raise
    return path


def clean_json(value):
    """``value`` as strict-JSON data: NaN and +-inf -> None (the policy of the module docstring).

    numpy scalars and arrays become Python numbers and (nested) lists, tuples become lists,
    dicts and lists are cleaned item by item; anything else is returned unchanged.

    Examples
    --------
    >>> import numpy as np
    >>> clean_json({"V": np.float64(1.5), "ca_b": float("inf"), "ok": np.bool_(True),
    ...             "x": np.array([1.0, np.nan]), "n": (np.int64(3), -float("inf"))})
    {'V': 1.5, 'ca_b': None, 'ok': True, 'x': [1.0, None], 'n': [3, None]}
    """
    if isinstance(value, dict):
        return {k: clean_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [clean_json(v) for v in value]
    if hasattr(value, "tolist") and not isinstance(value, (str, bytes)):
        return clean_json(value.tolist())          # numpy scalar or array
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write_json(path, data, *, indent: int = 2, sort_keys: bool = True) -> Path:
    """Write ``clean_json(data)`` as strict JSON to ``path`` atomically; returns the path."""
    data = clean_json(data)
    return atomic_write(path, lambda f: json.dump(data, f, indent=indent, sort_keys=sort_keys,
                                                  allow_nan=False))


def make_folder(directory) -> None:
    """Create ``directory`` (and its parents) if needed; :class:`WriteError` if it cannot be."""
    try:
        Path(directory).mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise _write_error(exc, directory) from exc


def save_json(directory, stem: str, data: dict) -> Path:
    """Write ``<directory>/<stem>.json`` by :func:`write_json`, creating ``directory``."""
    directory = Path(directory)
    make_folder(directory)
    return write_json(directory / f"{stem}.json", data)


def _csv_cell(value) -> str:
    """A number for a CSV cell: ``repr`` (round-trip exact), empty if not finite."""
    value = float(value)
    return repr(value) if math.isfinite(value) else ""


def save_result(directory, stem: str, data: dict, columns, profiles) -> tuple[Path, Path]:
    """Write ``<stem>.json`` (``data`` plus the column legend) and ``<stem>.csv`` (profiles).

    ``columns`` is a sequence of ``(name, description with unit)``; ``profiles(name)`` returns
    the array of that column. Both files are written atomically (:func:`atomic_write`), the
    JSON by :func:`write_json`; floats in the CSV are written with ``repr`` (round-trip exact),
    a non-finite one as an empty cell. A folder in the place of either file is refused
    (:class:`WriteError`) before either is written. Returns the two paths.
    """
    json_path, csv_path = Path(directory) / f"{stem}.json", Path(directory) / f"{stem}.csv"
    for path in (json_path, csv_path):
        _refuse_folder(path)
    json_path = save_json(directory, stem, dict(data, profile_columns=dict(columns)))

    def write_csv(f):
        w = csv.writer(f, lineterminator="\n")
        w.writerow([name for name, _ in columns])
        for row in zip(*(profiles(name) for name, _ in columns)):
            w.writerow([_csv_cell(v) for v in row])

    atomic_write(csv_path, write_csv)
    return json_path, csv_path


@functools.cache
def _git_commit() -> str:
    """The git commit of the source tree, "unknown" outside a git checkout of this project
    (once a process): an installed package inside a user's own repository is not that
    repository's commit."""
    root = Path(__file__).resolve().parents[1]
    try:
        git = subprocess.run(["git", "rev-parse", "--show-toplevel", "HEAD"], cwd=root,
                             capture_output=True, text=True, timeout=5, check=False)
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    lines = git.stdout.split()
    if git.returncode or len(lines) != 2 or Path(lines[0]).resolve() != root:
        return "unknown"
    return lines[1]


def provenance() -> dict:
    """Where a result comes from: ``vesicle-tube`` (the package version), ``python``, the
    versions of those of ``numpy``, ``scipy`` and ``numba`` that this process has loaded (the
    libraries the result can depend on; read from the modules, since a metadata lookup of
    packages not loaded costs tens of ms and the estimate's start-up must stay light),
    ``git_commit`` (of the source tree, "unknown" outside a git checkout) and ``date`` (now,
    UTC, ISO 8601 to the second).

    Examples
    --------
    >>> import numpy
    >>> {"vesicle-tube", "python", "numpy", "git_commit", "date"} <= set(provenance())
    True
    """
    out = {"vesicle-tube": lubrication.__version__, "python": platform.python_version()}
    for name in ("numpy", "scipy", "numba"):
        version = getattr(sys.modules.get(name), "__version__", None)
        if version is not None:
            out[name] = version
    out["git_commit"] = _git_commit()
    out["date"] = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    return out
