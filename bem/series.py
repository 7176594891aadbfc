r"""Numba back-end of :mod:`bem.shape`: the Clenshaw sums of the sine and cosine series of a
generating curve (tangent angle and arc-length density), evaluated at many parameters.

Each kernel takes the coefficients and the angles :math:`\theta` as flat float arrays, does no
validation and returns a new array. The recurrence (Clenshaw 1955; Press et al., *Numerical
Recipes* §5.5) is the one the numpy version of :mod:`bem.shape` ran, term by term, as one array
operation per coefficient; here the loop over coefficients runs inside the loop over angles.
Measured on the red blood cell solve (0.61, 1.39): the curve work (closed curves, sampling,
curvatures) was 35 % of the solve's time with the numpy recurrence.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["cosine_sum", "pole_integrals", "pole_terms", "sine_clenshaw"]


@numba.njit(cache=True, nogil=True)
def _recurrence(c, cos_theta):
    """(b_1, b_2) of b_k = c_k + 2 cos(theta) b_{k+1} - b_{k+2}, from the last coefficient:
    sum_k c_k sin(k theta) = b_1 sin(theta), sum_k c_k cos(k theta) = b_1 cos(theta) - b_2."""
    b1 = 0.0
    b2 = 0.0
    for k in range(c.size - 1, -1, -1):
        b1, b2 = c[k] + 2.0 * cos_theta * b1 - b2, b1
    return b1, b2


@numba.njit(cache=True, nogil=True)
def sine_clenshaw(c, theta):
    """b_1 of the Clenshaw recurrence, so that sum_k c_k sin(k theta) = b_1 sin(theta)."""
    out = np.empty(theta.size)
    for i in range(theta.size):
        out[i] = _recurrence(c, math.cos(theta[i]))[0]
    return out


@numba.njit(cache=True, nogil=True)
def cosine_sum(d, theta):
    """sum_{k=1}^N d_k cos(k theta) (0 for empty d)."""
    out = np.empty(theta.size)
    for i in range(theta.size):
        cs = math.cos(theta[i])
        b1, b2 = _recurrence(d, cs)
        out[i] = b1 * cs - b2
    return out


@numba.njit(cache=True, nogil=True)
def pole_terms(c, a, u):
    r"""(g cos phi, g sin phi) at one parameter distance ``u`` from a pole, with the pole angle
    :math:`\phi = \pi u - b_1\sin\pi u` (b_1 the sine sum of ``c``) and the density
    :math:`g = 1 + \sum_j a_j\cos(j\pi u)`: the integrands of the curve's position."""
    th = math.pi * u
    cs = math.cos(th)
    phi = th - _recurrence(c, cs)[0] * math.sin(th)
    g = 1.0
    if a.size:
        d1, d2 = _recurrence(a, cs)
        g += d1 * cs - d2
    return g * math.cos(phi), g * math.sin(phi)


@numba.njit(cache=True, nogil=True)
def _legendre(x, out):
    """out[k] = P_k(x), k = 0 .. out.size - 1, by (k + 1) P_{k+1} = (2k + 1) x P_k - k P_{k-1}."""
    out[0] = 1.0
    if out.size > 1:
        out[1] = x
    for k in range(1, out.size - 1):
        out[k + 1] = ((2.0 * k + 1.0) * x * out[k] - k * out[k - 1]) / (k + 1.0)


@numba.njit(cache=True, nogil=True)
def pole_integrals(c, a, us, t, w, pieces_per_u):
    r"""(int_0^1 g cos phi dt, int_0^1 g sin phi dt) with argument u t at the sorted distances
    ``us`` from a pole: the integrals from 0 to u divided by u; at u = 0 the limits (g(0), 0).

    [0, max us] is cut into max(1, ceil(max(us) pieces_per_u)) equal pieces; on each the
    integrand is sampled at the Gauss nodes (t, w) of [0, 1] and replaced by its interpolating
    polynomial, whose Legendre coefficients b_k = sum_j w_j f_j P_k(2 t_j - 1) the rule gives
    exactly; its integral from the piece's start to s (in units of the piece) is
    b_0 s + (1/2) sum_{k>=1} b_k (P_{k+1}(x) - P_{k-1}(x)), x = 2 s - 1 (from
    (2k + 1) P_k = (P_{k+1} - P_{k-1})', Abramowitz & Stegun 22.8.5), which is b_0 at s = 1.
    The integrand is evaluated on the pieces' nodes (and, for the few points in the first
    piece, on the rule over [0, u] itself), not once per point and gap: a curve's panel nodes
    (hundreds of points) cost a few hundred integrand values instead of 16 per point."""
    n = us.size
    p = t.size
    oc = np.empty(n)
    os_ = np.empty(n)
    if n == 0:
        return oc, os_
    # Legendre values at the rule's nodes, times the weights: lw[k, j] = w_j P_k(2 t_j - 1)
    lw = np.empty((p, p))
    leg = np.empty(p + 1)
    for j in range(p):
        _legendre(2.0 * t[j] - 1.0, leg)
        for k in range(p):
            lw[k, j] = w[j] * leg[k]
    g0, _ = pole_terms(c, a, 0.0)
    umax = us[n - 1]
    pieces = max(1, int(math.ceil(umax * pieces_per_u)))
    h = umax / pieces
    fc = np.empty(p)
    fs = np.empty(p)
    bc = np.empty(p)
    bs = np.empty(p)
    ic = 0.0
    is_ = 0.0
    i = 0
    while i < n and us[i] <= 0.0:
        oc[i] = g0
        os_[i] = 0.0
        i += 1
    for q in range(pieces):
        start = q * h
        for j in range(p):
            fc[j], fs[j] = pole_terms(c, a, start + h * t[j])
        for k in range(p):
            sc = 0.0
            ss = 0.0
            for j in range(p):
                sc += lw[k, j] * fc[j]
                ss += lw[k, j] * fs[j]
            bc[k] = sc
            bs[k] = ss
        end = umax if q == pieces - 1 else start + h
        while i < n and us[i] <= end:
            if q == 0:
                # first piece: the Gauss rule on [0, u] itself (the series below loses its
                # absolute rounding, ~1e-16 b, relative to a small u)
                u = us[i]
                sc = 0.0
                ss = 0.0
                for j in range(p):
                    gc, gs = pole_terms(c, a, u * t[j])
                    sc += w[j] * gc
                    ss += w[j] * gs
                oc[i] = sc
                os_[i] = ss
                i += 1
                continue
            s = (us[i] - start) / h
            _legendre(2.0 * s - 1.0, leg)
            vc = bc[0] * s
            vs = bs[0] * s
            for k in range(1, p):
                d = 0.5 * (leg[k + 1] - leg[k - 1])
                vc += bc[k] * d
                vs += bs[k] * d
            oc[i] = (ic + h * vc) / us[i]
            os_[i] = (is_ + h * vs) / us[i]
            i += 1
        ic += h * bc[0]
        is_ += h * bs[0]
    return oc, os_
