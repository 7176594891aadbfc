"""Correlations of Chen et al. 2020 against the numbers printed in the paper and their algebra."""

import math
import warnings

import numpy as np
import pytest
from hypothesis import given, strategies as st
from strategies import increasing_pairs

from correlations import film, pressure, shape
from lubrication.asymptotics import dp_plus_near_critical
from lubrication.checks import CannotPassError, InvalidParameterError, OutOfRangeWarning
from lubrication.geometry import critical_confinement, critical_length

BAD = st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -1.0])
BAD_NU = st.sampled_from([math.nan, math.inf, 0.0, -0.2, 1.0001, 3.0])


class _NoWarnings:
    def __enter__(self):
        self._cm = warnings.catch_warnings()
        self._cm.__enter__()
        warnings.simplefilter("error")

    def __exit__(self, *exc):
        return self._cm.__exit__(*exc)


def _quiet(f, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutOfRangeWarning)
        return f(*args, **kw)


# --------------------------------------------------------------------------- shape
def test_transition_confinement_of_red_cells_is_about_1_8(report):
    """Chen et al.: lambda_T(nu = 0.6) ~= 1.8 (printed to 2 digits)."""
    assert report.value("corr.lam_T_0.6", shape.transition_confinement_chen2020(0.6),
                        reference=1.8, tol="±0.02", source="Chen et al. 2020"
                        ) == pytest.approx(1.8, abs=0.02)


def test_the_two_vesicles_of_the_transition_figure(report):
    """Fig. transition: (0.95, 0.8, Ca_B = 5) bullet, (0.83, 0.67, Ca_B = 15) parachute."""
    source = "Chen et al. 2020, caption of the transition figure"
    with pytest.warns(OutOfRangeWarning, match="ca_b"):   # Ca_B = 5 is below the diagram's 10
        assert report.value("corr.class_0.95_0.8", shape.shape_class_chen2020(0.95, 0.8, ca_b=5),
                            reference="bullet", tol="equal", source=source) == "bullet"
    with _NoWarnings():
        assert report.value("corr.class_0.83_0.67",
                            shape.shape_class_chen2020(0.83, 0.67, ca_b=15),
                            reference="parachute", tol="equal", source=source) == "parachute"


def test_gap_at_the_red_cell_transition(report):
    """Chen et al.: at the nu = 0.6 transition the gap is ~7 % of R; eq. sfilm2 gives 8.4 %."""
    lam_T = shape.transition_confinement_chen2020(0.6)
    delta = report.value("corr.film_at_lam_T_0.6", film.film_thickness_chen2020(0.6, lam_T),
                         reference=0.07, tol="±0.02", source="Chen et al. 2020 (BEM, ≈ 7 %)")
    assert delta == pytest.approx(0.0845, abs=5e-4)
    assert abs(delta - 0.07) < 0.02   # consistent with "~7 %" only within the O(delta^2) slack


@given(lam=st.floats(0.68, 1.81))
def test_transition_round_trip(lam):
    with _NoWarnings():
        nu_T = shape.transition_reduced_volume_chen2020(lam)
        assert shape.transition_confinement_chen2020(nu_T) == pytest.approx(lam, rel=1e-12)


@given(nu=st.floats(0.3, 1.0), f=st.floats(0.05, 0.999))
def test_class_follows_the_line(nu, f):
    lam = f * critical_confinement(nu)
    cls = _quiet(shape.shape_class_chen2020, nu, lam)
    nu_T = _quiet(shape.transition_reduced_volume_chen2020, lam)
    assert cls == ("parachute" if nu < nu_T else "bullet")


@given(pair=increasing_pairs(0.01, 3.8, 1e-9))
def test_transition_line_decreases_with_confinement(pair):
    lo, hi = pair
    assert _quiet(shape.transition_reduced_volume_chen2020, lo) > _quiet(
        shape.transition_reduced_volume_chen2020, hi)


