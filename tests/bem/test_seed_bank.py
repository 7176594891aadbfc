"""The seed bank of converged shapes and the default solve's starts from it."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from bem.seed_bank import SHAPE_CLASSES, SeedBank, load_seed_bank
from correlations.map_build import write_seed_bank
from correlations.solution_map import query_map
from lubrication.checks import InvalidParameterError
from lubrication.geometry import critical_confinement

BUILD = Path(__file__).resolve().parents[2] / "correlations" / "data" / "solution_map_build"


def test_shipped_bank_is_the_shipped_builds_converged_shapes(tmp_path):
    """The bank is made from the build folder the map is packed from, never edited by hand."""
    shipped = load_seed_bank()
    made = load_seed_bank.__wrapped__(write_seed_bank(BUILD, tmp_path / "bank.npz"))
    for name in ("nu", "lam_ratio", "ca_b", "shape_class", "offsets", "modes", "density"):
        np.testing.assert_array_equal(getattr(shipped, name), getattr(made, name), err_msg=name)
    assert len(shipped) > 700 and set(np.unique(shipped.shape_class)) == {0, 1}


def test_nearest_ranks_by_the_scaled_distance_and_filters_by_class():
    bank = SeedBank.from_shapes([
        (0.80, 0.30, 25.0, "parachute", [0.0, 0.1, 0.0], [0.0]),
        (0.85, 0.30, 25.0, "bullet", [0.0, 0.2], [0.0]),
        (0.80, 0.50, 25.0, "bullet", [0.0, 0.3, 0.1, 0.0], [0.0])])
    # from (0.8, 0.3, 25): 0 away, one ν step (0.05) = 1, two λ/λc steps (0.1 each) = 2
    near = bank.nearest(0.8, 0.3, 25.0, k=3)
    assert [s.distance for s in near] == pytest.approx([0.0, 1.0, 2.0])
    assert [s.shape_class for s in near] == ["parachute", "bullet", "bullet"]
    assert near[2].modes.tolist() == [0.0, 0.3, 0.1, 0.0]
    assert [s.nu for s in bank.nearest(0.8, 0.3, 25.0, k=3, shape_class="bullet")] == [0.85, 0.8]
    assert bank.nearest(0.8, 0.3, 25.0 * 10 ** 0.3, k=3, within=0.99) == []   # one Ca_B unit away


def test_a_stored_shape_takes_the_volume_of_the_target():
    seed = load_seed_bank().nearest(0.7, 0.5, 20.0)[0]
    lam = 0.5 * float(critical_confinement(0.7))
    curve = seed.curve(lam)
    assert curve.volume() == pytest.approx(4.0 / 3.0 * math.pi * lam**3, rel=1e-12)
    assert seed.shape_class in SHAPE_CLASSES and seed.label().startswith("seed bank (")


def test_a_bank_of_inconsistent_arrays_is_refused():
    with pytest.raises(InvalidParameterError, match="seed bank"):
        SeedBank(nu=[0.8], lam_ratio=[0.3], ca_b=[25.0], shape_class=[0], offsets=[0, 3],
                 modes=[0.0, 0.1], density=[[0.0]])


@pytest.mark.parametrize("nu, ratio, ca_b", [(0.8703, 0.442, 12.8), (0.7543, 0.511, 24.3)])
def test_points_where_the_model_seeds_failed_converge_and_agree_with_the_map(nu, ratio, ca_b):
    """Two random points at which the default solve from the lubrication seed ended in a
    non-steady minimum (steady residual 5e-3 to 4e-2); from the nearest stored shape they
    converge. The map's interpolation (another set of solves, interpolated) covers them within
    its error bar."""
    from bem.vesicle import solve_vesicle
    res = solve_vesicle(nu, lam_ratio=ratio, ca_b=ca_b)
    assert res.success, res.message
    assert res.seed.startswith("seed bank")
    q = query_map(nu, ratio, ca_b)
    for k in ("V_over_U", "dp_plus_R0"):
        m = q.quantities[k]
        assert abs(getattr(res, k) - m.value) <= m.error, (k, getattr(res, k), m.value, m.error)


def test_a_bistable_point_returns_either_branch_on_request():
    """(0.8, 0.3 λc, Ca_B 35), inside the band where the elongated (bullet) and the parachute
    branch coexist (tests/benchmarks/map_bistability.py: both converged at ν = 0.8, λ/λc = 0.3,
    Ca_B 25 and 50). The default solve reports the other branch; asking for it gives the same
    state converged on its own, and the two differ in V/U by far more than their error."""
    from bem.vesicle import solve_vesicle
    default = solve_vesicle(0.8, lam_ratio=0.3, ca_b=35.0)
    assert default.success, default.message
    other = default.other_branch
    assert other and other["shape_class"] != default.shape_class
    assert "bistable" in default.message and f"branch={other['shape_class']!r}" in default.message
    asked = solve_vesicle(0.8, lam_ratio=0.3, ca_b=35.0, branch=other["shape_class"])
    assert asked.success and asked.shape_class == other["shape_class"], asked.message
    assert asked.V_over_U == pytest.approx(other["V_over_U"],
                                           abs=3 * asked.error_estimate["V_over_U"])
    assert abs(asked.V_over_U - default.V_over_U) > 1e3 * asked.error_estimate["V_over_U"]


def test_an_unknown_branch_is_refused_before_any_work():
    from bem.vesicle import solve_vesicle
    with pytest.raises(InvalidParameterError, match="branch"):
        solve_vesicle(0.8, lam_ratio=0.3, branch="round")


@pytest.mark.slow           # ~45 s: a failed start, a time relaxation and the ladder after it
def test_time_relaxation_reaches_the_steady_state_the_model_seed_missed():
    """At (0.6449, 0.281 λc, Ca_B 43.9) the solver's own seed (a spheroid: the lubrication branch
    ends above this λ) stalls in a non-steady minimum (residual 7e-3). Without the seed bank the
    pipeline relaxes that shape in time and refines the result: it must be the parachute the
    stored shape reaches directly, V/U equal within the two error estimates."""
    from bem.vesicle import solve_vesicle
    relaxed = solve_vesicle(0.6449, lam_ratio=0.281, ca_b=43.9, seed_bank=False)
    assert relaxed.success, relaxed.message
    assert relaxed.seed.startswith("time relaxation") and relaxed.failed_starts
    direct = solve_vesicle(0.6449, lam_ratio=0.281, ca_b=43.9)
    assert direct.success and direct.seed.startswith("seed bank"), direct.message
    assert relaxed.shape_class == direct.shape_class == "parachute"
    bound = 3 * (relaxed.error_estimate["V_over_U"] + direct.error_estimate["V_over_U"])
    assert abs(relaxed.V_over_U - direct.V_over_U) <= bound
