"""The estimate of a red cell (membrane shear elasticity) from the red-cell slice of the map.

References: the map's own query (:func:`correlations.solution_map.query_map`, tested in
test_solution_map.py) on a small analytic red-cell map built here (the fake build of
test_solution_map, packed with the BEM option ``shear_ratio`` of the default red cell); the
capillary numbers recomputed by hand from their definitions (Ca_S = eta U/G_s, beta =
G_s R0^2/kappa); and, for the vesicle, the answers of the estimate at the revision before red
cells (tests/correlations/data/estimate_vesicle_reference.json, written by
tests/benchmarks/estimate_vesicle_reference.py). No solver runs here.
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
from pathlib import Path

import pytest
from test_solution_map import _write_point

from correlations import registry
from correlations import solution_map as sm
from correlations.estimate import estimate, estimate_dimensionless
from correlations.map_build import SHEAR_RATIO, make_grid
from correlations.solution_map import DEFAULT_MAP, load_map, pack_map, query_map
from lubrication.checks import InvalidParameterError

sys.path.insert(0, str(Path(__file__).parents[1] / "benchmarks"))
import estimate_vesicle_reference  # noqa: E402  (the reference's cases and writer)

#: beta = G_s R0^2/kappa of the default red cell as the build stores it (6 significant digits)
BETA = 231.859
NUS = [0.55, 0.6, 0.65, 0.7]
RATIOS = [0.5, 0.6, 0.7, 0.8, 0.9]
CAS = [9.2744, 46.3718, 231.8589]          # the slice's Ca_B at 0.2, 1 and 5 mm/s
#: the rows a red cell takes from the map, with their names in the map
FROM_MAP = {"V_over_U": "V_over_U", "film": "film_min", "ell": "ell",
            "dp_plus_R0": "dp_plus_R0", "tension_max": "tension_max"}


def _red_cell_build(folder: Path, beta: float = BETA) -> Path:
    """An analytic red-cell map (BEM nodes only) packed like the slice build's."""
    folder.mkdir(parents=True, exist_ok=True)
    grid = make_grid(NUS, {"bem": RATIOS}, CAS)
    (folder / "build.json").write_text(json.dumps({
        "grid": grid, "parameters": {"options": {"bem": {SHEAR_RATIO: beta}}},
        "provenance": {"test": "analytic red cell"}}))
    for nu in NUS:
        for ca in CAS:
            for r in RATIOS:
                _write_point(folder, "bem", nu, r, ca)
    return pack_map(folder)


@pytest.fixture(scope="module")
def red_cell_map(tmp_path_factory):
    return _red_cell_build(tmp_path_factory.mktemp("red-cell-map"))


@pytest.fixture
def shipped_red_cell_map(red_cell_map, monkeypatch):
    """The analytic red-cell map in the place of the shipped one."""
    monkeypatch.setattr(sm, "RED_CELL_MAP", red_cell_map)
    return red_cell_map


@pytest.fixture
def no_red_cell_map(tmp_path, monkeypatch):
    """No red-cell map shipped."""
    monkeypatch.setattr(sm, "RED_CELL_MAP", tmp_path / "rbc_slice_map.json")


def test_the_map_knows_its_membrane(red_cell_map):
    assert load_map(red_cell_map).membrane == {"shear_ratio": BETA, "reference": "biconcave"}
    if DEFAULT_MAP.exists():
        assert load_map().membrane is None
    res = query_map(0.6, 0.7, 46.3718, red_cell_map)
    assert res.membrane["shear_ratio"] == BETA and res.to_dict()["membrane"] == res.membrane


