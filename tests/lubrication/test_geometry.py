"""Geometry of confinement against the cubic, its closed-form inverse and Chen et al. 2020."""

import math

import numpy as np
import pytest
from hypothesis import given, strategies as st
from strategies import increasing_pairs

from lubrication import geometry as g
from lubrication.checks import CannotPassError, InvalidParameterError

NU = st.floats(0.05, 1.0)


def cubic(lam_c, nu):
    """Residual of Chen et al. 2020 eq. critic, written independently of the implementation."""
    return 2 * lam_c**3 - 3 * nu ** (-2 / 3) * lam_c**2 + 1


def largest_root(nu):
    """The largest real root of the cubic of Chen et al. eq. critic, by ``numpy.roots``."""
    roots = np.roots([2, -3 * nu ** (-2 / 3), 0, 1])
    return max(r.real for r in roots if abs(r.imag) < 1e-9)


def test_lam_c_is_a_root_of_the_cubic_to_machine_precision(report):
    nu = np.linspace(0.3, 1.0, 20001)
    residual = report.value("geometry.cubic_residual",
                            np.max(np.abs(cubic(g.critical_confinement(nu), nu))),
                            reference=0.0, tol=1e-12, source="the cubic, nu in [0.3, 1]")
    assert residual <= 1e-12


def test_lam_c_is_the_largest_root(report):
    errors = []
    for nu in (0.3, 0.6, 0.9, 0.999):
        largest = largest_root(nu)
        assert g.critical_confinement(nu) == pytest.approx(largest, rel=1e-12)
        errors.append(abs(g.critical_confinement(nu) / largest - 1))
    report.value("geometry.largest_root_error", max(errors), reference=0.0, tol=1e-12,
                 source="numpy.roots")


def test_nu_c_inverts_lam_c_on_a_grid(report):
    nu = np.linspace(0.3, 1.0, 2001)
    error = report.value("geometry.nu_c_error",
                         np.max(np.abs(g.critical_reduced_volume(g.critical_confinement(nu)) - nu)),
                         reference=0.0, tol=1e-12, source="eq. critic2")
    assert error <= 1e-12


@given(nu=NU)
def test_lam_c_relative_residual(nu):
    lam_c = g.critical_confinement(nu)
    assert abs(cubic(lam_c, nu)) <= 1e-14 * 2 * lam_c**3 + 1e-14
    assert lam_c >= 1.0


@given(nu=NU)
def test_nu_c_inverts_lam_c(nu):
    assert g.critical_reduced_volume(g.critical_confinement(nu)) == pytest.approx(nu, rel=1e-12, abs=1e-12)


@given(pair=increasing_pairs(0.05, 0.999, 1e-9))
def test_lam_c_decreases_with_nu(pair):
    a, b = pair
    assert g.critical_confinement(a) > g.critical_confinement(b)


@given(shape=st.sampled_from([(3,), (2, 4), (1, 5, 2)]))
def test_vectorised_shapes(shape):
    nu = np.full(shape, 0.7)
    for f in (g.critical_confinement, g.critical_length, g.reduced_area_excess):
        out = f(nu)
        assert out.shape == shape
        assert np.all(out == f(0.7))
    lam = np.linspace(0.5, 1.2, 4)[:, None]
    assert g.clearance(np.array([0.6, 0.8, 0.95]), lam).shape == (4, 3)


def test_sphere_limits():
    assert g.critical_confinement(1.0) == 1.0
    assert g.critical_length(1.0) == 2.0
    assert g.critical_reduced_volume(1.0) == 1.0


def test_chen_2020_statements(report):
    """Chen et al. 2020 §IV.A: nu = 0.6, 90 um^3 -> lam_c ~ 1.98, ell_c ~ 11, d_c ~ 2.8 um, L_c ~ 15.4 um."""
    chen = "Chen et al. 2020 §IV.A"
    R0 = report.value("geometry.R0_90fl", g.volume_radius(90.0), reference=2.78, tol="±0.005",
                      source=chen)
    assert R0 == pytest.approx(2.78, abs=0.005)           # "R0 ~ 2.8 um"
    assert report.value("geometry.lam_c_0.6", g.critical_confinement(0.6), reference=1.98,
                        tol="±0.005", source=chen) == pytest.approx(1.98, abs=0.005)
    assert report.value("geometry.ell_c_0.6", g.critical_length(0.6), reference=11.04,
                        tol="±0.005", source="physics-notes") == pytest.approx(11.04, abs=0.005)
    assert report.value("geometry.d_c_0.6", g.critical_diameter_um(0.6, R0), reference=2.8,
                        tol="±0.05", source=chen) == pytest.approx(2.8, abs=0.05)
    # Our 15.48 um versus the paper's 15.4 um: the paper rounds ell_c to 11 (11 * 1.40 = 15.4).
    L_c = report.value("geometry.L_c_0.6", g.critical_length_um(0.6, R0), reference=15.4,
                       tol="1 %", source=chen)
    assert L_c == pytest.approx(15.4, rel=0.01)
    report.value("geometry.L_c_0.6_excess_pct", 100 * (L_c / 15.4 - 1), reference=0.0,
                 tol="1 %", source=chen)


