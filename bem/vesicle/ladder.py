r"""The mode ladder of one start: its seed, continuation near lam_c, the levels 16, 24, ...
and the error estimate that stops them (:func:`solve_from`).

:func:`solve_from` takes five steps: the plan of the start (:func:`plan_ladder`, a
:class:`LadderPlan`: regime, density, the levels), the continuation rungs near lam_c, the seed,
the climb through the levels, and the result with every problem named.

Regime defaults, from λ/λc and the estimated length ℓ ≈ ℓc λ/λc [R] (Chen et al. 2020 eq. sL):

* density (:mod:`bem.vesicle.seeds`): "film" from λ/λc =
  :data:`~bem.vesicle.seeds.NEAR_CRITICAL` unless the vesicle is long (ℓ > :data:`LONG_VESICLE`),
  else "bend";
* the valley Levenberg–Marquardt (:mod:`bem.vesicle.level`) for a long vesicle;
* continuation near lam_c: a vesicle with λ/λc > NEAR_CRITICAL and ℓ ≤
  :data:`RUNG_MAX_LENGTH` = 9 R is reached by continuation in λ/λc (rungs 0.9, 0.95, 0.975, ...
  below the target, each a ``rung_modes`` = 32 solve from the previous one, the first from
  lubrication): a cold start from the lubrication shape at the target can end in a spurious
  least-squares minimum (at (0.7, 0.95 λc): residual 2.1e-2 at every mode count, V/U 1.09, Δp⁺
  600, where the state reached by the rungs has V/U 1.0503, Δp⁺ 403, residual 2.2e-4 at 56
  modes; lubrication 1.0504, 391), and at λ/λc = 0.97 (ν = 0.9) it drifts to a spurious, nearly
  closed film (min gap 1.5e-3). A longer vesicle starts from the lubrication shape at its own
  λ, through carrier levels (below).

Ladder and error estimate (automatic refinement, ``n_modes`` None):

* the density is built on a BEM minimum and then kept: on the seed if it is one (``initial``
  a VesicleResult, or the continuation rungs), else on the shape of a first level solved
  from the lubrication seed (:data:`FIRST_LEVEL` = 16 modes; for a long vesicle the level
  ``first`` ≈ :data:`LONG_MODES_PER_LENGTH` = 6 modes per R of estimated length minus 16,
  reached through carrier levels 16, 32, ... of one difference Jacobian each, which keep the
  cold start on the physical branch: started at 43–64 modes it drifts to a closing film). A
  density built on the lubrication shape misses the BEM shape's rear film neck (at (0.6,
  1.94), 64 modes: γ_max 931 instead of the mode-converged 1011). A level on that first
  re-built density still resolves the neck only in part, so a long vesicle near lam_c re-builds
  it once more, on the next level's shape (:data:`NEAR_CRITICAL_REBUILDS`; at (0.6, 1.94) the
  consistent ladder then contracts by 0.26–0.38 per +8 modes instead of ~0.4 and converges at
  88 or 96 modes).
* the levels on that density, +:data:`LEVEL_STEP` = 8 modes each, form a consistent ladder:
  each starts from the previous minimum with its Jacobian prolonged (:mod:`bem.vesicle.level`),
  and their successive differences contract geometrically (spectral convergence; ratios
  0.02–0.3 per 8 modes measured at (0.9, 1.0), (0.8, 1.0), (0.7, 1.5), (0.6, 1.5), (0.6, 1.94)).
* the error estimate of the last level is the tail of that geometric series,
  :data:`ESTIMATE_SAFETY` × d ρ/(1 − ρ) from the last two differences, ρ the median of the
  three outputs' contractions (:func:`_error_estimate`); the ladder stops at the first level
  where :data:`ESTIMATE_LEVELS` = 3 consistent levels give an estimate within ``tol`` (V/U,
  Δp⁺) and ``tension_tol`` (γ_max) and the residual is below ``residual_tol``.

With ``n_modes`` given, the ladder is a single pair (round(2n/3), n) on the seed's density,
and its estimate is the pair difference (an overestimate).

Three fallbacks, each met by the map build: a given initial shape that cannot start at the
target (its film closes once the volume is re-imposed: (0.98, 0.98 λc) from the 0.95 λc shape)
is replaced by the solver's own seed; a re-built density that the next level cannot carry
((0.95, 0.2 λc): no positive volume at 24 modes) is dropped for the seed's; a seed density the
first level cannot carry ((0.85, 0.2 λc), "bend" on the lubrication shape) is replaced by
uniform arc length.

The result is the last level's, with every problem named and the leading one as its status
(:data:`lubrication.results.PRECEDENCE`): a self-intersecting membrane or a film closing below
:data:`FILM_CLOSED` = 1e-3 R or, for a red cell, a membrane compressed everywhere
(NO_STEADY_STATE: below), an estimated error above the tolerance
(UNRESOLVED), a steady residual above ``residual_tol`` or Levenberg–Marquardt failing on the
last level (NOT_CONVERGED), the time limit (TIME_LIMIT), no level able to start
(REJECTED_START).

A red cell whose largest isotropic tension γ_max is not positive has, with the deviatoric
tensions ±G_s f of its shear law, a principal tension γ − G_s|f| < 0 everywhere: a membrane
compressed everywhere, balanced by its own elastic loads, which a membrane of small bending
stiffness relieves by buckling (not representable here), not a state the flow drives. Such
states are steady solutions of the equations, reached at low Ca_S from a stored vesicle shape
far from the cell's own: on the red-cell slice (default cell, docs/data/rbc_slice_build) they
had γ_max −21 to −175 ηU, a wavy elongated shape and a V/U independent of the velocity (1.930
at (0.65, 0.2 λc) from 0.06 to 0.5 mm/s), while the same cell continued down in velocity from
1 mm/s has γ_max +1.3 to +1.5 ηU and V/U falling with velocity (1.687, 1.674, 1.664, 1.660 at
1, 0.5, 0.2, 0.1 mm/s); every other converged point of the slice has γ_max ≥ +1 ηU.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np

from lubrication.checks import Deadline, InvalidParameterError
from lubrication.geometry import critical_length
from lubrication.results import LubricationResult, Status, leading_status

from ..results import VesicleResult
from ..shape import SpectralCurve, fit_curve
from .inputs import MAX_MODES, VesicleInputs, check_vesicle_inputs
from .level import solve_level
from .operator import level_outputs, membrane_profile, self_intersects, vesicle_discretisation
from .seeds import (
    DENSITIES,
    NEAR_CRITICAL,
    capsule_seed,
    lubrication_seed,
    seed_from_lubrication,
    spheroid_seed,
)

__all__ = ["CARRIER_STEP", "ESTIMATED_OUTPUTS", "ESTIMATE_LEVELS", "ESTIMATE_SAFETY",
           "FILM_CLOSED", "FIRST_LEVEL", "LEVEL_STEP", "LONG_CONSISTENT_LEVELS",
           "LONG_FIRST_MIN", "LONG_FIRST_OFFSET", "LONG_MODES_PER_LENGTH", "LONG_VESICLE",
           "MIN_CONTRACTION", "NEAR_CRITICAL_REBUILDS", "PAIR_COARSE_FRACTION", "PAIR_LEVELS",
           "PAIR_MIN_MODES", "REBUILD_LEVEL", "RUNG_GAP_FACTOR", "RUNG_MAX_LENGTH",
           "RUNG_RESIDUAL_TOL", "RUNG_TENSION_TOL", "RUNG_TOL", "RUNG_XTOL", "SHORT_MAX_MODES",
           "SPHEROID_MAX_RADIUS", "LadderOptions", "LadderPlan", "plan_ladder", "solve_from"]

log = logging.getLogger(__name__)

# --- the regime --------------------------------------------------------------------------------

#: estimated length L/R above which :func:`bem.vesicle.solve_vesicle` uses the "bend" density
#: by default: long vesicles (ν ≲ 0.75 near λc) need it, e.g. at (0.7, 1.5) the residual falls
#: ÷4.5 per +8 modes with it against ÷2 with uniform arc length, while short ones converge
#: faster without it ((0.9, 1.0): 32-mode residual 2.3e-5 uniform, 1.0e-4 "bend")
LONG_VESICLE = 5.0

#: estimated length ℓ ≈ ℓc λ/λc [R] above which a vesicle near lam_c is not reached by
#: continuation rungs but from the lubrication shape at its own λ through carrier levels:
#: measured, (0.7, 0.95 λc), ℓ = 7.3, needs the rungs (from its own lubrication shape it ends
#: in a spurious minimum, residual 2e-2), while (0.6, 0.98 λc), ℓ = 10.8, is led astray by
#: 32-mode rungs (residual 1e-2 at each rung; at the target Δp⁺ 2818 at 40 modes, against
#: 1778 mode-converged) and converges from its own lubrication shape
RUNG_MAX_LENGTH = 9.0

# --- the levels --------------------------------------------------------------------------------

#: modes of the first level of an automatic ladder from a model seed, and the fewest modes a
#: ladder from a BEM seed starts with (no measurement recorded)
FIRST_LEVEL = 16

#: modes added from one level of a consistent ladder to the next: the successive differences
#: contract by 0.02–0.3 per 8 modes (module docstring), and +16 instead, measured for a long
#: vesicle near lam_c, left the Δp⁺ estimate above ``tol`` where the +8 ladder converges
#: ((0.6, 1.94): 64, 80, 96 modes, estimate 1.1e-4 relative; docs/vesicle-solver.md)
LEVEL_STEP = 8

#: modes added from one carrier level to the next (16, 32, ... below a long vesicle's
#: ``first``; each one difference Jacobian, which keeps the cold start on the physical branch:
#: started at 43–64 modes it drifts to a closing film); the spacing: no measurement recorded
CARRIER_STEP = 16

#: a long vesicle's first level on the re-built density (:func:`_long_first_level`): about
#: LONG_MODES_PER_LENGTH modes per R of estimated length in steps of LEVEL_STEP, minus
#: LONG_FIRST_OFFSET, at least LONG_FIRST_MIN (no measurement recorded for the three)
LONG_MODES_PER_LENGTH = 6
LONG_FIRST_OFFSET = 16
LONG_FIRST_MIN = 24

#: consistent levels of a long vesicle's default ladder (``max_modes`` None; a second
#: re-build takes one more level): the unconverged carrier levels make the re-built density
#: depend on details such as the wall mesh, and at (0.6, 0.98 lam_c) the ladder converged at
#: its fourth consistent level with one mesh and at its fifth with another
#: (:data:`NEAR_CRITICAL_REBUILDS`)
LONG_CONSISTENT_LEVELS = 5

#: default top of a short vesicle's automatic ladder (``max_modes`` None; no measurement
#: recorded)
SHORT_MAX_MODES = 80

#: consistent levels the extrapolated error estimate needs: two successive differences give
#: the contraction ρ (:func:`_error_estimate`); a ladder from a BEM seed, or a long vesicle's
#: re-built density, starts at most at ``max_modes`` − LEVEL_STEP (ESTIMATE_LEVELS − 1), so that
#: it has this many levels
ESTIMATE_LEVELS = 3

#: levels of the pair ladder with ``n_modes`` given (its estimate is the one difference):
#: the coarse level has PAIR_COARSE_FRACTION of the modes, at least PAIR_MIN_MODES (no
#: measurement recorded for the two)
PAIR_LEVELS = 2
PAIR_COARSE_FRACTION = 2 / 3
PAIR_MIN_MODES = 6

#: levels in a row whose density is re-built on the BEM shape of the level before, for a long
#: vesicle near lam_c started from its own lubrication shape (ℓ > RUNG_MAX_LENGTH): the first
#: re-built density comes from a level on the lubrication shape's density, which misses the
#: BEM shape's rear film neck, and resolves it only in part. Measured at (0.6, 0.98 lam_c),
#: Ca_B = 50 (consistent levels from 56 / 64 modes; V/U, γ_max, residual at 64 / 88 modes):
#: one re-build 1.021926 / 1.020839, 930.6 / 1005.7, 3.1e-3 / 5.6e-4, contraction ~0.4 per +8
#: modes, not converged at 88 modes (1602 BIE solves); two re-builds 1.021342 / 1.020790,
#: 964.9 / 1009.8, 1.8e-3 / 2.1e-4, contraction 0.26-0.35, converged at 88 modes (1587 BIE
#: solves; mode-converged 1.020781, 1011). The unconverged carrier levels make the shape the
#: density is built on depend on details such as the wall mesh: with WALL_BODY_LENGTH 6 R
#: instead of 5 R the same ladder contracts by ~0.38 and converges at 96 modes (1745 BIE
#: solves), which is why this regime keeps five consistent levels (``max_modes``). Farther from
#: lam_c one re-build is enough: at the red blood cell (0.61, 0.71 lam_c) a second one costs a
#: level (682 BIE solves, 64 modes, against 454 and 56)
NEAR_CRITICAL_REBUILDS = 2

#: level (index in the ladder 16, 24, ...) on whose BEM shape the density is re-built for the
#: rest of a short vesicle's automatic ladder (the seed's density family; "bend" for uniform)
REBUILD_LEVEL = 0

# --- continuation rungs ------------------------------------------------------------------------

#: gap 1 − λ/λc of each rung relative to the one before: the rungs lie at gaps 1 − NEAR_CRITICAL
#: = 0.1, 0.05, 0.025, ... below lam_c (no measurement recorded)
RUNG_GAP_FACTOR = 0.5
#: a rung within this of the target λ/λc is the target itself (the rounding of λ/λc)
RUNG_TARGET_MARGIN = 1e-9
#: decimals a rung's λ/λc is rounded to (its halved gaps are exact only to rounding)
RUNG_DIGITS = 12

#: tolerances of a rung (``tol``, ``tension_tol``, ``residual_tol`` of its pair of
#: ``rung_modes``): they set only the rung's own status, which the continuation does not test
#: (it stops only on a rung without a shape or with NO_STEADY_STATE), so they are loose: a rung
#: seeds the next, it is not an answer (no measurement recorded)
RUNG_TOL = 0.5
RUNG_TENSION_TOL = 0.5
RUNG_RESIDUAL_TOL = 10.0
#: Levenberg–Marquardt step tolerance of a rung: :func:`bem.vesicle.solve_vesicle`'s default
#: ``xtol``, not this start's (a rung's iteration budget and method are the defaults too)
RUNG_XTOL = 1e-9

# --- the seed and the result -------------------------------------------------------------------

#: widest spheroid seed [R]: a wider one (a prolate spheroid of small ν and large λ fills the
#: tube) is replaced by the capsule, which fits whenever the vesicle can pass
#: (:func:`bem.vesicle.capsule_seed`); the margin: no measurement recorded
SPHEROID_MAX_RADIUS = 0.95

#: film thickness [R] below which the film counts as closed (NO_STEADY_STATE; no measurement
#: recorded)
FILM_CLOSED = 1e-3

#: margin [R] of the parachute test (the profile reaching behind its rear pole) for the
#: rounding of the profile's positions
PROFILE_ROUNDING = 1e-12


def _rungs(ratio: float) -> list[float]:
    """Continuation rungs below ``ratio``: 1 - lam/lam_c = 0.1, 0.05, 0.025, ..."""
    out, gap = [], 1.0 - NEAR_CRITICAL
    while 1.0 - gap < ratio - RUNG_TARGET_MARGIN:
        out.append(round(1.0 - gap, RUNG_DIGITS))
        gap *= RUNG_GAP_FACTOR
    return out


#: the outputs whose discretisation error the ladder estimates (V/U, Δp⁺R0, γ_max)
ESTIMATED_OUTPUTS = ("V_over_U", "dp_plus_R0", "tension_max")

#: safety factor of the extrapolated error estimate (:func:`_error_estimate`): the observed
#: contraction ratio of the successive differences varies by up to 2.4x from one level to the
#: next in the pre-asymptotic range (γ_max at (0.6, 1.94): 0.14 then 0.33, docs/validation.md)
ESTIMATE_SAFETY = 3.0
#: smallest contraction ratio the estimate uses: the first difference of a ladder is often
#: pre-asymptotic and inflates d1 (Δp⁺ at (0.8, 1.0): observed 0.019 from 24-32-40 modes,
#: then 0.08 from 32-40-48; with the observed ratio the 40-mode error 1.9e-6 is estimated
#: as 1.4e-6, with this floor as 8e-6)
MIN_CONTRACTION = 0.1


def _error_estimate(outs: list[dict]) -> dict:
    r"""Estimated discretisation error of the last of ``outs`` (the outputs of successive
    levels of one consistent ladder: same density, +8 modes each) for the keys of
    ``ESTIMATED_OUTPUTS``.

    The spectral shape converges geometrically, :math:`q_N - q_\infty \propto \rho^{N/8}`
    (observed at (0.9, 1.0), (0.7, 1.5) and (0.6, 1.94), docs/validation.md); with the last
    two differences :math:`d_1, d_2` of an output and the contraction ρ < 1 the error of the
    last level is :math:`d_2\,\rho/(1-\rho)` (the tail of the geometric series), here
    multiplied by ``ESTIMATE_SAFETY``, with ρ at least ``MIN_CONTRACTION``. The rate is the
    discretisation's (set by the shape's analyticity, not by the output), so ρ is the median
    of the outputs' ratios :math:`d_2/d_1`: one output whose error has parts of opposite sign
    does not contract cleanly (Δp⁺ at (0.6, 1.94), 72 → 96 modes: differences +0.043,
    +0.056, +0.037 while V/U and γ_max contract by 0.29–0.37 per level; on its own ratio 0.66
    its 96-mode estimate was 0.21, 30 times the true error, and the solve ended "not
    converged"). An output whose own differences do not contract is estimated at least at
    its last difference. With two levels only, or where the median ratio is not below 1, the
    estimate is :math:`d_1 + d_2` (:math:`d_2` for a pair): the raw difference, an
    overestimate by :math:`(1-\rho)/\rho` for a contracting sequence. NaN for one level.
    """
    diffs = {}
    for k in ESTIMATED_OUTPUTS:
        q = [o[k] for o in outs]
        diffs[k] = (abs(q[-2] - q[-3]) if len(q) >= 3 else math.nan,
                    abs(q[-1] - q[-2]) if len(q) >= 2 else math.nan)
    ratios = [d2 / d1 for d1, d2 in diffs.values() if d1 > 0.0]
    rho = float(np.median(ratios)) if ratios else math.nan
    out = {}
    for k, (d1, d2) in diffs.items():
        if rho < 1.0:
            r = max(rho, MIN_CONTRACTION)
            tail = ESTIMATE_SAFETY * d2 * r / (1.0 - r)
            out[k] = tail if d2 < d1 else max(tail, d2)
        else:
            out[k] = d2 + (d1 if d1 == d1 else 0.0)
    return out


def _tolerance(key: str, tol: float, tension_tol: float) -> float:
    return tension_tol if key == "tension_max" else tol


def _within(err: dict, out: dict, tol: float, tension_tol: float) -> bool:
    """Whether every estimated error is within its relative tolerance."""
    return all(err[k] <= _tolerance(k, tol, tension_tol) * abs(out[k]) for k in ESTIMATED_OUTPUTS)


@dataclass(frozen=True)
class LadderOptions:
    """The choices of :func:`bem.vesicle.solve_vesicle` that the ladder takes as given (not
    checked by :func:`bem.vesicle.check_vesicle_inputs`; their meaning there): Gauss
    nodes per panel ``order``, the Levenberg–Marquardt step tolerance ``xtol``, the arc-length
    ``density`` ("auto", "uniform" or a key of :data:`bem.vesicle.seeds.DENSITIES`),
    ``continuation`` and ``valley`` (None: chosen by regime, module docstring), and
    ``own_seed_fallback``: a given shape that no level can start from is replaced by the
    solver's own seed (a caller's ``initial``; the pipeline's own starts are tried by the
    pipeline itself)."""

    order: int
    xtol: float
    density: str
    continuation: bool | None
    valley: bool | None
    own_seed_fallback: bool = True


# --- step 1: the plan --------------------------------------------------------------------------

@dataclass(frozen=True)
class LadderPlan:
    r"""What one start will do (:func:`plan_ladder`), the rules in the module docstring and at
    the constants.

    ``ratio`` λ/λc and ``ell`` the estimated length ℓc λ/λc [R] (Chen et al. 2020 eq. sL) set the
    regime: ``long`` (ℓ > :data:`LONG_VESICLE`), ``continuation`` (near lam_c, ℓ ≤
    :data:`RUNG_MAX_LENGTH`, no ``initial``; its ``rungs`` λ/λc below the target, empty without
    it), ``valley`` (the valley Levenberg–Marquardt: long), the arc-length ``density`` ("film"
    near lam_c unless long, else "bend") and ``rebuilt``, the family a density re-built on a BEM
    shape takes (the seed's; "bend" for uniform). ``bem_seed``: the seed is a BEM minimum (the
    rungs, or ``initial`` a result or curve), whose shape the density is built on.

    The ladder: the mode counts ``sequence``, up to ``max_modes`` (given, else
    :data:`SHORT_MAX_MODES`, or for a long vesicle ``first`` plus :data:`LONG_CONSISTENT_LEVELS`
    levels and one per re-build, within :data:`~bem.vesicle.MAX_MODES`); ``first`` the regime's
    first level on the re-built density (:data:`FIRST_LEVEL`, for a long vesicle
    :func:`_long_first_level`); the level index ``rebuild`` on whose BEM shape the density is
    re-built, again on each of the next ``rebuilds`` − 1 levels' (:data:`NEAR_CRITICAL_REBUILDS`
    for a valley solve near lam_c from a model seed, else 1), None where the seed's density is
    kept (a BEM seed, the pair); the levels below ``rebuild`` of a valley solve are carriers.
    ``min_levels``: the consistent levels the stop test needs (:data:`PAIR_LEVELS` with
    ``n_modes`` given, else :data:`ESTIMATE_LEVELS`).
    """

    ratio: float
    ell: float
    long: bool
    continuation: bool
    rungs: tuple[float, ...]
    valley: bool
    density: str
    rebuilt: str
    bem_seed: bool
    first: int
    rebuilds: int
    max_modes: int
    sequence: tuple[int, ...]
    rebuild: int | None
    min_levels: int

    def rebuilds_density(self, i: int) -> bool:
        """Whether level ``i`` first tries a density re-built on the level before's shape."""
        return self.rebuild is not None and self.rebuild < i <= self.rebuild + self.rebuilds

    def carrier(self, i: int) -> bool:
        """Whether level ``i`` is a carrier (one difference Jacobian, it only seeds the next)."""
        return self.rebuild is not None and self.valley and i < self.rebuild


