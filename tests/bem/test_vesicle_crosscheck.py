"""BEM vesicle against the lubrication solver near the critical confinement (slow validation).

Units: R = 1, U the mean velocity, lam = R0/R, Ca_B = eta U R0^2/kappa = 50 for both solvers.
Lubrication (Secomb et al. 1986 / Barakat & Shaqfeh 2018b, :mod:`lubrication.solve`) is the
asymptotically exact limit of the Stokes problem as lam -> lam_c, so the two solvers must agree
there, with a difference that shrinks as the film thins (that rate is measured at nu = 0.9 in
tests/bem/test_vesicle.py and docs/validation.md). Measured at nu = 0.9, 48 modes:

  lam/lam_c   V/U BEM / lub.        dp+R0/(eta U) BEM / lub.   residual
  0.95        1.048257 / 1.048661   146.2 / 136.9 (+6.8 %)     3.2e-4
  0.97        1.028833 / 1.028948   245.8 / 234.9 (+4.65 %)    1.2e-3

and at nu = 0.6 (default modes, "bend" density):

  0.95        1.050463 / 1.050373   676.10 / 661.81 (+2.16 %)  1.6e-3 (40 modes)
  0.98        1.021012 / 1.019998   1852.28 / 1834.19 (+0.99 %) 3.0e-3 (64 modes)

Long vesicles (nu < ~0.75) use the "bend" arc-length density, start from the lubrication
shape at their own lam and are solved by the valley Levenberg–Marquardt (bem.vesicle); their
near-lam_c solves are not converged to the default tolerances (nu = 0.6, lam = 1.94, 64 modes:
residual 1.3e-3; the refinement pair, 56 modes on the lubrication-shape density and 64 on the
density re-built on the BEM shape, differs by 1.8e-3 in V/U and 14 % in gamma_max,
docs/validation.md), so below nu = 0.85 the refinement pair is accepted within 5 % in V/U and
dp+ (gamma_max not required) and V/U is asserted within 0.5 %; above, within 1 % and 0.1 %,
where the 48-mode solves are converged to ~1e-4 in V/U.
"""

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from bem.vesicle import solve_vesicle
from lubrication.solve import solve_lubrication

# Near lam_c the 48-mode residual is ~1e-3 and the refinement pair differs by ~0.3-1 % in dp+
# (docs/validation.md), far below the BEM-lubrication differences asserted here.
KW = {"tol": 1e-2, "residual_tol": 5e-3}


@pytest.mark.slow          # ~4-10 min per example (16..48 modes, 16..64 for long vesicles)
@settings(max_examples=2, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(nu=st.floats(0.6, 0.95), ratio=st.floats(0.95, 0.98))
@example(nu=0.9, ratio=0.95)
@example(nu=0.6, ratio=0.98)
def test_bem_agrees_with_lubrication_near_lam_c(nu, ratio):
    """V/U within 0.1 % and dp+ within 10 % of lubrication (measured at (0.9, 0.95): -0.04 %
    and +6.8 %); the BEM film is thinner than 1 - lam/lam_c and the length within 1 % of
    lubrication's."""
    if nu >= 0.85:
        res = solve_vesicle(nu, lam_ratio=ratio, max_modes=48, **KW)
        assert res.success, res.message
    else:
        # long vesicles: gamma_max of the last pair still moves by up to ~9 % (it is not
        # compared here, and is reported as not converged in docs/validation.md); V/U and dp+
        # of the pair and the residual must meet the tolerances
        res = solve_vesicle(nu, lam_ratio=ratio, **(KW | {"tol": 5e-2}))
        assert res.residual <= KW["residual_tol"], res.message
        for key in ("V_over_U", "dp_plus_R0"):
            assert res.error_estimate[key] <= 5e-2 * abs(getattr(res, key)), res.message
    lub = solve_lubrication(nu, lam_ratio=ratio, ca_b=50.0)
    assert lub.success, lub.message
    assert res.V_over_U == pytest.approx(lub.V_over_U, rel=1e-3 if nu >= 0.85 else 5e-3)
    assert res.dp_plus_R0 == pytest.approx(lub.dp_plus_R0, rel=0.10)
    assert res.ell == pytest.approx(lub.ell, rel=0.01)
    assert 0 < res.film_min < 1 - ratio
