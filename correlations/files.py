"""The one reader of every file the tool accepts: map files, build folders, result tables.

Every input file passes the same gate before it is parsed (:func:`check_input_file`): it exists,
it is a regular file (a FIFO would block, ``/dev/zero`` never ends, a folder is not a file), it
is readable and not larger than the limit for its kind. JSON is then parsed strictly
(:func:`read_json`): no NaN, Infinity or number that overflows a double, integers of at most
:data:`MAX_INT_DIGITS` digits, nesting of at most ``max_depth`` levels, UTF-8 text. Every
failure is an :class:`UnreadableFile`, an :class:`~lubrication.checks.InvalidParameterError`
that names the option (or parameter) that gave the file, the file and what is wrong, so that
the command line answers with exit 2 and one line. What a file must contain (its schema) is checked by its
reader after parsing, with :func:`expect`.
"""

from __future__ import annotations

import json
import math
import os
import stat
from pathlib import Path

from lubrication.checks import InvalidParameterError

from .formatting import short_path

__all__ = ["UnreadableFile", "MAX_JSON_BYTES", "MAX_JSON_DEPTH", "MAX_INT_DIGITS",
           "check_input_file", "read_text", "read_json", "open_text", "expect"]

#: Largest JSON file read (bytes). The shipped map is 0.6 MB and a point file a few kB; JSON
#: parsing takes about ten times the file's size in memory, so this bounds a read at ~0.7 GB.
MAX_JSON_BYTES = 64 * 2**20
#: Deepest nesting of a JSON file (our files nest 4 levels at most).
MAX_JSON_DEPTH = 32
#: Most digits of a JSON integer (counts and indices; physical values are floats).
MAX_INT_DIGITS = 30


class UnreadableFile(InvalidParameterError):
    """A file given as input is missing, not a regular file, too large, not UTF-8, malformed,
    or does not hold what its reader expects. ``name`` is the option or parameter that gave it,
    ``value`` the path, ``detail`` the message after the name (the file, what is wrong and
    what was expected)."""

    def __init__(self, name: str, path, what: str, reason: str):
        self.name, self.value, self.valid, self.path = name, str(path), what, str(path)
        self.detail = f"{short_path(path)}: {reason} (expected {what})"
        ValueError.__init__(self, f"{name} {self.detail}")


def _reason(exc: OSError) -> str:
    """The operating system's reason for ``exc``, as a message continues it."""
    return (exc.strerror or str(exc)).lower()


def _size_text(n: int) -> str:
    return f"{n / 2**20:.3g} MB" if n >= 2**20 else f"{n} bytes"


def check_input_file(path, *, name: str, what: str, max_bytes: int | None = None) -> Path:
    """``path`` as a :class:`~pathlib.Path` after checking, without reading it, that it is an
    existing, readable regular file of at most ``max_bytes`` bytes (no limit: None). Raises
    :class:`UnreadableFile` (``name``: the option that gave it, ``what``: the kind of file
    expected) otherwise.

    Examples
    --------
    >>> check_input_file("/dev/zero", name="--map", what="a packed map")
    Traceback (most recent call last):
    ...
    correlations.files.UnreadableFile: --map /dev/zero: not a regular file (a device, FIFO or socket) (expected a packed map)
    """
    if path is None or str(path).strip() == "":
        raise UnreadableFile(name, "" if path is None else path, what, "the file name is empty")
    p = Path(path)
    try:
        st = os.stat(p)
    except OSError as exc:
        raise UnreadableFile(name, path, what, _reason(exc)) from None
    except ValueError as exc:       # an embedded NUL character
        raise UnreadableFile(name, ascii(str(path)), what, str(exc)) from None
    if stat.S_ISDIR(st.st_mode):
        raise UnreadableFile(name, path, what, "this is a folder, not a file")
    if not stat.S_ISREG(st.st_mode):
        raise UnreadableFile(name, path, what, "not a regular file (a device, FIFO or socket)")
    if not os.access(p, os.R_OK):
        raise UnreadableFile(name, path, what, "permission denied")
    if max_bytes is not None and st.st_size > max_bytes:
        raise UnreadableFile(name, path, what, f"the file has {_size_text(st.st_size)}, more "
                             f"than the {_size_text(max_bytes)} a file of this kind may have")
    return p


