"""``vesicle-tube figures``: the input contract, one cheap figure end to end with its cache, and
a comparison row against an independent value (fast: the figures used read the shipped map)."""

import json
import math
import os

import numpy as np
import pytest

from cli_helpers import strict_json

from correlations import figures
from correlations.solution_map import load_map, query_map
from lubrication.geometry import critical_confinement

#: the RBC-theory sweep as the tests see it (the real one: a continuation of ~1.5 min)
REAL_RBC_SWEEP = figures._rbc_sweep
#: λ/λc where the stand-in sweep fails: the lowest ratios (the end of the branch) and one
#: inside, so that a gap must show in the drawn curve
FAKE_FAILED = {0.2, 0.22, 0.24, 0.6}
RBC_CALLS = []


def _fake_rbc_sweep(cell):
    """Stands in for :func:`correlations.figures._rbc_sweep`: plausible values (V/U = 1 + δ/2,
    Δp⁺ = 5λ⁶/δ − 0.3, negative for the shortest cells as the parallel-flow model gives),
    failures at :data:`FAKE_FAILED`."""
    RBC_CALLS.append(cell)
    r = np.array(figures.RBC_RATIOS)
    ok = [x not in FAKE_FAILED for x in figures.RBC_RATIOS]
    return {"success": ok,
            "V_over_U": [1.0 + 0.5 * (1.0 - x) if o else None for x, o in zip(r, ok)],
            "dp_plus_R0": [5.0 * x**6 / (1.0 - x) - 0.3 if o else None for x, o in zip(r, ok)],
            "shape_class": [None] * len(r), "seconds": 0.0,
            "message": ["converged" if o else "fake: diverged" for o in ok]}


@pytest.fixture(autouse=True)
def fake_rbc_sweep(monkeypatch, tmp_path):
    """Every test here draws the RBC theory from the stand-in, and without a red-cell map
    unless it gives one (the shipped one is a preliminary pack)."""
    RBC_CALLS.clear()
    monkeypatch.setattr(figures, "_rbc_sweep", _fake_rbc_sweep)
    monkeypatch.setattr(figures, "RED_CELL_MAP", tmp_path / "no_red_cell_map.json")


@pytest.mark.parametrize("argv, option", [
    (("--format", "jpg"), "--format"),
    (("--only", "nope"), "--only"),
    (("--only",), "--only"),
    (("--bem-max-time", "0"), "--bem-max-time"),
])
def test_bad_options_exit_2_naming_the_option(cli_usage_error, tmp_path, argv, option):
    line = cli_usage_error("figures", "--out", str(tmp_path / "f"), *argv)
    assert option in line
    assert not (tmp_path / "f").exists()            # checked before any work


