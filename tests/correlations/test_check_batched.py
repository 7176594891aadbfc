"""Queries and checks answered for many points or rows at once against the same answered one at
a time (correlations/solution_map.py ``query_map_many``, correlations/check.py chunks).

The batched paths share their code with the single ones, so the reference is exact equality:
every value, error part, note, verdict and text of a point or a row answered among thousands of
others equals the one it gets alone, on a map object of its own (so that nothing found for
other points is reused). The points and rows are drawn with fixed seeds over the whole domain:
inside the shipped map, on its nodes and within the on-node tolerance of them, next to its
holes, at its edges, outside it, in its Ca_B clamp; vesicle rows with and without shape class,
ca_b, length and gap, near-critical and small vesicles outside the map, vesicles that do not
fit the tube, rigid spheres, drops (without BEM: closed forms), and bad rows.
"""

from __future__ import annotations

import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from correlations import check
from correlations.check import InputError, check_summary, parse_row, trend_checks
from correlations.solution_map import DEFAULT_MAP, load_map, query_map, query_map_many
from lubrication.geometry import critical_confinement

pytestmark = pytest.mark.skipif(not DEFAULT_MAP.exists(), reason="no map shipped")


def _fresh_map(tmp_path, name: str):
    """The shipped map as a map object of its own (a copy of the file: its own cache entry,
    nothing found for other queries)."""
    return load_map(shutil.copy(DEFAULT_MAP, tmp_path / f"{name}.json"))


def _near(rng, nodes, lo, hi) -> float:
    """A coordinate in [lo, hi]: uniform, or a node, or a node moved within or just beyond
    the on-node tolerance (1e-12 relative)."""
    k = rng.random()
    if k < 0.6:
        return rng.uniform(lo, hi)
    return rng.choice(nodes) * (1.0 + rng.choice((0.0, 0.0, 5e-13, -5e-13, 3e-12, -3e-12)))


def _points(m, n: int, seed: int) -> list[tuple]:
    """``n`` points (ν, λ/λc, Ca_B) over the map's box and beyond it."""
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        nu = min(_near(rng, m.nus, 0.55, 1.0), 1.0)
        ratio = (1.0 - 10 ** rng.uniform(-4.5, -0.05) if rng.random() < 0.5
                 else _near(rng, m.ratios, 0.1, 0.9999))
        ca_b = (10 ** rng.uniform(0.5, 4.2) if rng.random() < 0.6
                else _near(rng, m.cas, 4.0, 600.0))
        out.append((nu, min(ratio, 0.99999999), ca_b))
    return out


def test_queries_of_many_points_equal_each_point_alone(tmp_path):
    """3000 points answered together (in two orders) equal each answered alone: every value,
    error part, method and note, and the shape class."""
    alone = _fresh_map(tmp_path, "alone")
    points = _points(alone, 3000, seed=11)
    single = [query_map(*p, alone).to_dict() for p in points]
    together = [q.to_dict() for q in query_map_many(*zip(*points),
                                                    _fresh_map(tmp_path, "many"))]
    backwards = [q.to_dict() for q in query_map_many(*zip(*points[::-1]),
                                                     _fresh_map(tmp_path, "back"))][::-1]
    for answer in (*single, *together, *backwards):
        answer.pop("map")
    assert together == single
    assert backwards == single
    values = [q["quantities"]["V_over_U"] for q in single]
    inside = sum(v["value"] is not None for v in values)
    assert 1000 < inside < 2900, inside           # both inside and outside were drawn
    assert any("clamped" in v["note"] or "above the map's largest" in v["note"]
               for v in values), "no point in the Ca_B clamp"
    assert any(v["note"].startswith("hole at") for v in values), "no point next to a hole"


