r"""The pipeline of :func:`~bem.vesicle.solve_vesicle`: the starts tried in turn, and the probe for
a second steady state.

A steady vesicle shape changes smoothly with (ν, λ/λc, Ca_B) along a branch, so a converged
shape at a nearby point lies inside the basin of the Levenberg–Marquardt solve where a shape
built from a model may not (:mod:`bem.seed_bank`: at moderate confinement, λ/λc ≈ 0.3–0.65 and
ν ≤ 0.89, the model seeds end in non-steady least-squares minima at about one random point in
five). Without ``initial`` the starts are the nearest converged shapes of the seed bank
(:data:`BANK_STARTS` within :data:`BANK_REACH`) and the solver's own seed (the lubrication
shape, continuation in λ/λc near lam_c: :mod:`bem.vesicle.seeds`, :mod:`bem.vesicle.ladder`),
the bank first below :data:`~bem.vesicle.seeds.NEAR_CRITICAL` and last above it
(:func:`_starts`). Each start is refined by the mode ladder with its error estimate
(:func:`bem.vesicle.ladder.solve_from`); the first that converges is returned, with the
reasons of the starts that failed before it. A stored shape that cannot start here (its modes
do not close at this point) is a failed start; the own seed or a given ``initial`` that cannot
start raises.

Where no start converges because they stall in non-steady least-squares minima (a steady
residual above its tolerance), the two failed shapes with the smallest residual (or one and the
nearest stored shape) are relaxed in time (:func:`bem.vesicle_dynamics.relax_vesicle`,
:data:`RELAX_MODES` modes, at most :data:`RELAX_TIME` R/U each), and the ladder refines each
relaxed shape in turn. The relaxation both reaches steady states the starts missed (at
(0.6449, 0.281 λc, 43.9) without the seed bank: the spheroid's minimum, residual 7e-3, relaxed
for 20 R/U and refined to the parachute the stored shape reaches directly, V/U equal to 2e-9)
and is the evidence where none is found: the result then says what each relaxation did
(max|u·n − V n_x| and V/U from start to end), NO_STEADY_STATE where both kept changing without
settling, NOT_CONVERGED where one was still approaching a state the ladder did not reach. A
start that failed on resolution only (UNRESOLVED: its residual passed) or a mode count fixed by
the caller is reported as it is.

A converged point below :data:`~bem.vesicle.seeds.NEAR_CRITICAL` is then probed for a second
steady state (:func:`_other_branch`; :data:`BRANCH_REACH` says why not above): the nearest
stored shape of the other shape class within :data:`BRANCH_REACH`, solved in turn; where it
converges to that class the point is bistable, and the result says so (``other_branch``, the
message). ``branch`` asks for one class (only stored shapes of that class are tried, and a
solve ending in the other class does not count); ``seed_bank=False`` tries the own seed only.

A red cell (``ca_s`` finite: the membrane's shear elasticity, :mod:`bem.shear`) is also reached
by continuation along its velocity (:func:`_velocity_continuation`): the same cell faster, at
Ca_S = :data:`SHEAR_START` where shear is a modest correction and the starts (the stored shapes
are vesicles') converge, then slowed down step by step at fixed β = Ca_B/Ca_S to the case's
velocity, the last solve allowed up to MAX_MODES like a stored shape's (:func:`branch_modes`).
It is the physical path (a cell slowing down), and below :data:`VELOCITY_FIRST` it is tried
before the direct starts: there the stored vesicle shapes lie far from the cell's own and end
in compressed, self-equilibrated states (:mod:`bem.vesicle.ladder`) or stall (on the red-cell
slice at 0.1 mm/s, 20 of 40 points converged from them; continued from 0.2 mm/s the same
points converge at 32 modes in about a second). Neither the time relaxation (its time-dependent
solver has no shear elasticity) nor the probe for a second branch is run for a red cell.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections.abc import Callable

from lubrication.checks import Deadline, InvalidParameterError
from lubrication.results import Status, leading_status

from ..quadrature import DEFAULT_ORDER
from ..results import VesicleResult
from ..seed_bank import SHAPE_CLASSES, load_seed_bank
from ..shape import fit_curve
from ..threads import single_threaded_blas
from .inputs import CA_B_MAX, MAX_MODES, VesicleInputs, check_vesicle_inputs
from .ladder import (
    RUNG_RESIDUAL_TOL,
    RUNG_TENSION_TOL,
    RUNG_TOL,
    LadderOptions,
    solve_from,
)
from .operator import VesicleOperator, vesicle_discretisation
from .seeds import NEAR_CRITICAL

__all__ = ["BANK_REACH", "BANK_STARTS", "BRANCH_REACH", "solve_vesicle"]

log = logging.getLogger(__name__)

#: Reach of the seed bank: stored shapes farther than this (module distance of
#: :mod:`bem.seed_bank`, about one build grid step per unit) are not tried as starts.
BANK_REACH = 3.0
#: Stored shapes tried as starts, nearest first.
BANK_STARTS = 2
#: A stored shape of the other shape class within this distance is tried once the solve has
#: converged: where it converges to that class too, the point is bistable. Only below
#: NEAR_CRITICAL: over 200 random points of the domain the second branch was found at
#: λ/λc 0.20–0.48 only (docs/data/vesicle_domain*.json), while the probe of a point near λc,
#: a long shape, cost 4–10 s that found nothing ((0.7, 0.95 λc) 8.2 → 12.7 s, (0.6, 1.94)
#: 30 → 40 s).
BRANCH_REACH = 1.5
#: Modes of the coarse probe of the other branch (a single pair, PROBE_MODES and 2/3 of it):
#: enough to tell a steady state of the other class (residual ~1e-5, 32 modes at
#: (0.8, 0.3 λc, 35)) from a stored shape that leaves its class or stalls, at ~1 s, where a
#: full ladder from a shape that does not converge climbs to its last level (10–50 s measured
#: on the domain benchmark).
PROBE_MODES = 32
#: The time relaxation that follows when no start converged: modes, and the time [R/U] each
#: of its two seeds is relaxed for at most (measured at (0.6449, 0.281 λc, 43.9) from a
#: spheroid, 16 modes: 290 BEM evaluations, 18 s on 2 cores, for 10 R/U, the speed still
#: drifting by 1e-2 per R/U towards the parachute's).
RELAX_MODES = 16
RELAX_TIME = 20.0
#: A relaxation is still approaching a steady state where max|u·n − V n_x| at its end is
#: below this fraction of its largest value over the second half of the run (it decays, as
#: towards the parachute of (0.6449, 0.281 λc, 43.9): 1.7e-1 -> 9.2e-2 over 20 R/U).
RELAX_APPROACH = 0.8
#: Continuation of a red cell along its velocity (:func:`_velocity_continuation`): the Ca_S of
#: its first rung (a cell of Ca_S at least this is solved from the vesicle at its Ca_B instead)
#: and the factor between rungs. At Ca_S = 1 the shear tensions G_s f are a fraction of the
#: flow's: at (0.61, 0.7 λc, Ca_B 50, Ca_S 0.2) the tension difference f reaches 2.5
#: (λ_φ² = 0.19) against an isotropic tension of about 36 ηU.
SHEAR_START = 1.0
SHEAR_FACTOR = 3.0
#: A rung that fails is retried at the geometric middle of its step, at most this many times
#: in a row (no measurement recorded).
SHEAR_BISECTIONS = 3
#: Ca_S below which the continuation along the velocity is tried before the direct starts:
#: stored vesicle shapes ended in compressed states at Ca_S 0.02-0.1 on the red-cell slice
#: (module docstring); at Ca_S 0.2 and above none did.
VELOCITY_FIRST = 0.15


#: Top of the ladder of a vesicle started from a shape on a steady branch (a stored shape), where
#: the case leaves ``max_modes`` to the solver: 200 random points of the vesicle domain
#: converged within it (docs/data/vesicle_domain*.json), and a start stalled in a non-steady
#: minimum climbs the whole ladder before the next start is tried.
VESICLE_BRANCH_MODES = 96


def branch_modes(red_cell: bool) -> int:
    """Top of the ladder from a shape on a steady branch (a stored shape, a red cell's own start
    or faster self, also in the map build): :data:`VESICLE_BRANCH_MODES` for a vesicle;
    MAX_MODES for a red cell, which converges more slowly in modes where slow and confined (its
    shear load: at 0.03–0.06 mm/s and λ/λc 0.6–0.9 on the red-cell slice, 104–152 modes,
    docs/vesicle-solver.md)."""
    return MAX_MODES if red_cell else VESICLE_BRANCH_MODES


@dataclasses.dataclass(frozen=True)
class Start:
    """One start of the pipeline: its ``label``, ``make()`` -> the initial shape (None: the
    solver's own seed), the ``inputs`` its ladder runs with, and ``own`` (a start whose failure
    to begin is the caller's error, not a failed start)."""

    label: str
    make: Callable
    inputs: VesicleInputs
    own: bool = False


def _starts(case: VesicleInputs, initial, branch: str | None, seed_bank: bool) -> list[Start]:
    """The starts of :func:`~bem.vesicle.solve_vesicle` in the order tried (module docstring).
    A stored shape's ladder may climb to :func:`branch_modes` where the case leaves
    ``max_modes`` to the solver: its shape is on a steady branch, so an estimate still above
    the tolerance at the own seed's default cap (80) is resolution, not a spurious minimum
    (measured at (0.6267, 0.7517 λc, Ca_B 439): unresolved at 80 modes, V/U estimate 1.1e-4;
    converged at 88, 46 s). A red cell's own start may too: it converges more slowly in modes
    than a vesicle (docs/vesicle-solver.md), e.g. (0.5641, 0.319 λc, Ca_B 388.5, Ca_S 0.146) was
    unresolved at its cap (Δp⁺ estimate 1.4e-4) and converges at 88 modes."""
    if initial is not None:
        return [Start("initial", lambda: initial, case, own=True)]
    deeper = (dataclasses.replace(case, max_modes=branch_modes(case.shear is not None))
              if case.max_modes is None and case.n_modes is None else case)
    own = [Start("own", lambda: None, deeper if case.shear is not None else case, own=True)]
    if not seed_bank:
        return own
    ratio = case.lam_ratio
    bank = [Start(seed.label(), lambda seed=seed: seed.curve(case.lam), deeper)
            for seed in load_seed_bank().nearest(case.nu, ratio, case.ca_b, k=BANK_STARTS,
                                                 shape_class=branch, within=BANK_REACH)]
    return own + bank if ratio > NEAR_CRITICAL else bank + own


def _other_branch(case: VesicleInputs, res: VesicleResult, solve) -> dict:
    """The steady state of the other shape class at this point, if a stored shape of that
    class within BRANCH_REACH converges to it: its class and outputs, else {}. The stored shape
    is first solved as a single coarse pair (:data:`PROBE_MODES`, loose error tolerance, the
    case's residual tolerance), which decides whether it stays a steady state of its class; only
    then is it refined by the ladder to the case's tolerances."""
    other = "bullet" if res.shape_class == "parachute" else "parachute"
    near = load_seed_bank().nearest(case.nu, case.lam_ratio, case.ca_b,
                                    shape_class=other, within=BRANCH_REACH)
    if not near:
        return {}
    try:
        probe = solve(near[0].curve(case.lam), dataclasses.replace(
            case, n_modes=PROBE_MODES, max_modes=None, tol=0.5, tension_tol=0.5))
    except InvalidParameterError:
        return {}
    if not (probe.success and probe.shape_class == other):
        return {}
    alt = solve(probe, case)
    if not (alt.success and alt.shape_class == other):
        return {}
    return {"shape_class": other, "seed": near[0].label(),
            **{k: getattr(alt, k) for k in ("V_over_U", "dp_plus_R0", "ell", "film_min")}}


def _relax(case: VesicleInputs, label: str, curve, budget: float | None) -> dict:
    """Relax ``curve`` in time (:func:`bem.vesicle_dynamics.relax_vesicle`, RELAX_MODES modes on
    the curve's density) for at most RELAX_TIME R/U or until max|u·n − V n_x| < the case's
    residual tolerance. Returns the evidence: ``label``, the final ``curve`` (None if the membrane
    became invalid), time ``t`` [R/U], ``max_un`` and ``V`` at the start and the end,
    ``approaching`` (:data:`RELAX_APPROACH`), ``failure``, ``evaluations``."""
    from ..vesicle_dynamics import relax_vesicle  # lazy: it imports bem.vesicle (a cycle)
    try:
        reference = fit_curve(curve.sample, 0.0, 1.0, RELAX_MODES, density=curve.density)
        op = VesicleOperator(case.nu, case.lam, case.ca_b,
                             vesicle_discretisation(RELAX_MODES), reference)
        _, flow, info = relax_vesicle(op, reference.modes, RELAX_TIME,
                                          tol=case.residual_tol, max_time=budget)
    except InvalidParameterError as exc:          # the shape cannot start a relaxation
        return {"label": label, "curve": None, "t": 0.0, "approaching": False,
                "max_un": (math.nan, math.nan), "V": (math.nan, math.nan),
                "failure": f"cannot be relaxed ({exc})", "evaluations": 0}
    history = info["history"]
    (_, un0, v0), (t, un1, v1) = history[0], history[-1]
    half = [un for tt, un, _ in history if tt >= 0.5 * t]
    return {"label": label, "curve": None if info["failure"] else flow.curve, "t": t,
            "approaching": bool(un1 < RELAX_APPROACH * max(half, default=un1)),
            "max_un": (un0, un1), "V": (v0, v1), "failure": info["failure"],
            "evaluations": info["evaluations"]}


def _evidence(r: dict) -> str:
    """One clause of the diagnosis: what a relaxation did."""
    if r["failure"]:
        return f"from {r['label']}: {r['failure']}"
    return (f"from {r['label']}: after {r['t']:.3g} R/U max|u.n - V n_x| {r['max_un'][0]:.1e} -> "
            f"{r['max_un'][1]:.1e}, V/U {r['V'][0]:.5g} -> {r['V'][1]:.5g}")


def _first_converged(starts: list[Start], solve, branch: str | None, deadline) -> tuple:
    """Try the starts in turn. Returns (the first converged result of the asked ``branch`` or
    None, the label of its start, the failed starts as (label, reason, result or None))."""
    failed = []
    for start in starts:
        if deadline.expired():
            failed.append((start.label, f"not tried, {deadline.message()}", None))
            break
        try:
            res = solve(start.make(), start.inputs)
        except InvalidParameterError as exc:
            if start.own:
                raise
            failed.append((start.label, f"cannot start ({exc})", None))  # modes do not close
            continue
        if res.success and branch not in (None, res.shape_class):
            failed.append((start.label, f"converged to a {res.shape_class}, not a {branch}",
                           None))
        elif res.success:
            return res, (res.seed if start.own else start.label), failed
        else:
            failed.append((start.label, res.message, res))
    return None, "", failed


def _velocity_continuation(case: VesicleInputs, seed_bank: bool, solve, branch: str | None,
                           deadline) -> tuple:
    """A red cell reached along its velocity: its first rung solved from the starts of
    :func:`_starts` at the rung, then rungs at Ca_S / :data:`SHEAR_FACTOR` each, Ca_B in proportion
    (the same cell slower), each a coarse ``rung_modes`` pair at the rungs' loose tolerances
    from the one before (a failed rung is retried at the middle of its step,
    :data:`SHEAR_BISECTIONS` times at most), the last refined by the ladder at the case. The
    first rung is the cell at Ca_S = :data:`SHEAR_START` if the case is slower (its Ca_B
    capped at CA_B_MAX), else the vesicle at the case's Ca_B. Returns (result or None, the label
    of its start, the reason it failed)."""
    if case.ca_s < SHEAR_START:
        k = min(SHEAR_START / case.ca_s, CA_B_MAX / case.ca_b)
        first, what = dataclasses.replace(case, ca_b=case.ca_b * k, ca_s=case.ca_s * k), \
            "the cell faster"
    else:
        k, first, what = 1.0, dataclasses.replace(case, ca_s=math.inf), "the vesicle"
    res, label, failed = _first_converged(_starts(first, None, branch, seed_bank), solve,
                                          branch, deadline)
    if res is None:
        return None, "", (f"continuation along the velocity: {what} (Ca_B {first.ca_b:.4g}, "
                          f"Ca_S {first.ca_s:.3g}) has no steady state from the starts ("
                          + "; ".join(f"{lab}: {why}" for lab, why, _ in failed) + ")")
    rung = dataclasses.replace(case, n_modes=case.rung_modes, max_modes=None, tol=RUNG_TOL,
                               tension_tol=RUNG_TENSION_TOL, residual_tol=RUNG_RESIDUAL_TOL)
    path, at, factor, misses = [k], k, SHEAR_FACTOR, 0
    while at / factor > 1.0 + 1e-12:       # the last step, to the case, is the final solve
        if deadline.expired():
            return None, "", (f"continuation along the velocity: {deadline.message()} at "
                              f"Ca_S = {case.ca_s * at:.3g}")
        nxt_at = at / factor
        nxt = solve(res, dataclasses.replace(rung, ca_b=case.ca_b * nxt_at,
                                             ca_s=case.ca_s * nxt_at))
        if nxt.modes.size == 0 or nxt.status is Status.NO_STEADY_STATE:
            if misses == SHEAR_BISECTIONS:
                return None, "", (f"continuation along the velocity failed at Ca_S = "
                                  f"{case.ca_s * nxt_at:.3g}: {nxt.message}")
            factor, misses = factor ** 0.5, misses + 1
            continue
        res, at, factor, misses = nxt, nxt_at, SHEAR_FACTOR, 0
        path.append(at)
    # the continued shape is on a steady branch: as for a stored shape, an estimate still above
    # the tolerance at the default cap is resolution, so the ladder may climb further
    final = solve(res, dataclasses.replace(case, max_modes=branch_modes(case.shear is not None))
                  if case.max_modes is None and case.n_modes is None else case)
    rungs = ", ".join(f"{case.ca_s * a:.3g}" for a in path)
    if final.success and branch in (None, final.shape_class):
        return final, f"continuation along the velocity (Ca_S {rungs}) from {what} of {label}", ""
    return None, "", f"continuation along the velocity (Ca_S {rungs}): {final.message}"


def _by_residual(res: VesicleResult) -> float:
    """Rank of a failed start's result: its steady residual (NaN last)."""
    return res.residual if math.isfinite(res.residual) else math.inf


def _relaxation_seeds(case: VesicleInputs, failed: list, seed_bank: bool) -> list:
    """Two seeds of the time relaxation, as (label, curve): the final shapes of the two failed
    starts with the smallest steady residual, or, with one only, it and the nearest stored
    shape (with ``seed_bank``)."""
    ranked = sorted(((lab, r) for lab, _, r in failed if r is not None and r.modes.size),
                    key=lambda x: _by_residual(x[1]))
    seeds = [(f"the last shape of start {lab}", r.curve()) for lab, r in ranked[:2]]
    if len(seeds) < 2 and seed_bank:
        near = load_seed_bank().nearest(case.nu, case.lam_ratio, case.ca_b)
        seeds += [(s.label(), s.curve(case.lam)) for s in near]
    return seeds[:2]


def _diagnosis(evidence: list[dict], deadline) -> tuple[Status, str]:
    """Status and text of a point where neither the starts nor the relaxation converged."""
    said = "; ".join(_evidence(r) for r in evidence)
    if deadline.expired():
        return Status.TIME_LIMIT, f"{deadline.message()} in the time relaxation ({said})"
    if evidence and all(r["failure"] for r in evidence):
        return Status.NO_STEADY_STATE, f"no steady state: relaxed in time, the membrane {said}"
    if any(r["curve"] is not None and r["approaching"] for r in evidence):
        return (Status.NOT_CONVERGED, "not converged: a relaxation in time was still "
                f"approaching a steady state, which the ladder from its shape did not reach "
                f"({said})")
    return (Status.NO_STEADY_STATE, f"no steady state reached: relaxed in time from "
            f"{len(evidence)} seeds for up to {RELAX_TIME:g} R/U each, the shape still "
            f"changing and not settling ({said})")


@single_threaded_blas()      # small dense products between numba loops (bem.threads)
def solve_vesicle(nu: float, lam: float | None = None, *, lam_ratio: float | None = None,
                  ca_b: float = 50.0, initial=None, branch: str | None = None,
                  seed_bank: bool = True, n_modes: int | None = None,
                  tol: float = 1e-4, tension_tol: float = 1e-2, residual_tol: float = 1e-3,
                  max_modes: int | None = None,
                  order: int = DEFAULT_ORDER, xtol: float = 1e-9, max_iter: int = 40,
                  density: str = "auto", density_terms: int = 16,
                  continuation: bool | None = None, rung_modes: int = 32,
                  valley: bool | None = None, max_time: float | None = None,
                  ca_s: float | None = None, reference: str = "biconcave"):
    r"""Steady vesicle (inextensible bending membrane, viscosity ratio 1) on the tube axis.

    The pipeline (docs/vesicle-solver.md): without ``initial``, the starts are the nearest
    converged shapes of the seed bank (:mod:`bem.seed_bank`, ``BANK_STARTS`` within
    ``BANK_REACH``) and the solver's own seed (the lubrication shape, continuation in λ/λc near
    lam_c), the bank first below ``NEAR_CRITICAL`` and last above it; each start is refined by
    the mode ladder with its error estimate, and the first that converges is returned. A
    converged point below ``NEAR_CRITICAL`` is then probed for a second steady state: the
    nearest stored shape of the other shape class within ``BRANCH_REACH``, solved in turn;
    where it converges to that class the point is bistable, and the result says so
    (``other_branch``, the message). Where no
    start converges, their shapes are relaxed in time and refined again, and what the
    relaxations did is the diagnosis of a point that still fails (module docstring).

    Parameters
    ----------
    nu : float
        Reduced volume, 0 < nu < 1 [-].
    lam, lam_ratio : float
        Confinement R0/R, or lam/lam_c; exactly one, 0 < lam < lam_c(nu) [-].
    ca_b : float
        Bending capillary number ηUR0²/κ (Chen et al. 2020 use 50), CA_B_MIN = 1e-2 <= ca_b
        <= CA_B_MAX = 1e5 [-].
    initial : VesicleResult, SpectralCurve or LubricationResult, optional
        Initial shape, the only start tried. Default: the pipeline's starts (above); the
        solver's own seed among them is the lubrication solution at the same parameters, else
        a prolate spheroid of the right nu.
    n_modes : int, optional
        Shape modes of the fine level of a single refinement pair (round(2n/3), n), both on
        the seed's density; its error estimate is the pair difference. Default: the automatic
        ladder (:mod:`bem.vesicle.ladder`): levels 16, 24, ... up to
        ``max_modes``, the density re-built once on a BEM minimum, stopped when three levels
        on that density give an estimated error within ``tol`` (V/U, Δp⁺) and ``tension_tol``
        (γ_max) and the residual is below ``residual_tol``. Default ``max_modes``: 80, or for
        a long vesicle 40 more than the level whose shape re-builds the density (about 6
        modes per tube radius of its estimated length ℓ ≈ ℓc λ/λc, Chen et al. 2020 eq. sL,
        minus 16), 48 more near lam_c where the density is re-built twice (96 at
        (0.6, 0.98 λc)); at most MAX_MODES.
    tol, tension_tol : float
        Relative tolerances of the estimated discretisation error of V/U and Δp⁺, and of
        γ_max (a peak value of the tension, which converges more slowly: at (0.6, 1.94) its
        72-mode error is 4e-3 while V/U's is 3e-5).
    residual_tol : float
        Tolerance of the steady residual max|u − V e_x| of the fine level [U]. The default
        1e-3 is a test of steadiness, not of accuracy (the error estimate is): the genuine
        steady states measured have 1e-7–8e-4 at their converged level, the spurious
        least-squares minima 1.2e-2–2.1e-2 at every mode count.
    order : int
        Gauss nodes per panel.
    xtol, max_iter : float, int
        Relative step tolerance and iteration budget of each Levenberg–Marquardt level
        (:func:`bem.newton.levenberg_marquardt`; it also stops at the residual floor).
    density : {"auto", "uniform", "curvature", "bend", "film"}
        Arc-length density of the shape parametrisation (and hence of modes and panels):
        uniform; built from the seed's curvature (:func:`bem.shape.equidistributing_density`,
        concentrates on sharp bends); or from the lubrication weight (h + h_min)^(-1/2) of the
        gap h = 1 - r (:func:`bem.shape.film_density`, concentrates on the thin film and its
        entrance/exit); or "bend", the curvature density with a curvature-gradient term
        (``equidistributing_density(..., gradient=1)``, concentrates also on the ends of the
        film of a long vesicle, where a cap meets the cylindrical body). "auto" (default):
        "film" for lam/lam_c >= NEAR_CRITICAL (0.9) unless the vesicle is long (estimated
        ℓ ≈ ℓc λ/λc > LONG_VESICLE = 5), else "bend". With ``initial`` a curve or a
        VesicleResult, the density is re-built on that shape: re-solving a long vesicle from
        its own result (``initial=result, n_modes=...``) resolves it better than the density
        of the lubrication seed (at (0.6, 1.94), 64 modes: residual 8.2e-4 instead of 2.7e-3).
    density_terms : int
        Cosine terms of that density (ignored for "uniform").
    continuation : bool, optional
        Reach lam/lam_c > NEAR_CRITICAL through rungs 1 - lam/lam_c = 0.1, 0.05, 0.025, ...
        (each a ``rung_modes`` solve started from the previous one, the first from
        lubrication); a cold start from the lubrication shape there can drift to a spurious,
        closing film. Default: on when ``initial`` is None, lam/lam_c > NEAR_CRITICAL and the
        estimated length is at most RUNG_MAX_LENGTH = 9 R (a longer one, ν ≈ 0.6 near lam_c,
        is led astray by the rungs and converges from the lubrication shape at its own λ).
    rung_modes : int
        Shape modes of each continuation rung.
    valley : bool, optional
        Solve each level with :func:`bem.newton.valley_levenberg_marquardt` (directional
        Jacobian updates and extrapolation along the slow cap-to-cap mode) instead of
        :func:`bem.newton.levenberg_marquardt`. Default: on for a long vesicle, whose plain
        solve stops far from the minimum (at (0.6, 1.94): γ_max 799 instead of 932).
    max_time : float, optional
        Wall-time budget [s] (:class:`lubrication.checks.Deadline`), tested between BEM
        evaluations, levels and continuation rungs; when spent the result has status
        TIME_LIMIT. Default: no limit. Mode counts are at most MAX_MODES = 160.
    branch : {"parachute", "bullet"}, optional
        Shape class to return where two steady states coexist: only stored shapes of that
        class are tried as starts, and a solve that ends in the other class does not count as
        converged. Default: the state reached from the nearest stored shape.
    seed_bank : bool
        Try the seed bank's shapes (default). False: the solver's own seed only, a solve that
        depends on no stored solution.
    ca_s : float, optional
        Shear capillary number ηU/G_s of a red-cell membrane (:mod:`bem.shear`; the spectrin
        network's in-plane shear elasticity, Evans 1973, about 0.2 at 1 mm/s for
        G_s = 6 µN/m): :data:`~bem.vesicle.CA_S_RANGE` = 1e-3 <= ca_s <= 1e4. Default
        None: a vesicle (no shear elasticity). A red cell is solved from the same starts and by
        continuation along its velocity (:func:`_velocity_continuation`; first below
        Ca_S = VELOCITY_FIRST, else where no start converges); neither the time relaxation
        nor the probe for a second branch is run for it.
    reference : {"biconcave", "spheroid"}
        Stress-free shape of a red-cell membrane (:func:`lubrication.membrane.reference_shape`;
        the biconcave disc needs nu <= 0.743).

    Returns
    -------
    VesicleResult
        ``status`` and the reason in ``message``: NO_STEADY_STATE when the membrane
        self-intersects or the film closes, TIME_LIMIT, NOT_CONVERGED when Levenberg–Marquardt
        or the steady residual fell short, UNRESOLVED when the estimated discretisation error
        is above the tolerance (of several, the first in this order), REJECTED_START when no
        level could start from its seed.

    Raises
    ------
    InvalidParameterError, CannotPassError
        Bad input; lam >= lam_c(nu).
    """
    case = check_vesicle_inputs(
        nu, lam, lam_ratio=lam_ratio, ca_b=ca_b, n_modes=n_modes, tol=tol,
        tension_tol=tension_tol, residual_tol=residual_tol, max_modes=max_modes,
        rung_modes=rung_modes, density_terms=density_terms, max_iter=max_iter,
        max_time=max_time, ca_s=ca_s, reference=reference)
    nu, lam, lam_c, ca_b = case.nu, case.lam, case.lam_c, case.ca_b
    red_cell = case.shear is not None
    if branch is not None and branch not in SHAPE_CLASSES:
        raise InvalidParameterError("branch", branch, '"parachute", "bullet" or None')
    t_start = time.perf_counter()
    deadline = Deadline(max_time)
    # a stored, probed or relaxed shape that cannot start is a failed start: the pipeline
    # tries the own seed itself (once, under its own label)
    options = LadderOptions(order=order, xtol=xtol, density=density, continuation=continuation,
                            valley=valley, own_seed_fallback=initial is not None)

    def solve(start, inputs=case):
        return solve_from(inputs, start, options, deadline.remaining())

    def done(res: VesicleResult, **changes) -> VesicleResult:
        timings = {**res.timings, "total_s": time.perf_counter() - t_start}
        return dataclasses.replace(res, timings=timings, **changes)

    starts = _starts(case, initial, branch, seed_bank)
    # a red cell's continuation along the velocity: before the starts when slow, else after
    along = red_cell and initial is None
    first = along and case.ca_s < VELOCITY_FIRST
    res, failures, failed = None, [], []
    if first:
        res, label, why = _velocity_continuation(case, seed_bank, solve, branch, deadline)
        if res is None:
            failures.append(why)
    if res is None:
        res, label, failed = _first_converged(starts, solve, branch, deadline)
        failures += [f"{lab}: {why}" for lab, why, _ in failed]
    if res is None and along and not first and not deadline.expired():
        res, label, why = _velocity_continuation(case, seed_bank, solve, branch, deadline)
        if res is None:
            failures.append(why)
    if res is not None:
        other = ({} if branch or initial is not None or not seed_bank or deadline.expired()
                 or red_cell or case.lam_ratio > NEAR_CRITICAL
                 else _other_branch(case, res, solve))
        message = res.message
        if other:
            message += (f"; bistable: a {other['shape_class']} steady state also exists "
                        f"here (V/U {other['V_over_U']:.6g}), ask for it with "
                        f"branch={other['shape_class']!r}")
        return done(res, seed=label, other_branch=other, message=message,
                    failed_starts=failures)
    best = min((r for _, _, r in failed if r is not None), default=None, key=_by_residual)
    # the time relaxation is for starts stalled in non-steady minima; a start whose residual
    # passed but whose estimate did not (UNRESOLVED) or a mode count fixed by the caller is a
    # question of resolution, which relaxing at RELAX_MODES cannot answer
    if (initial is not None or case.n_modes is not None or deadline.expired() or best is None
            or best.status is Status.UNRESOLVED or red_cell):
        status = leading_status([r.status if r is not None else Status.REJECTED_START
                                 for _, _, r in failed]) if failed else Status.REJECTED_START
        message = "; ".join(failures) if failures else "no start"
        log.warning("solve_vesicle(nu=%g, lam=%g): %s", nu, lam, message)
        if best is None:
            return VesicleResult(nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, **case.membrane,
                                 status=status, message=message, tol=case.tol,
                                 residual_tol=case.residual_tol,
                                 timings={"total_s": time.perf_counter() - t_start})
        return done(best, status=status, message=message, failed_starts=failures)
    # no start converged: relaxation in time from two seeds, which either reaches a steady
    # state (the ladder then refines it) or is the evidence that none was found
    evidence = []
    for seed_label, curve in _relaxation_seeds(case, failed, seed_bank):
        r = _relax(case, seed_label, curve, deadline.remaining())
        evidence.append(r)
        if r["curve"] is None or deadline.expired():
            continue
        res = solve(r["curve"])
        if res.success and branch in (None, res.shape_class):
            return done(res, seed=f"time relaxation ({_evidence(r)})", failed_starts=failures)
        failures.append(f"time relaxation from {seed_label}: {res.message}")
    status, diagnosis = _diagnosis(evidence, deadline)
    message = diagnosis + "; the starts: " + "; ".join(failures)
    log.warning("solve_vesicle(nu=%g, lam=%g): %s", nu, lam, message)
    iterations = {**best.iterations, **{f"relaxation from {r['label']}": {
        k: r[k] for k in ("t", "max_un", "V", "approaching", "failure", "evaluations")}
        for r in evidence}}
    return done(best, status=status, message=message, failed_starts=failures,
                iterations=iterations)
