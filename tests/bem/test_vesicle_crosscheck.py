"""BEM vesicle against the lubrication solver near the critical confinement (slow validation).

Units: R = 1, U the mean velocity, lam = R0/R, Ca_B = eta U R0^2/kappa = 50 for both solvers.
Lubrication (Secomb et al. 1986 / Barakat & Shaqfeh 2018b, :mod:`lubrication.solve`) is the
asymptotically exact limit of the Stokes problem as lam -> lam_c, so the two solvers must agree
there, with a difference that shrinks as the film thins (that rate is measured at nu = 0.9 in
tests/bem/test_vesicle.py and docs/validation.md).

Long vesicles (nu < ~0.75) use the "bend" arc-length density, start from the lubrication
shape at their own lam and are solved by the valley Levenberg–Marquardt (bem.vesicle); their
near-lam_c solves are not converged to the default tolerances (docs/validation.md), so below
nu = 0.85 the refinement pair is accepted within 5 % in V/U and dp+ (gamma_max not required).

The tolerances are about 1.5-2 times the differences measured with this test's solves
(``MEASURED``, from ``python tests/bem/test_vesicle_crosscheck.py``; the last two rows are
the derandomized draws of the test):

  nu      lam/lam_c  V/U BEM/lub. - 1  dp+ BEM/lub. - 1  ell BEM/lub. - 1  modes, residual
  0.9     0.95       -3.85e-4          +6.81 %           -5.1e-4           48, 3.2e-4
  0.6     0.98       +3.2e-5           +1.00 %           -6.9e-5           88, 5.1e-4
  0.6     0.95       -8.7e-5           +2.09 %           -7.9e-5           72, 3.1e-5
  0.668   0.95       +5.1e-5           +2.73 %           -3.3e-4           48, 1.6e-3

(dp+ BEM / lubrication: 146.20 / 136.88, 1852.46 / 1834.19, 675.64 / 661.81, 472.97 / 460.39.)
The (0.6, 0.98) solve ends at the default maximum of 88 modes with gamma_max's estimate 1.9 %
above tension_tol (its pair estimates 2.4e-4 in V/U, 0.5 % in dp+ meet the 5 % asserted).

* V/U: 2 x the largest measured difference on each side of nu = 0.85: 7.7e-4 above, 1.75e-4
  below (was 1e-3 and 5e-3). Below it is tighter than the (0.6, 0.98) solve's own error estimate
  (2.4e-4): the BEM and lubrication speeds agree better than that estimate claims, and a change
  of the solver's path may need a new measurement (``python tests/bem/test_vesicle_crosscheck.py
  NU RATIO``).
* dp+: lubrication neglects the O(delta^(1/2)) corrections at the film ends, so BEM lies above
  lubrication by c(nu) delta^0.8 (docs/validation.md: the exponents 0.8 at nu = 0.9 and 0.85 at
  nu = 0.6); c(nu) grows with nu. The bound is 1.45 x c(nu) delta^0.8 (1.45: at nu = 0.9 this
  keeps it just below the former 10 %), c interpolated linearly between the measured
  coefficients c = (dp+ BEM/lub. - 1)/delta^0.8 (the largest at each measured nu) and
  extrapolated with the last slope above the largest measured nu; the sign (BEM above
  lubrication) is asserted too. Measured c: 0.230 (nu = 0.6; 0.228 at 0.98 lam_c: the
  delta^0.8 scaling holds), 0.300 (0.668), 0.748 (0.9); the bound at delta = 0.05 is 3.0 % at
  nu = 0.6 and 9.9 % at nu = 0.9, at delta = 0.02 1.5 % and 4.7 % (was 10 % everywhere).
* ell: 2 x the largest measured difference, 1.03e-3 (was 1e-2).

The differences are those of the two models; the BEM solves of the test are loose (tol 1e-2,
5e-2 for long vesicles), so each bound on V/U and dp+ also takes the solve's own error estimate
of that output (relative): a solver path that ends elsewhere within its estimate, on another
CPU or after a change of the ladder, still passes, and one that ends outside it does not.
"""

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from bem.vesicle import solve_vesicle
from lubrication.solve import solve_lubrication

