r"""Lubrication solver for a steady vesicle in a tube (Secomb et al. 1986; Barakat & Shaqfeh 2018b).

The method, in the order of this module:

1. **Inputs and targets.** Reduced volume ``nu``, confinement :math:`\lambda = R_0/R` (or
   :math:`\lambda/\lambda_c`), bending capillary number :math:`\mathrm{Ca}_B = \eta U R_0^2/\kappa`
   (``inf``: high-Ca model). In tube radii the vesicle has area :math:`4\pi\lambda_A^2`
   (:math:`\lambda_A = \lambda\nu^{-1/3}`) and volume :math:`\frac43\pi\lambda^3`.
2. **Polar caps.** The parallel-flow model fails at the poles and its membrane shear rate
   diverges there like :math:`1/(r\ln r)`. Caps of rim radius ``CAP_RADIUS`` are excised and
   treated as spherical (uniform pressure and tension); the boundary conditions at the rims
   carry the caps' angle, area and volume (:func:`lubrication.equations.spherical_cap`), so the
   ODEs are never integrated through the regular singular points.
3. **Initial guess.** A spherocylinder of radius :math:`\rho = \lambda/\lambda_c` (it has the
   vesicle's area and volume), :math:`Q_0 = \delta` (a uniform film), front tension from the
   immobile-interface Bretherton law :math:`\sigma_0 = 6(0.643/\delta)^{3/2}` [ηV], pressure
   :math:`-2\sigma_0/\rho` in the caps and :math:`-\sigma_0/\rho` on the body. Or a previous
   solution (warm start), rescaled to the new clearance. Warm starts carry the solution along a
   sweep (continuation in λ/λc, steps of at most half the clearance) and in Ca.
4. **High-Ca boundary-value problem** (:func:`lubrication.equations.rhs_high_ca`, 6 unknown
   functions, unknown parameters Q and the arc length S, 8 boundary conditions) by
   :func:`scipy.integrate.solve_bvp`. Pressure and tension are divided by a tension scale so
   that every unknown is O(1): solve_bvp measures residuals relative to 1 + ``|f|``, and unscaled
   tensions of 1e5 put a round-off floor above the tolerance at the poles (the "maximum number
   of mesh nodes exceeded" trap).
5. **Bending problem** (:func:`lubrication.equations.rhs_bending`, 8 functions, 10 conditions),
   by continuation in Ca from the high-Ca solution.
   **Red-cell membrane** (``ca_s`` finite, :mod:`lubrication.membrane`): the same two problems
   with the principal tensions of a shear-elastic membrane (the meridional tension takes the
   tension's place among the unknowns; the stretch comes from the area A already integrated),
   reached from the vesicle solution of the same point by continuation in
   :math:`\mathrm{Ca}_S = \eta U/G_s` from 1e3 down, or from a red-cell warm start.
6. **Acceptance.** Never the solver's status flag alone: largest collocation residual, area and
   volume recomputed by quadrature of the solution (relative error ≤ ``CONSTRAINT_TOL``), net
   axial force on the vesicle (≤ ``FORCE_TOL`` of its pressure force), positive tension on the
   physical branch, for a red cell the azimuthal stretch inside the guard of the material map
   and a meridian that does not cross itself. A failure is returned as a result with its
   :class:`~lubrication.results.Status` (``success`` False) and the reason.
7. **Result** in project units (:class:`lubrication.results.LubricationResult`):
   :math:`V/U = 1/(1 - Q)`, :math:`\Delta p^+ R/(\eta U) = [\Delta p^+R/(\eta V)]/(1 - Q)`,
   :math:`\Delta p^+R_0/(\eta U) = [\Delta p^+R/(\eta V)]\,\lambda/(1 - Q)` with
   :math:`\Delta p^+ = \Delta p - 8(1 - Q)L` (Poiseuille drop at the mean velocity over the
   length L), tensions in ηU.

:func:`sweep_lubrication` solves a list of confinements by continuation.

**Where the model is attempted** (checked by :func:`check_inputs` before any work; outside,
:class:`~lubrication.checks.InvalidParameterError` naming the parameter and its range):
``NU_RANGE`` 0.3 <= nu < 1; ``CA_B_RANGE`` 1e-2 <= Ca_B <= 1e5 or inf; lam/lam_c from
``MIN_LAM_RATIO`` = 0.1 (the parallel-flow model needs a vesicle that nearly fills the tube) and,
for the high-Ca model, from the measured end of its branch (``HIGH_CA_BRANCH_END``: 0.597 at
nu = 0.9), below which that model has no solution; up to 1 (exclusive: critical confinement).

**Resource envelope** (measured on a shared 2-core machine, tol = 1e-7):

* Mesh: at most ``max_nodes`` (default 20 000, at most ``MAX_NODES`` = 20 000) nodes per
  solve_bvp call; a cold start away from critical confinement at most 8000, a continuation step
  at most max(5000, 3 x its start), a warm start's mesh is thinned above 1500 nodes. The
  longest stretch in compiled code is the sparse LU of one Newton step: 0.46 s at 6200 nodes
  (8 unknowns), 1.0 s at 15 400 nodes, 2.0 s at 43 000 nodes; hence the cap, so that Ctrl-C
  (honoured whenever control returns to Python) and ``max_time`` act within about 1-2 s.
* Continuation: steps in lam/lam_c of at most ``MAX_STEP`` = 0.02 and at most half the
  clearance, at least ``MIN_STEP`` = 5e-4, and at most ``MAX_CONTINUATION_STEPS`` attempts per
  march; in Ca_B, factors of 3 from 1e4 down to Ca_B (at most 13 steps at Ca_B = 1e-2).
* Wall time: one point near critical 0.5-3 s (cold start); far from it, reached by
  continuation from lam/lam_c = 0.98, 10-30 s (high-Ca down to its branch end at nu = 0.9:
  13 s), up to ~2 min for the bending model near the end of its branch; a warm-started sweep
  point 0.2-1 s. ``max_time`` (seconds, :class:`~lubrication.checks.Deadline`) bounds any
  solve: it is tested at every right-hand-side evaluation of solve_bvp and between attempts
  and continuation steps, and a spent budget returns status TIME_LIMIT with the reason.
* Sweeps: at most ``MAX_SWEEP_POINTS`` = 2000 points.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, replace

import numpy as np
from scipy.integrate import cumulative_trapezoid, solve_bvp
from tqdm.auto import tqdm

from .checks import CannotPassError, Deadline, InvalidParameterError, check_choice, check_range
from .equations import (BENDING_STATE, HIGH_CA_STATE, gap_flow, capillary_number, rhs_bending,
                        rhs_high_ca, shear_modulus, spherical_cap)
from .geometry import critical_confinement, critical_length
from .io import provenance
from .membrane import (REFERENCE_SHAPES, STRETCH_SQ_GUARD, MembraneShear, reference_shape,
                       tension_difference)
from .results import LubricationResult, Status

__all__ = ["solve_lubrication", "sweep_lubrication", "check_inputs", "check_shear_inputs",
           "lowest_lam_ratio", "high_ca_branch_end", "CAP_RADIUS", "CONSTRAINT_TOL", "FORCE_TOL",
           "NU_RANGE", "MIN_LAM_RATIO", "CA_B_RANGE", "CA_S_RANGE", "HIGH_CA_BRANCH_END",
           "MAX_SWEEP_POINTS", "TOL_RANGE"]

logger = logging.getLogger(__name__)

# Rim radius of the excised polar caps [R]. Barakat & Shaqfeh switch to the spherical cap below
# r = 2e-3 (high-Ca). Halving it moves V/U by < 1e-9 and dp+ by < 1e-6 relative (nu = 0.6-0.9,
# lam/lam_c = 0.6-0.99, both models; tests/lubrication/test_solve.py), but the tensions at the
# poles by 4e-5 (lam/lam_c = 0.99) to 7e-2 (0.6, where the tension is O(eta U)): the
# parallel-flow shear rate ~ 1/(r ln r) has a log-log divergent integral at the poles.
CAP_RADIUS = 2e-3
# Acceptance: relative error of area and volume recomputed by quadrature; net axial force on the
# vesicle relative to the scale of its pressure force (physics notes §4).
CONSTRAINT_TOL = 1e-8
FORCE_TOL = 1e-3
# Accepted relative collocation tolerance of solve_bvp: below 1e-12 it is under the residuals'
# rounding floor; above 1e-3 the collocation no longer resolves the film.
TOL_RANGE = (1e-12, 1e-3)
# Resource envelope (module docstring). Largest mesh of one solve_bvp call: its Newton steps
# factorise a sparse system of (6 or 8) x nodes unknowns, the longest stretch in compiled code
# (where Ctrl-C waits): 1.0 s at 15 400 nodes, 2.0 s at 43 000 (measured, bending model).
MAX_NODES = 20_000
# Smallest continuation step in lam/lam_c: below it the branch is taken to end (or fold).
MIN_STEP = 5e-4
# Most solve attempts of one continuation in lam/lam_c: a full march from ANCHOR_RATIO to
# MIN_LAM_RATIO at the smallest step; measured marches take 20-200.
MAX_CONTINUATION_STEPS = 2000
# Most points of one sweep: 2000 points over 0 < lam/lam_c < 1 are 5e-4 = MIN_STEP apart, so a
# denser sweep resolves nothing the continuation itself could; at 0.2-1 s per warm-started point
# (measured) 2000 points take 10-30 minutes.
MAX_SWEEP_POINTS = 2000


# --------------------------------------------------------------------------- 1. inputs, targets
# Where the model is attempted (checked before any work; outside: InvalidParameterError).
#
# Reduced volume: the solver is measured for 0.3 <= nu <= 0.999 (tests/lubrication and the
# branch ends below; nu = 0.3-0.4 converge near critical, 0.99-0.999, in both models in 1-3 s).
# Below, the vesicle (length ~ 2 nu^(-2/3) lam_c^2 R: 49 R at nu = 0.3, 450 R at nu = 0.1) is
# untested, and a nu of 0 or a subnormal one would make lam_c overflow.
NU_RANGE = (0.3, 1.0)
# Smallest lam/lam_c in every model. The parallel-flow model needs a vesicle that nearly fills
# the tube (gap small against length); it is qualitative already below lam/lam_c ~ 0.45 (dp+ < 0
# at nu = 0.9). At 0.1 the vesicle is a body of radius ~0.1 R in a tube (the small-object limits
# of Faxen and Chen et al. 2020 eq. small1/small2, or the BEM, apply there), and below
# CAP_RADIUS / lam_c the excised polar caps would be wider than the vesicle.
MIN_LAM_RATIO = 0.1
# Shear capillary number Ca_S = eta U/G_s of a red-cell membrane (lubrication.membrane):
# 0.02-1 for red cells at 0.1-5 mm/s (G_s = 6 µN/m, eta = 1.2 mPa s). Measured at nu = 0.61,
# lam/lam_c = 0.95, high-Ca: Ca_S = 0.1-1000 converge in 1-3 s, 0.01 does not (its continuation
# in lam/lam_c stops at 0.962); the departure from the vesicle falls like 1/Ca_S (3.4e-8 in V/U
# and 6.8e-7 in dp+ at 1000), so above 1e4 the red cell is the vesicle (ca_s=None) within the
# solver's tolerance. The bending model in a 5 µm tube: tests/benchmarks/rbc_shear_lubrication.py.
CA_S_RANGE = (1e-2, 1e4)
# Bending capillary number Ca_B = eta U R0^2/kappa of the bending model (measured at nu = 0.9,
# lam/lam_c = 0.99): 1e-2 converges in 1.3 s (13 continuation steps in Ca from 1e4); at 1e5 the
# bending model agrees with the high-Ca model (ca_b=inf) to 1e-10 in V/U and 1e-8 in dp+, and
# above it the stiff bending problem takes ever longer (40 s at 1e7): use ca_b=inf there.
CA_B_RANGE = (1e-2, 1e5)
# End of the high-Ca branch: lowest lam/lam_c reached by continuation from 0.98 in lam/lam_c
# (steps down to 5e-4; precision ~1e-3) before the rear pole flattens and the tension vanishes
# there, so the tension-only (kappa -> 0) model has no physical solution below (measured with
# this solver, tol 1e-7; (nu, lowest lam/lam_c) pairs, linear interpolation in between).
# Below nu = 0.45 the end lies above the anchor 0.98 of the continuation (nu = 0.4 fails there)
# and was not measured: the value at 0.45 is used, a lower bound (the end rises as nu falls). At
# nu = 0.997 and 0.999 the branch was followed down to lam/lam_c = 0.1 and 0.05 without ending.
HIGH_CA_BRANCH_END = (
    (0.45, 0.9688), (0.475, 0.9617), (0.5, 0.9536), (0.55, 0.9338), (0.6, 0.9081),
    (0.65, 0.8768), (0.7, 0.8379), (0.75, 0.7925), (0.8, 0.7375), (0.85, 0.6725), (0.9, 0.5968),
    (0.93, 0.5509), (0.95, 0.5081), (0.96, 0.4744), (0.97, 0.4250), (0.98, 0.3450),
    (0.985, 0.2881), (0.99, 0.2116), (0.9925, 0.1624), (0.995, 0.1031), (0.997, 0.1),
    (0.999, 0.05),
)


def high_ca_branch_end(nu) -> float:
    """Lowest lam/lam_c of the high-Ca (``ca_b=inf``) model at reduced volume ``nu`` (measured).

    Linear interpolation in :data:`HIGH_CA_BRANCH_END` (constant beyond its ends). Below it the
    rear pole of the tension-only membrane would have to turn concave, which needs bending: the
    high-Ca model has no solution there, the bending model (finite ``ca_b``) continues into
    parachutes (Barakat & Shaqfeh 2018b).

    Examples
    --------
    >>> high_ca_branch_end(0.9)
    0.5968
    """
    table = np.array(HIGH_CA_BRANCH_END)
    return float(np.interp(nu, table[:, 0], table[:, 1]))


def lowest_lam_ratio(nu, ca_b=math.inf) -> float:
    """Lowest lam/lam_c the solver attempts for ``nu`` and ``ca_b``: :data:`MIN_LAM_RATIO`, and
    for the high-Ca model (``ca_b=inf``) the end of its branch, :func:`high_ca_branch_end`.

    Examples
    --------
    >>> lowest_lam_ratio(0.9), lowest_lam_ratio(0.9, 50.0)
    (0.5968, 0.1)
    """
    if ca_b == math.inf:
        return max(MIN_LAM_RATIO, high_ca_branch_end(nu))
    return MIN_LAM_RATIO


#: Names of the inputs in messages (the command line passes its option names instead).
PARAMETER_NAMES = {"nu": "nu", "lam": "lam", "lam_ratio": "lam_ratio", "ca_b": "ca_b",
                   "ca_s": "ca_s", "reference": "reference"}


def check_inputs(nu, lam=None, lam_ratio=None, ca_b=math.inf, *, names=None):
    """Checked ``(nu, lam, lam_c, ca_b)`` of a lubrication solve, before any work.

    Exactly one of ``lam``, ``lam_ratio``; ``nu`` in :data:`NU_RANGE` (open at 1), ``ca_b`` in
    :data:`CA_B_RANGE` or ``math.inf``; lam/lam_c below 1 (else :class:`CannotPassError`) and
    at least :func:`lowest_lam_ratio` (the model has no solution or does not apply below). The
    messages name the parameter through ``names`` (default :data:`PARAMETER_NAMES`; the command
    line passes ``{"nu": "--nu", ...}``) and give the valid range in the unit of the value that
    was given (lam or lam/lam_c).

    Raises
    ------
    InvalidParameterError
        A value NaN, infinite, of the wrong type or outside its range (the message names it).
    CannotPassError
        lam >= lam_c(nu).
    """
    n = dict(PARAMETER_NAMES, **(names or {}))
    nu = float(check_range(n["nu"], nu, *NU_RANGE, hi_open=True,
                           reason="the lubrication solver is measured for deflated vesicles "
                                  f"{NU_RANGE[0]:g} <= nu < 1 (a sphere cannot deform; more "
                                  "deflated ones are longer than 50 tube radii, untested)"))
    if (lam is None) == (lam_ratio is None):
        raise InvalidParameterError(n["lam"], "both" if lam is not None else "neither",
                                    f"give exactly one of {n['lam']} and {n['lam_ratio']}")
    if isinstance(ca_b, (int, float, np.integer, np.floating)) and ca_b == math.inf:
        ca_b = math.inf
    else:
        ca_b = float(check_range(n["ca_b"], ca_b, *CA_B_RANGE,
                                 reason=f"bending capillary number; {n['ca_b']}=inf selects the "
                                        "high-Ca (kappa -> 0) model, which bending approaches "
                                        f"within 1e-8 at {CA_B_RANGE[1]:g}"))
    lam_c = float(critical_confinement(nu))
    lowest = lowest_lam_ratio(nu, ca_b)
    if ca_b == math.inf and lowest > MIN_LAM_RATIO:
        why = (f"the high-Ca model ({n['ca_b']}=inf) has no solution below lam/lam_c = "
               f"{lowest:.4g} at nu={nu:g} (its branch ends where the rear pole flattens); "
               f"give a finite bending capillary number, e.g. {n['ca_b']}=50 (Chen et al. 2020)")
    else:
        why = (f"the lubrication (parallel-flow) model needs a vesicle that nearly fills the tube "
               f"and is not applied below lam/lam_c = {MIN_LAM_RATIO:g}; use the BEM "
               "(vesicle-tube bem vesicle) or the small-object limits there")
    if lam is None:
        name = n["lam_ratio"]
        ratio = float(check_range(name, lam_ratio, 0.0, 1.0, lo_open=True, hi_open=True,
                                  reason="lam/lam_c >= 1: the vesicle cannot pass this tube "
                                         "intact" if _at_least_one(lam_ratio) else "",
                                  error=CannotPassError if _at_least_one(lam_ratio)
                                  else InvalidParameterError))
        if ratio < lowest:
            raise InvalidParameterError(name, ratio, f"{lowest:.4g} <= {name} < 1", why)
        lam = ratio * lam_c
    else:
        name = n["lam"]
        lam = float(check_range(name, lam, 0.0, lam_c, lo_open=True, hi_open=True,
                                reason="lam >= lam_c(nu): the vesicle cannot pass this tube "
                                       "intact" if _at_least(lam, lam_c) else "",
                                error=CannotPassError if _at_least(lam, lam_c)
                                else InvalidParameterError))
        if lam < lowest * lam_c:
            raise InvalidParameterError(name, lam, f"{lowest * lam_c:.4g} <= {name} < "
                                        f"lam_c = {lam_c:.6g} at nu={nu:g}", why)
    return nu, lam, lam_c, ca_b


def check_shear_inputs(nu, ca_s=None, reference="biconcave", *, names=None,
                       ca_s_range=CA_S_RANGE):
    """Checked ``(ca_s, reference)`` of a red-cell membrane, before any work.

    ``ca_s`` None or ``math.inf``: no shear elasticity (a vesicle), returned as ``math.inf``;
    else within ``ca_s_range`` (default :data:`CA_S_RANGE`, this solver's; the BEM passes
    its own, :data:`bem.vesicle.CA_S_RANGE`). ``reference`` one of
    :data:`lubrication.membrane.REFERENCE_SHAPES`; with a finite ``ca_s`` the reference shape
    must exist at ``nu`` (:func:`lubrication.membrane.reference_nu_range`). ``names`` as in
    :func:`check_inputs`.

    Raises
    ------
    InvalidParameterError
        The message names the parameter, its value and the valid range.
    """
    n = dict(PARAMETER_NAMES, **(names or {}))
    reference = check_choice(n["reference"], reference, REFERENCE_SHAPES)
    if ca_s is None or (isinstance(ca_s, (int, float, np.integer, np.floating))
                        and ca_s == math.inf):
        return math.inf, reference
    ca_s = float(check_range(n["ca_s"], ca_s, *ca_s_range,
                             reason=f"shear capillary number eta U/G_s; {n['ca_s']}=None (or inf) "
                                    "for a vesicle (no shear elasticity)"))
    reference_shape(reference, nu)          # raises if the family has no member at nu
    return ca_s, reference


def _at_least(x, bound) -> bool:
    """``x >= bound`` for a finite real ``x``; False for anything else (checked elsewhere)."""
    try:
        x = float(x)
    except (TypeError, ValueError):
        return False
    return math.isfinite(x) and x >= bound


def _at_least_one(x) -> bool:
    return _at_least(x, 1.0)


@dataclass(frozen=True)
class _Problem:
    nu: float
    lam: float
    lam_c: float
    ca_b: float
    tol: float
    max_nodes: int
    deadline: Deadline = Deadline(None)
    ca_s: float = math.inf
    reference: str = "biconcave"

    @property
    def delta(self) -> float:
        return 1.0 - self.lam / self.lam_c

    @property
    def shear(self) -> MembraneShear | None:
        """The red-cell membrane's shear elasticity, or None for a vesicle (Ca_S = inf)."""
        if math.isinf(self.ca_s):
            return None
        return MembraneShear(self.ca_s, reference_shape(self.reference, self.nu), self.area)

    @property
    def model(self) -> str:
        return "high-Ca" if math.isinf(self.ca_b) else "bending"

    @property
    def area(self) -> float:
        """Vesicle area in R^2: 4 pi lam_A^2, lam_A = lam nu^(-1/3)."""
        return 4.0 * math.pi * self.lam**2 * self.nu ** (-2.0 / 3.0)

    @property
    def volume(self) -> float:
        """Vesicle volume in R^3: (4/3) pi lam^3."""
        return 4.0 / 3.0 * math.pi * self.lam**3


