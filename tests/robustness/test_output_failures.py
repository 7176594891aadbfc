"""Every output of ``vesicle-tube`` fails cleanly (the contract of correlations/cli/contract.py).

* stdout that cannot be written (a full disk: /dev/full): exit 1 and the one line
  "cannot write the output: No space left on device" on stderr, no traceback;
* stderr that cannot be written: the messages are lost, the exit status is the contract's;
* a stream whose encoding cannot write the tables' symbols (PYTHONIOENCODING=ascii): the
  output is written all the same, in ASCII spellings, and --json as the same JSON in ASCII;
* a result file that cannot be written when the work is done (full disk, permission, read-only
  folder, a folder where the file goes): exit 1, the result still printed, one line naming the
  file and the system's reason and what of the option was written; no file half-written and
  no temporary file left;
* an output path too long for the file system: exit 2 before any work, naming the option.

The commands run in-process (``cli`` fixtures of tests/conftest.py) where a failure can be
staged by replacing one system call, and as the installed console script where the real
stream matters (/dev/full, the encoding of the interpreter's own stdout).
"""

from __future__ import annotations

import errno
import io
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
from cli_helpers import strict_json

from correlations.cli import main
from lubrication.io import path_limits

ENOSPC = os.strerror(errno.ENOSPC)          # "No space left on device"
LUBRICATION = ["lubrication", "--nu", "0.9", "--lam-ratio", "0.99"]    # ~1 s, converges
GEOMETRY = ["geometry", "--nu", "0.6", "--lam", "1.9"]                 # prints "§IV.A"


@pytest.fixture(scope="module")
def lubrication_result():
    """The solve of :data:`LUBRICATION`, once for the module."""
    from lubrication.solve import solve_lubrication
    return solve_lubrication(0.9, lam_ratio=0.99)


@pytest.fixture
def fast(monkeypatch, lubrication_result):
    """``vesicle-tube lubrication`` answers :data:`LUBRICATION` from the stored solve, so that
    the tests of its outputs do not solve again."""
    import lubrication.solve
    monkeypatch.setattr(lubrication.solve, "solve_lubrication",
                        lambda *args, **kwargs: lubrication_result)


def _exe() -> str:
    return shutil.which("vesicle-tube") or str(Path(sys.executable).with_name("vesicle-tube"))


def _run(argv, *, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=None):
    """The console script with ``argv``: (exit status, stdout bytes, stderr text)."""
    proc = subprocess.run([_exe()] + argv, stdout=stdout, stderr=stderr, timeout=120, check=False,
                          env=None if env is None else {**os.environ, **env})
    err = proc.stderr.decode("utf-8", "replace") if proc.stderr is not None else ""
    return proc.returncode, proc.stdout, err


def _no_temporaries(folder: Path) -> None:
    left = [p for p in folder.rglob(".*") if p.name.endswith(".tmp")]
    assert not left, f"temporary files left behind: {left}"


# ------------------------------------------------------------------------------ stdout, stderr

@pytest.mark.parametrize("argv, prog", [(GEOMETRY, "vesicle-tube geometry"),
                                        (GEOMETRY + ["--json"], "vesicle-tube geometry"),
                                        (["--help"], "vesicle-tube")],
                         ids=["table", "json", "help"])
def test_stdout_on_a_full_disk_is_exit_1_with_one_line(argv, prog):
    with open("/dev/full", "wb") as full:
        code, _, err = _run(argv, stdout=full)
    assert code == 1, err
    assert err.splitlines() == [f"{prog}: error: cannot write the output: {ENOSPC}"], err


@pytest.mark.parametrize("argv, expected", [
    (GEOMETRY, 0),
    (["estimate", "--diameter-um", "2"], 2),               # below the cell's critical diameter
])
def test_stderr_on_a_full_disk_keeps_the_exit_status(argv, expected):
    """The messages are lost; the status and stdout are what they would have been."""
    with open("/dev/full", "wb") as full:
        code, out, _ = _run(argv, stderr=full)
    assert code == expected
    if expected == 0:
        assert b"critical confinement" in out


