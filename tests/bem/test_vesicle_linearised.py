"""The linearised far field of the difference-Jacobian points (:meth:`bem.vesicle.operator.
VesicleOperator.taylor`): its kernel derivatives, its residual against the exact fixed-load
residual, and the Jacobian columns it gives against exact differences."""

from __future__ import annotations

import numpy as np
import pytest

from bem import kernels as K

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable


def _stencil(x0, r0, x, r, axis, h):
    """Fourth-order central difference of the ring Stokeslet in x (axis 0) or r (axis 1) of the
    source, step h: the independent reference for :func:`bem.kernels._ring_taylor`."""
    e = np.array([h, 0.0]) if axis == 0 else np.array([0.0, h])

    def M(k):
        return np.array(K.ring_stokeslet(x0, r0, x + k * e[0], r + k * e[1]))

    return (M(-2) - 8 * M(-1) + 8 * M(1) - M(2)) / (12 * h)


@pytest.mark.parametrize("x0, r0, x, r", [(0.0, 1.2, 0.3, 0.8), (0.5, 1.0, -2.0, 0.2),
                                          (0.0, 0.05, 0.1, 0.9), (1.0, 1.0, 0.95, 0.97)])
def test_ring_taylor_derivatives_match_a_fourth_order_stencil(x0, r0, x, r):
    """The central differences of step TAYLOR_STEP times the distance (second order) against a
    five-point stencil with a step 100 times larger (truncation ~1e-12 of the derivative's
    scale): within 1e-8 of the largest component."""
    M, Dx, Dr = K._ring_taylor(x0, r0, x, r)
    np.testing.assert_array_equal(M, K.ring_stokeslet(x0, r0, x, r))
    d = np.hypot(x0 - x, r0 - r)
    h = min(1e-3 * d, 0.25 * r)
    for got, axis in ((Dx, 0), (Dr, 1)):
        ref = _stencil(x0, r0, x, r, axis, h)
        assert np.max(np.abs(np.array(got) - ref)) <= 1e-8 * np.max(np.abs(ref)), (axis, got, ref)


@pytest.fixture(scope="module")
def state():
    """A 24-mode minimum of (0.9, 1.0) at Ca_B = 50 and its operator and evaluated state."""
    from bem.vesicle import VesicleOperator, solve_vesicle, vesicle_discretisation

    curve = solve_vesicle(0.9, 1.0, n_modes=24).curve()
    op = VesicleOperator(0.9, 1.0, 50.0, vesicle_discretisation(24), curve)
    modes = op.curve(curve.modes).modes
    return op, modes, op.evaluate(op.curve(modes))


def _both(op, st, modes, taylor):
    """Exact fixed-load residual and its linearised counterpart at shape ``modes``."""
    curve = op.curve(modes, slope=op._area_slope)
    exact = op.fixed_residual(curve, st["g"], st["V"])
    part = op.linearised_residual(curve, st["g"], st["V"], taylor)
    return exact, op.linearised_finish(taylor, [part])[0]


def test_linearised_residual_at_the_base_is_the_fixed_residual(state):
    """Unmoved, the linearised residual is the exact one: the far entries are the same ring
    Stokeslets and the near pairs the same integrals (to rounding: 1e-13 of the weighted speed
    V sqrt(w), of which the residual at this minimum is a cancellation to ~1e-5)."""
    op, modes, st = state
    exact, lin = _both(op, st, modes, op.taylor(st["panels"]))
    scale = st["V"] * np.sqrt(st["panels"].w).max()
    assert np.max(np.abs(lin - exact)) <= 1e-13 * scale


