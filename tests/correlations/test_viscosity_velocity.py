"""The single-file apparent viscosity at a given velocity, for a red cell and a vesicle.

References: Chen et al. 2020's law (:func:`correlations.viscosity.viscosity_single_file_chen2020`,
tested against the printed formula in test_viscosity.py) applied to the Δp⁺ and H_T of an
:func:`~correlations.estimate.estimate` called here on its own; the analytic red-cell map of
test_estimate_red_cell.py (fixed numbers, Ca_B 9.2744-231.8589, i.e. about 0.2-5 mm/s for the
default cell) in the place of the shipped one; for the physics (Secomb et al. 1986: the red cell's
apparent viscosity rises as the flow slows, the vesicle's does not), the shipped maps.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from test_estimate_red_cell import red_cell_map, shipped_red_cell_map  # noqa: F401 (fixtures)

from correlations import cli as cli_module
from correlations import solution_map as sm
from correlations.estimate import estimate, single_file_viscosity
from correlations.registry import DEFAULT_MEMBRANE
from correlations.plotting import SINGLE_FILE_VELOCITIES_MM_S, plot_single_file_viscosity
from correlations.viscosity import viscosity_single_file_chen2020

MEMBRANES = ("red-cell", "vesicle")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture
def synthetic(shipped_red_cell_map):
    """The analytic red-cell map in the place of the shipped one."""
    return shipped_red_cell_map


def _line(text: str, label: str) -> str:
    return next(line for line in text.splitlines() if line.startswith(label))


# ------------------------------------------------------------------------------------------
# The library function.
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("membrane", MEMBRANES)
@pytest.mark.parametrize("diameter, velocity, kind", [(5.0, 1.0, "tube"), (4.0, 0.3, "tube"),
                                                      (4.5, 3.0, "discharge")])
def test_eta_rel_is_chen_law_on_the_estimates_dp(synthetic, membrane, diameter, velocity, kind):
    r = single_file_viscosity(diameter, 0.3, hematocrit_kind=kind, velocity_mm_s=velocity,
                              membrane=membrane)
    e = estimate(diameter_um=diameter, velocity_mm_s=velocity, membrane=membrane,
                 hematocrit=0.3, hematocrit_kind=kind)
    dp, h_t = e.quantities["dp_plus_R0"], e.quantities["tube_hematocrit"]
    assert dp.value is not None and dp.error is not None, dp.note
    expected = viscosity_single_file_chen2020(dp.value, diameter, e["R0_um"], h_t.value)
    assert r.eta_rel == pytest.approx(expected, rel=1e-12, abs=0)
    assert r.valid and r.note == "" and r.membrane == membrane
    assert r.estimate.inputs["velocity_mm_s"] == velocity
    assert ("ca_s" in r.estimate.quantities) == (membrane == "red-cell")


@pytest.mark.parametrize("membrane", MEMBRANES)
def test_error_bar_is_propagated_linearly(synthetic, membrane):
    """η_rel − 1 is linear in Δp⁺: the bar is (η_rel − 1) err(Δp⁺)/Δp⁺, i.e. the change of
    the law when Δp⁺ moves by its bar."""
    r = single_file_viscosity(5.0, 0.3, velocity_mm_s=1.0, membrane=membrane)
    dp, h_t = r.estimate.quantities["dp_plus_R0"], r.estimate.quantities["tube_hematocrit"]
    assert dp.error > 0
    assert r.error == pytest.approx((r.eta_rel - 1.0) * dp.error / dp.value, rel=1e-12)
    shifted = viscosity_single_file_chen2020(dp.value + dp.error, 5.0, r.estimate["R0_um"],
                                             h_t.value)
    assert r.error == pytest.approx(shifted - r.eta_rel, rel=1e-9)


def test_the_red_cell_value_changes_with_velocity_on_a_fixed_map(synthetic):
    """The map's line is one cell at several velocities: at 0.3, 1 and 3 mm/s the values are
    those of different Ca_B, hence different."""
    values = [single_file_viscosity(5.0, 0.3, velocity_mm_s=u, membrane="red-cell").eta_rel
              for u in (0.3, 1.0, 3.0)]
    assert len(set(values)) == 3, values


def test_no_value_gives_none_with_the_reason(synthetic):
    """10 µm: lam/lam_c = 0.28, below the analytic map's 0.5: no Δp⁺, so no η_rel."""
    r = single_file_viscosity(10.0, 0.3, velocity_mm_s=1.0, membrane="red-cell")
    assert r.eta_rel is None and r.error is None and not r.valid
    assert r.note.startswith("no dp+ for this cell and tube") and "lam" in r.note


