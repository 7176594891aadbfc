"""Time-dependent BEM vesicle: surface divergence, inextensibility tension, time stepping.

Units: R = 1, U the mean velocity, eta = 1, time in R/U, tension in eta U, Ca_B = eta U R0^2/kappa
= 50. The cheap point is nu = 0.98, lam = 0.3 with 16 modes on 8 panels of 16 nodes (the steady
solve takes ~20 s, shared by the module). Measured numbers in the comments come from this code
(2-core machine shared with other jobs, so times are indicative).
"""

import math

import numpy as np
import pytest

from bem.drop import DropDiscretisation
from bem.membrane import tension_profile
from bem.quadrature import gauss_legendre, panels_on_curve
from bem.shape import spheroid_curvatures, spheroid_curve
from bem.vesicle import VesicleOperator, solve_vesicle, spheroid_seed
from bem.vesicle_dynamics import (
    _fd_jacobian,
    inextensible_tension,
    quiescent_velocity,
    relax_vesicle,
    relaxation_rate_brochard_lennon_1975,
    surface_divergence,
    vesicle_flow,
    vesicle_operator,
)
from lubrication.checks import InvalidParameterError

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable

NU, LAM, CA_B = 0.98, 0.3, 50.0


# ------------------------------------------------------------------ surface divergence
def _spheroid_panels(a, b, n_panels=8, p=16):
    """Panels on the spheroid of spheroid_curve and the curve parameter t of their nodes."""
    br = np.linspace(0.0, math.pi, n_panels + 1)
    tg, _ = gauss_legendre(p)
    t = 0.5 * (br[:-1] + br[1:])[:, None] + 0.5 * np.diff(br)[:, None] * tg[None, :]
    return panels_on_curve(spheroid_curve(a, b), br, p), t


def _interleave(ux, ur):
    u = np.empty(2 * ux.size)
    u[0::2], u[1::2] = ux.ravel(), ur.ravel()
    return u


@pytest.mark.parametrize("a, b", [(0.7, 0.7), (0.9, 0.5), (0.4, 0.8)])
def test_surface_divergence_matches_the_projection_formula(a, b):
    """div_s u = (I - nn):grad u (Chen et al. 2020 eq. surface) against closed forms:
    u = (alpha x, beta r) has grad u = diag(alpha, beta, beta), so div_s = alpha + 2 beta -
    alpha n_x^2 - beta n_r^2 (a translation: 0; u = X: 2 on any surface); the Poiseuille field
    2(1 - r^2) e_x has div_s = 4 r n_x n_r; a unit normal velocity u = n has
    div_s = kappa_1 + kappa_2 with the spheroid's closed-form curvatures (2/a on a sphere of
    radius a), which fixes the sign convention of the curvature form
    (1/r) d(r u_s)/ds + (kappa_1 + kappa_2) u_n. Measured error (8 panels of 16) <= 3e-13,
    except u = n on the non-spheres: 4.8e-11 (0.9, 0.5) and 3.5e-10 (0.4, 0.8, rim curvature
    5/R), see the convergence test below."""
    P, t = _spheroid_panels(a, b)
    x, r, nx, nr = P.x, P.r, P.nx, P.nr
    k1, k2 = spheroid_curvatures(a, b, t)
    fields = {
        "translation": (np.ones_like(x), np.zeros_like(r), np.zeros_like(x)),
        "expansion": (x, r, np.full_like(x, 2.0)),
        "linear": (1.3 * x, -0.4 * r, 1.3 - 0.8 - 1.3 * nx**2 + 0.4 * nr**2),
        "poiseuille": (2.0 * (1.0 - r * r), np.zeros_like(r), 4.0 * r * nx * nr),
        "normal": (nx, nr, k1 + k2),
    }
    for name, (ux, ur, exact) in fields.items():
        div = surface_divergence(P, _interleave(ux, ur))
        bound = 1e-9 if name == "normal" else 1e-11       # n turns fast at a flat rim
        assert np.max(np.abs(div - exact.ravel())) < bound, name
    if a == b:
        assert np.allclose(k1 + k2, 2.0 / a, rtol=1e-14)
    # m fields at once give the same columns
    U = np.column_stack([_interleave(*f[:2]) for f in fields.values()])
    cols = surface_divergence(P, U)
    for k, (ux, ur, _) in enumerate(fields.values()):
        assert np.allclose(cols[:, k], surface_divergence(P, _interleave(ux, ur)),
                           rtol=0, atol=1e-13)


