"""``vesicle-tube map``: bad input (exit 2, one line), Ctrl-C and SIGKILL during a parallel
build followed by a resume that solves only the missing points, and Dask distributed builds.

The interrupted builds run as their own process with a stand-in solver (1 s per point, or
``STAND_IN_SECONDS``; each call logged) patched into correlations.map_build.SOLVERS before the
command starts; the process pool forks, so its workers use it too.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from cli_helpers import strict_json
from test_solution_map import TINY, TINY_OPTIONS, _fake_build, _fake_solver

from correlations import map_build
from correlations.map_build import build_map, make_grid
from correlations.solution_map import read_points

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def packed(tmp_path_factory):
    return str(_fake_build(tmp_path_factory.mktemp("cli")))


# ----------------------------------------------------------------------------- bad input

@pytest.mark.parametrize("argv, option", [
    (["--nu", "0.5", "--lam-ratio", "0.5", "--ca-b", "50"], "--nu"),
    (["--nu", "0.7", "--lam-ratio", "1.0", "--ca-b", "50"], "--lam-ratio"),
    (["--nu", "0.7", "--lam", "5", "--ca-b", "50"], "--lam"),
    (["--nu", "0.7", "--lam-ratio", "0.5", "--ca-b", "0"], "--ca-b"),
    (["--nu", "0.7", "--lam-ratio", "0.5", "--ca-b", "1"], "--ca-b"),
    (["--nu", "0.7", "--lam-ratio", "0.5"], "--ca-b"),
])
def test_query_outside_the_map_exits_2_naming_the_option(cli_usage_error, packed, argv, option):
    line = cli_usage_error("map", "query", *argv, "--map", packed)
    assert option in line


def test_query_prints_values_with_error_bars(cli, packed):
    code, out, err = cli("map", "query", "--nu", "0.75", "--lam-ratio", "0.95", "--ca-b", "60",
                         "--map", packed, "--json")
    assert code == 0, err
    data = strict_json(out)
    q = data["quantities"]["dp_plus_R0"]
    assert q["value"] == data["dp_plus_R0"] > 0 and q["error"] > 0
    assert q["methods"] == ["lubrication"] or "lubrication" in q["methods"]
    code, out, err = cli("map", "query", "--nu", "0.75", "--lam-ratio", "0.95", "--ca-b", "60",
                         "--map", packed)
    assert code == 0 and "dp_plus_R0" in out and "+-" in out


@pytest.mark.parametrize("content", ["{not json", json.dumps({"a": 1}),
                                     json.dumps({"format": "vesicle-tube solution map",
                                                 "version": 1, "grid": {}, "columns": {}})])
def test_corrupt_or_foreign_map_file_exits_2_naming_map(cli_usage_error, tmp_path, content):
    bad = tmp_path / "map.json"
    bad.write_text(content)
    line = cli_usage_error("map", "query", "--nu", "0.7", "--lam-ratio", "0.5", "--ca-b", "50",
                           "--map", str(bad))
    assert "--map" in line and str(bad) in line


def test_a_map_packed_with_other_interpolation_variables_is_refused(cli_usage_error, packed,
                                                                     tmp_path):
    data = json.loads(Path(packed).read_text())
    data["transforms"]["ell"]["power"] = 0.5         # its LOO errors would be in another variable
    old = tmp_path / "old.json"
    old.write_text(json.dumps(data))
    line = cli_usage_error("map", "query", "--nu", "0.7", "--lam-ratio", "0.5", "--ca-b", "50",
                           "--map", str(old))
    assert str(old) in line and "pack it again" in line


def test_no_shipped_map_is_reported_cleanly(cli_usage_error, monkeypatch, tmp_path):
    from correlations import solution_map
    monkeypatch.setattr(solution_map, "DEFAULT_MAP", tmp_path / "absent.json")
    line = cli_usage_error("map", "query", "--nu", "0.7", "--lam-ratio", "0.5", "--ca-b", "50")
    assert "no map shipped" in line


def test_build_bad_input_exits_2_before_any_work(cli_usage_error, tmp_path, monkeypatch):
    monkeypatch.setattr(map_build, "SCHEDULER_TIMEOUT_S", 1)
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    a_file = tmp_path / "file"
    a_file.write_text("x")
    cases = [(["--out", str(tmp_path / "d"), "--scheduler", "tcp://127.0.0.1:9"], "--scheduler"),
             (["--out", str(a_file)], "--out"),
             (["--out", str(tmp_path / "d"), "--nu", "1.5"], "--nu"),
             (["--out", str(tmp_path / "d"), "--ca-b", "-1"], "--ca-b"),
             (["--out", str(tmp_path / "d"), "--lam-ratio", "1"], "--lam-ratio")]
    for argv, option in cases:
        assert option in cli_usage_error("map", "build", *argv)
        assert not (tmp_path / "d").exists()
    build_map(tmp_path / "old", make_grid([0.9], [0.3], [50.0], ["bem"]), workers=1)
    line = cli_usage_error("map", "build", "--out", str(tmp_path / "old"), "--nu", "0.8",
                           "--methods", "bem")
    assert "--out" in line and "another grid" in line


def test_pack_bad_input_exits_2(cli_usage_error, tmp_path):
    assert "DIR" in cli_usage_error("map", "pack", str(tmp_path))
    _fake_build(tmp_path / "b")
    assert "--out" in cli_usage_error("map", "pack", str(tmp_path / "b"), "--out",
                                      str(tmp_path / "no" / "such" / "x.json"))


def test_pack_writes_the_map_and_reports_its_size(cli, tmp_path):
    """The packed file holds every converged stored point; the summary counts them (exit 0)."""
    _fake_build(tmp_path / "b")
    target = tmp_path / "map.json"
    code, out, err = cli("map", "pack", str(tmp_path / "b"), "--out", str(target), "--json")
    assert code == 0, err
    data = strict_json(out)
    packed = json.loads(target.read_text())
    stored = [p for p in read_points(tmp_path / "b") if p["success"]]
    assert data["points"] == len(packed["columns"]["nu"]) == len(stored) > 0
    assert data["bytes"] == target.stat().st_size


# ----------------------------------------------------------------------------- interrupt, resume

STAND_IN = """
import os, sys, time
from correlations import map_build
from correlations.solution_map import QUANTITIES
log = sys.argv[1]
# long enough that the signal lands mid-build on a loaded machine
seconds = float(os.environ.get("STAND_IN_SECONDS", "1.0"))
def stand_in(nu, lam_ratio, ca_b, warm, options, max_time):
    with open(log, "a") as f:
        f.write(f"{nu} {lam_ratio}\\n")
    time.sleep(seconds)
    return ({"success": True, "message": "ok", **{q: 1.0 + lam_ratio for q in QUANTITIES},
             "shape_class": "bullet", "error_estimate": {}, "residual": 0.0, "bie_solves": 0,
             "shape": None}, None)
