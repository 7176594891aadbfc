r"""Geometry of confinement: reduced volume, confinement, critical confinement and length.

Conventions (used throughout the project)
-----------------------------------------
* :math:`R_0 = (3\Omega/4\pi)^{1/3}` volume radius, :math:`R_A = (A/4\pi)^{1/2}` area radius.
* :math:`\nu = (R_0/R_A)^3 = 6\sqrt{\pi}\,\Omega A^{-3/2}` reduced volume, :math:`0 < \nu \le 1`.
* :math:`\lambda = R_0/R` confinement, :math:`R = d/2` tube radius.
* :math:`\lambda_c(\nu)` critical confinement: the vesicle is a cylinder of radius :math:`R` with
  hemispherical caps (Canham 1968; Barakat & Shaqfeh 2018a; Chen et al. 2020 eq. critic).
* :math:`\delta = 1 - \lambda/\lambda_c` clearance parameter (Chen et al. 2020 eq. sfilm2).
* :math:`\ell = L/R` reduced length (tube radius!), :math:`\ell_c = 2L_c/d_c` its maximum.

Physical units are explicit in names: ``_fl`` femtolitre (= µm³), ``_um2`` µm², ``_um`` µm.
"""

from __future__ import annotations

import math

import numpy as np

from .checks import (CannotPassError, InvalidParameterError, check_positive, check_range,
                     scalar_or_array)

__all__ = [
    "critical_confinement",
    "critical_reduced_volume",
    "critical_length",
    "clearance",
    "volume_radius",
    "area_radius",
    "reduced_volume",
    "reduced_area_excess",
    "check_passes",
    "resolve_confinement",
    "cell_from_volume_area",
    "confinement_from_diameter",
    "critical_diameter_um",
    "critical_length_um",
]

#: Smallest reduced volume accepted. Below it ell_c ~ nu^(-2) overflows double precision long
#: before any physical relevance (red cells: nu ~ 0.6; strongly deflated vesicles: nu ~ 0.3).
NU_MIN = 1e-6


def check_reduced_volume(nu) -> np.ndarray:
    """Check ``NU_MIN <= nu <= 1`` (a closed surface encloses at most a sphere's volume)."""
    return check_range("nu", nu, NU_MIN, 1.0,
                       reason="the reduced volume of a closed surface is at most 1 (sphere)")


def critical_confinement(nu):
    r"""Critical confinement :math:`\lambda_c(\nu)` of a vesicle in a tube.

    Largest :math:`\lambda = R_0/R` for which a vesicle of reduced volume ``nu`` fits the tube as
    a cylinder with hemispherical caps: the largest real root of
    :math:`2\lambda_c^3 - 3\nu^{-2/3}\lambda_c^2 + 1 = 0` (Canham 1968; Barakat & Shaqfeh 2018a;
    Chen et al. 2020 eq. critic). With :math:`a = \nu^{-2/3}` the trigonometric (Viète) form of
    the root is :math:`\lambda_c = a\,[1/2 + \cos(\tfrac{2}{3}\arcsin\nu)]`, exact for every
    :math:`0 < \nu \le 1` (:math:`\lambda_c(1) = 1`).

    Parameters
    ----------
    nu : float or array_like
        Reduced volume, 0 < nu <= 1 [-].

    Returns
    -------
    lam_c : float or ndarray
        Critical confinement [-], >= 1.

    Examples
    --------
    >>> round(critical_confinement(0.6), 4)
    1.9812
    >>> critical_confinement([1.0, 0.9])
    array([1.        , 1.32385897])
    """
    nu = check_reduced_volume(nu)
    a = nu ** (-2.0 / 3.0)
    # Viete: shifting lambda = t + a/2 gives t^3 - (3a^2/4) t + (1/2 - a^3/4) = 0, whose largest
    # root is t = a cos(theta/3) with cos(theta) = 1 - 2 nu^2, i.e. theta = 2 arcsin(nu).
    lam_c = a * (0.5 + np.cos(2.0 / 3.0 * np.arcsin(nu)))
    return scalar_or_array(lam_c)


