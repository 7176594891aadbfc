"""File probes of the campaign (group ``files`` of :mod:`probe_campaign`): every command that
reads or writes files, fed missing, special, malformed, huge and hostile files and output paths.

Each probe runs in its own sandbox folder, its working directory: made just before the run,
filled by the probe's ``setup`` (with two files of "the user" that must survive,
:data:`probe_campaign.CANARIES`), snapshot before and after, and removed (see
:func:`probe_campaign.run_probe`). The families, in the order of :func:`probes`:

* inputs: a file of every bad kind (:data:`KINDS`: missing, empty, a folder, a FIFO, /dev/zero,
  /dev/null, a 5000-digit integer, JSON nested 1e5 deep, NaN and Infinity, truncated, UTF-16,
  binary, a byte-order mark, CRLF, ...) given to every reader (:func:`_readers`): ``check``
  (CSV, JSON, no extension), ``--map`` of ``map query``, ``infer``, ``check``, ``figures`` and
  ``estimate``, and the ``build.json`` of ``map pack`` and ``map build``;
* packed maps: each field of the shipped map replaced by a string, a bool, null and a list of
  the wrong length, single values of the columns replaced, physically impossible columns; the
  maps ``map pack`` writes from builds of one point and of none;
* build folders: ``build.json`` and point files of wrong types or impossible values (a point
  with V/U = 7 or a negative film must not become a node silently);
* outputs: every ``--plot``, ``--report``, ``--out`` given an over-long name (> NAME_MAX) or path
  (> PATH_MAX), a missing folder, a folder, a file, a FIFO, an unknown or no extension, target
  file names that exist as folders; stdout on /dev/full; ``PYTHONIOENCODING=ascii`` with
  non-ASCII paths; read-only folders (skipped when running as root: permission bits do not
  bite);
* ``map build``: bad grids and tolerances, ``--max-time 0.001``, two builds at once into one
  folder (must not both solve every point), the user's ``.something.tmp`` files in the folder
  (must survive), resume after an interrupted build;
* bounded work: ``infer --samples 10**9``, ``check`` of a 1e5-row CSV (time and memory), a CSV
  of one 10 MB line, 1 GiB sparse files.

Inputs shared by many probes (the shipped map, the builds of one point and of none made by the
tool itself, the names of the files a command writes) are made once, on first use
(:class:`Fixtures`). Probes that run a BEM solve are few (about fifteen, seconds each).
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import threading
import time
from pathlib import Path

from probe_campaign import MAX_MB, ROOT, Outcome, Probe, Running, exe, judge

from correlations.solution_map import POINT_GLOB

SHIPPED_MAP = ROOT / "correlations" / "data" / "solution_map.json"
NAME_MAX = os.pathconf("/", "PC_NAME_MAX")
PATH_MAX = os.pathconf("/", "PC_PATH_MAX")
AS_ROOT = os.geteuid() == 0
ROOT_SKIP = ("running as root: permission bits do not bite (root writes in a read-only "
             "folder), so the read-only case cannot be made here")

# --------------------------------------------------------------------------- command lines

# a vesicle row close to the BEM solution at (0.9, 1.0, Ca_B 50)
CSV_HEADER = "name,nu,lam,ca_b,V_over_U,dp_plus_R0"
CSV_ROW = "mine,0.9,1.0,50,{v},13.72"
CSV_ROWS = f"{CSV_HEADER}\n{CSV_ROW.format(v='1.2575')}\n"
JSON_ROWS = json.dumps([{"name": "mine", "nu": 0.9, "lam": 1.0, "ca_b": 50,
                         "V_over_U": 1.2575, "dp_plus_R0": 13.72}], indent=1) + "\n"
QUERY = ["map", "query", "--nu", "0.82", "--lam-ratio", "0.62", "--ca-b", "40", "--json"]
INFER = ["infer", "--v-over-u", "1.3", "--length-um", "6", "--diameter-um", "5", "--u-mm-s",
         "1", "--uncertainty", "linear", "--json"]
# the cheapest build: one lubrication point (about a second)
GRID = ["--methods", "lubrication", "--nu", "0.9", "--lam-ratio", "0.95", "--ca-b", "50",
        "--workers", "1"]
POINT = "lubrication_nu0.9_lr0.95_caB50.json"
BUILD_OUTPUTS = ("build/build.json", "build/solution_map.json")
#: a result file that cannot be written (a folder of the user where it goes): refused up front
#: (2), or found at the end of the work (1, the contract's "not written")
NOT_WRITTEN = (1, 2)
BINARY = bytes((i * 7919 + 13) % 256 for i in range(16384))     # NULs, invalid UTF-8
BIG = "1" * 5000                                                # a 5000-digit integer


class Fixtures:
    """Inputs shared by many probes, made once in ``folder`` on first use (thread-safe); a
    failure is kept and raised again to every probe that needs it (its setup fails)."""

    def __init__(self, folder: Path):
        self.folder = folder
        self._lock = threading.Lock()
        self._made: dict = {}

    def _once(self, key, make):
        with self._lock:
            if key not in self._made:
                try:
                    self._made[key] = (True, make())
                except Exception as exc:    # noqa: BLE001 - raised again below, every time
                    self._made[key] = (False, exc)
            ok, value = self._made[key]
        if not ok:
            raise value
        return value

    def _tool(self, argv, codes=(0,)) -> None:
        """Run the tool to make a fixture; RuntimeError unless it exits with one of codes."""
        self.folder.mkdir(parents=True, exist_ok=True)
        r = subprocess.run([exe()] + argv, capture_output=True, text=True, timeout=300,
                           cwd=self.folder, stdin=subprocess.DEVNULL, check=False)
        if r.returncode not in codes:
            last = (r.stderr.strip().splitlines() or [""])[-1]
            raise RuntimeError(f"fixture {' '.join(argv[:2])} exit {r.returncode}: {last}")

    def map_bytes(self) -> bytes:
        """The shipped packed map."""
        return self._once("map", SHIPPED_MAP.read_bytes)

    def map_data(self) -> dict:
        """The shipped map parsed (a fresh copy: callers change it)."""
        return json.loads(self.map_bytes())

    def build(self, points: int) -> Path:
        """A build folder made by ``map build`` of :data:`GRID`: ``points`` = 1 converged, or 0
        (the point stopped by ``--max-time 0.001``, stored as failed, exit 1), packed."""
        def make():
            out = self.folder / f"build{points}"
            self._tool(["map", "build", "--out", str(out), *GRID]
                       + ([] if points else ["--max-time", "0.001"]), (0,) if points else (1,))
            if not (out / "solution_map.json").is_file():
                raise RuntimeError(f"fixture build of {points} points: no solution_map.json")
            return out
        return self._once(f"build{points}", make)

    def written(self, key: str, argv_of) -> list[str]:
        """The names of the files a command writes in its ``--out`` folder
        (``argv_of(folder)``), sorted, from one run."""
        def make():
            out = self.folder / f"written-{key.replace(' ', '-')}"
            self._tool(argv_of(str(out)))
            return sorted(p.name for p in out.iterdir() if p.is_file())
        return self._once(f"written {key}", make)


# --------------------------------------------------------------------------- setup helpers

def _data(data):
    data = data() if callable(data) else data
    return data.encode() if isinstance(data, str) else data


def put(rel: str, data):
    """Setup: write ``data`` (bytes, text, or a callable giving them) to ``rel``."""
    def setup(box: Path):
        path = box / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(_data(data))
    return setup


def copy_build(points: int, rel: str = "build"):
    """Setup: a copy of the fixture build of ``points`` points at ``rel``."""
    def setup(box: Path):
        shutil.copytree(F.build(points), box / rel)
    return setup


def both(*setups):
    def setup(box: Path):
        for s in setups:
            s(box)
    return setup


def mkdirs(*rels):
    def setup(box: Path):
        for rel in rels:
            (box / rel).mkdir(parents=True)
            (box / rel / "user-file.txt").write_text("the user's\n")
    return setup


def fifo(rel):
    def setup(box: Path):
        (box / rel).parent.mkdir(parents=True, exist_ok=True)
        os.mkfifo(box / rel)
    return setup


# --------------------------------------------------------------------------- bad files

def _with_literal(valid: bytes, fmt: str, literal: str) -> bytes:
    """``valid`` with one number replaced by the raw text ``literal`` (CSV: the V/U cell;
    JSON rows: V/U of the first row; a map: the first V/U; build.json: the first nu; a point
    file: its V/U)."""
    if fmt == "csv":
        return f"{CSV_HEADER}\n{CSV_ROW.format(v=literal)}\n".encode()
    data = json.loads(valid)
    mark = "\0LITERAL\0"
    if fmt == "rows":
        data[0]["V_over_U"] = mark
    elif fmt == "map":
        data["columns"]["V_over_U"][0] = mark
    elif fmt == "build":
        data["grid"]["nu"][0] = mark
    else:
        data["V_over_U"] = mark
    return json.dumps(data).replace(json.dumps(mark), literal).encode()


def _crlf(valid: bytes, fmt: str) -> bytes:
    text = valid.decode() if fmt == "csv" else json.dumps(json.loads(valid), indent=1)
    return text.replace("\r\n", "\n").replace("\n", "\r\n").encode()


#: kind -> bytes of the file made from (valid content, format); None: made by _make_special
KINDS = {
    "valid": lambda v, fmt: v,
    "missing": None, "folder": None, "fifo": None, "dev-zero": None, "dev-null": None,
    "symlink-loop": None, "dangling-link": None, "newline-name": None,
    "empty": lambda v, fmt: b"",
    "int-5000-digits": lambda v, fmt: _with_literal(v, fmt, BIG),
    "nested-1e5-deep": lambda v, fmt: b"[" * 10**5 + b"]" * 10**5,
    "NaN-literal": lambda v, fmt: _with_literal(v, fmt, "NaN"),
    "Infinity-literal": lambda v, fmt: _with_literal(v, fmt, "Infinity"),
    "truncated": lambda v, fmt: v[:len(v) // 2],
    "utf-16": lambda v, fmt: v.decode().encode("utf-16"),
    "binary": lambda v, fmt: BINARY,
    "bom": lambda v, fmt: b"\xef\xbb\xbf" + v,
    "crlf": _crlf,
    "top-level-string": lambda v, fmt: b'"a string"\n',
}
#: kinds whose file is valid (a reader must accept it; a JSON reader may refuse a BOM)
VALID_KINDS = ("valid", "crlf", "bom")


def _make_special(kind: str, path: Path) -> None:
    if kind == "folder":
        path.mkdir()
        (path / "user-file.txt").write_text("the user's\n")
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind in ("dev-zero", "dev-null"):
        path.symlink_to(f"/dev/{kind[4:]}")
    elif kind == "symlink-loop":
        path.symlink_to(path.name)
    elif kind == "dangling-link":
        path.symlink_to("no-such-target")
    # missing, newline-name: no file


def bad_file(kind: str, rel: str, valid, fmt: str):
    """Setup: the file ``rel`` of ``kind`` made from the valid content ``valid``."""
    def setup(box: Path):
        path = box / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.is_file() or path.is_symlink():
            path.unlink()
        make = KINDS[kind]
        if make is None:
            _make_special(kind, path)
        else:
            path.write_bytes(make(_data(valid), fmt))
    return setup


# --------------------------------------------------------------------------- post-run checks

def png_at(rel: str):
    """Post: an exit-0 run wrote ``rel`` as a PNG."""
    def post(box: Path, o: Outcome) -> list[str]:
        path = box / rel
        if o.code == 0 and not (path.is_file() and path.read_bytes()[:4] == b"\x89PNG"):
            return [f"file {rel} missing or not a PNG"]
        return []
    return post


def not_packed(column: str, value, rel: str = "build/solution_map.json"):
    """Post: the packed map at ``rel`` holds no node with ``column`` = ``value``, unless the
    run said so on stderr (naming the column or UNPHYSICAL)."""
    def post(box: Path, o: Outcome) -> list[str]:
        path = box / rel
        try:
            cols = json.loads(path.read_text())["columns"]
        except (OSError, ValueError, KeyError, TypeError):
            return []
        if value in cols.get(column, []) and column not in o.stderr \
                and "UNPHYSICAL" not in o.stderr:
            return [(f"silent bad result: the point with {column} = {value} packed as a "
                     "node without a word")]
        return []
    return post


def new_points(n: int):
    """Post: an exit-0 ``map build --json`` solved ``n`` points (the stored ones are kept)."""
    def post(box: Path, o: Outcome) -> list[str]:
        if o.code != 0:
            return []
        try:
            new = json.loads(o.stdout)["new"]
        except (ValueError, KeyError, TypeError):
            return []
        return [] if new == n else [f"resume solved {new} points, expected {n}"]
    return post


# --------------------------------------------------------------------------- scenarios

def _steps(outcomes, probe, extra) -> Outcome:
    """One outcome of a scenario of several runs: each run judged (unless its label starts
    with "~": its problems are set by the scenario), its problems prefixed "[label] "; the
    code of the last run."""
    problems, err = list(extra), []
    for label, o in outcomes:
        if label.startswith("~"):
            label = label[1:]
        else:
            judge(o)
        problems += [f"[{label}] {x}" for x in o.problems]
        err += [f"[{label}] {line}" for line in o.stderr.splitlines() if line.strip()]
    last = outcomes[-1][1]
    return Outcome(probe, last.code, sum(o.seconds for _, o in outcomes),
                   max((o.peak_mb for _, o in outcomes if o.peak_mb == o.peak_mb),
                       default=float("nan")), last.stdout, "\n".join(err), problems)


def _json(o: Outcome) -> dict:
    try:
        obj = json.loads(o.stdout)
    except ValueError:
        return {}
    return obj if isinstance(obj, dict) else {}


def two_builds(total: int):
    """Scenario: the probe's ``map build`` started twice at once into one folder. Both may
    finish (0) or one refuse (2); together they may not solve more than the grid's ``total``
    points (each point once)."""
    def run(probe: Probe, timeout: float) -> Outcome:
        a, b = Running(probe), Running(probe)
        oa, ob = a.finish(timeout), b.finish(timeout)
        extra = []
        new = [_json(o).get("new", 0) for o in (oa, ob) if o.code == 0]
        if sum(new) > total:
            extra.append(f"duplicate work: the two builds solved {' + '.join(map(str, new))} "
                         f"points of a grid of {total}")
        return _steps([("build A", oa), ("build B", ob)], probe, extra)
    return run


def interrupted(sig: int, total: int, stale: str = ""):
    """Scenario: the probe's ``map build`` stopped by ``sig`` (to its process group, as a
    terminal's Ctrl-C) once its first point file is stored, then run again: SIGINT exits 130;
    the rerun solves only the missing points (``total`` - stored) and finishes the grid.
    ``stale``: a half-written temporary of the build planted after the stop (a kill -9 during
    a write), which the rerun must clear."""
    def run(probe: Probe, timeout: float) -> Outcome:
        out = probe.sandbox / "build"
        first = Running(probe)
        end = time.perf_counter() + min(timeout, 45)
        while first.proc.poll() is None and time.perf_counter() < end \
                and not any(out.glob(POINT_GLOB)):
            time.sleep(0.05)
        if first.proc.poll() is None:
            os.killpg(first.proc.pid, sig)
        o1 = first.finish(timeout)
        stored = len(list(out.glob(POINT_GLOB)))
        extra = []
        if sig == signal.SIGINT and o1.code != 130:
            extra.append(f"[interrupted] exit {o1.code}, expected 130 after Ctrl-C")
        if "Traceback" in o1.stderr:
            o1.problems.append("traceback")
        if stored >= total:
            extra.append("setup failed: the build finished before it was interrupted")
        if stale:
            (out / stale).write_text('{"format": "vesicle-tube map po')
        o2 = Running(probe).finish(timeout)
        obj = _json(o2)
        if o2.code == 0 and obj:
            if obj.get("new") != total - stored:
                extra.append(f"resume solved {obj.get('new')} points, expected "
                             f"{total - stored} ({stored} stored before the stop)")
            if obj.get("done") != total:
                extra.append(f"resume finished {obj.get('done')} of {total} points")
        # the stopped run is judged here (its exit above, a traceback); a stale temporary
        # left by the rerun is found by the sandbox check
        return _steps([("~interrupted", o1), ("resumed", o2)], probe, extra)
    return run


# --------------------------------------------------------------------------- the probes

F: Fixtures


class _Maker:
    """Numbers the probes and gives each its sandbox folder under ``root``."""

    def __init__(self, root: Path):
        self.root, self.n, self.probes = root, 0, []

    def __call__(self, slug: str, argv_of, allowed, *, setup=None, **kw) -> None:
        self.n += 1
        box = self.root / f"{self.n:04d}-{slug}"
        argv = argv_of(box) if callable(argv_of) else argv_of
        files = [box / f for f in kw.pop("files_of", ())]
        self.probes.append(Probe(argv, tuple(allowed), slug, files, group="files", sandbox=box,
                                 setup=setup, max_mb=kw.pop("max_mb", MAX_MB), **kw))


def _readers():
    """The readers of an input file: name -> (argv of the file's path and the sandbox, the
    file's path in the sandbox, its valid content, its format, the codes a valid file gives,
    setup of the rest of the sandbox, files the command may rewrite)."""
    rows = put("rows.csv", CSV_ROWS)
    build_json = lambda: (F.build(1) / "build.json").read_bytes()
    return {
        "check-csv": (lambda p, b: ["check", p, "--no-bem", "--json"], "in.csv", CSV_ROWS,
                      "csv", (0, 1), None, ()),
        "check-json": (lambda p, b: ["check", p, "--no-bem", "--json"], "in.json", JSON_ROWS,
                       "rows", (0, 1), None, ()),
        "check-no-extension": (lambda p, b: ["check", p, "--no-bem", "--json"], "rows",
                               CSV_ROWS, "csv", (0, 1), None, ()),
        "map-query": (lambda p, b: QUERY + ["--map", p], "map.json", F.map_bytes, "map", (0,),
                      None, ()),
        "infer": (lambda p, b: INFER + ["--map", p], "map.json", F.map_bytes, "map", (0, 1),
                  None, ()),
        "check-map": (lambda p, b: ["check", str(b / "rows.csv"), "--no-bem", "--json",
                                    "--map", p], "map.json", F.map_bytes, "map", (0, 1), rows,
                      ()),
        "figures-map": (lambda p, b: ["figures", "--only", "speed", "--out", str(b / "fig"),
                                      "--json", "--map", p], "map.json", F.map_bytes, "map",
                        (0,), None, ()),
        "map-pack": (lambda p, b: ["map", "pack", str(b / "build"), "--json"],
                     "build/build.json", build_json, "build", (0,), copy_build(1),
                     BUILD_OUTPUTS[1:]),
        "map-build": (lambda p, b: ["map", "build", "--out", str(b / "build"), *GRID, "--json"],
                      "build/build.json", build_json, "build", (0,), copy_build(1),
                      BUILD_OUTPUTS),
    }


def _input_probes(P) -> None:
    """Every bad kind of file (:data:`KINDS`) to every reader (:func:`_readers`)."""
    for reader, (argv_of, rel, valid, fmt, ok, extra, outputs) in _readers().items():
        json_reader = fmt != "csv"
        for kind in KINDS:
            if kind == "newline-name" and extra is not None:
                continue                        # the build folder's file has its own name
            if kind in ("valid", "crlf"):
                allowed = ok
            elif kind == "bom":
                allowed = ok + (2,) if json_reader else ok
            elif kind == "missing" and reader == "map-build":
                allowed = ok                       # a new build in a folder with a point
            else:
                allowed = (2,)
            name = "bad\nname.json" if kind == "newline-name" else rel
            setup = bad_file(kind, name, valid, fmt)
            if extra is not None:               # the build folder first, then its build.json
                setup = both(extra, setup)
            P(f"{reader}-{kind}", lambda b, a=argv_of, n=name: a(str(b / n), b), allowed,
              setup=setup, may_change=outputs)
    for direct in ("/dev/zero", "/dev/null"):
        P(f"check-{direct[5:]}", ["check", direct, "--no-bem", "--json"], (2,))
        P(f"map-query-{direct[5:]}", QUERY + ["--map", direct], (2,))
    for kind in ("valid", "missing", "fifo"):   # estimate has no --map: exit 2 if refused
        P(f"estimate-map-{kind}", lambda b: ["estimate", "--json", "--map", str(b / "map.json")],
          (0, 2) if kind == "valid" else (2,), setup=bad_file(kind, "map.json", F.map_bytes,
                                                              "map"))
    sparse = lambda rel: lambda box: _sparse(box / rel)
    P("map-query-sparse-1GiB", lambda b: QUERY + ["--map", str(b / "map.json")], (2,),
      setup=sparse("map.json"))
    P("check-sparse-1GiB", lambda b: ["check", str(b / "rows.csv"), "--no-bem", "--json"], (2,),
      setup=sparse("rows.csv"))
    P("map-pack-sparse-1GiB-build-json", lambda b: ["map", "pack", str(b / "build"), "--json"],
      (2,), setup=both(copy_build(1), lambda box: (box / "build" / "build.json").unlink(),
                       sparse("build/build.json")), may_change=BUILD_OUTPUTS[1:])


def _sparse(path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "wb") as f:
        f.truncate(2**30)


# ------------------------------------------------------------------ packed maps

def _map_fields(data: dict) -> list[tuple[str, ...]]:
    """Every field of a packed map as a key path: the top level, the grid's, the columns."""
    fields = [(k,) for k in data]
    fields += [("grid", k) for k in data["grid"]]
    fields += [("grid", "lam_ratio", m) for m in data["grid"]["lam_ratio"]]
    fields += [("columns", c) for c in data["columns"]]
    return fields


