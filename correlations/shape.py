r"""Shape correlations of Chen et al. 2020: parachute-bullet transition line and vesicle length.

Nondimensionalisation: ``nu`` reduced volume, :math:`\lambda = R_0/R` confinement,
:math:`\lambda_c(\nu)` critical confinement, :math:`\ell = L/R` vesicle length in **tube** radii,
:math:`\mathrm{Ca_B} = \eta U R_0^2/\kappa` bending capillary number.

Reference: Chen, Lyu, Jaeger & Leonetti 2020, "Vesicles in tube flow", section "Phase diagram of
shapes and shape transition" (eq. transition, fig. B-P-phase-diagram, fig. transition) and
section "Lubrication film thickness" (eq. sL, fig. length).
"""

from __future__ import annotations

import numpy as np

from lubrication.checks import ValidityRange, check_positive, check_range, scalar_or_array
from lubrication.geometry import check_confinement, check_reduced_volume

__all__ = [
    "TRANSITION_RANGE_CHEN2020",
    "SHAPE_CLASS_RANGE_CHEN2020",
    "LENGTH_RANGE_CHEN2020",
    "transition_reduced_volume_chen2020",
    "transition_confinement_chen2020",
    "shape_class_chen2020",
    "length_chen2020",
]

# Coefficients of eq. transition, nu_T = A - B lam (linear fit to the BEM transition points).
_A, _B = 1.126, 0.29

# Chen et al. 2020: the line is fitted "for nu <= 0.93" to transition points found "when
# lam >= 0.6"; the smallest simulated reduced volume is 0.6, where the line ends at
# lam = (1.126 - 0.6)/0.29 = 1.8138; Ca_B from the caption of the phase diagram (10 < Ca_B < 1e4).
TRANSITION_RANGE_CHEN2020 = ValidityRange.of(
    "Chen et al. 2020 eq. transition", nu=(0.6, 0.93), lam=(0.6, (_A - 0.6) / _B),
    ca_b=(10.0, 1e4))

# Classifying a vesicle: the simulated box of the phase diagram. nu from the smallest simulated
# reduced volume (0.6) up to the sphere, since above nu = 0.93 the paper finds bullets only
# ("a near spherical vesicle (nu = 0.98) always exhibits a bullet-like shape"); lam from 0.6
# (where the line starts) to the largest simulated confinement (1.94, nu = 0.6, a bullet);
# Ca_B from the caption of the phase diagram.
SHAPE_CLASS_RANGE_CHEN2020 = ValidityRange.of(
    "Chen et al. 2020 phase diagram and eq. transition", nu=(0.6, 1.0), lam=(0.6, 1.94),
    ca_b=(10.0, 1e4))

# Chen et al. 2020 fig. length: simulated lengths tend to eq. sL as lam -> lam_c; the
# near-critical regime of the same simulations is delta < 0.1 (fig. film). At nu = 1 eq. sL is
# exact (l = 2 lam, the sphere's diameter), and the paper notes it is more precise for less
# deflated vesicles, so nu runs from the most deflated simulated (0.6) to 1.
LENGTH_RANGE_CHEN2020 = ValidityRange.of("Chen et al. 2020 eq. sL", nu=(0.6, 1.0),
                                         delta=(0.0, 0.1))


def transition_reduced_volume_chen2020(lam):
    r"""Reduced volume on the parachute-bullet transition line, :math:`\nu_T(\lambda)`.

    .. math:: \nu_T = 1.126 - 0.29\,\lambda

    Chen et al. 2020 eq. transition: linear fit to the BEM transition points (flat rear) at
    :math:`\mathrm{Ca_B} = 50`, stated valid for :math:`\nu \le 0.93` and :math:`\lambda \ge 0.6`
    and, since the shapes barely depend on :math:`\mathrm{Ca_B}` under confinement, over the
    phase diagram's :math:`10 < \mathrm{Ca_B} < 10^4`. Vesicles with :math:`\nu < \nu_T` are
    parachutes, above it bullets. The point :math:`(\nu_T(\lambda), \lambda)` must lie in
    :data:`TRANSITION_RANGE_CHEN2020`, i.e. :math:`0.676 \le \lambda \le 1.814`; outside an
    :class:`OutOfRangeWarning` is emitted.

    Parameters
    ----------
    lam : float or array_like
        Confinement R0/R, 0 < lam < 3.883 (where the line reaches nu_T = 0) [-].

    Returns
    -------
    nu_T : float or ndarray
        Transition reduced volume [-].

    Examples
    --------
    >>> round(transition_reduced_volume_chen2020(1.0), 3)
    0.836
    """
    lam = check_range("lam", lam, 0.0, _A / _B, lo_open=True, hi_open=True,
                      reason="the transition line gives nu_T <= 0 beyond lam = 1.126/0.29")
    nu_T = _A - _B * lam
    TRANSITION_RANGE_CHEN2020.warn_outside("transition_reduced_volume_chen2020", nu=nu_T, lam=lam)
    return scalar_or_array(nu_T)


