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

A converged point is then probed for a second steady state (:func:`_other_branch`): the nearest
stored shape of the other shape class within :data:`BRANCH_REACH`, solved in turn; where it
converges to that class the point is bistable, and the result says so (``other_branch``, the
message). ``branch`` asks for one class (only stored shapes of that class are tried, and a
solve ending in the other class does not count); ``seed_bank=False`` tries the own seed only.
"""

from __future__ import annotations

import dataclasses
import logging
import time

from lubrication.checks import Deadline, InvalidParameterError
from lubrication.results import Status, leading_status

from ..quadrature import DEFAULT_ORDER
from ..results import VesicleResult
from ..seed_bank import SHAPE_CLASSES, load_seed_bank
from ..threads import single_threaded_blas
from .inputs import check_vesicle_inputs
from .ladder import LadderOptions, solve_from
from .seeds import NEAR_CRITICAL

__all__ = ["BANK_REACH", "BANK_STARTS", "BRANCH_REACH", "solve_vesicle"]

log = logging.getLogger(__name__)

#: Reach of the seed bank: stored shapes farther than this (module distance of
#: :mod:`bem.seed_bank`, about one build grid step per unit) are not tried as starts.
BANK_REACH = 3.0
#: Stored shapes tried as starts, nearest first.
BANK_STARTS = 2
#: A stored shape of the other shape class within this distance is tried once the solve has
#: converged: where it converges to that class too, the point is bistable.
BRANCH_REACH = 1.5


def _starts(nu: float, lam: float, ratio: float, ca_b: float, branch: str | None,
            seed_bank: bool) -> list:
    """The starts of :func:`~bem.vesicle.solve_vesicle` in the order tried: (label, make the initial
    shape) pairs, None the solver's own seed."""
    own = [("own", lambda: None)]
    if not seed_bank:
        return own
    bank = [(seed.label(), lambda seed=seed: seed.curve(lam))
            for seed in load_seed_bank().nearest(nu, ratio, ca_b, k=BANK_STARTS,
                                                 shape_class=branch, within=BANK_REACH)]
    return own + bank if ratio > NEAR_CRITICAL else bank + own


def _other_branch(nu, lam, ratio, ca_b, res: VesicleResult, solve) -> dict:
    """The steady state of the other shape class at this point, if a stored shape of that
    class within BRANCH_REACH converges to it: its class and outputs, else {}."""
    other = "bullet" if res.shape_class == "parachute" else "parachute"
    near = load_seed_bank().nearest(nu, ratio, ca_b, shape_class=other, within=BRANCH_REACH)
    if not near:
        return {}
    try:
        alt = solve(near[0].curve(lam))
    except InvalidParameterError:
        return {}
    if not (alt.success and alt.shape_class == other):
        return {}
    return {"shape_class": other, "seed": near[0].label(),
            **{k: getattr(alt, k) for k in ("V_over_U", "dp_plus_R0", "ell", "film_min")}}


@single_threaded_blas()      # small dense products between numba loops (bem.threads)
def solve_vesicle(nu: float, lam: float | None = None, *, lam_ratio: float | None = None,
                  ca_b: float = 50.0, initial=None, branch: str | None = None,
                  seed_bank: bool = True, n_modes: int | None = None,
                  tol: float = 1e-4, tension_tol: float = 1e-2, residual_tol: float = 1e-3,
                  max_modes: int | None = None,
                  order: int = DEFAULT_ORDER, xtol: float = 1e-9, max_iter: int = 40,
                  density: str = "auto", density_terms: int = 16,
                  continuation: bool | None = None, rung_modes: int = 32,
                  valley: bool | None = None, max_time: float | None = None):
    r"""Steady vesicle (inextensible bending membrane, viscosity ratio 1) on the tube axis.

    The pipeline (docs/vesicle-solver.md): without ``initial``, the starts are the nearest
    converged shapes of the seed bank (:mod:`bem.seed_bank`, ``BANK_STARTS`` within
    ``BANK_REACH``) and the solver's own seed (the lubrication shape, continuation in λ/λc near
    lam_c), the bank first below ``NEAR_CRITICAL`` and last above it; each start is refined by
    the mode ladder with its error estimate, and the first that converges is returned. A
    converged point is then probed for a second steady state: the nearest stored shape of the
    other shape class within ``BRANCH_REACH``, solved in turn; where it converges to that class
    the point is bistable, and the result says so (``other_branch``, the message).

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
        TIME_LIMIT. Default: no limit. Mode counts are at most MAX_MODES = 96.
    branch : {"parachute", "bullet"}, optional
        Shape class to return where two steady states coexist: only stored shapes of that
        class are tried as starts, and a solve that ends in the other class does not count as
        converged. Default: the state reached from the nearest stored shape.
    seed_bank : bool
        Try the seed bank's shapes (default). False: the solver's own seed only, a solve that
        depends on no stored solution.

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
        max_time=max_time)
    nu, lam, lam_c, ca_b = case.nu, case.lam, case.lam_c, case.ca_b
    if branch is not None and branch not in SHAPE_CLASSES:
        raise InvalidParameterError("branch", branch, '"parachute", "bullet" or None')
    t_start = time.perf_counter()
    deadline = Deadline(max_time)
    options = LadderOptions(order=order, xtol=xtol, density=density, continuation=continuation,
                            valley=valley)

    def solve(start):
        return solve_from(case, start, options, deadline.remaining())

    def done(res: VesicleResult, **changes) -> VesicleResult:
        timings = {**res.timings, "total_s": time.perf_counter() - t_start}
        return dataclasses.replace(res, timings=timings, **changes)

    ratio = lam / lam_c
    starts = ([("initial", lambda: initial)] if initial is not None
              else _starts(nu, lam, ratio, ca_b, branch, seed_bank))
    failures, found, res = [], [], None
    for label, make in starts:
        if deadline.expired():
            failures.append(f"{label}: not tried, {deadline.message()}")
            found.append(Status.TIME_LIMIT)
            break
        try:
            res = solve(make())
        except InvalidParameterError as exc:
            if label in ("own", "initial"):
                raise
            failures.append(f"{label}: cannot start ({exc})")   # its modes do not close here
            found.append(Status.REJECTED_START)
            continue
        if res.success and branch not in (None, res.shape_class):
            failures.append(f"{label}: converged to a {res.shape_class}, not a {branch}")
            found.append(Status.NOT_CONVERGED)
            continue
        if res.success:
            seed = res.seed if label in ("own", "initial") else label
            other = {} if (branch or initial is not None or not seed_bank
                           or deadline.expired()) else \
                _other_branch(nu, lam, ratio, ca_b, res, solve)
            message = res.message
            if other:
                message += (f"; bistable: a {other['shape_class']} steady state also exists "
                            f"here (V/U {other['V_over_U']:.6g}), ask for it with "
                            f"branch={other['shape_class']!r}")
            return done(res, seed=seed, other_branch=other, message=message,
                        failed_starts=failures)
        failures.append(f"{label}: {res.message}")
        found.append(res.status)
    status = leading_status(found) if found else Status.REJECTED_START
    message = "; ".join(failures) if failures else "no start"
    log.warning("solve_vesicle(nu=%g, lam=%g): %s", nu, lam, message)
    if res is None:
        return VesicleResult(nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, status=status,
                             message=message, tol=tol, residual_tol=residual_tol,
                             timings={"total_s": time.perf_counter() - t_start})
    return done(res, status=status, message=message, failed_starts=failures)
