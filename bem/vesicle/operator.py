r"""The vesicle's BEM operator: the velocity of a membrane of given shape, its tension and speed by
least squares, the Jacobian points linearised about a state, the mesh, and a state's outputs.

Physics (Chen et al. 2020 §II, eq. E:fm; Pozrikidis 1992): the membrane loads the fluid with
:math:`q = f_b + f_\gamma` (:mod:`bem.membrane`); with equal viscosities the velocity is the
single layer of :math:`q` over the membrane plus the wall and inlet layers of the tube problem
(:mod:`bem.drop`, :mod:`bem.assembly`). In the frame moving with the vesicle a steady,
axisymmetric, inextensible membrane is at rest (r w_s = const = 0 from the poles), so the
steady state is a shape, a tension :math:`\gamma(\tau)` and a speed V with

.. math:: u(X_i) = V e_x \quad\text{at every membrane node (both components)},

volume, area and centroid fixed. Two rows are redundant at the solution (the null vector n of
the single layer and the global area-rate identity): the equations are solved in least squares.

Unknowns (:class:`~bem.vesicle.VesicleOperator`):

* shape: :class:`bem.shape.SpectralCurve` with N sine modes of the tangent angle; c_1 closes the
  curve, the length fixes the volume, the shift centres it (as for the drop), and one more mode
  (the ``area_mode``, the one with the largest effect on the area at the start) is solved for so
  that the area is exact. Volume, area and centring therefore hold to round-off.
* tension :math:`\gamma = \sum_{k=0}^{M-1} g_k\cos(k\pi\tau)` and V enter linearly: for each
  shape they are the linear least-squares solution (variable projection, Golub & Pereyra 1973),
  so the nonlinear unknowns are the N - 2 free shape modes (M = N tension modes).
* the wall, inlet and panel breaks are those of :class:`bem.drop.DropOperator`, fixed during one
  solve so that the residual is a smooth function of the modes; the wall is 4x coarser than the
  drop's and stops following a long vesicle's panels (:data:`WALL_REFINEMENT`,
  :data:`WALL_BODY_LENGTH`, :data:`WALL_BODY_PANELS`, :func:`~bem.vesicle.vesicle_discretisation`).

Jacobian points. :meth:`~bem.vesicle.VesicleOperator.fixed_residual` evaluates a shape at the
tension and V of the state differentiated (one load column instead of M + 1: Kaufman's
variable-projection Jacobian, whose J^T F is the full derivative's). From
:data:`bem.vesicle.level.LINEARISED_POINTS` points on (a difference Jacobian), the points share the
influence of the membrane expanded to first order in its geometry about that state
(:meth:`~bem.vesicle.VesicleOperator.taylor`, once per Jacobian): the far pairs of membrane and
wall, the wall's near panels on the membrane nodes and the membrane's near and self panels (in the
panels' Legendre coefficients and the nodes; their derivatives within 2.5e-10 of central differences
of the integrals), the inlet per point, the wall solves of all the points in one ``lu_solve``
(:meth:`~bem.vesicle.VesicleOperator.linearised_finish`). The linearised residual differs from the
exact one at second order in the displacement (at 96 modes of (0.6, 1.94): 1.9e-12 … 1.9e-6 for
steps 1e-8 … 1e-5), so at the Jacobian's step 1e-7 the columns of a 94-point Jacobian at the
converged 96-mode shape of (0.6, 1.94) are within 4.5e-6 of the largest column of exact differences:
these cancel the second-order terms of the two residuals of a difference, the linearised points do
not (``tests/bem/test_vesicle_linearised.py``).

Evaluations run concurrently, one per numba thread (:func:`bem.vesicle.level_function`):
the assembly serial on each thread, the products concurrent, the LAPACK calls under a lock.

Outputs of a state (:func:`level_outputs`, :func:`membrane_profile`, :func:`self_intersects`):
V/U, Δp⁺, the length, the film, the largest tension (a refined maximum, not a sampled one), the
volume and area errors, and the profile of shape and tension in arc length.
"""

from __future__ import annotations

import math
import threading

import numpy as np
import scipy.linalg as sla
from scipy.optimize import minimize_scalar

from lubrication.checks import InvalidParameterError
from lubrication.membrane import MembraneShear

