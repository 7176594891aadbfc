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

Resource envelope (checked before any BEM work; measured on 2 shared cores, Gauss order 16):

* one mesh has at most :data:`MAX_UNKNOWNS` = 4000 unknowns (2 per node of the sphere, wall
  and inlet): its dense system takes ~25 N² bytes (N = 4096: peak RSS 0.55 GB) and one LU
  factorisation ~1.5 s, the longest uninterruptible call. The automatic refinement stops at
  the last mesh under the cap (reported as not converged); an explicit ``panels`` above it is
  refused. A whole solve then stays under ~30 s and 0.6 GB.
* near contact the panels needed grow like (1 - a/R)^(-1/2) (:func:`initial_panels`): a/R
  whose first refinement pair does not fit the cap (a/R > ~0.996) is refused up front; use the
  near-contact result V/U ≈ 1 + 4ε/3, ε = 1 - a/R (Bungay & Brenner 1973).
  Measured: a/R = 0.9, 0.95, 0.98 converge to tol = 1e-10 in 1.4–2.5 s; from a/R = 0.99 the
  quiescent-tube drag K (~ε^(-5/2)) has a round-off floor above 1e-10 (relative pair difference
  3e-10 at 0.99, 1e-9 to 5e-9 at 0.995, 3e-8 at 0.998, while V/U and Δp⁺ agree to 1e-13):
  such runs stop at the cap unconverged unless ``tol`` is loosened (1e-9 at 0.99). The default
  ``tol`` = 1e-8 is therefore met up to a/R = 0.995 (the outputs are then accurate to far
  better than any use needs); 1e-10 is reachable below a/R ≈ 0.98.
* small spheres: Δp⁺R/(ηU) ≈ 16λ⁵ drowns in round-off (the refinement pair differs by
  1e-16–7e-16 whatever the mesh), so a relative ``tol`` is reachable only for
  λ >= (4e-16/(16 tol))^(1/5) (0.013 at the default tol = 1e-8, 0.048 at 1e-10); smaller λ are refused with the
  small-sphere limit (:func:`small_sphere_limit`), which is then more accurate than the
  tolerance asked for. Below λ = :data:`LAM_MIN` = 1e-3 the BEM is refused at any tol (the
  limit is exact to round-off there).
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np

from lubrication.checks import Deadline, InvalidParameterError, check_range
from lubrication.results import Status

from .assembly import assemble_influence, bordered_system
from .geometry import sphere_in_tube, wall_half_length
from .quadrature import DEFAULT_ORDER, DEFAULT_TOL, NEAR_FACTOR
from .results import SphereResult

__all__ = ["LAM_MIN", "MAX_UNKNOWNS", "check_sphere_inputs", "initial_panels",
           "mesh_unknowns", "small_sphere_limit", "solve_sphere", "solve_sphere_mesh",
           "sphere_drag"]

log = logging.getLogger(__name__)

#: unknowns of one mesh at most (memory ~25 N^2 bytes, one LU ~1.5 s at the cap; see above)
MAX_UNKNOWNS = 4000
#: smallest a/R the BEM accepts at any tolerance (the small-sphere limit is exact below)
LAM_MIN = 1e-3
#: the meshed wall ends where the sphere's disturbance has decayed to this (wall_half_length)
WALL_TOL = 1e-13
#: absolute round-off of Δp⁺R/(ηU) between two meshes (measured 6e-17 to 7e-16, a/R 1e-3-0.05)
_DP_ROUNDOFF = 4e-16


def initial_panels(lam: float) -> int:
    """Starting number of sphere panels: 4 for loose spheres, more as the gap 1 - lam closes."""
    gap = 1.0 - lam
    return int(max(4, math.ceil(2.0 + 1.2 / math.sqrt(gap))))


