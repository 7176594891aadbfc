r"""High-order panels on axisymmetric generating curves and their quadrature rules.

A generating curve is cut into panels; each panel carries ``p`` Gauss–Legendre nodes in its
parameter. Far from a target the nodes' own rule is used (Nyström). A target close to a panel
(distance below ``near`` panel lengths) is handled by splitting the panel at the nearest point
and integrating each side on a geometric mesh graded toward it, with the density interpolated
from the nodes (:func:`bem.kernels.panel_integral`). A target that is one of the panel's own
nodes (the logarithmic self-panel singularity of :math:`M_{xx}, M_{rr}`, the
:math:`\hat x\ln d` terms of :math:`M_{xr}, M_{rx}`) takes a fixed rule per node instead
(:func:`self_rule`: 2 x 40 kernel calls, exact for polynomial + polynomial x log on each side of
the node), unless the panel comes within one panel length of the axis, where the mirror
singularity of :math:`s^2 = \hat x^2 + (r + r_0)^2` is near, or ``tol`` < 1e-14; there the
graded mesh (~500 kernel calls at tol 1e-14) is kept. The convergence of the panel rule is
algebraic of order ~p in the panel size for near and self interactions, and spectral in p.

Measured on one BEM evaluation of the steady vesicle (lubrication seeds at (ν, λ) = (0.9, 1.0),
32 modes; (0.61, 1.39), 40 modes; (0.6, 1.94), 64 modes; Ca_B = 50;
tests/benchmarks/bench_evaluation.py): the fixed self rule changes V/U, Δp⁺ and γ_max by
≤ 3e-13 relative, the self blocks are within 5e-12 of the graded rule at tol 1e-16 (relative
to each row's largest entry; the graded rule at its default 1e-14 is 4e-12 off on the pole
panels), and the self integrals take 14 000 instead of 87 500 of the 204 000 kernel calls of the
assembly at (0.9, 1.0) (on one thread the membrane-source block fell from 43 to 24 ms).

The heavy lifting is in :mod:`bem.kernels`; this module builds the rule tables and the
:class:`PanelSet` arrays in numpy and checks the user's inputs.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cache

import numpy as np

from lubrication.checks import InvalidParameterError, check_positive, check_range

from ._log_rule_table import NODES as LOG_RULE_NODES, WEIGHTS as LOG_RULE_WEIGHTS

__all__ = [
    "DEFAULT_ORDER",
    "DEFAULT_TOL",
    "NEAR_FACTOR",
    "NMAX",
    "PanelSet",
    "barycentric_weights",
    "fit_log_rule",
    "gauss_legendre",
    "gauss_table",
    "influence",
    "influence_pair",
    "integrate_panel",
    "near_factor",
    "panels_on_curve",
    "self_rule",
    "self_rule_panels",
]

DEFAULT_ORDER = 16   # Gauss nodes per panel
#: target accuracy of the graded (near-singular, and self near the axis) panel integrals. Kept
#: at 1e-14: with the self panels on the fixed rule it governs the near panels only, and 1e-12,
#: 1e-11, 1e-10 change V/U, Δp⁺, γ_max of the three vesicle seeds (module docstring) by up to
#: 3.1e-11, 2.8e-10, 3.1e-9 (the 64-mode seed at (0.6, 1.94) the worst) while saving only 4-6 %
#: of the near-panel kernel calls (the grading depth is set by the distance, not by tol)
DEFAULT_TOL = 1e-14
NEAR_FACTOR = None   # None: near_factor(p, tol), the distance where the p-point rule meets tol
NMAX = 24            # highest Gauss order of the graded sub-intervals
#: the fixed self-panel rule is exact for P_j(u) and P_j(u) ln u on each side, j < 28: with
#: j < 20 the self blocks of the vesicle seeds were 1e-11 to 3e-11 off; from 24 on the
#: difference to the graded rule at tol 1e-16 stays at its floor, 5e-13 to 5e-12
SELF_BASIS = 28
SELF_RULE_TOL = 1e-14  # the fixed self-panel rule serves tol >= this (graded below)
#: ... on panels whose nodes stay this many panel lengths off the axis: with the fixed rule on
#: the pole panels too (r_min ~ 0.01 length) their self blocks were 1e-6 off
AXIS_CLEARANCE = 1.0
#: blocks with fewer (targets x source nodes) are assembled on the calling thread: starting
#: numba's parallel region costs more than such a block (measured on the 2 shared cores at load
#: 5: the vesicle's inlet block, 176 x 48, 0.74 ms on one thread, 4-8 ms on two)
SERIAL_WORK = 40_000

_ON_THIS_THREAD = threading.local()


@contextmanager
def serial_assembly():
    """Assemble every block on the calling thread (the serial numba kernels, which release the
    GIL) for the duration of a ``with`` block: for threads that each run whole BEM evaluations
    (:func:`bem.vesicle.level.solve_level` evaluates the difference-Jacobian columns two at a time);
    numba's default threading layer must not be entered from two threads at once."""
    before = getattr(_ON_THIS_THREAD, "serial", False)
    _ON_THIS_THREAD.serial = True
    try:
        yield
    finally:
        _ON_THIS_THREAD.serial = before


