"""Spectral generating curves: curvatures, pole limits, volume, closure, fitting.

Closed forms: sphere (kappa_1 = kappa_2 = 1/a); spheroid x = -a cos t, r = b sin t with
kappa_1 = ab/q^(3/2), kappa_2 = a/(b q^(1/2)), q = a^2 sin^2 t + b^2 cos^2 t; volume 4/3 pi a b^2.
Measured numbers in the comments come from this code.
"""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from bem.shape import (
    PIECE_NODES as PIECE,
    SpectralCurve,
    equidistributing_density,
    fit_curve,
    spheroid_curvatures,
    spheroid_curve,
)
from lubrication.checks import InvalidParameterError

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable

EPS = np.finfo(float).eps


def _integrand_rounding(c):
    """Rounding of one value of g cos(phi) or g sin(phi) at u <= 1/2 from a pole [eps max g]:
    the abscissa pi u, rounded to 4 eps relative, moves phi = pi u - sum c_k sin(k pi u) and g
    by (1 + sum k|c_k| + sum j|a_j|) pi/2 x 4 eps; the Clenshaw sums add (1 + N) sum|c_k| and
    (1 + J) sum|a_j|, the cosine or sine and the product 3."""
    c_abs, a_abs = np.abs(c.modes), np.abs(c.density)
    slope = 1 + np.sum(np.arange(1, c_abs.size + 1) * c_abs) + np.sum(
        np.arange(1, a_abs.size + 1) * a_abs)
    return (2 * math.pi * slope + (1 + c_abs.size) * np.sum(c_abs)
            + (1 + a_abs.size) * np.sum(a_abs) + 3)


def _position_rounding(c):
    """Worst-case rounding of position() [R]. The cumulative rule (pieces of length h <= 4/quad)
    sums, for u <= 1/2, the PIECE-node rules of the pieces before u (total weight <= u) and the
    last piece's PIECE-term Legendre series of PIECE-term coefficients (2 PIECE^2 terms of weight
    <= h); the front branch adds the 2 quad-node rule of the front pole. Each value carries
    _integrand_rounding; all are at most max g <= 1 + sum|a_j|, times S."""
    g_max = 1 + np.sum(np.abs(c.density))
    n = (PIECE * (0.5 + 8 * PIECE / c._quad) + 2 * c._quad + 1.5 * _integrand_rounding(c))
    return EPS * (n * c.length * g_max + 2 * (abs(c.x0) + c.length))


def _spheroid_error(curve, a, b, n=2001):
    """Largest relative curvature errors against the closed form, and the volume error."""
    tau = np.linspace(0.0, 1.0, n)
    x, _ = curve.position(tau)
    t = np.arccos(np.clip(-x / a, -1.0, 1.0))             # the spheroid's parameter at x
    k1, k2 = curve.curvatures(tau)
    e1, e2 = spheroid_curvatures(a, b, t)
    vol = curve.volume() / (4.0 / 3.0 * math.pi * a * b * b) - 1.0
    return np.max(np.abs(k1 / e1 - 1)), np.max(np.abs(k2 / e2 - 1)), abs(vol)