def test_length_is_exact_for_the_sphere_and_reaches_ell_c():
    lam = np.linspace(0.1, 0.99, 7)
    assert np.allclose(_quiet(shape.length_chen2020, 1.0, lam), 2 * lam, rtol=1e-14)
    for nu in (0.6, 0.8, 0.95):
        lam_c = critical_confinement(nu)
        assert shape.length_chen2020(nu, lam_c * (1 - 1e-12)) == pytest.approx(
            critical_length(nu), rel=1e-11)
    assert shape.length_chen2020(0.6, 1.94) == pytest.approx(11.04 * 1.94 / 1.9812, rel=1e-3)


@given(nu=st.floats(0.3, 1.0), pair=increasing_pairs(0.05, 0.999, 1e-6))
def test_length_increases_with_confinement(nu, pair):
    lo, hi = pair
    lam_c = critical_confinement(nu)
    assert _quiet(shape.length_chen2020, nu, lo * lam_c) < _quiet(
        shape.length_chen2020, nu, hi * lam_c)


@given(shape_=st.sampled_from([(3,), (2, 4), (1, 5, 2)]))
def test_shape_broadcasting(shape_):
    lam = np.full(shape_, 1.2)
    with _NoWarnings():
        assert shape.transition_reduced_volume_chen2020(lam).shape == shape_
        assert shape.transition_confinement_chen2020(np.full(shape_, 0.8)).shape == shape_
        nu = np.array([0.65, 0.8, 0.9])
        lam = np.array([1.0, 1.1, 1.2, 1.25])[:, None]
        cls = shape.shape_class_chen2020(nu, lam)
        assert cls.shape == (4, 3) and set(cls.ravel()) <= {"parachute", "bullet"}
        assert cls[0, 0] == shape.shape_class_chen2020(0.65, 1.0)
        assert isinstance(shape.shape_class_chen2020(0.8, 1.2), str)
        nu = np.array([0.6, 0.8, 0.95])
        lam = np.linspace(0.92, 0.99, 4)[:, None] * critical_confinement(nu)
        ell = shape.length_chen2020(nu, lam)
        assert ell.shape == (4, 3) and ell[1, 2] == shape.length_chen2020(0.95, lam[1, 2])
        assert isinstance(shape.transition_confinement_chen2020(0.8), float)


@given(bad=BAD)
def test_shape_bad_input(bad):
    with pytest.raises(InvalidParameterError, match="lam"):
        shape.transition_reduced_volume_chen2020(bad)
    with pytest.raises(InvalidParameterError, match="lam"):
        shape.shape_class_chen2020(0.8, bad)
    with pytest.raises(InvalidParameterError, match="lam"):
        shape.length_chen2020(0.8, bad)
    with pytest.raises(InvalidParameterError, match="ca_b"):
        shape.shape_class_chen2020(0.8, 1.0, ca_b=bad)


@given(bad=BAD_NU)
def test_shape_bad_nu(bad):
    for f in (shape.shape_class_chen2020, shape.length_chen2020):
        with pytest.raises(InvalidParameterError, match="nu"):
            f(bad, 1.0)
    with pytest.raises(InvalidParameterError, match="nu"):
        shape.transition_confinement_chen2020(bad)


@given(nu=st.floats(0.05, 1.0), over=st.floats(1.0, 2.0))
def test_shape_cannot_pass(nu, over):
    lam = over * critical_confinement(nu)
    for f in (shape.shape_class_chen2020, shape.length_chen2020):
        with pytest.raises(CannotPassError, match="lam"):
            f(nu, lam)


def test_transition_line_beyond_nu_T_zero_is_an_error():
    with pytest.raises(InvalidParameterError, match="lam"):
        shape.transition_reduced_volume_chen2020(4.0)


@given(lam=st.one_of(st.floats(0.01, 0.67), st.floats(1.82, 3.8)))
def test_transition_warns_outside(lam):
    with pytest.warns(OutOfRangeWarning):
        shape.transition_reduced_volume_chen2020(lam)


@given(nu=st.one_of(st.floats(0.01, 0.599), st.floats(0.931, 1.0)))
def test_transition_confinement_warns_outside(nu):
    with pytest.warns(OutOfRangeWarning, match="nu"):
        shape.transition_confinement_chen2020(nu)


