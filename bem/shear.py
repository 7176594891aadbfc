r"""In-plane shear elasticity of a red-cell membrane on a spectral generating curve (BEM).

A red cell's membrane resists in-plane shear relative to a stress-free reference shape; its law,
reference shapes and material map are those of the lubrication model
(:mod:`lubrication.membrane`, imported here, not repeated). This module gives the steady BEM
(:class:`bem.vesicle.VesicleOperator`) what it needs of them on a :class:`bem.shape.SpectralCurve`,
in the order of the computation:

1. **Area coordinate.** A steady axisymmetric membrane is at rest in the cell's frame, so each
   material point keeps its area coordinate :math:`a = \int_0^s 2\pi r\,\mathrm{d}s` from the rear
   pole (:mod:`lubrication.membrane`, item 3). :func:`area_coordinate` integrates
   :math:`\mathrm{d}a/\mathrm{d}\tau = 2\pi r S g` from each pole.
2. **Stretch.** :math:`\lambda_\varphi^2 = r^2/r_\mathrm{ref}^2(a)`, :math:`\lambda_s =
   1/\lambda_\varphi` (:func:`stretch_squared`), with :math:`r_\mathrm{ref}^2(a)` the series of
   :attr:`lubrication.membrane.ReferenceShape.radius_sq` scaled to the cell's area.
3. **Load.** The deviatoric tensions :math:`\tau_s = G_s f`, :math:`\tau_\varphi = -G_s f` of the
   Evans law (:func:`lubrication.membrane.tension_difference`) load the fluid with
   :func:`shear_force`; the isotropic part is the tension :math:`\gamma` of
   :func:`bem.membrane.tension_force` (the Lagrange multiplier of local area conservation), so
   the BEM adds only the deviatoric part.
4. **Energy.** :func:`shear_energy`, whose variation the load is (the sign check of the tests).

Conventions are those of :mod:`bem.membrane`: outward normal :math:`n = (-\sin\psi, \cos\psi)`,
tangent :math:`t = (\cos\psi, \sin\psi)` from the rear (τ = 0) to the front (τ = 1) pole,
:math:`\kappa_1 = -\mathrm{d}\psi/\mathrm{d}s`, :math:`\kappa_2 = \cos\psi/r`,
:math:`\mathrm{d}r/\mathrm{d}s = \sin\psi`; every force density is the force per unit area the
membrane exerts **on the fluid**, and :math:`\int f\cdot\delta X\,\mathrm{d}A = -\delta E`.
Units: lengths in tube radii R, tensions and :math:`G_s` in ηU (U the mean velocity), so
:math:`G_s/(\eta U) = 1/\mathrm{Ca}_S` with :math:`\mathrm{Ca}_S` =
:attr:`lubrication.membrane.MembraneShear.ca_s`; forces per area in ηU/R, energies in ηUR².

Numerics near the poles. :math:`\lambda_\varphi^2` is a ratio of two quantities that vanish like
a at the rear pole (and like :math:`b = A - a` at the front). Evaluated as they stand, a and
:math:`r_\mathrm{ref}^2(a)` carry absolute errors of round-off times the area, so the ratio's
relative error grows like :math:`\epsilon A/a` (5e-10 at the node nearest a pole of a 64-mode
level of the red cell, r = 2.3e-3, spheroid reference). Both are therefore evaluated in factored
form: the cumulative area from each pole as :math:`(x + 1)^2 Q(x)` (x the Chebyshev variable of
that half, Q the quotient of the series of the integral of :math:`u\,J(u)`, J the interpolant of
:math:`2\pi S g r/u`, u the parameter distance to the pole) and
the reference radius as :math:`(x \pm 1)\,q_\pm(x)` (the series of
:attr:`~lubrication.membrane.ReferenceShape.radius_sq` divided by its root at either pole).
:math:`\lambda_\varphi^2` then keeps a relative accuracy set by the reference series itself
(the derivative of its interpolation error at the pole: 2.5e-12 for the biconcave disc and
2.5e-11 for the spheroid at ν = 0.61, against the parametric profile). The load is much less
sensitive than the stretch: an additive error c in :math:`r_\mathrm{ref}^2` changes f by
:math:`c/r^2`, which leaves :math:`r^2 f`, hence the tangential load
:math:`G_s r^{-2}\mathrm{d}(r^2 f)/\mathrm{d}s`, unchanged to leading order (the two
evaluations' loads differ by 2e-12 G_s at that node). At the poles themselves the strain is
isotropic, :math:`f = (k^2 - k_\mathrm{ref}^2)a/(4\pi) + O(a^2)` (:mod:`lubrication.membrane`,
item 3), so :math:`f \to 0`, :math:`f/r \to 0` and the load vanishes: τ = 0 and 1 return exact
zeros.

References
----------
* Evans 1973, Biophys. J. 13, 941-954, doi:10.1016/S0006-3495(73)86036-9.
* Evans & Skalak 1980, *Mechanics and Thermodynamics of Biomembranes*, CRC Press.
* Pozrikidis 2003, *Modeling and Simulation of Capsules and Biological Cells*, Chapman & Hall.
* Secomb, Skalak, Özkaya & Gross 1986, J. Fluid Mech. 163, 405-423,
  doi:10.1017/S0022112086002355.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.polynomial import chebyshev

from lubrication.checks import InvalidParameterError, as_finite, check_range
from lubrication.membrane import (
    STRETCH_SQ_GUARD,
    MembraneShear,
    ReferenceShape,
    shear_energy_density,
    tension_difference,
)

from .shape import SpectralCurve, cosine_series, gauss_legendre01

__all__ = ["area_coordinate", "principal_tension_force", "shear_energy", "shear_force",
           "stretch_squared"]


# --------------------------------------------------------------------------- 1. area coordinate
def _area_degree(curve: SpectralCurve) -> int:
    # degree of the Chebyshev interpolant of (da/dtau)/u = 2 pi S g r/u over half the curve: r
    # carries the harmonics of the modes and the density (sin psi of a sine series); twice their
    # count plus 32 leaves the last coefficients at round-off for the shapes met here (the area
    # agrees with twice the degree to 9e-16 of the total on a 56-mode parachute, tests)
    return 2 * (curve.n_modes + curve.density.size) + 32


def _chebval(x, c):
    """sum_k c_k T_k(x) for x in [-1, 1]: the Clenshaw recurrence of
    :func:`bem.shape.cosine_series` at theta = arccos(x) (it recurs on cos(theta) = x, as
    numpy's ``chebval`` does, compiled: 2x faster at 352 points and 200 terms)."""
    return c[0] + cosine_series(c[1:], np.arccos(np.clip(x, -1.0, 1.0)))


def _divide_root(c, x0):
    """Chebyshev coefficients of q with p = (x - x0) q + rem for the series p = ``c`` and the
    root x0 = -1 or 1: synthetic division by the recurrence x T_k = (T_{k+1} + T_{k-1})/2 from
    the top, the remainder (round-off for a root at x0) dropped (as
    :func:`numpy.polynomial.chebyshev.chebdiv`, 6x faster at 200 terms)."""
    c = np.asarray(c, dtype=float)
    n = c.size - 1
    b = np.zeros(n + 2)                    # b[k] for k = 0..n-1, two zeros above
    for m in range(n, 1, -1):
        b[m - 1] = 2.0 * (c[m] + x0 * b[m]) - b[m + 1]
    if n >= 1:
        b[0] = c[1] + x0 * b[1] - 0.5 * b[2]
    return b[:max(n, 1)]


def _area_series(curve: SpectralCurve):
    """Quotients (Q_rear, Q_front) and the total area A_c [R^2] of the cumulative area from
    each pole: on a half, with u the parameter distance to its pole and x = 4u - 1,
    a(u) = int_0^u 2 pi r S g du' = (x + 1)^2 Q(x).

    The interpolant is that of J = 2 pi S g r/u (r/u = S int_0^1 g cos(phi(ut)) dt, nonzero at
    the pole), so that the integrand u J and the integral have their roots at the pole exactly
    and the quotient keeps the relative accuracy of J."""
    n = _area_degree(curve)
    x = chebyshev.chebpts1(n + 1)
    tau = np.concatenate([0.25 * (x + 1.0), 1.0 - 0.25 * (x + 1.0)])
    u = np.where(tau <= 0.5, tau, 1.0 - tau)      # the distance position() integrates over
    _, r = curve.position(tau)
    J = (2.0 * math.pi * curve.length * curve.g(tau) * r / u).reshape(2, -1).T     # (n+1, 2)
    # interpolation at the Chebyshev points of the first kind (as Chebyshev.interpolate)
    coef = chebyshev.chebvander(x, n).T @ J
    coef[0] /= n + 1
    coef[1:] /= 0.5 * (n + 1)
    quotients, total = [], 0.0
    for k in (0, 1):
        integrand = 0.25 * chebyshev.chebmul(coef[:, k], [1.0, 1.0])   # u J, u = (x + 1)/4
        P = chebyshev.chebint(integrand, lbnd=-1.0, scl=0.25)          # d/du = 4 d/dx
        total += float(chebyshev.chebval(1.0, P))
        # P has a double root at x = -1: divide it out
        quotients.append(_divide_root(_divide_root(P, -1.0), -1.0))
    return quotients[0], quotients[1], total


def _area_pair(curve: SpectralCurve, tau):
    """(a, b, A_c): area from the rear pole a, from the front pole b = A_c - a, each with its
    relative accuracy near its own pole, and the total A_c [R^2]."""
    tau = np.asarray(tau, dtype=float)
    q_rear, q_front, total = _area_series(curve)
    rear = tau <= 0.5
    u = np.where(rear, tau, 1.0 - tau)
    near = np.empty_like(u)
    for sel, q in ((rear, q_rear), (~rear, q_front)):
        near[sel] = 16.0 * u[sel] ** 2 * _chebval(4.0 * u[sel] - 1.0, q)
    a = np.where(rear, near, total - near)
    b = np.where(rear, total - near, near)
    return a, b, total


def area_coordinate(curve: SpectralCurve, tau):
    r"""Area coordinate :math:`a(\tau) = \int_0^\tau 2\pi r\,S g\,\mathrm{d}\tau'` of the
    surface of revolution of ``curve`` from the rear pole [R²].

    The material label of a steady membrane (Secomb et al. 1986; :mod:`lubrication.membrane`,
    item 3). The integrand is interpolated on each half of the curve at Chebyshev points (degree
    ``2(N + J) + 32`` for N modes and J density terms) and integrated from its pole; the
    halves meet at τ = 1/2, the front half gives :math:`a = A_c - b` with b the area from the
    front pole. ``a(1)`` is the total area :math:`A_c` (agrees with
    :meth:`bem.shape.SpectralCurve.area`, a Gauss rule, to round-off).

    Parameters
    ----------
    curve : SpectralCurve
        Generating curve [R].
    tau : array_like
        Curve parameters in [0, 1].

    Returns
    -------
    a : ndarray
        Area coordinate [R²], 0 at the rear pole, :math:`A_c` at the front pole.

    Examples
    --------
    >>> sphere = SpectralCurve.sphere(1.0)
    >>> a = area_coordinate(sphere, np.array([0.0, 0.5, 1.0]))
    >>> [round(float(v / np.pi), 12) for v in a]                    # 2 pi (1 - cos theta)
    [0.0, 2.0, 4.0]
    """
    tau = check_range("tau", tau, 0.0, 1.0)
    return _area_pair(curve, tau.ravel())[0].reshape(tau.shape)


# --------------------------------------------------------------------------- 2. stretch
@functools.lru_cache(maxsize=32)
def _reference_series(reference: ReferenceShape):
    """(q_rear, q_front, d rho^2/drho) of the reference's rho^2 = radius_sq on [0, 4 pi], as
    Chebyshev coefficients in x = rho/(2 pi) - 1: rho^2 with its pole value removed and divided
    by (x + 1) and by (x - 1), and its derivative in rho."""
    p = reference.radius_sq
    if not np.allclose(p.domain, [0.0, 4.0 * math.pi], rtol=0.0, atol=1e-14):
        raise InvalidParameterError("reference.radius_sq", f"domain {p.domain}",
                                    "a series on [0, 4 pi] (lubrication.membrane)")
    c = np.array(p.coef, dtype=float)
    rear, front = c.copy(), c.copy()
    rear[0] -= chebyshev.chebval(-1.0, c)          # exactly zero at the poles (round-off there)
    front[0] -= chebyshev.chebval(1.0, c)
    # the derivative's coefficients in the same variable x = rho/(2 pi) - 1 (d/drho = d/dx / 2pi)
    return (_divide_root(rear, -1.0), _divide_root(front, 1.0),
            chebyshev.chebder(c) / (2.0 * math.pi))


def _reference_radius_sq(shear: MembraneShear, a, b):
    r""":math:`r_\mathrm{ref}^2` [R²] at material area coordinates a from the rear and b = A - a
    from the front (A = ``shear.area``), and its derivative in a [-]: the reference of area
    :math:`4\pi` scaled to A, :math:`r_\mathrm{ref}^2(a) = \frac{A}{4\pi}\rho^2(4\pi a/A)`
    (:meth:`lubrication.membrane.ReferenceShape.radius_squared`), in the factored forms of the
    module docstring: :math:`(a/2\pi)\,q_-(x)` from the rear, :math:`-(b/2\pi)\,q_+(x)` from the
    front, x = (a - b)/A."""
    q_rear, q_front, drho = _reference_series(shear.reference)
    A = shear.area
    x = np.clip((a - b) / A, -1.0, 1.0)
    rear = a <= b
    ref_sq = np.empty_like(x)
    ref_sq[rear] = a[rear] * _chebval(x[rear], q_rear)
    ref_sq[~rear] = -b[~rear] * _chebval(x[~rear], q_front)
    return ref_sq / (2.0 * math.pi), _chebval(x, drho)


def _stretch(curve: SpectralCurve, tau, shear: MembraneShear, slope: bool):
    """lam_phi^2 off the poles (``inner``: the entries of tau strictly inside (0, 1)), r there,
    and with ``slope`` d(lam_phi^2)/ds [1/R] and psi. Material coordinates: the curve's area
    coordinates scaled by A/A_c (A = shear.area), so that the front pole maps to the front pole
    (the operator's curves have A_c = A to 1e-14)."""
    tau = np.asarray(tau, dtype=float)
    inner = (tau > 0.0) & (tau < 1.0)
    t = tau[inner]
    a, b, total = _area_pair(curve, t)
    k = shear.area / total
    a, b = np.maximum(k * a, 0.0), np.maximum(k * b, 0.0)
    ref_sq, dref = _reference_radius_sq(shear, a, b)
    _, r = curve.position(t)
    lo, hi = STRETCH_SQ_GUARD
    raw = r * r / np.maximum(ref_sq, 1e-300)
    L = np.clip(raw, lo, hi)
    if not slope:
        return inner, L, r, None, None
    psi = curve.tangent_angle(t)
    # d(r^2)/ds = 2 r sin(psi), d(r_ref^2)/ds = (d r_ref^2/da)(da/ds) = dref k 2 pi r
    dL = 2.0 * r / np.maximum(ref_sq, 1e-300) * (np.sin(psi) - math.pi * k * L * dref)
    dL = np.where(L == raw, dL, 0.0)                   # the guard holds L constant
    return inner, L, r, dL, psi


def stretch_squared(curve: SpectralCurve, tau, shear: MembraneShear):
    r"""Squared azimuthal stretch :math:`\lambda_\varphi^2 = r^2/r_\mathrm{ref}^2(a)` [-] at
    ``tau`` (Secomb et al. 1986; Evans & Skalak 1980 for the area-preserving map
    :math:`\lambda_s\lambda_\varphi = 1`).

    The material map of :mod:`lubrication.membrane` (item 3) on ``curve``: a the
    :func:`area_coordinate` (scaled by ``shear.area`` over the curve's area, a factor 1 for a
    curve of the cell's area), :math:`r_\mathrm{ref}^2` the reference of ``shear`` scaled to
    ``shear.area``, within :data:`lubrication.membrane.STRETCH_SQ_GUARD` as
    :meth:`~lubrication.membrane.MembraneShear.stretch_squared`; relative accuracy up to the
    poles (module docstring), exactly 1 at τ = 0 and 1 (isotropic strain at the poles).

    Examples
    --------
    >>> from lubrication.membrane import reference_shape
    >>> cell = SpectralCurve.sphere(1.0)
    >>> shear = MembraneShear(0.2, reference_shape("spheroid", 0.9), cell.area())
    >>> L = stretch_squared(cell, np.array([0.0, 0.5, 1.0]), shear)
    >>> float(L[0]), float(L[1]) < 1.0, float(L[2])    # the sphere's equator is shorter
    (1.0, True, 1.0)
    """
    tau = check_range("tau", tau, 0.0, 1.0)
    out = np.ones(tau.size)
    inner, L, *_ = _stretch(curve, tau.ravel(), shear, slope=False)
    out[inner] = L
    return out.reshape(tau.shape)


# --------------------------------------------------------------------------- 3. load
def _modulus(shear: MembraneShear) -> float:
    """G_s/(eta U) = 1/Ca_S (0 for Ca_S = inf)."""
    ca_s = float(shear.ca_s)
    if not ca_s > 0.0:                                  # NaN fails too
        raise InvalidParameterError("shear.ca_s", ca_s, "0 < Ca_S <= inf")
    return 1.0 / ca_s


def _divergence(psi, k1, k2, hoop, tau_s, tau_phi, dtau_s_ds):
    """(f_x, f_r) of the membrane equilibrium of :func:`principal_tension_force` from the
    geometry (psi, kappa_1, kappa_2), the hoop term (tau_s - tau_phi) sin(psi)/r and the
    tensions."""
    sin, cos = np.sin(psi), np.cos(psi)
    f_n = -(tau_s * k1 + tau_phi * k2)
    f_t = dtau_s_ds + hoop
    return -f_n * sin + f_t * cos, f_n * cos + f_t * sin       # n = (-sin, cos), t = (cos, sin)


def principal_tension_force(curve: SpectralCurve, tau, tau_s, tau_phi, dtau_s_ds):
    r"""Force on the fluid of an axisymmetric membrane with principal tensions
    :math:`\tau_s` (meridional) and :math:`\tau_\varphi` (azimuthal) at ``tau``.

    The surface divergence of the tension tensor
    :math:`T = \tau_s\,tt + \tau_\varphi\,e_\varphi e_\varphi`, the force per unit area the
    membrane exerts on the fluid (axisymmetric equilibrium of a membrane with unequal principal
    tensions: Evans & Skalak 1980; Pozrikidis 2003), in the conventions of :mod:`bem.membrane`:

    .. math:: f = \nabla_s\cdot T = -(\tau_s\kappa_1 + \tau_\varphi\kappa_2)\,n
              + \Big[\frac{\mathrm{d}\tau_s}{\mathrm{d}s}
              + (\tau_s - \tau_\varphi)\frac{\sin\psi}{r}\Big]\,t,

    from :math:`\frac{1}{r}\frac{\mathrm{d}(r\tau_s t)}{\mathrm{d}s}
    - \frac{\tau_\varphi}{r}e_r`, :math:`\mathrm{d}t/\mathrm{d}s = -\kappa_1 n`,
    :math:`e_r = \sin\psi\,t + \cos\psi\,n` and :math:`\mathrm{d}r/\mathrm{d}s = \sin\psi`.
    For :math:`\tau_s = \tau_\varphi = \gamma` it is :func:`bem.membrane.tension_force`'s
    :math:`-2\gamma H n + \gamma' t`; :func:`lubrication.membrane.membrane_load` is the same
    balance in the lubrication model's signs. At the poles (r = 0) the hoop term is taken as 0:
    the deviatoric part of a smooth axisymmetric tension field is :math:`O(r^2)` at the axis.

    Parameters
    ----------
    curve : SpectralCurve
        Generating curve [R].
    tau : array_like
        Curve parameters in [0, 1].
    tau_s, tau_phi, dtau_s_ds : array_like
        Principal tensions [ηU] and the arc-length derivative of tau_s [ηU/R] at ``tau``.

    Returns
    -------
    f_x, f_r : ndarray
        Axial and radial force per unit area on the fluid [ηU/R].

    Examples
    --------
    >>> sphere = SpectralCurve.sphere(2.0)                # -2 gamma H n, H = 1/2
    >>> f_x, f_r = principal_tension_force(sphere, np.array([0.5]), 3.0, 3.0, 0.0)
    >>> round(float(f_x[0]), 12), round(float(f_r[0]), 12)
    (0.0, -3.0)
    """
    tau = check_range("tau", tau, 0.0, 1.0)
    shape, tau = tau.shape, tau.ravel()
    tau_s, tau_phi, dtau = (np.broadcast_to(as_finite(n, v), shape).ravel() for n, v in (
        ("tau_s", tau_s), ("tau_phi", tau_phi), ("dtau_s_ds", dtau_s_ds)))
    psi = curve.tangent_angle(tau)
    k1, k2 = curve.curvatures(tau)
    _, r = curve.position(tau)
    inner = r > 0.0
    hoop = np.zeros(tau.size)
    hoop[inner] = (tau_s - tau_phi)[inner] * np.sin(psi[inner]) / r[inner]
    f_x, f_r = _divergence(psi, k1, k2, hoop, tau_s, tau_phi, dtau)
    return f_x.reshape(shape), f_r.reshape(shape)


def shear_force(curve: SpectralCurve, tau, shear: MembraneShear):
    r"""Force on the fluid of the membrane's deviatoric (shear) tensions at ``tau``.

    The principal tensions :math:`\tau_s = G_s f`, :math:`\tau_\varphi = -G_s f` with
    :math:`f = (\lambda_\varphi^{-2} - \lambda_\varphi^2)/2` (Evans 1973; Evans & Skalak 1980:
    :func:`lubrication.membrane.tension_difference`) and :math:`\lambda_\varphi^2` of
    :func:`stretch_squared`, in the equilibrium of :func:`principal_tension_force`:

    .. math:: f = G_s\Big\{-f(\kappa_1 - \kappa_2)\,n
              + \Big[\frac{\mathrm{d}f}{\mathrm{d}s} + \frac{2f\sin\psi}{r}\Big]\,t\Big\},

    :math:`\mathrm{d}f/\mathrm{d}s = -\frac12(\lambda_\varphi^{-4} + 1)\,
    \mathrm{d}\lambda_\varphi^2/\mathrm{d}s` with :math:`\mathrm{d}\lambda_\varphi^2/
    \mathrm{d}s = (2r/r_\mathrm{ref}^2)[\sin\psi - \pi\lambda_\varphi^2\,
    \mathrm{d}r_\mathrm{ref}^2/\mathrm{d}a]` (chain rule through r(τ) and
    :math:`r_\mathrm{ref}^2(a)`, :math:`\mathrm{d}a/\mathrm{d}s = 2\pi r`). The isotropic
    part of the tensions is the BEM's tension γ (the Lagrange multiplier), not included here.
    Its work is the variation of :func:`shear_energy` for every area-preserving displacement
    (:math:`\int f\cdot\delta X\,\mathrm{d}A = -\delta E_s`).

    Parameters
    ----------
    curve : SpectralCurve
        Generating curve [R], of the cell's area ``shear.area``.
    tau : array_like
        Curve parameters in [0, 1]; the force is exactly zero at the poles τ = 0 and 1
        (isotropic strain there: :math:`f \to 0` and :math:`f/r \to 0`).
    shear : MembraneShear
        :math:`\mathrm{Ca}_S = \eta U/G_s` (``inf``: zero load), reference shape and the cell's
        area [R²].

    Returns
    -------
    f_x, f_r : ndarray
        Axial and radial force per unit area on the fluid [ηU/R].

    Examples
    --------
    >>> from lubrication.membrane import reference_shape
    >>> cell = SpectralCurve.sphere(1.0)
    >>> shear = MembraneShear(0.2, reference_shape("spheroid", 0.9), cell.area())
    >>> f_x, f_r = shear_force(cell, np.array([0.0, 0.25, 1.0]), shear)
    >>> float(f_x[0]), float(f_r[0]), float(f_x[2]), float(f_r[2])
    (0.0, 0.0, 0.0, 0.0)
    >>> [round(float(v), 4) for v in (f_x[1], f_r[1])]     # tangential: kappa_1 = kappa_2
    [1.8872, 1.8872]
    """
    tau = check_range("tau", tau, 0.0, 1.0)
    shape, tau = tau.shape, tau.ravel()
    gs = _modulus(shear)
    f_x, f_r = np.zeros(tau.size), np.zeros(tau.size)
    inner, L, r, dL, psi = _stretch(curve, tau, shear, slope=True)
    if not np.any(inner):
        return f_x.reshape(shape), f_r.reshape(shape)
    f = gs * tension_difference(np.sqrt(L))
    df = gs * -0.5 * (1.0 / (L * L) + 1.0) * dL      # d/d(lam^2) of (1/lam^2 - lam^2)/2
    k1, k2 = curve.curvatures(tau[inner])
    f_x[inner], f_r[inner] = _divergence(psi, k1, k2, 2.0 * f * np.sin(psi) / r, f, -f, df)
    return f_x.reshape(shape), f_r.reshape(shape)


# --------------------------------------------------------------------------- 4. energy
def shear_energy(curve: SpectralCurve, shear: MembraneShear, n_quad: int | None = None) -> float:
    r"""Shear strain energy of the membrane [ηUR²] (Evans 1973; Evans & Skalak 1980):

    .. math:: E_s = \frac{G_s}{2}\int(\lambda_s^2 + \lambda_\varphi^2 - 2)\,\mathrm{d}A
              = \frac{G_s}{2}\int(\lambda_\varphi^2 + \lambda_\varphi^{-2} - 2)\,\mathrm{d}A,

    the area-incompressible neo-Hookean law
    (:func:`lubrication.membrane.shear_energy_density`; the reference and current area
    elements are equal), with :math:`G_s/(\eta U) = 1/\mathrm{Ca}_S`. By a Gauss rule of
    ``n_quad`` nodes on each half of the curve (default ``4(N + J) + 96``). Its variation at
    fixed local area is :math:`-\int` :func:`shear_force` :math:`\cdot\,\delta X\,\mathrm{d}A`.

    Examples
    --------
    >>> from lubrication.membrane import reference_shape
    >>> cell = SpectralCurve.sphere(1.0)
    >>> ref = reference_shape("spheroid", 0.9)
    >>> shear_energy(cell, MembraneShear(0.2, ref, cell.area())) > 0.0
    True
    >>> shear_energy(cell, MembraneShear(math.inf, ref, cell.area()))
    0.0
    """
    gs = _modulus(shear)
    m = int(check_range("n_quad", n_quad or 4 * (curve.n_modes + curve.density.size) + 96,
                        8, 1 << 16))
    t, w = gauss_legendre01(m)
    tau = np.concatenate([0.5 * t, 0.5 + 0.5 * t])
    weight = np.concatenate([0.5 * w, 0.5 * w])
    _, L, r, _, _ = _stretch(curve, tau, shear, slope=False)
    dA = 2.0 * math.pi * r * curve.length * curve.g(tau) * weight
    return float(gs * np.sum(shear_energy_density(np.sqrt(L)) * dA))
