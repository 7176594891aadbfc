"""The ``vesicle-tube`` command line against its contract (module docstring of correlations.cli).

Contract: a table with units for people; ``--json`` prints exactly one JSON object on stdout;
exit 0 on success, 2 on invalid input with ONE line on stderr naming the parameter, its value and
the valid range (no traceback); out-of-range warnings go to stderr as ``warning:`` lines and into
the JSON under ``"warnings"``. Commands run in-process through ``main(argv)``; one test runs the
installed console script.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from cli_helpers import strict_json

from correlations.viscosity import relative_viscosity
from lubrication.checks import OutOfRangeWarning

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

ESTIMATE_KEYS = ("nu", "lam", "lam_c", "ell_c", "delta", "V_over_U", "dp_plus_R0", "dp_plus_R",
                 "eta_rel", "tube_hematocrit", "discharge_hematocrit", "d_c_um", "L_c_um", "R0_um",
                 "passes")


def ref_lam_c(nu):
    """Largest real root of 2x^3 - 3 nu^(-2/3) x^2 + 1 (numpy.roots + one Newton step)."""
    a = nu ** (-2.0 / 3.0)
    x = float(max(r.real for r in np.roots([2.0, -3.0 * a, 0.0, 1.0]) if abs(r.imag) < 1e-9))
    return x - (2.0 * x**3 - 3.0 * a * x**2 + 1.0) / (6.0 * x * x - 6.0 * a * x)


def ref_fahraeus_tube(d, hd, a, b):
    """H_T/H_D = H_D + (1 - H_D)(1 + 1.7 e^(-aD) - 0.6 e^(-bD)) (physics-notes §6)."""
    return hd * (hd + (1.0 - hd) * (1.0 + 1.7 * math.exp(-a * d) - 0.6 * math.exp(-b * d)))


FAHRAEUS_AB = {"pries1990": (0.415, 0.011), "pries1992": (0.35, 0.01)}


# ------------------------------------------------------------------------------------------
# Every command: exit 0, a table with units, one JSON object with the fixed keys.
# ------------------------------------------------------------------------------------------

COMMANDS = {   # name: (argv, JSON keys that must be present, units the table must show)
    "estimate": (["estimate", "--diameter-um", "3", "--hematocrit", "0.3"], ESTIMATE_KEYS,
                 ("um", "mm/s", "Pa", "nm", "mN/m", "eta U/R0")),
    "estimate-dimensionless": (["estimate", "--nu", "0.9", "--lam", "1.25", "--hematocrit", "0.3"],
                               ESTIMATE_KEYS[:-4] + ("passes",),
                               ("eta U/R0", "eta U/R", "R", "R_c", "eta V", "eta U")),
    "geometry": (["geometry", "--volume-fl", "90", "--area-um2", "135", "--diameter-um", "4"],
                 ("nu", "lam", "lam_c", "ell_c", "delta", "d_c_um", "L_c_um", "R0_um", "passes"),
                 ("um",)),
    "geometry-nu": (["geometry", "--nu", "0.6", "--lam", "1.9"],
                    ("nu", "lam", "lam_c", "ell_c", "delta", "passes"), ("-",)),
    "viscosity": (["viscosity", "--diameter-um", "6", "--hematocrit", "0.45"],
                  ("eta_rel", "tube_hematocrit", "discharge_hematocrit"), ("um",)),
    "viscosity-single-file": (["viscosity", "--diameter-um", "3", "--hematocrit", "0.45",
                               "--law", "single-file"],
                              ("eta_rel", "tube_hematocrit", "discharge_hematocrit", "dp_plus_R0"),
                              ("um", "eta U/R0")),
    "fahraeus": (["fahraeus", "--diameter-um", "10", "--discharge-hematocrit", "0.45"],
                 ("tube_hematocrit", "discharge_hematocrit"), ("um",)),
}


#: What a unit cell may hold (the convention of correlations.cli.UNIT_CONVENTION): a physical
#: unit, the scale of a dimensionless value, "-" (plain dimensionless) or "" (not a number).
UNIT_CELLS = {"um", "mm/s", "Pa", "nm", "mN/m", "R", "R_c", "eta U/R0", "eta U/R", "eta V",
              "eta U", "-", ""}


def _unit_column(table: str) -> set:
    """The entries of the 'unit' column of a format_rows table (up to the table's end)."""
    lines = table.splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("quantity"))
    start = lines[head].index("unit")
    end = lines[head].index("method")
    rows = []
    for line in lines[head + 2:]:
        if not line.strip() or line.startswith("unit column:"):
            break
        rows.append(line)
    return {line[start:end].strip() for line in rows if len(line) > start}


