"""Tests of correlations.viscosity: apparent viscosity of blood in tubes and the Fåhræus effect.

The reference functions below are written straight from the printed formulas of the papers with
the math module and scalar loops; they share no code with the module under test.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, strategies as st
from scipy.optimize import brentq, minimize_scalar
from strategies import increasing_pairs

from correlations import viscosity as v
from correlations.plotting import plot_relative_viscosity
from correlations.viscosity import (
    FAHRAEUS_CONSTANTS, VISCOSITY_LAWS, discharge_hematocrit_fahraeus, eta_045_vitro_pries1992,
    relative_viscosity, shape_exponent_pries1992, tube_hematocrit_fahraeus,
    viscosity_single_file_chen2020, viscosity_vitro_pries1992, viscosity_vivo_pries1994,
    viscosity_vivo_pries2005,
)
from lubrication.checks import InvalidParameterError, OutOfRangeWarning

# ------------------------------------------------------------------------------------------
# Independent reference: printed formulas, math module, scalars.
# ------------------------------------------------------------------------------------------


def ref_eta045_vitro(D):
    return 220 * math.exp(-1.3 * D) + 3.2 - 2.44 * math.exp(-0.06 * D**0.645)


def ref_eta045_vivo(D):
    return 6 * math.exp(-0.085 * D) + 3.2 - 2.44 * math.exp(-0.06 * D**0.645)


def ref_C(D):
    return (0.8 + math.exp(-0.075 * D)) * (-1 + 1 / (1 + 10**-11 * D**12)) \
        + 1 / (1 + 10**-11 * D**12)


def ref_vitro(D, HD):
    C = ref_C(D)
    return 1 + (ref_eta045_vitro(D) - 1) * ((1 - HD)**C - 1) / ((1 - 0.45)**C - 1)


def ref_vivo1994(D, HD, W=1.1):
    C = ref_C(D)
    f = (D / (D - W))**2
    return (1 + (ref_eta045_vivo(D) - 1) * ((1 - HD)**C - 1) / ((1 - 0.45)**C - 1) * f) * f


def ref_vivo2005(D, HD):
    D_off, D_crit, D_50 = 2.4, 10.5, 100.0
    E_amp, E_width, E_peak, E_HD, W_max = 1.1, 0.03, 0.6, 1.18, 2.6
    W_as = 0.0 if D <= D_off else W_max * (D - D_off) / (D + D_50 - 2 * D_off)
    if D <= D_off:
        W_peak = 0.0
    elif D <= D_crit:
        W_peak = E_amp * (D - D_off) / (D_crit - D_off)
    else:
        W_peak = E_amp * math.exp(-E_width * (D - D_crit))
    W_ph = W_as + W_peak * E_peak
    W_eff = W_as + W_peak * (1 + HD * E_HD)
    D_ph, D_eff = D - 2 * W_ph, D - 2 * W_eff
    return ref_vitro(D_ph, HD) * (D / D_eff)**4


def ref_x(D, a, b):
    return 1 + 1.7 * math.exp(-a * D) - 0.6 * math.exp(-b * D)


def ref_tube_hematocrit(D, HD, a, b):
    return HD * (HD + (1 - HD) * ref_x(D, a, b))


def ref_discharge_hematocrit(D, HT, a, b):
    # the usual printed root, singular at x = 1: only used where |1 - x| is not small
    x = ref_x(D, a, b)
    return -x / (2 - 2 * x) + math.sqrt((x / (2 - 2 * x))**2 + HT / (1 - x))


# Grid away from C = 0 (D* ~ 8.05 µm), where the printed ratio is ill-conditioned.
DIAMETERS = [3.5, 4.0, 5.0, 6.0, 7.0, 10.0, 15.0, 20.0, 30.0, 50.0, 100.0, 300.0, 1000.0, 1900.0]
HEMATOCRITS = [0.0, 0.05, 0.2, 0.3, 0.45, 0.6, 0.8, 0.9]
RTOL = 1e-12


def assert_rel(actual, expected, rtol=RTOL):
    assert abs(actual - expected) <= rtol * abs(expected), f"{actual=}, {expected=}"


@pytest.mark.parametrize("D", DIAMETERS)
def test_in_vitro_law_matches_printed_formula(D):
    assert_rel(eta_045_vitro_pries1992(D), ref_eta045_vitro(D))
    assert_rel(shape_exponent_pries1992(D), ref_C(D))
    for HD in HEMATOCRITS:
        assert_rel(viscosity_vitro_pries1992(D, HD), ref_vitro(D, HD))


@pytest.mark.parametrize("D", DIAMETERS)
def test_in_vivo_laws_match_printed_formulas(D):
    for HD in HEMATOCRITS:
        assert_rel(viscosity_vivo_pries1994(D, HD), ref_vivo1994(D, HD))
        assert_rel(viscosity_vivo_pries2005(D, HD), ref_vivo2005(D, HD))
        for law, ref in (("pries1992", ref_vitro), ("pries1994", ref_vivo1994),
                         ("pries2005", ref_vivo2005)):
            assert_rel(relative_viscosity(D, HD, law=law), ref(D, HD))


def test_largest_deviation_from_the_printed_formulas_and_sample_values(report):
    """All three laws on the grid at once (the largest relative deviation, reported), and the
    sample values of the report (H_D = 0.45, d = 4, 6, 8, 10 µm) against the printed formulas."""
    refs = {"pries1992": ref_vitro, "pries1994": ref_vivo1994, "pries2005": ref_vivo2005}
    worst = max(abs(relative_viscosity(D, HD, law=law) / ref(D, HD) - 1)
                for law, ref in refs.items() for D in DIAMETERS for HD in HEMATOCRITS)
    assert report.value("visc.printed_worst", worst, reference=0.0, tol=RTOL,
                        source="printed formulas, plain Python") <= RTOL
    for law, ref in refs.items():
        for D in (4.0, 6.0, 8.0, 10.0):
            eta = report.value(f"visc.sample_{law}_{D:g}", relative_viscosity(D, 0.45, law=law),
                               reference=ref(D, 0.45), tol=f"{RTOL:g} rel",
                               source="printed formula")
            assert_rel(eta, ref(D, 0.45))


@pytest.mark.parametrize("constants", sorted(FAHRAEUS_CONSTANTS))
def test_fahraeus_matches_printed_formulas(constants):
    a, b = FAHRAEUS_CONSTANTS[constants]
    for D in [4.0, 5.0, 10.0, 20.0, 50.0, 100.0, 300.0]:   # |1 - x| >= 0.02 here
        for H in HEMATOCRITS[1:]:
            assert_rel(tube_hematocrit_fahraeus(D, H, constants), ref_tube_hematocrit(D, H, a, b))
            # the printed root cancels ~2 digits here; 1e-12 still holds
            assert_rel(discharge_hematocrit_fahraeus(D, H, constants),
                       ref_discharge_hematocrit(D, H, a, b))


def test_single_file_matches_printed_formula_and_chen_coefficient(report):
    for dp, d, R0, HT in [(1.0, 4.0, 2.8, 0.3), (250.0, 3.0, 2.78, 0.45), (1e-3, 7.5, 3.0, 0.1)]:
        assert_rel(viscosity_single_file_chen2020(dp, d, R0, HT),
                   1 + 3 / 32 * (d / 2 / R0)**4 * dp * HT)
    # Chen et al. 2020 §Visco prints K_T = 9.53e-5 d^4 (Δp+R0/ηU) for R0 = 2.8 µm, d in µm.
    coefficient = viscosity_single_file_chen2020(1.0, 1.0, 2.8, 0.5) / 0.5 - 1 / 0.5
    report.value("visc.chen_coefficient", coefficient, reference=9.53e-5, tol="3 digits",
                 source="Chen et al. 2020 §Visco: (3/32)/5.6^4")
    assert f"{coefficient:.3g}" == "9.53e-05"


def test_single_file_warns_above_8_um_and_rejects_negative_pressure_drop():
    with pytest.warns(OutOfRangeWarning, match="diameter_um"):
        viscosity_single_file_chen2020(1.0, 9.0, 2.8, 0.3)
    with pytest.raises(InvalidParameterError, match="dp_plus_R0"):
        viscosity_single_file_chen2020(-1.0, 5.0, 2.8, 0.3)
    with pytest.raises(InvalidParameterError, match="R0_um"):
        viscosity_single_file_chen2020(1.0, 5.0, 0.0, 0.3)


# ------------------------------------------------------------------------------------------
# Limits and shape of the in vitro law
# ------------------------------------------------------------------------------------------

def test_in_vitro_limits_at_zero_and_reference_hematocrit(report):
    """At H_D = 0.45 the law is 1 + (eta_0.45 - 1) x 1: two roundings, within 4 eps."""
    d = np.geomspace(3.3, 1978.0, 2001)
    assert np.all(viscosity_vitro_pries1992(d, 0.0) == 1.0)
    report.value("visc.limit_045", np.max(np.abs(viscosity_vitro_pries1992(d, 0.45)
                                                 / eta_045_vitro_pries1992(d) - 1)),
                 reference=0.0, tol="4 eps rel", source="Pries 1992 definition")
    np.testing.assert_allclose(viscosity_vitro_pries1992(d, 0.45), eta_045_vitro_pries1992(d),
                               rtol=4 * np.finfo(float).eps, atol=0)


def test_in_vitro_tends_to_3_2_for_wide_tubes(report):
    with pytest.warns(OutOfRangeWarning, match="diameter_um"):
        eta = report.value("visc.wide_tube", viscosity_vitro_pries1992(1e4, 0.45), reference=3.2,
                           tol="±1e-3", source="Pries 1992")
    assert abs(eta - 3.2) < 1e-3


def test_in_vitro_minimum_lies_between_5_and_7_um(report):
    """Pries & Secomb 2003 review: the in vitro viscosity minimum lies at D = 5-7 µm."""
    res = minimize_scalar(lambda d: viscosity_vitro_pries1992(d, 0.45), bounds=(3.3, 30.0),
                          method="bounded", options={"xatol": 1e-6})
    report.value("visc.minimum_d", res.x, reference="5–7 µm", tol="inside (5, 7)",
                 source="Pries & Secomb 2003")
    eta_min = report.value("visc.minimum_eta", res.fun, reference=ref_vitro(res.x, 0.45),
                           tol=f"{RTOL:g} rel", source="printed formula at the minimum")
    assert_rel(eta_min, ref_vitro(res.x, 0.45))
    assert 5.0 < res.x < 7.0, res


def _root_of_C():
    return brentq(lambda d: shape_exponent_pries1992(d), 7.0, 9.0, xtol=1e-14)


def test_shape_exponent_zero_is_near_8_05_um(report):
    assert abs(report.value("visc.d_star", _root_of_C(), reference=8.05, tol="±0.01",
                            source="brentq on C(D)") - 8.05) < 0.01


@pytest.mark.parametrize("law", ["pries1992", "pries1994"])
def test_exact_continuity_across_zero_of_shape_exponent(law, report):
    """At D*, D* +- 1e-9, D* +- 1e-6 the value agrees with 50-digit arithmetic to ROUNDING, the
    rounding of its ~10 elementary operations, each within 4 ulp (numpy's accuracy tests,
    numpy/_core/tests/test_umath_accuracy.py, hold its SIMD float64 exp and log, which differ
    between CPUs, to a few ulp; libm's are within 1): 40 eps. No jump at D*: the second
    difference across it is within four times that."""
    mp = pytest.importorskip("mpmath")
    mp.mp.dps = 50
    f = mp.mpf

    def high_precision(D, HD):
        D, HD = f(D), f(HD)
        q = f("1e-11") * D**12
        C = (f("0.8") + mp.exp(f("-0.075") * D)) * (-1 + 1 / (1 + q)) + 1 / (1 + q)
        ratio = mp.log(1 - HD) / mp.log(f("0.55")) if C == 0 else \
            mp.expm1(C * mp.log(1 - HD)) / mp.expm1(C * mp.log(f("0.55")))
        if law == "pries1992":
            eta45 = 220 * mp.exp(f("-1.3") * D) + f("3.2") \
                - f("2.44") * mp.exp(f("-0.06") * D**f("0.645"))
            return 1 + (eta45 - 1) * ratio
        eta45 = 6 * mp.exp(f("-0.085") * D) + f("3.2") \
            - f("2.44") * mp.exp(f("-0.06") * D**f("0.645"))
        g = (D / (D - f("1.1")))**2
        return (1 + (eta45 - 1) * ratio * g) * g

    rounding = 40 * np.finfo(float).eps
    d_star = _root_of_C()
    offsets = [0.0, 1e-9, -1e-9, 1e-6, -1e-6]
    worst = 0.0
    for HD in [0.0, 0.1, 0.3, 0.45, 0.6, 0.8, 0.95, 0.999]:
        values = []
        for off in offsets:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", OutOfRangeWarning)   # H_D > 0.9 extrapolates
                got = relative_viscosity(d_star + off, HD, law=law)
            want = high_precision(d_star + off, HD)
            assert abs(got - float(want)) <= rounding * float(want), (HD, off, got, want)
            worst = max(worst, abs(got - float(want)) / float(want))
            values.append(got)
        # no jump at D*: the steps D* - 1e-9 -> D* -> D* + 1e-9 are equal up to the curvature
        # term (|eta''| 1e-18, negligible) and round-off
        assert abs((values[1] - values[0]) - (values[0] - values[2])) <= 4 * rounding * values[0]
    report.value(f"visc.continuity_{law}", worst, reference=0.0, tol="40 eps rel",
                 source="50-digit mpmath")
    # the same points as one array: no RuntimeWarning (0/0) leaks, result finite
    eta = relative_viscosity(d_star + np.array(offsets)[:, None], np.array([0.1, 0.9]), law=law)
    assert eta.shape == (5, 2) and np.all(np.isfinite(eta))


# ------------------------------------------------------------------------------------------
# Published values
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("HD", [0.4, 0.45])
def test_in_vivo_over_in_vitro_factor_at_10_um(HD, report):
    """Pries et al. 1994, Circ. Res. 75:904, abstract: "flow resistance in 10-µm microvessels at
    normal hematocrit is found to exceed that of a corresponding glass tube by a factor of ≈4".
    The paper rounds to one figure; the fitted laws give 3.95 (H_D = 0.4) and 4.42 (0.45)."""
    factor = report.value(f"visc.vivo_over_vitro_{HD}",
                          viscosity_vivo_pries1994(10.0, HD) / viscosity_vitro_pries1992(10.0, HD),
                          reference=4.0, tol="±0.5", source="Pries et al. 1994 abstract")
    assert abs(factor - 4.0) < 0.5, factor


# ------------------------------------------------------------------------------------------
# In vivo laws: domain
# ------------------------------------------------------------------------------------------

def test_pries1994_diverges_at_W_and_rejects_smaller_diameters():
    for D in [1.1, 1.0, 0.5]:
        with pytest.raises(InvalidParameterError, match="diameter_um"):
            viscosity_vivo_pries1994(D, 0.45)


def test_pries2005_reduces_to_in_vitro_below_D_off():
    with pytest.warns(OutOfRangeWarning):
        for D in [1.0, 2.0, 2.4]:
            assert viscosity_vivo_pries2005(D, 0.45) == viscosity_vitro_pries1992(D, 0.45)


def test_pries2005_effective_diameter_stays_positive():
    d = np.geomspace(1e-3, 1e5, 20001)[:, None]
    h = np.linspace(0.0, np.nextafter(1.0, 0.0), 51)
    w_ph, w_eff = v._esl_widths(d, h)
    assert np.all(d - 2 * w_eff > 0.5 * d) and np.all(w_ph <= w_eff)


def test_pries2005_guard_names_the_diameter(monkeypatch):
    monkeypatch.setitem(v.PRIES2005_ESL, "E_amp", 10.0)   # an ESL thicker than the vessel
    with pytest.raises(InvalidParameterError, match="diameter_um.*W_eff"):
        viscosity_vivo_pries2005(10.0, 0.45)


# ------------------------------------------------------------------------------------------
# Fåhræus effect
# ------------------------------------------------------------------------------------------

def _x_equals_one_diameter(constants):
    a, b = FAHRAEUS_CONSTANTS[constants]
    return brentq(lambda d: ref_x(d, a, b) - 1.0, 1.0, 5.0, xtol=1e-14)


@pytest.mark.parametrize("constants", sorted(FAHRAEUS_CONSTANTS))
def test_fahraeus_round_trip_including_x_equal_one(constants, report):
    d_one = report.value(f"visc.x_one_{constants}", _x_equals_one_diameter(constants),
                         reference="2.6–3.1 µm", tol="inside (2.5, 3.1)", source="physics notes")
    assert 2.5 < d_one < 3.1   # physics notes: x = 1 at D ~ 2.6-3.1 µm
    # x = 1 at d_one (the lower end of the domain: below it H_T > H_D), and x == 1.0 exactly in
    # floating point for D >= ~1e4 (both outside the fitted range, hence the warnings); the grid
    # approaches d_one closely from above.
    special = d_one + np.array([1e-12, 1e-8, 1e-4])
    d = np.concatenate([special, np.geomspace(3.3, 1978.0, 60), [1e4, 1e6]])[:, None]
    hd = np.array([0.0, 1e-6, 0.01, 0.2, 0.45, 0.7, 0.9, 0.99])
    with pytest.warns(OutOfRangeWarning):
        ht = tube_hematocrit_fahraeus(d, hd, constants)
    with pytest.warns(OutOfRangeWarning):
        back = discharge_hematocrit_fahraeus(d, ht, constants)
    np.testing.assert_allclose(back, np.broadcast_to(hd, back.shape), rtol=1e-12, atol=0)
    assert np.all(np.isfinite(back))
    nonzero = hd > 0
    report.value(f"visc.round_trip_{constants}",
                 np.max(np.abs(back[:, nonzero] / hd[nonzero] - 1)), reference=0.0,
                 tol="1e-12 rel", source="identity")


@pytest.mark.parametrize("constants", sorted(FAHRAEUS_CONSTANTS))
def test_fahraeus_refuses_diameters_where_the_fit_gives_HT_above_HD(constants):
    """Below x = 1 (D* = ln(1.7/0.6)/(a - b), found here by root finding) the fit would give
    H_T > H_D, impossible in single file (H_T/H_D = U/V <= 1): an error naming the diameter and
    the bound, for the forward, inverse and ratio functions, arrays included."""
    d_one = _x_equals_one_diameter(constants)
    assert v.FAHRAEUS_MIN_DIAMETER_UM[constants] == pytest.approx(d_one, rel=1e-13)
    a, b = FAHRAEUS_CONSTANTS[constants]
    assert ref_x(d_one * (1 - 1e-6), a, b) > 1.0          # the reason for the bound
    for f in (tube_hematocrit_fahraeus, discharge_hematocrit_fahraeus,
              v.hematocrit_ratio_fahraeus):
        for d in (v.FAHRAEUS_MIN_DIAMETER_UM[constants], d_one * (1 - 1e-9), 2.0, 1e-300,
                  np.array([10.0, 2.0])):
            with pytest.raises(InvalidParameterError, match="diameter_um") as info:
                f(d, 0.45, constants)
            assert f"{d_one:.4g}" in str(info.value) and "H_T" in str(info.value)


@given(D=st.floats(3.07, 1e6), HD=st.floats(0.0, 0.9), constants=st.sampled_from(sorted(FAHRAEUS_CONSTANTS)))
def test_fahraeus_tube_hematocrit_never_exceeds_discharge(D, HD, constants):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutOfRangeWarning)
        ht = tube_hematocrit_fahraeus(D, HD, constants)
        ratio = v.hematocrit_ratio_fahraeus(D, HD, constants)
        back = discharge_hematocrit_fahraeus(D, HD, constants)
    a, b = FAHRAEUS_CONSTANTS[constants]
    assert ht <= HD and 0.0 < ratio <= 1.0 and back >= HD
    assert ratio == pytest.approx(HD + (1.0 - HD) * ref_x(D, a, b), rel=1e-14)


@pytest.mark.parametrize("constants", sorted(FAHRAEUS_CONSTANTS))
def test_fahraeus_tube_hematocrit_below_discharge_in_5_to_500_um(constants):
    d = np.geomspace(5.0, 500.0, 400)[:, None]
    hd = np.linspace(0.01, 0.9, 40)
    ratio = tube_hematocrit_fahraeus(d, hd, constants) / hd
    assert np.all(ratio < 1.0)


def test_fahraeus_unknown_constants_lists_choices():
    with pytest.raises(InvalidParameterError, match="constants.*pries1990"):
        tube_hematocrit_fahraeus(10.0, 0.45, constants="pries2005")


# ------------------------------------------------------------------------------------------
# Return types, broadcasting, properties (Hypothesis)
# ------------------------------------------------------------------------------------------

def test_scalar_in_float_out_array_in_array_out():
    assert type(viscosity_vitro_pries1992(10.0, 0.45)) is float
    assert type(relative_viscosity(np.float64(10.0), 0.3, "pries2005")) is float
    out = viscosity_vivo_pries1994([10.0], 0.45)
    assert isinstance(out, np.ndarray) and out.shape == (1,)


diam = st.floats(3.3, 1978.0)
hemat = st.floats(0.0, 0.9)


@given(n=st.integers(1, 5), m=st.integers(1, 5), law=st.sampled_from(VISCOSITY_LAWS),
       data=st.data())
def test_broadcasting_shapes(n, m, law, data):
    d = np.array(data.draw(st.lists(diam, min_size=n, max_size=n)))[:, None]
    h = np.array(data.draw(st.lists(hemat, min_size=m, max_size=m)))
    assert relative_viscosity(d, h, law=law).shape == (n, m)
    assert relative_viscosity(d[:, 0], h[0], law=law).shape == (n,)
    assert tube_hematocrit_fahraeus(d, h).shape == (n, m)
    assert discharge_hematocrit_fahraeus(d, h).shape == (n, m)


@given(D=diam, pair=increasing_pairs(0.0, 0.9, 1e-9), law=st.sampled_from(VISCOSITY_LAWS))
def test_viscosity_increases_with_hematocrit(D, pair, law):
    lo, hi = pair
    assert relative_viscosity(D, hi, law=law) > relative_viscosity(D, lo, law=law)


@given(D=diam, HD=hemat, constants=st.sampled_from(sorted(FAHRAEUS_CONSTANTS)))
def test_fahraeus_round_trip_property(D, HD, constants):
    back = discharge_hematocrit_fahraeus(D, tube_hematocrit_fahraeus(D, HD, constants), constants)
    assert abs(back - HD) <= 1e-12 * HD + 1e-300


bad_number = st.sampled_from([math.nan, math.inf, -math.inf]) | st.floats(max_value=0.0)
bad_fraction = (st.sampled_from([math.nan, math.inf, -math.inf, 1.0, 45.0])
                | st.floats(min_value=1.0) | st.floats(max_value=-1e-300))


@given(D=bad_number, law=st.sampled_from(VISCOSITY_LAWS))
def test_bad_diameter_raises(D, law):
    with pytest.raises(InvalidParameterError, match="diameter_um"):
        relative_viscosity(D, 0.45, law=law)
    with pytest.raises(InvalidParameterError, match="diameter_um"):
        relative_viscosity(np.array([10.0, D]), 0.45, law=law)
    with pytest.raises(InvalidParameterError, match="diameter_um"):
        tube_hematocrit_fahraeus(D, 0.45)
    with pytest.raises(InvalidParameterError, match="diameter_um"):
        viscosity_single_file_chen2020(1.0, D, 2.8, 0.3)


@given(H=bad_fraction, law=st.sampled_from(VISCOSITY_LAWS))
def test_bad_hematocrit_raises(H, law):
    with pytest.raises(InvalidParameterError, match="discharge_hematocrit"):
        relative_viscosity(10.0, H, law=law)
    with pytest.raises(InvalidParameterError, match="discharge_hematocrit"):
        tube_hematocrit_fahraeus(10.0, [0.3, H])
    with pytest.raises(InvalidParameterError, match="tube_hematocrit"):
        discharge_hematocrit_fahraeus(10.0, H)
    with pytest.raises(InvalidParameterError, match="tube_hematocrit"):
        viscosity_single_file_chen2020(1.0, 5.0, 2.8, H)


@given(law=st.text(max_size=12).filter(lambda s: s not in VISCOSITY_LAWS))
def test_unknown_law_raises_and_names_choices(law):
    with pytest.raises(InvalidParameterError, match="law=.*'pries1992', 'pries1994', 'pries2005'"):
        relative_viscosity(10.0, 0.45, law=law)


def test_percentage_hematocrit_gets_a_hint():
    with pytest.raises(InvalidParameterError, match="fraction, not a percentage"):
        viscosity_vitro_pries1992(10.0, 45.0)


# ------------------------------------------------------------------------------------------
# Plot
# ------------------------------------------------------------------------------------------

def test_plot_has_one_line_per_law_and_hematocrit():
    with warnings.catch_warnings():
        warnings.simplefilter("error")   # default grid is inside every validity range
        ax = plot_relative_viscosity()
    assert len(ax.get_lines()) == len(VISCOSITY_LAWS) * 2
    assert ax.get_xscale() == "log"
    assert ax.get_xlabel() == "d [µm]" and ax.get_ylabel() == "η_rel [-]"
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "pries2005, H_D = 0.45" in labels

    ax2 = plot_relative_viscosity(np.linspace(4.0, 40.0, 7), hematocrits=(0.3,),
                                  laws=("pries1994",), ax=ax)
    assert ax2 is ax and len(ax.get_lines()) == len(VISCOSITY_LAWS) * 2 + 1
