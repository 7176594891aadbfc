"""Ctrl-C and a closed pipe end every long command quietly (correlations/cli/contract.py).

Each long command runs as its own process (the installed console script). After it has been
working for a while it gets SIGINT, as a terminal's Ctrl-C sends it; it must exit with status
130 within 2 s, print one line (naming the complete files already written), no traceback, and
leave no half-written or temporary file behind. One command of each solver runs in the default
suite; the rest are marked slow.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

STOP_WITHIN_S = 2.0


def _exe() -> str:
    return shutil.which("vesicle-tube") or str(Path(sys.executable).with_name("vesicle-tube"))


def _interrupt(argv, working_s: float, wait_for: str | None = None):
    """Start ``vesicle-tube argv``, let it work ``working_s`` seconds (or until ``wait_for``
    appears on stderr, at most ``working_s``), send SIGINT; return (exit code, seconds to stop,
    stderr)."""
    proc = subprocess.Popen([_exe()] + argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(iter(proc.stderr.readline, "")),
                              daemon=True)
    reader.start()
    t_start = time.monotonic()
    while time.monotonic() - t_start < working_s and proc.poll() is None:
        if wait_for is not None and any(wait_for in line for line in lines):
            break
        time.sleep(0.1)
    assert proc.poll() is None, f"{argv} ended before the interrupt:\n{''.join(lines)}"
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail(f"{argv} ignored SIGINT for 30 s")
    seconds = time.monotonic() - t0
    reader.join(timeout=5)
    proc.stdout.close()
    return proc.returncode, seconds, "".join(lines)


def _assert_clean_stop(argv, code, seconds, err, folder: Path | None = None):
    assert "Traceback" not in err, err
    assert code == 130, f"{argv}: exit {code}\n{err}"
    assert seconds < STOP_WITHIN_S, f"{argv}: stopped {seconds:.1f} s after SIGINT"
    said = [line for line in err.splitlines() if "interrupted" in line]
    assert len(said) == 1, err
    last = err.strip().splitlines()[-1]
    assert last == said[0], f"the interrupt message is not the last line:\n{err}"
    if folder is not None and folder.exists():
        for f in folder.rglob("*"):
            assert not f.name.startswith("."), f"temporary file left behind: {f}"
            if f.suffix == ".json":
                json.loads(f.read_text())          # complete, parseable
            assert str(f) in last, f"{f} written but not named in: {last}"


def test_ctrl_c_stops_a_bem_vesicle_sweep_and_names_its_complete_files(tmp_path):
    """The sweep has finished its first point (files on disk) when it is interrupted."""
    out = tmp_path / "sweep"
    argv = ["bem", "vesicle-sweep", "--nu", "0.98", "--lam-ratio", "0.3", "0.5", "4",
            "--out", str(out)]
    code, seconds, err = _interrupt(argv, 120, wait_for="point 1/4")
    _assert_clean_stop(argv, code, seconds, err, out)
    assert any(out.rglob("*.json")), "no point saved before the interrupt"


def test_ctrl_c_stops_a_lubrication_sweep(tmp_path):
    argv = ["lubrication", "--nu", "0.9", "--ca-b", "50", "--sweep", "--from", "0.5", "--to",
            "0.999", "--points", "60", "--out", str(tmp_path)]
    code, seconds, err = _interrupt(argv, 4.0)
    _assert_clean_stop(argv, code, seconds, err, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("argv, working_s", [
    (["bem", "vesicle", "--nu", "0.7", "--lam", "1.5"], 4.0),      # ~10 s (0.9, 1.0: ~2 s)
    (["bem", "drop", "--lam", "0.8", "--ca", "0.3"], 4.0),
    (["bem", "sphere", "--lam", "0.99", "--tol", "1e-12"], 2.5),     # ~4.5 s in all
    (["estimate", "--nu", "0.7", "--lam", "1.5", "--solver", "bem"], 4.0),
    (["lubrication", "--nu", "0.6", "--lam-ratio", "0.8", "--ca-b", "50"], 4.0),
], ids=lambda a: " ".join(a[:2]) if isinstance(a, list) else "")
def test_ctrl_c_stops_every_long_command(argv, working_s):
    code, seconds, err = _interrupt(argv, working_s)
    _assert_clean_stop(argv, code, seconds, err)


def test_ctrl_c_stops_a_check_while_it_solves_its_bem_references(tmp_path):
    """``vesicle-tube check`` of drop rows solves a BEM drop per row (seconds each) before it
    writes its report: interrupted meanwhile, it stops and has written nothing."""
    rows = tmp_path / "drops.csv"
    rows.write_text("kind,lam,ca,V_over_U,dp_plus_R\n" + "".join(
        f"drop,0.8,{ca},1.5,1.5\n" for ca in (0.05, 0.1, 0.2, 0.3, 0.5)))
    out = tmp_path / "out"
    out.mkdir()
    argv = ["check", str(rows), "--report", str(out / "report.md")]
    code, seconds, err = _interrupt(argv, 4.0)
    _assert_clean_stop(argv, code, seconds, err, out)
    assert not any(out.iterdir())


def test_a_closed_pipe_ends_a_check_quietly(tmp_path):
    rows = tmp_path / "rows.csv"
    rows.write_text("nu,lam,V_over_U,dp_plus_R0\n" + "0.9,1.0,1.25,15\n" * 200)
    proc = subprocess.Popen([_exe(), "check", str(rows)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) in (0, 1, 141), err
    assert "Traceback" not in err and "BrokenPipe" not in err, err


@pytest.mark.parametrize("argv", [["estimate"], ["geometry", "--nu", "0.6", "--lam", "1.9"]])
def test_a_closed_pipe_ends_quietly(argv):
    """``vesicle-tube estimate | head -0``: the reader is gone before the table is printed; no
    BrokenPipeError traceback."""
    proc = subprocess.Popen([_exe()] + argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) in (0, 141), err
    assert "Traceback" not in err and "BrokenPipe" not in err, err


def test_an_interrupt_inside_numba_code_is_an_interrupt(monkeypatch, capsys):
    """A Ctrl-C that lands while numba-compiled code calls back into Python surfaces as a
    SystemError caused by the KeyboardInterrupt (seen once in a clean-clone run of the sweep
    test above): the command still ends with the one interrupt line and exit 130; any other
    SystemError propagates."""
    import correlations.cli as cli
    from correlations.cli.contract import EXIT_INTERRUPTED

    def numba_like(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("returned a result with an exception set") from exc

    monkeypatch.setattr(cli, "_run", numba_like)
    assert cli.main(["estimate"]) == EXIT_INTERRUPTED
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "interrupted" in err[0]

    def other(args):
        raise SystemError("something else")

    monkeypatch.setattr(cli, "_run", other)
    with pytest.raises(SystemError, match="something else"):
        cli.main(["estimate"])
