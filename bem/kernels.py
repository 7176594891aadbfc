r"""Numba back-end of the axisymmetric Stokes BEM: elliptic integrals, the ring Stokeslet, and
the assembly of the single-layer influence matrix of a panel set on a set of targets.

Everything here is ``@numba.njit(cache=True)`` and does no validation, no I/O and uses no
globals (the user API in :mod:`bem.quadrature`, :mod:`bem.assembly` and :mod:`bem.solve`
checks the inputs). Kernels of one family share one signature:

* pointwise elliptic integrals ``f(m1) -> float`` of the complementary parameter ``m1 = 1 - m``;
* pointwise ring Stokeslet ``ring_stokeslet(x0, r0, x, r) -> (Mxx, Mxr, Mrx, Mrr)``;
* panel kernels ``f(x0, r0, cx, cr, ..., acc)`` filling the weights acc[k, (xx, xr, rx, rr)]
  of one panel (:func:`panel_integral`, :func:`self_panel_integral`);
* the influence kernels ``influence_matrix`` (parallel over targets) and
  ``influence_matrix_serial``, both ``f(tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, near, tol,
  self_node, fixed, st, sw, sell, out)``, and :func:`cross_influence_matrix` of two panel sets
  on each other's nodes.

Normalisation (Pozrikidis 1992, *Boundary integral and singularity methods*, §2.4):
:math:`M_{\alpha\beta}(x_0, r_0; x, r) = r\int_0^{2\pi} G_{\alpha\beta'}\,d\varphi` with the
free-space Stokeslet :math:`G_{ij} = \delta_{ij}/\rho + \hat x_i \hat x_j/\rho^3`, so a ring
density ``q`` (force per unit *area* exerted on the fluid) along a generating curve with arc
length ``l`` produces :math:`u_\alpha(x_0) = (8\pi\eta)^{-1}\int M_{\alpha\beta} q_\beta\,dl`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = [
    "cross_influence_matrix",
    "cross_influence_matrix_serial",
    "ellipe_m1",
    "ellipk_m1",
    "ellipke_m1",
    "influence_matrix",
    "influence_matrix_serial",
    "panel_integral",
    "ring_stokeslet",
    "ring_stokeslet_phi",
    "self_panel_integral",
]

_PI = math.pi
_LN4 = math.log(4.0)


# --------------------------------------------------------------------------------------------
# Complete elliptic integrals K(m), E(m) as functions of m1 = 1 - m
# --------------------------------------------------------------------------------------------
# Cephes ellpk/ellpe (S. L. Moshier, *Methods and Programs for Mathematical Functions*, 1989;
# the approximations behind scipy.special.ellipkm1 and ellipe): K(1 - m1) = P_K(m1) -
# ln(m1) Q_K(m1), E(1 - m1) = P_E(m1) - ln(m1) m1 Q_E(m1), coefficients from the highest power
_K_P = (1.37982864606273237150e-4, 2.28025724005875567385e-3, 7.97404013220415179367e-3,
        9.85821379021226008714e-3, 6.87489687449949877925e-3, 6.18901033637687613229e-3,
        8.79078273952743772254e-3, 1.49380448916805252718e-2, 3.08851465246711995998e-2,
        9.65735902811690126535e-2, 1.38629436111989062502e0)
_K_Q = (2.94078955048598507511e-5, 9.14184723865917226571e-4, 5.94058303753167793257e-3,
        1.54850516649762399335e-2, 2.39089602715924892727e-2, 3.01204715227604046988e-2,
        3.73774314173823228969e-2, 4.88280347570998239232e-2, 7.03124996963957469739e-2,
        1.24999999999870820058e-1, 4.99999999999999999821e-1)
_E_P = (1.53552577301013293365e-4, 2.50888492163602060990e-3, 8.68786816565889628429e-3,
        1.07350949056076193403e-2, 7.77395492516787092951e-3, 7.58395289413514708519e-3,
        1.15688436810574127319e-2, 2.18317996015557253103e-2, 5.68051945617860553470e-2,
        4.43147180560990850618e-1, 1.00000000000000000299e0)
_E_Q = (3.27954898576485872656e-5, 1.00962792679356715133e-3, 6.50609489976927491433e-3,
        1.68862163993311317300e-2, 2.61769742454493659583e-2, 3.34833904888224918614e-2,
        4.27180926518931511717e-2, 5.85936634471101055642e-2, 9.37499997197644278445e-2,
        2.49999999999888314361e-1)
_EPS = 1.11022302462515654042e-16


@numba.njit(cache=True)
def ellipke_m1(m1):
    """Complete elliptic integrals (K(m), E(m)) of parameter m = 1 - m1, from m1 in (0, 1].

    Cephes' polynomial approximations in m1 with the logarithmic singularity at m1 = 0 split
    off (peak relative errors 2.5e-16 and 1.5e-16 in IEEE arithmetic, Moshier 1989; at most
    8.9e-16 against mpmath from m1 = 1e-300 to 1, tests/bem/test_kernels.py); below m1 = 2^-53,
    K = ln 4 - ln(m1)/2 and E = 1. One logarithm and 42 multiply-adds: 20-26 ns per pair
    against 31 ns for the arithmetic-geometric mean and 79 ns for the logarithmic series about
    m = 1 (m1 < 0.05) that served before, measured on one core; a ring Stokeslet of the
    elliptic branch 43 instead of 65 ns.
    """
    if m1 <= _EPS:
        return _LN4 - 0.5 * math.log(m1), 1.0
    L = math.log(m1)
    pk = _K_P[0]
    qk = _K_Q[0]
    pe = _E_P[0]
    for i in range(1, 11):
        pk = pk * m1 + _K_P[i]
        qk = qk * m1 + _K_Q[i]
        pe = pe * m1 + _E_P[i]
    qe = _E_Q[0]
    for i in range(1, 10):
        qe = qe * m1 + _E_Q[i]
    return pk - L * qk, pe - L * m1 * qe


@numba.njit(cache=True)
def ellipk_m1(m1):
    """K(m) of parameter m = 1 - m1 (the analogue of ``scipy.special.ellipkm1``)."""
    return ellipke_m1(m1)[0]


@numba.njit(cache=True)
def ellipe_m1(m1):
    """E(m) of parameter m = 1 - m1."""
    return ellipke_m1(m1)[1]


# --------------------------------------------------------------------------------------------
# Ring Stokeslet
# --------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def ring_stokeslet_phi(x0, r0, x, r, n):
    """Ring Stokeslet by the trapezoidal rule in the azimuth with ``n`` intervals on [0, pi].

    The integrand is even, periodic and analytic; the error falls like
    exp(-2 n arccosh(2/m - 1)), so n = 6 reaches the rounding floor for m < 0.1 (measured; see
    :func:`ring_stokeslet`). Accurate in absolute terms near the axis, where the elliptic form
    cancels.
    """
    xh = x0 - x
    xh2 = xh * xh
    c0 = xh2 + r0 * r0 + r * r
    sxx = 0.0
    sxr = 0.0
    srx = 0.0
    srr = 0.0
    h = _PI / n
    # cos(i h) by the recurrence cos((i+1)h) = 2 cos h cos(ih) - cos((i-1)h) for n <= 16 (one
    # cosine per call instead of n + 1; rounding grows with n, ~4e-16 at n = 8), directly above
    c1 = math.cos(h)
    c = 1.0
    c_prev = c1
    for i in range(n + 1):
        if n > 16:
            c = math.cos(i * h)
        elif i == n:
            c = -1.0
        rho2 = c0 - 2.0 * r * r0 * c
        i1 = 1.0 / math.sqrt(rho2)
        i3 = i1 * i1 * i1
        wgt = 0.5 if (i == 0 or i == n) else 1.0
        sxx += wgt * (i1 + xh2 * i3)
        sxr += wgt * (r0 * c - r) * i3
        srx += wgt * (r0 - r * c) * i3
        srr += wgt * (c * i1 + (r0 - r * c) * (r0 * c - r) * i3)
        c, c_prev = 2.0 * c1 * c - c_prev, c
    f = 2.0 * h * r
    return f * sxx, f * xh * sxr, f * xh * srx, f * srr


@numba.njit(cache=True)
def ring_stokeslet(x0, r0, x, r):
    """Axisymmetric ring Stokeslet (Mxx, Mxr, Mrx, Mrr) at field point (x0, r0) of a ring (x, r).

    Pozrikidis (1992) normalisation (see the module docstring). Three branches: the field point
    on the axis (r0 == 0: closed form, Mrx = Mrr = 0); small parameter m = 4 r r0 / s^2 < 0.1
    (azimuthal trapezoidal rule with 4-7 intervals by m, which avoids the 1/r0 cancellation of
    the elliptic form near the axis); otherwise the elliptic form with K, E computed from m1 = d^2/s^2 directly.
    The coincident point (d = 0) is singular and returns inf.
    """
    xh = x0 - x
    xh2 = xh * xh
    if r0 == 0.0:
        rho2 = xh2 + r * r
        rho = math.sqrt(rho2)
        rho3 = rho2 * rho
        return 2.0 * _PI * r * (1.0 / rho + xh2 / rho3), -2.0 * _PI * r * r * xh / rho3, 0.0, 0.0
    d2 = xh2 + (r - r0) * (r - r0)
    s2 = xh2 + (r + r0) * (r + r0)
    m = 4.0 * r * r0 / s2
    if m < 0.1:
        # intervals of the azimuthal rule: the largest n whose error exceeds 1e-15 (relative
        # to the largest component; measured against n = 64 on 2e4 random points), plus one:
        # n = 3, 4, 5, 6 reach the rounding floor below m = 0.003, 0.02, 0.05, 0.1
        if m < 0.003:
            n = 4
        elif m < 0.02:
            n = 5
        elif m < 0.05:
            n = 6
        else:
            n = 7
        return ring_stokeslet_phi(x0, r0, x, r, n)
    m1 = d2 / s2
    if m1 <= 0.0:
        return math.inf, 0.0, 0.0, math.inf
    K, E = ellipke_m1(m1)
    rr = math.sqrt(r * r0)
    k = 2.0 * rr / math.sqrt(s2)   # sqrt(m); sqrt(r/r0) = rr/r0 below (two square roots)
    i_r0 = 1.0 / r0
    i_rr = 1.0 / rr
    q = rr * i_r0
    sq = r * r + r0 * r0
    dq = (r - r0) * (r + r0)       # r^2 - r0^2 in factored form: no cancellation near d = 0
    ed = E / d2
    Mxx = 2.0 * k * q * (K + xh2 * ed)
    Mxr = -(k * xh * i_rr) * (K - (xh2 - dq) * ed)
    Mrx = (k * xh * i_r0) * q * (K - (xh2 + dq) * ed)
    Mrr = (k * i_r0 * i_rr) * ((2.0 * xh2 + sq) * K
                               - (2.0 * xh2 * xh2 + 3.0 * xh2 * sq + dq * dq) * ed)
    return Mxx, Mxr, Mrx, Mrr


# --------------------------------------------------------------------------------------------
# Panel geometry helpers (panels are polynomials of degree p-1 in t in [-1, 1], given by their
# Legendre coefficients; densities are interpolated by the Lagrange basis on the Gauss nodes)
# --------------------------------------------------------------------------------------------
#: the coefficients (2n + 1)/(n + 1) and n/(n + 1) of the Legendre recurrence for n < 128,
#: each the correctly rounded quotient (as the loop would compute it: the same values)
_REC_A = np.array([(2.0 * n + 1.0) / (n + 1.0) for n in range(128)])
_REC_B = np.array([n / (n + 1.0) for n in range(128)])


@numba.njit(cache=True)
def _curve_eval(cx, cr, t):
    """(x, dx/dt, r, dr/dt) of the panel curve sum_n (cx[n], cr[n]) P_n(t) at t, by the
    three-term recurrence (P'_{n+1} = P'_{n-1} + (2n+1) P_n), shared by both coordinates."""
    p = cx.shape[0]
    x = cx[0]
    r = cr[0]
    dx = 0.0
    dr = 0.0
    if p == 1:
        return x, dx, r, dr
    P0 = 1.0
    D0 = 0.0
    P1 = t
    D1 = 1.0
    x += cx[1] * P1
    dx += cx[1] * D1
    r += cr[1] * P1
    dr += cr[1] * D1
    for n in range(1, p - 1):
        # the coefficients depend on n only: no division in the chain P0 -> P1 -> P2
        a = _REC_A[n]
        b = _REC_B[n]
        P2 = a * t * P1 - b * P0
        D2 = D0 + (2.0 * n + 1.0) * P1
        x += cx[n + 1] * P2
        dx += cx[n + 1] * D2
        r += cr[n + 1] * P2
        dr += cr[n + 1] * D2
        P0, P1 = P1, P2
        D0, D1 = D1, D2
    return x, dx, r, dr


@numba.njit(cache=True)
def _lagrange(t, tn, bw, ell):
    """Lagrange basis values ell_k(t) on nodes tn with barycentric weights bw (in place)."""
    p = tn.shape[0]
    for k in range(p):
        if t == tn[k]:
            for j in range(p):
                ell[j] = 0.0
            ell[k] = 1.0
            return
    s = 0.0
    for k in range(p):
        ell[k] = bw[k] / (t - tn[k])
        s += ell[k]
    inv = 1.0 / s
    for k in range(p):
        ell[k] *= inv


@numba.njit(cache=True)
def _nearest_parameter(x0, r0, cx, cr, t_start):
    """Parameter in [-1, 1] of the point of the panel nearest to (x0, r0), by Gauss-Newton."""
    t = t_start
    for _ in range(30):
        x, dx, r, dr = _curve_eval(cx, cr, t)
        g = (x - x0) * dx + (r - r0) * dr
        h = dx * dx + dr * dr
        step = g / h
        tn = min(1.0, max(-1.0, t - step))
        if abs(tn - t) < 1e-15:
            t = tn
            break
        t = tn
    return t


@numba.njit(cache=True)
def _accumulate_interval(x0, r0, a, b, n, gx, gw, cx, cr, tn, bw, ell, acc):
    """Add the n-point Gauss rule on [a, b] of M(x0; X(t)) |X'(t)| ell_k(t) to acc[k, 4]."""
    half = 0.5 * (b - a)
    mid = 0.5 * (a + b)
    p = tn.shape[0]
    for i in range(n):
        t = mid + half * gx[n, i]
        x, dx, r, dr = _curve_eval(cx, cr, t)
        r = max(r, 0.0)
        if r == 0.0 or (x == x0 and r == r0):
            continue            # a ring of zero radius carries nothing; d = 0 has measure zero
        jac = math.sqrt(dx * dx + dr * dr)
        Mxx, Mxr, Mrx, Mrr = ring_stokeslet(x0, r0, x, r)
        w = half * gw[n, i] * jac
        _lagrange(t, tn, bw, ell)
        for k in range(p):
            wk = w * ell[k]
            acc[k, 0] += wk * Mxx
            acc[k, 1] += wk * Mxr
            acc[k, 2] += wk * Mrx
            acc[k, 3] += wk * Mrr


