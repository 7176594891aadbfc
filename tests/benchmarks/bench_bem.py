"""Benchmark of the axisymmetric BEM: prints a table (not a test; timings depend on the machine).

Run with ``python tests/benchmarks/bench_bem.py [--cold]``. ``--cold`` removes the numba cache
of ``bem`` first so that the compile time is measured from scratch (in a subprocess).
Targets (2-core machine): sphere at a/R = 0.6 to 1e-8 in V/U in <= 0.5 s after
compilation; clean drop at lam = 0.8, Ca = 0.1 (steady state by Newton, automatic refinement
pair) in <= 30 s. ``--no-drop`` skips the drop rows.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))


def compile_time(cold: bool) -> float:
    """Wall time of importing bem and the first solve in a fresh interpreter, minus a warm solve."""
    if cold:
        for cache in (ROOT / "bem" / "__pycache__").glob("*.nb*"):
            cache.unlink()
    code = ("import time; t=time.perf_counter(); from bem.solve import solve_sphere_mesh; "
            "solve_sphere_mesh(0.5, 4); t1=time.perf_counter(); solve_sphere_mesh(0.5, 4); "
            "t2=time.perf_counter(); print(t1-t-(t2-t1))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, check=True,
                         capture_output=True, text=True)
    return float(out.stdout.strip())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cold", action="store_true", help="clear the numba cache first")
    ap.add_argument("--no-drop", action="store_true", help="skip the clean-drop rows")
    args = ap.parse_args()

    print(f"numba compile + import ({'cold cache' if args.cold else 'cache as found'}): "
          f"{compile_time(args.cold):.2f} s")
    from bem.solve import solve_sphere, solve_sphere_mesh
    solve_sphere_mesh(0.5, 4)                          # warm-up in this process

    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        res = solve_sphere(0.6, tol=1e-10)
        times.append(time.perf_counter() - t0)
    print(f"\nsphere a/R = 0.6, tol 1e-10: V/U = {res.V_over_U:.12f} "
          f"(estimate {res.V_over_U_err:.1e}), dp+R/(eta U) = {res.dp_plus_R:.10f}, "
          f"K = {res.drag_K:.10f}")
    print(f"  meshes {res.timings['meshes']}, body panels {res.panels['body']}; "
          f"median {statistics.median(times):.3f} s (target <= 0.5 s)")

    print("\ncost growth with panel count (a/R = 0.6, order 16, one mesh, both problems)")
    print(f"{'body':>5} {'wall':>5} {'unknowns':>9} {'assembly s':>11} {'solve s':>8} "
          f"{'V/U':>18}")
    for n in (4, 8, 16, 32, 64):
        best = None
        for _ in range(3):
            s = solve_sphere_mesh(0.6, n)
            if best is None or s["assembly_s"] + s["solve_s"] < best["assembly_s"] + best["solve_s"]:
                best = s
        nodes = 16 * (best["panels"]["body"] + best["panels"]["wall"])
        print(f"{best['panels']['body']:>5} {best['panels']['wall']:>5} {2 * nodes + 3:>9} "
              f"{best['assembly_s']:>11.3f} {best['solve_s']:>8.3f} {best['V_over_U']:>18.14f}")

    if not args.no_drop:
        bench_drop()


def bench_drop(repeat: int = 3) -> None:
    """Clean drop, lam = 0.8: Ca = 0.1 (the target row) and the other Table I capillary numbers."""
    from bem.drop import solve_drop

    print("\nclean drop, lam = 0.8 (viscosity ratio 1), solve_drop defaults (tol 1e-5)")
    print(f"{'Ca':>5} {'modes':>6} {'BEM evals':>10} {'V/U':>14} {'dp+R/(eta U)':>14} "
          f"{'pair diff dp+':>13} {'median s':>9}")
    for ca, n in ((0.1, repeat), (0.05, 1), (0.2, 1), (0.3, 1), (0.5, 1)):
        times = []
        for _ in range(n):
            t0 = time.perf_counter()
            res = solve_drop(0.8, ca)
            times.append(time.perf_counter() - t0)
        evals = sum(v.get("evaluations", 0) for v in res.iterations.values())
        target = "  (target <= 30 s)" if ca == 0.1 else ""
        print(f"{ca:>5g} {res.panels.get('modes', 0):>6} {evals:>10} {res.V_over_U:>14.10f} "
              f"{res.dp_plus_R:>14.10f} {res.error_estimate['dp_plus_R']:>13.1e} "
              f"{statistics.median(times):>9.2f}{target}" + ("" if res.success else "  FAILED"))


if __name__ == "__main__":
    main()