def _long_first_level(ell: float) -> int:
    """A long vesicle's first level on the re-built density: ~LONG_MODES_PER_LENGTH modes per R
    of estimated length ``ell``, in steps of LEVEL_STEP, minus LONG_FIRST_OFFSET, at least
    LONG_FIRST_MIN."""
    levels = round(LONG_MODES_PER_LENGTH / LEVEL_STEP * ell)
    return max(LONG_FIRST_MIN, LEVEL_STEP * levels - LONG_FIRST_OFFSET)


def _sequence(case: VesicleInputs, initial, *, ratio: float, continuation: bool, valley: bool,
              bem_seed: bool, first: int, max_modes: int) -> tuple[list[int], int | None]:
    """The ladder's mode counts and the index of the level whose shape re-builds the density
    (None: the seed's density is kept), one of four ladders: the pair (``n_modes`` given); from
    a BEM seed; carriers below a long vesicle's re-built density (valley); the plain ladder."""
    top = max_modes - LEVEL_STEP * (ESTIMATE_LEVELS - 1)  # highest start that leaves 3 levels
    if case.n_modes is not None:
        return [max(PAIR_MIN_MODES, round(PAIR_COARSE_FRACTION * case.n_modes)),
                case.n_modes], None
    if bem_seed:
        # from the seed's mode count near lam_c (a refit to fewer modes loses the thin film:
        # from a 0.95 lam_c result refitted to 16 modes, the film of (0.98, 0.98 lam_c)
        # closed); below, a continued result restarts low
        start = (case.rung_modes if continuation else initial.modes.size
                 if ratio > NEAR_CRITICAL else min(initial.modes.size, first))
        start = min(max(FIRST_LEVEL, LEVEL_STEP * round(start / LEVEL_STEP)), top)
        return list(range(start, max_modes + 1, LEVEL_STEP)), None
    if valley:
        first = min(first, top)
        sequence = [*range(FIRST_LEVEL, first, CARRIER_STEP),
                    *range(first, max_modes + 1, LEVEL_STEP)]
        return sequence, sequence.index(first)
    return list(range(FIRST_LEVEL, max_modes + 1, LEVEL_STEP)), REBUILD_LEVEL


