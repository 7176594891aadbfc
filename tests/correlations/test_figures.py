"""``vesicle-tube figures``: the input contract, one cheap figure end to end with its cache, and
a comparison row against an independent value (fast: the figures used read the shipped map)."""

import json
import os

import numpy as np
import pytest

from cli_helpers import strict_json


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
    assert all(r.note.startswith("the map has no ") and r.ours == "—" for r in unchecked)
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