@numba.njit(cache=True)
def _graded_side(ts, length, sgn, delta_t, nmax, tol, iv, count):
    """Append to iv[count:] the intervals (a, b, n) of an n-point Gauss rule each that cover
    [ts, ts + sgn*length] on a geometric mesh graded toward ts; returns the new count.

    Interval j covers distances [sigma^(j+1), sigma^j] * length from ts; its Gauss order is
    the smallest that meets ``tol`` given the Bernstein-ellipse rate rho of a singularity at
    the graded end (rho = (1 + sqrt(sigma))/(1 - sqrt(sigma))) and the interval's share of
    the integral (~sigma^j). Grading stops when the innermost interval is shorter than the
    distance to the singularity delta_t (near-singular case) or than 1e-15 (on the panel).
    """
    sigma = 0.2
    log_rho = math.log((1.0 + math.sqrt(sigma)) / (1.0 - math.sqrt(sigma)))
    log_tol = -math.log(tol)
    hi = length
    j = 0
    floor = max(0.5 * delta_t, 1e-15)
    while True:
        lo = hi * sigma
        last = lo < floor
        if last:
            lo = 0.0
        share = j * math.log(1.0 / sigma)
        n = int(math.ceil(  # noqa: RUF046 (numba)
            (log_tol - share) / (2.0 * log_rho))) + 2
        if last and delta_t > 1e-15:
            # the innermost interval sees the singularity at ~its own length; the order the
            # Bernstein ellipse through t* +- i delta_t gives (12-20 points at tol 1e-14) moved
            # dp+ of the 64-mode vesicle seed at (0.6, 1.94) by 2e-8: keep nmax
            n = nmax
        n = max(4, min(nmax, n))
        if sgn > 0:
            iv[count, 0] = ts + lo
            iv[count, 1] = ts + hi
        else:
            iv[count, 0] = ts - hi
            iv[count, 1] = ts - lo
        iv[count, 2] = n
        count += 1
        if last:
            return count
        hi = lo
        j += 1