def _rows(m, n: int, seed: int) -> list[dict]:
    """``n`` rows of every kind the check accepts (module docstring), values near the
    references (the map's, moved by up to its error bar) or anywhere."""
    rng = random.Random(seed)
    points = _points(m, n, seed)
    answers = query_map_many(*zip(*points), m)
    rows = []
    for (nu, ratio, ca_b), q in zip(points, answers):
        kind = rng.random()
        if kind < 0.06:
            lam = rng.uniform(0.05, 0.95)
            rows.append({"kind": "sphere", "lam": f"{lam:.9g}",
                         "V_over_U": f"{2 - 4 / 3 * lam**2 + rng.uniform(-1e-3, 1e-3):.9g}",
                         "dp_plus_R0": f"{16 * lam**6 * rng.uniform(0.9, 1.1):.9g}"})
            continue
        if kind < 0.12:
            lam = rng.uniform(0.05, 1.2)
            rows.append({"kind": "drop", "lam": f"{lam:.9g}",
                         "ca": "" if rng.random() < 0.3 else f"{rng.uniform(0.05, 1):.6g}",
                         "V_over_U": f"{2 - 0.8 * lam**2:.9g}",
                         "dp_plus_R0": f"{4.8 * lam**6 + 1e-9:.9g}"})
            continue
        lam_c = float(critical_confinement(nu))
        lam = ratio * lam_c * (rng.uniform(1.0, 1.05) if kind < 0.15 else 1.0)
        v = q.quantities
        row = {"kind": "vesicle", "nu": f"{nu:.15g}", "lam": f"{lam:.15g}"}
        if rng.random() < 0.9:
            row["ca_b"] = f"{ca_b:.15g}"
        for name in ("V_over_U", "dp_plus_R0", "ell", "film_min"):
            value = v[name]
            if value.value is not None and value.error is not None:
                x = value.value + rng.uniform(-2, 2) * value.error
                row[name], row[f"{name}_err"] = f"{x:.10g}", f"{value.error:.3g}"
            elif name in ("V_over_U", "dp_plus_R0"):
                delta = max(1.0 - ratio, 1e-4)
                row[name] = f"{1 + delta:.6g}" if name == "V_over_U" else f"{4 * lam / delta:.6g}"
        if "dp_plus_R0" in row and rng.random() < 0.1:
            row["dp_plus_R"] = f"{float(row.pop('dp_plus_R0')) / lam:.10g}"
            row.pop("dp_plus_R0_err", None)
        if rng.random() < 0.5:
            shape = v["shape_class"].value or rng.choice(("bullet", "parachute"))
            row["shape_class"] = shape if rng.random() < 0.9 else (
                "parachute" if shape == "bullet" else "bullet")
        rows.append(row)
    return rows


def _alone(rows: list[dict], m) -> list[dict]:
    """Each row checked alone (bem=False), as the report lists it (with its series checks)."""
    for f in vars(check).values():            # nothing computed for other rows is reused
        if isinstance(f, check._Batched):
            f.known.clear()
    check._map_reference.cache_clear()
    parsed = [parse_row(cells, n) for n, cells in enumerate(rows, 1)]
    # the series hold the rows that fit the tube (the summary's series)
    trends = trend_checks([r for r in parsed if r.values["lam"] < critical_confinement(
        r.values.get("nu", 1.0))])
    out = []
    for row in parsed:
        checks, notes, _ = check._row_checks(row, False, m)
        out.append(check.RowReport(row, tuple(checks + trends.get(row.index, [])),
                                   tuple(notes)).to_dict())
    return out