def test_sphere_curvatures_are_exact_including_the_poles(report):
    """Sphere of radius 0.8: curvatures 1/a; positions on the circle within their worst-case
    rounding (:func:`_position_rounding`); volume, area and centroid within the change that
    the position errors at their Gauss nodes (against the exact circle) cause, plus 2n eps x
    the sum of the n terms' magnitudes (their summation and the rounded nodes and weights)."""
    a = 0.8
    c = SpectralCurve.sphere(a, 6)
    tau = np.array([0.0, 1e-12, 1e-8, 1e-3, 0.3, 0.5, 0.5 + 1e-12, 0.9, 1 - 1e-9, 1.0])
    k1, k2 = c.curvatures(tau)
    report.value("shape.sphere_curvature",
                 max(np.max(np.abs(k1 - 1.25)), np.max(np.abs(k2 - 1.25))), reference=0.0, tol="1e-14 (κ1), 1e-13 (κ2)", source="1/a")
    assert np.max(np.abs(k1 - 1.25)) < 1e-14 and np.max(np.abs(k2 - 1.25)) < 1e-13
    x, r = c.position(tau)
    assert np.max(np.abs(np.hypot(x, r) - a)) < 2 * _position_rounding(c)
    assert r[0] == 0.0 and abs(r[-1]) < 1e-16
    # the integral properties from the Gauss nodes they use, against the exact circle
    s, w = c._tau_rule()
    x, r = c.position(s)
    dx = np.abs(c.derivative(s)[0])
    xe, re, dxe = -a * np.cos(np.pi * s), a * np.sin(np.pi * s), np.pi * a * np.sin(np.pi * s)
    ref_rounding = 2 * EPS * a                          # of the exact values, cos and sin
    err_x, err_r = np.abs(x - xe) + ref_rounding, np.abs(r - re) + ref_rounding
    err_dx = np.abs(dx - dxe) + np.pi * ref_rounding
    dv = np.pi * w * r * r * dx
    err_dv = np.pi * w * ((r + re) * err_r * dx + re * re * err_dx)
    sums = 2 * s.size * EPS
    volume, area = 4 / 3 * math.pi * a**3, 4 * math.pi * a**2
    assert abs(c.volume() / volume - 1) < (np.sum(err_dv) + sums * np.sum(dv)) / volume
    assert abs(c.area() / area - 1) < (2 * math.pi * c.length * np.sum(w * err_r)) / area + sums
    assert abs(c.centroid()) < (np.sum(err_x * dv + np.abs(xe) * err_dv)
                                + sums * np.sum(np.abs(x) * dv)) / volume
    assert abs(c.closure_error()) < 1e-15


@pytest.mark.parametrize("a, b, n, bound", [(1.0, 0.6, 48, 1e-8), (0.5, 1.0, 48, 1e-11),
                                            (2.0, 0.5, 64, 5e-5)])
def test_spheroid_curvatures_match_the_closed_form(a, b, n, bound, report):
    """Prolate, oblate and 4:1 prolate spheroids fitted with an equidistributing density.
    Measured max relative curvature errors: 8e-14 (1:0.6), 2e-13 (0.5:1), 5e-6 (2:0.5)."""
    base = fit_curve(spheroid_curve(a, b), 0.0, math.pi, 24)
    curve = fit_curve(spheroid_curve(a, b), 0.0, math.pi, n,
                      density=equidistributing_density(base, 16))
    e1, e2, ev = _spheroid_error(curve, a, b)
    report.value(f"shape.spheroid_{a:g}_{b:g}", max(e1, e2), reference=0.0, tol=f"{bound:g} rel",
                 source="closed-form curvatures of the spheroid")
    report.value(f"shape.spheroid_volume_{a:g}_{b:g}", ev, reference=0.0, tol=1e-10,
                 source="4 pi a b^2/3")
    assert e1 < bound and e2 < bound, (e1, e2)
    assert ev < 1e-10
    # pole limits: both principal curvatures equal a/b^2 at t = 0 and pi
    k1, k2 = curve.curvatures(np.array([0.0, 1.0]))
    assert np.allclose(k1, a / b**2, rtol=bound) and np.allclose(k1, k2, rtol=1e-13, atol=0)


def test_spheroid_fit_converges_spectrally_and_density_helps():
    """Uniform arc length, oblate 0.5:1: errors 1.5e-2, 1.5e-4, 1.6e-6 at 16, 32, 48 modes
    (geometric); with the density 3.6e-5, 7.1e-9, 8e-14."""
    errs, errs_d = [], []
    base = fit_curve(spheroid_curve(0.5, 1.0), 0.0, math.pi, 24)
    dens = equidistributing_density(base, 16)
    for n in (16, 32, 48):
        errs.append(_spheroid_error(fit_curve(spheroid_curve(0.5, 1.0), 0, math.pi, n), 0.5,
                                    1.0)[0])
        errs_d.append(_spheroid_error(fit_curve(spheroid_curve(0.5, 1.0), 0, math.pi, n,
                                                density=dens), 0.5, 1.0)[0])
    assert errs[0] / errs[1] > 50 and errs[1] / errs[2] > 50, errs
    assert all(d < e / 100 for d, e in zip(errs_d, errs)), (errs, errs_d)