def test_default_red_cell_geometry(report):
    """The default red cell (90 fL, 135 um^2): lam_c by numpy.roots; d_c and L_c by the
    definition of the critical state, not by the formulas the code uses (d_c = 2 R0/lam_c,
    L_c = ell_c d_c/2): a cylinder of diameter d_c with hemispherical caps, of total length
    L_c, has the cell's volume and area."""
    nu, R0 = g.cell_from_volume_area(90.0, 135.0)
    lam_c = report.value("geometry.rbc_lam_c", g.critical_confinement(nu),
                         reference=largest_root(nu), tol="1e-12 rel", source="numpy.roots")
    assert lam_c == pytest.approx(largest_root(nu), rel=1e-12)
    a = report.value("geometry.rbc_d_c", g.critical_diameter_um(nu, R0), reference=None,
                     tol="1e-12 rel", source="spherocylinder of the cell's volume and area"
                     ) / 2
    L_c = report.value("geometry.rbc_L_c", g.critical_length_um(nu, R0), reference=None,
                       tol="1e-12 rel", source="spherocylinder of the cell's volume and area")
    assert math.pi * a**2 * (L_c - 2 * a) + 4 / 3 * math.pi * a**3 == pytest.approx(90.0,
                                                                                    rel=1e-12)
    assert 2 * math.pi * a * (L_c - 2 * a) + 4 * math.pi * a**2 == pytest.approx(135.0,
                                                                                 rel=1e-12)


def test_cell_geometry_against_direct_formulas(report):
    """nu = 6 sqrt(pi) V/A^(3/2) (the usual definition, e.g. Seifert 1997) and R0 the radius of
    the sphere of volume V, against the code's (R0/R_A)^3 and cube root."""
    nu, R0 = g.cell_from_volume_area(90.0, 135.0)
    assert 4 / 3 * math.pi * R0**3 == pytest.approx(90.0, rel=1e-14)
    ref = 6 * math.sqrt(math.pi) * 90.0 / 135.0**1.5
    assert report.value("geometry.rbc_nu", nu, reference=ref, tol="1e-13 rel",
                        source="6 sqrt(pi) V/A^(3/2)") == pytest.approx(ref, rel=1e-13)
    assert g.confinement_from_diameter(R0, 4.0) == pytest.approx(R0 / 2.0, rel=1e-15)


@given(R0=st.floats(0.1, 100.0))
def test_sphere_has_unit_reduced_volume(R0):
    volume = 4 / 3 * math.pi * R0**3
    area = 4 * math.pi * R0**2
    assert g.reduced_volume(volume, area) == pytest.approx(1.0, abs=1e-12)
    assert g.volume_radius(volume) == pytest.approx(R0, rel=1e-13)
    assert g.area_radius(area) == pytest.approx(R0, rel=1e-13)


def test_clearance_near_critical():
    lam_c = g.critical_confinement(0.6)
    assert g.clearance(0.6, 0.98 * lam_c) == pytest.approx(0.02, rel=1e-12)


@pytest.mark.parametrize("bad", [0.0, -0.1, 1.2, math.nan, math.inf])
def test_bad_reduced_volume(bad):
    with pytest.raises(InvalidParameterError, match="nu="):
        g.critical_confinement(bad)


@given(nu=st.floats(0.3, 0.99), excess=st.floats(0.0, 1.0))
def test_cannot_pass_at_or_beyond_critical(nu, excess):
    lam = g.critical_confinement(nu) * (1 + excess)
    with pytest.raises(CannotPassError, match="cannot pass"):
        g.clearance(nu, lam)


def test_error_messages_name_value_and_range():
    with pytest.raises(InvalidParameterError, match=r"area=50 .*area >= 97\.12"):
        g.reduced_volume(90.0, 50.0)
    with pytest.raises(InvalidParameterError, match=r"lam=0\.5 .*lam >= 1"):
        g.critical_reduced_volume(0.5)
    with pytest.raises(InvalidParameterError, match=r"diameter_um=-4"):
        g.confinement_from_diameter(2.8, -4.0)
    with pytest.raises(InvalidParameterError, match=r"volume_fl="):
        g.cell_from_volume_area("ninety", 135.0)