map_build.SOLVERS["lubrication"] = stand_in
from correlations.cli import main
sys.exit(main(sys.argv[2:]))
"""
GRID = ["--methods", "lubrication", "--nu", "0.8", "0.9", "--lam-ratio", "0.9", "0.92", "0.94",
        "0.96", "--ca-b", "50", "--workers", "2"]


def _start(log, out, seconds=1.0):
    env = {**os.environ, "PYTHONPATH": str(ROOT), "STAND_IN_SECONDS": str(seconds)}
    return subprocess.Popen([sys.executable, "-c", STAND_IN, str(log), "map", "build", "--out",
                             str(out), *GRID], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=env, start_new_session=True)


def _wait_for_points(out, n, proc, timeout=30.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if out.exists() and len(list(out.glob("lubrication_*.json"))) >= n:
            return
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    pytest.fail("no points written")


def _calls(log):
    return log.read_text().splitlines() if log.exists() else []


def _check_complete(out):
    """Every file complete, no temporary left (the lock file of a killed build may stay: it
    is unlocked, and the next build takes it)."""
    hidden = [p for p in out.glob(".*") if p.name != map_build.LOCK_NAME]
    assert not hidden, hidden
    for p in out.glob("*.json"):
        json.loads(p.read_text())                  # every file complete


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL])
def test_interrupted_build_resumes_with_only_the_missing_points(tmp_path, sig):
    out, log = tmp_path / "build", tmp_path / "calls.txt"
    proc = _start(log, out)
    _wait_for_points(out, 2, proc)
    t0 = time.monotonic()
    os.killpg(proc.pid, sig)                       # a terminal's Ctrl-C reaches the group
    _, err = proc.communicate(timeout=30)
    if sig == signal.SIGINT:
        assert proc.returncode == 130, err
        assert time.monotonic() - t0 < 15.0             # prompt, with room for a loaded machine
        last = err.strip().splitlines()[-1]
        assert "interrupted" in last and "resume" in last and "Traceback" not in err, err
    else:
        assert proc.returncode == -signal.SIGKILL
        for f in out.glob(".*.tmp"):               # a write cut by SIGKILL stays a temporary
            f.unlink()
    time.sleep(0.5)                                # orphaned workers (none expected) would write
    _check_complete(out)
    stored = len(read_points(out))
    assert 2 <= stored < 8
    log.write_text("")
    proc = _start(log, out)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert len(_calls(log)) == 8 - stored, (_calls(log), stored)
    assert len(read_points(out)) == 8 and (out / "solution_map.json").exists()
    _check_complete(out)


def _open_files(pid: int) -> set[str]:
    """What process ``pid`` holds open (the targets of its /proc/PID/fd links)."""
    found = set()
    for fd in Path(f"/proc/{pid}/fd").iterdir():
        try:
            found.add(os.readlink(fd))
        except OSError:                            # closed meanwhile
            pass
    return found


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc and the kernel's "
                    "parent-death signal (PR_SET_PDEATHSIG) are Linux's")
def test_a_build_whose_process_was_killed_resumes_at_once_with_the_missing_points(tmp_path):
    """kill -9 of the build process alone: its 2 workers never held the build lock (only the
    build has the lock file open) and die with it, the kernel releases the build's lock, so a
    new build is not refused as a concurrent one and solves exactly the missing points (about
    6 s: two command-line processes of ~2 s start-up each)."""
    out, log = tmp_path / "build", tmp_path / "calls.txt"
    proc = _start(log, out, seconds=0.5)
    _wait_for_points(out, 2, proc)
    lock = str(out / map_build.LOCK_NAME)
    workers = [int(p) for p in
               Path(f"/proc/{proc.pid}/task/{proc.pid}/children").read_text().split()]
    holders = [pid for pid in [proc.pid, *workers] if lock in _open_files(pid)]
    os.kill(proc.pid, signal.SIGKILL)
    proc.communicate(timeout=30)
    assert len(workers) >= 2 and holders == [proc.pid], (workers, holders)
    t0 = time.monotonic()
    while any(_alive(p) for p in workers) and time.monotonic() - t0 < 5:
        time.sleep(0.05)
    _check_complete(out)
    stored = len(read_points(out))
    assert 2 <= stored < 8
    log.write_text("")
    proc = _start(log, out, seconds=0.5)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert sorted(_calls(log)) == sorted(set(_calls(log))) and len(_calls(log)) == 8 - stored
    assert len(read_points(out)) == 8
    _check_complete(out)
    assert not (out / map_build.LOCK_NAME).exists()     # removed by the build that ended


# ----------------------------------------------------------------------------- Dask

def test_dask_threads_cluster_builds_the_same_map_as_the_serial_build(tmp_path, monkeypatch):
    """Fast representative check: an in-process LocalCluster (threads) with the stand-in."""
    distributed = pytest.importorskip("dask.distributed")
    monkeypatch.setitem(map_build.SOLVERS, "bem", _fake_solver)
    grid = make_grid([0.8, 0.9], [0.3, 0.4], [50.0], ["bem"])
    serial = build_map(tmp_path / "serial", grid, workers=1)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        dask = build_map(tmp_path / "dask", grid, scheduler=cluster.scheduler_address)
    assert dask["done"] == serial["done"] == 4 and dask["new"] == 4
    a, b = (json.loads(Path(s["map"]).read_text())["columns"] for s in (serial, dask))
    assert a["dp_plus_R0"] == b["dp_plus_R0"] and a["nu"] == b["nu"]


@pytest.mark.slow
def test_dask_process_cluster_builds_the_tiny_lubrication_map_like_the_serial_build(tmp_path):
    """A 2-worker LocalCluster of processes and the real lubrication solver (about 20 s)."""
    distributed = pytest.importorskip("dask.distributed")
    grid = make_grid(**TINY)
    serial = build_map(tmp_path / "serial", grid, options=TINY_OPTIONS, workers=1)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        dask = build_map(tmp_path / "dask", grid, options=TINY_OPTIONS,
                         scheduler=cluster.scheduler_address)
    a, b = (json.loads(Path(s["map"]).read_text())["columns"] for s in (serial, dask))
    assert a["nu"] == b["nu"] and a["lam_ratio"] == b["lam_ratio"]
    for q in ("V_over_U", "dp_plus_R0", "film_min", "tension_max"):
        assert b[q] == pytest.approx(a[q], rel=1e-5), q      # solver tolerance 1e-5


def test_pack_prints_the_coverage_and_lists_the_holes(cli, tmp_path):
    """The text summary shows, per Ca_B, which method holds each node, and names each hole."""
    from test_solution_map import BEM_RATIOS, CAS, NUS
    hole = (NUS[0], BEM_RATIOS[0], CAS[0])
    _fake_build(tmp_path / "b", hole=hole)
    code, out, err = cli("map", "pack", str(tmp_path / "b"), "--out", str(tmp_path / "m.json"))
    assert code == 0, err
    assert out.count("Ca_B = ") == len(CAS)
    assert "holes (no method converged): 1" in out
    assert f"(nu={hole[0]:g}, lam/lam_c={hole[1]:g}, Ca_B={hole[2]:g}): bem: " in out
    row = next(line for line in out.splitlines() if line.startswith(f"  {hole[0]:<16g}"))
    assert row.split()[1:3] == [".", "B"]       # the hole, then its BEM neighbour


def test_build_help_states_the_default_ca_b_grid(capsys):
    """``map build --help`` types the default Ca_B list (the parser stays free of numpy); it
    must be the grid the build uses."""
    import re

    from correlations.cli import main

    with pytest.raises(SystemExit):
        main(["map", "build", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    typed = re.search(r"capillary numbers [^(]*\(default ([\d. ]+)\)", text).group(1).split()
    assert [float(v) for v in typed] == map_build.DEFAULT_GRID["ca_b"]


def test_dask_tasks_get_the_cores_of_their_host_over_its_task_threads():
    """Two hosts: 8 cores for 2 workers of 2 threads (2 each), 4 cores for one worker of 1
    thread (4); the build takes the smaller, so no host is oversubscribed."""
    class Client:
        def scheduler_info(self, n_workers=-1):
            return {"workers": {"a": {"host": "h1", "nthreads": 2},
                                "b": {"host": "h1", "nthreads": 2},
                                "c": {"host": "h2", "nthreads": 1}}}

        def run(self, fn):
            return {"a": 8, "b": 8, "c": 4}

    assert map_build._dask_threads(Client()) == 2


def test_a_line_runs_on_the_threads_it_is_given():
    """numba's thread count is per thread: a line sets it for the thread that solves it."""
    import threading

    import numba
    seen = []

    def line():
        map_build._share_cores(1)
        seen.append(numba.get_num_threads())

    t = threading.Thread(target=line)
    t.start()
    t.join()
    assert seen == [1]


