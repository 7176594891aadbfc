"""Fixed self-panel rule and the reduced ring-Stokeslet work against independent references."""

import math

import numpy as np
import pytest

from bem import kernels as K
from bem import quadrature as Q
from bem.geometry import sphere_curve

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable

P = 16
#: the fixed self rule's agreement with the graded rule at tol 1e-16, relative to a row's largest
#: entry: 5e-13 to 5e-12 on this sphere and on the three vesicle seeds of bem.quadrature's
#: docstring, set by the rounding of the rule's weights; four times the largest
SELF_RULE_FLOOR = 2e-11


@pytest.mark.parametrize("rule", ["stored", "fitted"])
def test_log_rule_is_positive_and_exact_for_shifted_legendre_times_log(rule):
    r"""Closed forms: :math:`\int_0^1 P_j(2u-1)\,du = \delta_{j0}` and
    :math:`\int_0^1 P_j(2u-1)\ln u\,du = -1` (j = 0), :math:`(-1)^{j+1}/(j(j+1))` (j >= 1),
    to rounding: 2 n eps sum_i |w_i f(u_i)| for each moment (n nodes: the rounding of the
    weights and that of the sum). Both the table the solver uses and a fit on this CPU."""
    u, w = Q.log_rule(Q.SELF_BASIS) if rule == "stored" else Q.fit_log_rule(Q.SELF_BASIS)
    assert np.all(w > 0) and np.all((u >= 1e-8) & (u <= 1.0))
    assert u.size <= 2 * Q.SELF_BASIS
    j = np.arange(Q.SELF_BASIS)
    V = np.polynomial.legendre.legvander(2.0 * u - 1.0, Q.SELF_BASIS - 1)
    exact_log = np.where(j == 0, -1.0, (-1.0) ** (j + 1) / np.maximum(j * (j + 1), 1))
    for values, exact in ((V, j == 0), (V * np.log(u)[:, None], exact_log)):
        rounding = 2 * u.size * np.finfo(float).eps * (np.abs(values).T @ w)
        assert np.all(np.abs(values.T @ w - exact) <= rounding)


def test_self_rule_integrates_a_log_singular_function_at_every_node():
    """a(t) + b(t) ln|t - t_k| with a, b analytic (poles at distance 1.5 from the panel: the
    rule's polynomial degree 27 leaves ~1e-19), to rounding: 2 n eps sum |w f| (n nodes; the
    weights match their moments to rounding, previous test), which also covers the reference's
    rounding (positive weights on the same integrand, a random walk of its 4800 terms)."""
    st, sw, _ = Q.self_rule(P)
    t, _ = Q.gauss_legendre(P)
    u, w = Q._graded_rule(0.15, 40, 60)        # reference: graded composite Gauss, each side
    for k in range(P):
        tk = t[k]

        def f(s, dist):                          # dist = |s - t_k|, passed exactly
            return (np.cos(2 * s) + np.log(dist) / (2.5 - s)) / (2.5 + s)

        values = f(st[k], np.abs(st[k] - tk))
        ref = sum(L * w @ f(tk + sgn * L * u, L * u) for sgn, L in ((-1, 1 + tk), (1, 1 - tk)))
        rounding = 2 * st[k].size * np.finfo(float).eps * (np.abs(sw[k]) @ np.abs(values))
        assert abs(sw[k] @ values - ref) <= rounding, k


@pytest.fixture(scope="module")
def sphere():
    """Sphere of radius 0.6 in 8 panels: panels 0, 1, 6, 7 come within one panel length of the
    axis (adaptive rule), 2-5 take the fixed rule."""
    return Q.panels_on_curve(sphere_curve(0.6), np.linspace(0.0, np.pi, 9), P)


def test_self_panel_rows_match_the_adaptive_rule(sphere, monkeypatch):
    """Self-panel blocks of the matrix by the fixed rule against the adaptive graded rule at
    tol 1e-16 (which agrees with scipy quad to 1e-10, tests/bem/test_kernels.py), relative to
    the row's largest entry: within SELF_RULE_FLOOR, the fixed rule's floor (its weights come
    from a least-squares fit of condition ~5e16 and move with the rounding of numpy's log and
    LAPACK on each CPU; a rule with too small a basis, j < 20, is 1e-11 to 3e-11 off and one
    with a wrong node or weight 1e-6 or more). Pole panels keep the adaptive rule: at its
    default tol 1e-14 against 1e-16, within 100 tol (tol per panel integral, each side; the
    row's 2 p entries scaled by the largest)."""
    x, r = sphere.x.ravel(), sphere.r.ravel()
    got = Q.influence(x, r, sphere)
    monkeypatch.setattr(Q, "AXIS_CLEARANCE", math.inf)
    ref = Q.influence(x, r, sphere, tol=1e-16)
    monkeypatch.undo()
    fixed = sphere.r.min(axis=1) >= Q.AXIS_CLEARANCE * sphere.lengths
    assert fixed.sum() == 4 and not fixed[0] and not fixed[-1]
    err = np.empty(sphere.n_panels)
    for k in range(sphere.n_panels):
        rows = slice(2 * P * k, 2 * P * (k + 1))
        scale = np.abs(ref[rows]).max(axis=1, keepdims=True)
        err[k] = np.max(np.abs(got[rows, rows] - ref[rows, rows]) / scale)
    assert np.all(err[fixed] < SELF_RULE_FLOOR), err
    assert np.all(err[~fixed] < 100 * Q.DEFAULT_TOL), err