@pytest.mark.parametrize("name", COMMANDS)
def test_human_table_with_units(cli, name):
    argv, _, units = COMMANDS[name]
    code, out, err = cli(*argv)
    assert code == 0, err
    assert err == ""
    assert "{" not in out                  # a table, not JSON
    column = _unit_column(out)
    for unit in units:
        assert unit in column or re.search(rf"\b{re.escape(unit)}\b", out.splitlines()[0]), (unit, column)
    assert column <= UNIT_CELLS, column - UNIT_CELLS


@pytest.mark.parametrize("name", COMMANDS)
def test_json_is_one_object_with_the_fixed_keys(cli, name):
    argv, keys, _ = COMMANDS[name]
    code, out, err = cli(*argv, "--json")
    assert code == 0, err
    obj = strict_json(out)
    assert obj["converged"] is True
    assert obj["command"] == argv[0]
    missing = [k for k in keys if k not in obj]
    assert not missing, missing
    assert all(k == k.strip() and " " not in k and "-" not in k for k in obj)   # snake_case keys


def test_estimate_default_json_values(cli):
    code, out, _ = cli("estimate", "--json", "--no-map")     # closed forms: no V/U here
    obj = strict_json(out)
    assert code == 0 and obj["passes"] is True and obj["V_over_U"] is None
    nu = 6.0 * math.sqrt(math.pi) * 90.0 * 135.0 ** -1.5
    assert obj["nu"] == pytest.approx(nu, rel=1e-12)
    assert obj["lam_c"] == pytest.approx(ref_lam_c(nu), rel=1e-12)
    for k in ESTIMATE_KEYS:
        if k != "dp_plus_R":
            assert k in obj, k


def test_estimate_default_json_has_every_fixed_key(cli):
    _, out, _ = cli("estimate", "--json")
    obj = strict_json(out)
    assert [k for k in ESTIMATE_KEYS if k not in obj] == []


def test_installed_console_script():
    exe = Path(sys.executable).with_name("vesicle-tube")
    exe = str(exe) if exe.exists() else shutil.which("vesicle-tube")
    assert exe, "console script vesicle-tube not installed"
    proc = subprocess.run([exe, "estimate", "--json"], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    obj = strict_json(proc.stdout)
    assert obj["command"] == "estimate" and obj["converged"] is True
    assert "Traceback" not in proc.stderr


# ------------------------------------------------------------------------------------------
# Invalid input: exit 2, one line on stderr naming parameter, value and range; nothing on stdout.
# ------------------------------------------------------------------------------------------

INVALID = {
    "lam-beyond-critical": (["estimate", "--nu", "0.6", "--lam", "2.5"],
                            ("lam", "2.5", "lam_c", "cannot pass")),
    "tube-below-d_c": (["estimate", "--diameter-um", "2"], ("diameter_um", "2", "d_c", "cannot pass")),
    "nu-above-1": (["geometry", "--nu", "1.5"], ("nu", "1.5", "1e-06 <= nu <= 1")),
    "negative-diameter": (["viscosity", "--diameter-um", "-3", "--hematocrit", "0.4"],
                          ("diameter_um", "-3", "diameter_um > 0")),
    "hematocrit-in-percent": (["viscosity", "--diameter-um", "6", "--hematocrit", "45"],
                              ("hematocrit", "45", "< 1", "fraction")),
    "unknown-law": (["viscosity", "--diameter-um", "6", "--hematocrit", "0.4", "--law", "bogus"],
                    ("--law", "bogus", "pries1992", "single-file")),
    "fahraeus-no-hematocrit": (["fahraeus", "--diameter-um", "10"],
                               ("hematocrit", "--discharge-hematocrit", "--tube-hematocrit")),
    "nan-hematocrit": (["estimate", "--hematocrit", "nan"], ("hematocrit", "nan", "0 <= ", "< 1")),
    "inf-volume": (["estimate", "--volume-fl", "inf"], ("volume_fl", "inf")),
    "zero-velocity": (["estimate", "--velocity-mm-s", "0"], ("velocity_mm_s", "0", "> 0")),
    "negative-ca_b": (["estimate", "--nu", "0.9", "--lam", "1.2", "--ca-b", "-1"], ("ca_b", "-1", "> 0")),
    "nu-and-physical": (["estimate", "--nu", "0.6", "--lam", "1.9", "--diameter-um", "3"], ("nu",)),
    "geometry-lam-zero": (["geometry", "--nu", "0.6", "--lam", "0"], ("lam", "0", "lam > 0")),
    "fahraeus-hematocrit-percent": (["fahraeus", "--diameter-um", "10", "--tube-hematocrit", "30"],
                                    ("tube_hematocrit", "30")),
    "bad-kind": (["estimate", "--hematocrit", "0.3", "--hematocrit-kind", "both"],
                 ("--hematocrit-kind", "both")),
    "not-a-number": (["geometry", "--nu", "abc"], ("--nu", "abc")),
    "no-command": ([], ("command",)),
}


@pytest.mark.parametrize("name", INVALID)
def test_invalid_input_exits_2_with_one_line(cli, name):
    argv, needles = INVALID[name]
    code, out, err = cli(*argv)
    assert code == 2
    assert out == ""
    lines = err.strip("\n").splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert "error" in lines[0]
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])


