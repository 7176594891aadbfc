"""Hypothesis strategies shared by the tests: ordered pairs generated valid (no example of a
monotonicity test is discarded because its two draws came out equal or in the wrong order)."""

import math

from hypothesis import strategies as st


def increasing_pairs(lo: float, hi: float, min_gap: float, *, log: bool = False):
    """Pairs (a, b) with lo <= a < b <= hi and b - a >= min_gap (b/a >= 1 + min_gap with
    ``log``: the gap is relative and the pair is drawn uniformly in log a, log b)."""
    if log:
        return increasing_pairs(math.log(lo), math.log(hi), math.log1p(min_gap)).map(
            lambda p: (max(math.exp(p[0]), lo), min(math.exp(p[1]), hi)))

    def build(t):
        a, frac = t
        return a, min(a + min_gap + frac * (hi - a - min_gap), hi)
    return st.tuples(st.floats(lo, hi - min_gap), st.floats(0.0, 1.0)).map(build)
