"""The solution map as rows of the estimate's method table (correlations.registry map rows).

References: the map's own query (:func:`correlations.solution_map.query_map`, tested in
test_solution_map.py) on a small analytic map built here (the fake build of test_solution_map),
the values stored in the packed shipped map, and the printed closed forms (Chen et al. 2020
eq. asmyp1, as in test_estimate.py). Unit conversions are recomputed by hand.
"""

from __future__ import annotations

import json
import math

import pytest
from test_estimate import MAP_NAMES, ref_lam_c, ref_speed_asmyp1
from test_solution_map import _fake_build

from correlations import registry
from correlations.estimate import estimate as estimate_any_membrane
from correlations.estimate import estimate_dimensionless
from correlations.solution_map import DEFAULT_MAP, load_map, query_map


def estimate(*args, **kw):
    """The estimate of a vesicle (the model these tests are about; the red cell's:
    test_estimate_red_cell.py)."""
    return estimate_any_membrane(*args, **{"membrane": "vesicle", **kw})


#: Estimate quantity -> its name in the map, for the quantities in the same unit.
SAME_UNIT = {"V_over_U": "V_over_U", "film": "film_min", "ell": "ell",
             "dp_plus_R0": "dp_plus_R0"}
TENSIONS = ("tension_front", "tension_max")

shipped = pytest.mark.skipif(not DEFAULT_MAP.exists(),
                             reason=f"no solution map shipped at {DEFAULT_MAP}")


@pytest.fixture(scope="module")
def analytic_map(tmp_path_factory):
    """The analytic map of test_solution_map: nu 0.6-0.9, BEM lam/lam_c 0.2-0.9, lubrication
    0.9-0.99, Ca_B 5, 50, 500."""
    return load_map(_fake_build(tmp_path_factory.mktemp("analytic-estimate")))


@pytest.fixture
def count_queries(monkeypatch):
    """Number of calls of query_map (the estimate's cache cleared first)."""
    import correlations.solution_map as sm
    calls = []
    real = sm.query_map

    def counting(*args, **kwargs):
        calls.append(args)
        return real(*args, **kwargs)
    registry.map_query.cache_clear()
    monkeypatch.setattr(sm, "query_map", counting)
    yield calls
    registry.map_query.cache_clear()


# ----------------------------------------------------------------------------- (a) map values

@pytest.mark.parametrize("nu, ratio, ca_b, methods", [
    (0.75, 0.7, 100.0, ("bem",)),                   # between nodes on every axis
    (0.7, 0.8, 50.0, ("bem",)),                     # on a node
    (0.72, 0.93, 60.0, ("bem", "lubrication")),     # between a BEM and a lubrication node
    (0.72, 0.97, 60.0, ("lubrication",)),           # between lubrication nodes near lam_c
    (0.8, 0.99, 50.0, ("lubrication",)),            # a lubrication node
])
def test_the_map_rows_return_the_query_values_and_errors(analytic_map, count_queries, nu, ratio,
                                                         ca_b, methods):
    e = estimate_dimensionless(nu, ratio * ref_lam_c(nu), ca_b, solution_map=analytic_map)
    ref = query_map(nu, e["lam"] / e["lam_c"], ca_b, analytic_map).quantities
    assert len(count_queries) == 1          # one query serves every map row
    name = MAP_NAMES[methods]
    for key, q_map in SAME_UNIT.items():
        q = e.quantities[key]
        assert (q.value, q.error, q.method, q.valid) == (ref[q_map].value, ref[q_map].error,
                                                         name, True), key
        assert ref[q_map].methods == methods
    assert e["shape_class"] == ref["shape_class"].value == "bullet"
    assert e.quantities["shape_class"].method == name
    assert e["dp_plus_R"] == e["dp_plus_R0"] / e["lam"]
    assert e.quantities["dp_plus_R"].error == ref["dp_plus_R0"].error / e["lam"]
    # Tensions: the map's are gamma/(eta U); the table's gamma/(eta V) = (gamma/(eta U))/(V/U).
    speed = ref["V_over_U"].value
    for t in TENSIONS:
        assert e[t] == ref[t].value / speed and e.quantities[t].error == ref[t].error / speed
        assert e[f"{t}_etaU"] == pytest.approx(ref[t].value, rel=1e-15)
        assert e.quantities[f"{t}_etaU"].error == pytest.approx(ref[t].error, rel=1e-15)
        assert e.quantities[f"{t}_etaU"].method == name
    assert e.quantities["ca_b"].value == ca_b
    assert any(n.startswith("V_over_U, film, ell, dp_plus_R0, shape_class, tension_front, "
                            "tension_max from the solution map") for n in e.notes)