def _wrong_length(value):
    """A list of the wrong length for ``value``: a list one shorter, or a list where a
    scalar or an object belongs."""
    if isinstance(value, list):
        return value[:-1] if value else [1.0]
    return ["x"] if isinstance(value, dict) else [value, value]


REPLACEMENTS = {"string": lambda v: "not a number", "bool": lambda v: True,
                "null": lambda v: None, "wrong-length-list": _wrong_length}
#: map fields that only describe (a reader may ignore them)
INFORMATIONAL = {("parameters",), ("provenance",), ("units",)}


def _map_allowed(path: tuple, how: str) -> tuple:
    if path in INFORMATIONAL:
        return (0, 2)
    if path == ("holes",) and how in ("null", "wrong-length-list"):
        return (0, 2)        # no holes, or one fewer: a valid map
    if path[0] == "grid" and len(path) > 1 and how == "wrong-length-list" \
            and path != ("grid", "lam_ratio"):
        return (0, 2)        # a shorter node list of the right type
    return (2,)


def _set(data: dict, path: tuple, value) -> dict:
    holder = data
    for k in path[:-1]:
        holder = holder[k]
    holder[path[-1]] = value
    return data


def mutated_map(change, rel: str = "map.json"):
    """Setup: the shipped map changed by ``change(data)``, written to ``rel``."""
    return put(rel, lambda: json.dumps(change(F.map_data())))