def test_inner_quadrature_is_converged():
    """Doubling the inner Gauss rule of r(tau) changes the positions by no more than the
    worst-case rounding of the two (:func:`_position_rounding`; an inner rule of 12 instead of
    136 nodes moves them by 1e-11), the curvatures by no more than 1e-12."""
    c = fit_curve(spheroid_curve(1.0, 0.5), 0.0, math.pi, 40,
                  density=equidistributing_density(fit_curve(spheroid_curve(1.0, 0.5), 0,
                                                             math.pi, 24), 16))
    tau = np.linspace(0.0, 1.0, 301)
    x, r = c.position(tau)

    class Doubled(SpectralCurve):
        @property
        def _quad(self):
            return 2 * super()._quad

    d = Doubled(c.modes, c.length, c.x0, c.density)
    x2, r2 = d.position(tau)
    bound = _position_rounding(c) + _position_rounding(d)
    assert np.max(np.abs(x - x2)) < bound and np.max(np.abs(r - r2)) < bound
    k = np.array(c.curvatures(tau)) - np.array(d.curvatures(tau))
    assert np.max(np.abs(k)) < 1e-12


@given(st.lists(st.floats(-0.15, 0.15), min_size=2, max_size=10),
       st.floats(0.2, 0.9), st.floats(-0.5, 0.5))
def test_closed_curves_have_the_requested_volume_and_centroid(modes, lam, xc):
    c = SpectralCurve.closed([0.0, *modes], volume=4 / 3 * math.pi * lam**3, centroid=xc)
    assert abs(c.closure_error()) < 1e-14 * c.length
    assert abs(c.volume() / (4 / 3 * math.pi * lam**3) - 1) < 1e-13
    assert abs(c.centroid() - xc) < 1e-13
    # the azimuthal curvature is continuous across the two branches (rear/front pole)
    _, k2 = c.curvatures(np.array([0.5 - 1e-12, 0.5 + 1e-12]))
    assert abs(k2[0] - k2[1]) < 1e-9 * abs(k2[0])
    # a uniform density leaves the parameter equal to the normalised arc length
    assert abs(c.arc_length(np.array([0.37]))[0] - 0.37 * c.length) < 1e-14


def test_curvature_against_finite_differences_of_the_position():
    """kappa_1 = |x' r'' - r' x''| / |X'|^3 by central differences of position()."""
    c = SpectralCurve.closed([0.0, -0.1, 0.05, 0.02], volume=2.0)
    tau = np.linspace(0.05, 0.95, 19)
    h = 1e-4
    xp, rp = c.position(tau + h)
    xm, rm = c.position(tau - h)
    x0, r0 = c.position(tau)
    dx, dr = (xp - xm) / (2 * h), (rp - rm) / (2 * h)
    ddx, ddr = (xp - 2 * x0 + xm) / h**2, (rp - 2 * r0 + rm) / h**2
    k1_fd = (dx * ddr - dr * ddx) / np.hypot(dx, dr) ** 3
    k1, k2 = c.curvatures(tau)
    assert np.max(np.abs(-k1_fd - k1)) < 1e-6 * np.max(np.abs(k1))
    assert np.max(np.abs(dx / np.hypot(dx, dr) / r0 - k2)) < 1e-7 * np.max(np.abs(k2))


def test_bad_curves_are_rejected():
    with pytest.raises(InvalidParameterError):
        SpectralCurve([], 1.0)
    with pytest.raises(InvalidParameterError):
        SpectralCurve([0.1, math.nan], 1.0)
    with pytest.raises(InvalidParameterError):
        SpectralCurve([0.0], -1.0)
    with pytest.raises(InvalidParameterError, match="density"):
        SpectralCurve([0.0], 1.0, 0.0, [1.5])          # g = 1 + 1.5 cos(pi tau) < 0


