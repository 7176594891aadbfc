r"""Small-object and near-critical asymptotic laws for the speed and extra pressure drop.

Nondimensionalisation (stated once): :math:`\lambda = R_0/R` (for a sphere :math:`a/R`), ``nu``
the reduced volume, :math:`\lambda_c(\nu)` the critical confinement,
:math:`\delta = 1 - \lambda/\lambda_c`, :math:`U` the **mean** velocity of the undisturbed
Poiseuille flow (centreline :math:`2U`), :math:`V` the object velocity. The results, described
here once rather than in each law: a float for scalar input, else an ndarray; speeds as
``V_over_U`` :math:`= V/U`, extra pressure drops at fixed flow rate as ``dp_plus_R0``
:math:`=\Delta p^+R_0/(\eta U)` (:math:`\Delta p^+a/(\eta U)` for a sphere or a drop of radius
:math:`a`).

Two limits bracket the behaviour of a vesicle in a tube:

* :math:`\lambda \to 0`: the object is small and spherical. A quasi-spherical vesicle has an
  inextensible membrane and moves like a rigid sphere (Chen et al. 2020 eq. small1/small2); a
  clean drop of equal viscosity is faster and perturbs the flow less (Hetsroni, Haber &
  Wacholder 1970).
* :math:`\lambda \to \lambda_c`: the vesicle is a spherocylinder separated from the wall by a thin
  film; Chen et al. 2020 eq. asmyp1/asmyp2 (their transcription of Barakat & Shaqfeh 2018a).

Each law emits :class:`~lubrication.checks.OutOfRangeWarning` outside the range where its source
established it; the ranges are the module-level :class:`~lubrication.checks.ValidityRange`
constants below.

References
----------
* Chen, Lyu, Jaeger & Leonetti 2020, "Vesicles in tube flow" (the paper this project builds on),
  sections "Vesicle mobility and extra pressure drop" and the appendix.
* Barakat & Shaqfeh 2018a, J. Fluid Mech. 835, 721-761, doi:10.1017/jfm.2017.717.
* Haberman & Sayre 1958, David Taylor Model Basin report 1143 (sphere in a tube).
* Hetsroni, Haber & Wacholder 1970, J. Fluid Mech. 41, 689-705, doi:10.1017/S0022112070000848.
* Brenner 1970, J. Fluid Mech. 43, 641-660, doi:10.1017/S0022112070002641.
"""

from __future__ import annotations

import math

import numpy as np

from .checks import ValidityRange, scalar_or_array
from .geometry import check_confinement, check_passes, critical_confinement

__all__ = [
    "SMALL_SPHERE_RANGE",
    "SMALL_DROP_RANGE",
    "NEAR_CRITICAL_RANGE",
    "speed_small_sphere",
    "dp_plus_small_sphere",
    "speed_small_drop",
    "dp_plus_small_drop",
    "speed_near_critical",
    "dp_plus_near_critical",
    "speed_slope_near_critical",
]

# Chen et al. 2020 (after eq. small2): their BEM vesicles agree with eq. small1/small2 within 1 %
# for lam < 0.5 ("particularly for nearly spherical vesicles"; nu = 0.6 deviates).
SMALL_SPHERE_RANGE = ValidityRange.of("Chen et al. 2020 eq. small1/small2 (< 1 % error)",
                                      lam=(0.0, 0.5))

# No accuracy bound is published with the drop law (Hetsroni et al. 1970); it is the same
# reflection expansion truncated at the same order as the sphere's, so the sphere's range is used
# until the project's BEM drop results measure it.
SMALL_DROP_RANGE = ValidityRange.of("Hetsroni, Haber & Wacholder 1970 (range assumed equal to "
                                    "the rigid sphere's)", lam=(0.0, 0.5))

# Chen et al. 2020 (section "Lubrication film thickness" and fig. vel/dpa): the simulations
# approach the near-critical asymptotes when 1 - lam/lam_c < 0.1.
NEAR_CRITICAL_RANGE = ValidityRange.of("Chen et al. 2020 eq. asmyp (delta = 1 - lam/lam_c)",
                                       delta=(0.0, 0.1))


def _check_small_lam(lam, valid: ValidityRange, law: str) -> np.ndarray:
    """Checked ``lam`` of the small-object law ``law``, warned outside ``valid``.

    0 < lam < 1: a sphere fits the tube only if a < R (lam_c(nu=1) = 1).
    """
    check_passes(1.0, lam)
    lam = np.asarray(lam, dtype=float)
    valid.warn_outside(law, stacklevel=4, lam=lam)
    return lam