def _timed_out_solver(nu, lam_ratio, ca_b, warm, options, max_time):
    """Stands in for a solver that stops at its time limit at every point."""
    return {"success": False, "status": "time limit",
            "message": f"stopped at the time limit max_time={max_time:g} s"}, None


def test_build_that_reaches_max_time_exits_1_and_says_so(tmp_path, monkeypatch, capsys):
    """--max-time reached is exit 1, as for every command (the points are stored as failed);
    a rerun that solves nothing new exits 0 with the stored holes as a warning."""
    from correlations.cli import main
    monkeypatch.setitem(map_build.SOLVERS, "bem", _timed_out_solver)
    argv = ["map", "build", "--out", str(tmp_path / "d"), "--nu", "0.9", "--lam-ratio", "0.3",
            "--ca-b", "50", "--methods", "bem", "--workers", "1", "--no-pack", "--json"]
    assert main(argv + ["--max-time", "0.5"]) == 1
    out = strict_json(capsys.readouterr().out)
    assert out["converged"] is False and out["timed_out"] == 1 and "--max-time" in out["message"]
    assert main(argv) == 0
    out = strict_json(capsys.readouterr().out)
    assert out["timed_out"] == 0 and out["failed"] == 1


def _alive(pid: int) -> bool:
    """The process exists and is not a zombie (a killed child waits there for its reaper)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state != "Z"


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the kernel's parent-death "
                    "signal (PR_SET_PDEATHSIG) is Linux's")
def test_workers_die_with_a_killed_build(tmp_path):
    """kill -9 of a 2-worker build leaves no worker behind within 5 s (they would otherwise
    block on their queue for ever, holding the caller's pipe)."""
    script = (
        "import time\n"
        "from correlations import map_build\n"
        "def slow(*args, **kwargs):\n"
        "    time.sleep(120)\n"
        "map_build.SOLVERS['bem'] = slow\n"
        f"map_build.build_map({str(tmp_path / 'd')!r}, map_build.make_grid([0.9], [0.3], "
        "[50.0, 500.0], ['bem']), workers=2, pack=False)\n")
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    children = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
    workers, t0 = [], time.monotonic()
    while len(workers) < 2 and time.monotonic() - t0 < 60:
        time.sleep(0.2)
        workers = [int(p) for p in children.read_text().split()]
    assert len(workers) >= 2, workers
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    t0 = time.monotonic()
    while any(_alive(p) for p in workers) and time.monotonic() - t0 < 5:
        time.sleep(0.1)
    left = [p for p in workers if _alive(p)]
    for p in left:
        os.kill(p, signal.SIGKILL)
    assert not left, f"workers still alive 5 s after kill -9 of their build: {left}"