def test_surface_divergence_converges_at_high_order_under_panel_refinement():
    """u = n on the spheroid a = 0.4, b = 0.8 (rim curvature 5): error of div_s n against
    kappa_1 + kappa_2 with 4/8/16 panels of 16 nodes measured 8.1e-7, 3.5e-10, 7.8e-13
    (observed order 11.2, then round-off); the derivative of a degree-15 interpolant converges
    like h^15 asymptotically."""
    errs = []
    for n in (4, 8):
        P, t = _spheroid_panels(0.4, 0.8, n_panels=n)
        k1, k2 = spheroid_curvatures(0.4, 0.8, t)
        div = surface_divergence(P, _interleave(P.nx, P.nr))
        errs.append(np.max(np.abs(div - (k1 + k2).ravel())))
    order = math.log2(errs[0] / errs[1])
    assert order > 9.0, (errs, order)


def test_surface_divergence_rejects_a_wrong_length():
    P, _ = _spheroid_panels(0.5, 0.5, n_panels=2, p=4)
    with pytest.raises(InvalidParameterError, match="u="):
        surface_divergence(P, np.zeros(3))


# ------------------------------------------------------------------ tension at rest
def test_quiescent_tension_of_a_quasi_spherical_vesicle_tends_to_minus_6_kappa_over_R0sq():
    """Quasi-spherical vesicle r = R0 (1 + eps Y_2) in a quiescent tube: its O(eps) normal load
    is -eps (l+2)(l-1) Y [kappa l(l+1) + gamma R0^2]/R0^3 (2H = 2/R0 + eps (l+2)(l-1) Y/R0,
    Delta_s = -l(l+1)/R0^2, H^2 - K = O(eps^2)), so the tension that keeps the excess area,
    i.e. leaves the l = 2 amplitude at rest, is gamma = -6 kappa/R0^2 = -6/Ca_B = -0.12 eta U
    (Seifert 1999, Eur. Phys. J. B 8, 405: l(l+1) + sigma R0^2/kappa = 0), uniform, up to
    O(eps). Measured (lam = 0.3, 12 modes) with eps = 1 - b/a of spheroid_seed:
    nu 0.99999/0.9999/0.999, eps 0.0061/0.0192/0.0597: max relative error of gamma(tau)
    1.1e-3/3.4e-3/1.0e-2 (0.17 eps, observed order 0.99 and 0.95). Divergence left < 1e-8."""
    errs, eps = [], []
    for nu in (0.9999, 0.999):
        seed = spheroid_seed(nu, LAM, 12)
        op = VesicleOperator(nu, LAM, CA_B, DropDiscretisation(n_modes=12, n_panels=8), seed)
        curve = op.curve(seed.modes)
        panels, u0, U = quiescent_velocity(op, curve)
        g, _, div = inextensible_tension(panels, u0, U)
        assert np.max(np.abs(div)) < 1e-7
        gam = tension_profile(curve, g, np.linspace(0.0, 1.0, 201))[0]
        ref = -6.0 * op.kappa / LAM**2
        xr, xf = curve.extent()
        eps.append(1.0 - curve.max_radius() / (0.5 * (xf - xr)))
        errs.append(float(np.max(np.abs(gam / ref - 1.0))))
    errs, eps = np.array(errs), np.array(eps)
    order = math.log(errs[0] / errs[1]) / math.log(eps[0] / eps[1])
    assert np.all(errs < 0.25 * eps), (errs, eps)
    assert order > 0.8, (errs, eps, order)