def _check_inputs(nu, lam, lam_ratio, ca_b, tol, max_nodes, max_time=None, ca_s=None,
                  reference="biconcave") -> _Problem:
    nu, lam, lam_c, ca_b = check_inputs(nu, lam, lam_ratio, ca_b)
    ca_s, reference = check_shear_inputs(nu, ca_s, reference)
    tol = float(check_range("tol", tol, *TOL_RANGE,
                            reason="solve_bvp's relative residual tolerance"))
    if (not isinstance(max_nodes, (int, np.integer)) or isinstance(max_nodes, bool)
            or not 100 <= max_nodes <= MAX_NODES):
        raise InvalidParameterError("max_nodes", max_nodes, f"an integer, 100 <= max_nodes <= "
                                    f"{MAX_NODES}", "the mesh bounds the time of one solve_bvp "
                                    "call (module docstring: resource envelope)")
    return _Problem(nu, lam, lam_c, ca_b, tol, int(max_nodes), Deadline(max_time), ca_s,
                    reference)


# --------------------------------------------------------------------------- 2.-3. initial guess
def _tension_scale(delta):
    """Front tension of the immobile-interface Bretherton film h = 0.643 (6 Ca)^(2/3) [eta V]."""
    return 6.0 * (0.643 / delta) ** 1.5