@numba.njit(cache=True)
def _graded_plan(x0, r0, cx, cr, t_start, nmax, tol, iv):
    """The intervals (a, b, n) of :func:`panel_integral` in iv (at most 64; the grading stops
    at 1e-15 of the side, ~22 intervals): the panel split at the parameter t* of its point
    nearest to the target (Gauss-Newton from ``t_start``), each side graded toward t*
    (:func:`_graded_side`). Returns their count."""
    ts = _nearest_parameter(x0, r0, cx, cr, t_start)
    x, dx, r, dr = _curve_eval(cx, cr, ts)
    dist = math.sqrt((x - x0) ** 2 + (r - r0) ** 2)
    speed = math.sqrt(dx * dx + dr * dr)
    delta_t = dist / speed
    count = 0
    if ts > -1.0:
        count = _graded_side(ts, ts + 1.0, -1, delta_t, nmax, tol, iv, count)
    if ts < 1.0:
        count = _graded_side(ts, 1.0 - ts, 1, delta_t, nmax, tol, iv, count)
    return count


@numba.njit(cache=True)
def _graded_panel(x0, r0, cx, cr, t_start, tn, bw, gx, gw, tol, acc):
    """:func:`panel_integral` with the Gauss-Newton search for t* started from ``t_start``."""
    p = tn.shape[0]
    ell = np.empty(p)
    for k in range(p):
        for c in range(4):
            acc[k, c] = 0.0
    iv = np.empty((64, 3))
    for j in range(_graded_plan(x0, r0, cx, cr, t_start, gx.shape[0] - 1, tol, iv)):
        _accumulate_interval(x0, r0, iv[j, 0], iv[j, 1], int(iv[j, 2]), gx, gw, cx, cr, tn,
                             bw, ell, acc)


@numba.njit(cache=True)
def panel_integral(x0, r0, cx, cr, tn, bw, gx, gw, tol, acc):
    """Weights acc[k, (xx, xr, rx, rr)] of  int_panel M(x0, r0; X(t)) ell_k(t) dl  (singular-safe).

    The panel is the polynomial curve with Legendre coefficients cx, cr on t in [-1, 1]. The
    integral is split at the parameter t* of the point nearest to the target and each side is
    integrated on a geometric mesh graded toward t*: exact to ``tol`` for the logarithmic
    singularity of Mxx, Mrr (target on the panel) and for near-singular targets.
    """
    p = tn.shape[0]
    # start Gauss-Newton from the nearest node
    best = 0
    bestd = math.inf
    for k in range(p):
        x, _, r, _ = _curve_eval(cx, cr, tn[k])
        dd = (x - x0) ** 2 + (r - r0) ** 2
        if dd < bestd:
            bestd = dd
            best = k
    _graded_panel(x0, r0, cx, cr, tn[best], tn, bw, gx, gw, tol, acc)


