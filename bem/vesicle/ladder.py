r"""The mode ladder of one start: its seed, continuation near lam_c, the levels 16, 24, ...
and the error estimate that stops them (:func:`solve_from`).

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
  from the lubrication seed (16 modes; for a long vesicle the level ``first`` ≈ 6 modes per R
  of estimated length minus 16, reached through carrier levels 16, 32, ... of one difference
  Jacobian each, which keep the cold start on the physical branch: started at 43–64 modes it
  drifts to a closing film). A density built on the lubrication shape misses the BEM shape's
  rear film neck (at (0.6, 1.94), 64 modes: γ_max 931 instead of the mode-converged 1011).
  A level on that first re-built density still resolves the neck only in part, so a long
  vesicle near lam_c re-builds it once more, on the next level's shape
  (:data:`NEAR_CRITICAL_REBUILDS`; at (0.6, 1.94) the consistent ladder then contracts by
  0.26–0.38 per +8 modes instead of ~0.4 and converges at 88 or 96 modes).
* the levels on that density, +8 modes each, form a consistent ladder: each starts from the
  previous minimum with its Jacobian prolonged (:mod:`bem.vesicle.level`), and their
  successive differences contract geometrically (spectral convergence; ratios 0.02–0.3 per 8
  modes measured at (0.9, 1.0), (0.8, 1.0), (0.7, 1.5), (0.6, 1.5), (0.6, 1.94)).
* the error estimate of the last level is the tail of that geometric series,
  :data:`ESTIMATE_SAFETY` × d ρ/(1 − ρ) from the last two differences, ρ the median of the
  three outputs' contractions (:func:`_error_estimate`); the ladder stops at the first level
  where three consistent levels give an estimate within ``tol`` (V/U, Δp⁺) and
  ``tension_tol`` (γ_max) and the residual is below ``residual_tol``.

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
1e-3 R (NO_STEADY_STATE), an estimated error above the tolerance (UNRESOLVED), a steady residual
above ``residual_tol`` or Levenberg–Marquardt failing on the last level (NOT_CONVERGED), the
time limit (TIME_LIMIT), no level able to start (REJECTED_START).
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass

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

__all__ = ["ESTIMATED_OUTPUTS", "ESTIMATE_SAFETY", "LONG_VESICLE", "MIN_CONTRACTION",
           "NEAR_CRITICAL_REBUILDS", "REBUILD_LEVEL", "RUNG_MAX_LENGTH", "LadderOptions",
           "solve_from"]

log = logging.getLogger(__name__)

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


def _rungs(ratio: float) -> list[float]:
    """Continuation rungs below ``ratio``: 1 - lam/lam_c = 0.1, 0.05, 0.025, ..."""
    out, gap = [], 1.0 - NEAR_CRITICAL
    while 1.0 - gap < ratio - 1e-9:
        out.append(round(1.0 - gap, 12))
        gap *= 0.5
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
    ``density`` ("auto", "uniform" or a key of :data:`bem.vesicle.seeds.DENSITIES`), and
    ``continuation`` and ``valley`` (None: chosen by regime, module docstring)."""

    order: int
    xtol: float
    density: str
    continuation: bool | None
    valley: bool | None