def _spherocylinder_guess(prob: _Problem):
    """High-Ca unknowns on a spherocylinder of radius lam/lam_c: (t, y, [Q, S])."""
    # 400 nodes resolve the guess; solve_bvp refines where the solution needs it.
    n_nodes = 400
    rho = prob.lam / prob.lam_c
    eps = CAP_RADIUS
    cylinder = rho * (critical_length(prob.nu) - 2.0)
    theta_rim = math.asin(eps / rho)
    cap_arc = rho * (0.5 * math.pi - theta_rim)
    S = 2.0 * cap_arc + cylinder
    t = np.linspace(0.0, 1.0, n_nodes)
    s = S * t
    rear, front = s < cap_arc, s > S - cap_arc
    body = ~(rear | front)
    theta = np.where(rear, theta_rim + s / rho,
                     np.where(front, theta_rim + (S - s) / rho, 0.5 * math.pi))
    r = rho * np.sin(theta)
    psi = np.where(rear, theta - 0.5 * math.pi, np.where(front, 0.5 * math.pi - theta, 0.0))
    sigma0 = _tension_scale(prob.delta)
    sigma = np.full_like(s, sigma0)
    p = np.where(body, -sigma0 / rho, -2.0 * sigma0 / rho)
    _, cap_area, cap_volume = spherical_cap(1.0 / rho, eps)
    A = cap_area + cumulative_trapezoid(2.0 * math.pi * r, s, initial=0.0)
    Omega = cap_volume + cumulative_trapezoid(math.pi * r * r * np.cos(psi), s, initial=0.0)
    Q0 = prob.delta
    return t, np.vstack((r, psi, p, sigma, A, Omega)), np.array([Q0, S])


def _rescaled_guess(prob: _Problem, state):
    """A previous high-Ca or bending state moved to the clearance of ``prob`` (a predictor).

    The shape is scaled by (1 - delta_new)/(1 - delta_old) (a spherocylinder of radius 1 - delta
    keeps its gap equal to delta), Q like the rigid-cylinder estimate (1 - rho^2)/2, tension and
    pressure like the Bretherton scale delta^(-3/2), area and volume like their targets.
    """
    model, t, y, params, old = state
    # solve_bvp only ever adds nodes; a warm start from a mesh refined for another solution
    # drops every other node (the clustering survives) so that meshes do not grow along a sweep.
    remesh_above = 1500
    while len(t) > remesh_above:
        keep = np.r_[0:len(t) - 1:2, len(t) - 1]
        t, y = t[keep], y[:, keep]
    rho_old, rho_new = 1.0 - old["delta"], 1.0 - prob.delta
    f_len = rho_new / rho_old
    f_q = (1.0 - rho_new**2) / (1.0 - rho_old**2)
    f_sig = _tension_scale(prob.delta) / _tension_scale(old["delta"])
    y = y.copy()
    y[0] *= f_len
    names = HIGH_CA_STATE if model == "high-Ca" else BENDING_STATE
    if model == "bending":      # tensions in kappa/R^2 also scale with Ca = eta V R^2/kappa
        f_sig *= capillary_number(prob.ca_b, prob.lam, params[0] * f_q) / old["ca"]
    for name in ("p", "sigma"):
        y[names.index(name)] *= f_sig
    if model == "bending":
        y[names.index("c_s")] /= f_len
        y[names.index("q_s")] *= math.sqrt(f_sig)
    y[names.index("A")] *= prob.area / old["area"]
    y[names.index("Omega")] *= prob.volume / old["volume"]
    params = np.array([params[0] * f_q, params[1] * f_len])
    return model, t, y, params