# Near lam_c the 48-mode residual is ~1e-3 and the refinement pair differs by ~0.3-1 % in dp+
# (docs/validation.md), far below the BEM-lubrication differences asserted here.
KW = {"tol": 1e-2, "residual_tol": 5e-3}

#: (nu, lam/lam_c): (V/U BEM/lub. - 1, dp+ BEM/lub. - 1, ell BEM/lub. - 1), measured
MEASURED = {
    (0.9, 0.95): (-3.854e-04, 6.8122e-02, -5.138e-04),
    (0.6, 0.98): (3.221e-05, 9.9620e-03, -6.882e-05),
    (0.6, 0.95): (-8.739e-05, 2.0900e-02, -7.949e-05),
    (0.6681036532903545, 0.95): (5.096e-05, 2.7313e-02, -3.287e-04),
}


def _solve_pair(nu, ratio):
    """The BEM solve of the test (48 modes above nu = 0.85, the default ladder below) and
    the lubrication solution at the same parameters."""
    if nu >= 0.85:
        res = solve_vesicle(nu, lam_ratio=ratio, max_modes=48, **KW)
    else:
        res = solve_vesicle(nu, lam_ratio=ratio, **(KW | {"tol": 5e-2}))
    return res, solve_lubrication(nu, lam_ratio=ratio, ca_b=50.0)


def _speed_tol(nu):
    """2 x the largest measured |V/U BEM/lub. - 1| on nu's side of 0.85."""
    return 2 * max(abs(m[0]) for (n, _), m in MEASURED.items() if (n >= 0.85) == (nu >= 0.85))


def _dp_tol(nu, delta):
    """1.45 x c(nu) delta^0.8, c interpolated linearly between the largest measured
    coefficients of each nu (and extrapolated with the last slope above the largest nu)."""
    coef = {}
    for (n, r), m in MEASURED.items():
        coef[n] = max(coef.get(n, 0.0), m[1] / (1 - r) ** 0.8)
    n = np.array(sorted(coef))
    c = np.array([coef[k] for k in n])
    if nu <= n[-1]:
        c_nu = np.interp(nu, n, c)
    else:
        c_nu = c[-1] + (c[-1] - c[-2]) / (n[-1] - n[-2]) * (nu - n[-1])
    return 1.45 * c_nu * delta**0.8


def _ell_tol():
    """2 x the largest measured |ell BEM/lub. - 1|."""
    return 2 * max(abs(m[2]) for m in MEASURED.values())