def test_invalid_input_with_json_still_exits_2_and_prints_nothing(cli):
    code, out, err = cli("estimate", "--diameter-um", "2", "--json")
    assert (code, out, len(err.strip().splitlines())) == (2, "", 1)


@pytest.mark.parametrize("argv", [["fahraeus", "--diameter-um", "10"], ["geometry"],
                                  ["estimate", "--nu", "0.6"]])
def test_missing_parameter_is_not_reported_as_nan(cli, argv):
    code, _, err = cli(*argv)
    assert code == 2
    assert "=nan" not in err


def test_too_small_area_names_the_option(cli):
    code, _, err = cli("estimate", "--area-um2", "50")
    assert code == 2
    assert "area_um2" in err or "--area-um2" in err


@pytest.mark.filterwarnings("ignore::RuntimeWarning")   # fail on the output, not the overflow warning
def test_tiny_reduced_volume_gives_strict_json_or_exit_2(cli):
    code, out, _ = cli("geometry", "--nu", "1e-300", "--json")
    if code == 0:
        strict_json(out)
    else:
        assert code == 2


# ------------------------------------------------------------------------------------------
# Viscosity laws and the Fåhræus round trip.
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("law", ["pries1992", "pries1994", "pries2005"])
def test_viscosity_names_the_pries_law(cli, law):
    code, out, _ = cli("viscosity", "--diameter-um", "6", "--hematocrit", "0.45", "--law", law)
    assert code == 0 and law in out
    code, out, _ = cli("viscosity", "--diameter-um", "6", "--hematocrit", "0.45", "--law", law,
                       "--json")
    obj = strict_json(out)
    assert obj["law"] == law
    assert obj["eta_rel"] == pytest.approx(relative_viscosity(6.0, 0.45, law), rel=1e-12)


def test_viscosity_tube_hematocrit_is_converted_with_fahraeus(cli):
    _, out, _ = cli("viscosity", "--diameter-um", "6", "--hematocrit", "0.3",
                    "--hematocrit-kind", "tube", "--json")
    obj = strict_json(out)
    a, b = FAHRAEUS_AB["pries1992"]
    assert obj["tube_hematocrit"] == 0.3
    assert ref_fahraeus_tube(6.0, obj["discharge_hematocrit"], a, b) == pytest.approx(0.3, rel=1e-12)
    assert obj["eta_rel"] == pytest.approx(relative_viscosity(6.0, obj["discharge_hematocrit"]), rel=1e-12)


def test_viscosity_single_file_in_its_range(cli):
    """RBC in a 3 µm tube: Chen et al. single-file law with the estimate's dp+."""
    code, out, _ = cli("viscosity", "--diameter-um", "3", "--hematocrit", "0.3",
                       "--hematocrit-kind", "tube", "--law", "single-file")
    assert code == 0 and "single-file" in out
    _, out, _ = cli("viscosity", "--diameter-um", "3", "--hematocrit", "0.3",
                    "--hematocrit-kind", "tube", "--law", "single-file", "--json")
    obj = strict_json(out)
    assert "single-file" in obj["law"] and obj["valid"] is True
    R0 = (3.0 * 90.0 / (4.0 * math.pi)) ** (1.0 / 3.0)
    lam = 2.0 * R0 / 3.0
    expected = 1.0 + 3.0 / 32.0 * lam**-4 * obj["dp_plus_R0"] * 0.3
    assert obj["eta_rel"] == pytest.approx(expected, rel=1e-12)


def test_viscosity_single_file_outside_its_range_gives_no_other_law(cli):
    """16 µm: no valid dp+ for an RBC (lam/lam_c = 0.18, below the solution map's 0.2, and no
    closed form), so no single-file value (and never Pries's)."""
    code, out, err = cli("viscosity", "--diameter-um", "16", "--hematocrit", "0.45",
                         "--law", "single-file", "--json")
    obj = strict_json(out)
    assert code == 0
    assert obj["eta_rel"] is None and obj["valid"] is False
    assert "single-file" in obj["law"]
    assert err.startswith("warning:")


