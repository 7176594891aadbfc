"""Clean drop of viscosity ratio 1 in a tube: limits, published values, steadiness, convergence.

Units: R = 1, U the mean velocity, lam = R0/R, Ca = eta U/gamma. Measured numbers quoted in the
comments come from this solver (16-point panels, default tolerances).
"""

import dataclasses
import json
import math

import numpy as np
import pytest

from bem.drop import (
    DropDiscretisation,
    DropOperator,
    _outputs,
    _panels_for,
    _solve_stage,
    newton_drop,
    relax_drop,
    solve_drop,
)
from bem.results import DROP_PROFILE_COLUMNS, DropResult
from bem.shape import SpectralCurve, fit_curve, spheroid_curve
from lubrication.checks import InvalidParameterError

# Chen et al. (2020) Table I (tab:comp), lam = 0.8: Ca -> (V/U, dp+ R/(eta U)), and the
# two-digit values of Lac & Sherwood (2009) quoted there.
CHEN_TABLE_I = {0.05: (1.4218, 2.6591), 0.1: (1.4543, 2.2532), 0.2: (1.5311, 1.4981),
                0.3: (1.5999, 1.0063), 0.5: (1.7021, 0.4889)}
LAC_SHERWOOD = {0.05: (1.42, 2.65), 0.1: (1.45, 2.25), 0.2: (1.53, 1.50), 0.3: (1.60, 1.01),
                0.5: (1.70, 0.49)}
# Our converged digits (automatic refinement, tol 1e-5; the pair agrees to < 2e-6 relative):
OURS = {0.05: (1.42194472, 2.6654423), 0.1: (1.45450085, 2.2584564),
        0.2: (1.53118579, 1.5008985), 0.3: (1.60092296, 0.9984984),
        0.5: (1.70223173, 0.4867285)}


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("lam, ca", [(0.0, 0.1), (-0.1, 0.1), (1.0, 0.1), (1.2, 0.1),
                                     (math.nan, 0.1), (math.inf, 0.1), (0.5, 0.0),
                                     (0.5, -1.0), (0.5, math.nan), (0.5, math.inf)])
def test_bad_input_is_rejected(lam, ca):
    with pytest.raises(InvalidParameterError, match="lam=|ca="):
        solve_drop(lam, ca)


def test_bad_options_are_rejected():
    with pytest.raises(InvalidParameterError, match="tol="):
        solve_drop(0.5, 0.1, tol=0.0)
    with pytest.raises(InvalidParameterError, match="n_modes="):
        solve_drop(0.5, 0.1, n_modes=2)


# ------------------------------------------------------------------ small-drop limits
@pytest.fixture(scope="module")
def small_drops():
    lams = np.array([0.1, 0.2, 0.3])
    return lams, [solve_drop(lam, 0.05, n_modes=16) for lam in lams]


def test_speed_tends_to_2_minus_0p8_lam2_with_a_fifth_order_residual(small_drops):
    """V/U = 2 - 0.8 lam^2 + c lam^5 (notes §3, viscosity ratio 1): measured residual
    -5.02e-6, -1.53e-4, -1.08e-3 at lam = 0.1, 0.2, 0.3 (Ca = 0.05), local orders 4.93, 4.81,
    c = -0.50 as lam -> 0 (the rigid sphere has +0.32)."""
    lams, sols = small_drops
    assert all(s.success for s in sols), [s.message for s in sols]
    res = np.array([s.V_over_U - (2 - 0.8 * lam**2) for lam, s in zip(lams, sols)])
    order = np.log(res[1:] / res[:-1]) / np.log(lams[1:] / lams[:-1])
    assert np.all(np.abs(order - 5.0) < 0.3), order
    assert -0.53 < res[0] / lams[0] ** 5 < -0.47