def plan_ladder(case: VesicleInputs, initial, options: LadderOptions) -> LadderPlan:
    """The :class:`LadderPlan` of a start from ``initial`` (as in :func:`solve_from`).

    Raises
    ------
    InvalidParameterError
        ``options.density`` not "auto", "uniform" or a key of DENSITIES.

    Examples
    --------
    A long vesicle near lam_c: carriers 16, 32, the density built on the 48-mode shape and
    re-built on the 56-mode one, five consistent levels 64–96; a short one from its rung:

    >>> from bem.vesicle import check_vesicle_inputs
    >>> options = LadderOptions(order=16, xtol=1e-9, density="auto", continuation=None,
    ...                         valley=None)
    >>> plan = plan_ladder(check_vesicle_inputs(0.6, lam_ratio=0.98), None, options)
    >>> plan.density, plan.sequence, plan.rebuild, plan.rebuilds
    ('bend', (16, 32, 48, 56, 64, 72, 80, 88, 96), 2, 2)
    >>> plan = plan_ladder(check_vesicle_inputs(0.9, lam_ratio=0.95), None, options)
    >>> plan.rungs, plan.density, plan.sequence[:3]
    ((0.9,), 'film', (32, 40, 48))
    """
    density = options.density
    if density not in ("auto", "uniform", *DENSITIES):
        raise InvalidParameterError("density", density,
                                    '"auto", "uniform", "curvature", "bend" or "film"')
    ratio = case.lam_ratio
    ell = critical_length(case.nu) * ratio           # estimated length L/R (Chen eq. sL)
    long = ell > LONG_VESICLE
    continuation = options.continuation
    if continuation is None:
        continuation = initial is None and ratio > NEAR_CRITICAL and ell <= RUNG_MAX_LENGTH
    valley = long if options.valley is None else options.valley
    if density == "auto":
        density = "film" if ratio >= NEAR_CRITICAL and not long else "bend"
    bem_seed = continuation or isinstance(initial, (VesicleResult, SpectralCurve))
    first = _long_first_level(ell) if long else FIRST_LEVEL
    rebuilds = (NEAR_CRITICAL_REBUILDS if valley and ratio > NEAR_CRITICAL and not bem_seed
                and case.n_modes is None else 1)
    max_modes = case.max_modes
    if max_modes is None:
        long_top = first + LEVEL_STEP * (LONG_CONSISTENT_LEVELS - 1 + rebuilds)
        max_modes = min(MAX_MODES, long_top if long else SHORT_MAX_MODES)
    sequence, rebuild = _sequence(case, initial, ratio=ratio, continuation=continuation,
                                  valley=valley, bem_seed=bem_seed, first=first,
                                  max_modes=max_modes)
    return LadderPlan(
        ratio=ratio, ell=ell, long=long, continuation=continuation,
        rungs=tuple(_rungs(ratio)) if continuation else (), valley=valley, density=density,
        rebuilt=density if density in DENSITIES else "bend", bem_seed=bem_seed, first=first,
        rebuilds=rebuilds, max_modes=max_modes, sequence=tuple(sequence), rebuild=rebuild,
        min_levels=PAIR_LEVELS if case.n_modes is not None else ESTIMATE_LEVELS)


