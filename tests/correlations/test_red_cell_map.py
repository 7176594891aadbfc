"""The shipped red-cell slice of the map (correlations/data/rbc_slice_map.json) against direct
BEM solves of the same red cells off its grid.

The references are direct solves by :func:`bem.vesicle.solve_vesicle` with ``ca_s`` (each
converged to its own tolerance), stored with their inputs:

* ``docs/data/rbc_slice_offgrid.json``: a pseudo-random draw off every node of the slice's
  grid (ν, λ/λc and Ca_B; ``python tests/benchmarks/map_offgrid.py --map
  correlations/data/rbc_slice_map.json --json docs/data/rbc_slice_offgrid.json ...``);
* ``docs/data/rbc_shear_bem.json``: the default cell (ν = 0.610) in 4-8 µm tubes
  (``python tests/benchmarks/rbc_shear_bem.py``), off the slice's ν and λ/λc nodes.

The target of the red-cell estimate: its error bar covers |map − direct| at ≥ 90 % of ≥ 20
off-grid points, for each of V/U, Δp⁺, ℓ and the minimum film. Only the map is queried here
(milliseconds); the solves were done once.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from correlations.estimate import estimate
from correlations.solution_map import RED_CELL_MAP, load_map, query_map

DATA = Path(__file__).resolve().parents[2] / "docs" / "data"
QUANTITIES = ("V_over_U", "dp_plus_R0", "ell", "film_min")
COVERAGE = 0.9
MIN_POINTS = 20

pytestmark = pytest.mark.skipif(not RED_CELL_MAP.exists(), reason="no red-cell map shipped")


def _direct_solves() -> list[tuple]:
    """(ν, λ/λc, Ca_B, {quantity: direct value}) of every converged stored direct solve."""
    out = []
    for row in json.loads((DATA / "rbc_slice_offgrid.json").read_text())["points"]:
        if row["direct"]["success"]:
            out.append((*row["point"], row["direct"]))
    shear = json.loads((DATA / "rbc_shear_bem.json").read_text())
    nu = shear["parameters"]["nu"]
    for key, row in shear["rows"].items():
        if key.startswith("red cell") and row["success"]:
            out.append((nu, row["lam_ratio"], row["ca_b"], row))
    return out


def test_the_error_bar_covers_direct_solves_off_the_grid():
    m = load_map(RED_CELL_MAP)
    assert m.membrane is not None
    tallies = {q: [0, 0] for q in QUANTITIES}           # answered, covered
    for nu, ratio, ca_b, direct in _direct_solves():
        res = query_map(nu, ratio, ca_b, m)
        for q in QUANTITIES:
            v = res.quantities[q]
            if v.value is None or direct.get(q) is None:
                continue
            assert v.error is not None and v.error > 0, (nu, ratio, ca_b, q)
            tallies[q][0] += 1
            tallies[q][1] += abs(v.value - direct[q]) <= v.error
    for q, (answered, covered) in tallies.items():
        assert answered >= MIN_POINTS, (q, answered)
        assert covered / answered >= COVERAGE, (q, covered, answered)


def test_the_default_estimate_is_a_red_cell_with_every_error_bar():
    e = estimate()
    assert e.inputs["membrane"] == "red-cell"
    for q in ("V_over_U", "dp_plus_R0", "film", "ell", "tension_front", "tension_max"):
        quantity = e.quantities[q]
        assert quantity.value is not None and quantity.method.startswith("map ("), q
        assert quantity.error is not None and 0 < quantity.error < abs(quantity.value), q