def test_pressure_drop_tends_to_4p8_lam6_with_a_relative_fifth_order_residual(small_drops):
    """dp+ R0/(eta U) = 4.8 lam^6 (1 + c lam^5) (notes §3): measured relative residual 2.9e-5,
    9.2e-4, 6.6e-3 at lam = 0.1, 0.2, 0.3, local orders 4.97, 4.88 (absolute order 11, as for
    the rigid sphere's 16 lam^6)."""
    lams, sols = small_drops
    rel = np.array([s.dp_plus_R0 / (4.8 * lam**6) - 1 for lam, s in zip(lams, sols)])
    order = np.log(rel[1:] / rel[:-1]) / np.log(lams[1:] / lams[:-1])
    assert np.all(np.abs(order - 5.0) < 0.3), order
    assert 0 < rel[0] < 5e-5
    for lam, s in zip(lams, sols):
        assert s.dp_plus_R == pytest.approx(s.dp_plus_R0 / lam, rel=1e-14)


def test_small_drops_stay_nearly_spherical(small_drops):
    """At lam = 0.1, Ca = 0.05 the length is 2 lam to 1e-5 and the front curvature 1/lam to
    2.6e-3 (measured), the deformation falling with lam."""
    lams, sols = small_drops
    assert abs(sols[0].length / (2 * lams[0]) - 1) < 1e-4
    dev = [abs(s.curvature_front * lam - 1) for lam, s in zip(lams, sols)]
    assert dev[0] < 5e-3 and dev[0] < dev[1] < dev[2], dev


# ------------------------------------------------------------------ lam = 0.8, Ca = 0.1
@pytest.fixture(scope="module")
def drop01():
    return solve_drop(0.8, 0.1)


def test_table_I_row_ca_0p1_within_0p3_percent(drop01):
    """Chen et al. Table I, Ca = 0.1: V/U 1.4543, dp+ R/(eta U) 2.2532. Ours: 1.45450085,
    2.2584564 (+0.014 %, +0.23 %)."""
    V, dp = CHEN_TABLE_I[0.1]
    assert drop01.success, drop01.message
    assert abs(drop01.V_over_U / V - 1) < 3e-3
    assert abs(drop01.dp_plus_R / dp - 1) < 3e-3
    assert drop01.V_over_U == pytest.approx(OURS[0.1][0], abs=2e-8)
    assert drop01.dp_plus_R == pytest.approx(OURS[0.1][1], abs=2e-7)
    assert drop01.dp_plus_R0 == pytest.approx(0.8 * drop01.dp_plus_R, rel=1e-14)


def test_accuracy_diagnostics(drop01):
    """Pair difference (24 vs 32 modes) 4e-9 in V/U, 4e-8 in dp+; residual 3e-8; volume 2e-15."""
    assert drop01.error_estimate["V_over_U"] < 1e-7
    assert drop01.error_estimate["dp_plus_R"] < 1e-6
    assert drop01.residual < 1e-6
    assert drop01.volume_error < 1e-6
    assert drop01.panels["modes"] > drop01.panels_coarse["modes"]
    # shape: poles on the axis, centroid at 0, pole curvatures from both principal values
    assert drop01.r[0] == 0 and drop01.r[-1] == 0
    assert drop01.curvature_front == pytest.approx(drop01.kappa1[-1], rel=1e-12)
    assert drop01.curvature_rear == pytest.approx(drop01.kappa2[0], rel=1e-12)
    assert drop01.curvature_front > drop01.curvature_rear > 0        # bullet: pointed front
    assert abs(drop01.curve().centroid()) < 1e-12
    assert drop01.max_radius < 1 and drop01.film == pytest.approx(1 - drop01.max_radius)


def test_steady_state_stays_put(drop01):
    """A short time integration (u.n driven, tangential redistribution) from the Newton steady
    state keeps max|u.n - V n_x| <= 1e-6 and the volume to 1e-6 (measured: residual 3e-8 ->
    3e-8, modes move < 1e-8, V unchanged to 1e-9)."""
    n = drop01.panels["modes"]
    curve = drop01.curve()
    op = DropOperator(0.8, 0.1, DropDiscretisation(n, _panels_for(n)), curve)
    modes, state, info = relax_drop(op, curve.modes, 0.05)
    assert not info["failure"] and info["steps"] >= 5
    assert state.max_residual() <= 1e-6
    assert info["max_un"] <= 1e-6
    assert np.max(np.abs(modes - curve.modes)) < 1e-6
    assert abs(state.V_fit - drop01.V_over_U) < 1e-7
    p = state.panels
    vol = math.pi * np.sum(p.r**2 * p.tx * p.w)
    assert abs(vol / (4 / 3 * math.pi * 0.8**3) - 1) <= 1e-6


