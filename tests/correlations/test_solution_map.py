"""The solution map: store, pack, query (correlations/solution_map.py) and the in-process build
(correlations/map_build.py), on tiny grids.

Independent reference for the interpolation: an analytic function of (nu, lam/lam_c, Ca_B),
stored as a fake build, must be reproduced exactly at the nodes and within the stated error bar
between them. The shipped map's answers are held to those of the query as it was before it
computed its stencil once for the eight quantities (tests/correlations/data/
solution_map_queries.json, written by tests/benchmarks/map_query_speed.py --write-reference from
that revision), and its pack to the shipped file.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from pathlib import Path

import pytest

from lubrication.geometry import critical_confinement
from lubrication.results import Status
from correlations import map_build
from correlations.files import read_json
from correlations.map_build import build_map, line_tasks, make_grid
from correlations.solution_map import (DEFAULT_MAP, POINT_FORMAT, QUANTITIES, TRANSFORMS,
                                       load_map, pack_map, point_filename, query_map,
                                       read_points)

# ----------------------------------------------------------------------------- analytic map

NUS = [0.6, 0.7, 0.8, 0.9]
BEM_RATIOS = [0.2, 0.4, 0.6, 0.8, 0.9]
LUB_RATIOS = [0.9, 0.95, 0.99]
CAS = [5.0, 50.0, 500.0]
# lubrication = truth * (1 + LUB_BIAS (delta/0.1)^(1/2)), less the offset of TRANSFORMS (V/U - 1
# is what the map scales and interpolates): a model error to measure, shrinking
# toward lam_c as the real one does (tests/benchmarks/lubrication_overlap.py: the Delta p+ gap
# falls from 15 % at delta = 0.1 to 6 % at 0.02) and as the map's rule assumes
LUB_BIAS = 1e-3


def _lub(bias, r):
    return 1.0 + bias * math.sqrt((1.0 - r) / 0.1)


def stored(q, nu, r, ca, bias=0.0):
    """The value a point stores: the truth, with the lubrication bias on (q - offset)."""
    offset = TRANSFORMS[q]["offset"]
    return offset + (truth(q, nu, r, ca) - offset) * _lub(bias, r)


def truth(q, nu, r, ca):
    """Smooth, not polynomial, in the map's variables; the singular powers of delta as in
    correlations.solution_map.TRANSFORMS."""
    d = 1.0 - r
    s, c = math.sqrt(d), math.log(ca)
    g = 0.3 * math.sin(2 * nu) + 0.5 * s * s - 0.4 * s + 0.1 * c + 0.05 * s * c \
        + 0.2 * math.cos(3 * nu * s)
    if q == "curvature_rear":
        return -1.0 + 0.5 * s + 0.2 * math.sin(3 * nu) + 0.01 * c
    power = {"V_over_U": -1.0, "dp_plus_R0": 1.0, "ell": 0.0, "film_min": -1.0,
             "tension_max": 1.5, "tension_front": 1.5, "wall_shear_max": 1.0}[q]
    ratio_power = {"dp_plus_R0": 6.0, "ell": 1.0}.get(q, 0.0)
    # V/U - 1 and h/R at most 0.7 on the grid: inside the physical bounds a node must meet
    scale = {"V_over_U": 0.2, "film_min": 0.2, "ell": 3.0}.get(q, 10.0)
    return (1.0 if q == "V_over_U" else 0.0) + scale * math.exp(g) * d ** -power * r**ratio_power


def _write_point(folder, method, nu, r, ca, success=True, bias=0.0):
    rec = {"format": POINT_FORMAT, "method": method, "nu": nu, "lam_ratio": r, "ca_b": ca,
           "success": success, "message": "converged" if success else "no steady shape found",
           "shape_class": "bullet" if success else None,
           "error_estimate": {q: (1e-9 if method == "bem" and q in
                                  ("V_over_U", "dp_plus_R0", "tension_max") else None)
                              for q in QUANTITIES},
           "residual": 1e-6, "bie_solves": 10, "seconds": 1.0}
    for q in QUANTITIES:
        rec[q] = stored(q, nu, r, ca, bias) if success else None
    (folder / point_filename(method, nu, r, ca)).write_text(json.dumps(rec))


def _fake_build(folder, hole=None):
    folder.mkdir(parents=True, exist_ok=True)
    grid = make_grid(NUS, {"bem": BEM_RATIOS, "lubrication": LUB_RATIOS}, CAS)
    (folder / "build.json").write_text(json.dumps({"grid": grid, "parameters": {},
                                                   "provenance": {"test": "analytic"}}))
    for nu in NUS:
        for ca in CAS:
            for r in BEM_RATIOS:
                _write_point(folder, "bem", nu, r, ca, success=(nu, r, ca) != hole)
            for r in LUB_RATIOS:
                _write_point(folder, "lubrication", nu, r, ca, bias=LUB_BIAS)
    return pack_map(folder)


@pytest.fixture(scope="module")
def analytic_map(tmp_path_factory):
    return load_map(_fake_build(tmp_path_factory.mktemp("analytic")))


def test_query_reproduces_the_grid_values_at_the_nodes(analytic_map):
    for nu, r, ca, method in [(0.7, 0.4, 50.0, "bem"), (0.9, 0.9, 5.0, "bem"),
                              (0.6, 0.95, 500.0, "lubrication"), (0.8, 0.99, 50.0, "lubrication")]:
        res = query_map(nu, r, ca, analytic_map)
        bias = LUB_BIAS if method == "lubrication" else 0.0
        for q in QUANTITIES:
            v = res.quantities[q]
            # packed to 10 significant digits
            assert v.value == pytest.approx(stored(q, nu, r, ca, bias), rel=5e-10, abs=0)
            assert v.methods == (method,)
            assert v.interpolation_error == 0.0
        assert res["shape_class"] == "bullet"


BETWEEN = [(0.65, 0.3, 10.0), (0.75, 0.7, 100.0), (0.85, 0.5, 7.0), (0.62, 0.85, 300.0),
           (0.88, 0.93, 20.0), (0.72, 0.97, 60.0), (0.81, 0.985, 400.0)]


def test_interpolation_of_an_analytic_map_is_within_its_stated_error(analytic_map):
    ratios = []
    for nu, r, ca in BETWEEN:
        res = query_map(nu, r, ca, analytic_map)
        for q in QUANTITIES:
            v = res.quantities[q]
            exact = truth(q, nu, r, ca)
            assert v.value is not None, (q, v.note)
            assert v.error is not None and v.interpolation_error > 0
            assert abs(v.value - exact) <= v.error, (nu, r, ca, q, v.value, exact, v)
            ratios.append(v.error / abs(v.value - exact))
            if r > 0.9:
                assert "lubrication" in v.methods and v.model_error > 0
    # conservative by construction (leave-one-out doubles the spacing), but not a blanket:
    # measured 6-60x the true error, with rare outliers where the true error nearly cancels
    ratios.sort()
    assert ratios[len(ratios) // 2] < 60, ratios


def test_outside_the_map_and_holes_give_none_with_the_reason(tmp_path):
    m = load_map(_fake_build(tmp_path / "b", hole=(0.7, 0.6, 50.0)))
    for args, word in [((0.5, 0.5, 50.0), "nu=0.5"), ((0.7, 0.1, 50.0), "lam_ratio=0.1"),
                       ((0.7, 0.995, 50.0), "lam_ratio=0.995"), ((0.7, 0.5, 2.0), "ca_b=2"),
                       ((0.7, 0.5, 2e4), "ca_b=20000"), ((0.7, 0.55, 50.0), "hole"),
                       ((0.75, 0.6, 50.0), "hole"), ((0.7, 0.6, 20.0), "hole")]:
        res = query_map(*args, m)
        for q in (*QUANTITIES, "shape_class"):
            assert res[q] is None and word in res.quantities[q].note, (args, q, res.quantities[q])
    assert query_map(0.7, 0.3, 50.0, m)["V_over_U"] is not None    # away from the hole


def test_ca_b_above_the_map_is_clamped_with_the_measured_change_as_error(analytic_map):
    top = query_map(0.7, 0.5, 500.0, analytic_map).quantities["dp_plus_R0"]
    above = query_map(0.7, 0.5, 2000.0, analytic_map).quantities["dp_plus_R0"]
    at50 = query_map(0.7, 0.5, 50.0, analytic_map).quantities["dp_plus_R0"]
    assert above.value == top.value
    assert above.model_error >= 0.99 * abs(top.value - at50.value) > 0
    assert "Chen et al. 2020" in above.note


def test_invalid_queries_raise_naming_the_parameter(analytic_map):
    from lubrication.checks import CannotPassError, InvalidParameterError
    with pytest.raises(CannotPassError, match="lam_ratio"):
        query_map(0.7, 1.0, 50, analytic_map)
    for args, name in [((1.2, 0.5, 50), "nu"), ((0.7, -0.1, 50), "lam_ratio"),
                       ((0.7, 0.5, 0.0), "ca_b"), ((math.nan, 0.5, 50), "nu")]:
        with pytest.raises(InvalidParameterError, match=name):
            query_map(*args, analytic_map)


def test_packed_file_is_compact_json_with_units_holes_and_loo(tmp_path):
    path = _fake_build(tmp_path / "b", hole=(0.8, 0.4, 5.0))
    data = json.loads(path.read_text())
    assert data["format"] == "vesicle-tube solution map" and data["version"] == 1
    assert {h["reason"] for h in data["holes"]} == {"no steady shape found"}
    assert all(k in data["units"] for k in data["columns"])
    assert "shape" not in data["columns"] and "modes" not in path.read_text()
    assert any(v is not None for v in data["columns"]["loo_lam_dp_plus_R0"])


# ----------------------------------------------------------------------------- the shipped map

REFERENCE = Path(__file__).parent / "data" / "solution_map_queries.json"
BUILD = DEFAULT_MAP.with_name("solution_map_build")
#: Python adds floats in sum() term by term up to 3.11 (the reference's version) and with a
#: compensation from 3.12 on, where the last bits may differ; there the fields are compared to
#: 1e-13 of the quantity's magnitude (the map's values are packed to 1e-10).
BIT_FOR_BIT = sys.version_info < (3, 12)
REL = 1e-13


def _same(got, expected, scale: float) -> bool:
    """One field against the reference: bit for bit (``repr`` tells every double apart, -0.0
    from 0.0), or within :data:`REL` where :data:`BIT_FOR_BIT` does not hold."""
    if not BIT_FOR_BIT and isinstance(got, float) and isinstance(expected, float):
        return math.isclose(got, expected, rel_tol=REL, abs_tol=REL * scale)
    return repr(got) == repr(expected)


def test_queries_of_the_shipped_map_equal_the_reference():
    """At about 2400 points (inside the box, uniform in λ/λc and in δ^½; on nodes and within
    their tolerance; next to every hole; Ca_B above the largest node, clamped and past 1e4;
    λ/λc near 1; at and outside the box's edges) every field of every MapValue (value, error
    and its three parts, methods, rows, note) equals the reference; so does
    ``SolutionMap.quantity``, which computes one quantity alone, at every tenth point."""
    if not DEFAULT_MAP.exists():
        pytest.skip(f"no shipped map at {DEFAULT_MAP}")
    ref = read_json(REFERENCE, name="reference", what="reference answers of query_map")
    assert hashlib.sha256(DEFAULT_MAP.read_bytes()).hexdigest() == ref["map_sha256"], (
        f"the shipped map is not the one of {REFERENCE.name}: make it again with "
        f"'{ref['made_by']}'")
    m = load_map()
    compared = 0
    for i, (nu, ratio, ca_b, answers) in enumerate(ref["points"]):
        res = query_map(nu, ratio, ca_b, m)
        assert list(res.quantities) == ref["keys"]
        for key, a in zip(ref["keys"], answers):
            expected = [*a[:5], ref["methods"][a[5]], ref["rows"][a[6]], ref["note"][a[7]]]
            scale = max(1.0, abs(a[0])) if isinstance(a[0], float) else 1.0
            values = [res.quantities[key]]
            if i % 10 == 0 and key in QUANTITIES and res.quantities[key].rows:
                values.append(m.quantity(key, nu, ratio, ca_b))
            for v in values:
                got = [v.value, v.error, v.interpolation_error, v.solver_error, v.model_error,
                       list(v.methods), list(v.rows), v.note]
                bad = {f: (g, e) for f, g, e in zip(ref["fields"], got, expected)
                       if not _same(g, e, scale)}
                assert not bad, (nu, ratio, ca_b, key, bad)
                compared += len(got)
    assert compared > 150_000, compared


def test_packing_the_committed_build_gives_the_shipped_columns(tmp_path):
    """The pack of the committed build folder holds the shipped map's columns, the leave-one-out
    errors (interpolations of the map without each node) among them."""
    if not (BUILD.is_dir() and DEFAULT_MAP.exists()):
        pytest.skip(f"no shipped map with its build folder at {BUILD}")
    what = "a packed map"
    packed = read_json(pack_map(BUILD, tmp_path / "map.json"), name="map", what=what)
    shipped = read_json(DEFAULT_MAP, name="map", what=what)
    assert sorted(packed["columns"]) == sorted(shipped["columns"])
    for name, column in shipped["columns"].items():
        assert packed["columns"][name] == column, name


# ----------------------------------------------------------------------------- a real tiny build

TINY = {"nu": [0.9, 0.95], "lam_ratio": [0.9, 0.95, 0.98], "ca_b": [50.0],
        "methods": ["lubrication"]}
TINY_OPTIONS = {"lubrication": {"tol": 1e-5}}


@pytest.fixture(scope="module")
def tiny_build(tmp_path_factory):
    """Lubrication 2 nu x 3 lam/lam_c x 1 Ca_B, in this process (about 3 s)."""
    folder = tmp_path_factory.mktemp("tiny")
    summary = build_map(folder, make_grid(**TINY), options=TINY_OPTIONS, workers=1)
    return folder, summary


def test_tiny_lubrication_build_packs_and_queries_back_its_points(tiny_build):
    folder, summary = tiny_build
    assert summary["done"] == summary["total"] == 6 and summary["missing"] == 0
    m = load_map(summary["map"])
    for p in read_points(folder):
        assert p["success"] and p["status"] == "converged", p["message"]
        assert p["provenance"]["solver"]["name"] == "lubrication.solve.solve_lubrication"
        assert p["provenance"]["git_commit"] and p["provenance"]["vesicle-tube"]
        res = query_map(p["nu"], p["lam_ratio"], p["ca_b"], m)
        for q in QUANTITIES:
            assert res[q] == pytest.approx(p[q], rel=5e-10), q     # packed to 10 digits
        assert res["shape_class"] == p["shape_class"]
    # between the points: within the (loose, 2-node) error bar of the tiny grid
    mid = query_map(0.92, 0.96, 50.0, m).quantities["V_over_U"]
    assert mid.value is not None and 1.0 < mid.value < 2.0 and mid.error > 0


# ----------------------------------------------------------------------------- resume (in-process)

CALLS = []


def _fake_solver(nu, lam_ratio, ca_b, warm, options, max_time):
    """Stands in for a solver: a known smooth answer, a shape, and the warm start it got."""
    CALLS.append((nu, lam_ratio, ca_b, None if warm is None else
                  ((warm["nu"], warm["lam_ratio"]) if isinstance(warm, dict) else warm)))
    ok = nu != 0.85
    lam_c = float(critical_confinement(nu))
    fields = {"success": ok, "message": "ok" if ok else "did not converge",
              "lam": lam_ratio * lam_c, "lam_c": lam_c,
              **{q: (truth(q, nu, lam_ratio, ca_b) if ok else None) for q in QUANTITIES},
              "shape_class": "bullet" if ok else None,
              "error_estimate": dict.fromkeys(QUANTITIES), "residual": 0.0,
              "bie_solves": 1, "shape": {"modes": [0.1], "density": []} if ok else None}
    return fields, ({"nu": nu, "lam_ratio": lam_ratio} if ok else None)


def test_bem_lines_run_along_nu_and_lubrication_lines_along_lam():
    lines = line_tasks(make_grid([0.8, 0.9], [0.3, 0.95], [50.0, 500.0]))
    assert lines[0] == ("lubrication", 50.0, [(0.9, 0.3), (0.9, 0.95)])
    assert ("bem", 50.0, [(0.9, 0.3), (0.8, 0.3)]) in lines
    assert [t[0] for t in lines] == ["lubrication"] * 4 + ["bem"] * 4


def test_resume_solves_only_the_missing_points_and_warm_starts_from_the_stored_shape(
        tmp_path, monkeypatch):
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    grid = make_grid([0.8, 0.85, 0.9, 0.95], [0.3], [50.0], ["bem"])
    CALLS.clear()
    first = build_map(tmp_path, grid, workers=1)
    assert [c[0] for c in CALLS] == [0.95, 0.9, 0.85, 0.8]           # nu decreasing
    assert [c[3] for c in CALLS] == [None, (0.95, 0.3), (0.9, 0.3), (0.9, 0.3)]
    assert first["failed"] == 1 and first["missing"] == 0
    (tmp_path / point_filename("bem", 0.8, 0.3, 50.0)).unlink()
    (tmp_path / point_filename("bem", 0.95, 0.3, 50.0)).unlink()
    # a killed write: atomic_write's temporary (.NAME.XXXXXXXX.tmp) of a point file
    (tmp_path / ".bem_nu0.9_lr0.3_caB50.json.k2x_9ab0.tmp").write_text("{half")
    theirs = [tmp_path / ".notes.tmp", tmp_path / ".results.json.k3x9.tmp"]   # not the build's
    for f in theirs:
        f.write_text("the user's")
    CALLS.clear()
    again = build_map(tmp_path, None, workers=1)      # resume: the stored grid
    assert [c[0] for c in CALLS] == [0.95, 0.8]         # the failed 0.85 is not recomputed
    # 0.8 warm-starts from the *stored* record of 0.9 (the last converged point on disk)
    assert CALLS[1][3] == (0.9, 0.3)
    assert again["new"] == 2 and again["done"] == 4
    assert sorted(tmp_path.glob(".*.tmp")) == sorted(theirs)   # only its own temporaries go
    assert all(f.read_text() == "the user's" for f in theirs)
    CALLS.clear()
    build_map(tmp_path, None, workers=1, retry_failed=True)
    assert [c[0] for c in CALLS] == [0.85]


def test_a_folder_of_another_grid_is_refused(tmp_path, monkeypatch):
    from lubrication.checks import InvalidParameterError
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    build_map(tmp_path, make_grid([0.9], [0.3], [50.0], ["bem"]), workers=1)
    with pytest.raises(InvalidParameterError, match="another grid"):
        build_map(tmp_path, make_grid([0.8], [0.3], [50.0], ["bem"]), workers=1)


def test_a_grid_containing_the_stored_one_extends_the_build(tmp_path, monkeypatch):
    """Extension: the stored points are kept and not recomputed, only the new nodes are solved,
    and build.json records the new grid (a later resume without a grid uses it)."""
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    build_map(tmp_path, make_grid([0.9], [0.3], [50.0], ["bem"]), workers=1)
    CALLS.clear()
    wider = make_grid([0.9], [0.3, 0.35], [50.0], ["bem"])
    out = build_map(tmp_path, wider, workers=1)
    assert [c[:2] for c in CALLS] == [(0.9, 0.35)] and out["done"] == 2 and out["new"] == 1
    info = json.loads((tmp_path / "build.json").read_text())
    assert info["grid"]["lam_ratio"]["bem"] == [0.3, 0.35] and len(info["extended"]) == 1
    CALLS.clear()
    assert build_map(tmp_path, None, workers=1)["total"] == 2 and CALLS == []


@pytest.mark.slow
def test_a_cheap_bem_line_stores_shapes_and_resumes_from_them(tmp_path):
    """One real BEM line, lam/lam_c = 0.3, nu = 0.98 then 0.95, 8 modes, loose tolerances
    (about 30 s with numba compilation): the shapes are stored, the pack holds the points, and a
    resumed line warm-starts from the stored shape of the larger nu."""
    grid = make_grid([0.95, 0.98], [0.3], [50.0], ["bem"])
    options = {"bem": {"n_modes": 8, "tol": 5e-2, "residual_tol": 1e-2}}
    summary = build_map(tmp_path, grid, options=options, workers=1)
    points = {p["nu"]: p for p in read_points(tmp_path)}
    assert all(p["success"] for p in points.values()), [p["message"] for p in points.values()]
    neighbour = "neighbour (nu=0.98, lam/lam_c=0.3)"
    assert points[0.95]["seed"] == neighbour and len(points[0.95]["shape"]["modes"]) == 8
    assert points[0.98]["error_estimate"]["V_over_U"] is not None
    m = load_map(summary["map"])
    res = query_map(0.95, 0.3, 50.0, m)
    assert res["dp_plus_R0"] == pytest.approx(points[0.95]["dp_plus_R0"], rel=5e-10)
    assert res.quantities["dp_plus_R0"].solver_error > 0
    (tmp_path / point_filename("bem", 0.95, 0.3, 50.0)).unlink()
    again = build_map(tmp_path, None, options=options, workers=1)
    redo = {p["nu"]: p for p in read_points(tmp_path)}[0.95]
    assert again["new"] == 1 and redo["success"] and redo["seed"] == neighbour
    assert redo["dp_plus_R0"] == pytest.approx(points[0.95]["dp_plus_R0"], rel=5e-2)


def test_lubrication_only_nodes_between_bem_points_are_left_out(tmp_path):
    """The rule: below the largest converged BEM λ/λc of a line, a lubrication-only node (here
    0.95, lubrication 10 % off the truth) is not used; the BEM neighbours are interpolated.
    Above it (0.99) lubrication answers, with its model error."""
    folder = tmp_path / "b"
    folder.mkdir()
    nus, cas = [0.7, 0.8, 0.9], [15.0, 50.0, 500.0]
    grid = make_grid(nus, {"bem": [0.8, 0.85, 0.9, 0.98], "lubrication": [0.95, 0.98, 0.99]},
                     cas)
    (folder / "build.json").write_text(json.dumps({"grid": grid, "parameters": {},
                                                   "provenance": {"test": "rule"}}))
    for nu in nus:
        for ca in cas:
            for r in grid["lam_ratio"]["bem"]:
                _write_point(folder, "bem", nu, r, ca)
            for r in grid["lam_ratio"]["lubrication"]:
                _write_point(folder, "lubrication", nu, r, ca, bias=0.1)
    m = load_map(pack_map(folder))
    at = query_map(0.8, 0.95, 50.0, m).quantities["dp_plus_R0"]
    assert at.methods == ("bem",)
    assert at.value == pytest.approx(truth("dp_plus_R0", 0.8, 0.95, 50.0), rel=1e-2)
    beyond = query_map(0.8, 0.99, 50.0, m).quantities["dp_plus_R0"]
    assert beyond.methods == ("lubrication",)
    lub = _lub(0.1, 0.99)
    assert beyond.value == pytest.approx(lub * truth("dp_plus_R0", 0.8, 0.99, 50.0), rel=5e-10)
    # the model error: the gap at 0.98, the last common point, 0.1 (0.02/0.1)^(1/2) = 4.5 %
    assert beyond.model_error / beyond.value == pytest.approx(_lub(0.1, 0.98) - 1, rel=0.1)


@pytest.mark.parametrize("where", ["rescaling", "solver"])
def test_a_neighbour_shape_that_cannot_start_falls_back_to_the_own_seed(monkeypatch, where):
    """A neighbour whose density does not carry over to the point (the build met 'min g =
    -0.354' at (0.85, 0.9 lam_c, Ca_B 25), raised inside the solver) is a failed start, not a
    failed point."""
    import types

    import numpy as np

    import bem.shape
    import bem.vesicle
    from lubrication.checks import InvalidParameterError

    def bad_density():
        raise InvalidParameterError("density", "min g = -0.354", "coefficients with g > 0")

    def closed(*args, **kwargs):
        return bad_density() if where == "rescaling" else "neighbour curve"

    calls = []

    def solve(nu, lam_ratio, ca_b, initial=None, max_time=None, **options):
        calls.append(initial)
        if initial is not None:
            bad_density()
        d = {"lam": 1.0, "lam_c": 1.2, "shape_class": "bullet", "residual": 1e-6, "panels": 10,
             "refinement": [(16,), (24,)], "tol": 1e-4, "residual_tol": 1e-3,
             **{q: 1.0 for q in QUANTITIES}}
        return types.SimpleNamespace(success=True, message="converged", bie_solves=5,
                                     seed="lubrication", error_estimate={}, to_dict=lambda **k: d,
                                     modes=np.zeros(3), density=np.ones(2))

    monkeypatch.setattr(bem.shape.SpectralCurve, "closed", staticmethod(closed))
    monkeypatch.setattr(bem.vesicle, "solve_vesicle", solve)
    warm = {"nu": 0.9, "lam_ratio": 0.9, "shape": {"modes": [0.0], "density": [1.0]}}
    fields, _ = map_build._solve_bem(0.85, 0.9, 25.0, warm, {}, None)
    assert calls == ([None] if where == "rescaling" else ["neighbour curve", None])
    assert fields["success"] and fields["status"] == "converged"
    assert fields["seed"] == "lubrication"
    assert fields["failed_starts"][0].startswith("neighbour (nu=0.9, lam/lam_c=0.9): cannot start")


@pytest.mark.parametrize("neighbour_first", [False, True])
def test_a_slow_red_cell_tries_a_neighbour_at_its_velocity_second_unless_asked_first(
        monkeypatch, neighbour_first):
    """Below Ca_S = VELOCITY_FIRST a red cell's own continuation along the velocity comes
    before a neighbour's shape at the same velocity; a retry of a point whose own starts failed
    (``neighbour_first``, tests/benchmarks/rbc_slice_build.py --from-neighbours) starts from
    the neighbour. Here the own start fails and the neighbour converges: the same record either
    way, but the neighbour is solved first only when asked, and the own start is then not
    needed; asked first, the converged neighbour is a stored steady shape whose ladder may climb
    above the default mode cap (``max_modes``), as the same cell's faster shape does."""
    import types

    import numpy as np

    import bem.shape
    import bem.vesicle
    from bem.vesicle.pipeline import VELOCITY_FIRST

    calls, climbs = [], []

    def solve(nu, lam_ratio, ca_b, initial=None, max_time=None, **options):
        calls.append(initial)
        climbs.append("max_modes" in options)
        assert options["ca_s"] == pytest.approx(ca_b / 231.859) and options["ca_s"] < VELOCITY_FIRST
        ok = initial is not None
        d = {"lam": 1.0, "lam_c": 1.2, "shape_class": "parachute", "residual": 1e-6,
             "panels": 10, "refinement": [(16,), (24,)], "tol": 1e-3, "residual_tol": 1e-3,
             **{q: 1.0 for q in QUANTITIES}}
        return types.SimpleNamespace(success=ok, message="converged" if ok else "self-intersects",
                                     status=None if ok else Status.NO_STEADY_STATE,
                                     bie_solves=5, seed="own", error_estimate={},
                                     to_dict=lambda **k: d, modes=np.zeros(3),
                                     density=np.ones(2))

    monkeypatch.setattr(bem.shape.SpectralCurve, "with_volume_radius",
                        staticmethod(lambda *a, **k: "neighbour curve"))
    monkeypatch.setattr(bem.vesicle, "solve_vesicle", solve)
    warm = {"nu": 0.6, "lam_ratio": 0.6, "ca_b": 4.6372,
            "shape": {"modes": [0.0], "density": [1.0]}}
    fields, _ = map_build._solve_bem(0.575, 0.6, 4.6372, warm, {"shear_ratio": 231.859}, None,
                                     neighbour_first=neighbour_first)
    assert calls == (["neighbour curve"] if neighbour_first else [None, "neighbour curve"])
    assert climbs[-1] is neighbour_first
    assert fields["success"] and fields["seed"] == "neighbour (nu=0.6, lam/lam_c=0.6)"
