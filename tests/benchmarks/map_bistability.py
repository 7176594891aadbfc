"""Two steady branches at small λ/λc: the elongated (prolate, convex rear) vesicle followed up in
Ca_B and the parachute followed down, at fixed (ν, λ/λc), by continuation from the map's points.

Run with ``python tests/benchmarks/map_bistability.py [--json FILE] [--nu NU] [--lam-ratio R ...]``.
For each λ/λc: the elongated branch starts from the map's stored point at the smallest Ca_B and
is continued upward through the map's Ca_B values, each solve started from the last converged
shape of the branch; the parachute branch starts from the stored point at the largest Ca_B and is
continued downward. A branch stops at its first solve that does not converge or that ends in the
other shape class (the branch has ended or the solve left it). Where both branches converged at
the same Ca_B, the vesicle has two steady axisymmetric states there, and which one the map holds
depends on how its point was started (docs/validation.md, solution map). The BEM solves use the
default options (Ca_B given); results go to ``docs/data/map_bistability.json`` (atomic) with the
map's own point at each Ca_B for comparison. Our own values: no independent reference exists for
these states. Not a test: about 10–60 s per solve on 2 cores.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

from bem.shape import SpectralCurve
from bem.vesicle import solve_vesicle
from correlations.map_build import DEFAULT_GRID
from correlations.solution_map import point_filename, read_point
from lubrication.geometry import critical_confinement
from lubrication.io import write_json

BUILD = Path(__file__).resolve().parents[2] / "correlations" / "data" / "solution_map_build"
KEYS = ("V_over_U", "dp_plus_R0", "ell", "film_min", "shape_class", "curvature_rear")
CA_B = tuple(sorted(DEFAULT_GRID["ca_b"]))      # the shipped map's Ca_B nodes


def _curve(shape: dict, volume: float) -> SpectralCurve:
    return SpectralCurve.closed(shape["modes"], volume=volume, density=shape["density"])


def follow(nu: float, r: float, start: dict, cas: list[float], want: str) -> list[dict]:
    """Continue the branch of shape class ``want`` from the stored point ``start`` through the
    Ca_B values ``cas`` (in that order)."""
    lam = r * float(critical_confinement(nu))
    volume = 4.0 / 3.0 * math.pi * lam**3
    shape, rows = start["shape"], []
    for ca in cas:
        t0 = time.perf_counter()
        res = solve_vesicle(nu, lam_ratio=r, ca_b=ca, initial=_curve(shape, volume))
        d = res.to_dict(shape=False)
        row = {"ca_b": ca, "success": bool(res.success), "message": res.message,
               "seconds": round(time.perf_counter() - t0, 1),
               **{k: d.get(k) for k in KEYS}}
        on_branch = res.success and d.get("shape_class") == want
        row["on_branch"] = bool(on_branch)
        rows.append(row)
        print(f"  {want:9s} nu={nu:g} lam/lam_c={r:g} Ca_B={ca:g}: "
              + (f"V/U {d['V_over_U']:.6f}, dp+ {d['dp_plus_R0']:.5g}, ell {d['ell']:.4f}, "
                 f"{d['shape_class']}" if res.success else "not converged")
              + f" ({row['seconds']:.0f} s)", flush=True)
        if not on_branch:
            break
        shape = {"modes": res.modes.tolist(), "density": res.density.tolist()}
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default="docs/data/map_bistability.json", help="results file")
    ap.add_argument("--nu", type=float, default=0.8, help="reduced volume (default 0.8)")
    ap.add_argument("--lam-ratio", type=float, nargs="+", default=[0.2, 0.3],
                    help="lam/lam_c values (default 0.2 0.3)")
    ap.add_argument("--build", default=str(BUILD), help="map build folder")
    args = ap.parse_args(argv)
    out = Path(args.json)
    if not out.parent.is_dir():
        ap.error(f"--json: folder {out.parent} does not exist")
    build = Path(args.build)
    stored = {}
    for r in args.lam_ratio:
        for ca in CA_B:
            path = build / point_filename("bem", args.nu, r, ca)
            if not path.exists():
                ap.error(f"no stored point {path.name} in {build}")
            stored[r, ca] = read_point(path)
    result = {"nu": args.nu, "lines": []}
    for r in args.lam_ratio:
        line = {"lam_ratio": r,
                "map": [{"ca_b": ca, "success": stored[r, ca]["success"],
                         **{k: stored[r, ca].get(k) for k in KEYS}} for ca in CA_B]}
        elongated = [ca for ca in CA_B if stored[r, ca].get("shape_class") == "bullet"]
        parachute = [ca for ca in CA_B if stored[r, ca].get("shape_class") == "parachute"]
        line["elongated"] = (follow(args.nu, r, stored[r, elongated[0]],
                                    [c for c in CA_B if c > elongated[0]], "bullet")
                             if elongated else [])
        line["parachute"] = (follow(args.nu, r, stored[r, parachute[-1]],
                                    [c for c in reversed(CA_B) if c < parachute[-1]],
                                    "parachute") if parachute else [])
        result["lines"].append(line)
        write_json(out, result, indent=1, sort_keys=False)
    for line in result["lines"]:
        both = sorted({row["ca_b"] for row in line["elongated"] if row["on_branch"]}
                      & {row["ca_b"] for row in line["parachute"] if row["on_branch"]})
        print(f"lam/lam_c = {line['lam_ratio']:g}: both branches steady at Ca_B = "
              f"{', '.join(f'{c:g}' for c in both) or 'none of the solved values'}")
    return 0


if __name__ == "__main__":
    from bench_store import run_script

    run_script(main)