# ------------------------------------------------------------------ steady state (shared)
@pytest.fixture(scope="module")
def steady():
    """Newton steady state at (0.98, 0.3), pair 11/16 modes, uniform arc length (~20 s).
    Measured: V/U 1.88137869,
    residual max|u - V e_x| 1.19e-5 (its normal part 9.5e-6)."""
    res = solve_vesicle(NU, LAM, ca_b=CA_B, n_modes=16, tol=0.5, residual_tol=10.0,
                        density="uniform", seed_bank=False)
    # tol = 0.5 and residual_tol = 10 accept nearly any shape: success alone proves little, so
    # the state is held to the small-sphere limits (Faxén V/U = 2 - (4/3) lam^2 = 1.88 and
    # Chen et al. eq. small2 dp+ R0/(eta U) = 16 lam^6, within the 1 % and 3 % of
    # docs/validation.md) and to its measured steadiness (residual 1.19e-5)
    assert res.success, res.message
    assert res.V_over_U == pytest.approx(2 - 4 / 3 * LAM**2, rel=0.01)
    assert res.dp_plus_R0 == pytest.approx(16 * LAM**6, rel=0.03)
    assert res.residual < 1.5e-5
    return res


def test_integrating_from_the_newton_state_stays_steady(steady, report):
    """Five linearised backward Euler steps of 0.1 R/U (4x the explicit limit) from the Newton
    steady state (~4 s). Independent reference: the Newton solution, whose tension and V come
    from u = V e_x in least squares, not from inextensibility and eq. Vel. Measured:
    max|u.n - V n_x| 1.021e-5 at t = 0, 1.058e-5 at t = 0.5 (it drifts to the fixed point of
    the dynamics, within the truncation floor); V/U 1.8813787275 vs Newton 1.8813786914
    (1.9e-8 relative); modes moved 9.8e-7; tension within 1e-4 of Newton's (max 0.86)."""
    op = vesicle_operator(steady)
    newton = op.evaluate(op.curve(steady.modes))
    m0 = newton["curve"].modes
    modes, state, info = relax_vesicle(op, m0, 0.5, dt=0.1)
    assert not info["failure"] and info["steps"] == 5 and info["rejected"] == 0
    peaks = np.array([h[1] for h in info["history"]])
    report.value("dyn.steady16_peak", float(np.max(peaks)), reference=newton["residual"],
                 tol="1.2 × the Newton residual, and 1.5e-5", source="the Newton steady state")
    report.value("dyn.steady16_V", abs(state.V / steady.V_over_U - 1.0), reference=0.0,
                 tol="1e-6 rel", source="the Newton steady state")
    assert np.all(peaks <= 1.2 * newton["residual"]), (peaks, newton["residual"])
    # 1.5e-5, not the project's acceptance bound 1e-5: at this coarse default resolution (16
    # modes) the Newton state itself has residual 1.19e-5; the 1e-5 bound is held by the slow
    # 24-mode test_stays_steady_below_1e_5_at_24_modes (Newton residual 6.7e-7)
    assert np.all(peaks <= 1.5e-5)
    assert np.all(np.abs(np.array([h[2] for h in info["history"]]) / newton["V"] - 1) < 1e-6)
    assert abs(state.V / steady.V_over_U - 1.0) < 1e-6
    assert np.max(np.abs(modes - m0)) < 1e-5
    tt = np.linspace(0.0, 1.0, 101)
    g_dyn = tension_profile(state.curve, state.g, tt)[0]
    g_newton = tension_profile(state.curve, newton["g"], tt)[0]
    assert np.max(np.abs(g_dyn - g_newton)) < 1e-3 * np.max(np.abs(g_newton))
    assert abs(state.curve.area() / op.area - 1.0) < 1e-12
    assert abs(state.curve.volume() / op.volume - 1.0) < 1e-12
    assert np.max(np.abs(state.divergence)) < 1e-3                  # measured 5.6e-4