def test_red_cell_rows_come_from_the_red_cell_map(shipped_red_cell_map):
    e = estimate(hematocrit=0.3, membrane="red-cell")
    # Ca_S = eta U/G_s, beta = G_s R0^2/kappa, by hand: R0 = (3 * 90 / (4 pi))^(1/3) um
    R0 = (3 * 90.0 / (4 * math.pi)) ** (1 / 3) * 1e-6
    assert e["ca_s"] == pytest.approx(1.2e-3 * 1e-3 / 6e-6, rel=1e-12)
    assert e["shear_ratio"] == pytest.approx(6e-6 * R0**2 / 2e-19, rel=1e-12)
    assert e["shear_ratio"] == pytest.approx(e["ca_b"] / e["ca_s"], rel=1e-12)
    assert e.inputs["membrane"] == "red-cell" and e.inputs["shear_modulus_un_m"] == 6.0
    ref = query_map(e["nu"], e["lam"] / e["lam_c"], e["ca_b"], load_map(shipped_red_cell_map))
    for key, name in FROM_MAP.items():
        q, v = e.quantities[key], ref.quantities[name]
        value, error = v.value, v.error
        if key == "tension_max":            # eta V in the table: divided by the map's V/U
            value, error = value / ref["V_over_U"], error / ref["V_over_U"]
        assert q.method == "map (BEM, interpolated)", (key, q)
        assert q.value == pytest.approx(value, rel=1e-12), key
        assert q.error == pytest.approx(error, rel=1e-12), key
    assert e["shape_class"] == ref["shape_class"]
    # the apparent viscosity is the single-file law with the red cell's dp+
    assert e.quantities["eta_rel"].method == "single_file_chen2020"
    assert any("red-cell map (shear ratio beta = 231.9)" in n for n in e.notes), e.notes


def test_vesicle_membrane_is_the_estimate_before_red_cells():
    ref = json.loads(estimate_vesicle_reference.REFERENCE.read_text())
    if ref["map_sha256"] != (hashlib.sha256(DEFAULT_MAP.read_bytes()).hexdigest()
                             if DEFAULT_MAP.exists() else None):
        pytest.fail("the shipped vesicle map is not the one of the reference: write it again "
                    f"with '{ref['made_by']}' if the vesicle estimate is meant to change")
    got = estimate_vesicle_reference.answers()
    for name in estimate_vesicle_reference.CASES:
        assert got[name] == ref["answers"][name], name


def test_vesicle_ignores_the_red_cell_map(shipped_red_cell_map):
    e = estimate(membrane="vesicle", shear_modulus_un_m=8.0)
    assert "ca_s" not in e.quantities and "membrane" not in e.inputs
    assert e.to_dict() | {"provenance": None} == estimate(membrane="vesicle").to_dict() | {
        "provenance": None}


@pytest.mark.parametrize("modulus, answers", [(6.0 * (1 + 0.9e-3), True),
                                              (6.0 * (1 + 1.1e-3), False), (8.0, False)])
def test_beta_must_be_the_maps_within_its_tolerance(shipped_red_cell_map, modulus, answers):
    e = estimate(shear_modulus_un_m=modulus, membrane="red-cell")
    assert (e["V_over_U"] is not None) == answers
    if not answers:
        note = e.quantities["V_over_U"].note
        assert "the red-cell map holds beta = G_s R0^2/kappa = 231.9 (G_s 6 uN/m" in note, note
        assert f"this cell has beta = {e['shear_ratio']:.4g}" in note
        assert "--solver bem or --membrane vesicle" in note
        assert all(e[k] is None for k in FROM_MAP)


@pytest.mark.parametrize("velocity", [10.0, 0.1])      # Ca_B 464 > 231.9; 4.6 < 9.27
def test_a_velocity_outside_the_red_cell_map_is_refused(shipped_red_cell_map, velocity):
    """Outside the map's Ca_B range a red-cell map refuses before any work, naming the velocity
    and its range for this cell (U = Ca_B κ/(η R0²): 9.27-231.9 ↔ 0.2-5 mm/s): the vesicle's
    clamp does not apply (Ca_S changes along the line)."""
    with pytest.raises(InvalidParameterError, match=r"velocity_mm_s=.* valid range 0\.2 to 5 "
                       r"mm/s.*outside the red-cell map"):
        estimate(velocity_mm_s=velocity, membrane="red-cell")
    # with a solver the velocity is the solver's to take; another cell is not the map's
    assert estimate(velocity_mm_s=velocity, shear_modulus_un_m=7.0)["V_over_U"] is None


