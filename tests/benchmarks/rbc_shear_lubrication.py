"""A red blood cell with shear elasticity in a 5 µm tube, lubrication model: Secomb et al. 1986.

Run with ``python tests/benchmarks/rbc_shear_lubrication.py [--json FILE] [--max-time S]``;
writes ``docs/data/rbc_shear_lubrication.json`` by default. Not a test: it prints tables.

Secomb, Skalak, Özkaya & Gross (1986, J. Fluid Mech. 163, 405) found, in the lubrication model
of an axisymmetric red cell whose membrane resists shear and bending, that at cell velocities of
about 1 mm/s or more the membrane stress is nearly an isotropic tension, largest at the nose and
falling to zero at the rear, and shape and apparent viscosity hardly depend on the flow rate;
at lower velocities shear and bending matter more and apparent viscosity rises as flow falls.
This script measures that with :func:`lubrication.solve.solve_lubrication` (bending model,
``ca_s`` finite, reference shape the Evans-Fung disc made to the cell's reduced volume).

Nondimensionalisation (as the solver): lengths by the tube radius R, velocities by the mean
velocity U; Ca_B = eta U R0^2/kappa and Ca_S = eta U/G_s, both proportional to U; tensions in
eta U; dp+ R0/(eta U) the extra pressure drop. Apparent viscosity: Chen et al. 2020,
eta_rel = 1 + (3/32)(R/R0)^4 (dp+ R0/(eta U)) H_T
(:func:`correlations.viscosity.viscosity_single_file_chen2020`), linear in the tube
hematocrit H_T, reported at ``TUBE_HEMATOCRIT``.

Two tables:

1. **Velocity sweep** of the physical cell: V/U, dp+, the tensions at rear and nose, the
   minimum film, the length, eta_rel, at U = 0.1 ... 5 mm/s. Path: at ``START_MM_S`` the
   vesicle of the cell's nu at lam/lam_c = ``START_RATIO`` (the bending vesicle has no
   solution in the 5 µm tube, lam/lam_c = 0.569), the red cell there from it, continuation
   in lam/lam_c down to the tube, then continuation in U outward in steps of at most a factor
   1.25. Each solution must pass the solver's checks, including that the meridian does not
   cross itself: at the rear rim the hoop tension turns compressive (the disc's rim, 1.56 R
   in radius, is squeezed into the tube) and with weak bending the rim folds. Starting the
   path at 1 mm/s instead, the continuation in lam/lam_c meets such a fold at lam/lam_c =
   0.628 (measured), hence the lower START_MM_S.
2. **High-velocity limit at fixed bending**: Ca_S alone raised towards infinity (G_s -> 0) at a
   confinement where the vesicle model (isotropic tension) has a solution, ν of the cell,
   lam/lam_c = ``LIMIT_RATIO``, high-Ca model: the departure from the vesicle and its observed
   order in 1/Ca_S.
"""

from __future__ import annotations

import argparse
import itertools
import math
import time
from pathlib import Path

import numpy as np

from correlations.estimate import RBC_DEFAULTS
from correlations.viscosity import viscosity_single_file_chen2020
from lubrication.geometry import (
    cell_from_volume_area,
    confinement_from_diameter,
    critical_confinement,
)
from lubrication.io import provenance, write_json
from lubrication.solve import solve_lubrication

OUT = Path(__file__).resolve().parents[2] / "docs" / "data" / "rbc_shear_lubrication.json"

# ----------------------------------------------------------------------------- parameters
VOLUME_FL = RBC_DEFAULTS["volume_fl"]                  # 90 fL (Evans & Fung 1972)
AREA_UM2 = RBC_DEFAULTS["area_um2"]                    # 135 µm²
ETA_PAS = RBC_DEFAULTS["plasma_viscosity_mpas"] * 1e-3  # plasma at 37 °C [Pa s]
KAPPA_J = 1.8e-19                                      # bending modulus (Evans 1983) [J]
GS_N_M = 6e-6                                          # shear modulus (Hochmuth & Waugh 1987)
DIAMETER_UM = 5.0                                      # tube diameter [µm]
VELOCITIES_MM_S = (0.1, 0.2, 0.5, 1.0, 2.0, 5.0)       # reported velocities [mm/s]
START_MM_S = 0.4                                       # where the path starts (see velocity_sweep)
START_RATIO = 0.72                                     # lam/lam_c where the path starts
MAX_FACTOR, MIN_FACTOR = 1.25, 1.02                    # continuation steps in U
MAX_STEP, MIN_STEP = 0.02, 1e-3                        # continuation steps in lam/lam_c
TUBE_HEMATOCRIT = 0.25                                 # for eta_rel only (linear in H_T)
REFERENCE = "biconcave"
LIMIT_RATIO = 0.95                                     # lam/lam_c of the high-velocity table
LIMIT_CA_S = (1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0)