from ..assembly import poiseuille
from ..drop import DropDiscretisation, DropOperator, panels_for
from ..membrane import bending_force, tension_basis, tension_force, tension_profile
from ..quadrature import (
    DEFAULT_ORDER,
    assembles_serially,
    barycentric_weights,
    gauss_legendre,
    gauss_table,
    influence,
    influence_pair,
    near_factor,
    self_rule,
    self_rule_panels,
)
from ..shape import SpectralCurve
from ..shear import shear_force

__all__ = ["LSTSQ_COND", "WALL_BODY_LENGTH", "WALL_BODY_PANELS", "WALL_REFINEMENT",
           "VesicleOperator", "level_outputs", "membrane_profile", "range_projector",
           "self_intersects", "vesicle_discretisation", "workers"]

_EIGHT_PI = 8.0 * math.pi

#: held around the LAPACK calls of an evaluation: two threads evaluating shapes at once (the
#: Jacobian points, :func:`bem.vesicle.level_function`) gave wrong wall densities from
#: concurrent ``lu_solve`` calls on one factorisation (scipy 1.17, OpenBLAS 0.3.30: errors of
#: order one; with the lock, or sequentially, identical results); the products between them
#: run concurrently
_LAPACK = threading.Lock()

#: relative singular-value cutoff of the tension/V least squares (gelsy's rcond)
LSTSQ_COND = 1e-13


