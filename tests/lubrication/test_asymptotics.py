"""Small-object and near-critical asymptotics against independent references.

References used here, none of them the implementation:
* the algebra of Chen et al. 2020 (eq. dpa_v from eq. small1/small2; X = ell_c/2);
* the exact rigid-cylinder result of the local-flow model (physics notes §3);
* a thin-film (Reynolds) lubrication model of a rigid sphere near contact with the wall, solved
  numerically below, for the nu = 1 limit of eq. asmyp1/asmyp2.
"""

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, strategies as st
from scipy.integrate import quad
from scipy.optimize import brentq
from strategies import increasing_pairs

from correlations.pressure import dp_plus_small_sphere_coupling
from lubrication import asymptotics as a
from lubrication.checks import CannotPassError, InvalidParameterError, OutOfRangeWarning
from lubrication.geometry import critical_confinement, critical_length

SMALL = (a.speed_small_sphere, a.dp_plus_small_sphere, a.speed_small_drop, a.dp_plus_small_drop)
NEAR = (a.speed_near_critical, a.dp_plus_near_critical)


class _NoWarnings:
    """Turn every warning into an error inside the block."""

    def __enter__(self):
        self._cm = warnings.catch_warnings()
        self._cm.__enter__()
        warnings.simplefilter("error")

    def __exit__(self, *exc):
        return self._cm.__exit__(*exc)


# --------------------------------------------------------------------------- small objects
def test_small_sphere_values_at_lam_half():
    """Hand values: 2 - (4/3)/4 = 5/3 and 16/64 = 1/4."""
    assert a.speed_small_sphere(0.5) == pytest.approx(5 / 3, rel=1e-15)
    assert a.dp_plus_small_sphere(0.5) == pytest.approx(0.25, rel=1e-15)
    assert a.speed_small_drop(0.5) == pytest.approx(1.8, rel=1e-15)
    assert a.dp_plus_small_drop(0.5) == pytest.approx(0.075, rel=1e-14)


@given(lam=st.floats(1e-3, 0.5))
def test_eliminating_lam_reproduces_eq_dpa_v_exactly(lam):
    """eq. dpa_v is eq. small2 with lam taken from eq. small1: exact for the truncated laws."""
    with _NoWarnings():
        direct = a.dp_plus_small_sphere(lam)
        coupled = dp_plus_small_sphere_coupling(a.speed_small_sphere(lam))
    assert coupled == pytest.approx(direct, rel=1e-9)   # (2 - V/U) loses ~lam^-2 digits


def test_remainder_of_eq_dpa_v_scales_as_lam9_for_a_lam5_speed_correction():
    """A speed remainder c lam^5 (Faxen) shifts eq. dpa_v by 36 c lam^9: observed order 9.

    (With the remainder O(lam^3) that Chen et al. write in eq. small1, the shift would be
    O(lam^7); their "O(lam^3)" remainder of eq. dpa_v is a loose bound either way.)
    """
    lam = np.array([0.04, 0.02, 0.01])
    c = 0.7   # any O(1) coefficient
    speed = a.speed_small_sphere(lam) + c * lam**5
    residual = np.abs(dp_plus_small_sphere_coupling(speed) - a.dp_plus_small_sphere(lam))
    order = np.log(residual[:-1] / residual[1:]) / np.log(lam[:-1] / lam[1:])
    assert np.all(np.abs(order - 9) < 0.05), order
    assert residual[-1] / lam[-1] ** 9 == pytest.approx(36 * c, rel=1e-2)


def test_drop_is_between_the_unbounded_fluid_and_the_rigid_sphere():
    lam = np.linspace(0.05, 0.5, 10)
    assert np.all(a.speed_small_drop(lam) > a.speed_small_sphere(lam))
    assert np.all(a.dp_plus_small_drop(lam) < a.dp_plus_small_sphere(lam))
    # Faxen law of a drop, V = u(0) + k a^2 lap(u)/(2(3k + 2)), lap(u) = -8U/R^2, at k = 1
    k = 1.0
    assert np.allclose(a.speed_small_drop(lam), 2 - 8 * k / (2 * (3 * k + 2)) * lam**2, rtol=1e-15)


