"""The readers of map files and build folders (correlations/solution_map.py through
correlations/files.py): every malformed input is refused with exit 2 and one line naming the
option and the file, an unphysical point never becomes a map node, and whatever our own
``map build`` and ``map pack`` write is accepted by every reader.

Contract (correlations/cli/contract.py): exit 0 ok, 1 not converged or inconsistent, 2 invalid
input with one line on stderr naming the option; never a traceback. The builds here run
``map_build.build_map`` itself (the module's own writers of build.json and point files) with
the solvers replaced by a fake that returns plausible converged values: no BEM is run.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import tempfile
from pathlib import Path
from unittest import mock

import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from cli_helpers import strict_json
from lubrication.geometry import critical_confinement
from correlations import map_build
from correlations.cli import main
from correlations.estimate import estimate_dimensionless
from correlations.files import UnreadableFile
from correlations.solution_map import QUANTITIES, load_map, pack_map, point_filename, read_points

FAILED = "failed"          # what the fake solver makes of a point (default: converged)


def _values(nu, r) -> dict:
    """Plausible converged quantities at (nu, lam/lam_c): V/U = 1 + O(delta) inside [1, 2],
    film ~ delta / 2, dp+ ~ lam^6 / delta (the map's scalings), positive tensions."""
    d = 1.0 - r
    return {"V_over_U": 1.0 + 0.8 * d * (0.7 + 0.3 * nu), "dp_plus_R0": 5.0 * r**6 / d,
            "ell": 2.0 + 3.0 * r, "film_min": 0.5 * d, "tension_max": d**-1.5,
            "tension_front": 0.5 * d**-1.5, "wall_shear_max": 4.0 + 1.0 / d,
            "curvature_rear": -1.0 + nu * r}


def _fake_solver(outcome: dict):
    """A point solver for ``map_build.SOLVERS``: ``outcome[(nu, r, ca)]`` is FAILED, a dict of
    quantities overriding the plausible ones, or absent (converged, plausible)."""
    def solve(nu, lam_ratio, ca_b, warm, options, max_time):
        what = outcome.get((nu, lam_ratio, ca_b))
        if what == FAILED:
            return {"success": False, "status": "not converged", "message": "fake: diverged",
                    **dict.fromkeys(QUANTITIES), "shape_class": None,
                    "error_estimate": dict.fromkeys(QUANTITIES), "shape": None}, None
        lam_c = float(critical_confinement(nu))
        q = {**_values(nu, lam_ratio), **(what or {})}
        return {"lam": lam_ratio * lam_c, "lam_c": lam_c, "success": True,
                "status": "converged", "message": "converged", **q,
                "shape_class": "bullet" if nu > 0.75 else "parachute",
                "error_estimate": {k: 1e-6 for k in QUANTITIES}, "residual": 1e-7,
                "bie_solves": 3, "seed": "fake",
                "shape": {"modes": [0.1, 0.01], "density": [1.0]}}, None
    return solve


def build(folder, nus, ratios, cas, methods=("bem",), outcome=None) -> Path:
    """``map build`` of a tiny grid in this process (fake solver), packed; the map's path."""
    solve = _fake_solver(outcome or {})
    grid = map_build.make_grid(nus, ratios, cas, list(methods))
    with mock.patch.dict(map_build.SOLVERS, {"bem": solve, "lubrication": solve}):
        return Path(map_build.build_map(folder, grid, workers=1)["map"])


def run(*argv) -> tuple[int, str, str]:
    """``vesicle-tube *argv`` in this process: (exit code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:
            code = exc.code
    return code, out.getvalue(), err.getvalue()


def refused(code, out, err, option) -> str:
    """The contract's exit 2: nothing on stdout, one line on stderr naming ``option``."""
    assert code == 2, (code, err)
    assert out == "" and "Traceback" not in err, err
    lines = err.strip("\n").splitlines()
    assert len(lines) == 1 and option in lines[0], err
    return lines[0]


@pytest.fixture(scope="module")
def good(tmp_path_factory) -> Path:
    """A valid packed map of 2 nu x 3 lam/lam_c x 2 Ca_B (BEM)."""
    return build(tmp_path_factory.mktemp("good"), [0.8, 0.9], [0.5, 0.8, 0.95], [15.0, 50.0])


# ----------------------------------------------------------------------------- unphysical points

def test_unphysical_points_are_holes_listed_as_rejected_and_never_nodes(tmp_path):
    """V/U = 7, a negative film and a non-finite V/U (written as null) stored as converged:
    pack keeps them out of the nodes (holes, reason "rejected: ...") and lists them with the
    bound they break (lubrication.checks.OUTPUT_BOUNDS)."""
    bad = {(0.8, 0.5, 50.0): {"V_over_U": 7.0}, (0.9, 0.8, 50.0): {"film_min": -0.01},
           (0.9, 0.5, 50.0): {"V_over_U": math.nan}}
    path = build(tmp_path / "b", [0.8, 0.9], [0.5, 0.8], [50.0], outcome=bad)
    data = json.loads(path.read_text())
    rejected = {(r["nu"], r["lam_ratio"]): r["reason"] for r in data["rejected"]}
    assert set(rejected) == {(0.8, 0.5), (0.9, 0.8), (0.9, 0.5)}
    assert "V_over_U = 7 outside 1 <= V_over_U <= 2" in rejected[0.8, 0.5]
    assert "film_min: film = -0.01 outside 0 <= film <= 1" in rejected[0.9, 0.8]
    assert "V_over_U = None is not a finite number" in rejected[0.9, 0.5]
    assert len(data["columns"]["nu"]) == 1                      # only (0.8, 0.8) is a node
    holes = {(h["nu"], h["lam_ratio"]): h["reason"] for h in data["holes"]}
    assert holes[0.8, 0.5].startswith("rejected: V_over_U = 7")
    q = run("map", "query", "--nu", 0.8, "--lam-ratio", 0.5, "--ca-b", 50, "--map", path,
            "--json")
    assert q[0] == 0 and strict_json(q[1])["V_over_U"] is None
    assert "rejected: V_over_U = 7" in strict_json(q[1])["quantities"]["V_over_U"]["note"]


def _edit_columns(path: Path, column: str, row: int, value) -> None:
    data = json.loads(path.read_text())
    data["columns"][column][row] = value
    path.write_text(json.dumps(data))


@pytest.mark.parametrize("column, value, words", [
    ("V_over_U", 7.0, "V_over_U = 7 outside 1 <= V_over_U <= 2"),
    ("film_min", -0.1, "film = -0.1 outside 0 <= film <= 1"),
    ("dp_plus_R0", -3.0, "dp_plus_R0 = -3 outside dp_plus_R0 >= 0"),
])
def test_a_packed_map_with_an_unphysical_node_is_refused_naming_map(good, tmp_path, column,
                                                                   value, words):
    path = tmp_path / "edited.json"
    path.write_text(good.read_text())
    _edit_columns(path, column, 2, value)
    line = refused(*run("map", "query", "--nu", 0.8, "--lam-ratio", 0.5, "--ca-b", 50,
                        "--map", path), "--map")
    assert str(path) in line and "unphysical" in line and words in line


# ----------------------------------------------------------------------------- malformed maps

def _text(good: Path) -> str:
    return good.read_text()


def _replace(old: str, new: str):
    def make(good, path):
        text = _text(good)
        assert old in text
        path.write_text(text.replace(old, new, 1))
        return path
    return make


def _json_edit(edit):
    def make(good, path):
        data = json.loads(_text(good))
        edit(data)
        path.write_text(json.dumps(data))
        return path
    return make


def _fifo(good, path):
    os.mkfifo(path)
    return path


def _set(*keys_value):
    *keys, value = keys_value

    def edit(data):
        d = data
        for k in keys[:-1]:
            d = d[k]
        d[keys[-1]] = value
    return edit


#: (case, how the file is made, words the message must hold); measured in the report
MALFORMED_MAPS = [
    ("nu column holds text", _json_edit(_set("columns", "nu", 0, "0.8")), "column 'nu', row 0"),
    ("V/U true (a bool is no number)", _json_edit(_set("columns", "V_over_U", 0, True)),
     "column 'V_over_U'"),
    ("error column holds a list", _json_edit(_set("columns", "err_V_over_U", 1, [1e-6])),
     "column 'err_V_over_U'"),
    ("version as text", _json_edit(_set("version", "1")), "map format version '1'"),
    ("unknown method", _json_edit(_set("columns", "method", 0, "fem")), "column 'method'"),
    ("shape class 5", _json_edit(_set("columns", "shape_class", 0, 5)), "column 'shape_class'"),
    ("grid repeats a nu", _json_edit(_set("grid", "nu", [0.8, 0.8])), "'grid.nu' repeats"),
    ("grid Ca_B negative", _json_edit(_set("grid", "ca_b", [-15.0, 50.0])), "'grid.ca_b'"),
    ("grid lam_ratio 1.5", _json_edit(_set("grid", "lam_ratio", "bem", [0.5, 1.5])),
     "'grid.lam_ratio.bem'"),
    ("grid methods a string", _json_edit(_set("grid", "methods", "bem")), "'grid.methods'"),
    ("hole without reason", _json_edit(lambda d: d["holes"].append({"method": "bem"})),
     "hole 0"),
    ("columns of unequal length", _json_edit(lambda d: d["columns"]["nu"].pop()),
     "unequal length"),
    ("no node (all holes)", _json_edit(lambda d: d["columns"].update(
        {k: [] for k in d["columns"]})), "the map has no node"),
    ("5000-digit integer", _replace('"ca_b":[15.0', '"ca_b":[1' + "0" * 5000), "5001 digits"),
    ("1e999 (overflows)", _replace('"ca_b":[15.0', '"ca_b":[1e999'), "1e999 overflows a double"),
    ("NaN literal", _replace('"ca_b":[15.0', '"ca_b":[NaN'), "NaN is not strict JSON"),
    ("nested 100 deep", lambda g, p: (p.write_text("[" * 100 + "]" * 100), p)[1],
     "nested 100 levels"),
    ("truncated", lambda g, p: (p.write_text(_text(g)[:1000]), p)[1], "not valid JSON"),
    ("not UTF-8", lambda g, p: (p.write_bytes(b'{"format": "\xff"}'), p)[1], "not UTF-8"),
    ("empty file", lambda g, p: (p.write_text(""), p)[1], "not valid JSON"),
    ("a list, not an object", lambda g, p: (p.write_text("[1, 2]"), p)[1], "no 'format'"),
    ("FIFO", _fifo, "not a regular file"),
    ("/dev/zero", lambda g, p: Path("/dev/zero"), "not a regular file"),
    ("a folder", lambda g, p: (p.mkdir(), p)[1], "this is a folder"),
    ("missing", lambda g, p: p, "no such file"),
    ("over-long path", lambda g, p: Path("/tmp/" + "a" * 5000), "file name too long"),
]


@pytest.mark.parametrize("case, make, words", MALFORMED_MAPS, ids=[c[0] for c in MALFORMED_MAPS])
def test_a_malformed_map_exits_2_naming_map_and_the_file(good, tmp_path, case, make, words):
    path = make(good, tmp_path / "bad.json")
    line = refused(*run("map", "query", "--nu", 0.8, "--lam-ratio", 0.5, "--ca-b", 50,
                        "--map", path), "--map")
    assert words in line, line
    assert (str(path) if len(str(path)) < 120 else "(5005 characters)") in line


@pytest.mark.parametrize("argv", [
    ("infer", "--v-over-u", 1.3, "--length-um", 8, "--diameter-um", 6, "--u-mm-s", 1),
    ("figures", "--out", "{out}", "--only", "speed"),
    ("check", "{rows}", "--no-bem"),
], ids=["infer", "figures", "check"])
@pytest.mark.parametrize("case", ["5000-digit integer", "FIFO", "V/U true (a bool is no number)"])
def test_every_map_reader_refuses_a_malformed_map_the_same_way(good, tmp_path, argv, case):
    make, words = next((m, w) for c, m, w in MALFORMED_MAPS if c == case)
    path = make(good, tmp_path / "bad.json")
    rows = tmp_path / "rows.json"
    rows.write_text(json.dumps([{"name": "a", "kind": "vesicle", "nu": 0.9, "lam": 1.0,
                                 "ca_b": 50, "V_over_U": 1.3, "dp_plus_R0": 2.0,
                                 "ell": 3.0}]))
    argv = [str(a).format(out=tmp_path / "figs", rows=rows) for a in argv]
    line = refused(*run(*argv, "--map", path), "--map")
    assert words in line and str(path) in line
    assert not (tmp_path / "figs").exists()
    with pytest.raises(UnreadableFile, match="map"):
        estimate_dimensionless(0.9, 1.0, 50.0, solution_map=path)


# ----------------------------------------------------------------------------- build folders

def _point_edit(edit):
    """A build folder whose point (0.8, 0.5, 15) is edited by ``edit(text) -> text``."""
    def make(folder):
        p = folder / point_filename("bem", 0.8, 0.5, 15.0)
        p.write_text(edit(p.read_text()))
        return p
    return make


def _point_field(key, value):
    def edit(text):
        data = json.loads(text)
        data[key] = value
        return json.dumps(data)
    return _point_edit(edit)


def _build_json(edit):
    def make(folder):
        p = folder / "build.json"
        data = json.loads(p.read_text())
        edit(data)
        p.write_text(json.dumps(data))
        return p
    return make


def _point_fifo(folder):
    p = folder / point_filename("bem", 0.8, 0.5, 15.0)
    p.unlink()
    os.mkfifo(p)
    return p


MALFORMED_FOLDERS = [
    ("nu as text", _point_field("nu", "0.8"), "the field 'nu' is '0.8'"),
    ("success as text", _point_field("success", "yes"), "the field 'success'"),
    ("unknown status", _point_field("status", "done"), "the field 'status'"),
    ("success contradicts status", _point_field("status", "time limit"), "contradicts"),
    ("V/U as a list", _point_field("V_over_U", [1.2]), "the field 'V_over_U'"),
    ("shape without modes", _point_field("shape", {"density": []}), "'shape'"),
    ("error estimate as text", _point_field("error_estimate", {"V_over_U": "small"}),
     "'error_estimate.V_over_U'"),
    ("no method", _point_edit(lambda t: json.dumps({k: v for k, v in json.loads(t).items()
                                                    if k != "method"})), "without 'method'"),
    ("5000-digit integer", _point_edit(lambda t: t.replace('"bie_solves": 3',
                                                           '"bie_solves": ' + "9" * 5000)),
     "5000 digits"),
    ("nested 100 deep", _point_edit(lambda t: "[" * 100 + "]" * 100), "nested 100 levels"),
    ("truncated", _point_edit(lambda t: t[:200]), "not valid JSON"),
    ("FIFO named like a point", _point_fifo, "not a regular file"),
    ("build.json: unknown method", _build_json(_set("grid", "methods", ["fem"])),
     "'grid.methods'"),
    ("build.json: nu as text", _build_json(_set("grid", "nu", ["0.8", 0.9])), "'grid.nu'"),
    ("build.json: no grid", _build_json(lambda d: d.pop("grid")), "no 'grid' object"),
    ("build.json: a list", lambda f: ((f / "build.json").write_text("[]"), f / "build.json")[1],
     "not a JSON object"),
]


@pytest.mark.parametrize("case, make, words", MALFORMED_FOLDERS,
                         ids=[c[0] for c in MALFORMED_FOLDERS])
def test_a_malformed_build_folder_is_refused_naming_the_folder_and_the_file(
        tmp_path, case, make, words):
    folder = tmp_path / "b"
    build(folder, [0.8, 0.9], [0.5], [15.0])
    (folder / "solution_map.json").unlink()
    bad = make(folder)
    with pytest.raises(UnreadableFile) as info:
        pack_map(folder)
    assert info.value.name == "folder" and words in str(info.value)
    line = refused(*run("map", "pack", folder), "DIR")
    assert words in line and str(bad) in line
    assert not (folder / "solution_map.json").exists()          # refused before writing


# ----------------------------------------------------------------------------- our own maps

NUS, RATIOS, CAS = [0.6, 0.75, 0.9], [0.3, 0.6, 0.9, 0.98], [15.0, 50.0]


@st.composite
def tiny_builds(draw):
    """A tiny grid (1-3 nu, 1-4 lam/lam_c, 1-2 Ca_B, BEM or lubrication or both) and what
    became of each point: converged (plausible), failed, or unphysical (V/U = 2.5)."""
    sub = lambda values: st.lists(st.sampled_from(values), min_size=1, max_size=len(values),
                                  unique=True).map(sorted)
    nus, ratios, cas = draw(sub(NUS)), draw(sub(RATIOS)), draw(sub(CAS))
    methods = draw(st.sampled_from([("bem",), ("lubrication",), ("bem", "lubrication")]))
    points = [(nu, r, ca) for nu in nus for r in ratios for ca in cas]
    fate = st.sampled_from(["ok", "ok", FAILED, "unphysical"])
    outcome = {}
    for p in points:
        f = draw(fate)
        if f != "ok":
            outcome[p] = FAILED if f == FAILED else {"V_over_U": 2.5}
    return nus, ratios, cas, methods, outcome


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tiny_builds())
@example(([0.75], [0.6], [50.0], ("bem",), {}))                          # one point
@example(([0.75], [0.6, 0.9], [50.0], ("lubrication",), {}))              # two points, one nu
@example(([0.6, 0.9], [0.6], [15.0, 50.0], ("bem",), {}))                 # one lam_ratio
@example(([0.6, 0.9], [0.3, 0.98], [50.0], ("bem", "lubrication"), {}))   # one Ca_B
@example(([0.6, 0.9], [0.6], [50.0], ("bem",), {(0.6, 0.6, 50.0): FAILED,
                                                (0.9, 0.6, 50.0): FAILED}))  # all failed