# --- the budget of a start ---------------------------------------------------------------------

class _Budget:
    """The wall-time budget of one start, ``max_time`` [s] from its creation: a
    :class:`~lubrication.checks.Deadline` tested between evaluations, levels and rungs, and the
    seconds left for a nested start (a rung, the fallback to the own seed)."""

    def __init__(self, max_time: float | None):
        self.t_start = time.perf_counter()
        self.deadline = Deadline(max_time)
        self.clock = time.monotonic()
        self.max_time = max_time

    def left(self) -> float | None:
        """Seconds left (may be <= 0); None without a limit."""
        return None if self.max_time is None else self.max_time - (time.monotonic() - self.clock)

    def elapsed(self) -> float:
        return time.perf_counter() - self.t_start


class _Stopped(Exception):
    """Ends a start before its ladder with the result it carries (time limit, failed rung)."""

    def __init__(self, result: VesicleResult):
        super().__init__(result.message)
        self.result = result


def _stopped(case: VesicleInputs, budget: _Budget, status: Status, message: str,
             iterations: dict | None = None) -> _Stopped:
    """A start ended before any level, as the :class:`_Stopped` that carries its result."""
    return _Stopped(VesicleResult(
        nu=case.nu, lam=case.lam, lam_c=case.lam_c, ca_b=case.ca_b, **case.membrane,
        status=status, tol=case.tol, residual_tol=case.residual_tol, iterations=dict(iterations or {}),
        timings={"total_s": budget.elapsed()}, message=message))


