"""Measure the error models of the consistency check's references on our own solutions.

The constants of correlations/check.py (module docstring, "tolerances of the references") are
set from these numbers; run ``python tests/benchmarks/check_tolerances.py`` after the map build
or the solvers change and compare. Sources: the converged points of the committed map build
(correlations/data/solution_map_build; BEM and lubrication, nu 0.6-0.98, Ca_B 5-500), the
shipped map's parachute-bullet brackets, and our BEM sphere and drop (about a minute).
"""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

BUILD = Path(__file__).resolve().parents[2] / "correlations" / "data" / "solution_map_build"


def near_critical(points) -> None:
    """eq. asmyp1/asmyp2 against our points with delta <= 0.1; Chen's (3/2) lam ell/delta for
    0.02 <= delta <= 0.1; the spherocylinder volume and area for delta <= 0.05; film and length
    bounds."""
    from lubrication.asymptotics import (dp_plus_near_critical, speed_near_critical,
                                         speed_slope_near_critical)
    from lubrication.geometry import critical_confinement
    k_speed = k_dp = 0.0
    chen, vol, area, film, length = [], [], [], [], []
    for p in points:
        nu, lam, ell, h = p["nu"], p["lam"], p["ell"], p["film_min"]
        delta = 1.0 - lam / critical_confinement(nu)
        film.append(h / delta)
        length.append(ell / (4 / 3 * lam**3 / (1 - h) ** 2))
        if delta > 0.1 + 1e-12:
            continue
        slope = speed_slope_near_critical(nu)
        res = abs(p["V_over_U"] - speed_near_critical(nu, lam))
        k_speed = max(k_speed, (res - abs(slope - 1) * delta) / delta**1.5)
        k_dp = max(k_dp, abs(p["dp_plus_R0"] - dp_plus_near_critical(nu, lam))
                   / (lam / math.sqrt(delta)))
        if delta >= 0.02 - 1e-12:
            chen.append(p["dp_plus_R0"] / (1.5 * lam * ell / delta))
        if delta <= 0.05 + 1e-12:
            rho = 1.0 - h
            vol.append(((3 * rho**2 * ell - 2 * rho**3) / (4 * lam**3) - 1) / delta)
            area.append((rho * ell / (2 * lam**2 * nu ** (-2 / 3)) - 1) / delta)
    print(f"asmyp1: (|V/U - asmyp1| - |s - 1| delta)/delta^1.5 <= {k_speed:.3f} "
          f"(NEAR_CRITICAL_SPEED_K)")
    print(f"asmyp2: |dp+ - asmyp2|/(lam delta^-0.5) <= {k_dp:.2f} (NEAR_CRITICAL_DP_K)")
    print(f"Chen (3/2) lam ell/delta, 0.02 <= delta <= 0.1: ratio {min(chen):.3f} to "
          f"{max(chen):.3f} (CHEN_FILM_SCALING_RTOL)")
    print(f"spherocylinder, delta <= 0.05: eps_V/delta {min(vol):.3f} to {max(vol):.3f}, "
          f"eps_A/delta {min(area):.3f} to {max(area):.3f} (SHAPE_VOLUME_BAND, SHAPE_AREA_BAND)")
    print(f"film_min/delta {min(film):.3f} to {max(film):.3f} (film_upper_bound: <= 1); "
          f"ell/length bound >= {min(length):.3f} (length_lower_bound: >= 1)")


def small_vesicles(points) -> None:
    """Small-sphere laws against our BEM vesicles with nu >= 0.9, lam <= 0.5: what the
    sphere's next term (K lam^5, the check's constants) leaves, in units of (1 - nu) x the
    leading deviation (the asphericity term of the check has coefficient 1)."""
    from correlations.check import SMALL_SPHERE_DP_K, SMALL_SPHERE_SPEED_K
    worst = 0.0
    for p in points:
        nu, lam = p["nu"], p["lam"]
        if p["method"] != "bem" or nu < 0.9 or lam > 0.5:
            continue
        lead_v, lead_p = 4 / 3 * lam**2, 16 * lam**6
        for dev, next_term, lead in (
                (abs(p["V_over_U"] - (2 - lead_v)), SMALL_SPHERE_SPEED_K * lam**5, lead_v),
                (abs(p["dp_plus_R0"] - lead_p), SMALL_SPHERE_DP_K * lam**5 * lead_p, lead_p)):
            worst = max(worst, (dev - next_term) / ((1 - nu) * lead))
    print(f"small vesicles (nu >= 0.9, lam <= 0.5): beyond the sphere's next term, "
          f"<= {worst:.2f} (1 - nu) x the leading deviation")


def transition_band() -> None:
    """Distance nu - nu_T(lam) of Chen's transition line at the brackets of the shipped map."""
    from correlations.solution_map import load_map
    m = load_map()
    c, lines = m.columns, {}
    for method, nu, ca, lam, cls in zip(c["method"], c["nu"], c["ca_b"], c["lam"],
                                        c["shape_class"]):
        if method == "bem":
            lines.setdefault((nu, ca), []).append((lam, cls))
    worst = 0.0
    for (nu, _), pts in lines.items():
        pts.sort()
        for (l1, c1), (l2, c2) in zip(pts, pts[1:]):
            if c1 == "parachute" and c2 == "bullet":
                worst = max(worst, *(abs(nu - (1.126 - 0.29 * lam)) for lam in (l1, l2)))
    print(f"Chen's transition line to the ends of our parachute-bullet brackets: <= "
          f"{worst:.3f} in nu (TRANSITION_BAND_NU)")


def small_objects() -> None:
    """Next-term coefficients of the small rigid sphere and the small clean drop (BEM)."""
    from bem.drop import solve_drop
    from bem.solve import solve_sphere
    c_v, c_p = [], []   # BEM sphere to tol 1e-10
    for lam in (0.05, 0.1, 0.2, 0.3, 0.4, 0.5):
        r = solve_sphere(lam, tol=1e-10)
        c_v.append((r.V_over_U - (2 - 4 / 3 * lam**2)) / lam**5)
        c_p.append((r.dp_plus_R0 / (16 * lam**6) - 1) / lam**5)
    print(f"sphere: c_V {min(c_v):.2f} to {max(c_v):.2f}, c_P {min(c_p):.2f} to {max(c_p):.2f} "
          "(SMALL_SPHERE_SPEED_K, SMALL_SPHERE_DP_K)")
    d_v = d_p = 0.0
    for lam in (0.2, 0.3, 0.5):
        for ca in (0.1, 0.5):
            r = solve_drop(lam, ca)
            d_v = max(d_v, abs(r.V_over_U - (2 - 0.8 * lam**2)) / lam**5)
            d_p = max(d_p, abs(r.dp_plus_R0 / (4.8 * lam**6) - 1) / lam**5)
    print(f"drop (Ca <= 0.5): |V/U - law|/lam^5 <= {d_v:.2f}, |dp+/law - 1|/lam^5 <= {d_p:.2f} "
          "(SMALL_DROP_SPEED_K, SMALL_DROP_DP_K)")


def main() -> int:
    from correlations.solution_map import read_points
    points = [p for p in read_points(BUILD) if p["success"]]
    print(f"{len(points)} converged points of {BUILD}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        near_critical(points)
        small_vesicles(points)
        transition_band()
        small_objects()
    return 0


if __name__ == "__main__":
    sys.exit(main())