# --------------------------------------------------------------------------- near critical
@pytest.mark.parametrize("nu, slope", [(0.9, 1.07), (0.6, 1.02)])
def test_slope_of_eq_asmyp1_matches_the_physics_notes(nu, slope, report):
    assert report.value(f"asym.slope_notes_{nu}", a.speed_slope_near_critical(nu),
                        reference=slope, tol="±5e-3", source="physics-notes"
                        ) == pytest.approx(slope, abs=5e-3)


@pytest.mark.parametrize("nu", [0.6, 0.7, 0.8, 0.9, 0.98, 1.0])
def test_slope_of_eq_asmyp1_is_its_closed_form(nu, report):
    """d(V/U)/d delta = (4/3)(3X - 2)/(4X - 3), X = lam_c^2 nu^(-2/3) (Chen et al. eq. asmyp1)."""
    X = critical_confinement(nu) ** 2 * nu ** (-2 / 3)
    closed = 4 / 3 * (3 * X - 2) / (4 * X - 3)
    assert report.value(f"asym.slope_{nu}", a.speed_slope_near_critical(nu), reference=closed,
                        tol="1e-12 rel", source="Chen et al. 2020 eq. asmyp1"
                        ) == pytest.approx(closed, rel=1e-12)


@given(nu=st.floats(0.3, 1.0), frac=st.floats(0.9001, 0.9999))
def test_eq_asmyp1_is_linear_in_delta_with_the_slope(nu, frac):
    lam = frac * critical_confinement(nu)
    delta = 1 - frac
    assert (a.speed_near_critical(nu, lam) - 1) / delta == pytest.approx(
        a.speed_slope_near_critical(nu), rel=1e-9)