def _map_probes(P) -> None:
    try:
        data = json.loads(SHIPPED_MAP.read_bytes())
    except (OSError, ValueError):
        return                                  # no shipped map: the readers' probes say so
    for path in _map_fields(data):
        for how, replace in REPLACEMENTS.items():
            def change(d, path=path, replace=replace):
                holder = d
                for k in path:
                    holder = holder[k]
                return _set(d, path, replace(holder))
            P(f"map-field-{'.'.join(path)}-{how}",
              lambda b: QUERY + ["--map", str(b / "map.json")], _map_allowed(path, how),
              setup=mutated_map(change))
    # single values of the first row, queried at that row's node
    cols = data["columns"]
    at_row0 = ["map", "query", "--nu", repr(cols["nu"][0]), "--lam-ratio",
               repr(cols["lam_ratio"][0]), "--ca-b", repr(cols["ca_b"][0]), "--json"]
    for column in ("nu", "lam_ratio", "ca_b", "method", "shape_class", "V_over_U",
                   "dp_plus_R0", "film_min"):
        wrong = 1 if column in ("method", "shape_class") else "1.1"
        for how, value in (("wrong-type", wrong), ("bool", True), ("null", None)):
            may_be_missing = how == "null" and column not in ("nu", "lam_ratio", "ca_b",
                                                              "method")
            P(f"map-value-{column}[0]-{how}", lambda b: at_row0 + ["--map", str(b / "map.json")],
              (0, 2) if may_be_missing else (2,),
              setup=mutated_map(lambda d, c=column, v=value: _set(d, ("columns", c, 0), v)))
    P("map-query-shipped-map-at-row-0", at_row0, (0,))     # the reference of the above
    # physically impossible columns: refused, or reported with an UNPHYSICAL flag
    impossible = {"V_over_U": 7.0, "dp_plus_R0": -5.0, "film_min": 2.0, "ell": -1.0}
    for column, value in impossible.items():
        P(f"map-column-{column}-all-{value:g}", lambda b: QUERY + ["--map", str(b / "map.json")],
          (0, 2), setup=mutated_map(lambda d, c=column, v=value: _set(
              d, ("columns", c), [v] * len(d["columns"][c]))))
    # a subset of the mutations through the other readers of --map
    subset = [(("format",), "string"), (("version",), "bool"), (("grid",), "null"),
              (("columns", "nu"), "wrong-length-list"), (("holes",), "string"),
              (("provenance",), "string"), (("transforms",), "null"), (("units",), "bool")]
    readers = {"infer": lambda b: INFER + ["--map", str(b / "map.json")],
               "check": lambda b: ["check", str(b / "rows.csv"), "--no-bem", "--json", "--map",
                                   str(b / "map.json")],
               "figures": lambda b: ["figures", "--only", "speed", "--out", str(b / "fig"),
                                     "--json", "--map", str(b / "map.json")]}
    for reader, argv_of in readers.items():
        for path, how in subset:
            def change(d, path=path, replace=REPLACEMENTS[how]):
                holder = d
                for k in path:
                    holder = holder[k]
                return _set(d, path, replace(holder))
            P(f"{reader}-map-field-{'.'.join(path)}-{how}", argv_of, _map_allowed(path, how),
              setup=both(put("rows.csv", CSV_ROWS), mutated_map(change)))
        P(f"{reader}-map-V_over_U-all-7", argv_of, (0, 1, 2),
          setup=both(put("rows.csv", CSV_ROWS), mutated_map(lambda d: _set(
              d, ("columns", "V_over_U"), [7.0] * len(d["columns"]["V_over_U"])))))