def physical_cell():
    """(nu, R0 [µm], lam) of the default cell in the tube."""
    nu, R0 = cell_from_volume_area(VOLUME_FL, AREA_UM2)
    return float(nu), float(R0), float(confinement_from_diameter(R0, DIAMETER_UM))


def solve_cell(U_mm_s, initial, max_time, lam=None, shear=True):
    """The physical cell (or, ``shear=False``, the vesicle of its nu) at mean velocity U (Ca_B
    and Ca_S both proportional to U), in the tube or at confinement ``lam``."""
    nu, R0, lam_tube = physical_cell()
    U = U_mm_s * 1e-3
    return solve_lubrication(nu, lam_tube if lam is None else lam,
                             ca_b=ETA_PAS * U * (R0 * 1e-6) ** 2 / KAPPA_J,
                             ca_s=ETA_PAS * U / GS_N_M if shear else None, reference=REFERENCE,
                             initial=initial, max_time=max_time)


def start_in_tube(max_time):
    """The red cell in the tube at START_MM_S: the vesicle at START_RATIO (where the bending
    vesicle still has a solution), the red cell there from it (continuation in Ca_S inside the
    solver), then continuation in lam/lam_c down to the tube (steps of at most MAX_STEP, halved
    after a failure down to MIN_STEP). Returns (result, message)."""
    nu, _, lam_tube = physical_cell()
    lam_c = critical_confinement(nu)
    vesicle = solve_cell(START_MM_S, None, max_time, START_RATIO * lam_c, shear=False)
    res = solve_cell(START_MM_S, vesicle, max_time, START_RATIO * lam_c)
    ratio, step = START_RATIO, MAX_STEP
    while res.success and ratio > lam_tube / lam_c:
        nxt = max(lam_tube / lam_c, ratio - step)
        trial = solve_cell(START_MM_S, res, max_time, nxt * lam_c)
        if trial.success:
            res, ratio, step = trial, nxt, min(MAX_STEP, 1.5 * step)
            continue
        step *= 0.5
        if step < MIN_STEP:
            return trial, (f"continuation in lam/lam_c at {START_MM_S:g} mm/s stopped at "
                           f"{ratio:.4g}: {trial.message}")
    return res, "" if res.success else res.message


def continue_in_velocity(start, targets, max_time):
    """Continuation in U from the solved ``start`` (U, result) through ``targets`` (monotonic):
    steps of at most MAX_FACTOR, shrunk to their square root after a failure down to
    MIN_FACTOR; returns {U: (result, seconds, steps)} for the targets reached and the reason
    where it stopped."""
    (U, res), out, factor = start, {}, MAX_FACTOR
    clock, steps = time.perf_counter(), 0
    for target in targets:
        while U != target:
            up = target > U
            nxt = min(target, U * factor) if up else max(target, U / factor)
            trial = solve_cell(nxt, res, max_time)
            steps += 1
            if trial.success:
                U, res, factor = nxt, trial, min(MAX_FACTOR, factor**1.5)
                continue
            factor = math.sqrt(factor)
            if factor < MIN_FACTOR:
                return out, (f"continuation in U stopped at {U:.4g} mm/s on the way to "
                             f"{target:g}: {trial.message}")
        out[target] = (res, time.perf_counter() - clock, steps)
        clock, steps = time.perf_counter(), 0
    return out, ""


