"""Benchmarks of the foundation: prints a table of measured times against the targets.

Run with ``make benchmark`` (or ``python tests/benchmarks/run_benchmarks.py``). Not a test:
timings depend on the machine; the targets are the project's (2-core machine).
"""

from __future__ import annotations

import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path


def _cli() -> list[str]:
    exe = shutil.which("vesicle-tube") or str(Path(sys.executable).with_name("vesicle-tube"))
    return [exe, "estimate"]


def bench_cli_cold_start(repeat: int = 7) -> list[float]:
    """Wall time of a full ``vesicle-tube estimate`` process (interpreter start included)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(_cli(), check=True, capture_output=True)
        times.append(time.perf_counter() - t0)
    return times


def bench_viscosity(n: int = 1_000_000, repeat: int = 5) -> dict[str, list[float]]:
    """Each viscosity law on n diameters (3.3-1000 um) at one hematocrit, and Fahraeus both ways."""
    import warnings

    import numpy as np

    from correlations import viscosity as v
    d = np.geomspace(3.3, 1000.0, n)
    out = {}
    cases = {f"{law} ({n:.0e} diameters)": (lambda law=law: v.relative_viscosity(d, 0.45, law=law))
             for law in v.VISCOSITY_LAWS}
    cases[f"Fahraeus H_D -> H_T ({n:.0e})"] = lambda: v.tube_hematocrit_fahraeus(d, 0.45)
    cases[f"Fahraeus H_T -> H_D ({n:.0e})"] = lambda: v.discharge_hematocrit_fahraeus(d, 0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, f in cases.items():
            times = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                f()
                times.append(time.perf_counter() - t0)
            out[name] = times
    return out


def bench_lubrication() -> list[tuple[str, float, float]]:
    """Lubrication solver: (name, seconds, target) for warm, cold and sweep runs."""
    import numpy as np

    from lubrication.solve import solve_lubrication, sweep_lubrication
    rows = []
    for ca_b, label in ((float("inf"), "high-Ca"), (50.0, "Ca_B=50")):
        t0 = time.perf_counter()
        cold = solve_lubrication(0.9, lam_ratio=0.99, ca_b=ca_b)
        rows.append((f"lubrication cold point nu=0.9, 0.99 ({label})", time.perf_counter() - t0, 5.0))
        t0 = time.perf_counter()
        warm = solve_lubrication(0.9, lam_ratio=0.985, ca_b=ca_b, initial=cold)
        rows.append((f"lubrication warm point 0.99 -> 0.985 ({label})", time.perf_counter() - t0, 0.5))
        assert cold.success and warm.success
        t0 = time.perf_counter()
        sweep = sweep_lubrication(0.9, np.linspace(0.6, 0.999, 50), ca_b=ca_b, progress=False)
        ok = sum(r.success for r in sweep)
        rows.append((f"lubrication 50-point sweep 0.6-0.999 ({label}, {ok}/50 ok)",
                     time.perf_counter() - t0, 10.0))
    return rows


def main() -> None:
    rows = []
    cold = bench_cli_cold_start()
    rows.append(("vesicle-tube estimate, cold start", min(cold), statistics.median(cold), 1.5))
    for name, times in bench_viscosity().items():
        rows.append((name, min(times), statistics.median(times), 0.5))
    for name, seconds, target in bench_lubrication():
        rows.append((name, seconds, seconds, target))
    print(f"{'benchmark':56s} {'min [s]':>9s} {'median [s]':>11s} {'target [s]':>11s}  status")
    for name, best, median, target in rows:
        print(f"{name:56s} {best:9.3f} {median:11.3f} {target:11.2f}  {'ok' if median <= target else 'SLOW'}")


if __name__ == "__main__":
    main()
