"""How numbers and paths are written for people: table cells and values with their error bars,
shared by the estimate's notes and the command-line tables, and text and paths for one-line
messages."""

from __future__ import annotations

import math

__all__ = ["format_value", "format_value_error", "one_line", "short_path"]


def format_value(value) -> str:
    """A table cell: 4 significant digits, "—" for a missing value, yes/NO for booleans."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "NO"
    if isinstance(value, float):
        return f"{value:.4g}" if math.isfinite(value) else "—"
    return str(value)


def format_value_error(value, error) -> str:
    """A value with its error bar, ``value ± error``: the error to 2 significant digits and the
    value to the same decimal place, with a common power of ten outside 1e-3 to 1e5; a value
    without a (finite) error as :func:`format_value`.

    >>> format_value_error(1.18172, 0.00341), format_value_error(503.77, 6.17)
    ('1.1817 ± 0.0034', '503.8 ± 6.2')
    >>> format_value_error(12346.0, 251.0), format_value_error(2.5e5, 3.1e3)
    ('12350 ± 250', '(2.500 ± 0.031)e+05')
    """
    if (error is None or isinstance(value, bool) or not isinstance(value, (int, float))
            or not math.isfinite(value) or not math.isfinite(error)):
        return format_value(value)
    if error == 0 or abs(error) < 1e-6 * abs(value):      # below 7 significant digits
        return f"{value:.7g} ± {error:.2g}"
    place = math.floor(math.log10(abs(error))) - 1          # decimal place of its 2nd digit
    mag = max(abs(value), abs(error))
    if 1e-3 <= mag < 1e5:
        if place > 0:
            value, error = round(value, -place), round(error, -place)
        digits = max(-place, 0)
        return f"{value:.{digits}f} ± {error:.{digits}f}"
    power = math.floor(math.log10(mag))
    digits, scale = power - place, 10.0 ** power
    return f"({value / scale:.{digits}f} ± {error / scale:.{digits}f})e{power:+03d}"


def one_line(text: str) -> str:
    """``text`` with every character that is not printable (newlines, control characters a
    user may have typed) written as an escape, so that a message stays one line."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in str(text))


def short_path(path, limit: int = 120) -> str:
    """``path`` for a one-line message: as it is, or its start and end around "..." with its
    length when longer than ``limit`` characters (a path of thousands of characters).

    Examples
    --------
    >>> short_path("a" * 300, 20)
    'aaaaaaa...aaaaaaa (300 characters)'
    """
    text = one_line(path)
    if len(text) <= limit:
        return text
    half = (limit - 5) // 2
    return f"{text[:half]}...{text[-half:]} ({len(text)} characters)"
