r"""Levenberg–Marquardt with Broyden updates for the BEM steady-shape problems (drop, vesicle).

The residual :math:`F(z)` of a steady shape is an overdetermined, smooth function of a few dozen
shape coefficients z, each evaluation costing one BEM solve. The Jacobian is built by forward
differences (one evaluation per unknown, step ``fd_step`` max(1, |z_j|)), then kept up to date
by Broyden rank-one updates after each accepted step (Dennis & Schnabel 1983, §8.1); a fresh
difference Jacobian is computed when a Broyden step is rejected or reduces |F| by less than half
(at most ``max_jacobians`` in all). Damping: Marquardt's diagonal scaling, μ divided by 10 after
an accepted step and multiplied by 10 (at least to 1e-4) after a rejected one.

Stopping: the largest change of the unknowns relative to max(1, |z|) falls below ``tol``; or
|F| stalls at its floor (the truncation error of the shape modes: the equations outnumber the
unknowns): a step with a fresh Jacobian reduces |F| by less than 10 % with a step below
1e3 tol, or the Gauss–Newton model itself promises less than a 1e-3 relative decrease of |F|².
Near the critical confinement the vesicle problem is ill-conditioned (flat directions of |F|):
with ``floor_ratio`` the floor tests look at |F|, not at the step, and the refinement pair
judges the outputs.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field

import numpy as np

from lubrication.checks import InvalidParameterError

__all__ = ["LMReport", "difference_jacobian", "levenberg_marquardt"]

log = logging.getLogger(__name__)


@dataclass
class LMReport:
    """Outcome of :func:`levenberg_marquardt`; ``payload`` is what ``fun`` returned at ``z``."""

    success: bool
    message: str
    z: np.ndarray
    F: np.ndarray | None
    payload: object
    iterations: int
    evaluations: int
    jacobians: int
    history: list = field(default_factory=list)


def difference_jacobian(fun, z, F, fd_step, exact):
    """Forward-difference Jacobian; columns in ``exact`` (index -> column) are not differenced;
    a step that makes the shape invalid is taken backwards."""
    J = np.empty((F.size, z.size))
    n_eval = 0
    for j in range(z.size):
        if j in exact:
            J[:, j] = exact[j]
            continue
        h = fd_step * max(1.0, abs(z[j]))
        z2 = z.copy()
        z2[j] += h
        try:
            F2, _ = fun(z2)
        except InvalidParameterError:
            z2[j] -= 2.0 * h
            F2, _ = fun(z2)
            h = -h
        n_eval += 1
        J[:, j] = (F2 - F) / h
    return J, n_eval


def levenberg_marquardt(fun, z0, *, tol: float = 1e-9, max_iter: int = 40,
                        fd_step: float = 1e-7, max_jacobians: int = 8,
                        exact_columns=None, stall: float | None = None,
                        floor_ratio: float | None = None, start=None) -> LMReport:
    """Minimise |F(z)| (see the module docstring).

    ``fun(z)`` returns (F, payload) and raises InvalidParameterError for an invalid shape;
    ``exact_columns(payload)``, if given, returns {index: column} of Jacobian columns known
    exactly (e.g. the linear speed unknown). ``stall`` (e.g. 0.9): also stop, as converged
    to the floor, at the first accepted step that reduces |F| by less than this ratio, whatever
    the Jacobian, or when a Broyden step fails with the Jacobian budget spent (for a coarse
    level that only seeds a finer one). ``floor_ratio`` (e.g. 0.99): also accept as the floor
    a step with a fresh Jacobian that reduces |F| by less than this ratio whatever its size, or a
    spent Jacobian budget after |F| fell less than 10 % over three steps (ill-conditioned
    problems with flat directions: the vesicle near lam_c). Without it a stall is a failure
    (the drop: a stall there means no steady shape). ``start``: (F, payload) at ``z0`` if the
    caller has already evaluated it (saves one evaluation).
    """
    z = np.array(z0, dtype=float)
    if start is not None:
        (F, payload), n_eval = start, 0
    else:
        try:
            F, payload = fun(z)
        except InvalidParameterError as exc:
            return LMReport(False, f"initial shape rejected: {exc}", z, None, None, 0, 1, 0)
        n_eval = 1

    def exact(pl):
        return exact_columns(pl) if exact_columns is not None else {}

    norm = float(np.linalg.norm(F))
    history = [norm]
    J, n = difference_jacobian(fun, z, F, fd_step, exact(payload))
    n_eval += n
    n_jac, fresh = 1, True
    mu = 1e-8
    success, message, step, it = False, "", math.inf, 0
    for it in range(1, max_iter + 1):
        JTJ = J.T @ J
        g = J.T @ F
        D = np.diag(np.maximum(np.diag(JTJ), 1e-300))
        accepted = False
        for _ in range(10):
            delta = -np.linalg.solve(JTJ + mu * D, g)
            z_new = z + delta
            try:
                F_new, pl_new = fun(z_new)
            except InvalidParameterError:
                n_eval += 1
                mu = max(10.0 * mu, 1e-4)
                continue
            n_eval += 1
            norm_new = float(np.linalg.norm(F_new))
            if norm_new < norm * (1.0 + 1e-12):
                accepted = True
                break
            if not fresh:
                break
            mu = max(10.0 * mu, 1e-4)
        if not accepted:
            if not fresh and n_jac < max_jacobians:
                J, n = difference_jacobian(fun, z, F, fd_step, exact(payload))
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
            d_gn, *_ = np.linalg.lstsq(J, -F, rcond=None)
            promised = 1.0 - float(np.linalg.norm(F + J @ d_gn) / norm) ** 2 if norm > 0 else 0.0
            if promised < 1e-3:
                success = True
                message = (f"converged to the residual floor: the Gauss–Newton model promises "
                           f"a {promised:.1e} relative decrease of |F|^2")
            else:
                message = (f"Levenberg–Marquardt step rejected with a fresh Jacobian and damping "
                           f"{mu:.1e} (residual norm {norm:.2e})")
            break
        step = float(np.max(np.abs(delta) / np.maximum(1.0, np.abs(z))))
        ratio = norm_new / norm if norm > 0 else 0.0
        Jd = J @ delta
        predicted = float(np.linalg.norm(F + Jd)) / norm if norm > 0 else 0.0
        J = J + np.outer(F_new - F - Jd, delta) / (delta @ delta)
        for j, col in exact(pl_new).items():
            J[:, j] = col
        was_fresh, fresh = fresh, False
        z, F, payload, norm = z_new, F_new, pl_new, norm_new
        mu = max(mu / 10.0, 1e-12)
        history.append(norm)
        log.debug("levenberg_marquardt it %d: |F| = %.3e (ratio %.2f, model %.2f), step %.2e, "
                  "mu %.1e, jacobians %d", it, norm, ratio, predicted, step, mu, n_jac)
        if step < tol:
            success = True
            message = f"converged: relative step {step:.1e} < {tol:.0e}"
            break
        if (was_fresh and ((floor_ratio and ratio > floor_ratio)
                           or (ratio > 0.9 and step < 1e3 * tol))
                or (stall and ratio > stall)):
            success = True
            message = f"converged to the residual floor: relative step {step:.1e}"
            break
        if ratio > 0.5 and n_jac < max_jacobians:
            J, n = difference_jacobian(fun, z, F, fd_step, exact(payload))
            n_eval += n
            n_jac, fresh = n_jac + 1, True
    else:
        message = f"no convergence in {max_iter} iterations (last relative step {step:.1e})"
    return LMReport(success, message, z, F, payload, it, n_eval, n_jac, history)