def test_unwritable_out_exits_2_before_any_work(cli_usage_error, tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("x")
    assert "--out" in cli_usage_error("figures", "--out", str(afile), "--only", "viscosity")
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        if not os.access(locked, os.W_OK):          # root writes anywhere: skip that half
            line = cli_usage_error("figures", "--out", str(locked / "sub"), "--only", "viscosity")
            assert "--out" in line
    finally:
        locked.chmod(0o700)
    assert not (locked / "sub").exists()


def test_one_figure_end_to_end_and_the_rerun_uses_the_cache(cli, tmp_path):
    out = tmp_path / "figs"
    code, stdout, err = cli("figures", "--out", str(out), "--only", "viscosity", "--format",
                            "svg", "--json")
    assert code == 0, err
    result = strict_json(stdout)
    assert (out / "viscosity.svg").stat().st_size > 0
    assert {"figures.json", "figures.md"} <= {p.name for p in out.iterdir()}
    cache = list((out / "cache").glob("viscosity-*.json"))
    assert len(cache) == 1
    assert result["figures"] == [{"name": "viscosity", "caption": result["figures"][0]["caption"],
                                  "file": str(out / "viscosity.svg"), "cached": False}]
    rows = result["statements"]
    assert rows and {"statement", "paper", "ours", "tolerance", "verdict", "note"} <= set(rows[0])
    assert {r["verdict"] for r in rows} <= {"agree", "disagree", "not checked"}
    assert json.loads((out / "figures.json").read_text())["statements"] == rows
    md = (out / "figures.md").read_text()
    assert "| statement | paper | ours | tolerance | verdict | note |" in md
    assert "figures: [1/1] viscosity" in err                  # progress on stderr

    mtime = cache[0].stat().st_mtime_ns
    code, stdout, err = cli("figures", "--out", str(out), "--only", "viscosity", "--json")
    assert code == 0, err
    again = strict_json(stdout)
    assert again["figures"][0]["cached"] is True and "(cache)" in err
    assert cache[0].stat().st_mtime_ns == mtime                # read, not rewritten
    assert again["statements"] == rows                         # same numbers from the cache
    assert (out / "viscosity.png").is_file()


def test_phase_rows_match_independent_closed_forms(tmp_path):
    """The λc(0.6) row against the largest real root of 2λ³ − 3ν^(−2/3)λ² + 1 = 0 (numpy's
    companion-matrix roots, not our solver), and the L_c row against ℓc d_c/2 from it."""
    from correlations.figures import FigureContext, figure_phase
    _, rows, _ = figure_phase(FigureContext(tmp_path))
    roots = np.roots([2.0, -3.0 * 0.6 ** (-2.0 / 3.0), 0.0, 1.0])
    lam_c = max(r.real for r in roots if abs(r.imag) < 1e-12)
    row = next(r for r in rows if r.statement.startswith("λc"))
    assert float(row.ours) == pytest.approx(lam_c, abs=5e-4)    # 4 significant digits
    assert row.verdict == ("agree" if abs(lam_c - 1.98) <= 0.005 else "disagree")
    ell_c = 2.0 * 0.6 ** (-2.0 / 3.0) * lam_c ** 2
    row = next(r for r in rows if r.statement.startswith("L_c"))
    assert float(row.ours) == pytest.approx(ell_c * (2.0 * 2.8 / lam_c) / 2.0, rel=5e-4)
    line = next(r for r in rows if "takes place at λ_T" in r.statement)
    assert "1.814" in line.note                                 # (1.126 - 0.6)/0.29


def test_ctrl_c_during_a_solve_exits_130_and_keeps_only_complete_files(tmp_path):
    """Interrupted while the Ca_B series solves (BEM), the command stops with 130 and one line
    naming the files already written; no temporary file is left."""
    import signal
    import subprocess
    import sys
    import time
    out = tmp_path / "figs"
    proc = subprocess.Popen([sys.executable, "-m", "correlations.cli", "figures", "--out",
                             str(out), "--only", "phase", "shapes_cab"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    t0 = time.monotonic()
    while not (out / "phase.png").exists() and time.monotonic() - t0 < 60:
        time.sleep(0.1)
    time.sleep(1.0)                                  # inside the first BEM solve
    assert proc.poll() is None
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    last = err.strip().splitlines()[-1]
    assert "interrupted" in last and str(out / "phase.png") in last
    assert not [p for p in out.rglob("*") if p.name.startswith(".")]


def test_a_map_without_the_figures_nodes_is_refused_before_any_work(tmp_path, monkeypatch,
                                                                     capsys):
    """`map pack` of a one-point build writes a valid map from which the paper's figures
    cannot be drawn: exit 2 naming --map and what it lacks, before any file is written."""
    from test_solution_map import _fake_solver

    from correlations import map_build
    from correlations.cli import main
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    packed = map_build.build_map(tmp_path / "b", map_build.make_grid([0.9], [0.3], [50.0],
                                                                     ["bem"]), workers=1)["map"]
    out = tmp_path / "figs"
    assert main(["figures", "--out", str(out), "--only", "speed", "--map", packed]) == 2
    err = capsys.readouterr().err
    assert "--map" in err and "nu = 0.6" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_a_map_with_holes_where_the_statements_read_answers_not_checked(tmp_path):
    """A map of our own build with the figures' nu nodes at Ca_B = 50 but holes where the
    statements read (nu = 0.6 at lam/lam_c = 0.2, lam/lam_c = 0.9999 but for nu = 0.98): the
    figures are drawn and those statements say "not checked" and what the map lacks; never an
    exception (the figure functions are called without writing the files, which is what
    makes the command's time)."""
    from test_readers import FAILED, build

    from correlations.figures import FIGURES, FigureContext
    nus = [0.6, 0.7, 0.8, 0.9, 0.98]
    holes = {(0.6, 0.2, 50.0): FAILED, **{(nu, 0.9999, 50.0): FAILED for nu in nus[:-1]}}
    path = build(tmp_path / "b", nus, [0.2, 0.45, 0.9999], [50.0], outcome=holes)
    ctx = FigureContext(tmp_path / "figs", map_path=path)
    unchecked = []
    for name in ("speed", "pressure", "film_ca", "dp_scalings"):
        _, rows, _ = FIGURES[name][1](ctx)
        assert rows and {r.verdict for r in rows} <= {"agree", "disagree", "not checked"}
        unchecked += [r for r in rows if r.verdict == "not checked"]
    assert {r.figure for r in unchecked} == {"speed", "pressure", "film_ca", "dp_scalings"}
    assert all((r.note.startswith("the map has no ") or "red-cell map" in r.statement)
               and r.ours == "—" for r in unchecked)
    assert any("λ < 0.5 at ν = 0.6" in r.note for r in unchecked)


@pytest.mark.parametrize("damage", ["truncated", "edited data", "5000-digit integer", "fifo"])
def test_a_damaged_cache_file_is_ignored_and_recomputed(tmp_path, damage):
    """The cache is ours: a file that cannot be read or whose data fail their checksum is
    reported, recomputed and rewritten, never fatal; an intact one is read back."""
    from correlations.figures import FigureContext
    said = []
    ctx = FigureContext(tmp_path, progress=said.append)
    calls = []

    def compute():
        calls.append(1)
        return {"values": [1.0, 2.5], "n": 3}
    data, cached = ctx.cached("probe", {"a": 1}, compute)
    assert (data, cached, len(calls)) == ({"values": [1.0, 2.5], "n": 3}, False, 1)
    (path,) = (tmp_path / "cache").glob("probe-*.json")
    text = path.read_text()
    path.unlink()
    if damage == "truncated":
        path.write_text(text[: len(text) // 2])
    elif damage == "edited data":
        path.write_text(text.replace("2.5", "7.5"))
    elif damage == "5000-digit integer":
        path.write_text(text.replace('"n": 3', '"n": 3' + "0" * 5000))
    else:
        os.mkfifo(path)
    data, cached = ctx.cached("probe", {"a": 1}, compute)
    assert (data, cached, len(calls)) == ({"values": [1.0, 2.5], "n": 3}, False, 2)
    assert len(said) == 1 and "ignored" in said[0] and path.name in said[0]
    assert ctx.cached("probe", {"a": 1}, compute) == (data, True) and len(calls) == 2


# ----------------------------------------------------------------------------- RBC theory

RBC_STATEMENTS = {"speed": 3, "pressure": 3, "viscosity": 5}


@pytest.fixture(scope="module")
def red_cell_map(tmp_path_factory):
    """A tiny red-cell map of our own build (fake solver, the default cell's β = G_s R0²/κ):
    ν 0.6, 0.65, λ/λc 0.3, 0.6, 0.9, Ca_B around 50."""
    from unittest import mock

    from test_readers import _fake_solver

    from correlations import map_build
    grid = map_build.make_grid([0.6, 0.65], [0.3, 0.6, 0.9], [46.3718, 92.7436], ["bem"])
    with mock.patch.dict(map_build.SOLVERS, {"bem": _fake_solver({})}):
        return map_build.build_map(tmp_path_factory.mktemp("rbc"), grid, workers=1,
                                   options={"bem": {"shear_ratio": 231.859}})["map"]


def _line(fig, label):
    (line,) = [ln for ln in fig.axes[0].get_lines() if ln.get_label() == label]
    return np.asarray(line.get_xdata(), float), np.asarray(line.get_ydata(), float)


def test_rbc_theory_is_drawn_only_where_it_converged_and_its_statements_have_verdicts(
        tmp_path, red_cell_map):
    """The RBC-theory curve of figs. vel, dpa and Kt is drawn from the sweep, a gap (NaN)
    wherever a solve failed (and, on the log axes, where its Δp⁺ ≤ 0), never a value there;
    the BEM red cell of the red-cell map is drawn beside it; each figure carries its RBC
    statements with a verdict, the unchecked ones with their reason."""
    ctx = figures.FigureContext(tmp_path, red_cell_map=red_cell_map)
    fake = _fake_rbc_sweep(figures.red_cell())
    failed = np.array([not s for s in fake["success"]])
    dp = np.array([np.nan if v is None else v for v in fake["dp_plus_R0"]])
    for name, key in (("speed", "V_over_U"), ("pressure", "dp_plus_R0"),
                      ("viscosity", None)):
        fig, rows, _ = figures.FIGURES[name][1](ctx)
        x, y = _line(fig, figures.RBC_LABEL)
        assert len(x) == len(figures.RBC_RATIOS)
        assert np.all(np.isnan(y[failed]))
        gap = failed if key == "V_over_U" else failed | (dp <= 0)
        assert np.all(np.isfinite(y[~gap])) and np.isnan(y[gap]).any()
        if key == "V_over_U":
            assert y[~gap] == pytest.approx(np.array(fake["V_over_U"], float)[~gap])
        assert np.isfinite(_line(fig, figures.BEM_RBC_LABEL)[1]).any()
        rbc = [r for r in rows if "RBC theory" in r.statement or "parallel-flow" in r.statement
               or "flow rate" in r.statement]
        assert len(rbc) == RBC_STATEMENTS[name], [r.statement for r in rbc]
        # this map holds 1-2 mm/s only: no velocity with U/d <= 50 s⁻¹ (tested apart)
        checked = [r for r in rbc if "lower shear rates" not in r.statement]
        assert all(r.verdict in ("agree", "disagree") and r.ours != "—" for r in checked), rbc
    assert len(RBC_CALLS) == 2          # the check's own call and one sweep for three figures


def test_rbc_statements_without_a_red_cell_map_say_not_checked_and_why(tmp_path):
    """No red-cell map: the BEM red cell is not drawn and the statements against it are "not
    checked", naming the missing map; those against the vesicle map still have verdicts."""
    ctx = figures.FigureContext(tmp_path)
    fig, rows, _ = figures.figure_speed(ctx)
    assert figures.BEM_RBC_LABEL not in [ln.get_label() for ln in fig.axes[0].get_lines()]
    against = [r for r in rows if "red-cell map" in r.statement]
    assert len(against) == 1 and against[0].verdict == "not checked"
    assert "no red-cell map" in against[0].note and "no_red_cell_map.json" in against[0].note
    vs = [r for r in rows if "vesicle map" in r.statement or "RBC theory when" in r.statement]
    assert len(vs) == 2 and {r.verdict for r in vs} <= {"agree", "disagree"}


def test_the_rbc_theory_is_solved_once_and_read_from_the_cache_afterwards(tmp_path,
                                                                          monkeypatch):
    """The real sweep (two ratios near λc: a few seconds) by the lubrication red cell at
    Ca_B = 50 with the default cell's Ca_S; a second context on the same folder solves
    nothing and gives the same statements."""
    import lubrication.solve
    monkeypatch.setattr(figures, "_rbc_sweep", REAL_RBC_SWEEP)
    monkeypatch.setattr(figures, "RBC_RATIOS", (0.99, 0.98))
    real, calls = lubrication.solve.sweep_lubrication, []

    def counted(*args, **kwargs):
        calls.append(kwargs)
        return real(*args, **kwargs)
    monkeypatch.setattr(lubrication.solve, "sweep_lubrication", counted)
    cell = figures.red_cell()
    assert (round(cell["nu"], 3), round(cell["ca_s"], 3), round(cell["U_mm_s"], 2)) == \
        (0.61, 0.216, 1.08)
    fig, rows, cached = figures.figure_speed(figures.FigureContext(tmp_path))
    assert len(calls) == 1 and not cached
    assert calls[0]["ca_b"] == 50.0 and calls[0]["ca_s"] == pytest.approx(cell["ca_s"])
    _, y = _line(fig, figures.RBC_LABEL)
    assert np.all(np.isfinite(y)) and np.all((1.0 < y) & (y < 1.1))   # near λc: V/U → 1
    fig2, rows2, cached2 = figures.figure_speed(figures.FigureContext(tmp_path))
    assert len(calls) == 1 and cached2
    assert rows2 == rows
    np.testing.assert_array_equal(_line(fig2, figures.RBC_LABEL)[1], y)


def test_velocity_statements_read_the_red_cell_map(tmp_path):
    """η_rel against flow rate from a red-cell map (the analytic one of the red-cell estimate's
    tests): the change per doubling of U computed here from the map's Δp⁺ and the single-file
    law written out, (3/32)(R/R0)⁴ Δp⁺ H_T; no map makes both statements "not checked"."""
    from test_estimate_red_cell import _red_cell_build
    path = _red_cell_build(tmp_path / "red-cell")
    hi, lo = figures._velocity_rows(path)
    cell, m = figures.red_cell(), load_map(path)
    lam_c = float(critical_confinement(cell["nu"]))

    def eta(d, u):
        dp = query_map(cell["nu"], 2.0 * cell["R0_um"] / d / lam_c,
                       figures.CA_B * u / cell["U_mm_s"], map=m)["dp_plus_R0"]
        return 1.0 + 3.0 / 32.0 * (d / 2.0 / cell["R0_um"]) ** 4 * dp * 0.45
    assert f"1→2 {100 * (eta(5.0, 2.0) / eta(5.0, 1.0) - 1.0):+.1f} %" in hi.note
    slow = (eta(4.0, 0.3) / eta(4.0, 0.2)) ** (1.0 / math.log2(1.5)) - 1.0
    assert f"d = 4 µm: 0.2→0.3 {100 * slow:+.1f} %" in lo.note     # U/d = 50 s⁻¹ at 0.2
    assert "d = 6" not in hi.note + lo.note          # outside the analytic map's λ/λc
    assert {hi.verdict, lo.verdict} <= {"agree", "disagree"}
    missing = tmp_path / "missing.json"
    assert all(r.verdict == "not checked" and "missing.json" in r.note
               for r in figures._velocity_rows(missing))
