r"""Apparent (relative) viscosity of blood in small tubes and the Fåhræus effect.

Conventions
-----------
* ``diameter_um``: tube or vessel diameter D in µm (not a radius, not metres).
* ``discharge_hematocrit`` H_D and ``tube_hematocrit`` H_T: volume fractions, 0 <= H < 1 (not %).
  H_D is the flow-weighted (delivered) hematocrit, H_T the volume fraction inside the tube.
* Relative viscosity :math:`\eta_{rel} = \eta_{app}/\eta_{plasma}` [-]: the apparent viscosity
  from Poiseuille's law divided by the viscosity of the suspending medium (plasma, or the
  saline/albumin medium of the in vitro experiments).

The empirical laws of Pries and co-workers are fits for human red blood cells (mean cell volume
about 92 fL) at high shear rate (>= 50 s^-1). Secomb's network codes (NetFlowV2 ``viscor.cpp``)
multiply the diameter by a mean-cell-volume factor ``mcvcorr`` for other species ((92/MCV)^(1/3)
in a public translation of that code); this module does not.

Validity ranges are stored as :class:`~lubrication.checks.ValidityRange` data
(``PRIES1992_RANGE`` etc.); evaluating a law outside its range returns the extrapolated value
and emits an :class:`~lubrication.checks.OutOfRangeWarning`. Inputs where a law is undefined
raise :class:`~lubrication.checks.InvalidParameterError`.
"""

from __future__ import annotations

import math

import numpy as np

from lubrication.checks import (InvalidParameterError, OutOfRangeWarning, ValidityRange,
                                check_choice, check_fraction, check_positive, check_range,
                                scalar_or_array)

__all__ = [
    "VISCOSITY_LAWS",
    "FAHRAEUS_CONSTANTS",
    "PRIES1992_RANGE",
    "PRIES1994_RANGE",
    "PRIES2005_RANGE",
    "FAHRAEUS_RANGE",
    "FAHRAEUS_MIN_DIAMETER_UM",
    "CHEN2020_RANGE",
    "PRIES1994_W_UM",
    "PRIES2005_ESL",
    "eta_045_vitro_pries1992",
    "shape_exponent_pries1992",
    "viscosity_vitro_pries1992",
    "viscosity_vivo_pries1994",
    "viscosity_vivo_pries2005",
    "relative_viscosity",
    "hematocrit_ratio_fahraeus",
    "tube_hematocrit_fahraeus",
    "discharge_hematocrit_fahraeus",
    "viscosity_single_file_chen2020",
    "OutOfRangeWarning",
]

VISCOSITY_LAWS = ("pries1992", "pries1994", "pries2005")

#: Fåhræus-effect constants (a, b) [1/µm] of x = 1 + 1.7 exp(-a D) - 0.6 exp(-b D).
#: "pries1990": Pries, Secomb, Gaehtgens & Gross 1990, Circ. Res. 67:826-834, eq. 1 (also
#: used by Pries & Secomb 2005); "pries1992": Pries, Neuhaus & Gaehtgens 1992, Am. J. Physiol.
#: 263:H1770-H1778. Attribution as in public implementations that cite the equation numbers
#: (DuMux microcirculation module: "constants from Pries et al (1990) Eq. (1)"); the original
#: papers were not available to check.
FAHRAEUS_CONSTANTS = {"pries1990": (0.415, 0.011), "pries1992": (0.35, 0.01)}

#: Pries et al. 1994 in vivo law: effective thickness of the endothelial layer, W [µm].
PRIES1994_W_UM = 1.1

#: Pries & Secomb 2005 (Am. J. Physiol. Heart Circ. Physiol. 289:H2657-H2664) endothelial surface
#: layer (ESL) parameters, diameters and widths in µm.
PRIES2005_ESL = {
    "D_off": 2.4,     # diameter below which the ESL vanishes [µm]
    "D_crit": 10.5,   # diameter of the peak of the hematocrit-dependent part [µm]
    "D_50": 100.0,    # diameter where the asymptotic width reaches half of W_max [µm]
    "E_amp": 1.1,     # amplitude of the peaked part [µm]
    "E_width": 0.03,  # decay rate of the peaked part above D_crit [1/µm]
    "E_peak": 0.6,    # fraction of the peaked part that excludes cells (physical width) [-]
    "E_HD": 1.18,     # hematocrit dependence of the hydrodynamically effective width [-]
    "W_max": 2.6,     # asymptotic ESL width [µm]
}

_H_REF = 0.45
_LOG_ONE_MINUS_H_REF = math.log1p(-_H_REF)   # ln 0.55

PRIES1992_RANGE = ValidityRange.of(
    "Pries, Neuhaus & Gaehtgens 1992 (in vitro data base: tubes 3.3-1978 µm, H_D up to 0.9, "
    "shear rate >= 50 1/s)",
    diameter_um=(3.3, 1978.0), discharge_hematocrit=(0.0, 0.9))

