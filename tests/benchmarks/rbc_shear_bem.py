"""A red blood cell with membrane shear elasticity in tubes of 4-8 µm, steady BEM: the findings of
Secomb, Skalak, Özkaya & Gross (1986) measured with the full Stokes solution.

Run with ``python tests/benchmarks/rbc_shear_bem.py [--json FILE] [--max-time S]
[--diameters 4 5 6 8] [--velocities ...]``; writes ``docs/data/rbc_shear_bem.json`` by default,
after every solve (atomically), and on a rerun solves only the points not yet stored, so a
stopped run resumes. Not a test: it prints tables.

Secomb et al. (1986, J. Fluid Mech. 163, 405) found, in the lubrication model of an
axisymmetric red cell whose membrane resists shear and bending, that at cell velocities of
about 1 mm/s or more the membrane stress is close to an isotropic tension, largest at the nose
and falling to zero at the rear, and that shape and apparent viscosity hardly depend on the
flow rate; at lower velocities shear and bending matter more and apparent viscosity rises as
the flow rate falls. Here the same cell is solved with :func:`bem.vesicle.solve_vesicle`
(``ca_s`` finite, the Evans-Fung disc made to the cell's reduced volume as stress-free shape),
which, unlike the lubrication model, holds at moderate confinement (the lubrication vesicle has
no solution in a 5 µm tube, lam/lam_c = 0.57: tests/benchmarks/rbc_shear_lubrication.py), and,
for comparison, the vesicle of the same reduced volume (no shear elasticity: today's estimate).

The cell: the estimate's default red cell (:data:`correlations.estimate.RBC_DEFAULTS`: 90 fL,
135 µm², plasma 1.2 mPa s, bending modulus 2e-19 J) and G_s = 6 µN/m (Hochmuth & Waugh 1987).
Nondimensionalisation as the solver: lengths by the tube radius R, velocities by the mean
velocity U; Ca_B = eta U R0^2/kappa and Ca_S = eta U/G_s, both proportional to U; tensions in
eta U; dp+ R0/(eta U). Apparent viscosity (Chen et al. 2020,
:func:`correlations.viscosity.viscosity_single_file_chen2020`) at tube hematocrit
``TUBE_HEMATOCRIT`` (eta_rel - 1 is linear in it).

A point is solved by the default pipeline; where that fails, from the nearest converged point
of the same tube (``initial=``).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from correlations.estimate import RBC_DEFAULTS
from correlations.viscosity import viscosity_single_file_chen2020
from lubrication.geometry import cell_from_volume_area, confinement_from_diameter
from lubrication.io import provenance, write_json

OUT = Path(__file__).resolve().parents[2] / "docs" / "data" / "rbc_shear_bem.json"

VOLUME_FL = RBC_DEFAULTS["volume_fl"]
AREA_UM2 = RBC_DEFAULTS["area_um2"]
ETA_PAS = RBC_DEFAULTS["plasma_viscosity_mpas"] * 1e-3
KAPPA_J = RBC_DEFAULTS["bending_modulus_j"]
GS_N_M = 6e-6                                   # Hochmuth & Waugh 1987
REFERENCE = "biconcave"
TUBE_HEMATOCRIT = 0.3
DIAMETERS_UM = (4.0, 5.0, 6.0, 8.0)
#: from Ca_S = 0.012 to 1.6 (the red-cell map reaches lower, docs/red-cell.md)
VELOCITIES_MM_S = (0.06, 0.1, 0.2, 0.5, 1.0, 2.0, 4.0, 8.0)
#: besides these, a red cell's row has the smallest squared azimuthal stretch of its membrane,
#: (r/r_ref)^2 at equal area coordinate (``stretch_phi_sq_min``)
QUANTITIES = ("V_over_U", "dp_plus_R0", "ell", "film_min", "tension_front", "tension_rear",
              "tension_max", "shape_class", "residual")


def cell():
    """(nu, R0 [µm]) of the default cell."""
    nu, R0 = cell_from_volume_area(VOLUME_FL, AREA_UM2)
    return float(nu), float(R0)


def numbers(U_mm_s, R0_um):
    """(Ca_B, Ca_S) at mean velocity U."""
    eta_U = ETA_PAS * U_mm_s * 1e-3
    return eta_U * (R0_um * 1e-6) ** 2 / KAPPA_J, eta_U / GS_N_M


def solve(d_um, U_mm_s, shear, initial, max_time):
    """One point: the red cell (``shear``) or the vesicle of its nu."""
    from bem.vesicle import solve_vesicle  # lazy: numba
    nu, R0 = cell()
    ca_b, ca_s = numbers(U_mm_s, R0)
    return solve_vesicle(nu, float(confinement_from_diameter(R0, d_um)), ca_b=ca_b,
                         ca_s=ca_s if shear else None, reference=REFERENCE, initial=initial,
                         max_time=max_time)


def row_of(res, d_um, U_mm_s, seconds) -> dict:
    nu, R0 = cell()
    row = {"diameter_um": d_um, "U_mm_s": U_mm_s, "lam_ratio": res.lam_ratio,
           "ca_b": res.ca_b, "ca_s": None if math.isinf(res.ca_s) else res.ca_s,
           "success": res.success, "seconds": seconds, "seed": res.seed,
           "message": res.message}
    if res.success:
        row.update({k: getattr(res, k) for k in QUANTITIES})
        row["rear_over_front"] = res.tension_rear / res.tension_front
        if shear_of(res) is not None:
            from bem.shear import stretch_squared  # lazy: with the solver
            tau = np.linspace(0.0, 1.0, 2001)
            row["stretch_phi_sq_min"] = float(np.min(stretch_squared(res.curve(), tau,
                                                                     shear_of(res))))
        row["eta_rel"] = float(viscosity_single_file_chen2020(res.dp_plus_R0, d_um, R0,
                                                              TUBE_HEMATOCRIT))
    return row


def shear_of(res):
    """The red cell's shear elasticity in the solver's units (None for a vesicle)."""
    from bem.vesicle import check_vesicle_inputs  # lazy: with the solver
    return check_vesicle_inputs(res.nu, res.lam, ca_b=res.ca_b,
                                ca_s=None if res.reference is None else res.ca_s,
                                reference=res.reference or REFERENCE).shear


def key(d_um, U_mm_s, shear) -> str:
    return f"{'red cell' if shear else 'vesicle'} d={d_um:g} U={U_mm_s:g}"


def run(path: Path, diameters, velocities, max_time) -> dict:
    data = {"rows": {}}
    if path.exists():
        import json
        data = json.loads(path.read_text())
    nu, R0 = cell()
    data["parameters"] = {"volume_fl": VOLUME_FL, "area_um2": AREA_UM2, "eta_pas": ETA_PAS,
                          "kappa_j": KAPPA_J, "gs_n_m": GS_N_M, "reference": REFERENCE,
                          "nu": nu, "R0_um": R0, "tube_hematocrit": TUBE_HEMATOCRIT}
    # from 1 mm/s (Ca_S = 0.2) outward, so that a failed point has a converged neighbour
    order = sorted(velocities, key=lambda u: abs(math.log(u)))
    for d in diameters:
        for shear in (True, False):
            done = {}
            for U in order:
                k = key(d, U, shear)
                if k in data["rows"]:
                    continue
                t0 = time.perf_counter()
                res = solve(d, U, shear, None, max_time)
                if not res.success and done:
                    near = min(done, key=lambda u: abs(math.log(u / U)))
                    retry = solve(d, U, shear, done[near], max_time)
                    if retry.success:
                        res = retry
                if res.success:
                    done[U] = res
                data["rows"][k] = row_of(res, d, U, time.perf_counter() - t0)
                data["provenance"] = provenance()
                write_json(path, data)
                r = data["rows"][k]
                print(f"{k}: {'ok' if r['success'] else 'FAILED'} "
                      f"V/U {r.get('V_over_U', math.nan):.5f} "
                      f"dp+ {r.get('dp_plus_R0', math.nan):.4g} "
                      f"eta_rel {r.get('eta_rel', math.nan):.4f} ({r['seconds']:.0f} s)"
                      + ("" if r["success"] else f": {r['message'][:200]}"), flush=True)
    return data


def tables(data: dict) -> str:
    """Per tube: V/U, dp+, eta_rel of the red cell and the vesicle against U, the tension at the
    rear over that at the front; then the change of V/U and dp+ from each velocity to the next
    (the velocities double from 1 to 8 mm/s)."""
    rows = data["rows"]
    lines = []
    for d in sorted({r["diameter_um"] for r in rows.values()}):
        lines.append(f"\nd = {d:g} um, tube hematocrit {TUBE_HEMATOCRIT:g}: red cell (vesicle)")
        lines.append(f"{'U [mm/s]':>9} {'Ca_S':>6} {'V/U':>17} {'dp+ R0/(eta U)':>19} "
                     f"{'eta_rel':>17} {'rear/front':>10}")
        prev = None
        for U in sorted({r["U_mm_s"] for r in rows.values() if r["diameter_um"] == d}):
            red, ves = rows.get(key(d, U, True), {}), rows.get(key(d, U, False), {})

            def pair(q, fmt):
                a, b = red.get(q), ves.get(q)
                return (f"{a:{fmt}}" if a is not None else "—") + " (" + \
                       (f"{b:{fmt}}" if b is not None else "—") + ")"
            change = ""
            if prev is not None and red.get("success") and prev.get("success"):
                change = (f"  change from {prev['U_mm_s']:g}: V/U "
                          f"{red['V_over_U'] / prev['V_over_U'] - 1:+.2%}, dp+ "
                          f"{red['dp_plus_R0'] / prev['dp_plus_R0'] - 1:+.2%}")
            ratio = red.get("rear_over_front")
            lines.append(f"{U:>9g} {red.get('ca_s') or math.nan:>6.3g} {pair('V_over_U', '.5f'):>17} "
                         f"{pair('dp_plus_R0', '.2f'):>19} {pair('eta_rel', '.4f'):>17} "
                         f"{ratio if ratio is not None else math.nan:>10.3f}{change}")
            prev = red if red.get("success") else prev
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", type=Path, default=OUT)
    p.add_argument("--max-time", type=float, default=600.0, help="per solve [s]")
    p.add_argument("--diameters", type=float, nargs="+", default=DIAMETERS_UM)
    p.add_argument("--velocities", type=float, nargs="+", default=VELOCITIES_MM_S)
    p.add_argument("--table", action="store_true", help="print the tables of the stored "
                   "results only (no solve)")
    args = p.parse_args(argv)
    if args.table:
        import json
        print(tables(json.loads(args.json.read_text())))
        return 0
    print(tables(run(args.json, args.diameters, args.velocities, args.max_time)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
