"""Result output (lubrication.io): strict JSON with non-finite numbers as null, atomic files,
provenance; and every result writer of the project following that one policy."""

import datetime
import errno
import json
import math
import os
import re
import tempfile

import numpy as np
import pytest
from hypothesis import given, strategies as st

import lubrication
from lubrication.io import (WriteError, atomic_write, clean_json, make_folder, path_limits,
                            provenance, save_result, written_files, write_json)
from lubrication.results import Status


def _strict(text: str):
    """Parse JSON refusing NaN, Infinity and -Infinity (what a strict reader does)."""
    def refuse(token):
        raise ValueError(f"non-standard JSON token {token}")
    return json.loads(text, parse_constant=refuse)


# ------------------------------------------------------------------ clean_json
def test_non_finite_numbers_become_null_at_any_depth_and_in_numpy_containers():
    data = {"nan": math.nan, "inf": math.inf, "-inf": -math.inf, "np_nan": np.float64("nan"),
            "finite": np.float32(0.5), "int": np.int64(7), "flag": np.bool_(False),
            "array": np.array([[1.0, np.inf], [np.nan, -2.0]]), "tuple": (1, math.nan),
            "nested": {"list": [{"x": -math.inf}]}, "text": "nan", "none": None}
    assert clean_json(data) == {
        "nan": None, "inf": None, "-inf": None, "np_nan": None, "finite": 0.5, "int": 7,
        "flag": False, "array": [[1.0, None], [None, -2.0]], "tuple": [1, None],
        "nested": {"list": [{"x": None}]}, "text": "nan", "none": None}
    assert type(clean_json(np.int64(7))) is int and type(clean_json(np.bool_(True))) is bool


_leaves = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10**6, 10**6),
                    st.booleans(), st.none(), st.text(max_size=5))
_trees = st.recursive(_leaves, lambda kids: st.lists(kids, max_size=4)
                      | st.dictionaries(st.text(max_size=4), kids, max_size=4), max_leaves=20)


def _same(written, original) -> bool:
    """``written`` is ``original`` with every non-finite float replaced by None."""
    if isinstance(original, float) and not math.isfinite(original):
        return written is None
    if isinstance(original, dict):
        return written.keys() == original.keys() and all(_same(written[k], v)
                                                         for k, v in original.items())
    if isinstance(original, list):
        return len(written) == len(original) and all(map(_same, written, original))
    return written == original and type(written) is type(original)


@given(tree=_trees)
def test_write_json_is_strict_and_keeps_every_finite_value_exactly(tree, tmp_path_factory):
    path = tmp_path_factory.mktemp("json") / "a.json"
    assert write_json(path, {"data": tree}) == path
    assert _same(_strict(path.read_text(encoding="utf-8"))["data"], tree)


def test_written_files_are_atomic_and_csv_cells_of_non_finite_numbers_are_empty(tmp_path):
    cols = (("x", "position [R]"), ("y", "value [-]"))
    prof = {"x": np.array([0.0, 0.1]), "y": np.array([np.nan, 1.0 / 3.0])}
    jpath, cpath = save_result(tmp_path, "r", {"a": math.inf}, cols, prof.__getitem__)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv", "r.json"]   # no temp files
    assert _strict(jpath.read_text()) == {"a": None, "profile_columns": dict(cols)}
    assert cpath.read_text().splitlines() == ["x,y", "0.0,", f"0.1,{1.0 / 3.0!r}"]


# ------------------------------------------------------------------ failed writes
def _raise(number):
    def failing(*args, **kwargs):
        raise OSError(number, os.strerror(number))
    return failing