def test_film_density_clusters_the_parameter_in_the_thin_gap():
    """A capsule of radius 0.97 in a unit tube: the film density gives the film (gap 0.03) a
    larger share of the parameter than uniform arc length, and g stays positive with mean 1."""
    from bem.shape import film_density

    a, half = 0.97, 1.5                                 # hemispherical caps, cylinder |x| < half

    def capsule(t):                                     # t in [0, 1], arc length / S
        S = math.pi * a + 2 * half
        s = np.asarray(t, dtype=float) * S
        s1, s2 = 0.5 * math.pi * a, 0.5 * math.pi * a + 2 * half
        phi1, phi2 = s / a, (s - s2) / a + 0.5 * math.pi
        x = np.where(s < s1, -half - a * np.cos(phi1),
                     np.where(s < s2, -half + (s - s1), half + a * np.sin(phi2 - 0.5 * math.pi)))
        r = np.where(s < s1, a * np.sin(phi1), np.where(s < s2, a, a * np.cos(phi2 - 0.5 * math.pi)))
        psi = np.where(s < s1, 0.5 * math.pi - phi1, np.where(s < s2, 0.0, -(phi2 - 0.5 * math.pi)))
        return x, r, S * np.cos(psi), S * np.sin(psi)

    curve = fit_curve(capsule, 0.0, 1.0, 32)
    a_coef = film_density(curve, 16)
    shaped = SpectralCurve(curve.modes, curve.length, curve.x0, a_coef)
    t = np.linspace(0.0, 1.0, 2001)
    assert np.min(shaped.g(t)) > 0 and float(np.mean(shaped.g(t))) == pytest.approx(1, abs=0.02)
    # share of the parameter spent where the arc length is in the film (|x| < half)
    S, s_film = curve.length, (0.5 * math.pi * a, 0.5 * math.pi * a + 2 * half)
    s = shaped.arc_length(t)
    share = np.mean((s > s_film[0]) & (s < s_film[1]))
    assert share > 1.2 * (s_film[1] - s_film[0]) / S
    assert film_density(curve, 0).size == 0


def _lubrication_gap_error(nu, ratio, n_modes, density):
    """Largest error in r relative to the gap 1 - r of the n_modes fit (``density`` "curvature"
    or "bend", 32 terms) of the lubrication shape at (nu, lam/lam_c = ratio)."""
    from bem.vesicle import seed_from_lubrication
    from lubrication.solve import solve_lubrication

    lub = solve_lubrication(nu, lam_ratio=ratio, ca_b=50.0)
    assert lub.success, lub.message
    fit = seed_from_lubrication(lub, n_modes, density, 32)
    t = np.linspace(0.0, 1.0, 8001)
    s, (_, r) = fit.arc_length(t), fit.position(t)
    r_lub = np.interp(s, lub.s, lub.r)
    return float(np.max(np.abs(r - r_lub) / np.maximum(1.0 - r_lub, 1e-3)))


def test_curvature_gradient_density_resolves_the_long_near_critical_vesicle():
    """nu = 0.6, lam/lam_c = 0.98 (long bullet, film 1.5 % of R, cap-film junctions of length
    ~sqrt(hR)): with the curvature-gradient term the 64-mode fit of the lubrication shape
    represents the gap to better than 1e-3 relative (measured 9.5e-5, 2.1e-6 at 96 modes);
    the curvature weight alone leaves 8e-3 (1e-3 at 96). The error falls with the modes."""
    plain = _lubrication_gap_error(0.6, 0.98, 64, "curvature")
    bend = [_lubrication_gap_error(0.6, 0.98, n, "bend") for n in (48, 64, 96)]
    assert plain > 3e-3, plain
    assert bend[1] < 1e-3 and bend[1] < plain / 10, (bend, plain)
    assert bend[0] > bend[1] > bend[2], bend


