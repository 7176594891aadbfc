"""Local gap flow, its series, the polar caps and the right-hand sides against independent references.

References used here, none of them the implementation:
* the annular Couette-Poiseuille flow solved afresh in each test (u = G rho^2/4 + c1 ln rho + c2
  with the two no-slip conditions), integrated by scipy quadrature;
* 40-digit mpmath evaluation of the exact forms;
* Taylor series derived with sympy in this file;
* the spot values of the physics notes (r = 0.9, Q = 0.05; r = 0.5, Q = 0.1);
* the free rigid long cylinder: V/U = 2/(1 + k^2), dp+ = 4 eta V L k^4/(R^2 (1 - k^2)).
"""

import math

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings, strategies as st
from scipy.integrate import quad
from scipy.optimize import brentq

from lubrication import equations as eq
from lubrication.checks import InvalidParameterError

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable


# --------------------------------------------------------------------------- references
def _independent_flow(r, Q):
    """u(rho) = G rho^2/4 + c1 ln(rho) + c2 with u(r) = 0, u(1) = -1, G from the module.

    Returns (u, du/drho) as functions; c1, c2 come from a 2x2 solve of the no-slip conditions.
    """
    G = eq.pressure_gradient(r, Q)
    A = np.array([[math.log(r), 1.0], [0.0, 1.0]])
    b = np.array([-G * r * r / 4, -1.0 - G / 4])
    c1, c2 = np.linalg.solve(A, b)
    return (lambda rho: G * rho**2 / 4 + c1 * np.log(rho) + c2,
            lambda rho: G * rho / 2 + c1 / rho)


def _exact_mp(r, Q):
    """G, e_m, e_w from the exact formulas in 40-digit arithmetic."""
    with mpmath.workdps(40):
        r, Q = mpmath.mpf(r), mpmath.mpf(Q)
        L, a = mpmath.log(r), 1 - r * r
        G = 8 / a * (Q - 1 - a / (2 * L)) / (1 + r * r + a / L)
        return (float(G), float(G / 4 * (2 * r + a / (r * L)) + 1 / (r * L)),
                float(G / 4 * (2 + a / L) + 1 / L))


@pytest.fixture(scope="module")
def sympy_series():
    """Taylor series in d = 1 - r of G (through d^3), e_m and e_w (through d^4), by sympy."""
    d, Q = sp.symbols("d Q", positive=True)
    r = 1 - d
    L, a = sp.log(r), 1 - r**2
    G = 8 / a * (Q - 1 - a / (2 * L)) / (1 + r**2 + a / L)
    e_m = G / 4 * (2 * r + a / (r * L)) + 1 / (r * L)
    e_w = G / 4 * (2 + a / L) + 1 / L
    out = {"d": d, "Q": Q}
    for name, f, order in (("G", G, 4), ("e_m", e_m, 5), ("e_w", e_w, 5)):
        out[name] = sp.expand(sp.series(f, d, 0, order).removeO())
    return out


# --------------------------------------------------------------------------- spot values
@pytest.mark.parametrize("r, Q, G, e_m, e_w", [
    (0.9, 0.05, -305.2106, 4.997226, -24.49750),
    (0.5, 0.1, -22.79586, 3.748449, None),
])
def test_spot_values_of_the_physics_notes(r, Q, G, e_m, e_w, report):
    notes = "physics-notes"
    assert report.value(f"lub.spot_G_{r}", eq.pressure_gradient(r, Q), reference=G, tol="±1e-4",
                        source=notes) == pytest.approx(G, abs=1e-4)
    assert report.value(f"lub.spot_e_m_{r}", eq.membrane_shear_rate(r, Q), reference=e_m,
                        tol="±1e-6", source=notes) == pytest.approx(e_m, abs=1e-6)
    if e_w is not None:
        assert report.value(f"lub.spot_e_w_{r}", eq.wall_shear_rate(r, Q), reference=e_w,
                            tol="±1e-5", source=notes) == pytest.approx(e_w, abs=1e-5)


