"""Build (or resume) the red-cell slice of the solution map into ``docs/data/rbc_slice_build``.

The estimate's default red cell (:data:`correlations.estimate.RBC_DEFAULTS`: 90 fL, 135 µm²,
plasma 1.2 mPa s, bending modulus 2e-19 J) with the shear modulus G_s = 6 µN/m (Hochmuth &
Waugh 1987) and the Evans-Fung disc as stress-free shape: BEM points on ν 0.55-0.7, λ/λc
0.2-0.95 and the Ca_B of U = 0.01-10 mm/s of that cell, all with the build option
``shear_ratio`` β = G_s R0²/κ = Ca_B/Ca_S (:data:`correlations.solution_map.SHEAR_RATIO`), so
that each Ca_B line is the one cell at one velocity, and the tolerance :data:`BEM_TOL`. Run
with ``python tests/benchmarks/rbc_slice_build.py [--workers 2] [--max-time 900]``; a rerun
resumes (every finished point is its own file); ``--retry-failed`` solves the failed points
again, ``--from-neighbours`` from their converged ν and λ/λc neighbours
(:func:`retry_from_neighbours`).
``python tests/benchmarks/rbc_slice_build.py --pack correlations/data/rbc_slice_map.json`` packs
its complete velocity lines (:func:`pack_complete`) into the map the red-cell estimate reads.
"""

from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from correlations.estimate import RBC_DEFAULTS
from correlations.map_build import SHEAR_RATIO, _point, build_map, make_grid
from correlations.solution_map import pack_map, point_filename, read_build, read_points
from lubrication.io import provenance, write_json
from lubrication.geometry import cell_from_volume_area

FOLDER = Path(__file__).resolve().parents[2] / "docs" / "data" / "rbc_slice_build"
GS_N_M = 6e-6                                            # Hochmuth & Waugh 1987
VELOCITIES_MM_S = (0.01, 0.03, 0.06, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0)
NU = (0.55, 0.575, 0.6, 0.65, 0.7)
LAM_RATIO = (0.2, 0.3, 0.35, 0.4, 0.45, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95)
#: The BEM's relative tolerance on its estimated discretisation error (the solver's ``tol``;
#: default 1e-4). A slow, confined red cell converges slowly in modes (Δp⁺ at (0.65, 0.8 λc,
#: 0.06 mm/s): 253, 281, 292, 296 at 48-72 modes, 1e-4 reached at 128), so at 1e-4 many such
#: points end at the mode cap as holes. 1e-3 is half the map's V/U target (0.2 %) and a
#: twentieth of its Δp⁺ target (2 %), and each node's estimated error is added to the map's
#: error bar (:mod:`correlations.solution_map`, error bar). Points converged at 1e-4 meet it.
BEM_TOL = 1e-3


def slice_grid() -> tuple[dict, float]:
    """The grid and β of the default cell (Ca_B rounded to 4 decimals, β to 3: the values the
    build stores)."""
    _, R0 = cell_from_volume_area(RBC_DEFAULTS["volume_fl"], RBC_DEFAULTS["area_um2"])
    R0 = float(R0) * 1e-6
    kappa = RBC_DEFAULTS["bending_modulus_j"]
    eta = RBC_DEFAULTS["plasma_viscosity_mpas"] * 1e-3
    ca_b = [round(eta * u * 1e-3 * R0**2 / kappa, 4) for u in VELOCITIES_MM_S]
    beta = round(GS_N_M * R0**2 / kappa, 3)
    return make_grid(nu=list(NU), lam_ratio={"bem": list(LAM_RATIO)}, ca_b=ca_b,
                     methods=["bem"]), beta


def bem_options() -> dict:
    """The BEM options of every slice point: the default cell's β and :data:`BEM_TOL`."""
    return {SHEAR_RATIO: slice_grid()[1], "tol": BEM_TOL}


def pack_complete(out: Path) -> tuple[Path, list[float]]:
    """Pack the slice's complete velocity lines (every (ν, λ/λc) point stored, converged or
    not) into the map file ``out``; returns it and the Ca_B of the lines packed. Lines still
    building are left out, so that the map's Ca_B range is the range it was built over: the
    estimate refuses a velocity outside it instead of answering from a line of holes."""
    build = read_build(FOLDER)
    files = {}
    for f in FOLDER.glob("bem_*.json"):
        p = json.loads(f.read_text())
        files[(p["nu"], p["lam_ratio"], p["ca_b"])] = f
    grid = build["grid"]
    done = [c for c in grid["ca_b"] if all((nu, r, c) in files for nu in grid["nu"]
                                          for r in grid["lam_ratio"]["bem"])]
    with tempfile.TemporaryDirectory() as tmp:
        write_json(Path(tmp) / "build.json", {**build, "grid": {**grid, "ca_b": done}},
                   indent=1, sort_keys=False)
        for key, f in files.items():
            if key[2] in done:
                shutil.copy2(f, Path(tmp) / f.name)
        return pack_map(tmp, out), done