# The in vivo laws were optimised on rat mesentery networks (Pries et al. 1994: microvessels,
# systemic hematocrits 0.08-0.68 in the validation experiments). The diameter range of the
# network segments could not be retrieved; both in vivo laws reuse C(D) of the in vitro fit and
# reduce to it at large D (W/D -> 0), so we adopt the in vitro box. Values for D >~ 100 µm rest
# on the in vitro data, not on in vivo measurements.
PRIES1994_RANGE = ValidityRange.of(
    "Pries et al. 1994 (in vivo, rat mesentery; box adopted from the in vitro data base of "
    "Pries et al. 1992)",
    diameter_um=(3.3, 1978.0), discharge_hematocrit=(0.0, 0.9))
PRIES2005_RANGE = ValidityRange.of(
    "Pries & Secomb 2005 (in vivo with ESL; box adopted from the in vitro data base of "
    "Pries et al. 1992)",
    diameter_um=(3.3, 1978.0), discharge_hematocrit=(0.0, 0.9))

# Both Fåhræus fits describe the in vitro tube data; below D ~ 3 µm x > 1 and H_T > H_D, which is
# unphysical (in single file H_T/H_D = U/V < 1), so the lower bound is also physically needed.
FAHRAEUS_RANGE = ValidityRange.of(
    "Pries et al. 1990/1992 Fåhræus fit (box of the in vitro data base, 3.3-1978 µm)",
    diameter_um=(3.3, 1978.0), discharge_hematocrit=(0.0, 0.9), tube_hematocrit=(0.0, 0.9))


def _fahraeus_unit_diameter(constants: str) -> float:
    """Diameter D* [µm] where x = 1 + 1.7 e^(-aD) - 0.6 e^(-bD) = 1: D* = ln(1.7/0.6)/(a - b)."""
    a, b = FAHRAEUS_CONSTANTS[constants]
    return math.log(1.7 / 0.6) / (a - b)


#: Smallest diameter [µm] where each Fåhræus fit is physically meaningful: below D* the fit has
#: x > 1, i.e. H_T > H_D, impossible since H_T/H_D = U/V <= 1 (cells move at least as fast as
#: the mean flow: single file, physics-notes §6; Pries et al. 1990, 1992 data show H_T < H_D in
#: every tube). D* = ln(1.7/0.6)/(a - b): 2.578 µm (pries1990), 3.063 µm (pries1992). At D*
#: exactly x = 1 and H_T = H_D; the functions refuse D <= D* (InvalidParameterError) and warn
#: (extrapolated) between D* and 3.3 µm, the smallest tube of the data base.
FAHRAEUS_MIN_DIAMETER_UM = {name: _fahraeus_unit_diameter(name) for name in FAHRAEUS_CONSTANTS}

# Chen et al. 2020 §Visco: single-file flow holds in capillaries up to about 8 µm. The lower
# limit d > d_c (~2.8 µm for a red cell) is a property of the cell, enforced where Δp⁺ is computed.
CHEN2020_RANGE = ValidityRange.of(
    "Chen et al. 2020 single-file model (d_c < d <~ 8 µm)", diameter_um=(0.0, 8.0))


# --------------------------------------------------------------------------------------------
# Private kernels: no checks, plain NumPy, broadcast over their arguments.
# --------------------------------------------------------------------------------------------

def _eta_045_vitro(d):
    return 220.0 * np.exp(-1.3 * d) + 3.2 - 2.44 * np.exp(-0.06 * d**0.645)


def _eta_045_vivo(d):
    return 6.0 * np.exp(-0.085 * d) + 3.2 - 2.44 * np.exp(-0.06 * d**0.645)


def _shape_exponent(d):
    # Printed form: (0.8 + e)(-1 + 1/(1 + q)) + 1/(1 + q), q = 1e-11 D^12. Algebraically
    # -1 + 1/(1 + q) = -q/(1 + q) = -1/(1 + 1/q); written so it keeps full relative accuracy for
    # small q (D = 3 µm: q = 5e-6, where -1 + 1/(1+q) would lose 5 digits) and gives the exact
    # limit C = -0.8 once D^12 overflows to inf (D > 1e25 µm; no physical meaning, but no NaN).
    with np.errstate(over="ignore", divide="ignore"):
        q = 1e-11 * d**12
        s = 1.0 / (1.0 + q)          # 1/(1 + q)
        t = 1.0 / (1.0 + 1.0 / q)    # q/(1 + q)
    return s - (0.8 + np.exp(-0.075 * d)) * t