# --------------------------------------------------------------------------- 4. high-Ca problem
class _OutOfTime(Exception):
    """Raised inside solve_bvp's right-hand side once the deadline is spent; caught by
    :func:`_attempt`, which returns an unconverged attempt (never leaves this module)."""


def _solve_scaled(fun, bc, t, y, params, scales, prob):
    """solve_bvp on the unknowns divided by ``scales`` (an (n, 1) array); returns unscaled.

    The deadline of ``prob`` is tested at every evaluation of the right-hand side (many per
    Newton iteration), so a spent budget stops even a long solve_bvp call within one of them.
    """
    expired = prob.deadline.expired

    def scaled_fun(t_, yh, p):
        if expired():
            raise _OutOfTime
        return fun(t_, yh * scales, p) / scales

    def scaled_bc(ya, yb, p):
        return bc(ya * scales[:, 0], yb * scales[:, 0], p)

    sol = solve_bvp(scaled_fun, scaled_bc, t, y / scales, p=params, tol=prob.tol,
                    max_nodes=prob.max_nodes, bc_tol=prob.tol)
    sol.scales = scales          # sol.y and sol.sol are in scaled units
    return sol, sol.y * scales


def _high_ca_scales(y, prob):
    sig = float(np.max(np.abs(y[3])))
    return np.array([1.0, 1.0, sig, sig, prob.area, prob.volume])[:, None]


def _bc_high_ca(prob):
    eps = CAP_RADIUS

    def bc(ya, yb, params):
        # cap curvature from the normal balance p = -2 sigma k of a sphere
        th_r, area_r, vol_r = spherical_cap(-ya[2] / (2.0 * ya[3]), eps)
        th_f, area_f, vol_f = spherical_cap(-yb[2] / (2.0 * yb[3]), eps)
        return np.array([ya[0] - eps, ya[1] + 0.5 * math.pi - th_r,
                         (ya[4] - area_r) / prob.area, (ya[5] - vol_r) / prob.volume,
                         yb[0] - eps, yb[1] - 0.5 * math.pi + th_f,
                         (yb[4] + area_f) / prob.area - 1.0, (yb[5] + vol_f) / prob.volume - 1.0])
    return bc


def _solve_high_ca(prob, t, y, params):
    shear = prob.shear

    def fun(t_, y_, p):
        return rhs_high_ca(t_, y_, p, shear)

    scales = _high_ca_scales(y, prob)
    return _solve_scaled(fun, _bc_high_ca(prob), t, y, params, scales, prob)


# --------------------------------------------------------------------------- 5. bending problem
def _bending_from_high_ca(prob, t, y, params, ca_b):
    """Bending unknowns from a high-Ca solution: p, sigma times Ca, c_s from the normal balance."""
    r, psi, p, sigma, A, Omega = y
    ca = capillary_number(ca_b, prob.lam, params[0])
    c_s = p / sigma + np.cos(psi) / r
    q_s = np.zeros_like(r)
    return np.vstack((r, psi, c_s, q_s, ca * p, ca * sigma, A, Omega))


def _bending_scales(y, prob):
    sig = float(np.max(np.abs(y[5])))
    return np.array([1.0, 1.0, 1.0, math.sqrt(sig), sig, sig, prob.area, prob.volume])[:, None]


def _bc_bending(prob, q_scale):
    eps = CAP_RADIUS

    def bc(ya, yb, params):
        r0, psi0, c0, q0, p0, s0, a0, v0 = ya
        r1, psi1, c1, q1, p1, s1, a1, v1 = yb
        th_r, area_r, vol_r = spherical_cap(-c0, eps)
        th_f, area_f, vol_f = spherical_cap(-c1, eps)
        # regular expansion at a pole: q_s = +-(p - 2 sigma c_s) s/2 (rear +, front -)
        return np.array([r0 - eps, psi0 + 0.5 * math.pi - th_r,
                         (q0 - 0.5 * eps * (p0 - 2.0 * s0 * c0)) / q_scale,
                         (a0 - area_r) / prob.area, (v0 - vol_r) / prob.volume,
                         r1 - eps, psi1 - 0.5 * math.pi + th_f,
                         (q1 + 0.5 * eps * (p1 - 2.0 * s1 * c1)) / q_scale,
                         (a1 + area_f) / prob.area - 1.0, (v1 + vol_f) / prob.volume - 1.0])
    return bc


def _solve_bending(prob, t, y, params):
    shear = prob.shear

    def fun(t_, y_, p):
        return rhs_bending(t_, y_, p, prob.ca_b, prob.lam, shear)

    scales = _bending_scales(y, prob)
    return _solve_scaled(fun, _bc_bending(prob, scales[3, 0]), t, y, params, scales, prob)


# --------------------------------------------------------------------------- 6. acceptance
def _simpson_cumulative(f, t, f_mid):
    """Cumulative integral of a function with values f at nodes t and f_mid at midpoints."""
    h = np.diff(t)
    return np.concatenate(([0.0], np.cumsum(h * (f[:-1] + 4.0 * f_mid + f[1:]) / 6.0)))


def _gauss_integral(f_of_t, t):
    """Integral over [t0, t_end] of a function of t by 5-point Gauss-Legendre on each interval."""
    x, w = np.polynomial.legendre.leggauss(5)
    h = np.diff(t)
    tq = (t[:-1, None] + 0.5 * h[:, None] * (x[None, :] + 1.0)).ravel()
    return float(np.sum(f_of_t(tq).reshape(len(h), 5) * (0.5 * h[:, None] * w[None, :])))


def _self_intersects(x, r) -> bool:
    """Whether the meridian polyline (x, r) crosses itself (two non-adjacent segments cross).

    Only segments whose axial extents overlap are compared (sorted by their left end), so a
    meridian that is monotonic in x except near a parachute's rim costs O(n log n).
    """
    p0, p1 = np.column_stack((x[:-1], r[:-1])), np.column_stack((x[1:], r[1:]))
    lo, hi = np.minimum(p0[:, 0], p1[:, 0]), np.maximum(p0[:, 0], p1[:, 0])
    order = np.argsort(lo, kind="stable")

    def side(a, b, c):       # sign of the turn a -> b -> c
        return ((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
                - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))

    for i in range(len(p0)):
        j = order[:np.searchsorted(lo[order], hi[i], side="right")]
        j = j[(j > i + 1) & (hi[j] >= lo[i])]
        if j.size and np.any((side(p0[i], p1[i], p0[j]) * side(p0[i], p1[i], p1[j]) < 0)
                             & (side(p0[j], p1[j], p0[i]) * side(p0[j], p1[j], p1[i]) < 0)):
            return True
    return False


