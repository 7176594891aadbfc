"""``vesicle-tube map build`` and ``map pack`` guard their input and their folder.

* Every grid value and solver option is checked before the build folder is touched, with the
  ranges of the single-point commands (``bem vesicle``, ``lubrication``): the reference is the
  solvers' own constants (bem.vesicle, lubrication.solve) and the single-point commands' answer
  to the same value; the contract (correlations/cli/contract.py) is exit 2 with one line naming
  the option, its value and the valid range, and nothing written.
* A folder whose build.json records values the solvers refuse is reported with what to do.
* One build per folder (an advisory lock): a second build exits 2 at once naming --out and the
  pid of the first; two builds started together solve each point once; pool workers never hold
  the lock (the slow kill -9 test in test_solution_map_cli.py checks the resume after the build
  process dies).
* ``map pack``: every error names DIR or --out; a folder without a converged point is refused.

No solver runs: the stand-in solvers answer at once.
"""

from __future__ import annotations

import fcntl
import json
import os
import threading
from pathlib import Path

import pytest
from test_solution_map import _fake_build, _fake_solver, _write_point

from correlations import map_build
from correlations.map_build import LOCK_NAME, MAX_POINTS, build_map, check_build, make_grid
from correlations.solution_map import read_points

from bem.vesicle import CA_B_MAX, CA_B_MIN, MAX_MODES
from lubrication.checks import InvalidParameterError
from lubrication.solve import CA_B_RANGE, MIN_LAM_RATIO, NU_RANGE, TOL_RANGE

ONE_BEM = ["--methods", "bem", "--nu", "0.9", "--lam-ratio", "0.3", "--ca-b", "50"]
ONE_LUB = ["--methods", "lubrication", "--nu", "0.9", "--lam-ratio", "0.95", "--ca-b", "50"]


def _no_solve(*args, **kwargs):
    raise AssertionError("a solver ran: the input was not checked before the work")


@pytest.fixture
def no_solver(monkeypatch):
    for method in map_build.METHODS:
        monkeypatch.setitem(map_build.SOLVERS, method, _no_solve)


# ----------------------------------------------------------------------------- build options