@given(nu=st.floats(0.3, 1.0))
def test_X_minus_1_is_half_the_cylinder_length(nu):
    """X = lam_c^2 nu^(-2/3) = ell_c/2 (Chen eq. lc), so X - 1 = (ell_c - 2)/2 = ell_0/2."""
    lam_c = critical_confinement(nu)
    X = lam_c**2 * nu ** (-2 / 3)
    assert X - 1 == pytest.approx(critical_length(nu) / 2 - 1, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("nu", [0.6, 0.8, 0.95])
def test_leading_term_of_eq_asmyp2_is_4_lam_X_minus_1_over_delta(nu):
    """delta * dp_plus / lam -> 4 (X - 1) with an error of order delta^(1/2) (the cap term)."""
    lam_c = critical_confinement(nu)
    X = critical_length(nu) / 2
    delta = np.array([1e-2, 1e-3, 1e-4])
    lam = lam_c * (1 - delta)
    with _NoWarnings():
        scaled = a.dp_plus_near_critical(nu, lam) * delta / lam
    err = np.abs(scaled / (4 * (X - 1)) - 1)
    order = np.log(err[:-1] / err[1:]) / np.log(delta[:-1] / delta[1:])
    assert np.allclose(order, 0.5, atol=1e-6), order


@pytest.mark.parametrize("nu", [0.6, 0.8])
def test_eq_asmyp2_is_a_rigid_cylinder_of_length_ell_0_plus_the_caps(nu):
    """Rigid cylinder radius kR, length ell_0 R: dp+ = 4 eta V L k^4/(R^2(1 - k^2)),
    V/U = 2/(1 + k^2) (physics notes §3). With k = 1 - delta it carries the whole 1/delta term
    of eq. asmyp2; what is left, times delta^(1/2)/lam, is the caps' coefficient
    4 sqrt(2) pi/(4X - 3), approached with an error O(delta^(1/2))."""
    lam_c = critical_confinement(nu)
    ell_0 = critical_length(nu) - 2
    X = critical_length(nu) / 2
    delta = np.array([1e-6, 1e-8])
    lam = lam_c * (1 - delta)
    k = 1 - delta
    cylinder = lam * 4 * ell_0 * k**4 / (1 - k**2) * 2 / (1 + k**2)   # dp+ R0/(eta U)
    caps = (a.dp_plus_near_critical(nu, lam) - cylinder) * np.sqrt(delta) / lam
    err = np.abs(caps / (4 * math.sqrt(2) * math.pi / (4 * X - 3)) - 1)
    assert err[1] < 0.01 and err[1] < err[0] / 5, err


def _rigid_sphere_near_contact(eps):
    """Thin-film (Reynolds) model of a free rigid sphere of radius (1 - eps)R on the axis.

    Sphere frame, lengths /R, velocities /U; the wall moves at -V, the gap carries the flux
    pi(U - V). Per unit circumference the Couette-Poiseuille flux -V h/2 - h^3 p'/12 equals
    (U - V)/2, so p' = -6[(U - V) + V h]/h^3; the membrane shear traction is -V/h - p' h/2.
    The force balance (pressure on the projected area plus shear) fixes V; the pressure drop
    across the sphere minus the Poiseuille drop over its length is dp+ R/(eta U).
    """
    rad = 1 - eps

    # x = rad sin(t) removes the square-root end point: h = 1 - rad cos(t), dx = rad cos(t) dt.
    def h(t):   # 1 - rad cos(t) without cancellation
        return eps + 2 * rad * math.sin(t / 2) ** 2

    def dpdx(t, s):
        hh = h(t)
        return -6 * (-s + (1 + s) * hh) / hh**3

    def integral(f):   # even integrand over x in (-rad, rad); the gap has width ~ sqrt(eps)
        c = min(50 * math.sqrt(eps), 0.5)
        kw = dict(limit=400, epsabs=0, epsrel=1e-8)
        g = lambda t: f(t) * rad * math.cos(t)
        return 2 * (quad(g, 0, c, **kw)[0] + quad(g, c, math.pi / 2, **kw)[0])

    def force(s):
        v = 1 + s
        pressure = integral(lambda t: -(1 - h(t)) ** 2 * dpdx(t, s))
        shear = 2 * integral(lambda t: (1 - h(t)) * (-v / h(t) - dpdx(t, s) * h(t) / 2))
        return pressure + shear

    s = brentq(force, 0.5 * eps, 3 * eps, xtol=1e-16, rtol=1e-14)
    dp_plus = -integral(lambda t: dpdx(t, s)) - 8 * 2 * rad
    return 1 + s, dp_plus


def test_nu_1_limits_are_the_rigid_sphere_near_contact(report):
    """At nu = 1: lam_c = 1, X = 1, slope 4/3 and dp+ = 4 sqrt(2) pi lam delta^(-1/2).

    The thin-film model of a rigid sphere with gap eps R gives V/U -> 1 + 4 eps/3 and
    dp+ R/(eta U) -> 4 sqrt(2) pi eps^(-1/2), i.e. eq. asmyp1/asmyp2 at nu = 1 (R0 = a = lam R).
    """
    assert critical_confinement(1.0) == 1.0
    assert a.speed_slope_near_critical(1.0) == pytest.approx(4 / 3, rel=1e-14)
    eps = np.array([1e-3, 1e-4, 1e-5])
    model = np.array([_rigid_sphere_near_contact(e) for e in eps])
    lam = 1 - eps
    law_speed = a.speed_near_critical(1.0, lam)
    law_dp_R = a.dp_plus_near_critical(1.0, lam) / lam   # dp+ R/(eta U)
    assert np.allclose((model[:, 0] - 1) / eps, (law_speed - 1) / eps, rtol=5e-4)
    report.value("asym.nu1_slope_error", abs((model[-1, 0] - 1) / (law_speed[-1] - 1) - 1),
                 reference=0.0, tol="5e-4 rel", source="thin-film rigid sphere, eps = 1e-5")
    err = np.abs(model[:, 1] / law_dp_R - 1)
    report.value("asym.nu1_dp_error", err[-1], reference=0.0, tol=0.015,
                 source="thin-film rigid sphere, eps = 1e-5")
    order = np.log(err[:-1] / err[1:]) / np.log(eps[:-1] / eps[1:])
    assert err[-1] < 0.015, err
    assert np.all(np.abs(order - 0.5) < 0.1), order   # the O(1) remainder of eq. asmyp2


# --------------------------------------------------------------------------- properties
@given(pair=increasing_pairs(0.01, 0.98, 1e-6))
def test_small_laws_are_monotonic(pair):
    lo, hi = pair
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutOfRangeWarning)
        assert a.speed_small_sphere(lo) > a.speed_small_sphere(hi)
        assert a.speed_small_drop(lo) > a.speed_small_drop(hi)
        assert a.dp_plus_small_sphere(lo) < a.dp_plus_small_sphere(hi)
        assert a.dp_plus_small_drop(lo) < a.dp_plus_small_drop(hi)


