"""Input checking, the project's error and warning classes, and validity ranges as data.

Every public function of ``lubrication``, ``bem`` and ``correlations`` checks its inputs up front
with the helpers below. Bad input raises :class:`InvalidParameterError` (a :class:`ValueError`)
whose message names the parameter, the offending value and the valid range. A formula evaluated
outside the range where its source established it emits an :class:`OutOfRangeWarning`, never an
error: the caller gets the extrapolated number and is told so.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass

import numpy as np

__all__ = [
    "InvalidParameterError",
    "CannotPassError",
    "OutOfRangeWarning",
    "ValidityRange",
    "as_finite",
    "check_range",
    "check_positive",
    "check_fraction",
    "check_choice",
    "scalar_or_array",
    "Deadline",
    "OUTPUT_BOUNDS",
    "check_output",
]


class InvalidParameterError(ValueError):
    """A parameter is NaN, infinite, of the wrong sign or outside its valid range.

    Attributes ``name``, ``value`` and ``valid`` (a human-readable range) are kept for programs;
    the message reads ``name=value is invalid: valid range ...``.
    """

    def __init__(self, name: str, value, valid: str, reason: str = ""):
        self.name, self.value, self.valid = name, value, valid
        text = f"{name}={_fmt(value)} is invalid: valid range {valid}"
        super().__init__(f"{text}; {reason}" if reason else text)


class CannotPassError(InvalidParameterError):
    """The confinement is at or beyond critical: the vesicle cannot pass the tube intact."""


class OutOfRangeWarning(UserWarning):
    """A correlation or asymptotic law was evaluated outside its validity range (extrapolated)."""


def _fmt(value) -> str:
    """Format a scalar, or the first offending element of an array, for messages."""
    if isinstance(value, str):
        return repr(value)
    arr = np.asarray(value, dtype=float) if not isinstance(value, np.ndarray) else value
    if arr.ndim == 0:
        return f"{float(arr):.6g}"
    if arr.size == 0:
        return f"an empty array of shape {arr.shape}"
    return f"{float(arr.flat[0]):.6g} (first offending element of an array of shape {arr.shape})"


def scalar_or_array(x):
    """Return a Python float for 0-d input, the ndarray otherwise (the API's return convention)."""
    x = np.asarray(x)
    return float(x) if x.ndim == 0 else x


def as_finite(name: str, x, valid: str = "a finite real number") -> np.ndarray:
    """``x`` as a float ndarray; raise :class:`InvalidParameterError` if any element is NaN/inf.

    ``valid`` is the range quoted in the message.
    """
    try:
        arr = np.asarray(x, dtype=float)
    except (TypeError, ValueError):
        raise InvalidParameterError(name, str(x), valid) from None
    bad = ~np.isfinite(arr)
    if bad.any():
        raise InvalidParameterError(name, arr[bad] if arr.ndim else arr, valid,
                                    "NaN and infinity are not accepted")
    return arr


def check_range(name: str, x, lo=-math.inf, hi=math.inf, *, lo_open=False, hi_open=False,
                reason: str = "", error=InvalidParameterError) -> np.ndarray:
    """Check that every element of ``x`` is finite and within ``lo <(=) x <(=) hi``.

    Returns ``x`` as a float ndarray. The message states the interval in the form
    ``0 < nu <= 1``.
    """
    interval = _interval(name, lo, hi, lo_open, hi_open)
    arr = as_finite(name, x, interval)
    below = arr <= lo if lo_open else arr < lo
    above = arr >= hi if hi_open else arr > hi
    bad = below | above
    if bad.any():
        raise error(name, arr[bad] if arr.ndim else arr, interval, reason)
    return arr


def check_positive(name: str, x, reason: str = "") -> np.ndarray:
    """Check ``0 < x < inf`` elementwise (sizes, viscosities, velocities, moduli)."""
    return check_range(name, x, 0.0, math.inf, lo_open=True, reason=reason)


def check_fraction(name: str, x) -> np.ndarray:
    """Check a hematocrit-like volume fraction, ``0 <= x < 1`` (a fraction, not a percentage)."""
    arr = as_finite(name, x, f"0 <= {name} < 1")
    reason = "give a fraction, not a percentage" if np.any((arr >= 1) & (arr <= 100)) else ""
    return check_range(name, arr, 0.0, 1.0, hi_open=True, reason=reason)


def check_choice(name: str, value: str, choices) -> str:
    """Check that ``value`` is one of ``choices`` (for law and method names)."""
    if value not in choices:
        raise InvalidParameterError(name, str(value), "one of " + ", ".join(map(repr, choices)))
    return value


def _interval(name, lo, hi, lo_open, hi_open) -> str:
    """``0 < nu <= 1``, ``lam >= 1``, ``x < 5`` or ``x finite``."""
    has_lo, has_hi = lo != -math.inf, hi != math.inf
    if has_lo and has_hi:
        return f"{lo:g} {'<' if lo_open else '<='} {name} {'<' if hi_open else '<='} {hi:g}"
    if has_lo:
        return f"{name} {'>' if lo_open else '>='} {lo:g}"
    if has_hi:
        return f"{name} {'<' if hi_open else '<='} {hi:g}"
    return f"{name} finite"


@dataclass(frozen=True)
class ValidityRange:
    """Closed box of parameter values inside which a formula was established by its source.

    ``bounds`` holds ``(name, lo, hi)`` triples; ``source`` says who established the range.
    Build one with :meth:`of`, e.g. ``ValidityRange.of("Chen et al. 2020 eq. transition",
    nu=(0.6, 0.93), lam=(0.6, 1.81))``.
    """

    source: str
    bounds: tuple[tuple[str, float, float], ...]

    @classmethod
    def of(cls, source: str, **bounds: tuple[float, float]) -> "ValidityRange":
        return cls(source, tuple((k, float(lo), float(hi)) for k, (lo, hi) in bounds.items()))

    def violations(self, **values) -> list[str]:
        """Descriptions of the bounds that some element of the given values violates.

        Parameters not named in ``bounds`` are ignored; bounds whose parameter is not given are
        not checked.
        """
        out = []
        for name, lo, hi in self.bounds:
            if name not in values:
                continue
            arr = np.asarray(values[name], dtype=float)
            bad = (arr < lo) | (arr > hi)
            if bad.any():
                out.append(f"{name}={_fmt(arr[bad] if arr.ndim else arr)} outside "
                           f"{lo:g} <= {name} <= {hi:g}")
        return out

    def contains(self, **values) -> bool:
        """True when every given value lies inside the range."""
        return not self.violations(**values)

    def distance(self, **values) -> float:
        """How far outside the box a scalar point lies: the largest relative excess over a bound.

        0 inside; otherwise ``max(|x - bound| / max(|bound|, 1))`` over the violated bounds. Used
        to pick the least-extrapolated method when none is valid.
        """
        d = 0.0
        for name, lo, hi in self.bounds:
            if name in values:
                x = float(values[name])
                excess = lo - x if x < lo else (x - hi if x > hi else 0.0)
                bound = lo if x < lo else hi
                d = max(d, excess / max(abs(bound), 1.0))
        return d

    def warn_outside(self, what: str, stacklevel: int = 3, **values) -> bool:
        """Emit an :class:`OutOfRangeWarning` if any value is outside; return True if inside."""
        bad = self.violations(**values)
        if bad:
            warnings.warn(f"{what}: {'; '.join(bad)}, the range of {self.source}; the value is "
                          "extrapolated.", OutOfRangeWarning, stacklevel=stacklevel)
        return not bad

    def describe(self) -> str:
        """One line, e.g. ``0.6 <= nu <= 0.93, 0.6 <= lam <= 1.81 (Chen et al. 2020)``."""
        box = ", ".join(f"{lo:g} <= {name} <= {hi:g}" for name, lo, hi in self.bounds)
        return f"{box} ({self.source})"


class Deadline:
    """A wall-time budget for a solve (``max_time`` seconds from creation; None: no limit).

    Solvers test :meth:`expired` between iterations and, when it is, stop and return an
    unconverged result whose message names the limit; they never raise for it.

    Examples
    --------
    >>> Deadline(None).expired(), Deadline(3600.0).expired()
    (False, False)
    """

    def __init__(self, max_time: float | None):
        if max_time is not None:
            max_time = float(check_positive("max_time", max_time))
        self.max_time = max_time
        self._end = None if max_time is None else time.monotonic() + max_time

    def expired(self) -> bool:
        """True once the budget is spent."""
        return self._end is not None and time.monotonic() > self._end

    def remaining(self) -> float | None:
        """Seconds left (at least a millisecond, so that it is a valid ``max_time``); None
        without a limit."""
        return None if self._end is None else max(1e-3, self._end - time.monotonic())

    def message(self) -> str:
        """The reason an expired solve gives."""
        return f"stopped at the time limit max_time={self.max_time:g} s before converging"


#: Bounds the physics sets on the outputs, ``quantity: (lo, hi, reason)`` (closed bounds): the
#: estimate checks every value of its method table against them before it is reported (a value
#: outside comes from a method used beyond its meaning or from a failed solve: it is refused
#: and the next method is tried), and the command line flags any solver output outside them.
#:
#: The membrane tensions have no bound here: their sign is not a law. A vesicle whose bending
#: forces dominate the flow's keeps nearly its equilibrium shape, and a quasi-spherical vesicle
#: with excess area is held by a negative tension, gamma -> -6 kappa/R0^2 as nu -> 1, where its
#: l = 2 shape mode costs no energy, E_l ~ (l - 1)(l + 2)[l(l + 1) kappa + gamma R0^2]
#: (Milner & Safran 1987, Phys. Rev. A 36, 4371; Seifert, Berndl & Lipowsky 1991, Phys. Rev. A
#: 44, 1182). The BEM vesicle reproduces that limit (tests/test_cli.py), and the shipped map
#: holds compressive tensions of weakly confined vesicles at small Ca_B (down to -0.98 eta U,
#: each above -6 kappa/R0^2). Only a confined, flow-dominated vesicle has the positive front
#: tension of a Bretherton front; the lubrication solver, whose model is that front, refuses a
#: non-positive one itself.
OUTPUT_BOUNDS = {
    "V_over_U": (1.0, 2.0, "a cell on the axis moves between the mean (1) and the centreline (2) "
                           "velocity of the Poiseuille flow"),
    "film": (0.0, 1.0, "the film lies between the membrane and the wall: 0 <= h/R <= 1"),
    "ell": (0.0, math.inf, "a length is positive"),
    "dp_plus_R0": (0.0, math.inf, "at a fixed flow rate Q, dp+ Q is the extra dissipation of a "
                                  "force-free cell in Stokes flow, which is not negative"),
    "tube_hematocrit": (0.0, 1.0, "a volume fraction"),
    "discharge_hematocrit": (0.0, 1.0, "a volume fraction"),
    "eta_rel": (1.0, math.inf, "force-free cells add dissipation: eta_rel >= 1"),
}


def check_output(quantity: str, value, state: dict) -> str:
    """Why ``value`` cannot be reported for ``quantity`` (empty string if it can).

    Checks finiteness, :data:`OUTPUT_BOUNDS`, and H_T <= H_D (cell flux conservation in single
    file: H_T/H_D = U/V <= 1) against a hematocrit of the other kind already in ``state``.

    Examples
    --------
    >>> check_output("V_over_U", 1.2, {})
    ''
    >>> check_output("dp_plus_R0", -0.3, {})[:40]
    'dp_plus_R0 = -0.3 outside dp_plus_R0 >= '
    """
    if isinstance(value, str):
        return ""
    if value is None or not math.isfinite(value):
        return f"{quantity} = {value!r} is not a finite number"
    lo, hi, reason = OUTPUT_BOUNDS.get(quantity, (-math.inf, math.inf, ""))
    if not lo <= value <= hi:
        bound = (f"{lo:g} <= {quantity} <= {hi:g}" if math.isfinite(lo) and math.isfinite(hi)
                 else f"{quantity} >= {lo:g}" if math.isfinite(lo) else f"{quantity} <= {hi:g}")
        return f"{quantity} = {value:.6g} outside {bound} ({reason})"
    h_t = value if quantity == "tube_hematocrit" else state.get("tube_hematocrit")
    h_d = value if quantity == "discharge_hematocrit" else state.get("discharge_hematocrit")
    if quantity in ("tube_hematocrit", "discharge_hematocrit") and h_t is not None \
            and h_d is not None and h_t > h_d:
        return (f"tube hematocrit {h_t:.6g} > discharge hematocrit {h_d:.6g}: impossible, "
                "H_T/H_D = U/V <= 1")
    return ""