#: (options, the option the message names, the value as printed, the valid range as printed),
#: the ranges from the solvers' constants
BAD_BUILD = [
    (["--nu", "0.05"], "--nu", "nu=0.05", f"{NU_RANGE[0]:g} <= nu < 1"),
    (["--nu", "0.2", "0.9"], "--nu", "nu=0.2", f"{NU_RANGE[0]:g} <= nu < 1"),
    (["--nu", "1"], "--nu", "nu=1", "0 < nu < 1"),
    (["--ca-b", "1e7"], "--ca-b", "ca_b=1e+07", f"{CA_B_MIN:g} <= ca_b <= {CA_B_MAX:g}"),
    (["--ca-b", "0.001"], "--ca-b", "ca_b=0.001", f"{CA_B_MIN:g} <= ca_b <= {CA_B_MAX:g}"),
    (["--lam-ratio", "0.05"], "--lam-ratio", "lam_ratio=0.05", f"{MIN_LAM_RATIO:g} <= lam_ratio"),
    (["--lam-ratio-lubrication", "0.05"], "--lam-ratio-lubrication", "lam_ratio=0.05",
     f"{MIN_LAM_RATIO:g} <= lam_ratio"),
    (["--lam-ratio-bem", "1.2"], "--lam-ratio-bem", "=1.2", "< 1"),
    (["--bem-tol", "-1"], "--bem-tol", "tol=-1", "1e-12 <= tol <= 0.5"),
    (["--bem-residual-tol", "100"], "--bem-residual-tol", "residual_tol=100",
     "1e-14 <= residual_tol <= 10"),
    (["--bem-n-modes", "200"], "--bem-n-modes", "n_modes=200", f"8 <= n_modes <= {MAX_MODES}"),
    (["--bem-max-modes", "16"], "--bem-max-modes", "max_modes=16",
     f"24 <= max_modes <= {MAX_MODES}"),
    (["--lubrication-tol", "0.1"], "--lubrication-tol", "tol=0.1",
     f"{TOL_RANGE[0]:g} <= tol <= {TOL_RANGE[1]:g}"),
    (["--max-time", "0"], "--max-time", "max_time=0", "max_time > 0"),
    (["--workers", str(map_build.max_workers() + 1)], "--workers",
     f"workers={map_build.max_workers() + 1}", f"1 <= workers <= {map_build.max_workers()}"),
    (["--workers", "1", "--scheduler", "tcp://127.0.0.1:9"], "--workers", "workers=1",
     "with a scheduler"),
    # the default 24 lam/lam_c x 7 Ca_B with one nu too many
    (["--nu", *[f"{0.3 + 0.005 * i:.3f}" for i in range(MAX_POINTS // 168 + 1)]],
     "--nu", f"grid={168 * (MAX_POINTS // 168 + 1)}", f"at most {MAX_POINTS} points"),
]


@pytest.mark.parametrize("argv, option, value, valid", BAD_BUILD,
                         ids=[" ".join(c[0][:2]) for c in BAD_BUILD])
def test_bad_build_option_exits_2_naming_it_before_the_folder_is_touched(
        cli_usage_error, tmp_path, no_solver, argv, option, value, valid):
    out = tmp_path / "d"
    line = cli_usage_error("map", "build", "--out", str(out), *argv)
    assert f"error: {option}" in line and value in line and valid in line, line
    assert not out.exists()


@pytest.mark.parametrize("argv", [
    ["lubrication", "--nu", "0.05", "--lam-ratio", "0.95", "--ca-b", "50"],
    ["lubrication", "--nu", "0.9", "--lam-ratio", "0.05", "--ca-b", "50"],
    ["lubrication", "--nu", "0.9", "--lam-ratio", "0.95", "--ca-b", "1e7"],
    ["bem", "vesicle", "--nu", "0.9", "--lam-ratio", "0.3", "--ca-b", "1e7"],
    ["bem", "vesicle", "--nu", "0.9", "--lam-ratio", "0.3", "--tol", "-1"],
    ["bem", "vesicle", "--nu", "0.9", "--lam-ratio", "0.3", "--modes", "200"],
])
def test_the_single_point_commands_refuse_the_same_values(cli_usage_error, argv):
    """The reference of the build's ranges: the single-point command refuses the value too."""
    cli_usage_error(*argv)


@pytest.mark.parametrize("method, point, options", [
    ("lubrication", (NU_RANGE[0], MIN_LAM_RATIO, CA_B_RANGE[0]), {"tol": 1e-3}),
    ("lubrication", (0.99, 0.9999, CA_B_RANGE[1]), {"tol": 1e-12}),
    ("bem", (0.01, 0.02, CA_B_MIN), {"tol": 0.5, "n_modes": MAX_MODES}),
    ("bem", (0.99, 0.99, CA_B_MAX), {"residual_tol": 10.0, "max_modes": 24}),
])
def test_values_at_the_ends_of_the_ranges_are_accepted(method, point, options):
    """The build accepts what the single-point commands accept: the ends of the ranges."""
    nu, r, ca = point
    check_build(make_grid([nu], [r], [ca], [method]), {method: options}, max_time=1e-3)


def test_an_unknown_solver_option_is_refused():
    with pytest.raises(InvalidParameterError, match="options.bem.*n_modes"):
        check_build(make_grid([0.9], [0.3], [50.0], ["bem"]), {"bem": {"n_mode": 8}})


def test_a_red_cell_build_gives_each_point_its_own_shear_number():
    """``shear_ratio`` β = Ca_B/Ca_S: each point solves with ca_s = ca_b/β (one physical cell
    at several velocities), checked with the BEM's own Ca_S range before any work."""
    assert map_build.point_options({"shear_ratio": 250.0, "tol": 1e-3}, 50.0) == \
        {"tol": 1e-3, "ca_s": 0.2}
    assert map_build.point_options({"tol": 1e-3}, 50.0) == {"tol": 1e-3}
    check_build(make_grid([0.61], [0.5], [2.5, 5e4], ["bem"]), {"bem": {"shear_ratio": 250.0}})
    with pytest.raises(InvalidParameterError, match="shear_ratio.*ca_b=0.1"):  # Ca_S 4e-4
        check_build(make_grid([0.61], [0.5], [0.1], ["bem"]), {"bem": {"shear_ratio": 250.0}})
    with pytest.raises(InvalidParameterError, match="shear_ratio"):
        check_build(make_grid([0.61], [0.5], [50.0], ["bem"]), {"bem": {"shear_ratio": -1.0}})
    with pytest.raises(InvalidParameterError, match="nu"):              # no biconcave disc
        check_build(make_grid([0.9], [0.5], [50.0], ["bem"]), {"bem": {"shear_ratio": 250.0}})


def test_a_folder_whose_build_json_records_refused_values_says_what_to_do(
        cli_usage_error, tmp_path, no_solver):
    """A folder built before the checks with --bem-tol -1 (every point stored as failed): its
    rerun, corrected or not, is refused naming --out and saying to build into a new folder;
    the folder is left as it was."""
    folder = tmp_path / "old"
    folder.mkdir()
    grid = make_grid([0.9], [0.3], [50.0], ["bem"])
    (folder / "build.json").write_text(json.dumps(
        {"grid": grid, "parameters": {"options": {"bem": {"tol": -1.0},
                                                  "lubrication": {"tol": 1e-7}},
                                      "max_time": None}, "provenance": {}}))
    _write_point(folder, "bem", 0.9, 0.3, 50.0, success=False)
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    for argv in ([], ONE_BEM, [*ONE_BEM, "--bem-tol", "1e-4"]):
        line = cli_usage_error("map", "build", "--out", str(folder), *argv)
        assert "error: --out" in line and "bem_tol" in line and "tol=-1" in line, line
        assert "new folder" in line
        assert {p.name: p.read_bytes() for p in folder.iterdir()} == before


def test_a_corrupt_point_file_of_the_folder_is_named_as_out(cli_usage_error, tmp_path,
                                                           monkeypatch):
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    folder = tmp_path / "b"
    build_map(folder, make_grid([0.9], [0.3], [50.0], ["bem"]), workers=1)
    (folder / "bem_nu0.9_lr0.3_caB50.json").write_text("{half")
    line = cli_usage_error("map", "build", "--out", str(folder), *ONE_BEM)
    assert "error: --out" in line and "bem_nu0.9_lr0.3_caB50.json" in line
    line = cli_usage_error("map", "pack", str(folder))
    assert "error: DIR" in line and "bem_nu0.9_lr0.3_caB50.json" in line


def test_build_help_states_the_solvers_ranges(capsys):
    """The help types the ranges (the parser stays free of numpy); they must be the solvers'."""
    from correlations.cli import main
    with pytest.raises(SystemExit):
        main(["map", "build", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for typed in (f"{NU_RANGE[0]:g} <= nu < 1", f"{MIN_LAM_RATIO:g} <= r < 1",
                  f"{CA_B_MIN:g} to {CA_B_MAX:.0e}".replace("e+0", "e"),
                  f"8 to {MAX_MODES}", f"24 to {MAX_MODES}", "1e-12 to 0.5", "1e-14 to 10",
                  "1e-12 to 1e-3", f"at most {MAX_POINTS} points"):
        assert typed in text, typed
    assert CA_B_RANGE == (CA_B_MIN, CA_B_MAX)       # one range for both solvers
    assert TOL_RANGE == (1e-12, 1e-3)


# ----------------------------------------------------------------------------- one build per folder

def _hold_lock(folder: Path, pid: int = 4242):
    """The lock as a running build holds it: the file locked, its pid written."""
    folder.mkdir(parents=True, exist_ok=True)
    fd = os.open(folder / LOCK_NAME, os.O_RDWR | os.O_CREAT)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    os.write(fd, f"{pid}\n".encode())
    return fd


def test_a_second_build_into_a_locked_folder_exits_2_at_once(cli_usage_error, tmp_path,
                                                             monkeypatch):
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    folder = tmp_path / "b"
    fd = _hold_lock(folder)
    try:
        line = cli_usage_error("map", "build", "--out", str(folder), *ONE_BEM)
        assert "error: --out" in line and "another build (pid 4242) is writing there" in line
        assert sorted(p.name for p in folder.iterdir()) == [LOCK_NAME]   # nothing written
    finally:
        os.close(fd)                     # the "other build" ends
    summary = build_map(folder, make_grid([0.9], [0.3], [50.0], ["bem"]), workers=1)
    assert summary["new"] == 1
    assert not (folder / LOCK_NAME).exists()


def test_two_builds_started_together_solve_each_point_once(tmp_path, monkeypatch):
    """Two builds of the same folder started at the same moment (threads: the lock is per open
    file, so they exclude each other as processes do): every point is solved once; the
    build that did not get the folder is refused naming it, or (if it started after the
    other ended) finds every point stored."""
    calls, lock = [], threading.Lock()

    def slow(nu, lam_ratio, ca_b, warm, options, max_time):
        with lock:
            calls.append((nu, lam_ratio, ca_b))
        threading.Event().wait(0.05)
        return _fake_solver(nu, lam_ratio, ca_b, warm, options, max_time)

    monkeypatch.setitem(map_build.SOLVERS, "bem", slow)
    grid = make_grid([0.8, 0.9, 0.95], [0.3, 0.4], [50.0], ["bem"])
    start, results = threading.Barrier(2), []

    def build():
        start.wait()
        try:
            results.append(build_map(tmp_path, grid, workers=1, pack=False)["new"])
        except InvalidParameterError as exc:
            results.append(str(exc))

    threads = [threading.Thread(target=build) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert len(calls) == len(set(calls)) == 6, calls
    solved = [r for r in results if isinstance(r, int)]
    refused = [r for r in results if isinstance(r, str)]
    assert len(results) == 2 and sum(solved) == 6, results
    assert all("another build" in r for r in refused), refused


def _lock_holders(folder: Path) -> list[int]:
    """Processes with the lock file of ``folder`` open (from /proc)."""
    target = str(folder / LOCK_NAME)
    holders = []
    for proc in Path("/proc").iterdir():
        if proc.name.isdigit():
            try:
                links = [os.readlink(fd) for fd in (proc / "fd").iterdir()]
            except OSError:
                continue
            if target in links:
                holders.append(int(proc.name))
    return holders


def _worker_reports_lock(nu, lam_ratio, ca_b, warm, options, max_time):
    """Stands in for a solver in a pool worker: which processes hold the lock of the build
    folder (in the environment), as its message."""
    fields, warm = _fake_solver(nu, lam_ratio, ca_b, warm, options, max_time)
    folder = Path(os.environ["LOCK_TEST_FOLDER"])
    fields["message"] = json.dumps({"worker": os.getpid(), "holders": _lock_holders(folder)})
    return fields, warm


@pytest.mark.skipif(not Path("/proc/self/fd").is_dir(), reason="reads /proc")
def test_pool_workers_do_not_hold_the_build_lock(tmp_path, monkeypatch):
    """Forked workers close their copy of the lock: while they solve, only the build holds it
    (a worker alive after its build died would otherwise keep the folder locked)."""
    if map_build._pool_context().get_start_method() != "fork":
        pytest.skip("the pool spawns (numba's threads run in this process): nothing inherited")
    monkeypatch.setitem(map_build.SOLVERS, "bem", _worker_reports_lock)
    monkeypatch.setenv("LOCK_TEST_FOLDER", str(tmp_path))
    build_map(tmp_path, make_grid([0.9], [0.3], [50.0, 500.0], ["bem"]), workers=2,
              pack=False)
    seen = [json.loads(p["message"]) for p in read_points(tmp_path)]
    assert len(seen) == 2 and len({s["worker"] for s in seen}) == 2
    assert all(s["holders"] == [os.getpid()] for s in seen), seen


# ----------------------------------------------------------------------------- map pack

def test_pack_errors_name_dir_or_out(cli_usage_error, tmp_path, monkeypatch):
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    build = tmp_path / "b"
    build_map(build, make_grid([0.9], [0.3], [50.0], ["bem"]), workers=1, pack=False)
    a_file = tmp_path / "file"
    a_file.write_text("x")
    empty = tmp_path / "empty"
    empty.mkdir()
    cases = [([str(tmp_path / "absent")], "DIR", "no such folder"),
             ([str(a_file)], "DIR", "this is a file"),
             ([str(empty)], "DIR", "no build.json"),
             ([""], "DIR", "empty"),
             ([str(build), "--out", str(a_file / "m.json")], "--out", "is a file, not a folder"),
             ([str(build), "--out", str(tmp_path / "no" / "m.json")], "--out", "does not exist"),
             ([str(build), "--out", str(empty)], "--out", "this is a folder"),
             ([str(build), "--out", ""], "--out", "empty"),
             ([str(build), "--out", str(build / "build.json")], "--out", "build folder"),
             ([str(build), "--out", str(build / "bem_nu0.9_lr0.3_caB50.json")], "--out",
              "build folder"),
             ([str(build), "--out", "x" * 300 + ".json"], "--out", "too long")]
    before = sorted(p.name for p in build.iterdir())
    for argv, option, what in cases:
        line = cli_usage_error("map", "pack", *argv)
        assert f"error: {option}" in line and what in line, line
    assert sorted(p.name for p in build.iterdir()) == before


def test_pack_of_a_folder_without_a_converged_point_is_refused(cli_usage_error, cli,
                                                               tmp_path):
    """0 converged points: exit 2 (a map of holes answers nothing; the shipped map is not
    replaced by one); 1 point: a valid map of that point."""
    folder = tmp_path / "b"
    folder.mkdir()
    grid = make_grid([0.9], [0.3], [50.0], ["bem"])
    (folder / "build.json").write_text(json.dumps({"grid": grid, "parameters": {},
                                                   "provenance": {}}))
    line = cli_usage_error("map", "pack", str(folder))
    assert "error: DIR" in line and "no point stored" in line
    _write_point(folder, "bem", 0.9, 0.3, 50.0, success=False)
    line = cli_usage_error("map", "pack", str(folder))
    assert "its 1 points all failed" in line
    assert not (folder / "solution_map.json").exists()
    _write_point(folder, "bem", 0.9, 0.3, 50.0)
    code, out, err = cli("map", "pack", str(folder), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["points"] == 1 and data["holes"] == 0


def test_pack_of_a_fake_build_reports_its_points(cli, tmp_path):
    _fake_build(tmp_path / "b")
    code, out, err = cli("map", "pack", str(tmp_path / "b"), "--json")
    assert code == 0, err
    assert json.loads(out)["points"] > 1


def test_pack_reports_the_points_it_rejected_as_unphysical(cli, tmp_path):
    """A converged point with V/U = 7 (outside 1 <= V/U <= 2, lubrication.checks.OUTPUT_BOUNDS)
    is no node: the pack counts it under "rejected" and warns."""
    folder = tmp_path / "b"
    folder.mkdir()
    grid = make_grid([0.9], [0.3, 0.4], [50.0], ["bem"])
    (folder / "build.json").write_text(json.dumps({"grid": grid, "parameters": {},
                                                   "provenance": {}}))
    _write_point(folder, "bem", 0.9, 0.3, 50.0)
    _write_point(folder, "bem", 0.9, 0.4, 50.0)
    bad = folder / "bem_nu0.9_lr0.4_caB50.json"
    bad.write_text(json.dumps({**json.loads(bad.read_text()), "V_over_U": 7.0}))
    code, out, err = cli("map", "pack", str(folder), "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["points"] == 1 and data["rejected"] == 1 and data["holes"] == 1
    assert "1 converged points rejected as unphysical" in err


def test_a_red_cell_slows_down_from_its_next_velocity_up(tmp_path):
    """The warm start of a red-cell point is the converged point stored at the same (ν, λ/λc)
    with the next Ca_B up (the same cell faster); failed points, other (ν, λ/λc) and slower
    points are not."""
    def store(nu, r, ca_b, success):
        rec = {"nu": nu, "lam_ratio": r, "ca_b": ca_b, "success": success,
               "shape": {"modes": [0.1], "density": []} if success else None}
        (tmp_path / map_build.point_filename("bem", nu, r, ca_b)).write_text(json.dumps(rec))
    store(0.6, 0.3, 10.0, True)
    store(0.6, 0.3, 15.0, False)
    store(0.6, 0.3, 40.0, True)
    store(0.65, 0.3, 12.0, True)
    store(0.6, 0.35, 12.0, True)
    assert map_build._faster_point(tmp_path, 0.6, 0.3, 5.0)["ca_b"] == 10.0
    assert map_build._faster_point(tmp_path, 0.6, 0.3, 10.0)["ca_b"] == 40.0
    assert map_build._faster_point(tmp_path, 0.6, 0.3, 40.0) is None