def _time_limit(case: VesicleInputs, budget: _Budget, what: str, iterations: dict) -> _Stopped:
    return _stopped(case, budget, Status.TIME_LIMIT, f"{budget.deadline.message()} ({what})",
                    iterations)


# --- step 2: continuation rungs ----------------------------------------------------------------

@dataclass(frozen=True)
class _Start:
    """What the seed is made from: ``initial`` (as in :func:`solve_from`, or the last rung),
    its label ``source`` and the rungs' ``iterations``."""

    initial: object
    source: str
    iterations: dict = field(default_factory=dict)


def _continuation(case: VesicleInputs, plan: LadderPlan, options: LadderOptions, initial,
                  budget: _Budget) -> _Start:
    """The rungs of ``plan``, each a pair of ``rung_modes`` on this start's density at the
    loose RUNG_* tolerances, solved from the one before (the first from lubrication); the last
    one is the start (``initial`` if there is none). Raises :class:`_Stopped` at the time limit
    and where a rung ends without a shape or with no steady state."""
    rung_options = LadderOptions(order=options.order, xtol=RUNG_XTOL, density=plan.density,
                                 continuation=False, valley=None)
    rung, iterations = None, {}
    for q in plan.rungs:
        what = f"continuation rung lam/lam_c = {q:g}"
        left = budget.left()
        if left is not None and left <= 0.0:
            raise _time_limit(case, budget, what, iterations)
        rung_case = check_vesicle_inputs(case.nu, lam_ratio=q, ca_b=case.ca_b,
                                         n_modes=case.rung_modes, tol=RUNG_TOL,
                                         tension_tol=RUNG_TENSION_TOL,
                                         residual_tol=RUNG_RESIDUAL_TOL,
                                         density_terms=case.density_terms,
                                         ca_s=case.ca_s, reference=case.reference)
        rung = solve_from(rung_case, rung, rung_options, left)
        if budget.deadline.expired():
            raise _time_limit(case, budget, what, iterations)
        iterations[f"rung{q:g}"] = {
            "evaluations": sum(v["evaluations"] for v in rung.iterations.values()),
            "seconds": rung.timings.get("total_s", math.nan), "residual": rung.residual}
        if rung.modes.size == 0 or rung.status is Status.NO_STEADY_STATE:
            raise _stopped(case, budget, rung.status,
                           f"continuation failed at lam/lam_c = {q:g}: {rung.message}")
        log.info("solve_vesicle continuation rung lam/lam_c=%g: V/U=%.6f dp+R0=%.5g "
                 "residual %.1e", q, rung.V_over_U, rung.dp_plus_R0, rung.residual)
    if rung is None:
        return _Start(initial, "initial", iterations)
    labels = ", ".join(f"{r:g}" for r in plan.rungs)
    return _Start(rung, f"continuation (lam/lam_c = {labels})", iterations)


