"""The linearised far field of the difference-Jacobian points (:meth:`bem.vesicle.
VesicleOperator.taylor`): its kernel derivatives, its residual against the exact fixed-load
residual, and the Jacobian columns it gives against exact differences."""

from __future__ import annotations

import numpy as np
import pytest

from bem import kernels as K


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
    """Moved by h along a fixed direction of the modes, the linearised residual differs from
    the exact one by O(h^2): 100 times less per 10 times smaller h (asserted 60-160, the
    first-order part already cancelled), and by less than 1e-6 of the change of the residual
    itself at h = 1e-7, the step of the difference Jacobian."""
    op, modes, st = state
    taylor = op.taylor(st["panels"])
    rng = np.random.default_rng(3)
    direction = np.zeros_like(modes)
    direction[2:] = rng.standard_normal(modes.size - 2) / np.arange(3, modes.size + 1)
    base = op.fixed_residual(op.curve(modes, slope=op._area_slope), st["g"], st["V"])
    gaps = []
    for h in (1e-4, 1e-5, 1e-6):
        exact, lin = _both(op, st, modes + h * direction, taylor)
        gaps.append(np.max(np.abs(lin - exact)))
    ratios = [gaps[0] / gaps[1], gaps[1] / gaps[2]]
    assert all(60 < q < 160 for q in ratios), (gaps, ratios)
    exact, lin = _both(op, st, modes + 1e-7 * direction, taylor)
    assert np.max(np.abs(lin - exact)) <= 1e-6 * np.max(np.abs(exact - base))


def test_linearised_jacobian_columns_match_exact_differences(state):
    """The difference Jacobian from linearised points against the one from exact fixed-load
    residuals (:data:`bem.vesicle.LINEARISED_POINTS` disabled): every column within 1e-4 of its
    norm (the linearised points lose the exact cancellation of the second-order terms between
    the two residuals of a difference). Measured at the 88-mode lubrication seed of
    (0.6, 1.94): 1.8e-5 of the largest column at worst, median 5e-8 of a column's own norm,
    but 1.4e-3 of its own norm for the first column, whose norm is 1.3 % of the largest."""
    import bem.vesicle as bv
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


def _panel_weights(op, panels, key, n, cx, cr, x0, r0, tol):
    """The weights of pair n of the near pairs ``key`` of ``panels`` with the panel's Legendre
    coefficients replaced by cx, cr and the target by (x0, r0): by the graded rule, re-planned
    for the moved geometry (or the fixed self rule of the node), the independent reference."""
    from bem.quadrature import barycentric_weights, gauss_legendre, gauss_table, self_rule

    p = op.p
    i, P = panels["pairs"][key][n]
    acc = np.empty((p, 4))
    tn, _ = gauss_legendre(p)
    if key == "dd" and i // p == P and panels["fixed"][P]:
        st, sw, sell = self_rule(p)
        k0 = i - P * p
        K.self_panel_integral(x0, r0, cx, cr, st[k0], sw[k0], sell[k0], acc)
    else:
        gx, gw = gauss_table()
        K.panel_integral(x0, r0, cx, cr, tn, barycentric_weights(p), gx, gw, tol, acc)
    return acc


def test_near_panel_derivatives_match_central_differences_of_the_integrals(state):
    """The derivatives of the near blocks in the panel's Legendre coefficients and the target
    (:func:`bem.kernels.near_panels_taylor`, the integrand differentiated on a fixed rule)
    against central differences of step 1e-6 of the integrals themselves, re-planned for each
    moved panel: within 1e-8 of the block's largest derivative (measured 2e-11 to 2.5e-10, the
    differences' truncation and rounding), for wall nodes near a membrane
    panel and for membrane nodes near or on their own panel (the target then moves with the
    panel node it is: the sum of both parts). The values are the exact near blocks."""
    op, modes, st = state
    base = st["panels"]
    taylor = op.taylor(base)
    p, tol, h = op.p, op.disc.quad_tol, 1e-6
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
            cx, cr = base.cx[P].copy(), base.cr[P].copy()
            np.testing.assert_allclose(
                acc[n], _panel_weights(op, taylor, key, n, cx, cr, tx[i], tr[i], tol),
                rtol=0, atol=1e-13 * np.max(np.abs(acc[n])))
            direction = rng.standard_normal(2 * p) / (1.0 + np.arange(2 * p) % p) ** 2
            leg = np.polynomial.legendre.legvander(tn[i % p:i % p + 1], p - 1)[0]
            moved = [0.0, 0.0] if key == "ab" else (
                [leg @ direction[:p], leg @ direction[p:]] if own else rng.standard_normal(2))
            delta = np.concatenate([direction, moved])
            got = der[n] @ delta

            def at(s):
                return _panel_weights(op, taylor, key, n, cx + s * direction[:p],
                                      cr + s * direction[p:], tx[i] + s * moved[0],
                                      tr[i] + s * moved[1], tol)

            ref = (at(h) - at(-h)) / (2 * h)
            scale = np.max(np.abs(der[n]))
            err = np.max(np.abs(got - ref)) / scale
            assert err <= 1e-8, (key, own, err)
            checked["ab" if key == "ab" else "dd_self" if own else "dd_near"] += 1
    assert min(checked.values()) > 0, checked