def small_sphere_limit(lam: float) -> dict:
    r"""Small-sphere limit of the free sphere: :math:`V/U = 2 - \tfrac43\lambda^2 + O(\lambda^5)`
    (Faxén) and :math:`\Delta p^+a/(\eta U) = 16\lambda^6(1 + O(\lambda^5))` (Chen et al. 2020
    eq. small1, small2).

    Examples
    --------
    >>> small_sphere_limit(0.01)["V_over_U"]
    1.9998666666666667
    """
    return {"V_over_U": 2.0 - 4.0 / 3.0 * lam**2, "dp_plus_R0": 16.0 * lam**6}


def lam_min(tol: float) -> float:
    """Smallest a/R at which a refinement pair can agree to the relative ``tol`` in Δp⁺."""
    return max(LAM_MIN, (_DP_ROUNDOFF / (16.0 * tol)) ** 0.2)


def mesh_unknowns(lam: float, n_panels: int, order: int = DEFAULT_ORDER,
                  half_length: float | None = None) -> int:
    """Unknowns of the sphere mesh with ``n_panels`` panels (geometry only, no BEM work)."""
    geom = sphere_in_tube(lam, n_panels, p=order, half_length=half_length)
    c = geom.panel_counts
    return 2 * c["order"] * (c["body"] + c["wall"] + c["inlet"])


def _largest_panels(lam, order, half_length) -> int:
    """Largest panel count whose mesh has at most MAX_UNKNOWNS unknowns (0 if none)."""
    lo, hi = 2, 4096
    if mesh_unknowns(lam, 3, order, half_length) > MAX_UNKNOWNS:
        return 0
    lo = 3
    while hi - lo > 1:                      # unknowns grow with the panel count
        mid = (lo + hi) // 2
        if mesh_unknowns(lam, mid, order, half_length) <= MAX_UNKNOWNS:
            lo = mid
        else:
            hi = mid
    return lo


def check_sphere_inputs(lam, *, panels=None, tol=1e-8, order=DEFAULT_ORDER,
                        half_length=None, max_panels=None, max_time=None):
    """Check the inputs of :func:`solve_sphere` against their ranges and the resource envelope
    (module docstring); no BEM work, no numba. Returns (lam, panels, tol, max_panels, order,
    half_length) as Python numbers. Raises :class:`InvalidParameterError` naming the input."""
    lam = float(check_range("lam", lam, 0.0, 1.0, lo_open=True, hi_open=True,
                            reason="the sphere must fit inside the tube (a < R)"))
    tol = float(check_range("tol", tol, 1e-14, 1e-1))
    order = int(check_range("order", order, 2, 40))
    if half_length is not None:
        half_length = float(check_range("half_length", half_length, lam, 1e3, lo_open=True))
    if max_time is not None:
        Deadline(max_time)                               # checks 0 < max_time < inf
    smallest = lam_min(tol)
    if lam < smallest:
        lim = small_sphere_limit(lam)
        raise InvalidParameterError(
            "lam", lam, f"{smallest:.3g} <= lam < 1 at tol={tol:g}",
            f"for smaller spheres the extra pressure drop dp+ R/(eta U) ~ 16 lam^5 = "
            f"{16 * lam**5:.3g} is so small that its round-off (~4e-16) exceeds tol, "
            f"so the BEM cannot meet tol (a/R >= {LAM_MIN:g} with a larger tol); the "
            f"small-sphere limit is accurate to O(lam^5) there: V/U = 2 - (4/3) lam^2 = "
            f"{lim['V_over_U']:.10g}, dp+ a/(eta U) = 16 lam^6 = {lim['dp_plus_R0']:.4g}")
    cap = None

    def envelope():
        nonlocal cap
        if cap is None:
            cap = _largest_panels(lam, order, half_length)
        return cap
    if panels is not None:
        panels = check_range("panels", panels, 3, 4096)
        if float(panels) != int(panels):
            raise InvalidParameterError("panels", float(panels), "an integer >= 3")
        panels = int(panels)
        if mesh_unknowns(lam, panels, order, half_length) > MAX_UNKNOWNS:
            raise InvalidParameterError(
                "panels", panels, f"3 <= panels <= {envelope()} at a/R = {lam:g}",
                f"a mesh may have at most {MAX_UNKNOWNS} unknowns (memory and Ctrl-C response "
                "of one dense LU factorisation)")
    else:
        if max_panels is not None:
            max_panels = check_range("max_panels", max_panels, 3, 4096)
            if float(max_panels) != int(max_panels):
                raise InvalidParameterError("max_panels", float(max_panels), "an integer >= 3")
            max_panels = int(max_panels)
        n0 = initial_panels(lam)
        if mesh_unknowns(lam, math.ceil(1.5 * n0), order, half_length) > MAX_UNKNOWNS:
            eps = 1.0 - lam
            raise InvalidParameterError(
                "lam", lam, f"0 < lam <= {_largest_lam(order, half_length):.4g}",
                f"nearer contact (here gap 1 - a/R = {eps:.3g}) the first refinement pair needs "
                f"more than {MAX_UNKNOWNS} unknowns (memory and time envelope of the BEM); "
                f"use the near-contact lubrication result V/U ~ 1 + 4 eps/3 = "
                f"{1 + 4 * eps / 3:.6g} (relative error O(eps^2))")
    return lam, panels, tol, max_panels, order, half_length