class VesicleOperator(DropOperator):
    """Velocity of a membrane of given shape in the tube, tension and V by least squares.

    Wall, inlet, panel breaks and density are fixed from ``reference`` (as for the drop).
    ``n_tension`` cosine terms of the tension; ``area_mode`` the index of the mode solved for
    the area (default: the free mode with the largest area derivative at ``reference``).
    ``shear``: the in-plane shear elasticity of a red-cell membrane
    (:class:`lubrication.membrane.MembraneShear`, its area that of the vesicle,
    4π(λν^(-1/3))² in R²), whose load :func:`bem.shear.shear_force` joins the
    bending load; None (default) for a vesicle, whose loads are then those of the bending
    membrane alone, computed as without the option.
    """

    def __init__(self, nu: float, lam: float, ca_b: float, disc: DropDiscretisation,
                 reference: SpectralCurve, n_tension: int | None = None,
                 area_mode: int | None = None, shear: MembraneShear | None = None):
        super().__init__(lam, 1.0, disc, reference)
        self.nu = float(nu)
        self.ca_b = float(ca_b)
        self.kappa = self.lam**2 / self.ca_b
        self.area = 4.0 * math.pi * (self.lam * self.nu ** (-1.0 / 3.0)) ** 2
        if shear is not None and not abs(shear.area / self.area - 1.0) <= 1e-12:
            raise InvalidParameterError(
                "shear.area", shear.area, f"the vesicle's area {self.area:.12g} (to 1e-12)",
                "the shear reference is scaled to the cell's area 4 pi (lam nu^(-1/3))^2")
        self.shear = shear
        self.n_tension = int(n_tension or disc.n_modes)
        modes = reference.with_modes(disc.n_modes)
        self.area_mode = self._pick_area_mode(modes) if area_mode is None else int(area_mode)
        self._area_slope = 0.0                      # dA/dc of the last secant (curve)

    def _raw_curve(self, modes) -> SpectralCurve:
        return SpectralCurve.closed(modes, volume=self.volume, centroid=0.0,
                                    density=self.density)

    def _pick_area_mode(self, modes) -> int:
        base = self._raw_curve(modes).area()
        best, j_best = -1.0, 1
        for j in range(1, min(modes.size, 6)):
            m = modes.copy()
            m[j] += 1e-6
            d = abs(self._raw_curve(m).area() - base)
            if d > best:
                best, j_best = d, j
        return j_best

    def curve(self, modes, slope: float | None = None) -> SpectralCurve:
        """Closed, centred curve of the vesicle's volume and area; ``modes[area_mode]`` is
        replaced by the value that gives the area (secant iteration from the given value, its
        first step with the slope dA/dc ``slope``, default that of the previous call; a given
        slope is not stored, so that concurrent calls do not depend on each other)."""
        m = np.array(modes, dtype=float)
        j = self.area_mode
        x0 = m[j]
        c = self._raw_curve(m)
        f0 = c.area() - self.area
        if abs(f0) < 1e-14 * self.area:
            return c
        keep = slope is None
        slope = self._area_slope if keep else slope
        x1 = x0 - f0 / slope if slope else x0 + 1e-4 * max(1.0, abs(x0))
        for _ in range(40):
            m[j] = x1
            c = self._raw_curve(m)
            f1 = c.area() - self.area
            if abs(f1) < 1e-14 * self.area:
                if keep and f1 != f0 and x1 != x0:
                    self._area_slope = (f1 - f0) / (x1 - x0)
                return c
            if f1 == f0:
                break
            x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
        raise InvalidParameterError("modes", "a shape whose area cannot be adjusted",
                                    "a shape near the vesicle's area")

    def _dependent(self) -> list[int]:
        """c_1 closes the curve, the area mode gives the area."""
        return [0, self.area_mode]

    def velocity_columns(self, curve: SpectralCurve):
        r"""Membrane velocity as an affine function of the tension coefficients (one BEM solve).

        Returns (panels, u0, U, dp0, dp) with the velocity at the nodes (interleaved x, r;
        lab frame) :math:`u = u_0 + U g` for tension :math:`\gamma = \sum_k g_k\cos(k\pi\tau)`,
        and Δp⁺R/(ηU) :math:`= dp_0 + dp\cdot g` (reciprocal theorem, as for the drop).
        """
        return self._columns(curve)[:5]

    def wall_shear(self, curve: SpectralCurve, g) -> tuple[np.ndarray, np.ndarray]:
        r"""Shear stress of the fluid on the tube wall, :math:`\tau_w(x)` [ηU/R], at the wall
        nodes (x, tau_w): the Poiseuille value 4 minus the axial wall density of the disturbance
        (the force per area the wall exerts on the fluid, :mod:`bem.assembly`). Force balance
        on the fluid in the tube (the membrane load has zero resultant):
        :math:`\int(\tau_w - 4)\,2\pi R\,dx = \pi R^2\Delta p^+`. The wall shear rate is
        :math:`\tau_w/\eta` [U/R]."""
        qw = self._columns(curve)[5]
        q = qw[:, 0] + qw[:, 1:] @ np.asarray(g, dtype=float)
        return self.wall.x.ravel(), 4.0 - q[0::2]

    def _loads(self, curve: SpectralCurve, g=None):
        """Membrane panels and the load columns Q (interleaved x, r; bending force, then the
        tension modes) with their Δp⁺ columns; with tension coefficients ``g``, the one column
        of the total load (bending plus that tension). With ``shear``, the first column is
        the bending plus the shear load (:func:`bem.shear.shear_force`): neither depends on
        the tension."""
        drop = self.panels(curve)
        if np.max(drop.r) >= 1.0 - 1e-6:
            raise InvalidParameterError("shape", "a membrane touching the wall (closing film)",
                                        "a vesicle inside the tube (max r < 1)")
        tau = self.tau.ravel()
        nd = tau.size
        fb = bending_force(curve, tau, self.kappa)
        if self.shear is not None:
            fs = shear_force(curve, tau, self.shear)
            fb = (fb[0] + fs[0], fb[1] + fs[1])
        if g is None:
            T = tension_basis(curve, tau, self.n_tension)               # (M, 2, nd)
            Q = np.empty((2 * nd, self.n_tension + 1))
            Q[0::2, 0], Q[1::2, 0] = fb
            Q[0::2, 1:], Q[1::2, 1:] = T[:, 0].T, T[:, 1].T
        else:
            ft = tension_force(curve, g, tau)
            Q = np.empty((2 * nd, 1))
            Q[0::2, 0], Q[1::2, 0] = fb[0] + ft[0], fb[1] + ft[1]
        rb, wb = drop.r.ravel(), drop.w.ravel()
        dp = -4.0 * (rb * (1.0 - rb * rb) * wb) @ Q[0::2]                # per column
        return drop, Q, dp

    def _flow(self, drop, Q, dp):
        """Membrane velocity (interleaved, without the Poiseuille flow) of the load columns Q
        with Δp⁺ columns dp, and the wall densities."""
        tol = self.disc.quad_tol
        rb = drop.r.ravel()
        # membrane on itself; membrane on the wall and wall on the membrane in one pass (the
        # ring Stokeslet is reciprocal: one kernel call per far node pair)
        S_dd = influence(drop.x.ravel(), rb, drop, tol=tol)
        S_wd, B = influence_pair(self.wall, drop, tol=tol)
        inl = influence(drop.x.ravel(), rb, self.inlet, tol=tol)
        col_dp = inl[:, 0::2].sum(axis=1) / _EIGHT_PI
        rhs = (S_wd @ Q) / _EIGHT_PI + np.outer(self.col_dp_wall, dp)
        with _LAPACK:
            qw = -sla.lu_solve(self.lu_wall, rhs, check_finite=False)
        return (S_dd @ Q) / _EIGHT_PI + (B @ qw) / _EIGHT_PI + np.outer(col_dp, dp), qw

    def _columns(self, curve: SpectralCurve):
        """velocity_columns plus the wall density columns (2 n_wall, M + 1)."""
        drop, Q, dp = self._loads(curve)
        Uc, qw = self._flow(drop, Q, dp)
        u0 = Uc[:, 0].copy()
        u0[0::2] += poiseuille(drop.r.ravel())
        return drop, u0, Uc[:, 1:], float(dp[0]), dp[1:], qw

    def evaluate(self, curve: SpectralCurve) -> dict:
        """Flow of the membrane ``curve``: the least-squares tension and V, the residual."""
        drop, u0, Ug, dp0, dpg = self.velocity_columns(curve)
        nd = drop.r.size
        wb = drop.w.ravel()
        sw = np.repeat(np.sqrt(wb), 2)
        ex = np.zeros(2 * nd)
        ex[0::2] = 1.0
        M = np.column_stack([Ug, -ex]) * sw[:, None]
        with _LAPACK:
            sol, *_ = sla.lstsq(M, -u0 * sw, cond=LSTSQ_COND, lapack_driver="gelsy")
            self.evaluations += 1
        F = u0 * sw + M @ sol
        g, V = sol[:-1], float(sol[-1])
        res = F / sw
        return {"curve": curve, "panels": drop, "F": F, "g": g, "V": V, "M": M,
                "dp": float(dp0 + dpg @ g), "residual": float(np.max(np.abs(res))),
                "res_x": res[0::2], "res_r": res[1::2]}

    def fixed_residual(self, curve: SpectralCurve, g, V: float) -> np.ndarray:
        r"""Weighted residual :math:`\sqrt{w_i}(u_i - V e_x)` of ``curve`` with the tension
        coefficients ``g`` and speed ``V`` held fixed: one BEM solve of the single load
        :math:`Q[1; g]` instead of the M + 1 columns of :meth:`evaluate` (the assembly, the
        same for both, is then most of the cost: 39 against 48 ms per point at 88 modes on 2
        threads). Its differences, projected off the range of the tension and V columns,
        are the variable-projection Jacobian of Kaufman (1975) (:func:`bem.newton.
        difference_jacobian`)."""
        drop, Q, dp = self._loads(curve, g)
        u, _ = self._flow(drop, Q, dp)
        u = u[:, 0]
        u[0::2] += poiseuille(drop.r.ravel()) - V
        with _LAPACK:                        # the lock also guards the counter (threads)
            self.evaluations += 1
        return u * np.repeat(np.sqrt(drop.w.ravel()), 2)

    def taylor(self, base) -> dict:
        """The influence of a membrane expanded about its panels ``base`` (a state's
        ``panels``) to first order in its geometry, for :meth:`linearised_residual` and
        :meth:`linearised_finish`: the near pairs (membrane on itself, wall and membrane on
        each other; as :func:`bem.quadrature.influence` classifies them at ``base``), the far
        entries with their derivatives in the membrane node positions
        (:func:`bem.kernels.cross_far_taylor`, :func:`bem.kernels.self_far_taylor`: 5 and 7
        ring Stokeslets per far pair), the wall's near panels on the membrane nodes with
        their derivatives in those nodes (:func:`bem.kernels.near_target_taylor`: 5 graded
        integrals per pair) and the membrane's near panels on the wall nodes and on its own
        nodes with their derivatives in the panels' Legendre coefficients and the nodes
        (:func:`bem.kernels.near_panels_taylor`: the integrand differentiated on the rule of
        each pair, 7 ring Stokeslets per quadrature point), once for all the points."""
        from .. import kernels  # lazy: numba

        wall = self.wall
        nw, nb = wall.n_nodes, base.n_nodes
        xb, rb = base.x.ravel(), base.r.ravel()
        near = near_factor(self.p, self.disc.quad_tol)
        near_ab = np.empty((nw, base.n_panels), dtype=bool)
        kernels.near_flags(wall.x.ravel(), wall.r.ravel(), base.x, base.r, base.w, near,
                           near_ab)
        near_ba = np.empty((nb, wall.n_panels), dtype=bool)
        kernels.near_flags(xb, rb, wall.x, wall.r, wall.w, near, near_ba)
        near_dd = np.empty((nb, base.n_panels), dtype=bool)
        kernels.near_flags(xb, rb, base.x, base.r, base.w, near, near_dd)
        A_ab = np.zeros((2 * nw, 6 * nb))
        A_ba = np.zeros((6 * nb, 2 * nw))
        A_dd = np.zeros((2 * nb, 8 * nb))
        serial = assembles_serially(nw * nb)
        (kernels.cross_far_taylor_serial if serial else kernels.cross_far_taylor)(
            wall.x, wall.r, wall.w, base.x, base.r, near_ab, near_ba, A_ab, A_ba)
        (kernels.self_far_taylor_serial if serial else kernels.self_far_taylor)(
            base.x, base.r, near_dd, A_dd)
        fixed = self_rule_panels(base, self.disc.quad_tol)
        pairs = {k: np.argwhere(v).astype(np.int64)
                 for k, v in (("ab", near_ab), ("ba", near_ba), ("dd", near_dd))}
        n_ba, p = pairs["ba"].shape[0], self.p
        acc_ba = [np.empty((n_ba, p, 4)) for _ in range(3)]
        tn, _ = gauss_legendre(p)
        gx, gw = gauss_table()
        bw = barycentric_weights(p)
        tol = self.disc.quad_tol
        kernels.near_target_taylor(pairs["ba"], xb, rb, wall.x, wall.r, wall.w, wall.cx,
                                   wall.cr, tn, bw, gx, gw, tol, *acc_ba)
        near = {}
        for key, tx, tr, own in (("ab", wall.x.ravel(), wall.r.ravel(), False),
                                 ("dd", xb, rb, True)):
            n = pairs[key].shape[0]
            near[key] = (np.empty((n, p, 4)), np.empty((n, p, 4, 2 * p + 2)))
            kernels.near_panels_taylor(pairs[key], tx, tr, own, base.x, base.r, base.w,
                                       base.cx, base.cr, fixed, tn, bw, gx, gw, tol,
                                       *self_rule(p), *near[key])
        return {"base": base, "A_ab": A_ab, "A_ba": A_ba, "A_dd": A_dd, "pairs": pairs,
                "fixed": fixed, "acc_ba": acc_ba, "near": near}

    def linearised_residual(self, curve: SpectralCurve, g, V: float, taylor: dict) -> dict:
        r"""The part of :meth:`fixed_residual` that each point needs on its own: the loads,
        the displacements of the membrane's nodes and panel curves from ``taylor``'s and the
        inlet; the influence matrices and the wall solve of all the points are left to
        :meth:`linearised_finish`. Returns the pieces it needs."""
        drop, Q, dp = self._loads(curve, g)
        base = taylor["base"]
        q = Q[:, 0]
        xb, rb = drop.x.ravel(), drop.r.ravel()
        dx, dr = xb - base.x.ravel(), rb - base.r.ravel()
        inl = influence(xb, rb, self.inlet, tol=self.disc.quad_tol)
        u = inl[:, 0::2].sum(axis=1) * dp[0] / _EIGHT_PI
        u[0::2] += poiseuille(rb) - V
        return {"u": u, "q": q, "v": np.repeat(drop.w.ravel(), 2) * q, "dp": float(dp[0]),
                "dx": dx, "dr": dr, "dcx": drop.cx - base.cx, "dcr": drop.cr - base.cr,
                "sw": np.repeat(np.sqrt(drop.w.ravel()), 2)}

    def linearised_finish(self, taylor: dict, parts: list) -> list:
        r"""Weighted residuals of the points of :meth:`linearised_residual` (None where a
        point is None): every influence entry of each moved membrane is that of ``taylor``
        plus its derivatives times the displacements (exact to second order in the
        displacements; for a difference Jacobian, steps ~1e-7), all points in a few products,
        one pass through the near blocks (:func:`bem.kernels.near_products_taylor`) and one
        wall solve."""
        from .. import kernels  # lazy: numba

        ok = [k for k, pt in enumerate(parts) if pt is not None]
        out = [None] * len(parts)
        if not ok:
            return out
        pts = [parts[k] for k in ok]
        V = np.column_stack([pt["v"] for pt in pts])
        moved = {k: np.stack([pt[k] for pt in pts]) for k in ("q", "dx", "dr", "dcx", "dcr")}
        DX = np.repeat(moved["dx"].T, 2, axis=0)
        DR = np.repeat(moved["dr"].T, 2, axis=0)
        n2 = V.shape[0]
        # the near blocks of the membrane (on the wall nodes, on its own nodes) of every point
        still = np.zeros((len(pts), self.wall.n_nodes))               # the wall does not move
        near = {"ab": np.zeros((len(pts), 2 * self.wall.n_nodes)),
                "dd": np.zeros((len(pts), n2))}
        for key, dtx, dtr in (("ab", still, still), ("dd", moved["dx"], moved["dr"])):
            kernels.near_products_taylor(
                taylor["pairs"][key], *taylor["near"][key], moved["dcx"], moved["dcr"], dtx,
                dtr, moved["q"], min(workers(), len(pts)), near[key])
        X = np.vstack([V, DX * V, DR * V])
        rhs = taylor["A_ab"] @ X
        rhs += near["ab"].T
        rhs /= _EIGHT_PI
        rhs += np.outer(self.col_dp_wall, [pt["dp"] for pt in pts])
        with _LAPACK:
            qw = -sla.lu_solve(self.lu_wall, rhs, check_finite=False)
            self.evaluations += len(pts)
        Y = taylor["A_ba"] @ qw
        U = Y[:n2] + DX * Y[n2:2 * n2] + DR * Y[2 * n2:]
        A = taylor["A_dd"]
        U += A[:, :3 * n2] @ X - DX * (A[:, n2:2 * n2] @ V) + DR * (A[:, 3 * n2:] @ V)
        U /= _EIGHT_PI
        pba, p = taylor["pairs"]["ba"], self.p
        for c, (k, pt) in enumerate(zip(ok, pts)):
            u = [np.zeros(n2) for _ in range(3)]
            for acc, uc in zip(taylor["acc_ba"], u):
                kernels.near_product(pba, acc, p, qw[:, c], uc)
            u = u[0] + DX[:, c] * u[1] + DR[:, c] * u[2]
            out[k] = (pt["u"] + U[:, c] + (u + near["dd"][c]) / _EIGHT_PI) * pt["sw"]
        return out



