r"""Steady BEM vesicle swept over the confinement at fixed reduced volume, by continuation.

Nondimensionalisation as in :mod:`bem.vesicle`: tube radius R = 1, viscosity eta = 1, mean
velocity of the undisturbed Poiseuille flow U = 1; ``lam`` = R0/R (R0 the radius of the sphere
of equal volume), ``lam_c`` the critical confinement of ``nu``, ``ca_b`` = eta U R0^2/kappa.

Method (natural-parameter continuation in lam): the points are solved in order of increasing
lam; the first starts from the seed :func:`bem.vesicle.solve_vesicle` chooses (the lubrication
shape, or the caller's ``initial``), every later one from the last *converged* result
(``initial=`` that :class:`~bem.results.VesicleResult`, whose spectral shape is the seed). Going
from the less to the more confined shape is the direction :mod:`bem.vesicle.ladder` recommends:
a cold start near lam_c can drift to a spurious, nearly closed film. A point that fails is kept in the
output with ``success`` False and its reason, and the next point starts again from the last
converged one.

A secant predictor (the shape extrapolated from the two previous converged points) was
measured and is not used: on 10 points at ν = 0.8, λ/λc = 0.3 … 0.95 (Ca_B = 50) the sweep took
103 s with it and its last point, 0.878 → 0.95 λc, ended in a spurious minimum (residual 5e-2);
from the last converged result it took 75 s with every point converged (1.8–6.6 s per point
below 0.9 λc, 38 s at 0.95).

Each point costs a full :func:`~bem.vesicle.solve_vesicle` (automatic refinement from 16 modes,
on the density built on the previous shape): seconds per point below 0.9 λc, tens of seconds
near λc (the 10-point sweep above; ``python tests/benchmarks/bench_vesicle.py --cases sweep``).
Progress goes to the ``bem.sweep`` logger (INFO, one
line per point) and to the optional ``progress`` callback.

Resource envelope: at most :data:`MAX_POINTS` = 100 points (checked before any solve; at
seconds to minutes per point that is already hours), each point bounded as in
:mod:`bem.vesicle.inputs`; ``max_time`` bounds the whole sweep (tested between points and, through
each point's remaining budget, inside them): the points not reached are returned unsolved
(``success`` False, the deadline's message).

Output: :func:`save_sweep` writes one CSV row per point (:data:`SWEEP_COLUMNS`) and a JSON with
the parameters, atomically (:func:`lubrication.io.atomic_write`).
"""

from __future__ import annotations

import csv
import dataclasses
import logging
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from lubrication.checks import Deadline, InvalidParameterError, as_finite
from lubrication.io import atomic_write, clean_json, write_json
from lubrication.results import Status

from . import vesicle
from .results import VesicleResult

__all__ = ["MAX_POINTS", "SWEEP_COLUMNS", "save_sweep", "sweep_table", "sweep_vesicle"]

log = logging.getLogger(__name__)

#: most points of one sweep (each a full solve_vesicle, seconds to minutes)
MAX_POINTS = 100

#: Columns of the sweep CSV (one row per point), with their units.
SWEEP_COLUMNS = (
    ("nu", "reduced volume [-]"),
    ("lam", "confinement R0/R [-]"),
    ("lam_c", "critical confinement [-]"),
    ("lam_ratio", "lam/lam_c [-]"),
    ("ca_b", "bending capillary number eta U R0^2/kappa [-]"),
    ("V_over_U", "vesicle velocity over the mean velocity [-]"),
    ("dp_plus_R0", "extra pressure drop dp+ R0/(eta U) [-]"),
    ("ell", "length L/R, front pole to rearmost point [-]"),
    ("film_min", "smallest gap 1 - max r/R [-]"),
    ("tension_max", "largest membrane tension gamma_max/(eta U) [-]"),
    ("wall_shear_max", "largest wall shear stress tau_w R/(eta U) = shear rate R/U [-]"),
    ("shape_class", "bullet or parachute"),
    ("converged", "the solver's success flag"),
    ("residual", "steady residual max|u - V e_x| [U]"),
    ("volume_error", "relative volume error of the panel quadrature [-]"),
    ("area_error", "relative area error of the panel quadrature [-]"),
    ("runtime", "wall-clock time of the point [s]"),
    ("message", "the solver's message (why a point failed)"),
)

#: ``progress(i, n, result, seconds)``: point i of n (1-based, in solve order) is done.
Progress = Callable[[int, int, object, float], None]


