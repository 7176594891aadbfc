"""bem.newton.valley_levenberg_marquardt on a curved valley with a known minimiser.

Reference: scipy.optimize.least_squares (trust-region reflective, analytic Jacobian, tolerances
1e-15), an independent implementation.
"""

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from bem.newton import valley_levenberg_marquardt
from lubrication.checks import InvalidParameterError
from lubrication.results import Status

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable


def _banana(z):
    """A curved (Rosenbrock) valley in (z0, z1), coupled weakly to four stiffer unknowns, with
    more equations than unknowns so that the minimum has a non-zero residual (as the BEM's)."""
    r = [10.0 * (z[1] - z[0] ** 2), 1.0 - z[0], 0.3 * z[0] * z[1] - 0.1]
    for j in range(2, z.size):
        r.append(3.0 * (z[j] - 0.2 * z[j - 1]) + 0.05 * z[0] ** 2)
        r.append(0.1 * np.sin(z[j] + j) - 0.02 * z[1])
    return np.array(r)


def _jac(z, h=1e-7):
    F = _banana(z)
    return np.column_stack([(_banana(z + h * e) - F) / h for e in np.eye(z.size)])


def _reference(z0):
    return least_squares(_banana, z0, jac=_jac, xtol=1e-15, ftol=1e-15, gtol=1e-15).x


def test_valley_solver_finds_the_least_squares_minimiser_of_a_curved_valley():
    z0 = np.array([-1.2, 1.0, 0.5, -0.5, 0.3, 0.1])                  # Rosenbrock's start
    ref = _reference(z0)
    assert np.linalg.norm(_banana(ref)) > 0.05                     # a real residual floor
    calls = []

    def fun(z):
        calls.append(1)
        return _banana(z), None

    rep = valley_levenberg_marquardt(fun, z0, tol=1e-12, max_iter=400, directions=2,
                                     promise=1e-12, max_jacobians=10)
    assert rep.success, rep.message
    assert rep.evaluations == len(calls)
    assert np.allclose(rep.z, ref, atol=1e-6)
    assert np.linalg.norm(rep.F) == pytest.approx(np.linalg.norm(_banana(ref)), rel=1e-10)


@pytest.mark.parametrize("n", [4, 6])
def test_recent_jacobian_certifies_only_a_floor_a_fresh_one_confirms(n):
    """The floor certified by a Jacobian differenced earlier in the solve (moved since by less
    than RECENT_STEP) is a floor for a fresh difference Jacobian at the end point too (its
    Gauss-Newton promise below ``promise``), near scipy's least-squares minimiser."""
    from bem.newton import _promised

    z0 = np.array([-1.2, 1.0, 0.5, -0.5, 0.3, 0.1])[:n]
    rep = valley_levenberg_marquardt(lambda z: (_banana(z), None), z0, promise=1e-6,
                                     max_jacobians=10, directions=2)
    assert rep.success and "Jacobian differenced" in rep.message, rep.message
    F = _banana(rep.z)
    assert _promised(_jac(rep.z), F, np.linalg.norm(F)) < 1e-6
    assert np.max(np.abs(rep.z - _reference(z0))) < 1e-4


def test_valley_solver_reports_an_invalid_start_and_recovers_from_invalid_trials():
    def fun(z):
        if z[0] > 1.5:                                   # e.g. a shape that touches the wall
            raise InvalidParameterError("shape", z[0], "z0 <= 1.5")
        return _banana(z), None

    rep = valley_levenberg_marquardt(fun, np.array([2.0, 0, 0, 0]))
    assert rep.status is Status.REJECTED_START and not rep.success, rep.message
    z0 = np.array([-1.2, 1.0, 0.5, -0.5])
    rep = valley_levenberg_marquardt(fun, z0, tol=1e-12, directions=1, promise=1e-12,
                                     max_jacobians=10)
    assert rep.success, rep.message
    assert np.allclose(rep.z, _reference(z0), atol=1e-6)



def test_supplied_jacobian_reaches_the_minimiser_without_a_difference_jacobian():
    """levenberg_marquardt started with an accurate approximate Jacobian (as the vesicle's
    levels get from the coarser level) keeps it while its steps contract and stops at the
    least-squares minimiser (non-zero residual) without a difference Jacobian."""
    from bem.newton import levenberg_marquardt

    rng = np.random.default_rng(3)
    A = rng.standard_normal((14, 5))
    b = A @ rng.standard_normal(5) + 1e-3 * rng.standard_normal(14)   # a small residual floor

    def F(z):
        r = A @ z - b
        return r + 0.05 * r**2

    def jac(z):
        return (1.0 + 0.1 * (A @ z - b))[:, None] * A

    z_ref = least_squares(F, np.zeros(5), jac=jac, xtol=1e-15, ftol=1e-15, gtol=1e-15).x
    z0 = z_ref + 1e-3 * np.arange(1, 6)
    J0 = jac(z0) * (1.0 + 1e-3 * np.cos(np.arange(14)))[:, None]
    rep = levenberg_marquardt(lambda z: (F(z), None), z0, jacobian=J0, floor_ratio=0.99)
    assert rep.success, rep.message
    assert rep.jacobians == 0 and rep.evaluations <= z0.size, rep
    # the fixed point of steps with a Jacobian 1e-3 off lies ~1e-7 from the minimiser
    np.testing.assert_allclose(rep.z, z_ref, atol=1e-6)
    assert rep.jacobian is not None and rep.jacobian.shape == J0.shape


def test_difference_jacobian_with_batched_points_equals_the_one_by_one_columns():
    """``fun.many`` (the vesicle's concurrent evaluations) gives the columns of the plain loop,
    and a point it rejects is differenced backwards as before."""
    from bem.newton import _evaluate_points, difference_jacobian

    def fun(z):
        if z[1] > 1.0 + 5e-8:                       # a forward step on z[1] is rejected
            raise InvalidParameterError("z", z, "z[1] <= 1")
        return np.array([z[0] ** 2, z[0] * z[1], np.sin(z[1]), z[0] + z[1] ** 3]), None

    def batched(z):
        return fun(z)

    batched.many = lambda points: _evaluate_points(fun, points)     # fun has no ``many``
    z = np.array([0.7, 1.0])
    F, _ = fun(z)
    J1, n1 = difference_jacobian(fun, z, F, 1e-7, {})
    J2, n2 = difference_jacobian(batched, z, F, 1e-7, {})
    exact = np.array([[1.4, 0.0], [1.0, 0.7], [0.0, math.cos(1.0)], [1.0, 3.0]])
    assert n1 == n2 == 3                                 # two columns, one taken backwards
    np.testing.assert_array_equal(J1, J2)
    np.testing.assert_allclose(J2, exact, atol=1e-6)