def _hematocrit_ratio(c, hd):
    r"""[(1 - H_D)^C - 1] / [0.55^C - 1], exact across C = 0.

    With a = ln(1 - H_D), b = ln 0.55 the ratio is expm1(C a)/expm1(C b): expm1 is accurate to
    an ulp for every argument and the products C a, C b carry one rounding each, so this form
    has a relative error of a few ulp for every C != 0, however small (no cancellation). It is
    0/0 only at C = 0 exactly. Its Taylor expansion is
    (a/b)[1 + C(a - b)/2 + O(C^2)], so the limit a/b has relative error |C(a - b)|/2. We use the
    limit where |C (a - b)| <= 2^-52, i.e. where its truncation error is <= 2^-53 (half an ulp),
    and expm1 elsewhere: both sides are at machine precision and the switch is seamless
    (checked against 50-digit arithmetic: relative error <= 1e-15 at D*, D* +- 1e-9, +- 1e-6).
    C is smooth with dC/dD = -0.84/µm at its zero D* = 8.0518 µm, so for H_D away from 0.45 the
    limit branch is taken only at C == 0 and the float or two next to it; at H_D = 0.45 exactly
    (a = b) it is taken everywhere and returns the exact ratio 1.
    """
    a = np.log1p(-hd)
    b = _LOG_ONE_MINUS_H_REF
    use_limit = np.abs(c * (a - b)) <= 2.0**-52
    num = np.expm1(c * a)
    den = np.expm1(c * b)
    limit = np.broadcast_to(a / b, np.broadcast(num, den).shape).copy()
    # `where` masks exactly the 0/0 points, so no RuntimeWarning is raised there.
    return np.divide(num, den, out=limit, where=~use_limit)


def _viscosity_vitro(d, hd):
    return 1.0 + (_eta_045_vitro(d) - 1.0) * _hematocrit_ratio(_shape_exponent(d), hd)


def _esl_widths(d, hd):
    """Pries & Secomb 2005 ESL widths (W_ph, W_eff) [µm] for diameters d > 0."""
    p = PRIES2005_ESL
    above_off = d > p["D_off"]
    # the ratio first: W_max (D - D_off) alone overflows for D > ~7e307 µm
    w_as = np.where(above_off, p["W_max"] * ((d - p["D_off"]) / (d + p["D_50"] - 2.0 * p["D_off"])),
                    0.0)
    w_peak = np.where(
        d <= p["D_crit"],
        p["E_amp"] * (d - p["D_off"]) / (p["D_crit"] - p["D_off"]),
        p["E_amp"] * np.exp(-p["E_width"] * (d - p["D_crit"])))
    w_peak = np.where(above_off, w_peak, 0.0)
    w_ph = w_as + w_peak * p["E_peak"]
    w_eff = w_as + w_peak * (1.0 + hd * p["E_HD"])
    return w_ph, w_eff


def _fahraeus_x(d, constants):
    a, b = FAHRAEUS_CONSTANTS[constants]
    return 1.0 + 1.7 * np.exp(-a * d) - 0.6 * np.exp(-b * d)


def _fahraeus_ratio(d, hd, constants):
    """H_T/H_D = H_D + (1 - H_D) x, capped at 1 (x <= 1 for D > D*; the cap removes rounding)."""
    return np.minimum(hd + (1.0 - hd) * _fahraeus_x(d, constants), 1.0)


def _check_diameter(diameter_um):
    return check_positive("diameter_um", diameter_um,
                          reason="give the tube diameter in µm as a positive finite number")


def _check_fahraeus_diameter(diameter_um, constants):
    """D > D*(constants): the Fåhræus fit gives H_T <= H_D only there (FAHRAEUS_MIN_DIAMETER_UM)."""
    d_min = FAHRAEUS_MIN_DIAMETER_UM[constants]
    return check_range("diameter_um", diameter_um, d_min, lo_open=True,
                       reason=f"below {d_min:.4g} µm the {constants} Fåhræus fit gives a tube "
                              "hematocrit above the discharge hematocrit (H_T/H_D = U/V <= 1 is "
                              "required); the fit's data start at 3.3 µm")


# --------------------------------------------------------------------------------------------
# Public API
# --------------------------------------------------------------------------------------------

def eta_045_vitro_pries1992(diameter_um):
    r"""Relative apparent viscosity of blood at H_D = 0.45 in glass tubes, :math:`\eta_{0.45}(D)`.

    .. math:: \eta_{0.45} = 220\,e^{-1.3D} + 3.2 - 2.44\,e^{-0.06 D^{0.645}}

    Pries, Neuhaus & Gaehtgens (1992), "Blood viscosity in tube flow: dependence on diameter and
    hematocrit", Am. J. Physiol. 263:H1770-H1778, doi:10.1152/ajpheart.1992.263.6.H1770.

    Parameters
    ----------
    diameter_um : float or array_like
        Tube diameter D [µm], > 0. Fitted on 3.3-1978 µm (warns outside).

    Returns
    -------
    eta_045 : float or ndarray
        Relative viscosity at discharge hematocrit 0.45 [-]; tends to 3.2 as D -> inf.

    Examples
    --------
    >>> round(eta_045_vitro_pries1992(10.0), 4)
    1.3284
    >>> round(eta_045_vitro_pries1992(1000.0), 4)
    3.1861
    """
    d = _check_diameter(diameter_um)
    PRIES1992_RANGE.warn_outside("eta_045_vitro_pries1992", diameter_um=d)
    return scalar_or_array(_eta_045_vitro(d))