def test_series_spot_value_r_half_q_tenth(report):
    assert report.value("lub.series_e_m_0.5", eq.membrane_shear_rate_series(0.5, 0.1),
                        reference=3.729401, tol="±1e-6", source="physics-notes d^4 series"
                        ) == pytest.approx(3.729401, abs=1e-6)


# --------------------------------------------------------------------------- independent flow
@pytest.mark.parametrize("r", [0.01, 0.2, 0.5, 0.9, 0.98, 0.995, 0.999])
@pytest.mark.parametrize("Q", [1e-3, 0.05, 0.3])
def test_flux_by_quadrature_is_minus_pi_q(r, Q, report):
    """Flux through the gap, 2 pi int_r^1 u rho drho = -pi Q (r < 1 - SERIES_GAP: exact form;
    r > 1 - SERIES_GAP: series)."""
    u, _ = _independent_flow(r, Q)
    flux = 2 * math.pi * quad(lambda rho: u(rho) * rho, r, 1.0, epsabs=0, epsrel=1e-11,
                              limit=200)[0]
    report.value(f"lub.flux_{r}_{Q}", abs(flux / (-math.pi * Q) - 1), reference=0.0,
                 tol="1e-9 rel", source="adaptive quadrature of the gap velocity")
    assert flux == pytest.approx(-math.pi * Q, rel=1e-9, abs=1e-9 * (1 - r))


@pytest.mark.parametrize("r", [0.05, 0.5, 0.9, 0.995])
@pytest.mark.parametrize("Q", [1e-3, 0.2])
def test_shear_rates_are_the_derivatives_of_the_independent_flow(r, Q):
    _, du = _independent_flow(r, Q)
    assert eq.membrane_shear_rate(r, Q) == pytest.approx(du(r), rel=1e-10, abs=1e-10 / (1 - r))
    assert eq.wall_shear_rate(r, Q) == pytest.approx(du(1.0), rel=1e-10, abs=1e-10 / (1 - r))


@pytest.mark.parametrize("r, Q", [(0.3, 0.1), (0.9, 0.05), (0.995, 0.004)])
def test_gap_velocity_no_slip_and_profile(r, Q):
    # round-off: the two terms of u are each of size |G| (1 - r^2) / 4
    tol = 1e-14 * max(1.0, abs(eq.pressure_gradient(r, Q)) * (1 - r * r))
    assert eq.gap_velocity(r, r, Q) == pytest.approx(0.0, abs=tol)
    assert eq.gap_velocity(1.0, r, Q) == pytest.approx(-1.0, abs=tol)
    u, _ = _independent_flow(r, Q)
    rho = np.linspace(r, 1.0, 7)
    assert np.allclose(eq.gap_velocity(rho, r, Q), u(rho), rtol=1e-10, atol=1e-10)


def test_momentum_balance_of_the_gap_fluid():
    """Axial force on the annulus per length: pi (1 - r^2) G = 2 pi (e_w - r e_m)."""
    r = np.concatenate([np.linspace(0.01, 0.98, 50), 1 - np.geomspace(1e-5, 2e-2, 30)])
    for Q in (1e-4, 0.02, 0.4):
        G, e_m, e_w = (f(r, Q) for f in (eq.pressure_gradient, eq.membrane_shear_rate,
                                        eq.wall_shear_rate))
        scale = np.abs(e_w) + np.abs(r * e_m)
        assert np.all(np.abs(e_w - r * e_m - G * (1 - r * r) / 2) <= 1e-11 * scale)


