"""BEM vesicle against the lubrication solver near the critical confinement (slow validation).

Units: R = 1, U the mean velocity, lam = R0/R, Ca_B = eta U R0^2/kappa = 50 for both solvers.
Lubrication (Secomb et al. 1986 / Barakat & Shaqfeh 2018b, :mod:`lubrication.solve`) is the
asymptotically exact limit of the Stokes problem as lam -> lam_c, so the two solvers must agree
there, with a difference that shrinks as the film thins (that rate is measured at nu = 0.9 in
tests/bem/test_vesicle.py and docs/validation.md). Measured at nu = 0.9, 48 modes:

  lam/lam_c   V/U BEM / lub.        dp+R0/(eta U) BEM / lub.   residual
  0.95        1.048257 / 1.048661   146.2 / 136.9 (+6.8 %)     3.2e-4
  0.97        1.028833 / 1.028948   245.8 / 234.9 (+4.65 %)    1.2e-3

Scope: the issue asks for nu in [0.6, 0.95]; below nu ~ 0.85 the steady solver does not reach
lam/lam_c = 0.95 with 48 modes (long vesicles: the global spectral shape needs ~100 modes to
resolve the film ends, docs/validation.md), so the property is drawn from nu in [0.85, 0.95]
and this narrowing is reported in the issue.
"""

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from bem.vesicle import solve_vesicle
from lubrication.solve import solve_lubrication

# Near lam_c the 48-mode residual is ~1e-3 and the refinement pair differs by ~0.3-1 % in dp+
# (docs/validation.md), far below the BEM-lubrication differences asserted here.
KW = {"max_modes": 48, "tol": 1e-2, "residual_tol": 5e-3}


@pytest.mark.slow          # ~4-8 min per example (continuation rungs + 16..48 modes)
@settings(max_examples=2, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(nu=st.floats(0.85, 0.95), ratio=st.floats(0.95, 0.97))
@example(nu=0.9, ratio=0.95)
def test_bem_agrees_with_lubrication_near_lam_c(nu, ratio):
    """V/U within 0.1 % and dp+ within 10 % of lubrication (measured at (0.9, 0.95): -0.04 %
    and +6.8 %); the BEM film is thinner than 1 - lam/lam_c and the length within 1 % of
    lubrication's."""
    res = solve_vesicle(nu, lam_ratio=ratio, **KW)
    lub = solve_lubrication(nu, lam_ratio=ratio, ca_b=50.0)
    assert res.success, res.message
    assert lub.success, lub.message
    assert res.V_over_U == pytest.approx(lub.V_over_U, rel=1e-3)
    assert res.dp_plus_R0 == pytest.approx(lub.dp_plus_R0, rel=0.10)
    assert res.ell == pytest.approx(lub.ell, rel=0.01)
    assert 0 < res.film_min < 1 - ratio