def test_a_velocity_outside_the_red_cell_map_is_refused(synthetic):
    """The estimate refuses a red cell's velocity outside its map (here about 0.2-5 mm/s), naming
    the parameter; the function lets it through."""
    with pytest.raises(ValueError, match="velocity_mm_s"):
        single_file_viscosity(5.0, 0.3, velocity_mm_s=10.0, membrane="red-cell")


def test_the_default_membrane_is_the_estimates(synthetic):
    assert single_file_viscosity(5.0, 0.3).membrane == DEFAULT_MEMBRANE == "red-cell"
    assert estimate.__kwdefaults__["membrane"] == DEFAULT_MEMBRANE


# ------------------------------------------------------------------------------------------
# Physics, from the shipped maps.
# ------------------------------------------------------------------------------------------

def test_red_cell_viscosity_rises_as_the_flow_slows():
    """Secomb et al. 1986: shear elasticity raises the apparent viscosity at low velocity
    (5 µm tube, H_T 0.3; docs/red-cell.md: 2.03 at 0.2, 1.53 at 1, 1.39 at 4 mm/s by BEM)."""
    if not sm.RED_CELL_MAP.exists():
        pytest.skip(f"no red-cell map shipped ({sm.RED_CELL_MAP})")
    res = {u: single_file_viscosity(5.0, 0.3, velocity_mm_s=u, membrane="red-cell")
           for u in (0.2, 1.0, 5.0)}
    missing = {u: r.note for u, r in res.items() if r.eta_rel is None}
    if missing:
        pytest.skip(f"the shipped red-cell map has no value here (a partial pack): {missing}")
    assert res[0.2].eta_rel > res[1.0].eta_rel > res[5.0].eta_rel, res


def test_vesicle_viscosity_hardly_depends_on_velocity():
    if not sm.DEFAULT_MAP.exists():
        pytest.skip(f"no vesicle map shipped ({sm.DEFAULT_MAP})")
    slow, fast = (single_file_viscosity(5.0, 0.3, velocity_mm_s=u, membrane="vesicle").eta_rel
                  for u in (0.2, 5.0))
    assert abs(fast / slow - 1.0) < 0.02, (slow, fast)


# ------------------------------------------------------------------------------------------
# Command line.
# ------------------------------------------------------------------------------------------

SINGLE_FILE = ("viscosity", "--law", "single-file", "--diameter-um", "5", "--hematocrit", "0.3",
               "--hematocrit-kind", "tube")


@pytest.mark.parametrize("membrane", MEMBRANES)
def test_cli_table_and_json(cli, synthetic, membrane):
    code, out, err = cli(*SINGLE_FILE, "--velocity-mm-s", "1", "--membrane", membrane, "--json")
    assert code == 0 and err == "", err
    obj = json.loads(out)
    r = single_file_viscosity(5.0, 0.3, velocity_mm_s=1.0, membrane=membrane)
    dp = r.estimate.quantities["dp_plus_R0"]
    assert obj["eta_rel"] == r.eta_rel and obj["eta_rel_error"] == r.error
    assert obj["dp_plus_R0"] == dp.value and obj["dp_plus_R0_error"] == dp.error
    assert obj["membrane"] == membrane and obj["velocity_mm_s"] == 1.0
    assert obj["ca_b"] == pytest.approx(r.estimate["ca_b"], rel=1e-15)
    red = membrane == "red-cell"
    assert (obj["ca_s"] == pytest.approx(0.2, rel=1e-12)) if red else obj["ca_s"] is None
    code, table, err = cli(*SINGLE_FILE, "--velocity-mm-s", "1", "--membrane", membrane)
    assert code == 0 and err == ""
    assert "1" in _line(table, "mean velocity U") and "mm/s" in _line(table, "mean velocity U")
    assert ("red cell, G_s = 6 uN/m" if red else "vesicle") in _line(table, "membrane")
    assert "Ca_B" in table and ("Ca_S" in table) == red
    assert "±" in _line(table, "extra pressure drop dp+")
    assert "±" in _line(table, "relative apparent viscosity")


def test_cli_without_a_value_prints_the_reason(cli, synthetic):
    code, out, err = cli("viscosity", "--law", "single-file", "--diameter-um", "10",
                         "--hematocrit", "0.3", "--membrane", "red-cell")
    row = _line(out, "relative apparent viscosity")
    assert code == 0 and "—" in row and "no dp+ for this cell and tube" in row
    assert err.startswith("warning: no dp+")


def test_cli_default_membrane_is_the_estimates(cli, synthetic):
    code, out, _ = cli(*SINGLE_FILE, "--json")
    assert code == 0 and json.loads(out)["membrane"] == DEFAULT_MEMBRANE