@given(nu=st.floats(0.6, 0.93))
def test_transition_silent_inside(nu):
    with _NoWarnings():
        lam = shape.transition_confinement_chen2020(nu)
        shape.transition_reduced_volume_chen2020(lam)


@given(nu=st.floats(0.6, 1.0), f=st.floats(0.9001, 0.9999))
def test_length_and_class_silent_inside(nu, f):
    lam = f * critical_confinement(nu)
    with _NoWarnings():
        shape.length_chen2020(nu, lam)
        if 0.6 <= lam <= 1.94:
            shape.shape_class_chen2020(nu, lam, ca_b=50)


@given(nu=st.floats(0.3, 1.0), f=st.floats(0.05, 0.899))
def test_length_warns_for_wide_gaps(nu, f):
    with pytest.warns(OutOfRangeWarning, match="delta"):
        shape.length_chen2020(nu, f * critical_confinement(nu))


@given(nu=st.floats(0.3, 0.599), f=st.floats(0.05, 0.999))
def test_class_warns_below_the_simulated_reduced_volumes(nu, f):
    with pytest.warns(OutOfRangeWarning, match="nu"):
        shape.shape_class_chen2020(nu, f * critical_confinement(nu))


# --------------------------------------------------------------------------- film
def test_film_constants():
    assert film.C0_CHEN2020 == 2.0
    assert film.C0_SECOMB1986 == pytest.approx(2.123, abs=5e-4)   # "c0 ~ 2.123" in the paper
    assert film.C0_BRUINSMA1996 == 2.05


@given(ca=st.floats(1e-8, 0.3), c0=st.sampled_from([film.C0_CHEN2020, film.C0_SECOMB1986,
                                                     film.C0_BRUINSMA1996]))
def test_film_round_trip(ca, c0):
    delta = _quiet(film.film_from_capillary_chen2020, ca, c0=c0)
    assert _quiet(film.capillary_from_film_chen2020, delta, c0=c0) == pytest.approx(ca, rel=1e-13)
    # eq. tension2: gamma_F/(eta V) = (delta/c0)^(-3/2) = 1/Ca_v
    assert (delta / c0) ** -1.5 == pytest.approx(1 / ca, rel=1e-12)


@given(delta=st.floats(1e-6, 0.99))
def test_film_round_trip_from_delta(delta):
    ca = _quiet(film.capillary_from_film_chen2020, delta)
    assert _quiet(film.film_from_capillary_chen2020, ca) == pytest.approx(delta, rel=1e-13)


def test_film_thickness_is_the_clearance():
    assert film.film_thickness_chen2020(0.6, 1.94) == pytest.approx(1 - 1.94 / 1.981198, rel=1e-5)
    assert _quiet(film.film_thickness_chen2020, 1.0, 0.5) == pytest.approx(0.5, rel=1e-15)


@given(pair=increasing_pairs(1e-7, 0.3, 1e-9, log=True))
def test_film_increases_with_capillary_number(pair):
    c1, c2 = pair
    assert _quiet(film.film_from_capillary_chen2020, c1) < _quiet(
        film.film_from_capillary_chen2020, c2)


@given(shape_=st.sampled_from([(3,), (2, 4), (1, 5, 2)]))
def test_film_broadcasting(shape_):
    with _NoWarnings():
        d = film.film_from_capillary_chen2020(np.full(shape_, 1e-3))
        assert d.shape == shape_
        assert film.capillary_from_film_chen2020(d).shape == shape_
        two = film.film_from_capillary_chen2020(np.full(shape_, 1e-3)[..., None],
                                                c0=np.array([2.0, 2.05]))
        assert two.shape == shape_ + (2,)
        nu = np.array([0.6, 0.8, 0.95])
        lam = np.linspace(0.92, 0.99, 4)[:, None] * critical_confinement(nu)
        assert film.film_thickness_chen2020(nu, lam).shape == (4, 3)
        assert isinstance(film.film_from_capillary_chen2020(1e-3), float)