@pytest.mark.parametrize("constants", ["pries1990", "pries1992"])
@pytest.mark.parametrize("diameter", ["5", "10", "100"])
def test_fahraeus_round_trip(cli, constants, diameter):
    _, out, _ = cli("fahraeus", "--diameter-um", diameter, "--discharge-hematocrit", "0.45",
                    "--constants", constants, "--json")
    forward = strict_json(out)
    a, b = FAHRAEUS_AB[constants]
    assert forward["tube_hematocrit"] == pytest.approx(ref_fahraeus_tube(float(diameter), 0.45, a, b),
                                                       rel=1e-12)
    _, out, _ = cli("fahraeus", "--diameter-um", diameter, "--tube-hematocrit",
                    repr(forward["tube_hematocrit"]), "--constants", constants, "--json")
    back = strict_json(out)
    assert back["discharge_hematocrit"] == pytest.approx(0.45, rel=1e-12, abs=1e-12)


# ------------------------------------------------------------------------------------------
# Out-of-range warnings.
# ------------------------------------------------------------------------------------------

def _warning_lines(err):
    return [line for line in err.splitlines() if line.startswith("warning:")]


def test_out_of_range_viscosity_warns_on_stderr_and_in_json(cli):
    code, out, err = cli("viscosity", "--diameter-um", "2000", "--hematocrit", "0.45", "--json")
    assert code == 0
    obj = strict_json(out)
    lines = _warning_lines(err)
    assert lines and len(lines) == len(err.strip().splitlines())
    assert isinstance(obj["warnings"], list) and obj["warnings"]
    assert [f"warning: {w}" for w in obj["warnings"]] == lines
    assert all("2000" in w for w in obj["warnings"])
    code, out, err = cli("viscosity", "--diameter-um", "2000", "--hematocrit", "0.45")
    assert code == 0 and _warning_lines(err) and "warnings" not in out


@pytest.mark.parametrize("argv", [
    ["fahraeus", "--diameter-um", "3.2", "--discharge-hematocrit", "0.45"],
    ["viscosity", "--diameter-um", "2", "--hematocrit", "0.45"],
    ["viscosity", "--diameter-um", "12", "--hematocrit", "0.45", "--law", "single-file",
     "--extrapolate"],
    pytest.param(["viscosity", "--diameter-um", "16", "--hematocrit", "0.45", "--law", "single-file"], id="single-file-no-dp"),
])
def test_every_stderr_warning_is_in_the_json(cli, argv):
    code, out, err = cli(*argv, "--json")
    assert code == 0
    lines = _warning_lines(err)
    assert lines
    assert [f"warning: {w}" for w in strict_json(out).get("warnings", [])] == lines


# ------------------------------------------------------------------------------------------
# Plots.
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("argv", [["estimate", "--diameter-um", "3"],
                                  ["viscosity", "--diameter-um", "6", "--hematocrit", "0.45"]],
                         ids=["estimate", "viscosity"])
def test_plot_writes_a_png_atomically(cli, tmp_path, argv):
    target = tmp_path / "figure.png"
    code, out, err = cli(*argv, "--plot", str(target), "--json")
    assert code == 0, err
    strict_json(out)                       # the figure message goes to stderr, not stdout
    data = target.read_bytes()
    assert len(data) > 1000 and data.startswith(PNG_SIGNATURE)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["figure.png"]


def test_plot_file_permissions_follow_the_umask(cli, tmp_path):
    old = os.umask(0o022)
    try:
        cli("viscosity", "--diameter-um", "6", "--hematocrit", "0.45", "--plot",
            str(tmp_path / "eta.png"))
    finally:
        os.umask(old)
    assert (tmp_path / "eta.png").stat().st_mode & 0o777 == 0o644


# ------------------------------------------------------------------------------------------
# geometry.
# ------------------------------------------------------------------------------------------

def test_geometry_cell_that_cannot_pass(cli):
    code, out, _ = cli("geometry", "--volume-fl", "90", "--area-um2", "135", "--diameter-um",
                       "2", "--json")
    obj = strict_json(out)
    assert code == 0
    assert obj["passes"] is False
    R0 = (3.0 * 90.0 / (4.0 * math.pi)) ** (1.0 / 3.0)
    nu = 6.0 * math.sqrt(math.pi) * 90.0 * 135.0 ** -1.5
    assert obj["lam"] == pytest.approx(R0, rel=1e-12)          # lam = 2 R0 / 2 µm
    assert obj["d_c_um"] == pytest.approx(2.0 * R0 / ref_lam_c(nu), rel=1e-12)


def test_geometry_clearance(cli):
    code, out, _ = cli("geometry", "--nu", "0.6", "--lam", "1.9", "--json")
    obj = strict_json(out)
    assert code == 0 and obj["passes"] is True
    lam_c = ref_lam_c(0.6)
    assert obj["lam_c"] == pytest.approx(lam_c, rel=1e-12)
    assert obj["delta"] == pytest.approx(1.0 - 1.9 / lam_c, rel=1e-12)


def test_viscosity_json_names_the_fahraeus_constants_it_used(cli):
    _, out, _ = cli("viscosity", "--diameter-um", "10", "--hematocrit", "0.45", "--json")
    assert strict_json(out)["fahraeus_constants"] == "pries1992"