@pytest.mark.parametrize("velocity", [0.2, 5.0])
def test_the_velocities_of_the_end_lines_are_on_them(shipped_red_cell_map, velocity):
    """The build stores each line's Ca_B rounded to 4 decimals (9.2744 for the Ca_B 9.27436 of
    0.2 mm/s): the velocity of an end line is inside the map and answered on that line."""
    e = estimate(velocity_mm_s=velocity, membrane="red-cell")
    assert e["V_over_U"] is not None and e.quantities["V_over_U"].error is not None
    assert abs(e["ca_b"] - round(e["ca_b"], 4)) > 0          # not the stored node itself


def test_closed_form_vesicle_laws_never_answer_for_a_red_cell(shipped_red_cell_map):
    """delta = 0.06: the near-critical laws answer for the vesicle, not for the red cell."""
    vesicle = estimate(diameter_um=3.0, membrane="vesicle", solution_map=False)
    red = estimate(diameter_um=3.0, membrane="red-cell", solution_map=False)
    assert vesicle.quantities["V_over_U"].method == "near_critical_barakat2018a"
    for key in ("V_over_U", "dp_plus_R0", "film", "ell", "shape_class", "tension_front"):
        assert red[key] is None and red.quantities[key].method is None, key
    assert red["passes"] and red["lam_c"] == vesicle["lam_c"]       # geometry holds for both


def test_without_a_red_cell_map_the_estimate_says_so(no_red_cell_map):
    e = estimate(membrane="red-cell")
    assert e["V_over_U"] is None and e["R0_um"] == pytest.approx(2.7800, abs=1e-4)
    assert "no red-cell map shipped" in e.quantities["V_over_U"].note
    assert any("--solver bem" in n for n in e.notes)


def test_a_map_of_the_other_membrane_is_refused_before_any_work(red_cell_map):
    with pytest.raises(InvalidParameterError, match="red-cell map"):
        estimate(membrane="vesicle", solution_map=red_cell_map)
    if DEFAULT_MAP.exists():
        with pytest.raises(InvalidParameterError, match="vesicle map"):
            estimate(membrane="red-cell", solution_map=DEFAULT_MAP)


def test_dimensionless_estimate_takes_ca_s(red_cell_map):
    from lubrication.geometry import critical_confinement
    lam = 0.7 * float(critical_confinement(0.65))
    e = estimate_dimensionless(0.65, lam, 46.3718, ca_s=46.3718 / BETA,
                               solution_map=red_cell_map)
    assert e.quantities["V_over_U"].method == "map (BEM, interpolated)"
    assert e["shear_ratio"] == pytest.approx(BETA) and e.inputs["membrane"] == "red-cell"
    assert estimate_dimensionless(0.65, lam, 46.3718, ca_s=0.1,
                                  solution_map=red_cell_map)["V_over_U"] is None
    with pytest.raises(InvalidParameterError, match="ca_b"):
        estimate_dimensionless(0.65, lam, ca_s=0.2)