def velocity_sweep(max_time):
    """One row per velocity of the physical cell (table 1)."""
    nu, R0, lam = physical_cell()
    clock = time.perf_counter()
    first, why = start_in_tube(max_time)
    solved = {START_MM_S: (first, time.perf_counter() - clock, 1)}
    stops = {"start": why}
    if first.success:
        for side in (sorted(u for u in VELOCITIES_MM_S if u > START_MM_S),
                     sorted((u for u in VELOCITIES_MM_S if u < START_MM_S), reverse=True)):
            reached, stops[f"from {START_MM_S:g} to {side[-1]:g} mm/s"] = continue_in_velocity(
                (START_MM_S, first), side, max_time)
            solved.update(reached)
    rows = {}
    for U_mm_s in sorted(set(VELOCITIES_MM_S) | {START_MM_S}):
        U = U_mm_s * 1e-3
        res, seconds, steps = solved.get(U_mm_s, (None, math.nan, 0))
        row = {"U_mm_s": U_mm_s, "ca_b": ETA_PAS * U * (R0 * 1e-6) ** 2 / KAPPA_J,
               "ca_s": ETA_PAS * U / GS_N_M, "success": res is not None and res.success,
               "message": res.message if res is not None else "not reached (see stops)",
               "seconds": seconds, "continuation_steps": steps}
        if row["success"]:
            eta_U = ETA_PAS * U                                  # [N/m]
            tau_phi_min = float(np.min(res.tension_phi))
            row.update(
                V_over_U=res.V_over_U, dp_plus_R0=res.dp_plus_R0,
                dp_plus_pa=res.dp_plus_R0 * eta_U / (R0 * 1e-6),
                tension_rear=res.tension_rear, tension_front=res.tension_front,
                rear_over_front=res.tension_rear / res.tension_front,
                tension_front_mN_m=res.tension_front * eta_U * 1e3,
                tension_phi_min=tau_phi_min,
                shear_over_tension_max=float(np.max(np.abs(res.tension_s - res.tension_phi))
                                             / (2.0 * res.tension_max)),
                stretch_phi_min=float(np.nanmin(res.stretch_phi)),
                film_min_um=res.film_min * DIAMETER_UM / 2.0,
                length_um=res.ell * DIAMETER_UM / 2.0, shape_class=res.shape_class,
                eta_rel=float(viscosity_single_file_chen2020(res.dp_plus_R0, DIAMETER_UM, R0,
                                                             TUBE_HEMATOCRIT)))
        rows[U_mm_s] = row
    ordered = [rows[u] for u in sorted(rows)]
    return {"nu": nu, "R0_um": R0, "lam": lam, "rows": ordered, "stops": stops,
            "doubling": _doubling(ordered)}


def _doubling(rows):
    """Relative change of V/U and dp+ from one velocity to the next (sorted rows)."""
    out = []
    for a, b in itertools.pairwise(rows):
        if a["success"] and b["success"]:
            out.append({"from_mm_s": a["U_mm_s"], "to_mm_s": b["U_mm_s"],
                        "V_over_U": b["V_over_U"] / a["V_over_U"] - 1.0,
                        "dp_plus_R0": b["dp_plus_R0"] / a["dp_plus_R0"] - 1.0})
    return out


def high_velocity_limit(max_time):
    """V/U and dp+ against Ca_S at fixed confinement, high-Ca model, and the vesicle (table 2)."""
    nu, _, _ = physical_cell()
    vesicle = solve_lubrication(nu, lam_ratio=LIMIT_RATIO, max_time=max_time)
    rows = []
    for ca_s in LIMIT_CA_S:
        res = solve_lubrication(nu, lam_ratio=LIMIT_RATIO, ca_s=ca_s, reference=REFERENCE,
                                max_time=max_time)
        rows.append({"ca_s": ca_s, "success": res.success, "V_over_U": res.V_over_U,
                     "dp_plus_R0": res.dp_plus_R0,
                     "dV": res.V_over_U / vesicle.V_over_U - 1.0,
                     "ddp": res.dp_plus_R0 / vesicle.dp_plus_R0 - 1.0})
    for a, b in itertools.pairwise(rows):
        b["order_dV"] = math.log(abs(a["dV"] / b["dV"])) / math.log(b["ca_s"] / a["ca_s"])
        b["order_ddp"] = math.log(abs(a["ddp"] / b["ddp"])) / math.log(b["ca_s"] / a["ca_s"])
    return {"nu": nu, "lam_ratio": LIMIT_RATIO, "model": "high-Ca",
            "vesicle": {"V_over_U": vesicle.V_over_U, "dp_plus_R0": vesicle.dp_plus_R0},
            "rows": rows}