@given(volume=st.floats(10.0, 500.0), excess=st.floats(1.01, 2.0), diameter=st.floats(1.0, 20.0))
def test_physical_units_are_consistent(volume, excess, diameter):
    """d_c = 2 R0/lam_c, L_c = ell_c d_c/2, lam = 2 R0/d, and passing <=> d > d_c."""
    area = (36 * math.pi * volume**2) ** (1 / 3) * excess      # larger than the sphere's
    nu, R0 = g.cell_from_volume_area(volume, area)
    d_c = g.critical_diameter_um(nu, R0)
    assert d_c * g.critical_confinement(nu) / 2 == pytest.approx(R0, rel=1e-13)
    assert g.critical_length_um(nu, R0) == pytest.approx(g.critical_length(nu) * d_c / 2, rel=1e-13)
    lam = g.confinement_from_diameter(R0, diameter)
    assert (lam < g.critical_confinement(nu)) == (diameter > d_c)


# ------------------------------------------------------------------------------------------
# Huge and tiny inputs: finite, accurate results or an error naming the parameter.
# ------------------------------------------------------------------------------------------

def _ref_nu_c(lam: float) -> float:
    """(3 lam^2/(1 + 2 lam^3))^(3/2) in 60-digit decimal arithmetic (no overflow)."""
    from decimal import Decimal, getcontext
    getcontext().prec = 60
    x = Decimal(repr(lam))
    return float((3 * x * x / (1 + 2 * x**3)) ** Decimal("1.5"))


@pytest.mark.parametrize("lam", [1.0, 1.5, 7.0, 1e3, 1e50, 1e102, 1e104, 1e150, 1e200])
def test_critical_reduced_volume_is_finite_and_accurate_for_huge_lam(lam):
    assert g.critical_reduced_volume(lam) == pytest.approx(_ref_nu_c(lam), rel=1e-14)
    if lam >= 1e3:     # the asymptote (3/2)^(3/2) lam^(-3/2), relative error 3/(4 lam^3)
        assert g.critical_reduced_volume(lam) == pytest.approx(1.5**1.5 * lam**-1.5, rel=1e-8)


def test_critical_reduced_volume_beyond_the_double_range_underflows_to_zero():
    out = g.critical_reduced_volume(np.array([1e250, 1e308]))
    assert np.all(np.isfinite(out)) and np.all(out >= 0) and np.all(out < 1e-300)


@pytest.mark.parametrize("volume, area", [(1e300, 1e201), (1e-300, 1e-199), (1e-6, 1e-3)])
def test_reduced_volume_of_extreme_but_consistent_pairs(volume, area):
    """nu = 6 sqrt(pi) V A^(-3/2), computed here in logarithms."""
    ref = math.exp(math.log(6.0 * math.sqrt(math.pi)) + math.log(volume) - 1.5 * math.log(area))
    assert g.reduced_volume(volume, area) == pytest.approx(ref, rel=1e-13)


@pytest.mark.parametrize("volume, area", [(1e308, 135.0), (90.0, 1e308), (1e-320, 135.0),
                                          (90.0, 1e-320), (90.0, 1e6)])
def test_cell_outside_the_reduced_volume_range_names_the_area(volume, area):
    with pytest.raises(InvalidParameterError) as info:
        g.cell_from_volume_area(volume, area)
    assert info.value.name == "area_um2"
    assert "inf" not in str(info.value) and "nan" not in str(info.value)
    sphere = (36.0 * math.pi) ** (1 / 3) * volume ** (2 / 3)
    assert f"{sphere:.6g}" in str(info.value)


def test_volume_radius_of_the_largest_double():
    # 1e308 = 1e8 * 1e300, so R0 = (3e8/(4 pi))^(1/3) 1e100
    assert g.volume_radius(1e308) == pytest.approx((3e8 / (4 * math.pi)) ** (1 / 3) * 1e100,
                                                   rel=1e-14)


@pytest.mark.parametrize("call, name", [
    (lambda: g.confinement_from_diameter(2.78, 1e-320), "diameter_um"),
    (lambda: g.confinement_from_diameter(1e-300, 1e308), "diameter_um"),
    (lambda: g.critical_diameter_um(0.6, 1e308), "R0_um"),
    (lambda: g.critical_length_um(0.6, [1.0, 1e308]), "R0_um"),
    (lambda: g.critical_reduced_volume([2.0, math.nan]), "lam"),
    (lambda: g.critical_confinement([0.5, 1e-320]), "nu"),
])
def test_overflowing_results_raise_naming_the_parameter(call, name):
    with pytest.raises(InvalidParameterError) as info:
        call()
    assert info.value.name == name
