"""Clean drop of viscosity ratio 1 in a tube: limits, regression values, the published table
(Chen et al. 2020) as a documented comparison, steadiness, convergence.

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
    panels_for,
    _solve_stage,
    newton_drop,
    relax_drop,
    solve_drop,
)
from bem.results import DROP_PROFILE_COLUMNS, DropResult
from bem.shape import SpectralCurve, fit_curve, spheroid_curve
from lubrication.checks import InvalidParameterError
from lubrication.results import Status

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable

# ------------------------------------------------------------------ lam = 0.8: references
#: Regression values, lam = 0.8: Ca -> (V/U, dp+ R/(eta U)), 10 digits of our converged solution
#: (solve_drop defaults: modes 24, 32, 40, ... until the refinement pair agrees to tol = 1e-5 and
#: the residual is below 1e-4). An independent computation confirmed every row to better than
#: 0.01 %.
CONVERGED = {0.05: (1.421944725, 2.665442334), 0.1: (1.454500852, 2.258456440),
             0.2: (1.531185791, 1.500898520), 0.3: (1.600922961, 0.9984984256),
             0.5: (1.702231729, 0.4867284708)}
#: Relative tolerance of the regression values: the solver's own error estimate (|fine - coarse|
#: of the refinement pair, an upper bound of the error, test_error_estimate_bounds_the_actual_
#: error) is at most 3.1e-8 in V/U (Ca = 0.3) and 2.4e-6 in dp+ (Ca = 0.5), relative; rounded up.
REGRESSION_RTOL = {"V_over_U": 1e-7, "dp_plus_R": 3e-6}

#: Chen et al. (2020) Table I (tab:comp), lam = 0.8: Ca -> (V/U, dp+ R/(eta U)), and the
#: two-digit values of Lac & Sherwood (2009) quoted there: documented comparisons, not references.
CHEN_TABLE_I = {0.05: (1.4218, 2.6591), 0.1: (1.4543, 2.2532), 0.2: (1.5311, 1.4981),
                0.3: (1.5999, 1.0063), 0.5: (1.7021, 0.4889)}
LAC_SHERWOOD = {0.05: (1.42, 2.65), 0.1: (1.45, 2.25), 0.2: (1.53, 1.50), 0.3: (1.60, 1.01),
                0.5: (1.70, 0.49)}
#: Measured deviation of Chen's values from the converged ones, 100 (Chen/ours - 1) [%], quoted to
#: 0.01 %: V/U within 0.07 %; dp+ 0.19-0.24 % below ours at Ca <= 0.2, 0.78 % and 0.45 % above
#: at Ca = 0.3 and 0.5. Chen's dp+ rows are off there (ours: refinement pair, independent
#: computation, test_ca_0p3_value_does_not_depend_on_the_tube_discretisation).
CHEN_DEVIATION = {0.05: (-0.01, -0.24), 0.1: (-0.01, -0.23), 0.2: (-0.01, -0.19),
                  0.3: (-0.06, 0.78), 0.5: (-0.01, 0.45)}
#: Margin on CHEN_DEVIATION [percentage points]: 0.005 from quoting to 0.01 % plus the regression
#: tolerance (3e-4 %), rounded up.
CHEN_MARGIN = 0.01
#: Lac & Sherwood's two-digit values from ours, largest absolute differences over the rows
#: (V/U, dp+): 0.0045 (Ca = 0.1) and 0.0154 (Ca = 0.05), i.e. outside their rounding interval
#: (0.005) in dp+ at Ca = 0.05, 0.1 and 0.3; bounds 0.005 and 0.016.
LAC_SHERWOOD_ABS = (0.005, 0.016)


def _assert_regression(res, ca, report=None):
    """``res`` (lam = 0.8) reproduces CONVERGED[ca] within REGRESSION_RTOL, and its own error
    estimate still supports that tolerance; the values are recorded if ``report`` is given."""
    assert res.success, res.message
    for key, value in zip(("V_over_U", "dp_plus_R"), CONVERGED[ca]):
        got = getattr(res, key)
        if report is not None:
            report.value(f"drop.{key}_{ca}", got, reference=value,
                         tol=f"{REGRESSION_RTOL[key]:g} rel", kind="regression",
                         source="our converged solution (CONVERGED)")
            report.value(f"drop.estimate_{key}_{ca}", res.error_estimate[key] / abs(got),
                         reference=0.0, tol=f"{REGRESSION_RTOL[key]:g} rel", kind="regression",
                         source="the refinement pair must support REGRESSION_RTOL")
        assert got == pytest.approx(value, rel=REGRESSION_RTOL[key]), (key, got, value)
        assert res.error_estimate[key] <= REGRESSION_RTOL[key] * abs(got), key
    assert res.dp_plus_R0 == pytest.approx(0.8 * res.dp_plus_R, rel=1e-14)


def _assert_published_deviations(res, ca, report=None):
    """Chen's row deviates from ``res`` by CHEN_DEVIATION[ca] +- CHEN_MARGIN, Lac & Sherwood's
    by less than LAC_SHERWOOD_ABS; recorded if ``report`` is given."""
    for k, key in enumerate(("V_over_U", "dp_plus_R")):
        dev = 100.0 * (CHEN_TABLE_I[ca][k] / getattr(res, key) - 1.0)
        if report is not None:
            report.value(f"drop.chen_dev_{key}_{ca}", dev, reference=CHEN_DEVIATION[ca][k],
                         tol=f"±{CHEN_MARGIN:g} pp", kind="regression",
                         source=f"{CHEN_TABLE_I[ca][k]}")
            report.value(f"drop.lac_diff_{key}_{ca}", abs(getattr(res, key) - LAC_SHERWOOD[ca][k]),
                         reference=LAC_SHERWOOD[ca][k], tol=f"{LAC_SHERWOOD_ABS[k]:g}",
                         source="Lac & Sherwood (2009), two digits")
        assert abs(dev - CHEN_DEVIATION[ca][k]) <= CHEN_MARGIN, (key, dev)
        assert abs(getattr(res, key) - LAC_SHERWOOD[ca][k]) < LAC_SHERWOOD_ABS[k], key


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


def test_speed_tends_to_2_minus_0p8_lam2_with_a_fifth_order_residual(small_drops, report):
    """V/U = 2 - 0.8 lam^2 + c lam^5 (notes §3, viscosity ratio 1): measured residual
    -5.02e-6, -1.53e-4, -1.08e-3 at lam = 0.1, 0.2, 0.3 (Ca = 0.05), local orders 4.93, 4.81,
    c = -0.50 as lam -> 0 (the rigid sphere has +0.32)."""
    lams, sols = small_drops
    assert all(s.success for s in sols), [s.message for s in sols]
    res = np.array([s.V_over_U - (2 - 0.8 * lam**2) for lam, s in zip(lams, sols)])
    order = np.log(res[1:] / res[:-1]) / np.log(lams[1:] / lams[:-1])
    notes = "notes §3: V/U = 2 - 0.8 lam^2 + O(lam^5)"
    for lam, r in zip(lams, res):
        report.value(f"drop.small_V_{lam:g}", r, source=notes)
    for i, o in enumerate(order):
        report.value(f"drop.small_V_order_{i}", o, reference=5.0, tol="±0.3", source=notes)
    assert np.all(np.abs(order - 5.0) < 0.3), order
    assert -0.53 < report.value("drop.small_V_coefficient", res[0] / lams[0] ** 5,
                                reference="−0.53 … −0.47", tol="inside (−0.53, −0.47)",
                                kind="regression",
                                source="our earlier measurement") < -0.47


def test_pressure_drop_tends_to_4p8_lam6_with_a_relative_fifth_order_residual(small_drops,
                                                                               report):
    """dp+ R0/(eta U) = 4.8 lam^6 (1 + c lam^5) (notes §3): measured relative residual 2.9e-5,
    9.2e-4, 6.6e-3 at lam = 0.1, 0.2, 0.3, local orders 4.97, 4.88 (absolute order 11, as for
    the rigid sphere's 16 lam^6)."""
    lams, sols = small_drops
    rel = np.array([s.dp_plus_R0 / (4.8 * lam**6) - 1 for lam, s in zip(lams, sols)])
    order = np.log(rel[1:] / rel[:-1]) / np.log(lams[1:] / lams[:-1])
    notes = "notes §3: 4.8 lam^6 (1 + O(lam^5))"
    for lam, r in zip(lams, rel):
        report.value(f"drop.small_dp_{lam:g}", r, source=notes)
    for i, o in enumerate(order):
        report.value(f"drop.small_dp_order_{i}", o, reference=5.0, tol="±0.3", source=notes)
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


def test_regression_values_ca_0p1(drop01, report):
    """Regression (our converged values, not a published reference): lam = 0.8, Ca = 0.1 gives
    V/U 1.454500852, dp+ R/(eta U) 2.258456440 within REGRESSION_RTOL (1e-7, 3e-6 relative)."""
    _assert_regression(drop01, 0.1, report)


def test_chen_table_I_row_ca_0p1_deviates_as_measured(drop01, report):
    """Documented comparison: Chen et al. Table I, Ca = 0.1 (V/U 1.4543, dp+ 2.2532) lies
    -0.01 % and -0.23 % from ours, within CHEN_MARGIN = 0.01 % of that."""
    _assert_published_deviations(drop01, 0.1, report)


def test_accuracy_diagnostics(drop01, report):
    """Pair difference (24 vs 32 modes) 4e-9 in V/U, 4e-8 in dp+; residual 3e-8; volume 2e-15."""
    report.value("drop.ca01_residual", drop01.residual, reference=0.0, tol=1e-6,
                 source="max|u.n - V n_x|")
    report.value("drop.ca01_volume_error", drop01.volume_error, reference=0.0, tol=1e-6,
                 source="4 pi lam^3/3")
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


def test_steady_state_stays_put(drop01, report):
    """A short time integration (u.n driven, tangential redistribution) from the Newton steady
    state keeps max|u.n - V n_x| <= 1e-6 and the volume to 1e-6 (measured: residual 3e-8 ->
    3e-8, modes move < 1e-8, V unchanged to 1e-9)."""
    n = drop01.panels["modes"]
    curve = drop01.curve()
    op = DropOperator(0.8, 0.1, DropDiscretisation(n, panels_for(n)), curve)
    modes, state, info = relax_drop(op, curve.modes, 0.05)
    assert not info["failure"] and info["steps"] >= 5
    report.value("drop.relax_residual", state.max_residual(), reference=0.0, tol=1e-6,
                 source="steady state after a short time integration")
    report.value("drop.relax_modes", np.max(np.abs(modes - curve.modes)), reference=0.0,
                 tol=1e-6, source="steady state after a short time integration")
    assert state.max_residual() <= 1e-6
    assert info["max_un"] <= 1e-6
    assert np.max(np.abs(modes - curve.modes)) < 1e-6
    assert abs(state.V_fit - drop01.V_over_U) < 1e-7
    p = state.panels
    vol = math.pi * np.sum(p.r**2 * p.tx * p.w)
    assert abs(vol / (4 / 3 * math.pi * 0.8**3) - 1) <= 1e-6


def test_residual_falls_spectrally_with_the_number_of_modes(drop01, report):
    """Fixed density (that of the converged drop), 12, 16, 24 modes: max|u.n - V n_x| =
    1.2e-3, 8.0e-5, 2.0e-6, observed algebraic orders 9.3, 9.1 (rising: spectral)."""
    seed = drop01.curve()
    ns = np.array([12, 16, 24])
    res = []
    for n in ns:
        rep, op = _solve_stage(0.8, 0.1, DropDiscretisation(int(n), panels_for(int(n))), seed,
                               drop01.V_over_U, seed.density)
        assert rep.success, rep.message
        res.append(_outputs(0.8, op, rep)["residual"])
    res = np.array(res)
    order = np.log(res[:-1] / res[1:]) / np.log(ns[1:] / ns[:-1])
    for n, r in zip(ns, res):
        report.value(f"drop.modes_residual_{n}", r, source="fixed density, Ca = 0.1")
    for i, o in enumerate(order):
        report.value(f"drop.modes_order_{i}", o, reference="spectral", tol="> 7",
                     source="fixed density, Ca = 0.1")
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
    res = solve_drop(0.5, 0.2, n_modes=8, tol=1e-12, residual_tol=1.0)
    assert res.status is Status.UNRESOLVED and not res.success and not res.converged
    assert math.isfinite(res.V_over_U)              # best numbers kept, flagged
    assert res.to_dict()["converged"] is False


def test_a_drop_touching_the_wall_is_rejected():
    # oblate spheroid of the volume of lam = 0.8 (a b^2 = 0.8^3), wider than the tube
    curve = fit_curve(spheroid_curve(0.8**3 / 1.05**2, 1.05), 0.0, math.pi, 12)
    op = DropOperator(0.8, 0.1, DropDiscretisation(12, 8), SpectralCurve.sphere(0.8, 12))
    with pytest.raises(InvalidParameterError, match="touching the wall"):
        op.state(SpectralCurve.closed(curve.modes, volume=4 / 3 * math.pi * 0.8**3))
    rep = newton_drop(op, curve.modes)
    assert rep.status is Status.REJECTED_START and "touching the wall" in rep.message


# ------------------------------------------------------------------ slow validation
@pytest.fixture(scope="module", params=sorted(CONVERGED))
def table_I_row(request):
    """(Ca, solve_drop(0.8, Ca)) for the rows of Chen et al.'s Table I."""
    return request.param, solve_drop(0.8, request.param)


@pytest.fixture(scope="module")
def drop03():
    return solve_drop(0.8, 0.3)


@pytest.mark.slow
def test_regression_values(table_I_row, report):
    """Regression (our converged values): every row of CONVERGED, lam = 0.8, Ca = 0.05 ... 0.5,
    within REGRESSION_RTOL (1e-7 in V/U, 3e-6 in dp+, relative), with the residual below 1e-4
    and the volume exact to 1e-6."""
    ca, res = table_I_row
    _assert_regression(res, ca, report if ca != 0.1 else None)   # 0.1: the default-suite test
    assert res.volume_error < 1e-6 and res.residual < 1e-4


@pytest.mark.slow
def test_chen_table_I_deviates_as_measured(table_I_row, report):
    """Documented comparison, not a reference. lam = 0.8, 100 (Chen/ours - 1):
    Ca     V/U ours      Chen    dev       dp+R ours      Chen    dev
    0.05   1.421944725   1.4218  -0.01 %   2.665442334    2.6591  -0.24 %
    0.1    1.454500852   1.4543  -0.01 %   2.258456440    2.2532  -0.23 %
    0.2    1.531185791   1.5311  -0.01 %   1.500898520    1.4981  -0.19 %
    0.3    1.600922961   1.5999  -0.06 %   0.9984984256   1.0063  +0.78 %
    0.5    1.702231729   1.7021  -0.01 %   0.4867284708   0.4889  +0.45 %
    asserted to CHEN_MARGIN = 0.01 percentage points. Chen's dp+ at Ca = 0.3 and 0.5 is off
    (our values: converged to the regression tolerance, confirmed independently to < 0.01 %,
    independent of the tube discretisation to 1e-12). Lac & Sherwood's two-digit values: V/U
    within 0.005, dp+ within 0.016."""
    ca, res = table_I_row
    _assert_published_deviations(res, ca, report if ca != 0.1 else None)   # 0.1: default suite


@pytest.mark.slow
def test_ca_0p3_value_does_not_depend_on_the_tube_discretisation(drop03, report):
    """The converged Ca = 0.3 shape re-solved (Newton from it, same modes) with the wall panels
    twice as fine, 24 instead of 16 Gauss nodes per panel with quadrature tolerance 1e-13, or
    the tube meshed to a 1e-15 decay criterion: V/U and dp+ change by less than 1e-10
    (measured <= 1.2e-12 relative)."""
    seed = drop03.curve()
    n = drop03.panels["modes"]
    base = DropDiscretisation(n, panels_for(n))
    largest = 0.0
    for change in ({"wall_refinement": 2.0}, {"order": 24, "quad_tol": 1e-13},
                   {"tube_tol": 1e-15}):
        rep, op = _solve_stage(0.8, 0.3, dataclasses.replace(base, **change), seed,
                               drop03.V_over_U, seed.density)
        assert rep.success, (change, rep.message)
        out = _outputs(0.8, op, rep)
        for key in ("V_over_U", "dp_plus_R"):
            largest = max(largest, abs(out[key] / getattr(drop03, key) - 1))
            assert out[key] == pytest.approx(getattr(drop03, key), rel=1e-10), (change, key)
    report.value("drop.tube_change", largest, reference=0.0, tol="1e-10 rel",
                 source="finer wall, 24-point panels, longer tube")


def _convergence_study(ca, ns, base=None):
    """Outputs and residuals on a sequence of mode counts at fixed density (from the solver's
    own converged solution ``base``), each level started from the previous one."""
    base = solve_drop(0.8, ca) if base is None else base
    seed = base.curve()
    outs = []
    prev, V = seed, base.V_over_U
    for n in ns:
        rep, op = _solve_stage(0.8, ca, DropDiscretisation(int(n), panels_for(int(n))), prev, V,
                               seed.density)
        assert rep.success, rep.message
        outs.append(_outputs(0.8, op, rep))
        prev, V = rep.state.curve, rep.V
    return outs


@pytest.mark.slow
@pytest.mark.ci
def test_observed_order_ca_0p1(drop01, report):
    """Ca = 0.1, modes 12, 16, 24, 32 (panels n/3) against 40: residual 1.2e-3, 8e-5, 2e-6,
    2.9e-8, 4.3e-10; overall observed order (12 -> 32) of the residual 15, of Δp⁺ 13, of V/U
    10 (spectral: local orders grow, 8 -> 20; with 48 modes as well, 12 -> 40: 13, 16, 15).
    The outputs' order is that of their error envelope (the largest error at this or more
    modes): a single level can sit at a sign change of its error (V/U at 12 modes, 2.7e-8,
    below 1.9e-7 at 16)."""
    ns = np.array([12, 16, 24, 32, 40])
    outs = _convergence_study(0.1, ns, drop01)
    res = np.array([o["residual"] for o in outs])
    o_res = math.log(res[0] / res[-2]) / math.log(ns[-2] / ns[0])
    report.value("drop.order_ca01_residual", o_res, reference="spectral", tol="> 10",
                 source="modes 12 -> 32")
    assert o_res > 10, (res, o_res)
    for key in ("V_over_U", "dp_plus_R"):
        e = np.array([abs(o[key] / outs[-1][key] - 1) for o in outs[:-1]])
        e = np.maximum.accumulate(e[::-1])[::-1]           # the envelope from more modes
        o = math.log(e[0] / max(e[-1], 1e-15)) / math.log(ns[-2] / ns[0])
        report.value(f"drop.order_ca01_{key}", o, reference="spectral", tol="> 8",
                     source="modes 12 -> 32 against 40")
        assert o > 8, (key, e, o)
    assert all(o["volume_error"] < 1e-12 for o in outs)


@pytest.mark.slow
def test_observed_order_ca_0p5(report):
    """Ca = 0.5 (flattened rear with a sharp rim, density from the curvature): residual 1.0e-2,
    8e-4, 3.4e-4, 1.4e-4, 3.7e-5, 1.3e-6, 4.2e-7 at 12 ... 48 modes, overall order ~7;
    Δp⁺ error 1.2e-2 at 12 modes, 2.4e-6 at 32, 2.5e-8 at 40 (pre-asymptotic plateau 16-24)."""
    ns = np.array([12, 16, 20, 24, 32, 40, 48])
    outs = _convergence_study(0.5, ns)
    res = np.array([o["residual"] for o in outs])
    report.value("drop.ca05_residual_first", res[0], source="12 modes")
    report.value("drop.ca05_residual_last", res[-1], source="48 modes")
    o_res = report.value("drop.ca05_order_residual",
                         math.log(res[0] / res[-1]) / math.log(ns[-1] / ns[0]),
                         reference="spectral", tol="> 5", source="modes 12 -> 48")
    assert o_res > 5, res
    e = np.array([abs(o["dp_plus_R"] / outs[-1]["dp_plus_R"] - 1) for o in outs[:-1]])
    report.value("drop.ca05_dp_error_40", e[-1], reference=0.0, tol=1e-6,
                 source="40 against 48 modes")
    o_dp = report.value("drop.ca05_order_dp", math.log(e[0] / e[-1]) / math.log(ns[-2] / ns[0]),
                        reference="spectral", tol="> 5", source="modes 12 -> 40 against 48")
    assert e[-1] < 1e-6 and o_dp > 5, e


@pytest.mark.slow
def test_error_estimate_bounds_the_actual_error(drop03, report):
    """Ca = 0.3: the reported |fine - coarse| exceeds the difference to a 48-mode solution."""
    res = drop03
    seed = res.curve()
    rep, op = _solve_stage(0.8, 0.3, DropDiscretisation(48, panels_for(48)), seed, res.V_over_U,
                           seed.density)
    fine = _outputs(0.8, op, rep)
    for key in ("V_over_U", "dp_plus_R"):
        report.value(f"drop.bound_{key}", abs(getattr(res, key) - fine[key]) / res.error_estimate[key],
                     reference=1.0, tol="<= 1", source="48-mode solution")
        assert abs(getattr(res, key) - fine[key]) <= res.error_estimate[key], key


@pytest.mark.slow
def test_a_drop_without_steady_shape_is_reported():
    """Ca = 3: Newton fails from the sphere and after a relaxation (t = 6 R/U); the result is
    success False with the reason, and no numbers."""
    res = solve_drop(0.8, 3.0)
    assert res.status is Status.NO_STEADY_STATE, res.message
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
    assert res.status is Status.TIME_LIMIT and not res.success
    d = res.to_dict()
    assert d["V_over_U"] is None and d["dp_plus_R"] is None and d["shape"] is None