def open_text(path, *, name: str, what: str):
    """``path`` checked by :func:`check_input_file` (no size limit) and opened for reading
    as UTF-8 text (a byte-order mark skipped, newlines untranslated, for :mod:`csv`); the
    caller reads it as a stream and closes it. Decoding errors surface while reading, as
    :class:`UnicodeDecodeError`."""
    p = check_input_file(path, name=name, what=what)
    try:
        return p.open(encoding="utf-8-sig", newline="")
    except OSError as exc:
        raise UnreadableFile(name, path, what, _reason(exc)) from None


def read_text(path, *, name: str, what: str, max_bytes: int = MAX_JSON_BYTES) -> str:
    """The whole text of ``path`` (UTF-8, a byte-order mark skipped), checked by
    :func:`check_input_file` and read to at most ``max_bytes`` bytes (a file that grows while
    read is refused, not followed)."""
    p = check_input_file(path, name=name, what=what, max_bytes=max_bytes)
    try:
        with p.open("rb") as f:
            raw = f.read(max_bytes + 1)
    except OSError as exc:
        raise UnreadableFile(name, path, what, _reason(exc)) from None
    if len(raw) > max_bytes:
        raise UnreadableFile(name, path, what, f"the file grew beyond {_size_text(max_bytes)} "
                             "while read")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise UnreadableFile(name, path, what, f"not UTF-8 text (byte {exc.start})") from None


def _int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise ValueError(f"an integer of {len(text.lstrip('-'))} digits (at most "
                         f"{MAX_INT_DIGITS})")
    return int(text)


def _float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"{text} overflows a double (write a missing number as null)")
    return value


def _constant(text: str):
    raise ValueError(f"{text} is not strict JSON (write a missing number as null)")


_CONTAINERS = frozenset((dict, list))


def _depth(data) -> int:
    """Nesting depth of parsed JSON, without recursion. Only containers are visited: a list of
    numbers (the columns of a map, tens of thousands of values) is passed over by a test of
    its elements' types that runs in C."""
    if type(data) not in _CONTAINERS:
        return 0
    deepest, stack = 0, [(data, 1)]
    while stack:
        item, level = stack.pop()
        deepest = max(deepest, level)
        children = item.values() if type(item) is dict else item
        if not _CONTAINERS.isdisjoint(map(type, children)):
            stack.extend((v, level + 1) for v in children if type(v) in _CONTAINERS)
    return deepest


def read_json(path, *, name: str, what: str, max_bytes: int = MAX_JSON_BYTES,
              max_depth: int = MAX_JSON_DEPTH):
    """The parsed content of the JSON file ``path``, read by :func:`read_text` and parsed
    strictly: no NaN, Infinity or overflowing number (``1e999``), integers of at most
    :data:`MAX_INT_DIGITS` digits, at most ``max_depth`` levels of nesting. Raises :class:`UnreadableFile` for any failure.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "deep.json"
    >>> _ = p.write_text("[" * 100 + "]" * 100)
    >>> read_json(p, name="--map", what="a packed map")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    correlations.files.UnreadableFile: --map /tmp/.../deep.json: JSON nested 100 levels deep (at most 32) (expected a packed map)
    """
    text = read_text(path, name=name, what=what, max_bytes=max_bytes)
    try:
        data = json.loads(text, parse_float=_float, parse_int=_int, parse_constant=_constant)
    except RecursionError:
        raise UnreadableFile(name, path, what, f"JSON nested too deeply (at most "
                             f"{max_depth} levels)") from None
    except json.JSONDecodeError as exc:
        raise UnreadableFile(name, path, what, f"not valid JSON (line {exc.lineno}, column "
                             f"{exc.colno}: {exc.msg})") from None
    except ValueError as exc:
        raise UnreadableFile(name, path, what, f"not valid JSON: {exc}") from None
    depth = _depth(data)
    if depth > max_depth:
        raise UnreadableFile(name, path, what, f"JSON nested {depth} levels deep (at most "
                             f"{max_depth})")
    return data


def expect(condition: bool, *, name: str, path, what: str, reason: str) -> None:
    """Schema check of a parsed file: raise :class:`UnreadableFile` with ``reason`` (what is
    wrong, e.g. "the field 'nu' is not a list of numbers") unless ``condition``."""
    if not condition:
        raise UnreadableFile(name, path, what, reason)