# --------------------------------------------------------------------------- series and precision
def test_series_coefficients_derived_with_sympy(sympy_series):
    """The module's series equal the sympy Taylor series term by term (exact rationals)."""
    d, Q = sympy_series["d"], sympy_series["Q"]
    # the d^1 coefficient of e_m is 7/10 - 23/20 Q (a public copy has 32/20)
    assert sympy_series["e_m"].coeff(d, 1) == sp.Rational(7, 10) - sp.Rational(23, 20) * Q
    cases = (("G", eq.pressure_gradient_series), ("e_m", eq.membrane_shear_rate_series),
             ("e_w", eq.wall_shear_rate_series))
    for name, f in cases:
        expr = sympy_series[name]
        R = sp.Rational
        for dv, qv in ((R(1, 2), R(1, 10)), (R(1, 100), R(3, 1000)), (R(1, 7), R(2, 5))):
            exact = float(expr.subs({d: dv, Q: qv}))
            assert f(float(dv), float(qv)) == pytest.approx(exact, rel=1e-13), name


def test_series_of_the_notes_is_the_sympy_series(sympy_series):
    """The d^4 series printed in the physics notes (and its r = 0.5, Q = 0.1 value)."""
    d, Q = sympy_series["d"], sympy_series["Q"]
    R = sp.Rational
    notes = (-3 * Q / d**2 + 2 * (1 - Q) / d + (1 - R(29, 20) * Q) + d * (R(7, 10) - R(23, 20) * Q)
             + d**2 * (R(11, 20) - R(2749, 2800) * Q) + d**3 * (R(657, 1400) - R(309, 350) * Q)
             + d**4 * (R(237, 560) - R(45967, 56000) * Q))
    assert sp.simplify(sympy_series["e_m"] - notes) == 0
    assert float(notes.subs({d: R(1, 2), Q: R(1, 10)})) == pytest.approx(3.729401, abs=1e-6)


def test_switch_to_the_series_is_continuous():
    d = eq.SERIES_GAP
    for Q in (1e-4, 0.01, 0.3):
        for f, s in ((eq.pressure_gradient, eq.pressure_gradient_series),
                     (eq.membrane_shear_rate, eq.membrane_shear_rate_series),
                     (eq.wall_shear_rate, eq.wall_shear_rate_series)):
            below, above = f(1 - d * (1 - 1e-12), Q), f(1 - d * (1 + 1e-12), Q)
            assert below == pytest.approx(above, rel=1e-10)
            assert s(d, Q) == pytest.approx(f(1 - d * (1 + 1e-12), Q), rel=1e-10)


def test_accuracy_against_40_digit_arithmetic(report):
    """Largest error over 1e-7 <= d < 1, relative to the size of the leading terms (the
    functions cross zero, so plain relative errors are meaningless there): <= 1e-11."""
    ds = np.concatenate([np.geomspace(1e-7, 0.5, 120), 1 - np.geomspace(1e-6, 0.5, 30)])
    worst = 0.0
    for Q in (1e-4, 1e-2, 0.2, 0.45):
        for d in ds:
            r = 1.0 - d
            ref = _exact_mp(r, Q)
            got = (eq.pressure_gradient(r, Q), eq.membrane_shear_rate(r, Q),
                   eq.wall_shear_rate(r, Q))
            # leading terms: G ~ 6Q/d^3 + 6/d^2, e_m, e_w ~ 3Q/d^2 + 4/d (near the wall); O(1)
            # or 1/(r |ln r|) elsewhere
            scales = (6 * Q / d**3 + 6 / d**2 + 8,
                      3 * Q / d**2 + 4 / d + 1 / (r * abs(math.log(r))),
                      3 * Q / d**2 + 4 / d + 1 / abs(math.log(r)))
            worst = max(worst, max(abs(g - x) / s for g, x, s in zip(got, ref, scales)))
    assert report.value("lub.mpmath_worst", worst, reference=0.0, tol=1e-11,
                        source="40-digit mpmath") < 1e-11, worst