def test_physical_quantities_carry_the_scaled_error(analytic_map):
    """RBC default (90 fL, 135 um^2, 4 um, 1 mm/s, 1.2 mPa s, 2e-19 J) with the analytic map:
    every derived unit scales value and error alike."""
    e = estimate(solution_map=analytic_map, hematocrit=0.3)
    R0 = (3.0 * 90.0 / (4.0 * math.pi)) ** (1.0 / 3.0) * 1e-6        # [m]
    R, eta, U = 2e-6, 1.2e-3, 1e-3
    ca_b = eta * U * R0**2 / 2e-19
    nu = 6.0 * math.sqrt(math.pi) * 90.0 * 135.0 ** -1.5
    ref = query_map(nu, e["lam"] / e["lam_c"], ca_b, analytic_map).quantities
    expected = {"V_mm_s": ("V_over_U", U * 1e3), "dp_plus_Pa": ("dp_plus_R0", eta * U / R0),
                "film_nm": ("film_min", R * 1e9), "length_um": ("ell", R * 1e6),
                "tension_front_mN_m": ("tension_front", eta * U * 1e3),
                "tension_max_mN_m": ("tension_max", eta * U * 1e3)}
    for key, (q_map, factor) in expected.items():
        q = e.quantities[key]
        assert q.value == pytest.approx(ref[q_map].value * factor, rel=1e-12), key
        assert q.error == pytest.approx(ref[q_map].error * factor, rel=1e-12), key
        assert q.method == MAP_NAMES[ref[q_map].methods] and q.valid, key
    # The single-file viscosity takes the map's dp+: 1 + (3/32)(R/R0)^4 dp+ H_T (Chen 2020).
    assert e.quantities["eta_rel"].method == "single_file_chen2020"
    assert e["eta_rel"] == pytest.approx(
        1.0 + 3.0 / 32.0 * (R / R0) ** 4 * ref["dp_plus_R0"].value * 0.3, rel=1e-12)
    # The tensions are compared with the lysis range, with their error bars.
    assert any(n.startswith("Maximum tension ") and "±" in n and "lysis" in n for n in e.notes)
    assert e.quantities["ca_b"].value == pytest.approx(ca_b, rel=1e-12)


def test_without_a_ca_b_the_map_uses_50_and_says_so(analytic_map):
    nu = 0.75
    e = estimate_dimensionless(nu, 0.7 * ref_lam_c(nu), solution_map=analytic_map)
    ref = query_map(nu, e["lam"] / e["lam_c"], 50.0, analytic_map).quantities
    assert e["V_over_U"] == ref["V_over_U"].value
    q = e.quantities["ca_b"]
    assert q.value == 50.0 and "assumed by the solution map" in q.method
    assert any("Ca_B = 50 (assumed: not given)" in n for n in e.notes)


# ----------------------------------------------------------------------------- (b) outside

def test_outside_the_map_the_closed_forms_answer_and_the_reason_is_given(analytic_map):
    nu = 0.95                                   # above the map's largest nu = 0.9
    lam = 0.95 * ref_lam_c(nu)                  # delta = 0.05: near-critical closed forms
    e = estimate_dimensionless(nu, lam, solution_map=analytic_map)
    assert e.quantities["V_over_U"].method == "near_critical_barakat2018a"
    assert e["V_over_U"] == pytest.approx(ref_speed_asmyp1(nu, lam), rel=1e-12)
    assert e.quantities["V_over_U"].error is None                 # closed forms: no error bar
    assert any("The solution map gives no V_over_U" in n and "nu=0.95 outside the map's range "
               "0.6 <= nu <= 0.9" in n for n in e.notes)
    q = e.quantities["tension_max"]                               # no closed form
    assert q.value is None and "solution_map: nu=0.95 outside the map's range" in q.note


