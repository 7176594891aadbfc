"""Benchmark of ``vesicle-tube infer``: the best estimate (the fit, with the linearised
uncertainty) <= 1 s per cell; the default posterior's time per cell reported.

Cells: V/U and ℓ = L/R of the solution map itself at 20 random (ν, λ/λc) inside the map (ν
0.6-0.98, λ/λc 0.2-0.98, Ca_B = 50), turned into V [mm/s], L [µm] for a 6 µm tube at U = 1 mm/s,
then inferred with ``infer_cell`` (default 2 % errors) in this process, with
``uncertainty="linear"`` (the best estimate) and with the default posterior, once with Ca_B
known (η and κ given, Ca_B = 50 at the cell's λ) and once unknown (integrated); the map file is
read once before timing, as in one command. Also timed: one cell with ``samples=200``.
Not a test: timings depend on the machine. Run with ``python tests/benchmarks/bench_infer.py``;
the measurements, with the machine they were taken on, go to ``docs/data/bench_infer.json``
(``tests/benchmarks/bench_store.py``).
"""

from __future__ import annotations

import os
import random
import statistics
import time

TARGET_S = 1.0
CELLS = 20
DIAMETER_UM, U_MM_S = 6.0, 1.0


def cells(m, n: int = CELLS, seed: int = 1) -> list[dict]:
    from correlations.solution_map import query_map
    rng, out = random.Random(seed), []
    while len(out) < n:
        nu, ratio = rng.uniform(0.6, 0.98), rng.uniform(0.2, 0.98)
        q = query_map(nu, ratio, 50.0, map=m)
        if q["V_over_U"] is None or q["ell"] is None:
            continue
        out.append({"v_mm_s": q["V_over_U"] * U_MM_S, "length_um": q["ell"] * DIAMETER_UM / 2})
    return out


def main() -> None:
    from bench_store import machine, store
    from correlations.infer import infer_cell
    from correlations.solution_map import load_map
    load_before = os.getloadavg()
    m = load_map()
    times, consistent = [], 0
    for c in cells(m):
        t = time.perf_counter()
        r = infer_cell(diameter_um=DIAMETER_UM, u_mm_s=U_MM_S, solution_map=m,
                       uncertainty="linear", **c)
        times.append(time.perf_counter() - t)
        consistent += r.consistent
    print(f"infer_cell, best estimate (linearised), {len(times)} cells: median "
          f"{statistics.median(times):.3f} s, max {max(times):.3f} s per cell (target <= "
          f"{TARGET_S:g} s); {consistent} consistent")
    posterior = {}
    # Ca_B known: the red cell's eta and kappa (Ca_B = eta U R0^2/kappa follows lam); unknown:
    # neither given, the posterior integrates over the map's Ca_B
    for label, extra in (("ca_b_known", {"eta_mpas": 1.2, "kappa_j": 2e-19}),
                         ("ca_b_unknown", {})):
        runs = []
        for c in cells(m, 10):
            t = time.perf_counter()
            infer_cell(diameter_um=DIAMETER_UM, u_mm_s=U_MM_S, solution_map=m, **extra, **c)
            runs.append(time.perf_counter() - t)
        posterior[label] = {"runs": runs, "median": statistics.median(runs), "max": max(runs)}
        print(f"infer_cell, posterior ({label.replace('_', ' ')}), {len(runs)} cells: median "
              f"{statistics.median(runs):.2f} s, max {max(runs):.2f} s per cell")
    t = time.perf_counter()
    infer_cell(diameter_um=DIAMETER_UM, u_mm_s=U_MM_S, samples=200, solution_map=m,
               **cells(m, 1)[0])
    sampled = time.perf_counter() - t
    print(f"infer_cell, 200 samples, 1 cell: {sampled:.2f} s")
    store("infer", {
        "parameters": {"cells": CELLS, "seed": 1, "ca_b": 50.0, "diameter_um": DIAMETER_UM,
                       "u_mm_s": U_MM_S, "uncertainty": "linearised, default 2 % errors"},
        "per_cell_s": {"runs": times, "median": statistics.median(times), "max": max(times),
                       "target": TARGET_S},
        "consistent": consistent, "posterior_per_cell_s": posterior,
        "samples_200_one_cell_s": sampled,
        "machine": machine(load_before)})


if __name__ == "__main__":
    main()