def range_projector(M: np.ndarray):
    """X -> X minus its projection on the range of M (rank as in the least squares of
    :meth:`~bem.vesicle.VesicleOperator.evaluate`, singular values above LSTSQ_COND of the
    largest)."""
    U, sv, _ = np.linalg.svd(M, full_matrices=False)
    U = U[:, sv > LSTSQ_COND * sv[0]]
    return lambda X: X - U @ (U.T @ X)


def workers() -> int:
    """Threads for independent evaluations: numba's thread count (NUMBA_NUM_THREADS, or
    :func:`numba.set_num_threads`), so that one setting bounds both."""
    import numba  # lazy: numba

    return max(1, int(numba.get_num_threads()))


#: wall panels of the vesicle meshes, relative to the drop's rule
#: (``DropDiscretisation.wall_refinement``): the single layer on the wall is smooth on the scale
#: of the membrane panels, and a 4x coarser wall than the drop's changes V/U and Δp⁺ by < 1e-7
#: (relative) at (ν, λ) = (0.9, 1.0) and (0.6, 0.98 λc) while cutting the wall factorisation ~15x
#: (validation.md).
#: 0.15 would change them by ≤ 6e-9 more, but leaves a 6e-5 error in the wall shear at the
#: ends of the meshed tube (Poiseuille there), so the wall stays at 0.25
WALL_REFINEMENT = 0.25