@numba.njit(cache=True)
def self_panel_integral(x0, r0, cx, cr, st, sw, sell, acc):
    """Weights acc[k, (xx, xr, rx, rr)] of  int_panel M(x0, r0; X(t)) ell_k(t) dl  for a target
    at one of the panel's own nodes, by a fixed rule: parameters st (m,), weights sw (m,) in t
    and Lagrange values sell (m, p) of the rule for that node (:func:`bem.quadrature.self_rule`).
    """
    p = sell.shape[1]
    for k in range(p):
        for c in range(4):
            acc[k, c] = 0.0
    for i in range(st.shape[0]):
        x, dx, r, dr = _curve_eval(cx, cr, st[i])
        if r <= 0.0:
            continue            # a ring of zero radius carries nothing
        Mxx, Mxr, Mrx, Mrr = ring_stokeslet(x0, r0, x, r)
        w = sw[i] * math.sqrt(dx * dx + dr * dr)
        for k in range(p):
            wk = w * sell[i, k]
            acc[k, 0] += wk * Mxx
            acc[k, 1] += wk * Mxr
            acc[k, 2] += wk * Mrx
            acc[k, 3] += wk * Mrr


@numba.njit(cache=True)
def _store(out, i, base, acc):
    """Write the panel weights acc[k, (xx, xr, rx, rr)] into rows 2i, 2i+1 from column base."""
    for k in range(acc.shape[0]):
        out[2 * i, base + 2 * k] = acc[k, 0]
        out[2 * i, base + 2 * k + 1] = acc[k, 1]
        out[2 * i + 1, base + 2 * k] = acc[k, 2]
        out[2 * i + 1, base + 2 * k + 1] = acc[k, 3]


@numba.njit(cache=True)
def _near_panel(x0, r0, px, pr, pw, P, near):
    """(panel P of the set is near the target (x0, r0), nearest node of P): near when a node
    lies within ``near`` panel lengths."""
    p = px.shape[1]
    length = 0.0
    dmin = math.inf
    best = 0
    for k in range(p):
        length += pw[P, k]
        dd = (px[P, k] - x0) ** 2 + (pr[P, k] - r0) ** 2
        if dd < dmin:
            dmin = dd
            best = k
    return math.sqrt(dmin) < near * length, best


@numba.njit(cache=True)
def _influence_rows(c, n_chunks, tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, near, tol,
                    self_node, fixed, st, sw, sell, out):
    """Rows of the targets i = c, c + n_chunks, ... of :func:`influence_matrix`."""
    nt = tx.shape[0]
    npan, p = px.shape
    acc = np.empty((p, 4))
    for i in range(c, nt, n_chunks):
        x0 = tx[i]
        r0 = tr[i]
        for P in range(npan):
            is_near, best = _near_panel(x0, r0, px, pr, pw, P, near)
            base = 2 * P * p
            if self_node[i] >= 0 and self_node[i] // p == P and fixed[P]:
                k0 = self_node[i] - P * p
                self_panel_integral(x0, r0, pcx[P], pcr[P], st[k0], sw[k0], sell[k0], acc)
                _store(out, i, base, acc)
            elif is_near:                       # start from the nearest node
                _graded_panel(x0, r0, pcx[P], pcr[P], tn[best], tn, bw, gx, gw, tol, acc)
                _store(out, i, base, acc)
            else:
                for k in range(p):
                    Mxx, Mxr, Mrx, Mrr = ring_stokeslet(x0, r0, px[P, k], pr[P, k])
                    w = pw[P, k]
                    out[2 * i, base + 2 * k] = w * Mxx
                    out[2 * i, base + 2 * k + 1] = w * Mxr
                    out[2 * i + 1, base + 2 * k] = w * Mrx
                    out[2 * i + 1, base + 2 * k + 1] = w * Mrr


@numba.njit(cache=True, parallel=True)
def influence_matrix(tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, near, tol, self_node,
                     fixed, st, sw, sell, out):
    """Single-layer influence matrix of a panel set on targets, Nyström form.

    out[2i + a, 2(P p + k) + b] = int_panel_P M_ab(target i; X) ell_k dl, so that
    u_a(i) = (8 pi eta)^-1 sum out[2i+a, 2j+b] q_b(j) for node densities q (force per area on
    the fluid). Inputs: targets tx, tr (nt,); panel node coordinates px, pr (np, p); pw (np, p)
    Gauss weight times ``|dX/dt|`` at the nodes; Legendre coefficients pcx, pcr (np, p) of the
    panel curves; tn, bw Gauss nodes and barycentric weights on [-1, 1]; gx, gw Gauss rules
    (row n holds the n-point rule); panels closer to a target than ``near`` times their length
    are integrated by :func:`panel_integral` to ``tol``, the others by the nodes' own rule.
    A target that is node k of panel P (self_node[i] = P p + k, else -1) of a panel with
    fixed[P] true takes the fixed rule st[k], sw[k], sell[k] (:func:`self_panel_integral`).
    """
    # targets are dealt out cyclically to 64 chunks, the chunks to the threads: targets come
    # in runs of very different cost (an object's own nodes, each with its self and near
    # panels, then the wall's) and prange hands each thread one contiguous block, so that
    # with 2 threads the vesicle's membrane-source matrix (176 membrane + 160 wall targets)
    # took 29 ms against 34 ms on one thread; dealt out, 17-18 ms (any thread count to 64;
    # numba.get_num_threads() here would stop numba from caching the function)
    n_chunks = min(tx.shape[0], 64)
    for c in numba.prange(n_chunks):
        _influence_rows(c, n_chunks, tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, near, tol,
                        self_node, fixed, st, sw, sell, out)


@numba.njit(cache=True, nogil=True)
def influence_matrix_serial(tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, near, tol,
                            self_node, fixed, st, sw, sell, out):
    """:func:`influence_matrix` on the calling thread (for small blocks, where starting the
    parallel region costs more than the work: see :data:`bem.quadrature.SERIAL_WORK`)."""
    n_chunks = min(tx.shape[0], 64)
    for c in range(n_chunks):
        _influence_rows(c, n_chunks, tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, near, tol,
                        self_node, fixed, st, sw, sell, out)