def critical_reduced_volume(lam):
    r"""Inverse of :func:`critical_confinement`: :math:`\nu_c(\lambda) = (3\lambda^2/(1 + 2\lambda^3))^{3/2}`.

    Chen et al. 2020 eq. critic2. A vesicle with :math:`\nu < \nu_c(\lambda)` passes a tube of
    confinement ``lam``; for :math:`\lambda \le 1` every vesicle passes, so the domain is
    :math:`\lambda \ge 1`. Evaluated as
    :math:`[(3/2\lambda)/(1 + 1/(2\lambda^3))]^{3/2}`, which does not overflow: for large
    :math:`\lambda` it follows its asymptote :math:`(3/2)^{3/2}\lambda^{-3/2}` (and underflows to
    0 beyond :math:`\lambda \approx 10^{205}`, where :math:`\nu_c < 10^{-307}`).

    Parameters
    ----------
    lam : float or array_like
        Confinement R0/R, lam >= 1 [-].

    Returns
    -------
    nu_c : float or ndarray
        Largest reduced volume that passes intact [-].

    Examples
    --------
    >>> round(critical_reduced_volume(critical_confinement(0.6)), 12)
    0.6
    >>> float(f"{critical_reduced_volume(1e200):.6g}")       # (3/2)^(3/2) lam^(-3/2)
    1.83712e-300
    """
    lam = check_range("lam", lam, 1.0, reason="every vesicle (nu <= 1) passes a tube with lam < 1")
    # 3 lam^2/(1 + 2 lam^3) = (3/(2 lam)) / (1 + 1/(2 lam^3)): the printed form overflows to
    # inf/inf = NaN for lam > ~1e102; this one is exact in floating point for every lam >= 1,
    # 1/(2 lam^3) <= 1/2 and (its lam^3 may overflow to inf, giving the limit 0 exactly).
    with np.errstate(over="ignore"):
        ratio = (1.5 / lam) / (1.0 + 0.5 / lam**3)
    return scalar_or_array(ratio**1.5)


def critical_length(nu):
    r"""Critical reduced length :math:`\ell_c = 2L_c/d_c = 2\nu^{-2/3}\lambda_c^2` (Chen et al. 2020 eq. lc).

    The length, in tube radii, of the spherocylinder that just fits the tube, for the reduced
    volume ``nu`` of :func:`critical_confinement`.

    Returns
    -------
    ell_c : float or ndarray
        Critical length L_c/R_c [-], >= 2 (the sphere's).

    Examples
    --------
    >>> round(critical_length(0.6), 2)
    11.04
    >>> critical_length(1.0)
    2.0
    """
    nu = check_reduced_volume(nu)
    return scalar_or_array(2.0 * nu ** (-2.0 / 3.0) * np.asarray(critical_confinement(nu)) ** 2)


def check_passes(nu, lam):
    """Check ``0 < lam < lam_c(nu)``; raise :class:`CannotPassError` otherwise. Returns lam_c."""
    lam_c = np.asarray(critical_confinement(nu))
    lam = check_positive("lam", lam)
    lam_b, lam_c_b = np.broadcast_arrays(lam, lam_c)
    bad = lam_b >= lam_c_b
    if bad.any():
        i = np.flatnonzero(bad.ravel())[0]
        raise CannotPassError(
            "lam", lam_b.ravel()[i], f"0 < lam < lam_c={lam_c_b.ravel()[i]:.6g}",
            "lam >= lam_c(nu): the vesicle cannot pass this tube intact")
    return scalar_or_array(lam_c)


def check_confinement(nu, lam):
    """Checked ``(nu, lam, lam_c)`` as float arrays for the laws of ``(nu, lam)``: raises
    :class:`CannotPassError` unless ``0 < lam < lam_c(nu)`` (:func:`check_passes`)."""
    lam_c = np.asarray(check_passes(nu, lam))
    return np.asarray(nu, dtype=float), np.asarray(lam, dtype=float), lam_c


def resolve_confinement(nu, lam=None, lam_ratio=None, *, nu_reason: str = ""):
    """Checked scalar ``(nu, lam, lam_c)`` from ``lam`` or ``lam_ratio = lam/lam_c`` (exactly one).

    For the solvers: 0 < nu < 1 (``nu_reason`` says why a sphere is excluded) and
    0 < lam < lam_c(nu) (:class:`CannotPassError` otherwise).
    """
    nu = float(check_range("nu", nu, 0.0, 1.0, lo_open=True, hi_open=True, reason=nu_reason))
    if (lam is None) == (lam_ratio is None):
        raise InvalidParameterError("lam", lam, "give exactly one of lam and lam_ratio")
    lam_c = float(critical_confinement(nu))
    if lam is None:
        lam = float(check_positive("lam_ratio", lam_ratio, reason="lam_ratio = lam/lam_c")) * lam_c
    lam = float(check_positive("lam", lam))
    check_passes(nu, lam)
    return nu, lam, lam_c