@given(nu=st.floats(0.3, 1.0), pair=increasing_pairs(0.5, 0.9999, 1e-6))
def test_near_critical_laws_are_monotonic_in_lam(nu, pair):
    lo, hi = pair
    lam_c = critical_confinement(nu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutOfRangeWarning)
        assert a.speed_near_critical(nu, lo * lam_c) > a.speed_near_critical(nu, hi * lam_c)
        assert a.dp_plus_near_critical(nu, lo * lam_c) < a.dp_plus_near_critical(nu, hi * lam_c)


@given(pair=increasing_pairs(0.05, 1.0, 1e-9))
def test_slope_lies_between_1_and_4_3_and_decreases_with_deflation(pair):
    s1, s2 = (a.speed_slope_near_critical(nu) for nu in pair)
    assert 1.0 < s1 < s2 <= 4 / 3 + 1e-12


@given(shape=st.sampled_from([(3,), (2, 4), (1, 5, 2)]))
def test_broadcasting_and_scalar_returns(shape):
    lam = np.full(shape, 0.3)
    for f in SMALL:
        out = f(lam)
        assert isinstance(out, np.ndarray) and out.shape == shape
        assert isinstance(f(0.3), float) and np.all(out == f(0.3))
    nu = np.array([0.6, 0.8, 0.95])
    frac = np.linspace(0.91, 0.99, 4)[:, None]
    lam = frac * critical_confinement(nu)
    for f in NEAR:
        out = f(nu, lam)
        assert out.shape == (4, 3)
        assert isinstance(f(0.8, 1.5), float)
        assert out[2, 1] == f(0.8, lam[2, 1])
    assert a.speed_slope_near_critical(np.full(shape, 0.7)).shape == shape
    assert isinstance(a.speed_slope_near_critical(0.7), float)


BAD = st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.5])


@given(bad=BAD)
def test_bad_lam_raises_for_small_laws(bad):
    for f in SMALL:
        with pytest.raises(InvalidParameterError, match="lam"):
            f(bad)
        with pytest.raises(InvalidParameterError, match="lam"):
            f(np.array([0.2, bad]))


@given(lam=st.floats(1.0, 10.0))
def test_sphere_larger_than_tube_cannot_pass(lam):
    for f in SMALL:
        with pytest.raises(CannotPassError, match="lam"):
            f(lam)


@given(bad=st.sampled_from([math.nan, math.inf, 0.0, -0.3, 1.0001, 2.0]))
def test_bad_nu_raises_for_near_critical_laws(bad):
    for f in NEAR:
        with pytest.raises(InvalidParameterError, match="nu"):
            f(bad, 1.0)
    with pytest.raises(InvalidParameterError, match="nu"):
        a.speed_slope_near_critical(bad)


@given(nu=st.floats(0.05, 1.0), over=st.floats(1.0, 3.0), bad=BAD)
def test_bad_lam_raises_for_near_critical_laws(nu, over, bad):
    lam_c = critical_confinement(nu)
    for f in NEAR:
        with pytest.raises(CannotPassError, match="lam"):
            f(nu, over * lam_c)
        with pytest.raises(InvalidParameterError, match="lam"):
            f(nu, bad)


@given(lam=st.floats(0.5001, 0.999))
def test_small_laws_warn_outside_their_range(lam):
    for f in SMALL:
        with pytest.warns(OutOfRangeWarning, match="lam"):
            f(lam)


@given(lam=st.floats(1e-6, 0.5))
def test_small_laws_silent_inside_their_range(lam):
    with _NoWarnings():
        for f in SMALL:
            f(lam)