def _diagnose(prob, model, sol, y):
    """Quadrature checks of a solve_bvp solution: constraints, force balance, tension sign."""
    t, params = sol.x, sol.p
    Q, S = params
    names = HIGH_CA_STATE if model == "high-Ca" else BENDING_STATE
    ix = {n: i for i, n in enumerate(names)}
    t_mid = 0.5 * (t[:-1] + t[1:])
    y_mid = sol.sol(t_mid) * sol.scales
    # Caps: spherical with the rim curvature of the solution
    if model == "high-Ca":
        k_r = -y[ix["p"], 0] / (2.0 * y[ix["sigma"], 0])
        k_f = -y[ix["p"], -1] / (2.0 * y[ix["sigma"], -1])
    else:
        k_r, k_f = -y[ix["c_s"], 0], -y[ix["c_s"], -1]
    _, a_r, v_r = spherical_cap(k_r, CAP_RADIUS)
    _, a_f, v_f = spherical_cap(k_f, CAP_RADIUS)
    r, psi, p = y[ix["r"]], y[ix["psi"]], y[ix["p"]]
    r_m, psi_m, p_m = y_mid[ix["r"]], y_mid[ix["psi"]], y_mid[ix["p"]]
    # Area and volume from the shape r(t), psi(t) of the collocation polynomial by a quadrature
    # rule other than the collocation's (Simpson), not from the A and Omega unknowns.
    i_r, i_psi = ix["r"], ix["psi"]
    sc_r, sc_psi = sol.scales[i_r, 0], sol.scales[i_psi, 0]

    def shape(tq):
        yq = sol.sol(tq)
        return yq[i_r] * sc_r, yq[i_psi] * sc_psi

    area = a_r + a_f + _gauss_integral(lambda tq: 2 * math.pi * S * shape(tq)[0], t)
    volume = v_r + v_f + _gauss_integral(
        lambda tq: math.pi * S * shape(tq)[0] ** 2 * np.cos(shape(tq)[1]), t)
    # Net axial force on the vesicle: shear e_m cos(psi) and pressure -p sin(psi) on the body,
    # pressure on the projected area of each cap (uniform there); the units cancel in the ratio.
    ca = 1.0 if model == "high-Ca" else capillary_number(prob.ca_b, prob.lam, Q)
    e_m = gap_flow(np.clip(r, 1e-12, 1 - 1e-15), Q)[1]
    e_m_mid = gap_flow(np.clip(r_m, 1e-12, 1 - 1e-15), Q)[1]
    shear = _simpson_cumulative(2 * math.pi * S * r * ca * e_m * np.cos(psi), t,
                                2 * math.pi * S * r_m * ca * e_m_mid * np.cos(psi_m))[-1]
    press_f = _simpson_cumulative(-2 * math.pi * S * r * p * np.sin(psi), t,
                                  -2 * math.pi * S * r_m * p_m * np.sin(psi_m))[-1]
    caps = math.pi * CAP_RADIUS**2 * (p[0] - p[-1])
    scale = _simpson_cumulative(2 * math.pi * S * r * np.abs(p * np.sin(psi)), t,
                                2 * math.pi * S * r_m * np.abs(p_m * np.sin(psi_m)))[-1]
    force = (shear + press_f + caps) / scale
    stretch_sq, crossed = (1.0, 1.0), False
    if prob.shear is not None:      # unclipped lam_phi^2 = r^2 / r_ref^2(A) over the mesh
        raw = r * r / prob.shear.reference.radius_squared(y[ix["A"]], prob.area)
        stretch_sq = (float(np.min(raw)), float(np.max(raw)))
        # a red cell's membrane can fold at its rear rim, where the hoop tension turns
        # compressive: the meridian must not cross itself (the caps are too small to matter)
        x_body = _simpson_cumulative(S * np.cos(psi), t, S * np.cos(psi_m))
        crossed = _self_intersects(x_body, r)
    return dict(area_error=abs(area / prob.area - 1.0),
                volume_error=abs(volume / prob.volume - 1.0),
                force_balance_residual=abs(force), max_residual=float(np.max(sol.rms_residuals)),
                n_nodes=len(t), bvp_status=int(sol.status), bvp_message=sol.message,
                min_tension=float(np.min(y[ix["sigma"]])), front_tension=float(y[ix["sigma"], -1]),
                k_rear=float(k_r), k_front=float(k_f), stretch_sq=stretch_sq,
                self_intersects=crossed)


def _verdict(prob, model, diag):
    """(Status, message) from the diagnostics: CONVERGED, or NOT_CONVERGED with every failed
    check; the status flag of solve_bvp is only reported."""
    # A mesh that ran out of nodes may still hold a converged solution: accept residuals up to
    # 10 tol then, provided the constraints and force balance also pass.
    res_limit = prob.tol if diag["bvp_status"] == 0 else 10.0 * prob.tol
    problems = []
    if not np.isfinite(diag["max_residual"]) or diag["max_residual"] > res_limit:
        problems.append(f"collocation residual {diag['max_residual']:.2e} > {res_limit:.1e} "
                        f"(solve_bvp: {diag['bvp_message']})")
    if not diag["area_error"] <= CONSTRAINT_TOL or not diag["volume_error"] <= CONSTRAINT_TOL:
        problems.append(f"area error {diag['area_error']:.1e}, volume error "
                        f"{diag['volume_error']:.1e} (limit {CONSTRAINT_TOL:.0e})")
    if not diag["force_balance_residual"] <= FORCE_TOL:
        problems.append(f"net axial force {diag['force_balance_residual']:.1e} of the pressure "
                        f"force (limit {FORCE_TOL:.0e})")
    if model == "high-Ca" and not diag["min_tension"] > 0.0:
        problems.append(f"tension {diag['min_tension']:.3g} <= 0 somewhere: the high-Ca model "
                        "has no solution there (or the solver found its unphysical branch)")
    if model == "bending" and not diag["front_tension"] > 0.0:
        problems.append(f"front tension {diag['front_tension']:.3g} <= 0: unphysical branch")
    lo, hi = diag["stretch_sq"]
    if not (STRETCH_SQ_GUARD[0] < lo and hi < STRETCH_SQ_GUARD[1]):
        problems.append(f"azimuthal stretch squared {lo:.3g}-{hi:.3g} reaches the guard "
                        f"{STRETCH_SQ_GUARD} of the material map")
    if problems:
        return Status.NOT_CONVERGED, "not converged: " + "; ".join(problems)
    if diag["self_intersects"]:
        return Status.NO_STEADY_STATE, ("no steady shape: the membrane self-intersects (a fold "
                                        "of the meridian crosses itself; collocation converged)")
    return Status.CONVERGED, (f"converged: residual {diag['max_residual']:.1e}, "
                              f"{diag['n_nodes']} nodes, area/volume errors "
                              f"{diag['area_error']:.1e}/{diag['volume_error']:.1e}, "
                              f"force balance {diag['force_balance_residual']:.1e}")


# --------------------------------------------------------------------------- 7. result
def _cap_extent(k, eps):
    """Arc length and axial height (pole to rim, signed) of a spherical cap of curvature k."""
    theta, _, _ = spherical_cap(k, eps)
    theta, k = float(theta), float(k)
    if abs(k) * eps < 1e-8:                      # flat cap: arc eps, height k eps^2/2
        return eps, 0.5 * k * eps * eps
    return theta / k, (1.0 - math.cos(theta)) / k


def _failed(prob, status, message, diag, timings, state=None):
    """LubricationResult of a failed solve: ``status``, the reason, no physical numbers."""
    keep = {k: diag[k] for k in ("force_balance_residual", "area_error", "volume_error",
                                 "n_nodes", "max_residual") if k in diag}
    return LubricationResult(nu=prob.nu, lam=prob.lam, lam_c=prob.lam_c, ca_b=prob.ca_b,
                             model=prob.model, status=status, message=message, tol=prob.tol,
                             timings=timings, provenance=provenance(), solver_state=state,
                             **_membrane_inputs(prob), **keep)


def _membrane_inputs(prob):
    """ca_s and reference of a result: the reference only for a red-cell membrane."""
    return dict(ca_s=prob.ca_s, reference=None if prob.shear is None else prob.reference)


def _result(prob, model, sol, y, diag, message, timings):
    """LubricationResult in project units from a converged solution (model units)."""
    names = HIGH_CA_STATE if model == "high-Ca" else BENDING_STATE
    ix = {n: i for i, n in enumerate(names)}
    t = sol.x
    Q, S = (float(v) for v in sol.p)
    # model pressure and tension units -> eta V / R and eta V
    ca = 1.0 if model == "high-Ca" else capillary_number(prob.ca_b, prob.lam, Q)
    r, psi = y[ix["r"]], y[ix["psi"]]
    p_v, sigma_v = y[ix["p"]] / ca, y[ix["sigma"]] / ca
    # curvature at the poles (negative = convex), from the spherical caps
    if model == "high-Ca":
        c_rear, c_front = p_v[0] / (2 * sigma_v[0]), p_v[-1] / (2 * sigma_v[-1])
    else:
        c_rear, c_front = y[ix["c_s"], 0], y[ix["c_s"], -1]
    arc_r, height_r = _cap_extent(-c_rear, CAP_RADIUS)
    arc_f, height_f = _cap_extent(-c_front, CAP_RADIUS)
    # axial position by Simpson on the collocation cubic, from the rear pole
    psi_mid = sol.sol(0.5 * (t[:-1] + t[1:]))[ix["psi"]] * sol.scales[ix["psi"], 0]
    x_body = height_r + _simpson_cumulative(S * np.cos(psi), t, S * np.cos(psi_mid))
    s = np.concatenate(([0.0], arc_r + S * t, [arc_r + S + arc_f]))
    x = np.concatenate(([0.0], x_body, [x_body[-1] + height_f]))
    x -= x.min()
    length = float(x.max())
    _, e_m, e_w = gap_flow(r, Q)
    # Outputs in U units: V/U = 1/(1 - Q) converts eta V to eta U
    to_u = 1.0 / (1.0 - Q)
    delta_p = p_v[0] - p_v[-1]                                      # eta V / R
    dp_plus_v = delta_p - 8.0 * (1.0 - Q) * length                  # dp+ R/(eta V)
    zero = np.array([0.0])    # shear in the excised caps is neglected by the cap model
    pressure = to_u * np.concatenate((p_v[:1], p_v, p_v[-1:]))
    # principal tensions: sigma_v is tau_s for a red-cell membrane; tau_s - tau_phi = 2 G_s f
    if prob.shear is None:
        diff_v, stretch = np.zeros_like(sigma_v), np.full(len(sigma_v) + 2, math.nan)
    else:
        lam_phi = np.sqrt(prob.shear.stretch_squared(r, y[ix["A"]]))
        diff_v = 2.0 * shear_modulus(prob.ca_s, Q) * tension_difference(lam_phi)
        stretch = np.concatenate(([1.0], lam_phi, [1.0]))     # isotropic at the poles
    mean_v = sigma_v - 0.5 * diff_v
    tension = to_u * np.concatenate((mean_v[:1], mean_v, mean_v[-1:]))
    half = to_u * np.concatenate((zero, 0.5 * diff_v, zero))
    return LubricationResult(
        nu=prob.nu, lam=prob.lam, lam_c=prob.lam_c, ca_b=prob.ca_b, model=model,
        status=Status.CONVERGED, message=message,
        V_over_U=to_u, Q=Q, dp_plus_R0=dp_plus_v * prob.lam * to_u, dp_plus_R=dp_plus_v * to_u,
        ell=length, film_min=float(np.min(1.0 - r)),
        tension_front=float(tension[-1]), tension_rear=float(tension[0]),
        tension_max=float(tension.max()),
        curvature_rear=float(c_rear), curvature_front=float(c_front),
        # concave rear: the pole curvature is concave, or (deep parachutes, whose cavity floor
        # is convex again) the rear pole lies ahead of the rearmost point of the membrane
        shape_class="parachute" if (c_rear > 0 or x[0] > CAP_RADIUS**2) else "bullet",
        s=s, x=x, r=np.concatenate((zero, r, zero)),
        psi=np.concatenate(([-0.5 * math.pi], psi, [0.5 * math.pi])),
        pressure=pressure, tension=tension, tension_s=tension + half,
        tension_phi=tension - half, stretch_phi=stretch, **_membrane_inputs(prob),
        shear_membrane=to_u * np.concatenate((zero, e_m, zero)),
        shear_wall=to_u * np.concatenate((zero, e_w, zero)),
        force_balance_residual=diag["force_balance_residual"], area_error=diag["area_error"],
        volume_error=diag["volume_error"], n_nodes=diag["n_nodes"],
        max_residual=diag["max_residual"], tol=prob.tol, timings=timings,
        provenance=provenance(),
        solver_state=(model, t, y, sol.p.copy(),
                      dict(delta=prob.delta, area=prob.area, volume=prob.volume,
                           ca=ca, ca_s=prob.ca_s)))