@given(bad=BAD)
def test_film_bad_input(bad):
    with pytest.raises(InvalidParameterError, match="ca_v"):
        film.film_from_capillary_chen2020(bad)
    with pytest.raises(InvalidParameterError, match="delta"):
        film.capillary_from_film_chen2020(bad)
    with pytest.raises(InvalidParameterError, match="c0"):
        film.film_from_capillary_chen2020(1e-3, c0=bad)
    with pytest.raises(InvalidParameterError, match="c0"):
        film.capillary_from_film_chen2020(0.05, c0=bad)
    with pytest.raises(InvalidParameterError, match="lam"):
        film.film_thickness_chen2020(0.8, bad)


@given(bad=BAD_NU)
def test_film_bad_nu(bad):
    with pytest.raises(InvalidParameterError, match="nu"):
        film.film_thickness_chen2020(bad, 1.0)


def test_film_domain_edges():
    with pytest.raises(InvalidParameterError, match="ca_v"):   # film thicker than the tube
        film.film_from_capillary_chen2020(2.0 ** -1.5)
    with pytest.raises(InvalidParameterError, match="delta"):
        film.capillary_from_film_chen2020(1.0)
    with pytest.raises(CannotPassError, match="lam"):
        film.film_thickness_chen2020(0.6, 2.0)


@given(ca=st.floats(1.0001e-2, 0.3))
def test_film_warns_above_the_fitted_capillary_numbers(ca):
    with pytest.warns(OutOfRangeWarning, match="ca_v"):
        d = film.film_from_capillary_chen2020(ca)
    with pytest.warns(OutOfRangeWarning, match="ca_v"):
        film.capillary_from_film_chen2020(d * (1 + 1e-9))


@given(ca=st.floats(1e-9, 1e-2))
def test_film_silent_inside(ca):
    with _NoWarnings():
        film.capillary_from_film_chen2020(0.999999 * film.film_from_capillary_chen2020(ca))


@given(nu=st.floats(0.3, 1.0), f=st.floats(0.05, 0.899))
def test_film_thickness_warns_for_wide_gaps(nu, f):
    with pytest.warns(OutOfRangeWarning, match="delta"):
        film.film_thickness_chen2020(nu, f * critical_confinement(nu))


# --------------------------------------------------------------------------- pressure
def test_speed_fit_at_the_ends_of_its_range(report):
    """eq. dpa_v_fit at U/V = 0.6 and 0.995: 3e-6 e^12 = 0.48826, 3e-6 e^19.9 = 1316.99."""
    source = "3e-6 exp(...) of Chen et al. eq. dpa_v_fit evaluated by hand"
    with _NoWarnings():
        assert report.value("corr.dpa_v_fit_0.6", pressure.dp_plus_speed_fit_chen2020(1 / 0.6),
                            reference=0.488264, tol="1e-5 rel", source=source
                            ) == pytest.approx(0.488264, rel=1e-5)
        assert report.value("corr.dpa_v_fit_0.995",
                            pressure.dp_plus_speed_fit_chen2020(1 / 0.995), reference=1316.987,
                            tol="1e-5 rel", source=source) == pytest.approx(1316.987, rel=1e-5)


def test_film_correlation_against_the_near_critical_leading_term(report):
    """(3/2) lam ell/delta vs eq. asmyp2 at ell = ell_c: leading-term ratio (4/3)(1 - 2/ell_c)."""
    for nu in (0.6, 0.8, 0.9):
        lam_c, ell_c = critical_confinement(nu), critical_length(nu)
        delta = 1e-8
        lam = lam_c * (1 - delta)
        ratio = dp_plus_near_critical(nu, lam) / pressure.dp_plus_film_chen2020(lam, ell_c, delta)
        report.value(f"corr.film_vs_asmyp2_{nu}", ratio, reference=4 / 3 * (1 - 2 / ell_c),
                     tol="1e-3 rel", source="(4/3)(1 - 2/ell_c)")
        assert ratio == pytest.approx(4 / 3 * (1 - 2 / ell_c), rel=1e-3)