@numba.njit(cache=True)
def _cross_panels(c, n_chunks, ax, ar, aw, acx, acr, bx, br, bw_, bcx, bcr, tn, bw, gx, gw,
                  near, tol, out_ab, out_ba):
    """The a-panels P = c, c + n_chunks, ... of :func:`cross_influence_matrix`: the rows of
    out_ab of their nodes and the columns of out_ba of their nodes (no other chunk writes
    there)."""
    na_pan, p = ax.shape
    nb_pan = bx.shape[0]
    acc = np.empty((p, 4))
    near_ba = np.empty(nb_pan * p, dtype=np.bool_)
    for P in range(c, na_pan, n_chunks):
        # b-nodes near panel P: graded integrals into the columns of P in out_ba
        for Q in range(nb_pan):
            for kb in range(p):
                j = Q * p + kb
                is_near, best = _near_panel(bx[Q, kb], br[Q, kb], ax, ar, aw, P, near)
                near_ba[j] = is_near
                if is_near:
                    _graded_panel(bx[Q, kb], br[Q, kb], acx[P], acr[P], tn[best], tn, bw, gx,
                                  gw, tol, acc)
                    _store(out_ba, j, 2 * P * p, acc)
        for ka in range(p):
            i = P * p + ka
            x0 = ax[P, ka]
            r0 = ar[P, ka]
            wa = aw[P, ka]
            for Q in range(nb_pan):
                ab_near, best = _near_panel(x0, r0, bx, br, bw_, Q, near)
                if ab_near:
                    _graded_panel(x0, r0, bcx[Q], bcr[Q], tn[best], tn, bw, gx, gw, tol, acc)
                    _store(out_ab, i, 2 * Q * p, acc)
                for kb in range(p):
                    j = Q * p + kb
                    if ab_near and near_ba[j]:
                        continue
                    Mxx, Mxr, Mrx, Mrr = ring_stokeslet(x0, r0, bx[Q, kb], br[Q, kb])
                    if not ab_near:
                        w = bw_[Q, kb]
                        out_ab[2 * i, 2 * j] = w * Mxx
                        out_ab[2 * i, 2 * j + 1] = w * Mxr
                        out_ab[2 * i + 1, 2 * j] = w * Mrx
                        out_ab[2 * i + 1, 2 * j + 1] = w * Mrr
                    if not near_ba[j]:
                        f = wa * r0 / br[Q, kb]
                        out_ba[2 * j, 2 * i] = f * Mxx
                        out_ba[2 * j, 2 * i + 1] = f * Mrx
                        out_ba[2 * j + 1, 2 * i] = f * Mxr
                        out_ba[2 * j + 1, 2 * i + 1] = f * Mrr


@numba.njit(cache=True, parallel=True)
def cross_influence_matrix(ax, ar, aw, acx, acr, bx, br, bw_, bcx, bcr, tn, bw, gx, gw, near,
                           tol, out_ab, out_ba):
    """Influence matrices of two disjoint panel sets a and b on each other's nodes.

    out_ab: panels b on the nodes of a; out_ba: panels a on the nodes of b (each as
    :func:`influence_matrix` with the nodes as targets). Near panels are integrated by the
    graded rule; every other pair of nodes (a_i, b_j) costs one ring Stokeslet M(a_i; b_j),
    which gives the entry of out_ab and, by the reciprocity of the ring Stokeslet
    M_ab(x0; x)/r = M_ba(x; x0)/r0, the entry M_ba(b_j; a_i) = (r_i/r_j) M_ab(a_i; b_j) of out_ba.
    Inputs per set: node coordinates, weights (Gauss weight times ``|dX/dt|``), Legendre
    coefficients, all (n_panels, p); the rest as :func:`influence_matrix`. The a-panels are
    dealt out to the threads (one parallel region); out_ba is written by columns, so a should
    be the larger set (rows of out_ba short: measured 123 ms against 170 ms the other way
    round for a vesicle's 2176 wall and 352 membrane nodes, on one thread).
    """
    n_chunks = min(ax.shape[0], 64)
    for c in numba.prange(n_chunks):
        _cross_panels(c, n_chunks, ax, ar, aw, acx, acr, bx, br, bw_, bcx, bcr, tn, bw, gx, gw,
                      near, tol, out_ab, out_ba)


@numba.njit(cache=True, nogil=True)
def cross_influence_matrix_serial(ax, ar, aw, acx, acr, bx, br, bw_, bcx, bcr, tn, bw, gx, gw,
                                  near, tol, out_ab, out_ba):
    """:func:`cross_influence_matrix` on the calling thread (small blocks)."""
    n_chunks = min(ax.shape[0], 64)
    for c in range(n_chunks):
        _cross_panels(c, n_chunks, ax, ar, aw, acx, acr, bx, br, bw_, bcx, bcr, tn, bw, gx, gw,
                      near, tol, out_ab, out_ba)


# --------------------------------------------------------------------------------------------
# Linearisation in the node positions of a moving panel set (membrane) beside a fixed one (wall)
# --------------------------------------------------------------------------------------------
#: relative step (to the source-target distance) of the central differences of the ring
#: Stokeslet (:func:`_ring_taylor`) and of the near-panel integrals (:func:`near_target_taylor`):
#: truncation ~ STEP^2/6 and rounding ~ 1e-16/STEP of the kernel's scale, both ~1e-11 at 1e-5
TAYLOR_STEP = 1e-5


@numba.njit(cache=True)
def near_flags(tx, tr, px, pr, pw, near, out):
    """out[i, P] = target (tx[i], tr[i]) lies within ``near`` lengths of panel P (the test of
    the influence kernels, :func:`_near_panel`)."""
    for i in range(tx.shape[0]):
        for P in range(px.shape[0]):
            out[i, P] = _near_panel(tx[i], tr[i], px, pr, pw, P, near)[0]


@numba.njit(cache=True)
def _central(plus, minus, h):
    """Central difference (plus - minus) / 2h of two ring-Stokeslet 4-tuples."""
    s = 0.5 / h
    return ((plus[0] - minus[0]) * s, (plus[1] - minus[1]) * s, (plus[2] - minus[2]) * s,
            (plus[3] - minus[3]) * s)