def transition_confinement_chen2020(nu):
    r"""Confinement on the parachute-bullet transition line, :math:`\lambda_T(\nu)`.

    .. math:: \lambda_T = (1.126 - \nu)/0.29

    Inverse of :func:`transition_reduced_volume_chen2020` (Chen et al. 2020 eq. transition).
    A vesicle of reduced volume ``nu`` is a parachute for :math:`\lambda < \lambda_T` and a bullet
    above. For nu = 0.6 (red blood cells) :math:`\lambda_T \approx 1.81`, the paper's
    ":math:`\lambda_T(0.6) \simeq 1.8`". Warned outside 0.6 <= nu <= 0.93; ``nu`` as in
    :func:`~lubrication.geometry.critical_confinement`.

    Returns
    -------
    lam_T : float or ndarray
        Transition confinement R0/R [-].

    Examples
    --------
    >>> round(transition_confinement_chen2020(0.6), 4)
    1.8138
    """
    nu = check_reduced_volume(nu)
    lam_T = (_A - nu) / _B
    TRANSITION_RANGE_CHEN2020.warn_outside("transition_confinement_chen2020", nu=nu, lam=lam_T)
    return scalar_or_array(lam_T)


def shape_class_chen2020(nu, lam, ca_b=None):
    r"""Steady shape class, ``"parachute"`` if :math:`\nu < \nu_T(\lambda)`, else ``"bullet"``.

    Classification by the transition line of Chen et al. 2020 eq. transition
    (:func:`transition_reduced_volume_chen2020`). It reproduces the two vesicles of the paper's
    fig. transition: (nu, lam, Ca_B) = (0.95, 0.8, 5) bullet and (0.83, 0.67, 15) parachute.
    Near the line both shapes can coexist; the class there is a best estimate. Warned outside
    :data:`SHAPE_CLASS_RANGE_CHEN2020`.

    Parameters
    ----------
    nu, lam : float or array_like
        Reduced volume and confinement R0/R [-], as in :func:`~lubrication.geometry.clearance`
        (lam >= lam_c(nu) raises :class:`~lubrication.checks.CannotPassError`).
    ca_b : float or array_like, optional
        Bending capillary number :math:`\eta U R_0^2/\kappa` > 0 [-]; only used to warn outside
        the phase diagram's 10 <= Ca_B <= 1e4 (the class itself does not depend on it).

    Returns
    -------
    shape : str or ndarray of str
        ``"parachute"`` or ``"bullet"``.

    Examples
    --------
    >>> shape_class_chen2020(0.83, 0.67)
    'parachute'
    >>> shape_class_chen2020([0.6, 0.7], 1.5)
    array(['parachute', 'bullet'], dtype='<U9')
    """
    nu, lam, _ = check_confinement(nu, lam)
    values = {"nu": nu, "lam": lam}
    if ca_b is not None:
        values["ca_b"] = check_positive("ca_b", ca_b)
    SHAPE_CLASS_RANGE_CHEN2020.warn_outside("shape_class_chen2020", **values)
    out = np.where(nu < _A - _B * lam, "parachute", "bullet")
    return str(out) if out.ndim == 0 else out


def length_chen2020(nu, lam):
    r"""Vesicle length in tube radii, :math:`\ell = L/R`.

    .. math:: \ell = \ell_c\,\frac{\lambda}{\lambda_c} = 2\nu^{-2/3}\lambda_c\lambda

    Chen et al. 2020 eq. sL, fitted to BEM lengths as :math:`\lambda \to \lambda_c`
    (:math:`\mathrm{Ca_B} = 50`); it reaches the critical length :math:`\ell_c` of the
    spherocylinder at :math:`\lambda_c` (Barakat & Shaqfeh 2018a: :math:`\ell = \ell_c + O(\delta)`)
    and is exact for a sphere (nu = 1: :math:`\ell = 2\lambda`). More precise for less deflated
    vesicles; warned outside delta <= 0.1 or nu < 0.6 (:data:`LENGTH_RANGE_CHEN2020`).
    ``nu`` and ``lam`` as in :func:`~lubrication.geometry.clearance`: lam >= lam_c(nu) raises
    :class:`~lubrication.checks.CannotPassError`.

    Returns
    -------
    ell : float or ndarray
        Length L/R [-].

    Examples
    --------
    >>> round(length_chen2020(0.6, 1.94), 3)
    10.81
    """
    nu, lam, lam_c = check_confinement(nu, lam)
    LENGTH_RANGE_CHEN2020.warn_outside("length_chen2020", nu=nu, delta=1.0 - lam / lam_c)
    return scalar_or_array(2.0 * nu ** (-2.0 / 3.0) * lam_c * lam)
