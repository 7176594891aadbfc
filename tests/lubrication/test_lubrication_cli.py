"""`vesicle-tube lubrication` and the lubrication rows of the estimate's method table."""

import argparse
import csv
import json
import math
import time

import pytest

import lubrication.solve as solve_mod

from correlations import registry
from correlations.cli import main
from correlations.estimate import estimate, estimate_dimensionless
from lubrication.solve import solve_lubrication


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_single_point_json_contract(capsys, tmp_path):
    code, out, err = run(capsys, "lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--json",
                         "--out", str(tmp_path), "--plot", str(tmp_path / "shape.png"))
    assert code == 0, err
    data = json.loads(out)
    for key in ("nu", "lam", "lam_c", "V_over_U", "dp_plus_R0", "dp_plus_R", "ell", "film_min",
                "tension_max", "shape_class", "converged"):
        assert key in data, key
    assert data["converged"] is True
    assert data["lam"] == pytest.approx(0.99 * data["lam_c"], rel=1e-12)
    # Same numbers as the library call.
    ref = solve_lubrication(0.9, lam_ratio=0.99)
    assert data["V_over_U"] == pytest.approx(ref.V_over_U, rel=1e-12)
    assert sorted(p.suffix for p in tmp_path.iterdir()) == [".csv", ".json", ".png"]
    saved = json.loads(next(tmp_path.glob("*.json")).read_text())
    assert saved["dp_plus_R0"] == pytest.approx(data["dp_plus_R0"], rel=1e-12)


def _table(text):
    """{quantity: [cells]} of a fixed-width table of correlations.cli.contract.format_rows (column edges
    from its line of dashes); repeated quantities get a list of rows."""
    lines = text.splitlines()
    k = next(i for i, l in enumerate(lines) if l.startswith("---"))
    edges, pos = [], 0
    for dashes in lines[k].split("  "):
        edges.append((pos, pos + len(dashes)))
        pos += len(dashes) + 2
    rows = {}
    for line in lines[k + 1:]:
        cells = [line[a:b].strip() for a, b in edges] + [line[pos:].strip()]
        rows.setdefault(cells[0], []).append(cells[1:])
    return rows


def test_human_table_names_units(capsys):
    code, out, _ = run(capsys, "lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--ca-b", "50")
    assert code == 0
    assert "bending" in out and "converged" in out and "Ca_B = 50" in out
    rows = _table(out)
    # the unit column holds the unit the value is expressed in ("-": a pure number)
    unit = {q: [r[1] for r in rs] for q, rs in rows.items()}
    assert unit["speed V/U"] == ["-"] and unit["lam/lam_c"] == ["-"]
    assert unit["extra pressure drop dp+"] == ["eta U/R0", "eta U/R"]
    assert unit["length L"] == ["R"] and unit["thinnest film h_min"] == ["R"]
    assert unit["front tension"] == ["eta U"]
    assert unit["rear pole curvature (< 0 convex)"] == ["1/R"]
    assert rows["bending capillary number Ca_B = eta U R0^2/kappa"][0][:2] == ["50", "-"]
    ref = solve_lubrication(0.9, lam_ratio=0.99, ca_b=50.0)
    assert float(rows["extra pressure drop dp+"][0][0]) == pytest.approx(ref.dp_plus_R0, rel=1e-3)
    assert float(rows["extra pressure drop dp+"][1][0]) == pytest.approx(ref.dp_plus_R, rel=1e-3)


@pytest.mark.parametrize("argv, match", [
    (["--nu", "0.9", "--lam", "1.5"], "cannot pass"),
    (["--nu", "1.5", "--lam-ratio", "0.9"], "nu="),
    (["--nu", "0.9", "--lam-ratio", "0.9", "--ca-b", "-1"], "--ca-b="),
    (["--nu", "0.9"], "--lam"),
    (["--nu", "0.9", "--lam", "1.0", "--sweep"], "--sweep"),
])
def test_bad_input_exits_2_with_one_line(capsys, argv, match):
    code, out, err = run(capsys, "lubrication", *argv)
    assert code == 2
    assert out == "" and len(err.strip().splitlines()) == 1 and match in err


def test_non_convergence_exits_1_and_still_prints_json(capsys):
    # A spent time budget is a failed solve (exit 1), reported without numbers.
    code, out, _ = run(capsys, "lubrication", "--nu", "0.6", "--lam-ratio", "0.95",
                       "--max-time", "0.01", "--json")
    assert code == 1
    data = json.loads(out)
    assert data["converged"] is False and data["V_over_U"] is None and data["message"]