#: axial extent [R] above which the wall panels beside the vesicle are lengthened by
#: WALL_BODY_LENGTH/extent (:func:`bem.drop._wall_and_inlet`): the drop's rule ties them to the
#: membrane's panel count, which for a long vesicle grows with its length, not with the
#: resolution the wall needs. Measured at a fixed shape of (0.6, 0.98 lam_c), extent 10.8 R
#: (outputs of V/U, Δp⁺, γ_max against the unscaled wall): 48 modes 4.5e-8, 88 modes 2e-9
#: relative with 5 R, wall shear at the tube ends unchanged, half the wall nodes and
#: evaluation time; with 2.5 R the change is 9e-6 at 48 modes. 6 R keeps a factor 2.4 from
#: that and leaves the wall of the red blood cell (0.61, 1.39) as it was (extent 5.0 R, its
#: lubrication seed 5.2 R): with 5 R its outputs moved by 1.6e-9 but its carrier levels took
#: another path, 566 BIE solves instead of 454
WALL_BODY_LENGTH = 6.0

#: membrane panel count above which the wall panels beside the vesicle stop following it
#: (:attr:`bem.drop.DropDiscretisation.wall_body_panels`): the wall's share of the error is
#: already far below the ladder's there. Measured on fixed shapes at Ca_B = 50 against a wall
#: refined twice (outputs V/U, Δp⁺, γ_max, relative): with 16, (0.6, 0.98 lam_c) 64 / 96 modes
#: ≤ 7.8e-9 / 9.3e-10 (unlimited: 3.8e-9 / 1.7e-10), and ≤ 3.5e-9 on the stored map shapes
#: (0.9, 0.98 lam_c), (0.7, 0.95 lam_c), (0.6, 0.8 lam_c), (0.6, 0.95 lam_c) at their own mode
#: count and 80 modes; the largest wall shear on the nodes moves by up to 5.8e-4 (sampling of
#: its peak; 6.7e-5 unlimited). One evaluation at 96 modes of (0.6, 0.98 lam_c): 0.21 s → 0.14
#: s (wall nodes 1792 → 976). Re-measured with 14 on the default 96-mode minimum of (0.6,
#: 1.94) against 32: 3.1e-10 (V/U), 2.6e-10 (Δp⁺), residual (a maximum over the nodes) 1.257e-4
#: against 1.247e-4; wall nodes 992 → 880, a Jacobian point at 96 modes 108–116 → 103.5 ms
#: on one thread (55–60 → 53–58 ms with two, back to back); the six shorter default cases take
#: the same levels and BIE solves (``default_cases.py``). With 12 (768 nodes) the outputs still
#: agree to 2.2e-9, but the residual rose to 1.336e-4, and at the stored 64-mode shape by
#: 2.6e-6 (the test bound is 1e-7); with 8 it rose to 4.7e-4
WALL_BODY_PANELS = 14