@example(([0.6], [0.3], [50.0], ("bem",), {(0.6, 0.3, 50.0): {"V_over_U": 2.5}}))  # rejected
def test_a_map_of_our_own_build_and_pack_is_accepted_by_every_reader(case):
    """Every reader answers a map that our map build and map pack wrote (exit 0 or 1, strict
    JSON, finite numbers) or refuses it with exit 2 naming --map and what the map lacks (no
    node at all: every point failed or was rejected; fewer than two nu or lam/lam_c nodes for
    infer; the paper's nodes for figures)."""
    nus, ratios, cas, methods, outcome = case
    converged = [p for p in ((nu, r, ca) for nu in nus for r in ratios for ca in cas)
                 if p not in outcome]
    lacks = ("the map has no node", "at least two nu and two lam/lam_c", "this one lacks")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        path = build(tmp / "b", nus, ratios, cas, methods, outcome)
        assert len(read_points(tmp / "b")) == len(nus) * len(ratios) * len(cas) * len(methods)
        if not converged:
            with pytest.raises(UnreadableFile, match="the map has no node"):
                load_map(path)
        else:
            assert load_map(path).n == len(converged) * len(methods)
        nu, r, ca = converged[0] if converged else (nus[0], ratios[0], cas[0])
        lam = r * float(critical_confinement(nu))
        values = _values(nu, r)
        rows = tmp / "rows.json"
        rows.write_text(json.dumps([{"name": "node", "kind": "vesicle", "nu": nu, "lam": lam,
                                     "ca_b": ca, "V_over_U": values["V_over_U"],
                                     "dp_plus_R0": values["dp_plus_R0"],
                                     "ell": values["ell"]}]))
        commands = {
            "map query": ("map", "query", "--nu", nu, "--lam-ratio", r, "--ca-b", ca),
            "infer": ("infer", "--v-over-u", values["V_over_U"], "--length-um",
                      values["ell"] * 3.0, "--diameter-um", 6.0, "--u-mm-s", 1.0,
                      "--uncertainty", "linear"),
            "check": ("check", rows, "--no-bem"),
            "figures": ("figures", "--out", tmp / "figs", "--only", "speed"),
        }
        for name, argv in commands.items():
            code, out, err = run(*argv, "--map", path, "--json")
            if code == 2:
                line = refused(code, out, err, "--map")
                assert any(w in line for w in lacks), (name, line)
                assert converged or "the map has no node" in line, (name, line)
            else:
                assert code in (0, 1) and "Traceback" not in err, (name, code, err)
                result = strict_json(out)            # no NaN or Infinity anywhere
                if name == "map query":
                    assert code == 0 and 1.0 <= result["V_over_U"] <= 2.0
        if converged:
            e = estimate_dimensionless(nu, lam, ca, solution_map=path)
            assert e["V_over_U"] is None or 1.0 <= e["V_over_U"] <= 2.0
        else:
            with pytest.raises(UnreadableFile, match="map"):
                estimate_dimensionless(nu, lam, ca, solution_map=path)