@pytest.mark.slow          # ~8 s; the default suite keeps the stays-steady test
def test_relaxation_from_a_spheroid_approaches_the_newton_state(steady):
    """From the prolate spheroid of nu = 0.98, implicit steps of up to 0.5 R/U until the peak
    normal velocity falls 100-fold (~8 s). Measured: max|u.n - V n_x| 6.57e-2 -> 5.98e-4 at
    t = 5.4 R/U in 16 steps (1 rejected, 2 Jacobians); V/U 1.89589 -> 1.88165 vs Newton
    1.88138 (relative error 7.7e-3 -> 1.5e-4)."""
    seed = spheroid_seed(NU, LAM, 16)
    op = VesicleOperator(NU, LAM, CA_B, DropDiscretisation(n_modes=16, n_panels=8), seed)
    first = vesicle_flow(op, op.curve(seed.modes))
    _, state, info = relax_vesicle(op, seed.modes, 20.0, dt=0.5,
                                   tol=first.max_residual() / 100)
    assert not info["failure"] and info["t"] < 20.0
    assert info["max_un"] < first.max_residual() / 100
    err0 = abs(first.V / steady.V_over_U - 1.0)
    err = abs(state.V / steady.V_over_U - 1.0)
    assert err < 3e-4 and err < err0 / 20, (err0, err)
    assert abs(state.curve.area() / op.area - 1.0) < 1e-12


def test_bad_input_is_rejected_before_any_work():
    for kwargs in ({"method": "rk4"}, {"dt": 0.0}, {"dt": -1.0}, {"tol": -1.0},
                   {"growth": 1.0}, {"jacobian_every": 0}):
        with pytest.raises(InvalidParameterError):
            relax_vesicle(None, np.zeros(4), 1.0, **kwargs)
    with pytest.raises(InvalidParameterError, match="t_end="):
        relax_vesicle(None, np.zeros(4), math.nan)


# ------------------------------------------------------------------ slow validation
@pytest.mark.slow          # ~25-50 s: the 16/24 pair (~12 s of Newton) and a 24-mode Jacobian
def test_stays_steady_below_1e_5_at_24_modes(report):
    """Project acceptance: integration from the Newton steady state stays steady with
    max|u.n - V n_x|/U <= 1e-5, and the normal velocity stays at the Newton state's residual
    (it does not grow). Measured at 24 modes (8 panels): Newton residual 6.7e-7 (the solver
    stops once below its residual_tol); max|u.n - V n_x| 6.9e-7 at t = 0 and 8.5e-7 after five
    steps of 0.1 R/U; V/U equal to Newton's to 6e-10; modes moved 3.3e-8."""
    res = solve_vesicle(NU, LAM, ca_b=CA_B, n_modes=24, tol=0.5, residual_tol=10.0)
    assert res.success, res.message       # nearly vacuous at these tolerances: see the fixture
    assert res.V_over_U == pytest.approx(2 - 4 / 3 * LAM**2, rel=0.01)
    assert res.dp_plus_R0 == pytest.approx(16 * LAM**6, rel=0.03)
    op = vesicle_operator(res)
    m0 = op.curve(res.modes).modes
    modes, state, info = relax_vesicle(op, m0, 0.5, dt=0.1)
    peaks = np.array([h[1] for h in info["history"]])
    assert not info["failure"] and info["steps"] == 5
    report.value("dyn.steady24_peak", float(np.max(peaks)), reference=0.0,
                 tol="2x the Newton residual (acceptance 1e-5)",
                 source="the Newton steady state, 24 modes")
    report.value("dyn.steady24_V", abs(state.V / res.V_over_U - 1.0), reference=0.0,
                 tol="1e-8 rel", source="the Newton steady state, 24 modes")
    assert np.all(peaks <= 1e-5)                      # the acceptance bound
    assert np.all(peaks <= 2.0 * res.residual)        # no growth beyond the Newton residual
    assert abs(state.V / res.V_over_U - 1.0) < 1e-8
    assert np.max(np.abs(modes - m0)) < 1e-7


