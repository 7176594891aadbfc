"""The steady vesicle solver's ladder: extrapolated error estimate, seeds.

Units: R = 1, U the mean velocity, lam = R0/R, Ca_B = eta U R0^2/kappa = 50.
"""

import math

import pytest

from bem.vesicle import ESTIMATE_SAFETY, MIN_CONTRACTION, _error_estimate, solve_vesicle


def _levels(values):
    return [{"V_over_U": v, "dp_plus_R0": 10.0 * v, "tension_max": -v} for v in values]


@pytest.mark.parametrize("rho", [0.05, 0.1, 0.2, 0.35, 0.6])
@pytest.mark.parametrize("sign", [1.0, -1.0])           # monotone or alternating differences
def test_error_estimate_bounds_a_geometric_sequence(rho, sign):
    """q_k = q_inf + C (sign rho)^k, k = 1..3 (a spectral ladder): the closed-form error of the
    last level, C rho^3, is never above the estimate. Monotone: the estimate is the series'
    tail times ESTIMATE_SAFETY (rho >= MIN_CONTRACTION; ~6x at 0.05 through the floor).
    Alternating: the tail of |d| over-counts by (1 + rho)/(1 - rho), so the estimate is
    3(1 + rho)/(1 - rho) times the error: within 10x up to rho = 0.5 (12x at 0.6)."""
    q_inf, c = 1.3, 0.2
    q = [q_inf + c * (sign * rho) ** k for k in (1, 2, 3)]
    est = _error_estimate(_levels(q))
    true = c * rho**3
    assert true <= est["V_over_U"]
    assert est["dp_plus_R0"] == pytest.approx(10.0 * est["V_over_U"], rel=1e-9)
    if sign > 0 and rho >= MIN_CONTRACTION:
        assert est["V_over_U"] == pytest.approx(ESTIMATE_SAFETY * true, rel=1e-9)
    elif sign < 0 and rho >= MIN_CONTRACTION:
        factor = ESTIMATE_SAFETY * (1 + rho) / (1 - rho)
        assert est["V_over_U"] == pytest.approx(factor * true, rel=1e-9)
    if sign > 0 or rho <= 0.5:
        assert est["V_over_U"] <= 10.0 * true


def test_error_estimate_without_contraction_or_with_few_levels():
    """Two levels: the pair difference; growing differences: their sum; one level: NaN."""
    assert _error_estimate(_levels([1.0, 1.5]))["V_over_U"] == pytest.approx(0.5)
    assert _error_estimate(_levels([1.0, 1.1, 1.3]))["V_over_U"] == pytest.approx(0.3)
    assert math.isnan(_error_estimate(_levels([1.0]))["V_over_U"])


@pytest.mark.slow
def test_default_solve_reaches_the_genuine_state_where_the_lubrication_branch_ends():
    """(0.7, 1.2): the lubrication branch ends at lam/lam_c = 0.875 > 0.69, and a spheroid seed
    ends in a fore-aft symmetric least-squares minimum (residual 1.5e-2 at 40-64 modes, V/U
    1.386, not a steady state). The default seed (lubrication at 0.9 lam_c) converges
    geometrically: measured 48 modes, residual 4e-5, V/U 1.2591253, dp+R0 24.93230, gamma_max
    18.7684 (about 70 s on 2 loaded cores)."""
    res = solve_vesicle(0.7, 1.2)
    assert res.success, res.message
    assert res.residual < 1e-4
    assert res.V_over_U == pytest.approx(1.2591253, abs=1e-6)
    assert res.dp_plus_R0 == pytest.approx(24.93230, rel=1e-5)
    assert res.error_estimate["V_over_U"] < 1e-6