def confinements(nu, lams, lam_ratios, ca_b) -> tuple[float, np.ndarray, float, float]:
    """Checked (nu, lam of each point, lam_c, ca_b), with the single-point checks of
    :func:`bem.vesicle.solve_vesicle` applied to every point (0 < lam < lam_c(nu))."""
    if (lams is None) == (lam_ratios is None):
        given = "neither" if lams is None else "both lams and lam_ratios"
        raise InvalidParameterError("lams", given, "exactly one of lams and lam_ratios")
    name = "lams" if lam_ratios is None else "lam_ratios"
    values = as_finite(name, lams if lam_ratios is None else lam_ratios,
                       "a non-empty 1-d sequence of finite numbers")
    values = np.atleast_1d(values)
    if values.ndim != 1 or values.size == 0:
        raise InvalidParameterError(name, np.array2string(values),
                                    "a non-empty 1-d sequence of finite numbers")
    if values.size > MAX_POINTS:
        raise InvalidParameterError(name, f"{values.size} points",
                                    f"at most {MAX_POINTS} points",
                                    "each point is a full vesicle solve (seconds to minutes)")
    by_ratio = lam_ratios is not None
    points = [vesicle.check_vesicle_case(nu, None if by_ratio else v, v if by_ratio else None,
                                         ca_b) for v in map(float, values)]
    return points[0][0], np.array([p[1] for p in points]), points[0][2], points[0][3]


def _with_runtime(res, seconds: float):
    """``res`` with ``timings["total_s"]`` set to the measured time if the solver gave none."""
    if "total_s" in res.timings:
        return res
    return dataclasses.replace(res, timings={**res.timings, "total_s": seconds})


def sweep_vesicle(nu: float, lams: Sequence[float] | None = None, *,
                  lam_ratios: Sequence[float] | None = None, ca_b: float = 50.0,
                  progress: Progress | None = None, max_time: float | None = None,
                  **solver_kwargs) -> list:
    r"""Steady vesicles at several confinements, solved by continuation in increasing lam.

    Parameters
    ----------
    nu : float
        Reduced volume, 0 < nu < 1 [-].
    lams, lam_ratios : sequence of float
        Confinements R0/R, or lam/lam_c; exactly one, each 0 < lam < lam_c(nu) [-]. Any order:
        the points are *solved* in order of increasing lam.
    ca_b : float
        Bending capillary number eta U R0^2/kappa, > 0 [-].
    progress : callable, optional
        ``progress(i, n, result, seconds)`` after each point, i = 1..n in solve order (the
        ``bem.sweep`` logger gets the same line at INFO level).
    **solver_kwargs
        Passed to every :func:`bem.vesicle.solve_vesicle` call (``n_modes``, ``tol``,
        ``residual_tol``, ``max_modes``, ``density_terms``, ...). ``initial`` seeds the first
        point only; later points start from the last converged result.
    max_time : float, optional
        Wall-time budget of the whole sweep [s] (:class:`lubrication.checks.Deadline`): each
        point gets what is left; once spent, the remaining points are returned unsolved
        (status TIME_LIMIT with the deadline's message). Default: no limit.

    Returns
    -------
    list of VesicleResult
        In the order of ``lams`` (or ``lam_ratios``). A failed point is kept with the solver's
        status and message; ``timings["total_s"]`` is its wall-clock time.

    Raises
    ------
    InvalidParameterError, CannotPassError
        Bad input, checked for every point before the first solve (lam >= lam_c: CannotPassError).

    Examples
    --------
    Two points at nu = 0.98 (about 30 s, hence skipped in the doctests):

    >>> out = sweep_vesicle(0.98, [0.4, 0.3], n_modes=16, tol=1e-2,
    ...                     residual_tol=1e-3)     # doctest: +SKIP
    >>> [r.lam for r in out], [r.success for r in out], out[0].seed    # doctest: +SKIP
    ([0.4, 0.3], [True, True], 'initial')
    """
    nu, lam, lam_c, ca_b = confinements(nu, lams, lam_ratios, ca_b)
    for key in ("lam", "lam_ratio", "max_time"):
        if key in solver_kwargs:
            raise InvalidParameterError(key, str(solver_kwargs[key]),
                                        "set by the sweep, not a solver option")
    options = {k: v for k, v in solver_kwargs.items() if k in (
        "n_modes", "tol", "residual_tol", "max_modes", "rung_modes", "density_terms",
        "max_iter")}
    vesicle.check_vesicle_inputs(nu, float(lam[0]), ca_b=ca_b, max_time=max_time, **options)
    deadline = Deadline(max_time)
    started = time.monotonic()
    start = solver_kwargs.pop("initial", None)
    order = np.argsort(lam, kind="stable")
    n = int(lam.size)
    results: list = [None] * n
    previous = start                                   # last converged result (or the seed)
    for i, k in enumerate(order, start=1):
        clock = time.perf_counter()
        if deadline.expired():
            res = VesicleResult(nu=nu, lam=float(lam[k]), lam_c=lam_c, ca_b=ca_b,
                                status=Status.TIME_LIMIT,
                                message=f"not solved: {deadline.message()}")
        else:
            left = None if max_time is None else max_time - (time.monotonic() - started)
            res = vesicle.solve_vesicle(nu, float(lam[k]), ca_b=ca_b, initial=previous,
                                        max_time=max(left, 1e-3) if left is not None
                                        else None, **solver_kwargs)
        seconds = time.perf_counter() - clock
        res = results[k] = _with_runtime(res, seconds)
        if res.success:
            previous = res
        log.info("sweep nu=%g point %d/%d: lam=%.6g (lam/lam_c=%.4f) %s in %.1f s%s", nu, i, n,
                 res.lam, res.lam / lam_c, "converged" if res.success else "NOT converged",
                 seconds, "" if res.success else f" ({res.message})")
        if progress is not None:
            progress(i, n, res, seconds)
    return results


