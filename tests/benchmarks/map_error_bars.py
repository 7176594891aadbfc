"""Does the solution map's error bar cover its error? Coarsened-grid check on the stored points.

Run with ``python tests/benchmarks/map_error_bars.py [--build DIR] [--nu ...] [--lam-ratio ...]``.
For each axis, a map is packed from the build folder (default: the committed one) without some
of its nodes (default ν = 0.65, 0.75, 0.85; or the BEM λ/λc = 0.3, 0.5, 0.7), and queried at
the left-out points, whose stored values are the truth. Printed per quantity: points, the
largest relative error, the fraction of points whose error bar covers the error, and the median
of bar / error. With the default nodes the left-out grid has twice the spacing of the shipped
one, so errors here are larger than the shipped map's (degree-2 interpolation: up to 8×); the
check is of the error bar, not of the map's accuracy (that is ``map_offgrid.py``). The red-cell
slice: ``--build docs/data/rbc_slice_build --nu 0.575 --lam-ratio 0.35 0.45`` leaves out the
row and the columns added last, i.e. queries the grid it had before at them. No solver runs; a
few seconds.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import tempfile
from pathlib import Path

from correlations.files import UnreadableFile
from correlations.solution_map import (load_map, pack_map, point_filename, query_map,
                                     read_build, read_points)

BUILD = Path(__file__).resolve().parents[2] / "correlations" / "data" / "solution_map_build"
KEYS = ("V_over_U", "dp_plus_R0", "ell", "film_min", "tension_max")
LEFT_OUT = {"nu": (0.65, 0.75, 0.85), "lam_ratio": (0.3, 0.5, 0.7)}


def coarsened(build: Path, axis: str, tmp: Path, left_out=LEFT_OUT) -> list[dict]:
    """Pack ``build`` without the nodes ``left_out[axis]``, query it at the left-out converged
    points; one row of statistics per quantity."""
    points = read_points(build)
    info = json.loads((build / "build.json").read_text())
    grid = info["grid"]

    def out(p):
        return p[axis] in left_out[axis] and (axis == "nu" or p["method"] == "bem")

    if axis == "nu":
        grid["nu"] = [v for v in grid["nu"] if v not in left_out[axis]]
    else:
        grid["lam_ratio"]["bem"] = [v for v in grid["lam_ratio"]["bem"]
                                    if v not in left_out[axis]]
    folder = tmp / axis
    folder.mkdir()
    (folder / "build.json").write_text(json.dumps(info))
    for p in points:
        if not out(p):
            name = point_filename(p["method"], p["nu"], p["lam_ratio"], p["ca_b"])
            shutil.copy(build / name, folder / name)
    m = load_map(pack_map(folder, folder / "map.json"))
    stats = {q: [] for q in KEYS}
    for p in points:
        if not (out(p) and p["success"]):
            continue
        res = query_map(p["nu"], p["lam_ratio"], p["ca_b"], m)
        for q in KEYS:
            v = res.quantities[q]
            if v.value is not None and v.error is not None and p[q]:
                stats[q].append((abs(v.value - p[q]) / abs(p[q]), v.error / abs(p[q])))
    rows = []
    for q, s in stats.items():
        if s:
            rows.append({"axis": axis, "quantity": q, "points": len(s),
                         "max_error": max(e for e, _ in s),
                         "covered": sum(b >= e for e, b in s) / len(s),
                         "median_bar_over_error": statistics.median(
                             b / max(e, 1e-15) for e, b in s)})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build", default=str(BUILD), help="map build folder")
    ap.add_argument("--nu", type=float, nargs="*", default=LEFT_OUT["nu"],
                    help="ν nodes to leave out (none: no ν check)")
    ap.add_argument("--lam-ratio", type=float, nargs="*", default=LEFT_OUT["lam_ratio"],
                    help="BEM λ/λc nodes to leave out (none: no λ/λc check)")
    ap.add_argument("--json", help="write the table to this file")
    args = ap.parse_args(argv)
    build = Path(args.build)
    if not (build / "build.json").is_file():
        ap.error(f"--build: {build} is not a map build folder")
    try:
        grid = read_build(build, "--build")["grid"]
    except UnreadableFile as exc:
        ap.error(str(exc))
    left_out = {"nu": tuple(args.nu), "lam_ratio": tuple(args.lam_ratio)}
    for axis, nodes in (("nu", grid["nu"]), ("lam_ratio", grid["lam_ratio"]["bem"])):
        inner = nodes[1:-1]
        for v in left_out[axis]:
            if v not in inner:
                ap.error(f"--{axis.replace('_', '-')}: {v:g} is not an inner node of the build "
                         f"({', '.join(f'{x:g}' for x in inner)})")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for axis in left_out:
            if left_out[axis]:
                rows += coarsened(build, axis, Path(tmp), left_out)
    print(f"{'left out':>9} {'quantity':>12} {'points':>6} {'max rel err':>11} "
          f"{'covered':>8} {'median bar/err':>14}")
    for r in rows:
        print(f"{r['axis']:>9} {r['quantity']:>12} {r['points']:6d} {r['max_error']:11.1e} "
              f"{r['covered']:8.0%} {r['median_bar_over_error']:14.1f}")
    if args.json:
        from lubrication.io import write_json
        write_json(args.json, {"build": str(build), "left_out": left_out, "rows": rows})
    return 0


if __name__ == "__main__":
    from bench_store import run_script

    run_script(main)