def test_a_build_folder_without_point_files_packs_into_a_map_every_reader_refuses(tmp_path):
    """Packing 0 points (a build stopped before its first point): ``map pack`` refuses it with
    exit 2 naming DIR before writing; ``pack_map`` itself (which ``map build`` calls at its
    end, whatever its points gave, so that the build keeps its own exit status) writes the map
    of holes ("not computed"), and every reader refuses that with exit 2 naming --map and
    saying it has no node."""
    folder = tmp_path / "b"
    build(folder, [0.8, 0.9], [0.5], [50.0])
    for p in folder.glob("bem_*.json"):
        p.unlink()
    path = folder / "solution_map.json"
    path.unlink()
    line = refused(*run("map", "pack", folder), "DIR")
    assert "no converged point" in line and not path.exists()
    pack_map(folder)
    data = json.loads(path.read_text())
    assert data["columns"]["nu"] == [] and len(data["holes"]) == 2
    assert {h["reason"] for h in data["holes"]} == {"not computed"}
    for argv in (("map", "query", "--nu", 0.8, "--lam-ratio", 0.5, "--ca-b", 50),
                 ("infer", "--v-over-u", 1.3, "--length-um", 8, "--diameter-um", 6, "--u-mm-s",
                  1),
                 ("figures", "--out", tmp_path / "figs")):
        line = refused(*run(*argv, "--map", path), "--map")
        assert "the map has no node" in line and "2 holes" in line