def _cell(res, key: str):
    """Value of column ``key`` for one result: JSON/CSV-ready (non-finite floats -> None; the
    physical columns of a point that did not converge -> None)."""
    if key == "converged":
        return bool(res.success)
    if not res.success and key in getattr(res, "PHYSICAL", ()):
        return None
    if key == "runtime":
        value = res.timings.get("total_s")
    else:
        value = getattr(res, key)
    return clean_json(value)


def sweep_table(results) -> list[dict]:
    """One dict per result with the keys of :data:`SWEEP_COLUMNS` (None for NaN)."""
    return [{key: _cell(r, key) for key, _ in SWEEP_COLUMNS} for r in results]


def save_sweep(directory, results, parameters: dict | None = None, *,
               profiles: bool = True, complete: bool = True) -> list[Path]:
    """Write the sweep to ``directory``: CSV (one row per point) and JSON, each atomically.

    Parameters
    ----------
    directory : path
        Created if missing.
    results : sequence of VesicleResult
        The points, one nu and Ca_B (as returned by :func:`sweep_vesicle`).
    parameters : dict, optional
        Extra run parameters recorded in the JSON (e.g. the solver options).
    profiles : bool
        Also write each point's ``VesicleResult.save`` pair (JSON + CSV profiles).
    complete : bool
        Recorded in the JSON; False while a sweep is still running (partial saves).

    Returns
    -------
    list of Path
        The sweep CSV, the sweep JSON, then the profile files.

    The stem is ``bem_vesicle_sweep_nu<nu>_cab<ca_b>``; an interrupted write leaves the previous
    file (or none), never a half-written one.
    """
    if not results:
        raise InvalidParameterError("results", "[]", "at least one VesicleResult")
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    r0 = results[0]
    stem = f"bem_vesicle_sweep_nu{r0.nu:.6g}_cab{r0.ca_b:.6g}"
    table = sweep_table(results)

    def write_csv(f):
        w = csv.DictWriter(f, fieldnames=[k for k, _ in SWEEP_COLUMNS], lineterminator="\n")
        w.writeheader()
        w.writerows({k: ("" if v is None else repr(v) if isinstance(v, float) else v)
                     for k, v in row.items()} for row in table)

    paths = [atomic_write(directory / f"{stem}.csv", write_csv)]
    extra = []
    if profiles:
        for r in results:
            extra.extend(r.save(directory))
    data = {"nu": r0.nu, "lam_c": r0.lam_c, "ca_b": r0.ca_b, "n_points": len(results),
            "complete": bool(complete), "n_converged": sum(bool(r.success) for r in results),
            "converged": all(bool(r.success) for r in results),
            "lams": [float(r.lam) for r in results], "parameters": dict(parameters or {}),
            "columns": [list(c) for c in SWEEP_COLUMNS], "points": table,
            "profile_files": [p.name for p in extra], "provenance": r0.provenance}
    paths.append(write_json(directory / f"{stem}.json", data))
    return paths + extra