def test_make_run_exits_0_with_and_without_a_red_cell_map(cli, monkeypatch, tmp_path,
                                                          red_cell_map):
    """`make run` is `vesicle-tube estimate` with the defaults (a red cell); the red cell
    answers without a map (saying so) and from one; the vesicle on request."""
    monkeypatch.setattr(sm, "RED_CELL_MAP", tmp_path / "absent.json")
    code, out, err = cli("estimate", "--membrane", "vesicle")
    assert code == 0, err
    assert "vesicle (no shear elasticity)" in out
    code, out, err = cli("estimate")
    assert code == 0, err
    assert "red cell, G_s = 6 uN/m" in out and "no red-cell map shipped" in out
    monkeypatch.setattr(sm, "RED_CELL_MAP", red_cell_map)
    code, out, err = cli("estimate", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["methods"]["V_over_U"]["method"] == "map (BEM, interpolated)"
    assert d["ca_s"] == pytest.approx(0.2) and d["inputs"]["membrane"] == "red-cell"


@pytest.mark.parametrize("argv, option", [
    (("--shear-modulus-uN-m", "-1"), "--shear-modulus-uN-m"),
    (("--shear-modulus-uN-m", "0"), "--shear-modulus-uN-m"),
    (("--shear-modulus-uN-m", "nan"), "--shear-modulus-uN-m"),
    (("--shear-modulus-uN-m", "inf"), "--shear-modulus-uN-m"),
    (("--shear-modulus-uN-m", "1e9"), "--shear-modulus-uN-m"),
    (("--membrane", "red-cell", "--velocity-mm-s", "1e-3", "--solver", "bem"),
     "--velocity-mm-s"),
    (("--membrane", "red-cell", "--velocity-mm-s", "1e5", "--solver", "lubrication"),
     "--velocity-mm-s"),
    (("--membrane", "cell"), "--membrane"),
    (("--nu", "0.6", "--lam", "1.3", "--ca-b", "50", "--ca-s", "-1"), "--ca-s"),
    (("--nu", "0.6", "--lam", "1.3", "--ca-b", "50", "--ca-s", "1e-4", "--solver", "bem"),
     "--ca-s"),
    (("--nu", "0.6", "--lam", "1.3", "--ca-b", "50", "--ca-s", "5e-3", "--solver",
      "lubrication"), "--ca-s"),
    (("--nu", "0.6", "--lam", "1.3", "--ca-s", "0.2"), "--ca-s"),
    (("--ca-s", "0.2"), "--ca-s"),
    (("--nu", "0.6", "--lam", "1.3", "--shear-modulus-uN-m", "6"), "--shear-modulus-uN-m"),
])
def test_bad_red_cell_input_exits_2_naming_the_option(cli_usage_error, no_red_cell_map, argv,
                                                      option):
    line = cli_usage_error("estimate", *argv)
    assert option in line, line


def test_map_query_says_it_is_a_red_cell_map(cli, red_cell_map):
    code, out, err = cli("map", "query", "--map", str(red_cell_map), "--nu", "0.6",
                         "--lam-ratio", "0.7", "--ca-b", "46.3718")
    assert code == 0, err
    assert "RED-CELL map: shear ratio beta = G_s R0^2/kappa = 231.859" in out
    code, out, err = cli("map", "query", "--map", str(red_cell_map), "--nu", "0.6",
                         "--lam-ratio", "0.7", "--ca-b", "46.3718", "--json")
    assert json.loads(out)["membrane"] == {"shear_ratio": BETA, "reference": "biconcave"}


def test_registry_rule_is_symmetric(red_cell_map):
    m = load_map(red_cell_map)
    assert registry.membrane_mismatch(m, {}).startswith("the map is a red-cell map")
    assert registry.membrane_mismatch(m, {"membrane": "red-cell", "shear_ratio": BETA}) == ""


@pytest.mark.parametrize("argv", [
    ("check", str(Path(__file__).parents[2] / "docs" / "data" / "chen2020_table1.csv")),
    ("infer", "--v-over-u", "1.2", "--length-um", "8", "--diameter-um", "5", "--u-mm-s", "1"),
])
def test_vesicle_commands_refuse_a_red_cell_map(cli_usage_error, red_cell_map, argv):
    """The checker's references and the inverse estimate are vesicles: a red-cell map given to
    them is refused before any work, naming --map."""
    line = cli_usage_error(*argv, "--map", str(red_cell_map))
    assert "--map" in line and "it is a red-cell map" in line, line