def vesicle_discretisation(n_modes: int, order: int = DEFAULT_ORDER,
                           n_panels: int | None = None) -> DropDiscretisation:
    """Resolution of a vesicle level with ``n_modes`` shape modes (panels as for the drop: one
    per three modes; measured and not adopted, one per four modes: a Jacobian point at 96
    modes of (0.6, 1.94) 65 → 54 ms, outputs at its fixed minimum within 1.7e-8, but the
    default solve of (0.7, 0.95 lam_c) then ended with a γ_max estimate of half its true
    error, 0.075 against 0.137, ``default_cases.py``)."""
    return DropDiscretisation(n_modes=n_modes, n_panels=n_panels or panels_for(n_modes),
                              order=order, wall_refinement=WALL_REFINEMENT,
                              wall_body_length=WALL_BODY_LENGTH,
                              wall_body_panels=WALL_BODY_PANELS)


# ---------------------------------------------------------------------------- outputs
def _cross(u, v):
    """z-component of the cross product of 2-vectors (last axis)."""
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def self_intersects(x, r) -> bool:
    """Whether the polyline (x, r) crosses itself or the axis inside (O(n^2), n ~ 400)."""
    if np.any(r[1:-1] <= 0.0):
        return True
    p = np.column_stack([x, r])
    a, b = p[:-1], p[1:]
    n = len(a)
    for i in range(n - 2):
        c, d = a[i + 2:], b[i + 2:]
        if i == 0:
            c, d = c[:-1], d[:-1]                         # first and last share the axis
        d1 = _cross(b[i] - a[i], c - a[i])
        d2 = _cross(b[i] - a[i], d - a[i])
        d3 = _cross(d - c, a[i] - c)
        d4 = _cross(d - c, b[i] - c)
        if np.any((d1 * d2 < 0) & (d3 * d4 < 0)):
            return True
    return False