def shape_exponent_pries1992(diameter_um):
    r"""Shape exponent :math:`C(D)` of the hematocrit dependence (Pries et al. 1992).

    .. math::
        C = (0.8 + e^{-0.075D})\left(-1 + \frac{1}{1 + 10^{-11}D^{12}}\right)
            + \frac{1}{1 + 10^{-11}D^{12}}

    C goes from 1 (small D) to -0.8 (large D) and crosses zero near D = 8.05 µm. It is evaluated
    in the algebraically equal form :math:`[1 - (0.8 + e^{-0.075D})q]/(1 + q)`,
    :math:`q = 10^{-11}D^{12}`, which keeps full accuracy at small D. Same source, and the same
    ``diameter_um`` and range, as :func:`eta_045_vitro_pries1992` (also used unchanged by the in
    vivo laws of 1994 and 2005).

    Returns
    -------
    C : float or ndarray
        Shape exponent [-].

    Examples
    --------
    >>> round(shape_exponent_pries1992(5.0), 4)
    0.9939
    >>> round(shape_exponent_pries1992(100.0), 4)
    -0.8006
    """
    d = _check_diameter(diameter_um)
    PRIES1992_RANGE.warn_outside("shape_exponent_pries1992", diameter_um=d)
    return scalar_or_array(_shape_exponent(d))


def viscosity_vitro_pries1992(diameter_um, discharge_hematocrit):
    r"""Relative apparent viscosity of blood in glass tubes (in vitro), Pries et al. 1992.

    .. math::
        \eta_{rel} = 1 + (\eta_{0.45} - 1)\,
                     \frac{(1 - H_D)^C - 1}{(1 - 0.45)^C - 1}

    with :math:`\eta_{0.45}(D)` from :func:`eta_045_vitro_pries1992` and :math:`C(D)` from
    :func:`shape_exponent_pries1992`. The hematocrit factor is 0/0 where C = 0 (D ≈ 8.05 µm);
    it is evaluated as :math:`\mathrm{expm1}(C\ln(1 - H_D))/\mathrm{expm1}(C\ln 0.55)`, with the
    exact limit :math:`\ln(1 - H_D)/\ln 0.55` where :math:`|C| \to 0`, so the result is exact and
    continuous (to machine precision) across the zero of C.

    Source: Pries, Neuhaus & Gaehtgens (1992), Am. J. Physiol. 263:H1770-H1778,
    doi:10.1152/ajpheart.1992.263.6.H1770. Data base: tubes of 3.3-1978 µm, hematocrits up to
    0.9, shear rates >= 50 s^-1; relative to the suspending-medium viscosity.

    Parameters
    ----------
    diameter_um : float or array_like
        Tube diameter D [µm], > 0 (warns outside 3.3-1978 µm).
    discharge_hematocrit : float or array_like
        Discharge hematocrit H_D, 0 <= H_D < 1 [-] (warns above 0.9). Broadcasts with D.

    Returns
    -------
    eta_rel : float or ndarray
        Relative apparent viscosity [-], of the broadcast shape of the inputs.

    Examples
    --------
    >>> round(viscosity_vitro_pries1992(10.0, 0.45), 4)   # = eta_045_vitro_pries1992(10.0)
    1.3284
    >>> round(viscosity_vitro_pries1992(6.0, 0.3), 4)
    1.1814
    >>> viscosity_vitro_pries1992([20.0, 200.0], 0.0)
    array([1., 1.])
    """
    d = _check_diameter(diameter_um)
    hd = check_fraction("discharge_hematocrit", discharge_hematocrit)
    PRIES1992_RANGE.warn_outside("viscosity_vitro_pries1992", diameter_um=d,
                                 discharge_hematocrit=hd)
    return scalar_or_array(_viscosity_vitro(d, hd))