def test_an_ascii_stdout_gets_ascii_spellings_and_ascii_json():
    """PYTHONIOENCODING=ascii: the table is written with "sec. IV.A" for "§IV.A"; --json is the
    same JSON as in UTF-8, with \\u escapes."""
    code, out, err = _run(GEOMETRY, env={"PYTHONIOENCODING": "ascii"})
    assert code == 0 and "Traceback" not in err, err
    assert "Chen et al. 2020 sec. IV.A" in out.decode("ascii")
    objects = {}
    for encoding in ("ascii", "utf-8"):
        code, text, err = _run(["estimate", "--json"], env={"PYTHONIOENCODING": encoding})
        assert code == 0, err
        objects[encoding] = strict_json(text.decode(encoding))
        objects[encoding].pop("provenance")                    # its date may differ
    assert objects["ascii"] == objects["utf-8"]
    assert "§" in json.dumps(objects["utf-8"], ensure_ascii=False)    # an escape was needed


@pytest.mark.parametrize("argv", [
    ["estimate"], ["estimate", "--json"], ["estimate", "--nu", "0.9", "--lam", "1.25"],
    ["viscosity", "--diameter-um", "3", "--hematocrit", "0.45", "--law", "single-file"],
    LUBRICATION,
], ids=lambda a: " ".join(a))
def test_every_command_writes_to_an_ascii_stream(monkeypatch, fast, argv):
    """In-process, stdout and stderr are ASCII streams: exit 0, every byte ASCII, and a table
    or strict JSON."""
    streams = {name: io.TextIOWrapper(io.BytesIO(), encoding="ascii", errors="strict")
               for name in ("stdout", "stderr")}
    for name, stream in streams.items():
        monkeypatch.setattr(sys, name, stream)
    code = main(argv)
    texts = {}
    for name, stream in streams.items():
        stream.flush()
        texts[name] = stream.buffer.getvalue().decode("ascii")     # raises on a non-ASCII byte
    assert code == 0, texts["stderr"]
    assert "Traceback" not in texts["stderr"]
    if "--json" in argv:
        strict_json(texts["stdout"])
    else:
        assert texts["stdout"].strip()


# ------------------------------------------------------------------------------ result files

def _fail(monkeypatch, module, name, number):
    """Make ``module.name`` raise the OSError of ``number``."""
    def failing(*args, **kwargs):
        raise OSError(number, os.strerror(number))
    monkeypatch.setattr(module, name, failing)


@pytest.mark.parametrize("module, call, number", [
    (os, "fsync", errno.ENOSPC),                 # the disk fills while the file is written
    (tempfile, "mkstemp", errno.EACCES),         # the folder's permission changed meanwhile
    (tempfile, "mkstemp", errno.EROFS),          # the folder's file system became read-only
], ids=["ENOSPC", "EACCES", "EROFS"])
@pytest.mark.parametrize("option", ["--out", "--plot"])
def test_a_result_file_that_cannot_be_written_is_exit_1_with_the_result_printed(
        cli, fast, monkeypatch, tmp_path, module, call, number, option):
    target = tmp_path / "out" if option == "--out" else tmp_path / "shape.png"
    _fail(monkeypatch, module, call, number)
    code, out, err = cli(*LUBRICATION, option, str(target), "--json")
    assert code == 1, err
    obj = strict_json(out)                                  # the computed result, printed
    assert obj["converged"] is True and obj["V_over_U"] > 1
    [entry] = obj["not_written"]
    assert entry["option"] == option and entry["reason"] == os.strerror(number)
    assert entry["written"] == []
    [line] = [x for x in err.splitlines() if "error" in x]
    assert line.startswith(f"vesicle-tube lubrication: error: {option}: cannot write ")
    assert entry["file"] in line and os.strerror(number) in line and "Traceback" not in err
    assert not target.exists() or not any(target.iterdir())
    _no_temporaries(tmp_path)


def test_a_folder_where_a_result_file_goes_leaves_no_file_of_the_pair(cli, fast, tmp_path):
    """``--out DIR`` with DIR/<stem>.csv an existing folder: neither the JSON nor the CSV is
    written (no half of the pair), the result is printed, exit 1 naming the CSV."""
    code, out, _ = cli(*LUBRICATION, "--json")
    stem = "lubrication_nu0.9_lam{:.6g}_high-Ca".format(strict_json(out)["lam"])
    (tmp_path / f"{stem}.csv").mkdir()
    code, out, err = cli(*LUBRICATION, "--out", str(tmp_path), "--json")
    assert code == 1, err
    [entry] = strict_json(out)["not_written"]
    assert entry["file"] == str(tmp_path / f"{stem}.csv")
    assert entry["reason"] == os.strerror(errno.EISDIR) and entry["written"] == []
    assert sorted(p.name for p in tmp_path.iterdir()) == [f"{stem}.csv"]
    assert "none of its files was written" in err


