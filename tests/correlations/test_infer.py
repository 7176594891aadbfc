"""``correlations.infer``: recovery of our own BEM solutions, refusal of inconsistent data,
input checks, and the ``vesicle-tube infer`` command.

Independent reference: the converged BEM points of the map's build folder
(correlations/data/solution_map_build/bem_*.json: ν, λ/λc, Ca_B, V/U, ℓ as the solver wrote
them). They sit on map nodes, so their V/U and ℓ are perturbed with 1 % Gaussian noise (fixed
seed) and given a 1 % uncertainty; the true ν and λ must lie within 2σ of the inferred ones in
at least 90 % of the cases (for Gaussian errors 95 % would).
"""

import glob
import json
import math
from pathlib import Path

import numpy as np
import pytest

from correlations.infer import MAX_SAMPLES, Verdict, infer_cell, infer_map
from correlations.solution_map import DEFAULT_MAP
from lubrication.checks import InvalidParameterError

BUILD = Path(__file__).resolve().parents[2] / "correlations" / "data" / "solution_map_build"
NOISE = 0.01            # relative 1-sigma noise put on V/U and ell
COVERAGE_MIN = 0.90     # fraction of cases whose truth lies within K_SIGMA of the inference
K_SIGMA = 2.0

pytestmark = pytest.mark.skipif(not DEFAULT_MAP.exists(), reason="no solution map shipped")


def _bem_points():
    pts = [json.loads(Path(f).read_text()) for f in sorted(glob.glob(str(BUILD / "bem_*.json")))]
    return [p for p in pts if p.get("success")]


def _recovery(points, samples=0):
    """(cases whose true nu and lam lie within K_SIGMA of the linearised or sampled inference,
    rows)."""
    rng = np.random.default_rng(1)
    hits, rows = 0, []
    for p in points:
        vu = p["V_over_U"] * (1 + NOISE * rng.standard_normal())
        ell = p["ell"] * (1 + NOISE * rng.standard_normal())
        r = infer_map(vu, ell, NOISE * vu, NOISE * ell, ca_b=p["ca_b"], samples=samples,
                      uncertainty="linear")
        ok = False
        if r.consistent:
            q = r.quantities
            ok = (abs(q["nu"].value - p["nu"]) <= K_SIGMA * q["nu"].error + 1e-9
                  and abs(q["lam"].value - p["lam"]) <= K_SIGMA * q["lam"].error + 1e-9)
        hits += ok
        rows.append((p["nu"], p["lam_ratio"], p["ca_b"], r.status.value, ok))
    return hits, rows


def test_recovers_nu_and_lam_of_bem_solutions_within_two_sigma():
    points = _bem_points()
    assert len(points) >= 20, len(points)
    hits, rows = _recovery(points)
    assert hits >= COVERAGE_MIN * len(points), f"{hits}/{len(points)}: {rows}"


@pytest.mark.slow
def test_recovers_every_bem_solution_with_sampling():
    points = _bem_points()
    hits, rows = _recovery(points, samples=50)
    assert hits >= COVERAGE_MIN * len(points), f"{hits}/{len(points)}: {rows}"


def test_refuses_data_no_steady_vesicle_matches():
    r = infer_map(1.9, 20.0)
    assert r.status is Verdict.INCONSISTENT
    assert "inconsistent with any steady axisymmetric vesicle" in r.message
    assert r.fit.chi > 3


def test_cell_volume_and_area_follow_from_nu_and_lam():
    """R0 = lam d/2, volume 4/3 pi R0^3, area from nu = 6 sqrt(pi) Omega A^-3/2 (exact)."""
    r = infer_cell(length_um=8.0, diameter_um=6.0, u_mm_s=1.0, v_mm_s=1.3)
    assert r.consistent, r.message
    q = r.quantities
    R0 = q["lam"].value * 3.0
    assert q["R0_um"].value == pytest.approx(R0, rel=1e-12)
    omega, area = q["volume_fl"].value, q["area_um2"].value
    assert 6 * np.sqrt(np.pi) * omega * area**-1.5 == pytest.approx(q["nu"].value, rel=1e-12)
    assert any("Ca_B = 50" in a for a in r.assumptions)