# --------------------------------------------------------------------------- rigid cylinder
@pytest.mark.parametrize("k", [0.3, 0.6, 0.9, 0.99, 0.999])
def test_free_rigid_long_cylinder(k, report):
    """A long rigid cylinder of radius k with zero net force: V/U = 2/(1 + k^2) exactly, and
    the extra pressure drop per length dp+ R^2/(eta V L) = 4 k^4/(1 - k^2) (physics notes §3).
    dp+ is asserted to the accuracy the root Q carries: brentq's bracket (xtol + rtol |Q|)
    plus the rounding of the force (4 eps times its terms, over dF/dQ), times |d dp+/dQ|
    (~6/(1 - k)^3: 3e-9 of dp+ at k = 0.999), three times over, and at least 1e-11."""
    def net_force(Q):   # per unit length: pressure on the cross-section plus shear on the side
        return (-math.pi * k * k * eq.pressure_gradient(k, Q)
                + 2 * math.pi * k * eq.membrane_shear_rate(k, Q))

    def dp_plus_per_length(Q):
        return -eq.pressure_gradient(k, Q) - 8 * (1 - Q)

    Q = brentq(net_force, -0.5, 0.99, xtol=1e-15, rtol=1e-15)
    closed = "physics notes §3, closed form"
    report.value(f"lub.cylinder_V_{k}", abs((1 / (1 - Q)) / (2 / (1 + k * k)) - 1),
                 reference=0.0, tol="1e-11 rel", source=closed)
    assert 1 / (1 - Q) == pytest.approx(2 / (1 + k * k), rel=1e-11)
    h, eps = 1e-7, np.finfo(float).eps
    terms = (abs(math.pi * k * k * eq.pressure_gradient(k, Q))
             + abs(2 * math.pi * k * eq.membrane_shear_rate(k, Q)))
    root_error = 1e-15 + 1e-15 * abs(Q) + 4 * eps * terms / abs(
        (net_force(Q + h) - net_force(Q - h)) / (2 * h))
    exact = 4 * k**4 / (1 - k * k)
    rtol = max(1e-11, 3 * abs(dp_plus_per_length(Q + h) - dp_plus_per_length(Q - h)) / (2 * h)
               * root_error / exact)
    report.value(f"lub.cylinder_dp_{k}", abs(dp_plus_per_length(Q) / exact - 1),
                 reference=0.0, tol="3 x the root's error x |d dp+/dQ| (>= 1e-11) rel",
                 source=closed)
    assert dp_plus_per_length(Q) == pytest.approx(exact, rel=rtol)


# --------------------------------------------------------------------------- Ca, caps, RHS
def test_capillary_number_from_dimensional_definitions():
    eta, U, R0, R, kappa, Q = 1.2e-3, 1e-3, 2.8e-6, 1.6e-6, 2e-19, 0.07
    ca_b = eta * U * R0**2 / kappa
    V = U / (1 - Q)
    assert eq.capillary_number(ca_b, R0 / R, Q) == pytest.approx(eta * V * R**2 / kappa, rel=1e-14)


@pytest.mark.parametrize("k", [2.0, 0.3, -0.7, 1e-7])
def test_spherical_cap_against_quadrature(k):
    """Area and volume of revolution of the cap r = sin(phi)/k, x' = sin(phi) along the arc."""
    eps = 0.05 if abs(k) > 1e-3 else 2e-3
    theta, area, volume = eq.spherical_cap(k, eps)
    assert math.sin(theta) == pytest.approx(eps * k, rel=1e-14)
    # arc length s from the pole: r(s) = sin(k s)/k, dx/ds = sin(k s)
    s_end = float(theta) / k
    A = quad(lambda s: 2 * math.pi * math.sin(k * s) / k, 0, s_end, epsrel=1e-13)[0]
    V = quad(lambda s: math.pi * (math.sin(k * s) / k) ** 2 * math.sin(k * s), 0, s_end,
             epsrel=1e-13, epsabs=0)[0]
    assert area == pytest.approx(A, rel=1e-9)
    assert volume == pytest.approx(V, rel=1e-6)