def test_self_panel_rows_need_the_targets_to_be_the_panel_nodes(sphere):
    """The fixed rule applies only when the first targets are the panels' own nodes: the same
    target handed alone (the adaptive path) gives the same row to the rule's accuracy."""
    x, r = sphere.x.ravel(), sphere.r.ravel()
    i = 3 * P + 5
    full = Q.influence(x, r, sphere)[2 * i: 2 * i + 2]
    alone = Q.influence(x[i:i + 1], r[i:i + 1], sphere)
    assert np.max(np.abs(full - alone)) < SELF_RULE_FLOOR * np.max(np.abs(alone))


def _trapezoid_reference(x0, r0, x, r, n=64):
    """The azimuthal trapezoidal rule of ring_stokeslet_phi, in numpy with direct cosines."""
    phi = np.linspace(0.0, np.pi, n + 1)
    w = np.full(n + 1, np.pi / n)
    w[[0, -1]] *= 0.5
    c, xh = np.cos(phi), x0 - x
    rho2 = xh * xh + r0 * r0 + r * r - 2.0 * r * r0 * c
    i1, i3 = rho2 ** -0.5, rho2 ** -1.5
    return 2.0 * r * np.array([w @ (i1 + xh * xh * i3), xh * (w @ ((r0 * c - r) * i3)),
                               xh * (w @ ((r0 - r * c) * i3)),
                               w @ (c * i1 + (r0 - r * c) * (r0 * c - r) * i3)])


def test_fewer_azimuthal_intervals_keep_the_ring_stokeslet_at_rounding():
    """ring_stokeslet's m < 0.1 branch (4-7 trapezoid intervals by m, cosines by recurrence)
    against 64 intervals with direct cosines, relative to the largest component: to rounding,
    taken as 50 eps (sums of up to 8 terms in the branch, 65 in the reference, whose off-diagonal
    components cancel to ~m of the terms' size)."""
    rng = np.random.default_rng(3)
    worst = 0.0
    n_small = 0
    for _ in range(4000):
        x, r, r0 = rng.uniform(-4.0, 4.0), rng.uniform(1e-3, 1.0), rng.uniform(1e-3, 1.0)
        if 4 * r * r0 / (x * x + (r + r0) ** 2) >= 0.1:
            continue
        n_small += 1
        got = np.array(K.ring_stokeslet(0.0, r0, x, r))
        ref = _trapezoid_reference(0.0, r0, x, r)
        worst = max(worst, np.max(np.abs(got - ref)) / np.max(np.abs(ref)))
    assert n_small > 1000
    assert worst < 50 * np.finfo(float).eps


def test_influence_pair_equals_the_two_influence_calls():
    """Reciprocity fills the far entries of one matrix from the other's ring Stokeslets: a
    sphere near the wall (gap 0.1) and a wall segment with near and far pairs."""
    from bem.geometry import sphere_curve as sc

    body = Q.panels_on_curve(sc(0.9), np.linspace(0.0, np.pi, 9), P)
    wall = Q.panels_on_curve(lambda s: (s, np.ones_like(s), np.ones_like(s), np.zeros_like(s)),
                             np.linspace(-4.0, 4.0, 41), P)
    w_b, b_w = Q.influence_pair(wall, body)
    ref_wb = Q.influence(wall.x.ravel(), wall.r.ravel(), body)
    ref_bw = Q.influence(body.x.ravel(), body.r.ravel(), wall)
    for got, ref in ((w_b, ref_wb), (b_w, ref_bw)):
        # scale: the largest entry of the target node's two rows (the r-rows of nodes near the
        # axis are ~1e-4 of the x-rows; the ring Stokeslet is accurate relative to its largest
        # component there, notes §5)
        scale = np.repeat(np.abs(ref).reshape(-1, 2 * ref.shape[1]).max(axis=1), 2)[:, None]
        assert np.max(np.abs(got - ref) / scale) < 1e-13
