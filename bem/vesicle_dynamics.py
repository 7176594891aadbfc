r"""Time-dependent vesicle in a tube: tension from local inextensibility, linearly implicit steps.

Nondimensionalisation (as :mod:`bem.vesicle`, stated once): tube radius R = 1, outer viscosity
eta = 1, mean velocity of the undisturbed Poiseuille flow U = 1; lengths in R, velocities in U,
time in R/U, bending modulus :math:`\kappa = \lambda^2/\mathrm{Ca}_B` in :math:`\eta U R^2`,
tension in :math:`\eta U`.

Physics (Chen et al. 2020 §II). At each instant the membrane velocity is the single layer of the
membrane load :math:`f_b + f_\gamma` (viscosity ratio 1), affine in the tension coefficients,
:math:`u = u_0 + U g` with :math:`\gamma(\tau) = \sum_k g_k\cos(k\pi\tau)`
(:meth:`bem.vesicle.VesicleOperator.velocity_columns`). The tension is the Lagrange multiplier of
local inextensibility (Chen et al. 2020 eq. surface),
:math:`\nabla_s\cdot u = (I - nn):\nabla u = 0`, which on an axisymmetric surface (arc length s,
tangent :math:`t = (\cos\psi, \sin\psi)`, outward normal :math:`n = (-\sin\psi, \cos\psi)`) reads

.. math:: \nabla_s\cdot u = t\cdot\frac{du}{ds} + \frac{u_r}{r}
          = \frac{1}{r}\frac{d(r u_s)}{ds} + (\kappa_1 + \kappa_2)\,u_n ,

with :math:`\kappa_1 = -d\psi/ds`, :math:`\kappa_2 = \cos\psi/r` (positive for a sphere, the
convention of :mod:`bem.shape`; e.g. Pozrikidis 2003, *Modeling and Simulation of Capsules and
Biological Cells*). Both forms follow from :math:`dt/ds = -\kappa_1 n` and
:math:`dr/ds = \sin\psi`; u = X gives 2 on any surface, a unit normal velocity on a sphere of
radius a gives 2/a (both checked in the tests, with the curvature form on spheroids). The
first form needs only derivatives of the Cartesian components along the curve, so it is the one
used: the velocity at the p Gauss nodes of each panel is differentiated through its degree p-1
Lagrange interpolant (barycentric differentiation matrix, Berrut & Trefethen 2004). The
divergence is imposed in weighted least squares (weights :math:`\sqrt{w_i}`, w the arc-length
weights) at all nodes; the tension coefficients are its solution. A rigid translation has zero
divergence, so at a steady state (u = V e_x) the steady tension is recovered. Total area and
volume are held exactly by the shape parametrisation anyway.

The vesicle speed is the centroid velocity :math:`V = \Omega^{-1}\int x\,u\cdot n\,dS`
(Chen et al. 2020 eq. Vel); the shape moves in the frame of its centroid with the normal
velocity :math:`u\cdot n - V n_x`, projected in least squares on the free shape modes exactly as
:func:`bem.drop.relax_drop` does (nodes keep their parameter values: tangential redistribution).

Time scheme. The bending load :math:`\propto\kappa\,\partial_s^4 X` makes the mode equations
stiff (Chen et al. 2020 used the semi-implicit scheme of Boedec et al. 2011, J. Comput. Phys.
230, 1020, with 10⁴–10⁵ steps). With N ≲ 40 modes a dense Jacobian of the whole mode rate is
affordable, so the stiff part is not split off by hand: the default is the linearised backward Euler (Rosenbrock–Euler) step in the free modes z,

.. math:: (I - h J)\,\Delta z = h f(z_n), \qquad z_{n+1} = z_n + \Delta z,

with J a forward-difference Jacobian of the mode rate f, kept for ``jacobian_every`` steps and
refreshed after a rejected step: a W-method (Steihaug & Wolfbrandt 1979; Hairer & Wanner 1996
§IV.7), first order for any J and stable for the stiff modes as long as J approximates them. One
BEM evaluation per step plus N - 2 per Jacobian. Any steady state (f = 0) is a fixed point of the
step, whatever J and h. The explicit Heun step (``method="heun"``, as :func:`bem.drop.relax_drop`,
two evaluations per step) is kept for comparison; its step is bounded by the fastest mode,
:math:`h \le 2/\omega`, :math:`\omega = (\kappa q^3 + \gamma q)/4\eta` with q = Nπ/S
(Brochard & Lennon 1975), i.e. :math:`h \propto (S/N)^3\,\mathrm{Ca}_B/\lambda^2`. Step
control for both: a step that raises the peak normal velocity by more than ``growth`` is rejected
and h halved; a slower sustained rise halves h for good; after ``regrow`` accepted steps h grows
by 1.25 up to its cap. Measured numbers (stability limit, cost): :func:`relax_vesicle`.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from functools import cache

import numpy as np

from lubrication.checks import (
    Deadline,
    InvalidParameterError,
    check_choice,
    check_positive,
    check_range,
)

from .assembly import poiseuille
from .drop import shape_velocity_matrix
from .membrane import tension_profile
from .newton import difference_jacobian
from .quadrature import PanelSet, barycentric_weights, gauss_legendre
from .shape import SpectralCurve
from .vesicle import VesicleOperator, vesicle_discretisation

__all__ = ["VesicleFlow", "centroid_velocity", "inextensible_tension", "quiescent_velocity",
           "relax_vesicle", "relaxation_rate_brochard_lennon_1975", "surface_divergence",
           "vesicle_flow", "vesicle_operator"]

log = logging.getLogger(__name__)


# ---------------------------------------------------------------------------- surface divergence
@cache
def _differentiation_matrix(p: int) -> np.ndarray:
    """D with (D @ f)_i = f'(t_i) for the degree p-1 interpolant on the p Gauss–Legendre nodes
    of [-1, 1] (barycentric form, Berrut & Trefethen 2004, SIAM Rev. 46, 501; read-only)."""
    t, _ = gauss_legendre(p)
    b = barycentric_weights(p)
    diff = t[:, None] - t[None, :]
    np.fill_diagonal(diff, 1.0)
    D = (b[None, :] / b[:, None]) / diff
    np.fill_diagonal(D, 0.0)
    np.fill_diagonal(D, -D.sum(axis=1))              # derivative of a constant is 0
    D.flags.writeable = False
    return D


def surface_divergence(panels: PanelSet, u) -> np.ndarray:
    r"""Surface divergence :math:`t\cdot du/ds + u_r/r` [U/R] of an axisymmetric velocity field.

    Parameters
    ----------
    panels : PanelSet
        Panels of the membrane (nodes off the axis, r > 0).
    u : array_like, shape (2 n,) or (2 n, m)
        Velocity at the n nodes, interleaved (u_x, u_r) per node [U]; m fields at once.

    Returns
    -------
    ndarray, shape (n,) or (n, m)
        :math:`\nabla_s\cdot u = (I - nn):\nabla u` at the nodes, the derivative along each
        panel taken through the nodes' Lagrange interpolant (spectral in the panel order).
    """
    u = np.asarray(u, dtype=float)
    npan, p = panels.x.shape
    if u.shape[0] != 2 * panels.n_nodes:
        raise InvalidParameterError("u", f"{u.shape[0]} rows",
                                    f"2 x {panels.n_nodes} (x, r per node)")
    single = u.ndim == 1
    u2 = u.reshape(2 * panels.n_nodes, -1)
    m = u2.shape[1]
    ux = u2[0::2].reshape(npan, p, m)
    ur = u2[1::2].reshape(npan, p, m)
    D = _differentiation_matrix(p)
    _, wg = gauss_legendre(p)
    speed = (panels.w / wg[None, :])[..., None]        # |dX/dt| in the panel parameter t
    dux = np.einsum("ij,pjm->pim", D, ux) / speed
    dur = np.einsum("ij,pjm->pim", D, ur) / speed
    div = panels.tx[..., None] * dux + panels.tr[..., None] * dur + ur / panels.r[..., None]
    div = div.reshape(panels.n_nodes, m)
    return div[:, 0] if single else div


# ---------------------------------------------------------------------------- tension and speed
def inextensible_tension(panels: PanelSet, u0, U, rcond: float = 1e-12):
    r"""Tension coefficients g that make :math:`u = u_0 + U g` surface-divergence free.

    Weighted least squares :math:`\min_g \sum_i w_i (\nabla_s\cdot u)_i^2` (w the arc-length
    weights of the nodes; Chen et al. 2020 eq. surface). Singular values below ``rcond`` times
    the largest are dropped (the constant tension drives no flow on a sphere).

    Returns (g, u, div): coefficients [ηU], velocity [U] (interleaved x, r) and its remaining
    divergence at the nodes [U/R].
    """
    sw = np.sqrt(panels.w.ravel())
    d0 = surface_divergence(panels, u0)
    dU = surface_divergence(panels, U)
    g, *_ = np.linalg.lstsq(sw[:, None] * dU, -sw * d0, rcond=rcond)
    u = u0 + U @ g
    return g, u, d0 + dU @ g


def centroid_velocity(panels: PanelSet, un, volume: float) -> float:
    r"""Centroid velocity :math:`V = \Omega^{-1}\int x\,u\cdot n\,dS` [U] (Chen et al. 2020
    eq. Vel), with :math:`dS = 2\pi r\,dl` and ``un`` the normal velocity at the nodes."""
    dS = 2.0 * math.pi * panels.r.ravel() * panels.w.ravel()
    return float(np.sum(panels.x.ravel() * np.asarray(un) * dS) / volume)


@dataclass(frozen=True, eq=False)
class VesicleFlow:
    """Flow of one vesicle shape with the tension of local inextensibility.

    ``ux, ur, un`` membrane velocity at the nodes (lab frame) [U]; ``g`` tension coefficients
    [ηU]; ``V`` centroid velocity [U]; ``dp`` Δp⁺R/(ηU); ``divergence`` the remaining surface
    divergence at the nodes [U/R]; ``rate`` the free-mode rate (d z/dt) [1/(R/U)].
    """

    curve: SpectralCurve
    panels: PanelSet
    g: np.ndarray
    V: float
    dp: float
    ux: np.ndarray
    ur: np.ndarray
    un: np.ndarray
    divergence: np.ndarray
    rate: np.ndarray = field(repr=False)
    G: np.ndarray = field(repr=False)          # d(X.n)/dz of the free modes at the nodes

    def residual(self) -> np.ndarray:
        """u.n - V n_x at the nodes: the normal velocity in the centroid frame [U]."""
        return self.un - self.V * self.panels.nx.ravel()

    def max_residual(self) -> float:
        return float(np.max(np.abs(self.residual())))


def vesicle_flow(op, curve: SpectralCurve, G: np.ndarray | None = None) -> VesicleFlow:
    """Velocity, inextensibility tension, centroid speed and free-mode rate of ``curve``
    (one BEM evaluation; ``op`` a :class:`bem.vesicle.VesicleOperator`). ``G`` the shape
    velocity matrix to project with (default: that of ``curve``)."""
    panels, u0, U, dp0, dp = op.velocity_columns(curve)
    g, u, div = inextensible_tension(panels, u0, U)
    ux, ur = u[0::2], u[1::2]
    nx = panels.nx.ravel()
    un = ux * nx + ur * panels.nr.ravel()
    V = centroid_velocity(panels, un, op.volume)
    sw = np.sqrt(panels.w.ravel())
    if G is None:
        G = shape_velocity_matrix(op, curve.modes)
    rate, *_ = np.linalg.lstsq(sw[:, None] * G, sw * (un - V * nx), rcond=None)
    op.evaluations += 1
    return VesicleFlow(curve=curve, panels=panels, g=g, V=V, dp=float(dp0 + dp @ g), ux=ux,
                       ur=ur, un=un, divergence=div, rate=rate, G=G)


def quiescent_velocity(op, curve: SpectralCurve):
    """(panels, u0, U) of ``curve`` with the imposed Poiseuille flow removed (a tube at zero net
    flux): the columns of :meth:`VesicleOperator.velocity_columns` less u∞ = 2(1 - r²) e_x."""
    panels, u0, U, _, _ = op.velocity_columns(curve)
    u0 = u0.copy()
    u0[0::2] -= poiseuille(panels.r.ravel())
    return panels, u0, U


def vesicle_operator(result, n_tension: int | None = None):
    """:class:`bem.vesicle.VesicleOperator` at the parameters and resolution of a
    :class:`bem.results.VesicleResult`, its shape the reference (wall, inlet, panel breaks)."""
    pan = result.panels
    disc = vesicle_discretisation(int(pan["modes"]), int(pan["order"]), int(pan["drop"]))
    return VesicleOperator(result.nu, result.lam, result.ca_b, disc, result.curve(),
                           n_tension or int(pan.get("tension", pan["modes"])))


# ---------------------------------------------------------------------------- time stepping
def _fd_jacobian(op, z, template, base: VesicleFlow, fd_step):
    """Forward-difference Jacobian of the free-mode rate (N - 2 BEM evaluations).

    The projection matrix G is held at the base shape: this drops the term (dG⁺/dz)(u·n − V n_x),
    which vanishes at a steady state and is smooth (geometry only), and saves the N - 2 shape
    perturbations of each G; the stiff bending response is differenced in full."""
    def rate(z2):
        return vesicle_flow(op, op.curve(op.full(z2, template)), base.G).rate, None

    return difference_jacobian(rate, z, base.rate, fd_step, {})[0]


def relaxation_rate_brochard_lennon_1975(q, kappa: float, gamma: float):
    r"""Relaxation rate :math:`\omega = (\kappa q^3 + \gamma q)/(4\eta)` [U/R] of a shape mode
    of wavenumber q [1/R] of a flat membrane (bending modulus κ [ηUR²], tension γ [ηU]) between
    two fluids of viscosity η = 1 (Brochard & Lennon 1975, J. Phys. 36, 1035; Seifert 1997,
    Adv. Phys. 46, 13, §9). For the highest resolved mode it estimates the stiffest eigenvalue
    of the mode-rate Jacobian (measured within 4 %, see :func:`relax_vesicle`).

    Examples
    --------
    >>> float(relaxation_rate_brochard_lennon_1975(10.0, 0.01, 0.0))
    2.5
    """
    q = np.asarray(q, dtype=float)
    return (kappa * q**3 + gamma * q) / 4.0


def _explicit_step(op, flow: VesicleFlow) -> float:
    """Default Heun step: 0.8 of the real-axis stability limit 2/omega of the fastest mode,
    omega from :func:`relaxation_rate_brochard_lennon_1975` with q = N pi/(S min g) (the
    shortest wavelength of N modes) and the largest |tension|."""
    curve = flow.curve
    tt = np.linspace(0.0, 1.0, 201)
    q = curve.n_modes * math.pi / (curve.length * float(np.min(curve.g(tt))))
    gmax = float(np.max(np.abs(tension_profile(curve, flow.g, tt)[0])))
    return 0.8 * 2.0 / float(relaxation_rate_brochard_lennon_1975(q, op.kappa, gmax))


def relax_vesicle(op, modes0, t_end: float, *, dt: float | None = None, max_steps: int = 5000,
                  tol: float = 0.0, method: str = "implicit", jacobian_every: int = 25,
                  growth: float = 1.5, regrow: int = 5, fd_step: float = 1e-6,
                  max_time: float | None = None):
    r"""Integrate the vesicle shape in time, the tension from local inextensibility.

    Parameters
    ----------
    op : bem.vesicle.VesicleOperator
        Discretisation and parameters (ν, λ, Ca_B); its panel breaks and wall stay fixed.
    modes0 : array_like
        Initial shape modes (the closing and area modes are recomputed by ``op.curve``).
    t_end : float
        Final time [R/U].
    dt : float, optional
        Largest (and initial) step [R/U]. Default 0.1 for ``"implicit"`` (it resolves the
        advection time of the shape, as in :func:`bem.drop.relax_drop`); for ``"heun"`` 0.8 of
        the explicit limit 2/ω, ω the fastest mode's rate
        (:func:`relaxation_rate_brochard_lennon_1975`).
    max_steps : int
        Largest number of accepted steps.
    tol : float
        Stop once max|u·n − V n_x| < tol [U] (0: run to ``t_end``).
    method : {"implicit", "heun"}
        Linearised backward Euler with a reused difference Jacobian (default), or explicit Heun.
    jacobian_every : int
        Accepted steps between Jacobian refreshes (implicit only).
    growth : float
        Step control on the peak normal velocity P = max|u·n − V n_x|: a step that raises P by
        more than ``growth`` is rejected and h halved; when P has risen by more than ``growth``
        above its smallest value at the current step size (a slow instability just above the
        limit, which no single step reveals), h is halved and becomes the largest step.
    regrow : int
        After ``regrow`` accepted steps in a row h grows by 1.25, up to the largest step.
    fd_step : float
        Relative forward-difference step of the Jacobian.
    max_time : float, optional
        Wall-time budget [s] (:class:`lubrication.checks.Deadline`), tested between steps;
        when spent the integration stops (``info["time_limit"]``). Default: no limit.

    Returns
    -------
    modes : ndarray
        Final modes (the last valid ones on failure).
    state : VesicleFlow
        Flow of the final shape.
    info : dict
        ``t`` [R/U], ``steps`` (accepted), ``rejected``, ``jacobians``, ``evaluations`` (BEM),
        ``dt`` (last step size) [R/U], ``max_un`` = max|u·n − V n_x| at the end [U], ``history``
        [(t, max|u·n − V n_x|, V)] at the start and after each accepted step, ``failure``
        (empty, or why the shape became invalid, e.g. touching the wall), ``time_limit``
        (True if ``max_time`` ended the integration).

    Notes
    -----
    Measured at ν = 0.98, λ = 0.3, Ca_B = 50 (κ = 1.8e-3) at the steady state, 16-point panels:
    all eigenvalues of the mode-rate Jacobian are real and negative; the stiffest is −78.9 with
    16 modes and −245 with 24 (flat-membrane estimate of the highest mode 76.4 and 237), the
    slowest −0.83 (the approach to the steady shape). Explicit Heun is therefore limited to
    dt ≤ 2/78.9 = 0.025 R/U at 16 modes (observed: a perturbation decays at dt = 0.024 and grows
    ×175 in 40 steps at dt = 0.027), scaling like (N/S)^-3 κ^-1; relaxing the slowest mode then
    takes ~200 steps of two evaluations. The linearised backward Euler step damps every mode
    for any h (the test suite runs it at h = 0.1–0.5 R/U, 4–20 × the explicit limit), costs one
    evaluation per step plus N − 2 per Jacobian, and leaves a steady state in place.
    """
    method = check_choice("method", method, ("implicit", "heun"))
    t_end = float(check_range("t_end", t_end, 0.0))
    max_steps = int(check_range("max_steps", max_steps, 0))
    tol = float(check_range("tol", tol, 0.0))
    jacobian_every = int(check_range("jacobian_every", jacobian_every, 1))
    growth = float(check_range("growth", growth, 1.0, lo_open=True))
    regrow = int(check_range("regrow", regrow, 1))
    fd_step = float(check_range("fd_step", fd_step, 1e-12, 1e-2))
    deadline = Deadline(max_time)
    if dt is not None:
        dt = float(check_positive("dt", dt))
    ev0 = op.evaluations
    flow = vesicle_flow(op, op.curve(np.asarray(modes0, dtype=float)))
    modes = flow.curve.modes.copy()
    if dt is None:
        dt = 0.1 if method == "implicit" else _explicit_step(op, flow)
    cap = dt
    # below this the step control is waived: a transient that grows by ``growth`` within a
    # step of 1e-6 dt is physical, not an instability of the step
    dt_min = 1e-6 * cap
    h = cap
    t, steps, rejected, streak, n_jac, age = 0.0, 0, 0, 0, 0, 0
    peak = flow.max_residual()
    floor = peak                                   # smallest peak at the current step size
    history = [(t, peak, flow.V)]
    failure = ""
    J = None
    while (t < t_end - 1e-14 and steps < max_steps and not (tol > 0 and peak < tol)
           and not deadline.expired()):
        step = min(h, t_end - t)
        z = op.free(modes)
        try:
            if method == "implicit":
                if J is None or age >= jacobian_every:
                    J = _fd_jacobian(op, z, modes, flow, fd_step)
                    n_jac, age = n_jac + 1, 0
                dz = np.linalg.solve(np.eye(z.size) - step * J, step * flow.rate)
            else:
                k2 = vesicle_flow(op, op.curve(op.full(z + step * flow.rate, modes))).rate
                dz = 0.5 * step * (flow.rate + k2)
            new = vesicle_flow(op, op.curve(op.full(z + dz, modes)))
        except InvalidParameterError as exc:
            if h <= dt_min:
                failure = f"the membrane became invalid at t = {t:.4g} R/U ({exc})"
                break
            h, streak, J, rejected, floor = 0.5 * h, 0, None, rejected + 1, peak
            continue
        new_peak = new.max_residual()
        if new_peak > growth * peak and h > dt_min:
            log.debug("relax_vesicle t=%.4g: peak %.2e -> %.2e, step rejected, dt %.3g -> %.3g",
                      t, peak, new_peak, h, 0.5 * h)
            h, streak, rejected, floor = 0.5 * h, 0, rejected + 1, peak
            if method == "implicit" and age > 0:
                J = None                           # a stale Jacobian may be the cause
            continue
        flow, modes, peak = new, new.curve.modes.copy(), new_peak
        t += step
        steps, streak, age = steps + 1, streak + 1, age + 1
        history.append((t, peak, flow.V))
        if peak > growth * floor and h > dt_min:
            log.debug("relax_vesicle t=%.4g: peak grew %.2e -> %.2e at dt %.3g; dt -> %.3g",
                      t, floor, peak, h, 0.5 * h)
            h = cap = 0.5 * h
            streak, floor = 0, peak
            if method == "implicit":
                J = None
        floor = min(floor, peak)
        if streak >= regrow and h < cap:
            h, streak, floor = min(1.25 * h, cap), 0, peak
    info = {"t": t, "steps": steps, "rejected": rejected, "jacobians": n_jac,
            "evaluations": op.evaluations - ev0, "dt": h, "max_un": peak, "history": history,
            "failure": failure, "time_limit": deadline.expired()}
    log.info("relax_vesicle (%s): t=%.4g R/U, %d steps (%d rejected), %d Jacobians, "
             "max|u.n - V n_x| %.2e, V %.8f", method, t, steps, rejected, n_jac, peak, flow.V)
    return modes, flow, info