def solve_from(case: VesicleInputs, initial, options: LadderOptions,
               max_time: float | None = None) -> VesicleResult:
    r"""Steady vesicle from one start: ``initial`` (as in :func:`bem.vesicle.solve_vesicle`),
    or with None the solver's own seed (lubrication shape, continuation near lam_c), refined by
    the mode ladder with its error estimate (module docstring). ``case``: the checked inputs
    (:func:`bem.vesicle.check_vesicle_inputs`); ``options``: the choices passed on
    unchecked; ``max_time`` [s] the budget of this start. The result is that of
    :func:`bem.vesicle.solve_vesicle`, whose pipeline calls this once per start."""
    t_start = time.perf_counter()
    deadline = Deadline(max_time)
    clock = time.monotonic()
    nu, lam, lam_c, ca_b = case.nu, case.lam, case.lam_c, case.ca_b
    n_modes, max_modes, rung_modes = case.n_modes, case.max_modes, case.rung_modes
    tol, tension_tol, residual_tol = case.tol, case.tension_tol, case.residual_tol
    density_terms, max_iter = case.density_terms, case.max_iter
    order, xtol, density = options.order, options.xtol, options.density
    continuation, valley = options.continuation, options.valley
    if density not in ("auto", "uniform", *DENSITIES):
        raise InvalidParameterError("density", density,
                                    '"auto", "uniform", "curvature", "bend" or "film"')
    ratio = lam / lam_c
    ell = critical_length(nu) * ratio                # estimated length L/R (Chen eq. sL)
    long = ell > LONG_VESICLE
    if continuation is None:
        continuation = initial is None and ratio > NEAR_CRITICAL and ell <= RUNG_MAX_LENGTH
    if valley is None:
        valley = long
    if density == "auto":
        density = "film" if ratio >= NEAR_CRITICAL and not long else "bend"
    # the ladder (module docstring): levels of ``sequence``; a seed that is not a BEM minimum
    # has the density re-built on the BEM shape of level ``rebuild`` (an index; near lam_c
    # again on the next level's, ``rebuilds``), and every later level keeps it (a consistent
    # ladder); a BEM seed (``initial`` a result, or the continuation rungs) already gives the
    # density its shape
    bem_seed = continuation or isinstance(initial, (VesicleResult, SpectralCurve))
    rebuilt = density if density in DENSITIES else "bend"
    first = max(24, 8 * round(0.75 * ell) - 16) if long else 16
    # levels whose density is re-built on the shape of the level before (NEAR_CRITICAL_REBUILDS)
    rebuilds = (NEAR_CRITICAL_REBUILDS if valley and ratio > NEAR_CRITICAL and not bem_seed
                and n_modes is None else 1)
    if max_modes is None:      # a second re-build takes a level: the consistent ladder keeps 5
        max_modes = min(MAX_MODES, first + 32 + 8 * rebuilds if long else 80)
    if n_modes is not None:
        sequence, rebuild = [max(6, round(2 * n_modes / 3)), n_modes], None
    elif bem_seed:       # from the seed's mode count near lam_c (a refit to fewer modes
        # loses the thin film: from a 0.95 lam_c result refitted to 16 modes, the film of
        # (0.98, 0.98 lam_c) closed); below, a continued result restarts low
        start = (rung_modes if continuation else initial.modes.size if ratio > NEAR_CRITICAL
                 else min(initial.modes.size, first))
        start = min(max(16, 8 * round(start / 8)), max_modes - 16)
        sequence, rebuild = list(range(start, max_modes + 1, 8)), None
    elif valley:                     # carriers every 16 modes below the re-built density
        first = min(first, max_modes - 16)
        sequence = list(range(16, first, 16)) + list(range(first, max_modes + 1, 8))
        rebuild = sequence.index(first)
    else:
        sequence, rebuild = list(range(16, max_modes + 1, 8)), REBUILD_LEVEL
    seed_source = "initial"
    rung_log = {}

    def timed_out(what: str):
        return VesicleResult(nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=Status.TIME_LIMIT,
                             tol=tol, residual_tol=residual_tol, iterations=dict(rung_log),
                             timings={"total_s": time.perf_counter() - t_start},
                             message=f"{deadline.message()} ({what})")
    if continuation:
        # a rung: a single pair of rung_modes on this start's density at loose tolerances; its
        # step tolerance, iteration budget and method are the defaults, not this start's
        rung_options = LadderOptions(order=order, xtol=1e-9, density=density,
                                     continuation=False, valley=None)
        rung = None
        for q in _rungs(ratio):
            left = None if max_time is None else max_time - (time.monotonic() - clock)
            if left is not None and left <= 0.0:
                return timed_out(f"continuation rung lam/lam_c = {q:g}")
            rung_case = check_vesicle_inputs(nu, lam_ratio=q, ca_b=ca_b, n_modes=rung_modes,
                                             tol=0.5, tension_tol=0.5, residual_tol=10.0,
                                             density_terms=density_terms)
            rung = solve_from(rung_case, rung, rung_options, left)
            if deadline.expired():
                return timed_out(f"continuation rung lam/lam_c = {q:g}")
            rung_log[f"rung{q:g}"] = {
                "evaluations": sum(v["evaluations"] for v in rung.iterations.values()),
                "seconds": rung.timings.get("total_s", math.nan), "residual": rung.residual}
            if rung.modes.size == 0 or rung.status is Status.NO_STEADY_STATE:
                return VesicleResult(
                    nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=rung.status, tol=tol,
                    residual_tol=residual_tol, timings={"total_s": time.perf_counter() - t_start},
                    message=f"continuation failed at lam/lam_c = {q:g}: {rung.message}")
            log.info("solve_vesicle continuation rung lam/lam_c=%g: V/U=%.6f dp+R0=%.5g "
                     "residual %.1e", q, rung.V_over_U, rung.dp_plus_R0, rung.residual)
        if rung is not None:
            initial = rung
            seed_source = f"continuation (lam/lam_c = {', '.join(f'{r:g}' for r in _rungs(ratio))})"
    from_lubrication = False                         # the seed is already fitted with density
    if deadline.expired():
        return timed_out("before the seed")
    if isinstance(initial, SpectralCurve):
        seed = initial
    elif isinstance(initial, LubricationResult) or initial is None:
        seed = None
        if initial is None:
            seed, _ = lubrication_seed(nu, lam, ca_b, sequence[0], density, density_terms,
                                       max_time=deadline.remaining())
            seed_source = "lubrication"
        elif initial.success:
            seed = seed_from_lubrication(initial, sequence[0], density, density_terms)
        from_lubrication = seed is not None
        if seed is None:
            seed = spheroid_seed(nu, lam, sequence[0])
            seed_source = "spheroid"
            if seed.max_radius() > 0.95:                   # a spheroid of small nu: too fat
                seed = capsule_seed(nu, lam, sequence[0])
                seed_source = "capsule"
    elif isinstance(initial, VesicleResult):
        if initial.modes.size == 0:
            raise InvalidParameterError("initial", "a VesicleResult without a shape",
                                        "a result with a shape")
        seed = initial.curve()
    else:
        raise InvalidParameterError("initial", type(initial).__name__,
                                    "a VesicleResult, SpectralCurve, LubricationResult or None")
    if density != "uniform" and not from_lubrication:
        seed = fit_curve(seed.sample, 0.0, 1.0, sequence[0],
                         density=DENSITIES[density](seed, density_terms))
    levels, timings, iterations = [], {}, dict(rung_log)
    status, message = Status.CONVERGED, ""        # the ladder's own failure, if any
    prev = seed
    consistent = 0           # index of the first level on the density of the last one
    for i, n in enumerate(sequence):
        if deadline.expired():
            status = Status.TIME_LIMIT
            message = f"{deadline.message()} (before the level with {n} modes)"
            break
        disc = vesicle_discretisation(n, order)
        t0 = time.perf_counter()
        # the seeds of this level in the order tried: after one whose density the level
        # rejects, a density re-built on a shape that does not carry it (at (0.95, 0.2 lam_c)
        # the 16-mode level stopped at a 5e-2 step and the 24-mode curve on its density had no
        # positive volume) gives way to the seed's density, and a first level whose seed
        # density fails (the "bend" density of the lubrication shape at (0.85, 0.2 lam_c): a
        # curve c_1 cannot close) starts on uniform arc length (None: made when needed)
        seeds = [prev, None] if not levels and np.size(prev.density) else [prev]
        if rebuild is not None and rebuild < i <= rebuild + rebuilds and levels:
            # the density re-built on the BEM shape of the level before (it resolves what the
            # seed's density misses, e.g. a long vesicle's rear film neck)
            try:
                seeds = [fit_curve(prev.sample, 0.0, 1.0, n,
                                   density=DENSITIES[rebuilt](prev, density_terms)), prev]
                consistent = len(levels)
            except InvalidParameterError:
                pass
        # a carrier starts from a fresh difference Jacobian: one prolonged from the (unfinished)
        # level below led the cold start of (0.6, 1.94) to Δp⁺ 2829 at 32 modes (1778 converged)
        carrier = rebuild is not None and valley and i < rebuild
        st = rejected = None
        for k, seed in enumerate(seeds):
            if k:
                log.info("solve_vesicle: density rejected at %d modes (%s)", n, rejected)
                consistent = 0
            as_carrier = carrier and not k
            try:
                st, op, info = solve_level(
                    nu, lam, ca_b, disc, fit_curve(prev.sample, 0.0, 1.0, n) if seed is None
                    else seed, n, xtol=xtol, max_iter=max_iter, seed_level=not levels,
                    valley=valley, carrier=as_carrier, deadline=deadline,
                    coarse=(levels[-1][1], levels[-1][0]) if levels and not as_carrier else None)
                break
            except InvalidParameterError as exc:
                rejected = exc
        if st is None:
            # no seed of this level could start: the solve's start if it is the first level
            status = Status.NOT_CONVERGED if levels else Status.REJECTED_START
            message = f"level with {n} modes: {rejected}"
            break
        timings[f"modes{n}_s"] = time.perf_counter() - t0
        iterations[f"modes{n}"] = info
        out = level_outputs(nu, lam, op, st)
        levels.append((st, op, out))
        log.info("solve_vesicle nu=%g lam=%g modes=%d: V/U=%.10f dp+R0=%.8g gmax=%.6g "
                 "residual %.2e (%s)", nu, lam, n, out["V_over_U"], out["dp_plus_R0"],
                 out["tension_max"], out["residual"], info["message"])
        if not info["success"]:
            if deadline.expired():
                status = Status.TIME_LIMIT
                message = f"{deadline.message()} (in the level with {n} modes)"
                break
            if n == sequence[-1]:
                status = Status.NOT_CONVERGED
                message = f"Levenberg–Marquardt failed with {n} modes: {info['message']}"
                break
            # a coarser level only seeds the next one, which is judged on its own (residual,
            # refinement pair): an unfinished coarse level is not a failure of the solve
            log.info("solve_vesicle: level with %d modes unfinished (%s); refining", n,
                     info["message"])
        prev = st["curve"]
        err = _error_estimate([lv[2] for lv in levels[consistent:]])
        if (len(levels) - consistent >= (2 if n_modes is not None else 3)
                and _within(err, levels[-1][2], tol, tension_tol)
                and levels[-1][2]["residual"] <= residual_tol):
            break
    timings["total_s"] = time.perf_counter() - t_start
    if not levels and bem_seed and not continuation and not deadline.expired():
        # a continued shape that cannot start at this lam (its volume re-imposed, the film of
        # (0.98, 0.95 lam_c) closed at 0.98 lam_c): the solver's own seed and continuation
        log.info("solve_vesicle: the given initial shape was rejected (%s); own seed", message)
        left = None if max_time is None else max_time - (time.monotonic() - clock)
        if left is None or left > 0.0:
            return solve_from(case, None, dataclasses.replace(options, continuation=None), left)
    if not levels:
        return VesicleResult(nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=status,
                             message=message, tol=tol, residual_tol=residual_tol,
                             iterations=iterations, timings=timings)
    st, op, fine = levels[-1]
    err = _error_estimate([lv[2] for lv in levels[consistent:]])
    curve = st["curve"]
    prof = membrane_profile(curve, st["g"])
    # every problem is named; the status is the leading one (lubrication.results.PRECEDENCE)
    problems, found = ([message], [status]) if message else ([], [])
    if self_intersects(prof["x"], prof["r"]):
        problems.append("the membrane self-intersects")
        found.append(Status.NO_STEADY_STATE)
    if fine["film_min"] < 1e-3:
        problems.append(f"the film closes (min gap {fine['film_min']:.2e} R)")
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
    status = leading_status(found)
    success = status is Status.CONVERGED
    message = ("; ".join(problems) if problems else
               f"converged: {fine['panels']['modes']} modes, estimated errors "
               + ", ".join(f"{k} {err[k]:.1e}" for k in ESTIMATED_OUTPUTS)
               + f", residual {fine['residual']:.1e}")
    if not success:              # one start of the pipeline: solve_vesicle reports the outcome
        log.info("solve_vesicle start (nu=%g, lam=%g): %s", nu, lam, message)
    try:
        wall_x, wall_shear = op.wall_shear(curve, st["g"])
        wall_x = wall_x - curve.position(np.array([0.0]))[0][0]    # from the rear pole
    except InvalidParameterError:                     # a shape touching the wall
        wall_x = wall_shear = np.empty(0)
    k_rear = curve.curvatures(np.array([0.0]))[0][0]
    k_front = curve.curvatures(np.array([1.0]))[0][0]
    parachute = bool(k_rear < 0.0 or np.min(prof["x"]) < prof["x"][0] - 1e-12)
    history = [(lv[2]["panels"]["modes"], lv[2]["residual"], lv[2]["V_over_U"],
                lv[2]["dp_plus_R0"], lv[2]["tension_max"]) for lv in levels]
    return VesicleResult(
        nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=status, message=message,
        V_over_U=fine["V_over_U"], dp_plus_R0=fine["dp_plus_R0"], dp_plus_R=fine["dp_plus_R"],
        ell=fine["ell"], ell_poles=fine["ell_poles"], film_min=fine["film_min"],
        tension_max=fine["tension_max"],
        wall_shear_max=float(np.max(wall_shear)) if wall_shear.size else math.nan,
        wall_x=wall_x, wall_shear=wall_shear,
        tension_rear=float(prof["tension"][0]), tension_front=float(prof["tension"][-1]),
        curvature_rear=-float(k_rear), curvature_front=-float(k_front),
        shape_class="parachute" if parachute else "bullet", error_estimate=err,
        volume_error=fine["volume_error"], area_error=fine["area_error"],
        residual=fine["residual"], tol=tol, residual_tol=residual_tol, panels=fine["panels"],
        refinement=history, seed=seed_source, iterations=iterations, timings=timings,
        modes=curve.modes.copy(), density=np.asarray(curve.density).copy(),
        tension_modes=np.asarray(st["g"]).copy(), **prof)