def viscosity_vivo_pries1994(diameter_um, discharge_hematocrit):
    r"""Relative apparent viscosity of blood in microvessels in vivo, Pries et al. 1994.

    .. math::
        \eta_{vivo} = \left[1 + (\eta^*_{0.45} - 1)\,\frac{(1 - H_D)^C - 1}{(1 - 0.45)^C - 1}
                      \left(\frac{D}{D - W}\right)^2\right]\left(\frac{D}{D - W}\right)^2,

    :math:`\eta^*_{0.45} = 6e^{-0.085D} + 3.2 - 2.44e^{-0.06D^{0.645}}`, C(D) as in vitro
    (:func:`shape_exponent_pries1992`), W = 1.1 µm (``PRIES1994_W_UM``). The hematocrit factor is
    evaluated exactly across C = 0 as in :func:`viscosity_vitro_pries1992`.

    Source: Pries, Secomb, Gessner, Sperandio, Gross & Gaehtgens (1994), "Resistance to blood
    flow in microvessels in vivo", Circ. Res. 75:904-915, doi:10.1161/01.RES.75.5.904. Fitted to
    rat mesentery networks; the validity box used here is our choice (see ``PRIES1994_RANGE``).
    This is the law of Secomb's NetFlowV2 ``viscor.cpp`` (there multiplied by the plasma
    viscosity and with D rescaled by the mean cell volume).

    Parameters
    ----------
    diameter_um : float or array_like
        Vessel diameter D [µm], must exceed W = 1.1 µm (the law diverges at D = W); warns
        outside 3.3-1978 µm.
    discharge_hematocrit : float or array_like
        Discharge hematocrit H_D, 0 <= H_D < 1 [-]. Broadcasts with D.

    Returns
    -------
    eta_rel : float or ndarray
        Relative apparent viscosity in vivo [-].

    Raises
    ------
    InvalidParameterError
        If D <= W, D is not finite, or H_D is outside [0, 1).

    Examples
    --------
    >>> round(viscosity_vivo_pries1994(10.0, 0.45), 4)
    5.8724
    >>> round(viscosity_vivo_pries1994(10.0, 0.0), 4)   # plasma alone: (D/(D - W))^2
    1.2625
    """
    d = check_range("diameter_um", diameter_um, PRIES1994_W_UM, lo_open=True,
                    reason="the Pries et al. 1994 law diverges at D = W = 1.1 µm")
    hd = check_fraction("discharge_hematocrit", discharge_hematocrit)
    PRIES1994_RANGE.warn_outside("viscosity_vivo_pries1994", diameter_um=d,
                                 discharge_hematocrit=hd)
    f = (d / (d - PRIES1994_W_UM)) ** 2
    ratio = _hematocrit_ratio(_shape_exponent(d), hd)
    return scalar_or_array((1.0 + (_eta_045_vivo(d) - 1.0) * ratio * f) * f)


def viscosity_vivo_pries2005(diameter_um, discharge_hematocrit):
    r"""Relative apparent viscosity in vivo with an endothelial surface layer, Pries & Secomb 2005.

    The vessel of diameter D is lined by an endothelial surface layer (ESL). Its width is
    :math:`W_{as} = 0` for :math:`D \le D_{off}`, else
    :math:`W_{max}(D - D_{off})/(D + D_{50} - 2D_{off})`, plus a peaked part
    :math:`W_{peak} = 0` (:math:`D \le D_{off}`),
    :math:`E_{amp}(D - D_{off})/(D_{crit} - D_{off})` (:math:`D \le D_{crit}`),
    :math:`E_{amp}e^{-E_{width}(D - D_{crit})}` (:math:`D > D_{crit}`). Then

    .. math::
        W_{ph} = W_{as} + W_{peak}E_{peak},\quad
        W_{eff} = W_{as} + W_{peak}(1 + H_D E_{HD}),\\
        D_{ph} = D - 2W_{ph},\quad D_{eff} = D - 2W_{eff},\quad
        \eta_{vivo} = \eta_{vitro}(D_{ph}, H_D)\,(D/D_{eff})^4,

    with :math:`\eta_{vitro}` the in vitro law of Pries et al. 1992
    (:func:`viscosity_vitro_pries1992`, i.e. :math:`\eta_{0.45} = 220e^{-1.3D} + \dots`),
    evaluated at the physical diameter :math:`D_{ph}` and the discharge hematocrit.
    Constants (``PRIES2005_ESL``): D_off = 2.4 µm, D_crit = 10.5 µm, D_50 = 100 µm,
    E_amp = 1.1 µm, E_width = 0.03 /µm, E_peak = 0.6, E_HD = 1.18, W_max = 2.6 µm.

    Source: Pries & Secomb (2005), "Microvascular blood viscosity in vivo and the endothelial
    surface layer", Am. J. Physiol. Heart Circ. Physiol. 289:H2657-H2664,
    doi:10.1152/ajpheart.00297.2005.

    Implementation notes (public code read, not copied): secomb/NetFlowV2 ``viscor.cpp`` does
    *not* implement this law; it implements Pries et al. 1994 (W = 1.1 µm, η*_0.45 with
    6e^(-0.085D), parameters in ``RheolParams.dat``) with D rescaled by (92/MCV)^(1/3) and no
    special treatment of small D (secomb/AngioAdaptRetina clamps D from below to a threshold).
    The ESL law as implemented by P. Sweeney (psweens/VF_NatureBioEng ``viscor.cpp``) confirms
    the reading above: η_vitro with the 1992 in vitro coefficients (220, -1.3, ...) at D_ph,
    times (D/D_eff)^4, and no clamp: for D <= D_off both widths are zero and the law reduces to
    the in vitro law at D. We do the same. For 0 <= H_D < 1 and D > 0 these constants give
    2W_eff < D everywhere (the largest ratio 2W_eff/D ~ 0.5 is near D_crit), so the D <= 2W_eff
    guard below never fires for valid hematocrits; it is kept as a check of the constants.

    Arguments and result as in :func:`viscosity_vivo_pries1994`, except that every finite
    D > 0 is accepted (there is no W); :class:`~lubrication.checks.InvalidParameterError` is
    raised for D <= 2 W_eff(D, H_D) as well as for invalid inputs.

    Examples
    --------
    >>> round(viscosity_vivo_pries2005(10.0, 0.45), 4)
    7.3198
    >>> round(viscosity_vivo_pries2005(10.0, 0.0), 4)   # plasma in the ESL-narrowed lumen
    3.0611
    """
    d = _check_diameter(diameter_um)
    hd = check_fraction("discharge_hematocrit", discharge_hematocrit)
    w_ph, w_eff = _esl_widths(d, hd)
    d_ph = d - 2.0 * w_ph
    d_eff = d - 2.0 * w_eff
    bad = d_eff <= 0.0
    if np.any(bad):
        d_b = np.broadcast_to(d, bad.shape)
        w_b = np.broadcast_to(w_eff, bad.shape)
        i = np.flatnonzero(bad.ravel())[0]
        raise InvalidParameterError(
            "diameter_um", d_b.ravel()[i], f"diameter_um > 2 W_eff = {2 * w_b.ravel()[i]:.6g}",
            "the endothelial surface layer of Pries & Secomb 2005 fills the vessel")
    PRIES2005_RANGE.warn_outside("viscosity_vivo_pries2005", diameter_um=d,
                                 discharge_hematocrit=hd)
    return scalar_or_array(_viscosity_vitro(d_ph, hd) * (d / d_eff) ** 4)