def test_residual_falls_spectrally_with_the_number_of_modes(drop01):
    """Fixed density (that of the converged drop), 12, 16, 24 modes: max|u.n - V n_x| =
    1.2e-3, 8.0e-5, 2.0e-6, observed algebraic orders 9.3, 9.1 (rising: spectral)."""
    seed = drop01.curve()
    ns = np.array([12, 16, 24])
    res = []
    for n in ns:
        rep, op = _solve_stage(0.8, 0.1, DropDiscretisation(int(n), _panels_for(int(n))), seed,
                               drop01.V_over_U, seed.density)
        assert rep.success, rep.message
        res.append(_outputs(0.8, op, rep)["residual"])
    res = np.array(res)
    order = np.log(res[:-1] / res[1:]) / np.log(ns[1:] / ns[:-1])
    assert np.all(order > 7), (res, order)


def test_result_is_frozen_serialisable_and_saved_atomically(drop01, tmp_path):
    assert isinstance(drop01, DropResult)
    with pytest.raises(dataclasses.FrozenInstanceError):
        drop01.ca = 0.2
    d = drop01.to_dict()
    text = json.dumps(d, allow_nan=False)
    assert json.loads(text)["converged"] is True
    for key in ("V_over_U", "dp_plus_R", "dp_plus_R0", "error_estimate", "panels", "residual",
                "volume_error", "timings", "provenance", "curvature_front", "curvature_rear"):
        assert key in d, key
    assert set(d["provenance"]) >= {"python", "numpy", "scipy", "numba"}
    jpath, cpath = drop01.save(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([jpath.name, cpath.name])
    saved = json.loads(jpath.read_text())
    assert saved["V_over_U"] == drop01.V_over_U
    assert len(saved["shape"]["modes"]) == drop01.panels["modes"]
    rows = cpath.read_text().splitlines()
    assert rows[0].split(",") == [name for name, _ in DROP_PROFILE_COLUMNS]
    table = np.array([[float(v) for v in row.split(",")] for row in rows[1:]])
    assert np.allclose(table[:, 1], drop01.x) and np.allclose(table[:, 2], drop01.r)


def test_warm_start_reproduces_the_solution(drop01):
    again = solve_drop(0.8, 0.1, initial=drop01, n_modes=24)
    assert again.success, again.message
    assert again.V_over_U == pytest.approx(drop01.V_over_U, abs=1e-7)
    assert again.dp_plus_R == pytest.approx(drop01.dp_plus_R, abs=1e-6)


# ------------------------------------------------------------------ failures are reported
def test_refinement_pair_disagreement_is_reported_not_hidden():
    res = solve_drop(0.5, 0.2, n_modes=8, tol=1e-12)
    assert not res.success and not res.converged
    assert "refinement pair" in res.message
    assert math.isfinite(res.V_over_U)              # best numbers kept, flagged
    assert res.to_dict()["converged"] is False


def test_a_drop_touching_the_wall_is_rejected():
    # oblate spheroid of the volume of lam = 0.8 (a b^2 = 0.8^3), wider than the tube
    curve = fit_curve(spheroid_curve(0.8**3 / 1.05**2, 1.05), 0.0, math.pi, 12)
    op = DropOperator(0.8, 0.1, DropDiscretisation(12, 8), SpectralCurve.sphere(0.8, 12))
    with pytest.raises(InvalidParameterError, match="touching the wall"):
        op.state(SpectralCurve.closed(curve.modes, volume=4 / 3 * math.pi * 0.8**3))
    rep = newton_drop(op, curve.modes)
    assert not rep.success and "touching the wall" in rep.message


# ------------------------------------------------------------------ slow validation
@pytest.mark.slow
@pytest.mark.parametrize("ca", sorted(CHEN_TABLE_I))
def test_chen_table_I(ca):
    """lam = 0.8. Ours vs Chen et al. (2020) Table I, relative differences:
    Ca     V/U ours    Chen    diff       dp+R ours   Chen    diff
    0.05   1.4219447   1.4218  +0.010 %   2.6654423   2.6591  +0.24 %
    0.1    1.4545009   1.4543  +0.014 %   2.2584564   2.2532  +0.23 %
    0.2    1.5311858   1.5311  +0.006 %   1.5008985   1.4981  +0.19 %
    0.3    1.6009230   1.5999  +0.064 %   0.9984984   1.0063  -0.78 %
    0.5    1.7022317   1.7021  +0.008 %   0.4867285   0.4889  -0.44 %
    V/U agrees within 0.3 % everywhere. Δp⁺ agrees within 0.3 % for Ca <= 0.2 only: at
    Ca = 0.3 and 0.5 the differences are 0.78 % and 0.44 %, larger than the brief's 0.3 %.
    Our values are converged to < 2e-6 (refinement pair, spectral in the modes), satisfy
    the small-drop limits, and the wall pressure far upstream equals Δp⁺ to 1e-13; Chen's
    Ca = 0.3 row (V and Δp⁺ together) coincides with our solution at Ca = 0.2984, as a
    not fully relaxed time integration would. The bound for Δp⁺ is therefore 0.3 % for
    Ca <= 0.2; the Ca = 0.3 and 0.5 rows are asserted at 0.3 % in
    test_chen_table_I_dp_plus_above_ca_0p2, a strict xfail that records the open disagreement.
    Lac & Sherwood's two-digit values: V/U within 0.005, Δp⁺ within 0.016 (0.6 %, 0.4 %,
    0.06 %, 1.1 %, 0.7 %)."""
    res = solve_drop(0.8, ca)
    assert res.success, res.message
    V, dp = CHEN_TABLE_I[ca]
    assert abs(res.V_over_U / V - 1) < 3e-3
    if ca <= 0.2:
        assert abs(res.dp_plus_R / dp - 1) < 3e-3
    assert res.V_over_U == pytest.approx(OURS[ca][0], abs=5e-8)
    assert res.dp_plus_R == pytest.approx(OURS[ca][1], abs=2e-6)
    V_ls, dp_ls = LAC_SHERWOOD[ca]
    assert abs(res.V_over_U - V_ls) < 0.005 and abs(res.dp_plus_R - dp_ls) < 0.016
    assert res.volume_error < 1e-6 and res.residual < 1e-4


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason=(
    "open disagreement with Chen et al. Table I: our converged dp+ R/(eta U) differs by -0.78 % "
    "(Ca = 0.3) and -0.44 % (Ca = 0.5), beyond the 0.3 % asked; see test_chen_table_I and "
    "docs/validation.md"))