@given(lam=st.floats(0.05, 0.5))
def test_small_sphere_coupling_matches_the_laws(lam):
    V = 2 - 4 / 3 * lam**2
    with _NoWarnings():
        assert pressure.dp_plus_small_sphere_coupling(V) == pytest.approx(16 * lam**6, rel=1e-9)


@given(pair=increasing_pairs(1.0, 2.0, 1e-9))
def test_pressure_decreases_with_speed(pair):
    v1, v2 = pair
    assert _quiet(pressure.dp_plus_speed_fit_chen2020, v1) > _quiet(
        pressure.dp_plus_speed_fit_chen2020, v2)
    assert _quiet(pressure.dp_plus_small_sphere_coupling, v1) > _quiet(
        pressure.dp_plus_small_sphere_coupling, v2)


@given(pair=increasing_pairs(1e-6, 0.99, 1e-9, log=True))
def test_film_pressure_decreases_with_film(pair):
    d1, d2 = pair
    assert _quiet(pressure.dp_plus_film_chen2020, 1.5, 8.0, d1) > _quiet(
        pressure.dp_plus_film_chen2020, 1.5, 8.0, d2)


@given(shape_=st.sampled_from([(3,), (2, 4), (1, 5, 2)]))
def test_pressure_broadcasting(shape_):
    with _NoWarnings():
        out = pressure.dp_plus_film_chen2020(np.full(shape_, 1.5)[..., None], 8.0,
                                             np.array([0.01, 0.05]))
        assert out.shape == shape_ + (2,)
        assert pressure.dp_plus_speed_fit_chen2020(np.full(shape_, 1.2)).shape == shape_
        assert pressure.dp_plus_small_sphere_coupling(np.full(shape_, 1.8)).shape == shape_
        assert isinstance(pressure.dp_plus_small_sphere_coupling(1.8), float)
        assert isinstance(pressure.dp_plus_film_chen2020(1.5, 8.0, 0.05), float)


@given(bad=BAD)
def test_pressure_bad_input(bad):
    for name, args in (("lam", (bad, 8.0, 0.05)), ("ell", (1.5, bad, 0.05)),
                       ("delta", (1.5, 8.0, bad))):
        with pytest.raises(InvalidParameterError, match=name):
            pressure.dp_plus_film_chen2020(*args)
    for f in (pressure.dp_plus_speed_fit_chen2020, pressure.dp_plus_small_sphere_coupling):
        with pytest.raises(InvalidParameterError, match="V_over_U"):
            f(bad)


@given(v=st.one_of(st.floats(-5, 0.999), st.floats(2.001, 10)))
def test_speed_outside_1_2_is_invalid(v):
    for f in (pressure.dp_plus_speed_fit_chen2020, pressure.dp_plus_small_sphere_coupling):
        with pytest.raises(InvalidParameterError, match="V_over_U"):
            f(v)


@given(v=st.one_of(st.floats(1.0, 1.005), st.floats(1.6667, 2.0)))
def test_speed_fit_warns_outside(v):
    with pytest.warns(OutOfRangeWarning, match="V_over_U"):
        pressure.dp_plus_speed_fit_chen2020(v)


@given(u_over_v=st.floats(0.6, 0.995))
def test_speed_fit_silent_inside(u_over_v):
    with _NoWarnings():
        pressure.dp_plus_speed_fit_chen2020(min(max(1 / u_over_v, 1 / 0.995), 1 / 0.6))


@given(v=st.floats(1.0, 1.6666))
def test_coupling_warns_outside(v):
    with pytest.warns(OutOfRangeWarning, match="V_over_U"):
        pressure.dp_plus_small_sphere_coupling(v)


@given(v=st.floats(1.66667, 2.0))
def test_coupling_silent_inside(v):
    with _NoWarnings():
        pressure.dp_plus_small_sphere_coupling(v)


@given(delta=st.floats(0.1001, 0.99))
def test_film_pressure_warns_for_wide_gaps(delta):
    with pytest.warns(OutOfRangeWarning, match="delta"):
        pressure.dp_plus_film_chen2020(1.5, 8.0, delta)
