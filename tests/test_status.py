"""The one result status (lubrication.results.Status) of every solver result and report.

Each category is produced by a real solve of the solver that reports it (cheap cases: a spent
``max_time``, a tiny mesh or iteration budget, a refinement pair asked for 1e-12, a drop that
touches the wall, a start the operator rejects); ``success`` agrees with the status; the status
goes through ``to_dict``, the saved JSON and the command line's JSON and comes back by
``status_of``, which also gives the status of stored files written without one (the map build
points in correlations/data and the stored vesicle fixtures in tests/bem/data).
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from lubrication.results import (
    PRECEDENCE,
    LubricationResult,
    SolverResult,
    Status,
    leading_status,
    status_of,
)

ROOT = Path(__file__).resolve().parents[1]


# ------------------------------------------------------------------ the categories
def test_status_values_are_short_lowercase_strings():
    assert len(Status) <= 7
    for s in Status:
        assert s.value == s.value.lower() and len(s.value) <= 20 and s == s.value
        assert Status(s.value) is s
    assert set(PRECEDENCE) == set(Status) - {Status.CONVERGED}


@pytest.mark.parametrize("status", list(Status))
def test_success_and_converged_agree_with_the_status(status):
    res = LubricationResult(nu=0.9, lam=1.0, lam_c=1.2, ca_b=math.inf, model="high-Ca",
                            status=status, message="m", V_over_U=1.01, shape_class="bullet")
    assert res.success is res.converged is (status is Status.CONVERGED)
    d = res.to_dict()
    assert d["status"] == status.value
    assert d["success"] is d["converged"] is res.success
    assert (d["V_over_U"] is None) is (not res.success)     # no numbers from a failed solve
    assert status_of(json.loads(json.dumps(d, allow_nan=False))) is status


def test_a_status_given_as_its_value_is_stored_as_the_member():
    res = LubricationResult(nu=0.9, lam=1.0, lam_c=1.2, ca_b=math.inf, model="high-Ca",
                            status="time limit")
    assert res.status is Status.TIME_LIMIT
    with pytest.raises(ValueError):
        LubricationResult(nu=0.9, lam=1.0, lam_c=1.2, ca_b=math.inf, model="high-Ca",
                          status="stopped")
    with pytest.raises(TypeError):          # success is read from the status, not given
        LubricationResult(nu=0.9, lam=1.0, lam_c=1.2, ca_b=math.inf, model="high-Ca",
                          success=True)


def test_several_reasons_give_the_leading_status():
    assert leading_status([Status.UNRESOLVED, Status.NOT_CONVERGED]) is Status.NOT_CONVERGED
    assert leading_status([Status.TIME_LIMIT, Status.NO_STEADY_STATE]) is Status.NO_STEADY_STATE
    # of several starts (a map point), a rejected one gives way to one that ran
    assert leading_status([Status.REJECTED_START, Status.UNRESOLVED]) is Status.UNRESOLVED
    assert leading_status([Status.CONVERGED, Status.CONVERGED]) is Status.CONVERGED


def test_every_result_class_shares_the_one_base():
    from bem.drop import NewtonReport
    from bem.newton import LMReport
    from bem.results import DropResult, SphereResult, VesicleResult
    for cls in (LubricationResult, SphereResult, DropResult, VesicleResult):
        assert issubclass(cls, SolverResult)
    for cls in (LMReport, NewtonReport):
        assert "status" in cls.__dataclass_fields__ and "success" not in cls.__dataclass_fields__


# ------------------------------------------------------------------ produced by real solves
def test_lubrication_statuses():
    from lubrication.solve import solve_lubrication
    assert solve_lubrication(0.9, lam_ratio=0.99).status is Status.CONVERGED
    assert solve_lubrication(0.9, lam_ratio=0.99, max_time=1e-320).status is Status.TIME_LIMIT
    assert solve_lubrication(0.9, lam_ratio=0.99, max_nodes=100).status is Status.NOT_CONVERGED


def test_sphere_statuses():
    from bem.solve import solve_sphere
    assert solve_sphere(0.5, panels=6, tol=1e-3).status is Status.CONVERGED
    assert solve_sphere(0.9, panels=3, tol=1e-12).status is Status.UNRESOLVED
    assert solve_sphere(0.5, max_time=1e-9).status is Status.TIME_LIMIT


def test_drop_statuses():
    from bem.drop import solve_drop
    assert solve_drop(0.3, 0.1, n_modes=8, tol=1e-3).status is Status.CONVERGED
    assert solve_drop(0.3, 0.1, n_modes=8, max_time=1e-9).status is Status.TIME_LIMIT
    # 8 modes: the pair differs (unresolved) and the steady residual is above its tolerance
    # (not converged, which leads)
    both = solve_drop(0.5, 0.2, n_modes=8, tol=1e-12)
    assert both.status is Status.NOT_CONVERGED, both.message
    assert "refinement pair" in both.message and "steady residual" in both.message
    pair = solve_drop(0.5, 0.2, n_modes=8, tol=1e-12, residual_tol=1.0)
    assert pair.status is Status.UNRESOLVED, pair.message


def test_a_drop_that_touches_the_wall_has_no_steady_state():
    """lam = 0.95, Ca = 1: Newton fails from the sphere and in the time relaxation the drop
    touches the wall (about 6 s)."""
    from bem.drop import solve_drop
    res = solve_drop(0.95, 1.0)
    assert res.status is Status.NO_STEADY_STATE and not res.success, res.message
    assert "touching the wall" in res.message


def test_reports_of_the_iterations():
    from bem.drop import DropDiscretisation, DropOperator, newton_drop
    from bem.newton import levenberg_marquardt
    from bem.shape import SpectralCurve, fit_curve, spheroid_curve

    def fun(z):
        return np.array([z[0] - 1.0, z[1] - 2.0, 0.1 * (z[0] * z[1] - 2.0)]), None

    def rosenbrock(z):
        return np.array([z[0] - 1.0, 10.0 * (z[1] - z[0] ** 2)]), None

    assert levenberg_marquardt(fun, np.zeros(2)).status is Status.CONVERGED
    short = levenberg_marquardt(rosenbrock, np.array([-1.2, 1.0]), max_iter=1)
    assert short.status is Status.NOT_CONVERGED and not short.success
    # an oblate spheroid of the volume of lam = 0.8, wider than the tube
    curve = fit_curve(spheroid_curve(0.8**3 / 1.05**2, 1.05), 0.0, math.pi, 12)
    op = DropOperator(0.8, 0.1, DropDiscretisation(12, 8), SpectralCurve.sphere(0.8, 12))
    rep = newton_drop(op, curve.modes)
    assert rep.status is Status.REJECTED_START and not rep.success


# ------------------------------------------------------------------ files and the command line
def test_status_round_trips_through_the_saved_json(tmp_path):
    from bem.drop import solve_drop
    from bem.solve import solve_sphere
    from lubrication.solve import solve_lubrication
    results = [solve_lubrication(0.9, lam_ratio=0.99),
               solve_lubrication(0.9, lam_ratio=0.99, max_time=1e-320),
               solve_sphere(0.9, panels=3, tol=1e-12),
               solve_drop(0.3, 0.1, n_modes=8, max_time=1e-9)]
    for k, res in enumerate(results):
        path = res.save(tmp_path / str(k))[0]
        data = json.loads(path.read_text())
        assert data["status"] == res.status.value and data["success"] is res.success
        assert status_of(data) is res.status


def test_the_command_line_reports_the_status_and_exits_1_unless_converged(cli):
    code, out, _ = cli("bem", "sphere", "--lam", "0.5", "--panels", "6", "--tol", "1e-3",
                       "--json")
    obj = json.loads(out)
    assert code == 0 and obj["status"] == "converged" and obj["converged"] is True
    code, out, _ = cli("bem", "sphere", "--lam", "0.5", "--max-time", "1e-9", "--json")
    obj = json.loads(out)
    assert code == 1 and obj["status"] == "time limit" and obj["converged"] is False
    code, out, _ = cli("lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--max-time",
                       "1e-300", "--json")
    obj = json.loads(out)
    assert code == 1 and obj["status"] == "time limit" and obj["converged"] is False


def test_a_map_point_stores_its_status(tmp_path):
    from correlations import map_build
    fields, warm = map_build._solve_lubrication(0.9, 0.99, 50.0, None, {}, 1e-300)
    assert fields["status"] == "time limit" and fields["success"] is False and warm is None
    fields, warm = map_build._solve_lubrication(0.9, 0.99, 50.0, None, {}, None)
    assert fields["status"] == "converged" and fields["success"] is True


# ------------------------------------------------------------------ stored files without a status
@pytest.mark.parametrize("message, status", [
    ("own: the film closes (min gap 4.1e-04 R); neighbour (nu=0.9, lam/lam_c=0.9): estimated "
     "discretisation error above the tolerance in V_over_U (2e-05 > 1e-05)",
     Status.NO_STEADY_STATE),
    ("no steady shape: Newton failed from the initial shape and in a time relaxation the "
     "interface became invalid at t = 3.2 R/U", Status.NO_STEADY_STATE),
    ("own: stopped at the time limit max_time=600 s before converging (in the level with 64 "
     "modes); own: estimated discretisation error above the tolerance", Status.TIME_LIMIT),
    ("own: continuation failed at lam/lam_c = 0.95: level with 16 modes: initial='a shape "
     "rejected by the operator' is invalid", Status.REJECTED_START),
    ("Newton did not converge with 24 modes: initial shape rejected: shape='a drop touching "
     "the wall' is invalid", Status.NOT_CONVERGED),
    ("neighbour (nu=0.9, lam/lam_c=0.3): cannot start (density='min g = -0.35' is invalid); "
     "own: refinement pair differs by more than tol", Status.UNRESOLVED),
    ("own: steady residual max|u - V e_x| = 2.1e-02 exceeds residual_tol=0.001; estimated "
     "discretisation error above the tolerance in V_over_U", Status.NOT_CONVERGED),
    ("refinement pair differs by more than tol=1e-12 (relative): V_over_U 1e-08",
     Status.UNRESOLVED),
    ("not converged: collocation residual 3e-06 > 1e-07", Status.NOT_CONVERGED),
    ("InvalidParameterError: density='min g = -0.35' is invalid", Status.REJECTED_START),
    ("outside the lubrication model: lam_ratio=0.05 is invalid", Status.NO_STEADY_STATE),
    ("a reason of no known kind", Status.NOT_CONVERGED),
])
def test_the_status_of_a_stored_failure_without_one_is_derived_from_its_message(message,
                                                                                status):
    assert status_of({"success": False, "message": message}) is status
    assert status_of({"success": True, "message": message}) is Status.CONVERGED
    assert status_of({"converged": True}) is Status.CONVERGED


def test_the_stored_map_points_load_with_a_status():
    from correlations.solution_map import load_map, read_points
    points = read_points(ROOT / "correlations" / "data" / "solution_map_build")
    assert len(points) > 1000
    for p in points:
        assert Status(p["status"]) is (Status.CONVERGED if p["success"] else status_of(p))
        assert (p["status"] == "converged") is bool(p["success"])
    failed = {p["status"] for p in points if not p["success"]}
    assert failed and "converged" not in failed
    load_map()                                           # the packed map still loads


def test_the_stored_vesicle_fixtures_rebuild_as_results():
    from bem.results import VesicleResult
    for path in sorted((ROOT / "tests" / "bem" / "data").glob("vesicle_nu0.98_lam0.*.json")):
        data = json.loads(path.read_text())
        assert "status" not in data                   # written before results had one
        res = VesicleResult(nu=data["nu"], lam=data["lam"], lam_c=data["lam_c"],
                            ca_b=data["ca_b"], status=status_of(data), message=data["message"])
        assert res.success is data["success"] is True