@numba.njit(cache=True)
def _ring_taylor(x0, r0, x, r):
    """Ring Stokeslet M(x0, r0; x, r) and its derivatives in the source position (x, r), by
    central differences of step TAYLOR_STEP times the distance (r - step stays >= r/2):
    (M, dM/dx, dM/dr), each a 4-tuple (xx, xr, rx, rr)."""
    d = math.sqrt((x0 - x) ** 2 + (r0 - r) ** 2)
    h = TAYLOR_STEP * d
    hr = min(h, 0.5 * r)
    M = ring_stokeslet(x0, r0, x, r)
    Dx = _central(ring_stokeslet(x0, r0, x + h, r), ring_stokeslet(x0, r0, x - h, r), h)
    Dr = _central(ring_stokeslet(x0, r0, x, r + hr), ring_stokeslet(x0, r0, x, r - hr), hr)
    return M, Dx, Dr


@numba.njit(cache=True)
def _taylor_panels(c, n_chunks, ax, ar, aw, bx, br, near_ab, near_ba, A_ab, A_ba):
    """The a-panels P = c, c + n_chunks, ... of :func:`cross_far_taylor`."""
    na_pan, p = ax.shape
    nb = bx.size
    n2 = 2 * nb
    for P in range(c, na_pan, n_chunks):
        for ka in range(p):
            i = P * p + ka
            x0 = ax[P, ka]
            r0 = ar[P, ka]
            f0 = aw[P, ka] * r0
            for j in range(nb):
                Q = j // p
                x = bx[Q, j - Q * p]
                r = br[Q, j - Q * p]
                far_ab = not near_ab[i, Q]
                far_ba = not near_ba[j, P]
                if not (far_ab or far_ba):
                    continue
                M, Dx, Dr = _ring_taylor(x0, r0, x, r)
                if far_ab:
                    for c3 in range(3):
                        T = M if c3 == 0 else (Dx if c3 == 1 else Dr)
                        A_ab[2 * i, c3 * n2 + 2 * j] = T[0]
                        A_ab[2 * i, c3 * n2 + 2 * j + 1] = T[1]
                        A_ab[2 * i + 1, c3 * n2 + 2 * j] = T[2]
                        A_ab[2 * i + 1, c3 * n2 + 2 * j + 1] = T[3]
                if far_ba:
                    # H = f0 M^T / r: its r-derivative adds -H / r
                    f = f0 / r
                    for c3 in range(3):
                        T = M if c3 == 0 else (Dx if c3 == 1 else Dr)
                        row = c3 * n2 + 2 * j
                        A_ba[row, 2 * i] = f * T[0]
                        A_ba[row, 2 * i + 1] = f * T[2]
                        A_ba[row + 1, 2 * i] = f * T[1]
                        A_ba[row + 1, 2 * i + 1] = f * T[3]
                    g = f / r
                    row = 2 * n2 + 2 * j
                    A_ba[row, 2 * i] -= g * M[0]
                    A_ba[row, 2 * i + 1] -= g * M[2]
                    A_ba[row + 1, 2 * i] -= g * M[1]
                    A_ba[row + 1, 2 * i + 1] -= g * M[3]


@numba.njit(cache=True, parallel=True)
def cross_far_taylor(ax, ar, aw, bx, br, near_ab, near_ba, A_ab, A_ba):
    """First-order expansion, in the positions of the b nodes, of the far node pairs of
    :func:`cross_influence_matrix` (a fixed, b moving), without b's quadrature weights.

    For wall nodes a_i and membrane nodes b_j (flat index j = Q p + k) with near_ab[i, Q] false,
    A_ab[2i + α, c 2nb + 2j + β] holds, for c = 0, 1, 2, the ring Stokeslet M_αβ(a_i; b_j) and
    its derivatives in x_j and r_j; with near_ba[j, P] false (P the a-panel of i),
    A_ba[c 2nb + 2j + α, 2i + β] holds H_αβ = w_i r_i M_βα(a_i; b_j) / r_j (the entry of the
    reverse influence matrix, reciprocity, Pozrikidis 1992) and its derivatives. Near pairs are
    left at zero (A_ab, A_ba must come zeroed). Moving the b nodes by (Δx_j, Δr_j) changes the
    far entries of the two influence matrices by the c = 1, 2 blocks times Δx_j, Δr_j, to
    second order.
    """
    n_chunks = min(ax.shape[0], 64)
    for c in numba.prange(n_chunks):
        _taylor_panels(c, n_chunks, ax, ar, aw, bx, br, near_ab, near_ba, A_ab, A_ba)


@numba.njit(cache=True, nogil=True)
def cross_far_taylor_serial(ax, ar, aw, bx, br, near_ab, near_ba, A_ab, A_ba):
    """:func:`cross_far_taylor` on the calling thread."""
    n_chunks = min(ax.shape[0], 64)
    for c in range(n_chunks):
        _taylor_panels(c, n_chunks, ax, ar, aw, bx, br, near_ab, near_ba, A_ab, A_ba)


@numba.njit(cache=True, nogil=True)
def near_product(pairs, acc, p, q, out):
    """out[2 i + α] += sum_k acc[n, k, (α, β)] q[2 (Q p + k) + β] over pairs[n] = (i, Q)."""
    for n in range(pairs.shape[0]):
        i = pairs[n, 0]
        base = 2 * pairs[n, 1] * p
        sx = 0.0
        sr = 0.0
        for k in range(p):
            qx = q[base + 2 * k]
            qr = q[base + 2 * k + 1]
            sx += acc[n, k, 0] * qx + acc[n, k, 1] * qr
            sr += acc[n, k, 2] * qx + acc[n, k, 3] * qr
        out[2 * i] += sx
        out[2 * i + 1] += sr