# --------------------------------------------------------------------------- 8. driver
def _attempt(prob, model, guess):
    """One solve_bvp run from a guess (t, y, params): (sol, y, diag, status, message)."""
    t, y, params = guess
    solver = _solve_high_ca if model == "high-Ca" else _solve_bending
    if prob.deadline.expired():
        return None, None, {}, Status.TIME_LIMIT, prob.deadline.message()
    with np.errstate(all="ignore"):        # iterates may leave the domain; judged below
        try:
            sol, y_sol = solver(prob, t, y, params)
            diag = _diagnose(prob, model, sol, y_sol)
        except _OutOfTime:
            return None, None, {}, Status.TIME_LIMIT, prob.deadline.message()
        except (ValueError, np.linalg.LinAlgError, ArithmeticError) as exc:
            return (None, None, {}, Status.NOT_CONVERGED,
                    f"not converged: solve_bvp failed ({exc})")
    status, message = _verdict(prob, model, diag)
    return sol, y_sol, diag, status, message


def _bending_by_ca_continuation(prob, sol, y):
    """Bending solution from a high-Ca one: jump to Ca_B, else come down from Ca_B = 1e4.

    At Ca_B = 1e4 bending is a small perturbation wherever the high-Ca model has a solution;
    steps of a factor 3 in Ca_B then reach the target.
    """
    ca_start, factor = 1e4, 3.0
    n_steps = max(1, math.ceil(math.log(max(ca_start / prob.ca_b, 1.0)) / math.log(factor)))
    paths = ([prob.ca_b], list(np.geomspace(max(ca_start, prob.ca_b), prob.ca_b, n_steps + 1)))
    for path in paths:
        t, y_k, params = sol.x, y, sol.p
        for k, ca_b in enumerate(path):
            step = replace(prob, ca_b=float(ca_b))
            if k == 0:
                y_k = _bending_from_high_ca(step, t, y_k, params, float(ca_b))
            else:      # at fixed eta V the bending-unit p, sigma scale like Ca, q_s like Ca^(1/2)
                y_k = y_k.copy()
                y_k[4:6] *= path[k] / path[k - 1]
                y_k[3] *= math.sqrt(path[k] / path[k - 1])
            b_sol, b_y, diag, status, message = _attempt(step, "bending", (t, y_k, params))
            if status is not Status.CONVERGED:
                logger.debug("bending at Ca_B=%g on the path %s failed: %s", ca_b, path, message)
                break
            if prob.deadline.expired():
                status, message = Status.TIME_LIMIT, prob.deadline.message()
                break
            t, y_k, params = b_sol.x, b_y, b_sol.p
        if status is Status.CONVERGED:
            return b_sol, b_y, diag, status, message
        if prob.deadline.expired():
            return None, None, diag, Status.TIME_LIMIT, prob.deadline.message()
    return None, None, diag, status, message


def _shear_by_ca_s_continuation(prob, t, y, params):
    """Red-cell solution from a vesicle solution or guess (t, y, params) of the same model.

    A direct jump to Ca_S first; else continuation in Ca_S from ``CA_S_START`` (where the
    elastic tensions are ~1e-3 eta U, a small perturbation of the vesicle) down to Ca_S by
    factors that grow by 1.5 after a success (at most ``CA_S_MAX_FACTOR``) and shrink to their
    square root after a failure, until the factor falls below ``CA_S_MIN_FACTOR``. At fixed
    eta V the unknowns need no rescaling between steps: only G_s changes.
    """
    CA_S_START = 1e3
    CA_S_MAX_FACTOR, CA_S_MIN_FACTOR = 10.0, 1.05
    model = prob.model
    result = _attempt(prob, model, (t, y, params))
    if result[3] is Status.CONVERGED or prob.deadline.expired():
        return result
    ca_s, factor = math.inf, 3.0
    while True:
        nxt = max(prob.ca_s, min(CA_S_START, ca_s / factor))
        step = replace(prob, ca_s=nxt)
        result = _attempt(step, model, (t, y, params))
        if prob.deadline.expired():
            return (*result[:3], Status.TIME_LIMIT, prob.deadline.message())
        if result[3] is Status.CONVERGED:
            if nxt == prob.ca_s:
                return result
            ca_s, factor = nxt, min(CA_S_MAX_FACTOR, 1.5 * factor)
            t, y, params = result[0].x, result[1], result[0].p
            continue
        logger.debug("shear continuation to Ca_S=%g failed: %s", nxt, result[4])
        factor = math.sqrt(factor) if math.isfinite(ca_s) else factor
        if factor < CA_S_MIN_FACTOR or not math.isfinite(ca_s):
            where = "from the vesicle" if not math.isfinite(ca_s) else f"at Ca_S = {ca_s:.4g}"
            return (*result[:3], Status.NOT_CONVERGED,
                    f"continuation in Ca_S stuck {where} on the way to {prob.ca_s:.4g}: "
                    f"{result[4]}")


def _point(prob: _Problem, initial: LubricationResult | None, cold: bool) -> LubricationResult:
    """Solve one (nu, lam, Ca_B, Ca_S) from a warm start and/or the spherocylinder.

    A warm start of the same model is tried first (a vesicle's, for a red cell, by
    continuation in Ca_S). Otherwise the vesicle (no shear elasticity) is solved, high-Ca then
    bending by continuation in Ca, and a red-cell membrane is reached from it by continuation
    in Ca_S (:func:`_shear_by_ca_s_continuation`).
    """
    clock = time.perf_counter()
    timings = {}
    state = initial.solver_state if initial is not None and initial.success else None
    status, diag = Status.NOT_CONVERGED, {}
    message = "no initial guess (no warm start, cold start not allowed)"
    # 1) same-model warm start
    if state is not None and state[0] == prob.model:
        guess = _rescaled_guess(prob, state)[1:]
        if prob.shear is not None and math.isinf(state[4]["ca_s"]):
            sol, y, diag, status, message = _shear_by_ca_s_continuation(prob, *guess)
        else:
            sol, y, diag, status, message = _attempt(prob, prob.model, guess)
        if status is Status.CONVERGED:
            timings["total"] = time.perf_counter() - clock
            return _result(prob, prob.model, sol, y, diag, "warm start " + message, timings)
        if prob.deadline.expired():
            timings["total"] = time.perf_counter() - clock
            return _failed(prob, Status.TIME_LIMIT, prob.deadline.message(), diag, timings)
        message = "warm start " + message
        logger.debug("warm start failed: %s", message)
    # 2) high-Ca vesicle from a high-Ca warm start, else from the spherocylinder
    vesicle = replace(prob, ca_s=math.inf)
    high = replace(vesicle, ca_b=math.inf)
    guesses = []
    if state is not None and state[0] == "high-Ca" and prob.model == "bending":
        guesses.append(_rescaled_guess(high, state)[1:])
    if cold:
        guesses.append(_spherocylinder_guess(high))
    for guess in guesses:
        sol, y, diag, status, message = _attempt(high, "high-Ca", guess)
        if status is Status.CONVERGED or prob.deadline.expired():
            break
    timings["high_ca"] = time.perf_counter() - clock
    if status is Status.CONVERGED and prob.model == "bending":
        sol, y, diag, status, message = _bending_by_ca_continuation(vesicle, sol, y)
        timings["bending"] = time.perf_counter() - clock - timings["high_ca"]
    if status is Status.CONVERGED and prob.shear is not None:
        lap = time.perf_counter()
        sol, y, diag, status, message = _shear_by_ca_s_continuation(prob, sol.x, y, sol.p)
        timings["shear"] = time.perf_counter() - lap
    timings["total"] = time.perf_counter() - clock
    if status is not Status.CONVERGED:
        logger.info("nu=%.4g lam/lam_c=%.6g %s: %s", prob.nu, prob.lam / prob.lam_c, prob.model,
                    message)
        return _failed(prob, status, message, diag, timings)
    return _result(prob, prob.model, sol, y, diag, message, timings)