# ------------------------------------------------------------------------------------------
# Every numeric option, every kind of bad number: exit 2 naming the option, or finite output.
# ------------------------------------------------------------------------------------------

NUMERIC_OPTIONS = {   # base command line: the numeric options it takes
    "geometry-nu": (["geometry", "--nu", "0.6", "--lam", "1.5"], ("--nu", "--lam")),
    "geometry-cell": (["geometry", "--volume-fl", "90", "--area-um2", "135", "--diameter-um", "4"],
                      ("--volume-fl", "--area-um2", "--diameter-um")),
    "estimate": (["estimate", "--hematocrit", "0.3"],
                 ("--volume-fl", "--area-um2", "--diameter-um", "--velocity-mm-s",
                  "--plasma-viscosity-mpas", "--bending-modulus-j", "--hematocrit")),
    "estimate-nu": (["estimate", "--nu", "0.9", "--lam", "1.25", "--ca-b", "50", "--hematocrit", "0.3"],
                    ("--nu", "--lam", "--ca-b", "--hematocrit")),
    "viscosity": (["viscosity", "--diameter-um", "6", "--hematocrit", "0.3"],
                  ("--diameter-um", "--hematocrit")),
    "viscosity-tube": (["viscosity", "--diameter-um", "6", "--hematocrit", "0.3",
                        "--hematocrit-kind", "tube", "--law", "pries2005"],
                       ("--diameter-um", "--hematocrit")),
    "viscosity-single-file": (["viscosity", "--diameter-um", "3", "--hematocrit", "0.3",
                               "--law", "single-file"], ("--diameter-um", "--hematocrit")),
    "fahraeus-discharge": (["fahraeus", "--diameter-um", "10", "--discharge-hematocrit", "0.45"],
                           ("--diameter-um", "--discharge-hematocrit")),
    "fahraeus-tube": (["fahraeus", "--diameter-um", "10", "--tube-hematocrit", "0.45"],
                      ("--diameter-um", "--tube-hematocrit")),
}
BAD_NUMBERS = ("nan", "inf", "-inf", "1e308", "1e200", "1e-320", "1e-300", "0", "-1", "abc", "")


def _with_option(argv, option, value):
    argv = list(argv)
    if option in argv:
        i = argv.index(option)
        del argv[i:i + 2]
    return argv + [f"{option}={value}"]


@pytest.mark.parametrize("value", BAD_NUMBERS)
@pytest.mark.parametrize("base, option", [(b, o) for b, (_, opts) in NUMERIC_OPTIONS.items()
                                          for o in opts])
def test_every_numeric_option_is_refused_by_name_or_gives_finite_numbers(cli, base, option, value):
    argv = _with_option(NUMERIC_OPTIONS[base][0], option, value)
    code, out, err = cli(*argv, "--json")
    assert "Traceback" not in err
    if code == 2:
        lines = err.strip("\n").splitlines()
        assert out == "" and len(lines) == 1, err
        assert option in lines[0], (option, lines[0])
    else:
        assert code == 0, (code, err)
        strict_json(out)                   # no NaN, no Infinity
        code, table, _ = cli(*argv)
        assert code == 0 and "nan" not in table.lower() and "inf " not in table


@pytest.mark.parametrize("argv, option, bound", [
    (["estimate", "--velocity-mm-s", "1e308"], "--velocity-mm-s", "1e+06"),
    (["estimate", "--velocity-mm-s", "1e-320"], "--velocity-mm-s", "1e-09"),
    (["estimate", "--plasma-viscosity-mpas", "1e308"], "--plasma-viscosity-mpas", "1e+12"),
    (["estimate", "--bending-modulus-j", "1e-320"], "--bending-modulus-j", "1e-24"),
    (["estimate", "--volume-fl", "1e200"], "--volume-fl", "1e+12"),
    (["geometry", "--volume-fl", "90", "--area-um2", "135", "--diameter-um", "1e-320"],
     "--diameter-um", "0.001"),
])
def test_absurd_physical_inputs_are_refused_naming_the_option_and_bound(cli_usage_error, argv,
                                                                        option, bound):
    line = cli_usage_error(*argv)
    assert line.split("error: ", 1)[1].startswith(option) and bound in line


def test_an_inconsistent_default_is_named_as_such(cli_usage_error):
    """--volume-fl 1e9 with the default area 135 µm² (less than the sphere's): the message
    names --area-um2 as a default and gives the range for that volume."""
    line = cli_usage_error("estimate", "--volume-fl", "1e9")
    R0 = (3e9 / (4 * math.pi)) ** (1 / 3)
    assert "--area-um2 (default)" in line and f"{4 * math.pi * R0**2:.6g}" in line