@given(nu=st.floats(0.3, 1.0), frac=st.floats(0.01, 0.899))
def test_near_critical_laws_warn_for_wide_gaps(nu, frac):
    lam = frac * critical_confinement(nu)
    for f in NEAR:
        with pytest.warns(OutOfRangeWarning, match="delta"):
            f(nu, lam)


@given(nu=st.floats(0.3, 1.0), frac=st.floats(0.9001, 0.999999))
def test_near_critical_laws_silent_for_thin_gaps(nu, frac):
    lam = frac * critical_confinement(nu)
    with _NoWarnings():
        for f in NEAR:
            f(nu, lam)
        a.speed_slope_near_critical(nu)


# --------------------------------------------------------------------------- plots
def test_plots_return_axes_with_the_expected_lines():
    from lubrication.plotting import plot_dp_plus_asymptotics, plot_speed_asymptotics

    with _NoWarnings():
        ax = plot_speed_asymptotics()
        assert len(ax.get_lines()) == 2 + 2 * 3
        assert ax.get_xlabel() == "λ = R0/R [-]" and ax.get_ylabel() == "V/U [-]"
        styles = [line.get_linestyle() for line in ax.get_lines()]
        assert styles.count("-") == 4 and styles.count("--") == 4
        ax = plot_dp_plus_asymptotics(nu=(0.7, 0.9))
        assert len(ax.get_lines()) == 2 + 2 * 2
        assert ax.get_yscale() == "log" and ax.get_ylabel() == "Δp⁺R0/(ηU) [-]"


def test_plot_draws_on_a_given_axes():
    from matplotlib.figure import Figure

    from lubrication.plotting import plot_speed_asymptotics

    ax = Figure().add_subplot()
    assert plot_speed_asymptotics(nu=(0.8,), ax=ax) is ax
    assert len(ax.get_lines()) == 4
    with pytest.raises(InvalidParameterError, match="nu"):
        plot_speed_asymptotics(nu=(1.2,))


# ------------------------------------------------------------------------------------------
# Every public law: bad input (scalar or inside an array) raises naming the parameter; extreme
# valid input gives finite numbers.
# ------------------------------------------------------------------------------------------

_BAD = [math.nan, math.inf, -math.inf, 0.0, -1.0, 1e308, "abc"]
_LAWS_OF_LAM = [a.speed_small_sphere, a.dp_plus_small_sphere, a.speed_small_drop,
                a.dp_plus_small_drop]
_LAWS_OF_NU_LAM = [a.speed_near_critical, a.dp_plus_near_critical]


@pytest.mark.parametrize("bad", _BAD)
@pytest.mark.parametrize("law", _LAWS_OF_LAM, ids=lambda f: f.__name__)
def test_small_object_laws_name_a_bad_lam(law, bad):
    for lam in (bad, [0.3, bad]):
        with pytest.raises(InvalidParameterError) as info:
            law(lam)
        assert info.value.name == "lam"


@pytest.mark.parametrize("bad", _BAD)
@pytest.mark.parametrize("law", _LAWS_OF_NU_LAM, ids=lambda f: f.__name__)
def test_near_critical_laws_name_the_bad_parameter(law, bad):
    for name, args in (("nu", (bad, 1.0)), ("lam", (0.9, bad)), ("nu", ([0.9, bad], 1.0)),
                       ("lam", (0.9, [1.0, bad]))):
        with pytest.raises(InvalidParameterError) as info:
            law(*args)
        assert info.value.name == name


@pytest.mark.filterwarnings("ignore::lubrication.checks.OutOfRangeWarning")
def test_extreme_valid_inputs_give_finite_numbers():
    tiny = np.array([1e-320, 1e-300, 1e-100])
    assert np.all(a.speed_small_sphere(tiny) == 2.0)
    assert np.all(a.dp_plus_small_sphere(tiny) == 16.0 * tiny**6)      # underflows to 0
    lam_c = critical_confinement(1e-6)
    for nu, lam in ((1e-6, lam_c * (1 - 1e-15)), (0.6, np.nextafter(critical_confinement(0.6), 0))):
        v, dp = a.speed_near_critical(nu, lam), a.dp_plus_near_critical(nu, lam)
        assert math.isfinite(v) and 1.0 <= v <= 1.0 + 1e-12 and math.isfinite(dp) and dp > 0