@pytest.mark.parametrize("ca", [0.3, 0.5])
def test_chen_table_I_dp_plus_above_ca_0p2(ca):
    res = solve_drop(0.8, ca)
    assert abs(res.dp_plus_R / CHEN_TABLE_I[ca][1] - 1) < 3e-3


def _convergence_study(ca, ns, base=None):
    """Outputs and residuals on a sequence of mode counts at fixed density (from the solver's
    own converged solution ``base``), each level started from the previous one."""
    base = solve_drop(0.8, ca) if base is None else base
    seed = base.curve()
    outs = []
    prev, V = seed, base.V_over_U
    for n in ns:
        rep, op = _solve_stage(0.8, ca, DropDiscretisation(int(n), _panels_for(int(n))), prev, V,
                               seed.density)
        assert rep.success, rep.message
        outs.append(_outputs(0.8, op, rep))
        prev, V = rep.state.curve, rep.V
    return outs


@pytest.mark.slow
@pytest.mark.ci
def test_observed_order_ca_0p1(drop01):
    """Ca = 0.1, modes 12, 16, 24, 32 (panels n/3) against 40: residual 1.2e-3, 8e-5, 2e-6,
    2.9e-8, 4.3e-10; overall observed order (12 -> 32) of the residual 15, of Δp⁺ 15, of V/U
    ~9 (spectral: local orders grow, 8 -> 20; with 48 modes as well, 12 -> 40: 13, 16, 15)."""
    ns = np.array([12, 16, 24, 32, 40])
    outs = _convergence_study(0.1, ns, drop01)
    res = np.array([o["residual"] for o in outs])
    o_res = math.log(res[0] / res[-2]) / math.log(ns[-2] / ns[0])
    assert o_res > 10, (res, o_res)
    for key in ("V_over_U", "dp_plus_R"):
        e = np.array([abs(o[key] / outs[-1][key] - 1) for o in outs[:-1]])
        o = math.log(e[0] / max(e[-1], 1e-15)) / math.log(ns[-2] / ns[0])
        assert o > 8, (key, e, o)
    assert all(o["volume_error"] < 1e-12 for o in outs)