def test_sweep_writes_csv_and_plot(capsys, tmp_path):
    code, out, err = run(capsys, "lubrication", "--nu", "0.9", "--sweep", "--from", "0.97",
                         "--to", "0.99", "--points", "3", "--json", "--out", str(tmp_path),
                         "--plot", str(tmp_path / "sweep.png"))
    assert code == 0, err
    data = json.loads(out)
    assert data["n_converged"] == 3 and len(data["points"]) == 3
    speeds = [p["V_over_U"] for p in data["points"]]
    assert speeds == sorted(speeds, reverse=True)          # V/U falls toward lam_c
    (csv_file,) = tmp_path.glob("*.csv")
    assert csv_file.read_text().count("\n") == 4            # header + 3 rows
    assert (tmp_path / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_estimate_uses_the_solver_only_when_enabled():
    nu, ratio = 0.9, 0.97
    lam_c = registry.asymptotics.critical_confinement(nu)
    plain = estimate_dimensionless(nu, ratio * lam_c, solution_map=False)   # closed forms only
    assert plain.quantities["V_over_U"].method == "near_critical_barakat2018a"
    assert any("--solver lubrication" in n for n in plain.notes)
    solved = estimate_dimensionless(nu, ratio * lam_c, solvers=("lubrication",))
    ref = solve_lubrication(nu, ratio * lam_c, ca_b=registry.LUBRICATION_DEFAULT_CA_B)
    q = solved.quantities
    assert q["V_over_U"].method == "lubrication_solver" and q["V_over_U"].valid
    assert q["V_over_U"].value == ref.V_over_U
    assert q["dp_plus_R0"].value == ref.dp_plus_R0
    assert q["film"].value == ref.film_min and q["ell"].value == ref.ell
    # Table unit of the front tension is eta V; the solver reports eta U.
    assert q["tension_front"].value == pytest.approx(ref.tension_front / ref.V_over_U, rel=1e-14)
    assert solved.converged


def test_solver_outside_its_range_is_not_used():
    # delta = 0.5 > 0.05: outside LUBRICATION_RANGE, nothing runs, no note about the solver.
    e = estimate_dimensionless(0.9, 0.5 * registry.asymptotics.critical_confinement(0.9),
                               solvers=("lubrication",))
    assert e.quantities["V_over_U"].method != "lubrication_solver"


def test_solver_failure_is_reported_not_hidden(monkeypatch):
    def fail(*args):
        raise registry.SolverNotConverged("lubrication solver did not converge: test")
    monkeypatch.setattr(registry, "_lubrication_solution", fail)
    e = estimate(diameter_um=2.9, solvers=("lubrication",), solution_map=False,
                 membrane="vesicle")
    assert e.converged is False and e.to_dict()["converged"] is False
    assert any("did not converge" in n for n in e.notes)
    # The closed forms still answer where they are valid (2.9 um: near-critical, delta = 0.02).
    assert e.quantities["V_over_U"].method == "near_critical_barakat2018a"


def test_unknown_solver_is_rejected():
    with pytest.raises(ValueError, match="solvers=.fem."):
        estimate(solvers=("fem",))


def test_estimate_cli_exits_1_when_the_enabled_solver_fails(capsys, monkeypatch):
    def fail(*args):
        raise registry.SolverNotConverged("lubrication solver did not converge: test")
    monkeypatch.setattr(registry, "_lubrication_solution", fail)
    code, out, _ = run(capsys, "estimate", "--diameter-um", "2.9", "--solver", "lubrication", "--json")
    assert code == 1 and json.loads(out)["converged"] is False


def test_ca_b_inf_is_the_high_ca_model(capsys):
    code, out, _ = run(capsys, "lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--ca-b", "inf",
                       "--json")
    # strict JSON has no infinity: Ca_B = inf is null beside "model": "high-Ca"
    assert code == 0 and json.loads(out)["model"] == "high-Ca"
    assert json.loads(out)["ca_b"] is None


# --------------------------------------------------------------------------- every input answered
BASE = ["lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--json"]
SWEEP = ["lubrication", "--nu", "0.9", "--sweep", "--json"]
BAD_VALUES = ["nan", "inf", "-inf", "1e308", "1e-320", "0", "-1"]


def _argv(option, value):
    if option in ("--from", "--to", "--points"):
        return SWEEP + [f"{option}={value}"]
    if option == "--lam":
        return ["lubrication", "--nu", "0.9", "--json", f"--lam={value}"]
    if option == "--lam-ratio":
        return ["lubrication", "--nu", "0.9", "--json", f"--lam-ratio={value}"]
    if option == "--nu":
        return ["lubrication", "--lam-ratio", "0.99", "--json", f"--nu={value}"]
    return BASE + [f"{option}={value}"]


# The valid runs among the extreme values, with their exit status: the high-Ca model
# (--ca-b inf), a time budget so long it is no limit, one so short the solve stops (exit 1).
VALID = {("--ca-b", "inf"): 0, ("--max-time", "1e308"): 0, ("--max-time", "1e-320"): 1}


@pytest.mark.parametrize("value", BAD_VALUES)
@pytest.mark.parametrize("option", ["--nu", "--lam", "--lam-ratio", "--ca-b", "--from", "--to",
                                    "--points", "--max-time"])
def test_every_numeric_option_answers_every_value(cli, option, value):
    """nan, inf, -inf, 1e308, subnormal, 0, negative: exit 2 with one line naming the option,
    or a valid run whose JSON holds only finite numbers; never a traceback."""
    code, out, err = cli(*_argv(option, value))
    assert "Traceback" not in err
    expected = VALID.get((option, value), 2)
    assert code == expected, (code, err)
    if code == 2:
        lines = err.strip().splitlines()
        assert out == "" and len(lines) == 1 and option in lines[0], err
    else:
        data = json.loads(out)                  # strict JSON: NaN/Infinity would not parse
        assert data["converged"] is (code == 0)
        if code == 1:
            assert data["V_over_U"] is None and data["dp_plus_R0"] is None


@pytest.mark.parametrize("argv, option, needle", [
    (["--nu", "0.9", "--lam-ratio", "1e-3"], "--lam-ratio", "--ca-b=50"),
    (["--nu", "0.9", "--lam-ratio", "0.5"], "--lam-ratio", "0.5968 <= --lam-ratio"),
    (["--nu", "0.9", "--lam", "0.5"], "--lam", "0.7901 <= --lam"),
    (["--nu", "0.6", "--lam-ratio", "0.8"], "--lam-ratio", "--ca-b=50"),
    (["--nu", "0.9", "--lam-ratio", "1e-3", "--ca-b", "50"], "--lam-ratio", "0.1 <= --lam-ratio"),
    (["--nu", "0.9", "--lam", "1e-3", "--ca-b", "50"], "--lam", "--lam <"),
    (["--nu", "0.9", "--lam-ratio", "1"], "--lam-ratio", "cannot pass"),
    (["--nu", "0.9", "--sweep", "--from", "0.3"], "--from", "--ca-b=50"),
    (["--nu", "0.9", "--sweep", "--to", "1.5"], "--to", "cannot pass"),
    (["--nu", "0.9", "--sweep", "--from", "0.95", "--to", "0.9"], "--from", "below --to"),
    (["--nu", "0.9", "--sweep", "--points", "1000000"], "--points", "2000"),
    (["--nu", "0.9", "--sweep", "--points", "1"], "--points", "at least 2"),
    (["--nu", "0.9", "--lam-ratio", "0.99", "--points", "3"], "--points", "--sweep"),
    (["--nu", "0.9", "--lam-ratio", "0.99", "--ca-b", "1e7"], "--ca-b", "inf"),
    (["--nu", "0.2", "--lam-ratio", "0.99"], "--nu", "0.3 <= --nu < 1"),
])
def test_outside_the_model_is_refused_up_front(cli_usage_error, argv, option, needle):
    """Tiny confinements, the end of the high-Ca branch, absurd sweeps: exit 2 at once, one
    line naming the option as typed, its valid range, and what to do instead."""
    clock = time.perf_counter()
    line = cli_usage_error("lubrication", *argv)
    assert time.perf_counter() - clock < 2.0           # before any solve
    assert option in line and needle in line, line


def test_help_states_where_the_high_ca_model_has_solutions(cli):
    code, out, _ = cli("lubrication", "--help")
    text = " ".join(out.split())
    assert code == 0
    assert "0.597 at 0.9" in text and "--ca-b 50" in text and "--max-time" in text
    # the ranges written out in the help are the solver's
    assert f"{solve_mod.NU_RANGE[0]:g} <= nu < 1" in text
    assert f"{solve_mod.MIN_LAM_RATIO:g} <= lam/lam_c < 1" in text
    assert f"2 to {solve_mod.MAX_SWEEP_POINTS}" in text
    lo, hi = solve_mod.CA_B_RANGE
    assert f"{lo:g} to {hi:.0e}".replace("e+0", "e") in text
    for nu, end in ((0.6, "0.908"), (0.8, "0.738"), (0.9, "0.597"), (0.98, "0.345")):
        assert f"{solve_mod.high_ca_branch_end(nu):.3f}" == end and end in text


def test_failed_solve_reports_no_numbers_anywhere(cli, tmp_path):
    """A solve stopped by --max-time: exit 1, the table shows "—" for every physical row,
    the JSON has null there, --out writes only the JSON (no profiles), no figure."""
    code, out, err = cli("lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--max-time",
                         "0.01", "--out", str(tmp_path), "--plot", str(tmp_path / "shape.png"))
    assert code == 1 and "NOT CONVERGED" in out and "max_time=0.01" in err
    rows = _table(out)
    for quantity in ("speed V/U", "extra pressure drop dp+", "length L", "thinnest film h_min",
                     "front tension", "largest tension", "shape"):
        for cells in rows[quantity]:
            assert cells[0] == "—", (quantity, cells)
    assert rows["lam/lam_c"][0][0] == "0.99"              # inputs are still shown
    (saved,) = tmp_path.iterdir()
    assert saved.suffix == ".json" and "failed" in saved.name
    data = json.loads(saved.read_text())
    assert data["converged"] is False and data["status"] == "time limit" and data["ca_b"] is None
    for key in ("V_over_U", "Q", "dp_plus_R0", "dp_plus_R", "ell", "film_min", "tension_front",
                "tension_rear", "tension_max", "curvature_rear", "curvature_front"):
        assert data[key] is None, key
    code, out, _ = cli("lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--max-time", "0.01",
                       "--json")
    assert code == 1 and json.loads(out)["dp_plus_R0"] is None


def test_failed_sweep_reports_no_numbers(cli, tmp_path):
    code, out, err = cli("lubrication", "--nu", "0.9", "--sweep", "--from", "0.97", "--to",
                         "0.99", "--points", "3", "--max-time", "0.01", "--json", "--out",
                         str(tmp_path))
    assert code == 1 and "not converged" in err and "max_time" in err
    data = json.loads(out)
    assert data["converged"] is False and data["n_converged"] == 0 and data["ca_b"] is None
    for point in data["points"]:
        assert point["converged"] is False and point["V_over_U"] is None
        assert point["dp_plus_R0"] is None and point["shape_class"] is None
    (csv_file,) = tmp_path.glob("*.csv")
    rows = list(csv.DictReader(csv_file.open()))
    assert [r["V_over_U"] for r in rows] == ["", "", ""]


def test_sweep_table_has_one_column_per_quantity(cli):
    code, out, _ = cli("lubrication", "--nu", "0.9", "--sweep", "--from", "0.98", "--to", "0.99",
                       "--points", "2", "--ca-b", "50")
    assert code == 0
    lines = out.splitlines()
    assert "bending model, Ca_B = 50" in lines[0] and "2/2 points converged" in lines[0]
    head = lines[1].split()
    assert head[:4] == ["lam/lam_c", "[-]", "lam", "[-]"] and "dp+ [eta U/R0]" in lines[1]
    body = [l.split() for l in lines[3:5]]
    assert [b[0] for b in body] == ["0.9800", "0.9900"]
    ref = solve_lubrication(0.9, lam_ratio=0.99, ca_b=50.0)
    assert float(body[1][2]) == pytest.approx(ref.V_over_U, rel=1e-4)    # V/U column
    assert float(body[1][3]) == pytest.approx(ref.dp_plus_R0, rel=1e-3)  # dp+ column
    assert body[1][-1] == "converged"


def test_default_sweep_starts_where_the_model_has_solutions():
    """The default --from of the high-Ca model is just above its branch end, and 0.5 else."""
    from correlations.cli.lubrication import _sweep_ratios
    args = argparse.Namespace(nu=0.9, ca_b=math.inf, ratio_from=None, ratio_to=None, points=None)
    assert _sweep_ratios(args)[1:] == (0.61, 0.999, 50)
    args.ca_b = 50.0
    assert _sweep_ratios(args)[1] == 0.5


def test_max_time_bounds_a_long_solve(cli):
    """nu = 0.9, lam/lam_c = 0.61 takes ~4 s (continuation from 0.98); 1 s budget: exit 1
    within about 1 s more (the deadline is tested at every right-hand-side evaluation)."""
    clock = time.perf_counter()
    code, out, err = cli("lubrication", "--nu", "0.9", "--lam-ratio", "0.61", "--max-time", "1",
                         "--json")
    assert code == 1 and time.perf_counter() - clock < 3.0
    obj = json.loads(out)
    assert obj["status"] == "time limit" and "max_time=1 s" in obj["message"]
