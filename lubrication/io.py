"""Atomic file output shared by every result writer of the project.

A result file is written to a temporary file in the target directory and renamed over the target
(:func:`os.replace` is atomic on POSIX), so an interrupted run never leaves a half-written file.
"""

from __future__ import annotations

import csv
import json
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_write", "save_result", "written_files", "forget_written_files"]

# Every file completed by atomic_write in this process, in order: the command line names them
# after a run, and after an interrupt (each of them is complete).
_WRITTEN: list[Path] = []


def written_files() -> list[Path]:
    """The files :func:`atomic_write` has completed in this process (oldest first, no repeats)."""
    return list(dict.fromkeys(_WRITTEN))


def forget_written_files() -> None:
    """Start a new record of written files (called at the start of each command)."""
    _WRITTEN.clear()


def atomic_write(path, write, *, binary: bool = False) -> Path:
    """Call ``write(file)`` on a temporary file beside ``path``, then rename it to ``path``.

    The file gets the permissions of a normally created file (0666 minus the umask; mkstemp
    alone would leave 0600). Text files are UTF-8 with untranslated newlines. Returns the path.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a.txt"
    >>> atomic_write(p, lambda f: f.write("ok")).read_text()
    'ok'
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    umask = os.umask(0)
    os.umask(umask)
    try:
        os.chmod(tmp, 0o666 & ~umask)
        with (os.fdopen(fd, "wb") if binary else
              os.fdopen(fd, "w", newline="", encoding="utf-8")) as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
        _WRITTEN.append(path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def save_result(directory, stem: str, data: dict, columns, profiles) -> tuple[Path, Path]:
    """Write ``<stem>.json`` (``data`` plus the column legend) and ``<stem>.csv`` (profiles).

    ``columns`` is a sequence of ``(name, description with unit)``; ``profiles(name)`` returns
    the array of that column. Both files are written atomically (:func:`atomic_write`); floats
    in the CSV are written with ``repr`` (round-trip exact). Returns the two paths.
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    json_path, csv_path = directory / f"{stem}.json", directory / f"{stem}.csv"
    data = dict(data, profile_columns=dict(columns))
    atomic_write(json_path, lambda f: json.dump(data, f, indent=2, sort_keys=True, allow_nan=False))

    def write_csv(f):
        w = csv.writer(f, lineterminator="\n")
        w.writerow([name for name, _ in columns])
        for row in zip(*(profiles(name) for name, _ in columns)):
            w.writerow([repr(float(v)) for v in row])

    atomic_write(csv_path, write_csv)
    return json_path, csv_path
