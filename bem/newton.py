r"""Levenberg–Marquardt with Broyden updates for the BEM steady-shape problems (drop, vesicle).

The residual :math:`F(z)` of a steady shape is an overdetermined, smooth function of a few dozen
shape coefficients z, each evaluation costing one BEM solve. The Jacobian is built by forward
differences (one evaluation per unknown, step ``fd_step`` max(1, ``|z_j|``)), then kept up to date
by Broyden rank-one updates after each accepted step (Dennis & Schnabel 1983, §8.1); a fresh
difference Jacobian is computed when a Broyden step is rejected or reduces ``|F|`` by less than half
(at most ``max_jacobians`` in all); a Jacobian supplied by the caller (e.g. a coarser
level's) can replace the first difference Jacobian. Damping: Marquardt's diagonal scaling, μ
divided by 10 after an accepted step and multiplied by 10 (at least to 1e-4) after a rejected
one.

Stopping: the largest change of the unknowns relative to max(1, ``|z|``) falls below ``tol``; or
``|F|`` stalls at its floor (the truncation error of the shape modes: the equations outnumber the
unknowns): a step with a fresh Jacobian reduces ``|F|`` by less than 10 % with a step below
1e3 tol, or the Gauss–Newton model itself promises less than a 1e-3 relative decrease of ``|F|²``.
Near the critical confinement the vesicle problem is ill-conditioned (flat directions of ``|F|``):
with ``floor_ratio`` the floor tests look at ``|F|``, not at the step, and the refinement pair
judges the outputs.

:func:`valley_levenberg_marquardt` is the variant for a long, curved valley of ``|F|`` (the long
vesicle near lam_c, see its docstring): the same damped steps, but the Jacobian is kept
up to date by differences along a few directions per step instead of all of them, and every
second step is extrapolated along the valley (parallel tangents).

Independent points: the points of a difference Jacobian and of a directional update do not
depend on each other; if ``fun`` has an attribute ``many`` (a function of a list of points
returning their F, None where the shape is rejected) they are handed to it together, e.g. to
be evaluated concurrently (:func:`bem.vesicle.level._residuals`). The result must not depend on
the order of evaluation.

Separable problems: if ``fun`` has an attribute ``fixed`` (a function of the payload at z
returning (evaluate, project)), the difference quotients of a Jacobian or a directional update
are taken on ``evaluate``, the residual with the payload's linear unknowns held fixed, and
projected off the range of their columns by ``project`` (variable projection with Kaufman's
Jacobian, Kaufman 1975; Golub & Pereyra 2003): J^T F equals that of the full Jacobian at every
z, and the columns differ by a term of order ``|F|``.

Wall-time budget: both take an optional ``deadline`` (:class:`lubrication.checks.Deadline`),
tested before every evaluation of F after the first; once it is spent they return a report of
status TIME_LIMIT whose message is the deadline's, carrying the evaluated point of smallest
``|F|`` (never an exception). One evaluation is one BEM solve (well under a second at the
resolutions the solvers allow), so the budget is kept to within about one evaluation, or one
set of independent points handed to ``fun.many`` (a difference Jacobian: seconds at the
largest mode counts).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from lubrication.checks import InvalidParameterError
from lubrication.results import Outcome, Status

__all__ = ["LMReport", "difference_jacobian", "levenberg_marquardt",
           "valley_levenberg_marquardt"]


#: the valley method certifies its floor with the Jacobian it has, instead of a fresh one, when
#: that Jacobian was differenced at this solve and the iterate has moved since by less than
#: RECENT_STEP (sum of the relative steps), and its promise is below RECENT_MARGIN times
#: ``promise``. Measured at (0.6, 1.94), Ca_B = 50, levels 72, 80, 88 (moved 3e-5 since their
#: first fresh Jacobian): the promise 3.7e-9 - 7e-8 with it, 8.7e-7 - 3.6e-6 with a fresh one,
#: both far below 1e-2; the levels 48-64 (moved 3e-3 - 8e-3) differ by up to 2x (8e-3 against
#: 6e-3, 2.0e-2 against 9.8e-3) and keep their fresh Jacobian. A Jacobian prolonged from a
#: coarser level is never recent: its promise was 1e-3 - 2e-2 where a fresh one's was 4-5e-2.
RECENT_STEP = 1e-3
RECENT_MARGIN = 0.1
#: the valley method judges with a fresh difference Jacobian, as after a stall, once the last
#: CRAWL_STEPS steps with a supplied Jacobian (prolonged from a coarser level) reduced |F| by
#: less than CRAWL_GAIN together. Measured at (0.6, 1.94), Ca_B = 50: the 48-mode level
#: (its Jacobian prolonged from the 32-mode carrier) took 48 steps of |F| ratio 0.990-0.999,
#: 4.9e-3 -> 4.0e-3 in 11 s, before its first difference Jacobian; with this rule 14 steps.
CRAWL_STEPS = 5
CRAWL_GAIN = 2e-2


class _Expired(Exception):
    """The wall-time budget of a solve was spent (internal; turned into an LMReport)."""


def _budgeted(fun, deadline, best: list):
    """``fun`` that raises :class:`_Expired` once ``deadline`` is spent (never on the first
    call) and records in ``best`` = [norm, z, F, payload] the evaluated point of smallest |F|."""
    if deadline is None:
        return fun

    def check():
        if best and deadline.expired():
            raise _Expired

    def wrapped(z):
        check()
        F, payload = fun(z)
        norm = float(np.linalg.norm(F))
        if not best or norm < best[0]:
            best[:] = [norm, np.array(z, dtype=float), F, payload]
        return F, payload

    def checked(evaluate):                    # a function of a list of points, budgeted
        def run(points):
            check()
            return evaluate(points)
        return run

    if hasattr(fun, "many"):
        wrapped.many = checked(fun.many)
    if hasattr(fun, "fixed"):
        def fixed(payload):
            evaluate, project = fun.fixed(payload)
            return checked(evaluate), project
        wrapped.fixed = fixed
    return wrapped


def _within_budget(solver, fun, z0, deadline, start, **kwargs) -> "LMReport":
    """Run ``solver(fun, z, F, payload, evaluations, **kwargs)`` from the initial state of
    :func:`_initial_state` under ``deadline`` (the failure report if ``fun`` rejects ``z0``)."""
    best: list = []
    if deadline is not None and start is not None:
        F0, pl0 = start
        best[:] = [float(np.linalg.norm(F0)), np.array(z0, dtype=float), F0, pl0]
    try:
        fun = _budgeted(fun, deadline, best)
        first = _initial_state(fun, np.array(z0, dtype=float), start)
        if isinstance(first, LMReport):
            return first
        return solver(fun, *first, **kwargs)
    except _Expired:
        log.info("Levenberg–Marquardt: %s", deadline.message())
        _, z, F, payload = best
        return LMReport(Status.TIME_LIMIT, deadline.message(), z, F, payload, 0, 0, 0,
                        [best[0]])

log = logging.getLogger(__name__)


@dataclass
class LMReport(Outcome):
    """Outcome of :func:`levenberg_marquardt`; ``payload`` is what ``fun`` returned at ``z``.

    ``status``: CONVERGED (step or residual floor reached), NOT_CONVERGED (the iterations or
    the Jacobian budget ended first), TIME_LIMIT (the deadline) or REJECTED_START (``fun``
    rejected ``z0``); ``success`` is ``status is Status.CONVERGED``."""

    status: Status
    message: str
    z: np.ndarray
    F: np.ndarray | None
    payload: object
    iterations: int
    evaluations: int
    jacobians: int
    history: list = field(default_factory=list)
    jacobian: np.ndarray | None = None       # the last (difference or updated) Jacobian at z


def _evaluate_points(fun, points) -> list:
    """F at each of ``points`` (None where ``fun`` rejects the shape): ``fun.many(points)`` if
    ``fun`` has it (independent evaluations that may run concurrently), else one by one."""
    many = getattr(fun, "many", None)
    if many is not None:
        return many(points)
    out = []
    for zz in points:
        try:
            out.append(fun(zz)[0])
        except InvalidParameterError:
            out.append(None)
    return out


def _linearised(fun, F, payload, points):
    """(F at each of ``points``, evaluate, project) for difference quotients from F: by ``fun``
    itself (no projection), or by ``fun.fixed(payload)`` if ``fun`` has it and the payload is
    known: (evaluate, project), ``evaluate`` mapping points to the residual with the linear
    unknowns of ``payload`` held fixed (equal to F at the payload's point, to rounding),
    ``project`` the projection of the differences off the range of those unknowns' columns
    (variable projection, Kaufman 1975: the same gradient J^T F as the full derivative)."""
    fixed = getattr(fun, "fixed", None) if payload is not None else None
    if fixed is None:
        evaluate, project = (lambda pts: _evaluate_points(fun, pts)), None
    else:
        evaluate, project = fixed(payload)
    return evaluate(points), evaluate, project


def _backward(evaluate, z):
    """F at ``z``, the backward point of a difference whose forward point was rejected."""
    F = evaluate([z])[0]
    if F is None:
        raise InvalidParameterError("z", "a shape whose neighbours are both rejected",
                                    "a shape inside the operator's range")
    return F


def difference_jacobian(fun, z, F, fd_step, exact, payload=None):
    """Forward-difference Jacobian; columns in ``exact`` (index -> column) are not differenced;
    a step that makes the shape invalid is taken backwards. The forward points are evaluated
    together (:func:`_evaluate_points`); with ``fun.fixed`` and the ``payload`` at ``z``, by
    the linearised evaluation of :func:`_linearised`."""
    J = np.empty((F.size, z.size))
    todo = [j for j in range(z.size) if j not in exact]
    steps = [fd_step * max(1.0, abs(z[j])) for j in todo]
    points = []
    for j, h in zip(todo, steps):
        z2 = z.copy()
        z2[j] += h
        points.append(z2)
    values, evaluate, project = _linearised(fun, F, payload, points)
    n_eval = len(points)
    for j, h, z2, F2 in zip(todo, steps, points, values):
        if F2 is None:
            z2[j] -= 2.0 * h
            F2 = _backward(evaluate, z2)
            h = -h
            n_eval += 1
        J[:, j] = (F2 - F) / h
    if project is not None and todo:
        J[:, todo] = project(J[:, todo])
    for j, col in exact.items():
        J[:, j] = col
    return J, n_eval


def _initial_state(fun, z, start):
    """(z, F, payload, evaluations) at ``z``, ``start`` = (F, payload) if the caller has it; an
    LMReport of the failure if ``fun`` rejects ``z``."""
    if start is not None:
        return (z, *start, 0)
    try:
        F, payload = fun(z)
    except InvalidParameterError as exc:
        return LMReport(Status.REJECTED_START, f"initial shape rejected: {exc}", z, None, None,
                        0, 1, 0)
    return z, F, payload, 1


def levenberg_marquardt(fun, z0, *, tol: float = 1e-9, max_iter: int = 40,
                        fd_step: float = 1e-7, max_jacobians: int = 8,
                        exact_columns=None, stall: float | None = None,
                        floor_ratio: float | None = None, start=None,
                        jacobian=None, deadline=None) -> LMReport:
    """Minimise ``|F(z)|`` (see the module docstring).

    ``fun(z)`` returns (F, payload) and raises InvalidParameterError for an invalid shape;
    ``exact_columns(payload)``, if given, returns {index: column} of Jacobian columns known
    exactly (e.g. the linear speed unknown). ``stall`` (e.g. 0.9): also stop, as converged
    to the floor, at the first accepted step that reduces ``|F|`` by less than this ratio, whatever
    the Jacobian, or when a Broyden step fails with the Jacobian budget spent (for a coarse
    level that only seeds a finer one). ``floor_ratio`` (e.g. 0.99): also accept as the floor
    a step with a fresh Jacobian that reduces ``|F|`` by less than this ratio whatever its size, or a
    spent Jacobian budget after ``|F|`` fell less than 10 % over three steps (ill-conditioned
    problems with flat directions: the vesicle near lam_c). Without it a stall is a failure
    (the drop: a stall there means no steady shape). ``start``: (F, payload) at ``z0`` if the
    caller has already evaluated it (saves one evaluation). ``jacobian``: an approximate
    Jacobian at ``z0`` (e.g. prolonged from a coarser discretisation) used in place of the
    first difference Jacobian; it is kept (with Broyden updates) while its steps shrink
    tenfold per iteration, which proves it: when they stop shrinking, or the next step is
    rejected, below 1e3 ``tol`` that is the residual floor as for a fresh Jacobian; otherwise
    it is treated like a Broyden Jacobian (a rejected or slow step calls for a difference
    Jacobian). ``deadline``: wall-time budget (module docstring).
    """
    return _within_budget(_levenberg_marquardt, fun, z0, deadline, start, tol=tol,
                          max_iter=max_iter, fd_step=fd_step, max_jacobians=max_jacobians,
                          exact_columns=exact_columns, stall=stall, floor_ratio=floor_ratio,
                          jacobian=jacobian)


def _levenberg_marquardt(fun, z, F, payload, n_eval, *, tol, max_iter, fd_step, max_jacobians,
                         exact_columns, stall, floor_ratio, jacobian) -> LMReport:
    """The iteration of :func:`levenberg_marquardt` from ``z`` (``n_eval`` evaluations so far)."""

    def exact(pl):
        return exact_columns(pl) if exact_columns is not None else {}

    norm = float(np.linalg.norm(F))
    history = [norm]
    if jacobian is None:
        J, n = difference_jacobian(fun, z, F, fd_step, exact(payload), payload)
        n_eval += n
        n_jac, fresh = 1, True
    else:
        J, n_jac, fresh = np.array(jacobian, dtype=float), 0, False
    mu = 1e-8
    success, message, step, it, prev_step = False, "", math.inf, 0, math.inf
    proven = False                  # a supplied Jacobian's steps have contracted (see below)
    for it in range(1, max_iter + 1):
        # a Broyden Jacobian's rejected step is not damped further: a fresh one is made
        delta, F_new, pl_new, mu, n = _damped_step(fun, z, J, F, norm, mu, fresh)
        n_eval += n
        if F_new is None:
            if n_jac == 0 and proven and prev_step < 1e3 * tol:
                success = True
                message = (f"converged to the residual floor: relative step {prev_step:.1e} "
                           f"(supplied Jacobian; the next step rejected)")
                break
            if not fresh and n_jac < max_jacobians:
                J, n = difference_jacobian(fun, z, F, fd_step, exact(payload), payload)
                n_eval += n
                n_jac, fresh = n_jac + 1, True
                continue
            # budget spent: a seed level stops here; with floor_ratio also a level whose |F|
            # has stalled (less than 10 % decrease over the last three accepted steps)
            stalled = (floor_ratio is not None and len(history) > 3
                       and history[-1] > 0.9 * history[-4])
            if not fresh:          # the model of a Broyden Jacobian proves nothing
                success = stall is not None or stalled
                message = (f"Broyden step rejected with the difference-Jacobian budget "
                           f"({max_jacobians}) spent (residual norm {norm:.2e}"
                           + (", stalled at the floor)" if stalled else ")"))
                break
            promised = _promised(J, F, norm)
            if promised < 1e-3:
                success = True
                message = (f"converged to the residual floor: the Gauss–Newton model promises "
                           f"a {promised:.1e} relative decrease of |F|^2")
            else:
                message = (f"Levenberg–Marquardt step rejected with a fresh Jacobian and damping "
                           f"{mu:.1e} (residual norm {norm:.2e})")
            break
        step = float(np.max(np.abs(delta) / np.maximum(1.0, np.abs(z))))
        norm_new = float(np.linalg.norm(F_new))
        ratio = norm_new / norm if norm > 0 else 0.0
        Jd = J @ delta
        predicted = float(np.linalg.norm(F + Jd)) / norm if norm > 0 else 0.0
        J = J + np.outer(F_new - F - Jd, delta) / (delta @ delta)
        for j, col in exact(pl_new).items():
            J[:, j] = col
        was_fresh, fresh = fresh, False
        z, F, payload, norm = z + delta, F_new, pl_new, norm_new
        mu = max(mu / 10.0, 1e-12)
        history.append(norm)
        log.debug("levenberg_marquardt it %d: |F| = %.3e (ratio %.2f, model %.2f), step %.2e, "
                  "mu %.1e, jacobians %d", it, norm, ratio, predicted, step, mu, n_jac)
        # a supplied Jacobian (no difference Jacobian made yet) whose step is ten times shorter
        # than the one before has proved itself: it is kept, instead of a new difference
        # Jacobian, while its steps keep contracting, and once they stop (or one is rejected)
        # below the floor test's step size they pass that test like a fresh Jacobian's
        # (measured at (0.9, 1.0) with the coarse level's Jacobian at 24 and 32 modes: steps
        # fall 1e2-1e3 per iteration down to ~5e-9, where a fresh Jacobian moves the minimum
        # by ~3e-9)
        contracting = n_jac == 0 and step < 0.1 * prev_step
        proven = proven or contracting
        prev_step = step
        supplied_floor = (n_jac == 0 and proven and not contracting and ratio > 0.9
                          and step < 1e3 * tol)
        if step < tol:
            success = True
            message = f"converged: relative step {step:.1e} < {tol:.0e}"
            break
        if ((was_fresh and ((floor_ratio and ratio > floor_ratio)
                            or (ratio > 0.9 and step < 1e3 * tol)))
                or supplied_floor or (stall and ratio > stall)):
            success = True
            message = (f"converged to the residual floor: relative step {step:.1e}"
                       + (" (supplied Jacobian)" if supplied_floor and not was_fresh else ""))
            break
        if ratio > 0.5 and n_jac < max_jacobians and not contracting:
            J, n = difference_jacobian(fun, z, F, fd_step, exact(payload), payload)
            n_eval += n
            n_jac, fresh = n_jac + 1, True
    else:
        message = f"no convergence in {max_iter} iterations (last relative step {step:.1e})"
    return LMReport(Status.CONVERGED if success else Status.NOT_CONVERGED, message, z, F,
                    payload, it, n_eval, n_jac, history, J)


def _directional_update(fun, z, F, J, Q, fd_step, payload=None):
    """J corrected along the orthonormal columns of Q by forward differences (one evaluation
    per column, linearised as in :func:`difference_jacobian`): J <- J + (J_fd Q - J Q) Q^T; a
    step that makes the shape invalid is taken backwards. Returns (J, evaluations)."""
    h = fd_step * max(1.0, float(np.max(np.abs(z))))
    JQ = np.empty((F.size, Q.shape[1]))
    points = [z + h * Q[:, i] for i in range(Q.shape[1])]
    values, evaluate, project = _linearised(fun, F, payload, points)
    n_eval = Q.shape[1]
    for i, Fi in enumerate(values):
        if Fi is None:
            n_eval += 1
            JQ[:, i] = (F - _backward(evaluate, z - h * Q[:, i])) / h
        else:
            JQ[:, i] = (Fi - F) / h
    if project is not None:
        JQ = project(JQ)
    return J + (JQ - J @ Q) @ Q.T, n_eval


def _damped_step(fun, z, J, F, norm, mu, keep_damping):
    """Levenberg–Marquardt step with Marquardt's diagonal scaling (Marquardt 1963): up to 10
    trials, μ multiplied by 10 (at least 1e-4) after a shape the operator rejects
    (InvalidParameterError) or, if ``keep_damping``, after one that does not decrease |F|.
    Returns (delta, F_new, payload, mu, evaluations); F_new is None when no trial was
    accepted."""
    JTJ = J.T @ J
    g = J.T @ F
    D = np.diag(np.maximum(np.diag(JTJ), 1e-300))
    for trial in range(1, 11):
        delta = -np.linalg.solve(JTJ + mu * D, g)
        try:
            F_new, pl_new = fun(z + delta)
        except InvalidParameterError:
            mu = max(10.0 * mu, 1e-4)
            continue
        if np.linalg.norm(F_new) < norm * (1.0 + 1e-12):
            return delta, F_new, pl_new, mu, trial
        if not keep_damping:
            break
        mu = max(10.0 * mu, 1e-4)
    return delta, None, None, mu, trial


def _promised(J, F, norm):
    """Relative decrease of |F|^2 that the Gauss–Newton model of J promises."""
    if not norm > 0:
        return 0.0
    d_gn, *_ = np.linalg.lstsq(J, -F, rcond=None)
    return 1.0 - float(np.linalg.norm(F + J @ d_gn) / norm) ** 2


def valley_levenberg_marquardt(fun, z0, *, tol: float = 1e-9, max_iter: int = 300,
                               fd_step: float = 1e-7, max_jacobians: int = 4,
                               directions: int = 3, promise: float = 1e-2,
                               start=None, jacobian=None, deadline=None) -> LMReport:
    r"""Minimise ``|F(z)|`` along a long, curved valley (interface as :func:`levenberg_marquardt`).

    Why: near lam_c a long vesicle has one slow shape mode (volume moved between the rear and
    front caps, which the outer fluid must follow through the thin film); ``|F|`` is nearly flat
    along it and the valley is so curved (the second derivative of F along it has a large part
    outside the range of J) that a Gauss–Newton step along it is limited to ~10 % of its
    linear length. The plain method then gains 1–4 % of ``|F|`` per difference Jacobian and stops
    at its floor tests far from the minimum (measured at (0.6, 1.94), 64 modes: ``|F|`` 1.86e-3,
    V/U 1.02294, γ_max 799 where the minimum is 1.17e-3, 1.02176, 932; docs/validation.md).

    Method: one forward-difference Jacobian, then per accepted Levenberg–Marquardt step
    (Marquardt scaling, μ as in :func:`levenberg_marquardt`) a Broyden update along the step
    and forward differences along the step and the ``directions`` right singular vectors of
    the smallest singular values (``directions + 1`` evaluations instead of one per unknown).
    Every second step the iterate is extrapolated along z_k - z_{k-2} by 1, 2, 4, ... (up to
    64) times while ``|F|`` decreases (parallel tangents, Shah, Buehler & Kempthorne 1964).
    When a step fails, ``|F|`` falls by less than 0.1 % or the relative step is below ``tol``, a
    fresh difference Jacobian is made; converged when with it the Gauss–Newton model promises
    less than a ``promise`` relative decrease of ``|F|^2`` (the residual floor of the
    overdetermined equations), or its step is below ``tol`` (a small step of an updated
    Jacobian, with large damping, proves nothing). A Jacobian differenced in this solve, since
    moved by less than ``RECENT_STEP``, certifies the floor itself when it promises less than
    ``RECENT_MARGIN`` times ``promise`` (no fresh one; measurements at the constants). At most
    ``max_jacobians`` difference Jacobians. ``jacobian``: an approximate Jacobian at ``z0``
    (e.g. prolonged from a coarser discretisation) used in place of the first difference
    Jacobian (it is not counted; the floor is still certified with a fresh one, which is also
    made once ``CRAWL_STEPS`` steps with it reduced ``|F|`` by less than ``CRAWL_GAIN``).
    ``deadline``: wall-time budget (module docstring).
    """
    return _within_budget(_valley_levenberg_marquardt, fun, z0, deadline, start, tol=tol,
                          max_iter=max_iter, fd_step=fd_step, max_jacobians=max_jacobians,
                          directions=directions, promise=promise, jacobian=jacobian)


def _valley_levenberg_marquardt(fun, z, F, payload, n_eval, *, tol, max_iter, fd_step,
                                max_jacobians, directions, promise, jacobian) -> LMReport:
    """The iteration of :func:`valley_levenberg_marquardt` from ``z`` (``n_eval`` so far)."""
    norm = float(np.linalg.norm(F))
    history, path = [norm], [z.copy()]
    n_jac, mu = 0, 1e-8
    success, message, it = False, "", 0
    moved = math.inf                 # relative step since the last difference Jacobian
    supplied = jacobian is not None  # J is (updated from) the supplied Jacobian
    gains = []                       # |F| ratios of its steps

    def fresh_jacobian():
        nonlocal n_eval, n_jac, moved, supplied
        J, n = difference_jacobian(fun, z, F, fd_step, {}, payload)
        n_eval, n_jac, moved = n_eval + n, n_jac + 1, 0.0
        supplied = False
        return J

    if jacobian is None:
        J, fresh = fresh_jacobian(), True
    else:
        J, fresh = np.array(jacobian, dtype=float), False

    def evaluate(zz):
        nonlocal n_eval
        n_eval += 1
        try:
            return fun(zz)
        except InvalidParameterError:
            return None, None

    for it in range(1, max_iter + 1):
        delta, F_new, pl_new, mu, n = _damped_step(fun, z, J, F, norm, mu, True)
        n_eval += n
        if F_new is None:
            if not fresh and n_jac < max_jacobians:
                J, fresh = fresh_jacobian(), True
                continue
            promised = _promised(J, F, norm)
            success = fresh and promised < promise
            message = (f"converged to the residual floor: step rejected with a fresh Jacobian "
                       f"whose Gauss–Newton model promises a {promised:.1e} relative decrease "
                       f"of |F|^2 ({it} steps)" if success else
                       f"Levenberg–Marquardt step rejected with a "
                       f"{'fresh' if fresh else 'updated'} Jacobian (residual norm {norm:.2e}, "
                       f"{n_jac} difference Jacobians, promised decrease {promised:.1e})")
            break
        ratio = float(np.linalg.norm(F_new)) / norm if norm > 0 else 0.0
        J = J + np.outer(F_new - F - J @ delta, delta) / (delta @ delta)
        z, F, payload = z + delta, F_new, pl_new
        step_vec, fresh = delta, False
        path.append(z.copy())
        if len(path) % 2 == 1 and len(path) >= 3:            # parallel-tangent extrapolation
            e, a, best = path[-1] - path[-3], 1.0, None
            n_best = float(np.linalg.norm(F))
            while a <= 64.0:
                Fa, pla = evaluate(z + a * e)
                if Fa is None or not np.linalg.norm(Fa) < n_best:
                    break
                best, n_best, a = (a, Fa, pla), float(np.linalg.norm(Fa)), 2.0 * a
            if best is not None:
                a, Fa, pla = best
                J = J + np.outer(Fa - F - a * (J @ e), e) / (a * (e @ e))
                z, F, payload = z + a * e, Fa, pla
                step_vec = step_vec + a * e
                path[-1] = z.copy()
        step = float(np.max(np.abs(step_vec) / np.maximum(1.0, np.abs(z))))
        moved += step
        new_norm = float(np.linalg.norm(F))
        gain = new_norm / norm if norm > 0 else 0.0
        norm = new_norm
        history.append(norm)
        gains.append(gain)
        crawling = (supplied and len(gains) >= CRAWL_STEPS
                    and math.prod(gains[-CRAWL_STEPS:]) > 1.0 - CRAWL_GAIN)
        mu = max(mu / 10.0, 1e-12)
        log.debug("valley_levenberg_marquardt it %d: |F| = %.4e (step ratio %.3f, with "
                  "extrapolation %.3f), step %.2e, mu %.1e, evaluations %d, jacobians %d",
                  it, norm, ratio, gain, step, mu, n_eval, n_jac)
        if gain > 1.0 - 1e-3 or step < tol or crawling:   # stalled (or a heavily damped
            if fresh and step < tol:                          # step): judge with a fresh J
                success, message = True, f"converged: relative step {step:.1e} < {tol:.0e}"
                break
            if moved < RECENT_STEP:
                # a difference Jacobian of this level, moved since by less than RECENT_STEP
                # and updated along the steps and the valley: its promise certifies the floor
                promised = _promised(J, F, norm)
                if promised < RECENT_MARGIN * promise:
                    success = True
                    message = (f"converged to the residual floor: with the Jacobian differenced "
                               f"{moved:.1e} (relative step) ago the Gauss–Newton model promises "
                               f"a {promised:.1e} relative decrease of |F|^2 ({it} steps)")
                    break
            if n_jac >= max_jacobians:
                message = (f"|F| stalled at {norm:.3e} with the difference-Jacobian budget "
                           f"({max_jacobians}) spent")
                break
            J, fresh = fresh_jacobian(), True
            promised = _promised(J, F, norm)
            if promised < promise:
                success = True
                message = (f"converged to the residual floor: with a fresh Jacobian the "
                           f"Gauss–Newton model promises a {promised:.1e} relative decrease "
                           f"of |F|^2 ({it} steps)")
                break
            continue
        _, _, Vt = np.linalg.svd(J, full_matrices=False)
        Q, _ = np.linalg.qr(np.column_stack([step_vec, Vt[-directions:].T]))
        J, n = _directional_update(fun, z, F, J, Q, fd_step, payload)
        n_eval += n
    else:
        message = f"no convergence in {max_iter} iterations (residual norm {norm:.2e})"
    return LMReport(Status.CONVERGED if success else Status.NOT_CONVERGED, message, z, F,
                    payload, it, n_eval, n_jac, history, J)