# --- step 3: the seed --------------------------------------------------------------------------

def _model_seed(case: VesicleInputs, n: int) -> tuple[SpectralCurve, str]:
    """The last-resort seed of ``n`` modes: the prolate spheroid, or the capsule where the
    spheroid is wider than SPHEROID_MAX_RADIUS."""
    seed = spheroid_seed(case.nu, case.lam, n)
    if seed.max_radius() > SPHEROID_MAX_RADIUS:
        return capsule_seed(case.nu, case.lam, n), "capsule"
    return seed, "spheroid"


def _seed(case: VesicleInputs, plan: LadderPlan, start: _Start,
          deadline: Deadline) -> tuple[SpectralCurve, str]:
    """The first level's seed curve, on the plan's density, and its label: a given curve or
    result's shape; a lubrication result's shape, or the lubrication seed's without one
    (:mod:`bem.vesicle.seeds`); the spheroid or capsule where these fail.

    Raises
    ------
    InvalidParameterError
        ``initial`` of another type, or a result without a shape.
    """
    n, density, terms = plan.sequence[0], plan.density, case.density_terms
    initial, source = start.initial, start.source
    from_lubrication = False                         # the seed is already fitted with density
    if isinstance(initial, SpectralCurve):
        seed = initial
    elif isinstance(initial, LubricationResult) or initial is None:
        seed = None
        if initial is None:
            seed, _ = lubrication_seed(case.nu, case.lam, case.ca_b, n, density, terms,
                                       max_time=deadline.remaining())
            source = "lubrication"
        elif initial.success:
            seed = seed_from_lubrication(initial, n, density, terms)
        from_lubrication = seed is not None
        if seed is None:
            seed, source = _model_seed(case, n)
    elif isinstance(initial, VesicleResult):
        if initial.modes.size == 0:
            raise InvalidParameterError("initial", "a VesicleResult without a shape",
                                        "a result with a shape")
        seed = initial.curve()
    else:
        raise InvalidParameterError("initial", type(initial).__name__,
                                    "a VesicleResult, SpectralCurve, LubricationResult or None")
    if density != "uniform" and not from_lubrication:
        seed = fit_curve(seed.sample, 0.0, 1.0, n, density=DENSITIES[density](seed, terms))
    return seed, source


# --- step 4: the climb -------------------------------------------------------------------------

@dataclass
class _Ladder:
    """The levels climbed, each (state, operator, outputs), with the ladder's own failure
    (``status``, ``message``; CONVERGED and "" if none) and ``consistent``, the index of the
    first level on the density of the last one."""

    iterations: dict
    levels: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    status: Status = Status.CONVERGED
    message: str = ""
    consistent: int = 0

    def estimate(self) -> dict:
        """The error estimate of the last level from the consistent ones (_error_estimate)."""
        return _error_estimate([lv[2] for lv in self.levels[self.consistent:]])

    def resolved(self, case: VesicleInputs, plan: LadderPlan) -> bool:
        """Whether the ladder stops here: enough consistent levels, the estimate within the
        tolerances and the steady residual within ``residual_tol``."""
        err = self.estimate()
        fine = self.levels[-1][2]
        return (len(self.levels) - self.consistent >= plan.min_levels
                and _within(err, fine, case.tol, case.tension_tol)
                and fine["residual"] <= case.residual_tol)

    def stop(self, status: Status, message: str) -> None:
        self.status, self.message = status, message