@pytest.mark.slow          # ~4-10 min per example (16..48 modes, 16..64 for long vesicles)
@settings(max_examples=2, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(nu=st.floats(0.6, 0.95), ratio=st.floats(0.95, 0.98))
@example(nu=0.9, ratio=0.95)
@example(nu=0.6, ratio=0.98)
def test_bem_agrees_with_lubrication_near_lam_c(nu, ratio):
    """V/U, dp+ and ell within about twice the measured differences of lubrication (module
    docstring), dp+ above lubrication's, the BEM film thinner than 1 - lam/lam_c."""
    res, lub = _solve_pair(nu, ratio)
    if nu >= 0.85:
        assert res.success, res.message
    else:
        # long vesicles: gamma_max of the last pair still moves by up to ~9 % (it is not
        # compared here, and is reported as not converged in docs/validation.md); V/U and dp+
        # of the pair and the residual must meet the tolerances
        assert res.residual <= KW["residual_tol"], res.message
        for key in ("V_over_U", "dp_plus_R0"):
            assert res.error_estimate[key] <= 5e-2 * abs(getattr(res, key)), res.message
    assert lub.success, lub.message
    speed, dp, ell = (res.V_over_U / lub.V_over_U - 1, res.dp_plus_R0 / lub.dp_plus_R0 - 1,
                      res.ell / lub.ell - 1)
    own = {k: res.error_estimate[k] / abs(getattr(res, k)) for k in ("V_over_U", "dp_plus_R0")}
    speed_tol, dp_tol = _speed_tol(nu) + own["V_over_U"], _dp_tol(nu, 1 - ratio) + own["dp_plus_R0"]
    assert abs(speed) <= speed_tol, (speed, speed_tol)
    assert 0 < dp <= dp_tol, (dp, dp_tol)
    assert abs(ell) <= _ell_tol(), (ell, _ell_tol())
    assert 0 < res.film_min < 1 - ratio


# --- red cell (membrane shear elasticity) -------------------------------------------------------
#: The red cell of the cross-check: Ca_B 50 and Ca_S 0.2 (G_s = 6 µN/m at U ≈ 1 mm/s), the
#: Evans-Fung disc as stress-free shape. Near lam_c the shear tensions (G_s) are small against the
#: flow's (they grow like dp+), so the two solvers must agree as for the vesicle: V/U within the
#: vesicle's bound, dp+ above lubrication by no more than the vesicle's c(nu) delta^0.8 bound.
#: Measured (``python tests/bem/test_vesicle_crosscheck.py red-cell 0.65 RATIO``), BEM/lub. - 1:
#: at 0.95 lam_c V/U -9.9e-5, dp+ +2.57 % (519.96/506.92), ell -2.2e-4 (64 modes); at 0.98
#: V/U +2.4e-6, dp+ +1.22 % (1415.07/1398.04), ell -6.2e-5 (80 modes): dp+ converges like
#: delta^0.81 (the vesicle's delta^0.8), the bounds asserted are 3.7 % and 1.8 %.
RED_CELL = {"ca_b": 50.0, "ca_s": 0.2, "reference": "biconcave"}


def _solve_red_cell_pair(nu, ratio):
    res = solve_vesicle(nu, lam_ratio=ratio, **RED_CELL, **(KW | {"tol": 5e-2}))
    return res, solve_lubrication(nu, lam_ratio=ratio, **RED_CELL)


@pytest.mark.slow          # ~1-3 min per point
@pytest.mark.parametrize("ratio", [0.95, 0.98])
def test_red_cell_bem_agrees_with_lubrication_near_lam_c(ratio):
    """The red cell (nu 0.65) near lam_c: BEM and lubrication with shear elasticity agree within
    the vesicle's measured bounds (module docstring) plus the solve's own error estimate."""
    nu = 0.65
    res, lub = _solve_red_cell_pair(nu, ratio)
    assert res.residual <= KW["residual_tol"], res.message
    for key in ("V_over_U", "dp_plus_R0"):
        assert res.error_estimate[key] <= 5e-2 * abs(getattr(res, key)), res.message
    assert lub.success, lub.message
    speed, dp = res.V_over_U / lub.V_over_U - 1, res.dp_plus_R0 / lub.dp_plus_R0 - 1
    own = {k: res.error_estimate[k] / abs(getattr(res, k)) for k in ("V_over_U", "dp_plus_R0")}
    assert abs(speed) <= _speed_tol(nu) + own["V_over_U"], speed
    assert 0 < dp <= _dp_tol(nu, 1 - ratio) + own["dp_plus_R0"], dp


if __name__ == "__main__":          # the measurements behind the bounds: one point per process
    import sys
    red = sys.argv[1:2] == ["red-cell"]         # python ... [red-cell] NU RATIO
    nu, ratio = map(float, sys.argv[1 + red:3 + red])
    res, lub = (_solve_red_cell_pair if red else _solve_pair)(nu, ratio)
    print(f"({nu!r}, {ratio!r}): ({res.V_over_U / lub.V_over_U - 1:.3e}, "
          f"{res.dp_plus_R0 / lub.dp_plus_R0 - 1:.4e}, {res.ell / lub.ell - 1:.3e}),  # "
          f"V/U {res.V_over_U:.6f}/{lub.V_over_U:.6f}, dp+ {res.dp_plus_R0:.2f}/"
          f"{lub.dp_plus_R0:.2f}, ell {res.ell:.4f}/{lub.ell:.4f}, film {res.film_min:.4f}, "
          f"residual {res.residual:.1e}, modes {res.modes.size}, success {res.success}, "
          f"est {res.error_estimate}", flush=True)