def speed_small_sphere(lam):
    r"""Speed of a small freely suspended rigid sphere on the tube axis.

    .. math:: V/U = 2 - \tfrac{4}{3}\lambda^2 + O(\lambda^5)

    Faxén's law for a sphere in the Poiseuille flow :math:`u = 2U(1 - r^2/R^2)`, i.e. the first
    two terms of Haberman & Sayre (1958); Chen et al. 2020 eq. small1 (they write the remainder
    as O(λ³)). A quasi-spherical vesicle follows it because its inextensible membrane moves like a
    rigid surface.

    Parameters
    ----------
    lam : float or array_like
        Size ratio a/R (R0/R for a vesicle), 0 < lam < 1 [-]. Accurate to 1 % for lam <= 0.5
        (:data:`SMALL_SPHERE_RANGE`); an :class:`OutOfRangeWarning` is emitted above.

    Examples
    --------
    >>> speed_small_sphere(0.3)
    1.88
    >>> speed_small_sphere([0.1, 0.5])
    array([1.98666667, 1.66666667])
    """
    lam = _check_small_lam(lam, SMALL_SPHERE_RANGE, "speed_small_sphere")
    return scalar_or_array(2.0 - 4.0 / 3.0 * lam**2)


def dp_plus_small_sphere(lam):
    r"""Extra pressure drop of a small freely suspended rigid sphere on the tube axis.

    .. math:: \Delta p^+ a/(\eta U) = 16\lambda^6 + O(\lambda^{11})

    Chen et al. 2020 eq. small2 (exact Stokes solution plus the reciprocal theorem; Brenner 1970).
    Scaled with the sphere radius :math:`a` (= :math:`R_0` for a vesicle); ``lam`` and its
    range as in :func:`speed_small_sphere`.

    Examples
    --------
    >>> dp_plus_small_sphere(0.5)
    0.25
    """
    lam = _check_small_lam(lam, SMALL_SPHERE_RANGE, "dp_plus_small_sphere")
    return scalar_or_array(16.0 * lam**6)


def speed_small_drop(lam):
    r"""Speed of a small spherical clean drop of equal viscosity on the tube axis (Ca → 0).

    .. math:: V/U = 2 - 0.8\,\lambda^2

    Hetsroni, Haber & Wacholder 1970, viscosity ratio 1, undeformed (spherical) drop. It is the
    Faxén law of a drop, :math:`V = u(0) + \frac{k}{2(3k+2)}a^2\nabla^2 u`, at :math:`k = 1`
    (:math:`k \to \infty` gives the rigid sphere, :func:`speed_small_sphere`). Only the
    viscosity ratio 1 is implemented: the general-ratio forms could not be checked against the
    original papers. ``lam`` as in :func:`speed_small_sphere`, warned above 0.5
    (:data:`SMALL_DROP_RANGE`).

    Examples
    --------
    >>> speed_small_drop(0.5)
    1.8
    """
    lam = _check_small_lam(lam, SMALL_DROP_RANGE, "speed_small_drop")
    return scalar_or_array(2.0 - 0.8 * lam**2)


def dp_plus_small_drop(lam):
    r"""Extra pressure drop of a small spherical clean drop of equal viscosity (Ca → 0).

    .. math:: \Delta p^+ a/(\eta U) = 4.8\,\lambda^6

    Hetsroni, Haber & Wacholder 1970, viscosity ratio 1 (the rigid-sphere coefficient is 16,
    :func:`dp_plus_small_sphere`). ``lam`` as in :func:`speed_small_drop`.

    Examples
    --------
    >>> round(dp_plus_small_drop(0.5), 6)
    0.075
    """
    lam = _check_small_lam(lam, SMALL_DROP_RANGE, "dp_plus_small_drop")
    return scalar_or_array(4.8 * lam**6)


def _near_critical(nu, lam, law: str):
    """Checked inputs of the near-critical law ``law`` -> (lam, delta, X), broadcast.

    X = lam_c^2 nu^(-2/3) = ell_c/2; warned outside NEAR_CRITICAL_RANGE.
    """
    nu, lam, lam_c = check_confinement(nu, lam)
    delta = 1.0 - lam / lam_c
    NEAR_CRITICAL_RANGE.warn_outside(law, stacklevel=4, delta=delta)
    X = lam_c**2 * nu ** (-2.0 / 3.0)
    return lam, delta, X