def test_huge_confinement_gives_the_asymptote_of_nu_c(cli):
    """nu_c = (3 lam^2/(1 + 2 lam^3))^(3/2) -> (3/2)^(3/2) lam^(-3/2) (relative error 3/(4 lam^3)),
    where the printed form overflows to NaN (lam > ~1e103)."""
    for lam in (1e104, 1e200):
        code, out, err = cli("geometry", "--nu", "0.6", "--lam", repr(lam), "--json")
        assert code == 0, err
        obj = strict_json(out)
        assert obj["passes"] is False and obj["delta"] is None
        assert obj["nu_c"] == pytest.approx(1.5**1.5 * lam**-1.5, rel=1e-14)


def test_huge_velocity_no_longer_gives_infinite_ca_b(cli):
    code, out, _ = cli("estimate", "--velocity-mm-s", "1e6", "--membrane", "vesicle", "--json")
    obj = strict_json(out)
    R0 = (3.0 * 90.0 / (4.0 * math.pi)) ** (1.0 / 3.0) * 1e-6
    assert code == 0 and obj["ca_b"] == pytest.approx(1.2e-3 * 1e3 * R0**2 / 2e-19, rel=1e-12)
    # the default red cell: beyond the red-cell map, refused naming the option
    code, out, err = cli("estimate", "--velocity-mm-s", "1e6")
    assert code == 2 and "--velocity-mm-s" in err and out == ""


# ------------------------------------------------------------------------------------------
# Fåhræus below x = 1: an error or a flagged missing value, never H_T > H_D.
# ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("argv", [
    ["fahraeus", "--diameter-um", "2", "--discharge-hematocrit", "0.45"],
    ["fahraeus", "--diameter-um", "3.0", "--tube-hematocrit", "0.45"],
    ["viscosity", "--diameter-um", "2", "--hematocrit", "0.45", "--hematocrit-kind", "tube"],
])
def test_fahraeus_below_its_meaningful_diameter_is_an_error(cli_usage_error, argv):
    line = cli_usage_error(*argv)
    assert "--diameter-um" in line and "3.063" in line and "H_T" in line


def test_fahraeus_near_its_singular_point_keeps_HT_below_HD(cli):
    d_star = math.log(1.7 / 0.6) / (0.35 - 0.01)        # x = 1 for the pries1992 constants
    for d in (d_star * (1 + 1e-12), d_star * (1 + 1e-6), 3.2):
        code, out, _ = cli("fahraeus", "--diameter-um", repr(d), "--discharge-hematocrit", "0.45",
                           "--json")
        obj = strict_json(out)
        assert code == 0 and obj["tube_hematocrit"] <= 0.45 and obj["ratio_HT_over_HD"] <= 1.0
        assert obj["ratio_HT_over_HD"] == pytest.approx(ref_fahraeus_tube(d, 0.45, 0.35, 0.01) / 0.45,
                                                        rel=1e-12)
        code, out, _ = cli("fahraeus", "--diameter-um", repr(d), "--tube-hematocrit", "0.45",
                           "--json")
        back = strict_json(out)
        assert code == 0 and back["discharge_hematocrit"] >= 0.45
        assert ref_fahraeus_tube(d, back["discharge_hematocrit"], 0.35, 0.01) == pytest.approx(0.45, rel=1e-12)


def test_viscosity_in_a_2um_tube_reports_no_tube_hematocrit(cli):
    code, out, _ = cli("viscosity", "--diameter-um", "2", "--hematocrit", "0.45", "--json")
    obj = strict_json(out)
    assert code == 0 and obj["tube_hematocrit"] is None
    assert any("H_T > H_D" in w for w in obj["warnings"])
    with pytest.warns(OutOfRangeWarning, match="diameter_um=2 outside"):
        direct = relative_viscosity(2.0, 0.45)      # below the Pries et al. tubes: extrapolated
    assert obj["eta_rel"] == pytest.approx(direct, rel=1e-12)


def test_estimate_just_above_d_c_keeps_HT_below_HD(cli):
    """2.9 µm: below the Fåhræus fit's x = 1, the single-file flux H_T = H_D/(V/U) answers."""
    code, out, _ = cli("estimate", "--diameter-um", "2.9", "--hematocrit", "0.45",
                       "--hematocrit-kind", "discharge", "--membrane", "vesicle", "--json")
    obj = strict_json(out)
    assert code == 0 and obj["tube_hematocrit"] == pytest.approx(0.45 / obj["V_over_U"], rel=1e-12)
    assert obj["tube_hematocrit"] < 0.45 and obj["methods"]["tube_hematocrit"]["method"] == "single_file_flux"


# ------------------------------------------------------------------------------------------
# Single-file viscosity: its diameter range comes from the stored validity range.
# ------------------------------------------------------------------------------------------

