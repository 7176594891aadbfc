"""``bem.sweep.sweep_vesicle``, its files and plot, and ``vesicle-tube bem vesicle-sweep``.

A real vesicle solve takes 6-30 s, so the fast tests replace :func:`bem.vesicle.solve_vesicle`
by :class:`FakeSolver`, which records every call and returns copies of two real, cached solves
(nu = 0.98, lam = 0.3 and 0.4, 16 modes; made by ``data/make_vesicle_sweep_fixture.py``),
relabelled with the requested lam. One slow test runs the real two-point sweep.

CLI contract (correlations.cli): exit 0 ok; 2 invalid input with ONE line on stderr and nothing
on stdout; 1 when a point did not converge, the JSON still printed.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import logging
import math
from pathlib import Path

import numpy as np
import pytest

import bem.sweep as sweep_module
import bem.vesicle
from bem.results import VESICLE_PROFILE_COLUMNS, VesicleResult
from bem.sweep import save_sweep, sweep_vesicle
from correlations.cli import main
from lubrication.checks import CannotPassError, InvalidParameterError
from lubrication.results import Status, status_of

DATA = Path(__file__).resolve().parent / "data"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
NU = 0.98
LAM_C = 1.1259300042085487        # root of 2x^3 - 3 nu^(-2/3) x^2 + 1 for nu = 0.98

#: The columns the sweep CSV must have, in this order, before the message.
CSV_COLUMNS = ["nu", "lam", "lam_c", "lam_ratio", "ca_b", "V_over_U", "dp_plus_R0", "ell",
               "film_min", "tension_max", "wall_shear_max", "shape_class", "converged", "residual", "volume_error",
               "area_error", "runtime"]
_ARRAYS = {f.name for f in dataclasses.fields(VesicleResult) if f.repr is False} - {"provenance"}


def load_vesicle(stem: str) -> VesicleResult:
    """Rebuild a VesicleResult from the JSON + CSV pair that ``VesicleResult.save`` writes."""
    data = json.loads((DATA / f"{stem}.json").read_text())
    table = np.loadtxt(DATA / f"{stem}.csv", delimiter=",", skiprows=1)
    names = [name for name, _ in VESICLE_PROFILE_COLUMNS]
    kw = {k: (math.nan if v is None else v) for k, v in data.items()
          if k in {f.name for f in dataclasses.fields(VesicleResult)} and k not in _ARRAYS}
    kw["status"] = status_of(data)
    kw.update({name: table[:, i] for i, name in enumerate(names)})
    kw.update({k: np.array(data["shape"][k]) for k in ("modes", "density", "tension_modes")})
    return VesicleResult(**kw)


CACHED = {0.3: load_vesicle("vesicle_nu0.98_lam0.3"), 0.4: load_vesicle("vesicle_nu0.98_lam0.4")}


class FakeSolver:
    """Stand-in for solve_vesicle: records the calls, returns the nearest cached solve.

    The copy carries the requested nu, lam and ca_b, no ``total_s`` timing (the sweep must
    measure it), and ``success`` False at the confinements listed in ``fail_at``.
    """

    def __init__(self, fail_at=()):
        self.fail_at, self.calls = tuple(fail_at), []

    def __call__(self, nu, lam=None, *, lam_ratio=None, ca_b=50.0, initial=None, **kwargs):
        self.calls.append({"nu": nu, "lam": lam, "ca_b": ca_b, "initial": initial, **kwargs})
        base = CACHED[min(CACHED, key=lambda k: abs(k - lam))]
        failed = any(abs(lam - f) < 1e-9 for f in self.fail_at)
        return dataclasses.replace(
            base, nu=nu, lam=lam, lam_c=LAM_C, ca_b=ca_b,
            status=Status.NOT_CONVERGED if failed else Status.CONVERGED,
            message="fake failure: residual too large" if failed else "converged (cached)",
            timings={"modes16_s": 0.0})


@pytest.fixture
def fake(monkeypatch):
    solver = FakeSolver()
    monkeypatch.setattr(bem.vesicle, "solve_vesicle", solver)
    return solver



# ------------------------------------------------------------------ the cached solves
def test_cached_solves_are_converged_small_vesicles():
    """The fixture is a real solve: V/U within 1 % of the small-sphere law 2 - (4/3) lam^2."""
    for lam, res in CACHED.items():
        assert res.success and res.nu == NU and res.lam == lam
        assert res.V_over_U == pytest.approx(2 - 4 / 3 * lam**2, rel=0.01)
        assert res.x.size == res.r.size == res.tension.size > 100
    assert CACHED[0.3].seed == "lubrication" and CACHED[0.4].seed == "initial"


# ------------------------------------------------------------------ sweep_vesicle
def test_points_are_solved_by_increasing_lam_and_returned_in_input_order(fake):
    out = sweep_vesicle(NU, [0.4, 0.3, 0.35])
    assert [c["lam"] for c in fake.calls] == [0.3, 0.35, 0.4]
    assert [r.lam for r in out] == [0.4, 0.3, 0.35]
    assert all(r.success for r in out)


def test_each_point_continues_from_the_previous_result(fake):
    out = sweep_vesicle(NU, [0.3, 0.35, 0.4], ca_b=20.0, n_modes=16, tol=1e-2)
    assert fake.calls[0]["initial"] is None                # the solver's own seed
    assert fake.calls[1]["initial"] is out[0]
    assert fake.calls[2]["initial"] is out[1]
    assert all(c["ca_b"] == 20.0 and c["n_modes"] == 16 and c["tol"] == 1e-2
               for c in fake.calls)


def test_initial_seeds_only_the_first_point(fake):
    seed = CACHED[0.3]
    out = sweep_vesicle(NU, [0.35, 0.3], initial=seed)
    assert fake.calls[0]["initial"] is seed and fake.calls[0]["lam"] == 0.3
    assert fake.calls[1]["initial"] is out[1]


def test_lam_ratios_are_converted_with_lam_c(fake):
    sweep_vesicle(NU, lam_ratios=[0.35, 0.3])
    assert [c["lam"] for c in fake.calls] == pytest.approx([0.3 * LAM_C, 0.35 * LAM_C],
                                                           rel=1e-12)


def test_failed_point_is_kept_reported_and_skipped_by_the_continuation(fake, caplog):
    fake.fail_at = (0.35,)
    steps = []
    with caplog.at_level(logging.INFO, logger="bem.sweep"):
        out = sweep_vesicle(NU, [0.3, 0.35, 0.4],
                            progress=lambda i, n, r, s: steps.append((i, n, r.lam, r.success, s)))
    assert [r.success for r in out] == [True, False, True]
    assert "fake failure" in out[1].message
    assert fake.calls[2]["initial"] is out[0]              # resumes from the last converged
    assert [s[:4] for s in steps] == [(1, 3, 0.3, True), (2, 3, 0.35, False), (3, 3, 0.4, True)]
    # runtime: the measured seconds, recorded since the (fake) solver gave none
    assert [r.timings["total_s"] for r in out] == [s[4] for s in steps]
    lines = [rec.getMessage() for rec in caplog.records if rec.name == "bem.sweep"]
    assert len(lines) == 3 and "2/3" in lines[1] and "NOT converged" in lines[1]
    assert "fake failure" in lines[1] and "NOT" not in lines[0]


@pytest.mark.parametrize("args, kwargs, exc, needle", [
    ((NU, [0.3, 1.2]), {}, CannotPassError, "lam=1.2"),
    ((NU,), {"lam_ratios": [0.5, 1.0]}, CannotPassError, "lam"),
    ((1.0, [0.3]), {}, InvalidParameterError, "nu=1"),
    ((NU, [0.3, math.nan]), {}, InvalidParameterError, "nan"),
    ((NU, []), {}, InvalidParameterError, "non-empty"),
    ((NU, [[0.3, 0.4]]), {}, InvalidParameterError, "1-d"),
    ((NU,), {}, InvalidParameterError, "exactly one"),
    ((NU, [0.3]), {"lam_ratios": [0.3]}, InvalidParameterError, "exactly one"),
    ((NU, [0.3]), {"ca_b": 0.0}, InvalidParameterError, "ca_b=0"),
    ((NU, [0.3]), {"ca_b": math.inf}, InvalidParameterError, "ca_b=inf"),
    ((NU, [0.3]), {"lam_ratio": 0.3}, InvalidParameterError, "set by the sweep"),
])
def test_bad_input_is_rejected_before_any_solve(fake, args, kwargs, exc, needle):
    with pytest.raises(exc) as info:
        sweep_vesicle(*args, **kwargs)
    assert needle in str(info.value)
    assert fake.calls == []


# ------------------------------------------------------------------ files
def _read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_save_sweep_writes_the_columns_the_json_and_the_profiles(fake, tmp_path):
    fake.fail_at = (0.4,)
    out = sweep_vesicle(NU, [0.3, 0.4])
    paths = save_sweep(tmp_path, out, {"n_modes": 16})
    csv_path, json_path = paths[:2]
    with open(csv_path, newline="") as f:
        header = next(csv.reader(f))
    assert header == CSV_COLUMNS + ["message"]
    rows = _read_csv(csv_path)
    assert len(rows) == 2
    assert [float(r["lam"]) for r in rows] == [0.3, 0.4]
    assert float(rows[0]["V_over_U"]) == out[0].V_over_U           # repr: round-trip exact
    assert rows[1]["dp_plus_R0"] == "" and rows[1]["V_over_U"] == ""     # failed: no numbers
    assert float(rows[0]["lam_ratio"]) == pytest.approx(0.3 / LAM_C, rel=1e-15)
    assert [r["converged"] for r in rows] == ["True", "False"]
    assert rows[0]["shape_class"] == out[0].shape_class
    assert float(rows[1]["runtime"]) == out[1].timings["total_s"]
    data = json.loads(json_path.read_text())
    assert data["nu"] == NU and data["ca_b"] == 50.0 and data["lam_c"] == LAM_C
    assert data["parameters"] == {"n_modes": 16} and data["complete"] is True
    assert data["n_points"] == 2 and data["n_converged"] == 1 and data["converged"] is False
    assert [c[0] for c in data["columns"]] == CSV_COLUMNS + ["message"]
    profiles = paths[2:]
    assert len(profiles) == 4 and sorted(data["profile_files"]) == sorted(p.name for p in profiles)
    for p in profiles:
        if p.suffix == ".csv":
            assert p.read_text().startswith("s,x,r,psi,tension,shear_membrane\n")
    assert not list(tmp_path.glob(".*.tmp"))


def test_interrupted_write_keeps_the_previous_file(fake, tmp_path, monkeypatch):
    out = sweep_vesicle(NU, [0.3, 0.4])
    csv_path = save_sweep(tmp_path, out[:1], profiles=False)[0]
    before = csv_path.read_bytes()

    class Interrupted(csv.DictWriter):
        def writerows(self, rows):
            self.writerow(next(iter(rows)))
            raise KeyboardInterrupt                 # half of the file written

    monkeypatch.setattr(sweep_module.csv, "DictWriter", Interrupted)
    with pytest.raises(KeyboardInterrupt):
        save_sweep(tmp_path, out, profiles=False)
    assert csv_path.read_bytes() == before
    assert not list(tmp_path.glob(".*.tmp"))


# ------------------------------------------------------------------ plot
def test_plot_draws_every_shape_in_the_tube_coloured_by_lam(fake):
    from bem.plotting import plot_vesicle_sweep
    fake.fail_at = (0.4,)
    out = sweep_vesicle(NU, [0.3, 0.35, 0.4])
    ax = plot_vesicle_sweep(out)
    assert ax.get_xlabel() == "x/R [-]" and ax.get_ylabel() == "r/R [-]"
    shapes = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == out[0].x.size]
    assert len(shapes) == 6                                   # upper and lower half each
    assert len({tuple(ln.get_color()) for ln in shapes}) == 3  # one colour per lam
    assert [ln.get_linestyle() for ln in shapes].count("--") == 2   # the failed point
    walls = [ln for ln in ax.get_lines() if list(ln.get_ydata()) in ([1.0, 1.0], [-1.0, -1.0])]
    assert len(walls) == 2
    for ln in shapes:                                         # centred, inside the wall
        x, y = np.asarray(ln.get_xdata()), np.abs(ln.get_ydata())
        assert abs(x.min() + x.max()) < 1e-12 and y.max() < 1.0
    assert "1 NOT CONVERGED" in ax.get_title() and "3 of 3" in ax.get_title()
    assert len(ax.figure.axes) == 2                           # the colour bar of lam


# ------------------------------------------------------------------ CLI
def test_cli_json_files_and_plot_exit_0(fake, cli, tmp_path):
    png = tmp_path / "sweep.png"
    code, out, err = cli("bem", "vesicle-sweep", "--nu", "0.98", "--lam", "0.3", "0.4",
                         "3", "--n-modes", "16", "--json", "--out", str(tmp_path / "out"),
                         "--plot", str(png))
    assert code == 0, err
    obj = json.loads(out)
    assert obj["subcommand"] == "vesicle-sweep" and obj["converged"] is True
    assert [p["lam"] for p in obj["points"]] == pytest.approx([0.3, 0.35, 0.4])
    assert obj["n_converged"] == 3 and obj["parameters"]["n_modes"] == 16
    assert all(c["n_modes"] == 16 for c in fake.calls)
    assert len(_read_csv(next((tmp_path / "out").glob("bem_vesicle_sweep_*.csv")))) == 3
    assert len(obj["files"]) == 2 + 2 * 3 and all(Path(f).exists() for f in obj["files"])
    assert png.read_bytes()[:8] == PNG_SIGNATURE
    assert "point 1/3" not in err                              # no progress lines with --json


def test_cli_table_with_progress_lines_on_stderr(fake, cli):
    code, out, err = cli("bem", "vesicle-sweep", "--nu", "0.98", "--lam-ratio", "0.27",
                         "0.35", "2")
    assert code == 0, err
    assert "{" not in out and "2/2 points converged" in out and "V/U" in out
    progress = [ln for ln in err.splitlines() if ln.startswith("point ")]
    assert len(progress) == 2 and "point 2/2" in progress[1] and "converged" in progress[1]


def test_cli_exits_1_when_a_point_did_not_converge(fake, cli):
    fake.fail_at = (0.35,)
    code, out, _ = cli("bem", "vesicle-sweep", "--nu", "0.98", "--lam", "0.3", "0.4",
                       "3", "--json")
    assert code == 1
    obj = json.loads(out)
    assert obj["converged"] is False and obj["n_converged"] == 2
    assert [p["converged"] for p in obj["points"]] == [True, False, True]
    assert "fake failure" in obj["points"][1]["message"]


def test_cli_interrupted_sweep_keeps_the_finished_points(fake, cli, tmp_path, monkeypatch):
    def stop_at_third(*args, **kwargs):
        if len(fake.calls) == 2:
            raise KeyboardInterrupt
        return fake(*args, **kwargs)
    monkeypatch.setattr(bem.vesicle, "solve_vesicle", stop_at_third)
    assert main(["bem", "vesicle-sweep", "--nu", "0.98", "--lam", "0.3", "0.4", "3", "--json",
                 "--out", str(tmp_path)]) == 130                       # Ctrl-C: exit 130
    (csv_path,) = tmp_path.glob("bem_vesicle_sweep_*.csv")
    assert [float(r["lam"]) for r in _read_csv(csv_path)] == pytest.approx([0.3, 0.35])
    assert json.loads(csv_path.with_suffix(".json").read_text())["complete"] is False


@pytest.mark.parametrize("argv, needles", [
    (["--lam", "0.3", "1.2", "3"], ("lam", "1.2", "lam_c")),           # lam >= lam_c
    (["--lam-ratio", "0.5", "1.0", "3"], ("lam", "lam_c")),
    (["--lam", "0.3", "0.4", "1"], ("--lam", "integer >= 2")),
    (["--lam", "0.3", "0.4", "2.5"], ("--lam", "integer >= 2")),
    (["--lam", "nan", "0.4", "3"], ("--lam", "nan")),
    (["--lam", "0.3", "0.4"], ("--lam", "3 arguments")),
    (["--lam", "0.3", "0.4", "3", "--lam-ratio", "0.3", "0.4", "3"], ("not allowed",)),
    ([], ("--lam",)),
    (["--lam", "0.3", "0.4", "3", "--ca-b", "0"], ("ca_b", "0")),
])
def test_cli_invalid_input_exits_2_with_one_line(fake, cli_usage_error, argv, needles):
    line = cli_usage_error("bem", "vesicle-sweep", "--nu", "0.98", *argv)
    for n in needles:
        assert n in line, (n, line)
    assert fake.calls == []


def test_cli_nu_out_of_range_exits_2(fake, cli):
    code, out, err = cli("bem", "vesicle-sweep", "--nu", "1.0", "--lam", "0.3", "0.4", "2")
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1 and "nu=1" in err
    assert fake.calls == []


# ------------------------------------------------------------------ validation (slow)
@pytest.mark.slow          # ~25 s on 2 cores
def test_real_sweep_reproduces_the_cached_solves():
    """The fixture's sweep, run for real: lam = 0.4 is continued from lam = 0.3, and both agree
    with the stored results to their accuracy (pair differences ~1e-6 in V/U, ~1e-5 in dp+;
    bounds looser so that a change of the solver's default mesh density does not fail it)."""
    out = sweep_vesicle(NU, [0.4, 0.3], n_modes=16, tol=1e-2, residual_tol=1e-3)
    assert [r.success for r in out] == [True, True], [r.message for r in out]
    assert out[0].seed == "initial"
    for res in out:
        ref = CACHED[res.lam]
        assert res.V_over_U == pytest.approx(ref.V_over_U, rel=1e-5)
        assert res.dp_plus_R0 == pytest.approx(ref.dp_plus_R0, rel=1e-3)


def test_absurd_number_of_points_is_refused_before_any_solve(fake):
    from bem.sweep import MAX_POINTS
    with pytest.raises(InvalidParameterError, match="at most"):
        sweep_vesicle(0.9, np.linspace(0.3, 0.5, MAX_POINTS + 1))