def level_outputs(nu, lam, op: VesicleOperator, st: dict) -> dict:
    """The outputs of a level's state ``st`` (:meth:`~bem.vesicle.VesicleOperator.evaluate`)
    at (nu, lam): V/U, Δp⁺R/(ηU) and Δp⁺R0/(ηU), the length from the rearmost point to the
    front pole and between the poles [R], the smallest gap 1 - max r [R], the steady residual,
    the volume and area errors of the panels' quadrature, the largest tension and the panel
    counts."""
    curve, p = st["curve"], st["panels"]
    rb, wb = p.r.ravel(), p.w.ravel()
    vol = float(math.pi * np.sum(rb**2 * p.tx.ravel() * wb))
    area = float(2.0 * math.pi * np.sum(rb * wb))
    xr, xf = curve.extent()
    return {"V_over_U": st["V"], "dp_plus_R": st["dp"], "dp_plus_R0": st["dp"] * lam,
            "ell": xf - _rearmost(curve), "ell_poles": xf - xr,
            "film_min": 1.0 - curve.max_radius(), "residual": st["residual"],
            "volume_error": abs(vol / op.volume - 1.0), "area_error": abs(area / op.area - 1.0),
            "tension_max": _tension_max(curve, st["g"]),
            "panels": op.panel_counts | {"tension": op.n_tension}}