def clearance(nu, lam):
    r"""Clearance parameter :math:`\delta = 1 - \lambda/\lambda_c(\nu)` (Chen et al. 2020 eq. sfilm2).

    To leading order as :math:`\lambda \to \lambda_c` it is the film thickness h/R.

    Parameters
    ----------
    nu : float or array_like
        Reduced volume, 0 < nu <= 1 [-].
    lam : float or array_like
        Confinement R0/R, 0 < lam < lam_c(nu) [-]; :class:`~lubrication.checks.CannotPassError`
        otherwise (:func:`check_passes`).

    Returns
    -------
    delta : float or ndarray
        1 - lam/lam_c, in (0, 1) [-].

    Examples
    --------
    >>> round(clearance(0.6, 1.94), 4)
    0.0208
    """
    lam_c = np.asarray(check_passes(nu, lam))
    return scalar_or_array(1.0 - np.asarray(lam, dtype=float) / lam_c)


def volume_radius(volume):
    r"""Volume radius :math:`R_0 = (3\Omega/4\pi)^{1/3}` (same length unit as volume^(1/3)).

    Examples
    --------
    >>> round(volume_radius(90.0), 4)   # 90 fL = 90 um^3 -> um
    2.78
    """
    volume = check_positive("volume", volume)
    # cbrt(volume) first: 3 volume/(4 pi) would overflow for volume > 4e308/3.
    return scalar_or_array(np.cbrt(volume) * (3.0 / (4.0 * math.pi)) ** (1.0 / 3.0))


def area_radius(area):
    r"""Area radius :math:`R_A = (A/4\pi)^{1/2}` (same length unit as area^(1/2)).

    Examples
    --------
    >>> round(area_radius(4 * 3.141592653589793), 12)
    1.0
    """
    area = check_positive("area", area)
    return scalar_or_array(np.sqrt(area / (4.0 * math.pi)))


def reduced_volume(volume, area):
    r"""Reduced volume :math:`\nu = (R_0/R_A)^3 = 6\sqrt{\pi}\,\Omega A^{-3/2}` (Chen et al. 2020 eq. nu1).

    Parameters
    ----------
    volume, area : float or array_like
        Enclosed volume and membrane area in consistent units (e.g. µm³ and µm²).

    Returns
    -------
    nu : float or ndarray
        Reduced volume, 0 < nu <= 1 [-].

    Raises
    ------
    InvalidParameterError
        If the area is smaller than that of the sphere of the same volume (nu > 1).

    Examples
    --------
    >>> round(reduced_volume(90.0, 135.0), 4)
    0.6102
    """
    return _reduced_volume(volume, area, "volume", "area")


def _reduced_volume(volume, area, volume_name, area_name, nu_min=0.0):
    """nu = 6 sqrt(pi) (Omega^(1/3)/A^(1/2))^3, checked to lie in [nu_min, 1].

    Written with the cube root of the volume and the square root of the area so that no
    intermediate overflows or underflows for any pair of positive finite doubles whose nu is
    representable; an area outside [sphere area, area at nu_min] raises naming ``area_name``.
    """
    volume = check_positive(volume_name, volume)
    area = check_positive(area_name, area)
    with np.errstate(over="ignore", under="ignore"):
        nu = 6.0 * math.sqrt(math.pi) * (np.cbrt(volume) / np.sqrt(area)) ** 3
    # Round-off tolerance: a sphere computed from its own volume may land at 1 + 1e-15.
    too_small, too_large = nu > 1.0 + 1e-12, nu < nu_min
    if np.any(too_small | too_large):
        shape = np.shape(nu)
        bad = np.flatnonzero(np.ravel(too_small | too_large))[0]
        v = float(np.ravel(np.broadcast_to(volume, shape))[bad])
        a = float(np.ravel(np.broadcast_to(area, shape))[bad])
        # area of the sphere of volume v, (36 pi v^2)^(1/3), and of nu = nu_min; no overflow
        sphere = (36.0 * math.pi) ** (1.0 / 3.0) * np.cbrt(v) ** 2
        if nu_min > 0:
            largest = sphere * (1.0 / nu_min) ** (2.0 / 3.0)
            valid = (f"{sphere:.6g} <= {area_name} <= {largest:.6g} for {volume_name}={v:.6g} "
                     f"(from the sphere of that volume to reduced volume nu = {nu_min:g})")
        else:
            valid = f"{area_name} >= {sphere:.6g} (the sphere of the same volume)"
        raise InvalidParameterError(
            area_name, a, valid,
            "a closed membrane cannot enclose more than a sphere of equal area"
            if too_small.ravel()[bad] else f"the reduced volume would be below {nu_min:g}")
    return scalar_or_array(np.minimum(nu, 1.0))


