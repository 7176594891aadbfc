r"""In-plane shear elasticity of a red-cell membrane for the lubrication model.

A vesicle's membrane is a two-dimensional fluid: its only in-plane stress is an isotropic
tension :math:`\sigma`, the Lagrange multiplier of local area conservation. A red cell's membrane
carries a spectrin network that also resists in-plane **shear** relative to a stress-free
reference shape (Skalak, Tozeren, Zarda & Chien 1973; Evans 1973; Evans & Skalak 1980). Secomb,
Skalak, Özkaya & Gross (1986) put this membrane into the lubrication model of a cell in a tube.
This module holds what the lubrication equations need for it, in the order of the model:

1. **The law.** Local area is conserved, :math:`\lambda_s\lambda_\varphi = 1` (the bilayer's
   area modulus is 10⁴-10⁵ times the shear modulus), so the strain has one invariant and the
   in-plane stress is an isotropic multiplier plus a deviatoric part fixed by the shear modulus
   :math:`G_s`. We use Evans's law (Evans 1973, Biophys. J. 13, 941; Evans & Skalak 1980 eq. for
   the maximum shear resultant), the area-incompressible neo-Hookean membrane:

   .. math:: w = \frac{G_s}{2}(\lambda_s^2 + \lambda_\varphi^2 - 2), \qquad
             \tau_s - \tau_\varphi = G_s(\lambda_s^2 - \lambda_\varphi^2)

   per unit reference area. Why this one: it is the area-incompressible law of the red-cell
   mechanics that Secomb et al. (1986) built on (Evans 1973; Evans & Skalak 1980), it has one
   parameter (the small-strain shear modulus :math:`G_s`, 4-10 µN/m by micropipette, Hochmuth &
   Waugh 1987), and every area-incompressible law whose energy is linear in
   :math:`I_1 = \lambda_s^2 + \lambda_\varphi^2 - 2` reduces to it (neo-Hookean, Mooney-Rivlin):
   their isotropic parts fold into the multiplier. The Skalak et al. (1973) law does **not**
   reduce to it: with :math:`I_2 = 0` its energy :math:`\frac{G_s}{4}(I_1^2 + 2I_1)` keeps a
   term in :math:`I_1^2` that the multiplier cannot absorb, and its tension difference
   :math:`G_s(1 + I_1)(\lambda_s^2 - \lambda_\varphi^2)` hardens at large strain (the reason fits
   of the SK law give lower moduli, ≈ 2.5 µN/m: Dimitrakopoulos 2012, Phys. Rev. E 85, 041917).
   Both agree to first order in the strain.

   We write the principal tensions as :math:`\tau_s = \sigma + G_s f`,
   :math:`\tau_\varphi = \sigma - G_s f` with :math:`\sigma = (\tau_s + \tau_\varphi)/2` the
   isotropic part (the multiplier) and :func:`tension_difference`
   :math:`f = (\lambda_s^2 - \lambda_\varphi^2)/2`.

2. **The reference shape.** The resting biconcave disc of Evans & Fung (1972), its axis along the
   tube axis as in Secomb et al. (1986) (the disc is symmetric about its equator, so either
   dimple may lead), or an oblate spheroid with the same axis. Either is scaled to the cell's
   area; to give it the cell's volume as well, each is one member of a one-parameter family
   (:func:`reference_shape`): the Evans-Fung disc stretched affinely along its axis (thickness
   factor ``aspect``; ``aspect`` = 1 is Evans & Fung's own cell, reduced volume 0.644; the
   family reaches at most :data:`BICONCAVE_NU_MAX`), the spheroid of axis ratio ``aspect``.

3. **The material map.** A steady axisymmetric membrane is at rest in the cell's frame (no
   tank-treading: ``u·n = 0`` and surface incompressibility give :math:`\mathrm{d}(r u_s)/
   \mathrm{d}s = 0`, and :math:`u_s = 0` at the poles), so each material point keeps its area
   coordinate :math:`a = \int_0^s 2\pi r\,\mathrm{d}s` measured from the rear pole. With
   :math:`\lambda_s\lambda_\varphi = 1`:

   .. math:: \lambda_\varphi = r(a)/r_\mathrm{ref}(a), \qquad \lambda_s = 1/\lambda_\varphi.

   **At the poles** :math:`\lambda_\varphi \to 1`: near a smooth pole of curvature :math:`k` the
   cap area is :math:`a = \pi r^2(1 + k^2 r^2/4 + O(r^4))` whatever the sign of k (a dimple as
   well as a dome), so :math:`\lambda_\varphi^2 = 1 - (k^2 - k_\mathrm{ref}^2)a/(4\pi) + O(a^2)`
   and :math:`f = (k^2 - k_\mathrm{ref}^2)a/(4\pi) + O(a^2) \to 0`: the membrane is isotropic at
   the poles and :math:`f/r` stays finite.

4. **Equilibrium with unequal principal tensions** (Evans & Skalak 1980 ch. 4; Pozrikidis 2003,
   *Modeling and Simulation of Capsules and Biological Cells*, axisymmetric membranes), in the
   sign conventions of :mod:`lubrication.equations` (tilt angle :math:`\psi`,
   :math:`\mathrm{d}r/\mathrm{d}s = -\sin\psi`, curvatures :math:`c_s = -\mathrm{d}\psi/
   \mathrm{d}s`, :math:`c_\varphi = -\cos\psi/r`, negative where convex, outward normal
   :math:`(\sin\psi, \cos\psi)` in (x, r)): the force per unit area that the membrane's
   tensions exert (:func:`membrane_load`) is

   .. math:: F_n = \tau_s c_s + \tau_\varphi c_\varphi, \qquad
             F_t = \frac{1}{r}\left[\frac{\mathrm{d}(r\tau_s)}{\mathrm{d}s}
             - \tau_\varphi\frac{\mathrm{d}r}{\mathrm{d}s}\right],

   and its work is the variation of the strain energy: :math:`\delta W = -\int \mathbf F\cdot
   \delta\mathbf X\,\mathrm{d}A` for any shape change that keeps the local area (then the
   isotropic part does no work). The sign conventions were fixed by that test
   (tests/lubrication/test_membrane_shear.py), not by hand. The lubrication equations balance
   it against the gap flow: :math:`F_n = p` (gap minus inside pressure) and :math:`F_t = -e_m`.

The dimensionless shear number and its conversion to the solver's units are in
:func:`lubrication.equations.shear_modulus`.

References
----------
* Evans & Fung 1972, Microvasc. Res. 4, 335-347, doi:10.1016/0026-2862(72)90069-6.
* Evans 1973, Biophys. J. 13, 941-954, doi:10.1016/S0006-3495(73)86036-9.
* Skalak, Tozeren, Zarda & Chien 1973, Biophys. J. 13, 245-264,
  doi:10.1016/S0006-3495(73)85983-1.
* Evans & Skalak 1980, *Mechanics and Thermodynamics of Biomembranes*, CRC Press.
* Secomb, Skalak, Özkaya & Gross 1986, J. Fluid Mech. 163, 405-423,
  doi:10.1017/S0022112086002355.
* Pozrikidis 2003, *Modeling and Simulation of Capsules and Biological Cells*, Chapman & Hall.
* Lim, Wortis & Mukhopadhyay 2002, PNAS 99, 16766 (near-oblate stress-free shapes).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import chebyshev
from scipy.optimize import brentq, minimize_scalar

from .checks import (
    InvalidParameterError,
    as_finite,
    check_choice,
    check_range,
    scalar_or_array,
)

__all__ = [
    "BICONCAVE_NU_MAX",
    "EVANS_FUNG_1972",
    "REFERENCE_NU_MIN",
    "REFERENCE_SHAPES",
    "STRETCH_SQ_GUARD",
    "MembraneShear",
    "ReferenceShape",
    "evans_fung_profile",
    "membrane_load",
    "reference_nu_range",
    "reference_shape",
    "shear_energy_density",
    "spheroid_profile",
    "tension_difference",
]


# --------------------------------------------------------------------------- 1. the law
def shear_energy_density(lam_phi):
    r"""Shear strain energy per unit reference area, in units of :math:`G_s` (Evans 1973).

    .. math:: \frac{w}{G_s} = \frac12(\lambda_s^2 + \lambda_\varphi^2 - 2)
              = \frac12\left(\lambda_\varphi - \frac{1}{\lambda_\varphi}\right)^2,
              \qquad \lambda_s = 1/\lambda_\varphi

    The area-incompressible neo-Hookean (Evans) membrane (module docstring, item 1).

    Parameters
    ----------
    lam_phi : float or array_like
        Azimuthal stretch, > 0 [-].

    Returns
    -------
    w : float or ndarray
        Energy per unit reference area [G_s].

    Examples
    --------
    >>> shear_energy_density(1.0), shear_energy_density(2.0)
    (0.0, 1.125)
    """
    lam = check_range("lam_phi", lam_phi, 0.0, math.inf, lo_open=True)
    return scalar_or_array(0.5 * (lam - 1.0 / lam) ** 2)


def tension_difference(lam_phi):
    r"""Deviatoric tension :math:`f = (\tau_s - \tau_\varphi)/(2G_s)` of the Evans law.

    .. math:: f = \frac{\lambda_s^2 - \lambda_\varphi^2}{2}
              = \frac12\left(\frac{1}{\lambda_\varphi^2} - \lambda_\varphi^2\right),
              \qquad \tau_s = \sigma + G_s f,\quad \tau_\varphi = \sigma - G_s f

    (Evans 1973; Evans & Skalak 1980: maximum shear resultant
    :math:`(\tau_s - \tau_\varphi)/2 = G_s(\lambda_1^2 - \lambda_2^2)/2` at
    :math:`\lambda_1\lambda_2 = 1`). It follows from :func:`shear_energy_density` by the work of
    an area-preserving stretch: :math:`\mathrm{d}w = (\tau_\varphi - \tau_s)\,\mathrm{d}
    \lambda_\varphi/\lambda_\varphi`, so :math:`f = -\frac{\lambda_\varphi}{2}\,
    \mathrm{d}(w/G_s)/\mathrm{d}\lambda_\varphi`. ``lam_phi`` as in
    :func:`shear_energy_density`; ``f`` [-] is positive where the membrane is stretched along
    the meridian (lam_phi < 1).

    Examples
    --------
    >>> tension_difference(1.0), tension_difference(0.5)
    (0.0, 1.875)
    """
    lam = check_range("lam_phi", lam_phi, 0.0, math.inf, lo_open=True)
    return scalar_or_array(_deviatoric(lam * lam))


def _deviatoric(lam_phi_sq):
    """f of :func:`tension_difference` from the squared stretch (no checks)."""
    return 0.5 * (1.0 / lam_phi_sq - lam_phi_sq)


# --------------------------------------------------------------------------- 2. reference shapes
#: Resting biconcave disc of Evans & Fung 1972 (their mean cell): radius ``R`` and thickness
#: coefficients ``C0, C1, C2`` [µm] of the thickness
#: :math:`D(x) = \sqrt{1 - x^2}\,(C_0 + C_1x^2 + C_2x^4)`, :math:`x = r/R`. Area 134.1 µm²,
#: volume 94.1 µm³, reduced volume 0.6444 (computed by :func:`reference_shape`'s quadrature).
EVANS_FUNG_1972 = {"R": 3.91, "C0": 0.81, "C1": 7.83, "C2": -4.39}

REFERENCE_SHAPES = ("biconcave", "spheroid")

#: Largest reduced volume of the stretched Evans-Fung family: reached at the thickness factor
#: aspect ≈ 2.0 (the disc twice as thick), beyond which the stretched shape grows slimmer again
#: (ν falls). Rounded down from the maximum 0.74303 found by the quadrature of
#: :func:`reference_shape` (tests/lubrication/test_membrane_shear.py recomputes it).
BICONCAVE_NU_MAX = 0.743

# Gauss-Legendre rule for the area and volume of a profile over 0 <= theta <= pi. The integrands
# are analytic in theta; the thinnest rim of the families (the spheroid at nu = 0.3, axis ratio
# 0.11) needs ~300 Chebyshev terms to reach round-off, so 400 nodes leave a margin (the
# spheroid's area agrees with its closed form to round-off down to axis ratio 0.1).
_GAUSS = np.polynomial.legendre.leggauss(400)
# A Chebyshev series is taken as resolved when its last 8 coefficients are below this fraction
# of the largest (the round-off plateau of the interpolation lies at 1e-15 relative).
_CHEB_TAIL = 1e-14


def evans_fung_profile(theta, aspect=1.0):
    r"""Meridian of the Evans-Fung disc, axis stretched by ``aspect``, in units of its radius.

    .. math:: r = \sin\theta, \qquad z = \frac{\text{aspect}}{2}\cos\theta\,
              (c_0 + c_1\sin^2\theta + c_2\sin^4\theta), \qquad c_i = C_i/R

    for :math:`0 \le \theta \le \pi` (θ = 0 and π are the dimples on the axis), the thickness
    law of Evans & Fung 1972 (:data:`EVANS_FUNG_1972`) with :math:`x = r/R = \sin\theta`, so
    that :math:`\sqrt{1 - x^2} = |\cos\theta|` and one analytic curve gives both faces.

    Returns
    -------
    r, z, dr_dtheta, dz_dtheta : ndarray
        Radius and axial position [R] and their derivatives.

    Examples
    --------
    >>> r, z, _, _ = evans_fung_profile(np.array([0.0, np.pi / 2]))
    >>> [round(float(v), 4) for v in (r[0], z[0], r[1], z[1])]
    [0.0, 0.1036, 1.0, 0.0]
    """
    c0, c1, c2 = (EVANS_FUNG_1972[k] / EVANS_FUNG_1972["R"] for k in ("C0", "C1", "C2"))
    s, c = np.sin(theta), np.cos(theta)
    poly = c0 + c1 * s * s + c2 * s**4
    dpoly = 2.0 * s * c * (c1 + 2.0 * c2 * s * s)
    return s, 0.5 * aspect * c * poly, c, 0.5 * aspect * (c * dpoly - s * poly)


def spheroid_profile(theta, aspect):
    r"""Meridian of a spheroid of axis ratio ``aspect`` = c/a (oblate below 1), units of a.

    :math:`r = \sin\theta`, :math:`z = \text{aspect}\,\cos\theta`, :math:`0 \le \theta \le \pi`.

    Returns
    -------
    r, z, dr_dtheta, dz_dtheta : ndarray

    Examples
    --------
    >>> [float(v) for v in spheroid_profile(0.0, 0.5)]
    [0.0, 0.5, 1.0, -0.0]
    """
    s, c = np.sin(theta), np.cos(theta)
    return s, aspect * c, c, -aspect * s


_PROFILES = {"biconcave": evans_fung_profile, "spheroid": spheroid_profile}


def _area_density(profile, theta):
    """dA/dtheta = 2 pi r |dX/dtheta| of a profile (theta-independent units)."""
    r, _, r_t, z_t = profile(theta)
    return 2.0 * math.pi * r * np.hypot(r_t, z_t)


def _area_volume(profile):
    """Area and enclosed volume of the surface of revolution of a profile (Gauss-Legendre)."""
    x, w = _GAUSS
    theta, weight = 0.5 * math.pi * (x + 1.0), 0.5 * math.pi * w
    r, _, _, z_t = profile(theta)
    # volume by the divergence theorem: V = -int pi r^2 dz along the meridian from the top pole
    return (float(np.sum(weight * _area_density(profile, theta))),
            float(np.sum(weight * -math.pi * r * r * z_t)))


def _reduced_volume(profile) -> float:
    """nu = 6 sqrt(pi) V A^(-3/2) of a profile."""
    area, volume = _area_volume(profile)
    return 6.0 * math.sqrt(math.pi) * volume / area**1.5


def _family(name, aspect):
    return functools.partial(_PROFILES[name], aspect=aspect)


@functools.cache
def _biconcave_peak() -> tuple[float, float]:
    """(aspect, nu) where the stretched Evans-Fung family has its largest reduced volume."""
    best = minimize_scalar(lambda k: -_reduced_volume(_family("biconcave", k)), bounds=(1.0, 4.0),
                           method="bounded", options={"xatol": 1e-10})
    return float(best.x), -float(best.fun)


#: Lowest reduced volume of a reference shape. Thinner shapes have sharper rims, and the series
#: of r_ref^2(a) needs more terms, evaluated at every right-hand side of the solver: at nu = 0.45
#: it has 257 (biconcave) and 513 (spheroid) terms, 1.7 and 3.3 ms per 5000 points; at nu = 0.4,
#: 513 and 1025 (measured). Red cells have 0.55 < nu < 0.7.
REFERENCE_NU_MIN = 0.45


def reference_nu_range(name) -> tuple[float, float]:
    """Reduced volumes (lo, hi) for which :func:`reference_shape` builds ``name``: from
    :data:`REFERENCE_NU_MIN` to :data:`BICONCAVE_NU_MAX` (biconcave) or 1 (spheroid,
    exclusive).

    Examples
    --------
    >>> reference_nu_range("biconcave")
    (0.45, 0.743)
    """
    check_choice("reference", name, REFERENCE_SHAPES)
    return (REFERENCE_NU_MIN, BICONCAVE_NU_MAX if name == "biconcave" else 1.0)


@dataclass(frozen=True, eq=False)
class ReferenceShape:
    r"""Stress-free shape of the membrane, scaled to area :math:`4\pi` (area radius 1).

    Attributes
    ----------
    name : str
        "biconcave" (stretched Evans-Fung disc) or "spheroid".
    nu : float
        Its reduced volume [-] (that of the cell it was built for).
    aspect : float
        Family parameter: thickness factor of the Evans-Fung disc, or axis ratio c/a of the
        spheroid [-].
    scale : float
        Length of the profile's unit (the disc's or spheroid's equatorial radius) in area radii.
    radius_sq : numpy.polynomial.Chebyshev
        :math:`r_\mathrm{ref}^2(a)` for :math:`0 \le a \le 4\pi` (area coordinate from a pole),
        in area radii squared: an analytic function of a (near a pole
        :math:`r^2 = a/\pi + O(a^2)`), interpolated at Chebyshev points to round-off.
    """

    name: str
    nu: float
    aspect: float
    scale: float
    radius_sq: chebyshev.Chebyshev

    def radius_squared(self, a, area):
        r"""Squared reference radius at area coordinate ``a`` of a cell of area ``area``.

        :math:`r_\mathrm{ref}^2(a) = \frac{A}{4\pi}\,\rho^2\!\left(\frac{4\pi a}{A}\right)`
        with :math:`\rho^2` = ``radius_sq``; ``a`` is clipped to [0, area] (Newton iterates
        may leave it).
        """
        unit = area / (4.0 * math.pi)
        return unit * self.radius_sq(np.clip(np.asarray(a, dtype=float) / unit, 0.0,
                                             4.0 * math.pi))

    def profile(self, theta):
        """(r, z) of the meridian at parameter ``theta`` (0 to pi), in area radii."""
        r, z, _, _ = _PROFILES[self.name](theta, self.aspect)
        return self.scale * r, self.scale * z


def _aspect_for(name, nu) -> float:
    """Family parameter with reduced volume ``nu`` (bracketing root of nu(aspect) - nu)."""
    if name == "spheroid":
        lo, hi = 1e-3, 1.0
    else:
        lo, hi = 1e-3, _biconcave_peak()[0]
    return brentq(lambda k: _reduced_volume(_family(name, k)) - nu, lo, hi, xtol=1e-14,
                  rtol=1e-14)


def _cumulative_area(profile):
    """Chebyshev series of the area a(theta) swept from theta = 0, on [0, pi], to round-off."""
    for degree in (64, 128, 256, 512, 1024):
        density = chebyshev.Chebyshev.interpolate(lambda t: _area_density(profile, t), degree,
                                                  domain=[0.0, math.pi])
        if np.max(np.abs(density.coef[-8:])) < _CHEB_TAIL * np.max(np.abs(density.coef)):
            area = density.integ(lbnd=0.0)
            return area
    raise ArithmeticError("the area density of the reference shape did not resolve with 1024 "
                          "Chebyshev terms (a too thin rim)")


def _invert(increasing, targets, lo, hi):
    """theta with increasing(theta) = targets, by vectorised bisection to round-off."""
    a, b = np.full_like(targets, lo), np.full_like(targets, hi)
    for _ in range(64):               # (hi - lo) / 2^64 is below the spacing of doubles
        mid = 0.5 * (a + b)
        below = increasing(mid) < targets
        a, b = np.where(below, mid, a), np.where(below, b, mid)
    return 0.5 * (a + b)


@functools.lru_cache(maxsize=64)
def _build(name, nu) -> ReferenceShape:
    aspect = _aspect_for(name, nu)
    profile = _family(name, aspect)
    area_of = _cumulative_area(profile)
    total = float(area_of(math.pi))
    scale = math.sqrt(4.0 * math.pi / total)          # profile units -> area radii

    def radius_sq_at(a):                                # a in area radii squared, 0 < a < 4 pi
        theta = _invert(area_of, a / scale**2, 0.0, math.pi)
        return (scale * profile(theta)[0]) ** 2

    for degree in (64, 128, 256, 512, 1024):
        fit = chebyshev.Chebyshev.interpolate(radius_sq_at, degree, domain=[0.0, 4.0 * math.pi])
        top = np.max(np.abs(fit.coef))
        if np.max(np.abs(fit.coef[-8:])) < _CHEB_TAIL * top:
            # drop the round-off tail: fewer terms to evaluate at every right-hand side
            return ReferenceShape(name, nu, aspect, scale, fit.trim(0.1 * _CHEB_TAIL * top))
    raise ArithmeticError(f"the {name} reference shape at nu={nu:g} did not resolve with 1024 "
                          "Chebyshev terms")


def reference_shape(name, nu) -> ReferenceShape:
    r"""The stress-free shape ``name`` with reduced volume ``nu``, scaled to area :math:`4\pi`.

    * ``"biconcave"``: the Evans-Fung (1972) disc with its thickness multiplied by a factor
      ``aspect`` (an affine stretch along the axis, :func:`evans_fung_profile`), the factor
      chosen so that the reduced volume is ``nu``: a cell of another volume keeps Evans &
      Fung's outline and changes its thickness. ``aspect`` = 1 is their cell (ν = 0.6444);
      the default red cell of this project (90 fL, 135 µm², ν = 0.61) has aspect 0.88. The
      family's reduced volume peaks at :data:`BICONCAVE_NU_MAX` (aspect ≈ 2): above it no
      member fits, and the call raises.
    * ``"spheroid"``: the oblate spheroid of axis ratio ``aspect`` < 1 with reduced volume
      ``nu`` (a near-oblate stress-free shape, e.g. Lim, Wortis & Mukhopadhyay 2002).

    Either is symmetric about its equator, so which pole leads in the tube does not matter; its
    axis is the tube's (Secomb et al. 1986). Results are cached per (name, nu).

    Parameters
    ----------
    name : str
        One of :data:`REFERENCE_SHAPES`.
    nu : float
        Reduced volume, within :func:`reference_nu_range` [-].

    Returns
    -------
    ReferenceShape

    Raises
    ------
    InvalidParameterError
        Unknown name or nu outside the family's range (the message names both).

    Examples
    --------
    >>> ref = reference_shape("biconcave", 0.6444)
    >>> round(ref.aspect, 3), round(float(ref.radius_sq(4 * np.pi)), 12)
    (1.0, 0.0)
    """
    check_choice("reference", name, REFERENCE_SHAPES)
    lo, hi = reference_nu_range(name)
    above = float(as_finite("nu", nu)) > hi
    if above and name == "biconcave":
        reason = (f"the stretched Evans-Fung disc reaches at most nu = {BICONCAVE_NU_MAX:g} (its "
                  "thickness doubled); give reference='spheroid' for a rounder cell")
    elif above:
        reason = "a sphere (nu = 1) cannot deform at constant area and volume"
    else:
        reason = (f"reference shapes below nu = {REFERENCE_NU_MIN:g} have rims too thin for the "
                  "series of the material map (not measured there)")
    nu = float(check_range("nu", nu, lo, hi, hi_open=name == "spheroid", reason=reason))
    return _build(name, nu)


# --------------------------------------------------------------------------- 3. material map
#: Bounds of the squared stretch lam_phi^2 evaluated for Newton iterates (the gap-flow guards of
#: :mod:`lubrication.equations` play the same role). A converged solution must lie strictly
#: inside (checked by the solver); physical cells stay within 0.1 < lam_phi^2 < 10.
STRETCH_SQ_GUARD = (1e-4, 1e4)


@dataclass(frozen=True, eq=False)
class MembraneShear:
    r"""Shear elasticity of one cell: the shear number and the reference scaled to the cell.

    Attributes
    ----------
    ca_s : float
        Shear capillary number :math:`\mathrm{Ca}_S = \eta U/G_s` [-].
    reference : ReferenceShape
        Stress-free shape (area :math:`4\pi`).
    area : float
        Cell area in the solver's length unit squared (tube radii: :math:`4\pi\lambda_A^2`).
    """

    ca_s: float
    reference: ReferenceShape
    area: float

    def stretch_squared(self, r, a):
        r""":math:`\lambda_\varphi^2 = r^2/r_\mathrm{ref}^2(a)` at radius r and area coordinate a
        from the rear pole (module docstring, item 3), within :data:`STRETCH_SQ_GUARD`."""
        ref_sq = self.reference.radius_squared(a, self.area)
        lo, hi = STRETCH_SQ_GUARD
        return np.clip(r * r / np.maximum(ref_sq, 1e-300), lo, hi)

    def tension_difference(self, r, a):
        r""":math:`f = (\tau_s - \tau_\varphi)/(2G_s)` at radius r and area coordinate a
        (:func:`tension_difference` of :meth:`stretch_squared`)."""
        return _deviatoric(self.stretch_squared(r, a))


# --------------------------------------------------------------------------- 4. equilibrium
def membrane_load(r, psi, c_s, tau_s, tau_phi, dtau_s_ds):
    r"""Force per unit area that membrane tensions exert, normal and tangential components.

    .. math:: F_n = \tau_s c_s + \tau_\varphi c_\varphi, \qquad
              F_t = \frac{\mathrm{d}\tau_s}{\mathrm{d}s}
              + (\tau_s - \tau_\varphi)\frac{1}{r}\frac{\mathrm{d}r}{\mathrm{d}s},

    i.e. :math:`F_t = r^{-1}[\mathrm{d}(r\tau_s)/\mathrm{d}s - \tau_\varphi\,\mathrm{d}r/
    \mathrm{d}s]`, with :math:`c_\varphi = -\cos\psi/r`, :math:`\mathrm{d}r/\mathrm{d}s =
    -\sin\psi`, :math:`F_n` along the outward normal :math:`(\sin\psi, \cos\psi)` and
    :math:`F_t` along :math:`(\cos\psi, -\sin\psi)` (increasing s, rear to front). Evans &
    Skalak 1980 (axisymmetric equilibrium of a membrane with principal tensions); Pozrikidis
    2003. For :math:`\tau_s = \tau_\varphi = \sigma` it is the vesicle's
    :math:`(\sigma(c_s + c_\varphi),\ \mathrm{d}\sigma/\mathrm{d}s)`. The lubrication equations
    set :math:`F_n = p`, :math:`F_t = -e_m` (module docstring, item 4).

    Parameters
    ----------
    r, psi, c_s : array_like
        Radius [R], tilt angle [rad], meridional curvature [1/R].
    tau_s, tau_phi, dtau_s_ds : array_like
        Principal tensions and the arc-length derivative of tau_s [any tension unit, per R].

    Returns
    -------
    F_n, F_t : ndarray
        [tension unit / R].

    Examples
    --------
    >>> F_n, F_t = membrane_load(1.0, 0.0, 0.0, 2.0, 2.0, 0.0)    # cylinder of radius 1
    >>> float(F_n), float(F_t)
    (-2.0, 0.0)
    """
    r, psi, c_s, tau_s, tau_phi, dtau = (as_finite(n, v) for n, v in (
        ("r", r), ("psi", psi), ("c_s", c_s), ("tau_s", tau_s), ("tau_phi", tau_phi),
        ("dtau_s_ds", dtau_s_ds)))
    if np.any(r <= 0.0):
        raise InvalidParameterError("r", r[r <= 0.0] if r.ndim else r, "r > 0",
                                    "the load is defined off the axis")
    return tau_s * c_s - tau_phi * np.cos(psi) / r, dtau - (tau_s - tau_phi) * np.sin(psi) / r
