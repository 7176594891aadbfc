"""``vesicle-tube bem sphere`` and ``vesicle-tube bem drop`` against the CLI contract.

Contract (correlations.cli): a table with units for people; ``--json`` prints exactly one JSON
object; exit 0 on success, 2 on invalid input with ONE line on stderr naming the parameter and
its valid range, 1 when a solver did not converge (JSON still printed, "converged": false).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest
from cli_helpers import strict_json

from correlations.cli import main

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
ROOT = Path(__file__).resolve().parents[2]


def test_sphere_table(cli):
    code, out, err = cli("bem", "sphere", "--lam", "0.5")
    assert code == 0, err
    assert "{" not in out and "speed V" in out and "eta U/R" in out
    row = next(line for line in out.splitlines() if line.startswith("speed V"))
    assert "1.68" in row and " U " in row


def test_sphere_json(cli):
    code, out, err = cli("bem", "sphere", "--lam", "0.5", "--json")
    assert code == 0, err
    obj = strict_json(out)
    assert obj["command"] == "bem" and obj["subcommand"] == "sphere"
    for key in ("V_over_U", "dp_plus_R", "dp_plus_R0", "converged", "panels", "error_estimate"):
        assert key in obj, key
    assert obj["converged"] is True
    assert obj["V_over_U"] == pytest.approx(1.68, abs=0.01)
    assert obj["error_estimate"]["V_over_U"] < 1e-9


@pytest.fixture(scope="module")
def drop_json(tmp_path_factory):
    """One cheap drop run (16 modes) with --json --out --plot, shared by the tests below."""
    d = tmp_path_factory.mktemp("drop")
    code = main(["bem", "drop", "--lam", "0.8", "--ca", "0.1", "--modes", "16", "--tol", "1e-3",
                 "--json", "--out", str(d / "out"), "--plot", str(d / "shape.png")])
    return code, d


def test_drop_json_keys_and_files(drop_json):
    code, d = drop_json
    assert code == 0
    saved = json.loads(next((d / "out").glob("*.json")).read_text())
    for key in ("V_over_U", "dp_plus_R", "dp_plus_R0", "converged", "panels", "error_estimate"):
        assert key in saved, key
    assert saved["converged"] is True
    assert saved["V_over_U"] == pytest.approx(1.4545, abs=2e-4)
    assert saved["dp_plus_R"] == pytest.approx(2.2585, abs=2e-3)
    assert next((d / "out").glob("*.csv")).read_text().startswith("s,x,r,psi,kappa1,kappa2")
    assert (d / "shape.png").read_bytes()[:8] == PNG_SIGNATURE


def test_drop_json_on_stdout(cli):
    code, out, err = cli("bem", "drop", "--lam", "0.3", "--ca", "0.1", "--modes", "8",
                         "--tol", "1e-3", "--json")
    assert code == 0, err
    obj = strict_json(out)
    assert obj["command"] == "bem" and obj["subcommand"] == "drop"
    for key in ("V_over_U", "dp_plus_R", "dp_plus_R0", "converged", "panels", "error_estimate"):
        assert key in obj, key
    assert obj["V_over_U"] == pytest.approx(2 - 0.8 * 0.09, abs=2e-3)
    assert "wrote " not in err


def test_drop_table(cli):
    code, out, err = cli("bem", "drop", "--lam", "0.3", "--ca", "0.1", "--modes", "8",
                         "--tol", "1e-3")
    assert code == 0, err
    assert "{" not in out and "speed V" in out and "1/R" in out and "converged" in out


def test_not_converged_exits_1_with_the_json(cli):
    code, out, _ = cli("bem", "drop", "--lam", "0.5", "--ca", "0.2", "--modes", "8",
                       "--tol", "1e-12", "--json")
    assert code == 1
    obj = strict_json(out)
    assert obj["converged"] is False and obj["status"] == "not converged"


@pytest.mark.parametrize("argv, needles", [
    (["bem", "sphere", "--lam", "1.0"], ("lam", "1", "< 1")),
    (["bem", "sphere", "--lam", "0"], ("lam", "0")),
    (["bem", "sphere", "--lam", "nan"], ("lam", "nan")),
    (["bem", "drop", "--lam", "1.2", "--ca", "0.1"], ("lam", "1.2", "< 1")),
    (["bem", "drop", "--lam", "-0.5", "--ca", "0.1"], ("lam", "-0.5")),
    (["bem", "drop", "--lam", "0.8", "--ca", "0"], ("--ca", "0", "ca > 0")),
    (["bem", "drop", "--lam", "0.8", "--ca", "-1"], ("ca", "-1")),
    (["bem", "drop", "--lam", "nan", "--ca", "0.1"], ("lam", "nan")),
    (["bem", "drop", "--lam", "0.8", "--ca", "inf"], ("ca", "inf")),
    (["bem", "drop", "--lam", "0.8"], ("--ca",)),
    (["bem", "drop", "--lam", "abc", "--ca", "0.1"], ("--lam", "abc")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--max-modes", "4"],
     ("--max-modes", "max_modes", "4")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--residual-tol", "0"],
     ("--residual-tol", "residual_tol", "0")),
    (["bem"], ("bem_command",)),
])
def test_invalid_input_exits_2_with_one_line(cli_usage_error, argv, needles):
    line = cli_usage_error(*argv)
    for n in needles:
        assert n in line, (n, line)


def test_estimate_does_not_load_numba_and_stays_fast():
    """Registering ``bem`` must not import numba (measured: estimate 0.10-0.11 s before and
    after the bem registration on the 2-core machine)."""
    code = ("import sys, time; t = time.perf_counter(); from correlations.cli import main; "
            "import contextlib, io\n"
            "with contextlib.redirect_stdout(io.StringIO()): main(['estimate'])\n"
            "print('numba' in sys.modules, time.perf_counter() - t)")
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                          timeout=60, check=False)
    assert proc.returncode == 0, proc.stderr
    loaded, elapsed = proc.stdout.split()
    assert loaded == "False"
    assert float(elapsed) < 2.0 and time.perf_counter() - t0 < 10


def test_sphere_plot_is_written(cli, tmp_path):
    path = tmp_path / "sphere.png"
    code, _, err = cli("bem", "sphere", "--lam", "0.4", "--plot", str(path))
    assert code == 0
    assert path.read_bytes()[:8] == PNG_SIGNATURE and f"wrote {path}" in err


def test_plot_shape_labels_axes():
    from bem.plotting import plot_shape
    from bem.solve import solve_sphere
    ax = plot_shape(solve_sphere(0.5, panels=4))
    assert ax.get_xlabel() == "x/R [-]" and ax.get_ylabel() == "r/R [-]"
    assert "λ = 0.5" in ax.get_title()


# ------------------------------------------------------------------ every input answered
@pytest.mark.parametrize("argv, needles", [
    (["bem", "sphere", "--lam", "1e-300"], ("--lam", "16 lam^6", "small-sphere limit")),
    (["bem", "sphere", "--lam", "0.01"], ("--lam", "0.019", "1.999866667")),
    (["bem", "sphere", "--lam", "0.999"], ("--lam", "0.996", "1 + 4 eps/3")),
    (["bem", "sphere", "--lam", "0.5", "--panels", "100"], ("--panels", "100", "4000")),
    (["bem", "sphere", "--lam", "0.5", "--panels", "1e308"], ("--panels", "1e308")),
    (["bem", "sphere", "--lam", "inf"], ("--lam", "inf")),
    (["bem", "sphere", "--lam", "0.5", "--tol", "0"], ("--tol", "0")),
    (["bem", "sphere", "--lam", "0.5", "--max-time", "nan"], ("--max-time", "nan")),
    (["bem", "drop", "--lam", "0.5", "--ca", "1e-300"], ("--ca", "1e-08")),
    (["bem", "drop", "--lam", "0.5", "--ca", "1e308"], ("--ca", "100")),
    (["bem", "drop", "--lam", "1e-320", "--ca", "0.1"], ("--lam", "0.8 lam^2")),
    (["bem", "drop", "--lam", "0.5", "--ca", "0.1", "--modes", "1000000000000000000000"],
     ("--modes", "64")),
    (["bem", "drop", "--lam", "0.5", "--ca", "0.1", "--modes", "0"], ("--modes", "0")),
    (["bem", "drop", "--lam", "0.5", "--ca", "0.1", "--max-time", "0"], ("--max-time", "0")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--ca-b", "1e308"], ("--ca-b", "100000")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--ca-b", "1e-320"], ("--ca-b",)),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--modes", "-3"], ("--modes", "-3")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--max-modes", "1e308"],
     ("--max-modes", "1e308")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--max-modes", "500"],
     ("--max-modes", "160")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--tol", "nan"], ("--tol", "nan")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--residual-tol", "-inf"],
     ("--residual-tol",)),
    (["bem", "vesicle", "--nu", "nan", "--lam", "1.0"], ("--nu", "nan")),
    (["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--branch", "round"], ("--branch", "round")),
    (["bem", "vesicle-sweep", "--nu", "0.9", "--lam", "0.5", "1.0", "1e6"], ("--lam", "100")),
    (["bem", "vesicle-sweep", "--nu", "0.9", "--lam", "0.5", "1.0", "3", "--ca-b", "0"],
     ("--ca-b",)),
])
def test_bad_numbers_exit_2_naming_the_option_before_numba(cli_usage_error, argv, needles):
    t0 = time.perf_counter()
    line = cli_usage_error(*argv)
    assert time.perf_counter() - t0 < 1.0
    for n in needles:
        assert n in line, (n, line)


def test_input_checks_do_not_load_numba():
    """The checks of every bem command run before numba is imported."""
    code = ("import sys\nfrom correlations.cli import main\n"
            "for argv in (['bem','sphere','--lam','1e-300'], ['bem','drop','--lam','0.5','--ca',"
            "'1e-300'], ['bem','vesicle','--nu','0.9','--lam','1','--ca-b','1e308'],"
            " ['bem','vesicle-sweep','--nu','0.9','--lam','0.5','1','1e6']):\n"
            "    assert main(argv) == 2, argv\n"
            "print('numba' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                          timeout=60, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "False"


def test_failed_drop_prints_and_saves_no_numbers(cli, tmp_path):
    """A spent time budget (exit 1): "—" in the table, null in the JSON and the saved file."""
    code, out, err = cli("bem", "drop", "--lam", "0.3", "--ca", "0.1", "--modes", "8",
                         "--max-time", "1e-9", "--out", str(tmp_path))
    assert code == 1, err
    assert "time limit" in err and "nan" not in out
    row = next(line for line in out.splitlines() if line.startswith("speed V"))
    assert "—" in row
    saved = json.loads(next(tmp_path.glob("*.json")).read_text())
    assert saved["converged"] is False and saved["status"] == "time limit"
    assert saved["V_over_U"] is None and saved["dp_plus_R0"] is None and saved["length"] is None
    assert next(tmp_path.glob("*.csv")).read_text().count("\n") == 1      # header only


def test_vesicle_sweep_table_has_one_labelled_row_per_point():
    from correlations.cli.bem import _sweep_text
    table = [{"lam": 0.5, "lam_ratio": 0.4, "V_over_U": 1.8, "dp_plus_R0": 0.3, "film_min": 0.4,
              "ell": 1.1, "shape_class": "bullet", "runtime": 3.0, "converged": True,
              "message": "converged"},
             {"lam": 0.6, "lam_ratio": 0.5, "V_over_U": None, "dp_plus_R0": None,
              "film_min": None, "ell": None, "shape_class": None, "runtime": 2.0,
              "converged": False, "message": "residual too large"}]
    text = _sweep_text(table, "title")
    lines = text.splitlines()
    assert "V/U" in lines[1] and "dp+ R0/(eta U)" in lines[1]
    assert "1.8" in lines[3] and "—" in lines[4] and "NOT CONVERGED" in lines[-1]


def test_vesicle_json_names_its_start_and_the_other_branch(cli):
    """The default solve says which start converged (a stored shape here), the starts that
    failed before it, and the other branch where one exists (none at (0.9, 1.0))."""
    code, out, err = cli("bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["converged"] and d["seed"].startswith("seed bank (")
    assert d["failed_starts"] == [] and d["other_branch"] == {}
    code, out, err = cli("bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--json",
                         "--no-seed-bank")
    assert code == 0, err
    assert json.loads(out)["seed"] == "lubrication"


@pytest.mark.parametrize("argv, needles", [
    (["--ca-s", "-1"], ["--ca-s", "-1", "0.001"]),
    (["--ca-s", "nan"], ["--ca-s"]),
    (["--ca-s", "0.2", "--reference", "torus"], ["--reference", "torus"]),
    (["--ca-s", "0.2", "--nu", "0.9"], ["nu", "0.743", "spheroid"]),
])
def test_red_cell_options_are_checked_before_any_work(cli_usage_error, argv, needles):
    """Shear number, reference shape and a reduced volume the biconcave family cannot reach:
    exit 2 with one line naming the option, at once."""
    base = ["bem", "vesicle", "--lam-ratio", "0.7"]
    if "--nu" not in argv:
        base += ["--nu", "0.61"]
    t0 = time.perf_counter()
    line = cli_usage_error(*base, *argv)
    assert time.perf_counter() - t0 < 1.0
    for n in needles:
        assert n in line, (n, line)


def test_red_cell_table_and_json_carry_the_shear_number(cli):
    """A red cell at a coarse pair (loose tolerances: the pair is far from converged): the
    table shows Ca_S and the reference shape, the JSON stores them, and its V/U lies within
    three times its pair estimate of the default solve's 1.14700 (72 modes, estimated error
    5e-6; the pair's own error bar is the tolerance, not a tuned one)."""
    loose = ("--modes", "48", "--tol", "0.1", "--tension-tol", "0.5", "--residual-tol", "0.01")
    code, out, err = cli("bem", "vesicle", "--nu", "0.61", "--lam-ratio", "0.7", "--ca-s", "0.2",
                         *loose, "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["ca_s"] == 0.2 and d["reference"] == "biconcave"
    assert abs(d["V_over_U"] - 1.14700) <= 3 * d["error_estimate"]["V_over_U"] + 1e-5
    code, out, err = cli("bem", "vesicle", "--nu", "0.61", "--lam-ratio", "0.7", "--ca-s", "0.2",
                         *loose)
    assert "shear capillary number Ca_S" in out and "biconcave" in out