@pytest.mark.slow
def test_observed_order_ca_0p5():
    """Ca = 0.5 (flattened rear with a sharp rim, density from the curvature): residual 1.0e-2,
    8e-4, 3.4e-4, 1.4e-4, 3.7e-5, 1.3e-6, 4.2e-7 at 12 ... 48 modes, overall order ~7;
    Δp⁺ error 1.2e-2 at 12 modes, 2.4e-6 at 32, 2.5e-8 at 40 (pre-asymptotic plateau 16-24)."""
    ns = np.array([12, 16, 20, 24, 32, 40, 48])
    outs = _convergence_study(0.5, ns)
    res = np.array([o["residual"] for o in outs])
    assert math.log(res[0] / res[-1]) / math.log(ns[-1] / ns[0]) > 5, res
    e = np.array([abs(o["dp_plus_R"] / outs[-1]["dp_plus_R"] - 1) for o in outs[:-1]])
    assert e[-1] < 1e-6 and math.log(e[0] / e[-1]) / math.log(ns[-2] / ns[0]) > 5, e


@pytest.mark.slow
def test_error_estimate_bounds_the_actual_error():
    """Ca = 0.3: the reported |fine - coarse| exceeds the difference to a 48-mode solution."""
    res = solve_drop(0.8, 0.3)
    seed = res.curve()
    rep, op = _solve_stage(0.8, 0.3, DropDiscretisation(48, _panels_for(48)), seed, res.V_over_U,
                           seed.density)
    fine = _outputs(0.8, op, rep)
    for key in ("V_over_U", "dp_plus_R"):
        assert abs(getattr(res, key) - fine[key]) <= res.error_estimate[key], key


@pytest.mark.slow
def test_a_drop_without_steady_shape_is_reported():
    """Ca = 3: Newton fails from the sphere and after a relaxation (t = 6 R/U); the result is
    success False with the reason, and no numbers."""
    res = solve_drop(0.8, 3.0)
    assert not res.success
    assert "no steady shape" in res.message
    assert math.isnan(res.V_over_U)


# ------------------------------------------------------------------ resource envelope
@pytest.mark.parametrize("kwargs, needle", [
    ({"lam": 0.5, "ca": 1e-300}, "ca="), ({"lam": 0.5, "ca": 1e308}, "ca="),
    ({"lam": 1e-320, "ca": 0.1}, "lam="), ({"lam": 0.5, "ca": 0.1, "n_modes": 10**21}, "n_modes="),
    ({"lam": 0.5, "ca": 0.1, "max_modes": 500}, "max_modes="),
    ({"lam": 0.5, "ca": 0.1, "max_time": math.nan}, "max_time="),
])
def test_requests_outside_the_envelope_are_refused_up_front(kwargs, needle):
    with pytest.raises(InvalidParameterError, match=needle):
        solve_drop(**kwargs)


def test_spent_time_budget_is_an_unconverged_result_without_numbers():
    res = solve_drop(0.3, 0.1, n_modes=8, max_time=1e-9)
    assert not res.success and "time limit" in res.message
    d = res.to_dict()
    assert d["V_over_U"] is None and d["dp_plus_R"] is None and d["shape"] is None