def test_a_plot_path_that_is_a_folder_is_refused_before_any_work(cli_usage_error, tmp_path):
    line = cli_usage_error(*LUBRICATION, "--plot", str(tmp_path))
    assert "--plot" in line and "this is a folder" in line


def test_files_written_before_a_failure_are_named(cli, fast, monkeypatch, tmp_path):
    """The JSON of a result is written, then the disk fills: the CSV is not, and the line says
    which file of --out exists (complete)."""
    real_fsync, calls = os.fsync, []

    def fsync_second_fails(fd):
        calls.append(fd)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, ENOSPC)
        real_fsync(fd)
    monkeypatch.setattr(os, "fsync", fsync_second_fails)
    code, out, err = cli(*LUBRICATION, "--out", str(tmp_path), "--json")
    assert code == 1, err
    [entry] = strict_json(out)["not_written"]
    [json_file] = entry["written"]
    assert entry["file"].endswith(".csv") and json_file.endswith(".json")
    assert json.loads(Path(json_file).read_text())["converged"] is True      # complete
    assert not Path(entry["file"]).exists()
    assert f"written: {json_file}" in err
    _no_temporaries(tmp_path)


# ------------------------------------------------------------------------------ path limits

def _too_long(tmp_path: Path) -> dict:
    """Paths beyond the file system's limits under ``tmp_path``: a name longer than NAME_MAX and
    a path longer than PATH_MAX (folders of one character)."""
    name_max, path_max = path_limits(tmp_path)
    return {"name": tmp_path / ("n" * (name_max + 1)),
            "path": Path(str(tmp_path) + "/a" * (path_max // 2 + 1))}


@pytest.mark.parametrize("kind", ["name", "path"])
@pytest.mark.parametrize("argv, option, suffix", [
    (LUBRICATION, "--out", ""),
    (LUBRICATION, "--plot", ".png"),
    (["estimate"], "--plot", ".png"),
    (["check", os.devnull], "--report", ".md"),
])
def test_an_output_path_beyond_the_file_systems_limits_is_exit_2_before_any_work(
        cli_usage_error, tmp_path, kind, argv, option, suffix):
    path = str(_too_long(tmp_path)[kind]) + suffix
    clock = time.perf_counter()
    line = cli_usage_error(*argv, option, path)
    assert time.perf_counter() - clock < 2.0                    # before any solve
    assert f" {option} " in f" {line}" and ("PC_NAME_MAX" if kind == "name" else "PC_PATH_MAX") \
        in line, line
    assert len(line) < 600, "the message quotes the whole path"


def test_an_out_folder_without_room_for_its_file_names_is_refused(cli_usage_error, tmp_path):
    """A folder whose own path fits, but not with the names written in it (MAX_OUTPUT_NAME)."""
    from correlations.cli.contract import MAX_OUTPUT_NAME
    _, path_max = path_limits(tmp_path)
    folder = Path(str(tmp_path) + "/a" * ((path_max - len(str(tmp_path)) - MAX_OUTPUT_NAME) // 2))
    assert len(os.fsencode(str(folder))) < path_max - 1
    line = cli_usage_error(*LUBRICATION, "--out", str(folder))
    assert "--out" in line and "PC_PATH_MAX" in line


def test_a_name_at_the_limit_is_written(cli, fast, tmp_path):
    """--plot with a file name of exactly NAME_MAX bytes: its temporary file is named within the
    limit too, and the figure is written."""
    name_max, _ = path_limits(tmp_path)
    target = tmp_path / ("p" * (name_max - len(".png")) + ".png")
    code, _, err = cli(*LUBRICATION, "--plot", str(target))
    assert code == 0, err
    assert target.read_bytes().startswith(b"\x89PNG")
    _no_temporaries(tmp_path)


def test_a_report_that_cannot_be_written_is_exit_1_with_one_line(cli, monkeypatch, tmp_path):
    """A command that writes its file in the middle of its work (check --report): one line
    naming the file and the reason, exit 1, no traceback, nothing left behind."""
    rows = tmp_path / "rows.csv"
    rows.write_text("nu,lam,V_over_U,dp_plus_R0\n0.9,1.0,1.25,15\n")
    report = tmp_path / "out" / "report.html"              # one file (the figure embedded)
    report.parent.mkdir()
    _fail(monkeypatch, os, "fsync", errno.ENOSPC)
    code, _, err = cli("check", str(rows), "--report", str(report))
    assert code == 1, err
    expected = f"vesicle-tube check: error: cannot write {report}: {ENOSPC}; the work stopped there"
    assert err.splitlines() == [expected], err
    assert not any(report.parent.iterdir())