# ------------------------------------------------------------------ builds and their maps

def map_of(box: Path) -> list:
    """``--map`` of the sandbox's map file."""
    return ["--map", str(box / "map.json")]


def _build_probes(P) -> None:
    # the maps map pack writes from builds of one point and of none, made by the tool
    for n in (1, 0):
        packed = lambda box, n=n: shutil.copy(F.build(n) / "solution_map.json",
                                              box / "map.json")
        P(f"map-query-{n}-point-map-on-node",
          lambda b: ["map", "query", "--nu", "0.9", "--lam-ratio", "0.95", "--ca-b", "50",
                     "--json", *map_of(b)], (0, 2), setup=packed)
        P(f"map-query-{n}-point-map-off-node", lambda b: QUERY + map_of(b), (0, 2),
          setup=packed)
        P(f"infer-{n}-point-map", lambda b: INFER + map_of(b), (2,), setup=packed)
        P(f"check-{n}-point-map", lambda b: ["check", str(b / "rows.csv"), "--no-bem",
                                             "--json", *map_of(b)], (0, 1, 2),
          setup=both(put("rows.csv", CSV_ROWS), packed))
        P(f"figures-{n}-point-map", lambda b: ["figures", "--only", "speed", "--out",
                                               str(b / "fig"), "--json", *map_of(b)], (2,),
          setup=packed)
        P(f"map-pack-{n}-point-build", lambda b: ["map", "pack", str(b / "build"), "--json"],
          (0,) if n else (0, 2), setup=copy_build(n), may_change=BUILD_OUTPUTS[1:])
    # build folders that are not builds
    pack = lambda b: ["map", "pack", str(b / "build"), "--json"]
    resume = lambda b: ["map", "build", "--out", str(b / "build"), "--workers", "1",
                        "--json"]
    P("map-pack-empty-folder", pack, (2,), setup=mkdirs("build"))
    P("map-pack-folder-without-build-json", pack, (2,),
      setup=both(copy_build(1), lambda box: (box / "build" / "build.json").unlink()))
    P("map-pack-a-file", pack, (2,), setup=put("build", "not a folder\n"))
    P("map-pack-missing-folder", pack, (2,))
    P("map-build-into-folder-of-user-files", lambda b: ["map", "build", "--out",
                                                        str(b / "build"), *GRID, "--json"],
      (0,), setup=mkdirs("build"))
    # build.json of wrong types: pack (2), resume with the stored grid (2)
    def bj(change):
        def setup(box):
            copy_build(1)(box)
            path = box / "build" / "build.json"
            path.write_text(json.dumps(change(json.loads(path.read_text()))))
        return setup
    wrong = {
        "grid-string": lambda d: _set(d, ("grid",), "x"),
        "grid-null": lambda d: _set(d, ("grid",), None),
        "no-grid": lambda d: {k: v for k, v in d.items() if k != "grid"},
        "methods-string": lambda d: _set(d, ("grid", "methods"), "lubrication"),
        "methods-unknown": lambda d: _set(d, ("grid", "methods"), ["magic"]),
        "methods-empty": lambda d: _set(d, ("grid", "methods"), []),
        "nu-string": lambda d: _set(d, ("grid", "nu"), "0.9"),
        "nu-bool": lambda d: _set(d, ("grid", "nu"), [True]),
        "nu-empty": lambda d: _set(d, ("grid", "nu"), []),
        "nu-7": lambda d: _set(d, ("grid", "nu"), [7]),
        "ca_b-negative": lambda d: _set(d, ("grid", "ca_b"), [-1]),
        "lam_ratio-list": lambda d: _set(d, ("grid", "lam_ratio"), [0.95]),
        "lam_ratio-string": lambda d: _set(d, ("grid", "lam_ratio", "lubrication"), "x"),
        "lam_ratio-1.5": lambda d: _set(d, ("grid", "lam_ratio", "lubrication"), [1.5]),
        "parameters-string": lambda d: _set(d, ("parameters",), "x"),
        "provenance-list": lambda d: _set(d, ("provenance",), [1, 2]),
        "top-level-list": lambda d: [d],
    }
    for name, change in wrong.items():
        informative = name in ("parameters-string", "provenance-list")
        P(f"map-pack-build-json-{name}", pack, (0, 2) if informative else (2,),
          setup=bj(change), may_change=BUILD_OUTPUTS[1:])
        P(f"map-build-resume-build-json-{name}", resume,
          (0, 2) if name == "provenance-list" else (2,), setup=bj(change),
          may_change=BUILD_OUTPUTS)
    # point files: impossible values must not become nodes silently; wrong types refused
    def pt(change=None, raw=None, special=None):
        def setup(box):
            copy_build(1)(box)
            path = box / "build" / POINT
            if special is not None:
                path.unlink()
                _make_special(special, path)
            elif raw is not None:
                path.write_bytes(raw(path.read_bytes()))
            else:
                path.write_text(json.dumps(change(json.loads(path.read_text()))))
        return setup
    impossible = {"V_over_U": 7.0, "film_min": -0.1, "dp_plus_R0": -5.0, "ell": -2.0,
                  "nu": 7.0, "lam_ratio": 1.5, "ca_b": -1.0}
    for column, value in impossible.items():
        P(f"map-pack-point-{column}-{value:g}", pack, (0, 1, 2),
          setup=pt(lambda d, c=column, v=value: _set(d, (c,), v)),
          may_change=BUILD_OUTPUTS[1:], post=not_packed(column, value))
    P("map-build-resume-point-V_over_U-7", resume, (0, 1, 2),
      setup=pt(lambda d: _set(d, ("V_over_U",), 7.0)), may_change=BUILD_OUTPUTS,
      post=not_packed("V_over_U", 7.0))
    types = {"nu-string": ("nu", "0.9"), "success-string": ("success", "yes"),
             "success-null": ("success", None), "V_over_U-string": ("V_over_U", "1.05"),
             "V_over_U-bool": ("V_over_U", True), "method-number": ("method", 5),
             "status-unknown": ("status", "bogus"), "format-other": ("format", "x"),
             "error_estimate-string": ("error_estimate", "x"), "shape_class-number":
             ("shape_class", 3)}
    for name, (column, value) in types.items():
        P(f"map-pack-point-{name}", pack, (2,),
          setup=pt(lambda d, c=column, v=value: _set(d, (c,), v)),
          may_change=BUILD_OUTPUTS[1:])
    P("map-pack-point-without-nu", pack, (2,),
      setup=pt(lambda d: {k: v for k, v in d.items() if k != "nu"}),
      may_change=BUILD_OUTPUTS[1:])
    raws = {"truncated": lambda b: b[:len(b) // 2], "empty": lambda b: b"",
            "nested-1e5-deep": lambda b: b"[" * 10**5 + b"]" * 10**5,
            "int-5000-digits": lambda b: _with_literal(b, "point", BIG),
            "NaN-literal": lambda b: _with_literal(b, "point", "NaN"),
            "utf-16": lambda b: b.decode().encode("utf-16"), "binary": lambda b: BINARY}
    for name, raw in raws.items():
        P(f"map-pack-point-{name}", pack, (2,), setup=pt(raw=raw), may_change=BUILD_OUTPUTS[1:])
    for special in ("folder", "fifo", "dev-zero"):
        P(f"map-pack-point-{special}", pack, (2,), setup=pt(special=special),
          may_change=BUILD_OUTPUTS[1:])
    for name, setup in (("truncated", pt(raw=raws["truncated"])), ("fifo", pt(special="fifo")),
                        ("folder", pt(special="folder")),
                        ("success-string", pt(lambda d: _set(d, ("success",), "yes")))):
        P(f"map-build-resume-point-{name}", resume, (2,), setup=setup, may_change=BUILD_OUTPUTS)


# ------------------------------------------------------------------ outputs

def _long_name(box: Path, ext: str) -> str:
    return str(box / ("n" * (NAME_MAX + 1) + ext))


def _long_path(box: Path, leaf: str) -> str:
    parts = ["d" * 200] * (PATH_MAX // 200 + 1)
    return str(box.joinpath(*parts, leaf))


PLOTTERS = {
    "estimate": lambda f: ["estimate", "--plot", f, "--json"],
    "viscosity": lambda f: ["viscosity", "--diameter-um", "6", "--hematocrit", "0.45", "--plot",
                            f, "--json"],
    "lubrication": lambda f: ["lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--plot", f,
                              "--json"],
    "bem-sphere": lambda f: ["bem", "sphere", "--lam", "0.5", "--plot", f, "--json"],
    "bem-drop": lambda f: ["bem", "drop", "--lam", "0.5", "--ca", "0.1", "--plot", f, "--json"],
    "bem-vesicle": lambda f: ["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--plot", f,
                              "--json"],
}

OUT_COMMANDS = {
    "lubrication": (lambda d: ["lubrication", "--nu", "0.9", "--lam-ratio", "0.99", "--out", d,
                               "--json"], 2),
    "lubrication-sweep": (lambda d: ["lubrication", "--nu", "0.9", "--sweep", "--from", "0.95",
                                     "--to", "0.99", "--points", "3", "--ca-b", "50", "--out",
                                     d, "--json"], 1),
    "bem-drop": (lambda d: ["bem", "drop", "--lam", "0.5", "--ca", "0.1", "--out", d, "--json"],
                 2),
    "bem-vesicle": (lambda d: ["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--out", d,
                               "--json"], 2),
    "figures": (lambda d: ["figures", "--only", "viscosity", "--out", d, "--json"], 3),
    "map-build": (lambda d: ["map", "build", "--out", d, *GRID, "--json"], 3),
}
# bounded at 20 s a point: only its refusals are probed (a sweep takes minutes)
SWEEP = lambda d: ["bem", "vesicle-sweep", "--nu", "0.9", "--lam-ratio", "0.5", "0.75", "3",
                   "--max-time", "20", "--out", d, "--json"]


def _output_probes(P) -> None:
    for name, argv_of in PLOTTERS.items():
        cases = {
            "name-over-NAME_MAX": (lambda b: _long_name(b, ".png"), (2,), None),
            "path-over-PATH_MAX": (lambda b: _long_path(b, "f.png"), (2,), None),
            "missing-folder": (lambda b: str(b / "no-such-folder" / "f.png"), (2,), None),
            "a-folder": (lambda b: str(b / "plots"), (2,), mkdirs("plots")),
            "a-folder-named-png": (lambda b: str(b / "f.png"), (2,), mkdirs("f.png")),
            "unknown-format": (lambda b: str(b / "f.xyz"), (2,), None),
            "empty-name": (lambda b: "", (2,), None),
            "trailing-slash": (lambda b: str(b / "f.png") + "/", (2,), None),
        }
        for case, (path_of, allowed, setup) in cases.items():
            P(f"{name}-plot-{case}", lambda b, a=argv_of, f=path_of: a(f(b)), allowed,
              setup=setup)
        P(f"{name}-plot-no-extension", lambda b, a=argv_of: a(str(b / "figure")), (0,),
          post=png_at("figure"))
        P(f"{name}-plot-overwrites-user-file", lambda b, a=argv_of: a(str(b / "old.png")), (0,),
          setup=put("old.png", b"old picture"), may_change=("old.png",), post=png_at("old.png"))
        P(f"{name}-plot-read-only-folder", lambda b, a=argv_of: a(str(b / "ro" / "f.png")),
          (2,), skip=ROOT_SKIP if AS_ROOT else "", setup=read_only("ro"))
    # check --report
    report = lambda f: ["check", "rows.csv", "--no-bem", "--json", "--report", f]
    rows = put("rows.csv", CSV_ROWS)
    for case, (path_of, allowed, setup, files) in {
            "md": (lambda b: str(b / "r.md"), (0, 1), rows, ("r.md", "r.png")),
            "html": (lambda b: str(b / "r.html"), (0, 1), rows, ("r.html",)),
            "no-extension": (lambda b: str(b / "report"), (2,), rows, ()),
            "unknown-format": (lambda b: str(b / "r.txt"), (2,), rows, ()),
            "name-over-NAME_MAX": (lambda b: _long_name(b, ".md"), (2,), rows, ()),
            "path-over-PATH_MAX": (lambda b: _long_path(b, "r.md"), (2,), rows, ()),
            "missing-folder": (lambda b: str(b / "no-such-folder" / "r.md"), (2,), rows, ()),
            "a-folder": (lambda b: str(b / "r.md"), (2,), both(rows, mkdirs("r.md")), ()),
            "figure-name-is-a-folder": (lambda b: str(b / "r.md"), NOT_WRITTEN,
                                        both(rows, mkdirs("r.png")), ()),
            "overwrites-user-files": (lambda b: str(b / "r.md"), (0, 1),
                                      both(rows, put("r.md", "mine"), put("r.png", b"mine")),
                                      ())}.items():
        P(f"check-report-{case}", lambda b, f=path_of: report(f(b)), allowed, setup=setup,
          may_change=("r.md", "r.png") if case == "overwrites-user-files" else (),
          files_of=files)
    P("check-report-read-only-folder", lambda b: report(str(b / "ro" / "r.md")), (2,),
      skip=ROOT_SKIP if AS_ROOT else "", setup=both(rows, read_only("ro")))
    # map pack --out
    pack = lambda f: lambda b: ["map", "pack", str(b / "build"), "--json", "--out", f(b)]
    for case, (path_of, allowed, extra, may) in {
            "new-file": (lambda b: str(b / "packed.json"), (0,), None, ()),
            "no-extension": (lambda b: str(b / "packed"), (0,), None, ()),
            "overwrites-user-file": (lambda b: str(b / "packed.json"), (0,),
                                     put("packed.json", "mine"), ("packed.json",)),
            "name-over-NAME_MAX": (lambda b: _long_name(b, ".json"), (2,), None, ()),
            "path-over-PATH_MAX": (lambda b: _long_path(b, "m.json"), (2,), None, ()),
            "missing-folder": (lambda b: str(b / "no-such-folder" / "m.json"), (2,), None, ()),
            "a-folder": (lambda b: str(b / "maps"), (2,), mkdirs("maps"), ()),
            "the-build-json": (lambda b: str(b / "build" / "build.json"), (2,), None, ()),
            "a-point-file": (lambda b: str(b / "build" / POINT), (2,), None, ()),
            "empty-name": (lambda b: "", (2,), None, ())}.items():
        setup = copy_build(1) if extra is None else both(copy_build(1), extra)
        P(f"map-pack-out-{case}", pack(path_of), allowed, setup=setup, may_change=may)
    P("map-pack-default-out-read-only-build", lambda b: ["map", "pack", str(b / "ro"), "--json"],
      (2,), skip=ROOT_SKIP if AS_ROOT else "", setup=both(copy_build(1, "ro"), read_only("ro")))
    # --out folders
    for name, (argv_of, n_written) in OUT_COMMANDS.items():
        cases = {
            "name-over-NAME_MAX": (lambda b: _long_name(b, ""), (2,), None, ()),
            "path-over-PATH_MAX": (lambda b: _long_path(b, "out"), (2,), None, ()),
            "a-file": (lambda b: str(b / "out"), (2,), put("out", "the user's file\n"), ()),
            "a-fifo": (lambda b: str(b / "out"), (2,), fifo("out"), ()),
            "empty-name": (lambda b: "", (2,), None, ()),
            "missing-parents": (lambda b: str(b / "a" / "b" / "out"), (0,), None, ()),
            "existing-folder-with-user-files": (lambda b: str(b / "out"), (0,), both(
                mkdirs("out"), put("out/.notes.tmp", "mine\n")), ()),
        }
        for case, (path_of, allowed, setup, may) in cases.items():
            P(f"{name}-out-{case}", lambda b, a=argv_of, f=path_of: a(f(b)), allowed,
              setup=setup, may_change=may)
        for k in range(n_written):
            P(f"{name}-out-written-name-{k + 1}-is-a-folder",
              lambda b, a=argv_of: a(str(b / "out")), NOT_WRITTEN,
              setup=written_as_folder(name, argv_of, k))
        P(f"{name}-out-read-only-folder", lambda b, a=argv_of: a(str(b / "ro" / "out")), (2,),
          skip=ROOT_SKIP if AS_ROOT else "", setup=read_only("ro"))
    P("figures-out-cache-is-a-file", lambda b: OUT_COMMANDS["figures"][0](str(b / "out")),
      NOT_WRITTEN,
      setup=put("out/cache", "the user's file\n"))
    for case, (path_of, setup) in {"name-over-NAME_MAX": (lambda b: _long_name(b, ""), None),
                                   "path-over-PATH_MAX": (lambda b: _long_path(b, "out"), None),
                                   "a-file": (lambda b: str(b / "out"), put("out", "mine\n")),
                                   "a-fifo": (lambda b: str(b / "out"), fifo("out"))}.items():
        P(f"bem-vesicle-sweep-out-{case}", lambda b, f=path_of: SWEEP(f(b)), (2,), setup=setup)


def written_as_folder(name: str, argv_of, k: int):
    """Setup: the folder ``out`` in which the ``k``-th name the command writes (found by a
    run of it, :meth:`Fixtures.written`) exists as a folder of the user."""
    def setup(box: Path):
        names = F.written(name, argv_of)
        target = box / "out" / names[k]
        target.mkdir(parents=True)
        (target / "user-file.txt").write_text("the user's\n")
    return setup


def read_only(rel: str):
    """Setup: ``rel`` a folder without write permission."""
    def setup(box: Path):
        (box / rel).mkdir(exist_ok=True)
        (box / rel).chmod(0o555)
    return setup


# ------------------------------------------------------------------ stdout and encodings

def _stream_probes(P) -> None:
    full = {"stdout": "/dev/full"}
    for slug, argv_of, setup in (
            ("estimate", lambda b: ["estimate", "--json"], None),
            ("geometry-table", lambda b: ["geometry", "--nu", "0.6", "--lam", "1.9"], None),
            ("map-query", lambda b: QUERY, None),
            ("check", lambda b: ["check", "rows.csv", "--no-bem", "--json"],
             put("rows.csv", CSV_ROWS)),
            ("infer", lambda b: INFER, None),
            ("lubrication-out", lambda b: ["lubrication", "--nu", "0.9", "--lam-ratio", "0.99",
                                           "--out", str(b / "out"), "--json"], None),
            ("map-build", lambda b: ["map", "build", "--out", str(b / "build"), *GRID,
                                     "--json"], None)):
        P(f"{slug}-stdout-dev-full", argv_of, (1,), setup=setup, **full)
    ascii_env = {"env": {"PYTHONIOENCODING": "ascii"}}
    rows = put("résultats.csv", CSV_ROWS)
    carte = lambda box: shutil.copy(SHIPPED_MAP, box / "carte-é.json")
    for slug, argv_of, allowed, setup in (
            ("check-json", lambda b: ["check", "résultats.csv", "--no-bem", "--json"], (0, 1),
             rows),
            ("check-table", lambda b: ["check", "résultats.csv", "--no-bem"], (0, 1), rows),
            ("check-missing-file", lambda b: ["check", "manquant-é.csv"], (2,), None),
            ("map-query-json", lambda b: QUERY + ["--map", "carte-é.json"], (0,), carte),
            ("map-query-table", lambda b: QUERY[:-1] + ["--map", "carte-é.json"], (0,), carte),
            ("map-query-missing-map", lambda b: QUERY + ["--map", "manquant-é.json"], (2,),
             None),
            ("infer-table", lambda b: INFER[:-1] + ["--map", "carte-é.json"], (0, 1), carte),
            ("estimate-table", lambda b: ["estimate"], (0,), None),
            ("estimate-plot", lambda b: ["estimate", "--plot", "é.png"], (0,), None),
            ("lubrication-out", lambda b: ["lubrication", "--nu", "0.9", "--lam-ratio", "0.99",
                                           "--out", "dossier-é", "--json"], (0,), None),
            ("figures-table", lambda b: ["figures", "--only", "viscosity", "--out",
                                         "figures-é"], (0,), None),
            ("map-build-table", lambda b: ["map", "build", "--out", "construit-é", *GRID], (0,),
             None),
            ("map-pack-table", lambda b: ["map", "pack", "construit-é"], (0,),
             copy_build(1, "construit-é"))):
        P(f"{slug}-PYTHONIOENCODING-ascii", argv_of, allowed, setup=setup,
          may_change=("construit-é/solution_map.json",), **ascii_env)


# ------------------------------------------------------------------ map build

def _map_build_probes(P) -> None:
    out = lambda b: ["map", "build", "--out", str(b / "build")]
    lub = ["--methods", "lubrication", "--lam-ratio", "0.95", "--ca-b", "50", "--workers", "1",
           "--json"]
    bem = ["--methods", "bem", "--nu", "0.9", "--lam-ratio", "0.5", "--ca-b", "50",
           "--workers", "1", "--max-time", "10", "--json"]
    P("map-build-nu-0.05-lubrication", lambda b: out(b) + ["--nu", "0.05"] + lub, (0, 2))
    P("map-build-nu-0.05-bem", lambda b: out(b) + bem + ["--nu", "0.05"], (0, 1, 2))
    P("map-build-ca-b-1e7-lubrication", lambda b: out(b) + ["--nu", "0.9"] + lub
      + ["--ca-b", "1e7"], (0, 1, 2))
    P("map-build-ca-b-1e7-bem", lambda b: out(b) + bem + ["--ca-b", "1e7"], (0, 1, 2))
    for option, value in (("--bem-tol", "-1"), ("--bem-tol", "0"), ("--bem-tol", "1e308"),
                          ("--bem-residual-tol", "-1"), ("--bem-n-modes", "100000"),
                          ("--bem-max-modes", "100000")):
        P(f"map-build-{option[2:]}-{value}", lambda b, o=option, v=value: out(b) + bem + [o, v],
          (2,))
    for option, value in (("--lubrication-tol", "-1"), ("--lubrication-tol", "0"),
                          ("--max-time", "0"), ("--max-time", "-1"), ("--workers", BIG),
                          ("--nu", "1"), ("--lam-ratio", "1"), ("--lam-ratio", "0"),
                          ("--ca-b", "0"), ("--scheduler", "tcp://127.0.0.1:9")):
        P(f"map-build-{option[2:]}-{value[:12]}",
          lambda b, o=option, v=value: out(b) + ["--nu", "0.9"] + lub + [o, v], (2,))
    P("map-build-max-time-0.001", lambda b: out(b) + ["--nu", "0.9"] + lub
      + ["--max-time", "0.001"], (1,))
    # resume, extend, retry: the stored points are kept
    resume = lambda b, *more: out(b) + [*GRID, "--json", *more]
    P("map-build-resume-complete", lambda b: resume(b), (0,), setup=copy_build(1),
      may_change=BUILD_OUTPUTS, post=new_points(0))
    P("map-build-extend-grid", lambda b: out(b) + ["--methods", "lubrication", "--nu", "0.9",
                                                   "--lam-ratio", "0.95", "0.97", "--ca-b",
                                                   "50", "--workers", "1", "--json"], (0,),
      setup=copy_build(1), may_change=BUILD_OUTPUTS, post=new_points(1))
    P("map-build-other-options", lambda b: resume(b, "--lubrication-tol", "1e-6"), (2,),
      setup=copy_build(1), may_change=BUILD_OUTPUTS)
    P("map-build-retry-failed", lambda b: out(b) + [*GRID, "--json", "--retry-failed"], (0,),
      setup=copy_build(0), may_change=BUILD_OUTPUTS + (f"build/{POINT}",), post=new_points(1))
    # the user's temporaries in the build folder survive
    for name in (".something.tmp", ".notes.tmp", ".build.json.old.tmp", f".{POINT}.mine.tmp"):
        P(f"map-build-keeps-user-{name}", lambda b: out(b) + [*GRID, "--json"], (0,),
          setup=put(f"build/{name}", "the user's draft\n"))
        P(f"map-build-resume-keeps-user-{name}", lambda b: out(b) + [*GRID, "--json"], (0,),
          setup=both(copy_build(1), put(f"build/{name}", "the user's draft\n")),
          may_change=BUILD_OUTPUTS)
    # two builds at once into one folder; resume after an interrupted build
    ratios = ["0.9", "0.93", "0.96", "0.99"]
    line = ["--methods", "lubrication", "--nu", "0.9", "--lam-ratio", *ratios, "--ca-b", "50",
            "--json"]
    P("map-build-twice-at-once", lambda b: out(b) + line + ["--workers", "1"], (0, 2),
      run=two_builds(len(ratios)), may_change=BUILD_OUTPUTS + ("build/*.json",))
    many = ["0.9", "0.92", "0.94", "0.96", "0.98", "0.99"]
    for sig, workers, stale, nus in (
            (signal.SIGINT, "1", "", ["0.9"]),
            (signal.SIGINT, "2", "", ["0.85", "0.9"]),
            (signal.SIGKILL, "1", ".lubrication_nu0.9_lr0.99_caB50.json.k3x9a2bq.tmp",
             ["0.9"])):
        argv = ["--methods", "lubrication", "--nu", *nus, "--lam-ratio", *many, "--ca-b", "50",
                "--workers", workers, "--json"]
        P(f"map-build-resume-after-{signal.Signals(sig).name}-workers-{workers}",
          lambda b, a=argv: out(b) + a, (0,),
          run=interrupted(sig, len(many) * len(nus), stale),
          may_change=BUILD_OUTPUTS + ("build/*.json",))


# ------------------------------------------------------------------ bounded work, CSV content

def _rows_csv(n: int) -> str:
    lines = [CSV_HEADER] + [f"r{i},{0.6 + 0.35 * (i % 997) / 997:.5f},"
                            f"{0.5 + 0.5 * (i % 991) / 991:.5f},{5 + i % 400},1.2,10.5"
                            for i in range(n)]
    return "\n".join(lines) + "\n"


def _bounded_probes(P) -> None:
    infer = lambda s: INFER + ["--samples", s]
    for value in (str(10**9), "1" + "0" * 30, BIG, "1e3", "2001"):
        P(f"infer-samples-{value[:12]}", infer(value), (2,))
    P("check-1e5-rows", lambda b: ["check", "big.csv", "--no-bem", "--json"], (0, 1, 2),
      setup=put("big.csv", lambda: _rows_csv(10**5)))
    ten_mb = 10 * 2**20
    for slug, text in (
            ("csv-one-10MB-line-no-newline", lambda: "nu" + ",x" * (ten_mb // 2)),
            ("csv-one-10MB-cell", lambda: f"{CSV_HEADER}\nmine,0.{'1' * ten_mb},1.0,50,1.2,13\n"),
            ("csv-one-10MB-header-name", lambda: "n" * ten_mb + "\n1\n"),
            ("csv-header-only", CSV_HEADER + "\n"),
            ("csv-header-and-blank-lines", CSV_HEADER + "\n\n\n  \n"),
            ("csv-semicolons", CSV_ROWS.replace(",", ";")),
            ("csv-NUL-in-a-number", CSV_ROWS.replace("0.9,", "0.9\0,")),
            ("csv-5000-digit-cell", f"{CSV_HEADER}\n{CSV_ROW.format(v=BIG)}\n"),
            ("csv-1e999-cell", f"{CSV_HEADER}\n{CSV_ROW.format(v='1e999')}\n"),
            ("csv-1e5-columns", ",".join(f"c{i}" for i in range(10**5)) + "\n"
             + ",".join("1" for _ in range(10**5)) + "\n"),
            ("csv-latin-1", CSV_ROWS.replace("mine", "été").encode("latin-1"))):
        P(f"check-{slug}", lambda b: ["check", "in.csv", "--no-bem", "--json"], (2,),
          setup=put("in.csv", text))


# ------------------------------------------------------------------ all

def probes(root: Path) -> list[Probe]:
    """The file probes, each with its sandbox folder under ``root`` (made at run time); the
    shared inputs are made under ``root/_fixtures`` when a probe first needs them."""
    global F
    F = Fixtures(root / "_fixtures")
    P = _Maker(root)
    _input_probes(P)
    _map_probes(P)
    _build_probes(P)
    _output_probes(P)
    _stream_probes(P)
    _map_build_probes(P)
    _bounded_probes(P)
    return P.probes