def _print_sweep(sweep):
    print(f"red cell nu={sweep['nu']:.4f}, R0={sweep['R0_um']:.3f} µm, d={DIAMETER_UM:g} µm "
          f"(lam={sweep['lam']:.4f}), G_s={GS_N_M * 1e6:g} µN/m, kappa={KAPPA_J:.2g} J, "
          f"eta={ETA_PAS * 1e3:g} mPa s, reference {REFERENCE}")
    head = (f"{'U mm/s':>7} {'Ca_B':>7} {'Ca_S':>6} {'V/U':>7} {'dp+R0/nU':>9} {'dp+ Pa':>7} "
            f"{'t_rear':>7} {'t_nose':>7} {'rear/nose':>9} {'min t_phi':>9} {'film um':>7} "
            f"{'L um':>6} {'eta_rel':>7} {'shape':>9} {'s':>6}")
    print(head)
    for r in sweep["rows"]:
        if not r["success"]:
            print(f"{r['U_mm_s']:7g} {r['ca_b']:7.3g} {r['ca_s']:6.3g}  failed: {r['message']}")
            continue
        print(f"{r['U_mm_s']:7g} {r['ca_b']:7.3g} {r['ca_s']:6.3g} {r['V_over_U']:7.4f} "
              f"{r['dp_plus_R0']:9.3f} {r['dp_plus_pa']:7.2f} {r['tension_rear']:7.3f} "
              f"{r['tension_front']:7.3f} {r['rear_over_front']:9.3f} "
              f"{r['tension_phi_min']:9.3f} {r['film_min_um']:7.4f} {r['length_um']:6.3f} "
              f"{r['eta_rel']:7.4f} {r['shape_class']:>9} {r['seconds']:6.1f}")
    for where, why in sweep["stops"].items():
        if why:
            print(f"  {where}: {why}")
    print("change from one velocity to the next:")
    for d in sweep["doubling"]:
        print(f"  {d['from_mm_s']:g} -> {d['to_mm_s']:g} mm/s: V/U {d['V_over_U']:+.2%}, "
              f"dp+ {d['dp_plus_R0']:+.2%}")


def _print_limit(limit):
    v = limit["vesicle"]
    print(f"\nhigh-velocity limit at nu={limit['nu']:.4f}, lam/lam_c={limit['lam_ratio']:g}, "
          f"{limit['model']}: vesicle V/U={v['V_over_U']:.8f}, dp+R0/(eta U)={v['dp_plus_R0']:.6f}")
    print(f"{'Ca_S':>7} {'V/U':>12} {'dp+R0/nU':>12} {'dV rel':>10} {'ddp rel':>10} "
          f"{'order V':>8} {'order dp':>8}")
    for r in limit["rows"]:
        print(f"{r['ca_s']:7g} {r['V_over_U']:12.8f} {r['dp_plus_R0']:12.6f} {r['dV']:10.2e} "
              f"{r['ddp']:10.2e} {r.get('order_dV', math.nan):8.3f} "
              f"{r.get('order_ddp', math.nan):8.3f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", default=str(OUT), help="write the tables to this file")
    ap.add_argument("--max-time", type=float, default=900.0,
                    help="wall-time budget of each solve [s]")
    args = ap.parse_args(argv)
    sweep = velocity_sweep(args.max_time)
    _print_sweep(sweep)
    limit = high_velocity_limit(args.max_time)
    _print_limit(limit)
    write_json(args.json, {
        "parameters": {"volume_fl": VOLUME_FL, "area_um2": AREA_UM2, "eta_pas": ETA_PAS,
                       "kappa_j": KAPPA_J, "gs_n_m": GS_N_M, "diameter_um": DIAMETER_UM,
                       "tube_hematocrit": TUBE_HEMATOCRIT, "reference": REFERENCE},
        "velocity_sweep": sweep, "high_velocity_limit": limit, "provenance": provenance()},
        indent=1, sort_keys=False)
    return 0 if all(r["success"] for r in sweep["rows"]) else 1


if __name__ == "__main__":
    from bench_store import run_script

    run_script(main)
