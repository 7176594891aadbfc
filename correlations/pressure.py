r"""Extra pressure drop correlations of Chen et al. 2020.

Nondimensionalisation: ``dp_plus_R0`` :math:`= \Delta p^+R_0/(\eta U)` with :math:`U` the mean
velocity, :math:`R_0` the volume radius (sphere radius :math:`a` for a sphere);
:math:`\lambda = R_0/R`, :math:`\ell = L/R`, :math:`\delta = h/R`, ``V_over_U`` the vesicle speed
over the mean velocity (between 1, a tight piston, and 2, a vanishing object on the axis).

Reference: Chen, Lyu, Jaeger & Leonetti 2020, "Vesicles in tube flow", section "Vesicle mobility
and extra pressure drop" (fig. dpa_film, eq. dpa_v, eq. dpa_v_fit, fig. dpa_v).
"""

from __future__ import annotations

import numpy as np

from lubrication.checks import (InvalidParameterError, ValidityRange, check_positive, check_range,
                                scalar_or_array)

__all__ = [
    "DP_PLUS_FILM_RANGE_CHEN2020",
    "DP_PLUS_SPEED_FIT_RANGE_CHEN2020",
    "DP_PLUS_SMALL_SPHERE_COUPLING_RANGE",
    "dp_plus_film_chen2020",
    "dp_plus_speed_fit_chen2020",
    "dp_plus_small_sphere_coupling",
]

# Chen et al. 2020 fig. dpa_film: compiled from "highly confined vesicles (lam -> lam_c)"; the
# same simulations approach the near-critical asymptotes for delta = 1 - lam/lam_c < 0.1.
DP_PLUS_FILM_RANGE_CHEN2020 = ValidityRange.of("Chen et al. 2020 fig. dpa_film", delta=(0.0, 0.1))

# Chen et al. 2020 eq. dpa_v_fit: fitted to nu = 0.6 "in the range of 0.6 < (V/U)^-1 < 0.995",
# stored as bounds on V/U (1.005 ... 1.667) so that V/U = 1/0.995 is inside to the last bit.
DP_PLUS_SPEED_FIT_RANGE_CHEN2020 = ValidityRange.of("Chen et al. 2020 eq. dpa_v_fit (nu = 0.6)",
                                               V_over_U=(1.0 / 0.995, 1.0 / 0.6))

# eq. dpa_v eliminates lam between eq. small1 and small2, which hold to 1 % for lam <= 0.5
# (Chen et al. 2020); lam = 0.5 maps to V/U = 2 - (4/3)(0.5)^2 = 5/3.
DP_PLUS_SMALL_SPHERE_COUPLING_RANGE = ValidityRange.of(
    "Chen et al. 2020 eq. dpa_v (eq. small1/small2 for lam <= 0.5)", V_over_U=(5.0 / 3.0, 2.0))


def _check_speed(V_over_U, valid: ValidityRange, law: str) -> np.ndarray:
    """Checked ``V_over_U`` of the law ``law``: 1 <= V/U <= 2, warned outside ``valid``."""
    V_over_U = check_range("V_over_U", V_over_U, 1.0, 2.0,
                           reason="a vesicle on the axis moves between the mean (1) and the "
                                  "centreline (2) velocity")
    valid.warn_outside(law, stacklevel=4, V_over_U=V_over_U)
    return V_over_U