@pytest.mark.slow          # ~15 s (plus the shared steady solve)
def test_long_relaxation_reaches_the_newton_state(steady, report):
    """Relaxed from the spheroid down to the truncation floor (max|u.n - V n_x| < 1.2e-5):
    measured at t = 13.7 R/U after 33 steps, V/U 1.8813809 vs Newton 1.8813787 (1.2e-6),
    modes within 2.1e-5 of Newton's."""
    seed = spheroid_seed(NU, LAM, 16)
    op = VesicleOperator(NU, LAM, CA_B, DropDiscretisation(n_modes=16, n_panels=8), seed)
    modes, state, info = relax_vesicle(op, seed.modes, 40.0, dt=0.5, tol=1.2e-5)
    assert not info["failure"] and info["max_un"] < 1.2e-5
    report.value("dyn.relax_V", abs(state.V / steady.V_over_U - 1.0), reference=0.0,
                 tol="3e-6 rel", source="the Newton steady state")
    assert abs(state.V / steady.V_over_U - 1.0) < 3e-6
    assert np.max(np.abs(modes - op.curve(steady.modes).modes)) < 1e-4


@pytest.mark.slow          # ~50 s
def test_explicit_stability_limit_is_set_by_the_fastest_membrane_mode(steady, report):
    """Stiffest eigenvalue of the mode-rate Jacobian at the steady state vs the flat-membrane
    rate (kappa q^3 + gamma q)/(4 eta) of the highest mode, q = N pi/S (Brochard & Lennon
    1975): measured -78.9 vs 76.4 (16 modes; -245 vs 237 at 24), limit 2/78.9 = 0.0254 R/U.
    Explicit Heun with the step control off, 40 steps after a kick of the two highest modes:
    peak x0.027 at 0.95 x the limit, x478 at 1.1 x. With the control on, a step of 2.4 x the
    limit is cut back (3 rejections, final step 0.0232 R/U) and the run ends at the steady
    peak 1.06e-5."""
    op = vesicle_operator(steady)
    base = vesicle_flow(op, op.curve(steady.modes))
    m0 = base.curve.modes
    J = _fd_jacobian(op, op.free(m0), m0, base, 1e-6)
    ev = np.linalg.eigvals(J)
    assert np.max(np.abs(ev.imag)) < 1e-6 * np.max(np.abs(ev)) and np.all(ev.real < 0)
    lam_max = float(-np.min(ev.real))
    q = m0.size * math.pi / base.curve.length
    gmax = np.max(np.abs(tension_profile(base.curve, base.g, np.linspace(0, 1, 201))[0]))
    report.value("dyn.stiffest_rate", lam_max,
                 reference=relaxation_rate_brochard_lennon_1975(q, op.kappa, gmax), tol="10 %",
                 source="Brochard & Lennon 1975: (kappa q^3 + gamma q)/(4 eta)")
    assert lam_max == pytest.approx(relaxation_rate_brochard_lennon_1975(q, op.kappa, gmax),
                                    rel=0.1)
    limit = 2.0 / lam_max
    kicked = m0.copy()
    kicked[-2:] += 1e-4                                    # excite the stiff modes
    ends = {}
    for factor in (0.95, 1.1):
        _, _, info = relax_vesicle(op, kicked, 40 * limit * factor, dt=limit * factor,
                                   method="heun", growth=1e9)
        ends[factor] = info["history"][-1][1] / info["history"][0][1]
    assert ends[0.95] < 0.1 and ends[1.1] > 1.0, ends
    _, _, info = relax_vesicle(op, kicked, 0.6, dt=2.4 * limit, method="heun")
    assert info["rejected"] >= 1 and info["dt"] < limit
    assert info["max_un"] < 1.2 * base.max_residual()
