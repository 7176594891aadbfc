r"""One level of the mode ladder: the free shape modes at one resolution, solved by
Levenberg–Marquardt on the steady residual of :class:`bem.vesicle.VesicleOperator`.

* The weighted residual :math:`\sqrt{w_i}(u_i - V e_x)` (both components) is minimised by
  Levenberg–Marquardt with a forward-difference Jacobian and Broyden updates
  (:func:`bem.newton.levenberg_marquardt`, shared with the drop). The Jacobian's points are
  evaluated concurrently (:func:`_residuals`), each at the tension and V of the state it
  differentiates, the differences projected off their columns: the variable-projection
  Jacobian of Kaufman 1975, whose J^T F is the full derivative's
  (:meth:`~bem.vesicle.VesicleOperator.fixed_residual`; columns within 6e-6 of the full
  ones at a 24-mode minimum of (0.9, 1.0)); from :data:`LINEARISED_POINTS` points on, linearised
  about that state (:meth:`~bem.vesicle.VesicleOperator.taylor`). Every point starts its
  area secant from the same slope, so the result does not depend on the thread count or on the
  order of the points.
* A level on the density of the level below starts from that level's Jacobian interpolated to
  its nodes and differences only its new modes (:func:`_prolonged_columns`): at (0.9, 1.0) 57
  BEM evaluations instead of 113, outputs within 3e-8 of the fresh-Jacobian minimum.
* Long vesicles near lam_c have a slow, strongly curved valley of ``|F|`` (volume moved between
  the caps through the thin film); they use :func:`bem.newton.valley_levenberg_marquardt`
  (directional Jacobian updates, extrapolation along the valley), which reaches the minimum
  where the plain method stops on the valley's side (at (0.6, 1.94), 64 modes: γ_max 799
  instead of 932; docs/validation.md). Its floor test certifies with the Jacobian differenced
  at this level while the iterate has moved by less than :data:`bem.newton.RECENT_STEP` since,
  and a Jacobian prolonged from the level below is replaced by a difference Jacobian once five
  steps with it together reduce ``|F|`` by less than 2 % (:data:`bem.newton.CRAWL_GAIN`).
* Budgets (:func:`solve_level`): ``max_iter`` iterations (valley: 8 ``max_iter`` cheap ones);
  difference Jacobians 3 on the first level of a ladder, 8 on the others (valley: 2 and 4, and 1
  on a carrier level, which only seeds the next).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext

import numpy as np

from lubrication.checks import InvalidParameterError

from ..newton import difference_jacobian, levenberg_marquardt, valley_levenberg_marquardt
from ..quadrature import barycentric_weights, gauss_legendre, serial_assembly
from ..shape import SpectralCurve, fit_curve
from ..threads import single_threaded_blas
from .operator import VesicleOperator, range_projector, workers

__all__ = ["LINEARISED_POINTS", "level_function", "solve_level"]


def _prolonged_columns(coarse: VesicleOperator, coarse_state: dict, op: VesicleOperator,
                       state: dict) -> dict:
    """Jacobian columns of ``op``'s free modes that ``coarse`` also has, from the coarse
    level's final Jacobian (``coarse_state["jacobian"]``, weighted rows at its nodes)
    interpolated in tau to ``op``'s nodes: {free index: column}; empty if the two levels
    solve for different area modes or have different arc-length densities (a mode is then
    another shape change). The unweighted rows d(u - V e_x)/dc are smooth in tau within a
    coarse panel (the velocity of a smooth shape), so the panel's Lagrange interpolant
    carries them."""
    J = coarse_state.get("jacobian")
    if (J is None or coarse.area_mode != op.area_mode
            or not np.array_equal(coarse.density, op.density)):
        return {}
    p = coarse.p
    tn, _ = gauss_legendre(p)
    bw = barycentric_weights(p)
    br = coarse.breaks
    t = op.tau.ravel()
    i = np.clip(np.searchsorted(br, t, side="right") - 1, 0, br.size - 2)
    s = 2.0 * (t - br[i]) / (br[i + 1] - br[i]) - 1.0
    d = s[:, None] - tn[None, :]
    hit = d == 0.0
    d[hit] = 1.0
    L = bw / d
    L[hit.any(axis=1)] = hit[hit.any(axis=1)]
    L /= L.sum(axis=1, keepdims=True)
    cols = i[:, None] * p + np.arange(p)
    sw_c = np.repeat(np.sqrt(coarse_state["panels"].w.ravel()), 2)
    sw_f = np.repeat(np.sqrt(state["panels"].w.ravel()), 2)
    G = J / sw_c[:, None]                                   # unweighted rows
    Gf = np.empty((sw_f.size, J.shape[1]))
    for a in (0, 1):                                        # x rows, r rows
        Gf[a::2] = np.einsum("ik,ikj->ij", L, G[a::2][cols])
    Gf *= sw_f[:, None]
    free_c = [m for m in range(coarse.disc.n_modes) if m not in coarse._dependent()]
    free_f = [m for m in range(op.disc.n_modes) if m not in op._dependent()]
    where = {m: j for j, m in enumerate(free_c)}
    return {jf: Gf[:, where[m]] for jf, m in enumerate(free_f) if m in where}


#: fixed-load points evaluated together from this many on (a difference Jacobian, not the few points
#: of a directional update) share the influence of the membrane expanded about the state
#: differentiated (:meth:`~bem.vesicle.VesicleOperator.taylor`: 5 or 7 ring Stokeslets per far pair
#: and 7 per quadrature point of a near pair once, against one of each per point); fewer points (the
#: 3 of a directional update) are not worth it: the expansion costs about what 3 points save
LINEARISED_POINTS = 8


def _residuals(op: VesicleOperator, modes_list, fixed=None) -> list:
    """Weighted residuals F of the shapes ``modes_list`` (None where the operator rejects one),
    evaluated ``workers()`` at a time, each on one thread (serial assembly; the products and kernels
    release the GIL); with ``fixed`` = (g, V, panels) of a state, the residuals at those fixed
    tension coefficients and speed (:meth:`~bem.vesicle.VesicleOperator.fixed_residual`), from
    LINEARISED_POINTS points on with the wall–membrane far field expanded about the state's panels
    (:meth:`~bem.vesicle.VesicleOperator.linearised_finish`). Every shape starts its area secant
    from the same slope, so the result does not depend on the number of threads or on the order.
    Measured at (0.6, 1.94), 96 modes, on 2 cores: 0.08 s per evaluation against 0.12 s one after
    the other."""
    slope = op._area_slope
    taylor = None
    if fixed is not None and len(modes_list) >= LINEARISED_POINTS:
        taylor = op.taylor(fixed[2])

    def one(modes, serial=True):
        with serial_assembly() if serial else nullcontext(), single_threaded_blas():
            try:
                curve = op.curve(modes, slope=slope)
                if taylor is not None:
                    return op.linearised_residual(curve, fixed[0], fixed[1], taylor)
                if fixed is not None:
                    return op.fixed_residual(curve, *fixed[:2])
                return op.evaluate(curve)["F"]
            except InvalidParameterError:
                return None

    n_workers = min(workers(), len(modes_list))
    if n_workers <= 1:
        out = [one(m, serial=False) for m in modes_list]
    else:
        pool = ThreadPoolExecutor(n_workers)
        try:
            out = list(pool.map(one, modes_list))
        finally:                   # on Ctrl-C: drop the queued shapes, finish the running ones
            pool.shutdown(wait=True, cancel_futures=True)
    return out if taylor is None else op.linearised_finish(taylor, out)


def level_function(op: VesicleOperator, template):
    """The residual of one level as :mod:`bem.newton` takes it: ``fun(z)`` = (F, state) of
    the shape with free modes z (the other modes from ``template``), with ``fun.many`` (independent
    points evaluated concurrently, :func:`_residuals`) and ``fun.fixed`` (Jacobian points at the
    tension and V of the state differentiated, projected off their columns: Kaufman's
    variable-projection Jacobian, :meth:`~bem.vesicle.VesicleOperator.fixed_residual`)."""
    def fun(z):
        st = op.evaluate(op.curve(op.full(z, template)))
        return st["F"], st

    def many(points, at=None):
        return _residuals(op, [op.full(z, template) for z in points], at)

    def fixed(state):
        at = (state["g"], state["V"], state["panels"])
        return (lambda points: many(points, at)), range_projector(state["M"])

    fun.many, fun.fixed = many, fixed
    return fun


def solve_level(nu, lam, ca_b, disc, seed: SpectralCurve, n_tension, *, xtol, max_iter,
                seed_level=False, valley=False, carrier=False, deadline=None, coarse=None,
                shear=None):
    """Levenberg–Marquardt at one resolution from ``seed``
    (:func:`bem.newton.valley_levenberg_marquardt` if ``valley``, with 8 ``max_iter`` cheap
    iterations, else :func:`bem.newton.levenberg_marquardt`); returns (state, op, info), the
    state with the final Jacobian. ``seed_level``: the first level of a ladder (a smaller
    Jacobian budget); ``carrier``: a valley level that only seeds the next one (one difference
    Jacobian). ``coarse``: (op, state) of the level below (either method): its Jacobian,
    interpolated to this level's nodes, gives the columns of the modes it has, and only the
    new modes are differenced (:func:`_prolonged_columns`). ``shear``: the red-cell membrane's
    shear elasticity (:class:`lubrication.membrane.MembraneShear`), passed to the operator
    (None: a vesicle)."""
    ref = fit_curve(seed.sample, 0.0, 1.0, disc.n_modes, density=seed.density) \
        if seed.n_modes != disc.n_modes else seed
    op = VesicleOperator(nu, lam, ca_b, disc, ref, n_tension, shear=shear)
    template = op.curve(ref.modes).modes.copy()
    fun = level_function(op, template)
    z0, start, J0, extra = op.free(template), None, None, 0
    if coarse is not None and not (deadline is not None and deadline.expired()):
        try:
            start, extra = fun(z0), 1
        except InvalidParameterError:                # reported by the Levenberg–Marquardt
            start = None
        known = _prolonged_columns(*coarse, op, start[1]) if start else {}
        if known:
            J0, n = difference_jacobian(fun, z0, start[0], 1e-7, known, start[1])
            extra += n
    if valley:
        rep = valley_levenberg_marquardt(fun, z0, tol=xtol, max_iter=8 * max_iter,
                                         deadline=deadline, start=start, jacobian=J0,
                                         max_jacobians=1 if carrier else 2 if seed_level else 4)
    else:
        rep = levenberg_marquardt(fun, z0, tol=xtol, max_iter=max_iter,
                                  max_jacobians=3 if seed_level else 8, deadline=deadline,
                                  stall=0.9 if seed_level else None, floor_ratio=0.99,
                                  start=start, jacobian=J0)
    rep.evaluations += extra
    if rep.payload is None:
        raise InvalidParameterError("initial", "a shape rejected by the operator", rep.message)
    state = rep.payload
    state["jacobian"] = rep.jacobian
    info = {"success": rep.success, "message": rep.message, "iterations": rep.iterations,
            "evaluations": rep.evaluations, "jacobians": rep.jacobians,
            "norm0": rep.history[0], "norm": rep.history[-1], "area_mode": op.area_mode}
    return state, op, info