def test_linearised_residual_differs_from_the_exact_one_at_second_order(state):
    """Moved by h along a fixed direction d of the modes, the linearised residual differs from
    the exact one by D(h) = a h + C h^2 with a = 0 (the first-order part cancelled):

    * |D| falls 100 times per 10 times smaller h from 1e-3 to 1e-6 (asserted 60-160: a pure
      h^2 law gives 100; the third-order term moves it by ~1e-4 at h = 1e-3, and the window
      leaves room for a floor up to a quarter of |D(1e-6)|, ~1e-12 of the weighted speed, ten
      times the exact residual's quadrature error at its default tolerance);
    * a, the error the linearised points add to a column of the difference Jacobian, from the
      slopes s(h) = D(h)/h = a + C h + C3 h^2 at h = 1e-3, 5e-4, 2.5e-4 by the Richardson
      combination (s(h) - 6 s(h/2) + 8 s(h/4))/3 (what is left: the fourth-order term,
      ~h^3, and 15 times the residuals' floor over h, ~1e-12): below the forward difference's
      own truncation at the Jacobian's step h_J = 1e-7, h_J |R''(d, d)| / 2, with R'' from a
      central second difference of the exact residual.

    At h_J itself C h^2 is ~1e-13 of the weighted speed, the two residuals' own floor (their
    near integrals held to 1e-14 each, by re-planned rules for the exact one): a bound there
    would test the floor of this CPU, not the linearisation."""
    op, modes, st = state
    taylor = op.taylor(st["panels"])
    rng = np.random.default_rng(3)
    direction = np.zeros_like(modes)
    direction[2:] = rng.standard_normal(modes.size - 2) / np.arange(3, modes.size + 1)
    exact0, lin0 = _both(op, st, modes, taylor)

    def gap(h):
        exact, lin = _both(op, st, modes + h * direction, taylor)
        return lin - exact - (lin0 - exact0), exact

    gaps = [np.max(np.abs(gap(h)[0])) for h in (1e-3, 1e-4, 1e-5, 1e-6)]
    ratios = [g / g_next for g, g_next in zip(gaps, gaps[1:])]
    assert all(60 < q < 160 for q in ratios), (gaps, ratios)

    h, h_jacobian = 1e-3, 1e-7
    slope = [gap(h / k)[0] * k / h for k in (1, 2, 4)]
    first_order = (slope[0] - 6.0 * slope[1] + 8.0 * slope[2]) / 3.0
    curvature = np.max(np.abs(gap(1e-3)[1] - 2.0 * exact0 + gap(-1e-3)[1])) / 1e-6
    truncation = 0.5 * h_jacobian * curvature
    assert np.max(np.abs(first_order)) <= truncation, (np.max(np.abs(first_order)), truncation)


def test_linearised_jacobian_columns_match_exact_differences(state):
    """The difference Jacobian from linearised points against the one from exact fixed-load
    residuals (:data:`bem.vesicle.level.LINEARISED_POINTS` disabled): every column within 1e-4 of
    its norm (the linearised points lose the exact cancellation of the second-order terms between
    the two residuals of a difference). Measured at the 88-mode lubrication seed of
    (0.6, 1.94): 1.8e-5 of the largest column at worst, median 5e-8 of a column's own norm,
    but 1.4e-3 of its own norm for the first column, whose norm is 1.3 % of the largest."""
    from bem.vesicle import level as bv
    from bem.newton import difference_jacobian

    op, modes, st = state
    fun = bv.level_function(op, modes.copy())
    z0 = op.free(modes)
    F0, st = fun(z0)
    lin, n = difference_jacobian(fun, z0, F0, 1e-7, {}, st)
    assert n == z0.size >= bv.LINEARISED_POINTS
    saved = bv.LINEARISED_POINTS
    bv.LINEARISED_POINTS = 10**9
    try:
        exact, _ = difference_jacobian(fun, z0, F0, 1e-7, {}, st)
    finally:
        bv.LINEARISED_POINTS = saved
    col = np.linalg.norm(lin - exact, axis=0) / np.linalg.norm(exact, axis=0)
    assert col.max() < 1e-4, col.max()


def _panel_rule(op, panels, key, n, tx, tr):
    """Pair n of the near pairs ``key`` of ``panels`` as a function (cx, cr, x0, r0) -> its
    weights on a rule fixed at the unmoved geometry (the rule that
    :func:`bem.kernels.near_panels_taylor` differentiates on): the graded rule planned there
    (:func:`bem.kernels._graded_plan`, as :func:`bem.kernels.panel_integral` plans it), or the
    fixed self rule of the node; and the same weights re-planned, by the public kernels."""
    from bem.quadrature import barycentric_weights, gauss_legendre, gauss_table, self_rule

    p, tol = op.p, op.disc.quad_tol
    i, P = panels["pairs"][key][n]
    tn, _ = gauss_legendre(p)
    gx, gw = gauss_table()
    bw = barycentric_weights(p)
    cx0, cr0, x00, r00 = panels["base"].cx[P], panels["base"].cr[P], tx[i], tr[i]
    if key == "dd" and i // p == P and panels["fixed"][P]:
        st, sw, sell = self_rule(p)
        k0 = i - P * p

        def fixed(cx, cr, x0, r0):
            acc = np.empty((p, 4))
            K.self_panel_integral(x0, r0, cx, cr, st[k0], sw[k0], sell[k0], acc)
            return acc

        return fixed, fixed(cx0, cr0, x00, r00)
    nearest = np.argmin([np.hypot(x - x00, r - r00) for x, _, r, _ in
                         (K._curve_eval(cx0, cr0, t) for t in tn)])
    plan = np.empty((64, 3))
    plan = plan[:K._graded_plan(x00, r00, cx0, cr0, tn[nearest], gx.shape[0] - 1, tol, plan)]

    def fixed(cx, cr, x0, r0):
        acc, ell = np.zeros((p, 4)), np.empty(p)
        for a, b, m in plan:
            K._accumulate_interval(x0, r0, a, b, int(m), gx, gw, cx, cr, tn, bw, ell, acc)
        return acc

    replanned = np.empty((p, 4))
    K.panel_integral(x00, r00, cx0, cr0, tn, bw, gx, gw, tol, replanned)
    return fixed, replanned