def _level_seeds(case: VesicleInputs, plan: LadderPlan, i: int, n: int, prev: SpectralCurve,
                 ladder: _Ladder) -> list:
    """The seeds of level ``i`` (``n`` modes) in the order tried, from the last shape ``prev``.

    After one whose density the level rejects: a density re-built on a shape that does not carry
    it (at (0.95, 0.2 lam_c) the 16-mode level stopped at a 5e-2 step and the 24-mode curve on
    its density had no positive volume) gives way to the seed's density, and a first level whose
    seed density fails (the "bend" density of the lubrication shape at (0.85, 0.2 lam_c): a
    curve c_1 cannot close) starts on uniform arc length (None: made when needed). Where the
    plan re-builds the density here, the re-built curve comes first (it resolves what the
    seed's density misses, e.g. a long vesicle's rear film neck) and starts a consistent ladder.
    """
    seeds = [prev, None] if not ladder.levels and np.size(prev.density) else [prev]
    if plan.rebuilds_density(i) and ladder.levels:
        try:
            seeds = [fit_curve(prev.sample, 0.0, 1.0, n,
                               density=DENSITIES[plan.rebuilt](prev, case.density_terms)), prev]
            ladder.consistent = len(ladder.levels)
        except InvalidParameterError:
            pass
    return seeds


def _start_level(case: VesicleInputs, plan: LadderPlan, options: LadderOptions, i: int, n: int,
                 seeds: list, prev: SpectralCurve, ladder: _Ladder, deadline: Deadline):
    """Level ``i`` solved from the first of ``seeds`` it accepts: (state, op, info), or None
    and the last rejection. A carrier starts from a fresh difference Jacobian (one prolonged
    from the unfinished level below led the cold start of (0.6, 1.94) to Δp⁺ 2829 at 32 modes,
    1778 converged); a later seed is not a carrier and breaks the consistent ladder."""
    disc = vesicle_discretisation(n, options.order)
    levels, rejected = ladder.levels, None
    for k, seed in enumerate(seeds):
        if k:
            log.info("solve_vesicle: density rejected at %d modes (%s)", n, rejected)
            ladder.consistent = 0
        as_carrier = plan.carrier(i) and not k
        try:
            return solve_level(
                case.nu, case.lam, case.ca_b, disc, fit_curve(prev.sample, 0.0, 1.0, n)
                if seed is None else seed, n, xtol=options.xtol, max_iter=case.max_iter,
                seed_level=not levels, valley=plan.valley, carrier=as_carrier,
                deadline=deadline, shear=case.shear,
                coarse=(levels[-1][1], levels[-1][0]) if levels and not as_carrier else None), None
        except InvalidParameterError as exc:
            rejected = exc
    return None, rejected


def _climb(case: VesicleInputs, plan: LadderPlan, options: LadderOptions, seed: SpectralCurve,
           deadline: Deadline, iterations: dict) -> _Ladder:
    """The levels of ``plan.sequence`` from ``seed``, until one is resolved
    (:meth:`_Ladder.resolved`), the time limit, a level that no seed can start, or
    Levenberg–Marquardt failing on the last level. An unfinished coarser level only seeds the
    next one, which is judged on its own."""
    ladder = _Ladder(iterations=dict(iterations))
    prev = seed
    for i, n in enumerate(plan.sequence):
        if deadline.expired():
            ladder.stop(Status.TIME_LIMIT,
                        f"{deadline.message()} (before the level with {n} modes)")
            break
        t0 = time.perf_counter()
        seeds = _level_seeds(case, plan, i, n, prev, ladder)
        solved, rejected = _start_level(case, plan, options, i, n, seeds, prev, ladder, deadline)
        if solved is None:      # no seed could start: the solve's start if it is the first level
            ladder.stop(Status.NOT_CONVERGED if ladder.levels else Status.REJECTED_START,
                        f"level with {n} modes: {rejected}")
            break
        st, op, info = solved
        ladder.timings[f"modes{n}_s"] = time.perf_counter() - t0
        ladder.iterations[f"modes{n}"] = info
        out = level_outputs(case.nu, case.lam, op, st)
        ladder.levels.append((st, op, out))
        log.info("solve_vesicle nu=%g lam=%g modes=%d: V/U=%.10f dp+R0=%.8g gmax=%.6g "
                 "residual %.2e (%s)", case.nu, case.lam, n, out["V_over_U"], out["dp_plus_R0"],
                 out["tension_max"], out["residual"], info["message"])
        if not info["success"]:
            if deadline.expired():
                ladder.stop(Status.TIME_LIMIT,
                            f"{deadline.message()} (in the level with {n} modes)")
                break
            if n == plan.sequence[-1]:
                ladder.stop(Status.NOT_CONVERGED,
                            f"Levenberg–Marquardt failed with {n} modes: {info['message']}")
                break
            log.info("solve_vesicle: level with %d modes unfinished (%s); refining", n,
                     info["message"])
        prev = st["curve"]
        if ladder.resolved(case, plan):
            break
    return ladder


# --- step 5: the result ------------------------------------------------------------------------

def _verdict(case: VesicleInputs, ladder: _Ladder, prof: dict, err: dict) -> tuple[Status, str]:
    """Status and message of the last level: every problem named, the status the leading one
    (:data:`lubrication.results.PRECEDENCE`), else the converged summary."""
    fine = ladder.levels[-1][2]
    tol, tension_tol, residual_tol = case.tol, case.tension_tol, case.residual_tol
    problems, found = ([ladder.message], [ladder.status]) if ladder.message else ([], [])
    if self_intersects(prof["x"], prof["r"]):
        problems.append("the membrane self-intersects")
        found.append(Status.NO_STEADY_STATE)
    if fine["film_min"] < FILM_CLOSED:
        problems.append(f"the film closes (min gap {fine['film_min']:.2e} R)")
        found.append(Status.NO_STEADY_STATE)
    if case.shear is not None and fine["tension_max"] <= 0.0:
        problems.append(f"the membrane is compressed everywhere (largest isotropic tension "
                        f"{fine['tension_max']:.3g} ηU): a self-equilibrated elastic state, "
                        f"not the flow-driven one")
        found.append(Status.NO_STEADY_STATE)
    bad = [k for k in ESTIMATED_OUTPUTS
           if not err[k] <= _tolerance(k, tol, tension_tol) * abs(fine[k])]
    if bad:
        problems.append("estimated discretisation error above the tolerance in "
                        + ", ".join(f"{k} ({err[k] / abs(fine[k]):.1e} > "
                                    f"{_tolerance(k, tol, tension_tol):g})" for k in bad))
        found.append(Status.UNRESOLVED)
    if not fine["residual"] <= residual_tol:
        problems.append(f"steady residual max|u - V e_x| = {fine['residual']:.2e} exceeds "
                        f"residual_tol={residual_tol:g}")
        found.append(Status.NOT_CONVERGED)
    message = ("; ".join(problems) if problems else
               f"converged: {fine['panels']['modes']} modes, estimated errors "
               + ", ".join(f"{k} {err[k]:.1e}" for k in ESTIMATED_OUTPUTS)
               + f", residual {fine['residual']:.1e}")
    return leading_status(found), message