def dp_plus_film_chen2020(lam, ell, delta):
    r"""Extra pressure drop of a highly confined vesicle from its length and film thickness.

    .. math:: \frac{\Delta p^+R_0}{\eta U} \simeq \frac{3}{2}\,\frac{\lambda\ell}{\delta}

    Chen et al. 2020 fig. dpa_film: BEM results for all reduced volumes collapse on
    :math:`\tfrac{3}{2}\alpha`, :math:`\alpha = \lambda\ell/\delta`, as :math:`\lambda \to \lambda_c`
    (Barakat & Shaqfeh 2018a give the scaling :math:`O(\lambda\ell/\delta)`). Warned for
    delta > 0.1 (:data:`DP_PLUS_FILM_RANGE_CHEN2020`). Compare the leading term of
    :func:`lubrication.asymptotics.dp_plus_near_critical`, :math:`2\lambda(\ell_c - 2)/\delta`.

    Parameters
    ----------
    lam : float or array_like
        Confinement R0/R > 0 [-].
    ell : float or array_like
        Vesicle length L/R > 0 [-] (e.g. :func:`correlations.shape.length_chen2020`).
    delta : float or array_like
        Film thickness h/R, 0 < delta < 1 [-] (e.g. :func:`correlations.film.film_thickness_chen2020`).

    Returns
    -------
    dp_plus_R0 : float or ndarray
        :math:`\Delta p^+R_0/(\eta U)` [-].

    Raises
    ------
    InvalidParameterError
        For invalid inputs, or (naming ``delta``) when the result would overflow.

    Examples
    --------
    >>> round(dp_plus_film_chen2020(1.94, 10.81, 0.0208), 0)
    1512.0
    """
    lam = check_positive("lam", lam)
    ell = check_positive("ell", ell)
    delta = check_range("delta", delta, 0.0, 1.0, lo_open=True, hi_open=True,
                        reason="the film is thinner than the tube radius")
    DP_PLUS_FILM_RANGE_CHEN2020.warn_outside("dp_plus_film_chen2020", delta=delta)
    with np.errstate(over="ignore"):
        lam_ell = 1.5 * lam * ell
        dp = lam_ell / delta
    bad = ~np.isfinite(dp)
    if bad.any():     # an absurd length or confinement, or a film thinner than any physical one
        lam_ell_b, delta_b = np.broadcast_arrays(lam_ell, delta)
        raise InvalidParameterError(
            "delta", delta_b[bad] if delta_b.ndim else delta_b,
            f"delta > 1.5 lam ell/{np.finfo(float).max:.4g} = "
            f"{float(np.ravel(lam_ell_b[bad])[0]) / np.finfo(float).max:.4g}",
            "the extra pressure drop 1.5 lam ell/delta would overflow")
    return scalar_or_array(dp)


def dp_plus_speed_fit_chen2020(V_over_U):
    r"""Extra pressure drop of a red-blood-cell-like vesicle (nu = 0.6) from its speed.

    .. math:: \frac{\Delta p^+R_0}{\eta U} \simeq 3\times10^{-6}\exp\!\left[20\,\frac{U}{V}\right]

    Chen et al. 2020 eq. dpa_v_fit, fitted to their nu = 0.6 BEM results (Ca_B = 50) for
    0.6 < U/V < 0.995, i.e. 1.005 < V/U < 1.667 (:data:`DP_PLUS_SPEED_FIT_RANGE_CHEN2020`, warned
    outside). Not valid for other
    reduced volumes.

    Parameters
    ----------
    V_over_U : float or array_like
        Vesicle speed over mean velocity, 1 <= V_over_U <= 2 [-].

    Returns
    -------
    dp_plus_R0 : float or ndarray
        :math:`\Delta p^+R_0/(\eta U)` [-].

    Examples
    --------
    >>> round(dp_plus_speed_fit_chen2020(1 / 0.6), 4)
    0.4883
    """
    V_over_U = _check_speed(V_over_U, DP_PLUS_SPEED_FIT_RANGE_CHEN2020,
                            "dp_plus_speed_fit_chen2020")
    return scalar_or_array(3e-6 * np.exp(20.0 / V_over_U))


def dp_plus_small_sphere_coupling(V_over_U):
    r"""Extra pressure drop of a small rigid sphere expressed through its speed.

    .. math:: \frac{\Delta p^+a}{\eta U} = \frac{27}{4}\left(2 - \frac{V}{U}\right)^3

    Chen et al. 2020 eq. dpa_v: :math:`\lambda` eliminated between eq. small1
    (:math:`V/U = 2 - \tfrac{4}{3}\lambda^2`) and eq. small2 (:math:`16\lambda^6`); exact for the
    truncated laws. Established where those hold, lam <= 0.5, i.e. V/U >= 5/3
    (:data:`DP_PLUS_SMALL_SPHERE_COUPLING_RANGE`, warned outside). ``V_over_U``, here the
    sphere's speed, and the result as in :func:`dp_plus_speed_fit_chen2020`, with the sphere
    radius :math:`a` for :math:`R_0`.

    Examples
    --------
    The pressure drop at the speed of eq. small1 is that of eq. small2:

    >>> from lubrication.asymptotics import dp_plus_small_sphere, speed_small_sphere
    >>> round(dp_plus_small_sphere_coupling(speed_small_sphere(0.5)), 12), dp_plus_small_sphere(0.5)
    (0.25, 0.25)
    """
    V_over_U = _check_speed(V_over_U, DP_PLUS_SMALL_SPHERE_COUPLING_RANGE,
                            "dp_plus_small_sphere_coupling")
    return scalar_or_array(6.75 * (2.0 - V_over_U) ** 3)