_LAW_FUNCTIONS = {
    "pries1992": viscosity_vitro_pries1992,
    "pries1994": viscosity_vivo_pries1994,
    "pries2005": viscosity_vivo_pries2005,
}


def relative_viscosity(diameter_um, discharge_hematocrit, law="pries1992"):
    r"""Relative apparent viscosity of blood by the chosen law.

    Parameters
    ----------
    diameter_um : float or array_like
        Tube or vessel diameter D [µm].
    discharge_hematocrit : float or array_like
        Discharge hematocrit H_D, 0 <= H_D < 1 [-].
    law : {"pries1992", "pries1994", "pries2005"}
        ``"pries1992"``: in vitro, glass tubes (:func:`viscosity_vitro_pries1992`);
        ``"pries1994"``: in vivo (:func:`viscosity_vivo_pries1994`);
        ``"pries2005"``: in vivo with endothelial surface layer
        (:func:`viscosity_vivo_pries2005`). See those functions for sources and ranges.

    Returns
    -------
    eta_rel : float or ndarray
        Relative apparent viscosity [-].

    Raises
    ------
    InvalidParameterError
        For an unknown ``law`` (the message lists the choices) or invalid inputs.

    Examples
    --------
    >>> [round(relative_viscosity(10.0, 0.45, law), 3) for law in VISCOSITY_LAWS]
    [1.328, 5.872, 7.32]
    """
    check_choice("law", law, VISCOSITY_LAWS)
    return _LAW_FUNCTIONS[law](diameter_um, discharge_hematocrit)


def _check_fahraeus(caller, diameter_um, constants, hematocrit_name, hematocrit):
    """Inputs of a Fåhræus function checked, as arrays (D, H); warns, naming ``caller`` (the
    public function that calls this directly), outside the fit's data range."""
    check_choice("constants", constants, tuple(FAHRAEUS_CONSTANTS))
    d = _check_fahraeus_diameter(diameter_um, constants)
    h = check_fraction(hematocrit_name, hematocrit)
    FAHRAEUS_RANGE.warn_outside(caller, stacklevel=4, diameter_um=d, **{hematocrit_name: h})
    return d, h


def hematocrit_ratio_fahraeus(diameter_um, discharge_hematocrit, constants="pries1990"):
    r"""Fåhræus ratio :math:`H_T/H_D = H_D + (1 - H_D)x` (see :func:`tube_hematocrit_fahraeus`).

    Computed directly rather than as a quotient of two hematocrits, so it stays exact for tiny
    (even subnormal) hematocrits, and is 1 - (1 - x) at H_D = 0. Arguments, errors and warnings
    as in :func:`tube_hematocrit_fahraeus`.

    Returns
    -------
    ratio : float or ndarray
        H_T/H_D [-], in (0, 1].

    Examples
    --------
    >>> round(hematocrit_ratio_fahraeus(10.0, 0.45, constants="pries1992"), 4)
    0.7296
    """
    d, hd = _check_fahraeus("hematocrit_ratio_fahraeus", diameter_um, constants,
                            "discharge_hematocrit", discharge_hematocrit)
    return scalar_or_array(_fahraeus_ratio(d, hd, constants))