@pytest.mark.parametrize("kwargs, name", [
    (dict(length_um=8.0, diameter_um=-6.0, u_mm_s=1.0, v_mm_s=1.3), "diameter_um"),
    (dict(length_um=8.0, diameter_um=6.0, u_mm_s=0.0, v_mm_s=1.3), "u_mm_s"),
    (dict(length_um=float("nan"), diameter_um=6.0, u_mm_s=1.0, v_mm_s=1.3), "length_um"),
    (dict(length_um=8.0, diameter_um=6.0, u_mm_s=1.0), "v_mm_s"),
    (dict(length_um=8.0, diameter_um=6.0, u_mm_s=1.0, v_mm_s=1.3, v_err=-1.0), "v_err"),
    (dict(length_um=8.0, diameter_um=6.0, u_mm_s=1.0, v_mm_s=1.3, samples=MAX_SAMPLES + 1),
     "samples"),
    (dict(length_um=8.0, diameter_um=6.0, u_mm_s=1.0, v_mm_s=1.3, samples=2.5), "samples"),
])
def test_bad_input_names_the_parameter(kwargs, name):
    with pytest.raises(InvalidParameterError) as info:
        infer_cell(**kwargs)
    assert info.value.name == name
    assert name in str(info.value)


def test_cli_exit_codes_and_json(capsys):
    from correlations.cli import main
    assert main(["infer", "--v-over-u", "1.9", "--length-um", "40", "--diameter-um", "4",
                 "--u-mm-s", "1"]) == 1
    capsys.readouterr()
    assert main(["infer", "--v-mm-s", "1.3", "--length-um", "8", "--diameter-um", "-6",
                 "--u-mm-s", "1"]) == 2
    assert "--diameter-um" in capsys.readouterr().err
    assert main(["infer", "--v-mm-s", "1.3", "--length-um", "8", "--diameter-um", "6",
                 "--u-mm-s", "1", "--samples", str(MAX_SAMPLES + 1)]) == 2
    assert "--samples" in capsys.readouterr().err
    assert main(["infer", "--v-mm-s", "1.3", "--length-um", "8", "--diameter-um", "6",
                 "--u-mm-s", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["command"] == "infer" and out["status"] == "consistent"
    assert out["quantities"]["volume_fl"]["error"] > 0


def test_worked_example_recovers_the_cell_it_was_made_from():
    """docs/user-guide.md section 10: V and L are the map's values for a 90 fL, nu = 0.65 cell
    in a 4.5 um tube (rounded as a measurement); the true nu, volume and area must lie within
    the reported 68 % intervals (independent reference: the cell the data were made from)."""
    import math
    r = infer_cell(v_mm_s=1.24, v_err=0.02, length_um=10.6, length_err=0.3, diameter_um=4.5,
                   diameter_err=0.05, u_mm_s=1.0, u_err=0.02, eta_mpas=1.2, kappa_j=2e-19)
    assert r.consistent, r.message
    R0 = (90.0 * 3 / (4 * math.pi))**(1 / 3)
    truth = {"nu": 0.65, "volume_fl": 90.0, "area_um2": 4 * math.pi * R0**2 * 0.65**(-2 / 3)}
    for k, v in truth.items():
        q = r.quantities[k]
        assert q.low <= v <= q.high, (k, q, v)


def test_the_pressure_gradient_gives_the_poiseuille_mean_velocity(capsys):
    """-dp/dx = G drives U = G R^2/(8 eta) (Hagen-Poiseuille, independent closed form): the CLI
    with --dpdx-pa-m infers the same cell as with that U; without --eta-mpas it refuses."""
    from correlations.cli import main
    from correlations.infer import mean_velocity_from_gradient
    d, eta = 6.0, 1.2
    g = 8.0 * eta * 1e-3 * 1e-3 / (0.5 * d * 1e-6) ** 2          # U = 1 mm/s
    u, u_err = mean_velocity_from_gradient(g, d, eta)
    assert u == pytest.approx(1.0, rel=1e-12)
    assert u_err == pytest.approx(u * math.hypot(0.02, 0.04), rel=1e-12)
    base = ["infer", "--v-mm-s", "1.3", "--length-um", "8", "--diameter-um", str(d), "--json",
            "--eta-mpas", str(eta)]
    assert main(base + ["--u-mm-s", "1", "--u-err", repr(u_err)]) == 0
    with_u = json.loads(capsys.readouterr().out)["quantities"]
    assert main(base + ["--dpdx-pa-m", repr(g)]) == 0
    with_g = json.loads(capsys.readouterr().out)["quantities"]
    for key in ("nu", "lam", "volume_fl"):
        assert with_g[key]["value"] == pytest.approx(with_u[key]["value"], rel=1e-9)
    assert main(base[:-2] + ["--dpdx-pa-m", repr(g)]) == 2
    assert "--dpdx-pa-m" in capsys.readouterr().err


def test_a_degenerate_inverse_reports_the_valley_and_covers_the_truth():
    """A steady vesicle at (nu, lam) = (0.6, 1.5), Ca_B = 50, computed by an independent
    solver (V/U 1.149332, L/R 6.75006), measured to 0.1 %: a second cell near nu = 0.66 gives
    the same speed and length within the map's accuracy. The posterior must contain the truth in
    its 95 % intervals of nu and lam and say that the data leave nu undetermined."""
    r = infer_cell(v_over_u=1.149332, length_um=33.7503, diameter_um=10.0, u_mm_s=1.0,
                   v_err=0.00115, length_err=0.0337, diameter_err=0.001, u_err=0.001)
    assert r.consistent, r.message
    for name, truth in (("nu", 0.6), ("lam", 1.5)):
        q = r.quantities[name]
        assert q.low95 <= truth <= q.high95, (name, q)
    assert any(n.startswith("degenerate: nu between") for n in r.notes), r.notes


def test_a_map_of_one_node_is_refused_naming_map(tmp_path, monkeypatch, capsys):
    """A map that `map pack` wrote from a one-point build is read, but two unknowns cannot be
    fitted inside one node: infer exits 2 naming --map, before any fit (no traceback)."""
    from test_solution_map import _fake_solver

    from correlations import map_build
    from correlations.cli import main
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    packed = map_build.build_map(tmp_path / "b", map_build.make_grid([0.9], [0.3], [50.0],
                                                                     ["bem"]), workers=1)["map"]
    with pytest.raises(InvalidParameterError) as info:
        infer_map(1.5, 2.0, solution_map=packed)
    assert info.value.name == "map" and "at least two" in str(info.value)
    assert main(["infer", "--v-over-u", "1.5", "--length-um", "4", "--diameter-um", "4",
                 "--u-mm-s", "1", "--map", packed]) == 2
    err = capsys.readouterr().err
    assert "--map" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("extra, option, words", [
    # U = G R^2/(8 eta) = 1e12 Pa/m (3e-6 m)^2 / (8e-3 Pa s) = 1.125e3 m/s, above 1 km/s
    (["--dpdx-pa-m", "1e12"], "--dpdx-pa-m", "U = G R^2/(8 eta) = 1.125e+06 mm/s"),
    (["--dpdx-pa-m", "1e-9"], "--dpdx-pa-m", "U = G R^2/(8 eta) = 1.125e-15 mm/s"),
    (["--dpdx-pa-m", "1e5", "--dpdx-err", "-5"], "--dpdx-err", "dpdx_err=-5"),
    (["--dpdx-pa-m", "1e5", "--diameter-err", "-1"], "--diameter-err", "diameter_err=-1"),
])
def test_errors_of_the_velocity_from_the_gradient_name_the_options_typed(cli_usage_error, extra,
                                                                         option, words):
    """U derived from --dpdx-pa-m: a message about it names that option (and --dpdx-err for
    its error), never the untyped --u-mm-s marked "(default)" (it has no default)."""
    line = cli_usage_error("infer", "--v-mm-s", "1.2", "--length-um", "8", "--diameter-um", "6",
                           "--eta-mpas", "1", *extra)
    assert f"error: {option}:" in line and words in line, line
    assert "(default)" not in line and "u_mm_s" not in line and "--u-mm-s" not in line
