r"""Clean drop of viscosity ratio 1 and constant tension in Poiseuille flow in a tube (BEM).

Nondimensionalisation (stated once): tube radius R = 1, outer viscosity eta = 1, mean velocity of
the undisturbed Poiseuille flow U = 1 (so :math:`u^\infty = 2(1 - r^2)e_x`); the drop has the
volume of a sphere of radius :math:`R_0 = \lambda R`, tension :math:`\gamma = \eta U/\mathrm{Ca}`
and the viscosity of the outer fluid.

Physics (Pozrikidis 1992 §5.3; Chen et al. 2020 §II, eq. BEM2, deltap1): with equal viscosities
the interface enters the boundary integral equation through the jump of traction alone, so the
velocity everywhere is a single layer over the drop, the wall and the inlet disc,

.. math:: u_\alpha(x_0) = u^\infty_\alpha + \frac{1}{8\pi}\Big[\int_{\rm drop} M_{\alpha\beta}
          q_\beta\,dl + \int_{\rm wall} M_{\alpha\beta} q^w_\beta\,dl
          + \Delta p^+\!\int_{\rm inlet} M_{\alpha x}\,dl\Big],

with the force on the fluid :math:`q = -2H\gamma\,n = -(\kappa_1 + \kappa_2)n/\mathrm{Ca}` (n
outward, H > 0 for a sphere; Chen et al. :math:`f^\gamma = -2\gamma H n`). A uniform normal load
on a closed surface drives no flow, so the mean of :math:`\kappa_1 + \kappa_2` is subtracted
before the quadrature (this removes the O(1/Ca) cancellation at small Ca). Δp⁺ follows from the
reciprocal theorem, :math:`\Delta p^+ = -4\int r(1 - r^2) q_x\,dl`; the wall load
:math:`q^w` from no slip on the wall (:mod:`bem.assembly` for the rigid-body version).

Steady state found directly (no time stepping; :func:`newton_drop`): unknowns are the shape
coefficients of the tangent angle (:class:`bem.shape.SpectralCurve`; c_1 from closure, the length
from the volume, the axial shift from centring, so volume and centre are imposed exactly) and the
drop velocity V; the equations are :math:`u\cdot n = V n_x` at every quadrature node of the drop,
weighted by the square root of the arc-length weight and solved in least squares by
Levenberg–Marquardt. Jacobian: forward differences (one BEM evaluation per shape coefficient;
the V column is the exact :math:`-n_x`), then Broyden updates, a fresh difference Jacobian when
the convergence slows. The equations outnumber the unknowns; their residual falls spectrally
with the number of modes, and the largest pointwise residual :math:`\max|u\cdot n - V n_x|` is
reported and tested. The wall mesh and the drop's panel breaks are fixed during one Newton solve
so that the residual is a smooth function of the coefficients.

Driver (:func:`solve_drop`): a seed with 16 modes of uniform arc-length density is found from the
sphere (:func:`find_seed`; time relaxation as the fallback), an arc-length density that
concentrates the parameter at sharp bends is built from its curvature
(:func:`bem.shape.equidistributing_density`), and the shape is refined (24, 32, 40, ... modes,
each level started from the previous one) until a refinement pair agrees; its difference is the
error estimate.

Time integration (:func:`relax_drop`) moves the interface with the normal velocity
:math:`u\cdot n - V n_x` projected on the shape modes in least squares, i.e. with the tangential
motion that keeps the nodes at fixed values of the curve parameter (tangential redistribution);
it provides initial guesses and shows that a steady state stays put.

Resource envelope (checked before any BEM work by :func:`check_drop_inputs`; measured on 2
shared cores):

* 8 <= modes <= 64 (``n_modes`` or ``max_modes``): panels max(8, ceil(N/3)), so a level has at
  most 22 drop panels and its dense operators stay ~0.2 GB (peak RSS 0.17 GB at 32 modes);
  one BEM evaluation takes ~0.05–0.3 s, a difference Jacobian one evaluation per mode.
* Ca: :data:`CA_MIN` = 1e-8 <= Ca <= :data:`CA_MAX` = 100. The interface load is
  κ/Ca, so the round-off of the curvature is amplified by 1/Ca: the steady residual is
  ~1e-17/Ca (8.7e-15 at Ca = 1e-3, 1.4e-12 at 1e-5, 9.5e-10 at 1e-8, λ = 0.5, 7–10 s each),
  and it overflows to NaN near Ca = 1e-300, where the seed search then relaxed the shape in
  time with a step ∝ Ca (5000 steps of two BEM solves: hours). Below Ca = 1e-8 the drop is a
  sphere to O(Ca) (V/U at λ = 0.5 changes by 4e-8 from Ca = 1e-3 to 1e-8); small drops then
  follow the clean-drop limit V/U = 2 − 0.8λ², Δp⁺R0/(ηU) = 4.8λ⁶ (Hetsroni & Haber 1970;
  notes of this package). Above Ca ~ 1 a drop of λ = 0.8 has no steady shape (it keeps
  elongating; reported after a relaxation of 6 R/U); Ca > 100 is refused.
* λ: Δp⁺R/(ηU) ≈ 4.8λ⁵ meets the BEM's round-off (pair differences 2e-16–5e-16) for small
  drops, as for the rigid sphere (:mod:`bem.solve`): λ >= max(0.01, (4e-16/(4.8 tol))^(1/5))
  (0.0095 at tol = 1e-5; λ = 0.02 and 0.05 at Ca = 0.1 converge in 9 s), below that the
  small clean-drop limit is quoted in the refusal. Near λ = 1 the drop touches the wall
  (reported, status NO_STEADY_STATE).
* ``max_time`` (wall time, :class:`lubrication.checks.Deadline`) is tested between BEM
  evaluations (Levenberg–Marquardt, relaxation steps) and levels; the time relaxation stops
  after ``max_steps`` = 5000 steps in any case.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from lubrication.checks import Deadline, InvalidParameterError, check_positive, check_range
from lubrication.results import Outcome, Status, leading_status

from .assembly import poiseuille
from .geometry import graded_breaks, tube_panels, wall_half_length
from .newton import levenberg_marquardt
from .quadrature import (
    DEFAULT_ORDER,
    DEFAULT_TOL,
    PanelSet,
    gauss_legendre,
    influence,
    panels_on_curve,
)
from .results import DropResult
from .shape import SpectralCurve, equidistributing_density, fit_curve
from .threads import single_threaded_blas

__all__ = ["CA_MAX", "CA_MIN", "LAM_MIN", "MAX_MODES", "DropDiscretisation", "DropOperator",
           "DropState", "NewtonReport", "check_drop_inputs", "find_seed", "newton_drop",
           "relax_drop", "solve_drop"]

#: capillary numbers accepted by :func:`solve_drop` (see the module docstring)
CA_MIN, CA_MAX = 1e-8, 100.0
#: smallest confinement accepted by :func:`solve_drop` (at any tol; module docstring)
LAM_MIN = 0.01
#: absolute round-off of dp+ R/(eta U) between two levels (measured 2e-16 to 5e-16)
_DP_ROUNDOFF = 4e-16
#: most shape modes of one level (resource envelope)
MAX_MODES = 64

log = logging.getLogger(__name__)

_EIGHT_PI = 8.0 * math.pi


@dataclass(frozen=True)
class DropDiscretisation:
    """Resolution of one drop computation.

    ``n_modes`` sine modes of the tangent angle; ``n_panels`` panels of ``order`` Gauss nodes
    on the drop; the wall panel length near the drop follows the drop panels
    (``wall_refinement`` scales it); ``quad_tol`` is the accuracy of the singular and
    near-singular panel integrals; ``tube_tol`` sets the meshed wall length from the
    exp(-4.47 x/R) decay of the disturbance. ``wall_body_length`` (None: off) scales the
    wall panels beside a body longer than it by wall_body_length/extent, and
    ``wall_body_panels`` (None: off) caps the body panel count that the wall panels beside the
    body follow (:func:`_wall_and_inlet`).
    """

    n_modes: int
    n_panels: int
    order: int = DEFAULT_ORDER
    wall_refinement: float = 1.0
    quad_tol: float = DEFAULT_TOL
    tube_tol: float = 1e-12
    wall_body_length: float | None = None
    wall_body_panels: int | None = None


def _drop_breaks(curve: SpectralCurve, n_panels: int) -> np.ndarray:
    """Panel ends in the curve parameter tau: panel size in tau ~ sqrt(gap to the wall) (the
    lubrication length; the density of the curve already concentrates tau at sharp bends)."""
    t = np.linspace(0.0, 1.0, 401)
    _, r = curve.position(t)
    gap = np.clip(1.0 - r, 1e-3, None)
    return graded_breaks(0.0, 1.0, lambda q: np.sqrt(np.interp(q, t, gap)), n=n_panels)


def _wall_and_inlet(curve: SpectralCurve, disc: DropDiscretisation, p: int):
    """Wall and inlet panels for the drop ``curve`` (fixed during one Newton solve), with the
    half-length of the meshed tube.

    :func:`bem.geometry.tube_panels` with the refinement n_panels/8 * wall_refinement (at least
    0.5 wall_refinement): the finest wall panels over the drop's extent plus 0.2 R. The rule
    follows the body's panel count, which for a compact body measures its resolution; a long
    body's panels spread over its length (a long vesicle's ladder starts at ~6 modes per R of
    length), so with ``disc.wall_body_length`` = L the panels beside a body of axial extent
    ℓ > L are ℓ/L times longer (their growth toward the tube ends is kept).
    """
    xr, xf = curve.extent()
    half = wall_half_length(max(-xr, xf), disc.tube_tol)
    refinement = max(disc.n_panels / 8.0, 0.5) * disc.wall_refinement
    flat_refinement = refinement
    if disc.wall_body_panels is not None and disc.n_panels > disc.wall_body_panels:
        flat_refinement *= disc.wall_body_panels / disc.n_panels
    if disc.wall_body_length is not None and xf - xr > disc.wall_body_length:
        flat_refinement *= disc.wall_body_length / (xf - xr)
    wall, inlet = tube_panels(gap=1.0 - curve.max_radius(), half_length=half,
                              refinement=refinement, flat=(xr - 0.2, xf + 0.2), p=p,
                              flat_refinement=flat_refinement)
    return wall, inlet, half


@dataclass(frozen=True, eq=False)
class DropState:
    """Drop shape and the flow it drives, at one set of shape coefficients.

    ``un`` is the normal velocity at the drop nodes (lab frame), ``V_fit`` the drop velocity
    that best matches it in least squares, ``dp`` the extra pressure drop Δp⁺R/(ηU).
    """

    curve: SpectralCurve
    panels: PanelSet
    tau: np.ndarray            # node parameters (n_panels, p)
    kappa1: np.ndarray
    kappa2: np.ndarray
    un: np.ndarray             # u.n at the nodes (flattened)
    ux: np.ndarray
    ur: np.ndarray
    dp: float
    V_fit: float
    weights: np.ndarray = field(repr=False)   # arc-length quadrature weights of the nodes

    def residual(self, V: float | None = None) -> np.ndarray:
        """u.n - V n_x at the nodes (V defaults to the least-squares fit)."""
        V = self.V_fit if V is None else V
        return self.un - V * self.panels.nx.ravel()

    def max_residual(self, V: float | None = None) -> float:
        return float(np.max(np.abs(self.residual(V))))

    def centroid_velocity(self) -> float:
        r"""Drop velocity from the volume flux, :math:`V = \Omega^{-1}\int x\,u\cdot n\,dS`
        (Chen et al. 2020 eq. Vel)."""
        p = self.panels
        dS = 2.0 * math.pi * p.r.ravel() * p.w.ravel()
        return float(np.sum(p.x.ravel() * self.un * dS) / self.curve.volume())


class DropOperator:
    """Normal velocity of a drop of given shape in the tube, with the wall operator factored once.

    The wall and inlet meshes and the drop's panel breaks (in the curve parameter tau) are
    fixed at construction from ``reference``, and so is the arc-length density, so that the map
    from shape coefficients to velocities is smooth (no remeshing inside a Newton solve).
    """

    def __init__(self, lam: float, ca: float, disc: DropDiscretisation,
                 reference: SpectralCurve):
        self.lam = float(lam)
        self.ca = float(ca)
        self.disc = disc
        self.p = int(disc.order)
        self.volume = 4.0 / 3.0 * math.pi * self.lam**3
        self.density = reference.density
        self.breaks = _drop_breaks(reference, disc.n_panels)
        self.wall, self.inlet, self.half_length = _wall_and_inlet(reference, disc, self.p)
        t, _ = gauss_legendre(self.p)
        half = 0.5 * np.diff(self.breaks)[:, None]
        self.tau = 0.5 * (self.breaks[:-1] + self.breaks[1:])[:, None] + half * t[None, :]
        w = self.wall
        S_ww = influence(w.x.ravel(), w.r.ravel(), w, tol=disc.quad_tol) / _EIGHT_PI
        inl = influence(w.x.ravel(), w.r.ravel(), self.inlet, tol=disc.quad_tol) / _EIGHT_PI
        self.col_dp_wall = inl[:, 0::2].sum(axis=1)
        self.lu_wall = sla.lu_factor(S_ww)
        self.evaluations = 0

    @property
    def panel_counts(self) -> dict:
        return {"drop": self.disc.n_panels, "wall": self.wall.n_panels,
                "inlet": self.inlet.n_panels, "order": self.p, "modes": self.disc.n_modes}

    def panels(self, curve: SpectralCurve) -> PanelSet:
        return panels_on_curve(curve.sample, self.breaks, self.p)

    def curve(self, modes) -> SpectralCurve:
        """Closed, volume-scaled, centred curve with these modes (c_1 is recomputed)."""
        return SpectralCurve.closed(modes, volume=self.volume, centroid=0.0,
                                    density=self.density)

    def _dependent(self) -> list[int]:
        """Modes fixed by the constraints of :meth:`curve` (c_1 closes the curve)."""
        return [0]

    def free(self, modes) -> np.ndarray:
        """The shape unknowns: the modes without the dependent ones."""
        keep = np.ones(len(modes), dtype=bool)
        keep[self._dependent()] = False
        return np.asarray(modes, dtype=float)[keep]

    def full(self, z, template) -> np.ndarray:
        """``template`` with its free modes replaced by ``z`` (inverse of :meth:`free`)."""
        m = np.array(template, dtype=float)
        keep = np.ones(m.size, dtype=bool)
        keep[self._dependent()] = False
        m[keep] = z
        return m

    def state(self, curve: SpectralCurve) -> DropState:
        """Velocity of the interface of ``curve`` (one BEM evaluation)."""
        tol = self.disc.quad_tol
        drop = self.panels(curve)
        if np.max(drop.r) >= 1.0 - 1e-6:
            raise InvalidParameterError("shape", "a drop touching the wall",
                                        "a drop inside the tube (max r < 1)")
        k1, k2 = curve.curvatures(self.tau)
        h2 = (k1 + k2).ravel()
        rb, wb = drop.r.ravel(), drop.w.ravel()
        nx, nr = drop.nx.ravel(), drop.nr.ravel()
        dS = rb * wb
        h2 = h2 - np.sum(h2 * dS) / np.sum(dS)           # a uniform load drives no flow
        q = np.empty(2 * rb.size)
        q[0::2] = -h2 * nx / self.ca
        q[1::2] = -h2 * nr / self.ca
        dp = float(-4.0 * np.sum(rb * (1.0 - rb * rb) * q[0::2] * wb))
        w = self.wall
        nd = rb.size
        tx = np.concatenate([drop.x.ravel(), w.x.ravel()])
        tr = np.concatenate([rb, w.r.ravel()])
        A = influence(tx, tr, drop, tol=tol)                             # drop sources
        B = influence(drop.x.ravel(), rb, w, tol=tol)                    # wall sources
        inl = influence(drop.x.ravel(), rb, self.inlet, tol=tol)
        col_dp = inl[:, 0::2].sum(axis=1) / _EIGHT_PI
        Aq = (A @ q) / _EIGHT_PI
        qw = -sla.lu_solve(self.lu_wall, Aq[2 * nd:] + dp * self.col_dp_wall)
        u = Aq[: 2 * nd] + (B @ qw) / _EIGHT_PI + dp * col_dp
        ux = u[0::2] + poiseuille(rb)
        ur = u[1::2]
        un = ux * nx + ur * nr
        V_fit = float(np.sum(wb * un * nx) / np.sum(wb * nx * nx))
        self.evaluations += 1
        return DropState(curve=curve, panels=drop, tau=self.tau, kappa1=k1, kappa2=k2,
                         un=un, ux=ux, ur=ur, dp=dp, V_fit=V_fit, weights=wb)


# -------------------------------------------------------------------------------- Newton
@dataclass
class NewtonReport(Outcome):
    """Outcome of :func:`newton_drop` (``status`` as in :class:`bem.newton.LMReport`)."""

    status: Status
    message: str
    state: DropState | None
    V: float
    modes: np.ndarray
    iterations: int
    evaluations: int
    history: list
    jacobians: int = 0


def newton_drop(op: DropOperator, modes0, V0: float | None = None, *, tol: float = 1e-9,
                max_iter: int = 40, fd_step: float = 1e-7,
                max_jacobians: int = 8, deadline=None) -> NewtonReport:
    r"""Steady drop shape by Levenberg–Marquardt on the weighted residual.

    Unknowns: modes c_2..c_N (c_1 closes the curve) and V. Residual
    :math:`F_i = \sqrt{w_i}\,(u\cdot n - V n_x)_i` at the drop nodes, minimised by
    :func:`bem.newton.levenberg_marquardt` (difference Jacobian, one BEM evaluation per mode,
    then Broyden updates; the V column is exact). ``deadline``: wall-time budget
    (:class:`lubrication.checks.Deadline`), a report of status TIME_LIMIT when spent.
    """
    modes = np.array(modes0, dtype=float)
    ev0 = op.evaluations
    try:
        state = op.state(op.curve(modes))
    except InvalidParameterError as exc:
        return NewtonReport(Status.REJECTED_START, f"initial shape rejected: {exc}", None,
                            math.nan, modes, 0, op.evaluations - ev0, [])
    modes = state.curve.modes.copy()
    V0 = state.V_fit if V0 is None else float(V0)

    def fun(z):
        st = op.state(op.curve(op.full(z[:-1], modes)))
        return np.sqrt(st.weights) * st.residual(z[-1]), st

    def v_column(st):
        return {modes.size - 1: -np.sqrt(st.weights) * st.panels.nx.ravel()}

    rep = levenberg_marquardt(fun, np.concatenate([op.free(modes), [V0]]), tol=tol,
                              max_iter=max_iter, fd_step=fd_step, max_jacobians=max_jacobians,
                              exact_columns=v_column, deadline=deadline,
                              start=(np.sqrt(state.weights) * state.residual(V0), state))
    st = rep.payload
    return NewtonReport(rep.status, rep.message, st, float(rep.z[-1]),
                        st.curve.modes.copy() if st is not None else modes, rep.iterations,
                        op.evaluations - ev0, rep.history, rep.jacobians)


# -------------------------------------------------------------------------------- relaxation
def shape_velocity_matrix(op: DropOperator, modes: np.ndarray, h: float = 1e-7) -> np.ndarray:
    """d(X.n)/dz at the nodes for the free modes z = op.free(modes) (geometry only, no BEM;
    the dependent modes follow through ``op.curve``)."""
    base = op.curve(modes)
    x0, r0 = base.position(op.tau)
    nx, nr = base.normal(op.tau)
    x0, r0, nx, nr = (a.ravel() for a in (x0, r0, nx, nr))
    z = op.free(base.modes)
    G = np.empty((x0.size, z.size))
    for j in range(z.size):
        z2 = z.copy()
        z2[j] += h
        x2, r2 = op.curve(op.full(z2, base.modes)).position(op.tau)
        G[:, j] = ((x2.ravel() - x0) * nx + (r2.ravel() - r0) * nr) / h
    return G


def relax_drop(op: DropOperator, modes0, t_end: float, *, dt: float | None = None,
               max_steps: int = 5000, tol: float = 0.0, deadline=None):
    r"""Integrate the interface in time with the normal velocity :math:`u\cdot n - V n_x`.

    The normal velocity at the nodes is projected on the shape modes in least squares
    (weights as in :func:`newton_drop`), which moves the nodes along the normal with the
    tangential motion that keeps them at fixed parameter values (tangential redistribution);
    volume and centroid are imposed by the parametrisation. Second-order Runge–Kutta (Heun).
    The default step min(0.8 Ca S/N, 0.1 R/U) keeps the fastest capillary relaxation rate of the resolved
    modes, ~k/(2 Ca R0) for mode k (Rallison 1984, equal viscosities), inside the stability
    region and resolves the advection by the flow; the step is halved whenever the largest normal velocity grows by more than 50 %.
    V is the centroid velocity :math:`\Omega^{-1}\int x\,u\cdot n\,dS` (Chen et al. 2020 eq.
    Vel). Stops at ``t_end``, after ``max_steps``, or when the largest normal velocity in the
    drop frame falls below ``tol``, or (a failure) when ``deadline`` is spent.

    Returns (modes, state, info) with info = {t, steps, max_un, history, length, failure,
    status}; history holds (t, max|u.n - V n_x|, V) per step, length the drop length
    x_front - x_rear, failure a message (empty if none) when the interface became invalid
    (self-intersecting, touching the wall) or the deadline was spent -- then modes and state
    are the last valid ones; status is CONVERGED (stopped at ``tol``), NO_STEADY_STATE (the
    interface became invalid), TIME_LIMIT or NOT_CONVERGED (``t_end`` or ``max_steps`` came
    first).
    """
    modes = np.array(modes0, dtype=float)
    curve = op.curve(modes)
    modes = curve.modes.copy()
    if dt is None:
        dt = min(0.8 * op.ca * curve.length / modes.size, 0.1)
    dt = float(check_positive("dt", dt))

    def rate(m):
        st = op.state(op.curve(m))
        V = st.centroid_velocity()
        un = st.residual(V)
        sw = np.sqrt(st.weights)
        G = shape_velocity_matrix(op, st.curve.modes)
        dm, *_ = np.linalg.lstsq(sw[:, None] * G, sw * un, rcond=None)
        return np.concatenate([[0.0], dm]), st, V, un

    t = 0.0
    steps = 0
    history = []
    lengths = []
    failure, status = "", Status.NOT_CONVERGED
    state = None
    while t < t_end - 1e-14 and steps < max_steps:
        if deadline is not None and deadline.expired():
            failure, status = deadline.message(), Status.TIME_LIMIT
            break
        h = min(dt, t_end - t)
        try:
            k1, state, V, un = rate(modes)
        except InvalidParameterError as exc:
            failure = f"the interface became invalid at t = {t:.3g} R/U ({exc})"
            status = Status.NO_STEADY_STATE
            break
        peak = float(np.max(np.abs(un)))
        if history and peak > 1.5 * history[-1][1] and dt > 1e-6:
            dt *= 0.5                                # unstable: back off (modes already moved)
        history.append((t, peak, V))
        xr, xf = state.curve.extent()
        lengths.append(xf - xr)
        if tol > 0 and peak < tol:
            status = Status.CONVERGED
            break
        try:
            k2, *_ = rate(modes + h * k1)
            modes = op.curve(modes + 0.5 * h * (k1 + k2)).modes.copy()
        except InvalidParameterError as exc:
            failure = f"the interface became invalid at t = {t + h:.3g} R/U ({exc})"
            status = Status.NO_STEADY_STATE
            break
        t += h
        steps += 1
    if not failure:
        state = op.state(op.curve(modes))
        V = state.centroid_velocity()
        history.append((t, state.max_residual(V), V))
        xr, xf = state.curve.extent()
        lengths.append(xf - xr)
    return modes, state, {"t": t, "steps": steps, "max_un": history[-1][1] if history else
                          math.inf, "history": history, "length": lengths, "failure": failure,
                          "status": status}


# -------------------------------------------------------------------------------- driver
#: shape modes of the first (uniform-density) stage that finds the shape from a sphere
SEED_MODES = 16


def panels_for(n_modes: int) -> int:
    """Drop panels for ``n_modes`` shape modes: the panel rule must resolve the curvature of
    the highest mode; one 16-point panel per three modes was enough in the convergence study
    (maxres unchanged when the panels were doubled), with at least 8 panels."""
    return max(8, math.ceil(n_modes / 3))


def _check_inputs(lam, ca):
    lam = float(check_range("lam", lam, 0.0, 1.0, lo_open=True, hi_open=True,
                            reason="the undeformed drop must fit inside the tube (R0 < R)"))
    ca = float(check_positive("ca", ca))
    if ca < CA_MIN:
        raise InvalidParameterError(
            "ca", ca, f"{CA_MIN:g} <= ca <= {CA_MAX:g}",
            f"below it the drop is a sphere to O(Ca) and the round-off of the interface load "
            f"(~1e-17/Ca) dominates; solve at Ca = {CA_MIN:g} instead (small drops: V/U = "
            f"2 - 0.8 lam^2 = {2 - 0.8 * lam**2:.6g})")
    if ca > CA_MAX:
        raise InvalidParameterError(
            "ca", ca, f"{CA_MIN:g} <= ca <= {CA_MAX:g}",
            "a clean drop of viscosity ratio 1 has no steady shape at such capillary numbers "
            "(it keeps elongating: no steady shape is found already near Ca = 1 at lam = 0.8)")
    return lam, ca


def check_drop_inputs(lam, ca, *, n_modes=None, tol=1e-5, residual_tol=1e-4, max_modes=64,
                      max_time=None):
    """Check the inputs of :func:`solve_drop` (ranges and the resource envelope of the module
    docstring) without any BEM work; returns them as Python numbers (lam, ca, n_modes, tol,
    residual_tol, max_modes). Raises :class:`InvalidParameterError` naming the input."""
    lam, ca = _check_inputs(lam, ca)
    tol = float(check_range("tol", tol, 1e-12, 0.1))
    smallest = max(LAM_MIN, (_DP_ROUNDOFF / (4.8 * tol)) ** 0.2)
    if lam < smallest:
        raise InvalidParameterError(
            "lam", lam, f"{smallest:.3g} <= lam < 1 at tol={tol:g}",
            f"below it dp+ R/(eta U) ~ 4.8 lam^5 = {4.8 * lam**5:.3g} is within the relative "
            f"tol of the BEM's round-off (~4e-16); the small clean-drop limit applies there: "
            f"V/U = 2 - 0.8 lam^2 = {2 - 0.8 * lam**2:.10g}, dp+ R0/(eta U) = 4.8 lam^6 = "
            f"{4.8 * lam**6:.4g} (relative error O(lam^5))")
    residual_tol = float(check_range("residual_tol", residual_tol, 1e-14, 1.0))
    max_modes = mode_count("max_modes", max_modes, 8)
    if n_modes is not None:
        n_modes = mode_count("n_modes", n_modes, 6)
    if max_time is not None:
        Deadline(max_time)                              # 0 < max_time < inf
    return lam, ca, n_modes, tol, residual_tol, max_modes


def mode_count(name, value, lo, hi=MAX_MODES) -> int:
    """An integer number of shape modes within lo..hi (the drop's or the vesicle's envelope)."""
    value = check_range(name, value, lo, hi,
                        reason="more modes exceed the resource envelope of one level "
                               "(memory, time per difference Jacobian)")
    if float(value) != int(value):
        raise InvalidParameterError(name, float(value), f"an integer, {lo} <= {name} <= {hi}")
    return int(value)


def _solve_stage(lam, ca, disc, seed: SpectralCurve, V0, density=None, deadline=None):
    """Refit ``seed`` to the discretisation (and density) and run Newton; returns (report, op)."""
    dens = seed.density if density is None else np.asarray(density, dtype=float)
    same = (seed.n_modes == disc.n_modes and seed.density.size == dens.size
            and np.array_equal(seed.density, dens))
    ref = seed if same else fit_curve(seed.sample, 0.0, 1.0, disc.n_modes, density=dens)
    op = DropOperator(lam, ca, disc, ref)
    return newton_drop(op, ref.modes, V0, deadline=deadline), op


def _elongation(info) -> float:
    """Growth rate of the drop length over the last third of a relaxation [R per unit time]."""
    hist, lengths = info["history"], info["length"]
    n = len(lengths)
    if n < 6:
        return 0.0
    t = np.array([h[0] for h in hist[: n]])
    k = n // 3
    return float((lengths[-1] - lengths[-k]) / max(t[-1] - t[-k], 1e-12))


def find_seed(lam: float, ca: float, *, initial: SpectralCurve | None = None,
              relax_time: float = 6.0, order: int = DEFAULT_ORDER, deadline=None):
    """Shape with ``SEED_MODES`` uniform-density modes close to the steady drop.

    Newton from ``initial`` (default: the sphere); if it fails, the interface is relaxed in
    time for up to ``relax_time`` (R/U) and Newton restarted. Returns (curve, V, info); curve
    is None when no steady shape was found, with info["status"] and info["message"] saying why:
    NO_STEADY_STATE for a drop that keeps elongating, whose interface became invalid in the
    relaxation, or that did not settle in it (max|u·n − V n_x| > 0.01) and from whose relaxed
    shape Newton failed too; TIME_LIMIT; else the status of the last Newton. ``deadline``:
    wall-time budget, tested between BEM evaluations.
    """
    disc = DropDiscretisation(n_modes=SEED_MODES, n_panels=panels_for(SEED_MODES), order=order)
    start = SpectralCurve.sphere(lam, SEED_MODES) if initial is None else initial
    if start.density.size:                                   # the seed stage is uniform
        start = fit_curve(start.sample, 0.0, 1.0, SEED_MODES)
    info = {"relaxed": False}
    rep, op = _solve_stage(lam, ca, disc, start, None, deadline=deadline)
    info.update(iterations=rep.iterations, evaluations=rep.evaluations, jacobians=rep.jacobians)
    # a seed only has to be close: accept the floor of 16 modes (sharp rims) if LM stalled
    if rep.state is not None and (rep.success or rep.state.max_residual(rep.V) < 0.02):
        info["message"] = rep.message
        info["residual"] = rep.state.max_residual(rep.V)
        return rep.state.curve, rep.V, info
    if deadline is not None and deadline.expired():
        info["status"] = Status.TIME_LIMIT
        info["message"] = f"no steady shape found: {deadline.message()}"
        return None, math.nan, info
    log.info("seed Newton failed at lam=%g ca=%g (%s); relaxing in time", lam, ca, rep.message)
    info["relaxed"] = True
    op = DropOperator(lam, ca, disc, start)
    _, state, rinfo = relax_drop(op, start.modes, relax_time, tol=0.01, deadline=deadline)
    info["relax_time"] = rinfo["t"]
    relax_evaluations = op.evaluations
    rate = _elongation(rinfo)
    lengths = rinfo["length"]
    if rinfo["status"] is Status.TIME_LIMIT:
        info["status"] = Status.TIME_LIMIT
        info["message"] = (f"no steady shape found: {deadline.message()} (in a time relaxation "
                           f"after Newton failed from the initial shape)")
        return None, math.nan, info
    if rinfo["failure"] or (rinfo["max_un"] > 0.01 and rate > 0.02):
        what = (rinfo["failure"] if rinfo["failure"] else
                f"after t = {rinfo['t']:.3g} R/U the drop keeps elongating")
        grow = (f" (length {lengths[0]:.3f} -> {lengths[-1]:.3f} R, growing at {rate:.3g} U at "
                f"the end)" if len(lengths) > 1 else "")
        info["status"] = Status.NO_STEADY_STATE
        info["message"] = (f"no steady shape: Newton failed from the initial shape and in a time "
                           f"relaxation {what}{grow}; breakup or a non-steady drop")
        return None, math.nan, info
    rep, op = _solve_stage(lam, ca, disc, state.curve, None, deadline=deadline)
    info.update(iterations=info["iterations"] + rep.iterations,
                evaluations=info["evaluations"] + rep.evaluations + relax_evaluations,
                jacobians=info["jacobians"] + rep.jacobians)
    if rep.state is not None and (rep.success or rep.state.max_residual(rep.V) < 0.02):
        info["message"] = rep.message
        info["residual"] = rep.state.max_residual(rep.V)
        return rep.state.curve, rep.V, info
    # a relaxation that did not settle, and Newton failing from its end: no steady state;
    # a settled one: Newton's own failure
    info["status"] = (rep.status if rinfo["status"] is Status.CONVERGED
                      or rep.status is Status.TIME_LIMIT else Status.NO_STEADY_STATE)
    info["message"] = (f"no steady shape found: Newton failed from the initial shape and after "
                       f"a relaxation to t = {rinfo['t']:.3g} R/U (length {lengths[0]:.3f} -> "
                       f"{lengths[-1]:.3f} R, max|u.n - V n_x| = {rinfo['max_un']:.2e}; "
                       f"{rep.message})")
    return None, math.nan, info


def _outputs(lam: float, op: DropOperator, rep: NewtonReport) -> dict:
    """Physical outputs and diagnostics of one converged stage."""
    st = rep.state
    p = st.panels
    target = 4.0 / 3.0 * math.pi * lam**3
    vol = float(math.pi * np.sum(p.r.ravel() ** 2 * p.tx.ravel() * p.w.ravel()))
    return {"V_over_U": float(rep.V), "dp_plus_R": float(st.dp), "dp_plus_R0": float(st.dp * lam),
            "residual": st.max_residual(rep.V), "volume_error": abs(vol / target - 1.0),
            "panels": op.panel_counts, "half_length": op.half_length}


_KEYS = ("V_over_U", "dp_plus_R", "dp_plus_R0")


def _profile(curve: SpectralCurve, n: int = 201) -> dict:
    """Shape sampled at ``n`` points equally spaced in arc length, poles included."""
    tt = np.linspace(0.0, 1.0, 4001)
    s_dense = curve.arc_length(tt)
    s = np.linspace(0.0, curve.length, n)
    tau = np.interp(s, s_dense, tt)
    for _ in range(3):                                    # polish s(tau) = s by Newton
        tau = np.clip(tau - (curve.arc_length(tau) - s) / (curve.length * curve.g(tau)), 0, 1)
    x, r = curve.position(tau)
    k1, k2 = curve.curvatures(tau)
    r[0] = r[-1] = 0.0
    return {"s": s, "x": x, "r": r, "psi": curve.tangent_angle(tau), "kappa1": k1,
            "kappa2": k2}


@single_threaded_blas()      # small dense products between numba loops (bem.threads)
def solve_drop(lam: float, ca: float, *, n_modes: int | None = None, tol: float = 1e-5,
               residual_tol: float = 1e-4, max_modes: int = 64, order: int = DEFAULT_ORDER,
               initial=None, density_terms: int = 16, max_time: float | None = None):
    r"""Steady clean drop (viscosity ratio 1, constant tension) on the axis of a tube.

    Parameters
    ----------
    lam : float
        Confinement R0/R, max(0.01, (4e-16/(4.8 tol))^(1/5)) <= lam < 1, R0 the radius of the sphere of the
        drop's volume [-].
    ca : float
        Capillary number ηU/γ, U the mean velocity, γ the tension, CA_MIN = 1e-8 <= ca <=
        CA_MAX = 100 [-] (module docstring).
    n_modes : int, optional
        Shape modes of the fine mesh (panels follow: max(8, ceil(n/3))); the coarse mesh of
        the refinement pair has round(2n/3). Default: automatic, n = 24, 32, 40, ... until the
        pair agrees to ``tol`` (relative, in V/U and Δp⁺) and the steady residual
        max|u·n − V n_x| is below ``residual_tol`` [U], or ``max_modes``.
    initial : DropResult or SpectralCurve, optional
        Warm start (e.g. the solution at a neighbouring Ca): the seed stage starts from it
        instead of the sphere (:func:`find_seed`, with a time relaxation as fallback).
    order : int
        Gauss nodes per panel.
    density_terms : int
        Cosine terms of the arc-length density built from the seed's curvature
        (:func:`bem.shape.equidistributing_density`); 0 keeps the arc length uniform.
    max_time : float, optional
        Wall-time budget [s] (:class:`lubrication.checks.Deadline`), tested between BEM
        evaluations; when spent the result is returned with status TIME_LIMIT. Default: no
        limit.

    Returns
    -------
    DropResult
        ``status`` and the reason in ``message``: NO_STEADY_STATE when the drop keeps
        elongating or touches the wall, NOT_CONVERGED when Newton or the steady residual fell
        short, UNRESOLVED when the refinement pair disagrees, TIME_LIMIT when ``max_time`` was
        spent, REJECTED_START when the first stage could not start.

    Raises
    ------
    InvalidParameterError
        Bad input or a request outside the resource envelope, before any BEM work.

    Examples
    --------
    A small drop moves at nearly 2 - 0.8 lam^2 with dp+ R0/(eta U) near 4.8 lam^6 (notes §3):

    >>> res = solve_drop(0.3, 0.1, n_modes=8, tol=1e-3)
    >>> res.success, round(res.V_over_U, 4), round(2 - 0.8 * 0.3**2, 4)
    (True, 1.9269, 1.928)
    >>> round(res.dp_plus_R0 / (4.8 * 0.3**6), 3)
    1.006
    """
    t_start = time.perf_counter()
    lam, ca, n_modes, tol, residual_tol, max_modes = check_drop_inputs(
        lam, ca, n_modes=n_modes, tol=tol, residual_tol=residual_tol, max_modes=max_modes,
        max_time=max_time)
    deadline = Deadline(max_time)
    if n_modes is not None:
        sequence = [max(4, round(2 * n_modes / 3)), n_modes]
    else:
        sequence = list(range(24, max(max_modes, 32) + 1, 8))
    timings, iterations = {}, {}

    # ---- seed: the shape from a sphere or a warm start, uniform density, then the density
    seed_V = None
    if initial is not None and not isinstance(initial, SpectralCurve):
        initial = initial.curve()
    t0 = time.perf_counter()
    seed, seed_V, info = find_seed(lam, ca, initial=initial, order=order, deadline=deadline)
    iterations["seed"] = {k: v for k, v in info.items() if k not in ("message", "status")}
    if seed is None:
        timings["seed_s"] = timings["total_s"] = time.perf_counter() - t_start
        return DropResult(lam=lam, ca=ca, status=info["status"], message=info["message"],
                          tol=tol, residual_tol=residual_tol, iterations=iterations,
                          timings=timings)
    density = equidistributing_density(seed, density_terms)
    if density_terms and info["residual"] > 1e-3:
        # the 16 uniform modes did not resolve the shape (a sharp rim): adapt the density to
        # a solution that uses it, which does
        disc = DropDiscretisation(n_modes=sequence[0], n_panels=panels_for(sequence[0]),
                                  order=order)
        rep, _ = _solve_stage(lam, ca, disc, seed, seed_V, density, deadline=deadline)
        iterations["density"] = {"iterations": rep.iterations, "evaluations": rep.evaluations,
                                 "jacobians": rep.jacobians}
        if rep.state is not None:
            seed, seed_V = rep.state.curve, rep.V
            density = equidistributing_density(seed, density_terms)
    timings["seed_s"] = time.perf_counter() - t0

    # ---- refinement levels with the curvature-adapted density
    levels = []
    prev, V_prev = seed, seed_V
    status, message = Status.CONVERGED, ""
    for k, n in enumerate(sequence):
        if deadline.expired():
            status, message = Status.TIME_LIMIT, deadline.message()
            break
        disc = DropDiscretisation(n_modes=n, n_panels=panels_for(n), order=order)
        t0 = time.perf_counter()
        try:
            rep, op = _solve_stage(lam, ca, disc, prev, V_prev, density, deadline=deadline)
        except InvalidParameterError as exc:
            # no iteration of this level could start: the solve's start if it is the first
            status = Status.NOT_CONVERGED if levels else Status.REJECTED_START
            message = f"stage with {n} modes: {exc}"
            break
        timings[f"modes{n}_s"] = time.perf_counter() - t0
        iterations[f"modes{n}"] = {"iterations": rep.iterations, "evaluations": rep.evaluations,
                                   "jacobians": rep.jacobians}
        if not rep.success:
            status = (Status.NOT_CONVERGED if levels and rep.status is Status.REJECTED_START
                      else rep.status)
            message = f"Newton did not converge with {n} modes: {rep.message}"
            if rep.state is not None:
                levels.append((rep, op, _outputs(lam, op, rep)))
            break
        out = _outputs(lam, op, rep)
        levels.append((rep, op, out))
        prev, V_prev = rep.state.curve, rep.V
        log.info("solve_drop lam=%g ca=%g modes=%d: V/U=%.10f dp+R=%.10f residual %.2e", lam,
                 ca, n, out["V_over_U"], out["dp_plus_R"], out["residual"])
        if len(levels) >= 2:
            c, f = levels[-2][2], levels[-1][2]
            err = {key: abs(f[key] - c[key]) for key in _KEYS}
            if (all(err[key] <= tol * abs(f[key]) for key in ("V_over_U", "dp_plus_R"))
                    and f["residual"] <= residual_tol) or n_modes is not None:
                break

    timings["total_s"] = time.perf_counter() - t_start
    if not levels:
        return DropResult(lam=lam, ca=ca, status=status, message=message, tol=tol,
                          residual_tol=residual_tol, iterations=iterations, timings=timings)
    rep, op, fine = levels[-1]
    coarse = levels[-2][2] if len(levels) >= 2 else None
    err = ({key: abs(fine[key] - coarse[key]) for key in _KEYS} if coarse is not None
           else {key: math.nan for key in _KEYS})
    if not message:
        problems = []
        bad = [key for key in ("V_over_U", "dp_plus_R") if not err[key] <= tol * abs(fine[key])]
        if bad:
            status = Status.UNRESOLVED
            problems.append(f"refinement pair differs by more than tol={tol:g} (relative) in "
                            + ", ".join(f"{key} ({err[key] / abs(fine[key]):.1e})" for key in bad))
        if not fine["residual"] <= residual_tol:
            status = leading_status([status, Status.NOT_CONVERGED])
            problems.append(f"steady residual max|u.n - V n_x| = {fine['residual']:.2e} exceeds "
                            f"residual_tol={residual_tol:g}")
        message = "; ".join(problems)
    success = status is Status.CONVERGED
    if success:
        message = (f"converged: {levels[-1][2]['panels']['modes']} modes, pair differences "
                   + ", ".join(f"{key} {err[key]:.1e}" for key in ("V_over_U", "dp_plus_R"))
                   + f", residual {fine['residual']:.1e}")
    else:
        log.warning("solve_drop(lam=%g, ca=%g): %s", lam, ca, message)
    curve = rep.state.curve
    prof = _profile(curve)
    xr, xf = curve.extent()
    k_rear, _ = curve.curvatures(np.array([0.0]))
    k_front, _ = curve.curvatures(np.array([1.0]))
    rmax = curve.max_radius()
    return DropResult(
        lam=lam, ca=ca, status=status, message=message, V_over_U=fine["V_over_U"],
        dp_plus_R=fine["dp_plus_R"], dp_plus_R0=fine["dp_plus_R0"], error_estimate=err,
        length=xf - xr, max_radius=rmax, film=1.0 - rmax, curvature_front=float(k_front[0]),
        curvature_rear=float(k_rear[0]), volume_error=fine["volume_error"],
        residual=fine["residual"], tol=tol, residual_tol=residual_tol, panels=fine["panels"],
        panels_coarse=coarse["panels"] if coarse is not None else {},
        half_length=fine["half_length"], iterations=iterations, timings=timings, **prof,
        modes=curve.modes.copy(), density=np.asarray(curve.density).copy(),
        shape_length=curve.length)