def tube_hematocrit_fahraeus(diameter_um, discharge_hematocrit, constants="pries1990"):
    r"""Tube hematocrit from the discharge hematocrit (Fåhræus effect).

    .. math::
        \frac{H_T}{H_D} = H_D + (1 - H_D)\,x,\qquad
        x = 1 + 1.7e^{-aD} - 0.6e^{-bD}

    with (a, b) [1/µm] from ``FAHRAEUS_CONSTANTS``: ``"pries1990"`` (0.415, 0.011), Pries et al.
    1990, Circ. Res. 67:826-834, doi:10.1161/01.RES.67.4.826; ``"pries1992"`` (0.35, 0.01),
    Pries, Neuhaus & Gaehtgens 1992, Am. J. Physiol. 263:H1770-H1778. x < 1 (H_T < H_D) for
    D above D* = ln(1.7/0.6)/(a - b) (2.578 µm, pries1990; 3.063 µm, pries1992) and x -> 1 from
    below as D -> inf (no Fåhræus effect in wide tubes; x rounds to 1 for D >~ 3700 µm, where
    H_T = H_D). Below D* the fit would give H_T > H_D, impossible (H_T/H_D = U/V <= 1): such
    diameters raise (:data:`FAHRAEUS_MIN_DIAMETER_UM`).

    Parameters
    ----------
    diameter_um : float or array_like
        Tube diameter D [µm], D > D*(constants); warns outside 3.3-1978 µm.
    discharge_hematocrit : float or array_like
        Discharge hematocrit H_D, 0 <= H_D < 1 [-].
    constants : {"pries1990", "pries1992"}
        Which fit to use.

    Returns
    -------
    tube_hematocrit : float or ndarray
        H_T [-], H_T <= H_D.

    Raises
    ------
    InvalidParameterError
        For D <= D*(constants) (the message gives the bound), or invalid inputs.

    Examples
    --------
    >>> round(tube_hematocrit_fahraeus(10.0, 0.45), 4)
    0.3236
    >>> round(tube_hematocrit_fahraeus(10.0, 0.45, constants="pries1992"), 4)
    0.3283
    """
    d, hd = _check_fahraeus("tube_hematocrit_fahraeus", diameter_um, constants,
                            "discharge_hematocrit", discharge_hematocrit)
    # x <= 1 for D > D*, so H_T/H_D = H_D + (1 - H_D) x <= 1: H_T <= H_D to the last bit.
    return scalar_or_array(hd * _fahraeus_ratio(d, hd, constants))


def discharge_hematocrit_fahraeus(diameter_um, tube_hematocrit, constants="pries1990"):
    r"""Discharge hematocrit from the tube hematocrit: inverse of :func:`tube_hematocrit_fahraeus`.

    H_D is the root in [0, 1) of :math:`(1 - x)H_D^2 + xH_D - H_T = 0`, computed as

    .. math:: H_D = \frac{2H_T}{x + \sqrt{x^2 + 4(1 - x)H_T}}.

    This is the usual root :math:`[-x + \sqrt{x^2 + 4(1 - x)H_T}]/(2(1 - x))` multiplied above
    and below by :math:`x + \sqrt{\cdot}`. The usual form (e.g. Pries et al. 1992; written
    :math:`-x/(2 - 2x) + \sqrt{(x/(2 - 2x))^2 + H_T/(1 - x)}` in many codes) divides by
    :math:`1 - x`, which vanishes at D ≈ 2.6-3.1 µm and as D -> inf, and it subtracts two nearly
    equal numbers nearby (catastrophic cancellation); codes then patch it, e.g. H_D = H_T for
    x > 0.99. The form used here has neither problem: x >= 0.4 and the discriminant
    :math:`x^2 + 4(1 - x)H_T \ge (x - 2)^2 \ge 0` for 0 <= H_T <= 1, so the denominator is
    >= 0.4, the expression is smooth through x = 1 (where it gives H_D = H_T exactly), and
    every operation is well conditioned. The singular point x = 1 of the usual form is met at
    D = D* (the lower bound of the domain, excluded: below it the fit is unphysical, see
    :func:`tube_hematocrit_fahraeus`) and, in floating point, for D >~ 3700 µm, where this form
    returns H_D = H_T exactly.

    Parameters
    ----------
    diameter_um : float or array_like
        Tube diameter D [µm], with the bound D > D*(constants), error and warning of
        :func:`tube_hematocrit_fahraeus`.
    tube_hematocrit : float or array_like
        Tube hematocrit H_T, 0 <= H_T < 1 [-].
    constants : {"pries1990", "pries1992"}
        Which fit to use (see ``FAHRAEUS_CONSTANTS``).

    Returns
    -------
    discharge_hematocrit : float or ndarray
        H_D [-], H_T <= H_D < 1.

    Examples
    --------
    >>> round(discharge_hematocrit_fahraeus(10.0, tube_hematocrit_fahraeus(10.0, 0.45)), 12)
    0.45
    """
    d, ht = _check_fahraeus("discharge_hematocrit_fahraeus", diameter_um, constants,
                            "tube_hematocrit", tube_hematocrit)
    x = _fahraeus_x(d, constants)
    # x <= 1 here, so the discriminant x^2 + 4(1 - x)H_T >= x^2 and H_D >= H_T; at x = 1 (D -> inf
    # in floating point) this is exactly H_T. np.maximum guards H_D >= H_T against rounding.
    hd = 2.0 * ht / (x + np.sqrt(x * x + 4.0 * (1.0 - x) * ht))
    return scalar_or_array(np.maximum(hd, ht))