def test_single_file_range_is_the_stored_validity_range(cli, monkeypatch):
    from correlations import viscosity
    from lubrication.checks import ValidityRange
    argv = ("viscosity", "--diameter-um", "3", "--hematocrit", "0.3", "--law", "single-file", "--json")
    _, out, _ = cli(*argv)
    obj = strict_json(out)
    assert obj["valid"] is True and "8" in obj["validity"]
    monkeypatch.setattr(viscosity, "CHEN2020_RANGE",
                        ValidityRange.of("narrowed for the test", diameter_um=(0.0, 2.95)))
    code, out, err = cli(*argv)
    obj = strict_json(out)
    assert code == 0 and obj["valid"] is False and "narrowed for the test" in obj["validity"]
    assert "extrapolated" in err


# ------------------------------------------------------------------------------------------
# The Ca_B an estimate used is stated.
# ------------------------------------------------------------------------------------------

def test_dimensionless_estimate_states_the_ca_b_it_used(cli):
    _, out, _ = cli("estimate", "--nu", "0.9", "--lam", "1.25", "--json", "--no-map")
    obj = strict_json(out)
    assert obj["ca_b"] is None and "not given" in obj["methods"]["ca_b"]["note"]
    assert "10 <= Ca_B <= 1e4" in obj["methods"]["ca_b"]["note"]
    _, table, _ = cli("estimate", "--nu", "0.9", "--lam", "1.25", "--no-map")
    assert "Ca_B" in table and "not given" in table
    from correlations.solution_map import DEFAULT_MAP
    if DEFAULT_MAP.exists():        # lam/lam_c = 0.94: inside the map, which assumes Ca_B = 50
        _, out, _ = cli("estimate", "--nu", "0.9", "--lam", "1.25", "--json")
        obj = strict_json(out)
        assert obj["methods"]["V_over_U"]["method"].startswith("map (")
        assert obj["ca_b"] == 50.0
        assert "assumed by the solution map" in obj["methods"]["ca_b"]["method"]
    _, out, _ = cli("estimate", "--nu", "0.9", "--lam", "1.25", "--ca-b", "30", "--json")
    obj = strict_json(out)
    assert obj["ca_b"] == 30.0 and obj["methods"]["ca_b"]["method"] == "input"


def test_an_unphysical_model_output_is_flagged_not_silent(cli):
    """The lubrication model of a short vesicle (nu = 0.9, lam/lam_c = 0.3) gives dp+ < 0, which
    no force-free cell can (dp+ Q is its extra dissipation): the number is flagged in the JSON,
    on stderr and under the table."""
    argv = ("lubrication", "--nu", "0.9", "--lam-ratio", "0.3", "--ca-b", "50")
    code, out, err = cli(*argv, "--json")
    obj = strict_json(out)
    assert code == 0 and obj["dp_plus_R0"] < 0
    assert any(f.startswith("UNPHYSICAL dp_plus_R0:") for f in obj["unphysical"])
    assert "warning: UNPHYSICAL dp_plus_R0" in err
    code, out, err = cli(*argv)
    assert "UNPHYSICAL dp_plus_R0" in out


def test_physical_outputs_raise_no_flag(cli):
    code, out, err = cli("lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--json")
    assert code == 0 and "unphysical" not in strict_json(out) and "UNPHYSICAL" not in err


# ------------------------------------------------------------------------------------------
# Counts: every count option has a maximum, stated in its help, checked as it is parsed.
# ------------------------------------------------------------------------------------------

def _count_options():
    from correlations.cli.bem import DROP_MODES, SPHERE_PANELS, VESICLE_MAX_MODES, VESICLE_MODES
    from correlations.cli.lubrication import SWEEP_POINTS_RANGE
    return [(["bem", "sphere", "--lam", "0.5"], "--panels", SPHERE_PANELS),
            (["bem", "drop", "--lam", "0.5", "--ca", "0.1"], "--modes", DROP_MODES),
            (["bem", "vesicle", "--nu", "0.9", "--lam-ratio", "0.5"], "--modes", VESICLE_MODES),
            (["bem", "vesicle", "--nu", "0.9", "--lam-ratio", "0.5"], "--max-modes",
             VESICLE_MAX_MODES),
            (["bem", "vesicle-sweep", "--nu", "0.9", "--lam-ratio", "0.3", "0.5", "2"],
             "--modes", VESICLE_MODES),
            (["lubrication", "--nu", "0.9", "--sweep"], "--points", SWEEP_POINTS_RANGE)]


@pytest.mark.parametrize("argv, option, bounds", _count_options(),
                         ids=lambda x: x if isinstance(x, str) else None)
