"""Benchmarks of the foundation: prints a table of measured times against the targets.

Run with ``make benchmark`` (or ``python tests/benchmarks/run_benchmarks.py``). Not a test:
timings depend on the machine; the targets are the project's (2-core machine). The
measurements, with the machine they were taken on, go to ``docs/data/bench_foundation.json``
(``tests/benchmarks/bench_store.py``): each benchmark under a fixed key (``cold_start``,
``viscosity/<law>``, ``fahraeus_forward``, ``fahraeus_inverse``, ``lubrication/<model>/<run>``)
with its runs, minimum, median and target in seconds.
"""

from __future__ import annotations

import os
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


def bench_viscosity(n: int = 1_000_000, repeat: int = 5) -> dict[str, tuple[str, list[float]]]:
    """Each viscosity law on n diameters (3.3-1000 um) at one hematocrit, and Fahraeus both ways:
    {key: (printed name, times [s])}."""
    import warnings

    import numpy as np

    from correlations import viscosity as v
    d = np.geomspace(3.3, 1000.0, n)
    out = {}
    cases = {law: (f"{law} ({n:.0e} diameters)",
                   lambda law=law: v.relative_viscosity(d, 0.45, law=law))
             for law in v.VISCOSITY_LAWS}
    cases["fahraeus_forward"] = (f"Fahraeus H_D -> H_T ({n:.0e})",
                                 lambda: v.tube_hematocrit_fahraeus(d, 0.45))
    cases["fahraeus_inverse"] = (f"Fahraeus H_T -> H_D ({n:.0e})",
                                 lambda: v.discharge_hematocrit_fahraeus(d, 0.3))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for key, (name, f) in cases.items():
            times = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                f()
                times.append(time.perf_counter() - t0)
            out[key] = (name, times)
    return out


def bench_lubrication() -> list[tuple[str, str, float, float]]:
    """Lubrication solver: (key, name, seconds, target) for cold, warm and sweep runs (one run
    each)."""
    import numpy as np

    from lubrication.solve import solve_lubrication, sweep_lubrication
    rows = []
    for ca_b, label, key in ((float("inf"), "high-Ca", "high_ca"), (50.0, "Ca_B=50", "ca_b_50")):
        t0 = time.perf_counter()
        cold = solve_lubrication(0.9, lam_ratio=0.99, ca_b=ca_b)
        rows.append((f"lubrication/{key}/cold", f"lubrication cold point nu=0.9, 0.99 ({label})",
                     time.perf_counter() - t0, 5.0))
        t0 = time.perf_counter()
        warm = solve_lubrication(0.9, lam_ratio=0.985, ca_b=ca_b, initial=cold)
        rows.append((f"lubrication/{key}/warm", f"lubrication warm point 0.99 -> 0.985 ({label})",
                     time.perf_counter() - t0, 0.5))
        assert cold.success and warm.success
        t0 = time.perf_counter()
        sweep = sweep_lubrication(0.9, np.linspace(0.6, 0.999, 50), ca_b=ca_b, progress=False)
        ok = sum(r.success for r in sweep)
        rows.append((f"lubrication/{key}/sweep",
                     f"lubrication 50-point sweep 0.6-0.999 ({label}, {ok}/50 ok)",
                     time.perf_counter() - t0, 10.0))
    return rows


def _nest(doc: dict, key: str, value) -> None:
    *parents, last = key.split("/")
    for p in parents:
        doc = doc.setdefault(p, {})
    doc[last] = value


def main() -> None:
    from bench_store import machine, store
    load_before = os.getloadavg()
    rows = []
    cold = bench_cli_cold_start()
    rows.append(("cold_start", "vesicle-tube estimate, cold start", cold, 1.5))
    visc = bench_viscosity()
    for key, (name, times) in visc.items():
        rows.append((key if key.startswith("fahraeus") else f"viscosity/{key}", name, times, 0.5))
    for key, name, seconds, target in bench_lubrication():
        rows.append((key, name, [seconds], target))
    print(f"{'benchmark':56s} {'min [s]':>9s} {'median [s]':>11s} {'target [s]':>11s}  status")
    doc = {"parameters": {"cold_start_repeat": len(cold), "viscosity_diameters": 1_000_000,
                          "viscosity_repeat": 5, "lubrication": "nu = 0.9, one run each"}}
    for key, name, times, target in rows:
        best, median = min(times), statistics.median(times)
        print(f"{name:56s} {best:9.3f} {median:11.3f} {target:11.2f}  "
              f"{'ok' if median <= target else 'SLOW'}")
        _nest(doc, key, {"label": name, "runs": times, "min": best, "median": median,
                         "target": target})
    store("foundation", {**doc, "machine": machine(load_before)})


if __name__ == "__main__":
    main()