@pytest.mark.parametrize("module, call, number", [
    (os, "fsync", errno.ENOSPC),            # the disk is full when the data reach it
    (tempfile, "mkstemp", errno.EACCES),    # no permission to create a file in the folder
    (tempfile, "mkstemp", errno.EROFS),     # a read-only file system
    (os, "replace", errno.EXDEV),           # any failure of the final rename
], ids=["ENOSPC", "EACCES", "EROFS", "rename"])
def test_a_failed_write_names_the_file_and_leaves_the_old_one(monkeypatch, tmp_path, module,
                                                              call, number):
    """Contract of atomic_write: WriteError with the target as filename and the system's
    reason; the previous file is untouched; no temporary file is left; not recorded as
    written."""
    target = tmp_path / "r.json"
    target.write_text("old")
    monkeypatch.setattr(module, call, _raise(number))
    with pytest.raises(WriteError) as info:
        atomic_write(target, lambda f: f.write("new"))
    monkeypatch.undo()
    assert (info.value.errno, info.value.strerror, info.value.filename) == (
        number, os.strerror(number), str(target))
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]
    assert target not in written_files()


def test_a_folder_in_place_of_the_file_is_refused_before_writing(tmp_path):
    (tmp_path / "r.json").mkdir()
    with pytest.raises(WriteError) as info:
        atomic_write(tmp_path / "r.json", lambda f: pytest.fail("written into a folder"))
    assert info.value.errno == errno.EISDIR and info.value.filename == str(tmp_path / "r.json")
    assert [p.name for p in tmp_path.iterdir()] == ["r.json"]


def test_save_result_writes_neither_file_when_one_is_a_folder(tmp_path):
    """JSON and CSV are a pair: with a folder where the CSV goes, the JSON is not written
    either."""
    (tmp_path / "r.csv").mkdir()
    with pytest.raises(WriteError) as info:
        save_result(tmp_path, "r", {"a": 1.0}, (("x", "[-]"),), lambda name: [0.0])
    assert info.value.filename == str(tmp_path / "r.csv")
    assert [p.name for p in tmp_path.iterdir()] == ["r.csv"]


def test_names_at_and_beyond_the_file_systems_limit(tmp_path):
    """A name of exactly NAME_MAX bytes is written (its temporary file's name is shortened to
    fit); one byte more is a WriteError naming it (ENAMETOOLONG), with nothing left behind."""
    name_max, path_max = path_limits(tmp_path)
    assert name_max >= 14 and path_max > name_max          # os.pathconf answered sensibly
    at_limit = tmp_path / ("a" * name_max)
    assert atomic_write(at_limit, lambda f: f.write("ok")).read_text() == "ok"
    beyond = tmp_path / ("b" * (name_max + 1))
    with pytest.raises(WriteError) as info:
        atomic_write(beyond, lambda f: f.write("no"))
    assert info.value.errno == errno.ENAMETOOLONG and info.value.filename == str(beyond)
    assert [p.name for p in tmp_path.iterdir()] == [at_limit.name]


def test_a_folder_that_cannot_be_made_is_a_write_error(tmp_path):
    (tmp_path / "file").write_text("")
    with pytest.raises(WriteError) as info:
        make_folder(tmp_path / "file" / "sub")
    assert info.value.filename == str(tmp_path / "file" / "sub")