def _march(prob: _Problem, start: LubricationResult, ratio: float, max_step: float):
    """Continuation in lam/lam_c from the converged ``start`` to ``ratio`` (warm starts only).

    Each step is at most ``max_step`` and at most half the current clearance delta (delta at
    most halves or grows by half per step: tension scales like delta^(-3/2)); the step grows by
    1.5 after a success and halves after a failure, down to ``min_step``. Returns the result at
    ``ratio``, status NOT_CONVERGED if the continuation got stuck (a fold or the end of the
    branch), TIME_LIMIT if ``max_time`` ran out.
    """
    min_step = MIN_STEP    # below this the branch is taken to end (or fold) here
    current, step = start, max_step
    clock = time.perf_counter()
    for _ in range(MAX_CONTINUATION_STEPS):
        here = current.lam / current.lam_c
        gap = ratio - here
        if abs(gap) <= 1e-12 * ratio:
            return current
        if prob.deadline.expired():
            return _failed(prob, Status.TIME_LIMIT,
                           f"{prob.deadline.message()} (the continuation in lam/lam_c "
                                 f"had reached {here:.6g} on the way to {ratio:.6g})", {},
                           {"total": time.perf_counter() - clock})
        limit = min(step, 0.5 * (1.0 - here))
        nxt = ratio if abs(gap) <= limit else here + math.copysign(limit, gap)
        # A warm step that needs many more nodes than its start has diverged: cap its mesh.
        nodes = min(prob.max_nodes, max(5000, 3 * current.n_nodes))
        trial = _point(replace(prob, lam=nxt * prob.lam_c, max_nodes=nodes), current, cold=False)
        if trial.success:
            current, step = trial, min(max_step, 1.5 * step)
            continue
        step = 0.5 * min(step, abs(gap))
        if step < min_step:
            return _failed(prob, Status.NOT_CONVERGED,
                           f"continuation in lam/lam_c stuck at {here:.6g} on the way to "
                                 f"{ratio:.6g} (step < {min_step:g}): the branch ends or folds "
                                 f"(last converged point: curvature_rear="
                                 f"{current.curvature_rear:.3g}/R, tension_rear="
                                 f"{current.tension_rear:.3g} eta U); last attempt: "
                                 f"{trial.message}", {},
                           {"total": time.perf_counter() - clock})
    return _failed(prob, Status.NOT_CONVERGED,
                   f"continuation in lam/lam_c stopped after {MAX_CONTINUATION_STEPS} "
                         f"steps at {current.lam / current.lam_c:.6g} on the way to {ratio:.6g}",
                   {}, {"total": time.perf_counter() - clock})


# Cold starts (the spherocylinder) converge near critical confinement; below ANCHOR_RATIO a
# point that fails cold is reached by continuation from a cold solution at ANCHOR_RATIO.
ANCHOR_RATIO = 0.98
MAX_STEP = 0.02


def solve_lubrication(nu, lam=None, *, lam_ratio=None, ca_b=math.inf, ca_s=None,
                      reference="biconcave", initial=None, tol=1e-7, max_nodes=20_000,
                      max_time=None) -> LubricationResult:
    r"""Steady shape, speed, extra pressure drop and tension of a vesicle in a tube (lubrication).

    Solves the parallel-flow lubrication model of Secomb et al. (1986) in the form of Barakat &
    Shaqfeh (2018b): high-Ca (tension only, ``ca_b=inf``) or with Helfrich bending (finite
    ``ca_b``); a vesicle (``ca_s=None``), or a red cell whose membrane also resists in-plane
    shear relative to a stress-free ``reference`` shape (finite ``ca_s``, Secomb et al. 1986;
    :mod:`lubrication.membrane`). See the module docstring for the method, the acceptance
    checks and the resource envelope. Without ``initial``, the spherocylinder guess is tried
    first; if it fails below ``lam_ratio = ANCHOR_RATIO`` the point is reached by continuation
    from ``ANCHOR_RATIO``.

    Parameters
    ----------
    nu : float
        Reduced volume, 0.3 <= nu < 1 [-] (:data:`NU_RANGE`).
    lam : float, optional
        Confinement R0/R, lowest_lam_ratio(nu, ca_b) lam_c <= lam < lam_c(nu) [-]. Give exactly
        one of ``lam``, ``lam_ratio``.
    lam_ratio : float, optional
        lam / lam_c, :func:`lowest_lam_ratio` <= lam_ratio < 1 [-]: at least
        :data:`MIN_LAM_RATIO` = 0.1, and for the high-Ca model at least the end of its branch
        (:func:`high_ca_branch_end`: 0.954, 0.908, 0.838, 0.738, 0.597, 0.345 at nu = 0.5, 0.6,
        0.7, 0.8, 0.9, 0.98).
    ca_b : float
        Bending capillary number eta U R0^2 / kappa, 1e-2 <= ca_b <= 1e5 [-]
        (:data:`CA_B_RANGE`); ``math.inf`` (default) for the high-Ca model.
    ca_s : float, optional
        Shear capillary number eta U / G_s of a red-cell membrane, :data:`CA_S_RANGE` [-]
        (U the mean velocity, G_s the shear modulus: 0.2 for U = 1 mm/s, eta = 1.2 mPa s,
        G_s = 6 µN/m). None (default) or ``math.inf``: a vesicle, the same computation as
        without this argument.
    reference : str
        Stress-free shape of the red-cell membrane: "biconcave" (default; the Evans-Fung disc
        made to the cell's reduced volume, 0.45 <= nu <= 0.743) or "spheroid" (oblate,
        0.45 <= nu < 1), its axis along the tube (:func:`lubrication.membrane.reference_shape`).
        Checked, and ignored for a vesicle.
    initial : LubricationResult, optional
        A converged solution to start from (warm start), preferably at the same nu and a nearby
        lam; it is rescaled to the new clearance. If it fails, the cold start is tried.
    tol : float
        Relative collocation tolerance of :func:`scipy.integrate.solve_bvp`, 1e-12 to 1e-3.
    max_nodes : int
        Largest mesh, 100 <= max_nodes <= :data:`MAX_NODES`.
    max_time : float, optional
        Wall-time budget [s], > 0; None (default): no limit. When it is spent the solve stops
        (within one evaluation of the right-hand side) and returns status TIME_LIMIT with the
        reason in ``message``; it never raises for it.

    Returns
    -------
    LubricationResult
        ``status`` NOT_CONVERGED (no solution passed the acceptance checks) or TIME_LIMIT
        (the time ran out), NaN outputs and the reason in ``message`` when it failed.

    Notes
    -----
    Red-cell membrane: the meridional tension replaces the tension as unknown (
    :func:`lubrication.equations.rhs_high_ca`); the polar caps stay isotropic (the
    deviatoric tension vanishes like r^2 at a pole, module :mod:`lubrication.membrane`), so
    their boundary conditions neglect a relative O(CAP_RADIUS^2) difference of the principal
    tensions at the rims. Below the measured end of the high-Ca vesicle branch the high-Ca
    red cell is refused like the vesicle (its own branch end was not measured). Where the hoop
    tension turns compressive (a disc squeezed into a narrow tube, at its rear rim) and bending
    is weak, the meridian folds; a solution whose meridian crosses itself is returned with
    status NO_STEADY_STATE. Measured for the default red cell in a 5 µm tube (G_s = 6 µN/m,
    kappa = 1.8e-19 J; tests/benchmarks/rbc_shear_lubrication.py): fold-free solutions from 0.1
    to 1.12 mm/s, reached from the vesicle at lam/lam_c = 0.72 and 0.4 mm/s; above, the rear
    rim folds over.

    Range (measured, tol = 1e-7): every nu in [0.6, 0.98] converges up to lam/lam_c = 0.9999 in
    both models. The high-Ca branch ends where the rear pole flattens: lowest lam/lam_c = 0.909,
    0.838, 0.738, 0.597, 0.346 for nu = 0.6, 0.7, 0.8, 0.9, 0.98 (:data:`HIGH_CA_BRANCH_END`).
    Below it the high-Ca model has no solution at all, whatever the solver: that is a limit of
    the model, known before any work, so such input raises :class:`InvalidParameterError`
    (exit 2 on the command line, with the advice to give a finite ``ca_b``) instead of failing
    after a 20 s continuation. Within ~1e-3 above the tabulated end the continuation may still
    stop: that is a solver failure, returned as status NOT_CONVERGED. With Ca_B = 50 the bending
    model continues into parachutes down to 0.704, 0.539, < 0.1, 0.209, 0.204 (a single-point
    continuation from 0.98 at nu = 0.8 stopped at 0.177 after 135 s: the bending range depends on
    the path); there a failure is a solver limit, not known in advance, and is returned, not
    raised. The parallel-flow
    approximation needs a long vesicle with small slopes; for short vesicles it is qualitative
    only, and it gives dp+ < 0 (unphysical) below lam/lam_c ~ 0.45 at nu = 0.9.

    Raises
    ------
    InvalidParameterError
        Bad input (nu outside NU_RANGE, ca_b outside CA_B_RANGE, NaN, lam/lam_c below the
        model's lowest, max_time <= 0, ...); the message names the parameter and its range.
    CannotPassError
        lam >= lam_c(nu).

    Examples
    --------
    >>> res = solve_lubrication(0.9, lam_ratio=0.99)
    >>> res.success, round(res.V_over_U, 4), res.shape_class
    (True, 1.0096, 'bullet')
    """
    prob = _check_inputs(nu, lam, lam_ratio, ca_b, tol, max_nodes, max_time, ca_s, reference)
    if initial is not None and not isinstance(initial, LubricationResult):
        raise InvalidParameterError("initial", type(initial).__name__,
                                    "a LubricationResult or None")
    return _solve_point(prob, initial)


