r"""Rigid sphere on the axis of a tube: user API of the axisymmetric Stokes BEM.

Nondimensionalisation (stated once): tube radius R = 1, viscosity eta = 1, mean velocity of the
undisturbed Poiseuille flow U = 1 (centreline 2U); the sphere radius is a = lam.

Two problems share one assembled single-layer operator (:mod:`bem.assembly`):

* **free sphere in Poiseuille flow** at fixed flow rate: force-free, translating at V;
  outputs V/U and the extra pressure drop Δp⁺ (reciprocal theorem closure);
* **translating sphere in a quiescent tube** (fluid at rest far away, zero net flux):
  drag K = F/(6π η a V) and the pressure rise across the sphere.

Every output is computed on a refinement pair (the requested panel count and 2/3 of it, or an
automatic sequence growing by 3/2 until the pair agrees to ``tol``); the difference is reported
as the error estimate.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from lubrication.checks import InvalidParameterError, check_range

from .assembly import assemble_influence, bordered_system
from .geometry import sphere_in_tube, wall_half_length
from .quadrature import DEFAULT_ORDER, DEFAULT_TOL, NEAR_FACTOR
from .results import SphereResult

__all__ = ["initial_panels", "solve_sphere", "solve_sphere_mesh", "sphere_drag"]

log = logging.getLogger(__name__)


def initial_panels(lam: float) -> int:
    """Starting number of sphere panels: 4 for loose spheres, more as the gap 1 - lam closes."""
    gap = 1.0 - lam
    return int(max(4, math.ceil(2.0 + 1.2 / math.sqrt(gap))))


def solve_sphere_mesh(lam: float, n_panels: int, *, order: int = DEFAULT_ORDER,
                      half_length: float | None = None, near: float | None = NEAR_FACTOR,
                      quad_tol: float = DEFAULT_TOL) -> dict:
    """Solve both sphere problems on one mesh; returns a dict of outputs and diagnostics.

    Keys: V_over_U, dp_plus_R, dp_plus_R0, drag_K, dp_translating_R, residual,
    null_multiplier, panels, half_length, assembly_s, solve_s.
    """
    lam = float(check_range("lam", lam, 0.0, 1.0, lo_open=True, hi_open=True,
                            reason="the sphere must fit inside the tube (a < R)"))
    if half_length is None:
        half_length = wall_half_length(lam, 1e-13)
    t0 = time.perf_counter()
    geom = sphere_in_tube(lam, n_panels, p=order, half_length=half_length)
    blocks = assemble_influence(geom, near=near, tol=quad_tol)
    t1 = time.perf_counter()
    free = bordered_system(blocks, geom, "free")
    z = np.linalg.solve(free.A, free.b)
    trans = bordered_system(blocks, geom, "translating", V=1.0)
    zt = np.linalg.solve(trans.A, trans.b)
    t2 = time.perf_counter()
    res = max(np.max(np.abs(free.A @ z - free.b)) / np.max(np.abs(free.b)),
              np.max(np.abs(trans.A @ zt - trans.b)) / np.max(np.abs(trans.b)))
    nb = free.n_body
    qt = zt[: 2 * nb].reshape(-1, 2)
    body = geom.body
    force = -np.sum(2.0 * math.pi * body.r.ravel() * body.w.ravel() * qt[:, 0])
    dp = float(z[free.i_dp])
    return {
        "V_over_U": float(z[free.i_V]),
        "dp_plus_R": dp,
        "dp_plus_R0": dp * lam,
        "drag_K": float(-force / (6.0 * math.pi * lam)),
        "dp_translating_R": float(zt[trans.i_dp]),
        "residual": float(res),
        "null_multiplier": float(max(abs(z[free.i_mu]), abs(zt[trans.i_mu]))),
        "panels": geom.panel_counts,
        "half_length": float(half_length),
        "assembly_s": t1 - t0,
        "solve_s": t2 - t1,
    }


_OUTPUTS = ("V_over_U", "dp_plus_R", "drag_K")


def _estimates(fine: dict, coarse: dict) -> dict:
    return {k: abs(fine[k] - coarse[k]) for k in _OUTPUTS}


def solve_sphere(lam: float, *, panels: int | None = None, tol: float = 1e-10,
                 order: int = DEFAULT_ORDER, half_length: float | None = None,
                 max_panels: int = 256, near: float | None = NEAR_FACTOR,
                 quad_tol: float = DEFAULT_TOL) -> SphereResult:
    r"""Free rigid sphere of radius a = lam R on the axis of Poiseuille flow in a tube.

    Parameters
    ----------
    lam : float
        Confinement a/R, 0 < lam < 1 [-].
    panels : int, optional
        Number of panels on the sphere (the wall and inlet meshes follow). If given, the
        result is computed with ``panels`` and checked against ``round(2 panels / 3)``;
        if None, the panel count grows by 3/2 from :func:`initial_panels` until the
        refinement pair agrees to ``tol`` (relative) in V/U, Δp⁺ and K, or ``max_panels``.
    tol : float
        Relative tolerance of the automatic refinement [-].
    order : int
        Gauss–Legendre nodes per panel.
    half_length : float, optional
        Meshed half-length of the wall [R]; default from the exp(-4.47 x/R) decay of the
        disturbance to 1e-13.

    Returns
    -------
    SphereResult
        V/U, Δp⁺R/(ηU), Δp⁺a/(ηU), the quiescent-tube drag K and diagnostics.

    Examples
    --------
    >>> res = solve_sphere(0.1, panels=4)
    >>> round(res.V_over_U, 6), round(res.dp_plus_R0 / (16 * 0.1**6), 4)
    (1.98667, 1.0)
    """
    t_start = time.perf_counter()
    lam = float(check_range("lam", lam, 0.0, 1.0, lo_open=True, hi_open=True,
                            reason="the sphere must fit inside the tube (a < R)"))
    tol = float(check_range("tol", tol, 1e-14, 1e-1))
    max_panels = int(check_range("max_panels", max_panels, 3, 4096))
    if panels is not None:
        panels = int(check_range("panels", panels, 3, 4096))
        if panels != float(panels):
            raise InvalidParameterError("panels", panels, "an integer >= 3")
        coarse = solve_sphere_mesh(lam, max(2, round(2 * panels / 3)), order=order,
                                   half_length=half_length, near=near, quad_tol=quad_tol)
        fine = solve_sphere_mesh(lam, panels, order=order, half_length=half_length,
                                 near=near, quad_tol=quad_tol)
        history = [coarse, fine]
    else:
        n = initial_panels(lam)
        coarse = solve_sphere_mesh(lam, n, order=order, half_length=half_length, near=near,
                                   quad_tol=quad_tol)
        history = [coarse]
        while True:
            n = math.ceil(1.5 * n)
            fine = solve_sphere_mesh(lam, n, order=order, half_length=half_length, near=near,
                                     quad_tol=quad_tol)
            history.append(fine)
            err = _estimates(fine, coarse)
            if all(err[k] <= tol * abs(fine[k]) for k in _OUTPUTS) or n >= max_panels:
                break
            coarse = fine
    err = _estimates(fine, coarse)
    converged = all(err[k] <= tol * abs(fine[k]) for k in _OUTPUTS)
    message = ("converged" if converged else
               f"refinement pair differs by more than tol={tol:g} (relative): " +
               ", ".join(f"{k} {err[k] / abs(fine[k]):.2e}" for k in _OUTPUTS))
    if not converged:
        log.warning("solve_sphere(lam=%g): %s", lam, message)
    timings = {"assembly_s": sum(h["assembly_s"] for h in history),
               "solve_s": sum(h["solve_s"] for h in history),
               "total_s": time.perf_counter() - t_start,
               "meshes": len(history)}
    return SphereResult(
        lam=lam, V_over_U=fine["V_over_U"], dp_plus_R=fine["dp_plus_R"],
        dp_plus_R0=fine["dp_plus_R0"], drag_K=fine["drag_K"],
        dp_translating_R=fine["dp_translating_R"],
        V_over_U_err=err["V_over_U"], dp_plus_R_err=err["dp_plus_R"],
        drag_K_err=err["drag_K"], converged=converged, tol=tol,
        panels=fine["panels"], panels_coarse=coarse["panels"],
        half_length=fine["half_length"], residual=fine["residual"],
        null_multiplier=fine["null_multiplier"], timings=timings, message=message)


def sphere_drag(lam: float, **kwargs) -> float:
    r"""Drag K = F/(6π η a V) of a sphere translating on the axis of a tube of quiescent fluid
    (fluid at rest far away, hence zero net flux), by the BEM; keyword arguments as in
    :func:`solve_sphere`. Compare Haberman & Sayre (1958), Bohlin (1960).

    Examples
    --------
    >>> round(sphere_drag(0.1, panels=4), 4)
    1.2632
    """
    return solve_sphere(lam, **kwargs).drag_K