def test_pole_integrals_match_one_fine_gauss_rule_per_point():
    """The cumulative pole integrals of SpectralCurve._integrals against the direct rule (one
    Gauss rule on [0, u] per point, 4x the ``_quad`` nodes) for dense panel-like samples,
    sparse random ones, repeated points, the pole itself and u = 1/2. Bound: the worst-case
    rounding of both. The cumulative rule, for u in piece q >= 1 (u >= q h): q PIECE terms of
    the pieces before and the 2 PIECE^2 terms of the last piece's Legendre series, of weight
    <= h/u, i.e. PIECE (q + 2 PIECE/q) eps max g; the direct rule n eps sum|terms| with n its
    nodes; both evaluate the integrand (:func:`_integrand_rounding`). Half as many pieces move
    the integrals of the rough 96-mode curve by 2e-10."""
    from bem.shape import gauss_legendre01
    rng = np.random.default_rng(3)
    for n, j, amp in ((64, 16, 0.01), (96, 16, 0.02), (8, 0, 0.1)):
        c = SpectralCurve(rng.normal(size=n) * amp, 10.0, 0.0, rng.normal(size=j) * 0.02)
        t, w = gauss_legendre01(4 * c._quad)
        q = max(1, math.ceil(c._quad / 8) - 1)            # pieces after the first, u <= 1/2
        g_max = 1 + np.sum(np.abs(c.density))
        own = EPS * g_max * (2 * _integrand_rounding(c)
                             + PIECE * max(1 + 2 * PIECE, q + 2 * PIECE / q))
        for u in (np.linspace(0.0, 0.5, 352), rng.uniform(0.0, 0.5, 50), np.array([0.2, 0.2]),
                  np.array([0.5]), np.array([1e-9, 0.3])):
            for front in (False, True):
                phi, g = c._phi(u[:, None] * t, front)
                ic, is_ = c._integrals(u, front)
                for got, f in ((ic, g * np.cos(phi)), (is_, g * np.sin(phi))):
                    bound = own + t.size * EPS * (np.abs(f) @ w)
                    assert np.all(np.abs(got - f @ w) <= bound), np.max(np.abs(got - f @ w))


@given(st.lists(st.floats(-2.0, 2.0), min_size=0, max_size=40),
       st.lists(st.floats(-4.0, 4.0), min_size=1, max_size=30))
def test_clenshaw_sums_equal_the_direct_trigonometric_sums(coeffs, angles):
    """The numba Clenshaw kernels of the curve against sum_k c_k sin(k theta) and
    sum_k c_k cos(k theta) summed term by term (numpy), to rounding."""
    from bem.series import cosine_sum, pole_terms, sine_clenshaw

    c, th = np.array(coeffs, dtype=float), np.array(angles, dtype=float)
    k = np.arange(1, c.size + 1)
    sines = np.sin(np.outer(th, k)) @ c
    cosines = np.cos(np.outer(th, k)) @ c
    scale = 1.0 + np.sum(np.abs(c)) * (1.0 + k.size)
    assert np.max(np.abs(sine_clenshaw(c, th) * np.sin(th) - sines), initial=0.0) < 1e-13 * scale
    assert np.max(np.abs(cosine_sum(c, th) - cosines), initial=0.0) < 1e-13 * scale
    # the position integrands: phi = pi u - sum c_k sin(k pi u), g = 1 + sum a_j cos(j pi u)
    u = th / np.pi
    a = 0.1 * c[:5]
    phi = np.pi * u - np.sin(np.outer(np.pi * u, k)) @ c
    g = 1.0 + np.cos(np.outer(np.pi * u, np.arange(1, a.size + 1))) @ a
    gc, gs = np.array([pole_terms(c, a, x) for x in u]).T.reshape(2, -1)
    assert np.max(np.abs(gc - g * np.cos(phi))) < 1e-13 * scale
    assert np.max(np.abs(gs - g * np.sin(phi))) < 1e-13 * scale