def test_an_interrupt_while_writing_leaves_no_temporary_and_stays_an_interrupt(tmp_path):
    def interrupted(f):
        f.write("half")
        raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        atomic_write(tmp_path / "r.json", interrupted)
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ every result writer
def test_result_writers_write_non_finite_numbers_as_null(tmp_path):
    """The failed results and sweeps of both solvers (NaN outputs, an infinite Ca_B) and a
    sphere result with NaN error estimates: strict JSON, null where the number is not finite."""
    from bem.results import DropResult, SphereResult, VesicleResult
    from bem.sweep import save_sweep
    from lubrication.results import LubricationResult

    failed = {"status": Status.NOT_CONVERGED, "message": "failed"}
    lub = LubricationResult(nu=0.9, lam=1.0, lam_c=1.2, ca_b=math.inf, model="high-Ca",
                            timings={"total_s": math.nan}, **failed)
    drop = DropResult(lam=0.8, ca=0.1, error_estimate={"V_over_U": math.nan}, **failed)
    ves = VesicleResult(nu=0.9, lam=1.0, lam_c=1.2, ca_b=50.0,
                        refinement=[[16, math.inf, math.nan, math.nan, math.nan]], **failed)
    sphere = SphereResult(lam=0.5, V_over_U=1.6, dp_plus_R=0.5, dp_plus_R0=0.25, drag_K=5.9,
                          dp_translating_R=-3.0, V_over_U_err=math.nan, dp_plus_R_err=math.inf,
                          drag_K_err=np.float64(1e-9), status=Status.CONVERGED, tol=1e-8, panels={},
                          panels_coarse={}, half_length=math.nan, residual=1e-15,
                          null_multiplier=0.0, timings={})
    paths = [*lub.save(tmp_path), *drop.save(tmp_path), *ves.save(tmp_path),
             *sphere.save(tmp_path), *save_sweep(tmp_path / "sweep", [ves], profiles=False)]
    saved = {p.name: _strict(p.read_text()) for p in paths if p.suffix == ".json"}
    assert len(saved) == 5
    lub_d = next(v for k, v in saved.items() if k.startswith("lubrication"))
    assert lub_d["ca_b"] is None and lub_d["model"] == "high-Ca" and lub_d["V_over_U"] is None
    assert lub_d["timings"] == {"total_s": None}
    drop_d = next(v for k, v in saved.items() if k.startswith("bem_drop"))
    assert drop_d["error_estimate"] == {"V_over_U": None} and drop_d["dp_plus_R"] is None
    ves_d = next(v for k, v in saved.items() if k.startswith("bem_vesicle_nu"))
    assert ves_d["refinement"] == [[16, None, None, None, None]]
    sph_d = next(v for k, v in saved.items() if k.startswith("bem_sphere"))
    assert sph_d["V_over_U_err"] is None and sph_d["dp_plus_R_err"] is None
    assert sph_d["drag_K_err"] == 1e-9 and sph_d["half_length"] is None
    sweep_d = next(v for k, v in saved.items() if k.startswith("bem_vesicle_sweep"))
    assert sweep_d["points"][0]["V_over_U"] is None


# ------------------------------------------------------------------ provenance
def test_provenance_names_versions_commit_and_date():
    p = provenance()
    assert p["vesicle-tube"] == lubrication.__version__
    assert p["numpy"] == np.__version__ and re.fullmatch(r"3\.\d+\.\d+.*", p["python"])
    import numba
    import scipy
    assert provenance()["scipy"] == scipy.__version__ and provenance()["numba"] == numba.__version__
    assert p["git_commit"] == "unknown" or re.fullmatch(r"[0-9a-f]{40}", p["git_commit"])
    when = datetime.datetime.fromisoformat(p["date"])
    now = datetime.datetime.now(datetime.timezone.utc)
    assert when.tzinfo is not None and abs((now - when).total_seconds()) < 60
    assert json.loads(json.dumps(p, allow_nan=False)) == p


@pytest.mark.parametrize("make", ["bem_drop", "bem_vesicle", "lubrication"])
def test_every_result_records_the_one_provenance(make):
    """Results of both packages carry lubrication.io.provenance (the BEM results by default;
    the lubrication solver fills it in)."""
    from bem.results import DropResult, VesicleResult
    from lubrication.solve import solve_lubrication

    if make == "bem_drop":
        p = DropResult(lam=0.8, ca=0.1, status=Status.NOT_CONVERGED).provenance
    elif make == "bem_vesicle":
        p = VesicleResult(nu=0.9, lam=1.0, lam_c=1.2, ca_b=50.0,
                          status=Status.NOT_CONVERGED).provenance
    else:
        p = solve_lubrication(0.9, lam_ratio=0.9, tol=1e-4).provenance
    assert set(p) == set(provenance())