def _result(case: VesicleInputs, ladder: _Ladder, source: str) -> VesicleResult:
    """The VesicleResult of the last level: outputs, profile, wall shear, shape class, the
    refinement history and the verdict (:func:`_verdict`)."""
    nu, lam = case.nu, case.lam
    st, op, fine = ladder.levels[-1]
    err = ladder.estimate()
    curve = st["curve"]
    prof = membrane_profile(curve, st["g"])
    status, message = _verdict(case, ladder, prof, err)
    if status is not Status.CONVERGED:  # one start of the pipeline: solve_vesicle reports it
        log.info("solve_vesicle start (nu=%g, lam=%g): %s", nu, lam, message)
    try:
        wall_x, wall_shear = op.wall_shear(curve, st["g"])
        wall_x = wall_x - curve.position(np.array([0.0]))[0][0]    # from the rear pole
    except InvalidParameterError:                     # a shape touching the wall
        wall_x = wall_shear = np.empty(0)
    k_rear = curve.curvatures(np.array([0.0]))[0][0]
    k_front = curve.curvatures(np.array([1.0]))[0][0]
    parachute = bool(k_rear < 0.0 or np.min(prof["x"]) < prof["x"][0] - PROFILE_ROUNDING)
    history = [(lv[2]["panels"]["modes"], lv[2]["residual"], lv[2]["V_over_U"],
                lv[2]["dp_plus_R0"], lv[2]["tension_max"]) for lv in ladder.levels]
    return VesicleResult(
        nu=nu, lam=lam, lam_c=case.lam_c, ca_b=case.ca_b, **case.membrane, status=status,
        message=message,
        V_over_U=fine["V_over_U"], dp_plus_R0=fine["dp_plus_R0"], dp_plus_R=fine["dp_plus_R"],
        ell=fine["ell"], ell_poles=fine["ell_poles"], film_min=fine["film_min"],
        tension_max=fine["tension_max"],
        wall_shear_max=float(np.max(wall_shear)) if wall_shear.size else math.nan,
        wall_x=wall_x, wall_shear=wall_shear,
        tension_rear=float(prof["tension"][0]), tension_front=float(prof["tension"][-1]),
        curvature_rear=-float(k_rear), curvature_front=-float(k_front),
        shape_class="parachute" if parachute else "bullet", error_estimate=err,
        volume_error=fine["volume_error"], area_error=fine["area_error"],
        residual=fine["residual"], tol=case.tol, residual_tol=case.residual_tol,
        panels=fine["panels"], refinement=history, seed=source, iterations=ladder.iterations,
        timings=ladder.timings, modes=curve.modes.copy(),
        density=np.asarray(curve.density).copy(), tension_modes=np.asarray(st["g"]).copy(),
        **prof)


def solve_from(case: VesicleInputs, initial, options: LadderOptions,
               max_time: float | None = None) -> VesicleResult:
    r"""Steady vesicle from one start: ``initial`` (as in :func:`bem.vesicle.solve_vesicle`),
    or with None the solver's own seed (lubrication shape, continuation near lam_c), refined by
    the mode ladder with its error estimate (module docstring). ``case``: the checked inputs
    (:func:`bem.vesicle.check_vesicle_inputs`); ``options``: the choices passed on
    unchecked; ``max_time`` [s] the budget of this start. The result is that of
    :func:`bem.vesicle.solve_vesicle`, whose pipeline calls this once per start.

    The steps: the plan (:func:`plan_ladder`), the continuation rungs, the seed, the climb
    through the levels, the result; a given shape that no level can start from is replaced by
    the solver's own seed where ``options.own_seed_fallback`` (module docstring, the
    fallbacks)."""
    budget = _Budget(max_time)
    plan = plan_ladder(case, initial, options)
    try:
        start = (_continuation(case, plan, options, initial, budget) if plan.continuation
                 else _Start(initial, "initial"))
        if budget.deadline.expired():
            raise _time_limit(case, budget, "before the seed", start.iterations)
    except _Stopped as stop:
        return stop.result
    seed, source = _seed(case, plan, start, budget.deadline)
    ladder = _climb(case, plan, options, seed, budget.deadline, start.iterations)
    ladder.timings["total_s"] = budget.elapsed()
    if (not ladder.levels and plan.bem_seed and not plan.continuation
            and options.own_seed_fallback and not budget.deadline.expired()):
        # a continued shape that cannot start at this lam (its volume re-imposed, the film of
        # (0.98, 0.95 lam_c) closed at 0.98 lam_c): the solver's own seed and continuation
        log.info("solve_vesicle: the given initial shape was rejected (%s); own seed",
                 ladder.message)
        left = budget.left()
        if left is None or left > 0.0:
            return solve_from(case, None, dataclasses.replace(options, continuation=None), left)
    if not ladder.levels:
        return VesicleResult(nu=case.nu, lam=case.lam, lam_c=case.lam_c, ca_b=case.ca_b,
                             **case.membrane, status=ladder.status, message=ladder.message, tol=case.tol,
                             residual_tol=case.residual_tol, iterations=ladder.iterations,
                             timings=ladder.timings)
    return _result(case, ladder, source)