@pytest.mark.parametrize("workers", ["default", "none"])
def test_rows_checked_in_chunks_equal_each_row_checked_alone(tmp_path, monkeypatch, workers):
    """5000 rows of every kind checked in chunks (in worker processes where the machine has
    several cores, and without them) give every row the report it gets checked alone: each
    check's verdict, value, reference, deviation, tolerance and texts, and each note."""
    if workers == "none":
        monkeypatch.setattr(check, "_workers", lambda: 0)
    rows = _rows(_fresh_map(tmp_path, "rows"), 5000, seed=5)
    report = check_summary(rows, bem=False, keep=None, solution_map=_fresh_map(tmp_path, "many"))
    single = _alone(rows, _fresh_map(tmp_path, "alone"))
    chunked = [r.to_dict() for r in report.rows]
    assert len(chunked) == len(single) == 5000
    for s, c in zip(single, chunked):
        assert c == s, s["row"]
    verdicts = {r["verdict"] for r in chunked}
    sources = {c["source"] for r in chunked for c in r["checks"]}
    assert verdicts == {"pass", "warn", "fail"}, verdicts
    for source in ("solution map", "Chen et al. 2020 eq. asmyp1", "small rigid sphere",
                   "small clean drop", "Chen et al. 2020 eq. transition"):
        assert any(source in s for s in sources), source


def test_the_first_bad_row_is_named_whatever_the_chunks(tmp_path):
    """Bad rows in the fourth and the second chunk: the error names the first (as a row-by-row
    read would), wherever the chunks are checked."""
    rows = _rows(_fresh_map(tmp_path, "rows"), 4 * check.CHUNK_ROWS, seed=7)
    first, second = 2 * check.CHUNK_ROWS - 5, 3 * check.CHUNK_ROWS + 17
    rows[first - 1] = {**rows[first - 1], "lam": "1,2"}
    rows[second - 1] = {**rows[second - 1], "lam": "x"}
    with pytest.raises(InputError) as alone:
        parse_row(rows[first - 1], first)
    with pytest.raises(InputError) as chunked:
        check_summary(rows, bem=False)
    assert str(chunked.value) == str(alone.value)
    assert f"row {first}, column 'lam'" in str(chunked.value)
    assert np.isfinite(float(rows[0]["lam"]))


def _exe() -> str:
    return shutil.which("vesicle-tube") or str(Path(sys.executable).with_name("vesicle-tube"))


def _children(pid: int) -> list[int]:
    """The child processes of ``pid`` (Linux; empty elsewhere)."""
    try:
        return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:
        return []


@pytest.mark.skipif(check._workers() == 0 or not Path("/proc").exists(),
                    reason="one core: no worker processes; or no /proc")
def test_ctrl_c_stops_a_check_whose_chunks_are_in_worker_processes(tmp_path):
    """A long first pass (distinct rows, chunks checked in worker processes): SIGINT to the
    command stops it within 2 s with exit 130, one line naming the interrupt and no traceback,
    and its worker processes end with it; a closed stdout ends it quietly."""
    rows = _rows(_fresh_map(tmp_path, "rows"), 20 * check.CHUNK_ROWS, seed=3)
    path = tmp_path / "rows.csv"
    head = sorted({k for r in rows for k in r})
    path.write_text(",".join(head) + "\n" + "".join(
        ",".join(r.get(k, "") for k in head) + "\n" for r in rows))
    proc = subprocess.Popen([_exe(), "check", str(path), "--no-bem"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    deadline = time.monotonic() + 60
    while not _children(proc.pid) and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    workers = _children(proc.pid)
    assert workers and proc.poll() is None, "no worker process seen"
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert time.monotonic() - t0 < 2.0
    assert proc.returncode == 130 and "Traceback" not in err, err
    assert [line for line in err.splitlines() if "interrupted" in line] == \
        err.strip().splitlines()[-1:], err
    time.sleep(0.2)
    assert not [w for w in workers if Path(f"/proc/{w}").exists()
                and "zombie" not in Path(f"/proc/{w}/status").read_text()], workers
    short = tmp_path / "short.csv"            # three chunks: workers start, the run is short
    short.write_text("".join(path.read_text().splitlines(keepends=True)[:3 * check.CHUNK_ROWS + 1]))
    piped = subprocess.Popen([_exe(), "check", str(short), "--no-bem"], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE)
    piped.stdout.close()
    err = piped.stderr.read().decode()
    assert piped.wait(timeout=300) in (0, 1, 141), err
    assert "Traceback" not in err and "BrokenPipe" not in err, err
