"""`vesicle-tube lubrication` and the lubrication rows of the estimate's method table."""

import json
import math

import pytest

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


def test_human_table_names_units(capsys):
    code, out, _ = run(capsys, "lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--ca-b", "50")
    assert code == 0
    assert "bending" in out and "dp+ R0/(eta U)" in out and "converged" in out


@pytest.mark.parametrize("argv, match", [
    (["--nu", "0.9", "--lam", "1.5"], "cannot pass"),
    (["--nu", "1.5", "--lam-ratio", "0.9"], "nu="),
    (["--nu", "0.9", "--lam-ratio", "0.9", "--ca-b", "-1"], "ca_b="),
    (["--nu", "0.9"], "--lam"),
    (["--nu", "0.9", "--lam", "1.0", "--sweep"], "--sweep"),
])
def test_bad_input_exits_2_with_one_line(capsys, argv, match):
    code, out, err = run(capsys, "lubrication", *argv)
    assert code == 2
    assert out == "" and len(err.strip().splitlines()) == 1 and match in err


def test_non_convergence_exits_1_and_still_prints_json(capsys):
    # The high-Ca branch of nu = 0.6 ends near lam/lam_c = 0.909 (rear pole flattens).
    code, out, _ = run(capsys, "lubrication", "--nu", "0.6", "--lam-ratio", "0.8", "--json")
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
    plain = estimate_dimensionless(nu, ratio * lam_c)
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
    # delta = 0.5 > 0.3: outside LUBRICATION_RANGE, nothing runs, no note about the solver.
    e = estimate_dimensionless(0.9, 0.5 * registry.asymptotics.critical_confinement(0.9),
                               solvers=("lubrication",))
    assert e.quantities["V_over_U"].method != "lubrication_solver"


def test_solver_failure_is_reported_not_hidden(monkeypatch):
    def fail(*args):
        raise registry.SolverNotConverged("lubrication solver did not converge: test")
    monkeypatch.setattr(registry, "_lubrication_solution", fail)
    e = estimate(diameter_um=3.0, solvers=("lubrication",))
    assert e.converged is False and e.to_dict()["converged"] is False
    assert any("did not converge" in n for n in e.notes)
    # The closed forms still answer where they are valid (3 um: near-critical).
    assert e.quantities["V_over_U"].method == "near_critical_barakat2018a"


def test_unknown_solver_is_rejected():
    with pytest.raises(ValueError, match="solvers=.fem."):
        estimate(solvers=("fem",))


def test_estimate_cli_exits_1_when_the_enabled_solver_fails(capsys, monkeypatch):
    def fail(*args):
        raise registry.SolverNotConverged("lubrication solver did not converge: test")
    monkeypatch.setattr(registry, "_lubrication_solution", fail)
    code, out, _ = run(capsys, "estimate", "--diameter-um", "3", "--solver", "lubrication", "--json")
    assert code == 1 and json.loads(out)["converged"] is False


def test_ca_b_inf_is_the_high_ca_model(capsys):
    code, out, _ = run(capsys, "lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--ca-b", "inf",
                       "--json")
    assert code == 0 and json.loads(out)["model"] == "high-Ca"
    assert math.isinf(float(json.loads(out)["ca_b"]))