@numba.njit(cache=True)
def _self_taylor_rows(c, n_chunks, bx, br, near_dd, A):
    """The targets i = c, c + n_chunks, ... of :func:`self_far_taylor`."""
    p = bx.shape[1]
    nb = bx.size
    n2 = 2 * nb
    for i in range(c, nb, n_chunks):
        x0 = bx[i // p, i % p]
        r0 = br[i // p, i % p]
        for j in range(nb):
            Q = j // p
            if near_dd[i, Q]:
                continue
            x = bx[Q, j - Q * p]
            r = br[Q, j - Q * p]
            M, Dx, Dr = _ring_taylor(x0, r0, x, r)
            h0 = min(TAYLOR_STEP * math.sqrt((x0 - x) ** 2 + (r0 - r) ** 2), 0.5 * r0)
            Dr0 = _central(ring_stokeslet(x0, r0 + h0, x, r),
                           ring_stokeslet(x0, r0 - h0, x, r), h0)
            for c4 in range(4):
                T = M if c4 == 0 else (Dx if c4 == 1 else (Dr if c4 == 2 else Dr0))
                A[2 * i, c4 * n2 + 2 * j] = T[0]
                A[2 * i, c4 * n2 + 2 * j + 1] = T[1]
                A[2 * i + 1, c4 * n2 + 2 * j] = T[2]
                A[2 * i + 1, c4 * n2 + 2 * j + 1] = T[3]


@numba.njit(cache=True, parallel=True)
def self_far_taylor(bx, br, near_dd, A):
    """First-order expansion, in the node positions, of the far node pairs of the influence
    matrix of a moving panel set on its own nodes, without the quadrature weights.

    For nodes i, j (flat index j = Q p + k) with near_dd[i, Q] false, A[2i + α, c 2nb + 2j + β]
    holds, for c = 0, 1, 2, 3, the ring Stokeslet M_αβ(b_i; b_j) and its derivatives in x_j, r_j
    and r_i (the derivative in x_i is minus that in x_j: the kernel depends on x_i - x_j).
    Near pairs are left at zero (A must come zeroed).
    """
    n_chunks = min(bx.size, 64)
    for c in numba.prange(n_chunks):
        _self_taylor_rows(c, n_chunks, bx, br, near_dd, A)


@numba.njit(cache=True, nogil=True)
def self_far_taylor_serial(bx, br, near_dd, A):
    """:func:`self_far_taylor` on the calling thread."""
    n_chunks = min(bx.size, 64)
    for c in range(n_chunks):
        _self_taylor_rows(c, n_chunks, bx, br, near_dd, A)


@numba.njit(cache=True)
def _near_target_rows(ch, n_chunks, pairs, tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, tol,
                      acc, dx, dr):
    """The pairs n = ch, ch + n_chunks, ... of :func:`near_target_taylor`."""
    p = tn.shape[0]
    plus = np.empty((p, 4))
    minus = np.empty((p, 4))
    for n in range(ch, pairs.shape[0], n_chunks):
        j = pairs[n, 0]
        P = pairs[n, 1]
        x0 = tx[j]
        r0 = tr[j]
        best = _near_panel(x0, r0, px, pr, pw, P, math.inf)[1]
        t0 = tn[best]
        h = TAYLOR_STEP * math.sqrt((px[P, best] - x0) ** 2 + (pr[P, best] - r0) ** 2)
        hr = min(h, 0.5 * r0)
        _graded_panel(x0, r0, pcx[P], pcr[P], t0, tn, bw, gx, gw, tol, acc[n])
        _graded_panel(x0 + h, r0, pcx[P], pcr[P], t0, tn, bw, gx, gw, tol, plus)
        _graded_panel(x0 - h, r0, pcx[P], pcr[P], t0, tn, bw, gx, gw, tol, minus)
        for k in range(p):
            for c in range(4):
                dx[n, k, c] = (plus[k, c] - minus[k, c]) * (0.5 / h)
        _graded_panel(x0, r0 + hr, pcx[P], pcr[P], t0, tn, bw, gx, gw, tol, plus)
        _graded_panel(x0, r0 - hr, pcx[P], pcr[P], t0, tn, bw, gx, gw, tol, minus)
        for k in range(p):
            for c in range(4):
                dr[n, k, c] = (plus[k, c] - minus[k, c]) * (0.5 / hr)


@numba.njit(cache=True, parallel=True)
def near_target_taylor(pairs, tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, tol, acc, dx, dr):
    """Graded integrals of fixed panels on moving targets and their derivatives in the target
    position: for pairs[n] = (j, P), acc[n] the weights of panel P on target (tx[j], tr[j]) (the
    block :func:`_store` writes there), dx[n] and dr[n] their derivatives in tx[j] and tr[j]
    by central differences of step TAYLOR_STEP times the distance to P's nearest node (r -
    step stays >= r/2), each integral with the Gauss–Newton search started from that node.
    Parallel over the pairs."""
    n_chunks = min(pairs.shape[0], 64)
    for ch in numba.prange(n_chunks):
        _near_target_rows(ch, n_chunks, pairs, tx, tr, px, pr, pw, pcx, pcr, tn, bw, gx, gw, tol,
                          acc, dx, dr)


# --------------------------------------------------------------------------------------------
# Near panels of a moving panel set: the integrals and their derivatives in the panel's curve
# (its Legendre coefficients) and in the target position, by differentiating the integrand at
# the quadrature points (the rule is held fixed: it is smooth in the geometry)
# --------------------------------------------------------------------------------------------
@numba.njit(cache=True)
def _legendre_values(t, P, D):
    """P[n] = P_n(t) and D[n] = P_n'(t) for n < P.size (the recurrences of :func:`_curve_eval`:
    (n + 1) P_{n+1} = (2n + 1) t P_n - n P_{n-1} and P'_{n+1} = P'_{n-1} + (2n + 1) P_n,
    Abramowitz & Stegun 22.7.10 and 22.8.5)."""
    p = P.shape[0]
    P[0] = 1.0
    D[0] = 0.0
    if p > 1:
        P[1] = t
        D[1] = 1.0
    for n in range(1, p - 1):
        P[n + 1] = ((2.0 * n + 1.0) * t * P[n] - n * P[n - 1]) / (n + 1.0)
        D[n + 1] = D[n - 1] + (2.0 * n + 1.0) * P[n]


@numba.njit(cache=True)
def _taylor_point(x0, r0, x, dx, r, dr, w, ell, P, D, g, acc, der):
    r"""Add one quadrature point of a panel integral, the source X = (x, r) with X' = (dx, dr)
    at its parameter t, weight w in t, Lagrange values ell and Legendre values P, D at t: to
    acc[k, c] the weight :math:`w |X'| \ell_k M_c(x_0, r_0; X)` (as :func:`_accumulate_interval`)
    and to der[k, c, m] its derivatives in the panel's Legendre coefficients (m < p: cx_m,
    p <= m < 2p: cr_{m-p}; X = sum c_m P_m(t), so dX/dc_m = P_m(t), dX'/dc_m = P_m'(t)) and in
    the target (m = 2p: x0, 2p + 1: r0). The kernel's derivatives by central differences
    (:func:`_ring_taylor`; in x0 minus that in x: the kernel depends on x - x0)."""
    p = P.shape[0]
    jac = math.sqrt(dx * dx + dr * dr)
    M, Mx, Mr = _ring_taylor(x0, r0, x, r)
    h0 = min(TAYLOR_STEP * math.sqrt((x0 - x) ** 2 + (r0 - r) ** 2), 0.5 * r0)
    Mr0 = _central(ring_stokeslet(x0, r0 + h0, x, r), ring_stokeslet(x0, r0 - h0, x, r), h0)
    wj = w * jac
    ux = w * dx / jac
    ur = w * dr / jac
    for c in range(4):
        for m in range(p):
            g[c, m] = wj * Mx[c] * P[m] + M[c] * ux * D[m]
            g[c, p + m] = wj * Mr[c] * P[m] + M[c] * ur * D[m]
        g[c, 2 * p] = -wj * Mx[c]
        g[c, 2 * p + 1] = wj * Mr0[c]
    for k in range(p):
        wk = wj * ell[k]
        acc[k, 0] += wk * M[0]
        acc[k, 1] += wk * M[1]
        acc[k, 2] += wk * M[2]
        acc[k, 3] += wk * M[3]
    # der[k] += ell[k] g: rank-one updates of contiguous rows (vectorised)
    flat = g.ravel()
    rows = der.reshape(p, flat.size)
    for k in range(p):
        e = ell[k]
        row = rows[k]
        for m in range(flat.size):
            row[m] += e * flat[m]


@numba.njit(cache=True)
def _panel_taylor(x0, r0, cx, cr, t_start, self_k, st, sw, sell, tn, bw, gx, gw, tol, acc,
                  der):
    """acc = the weights of the panel (cx, cr) on the target (x0, r0) (as :func:`_graded_panel`
    or, for self_k >= 0, as :func:`self_panel_integral` with the rule of node self_k) and der
    their derivatives in the panel's Legendre coefficients and the target (:func:`_taylor_point`).
    For a target that is a panel node, moving with it, the two parts' singular terms cancel in
    the sum of der's products with a displacement of both (the rule sees their sum)."""
    p = tn.shape[0]
    ell = np.empty(p)
    P = np.empty(p)
    D = np.empty(p)
    g = np.empty((4, 2 * p + 2))
    acc[:] = 0.0
    der[:] = 0.0
    if self_k >= 0:
        for i in range(st.shape[1]):
            t = st[self_k, i]
            x, dx, r, dr = _curve_eval(cx, cr, t)
            if r <= 0.0:
                continue
            _legendre_values(t, P, D)
            _taylor_point(x0, r0, x, dx, r, dr, sw[self_k, i], sell[self_k, i], P, D, g, acc,
                          der)
        return
    iv = np.empty((64, 3))
    for j in range(_graded_plan(x0, r0, cx, cr, t_start, gx.shape[0] - 1, tol, iv)):
        a = iv[j, 0]
        b = iv[j, 1]
        n = int(iv[j, 2])
        half = 0.5 * (b - a)
        mid = 0.5 * (a + b)
        for i in range(n):
            t = mid + half * gx[n, i]
            x, dx, r, dr = _curve_eval(cx, cr, t)
            r = max(r, 0.0)
            if r == 0.0 or (x == x0 and r == r0):
                continue
            _lagrange(t, tn, bw, ell)
            _legendre_values(t, P, D)
            _taylor_point(x0, r0, x, dx, r, dr, half * gw[n, i], ell, P, D, g, acc, der)


@numba.njit(cache=True, parallel=True)
def near_panels_taylor(pairs, tx, tr, own, px, pr, pw, pcx, pcr, fixed, tn, bw, gx, gw, tol,
                       st, sw, sell, acc, der):
    """The near blocks of a moving panel set on targets, and their derivatives: for
    pairs[n] = (i, P), acc[n] the weights of panel P on target i (the block :func:`_store`
    writes there; if ``own`` the targets are the panels' nodes, flat index i = Q p + k, and a
    node on its own panel P with fixed[P] takes the fixed self rule, as in
    :func:`influence_matrix`) and der[n, k, c, m] their derivatives in P's Legendre
    coefficients and the target's position (:func:`_panel_taylor`). Parallel over the pairs."""
    p = tn.shape[0]
    n_chunks = min(pairs.shape[0], 64)
    for ch in numba.prange(n_chunks):
        for n in range(ch, pairs.shape[0], n_chunks):
            i = pairs[n, 0]
            P = pairs[n, 1]
            self_k = i - P * p if own and i // p == P and fixed[P] else -1
            best = _near_panel(tx[i], tr[i], px, pr, pw, P, math.inf)[1]
            _panel_taylor(tx[i], tr[i], pcx[P], pcr[P], tn[best], self_k, st, sw, sell, tn, bw,
                          gx, gw, tol, acc[n], der[n])


@numba.njit(cache=True, parallel=True, fastmath=True)
def near_products_taylor(pairs, acc, der, dcx, dcr, dtx, dtr, q, n_chunks, out):
    """:func:`near_product` for many moved copies j of a panel set, each block to first order:
    acc[n] plus der[n] times the displacement of panel Q's Legendre coefficients (dcx[j, Q],
    dcr[j, Q]) and of target i (dtx[j, i], dtr[j, i]), for pairs[n] = (i, Q)
    (:func:`near_panels_taylor`); out[j, 2 i + α] += sum_k block[k, (α, β)]
    q[j, 2 (Q p + k) + β].
    The copies are dealt to ``n_chunks`` threads, each running through the pairs once (a
    block's derivatives, 2176 numbers at p = 16, stay in cache for all its copies); the
    contractions are vectorised (fastmath: summed in another order than written)."""
    p = acc.shape[1]
    nm = 2 * p + 2
    m_pts = q.shape[0]
    for ch in numba.prange(n_chunks):
        delta = np.empty(nm)
        for n in range(pairs.shape[0]):
            i = pairs[n, 0]
            Q = pairs[n, 1]
            base = 2 * Q * p
            for j in range(ch, m_pts, n_chunks):
                for m in range(p):
                    delta[m] = dcx[j, Q, m]
                    delta[p + m] = dcr[j, Q, m]
                delta[2 * p] = dtx[j, i]
                delta[2 * p + 1] = dtr[j, i]
                sx = 0.0
                sr = 0.0
                for k in range(p):
                    a0 = acc[n, k, 0]
                    a1 = acc[n, k, 1]
                    a2 = acc[n, k, 2]
                    a3 = acc[n, k, 3]
                    for m in range(nm):
                        a0 += der[n, k, 0, m] * delta[m]
                        a1 += der[n, k, 1, m] * delta[m]
                        a2 += der[n, k, 2, m] * delta[m]
                        a3 += der[n, k, 3, m] * delta[m]
                    qx = q[j, base + 2 * k]
                    qr = q[j, base + 2 * k + 1]
                    sx += a0 * qx + a1 * qr
                    sr += a2 * qx + a3 * qr
                out[j, 2 * i] += sx
                out[j, 2 * i + 1] += sr
