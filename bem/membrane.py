r"""Forces of an inextensible bending membrane on a spectral generating curve.

Conventions (stated once): outward normal :math:`n = (-\sin\psi, \cos\psi)`, unit tangent
:math:`t = (\cos\psi, \sin\psi)` from the rear to the front pole, principal curvatures
:math:`\kappa_1 = -d\psi/ds`, :math:`\kappa_2 = \cos\psi/r` (positive for a sphere), mean
curvature :math:`H = (\kappa_1 + \kappa_2)/2` (1/a for a sphere), Gaussian curvature
:math:`K = \kappa_1\kappa_2`. Every force density is the force per unit area that the membrane
exerts **on the fluid** (``q`` of :mod:`bem.assembly` and :mod:`bem.drop`).

Helfrich bending without spontaneous curvature, energy :math:`E = 2\kappa\int H^2\,dA`
(Helfrich 1973; Zhong-can & Helfrich 1989; Chen et al. 2020 eq. E:fm):

.. math:: f_b = 2\kappa\,[\Delta_s H + 2H(H^2 - K)]\,n, \qquad
          \int f_b\cdot\delta X\,dA = -\delta E ,

and the tension of local inextensibility (Lagrange multiplier :math:`\gamma(s)`):

.. math:: f_\gamma = -2\gamma H\,n + \nabla_s\gamma, \qquad
          \int f_\gamma\cdot\delta X\,dA = -\int\gamma\,\nabla_s\!\cdot\delta X\,dA .

The second identities (virtual work) are the sign checks of the tests: with constant
:math:`\gamma` the right-hand side is :math:`-\gamma\,\delta A` (the area-rate identity).

Numerics: H is even about both poles in the curve parameter :math:`\tau`, so it is expanded in
the cosine series :math:`H = \sum_{k\ge 0} h_k\cos(k\pi\tau)` from its values on
:math:`\tau_j = j/M` (a DCT-I, exact pole values from :meth:`SpectralCurve.curvatures`) and
differentiated term by term. With :math:`d/ds = (Sg)^{-1}d/d\tau`,
:math:`\Delta_s H = H_{ss} + (\sin\psi/r) H_s`, which tends to :math:`2H_{ss}` at the poles.
The tension is the cosine series :math:`\gamma = \sum_{k=0}^{M} g_k\cos(k\pi\tau)` (arc length
from the rear pole when the curve has no density terms); it is regular at both poles.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.fft

from lubrication.checks import check_range

from .shape import SpectralCurve, cosine_series, gauss_legendre01, sine_series

__all__ = ["bending_energy", "bending_force", "mean_curvature_series", "surface_laplacian_H",
           "tension_basis", "tension_force", "tension_profile"]


def _default_points(curve: SpectralCurve) -> int:
    # H carries the bandwidth of the modes and of the density, plus the nonlinear harmonics of
    # cos(psi)/r; four points per mode plus 64 resolve it to round-off for the shapes met here
    # (checked in the tests against twice as many points)
    return 4 * (curve.n_modes + curve.density.size) + 64


def mean_curvature_series(curve: SpectralCurve, n_points: int | None = None) -> np.ndarray:
    """Cosine coefficients h_0..h_M of H(tau) = sum_k h_k cos(k pi tau) [1/R], M = n_points."""
    M = int(check_range("n_points", n_points or _default_points(curve), 8, 1 << 16))
    tau = np.arange(M + 1) / M
    k1, k2 = curve.curvatures(tau)
    c = scipy.fft.dct(0.5 * (k1 + k2), type=1) / M
    c[0] *= 0.5
    c[-1] *= 0.5
    return c


def _cos_series(c, tau, deriv=0):
    """sum_k c_k d^n/dtau^n cos(k pi tau), k = 0..len(c)-1, n = deriv in 0, 1, 2 (tau an
    array), by the Clenshaw recurrences of :mod:`bem.shape` (the derivative series are the
    sine and cosine series of k c_k and k^2 c_k)."""
    c = np.asarray(c, dtype=float)
    tau = np.asarray(tau, dtype=float)
    th = np.pi * tau
    k = np.arange(1, c.size)
    if deriv == 0:
        return c[0] + cosine_series(c[1:], th)
    if deriv == 1:
        return -np.pi * sine_series(k * c[1:], th) * np.sin(th)
    return -np.pi**2 * cosine_series(k * k * c[1:], th)


def _g_and_derivative(curve: SpectralCurve, tau):
    """Density g(tau) and dg/dtau."""
    tau = np.asarray(tau, dtype=float)
    if not curve.density.size:
        return np.ones_like(tau), np.zeros_like(tau)
    a = np.concatenate([[1.0], curve.density])
    return _cos_series(a, tau), _cos_series(a, tau, 1)


def _sin_over_r(curve: SpectralCurve, tau):
    """sin(psi)/r [1/R] away from the poles (the caller takes the pole limits)."""
    _, r = curve.position(tau)
    return np.sin(curve.tangent_angle(tau)) / r


def surface_laplacian_H(curve: SpectralCurve, tau, n_points: int | None = None):
    r"""(H, K, Δ_s H) at ``tau`` [1/R, 1/R², 1/R³], exact pole limit Δ_s H = 2 H_ss."""
    tau = np.asarray(tau, dtype=float)
    c = mean_curvature_series(curve, n_points)
    S = curve.length
    g, g_t = _g_and_derivative(curve, tau)
    H_t, H_tt = _cos_series(c, tau, 1), _cos_series(c, tau, 2)
    H_s = H_t / (S * g)
    H_ss = H_tt / (S * g) ** 2 - H_t * g_t / (S * S * g**3)
    pole = (tau <= 0.0) | (tau >= 1.0)
    lap = 2.0 * H_ss
    if np.any(~pole):
        lap[~pole] = H_ss[~pole] + _sin_over_r(curve, tau[~pole]) * H_s[~pole]
    k1, k2 = curve.curvatures(tau)
    return 0.5 * (k1 + k2), k1 * k2, lap


def bending_force(curve: SpectralCurve, tau, kappa: float, n_points: int | None = None):
    r"""Helfrich force on the fluid :math:`2\kappa[\Delta_sH + 2H(H^2 - K)]n` at ``tau``.

    ``kappa`` is the bending modulus in the units of the problem (here ηUR², i.e.
    :math:`\lambda^2/\mathrm{Ca}_B` with Ca_B = ηUR0²/κ). Returns (f_x, f_r) [κ/R³ times kappa].
    """
    H, K, lap = surface_laplacian_H(curve, tau, n_points)
    mag = 2.0 * kappa * (lap + 2.0 * H * (H * H - K))
    nx, nr = curve.normal(tau)
    return mag * nx, mag * nr


def tension_profile(curve: SpectralCurve, g, tau):
    """(gamma, dgamma/ds) of gamma = sum_k g_k cos(k pi tau) at ``tau`` [ηU, ηU/R]."""
    g = np.asarray(g, dtype=float)
    dens, _ = _g_and_derivative(curve, tau)
    return _cos_series(g, tau), _cos_series(g, tau, 1) / (curve.length * dens)


def tension_force(curve: SpectralCurve, g, tau):
    r"""Tension force on the fluid :math:`-2\gamma H n + (d\gamma/ds)\,t` at ``tau``, for
    :math:`\gamma = \sum_k g_k\cos(k\pi\tau)` (k = 0..len(g)-1). Returns (f_x, f_r).

    Summed directly (:func:`tension_profile`), not as ``g`` times :func:`tension_basis`: the
    load of one tension at 96 modes without the (M, 2, nodes) basis."""
    tau = np.asarray(tau, dtype=float)
    gam, dgam = tension_profile(curve, g, tau)
    psi = curve.tangent_angle(tau)
    tx, tr = np.cos(psi), np.sin(psi)
    two_gh = 2.0 * gam * curve.mean_curvature(tau)
    return two_gh * tr + dgam * tx, -two_gh * tx + dgam * tr


def tension_basis(curve: SpectralCurve, tau, n_terms: int) -> np.ndarray:
    """Tension force of each term cos(k pi tau), k = 0..n_terms-1: array
    ``(n_terms, 2, *tau.shape)`` with the x and r components (the force is linear in the
    coefficients)."""
    tau = np.asarray(tau, dtype=float)
    n_terms = int(check_range("n_terms", n_terms, 1, 4096))
    psi = curve.tangent_angle(tau)
    tx, tr = np.cos(psi), np.sin(psi)
    nx, nr = -tr, tx
    H = curve.mean_curvature(tau)
    dens, _ = _g_and_derivative(curve, tau)
    k = np.pi * np.arange(n_terms)
    th = np.multiply.outer(k, tau)
    gam = np.cos(th)
    dgam = -k.reshape((-1,) + (1,) * tau.ndim) * np.sin(th) / (curve.length * dens)
    out = np.empty((n_terms, 2) + tau.shape)
    out[:, 0] = -2.0 * gam * H * nx + dgam * tx
    out[:, 1] = -2.0 * gam * H * nr + dgam * tr
    return out


def bending_energy(curve: SpectralCurve, kappa: float = 1.0, n_quad: int | None = None) -> float:
    r"""Helfrich energy :math:`2\kappa\int H^2\,dA` (8πκ for any sphere)."""
    t, w = gauss_legendre01(n_quad or (4 * (curve.n_modes + curve.density.size) + 96))
    _, r = curve.position(t)
    H = curve.mean_curvature(t)
    dA = 2.0 * math.pi * r * curve.length * curve.g(t) * w
    return float(2.0 * kappa * np.sum(H * H * dA))