def test_every_count_option_states_and_checks_its_range(cli, cli_usage_error, argv, option,
                                                        bounds):
    """Below the minimum, above the maximum, and a number of 5000 digits (more than Python
    converts): exit 2 at once naming the option and its range; the help states the range."""
    lo, hi = bounds[:2]
    for value, needle in ((lo - 1, str(lo)), (hi + 1, f"at most {hi}"),
                          ("9" * 5000, f"at most {hi}")):
        clock = time.perf_counter()
        line = cli_usage_error(*argv, option, str(value))
        assert time.perf_counter() - clock < 2.0
        assert option in line and needle in line and len(line) < 300, line
    _, out, _ = cli(*argv[:2 if argv[0] == "bem" else 1], "--help")
    assert f"{lo} to {hi} (" in " ".join(out.split()), out


def test_the_count_ranges_are_the_solvers_own():
    """The ranges written out in correlations/cli (no solver import at start-up) are those of
    the solvers' resource envelopes: the largest sphere mesh under MAX_UNKNOWNS at the smallest
    sphere, the mode limits of the drop and the vesicle, the sweep limit of the lubrication
    model."""
    from bem import drop, solve, vesicle
    from lubrication.checks import InvalidParameterError
    from lubrication.solve import MAX_SWEEP_POINTS
    from correlations.cli.bem import DROP_MODES, SPHERE_PANELS, VESICLE_MAX_MODES, VESICLE_MODES
    from correlations.cli.lubrication import SWEEP_POINTS_RANGE

    small = solve.lam_min(1e-1)
    assert solve.mesh_unknowns(small, SPHERE_PANELS[1]) <= solve.MAX_UNKNOWNS \
        < solve.mesh_unknowns(small, SPHERE_PANELS[1] + 1)
    solve.check_sphere_inputs(small, panels=SPHERE_PANELS[0], tol=1e-1)
    with pytest.raises(InvalidParameterError):
        solve.check_sphere_inputs(small, panels=SPHERE_PANELS[0] - 1, tol=1e-1)
    for check, (lo, hi, _), kw in (
            (lambda **k: drop.check_drop_inputs(0.5, 0.1, **k), DROP_MODES, "n_modes"),
            (lambda **k: vesicle.check_vesicle_inputs(0.9, lam_ratio=0.5, **k), VESICLE_MODES,
             "n_modes"),
            (lambda **k: vesicle.check_vesicle_inputs(0.9, lam_ratio=0.5, **k),
             VESICLE_MAX_MODES, "max_modes")):
        check(**{kw: lo})
        check(**{kw: hi})
        for outside in (lo - 1, hi + 1):
            with pytest.raises(InvalidParameterError):
                check(**{kw: outside})
    assert SWEEP_POINTS_RANGE == (2, MAX_SWEEP_POINTS)


# ------------------------------------------------------------------------------------------
# Membrane tension: negative is physical for a weakly confined vesicle, so it is not flagged.
# ------------------------------------------------------------------------------------------

def test_a_negative_tension_is_not_flagged_as_unphysical():
    """The decision of correlations.cli._BOUNDED_KEYS: a quasi-spherical vesicle is held by a
    negative tension (-6 kappa/R0^2 as nu -> 1, the test below), so a negative front or
    largest tension is reported as it is, while dp+ < 0 stays flagged."""
    from correlations.cli import _unphysical_flags
    assert _unphysical_flags({"tension_front": -0.105, "tension_max": -0.102,
                              "tension_front_etaU": -0.105, "tension_max_etaU": -0.1}) == []
    assert _unphysical_flags({"dp_plus_R0": -1.0})


@pytest.mark.slow
def test_a_small_vesicle_is_held_by_the_quasi_spherical_tension(cli):
    """BEM vesicle at lam = 0.05, Ca_B = 0.5 (bending dominates: the flow's stress over the
    bending stress ~2 Ca_B lam^2 = 2.5e-3): gamma R0^2/kappa = (gamma/(eta U)) Ca_B tends to
    -6, the tension at which the l = 2 mode of a near-sphere is free (Milner & Safran 1987;
    Seifert, Berndl & Lipowsky 1991), as sqrt(1 - nu) (the l = 2 amplitude that holds the
    excess area; the next term, O(1 - nu), shifts the observed order by <= 0.15 here). Exit 0,
    converged, no "unphysical" flag. ~7 s per solve."""
    nus, distance = (0.98, 0.995, 0.999), []
    for nu in nus:
        code, out, err = cli("bem", "vesicle", "--nu", str(nu), "--lam", "0.05", "--ca-b", "0.5",
                             "--json")
        obj = strict_json(out)
        assert code == 0 and obj["converged"] is True and "unphysical" not in obj, err
        scaled = obj["tension_front"] * 0.5
        assert -6.0 < scaled < 0.0, (nu, scaled)
        distance.append(scaled + 6.0)
    x = 1.0 - np.array(nus)
    order = np.log(np.array(distance[:-1]) / distance[1:]) / np.log(x[:-1] / x[1:])
    assert np.all(np.abs(order - 0.5) < 0.15), (distance, order)