def _largest_lam(order, half_length) -> float:
    """Largest a/R whose first automatic refinement pair fits the envelope (bisection on the
    gap, geometry only)."""
    lo, hi = 0.9, 1.0 - 1e-6
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if mesh_unknowns(mid, math.ceil(1.5 * initial_panels(mid)), order,
                         half_length) <= MAX_UNKNOWNS:
            lo = mid
        else:
            hi = mid
    return lo


def solve_sphere_mesh(lam: float, n_panels: int, *, order: int = DEFAULT_ORDER,
                      half_length: float | None = None, near: float | None = NEAR_FACTOR,
                      quad_tol: float = DEFAULT_TOL) -> dict:
    """Solve both sphere problems on one mesh; returns a dict of outputs and diagnostics.

    Keys: V_over_U, dp_plus_R, dp_plus_R0, drag_K, dp_translating_R, residual,
    null_multiplier, panels, half_length, assembly_s, solve_s.
    """
    lam = float(check_range("lam", lam, LAM_MIN, 1.0, hi_open=True,
                            reason="the sphere must fit inside the tube (a < R); below "
                                   f"a/R = {LAM_MIN:g} use small_sphere_limit"))
    if half_length is None:
        half_length = wall_half_length(lam, WALL_TOL)
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


def solve_sphere(lam: float, *, panels: int | None = None, tol: float = 1e-8,
                 order: int = DEFAULT_ORDER, half_length: float | None = None,
                 max_panels: int | None = None, near: float | None = NEAR_FACTOR,
                 quad_tol: float = DEFAULT_TOL, max_time: float | None = None) -> SphereResult:
    r"""Free rigid sphere of radius a = lam R on the axis of Poiseuille flow in a tube.

    Parameters
    ----------
    lam : float
        Confinement a/R [-]: lam_min(tol) <= lam < 1 (0.013 at the default tol; smaller
        spheres are refused with the small-sphere limit, see the module docstring), and near
        contact no larger than the resource envelope allows (~0.996).
    panels : int, optional
        Number of panels on the sphere (the wall and inlet meshes follow). If given, the
        result is computed with ``panels`` and checked against ``round(2 panels / 3)``;
        if None, the panel count grows by 3/2 from :func:`initial_panels` until the
        refinement pair agrees to ``tol`` (relative) in V/U, Δp⁺ and K, or ``max_panels``,
        or the last mesh within :data:`MAX_UNKNOWNS` unknowns.
    tol : float
        Relative tolerance of the automatic refinement, 1e-14 <= tol <= 0.1 [-].
    order : int
        Gauss–Legendre nodes per panel.
    half_length : float, optional
        Meshed half-length of the wall [R]; default from the exp(-4.47 x/R) decay of the
        disturbance to 1e-13.
    max_time : float, optional
        Wall-time budget [s], checked between meshes (:class:`lubrication.checks.Deadline`);
        when spent the result is returned with status TIME_LIMIT. Default: no limit.

    Returns
    -------
    SphereResult
        V/U, Δp⁺R/(ηU), Δp⁺a/(ηU), the quiescent-tube drag K and diagnostics; ``status``
        UNRESOLVED when the refinement pair differs by more than ``tol`` at the last mesh,
        TIME_LIMIT when ``max_time`` stopped the refinement.

    Raises
    ------
    InvalidParameterError
        Bad input, or a request outside the resource envelope (checked before any BEM work).

    Examples
    --------
    >>> res = solve_sphere(0.1, panels=4)
    >>> round(res.V_over_U, 6), round(res.dp_plus_R0 / (16 * 0.1**6), 4)
    (1.98667, 1.0)
    """
    t_start = time.perf_counter()
    lam, panels, tol, max_panels, order, half_length = check_sphere_inputs(
        lam, panels=panels, tol=tol, order=order, half_length=half_length,
        max_panels=max_panels, max_time=max_time)
    deadline = Deadline(max_time)
    stop, timed_out = "", False

    def mesh(n):
        return solve_sphere_mesh(lam, n, order=order, half_length=half_length, near=near,
                                 quad_tol=quad_tol)
    if panels is not None:
        coarse = mesh(max(2, round(2 * panels / 3)))
        fine = mesh(panels)
        history = [coarse, fine]
    else:
        n = initial_panels(lam)
        coarse = mesh(n)
        history = [coarse]
        while True:
            n = math.ceil(1.5 * n)
            if max_panels is not None and n > max_panels and len(history) > 1:
                stop = f"stopped at max_panels={max_panels}"
                break
            if mesh_unknowns(lam, n, order, half_length) > MAX_UNKNOWNS:
                if len(history) > 1:
                    stop = (f"stopped at the resource cap of {MAX_UNKNOWNS} unknowns per mesh "
                            f"({history[-1]['panels']['body']} sphere panels)")
                    break
            if deadline.expired():
                stop, timed_out = deadline.message(), True
                break
            fine = mesh(n)
            history.append(fine)
            err = _estimates(fine, coarse)
            if all(err[k] <= tol * abs(fine[k]) for k in _OUTPUTS):
                break
            coarse = fine
        if len(history) < 2:                 # the deadline struck before the second mesh
            fine = coarse
        else:
            fine, coarse = history[-1], history[-2]
    err = _estimates(fine, coarse) if fine is not coarse else {k: math.nan for k in _OUTPUTS}
    converged = fine is not coarse and all(err[k] <= tol * abs(fine[k]) for k in _OUTPUTS)
    # the refinement ends with the pair within tol, at a resource cap (the error estimate is
    # then above tol) or at the deadline
    status = (Status.CONVERGED if converged else Status.TIME_LIMIT if timed_out
              else Status.UNRESOLVED)
    if converged:
        message = "converged"
    else:
        bad = [k for k in _OUTPUTS if not err[k] <= tol * abs(fine[k])]
        message = (f"refinement pair differs by more than tol={tol:g} (relative): "
                   + ", ".join(f"{k} {err[k] / abs(fine[k]):.2e}" for k in bad)
                   if fine is not coarse else "no refinement pair")
        if stop:
            message = f"{stop}; {message}"
        if "drag_K" in bad and lam >= 0.985:
            message += (" (near contact the drag K ~ (1 - a/R)^(-5/2) has a round-off floor "
                        "above 1e-10: loosen tol, e.g. 1e-8)")
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
        drag_K_err=err["drag_K"], status=status, tol=tol,
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
