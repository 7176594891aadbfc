r"""Lubrication film between a highly confined vesicle and the tube wall (Chen et al. 2020).

Nondimensionalisation: :math:`\delta = h/R` film thickness at the vesicle's midplane in tube
radii; :math:`\mathrm{Ca_v} = \eta V/\gamma_F` capillary number built on the vesicle velocity
:math:`V` and the membrane tension at the front :math:`\gamma_F` (the largest tension).

Reference: Chen, Lyu, Jaeger & Leonetti 2020, "Vesicles in tube flow", section "Lubrication film
thickness" (eq. sfilm2, eq. sfilm4, fig. film, fig. film_Ca) and appendix (eq. tension2).
"""

from __future__ import annotations


import numpy as np

from lubrication.checks import ValidityRange, check_positive, check_range, scalar_or_array
from lubrication.geometry import clearance

__all__ = [
    "C0_CHEN2020",
    "C0_SECOMB1986",
    "C0_BRUINSMA1996",
    "FILM_RANGE_CHEN2020",
    "CAPILLARY_RANGE_CHEN2020",
    "film_thickness_chen2020",
    "film_from_capillary_chen2020",
    "capillary_from_film_chen2020",
]

#: Prefactor of eq. sfilm4 fitted to the BEM films of Chen et al. 2020 (Ca_v < 1e-2).
C0_CHEN2020 = 2.0
#: Immobile-interface Bretherton constant 0.643 * 6**(2/3) ≈ 2.123 (Secomb et al. 1986).
C0_SECOMB1986 = 0.643 * 6.0 ** (2.0 / 3.0)
#: Prefactor of Bruinsma 1996 (Physica A 234, 249-270).
C0_BRUINSMA1996 = 2.05

# Chen et al. 2020 fig. film: the BEM films approach eq. sfilm2 when 1 - lam/lam_c < 0.1.
FILM_RANGE_CHEN2020 = ValidityRange.of("Chen et al. 2020 eq. sfilm2", delta=(0.0, 0.1))

# Chen et al. 2020 fig. film_Ca: c0 = 2 was fitted for Ca_v < 1e-2. The figure also shows the
# 2/3-power regime giving way to a 1/2-power regime near Ca_v = 6e-3, so values between 6e-3 and
# 1e-2 are already at the edge of the law.
CAPILLARY_RANGE_CHEN2020 = ValidityRange.of("Chen et al. 2020 eq. sfilm4 (fit)",
                                                 ca_v=(0.0, 1e-2))


def film_thickness_chen2020(nu, lam):
    r"""Film thickness near critical confinement, :math:`\delta = h/R \approx 1 - \lambda/\lambda_c`.

    .. math:: \delta = 1 - \lambda/\lambda_c + O\big[(1 - \lambda/\lambda_c)^2\big]

    Chen et al. 2020 eq. sfilm2 (from the geometric expansion of Barakat & Shaqfeh 2018a); the
    BEM films approach it for :math:`1 - \lambda/\lambda_c < 0.1` (:data:`FILM_RANGE_CHEN2020`,
    warned outside). It is :func:`~lubrication.geometry.clearance` with that warning: the same
    ``nu`` and ``lam`` (lam >= lam_c(nu) raises :class:`~lubrication.checks.CannotPassError`)
    and the same value, read as the film thickness h/R.

    Examples
    --------
    >>> round(film_thickness_chen2020(0.6, 1.94), 4)
    0.0208
    """
    delta = np.asarray(clearance(nu, lam))
    FILM_RANGE_CHEN2020.warn_outside("film_thickness_chen2020", delta=delta)
    return scalar_or_array(delta)


def _check_c0(c0) -> np.ndarray:
    return check_positive("c0", c0)


def film_from_capillary_chen2020(ca_v, c0=C0_CHEN2020):
    r"""Film thickness from the front-tension capillary number, :math:`\delta = c_0\,\mathrm{Ca_v}^{2/3}`.

    Chen et al. 2020 eq. sfilm4 (Bretherton scaling with an immobile membrane; appendix eq.
    tension2). ``c0`` = :data:`C0_CHEN2020` (2, their fit for Ca_v < 1e-2),
    :data:`C0_SECOMB1986` (2.123) or :data:`C0_BRUINSMA1996` (2.05). Warned above
    Ca_v = 1e-2 (:data:`CAPILLARY_RANGE_CHEN2020`); the BEM data leave the 2/3 law for a
    1/2-power law near Ca_v = 6e-3.

    Parameters
    ----------
    ca_v : float or array_like
        :math:`\eta V/\gamma_F`, 0 < ca_v < c0**(-3/2) (film thinner than the tube radius) [-].
    c0 : float or array_like, optional
        Prefactor > 0 [-].

    Returns
    -------
    delta : float or ndarray
        Film thickness h/R, 0 < delta < 1 [-].

    Examples
    --------
    >>> round(film_from_capillary_chen2020(1e-3), 6)
    0.02
    >>> round(film_from_capillary_chen2020(1e-3, c0=C0_SECOMB1986), 4)
    0.0212
    """
    c0 = _check_c0(c0)
    ca_v = check_positive("ca_v", ca_v)
    ca_max = c0 ** -1.5
    ca_b, ca_max_b = np.broadcast_arrays(ca_v, ca_max)
    bad = ca_b >= ca_max_b
    if bad.any():
        check_range("ca_v", ca_b[bad], 0.0, float(ca_max_b[bad].flat[0]), lo_open=True,
                    hi_open=True, reason="the film would be thicker than the tube radius")
    CAPILLARY_RANGE_CHEN2020.warn_outside("film_from_capillary_chen2020", ca_v=ca_v)
    return scalar_or_array(c0 * np.cbrt(ca_v) ** 2)


def capillary_from_film_chen2020(delta, c0=C0_CHEN2020):
    r"""Front-tension capillary number from the film thickness, :math:`\mathrm{Ca_v} = (\delta/c_0)^{3/2}`.

    Inverse of :func:`film_from_capillary_chen2020` (Chen et al. 2020 eq. sfilm4); the front
    tension follows as :math:`\gamma_F = \eta V/\mathrm{Ca_v} = \eta V(\delta/c_0)^{-3/2}`
    (eq. tension2). Warned when the result exceeds Ca_v = 1e-2, i.e. delta > 0.0928 for c0 = 2.

    Parameters
    ----------
    delta : float or array_like
        Film thickness h/R, 0 < delta < 1 [-].
    c0 : float or array_like, optional
        Prefactor > 0 [-].

    Returns
    -------
    ca_v : float or ndarray
        :math:`\eta V/\gamma_F` [-].

    Examples
    --------
    >>> round(capillary_from_film_chen2020(0.02), 9)
    0.001
    >>> gamma_F = 1.0 / capillary_from_film_chen2020(0.0208)   # in units of eta*V
    >>> round(gamma_F)
    943
    """
    c0 = _check_c0(c0)
    delta = check_range("delta", delta, 0.0, 1.0, lo_open=True, hi_open=True,
                        reason="the film is thinner than the tube radius")
    ca_v = (delta / c0) ** 1.5
    CAPILLARY_RANGE_CHEN2020.warn_outside("capillary_from_film_chen2020", ca_v=ca_v)
    return scalar_or_array(ca_v)