def _refined_extremum(f, n: int = 401) -> tuple[float, float]:
    """(tau, f) of the largest value of the smooth function ``f`` on [0, 1]: the best of ``n``
    equally spaced samples, refined by a bounded scalar search between its neighbours (a
    sampled maximum differs between parametrisations by its sampling error, 1e-5 relative for
    γ_max at 401 samples, which the refinement pair would read as discretisation error)."""
    t = np.linspace(0.0, 1.0, n)
    v = f(t)
    i = int(np.argmax(v))
    lo, hi = t[max(i - 1, 0)], t[min(i + 1, n - 1)]
    res = minimize_scalar(lambda x: -float(f(np.array([x]))[0]), bounds=(lo, hi),
                          method="bounded", options={"xatol": 1e-12})
    return (float(res.x), -float(res.fun)) if -res.fun > v[i] else (float(t[i]), float(v[i]))


def _tension_max(curve: SpectralCurve, g) -> float:
    """Largest membrane tension [ηU] (:func:`_refined_extremum`)."""
    return _refined_extremum(lambda t: tension_profile(curve, g, t)[0])[1]


def _rearmost(curve: SpectralCurve) -> float:
    """Axial position of the rearmost point of the membrane [R]: the rear pole of a bullet, the
    rim of a parachute (:func:`_refined_extremum` of -x)."""
    return -_refined_extremum(lambda t: -curve.position(t)[0])[1]



def membrane_profile(curve: SpectralCurve, g, n: int = 201) -> dict:
    """Shape and tension at ``n`` points equally spaced in arc length, poles included."""
    tt = np.linspace(0.0, 1.0, 4001)
    s_dense = curve.arc_length(tt)
    s = np.linspace(0.0, curve.length, n)
    tau = np.interp(s, s_dense, tt)
    for _ in range(3):
        tau = np.clip(tau - (curve.arc_length(tau) - s) / (curve.length * curve.g(tau)), 0, 1)
    x, r = curve.position(tau)
    r[0] = r[-1] = 0.0
    gam, dgam = tension_profile(curve, g, tau)
    return {"s": s, "x": x - x[0], "r": r, "psi": curve.tangent_angle(tau), "tension": gam,
            "shear_membrane": -dgam}