@pytest.mark.parametrize("argv, option", [
    (SINGLE_FILE + ("--velocity-mm-s", "-1"), "--velocity-mm-s"),
    (SINGLE_FILE + ("--velocity-mm-s", "0"), "--velocity-mm-s"),
    (SINGLE_FILE + ("--velocity-mm-s", "nan"), "--velocity-mm-s"),
    (SINGLE_FILE + ("--velocity-mm-s", "inf"), "--velocity-mm-s"),
    (SINGLE_FILE + ("--velocity-mm-s", "1e9"), "--velocity-mm-s"),
    (SINGLE_FILE + ("--membrane", "red-cell", "--velocity-mm-s", "10"), "--velocity-mm-s"),
    (SINGLE_FILE + ("--shear-modulus-uN-m", "-6"), "--shear-modulus-uN-m"),
    (SINGLE_FILE + ("--shear-modulus-uN-m", "nan"), "--shear-modulus-uN-m"),
    (SINGLE_FILE + ("--shear-modulus-uN-m", "inf"), "--shear-modulus-uN-m"),
    (SINGLE_FILE + ("--membrane", "cell"), "--membrane"),
    (("viscosity", "--diameter-um", "5", "--hematocrit", "0.3", "--velocity-mm-s", "1"),
     "--velocity-mm-s"),
    (("viscosity", "--diameter-um", "5", "--hematocrit", "0.3", "--law", "pries1994",
      "--membrane", "vesicle"), "--membrane"),
    (("viscosity", "--diameter-um", "5", "--hematocrit", "0.3", "--law", "pries2005",
      "--shear-modulus-uN-m", "6"), "--shear-modulus-uN-m"),
])
def test_cli_bad_input_exits_2_naming_the_option(cli_usage_error, synthetic, tmp_path, argv,
                                                 option):
    """Checked before any work: no figure is written."""
    figure = tmp_path / "eta.png"
    line = cli_usage_error(*argv, "--plot", str(figure))
    assert option in line, line
    assert not figure.exists()


# ------------------------------------------------------------------------------------------
# Plot.
# ------------------------------------------------------------------------------------------

def _velocity_lines(ax):
    return [line for line in ax.get_lines() if line.get_label().startswith("U = ")]


def test_plot_has_one_line_per_velocity_the_map_takes(synthetic):
    """0.3, 1 (the case) and 3 mm/s; 10 mm/s is outside the analytic map (about 0.2-5 mm/s):
    left out. Tubes outside the map's lam/lam_c 0.5-0.9 are gaps (NaN), never zeros."""
    ax = plot_single_file_viscosity(0.3, velocity_mm_s=1.0, membrane="red-cell",
                                    velocities_mm_s=(0.3, 3.0, 10.0), points=20)
    lines = _velocity_lines(ax)
    assert [line.get_label() for line in lines] == ["U = 0.3 mm/s", "U = 1 mm/s (this case)",
                                                    "U = 3 mm/s"]
    for line in lines:
        y = np.asarray(line.get_ydata(), dtype=float)
        assert np.isnan(y).any() and np.all(y[~np.isnan(y)] > 1.0)
    labels = [line.get_label() for line in ax.get_lines()]
    assert any(label.startswith("vesicle") for label in labels)
    assert any(label.startswith("Pries et al. 1992") for label in labels)
    assert ax.get_xlabel() == "d [µm]" and ax.get_ylabel() == "η_rel [-]"


def test_cli_plot_writes_a_png_with_one_line_per_velocity(cli, synthetic, tmp_path,
                                                          monkeypatch):
    drawn = []
    save = cli_module.save_plot
    monkeypatch.setattr(cli_module, "save_plot",
                        lambda ax, path: drawn.append(ax) or save(ax, path))
    target = tmp_path / "eta.png"
    code, _, err = cli(*SINGLE_FILE, "--membrane", "red-cell", "--velocity-mm-s", "2",
                       "--plot", str(target))
    assert code == 0, err
    assert target.read_bytes().startswith(PNG_SIGNATURE)
    # the default velocities and the case's, clipped to those the analytic map takes (0.3, 1,
    # 2 and 3; it spans just inside 0.2-5 mm/s)
    taken = [u for u in sorted({*SINGLE_FILE_VELOCITIES_MM_S, 2.0}) if _takes(u)]
    assert {0.3, 1.0, 2.0, 3.0} <= set(taken) and not {0.1, 10.0} & set(taken)
    lines = _velocity_lines(drawn[0])
    assert [line.get_label() for line in lines] == [
        f"U = {u:g} mm/s" + (" (this case)" if u == 2.0 else "") for u in taken]
    widths = {line.get_label(): line.get_linewidth() for line in lines}
    assert max(widths, key=widths.get) == "U = 2 mm/s (this case)"


def _takes(velocity: float) -> bool:
    """Whether the red-cell map in use takes this velocity of the default cell."""
    try:
        single_file_viscosity(5.0, 0.3, velocity_mm_s=velocity, membrane="red-cell")
    except ValueError:
        return False
    return True
