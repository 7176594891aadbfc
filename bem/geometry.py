r"""Generating curves and panel layouts of the tube problem (lengths in units of the tube radius R).

The object is a closed axisymmetric body centred at x = 0, described from its **rear** pole
(upstream, smallest x) to its **front** pole; the flow goes toward +x. The tube wall r = 1 is
meshed over -L_up <= x <= L_down with panels graded toward the object, and the inlet disc
x = -L_up, 0 <= r <= 1 carries the (known, uniform) extra pressure. The outlet disc carries zero
extra pressure and needs no mesh.

Truncation: the disturbance of a body in a tube decays like :math:`e^{-k_1 |x|}` with
:math:`k_1 \approx 4.466` (the real part of the first complex eigenvalue of axisymmetric Stokes
flow in a tube; measured here as an exp(-4.5 x/R) decay, see ``tests/bem``), so the default
half-length is ``extent + ln(1/tol)/4.4 + 1``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from lubrication.checks import check_positive, check_range

from .quadrature import DEFAULT_ORDER, PanelSet, panels_on_curve

__all__ = [
    "DISTURBANCE_DECAY_RATE",
    "TubeGeometry",
    "graded_breaks",
    "sphere_curve",
    "sphere_in_tube",
    "tube_geometry",
    "tube_panels",
    "wall_half_length",
]

#: real part of the slowest decay rate of a Stokes disturbance in a tube, k1 R (Fourier-Bessel
#: eigenvalue of the Stokes operator in a circular pipe; 4.46630 + 1.46747 i)
DISTURBANCE_DECAY_RATE = 4.4663


def sphere_curve(a: float) -> Callable:
    """Sphere of radius ``a`` centred at the origin, theta in [0, pi] from rear to front pole.

    Returns ``curve(theta) -> (x, r, dx/dtheta, dr/dtheta)`` with x = -a cos(theta),
    r = a sin(theta).
    """
    a = float(check_positive("a", a))

    def curve(theta):
        c, s = np.cos(theta), np.sin(theta)
        return -a * c, a * s, a * s, a * c

    return curve


def graded_breaks(lo: float, hi: float, size: Callable, n_min: int = 1,
                  n: int | None = None) -> np.ndarray:
    """Panel breakpoints on [lo, hi] with panel lengths following the size function ``size(s)``.

    The breakpoints are equally spaced in N(s) = int_lo^s ds'/size(s'); the panel count is
    ``n`` if given, else ceil(N(hi)) but at least ``n_min``.
    """
    s = np.linspace(lo, hi, 8001)
    inv = 1.0 / size(s)
    N = np.concatenate([[0.0], np.cumsum(0.5 * (inv[1:] + inv[:-1]) * np.diff(s))])
    if n is None:
        n = max(int(n_min), math.ceil(N[-1] - 1e-9))
    targets = np.linspace(0.0, N[-1], n + 1)
    br = np.interp(targets, N, s)
    br[0], br[-1] = lo, hi
    return br


def wall_half_length(extent: float, tol: float) -> float:
    """Half-length of the meshed wall: object half-extent plus ln(1/tol)/k1 plus one radius."""
    return float(extent) + math.log(1.0 / float(tol)) / (DISTURBANCE_DECAY_RATE - 0.07) + 1.0


@dataclass(frozen=True)
class TubeGeometry:
    """Panels of the object, the wall and the inlet disc, with the layout parameters."""

    body: PanelSet
    wall: PanelSet
    inlet: PanelSet
    x_in: float
    x_out: float
    body_extent: float

    @property
    def panel_counts(self) -> dict:
        return {"body": self.body.n_panels, "wall": self.wall.n_panels,
                "inlet": self.inlet.n_panels, "order": self.body.order}


def tube_panels(*, gap: float, half_length: float, refinement: float = 1.0,
                flat: tuple[float, float] = (0.0, 0.0),
                p: int = DEFAULT_ORDER,
                flat_refinement: float | None = None) -> tuple[PanelSet, PanelSet]:
    """Panels of the wall r = 1, -half_length <= x <= half_length, and of the inlet disc
    x = -half_length, for a body leaving the wall gap ``gap``.

    Wall panel length h(x) = h0 + kappa d(x), with d(x) the distance from x to the interval
    ``flat`` = (x_lo, x_hi) (0 inside it), h0 = clip(sqrt(gap)/2, 0.03, 0.5)/refinement (the
    lubrication length sqrt(gap a) sets the scale of wall tractions near the body) and kappa =
    0.5/refinement; the inlet disc has max(2, 3 refinement) panels graded toward the corner
    with the wall. ``flat_refinement`` (default ``refinement``) replaces ``refinement`` in h0
    only: the panels beside the body, not their growth toward the tube ends (which sets the
    Poiseuille wall shear there). Returns (wall, inlet).
    """
    refinement = float(check_positive("refinement", refinement))
    flat_refinement = (refinement if flat_refinement is None
                       else float(check_positive("flat_refinement", flat_refinement)))
    h0 = min(0.5, max(0.03, 0.5 * math.sqrt(max(gap, 0.0)))) / flat_refinement
    kappa = 0.5 / refinement
    lo, hi = flat

    def size(x):
        return h0 + kappa * np.maximum(0.0, np.maximum(lo - x, x - hi))

    br = graded_breaks(-half_length, half_length, size, n_min=2)
    wall = panels_on_curve(lambda x: (x, np.ones_like(x), np.ones_like(x), np.zeros_like(x)),
                           br, p)
    n_in = max(2, math.ceil(3 * refinement))
    brd = graded_breaks(0.0, 1.0, lambda r: 0.15 + 0.85 * (1.0 - r) + 1e-3, n_min=n_in)
    inlet = panels_on_curve(lambda r: (np.full_like(r, -half_length), r, np.zeros_like(r),
                                       np.ones_like(r)), brd, p)
    return wall, inlet


def tube_geometry(body: PanelSet, *, body_extent: float, gap: float, half_length: float,
                  refinement: float = 1.0, p: int = DEFAULT_ORDER) -> TubeGeometry:
    """Wall and inlet panels (:func:`tube_panels`, graded from x = 0) for a body of half-extent
    ``body_extent`` and wall gap ``gap``."""
    half_length = float(check_range("half_length", half_length, body_extent, lo_open=True))
    wall, inlet = tube_panels(gap=gap, half_length=half_length, refinement=refinement, p=p)
    return TubeGeometry(body=body, wall=wall, inlet=inlet, x_in=-half_length,
                        x_out=half_length, body_extent=float(body_extent))


def sphere_in_tube(lam: float, n_panels: int, *, p: int = DEFAULT_ORDER,
                   half_length: float | None = None, tol: float = 1e-12) -> TubeGeometry:
    """Sphere of radius ``lam`` (R = 1) on the axis, with ``n_panels`` panels graded toward
    the equator when the gap 1 - lam is small, plus the matching wall and inlet meshes."""
    lam = float(check_range("lam", lam, 0.0, 1.0, lo_open=True, hi_open=True))
    n_panels = int(check_range("n_panels", n_panels, 2, 4096))
    gap = 1.0 - lam
    g = min(1.0, math.sqrt(2.0 * gap / lam))          # angular lubrication scale
    size = lambda th: np.sqrt((th - 0.5 * np.pi) ** 2 + g * g)
    br = graded_breaks(0.0, math.pi, size, n=n_panels)
    body = panels_on_curve(sphere_curve(lam), br, p)
    if half_length is None:
        half_length = wall_half_length(lam, tol)
    refinement = max(n_panels / 8.0, 0.5)      # wall and inlet follow the body resolution
    return tube_geometry(body, body_extent=lam, gap=gap, half_length=half_length,
                         refinement=refinement, p=p)