@pytest.mark.parametrize("ratio, ca_b, words", [
    (0.1, 50.0, "lam_ratio=0.1 outside the map's range 0.2 <= lam/lam_c <= 0.99"),
    (0.5, 2.0, "ca_b=2 outside the map's range 5 <= Ca_B <= 10000"),
    (0.5, 2e4, "ca_b=20000 outside the map's range 5 <= Ca_B <= 10000"),
])
def test_outside_the_map_and_no_closed_form_the_value_is_missing_with_the_reason(
        analytic_map, ratio, ca_b, words):
    nu = 0.8                                    # intermediate: no closed form for V/U
    e = estimate_dimensionless(nu, ratio * ref_lam_c(nu), ca_b, solution_map=analytic_map)
    for key in ("V_over_U", "dp_plus_R0", "film", "tension_front", "tension_max"):
        q = e.quantities[key]
        assert q.value is None and q.error is None, key
        assert q.note.startswith(f"no valid method (solution_map: {words}"), (key, q.note)


def test_next_to_a_hole_the_map_has_no_value(tmp_path):
    m = load_map(_fake_build(tmp_path / "b", hole=(0.7, 0.6, 50.0)))
    e = estimate_dimensionless(0.7, 0.55 * ref_lam_c(0.7), 50.0, solution_map=m)
    assert e["V_over_U"] is None
    assert "hole at nu=0.7, lam/lam_c=0.6, Ca_B=50" in e.quantities["V_over_U"].note


def test_above_the_largest_ca_b_the_map_clamps_with_its_model_error(analytic_map):
    nu, ratio = 0.75, 0.7
    e = estimate_dimensionless(nu, ratio * ref_lam_c(nu), 2000.0, solution_map=analytic_map)
    top = query_map(nu, e["lam"] / e["lam_c"], 500.0, analytic_map).quantities["dp_plus_R0"]
    clamped = query_map(nu, e["lam"] / e["lam_c"], 2000.0, analytic_map).quantities["dp_plus_R0"]
    q = e.quantities["dp_plus_R0"]
    assert q.value == clamped.value == top.value
    assert q.error == clamped.error > top.error                 # + the measured Ca_B change
    assert "above the map's largest 500" in q.note


def test_without_the_map_the_map_rows_are_not_tried(count_queries):
    e = estimate_dimensionless(0.9, 0.6 * ref_lam_c(0.9), 50.0, solution_map=False)
    assert count_queries == [] and e["V_over_U"] is None
    assert "solution_map" not in e.quantities["V_over_U"].note


def test_a_bad_map_is_refused_before_any_work(tmp_path):
    from lubrication.checks import InvalidParameterError
    bad = tmp_path / "map.json"
    bad.write_text("{}")
    with pytest.raises(InvalidParameterError, match="map") as info:
        estimate_dimensionless(0.9, 1.0, solution_map=bad)
    assert info.value.name == "map" and str(bad) in str(info.value)
    with pytest.raises(InvalidParameterError, match="solution_map=3"):
        estimate(solution_map=3)


# ----------------------------------------------------------------------------- (d) solvers first

def test_an_enabled_solver_overrides_the_map_and_the_map_is_its_fallback(analytic_map,
                                                                          monkeypatch):
    from types import SimpleNamespace
    calls = []

    def fake_bem(nu, lam, ca_b):
        calls.append((nu, lam, ca_b))
        return SimpleNamespace(success=success, message="fake: no convergence", V_over_U=1.2345,
                               dp_plus_R0=123.4, ell=3.21, film_min=0.0432, tension_front=6.5,
                               tension_max=7.5, shape_class="parachute")
    monkeypatch.setattr(registry, "_bem_result", fake_bem)
    nu = 0.75
    lam = 0.7 * ref_lam_c(nu)
    success = True
    e = estimate_dimensionless(nu, lam, 50.0, solvers=("bem",), solution_map=analytic_map)
    for key in ("V_over_U", "film", "ell", "dp_plus_R0", "shape_class", *TENSIONS):
        assert e.quantities[key].method == "bem_vesicle" and e.quantities[key].error is None
    assert (e["V_over_U"], e["tension_max_etaU"]) == (1.2345, pytest.approx(7.5, rel=1e-15))
    assert set(calls) == {(nu, lam, 50.0)} and e.converged     # the case's point, solved
    success = False
    f = estimate_dimensionless(nu, lam, 50.0, solvers=("bem",), solution_map=analytic_map)
    ref = query_map(nu, f["lam"] / f["lam_c"], 50.0, analytic_map).quantities["V_over_U"]
    assert f.quantities["V_over_U"].method == "map (BEM, interpolated)"
    assert f["V_over_U"] == ref.value and f.converged is False


# ----------------------------------------------------------------------------- (c, e) shipped map

MAP_KEYS = ("V_over_U", "V_mm_s", "dp_plus_R0", "dp_plus_Pa", "film", "film_nm", "ell",
            "length_um", "tension_front_mN_m", "tension_max_mN_m")