def test_rhs_on_a_sphere_is_the_geometry_of_the_sphere():
    """On a sphere of radius a with p = -2 sigma/a, q_s = 0: psi' = S/a, c_s' = q_s' = 0."""
    a, S, Q, sigma = 0.8, 2.0, 0.1, 3.0
    phi = np.linspace(0.1, 3.0, 9)
    r, psi = a * np.sin(phi), phi - math.pi / 2
    y_h = np.vstack([r, psi, np.full_like(r, -2 * sigma / a), np.full_like(r, sigma),
                     np.zeros_like(r), np.zeros_like(r)])
    f = eq.rhs_high_ca(phi, y_h, np.array([Q, S]))
    assert np.allclose(f[1], S / a, rtol=1e-13)
    assert np.allclose(f[0], -S * np.sin(psi), rtol=1e-14)
    assert np.allclose(f[4], 2 * math.pi * S * r)
    assert np.allclose(f[5], math.pi * S * r**2 * np.cos(psi))
    y_b = np.vstack([r, psi, np.full_like(r, -1 / a), np.zeros_like(r),
                     np.full_like(r, -2 * sigma / a), np.full_like(r, sigma), np.zeros_like(r),
                     np.zeros_like(r)])
    f = eq.rhs_bending(phi, y_b, np.array([Q, S]), 30.0, 1.0)
    assert np.allclose(f[1], S / a, rtol=1e-13)
    assert np.allclose(f[2:4], 0.0, atol=1e-12)
    ca = eq.capillary_number(30.0, 1.0, Q)
    assert np.allclose(f[4], S * ca * eq.pressure_gradient(r, Q) * np.cos(psi), rtol=1e-13)
    assert np.allclose(f[5], -S * ca * eq.membrane_shear_rate(r, Q), rtol=1e-13)


def test_polar_regularisation_is_the_limit_of_the_regular_form():
    """Just below and above POLE_RADIUS on a sphere the right-hand sides agree."""
    a, S, Q, sigma = 1.0, 1.0, 0.05, 2.0
    r_pole = eq.POLE_RADIUS
    r = np.array([r_pole * (1 - 1e-6), r_pole * (1 + 1e-6)])
    phi = np.arcsin(r / a)
    psi = phi - math.pi / 2
    y = np.vstack([r, psi, np.full(2, -2 * sigma / a), np.full(2, sigma), np.zeros(2), np.zeros(2)])
    f = eq.rhs_high_ca(phi, y, np.array([Q, S]))
    assert f[1, 0] == pytest.approx(f[1, 1], rel=1e-5)
    yb = np.vstack([r, psi, np.full(2, -1 / a), np.zeros(2), np.full(2, -2 * sigma / a),
                    np.full(2, sigma), np.zeros(2), np.zeros(2)])
    fb = eq.rhs_bending(phi, yb, np.array([Q, S]), 10.0, 1.0)
    assert np.allclose(fb[:4, 0], fb[:4, 1], rtol=1e-5, atol=1e-6)


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("r", [0.0, 1.0, -0.1, 1.5, float("nan")])
def test_radius_outside_the_gap_is_rejected(r):
    with pytest.raises(InvalidParameterError, match="r="):
        eq.pressure_gradient(r, 0.1)


def test_nan_q_is_rejected():
    with pytest.raises(InvalidParameterError, match="Q="):
        eq.membrane_shear_rate(0.5, float("nan"))
    with pytest.raises(InvalidParameterError, match="d="):
        eq.membrane_shear_rate_series(0.0, 0.1)


@settings(max_examples=30, deadline=None)
@given(d=st.floats(1e-6, 0.999), Q=st.floats(0.0, 0.5))
def test_functions_are_finite_and_vectorised(d, Q):
    r = np.array([1 - d, 0.5])
    for f in (eq.pressure_gradient, eq.membrane_shear_rate, eq.wall_shear_rate):
        v = f(r, Q)
        assert v.shape == (2,) and np.all(np.isfinite(v))
        assert v[0] == f(1 - d, Q)