def viscosity_single_file_chen2020(dp_plus_R0, diameter_um, R0_um, tube_hematocrit):
    r"""Relative apparent viscosity of dilute single-file vesicle/red-cell flow (Chen et al. 2020).

    A train of identical cells spaced :math:`l_v = \Omega/(\pi R^2 H_T)` apart, each adding the
    extra pressure drop :math:`\Delta p^+` at fixed flow rate, gives (Chen et al. 2020, §Visco)

    .. math::
        \eta_{rel} = 1 + \frac{3}{32}\left(\frac{R}{R_0}\right)^4
                     \frac{\Delta p^+ R_0}{\eta U}\,H_T,\qquad R = d/2,

    with U the mean velocity and H_T the tube hematocrit. With R0 = 2.8 µm and d in µm this is
    :math:`1 + 9.53\times10^{-5}d^4(\Delta p^+R_0/\eta U)H_T`.

    Source: Chen, Lyu, Jaeger & Leonetti (2020), vesicles in tube flow (axisymmetric BEM),
    section "Implications for the rheology of dilute red blood cell suspensions".
    Valid for single-file flow, :math:`d_c < d \lesssim 8` µm (warns above 8 µm). The lower
    limit d > d_c (≈ 2.8 µm for a red cell) is a property of the cell: Δp⁺ exists only there.

    Parameters
    ----------
    dp_plus_R0 : float or array_like
        Dimensionless extra pressure drop :math:`\Delta p^+R_0/(\eta U)` [-], >= 0.
    diameter_um : float or array_like
        Tube diameter d [µm], > 0.
    R0_um : float or array_like
        Volume radius of the cell :math:`R_0 = (3\Omega/4\pi)^{1/3}` [µm], > 0.
    tube_hematocrit : float or array_like
        Tube hematocrit H_T, 0 <= H_T < 1 [-].

    Returns
    -------
    eta_rel : float or ndarray
        Relative apparent viscosity [-], >= 1.

    Raises
    ------
    InvalidParameterError
        For invalid inputs, or when the result would overflow (an absurd dp+ or d/R0).

    Examples
    --------
    >>> coefficient = viscosity_single_file_chen2020(2.0, 1.0, 2.8, 0.5) - 1.0   # 9.53e-5 d^4
    >>> float(f"{coefficient:.3g}")
    9.53e-05
    >>> round(viscosity_single_file_chen2020(10.0, 5.0, 2.8, 0.3), 4)
    1.1787
    """
    dp = check_range("dp_plus_R0", dp_plus_R0, 0.0,
                     reason="the extra pressure drop of a cell in Stokes flow is non-negative")
    d = _check_diameter(diameter_um)
    r0 = check_positive("R0_um", R0_um)
    ht = check_fraction("tube_hematocrit", tube_hematocrit)
    CHEN2020_RANGE.warn_outside("viscosity_single_file_chen2020", diameter_um=d)
    # In logarithms: (R/R0)^4 alone overflows for a small cell (lam = R0/R < 1e-77) although
    # dp+ ~ 16 lam^6 makes the product small; a zero factor gives exactly 0.
    with np.errstate(divide="ignore", over="ignore"):
        log_term = (math.log(3.0 / 32.0) + np.log(dp) + np.log(ht)
                    + 4.0 * (np.log(0.5 * d) - np.log(r0)))
        eta = 1.0 + np.exp(log_term)
    if not np.all(np.isfinite(eta)):
        raise InvalidParameterError(
            "dp_plus_R0", dp[~np.isfinite(np.broadcast_to(eta, np.shape(dp)))] if np.ndim(dp)
            else dp, "(3/32)(R/R0)^4 dp_plus_R0 H_T representable",
            "the relative viscosity overflows")
    return scalar_or_array(eta)