@shipped
def test_the_default_estimate_answers_from_the_shipped_map(cli, report):
    """The human RBC as a vesicle in a 4 um capillary (nu = 0.61, lam/lam_c = 0.71, Ca_B = 46)
    gets V/U, V, dp+, film, L and both tensions from the map, each with an error bar; the
    single-file viscosity then has its dp+."""
    e = estimate(hematocrit=0.3)
    missing = {k: e.quantities[k].note for k in MAP_KEYS if e[k] is None}
    assert not missing, missing
    for key in MAP_KEYS:
        q = e.quantities[key]
        assert q.method.startswith("map (") and q.valid and q.error is not None, (key, q)
        assert 0.0 <= q.error < abs(q.value), (key, q)
        report.value(f"est.map_{key}", q.value, reference=q.error, tol="error bar < |value|",
                     kind="regression", source="the shipped solution map (our BEM values)")
    assert e.quantities["eta_rel"].method == "single_file_chen2020"
    code, table, _ = cli("estimate", "--membrane", "vesicle")
    for label in ("speed V/U", "cell speed V", "extra pressure drop dp+", "film thickness h",
                  "length L", "front tension gamma_F", "maximum tension gamma_max"):
        rows = [line for line in table.splitlines() if line.startswith(label)]
        assert rows and all("±" in line for line in rows), (label, rows)


@shipped
def test_the_estimate_reproduces_a_stored_node_of_the_shipped_map():
    """nu = 0.9, lam/lam_c = 0.5, Ca_B = 50: the values stored in the packed file (read here
    from its columns, not through the map code) within 1e-9."""
    data = json.loads(DEFAULT_MAP.read_text(encoding="utf-8"))
    cols = data["columns"]
    rows = [i for i, (m, nu, r, ca) in enumerate(zip(cols["method"], cols["nu"],
                                                      cols["lam_ratio"], cols["ca_b"]))
            if m == "bem" and (nu, r, ca) == (0.9, 0.5, 50.0)]
    assert len(rows) == 1, "the shipped map has no converged BEM point at (0.9, 0.5, 50)"
    stored = {c: cols[c][rows[0]] for c in cols}
    e = estimate_dimensionless(0.9, 0.5 * ref_lam_c(0.9), 50.0)
    for key, col in (("V_over_U", "V_over_U"), ("dp_plus_R0", "dp_plus_R0"),
                     ("film", "film_min"), ("ell", "ell"), ("tension_front_etaU", "tension_front"),
                     ("tension_max_etaU", "tension_max")):
        assert e[key] == pytest.approx(stored[col], rel=1e-9, abs=0), key
        assert e.quantities[key].method == "map (BEM, interpolated)", key
    assert e["shape_class"] == stored["shape_class"]


def _between_nodes():
    """nu = 0.9, lam/lam_c = 0.55, Ca_B = 50: between BEM nodes of the shipped map."""
    return 0.9, 0.55 * ref_lam_c(0.9)


@shipped
def test_the_cli_shows_error_bars_and_the_json_has_them(cli):
    nu, lam = _between_nodes()
    argv = ("estimate", "--nu", "0.9", "--lam", repr(lam), "--ca-b", "50")
    code, out, err = cli(*argv, "--json")
    assert code == 0, err
    obj = json.loads(out)
    ref = query_map(nu, obj["lam"] / obj["lam_c"], 50.0).quantities
    for key, col in (("V_over_U", "V_over_U"), ("dp_plus_R0", "dp_plus_R0")):
        assert obj[key] == ref[col].value, key
        assert obj["methods"][key]["error"] == ref[col].error, key
        assert obj["methods"][key]["method"].startswith("map (")
    assert obj["methods"]["lam_c"]["error"] is None                # geometry: exact
    code, table, _ = cli(*argv)
    row = next(line for line in table.splitlines() if line.startswith("speed V/U"))
    value, error = (float(x) for x in row.split()[2:5:2])          # "speed V/U a ± b ..."
    assert row.split()[3] == "±"
    assert abs(value - ref["V_over_U"].value) <= 0.5 * error
    assert error == pytest.approx(ref["V_over_U"].error, rel=0.05)  # 2 significant digits
    code, table, _ = cli(*argv, "--no-map")
    row = next(line for line in table.splitlines() if line.startswith("speed V/U"))
    assert "±" not in row and "map" not in row