def _solve_point(prob: _Problem, initial) -> LubricationResult:
    """:func:`solve_lubrication` on checked inputs (the deadline is that of ``prob``)."""
    clock = time.perf_counter()
    ratio = prob.lam / prob.lam_c
    # Away from critical a cold start that needs more nodes than this has diverged (converged
    # cold solutions there use < 5000 at tol = 1e-7): fail early and continue from the anchor.
    cold_nodes = prob.max_nodes if ratio >= ANCHOR_RATIO or initial is not None else 8000
    result = _point(replace(prob, max_nodes=min(prob.max_nodes, cold_nodes)), initial, cold=True)
    if (not result.success and ratio < ANCHOR_RATIO and prob.deadline.expired()
            and result.status is not Status.TIME_LIMIT):
        # the cold start failed on its own and the budget ran out meanwhile: the continuation
        # that could have reached the point was not tried, which the reason must say
        result = replace(result, status=Status.TIME_LIMIT,
                         message=f"{result.message}; the continuation from lam/lam_c = "
                                 f"{ANCHOR_RATIO:g} was not tried: {prob.deadline.message()}")
    elif not result.success and ratio < ANCHOR_RATIO and not prob.deadline.expired():
        logger.info("nu=%.4g lam/lam_c=%.6g: cold start failed, continuing from %g",
                    prob.nu, ratio, ANCHOR_RATIO)
        anchor = _point(replace(prob, lam=ANCHOR_RATIO * prob.lam_c), None, cold=True)
        if anchor.success:
            result = _march(prob, anchor, ratio, MAX_STEP)
        elif prob.deadline.expired():
            result = _failed(prob, anchor.status, anchor.message, {}, anchor.timings)
    timings = dict(result.timings, total=time.perf_counter() - clock)
    return replace(result, timings=timings)


def sweep_lubrication(nu, lam_ratios, ca_b=math.inf, progress=True, *, ca_s=None,
                      reference="biconcave", tol=1e-7, max_nodes=20_000, max_step=MAX_STEP,
                      max_time=None) -> list[LubricationResult]:
    r"""Solve a list of confinements by warm-started continuation in lam/lam_c.

    The sweep starts from a cold solution at the requested ratio nearest to ``ANCHOR_RATIO``
    (near critical confinement, where the spherocylinder guess converges; for finite ``ca_b``
    via continuation in Ca from the high-Ca solution), then continues upward to the larger
    ratios and downward to the smaller ones, each point warm-started from its neighbour, with
    intermediate steps inserted where a step would exceed ``max_step`` or half the clearance.
    Once a point fails, the points beyond it in the same direction are reported as failed.

    Parameters
    ----------
    nu : float
        Reduced volume, 0.3 <= nu < 1 [-].
    lam_ratios : array_like
        lam / lam_c values, each in [lowest_lam_ratio(nu, ca_b), 1) [-], any order; at most
        :data:`MAX_SWEEP_POINTS` of them.
    ca_b : float
        Bending capillary number eta U R0^2/kappa [-]; ``math.inf`` for the high-Ca model.
    progress : bool
        Show a tqdm progress bar (on stderr).
    ca_s, reference, tol, max_nodes :
        As in :func:`solve_lubrication`.
    max_step : float
        Largest continuation step in lam/lam_c.
    max_time : float, optional
        Wall-time budget of the whole sweep [s]; once spent, the point being solved and all
        points not yet solved are returned with status TIME_LIMIT and the reason.

    Returns
    -------
    list of LubricationResult
        In the order of ``lam_ratios``.

    Examples
    --------
    >>> out = sweep_lubrication(0.9, [0.99, 0.98], progress=False)
    >>> [r.success for r in out], out[0].V_over_U < out[1].V_over_U
    ([True, True], True)
    """
    try:
        ratios = np.atleast_1d(np.asarray(lam_ratios, dtype=float))
    except (TypeError, ValueError):
        raise InvalidParameterError("lam_ratios", str(lam_ratios),
                                    "a non-empty 1-d sequence of numbers") from None
    if ratios.ndim != 1 or ratios.size == 0:
        raise InvalidParameterError("lam_ratios", ratios, "a non-empty 1-d sequence")
    if ratios.size > MAX_SWEEP_POINTS:
        raise InvalidParameterError("lam_ratios", float(ratios.size),
                                    f"at most {MAX_SWEEP_POINTS} points",
                                    "points closer than the smallest continuation step "
                                    f"{MIN_STEP:g} resolve nothing more; split the sweep")
    check_range("lam_ratios", ratios, 0.0, 1.0, lo_open=True, hi_open=True,
                reason="lam/lam_c of each point")
    max_step = float(check_range("max_step", max_step, 1e-4, 0.5))
    # the lowest ratio carries the model's range check (its message names the value)
    base = _check_inputs(nu, None, float(ratios.min()), ca_b, tol, max_nodes, max_time, ca_s,
                         reference)
    results: list[LubricationResult | None] = [None] * ratios.size
    # the bar is closed on any exit (Ctrl-C included), so that it is not redrawn after the
    # command line's last message
    with tqdm(total=ratios.size, disable=not progress, desc=f"lubrication nu={base.nu:g}",
              unit="point") as bar:
        i_anchor = int(np.argmin(np.abs(ratios - ANCHOR_RATIO)))
        anchor = _solve_point(replace(base, lam=float(ratios[i_anchor]) * base.lam_c), None)
        results[i_anchor] = anchor
        bar.update(1)
        order = np.argsort(ratios, kind="stable")
        pos = int(np.flatnonzero(order == i_anchor)[0])
        for direction in (order[pos + 1:], order[:pos][::-1]):      # upward, then downward
            current = anchor
            for i in direction:
                ratio = float(ratios[i])
                prob = replace(base, lam=ratio * base.lam_c)
                if base.deadline.expired():
                    res = _failed(prob, Status.TIME_LIMIT,
                                  f"not attempted: {base.deadline.message()}", {}, {})
                elif not current.success:
                    res = _failed(prob, current.status, f"not attempted: the continuation "
                                  f"failed before lam/lam_c = {ratio:.6g} ({current.message})",
                                  {}, {})
                else:
                    clock = time.perf_counter()
                    res = _march(prob, current, ratio, max_step)
                    res = replace(res, timings=dict(res.timings,
                                                    total=time.perf_counter() - clock))
                    current = res
                results[i] = res
                bar.update(1)
                logger.debug("nu=%.4g lam/lam_c=%.6g: %s", base.nu, ratio, res.message)
    return results
