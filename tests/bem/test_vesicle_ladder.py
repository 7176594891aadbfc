"""The steady vesicle solver's ladder: extrapolated error estimate, seeds.

Units: R = 1, U the mean velocity, lam = R0/R, Ca_B = eta U R0^2/kappa = 50.
"""

import math

import pytest

from bem.vesicle import solve_vesicle
from bem.vesicle.ladder import ESTIMATE_SAFETY, MIN_CONTRACTION, _error_estimate


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


def test_error_estimate_shares_the_contraction_of_the_outputs(report):
    """The recorded consistent ladder of the default solve at (0.6, 1.94), Ca_B = 50.01 (64 to
    96 modes): V/U and gamma_max contract by 0.29-0.37 per level while the dp+ differences are
    +0.043, +0.056, +0.037. With the median contraction the 96-mode dp+ estimate is within
    tol = 1e-4 (on dp+'s own ratio 0.66 it was 0.21, 1.2e-4 relative, and the solve ended not
    converged) and still above the true error against the mode-converged value 1778.364
    (uncertainty 0.0064, docs/validation.md; independent reference)."""
    ladder = [(1.021753986284925, 1778.5676773020396, 936.774180895389),
              (1.0211115492785439, 1778.2286355171807, 984.1322544254806),
              (1.0208949620553296, 1778.2715180826492, 1001.5407286404236),
              (1.0208139654246577, 1778.3275483914058, 1007.9805076450023),
              (1.0207878101933006, 1778.3644295660795, 1009.8686949067805)]
    outs = [dict(zip(("V_over_U", "dp_plus_R0", "tension_max"), row)) for row in ladder]
    est = _error_estimate(outs)
    rho = 0.3228                       # median: V/U's (2.6e-5 / 8.1e-5)
    d2 = ladder[-1][1] - ladder[-2][1]
    assert est["dp_plus_R0"] == pytest.approx(ESTIMATE_SAFETY * d2 * rho / (1 - rho), rel=1e-3)
    assert est["dp_plus_R0"] <= 1e-4 * ladder[-1][1]
    assert est["dp_plus_R0"] >= abs(ladder[-1][1] - 1778.364) + 0.0064
    report.value("ves.ladder_5001_dp_estimate", est["dp_plus_R0"] / ladder[-1][1],
                 reference="<= tol 1e-4 rel, >= true error + reference uncertainty",
                 tol="1e-4 rel")
    own = abs(ladder[-1][1] - ladder[-2][1]) / abs(ladder[-2][1] - ladder[-3][1])
    report.value("ves.ladder_5001_dp_own_estimate",
                 ESTIMATE_SAFETY * d2 * own / (1 - own) / ladder[-1][1],
                 reference="the former rule (the output's own contraction)", kind="regression")
    # an output whose differences grow is estimated at least at its last difference
    # (V/U and dp+ contracting by 0.1: the tail would be 0.33 times the last difference)
    grown = _levels([1.3 + 0.2 * 0.1**k for k in (1, 2, 3)])
    for o, t in zip(grown, (1.0, 1.1, 1.3)):
        o["tension_max"] = t
    assert _error_estimate(grown)["tension_max"] == pytest.approx(0.2)


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