def test_near_panel_derivatives_match_differences_on_their_rule(state):
    """The derivatives of the near blocks in the panel's Legendre coefficients and the target
    (:func:`bem.kernels.near_panels_taylor`, the integrand differentiated on a fixed rule)
    against differences of the integrals on the same rule: central differences at steps
    h = 1e-4, 5e-5, 2.5e-5 along a random direction, Richardson-extrapolated twice
    (truncation O(h^6), rounding ~30 eps |block| / h ~ 1e-11 of the largest derivative), for
    wall nodes near a membrane panel and for membrane nodes near or on their own panel (the
    target then moves with the panel node it is: the sum of both parts). Asserted within 1e-8
    of the block's largest derivative, a hundred times the accuracy of the kernels' derivatives
    (central differences of step 1e-5 of the distance in each ring Stokeslet, truncation
    ~1e-10); the reference's own error, estimated by the change from one Richardson step to
    two, is checked to be below a tenth of that. The values are the
    exact near blocks (re-planned, to 1e-13). The differences are taken on the rule, not
    re-planned for each moved panel: a re-planned rule jumps by its quadrature error (1e-14 of
    the integral) wherever the plan changes, which over a step h is noise of 1e-14/h."""
    op, modes, st = state
    base = st["panels"]
    taylor = op.taylor(base)
    p = op.p
    tn = np.polynomial.legendre.leggauss(p)[0]
    rng = np.random.default_rng(7)
    checked = {"ab": 0, "dd_near": 0, "dd_self": 0}
    for key, tx, tr in (("ab", op.wall.x.ravel(), op.wall.r.ravel()),
                        ("dd", base.x.ravel(), base.r.ravel())):
        acc, der = taylor["near"][key]
        pairs = taylor["pairs"][key]
        for n in rng.choice(pairs.shape[0], size=min(12, pairs.shape[0]), replace=False):
            i, P = pairs[n]
            own = key == "dd" and i // p == P
            on_rule, replanned = _panel_rule(op, taylor, key, n, tx, tr)
            np.testing.assert_allclose(acc[n], replanned, rtol=0,
                                       atol=1e-13 * np.max(np.abs(acc[n])))
            direction = rng.standard_normal(2 * p) / (1.0 + np.arange(2 * p) % p) ** 2
            leg = np.polynomial.legendre.legvander(tn[i % p:i % p + 1], p - 1)[0]
            moved = [0.0, 0.0] if key == "ab" else (
                [leg @ direction[:p], leg @ direction[p:]] if own else rng.standard_normal(2))
            got = der[n] @ np.concatenate([direction, moved])
            cx, cr = base.cx[P], base.cr[P]

            def central(h):
                at = [on_rule(cx + s * direction[:p], cr + s * direction[p:],
                              tx[i] + s * moved[0], tr[i] + s * moved[1]) for s in (h, -h)]
                return (at[0] - at[1]) / (2 * h)

            d1, d2, d4 = (central(1e-4 / k) for k in (1, 2, 4))
            coarse = (4 * d2 - d1) / 3
            ref = (16 * (4 * d4 - d2) / 3 - coarse) / 15
            scale = np.max(np.abs(der[n]))
            ref_error = np.max(np.abs(ref - (4 * d4 - d2) / 3))
            assert ref_error <= 1e-9 * scale, (key, own, ref_error / scale)
            err = np.max(np.abs(got - ref)) / scale
            assert err <= 1e-8, (key, own, err)
            checked["ab" if key == "ab" else "dd_self" if own else "dd_near"] += 1
    assert min(checked.values()) > 0, checked