def assembles_serially(work: int) -> bool:
    return work < SERIAL_WORK or getattr(_ON_THIS_THREAD, "serial", False)


@cache
def gauss_legendre(p: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights on [-1, 1] (read-only arrays)."""
    t, w = np.polynomial.legendre.leggauss(int(p))
    t.flags.writeable = False
    w.flags.writeable = False
    return t, w


@cache
def barycentric_weights(p: int) -> np.ndarray:
    """Barycentric interpolation weights of the p Gauss–Legendre nodes.

    For Gauss–Legendre nodes the weights are proportional to (-1)^k sqrt((1 - t_k^2) w_k)
    (Wang & Xiang 2012); the common factor cancels in the barycentric formula.
    """
    t, w = gauss_legendre(p)
    bw = (-1.0) ** np.arange(p) * np.sqrt((1.0 - t**2) * w)
    bw.flags.writeable = False
    return bw


@cache
def gauss_table(nmax: int = NMAX) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre rules for n = 1..nmax; row n holds the n-point rule, zero-padded."""
    gx = np.zeros((nmax + 1, nmax))
    gw = np.zeros((nmax + 1, nmax))
    for n in range(1, nmax + 1):
        gx[n, :n], gw[n, :n] = gauss_legendre(n)
    gx.flags.writeable = False
    gw.flags.writeable = False
    return gx, gw


def _graded_rule(sigma: float = 0.15, levels: int = 40, n: int = 30):
    """Composite Gauss rule on [0, 1] on a geometric mesh graded toward 0 (smallest node
    ~1e-33): exact to rounding for polynomials of degree < 60 times ln u."""
    g, w = gauss_legendre(n)
    hi = sigma ** np.arange(levels)
    lo = hi * sigma
    u = lo[:, None] + (hi - lo)[:, None] * 0.5 * (g + 1.0)
    return u.ravel(), (0.5 * (hi - lo)[:, None] * w).ravel()


def fit_log_rule(n_basis: int) -> tuple[np.ndarray, np.ndarray]:
    r"""Positive rule (u_i, w_i) on [0, 1] exact for :math:`P_j(2u-1)` and :math:`P_j(2u-1)\ln u`,
    j < n_basis, with 2 n_basis nodes in [1e-8, 1].

    Built by non-negative least squares (Carathéodory: a positive rule with at most as many
    nodes as conditions exists) from the moments of :func:`_graded_rule`, with the conditions
    orthonormalised in that rule's inner product; nodes below 1e-8 are excluded so that no
    node of a self-panel rule rounds onto the target. The moments are matched to ~1.5e-15.
    The fit's basis has condition ~5e16, so which nodes it keeps follows the rounding of
    numpy's log and of LAPACK's QR: on other CPUs it returns another, equally exact rule.
    """
    from scipy.optimize import nnls  # lazy: scipy.optimize, only to fit a new rule

    u, w = _graded_rule()
    V = np.polynomial.legendre.legvander(2.0 * u - 1.0, n_basis - 1)
    phi = np.hstack([V, V * np.log(u)[:, None]]) * np.sqrt(w)[:, None]
    q, _ = np.linalg.qr(phi)
    keep = u > 1e-8
    z, _ = nnls((q.T / np.sqrt(w))[:, keep], q.T @ np.sqrt(w), maxiter=50 * n_basis)
    sel = np.nonzero(z)[0]
    return u[keep][sel], z[sel]


@cache
def log_rule(n_basis: int = SELF_BASIS) -> tuple[np.ndarray, np.ndarray]:
    r"""The rule of :func:`fit_log_rule` (read-only arrays). For SELF_BASIS, the one the solver
    uses, the stored table :mod:`bem._log_rule_table` (one fit, its smallest node 8.3e-6), so
    that every CPU integrates with the same nodes: fitted afresh, a CPU whose numpy has no
    AVX-512 keeps a node at 2e-8, where the kernel derivatives of the linearised Jacobian
    lose digits to the rounding of the node's distance to the target."""
    if n_basis == SELF_BASIS:
        u, w = np.array(LOG_RULE_NODES), np.array(LOG_RULE_WEIGHTS)
    else:
        u, w = fit_log_rule(n_basis)
    u.flags.writeable = False
    w.flags.writeable = False
    return u, w


@cache
def self_rule(p: int, n_basis: int = SELF_BASIS) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Fixed rules for a target at node k of a p-node panel: parameters st[k], weights sw[k]
    in t in [-1, 1] and Lagrange values sell[k] (m, p) of the nodes' basis at st[k].

    The panel is split at the target t_k and :func:`log_rule` is mapped onto each side:
    exact for :math:`a(t) + b(t)\ln|t - t_k|` with a, b polynomials of degree < n_basis on
    each side, the form of :math:`M_{\alpha\beta}\,\ell_j\,|X'|` on the panel (the kernel's
    logarithm is :math:`\ln d = \ln|t - t_k| +` analytic, as long as the ring does not come near
    the axis, where :math:`s^2 = \hat x^2 + (r + r_0)^2` vanishes).
    """
    t, _ = gauss_legendre(p)
    u, w = log_rule(n_basis)
    left, right = 1.0 + t[:, None], 1.0 - t[:, None]
    st = np.hstack([t[:, None] - left * u, t[:, None] + right * u])
    sw = np.hstack([left * w, right * w])
    bw = barycentric_weights(p)
    diff = st[:, :, None] - t[None, None, :]
    ell = bw / diff
    sell = ell / ell.sum(axis=2, keepdims=True)
    for a in (st, sw, sell):
        a.flags.writeable = False
    return st, sw, sell


def _legendre_coefficients(values: np.ndarray, p: int) -> np.ndarray:
    """Legendre coefficients of the degree p-1 interpolant of node values (last axis)."""
    t, w = gauss_legendre(p)
    V = np.polynomial.legendre.legvander(t, p - 1)          # V[k, n] = P_n(t_k)
    scale = (2.0 * np.arange(p) + 1.0) / 2.0
    return (values * w) @ V * scale


@dataclass(frozen=True)
class PanelSet:
    r"""Panels on one generating curve (or a concatenation of curves).

    Arrays have shape (n_panels, p): node coordinates ``x``, ``r``; unit tangent ``tx``,
    ``tr`` (direction of increasing parameter); unit normal ``nx, nr = -tr, tx`` (outward for
    a closed body described from rear pole to front pole); ``w`` = Gauss weight times
    :math:`|dX/dt|` (so that ``sum(w * f)`` is :math:`\int f\,dl`); Legendre coefficients
    ``cx``, ``cr`` of the panel curves in the local parameter t in [-1, 1].
    """

    x: np.ndarray
    r: np.ndarray
    tx: np.ndarray
    tr: np.ndarray
    w: np.ndarray
    cx: np.ndarray
    cr: np.ndarray

    @property
    def order(self) -> int:
        return self.x.shape[1]

    @property
    def n_panels(self) -> int:
        return self.x.shape[0]

    @property
    def n_nodes(self) -> int:
        return self.x.size

    @property
    def nx(self) -> np.ndarray:
        return -self.tr

    @property
    def nr(self) -> np.ndarray:
        return self.tx

    @property
    def lengths(self) -> np.ndarray:
        return self.w.sum(axis=1)

    def concat(self, other: PanelSet) -> PanelSet:
        if other.order != self.order:
            raise InvalidParameterError("order", other.order, f"equal to {self.order}")
        return PanelSet(*(np.concatenate([getattr(self, f), getattr(other, f)])
                          for f in ("x", "r", "tx", "tr", "w", "cx", "cr")))


def panels_on_curve(curve: Callable, breaks, p: int = DEFAULT_ORDER) -> PanelSet:
    """Cut the parametrised curve at ``breaks`` into panels with ``p`` Gauss nodes each.

    Parameters
    ----------
    curve : callable
        ``curve(s) -> (x, r, dx/ds, dr/ds)`` for an array of curve parameters ``s`` [R].
    breaks : array_like
        Strictly increasing panel end parameters (n_panels + 1 values).
    p : int
        Gauss–Legendre nodes per panel (2 <= p <= 40).
    """
    check_range("p", p, 2, 40)
    p = int(p)
    s = np.asarray(breaks, dtype=float)
    if s.ndim != 1 or s.size < 2 or np.any(np.diff(s) <= 0) or not np.all(np.isfinite(s)):
        raise InvalidParameterError("breaks", s, "a finite, strictly increasing 1-D array "
                                    "of at least two values")
    t, wg = gauss_legendre(p)
    half = 0.5 * np.diff(s)[:, None]
    ss = 0.5 * (s[:-1] + s[1:])[:, None] + half * t[None, :]
    x, r, dx, dr = (np.asarray(v, dtype=float) for v in curve(ss))
    speed = np.hypot(dx, dr)
    if np.any(r < 0) or np.any(speed <= 0):
        raise InvalidParameterError("curve", "r < 0 or a zero tangent",
                                    "r >= 0 and a regular parametrisation")
    return PanelSet(x=x, r=r, tx=dx / speed, tr=dr / speed, w=wg * speed * half,
                    cx=_legendre_coefficients(x, p), cr=_legendre_coefficients(r, p))


def near_factor(p: int, tol: float = DEFAULT_TOL) -> float:
    """Distance, in panel lengths, beyond which the panel's own p-point Gauss rule meets ``tol``.

    The p-point rule converges like rho^(-2p), rho the Bernstein ellipse through the target's
    pre-image; a target at distance d from a panel of length h has rho >~ 4 d/h, so the rule
    is trusted for d/h > rho*/4 with rho* = tol^(-1/(2p)), and never closer than one length
    (the estimate alone gives 0.68 lengths for p = 16 at 1e-14; at 0.8 lengths V/U and Δp⁺ of
    the vesicle at (0.6, 1.94), 64 modes, moved by 6e-7).
    """
    return max(1.0, float(tol) ** (-1.0 / (2.0 * int(p))) / 4.0)


def self_rule_panels(panels: PanelSet, tol: float) -> np.ndarray:
    """Mask of the panels whose nodes take the fixed self rule (:func:`self_rule`) on
    themselves: those at least AXIS_CLEARANCE lengths off the axis, when tol >= SELF_RULE_TOL
    (the graded rule elsewhere)."""
    fixed = panels.r.min(axis=1) >= AXIS_CLEARANCE * panels.lengths
    if tol < SELF_RULE_TOL:
        fixed[:] = False
    return fixed


def influence(targets_x, targets_r, panels: PanelSet, *, near: float | None = NEAR_FACTOR,
              tol: float = DEFAULT_TOL) -> np.ndarray:
    r"""Matrix A with :math:`u_\alpha(i) = (8\pi\eta)^{-1}\sum_j A_{2i+\alpha, 2j+\beta} q_\beta(j)`.

    ``q`` are node values of the ring density (force per area on the fluid) on ``panels``; the
    unknown order is node-major, ``(q_x, q_r)`` per node, panels in order.
    """
    tx = np.ascontiguousarray(targets_x, dtype=float).ravel()
    tr = np.ascontiguousarray(targets_r, dtype=float).ravel()
    check_range("targets_r", tr, 0.0)
    as_tol = float(check_range("tol", tol, 1e-16, 1e-2))
    p = panels.order
    as_near = near_factor(p, as_tol) if near is None else float(check_positive("near", near))
    from . import kernels  # lazy: numba

    t, _ = gauss_legendre(p)
    gx, gw = gauss_table()
    n = panels.n_nodes
    self_node = np.full(tx.size, -1, dtype=np.int64)
    if (tx.size >= n and np.array_equal(tx[:n], panels.x.ravel())
            and np.array_equal(tr[:n], panels.r.ravel())):
        self_node[:n] = np.arange(n)
    fixed = self_rule_panels(panels, as_tol)
    st, sw, sell = self_rule(p)
    out = np.empty((2 * tx.size, 2 * n))
    kernel = (kernels.influence_matrix_serial if assembles_serially(tx.size * n)
              else kernels.influence_matrix)
    kernel(tx, tr, panels.x, panels.r, panels.w, panels.cx, panels.cr, t, barycentric_weights(p),
           gx, gw, as_near, as_tol, self_node, fixed, st, sw, sell, out)
    return out


def influence_pair(a: PanelSet, b: PanelSet, *, near: float | None = NEAR_FACTOR,
                   tol: float = DEFAULT_TOL) -> tuple[np.ndarray, np.ndarray]:
    r"""``(influence(a nodes, b), influence(b nodes, a))`` of two disjoint panel sets (say a
    membrane and the tube wall) with one ring Stokeslet per far pair of nodes.

    The ring Stokeslet is reciprocal, :math:`M_{\alpha\beta}(x_0; x)/r = M_{\beta\alpha}(x; x_0)/r_0`
    (Pozrikidis 1992), so the far entries of one matrix give those of the other; near panels
    are integrated by the graded rule as in :func:`influence`. Equal to the two calls of
    :func:`influence` to rounding (tests/bem/test_quadrature_self_rule.py). Pass the larger set
    as ``a`` (:func:`bem.kernels.cross_influence_matrix`).
    """
    if a.order != b.order:
        raise InvalidParameterError("b.order", b.order, f"equal to a.order = {a.order}")
    as_tol = float(check_range("tol", tol, 1e-16, 1e-2))
    p = a.order
    as_near = near_factor(p, as_tol) if near is None else float(check_positive("near", near))
    from . import kernels  # lazy: numba

    t, _ = gauss_legendre(p)
    gx, gw = gauss_table()
    out_ab = np.empty((2 * a.n_nodes, 2 * b.n_nodes))
    out_ba = np.empty((2 * b.n_nodes, 2 * a.n_nodes))
    kernel = (kernels.cross_influence_matrix_serial if assembles_serially(a.n_nodes * b.n_nodes)
              else kernels.cross_influence_matrix)
    kernel(a.x, a.r, a.w, a.cx, a.cr, b.x, b.r, b.w, b.cx, b.cr, t, barycentric_weights(p), gx,
           gw, as_near, as_tol, out_ab, out_ba)
    return out_ab, out_ba


def integrate_panel(x0: float, r0: float, panels: PanelSet, index: int, density,
                    *, tol: float = DEFAULT_TOL) -> np.ndarray:
    r"""Singular-safe :math:`\int_{\rm panel} M_{\alpha\beta}(x_0, r_0; X)\,q_\beta\,dl`.

    ``density`` is an array (p, 2) of node values of ``q`` on panel ``index``; returns the
    2-vector of the integral. Works for targets on, near or far from the panel.
    """
    from . import kernels  # lazy: numba

    p = panels.order
    t, _ = gauss_legendre(p)
    gx, gw = gauss_table()
    acc = np.empty((p, 4))
    kernels.panel_integral(float(x0), float(r0), panels.cx[index], panels.cr[index], t,
                           barycentric_weights(p), gx, gw, float(tol), acc)
    q = np.asarray(density, dtype=float).reshape(p, 2)
    return np.array([acc[:, 0] @ q[:, 0] + acc[:, 1] @ q[:, 1],
                     acc[:, 2] @ q[:, 0] + acc[:, 3] @ q[:, 1]])