def _from_neighbour(task: tuple) -> tuple:
    """Solve the failed point (ν, λ/λc, Ca_B) from ``warm``, the stored converged point of a
    neighbour at the same velocity, by the build's own point solver with that start first (the
    build's own starts, which failed, after it); the record replaces the stored one only if it
    converged. Returns (point, status)."""
    point, warm, max_time = task
    start = f"converged neighbour (ν {warm['nu']:g}, λ/λc {warm['lam_ratio']:g}), same velocity"
    record, _ = _point("bem", *point, warm, bem_options(), max_time,
                       {**provenance(), "start": start}, neighbour_first=True)
    if record["success"]:
        write_json(FOLDER / point_filename("bem", *point), record, indent=1, sort_keys=False)
    return point, record["status"]


def _neighbours(nodes: list, x: float) -> list:
    """The nodes next to ``x`` in ``nodes``, nearer first."""
    i = nodes.index(x)
    return sorted((nodes[j] for j in (i - 1, i + 1) if 0 <= j < len(nodes)),
                  key=lambda y: abs(y - x))


def retry_from_neighbours(workers: int, max_time: float, velocities=None) -> list[tuple]:
    """Solve every failed point of the slice again (only on the lines of ``velocities`` [mm/s]
    if given), started from each converged neighbour at the same velocity in turn until one
    converges: first its ν neighbours at the same λ/λc, then its λ/λc neighbours at the same
    ν, nearer first. The build's starts are the same cell faster, the neighbour in ν at a start of
    the line and the seed bank; where the slice's low-ν points self-intersect or find no steady
    state from those, the same cell at the next ν, or the next confinement, can still be on the
    steady branch. Returns (point, status) per attempt."""
    grid = read_build(FOLDER)["grid"]
    nus, lams = grid["nu"], grid["lam_ratio"]["bem"]
    lines = None if velocities is None else {
        c for c, u in zip(slice_grid()[0]["ca_b"], VELOCITIES_MM_S) if u in velocities}
    stored = {(p["nu"], p["lam_ratio"], p["ca_b"]): p for p in read_points(FOLDER)}
    pending = {}                  # failed point -> its converged neighbours, in order
    for (nu, r, ca), p in sorted(stored.items()):
        if not p["success"] and (lines is None or ca in lines):
            near = ([(x, r) for x in _neighbours(nus, nu)]
                    + [(nu, x) for x in _neighbours(lams, r)])
            pending[nu, r, ca] = [stored[key + (ca,)] for key in near
                                  if stored.get(key + (ca,), {}).get("success")]
    out = []
    with ProcessPoolExecutor(workers) as pool:
        for attempt in range(max(map(len, pending.values()), default=0)):
            tasks = [(point, warm[attempt], max_time) for point, warm in pending.items()
                     if len(warm) > attempt]
            for point, status in pool.map(_from_neighbour, tasks):
                print(point, status, flush=True)
                out.append((point, status))
                if status == "converged":
                    del pending[point]
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--max-time", type=float, default=900.0, help="per point [s]")
    p.add_argument("--retry-failed", action="store_true",
                   help="solve again the stored points that did not converge")
    p.add_argument("--from-neighbours", action="store_true",
                   help="solve the failed points again from their converged ν and λ/λc "
                        "neighbours at the same velocity")
    p.add_argument("--velocities", type=float, nargs="+", metavar="MM_S",
                   choices=VELOCITIES_MM_S,
                   help="with --from-neighbours: only the points at these velocities [mm/s]")
    p.add_argument("--pack", type=Path, metavar="FILE",
                   help="instead of building, pack the complete velocity lines into FILE")
    args = p.parse_args(argv)
    if args.velocities and not args.from_neighbours:
        p.error("--velocities selects the points of --from-neighbours; give both")
    if args.pack:
        path, done = pack_complete(args.pack)
        print(f"packed {path}: Ca_B {', '.join(f'{c:g}' for c in done)}")
        return 0
    if args.from_neighbours:
        retry_from_neighbours(args.workers, args.max_time, args.velocities)
        return 0
    print(build_map(FOLDER, slice_grid()[0], options={"bem": bem_options()},
                    workers=args.workers, max_time=args.max_time, retry_failed=args.retry_failed,
                    pack=False), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