def reduced_area_excess(nu):
    r"""Reduced excess area :math:`\Delta = 4\pi(\nu^{-2/3} - 1)` (Chen et al. 2020 eq. nu2).

    Examples
    --------
    >>> round(reduced_area_excess(0.6), 4)
    5.0984
    """
    nu = check_reduced_volume(nu)
    return scalar_or_array(4.0 * math.pi * (nu ** (-2.0 / 3.0) - 1.0))


def cell_from_volume_area(volume_fl, area_um2):
    """Reduced volume and volume radius of a cell from its volume [fL] and area [µm²].

    Returns
    -------
    nu : float or ndarray
        Reduced volume [-].
    R0_um : float or ndarray
        Volume radius [µm] (1 fL = 1 µm³).

    Raises
    ------
    InvalidParameterError
        Naming ``area_um2`` when the area is below the sphere of that volume (nu > 1) or above
        the area of reduced volume ``NU_MIN`` (the range is in the message).

    Examples
    --------
    >>> nu, R0 = cell_from_volume_area(90.0, 135.0)   # human red blood cell
    >>> round(nu, 3), round(R0, 3)
    (0.61, 2.78)
    """
    return (_reduced_volume(volume_fl, area_um2, "volume_fl", "area_um2", nu_min=NU_MIN),
            volume_radius(check_positive("volume_fl", volume_fl)))


def confinement_from_diameter(R0_um, diameter_um):
    r"""Confinement :math:`\lambda = R_0/R = 2R_0/d` from the volume radius and tube diameter [µm].

    Examples
    --------
    >>> round(confinement_from_diameter(2.78, 4.0), 3)
    1.39
    """
    R0_um = check_positive("R0_um", R0_um)
    diameter_um = check_positive("diameter_um", diameter_um)
    with np.errstate(over="ignore", under="ignore"):
        lam = 2.0 * R0_um / diameter_um
    bad = ~np.isfinite(lam) | (lam == 0.0)
    if np.any(bad):
        i = np.flatnonzero(np.ravel(bad))[0]
        d = float(np.ravel(np.broadcast_to(diameter_um, np.shape(lam)))[i])
        r = float(np.ravel(np.broadcast_to(R0_um, np.shape(lam)))[i])
        valid = (f"diameter_um > {2.0 * (r / np.finfo(float).max):.3g} for R0_um={r:.6g}"
                 if d < r else f"0 < 2 R0_um/diameter_um representable, R0_um={r:.6g}")
        raise InvalidParameterError("diameter_um", d, valid,
                                    "the confinement 2 R0/d would overflow or underflow")
    return scalar_or_array(lam)


def critical_diameter_um(nu, R0_um):
    r"""Critical tube diameter :math:`d_c = 2R_0/\lambda_c(\nu)` [µm] (Chen et al. 2020 §IV.A).

    The smallest tube a vesicle passes intact.

    Examples
    --------
    >>> round(critical_diameter_um(0.6, 2.78), 2)
    2.81
    """
    R0_um = check_positive("R0_um", R0_um)
    with np.errstate(over="ignore"):
        d_c = 2.0 * R0_um / np.asarray(critical_confinement(nu))
    return scalar_or_array(_representable("R0_um", R0_um, d_c, "d_c = 2 R0/lam_c"))


def _representable(name, x, result, what):
    """``result`` if every element is finite, else InvalidParameterError naming ``name``."""
    bad = ~np.isfinite(result)
    if np.any(bad):
        x_b = np.broadcast_to(x, np.shape(result))
        raise InvalidParameterError(name, x_b[bad] if x_b.ndim else x_b,
                                    f"{name} small enough that {what} is a finite number",
                                    "the result would overflow")
    return result


def critical_length_um(nu, R0_um):
    r"""Critical (maximum) cell length :math:`L_c = \ell_c d_c/2` [µm] (Chen et al. 2020 eq. lc).

    Examples
    --------
    >>> round(critical_length_um(0.6, 2.78), 1)
    15.5
    """
    with np.errstate(over="ignore"):
        L_c = np.asarray(critical_length(nu)) * (np.asarray(critical_diameter_um(nu, R0_um)) / 2.0)
    return scalar_or_array(_representable("R0_um", R0_um, L_c, "L_c = ell_c d_c/2"))