def speed_slope_near_critical(nu):
    r"""Slope :math:`\mathrm{d}(V/U)/\mathrm{d}\delta` at :math:`\delta \to 0` of eq. asmyp1.

    .. math:: \frac{4}{3}\,\frac{3X - 2}{4X - 3}, \qquad X = \lambda_c^2\nu^{-2/3} = \ell_c/2

    Chen et al. 2020 eq. asmyp1 (their transcription of Barakat & Shaqfeh 2018a). It equals
    4/3 at nu = 1 (the rigid sphere near contact, :math:`V/U \approx 1 + 4\varepsilon/3`) and
    tends to 1 as nu → 0. Open point: a spherocylinder with a uniform film :math:`Q = \delta`
    gives slope 1, and the appendix of Chen et al. (eq. vel2) also states
    :math:`V/U = 1 + \delta + O(\delta^2)`, while this slope exceeds 1 (≈ 1.07 at nu = 0.9,
    ≈ 1.02 at nu = 0.6). The formula is kept as published; the lubrication and BEM solvers
    report their measured slope beside it. ``nu`` as in
    :func:`~lubrication.geometry.critical_confinement`.

    Returns
    -------
    slope : float or ndarray
        :math:`\mathrm{d}(V/U)/\mathrm{d}\delta` [-].

    Examples
    --------
    >>> speed_slope_near_critical([1.0, 0.9, 0.6])
    array([1.33333333, 1.07373767, 1.01747888])
    """
    lam_c = np.asarray(critical_confinement(nu))   # checks nu
    X = lam_c**2 * np.asarray(nu, dtype=float) ** (-2.0 / 3.0)
    return scalar_or_array(4.0 / 3.0 * (3.0 * X - 2.0) / (4.0 * X - 3.0))


def speed_near_critical(nu, lam):
    r"""Vesicle speed as the confinement approaches its critical value.

    .. math:: \frac{V}{U} = 1 + \frac{4}{3}\,\frac{3X - 2}{4X - 3}\,\delta + O(\delta^2),
              \qquad X = \lambda_c^2\nu^{-2/3},\ \delta = 1 - \lambda/\lambda_c

    Chen et al. 2020 eq. asmyp1, their transcription of Barakat & Shaqfeh 2018a. The slope is
    :func:`speed_slope_near_critical`; see its note on the open point (slope > 1, whereas a
    uniform film gives 1). Chen et al. find their BEM speeds slightly *below* this line near
    :math:`\lambda_c`, most visibly at nu = 0.6. The law holds for delta <= 0.1
    (:data:`NEAR_CRITICAL_RANGE`); an :class:`OutOfRangeWarning` is emitted for a wider gap.
    ``nu`` and ``lam`` as in :func:`~lubrication.geometry.clearance`: lam >= lam_c(nu) raises
    :class:`~lubrication.checks.CannotPassError`.

    Examples
    --------
    >>> round(speed_near_critical(0.6, 1.94), 4)
    1.0212
    """
    _, delta, _ = _near_critical(nu, lam, "speed_near_critical")
    return scalar_or_array(1.0 + np.asarray(speed_slope_near_critical(nu)) * delta)


def dp_plus_near_critical(nu, lam):
    r"""Extra pressure drop of a vesicle as the confinement approaches its critical value.

    .. math:: \frac{\Delta p^+R_0}{\eta U} = \frac{4\lambda(X - 1)}{\delta}
              + \frac{4\sqrt{2}\,\pi\,\lambda}{4X - 3}\,\delta^{-1/2} + O(1),
              \qquad X = \lambda_c^2\nu^{-2/3}

    Chen et al. 2020 eq. asmyp2, their transcription of Barakat & Shaqfeh 2018a. Since
    :math:`X = \ell_c/2`, the leading term is :math:`2\lambda\ell_0/\delta` with
    :math:`\ell_0 = \ell_c - 2` the cylindrical length in tube radii: the extra pressure drop of
    a rigid cylinder of that length in the film :math:`\delta`. At nu = 1 only the second term
    is left, :math:`4\sqrt{2}\pi\lambda\delta^{-1/2}`: the rigid sphere near contact. Range
    (:data:`NEAR_CRITICAL_RANGE`) and arguments as for :func:`speed_near_critical`.

    Returns
    -------
    dp_plus_R0 : float or ndarray
        :math:`\Delta p^+R_0/(\eta U)` to the two terms above, error O(1) [-].

    Examples
    --------
    >>> round(dp_plus_near_critical(0.6, 1.94), 1)
    1698.4
    """
    lam, delta, X = _near_critical(nu, lam, "dp_plus_near_critical")
    lead = 4.0 * lam * (X - 1.0) / delta
    second = lam * 4.0 * math.sqrt(2.0) * math.pi / (4.0 * X - 3.0) / np.sqrt(delta)
    return scalar_or_array(lead + second)
