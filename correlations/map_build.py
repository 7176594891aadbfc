r"""Build the solution map: solve every grid point, store it, resume, run in parallel.

Scalings as in :mod:`correlations.solution_map` (ν, λ/λc, Ca_B = ηUR0²/κ, Δp⁺R0/(ηU), ...).

Method
------
The grid (:data:`DEFAULT_GRID`, overridable) is cut into *lines*, paths through the grid along
which every solve starts from the previous converged point (:func:`line_tasks`):

* lubrication: (ν, Ca_B) fixed, λ/λc increasing (``initial=`` the previous result), the
  direction :mod:`bem.sweep` recommends;
* BEM: (λ/λc, Ca_B) fixed, ν *decreasing* from the nearly spherical 0.98 (``initial=`` the
  previous shape, rescaled to the new volume). Measured at Ca_B = 50: continued along λ from
  λ/λc = 0.2, the ν = 0.75 line converged at 2 of its 10 points (the others ended in non-steady
  least-squares minima, residual 6e-3–1.5e-1, or above the tolerance at 80 modes); started from
  the converged ν = 0.8 shape at the same λ/λc, (0.75, λ/λc) converged at 0.2, 0.3, 0.6, 0.8 and
  0.9 in 2–22 s each. Above λ/λc = ``bem.vesicle.NEAR_CRITICAL`` the solver's own continuation
  (rungs from the lubrication shape) is tried first and the neighbour's shape second: continued
  from its 0.95 λc shape along λ, (0.9, 0.98 λc) failed at 80 modes (608 s), the rungs converge.
  Below it the neighbour's shape is tried first and the solver's own seed second. A red cell
  (``shear_ratio``) starts instead from the same (ν, λ/λc) at the next velocity up where that
  point is stored and converged (:func:`_faster_point`), first whatever λ/λc, its ladder allowed
  as high as a stored shape's (``bem.vesicle.pipeline.branch_modes``); below
  Ca_S = ``bem.vesicle.pipeline.VELOCITY_FIRST`` a neighbour at the same velocity comes after
  the solver's own continuation along the velocity, unless the caller asks for it first (a
  retry of a point whose own starts failed, ``neighbour_first``; its ladder then climbs as the
  faster point's does). The record's ``seed`` names the start that converged, its ``message``
  the reasons of the others.

Every finished point, converged or failed, is written at once as its own JSON file
(:func:`correlations.solution_map.point_filename`) through :func:`lubrication.io.write_json`
(atomic), so a killed build leaves only complete files. A restarted build skips the stored points of each
line and warm-starts from the last converged *stored* point (BEM: the spectral ``modes`` and
``density`` of the point, rebuilt with :meth:`bem.shape.SpectralCurve.closed` at the new volume;
lubrication stores no solver state and cold-starts, which costs about a second).

Lines are independent tasks: by default a local :class:`concurrent.futures.ProcessPoolExecutor`
(``workers`` processes; ``workers=1`` solves in this process), or a Dask distributed cluster
(``scheduler`` = its address). With Dask the workers write the point files into the build
folder (a file system they share with the client, as on a cluster); the client also writes any
point a finished line returns that is not yet on disk. Each line's BEM solves run on the cores
of its host divided among the lines running there (numba threads: cores // workers for the
local pool; cores // task threads of the host's Dask workers, :func:`_share_cores`).

Resource envelope: a point takes 0.1–3 s (lubrication) to minutes (BEM near λc); ``max_time``
bounds each point (an expired point is stored as failed with the reason). The default grid has
9 ν × (13 BEM + 11 lubrication λ/λc) × 7 Ca_B = 1512 points in 154 lines (63 lubrication, 91
BEM); each point file stores its solve time (``seconds``), so a build's cost is their sum. A grid
holds at most :data:`MAX_POINTS` points, and a local pool at most one worker per core.

Input checks: before the folder is touched, every grid point and solver option is checked by
the check of the solver that will solve it (:func:`check_build`: the ranges of ``vesicle-tube
bem vesicle`` and ``vesicle-tube lubrication``), so that a value the solver refuses is an error
of the build, not a folder of failed points; a folder whose ``build.json`` records values the
solvers now refuse is reported, not resumed.

One build per folder: a build holds an advisory lock (``fcntl.flock``) on :data:`LOCK_NAME` in
its folder from before it reads ``build.json`` to after the pack, with its process id in the
file; a second build into the folder is refused at once. The kernel releases the lock when the
process ends in any way (kill -9 included); pool workers close their inherited copy of it, so
they never hold it for a dead build.
"""

from __future__ import annotations

import contextlib
import ctypes
import datetime
import fcntl
import fnmatch
import inspect
import json
import logging
import math
import multiprocessing
import os
import signal
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from lubrication.checks import Deadline, InvalidParameterError, check_range
from lubrication.geometry import critical_confinement
from lubrication.io import provenance as run_provenance
from lubrication.io import temporary_target, write_json
from lubrication.results import Status, leading_status, status_of

from .solution_map import (POINT_FORMAT, POINT_GLOB, QUANTITIES, SHEAR_RATIO, pack_map,
                           point_filename, read_build, read_point, read_points)

__all__ = ["DEFAULT_GRID", "DEFAULT_OPTIONS", "LOCK_NAME", "MAX_POINTS", "METHODS", "SOLVERS",
           "BuildInputError", "make_grid", "check_build", "max_workers", "line_tasks",
           "solve_line", "build_map", "write_seed_bank"]

log = logging.getLogger(__name__)

METHODS = ("bem", "lubrication")

#: seconds to wait for a Dask scheduler before --scheduler is reported unreachable
SCHEDULER_TIMEOUT_S = 5

#: The shipped map's grid. The BEM and lubrication λ/λc lists overlap at 0.9–0.98 on purpose:
#: the overlap measures where lubrication becomes accurate (the model error of the map's
#: lubrication values, :mod:`correlations.solution_map`). λ/λc = 0.35, 0.45 and Ca_B = 9, 25,
#: 150 refine the minimum grid where the bullet–parachute change makes Δp⁺ and ℓ vary fastest
#: (off-grid errors of tests/benchmarks/map_offgrid.py), λ/λc = 0.85 before the film forms.
DEFAULT_GRID = {
    "methods": list(METHODS),
    "nu": [0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95, 0.98],
    "lam_ratio": {"bem": [0.2, 0.3, 0.35, 0.4, 0.45, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.95, 0.98],
                  "lubrication": [0.9, 0.92, 0.94, 0.95, 0.96, 0.97, 0.98, 0.99, 0.995, 0.999,
                                  0.9999]},
    "ca_b": [5.0, 9.0, 15.0, 25.0, 50.0, 150.0, 500.0],
}

#: Solver options per method (keyword arguments of solve_vesicle / solve_lubrication); the
#: empty BEM set means its automatic refinement at the solver's default tolerances.
DEFAULT_OPTIONS = {"bem": {}, "lubrication": {"tol": 1e-7}}

#: Most points of one build: 13 times the default grid (1512 points, packed in 2 s into
#: 0.6 MB, docs/data/bench_solution_map.json). The pack holds every point in memory and its
#: leave-one-out errors grow with the count; a larger map is several builds, or an extension.
MAX_POINTS = 20_000

#: The lock file of a build in its folder (module docstring: one build per folder).
LOCK_NAME = ".vesicle-tube-build.lock"


# --------------------------------------------------------------------------- grid

def make_grid(nu=None, lam_ratio=None, ca_b=None, methods=None) -> dict:
    """The build grid: :data:`DEFAULT_GRID` with the given lists replacing its own.

    ``lam_ratio`` is a list (the same λ/λc for every method) or a dict ``{method: list}``.
    Values are checked (0 < ν < 1, 0 < λ/λc < 1, Ca_B > 0, methods from :data:`METHODS`, at
    most :data:`MAX_POINTS` points in all), sorted and de-duplicated; an error about a list of
    the dict is named ``lam_ratio_<method>``. Whether the solvers accept every point is
    :func:`check_build`'s question.
    """
    methods = list(DEFAULT_GRID["methods"] if methods is None else methods)
    if not methods:
        raise InvalidParameterError("methods", "[]", "one or more of " + ", ".join(METHODS))
    for m in methods:
        if m not in METHODS:
            raise InvalidParameterError("methods", m, "one or more of " + ", ".join(METHODS))
    methods = [m for m in METHODS if m in methods]

    def values(name, given, default, lo, hi, hi_open=True):
        v = [float(x) for x in (default if given is None else given)]
        if not v:
            raise InvalidParameterError(name, "[]", "a non-empty list")
        for x in v:                      # one by one: the message names the value
            check_range(name, x, lo, hi, lo_open=True, hi_open=hi_open)
        return sorted(set(v))

    ratios = {}
    for m in methods:
        per_method = isinstance(lam_ratio, dict)
        given = lam_ratio.get(m) if per_method else lam_ratio
        ratios[m] = values(f"lam_ratio_{m}" if per_method else "lam_ratio", given,
                           DEFAULT_GRID["lam_ratio"][m], 0.0, 1.0)
    grid = {"methods": methods,
            "nu": values("nu", nu, DEFAULT_GRID["nu"], 0.0, 1.0),
            "lam_ratio": ratios,
            "ca_b": values("ca_b", ca_b, DEFAULT_GRID["ca_b"], 0.0, math.inf)}
    total = _count(grid)
    if total > MAX_POINTS:
        sizes = " + ".join(f"{len(ratios[m])} {m}" for m in methods)
        raise InvalidParameterError(
            "grid", total, f"at most {MAX_POINTS} points",
            f"{len(grid['nu'])} nu x ({sizes} lam/lam_c) x {len(grid['ca_b'])} Ca_B; build "
            "it in parts (a build extends to a grid that contains its own)")
    return grid


def _count(grid: dict) -> int:
    """Number of points of a grid."""
    return (sum(len(grid["lam_ratio"][m]) for m in grid["methods"]) * len(grid["nu"])
            * len(grid["ca_b"]))


def _contains(grid: dict, other: dict) -> bool:
    """True if every list of ``grid`` (methods, ν, λ/λc per method, Ca_B) contains ``other``'s:
    a build of ``other`` extended to ``grid`` keeps all its points."""
    return (set(other["methods"]) <= set(grid["methods"])
            and set(other["nu"]) <= set(grid["nu"]) and set(other["ca_b"]) <= set(grid["ca_b"])
            and all(set(other["lam_ratio"][m]) <= set(grid["lam_ratio"][m])
                    for m in other["methods"]))


# --------------------------------------------------------------------------- input checks

class BuildInputError(InvalidParameterError):
    """A grid value or solver option of a build that the solver of its lines refuses: the
    solver's own error, named for the build (``lam_ratio`` -> ``lam_ratio_bem``, a solver option
    ``tol`` -> ``bem_tol``; ``nu``, ``ca_b`` and ``max_time`` keep their names) and saying which
    lines hold the value (``method``)."""

    def __init__(self, method: str, exc: InvalidParameterError):
        name = exc.name
        if name in ("lam", "lam_ratio"):
            name = f"lam_ratio_{method}"
        elif name not in ("nu", "ca_b", "max_time"):
            name = f"{method}_{name}"
        self.name, self.value, self.valid, self.method = name, exc.value, exc.valid, method
        ValueError.__init__(self, f"{exc} (a value of the {method} lines of the build)")


# The BEM option of a red-cell build, SHEAR_RATIO (defined with the map that reads it,
# correlations.solution_map): the cell's ratio of shear to bending stiffness
# β = G_s R0²/κ = Ca_B/Ca_S, a constant of one cell (232 for the estimate's default red cell:
# G_s 6 µN/m, R0 2.78 µm, κ 2e-19 J), so that each point has Ca_S = Ca_B/β and a line in Ca_B is
# one physical cell at different velocities (point_options).


def point_options(options: dict, ca_b: float) -> dict:
    """The solver options of one BEM point at ``ca_b``: a :data:`SHEAR_RATIO` β becomes the
    point's ``ca_s`` = ca_b/β; other options pass unchanged."""
    if SHEAR_RATIO not in options:
        return options
    out = dict(options)
    beta = out.pop(SHEAR_RATIO)
    if "ca_s" in out:
        raise InvalidParameterError(SHEAR_RATIO, beta, "either shear_ratio or ca_s",
                                    "shear_ratio sets each point's ca_s = ca_b/shear_ratio")
    from bem.vesicle.inputs import CA_S_RANGE  # lazy: scipy off the build's start-up
    lo, hi = CA_S_RANGE
    check_range(SHEAR_RATIO, beta, ca_b / hi, ca_b / lo,
                reason=f"G_s R0^2/kappa = Ca_B/Ca_S of the cell; at ca_b={ca_b:g} the solver's "
                       f"{lo:g} <= Ca_S <= {hi:g}")
    out["ca_s"] = ca_b / float(beta)
    return out


def _bem_option_names() -> tuple:
    """The solver options of the BEM lines: those :func:`bem.vesicle.check_vesicle_inputs`
    checks besides the point and ``max_time`` (the build sets those), and
    :data:`SHEAR_RATIO`."""
    from bem.vesicle import check_vesicle_inputs  # lazy: bem and scipy off the build's start-up
    return tuple(k for k, p in inspect.signature(check_vesicle_inputs).parameters.items()
                 if p.default is not inspect.Parameter.empty
                 and k not in ("lam", "lam_ratio", "ca_b", "max_time")) + (SHEAR_RATIO,)


def _check_bem_point(nu, lam_ratio, ca_b, options, max_time) -> None:
    """The check of ``vesicle-tube bem vesicle`` (:func:`bem.vesicle.check_vesicle_inputs`)."""
    from bem.vesicle import check_vesicle_inputs  # lazy: bem and scipy off the build's start-up
    check_vesicle_inputs(nu, lam_ratio=lam_ratio, ca_b=ca_b, max_time=max_time,
                         **point_options(options, ca_b))


def _check_lubrication_point(nu, lam_ratio, ca_b, options, max_time) -> None:
    """The check of ``vesicle-tube lubrication`` (:func:`lubrication.solve.check_inputs`), and
    the tolerance's range."""
    from lubrication.solve import TOL_RANGE, check_inputs  # lazy: scipy off the start-up
    check_inputs(nu, lam_ratio=lam_ratio, ca_b=ca_b)
    if "tol" in options:
        check_range("tol", options["tol"], *TOL_RANGE,
                    reason="solve_bvp's relative residual tolerance")


#: method -> (check of one point ``f(nu, lam_ratio, ca_b, options, max_time)``, the names of
#: the solver options the build accepts for it)
POINT_CHECKS = {"bem": (_check_bem_point, _bem_option_names),
                "lubrication": (_check_lubrication_point, lambda: ("tol",))}


def check_build(grid: dict, options: dict, max_time=None) -> None:
    """Check a build before any work: ``max_time`` (> 0 or None), the solver options of each
    method of the grid (names the build accepts, values in the solver's range) and every point
    of the grid against the check of the solver that will solve it, the same checks as the
    single-point commands. Raises :class:`BuildInputError` (an
    :class:`~lubrication.checks.InvalidParameterError`) naming the value."""
    if max_time is not None:
        Deadline(max_time)                               # 0 < max_time < inf
    for method in grid["methods"]:
        check_point, names = POINT_CHECKS[method]
        given = options.get(method, {})
        accepted = names()
        for key in given:
            if key not in accepted:
                raise InvalidParameterError(f"options.{method}", key,
                                            "one of " + ", ".join(accepted))
        try:
            for nu in grid["nu"]:
                for ca in grid["ca_b"]:
                    for r in grid["lam_ratio"][method]:
                        check_point(nu, r, ca, given, max_time)
        except InvalidParameterError as exc:
            raise BuildInputError(method, exc) from None


def max_workers() -> int:
    """Most local worker processes: one per core (``os.cpu_count``). The lines are CPU-bound,
    so more processes only share the cores, each holding its own solvers (a BEM line up to
    about 1 GB, :mod:`bem.vesicle`'s resource envelope)."""
    return os.cpu_count() or 1


def line_tasks(grid: dict) -> list[tuple[str, float, list[tuple[float, float]]]]:
    """The lines ``(method, Ca_B, [(ν, λ/λc), ...])`` of a grid, each in solve order (see the
    module docstring), in build order: lubrication first (seconds per line), then BEM by Ca_B
    nearest to 50 (Chen et al.'s value and the red-blood-cell default, so that an interrupted
    build has the most used slice first), λ/λc from small to large."""
    lines = []
    for m in grid["methods"]:
        for ca in grid["ca_b"]:
            if m == "lubrication":
                lines += [(m, ca, [(nu, r) for r in grid["lam_ratio"][m]]) for nu in grid["nu"]]
            else:
                lines += [(m, ca, [(nu, r) for nu in reversed(grid["nu"])])
                          for r in grid["lam_ratio"][m]]
    return sorted(lines, key=lambda t: (t[0] != "lubrication", abs(math.log(t[1] / 50.0)),
                                        t[2][0][1], -t[2][0][0]))


# --------------------------------------------------------------------------- one point

def _now() -> str:
    return datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")


def _solve_bem(nu, lam_ratio, ca_b, warm, options, max_time, neighbour_first=False):
    """One BEM point. ``warm``: the previous converged point of the line (a dict with ``nu``,
    ``lam_ratio`` and ``shape``: a stored record or what this function returned), or None.
    The starts are tried in the order of the module docstring (``warm`` first whatever the
    order if ``neighbour_first``), within ``max_time`` in all.
    The point's status is CONVERGED if a start converged, else the leading status of the failed
    starts (:func:`lubrication.results.leading_status`). Returns (record fields, the warm start
    of the next point or None)."""
    from bem import vesicle  # lazy: scipy and the BEM off the build's input checks
    from bem.shape import SpectralCurve  # lazy: with bem.vesicle
    from bem.vesicle.pipeline import VELOCITY_FIRST, branch_modes  # lazy: with bem.vesicle
    options = point_options(options, ca_b)

    def neighbour():
        lam = lam_ratio * float(critical_confinement(nu))
        return SpectralCurve.with_volume_radius(warm["shape"]["modes"], lam,
                                                density=warm["shape"]["density"])

    starts, faster = [("own", lambda: None)], False
    if warm is not None:
        # the same cell faster (a red cell: the physical path, :func:`_faster_point`) first;
        # a neighbour at the same velocity is not for a slow red cell, where it may sit on a
        # compressed, self-equilibrated state: its own continuation along the velocity first
        faster = warm.get("ca_b", ca_b) != ca_b
        first = neighbour_first or faster or (lam_ratio <= vesicle.NEAR_CRITICAL
                           and not options.get("ca_s", math.inf) < VELOCITY_FIRST)
        label = (f"neighbour (nu={warm['nu']:g}, lam/lam_c={warm['lam_ratio']:g}"
                 + (f", Ca_B={warm['ca_b']:g})" if faster else ")"))
        starts.insert(0 if first else 1, (label, neighbour))
    # the same cell faster, or a converged neighbour asked for first, is on a steady branch: as
    # for a stored shape, an estimate still above the tolerance at the default cap is
    # resolution, so its ladder may climb further
    climb = ((faster or neighbour_first) and "n_modes" not in options
             and "max_modes" not in options)
    deeper = {**options, "max_modes": branch_modes(red_cell=True)} if climb else options
    deadline = None if max_time is None else time.monotonic() + max_time
    failures, found, bie, res = [], [], 0, None
    for label, make_initial in starts:
        left = None if deadline is None else deadline - time.monotonic()
        if left is not None and left <= 0:
            failures.append(f"{label}: not tried, max_time spent")
            found.append(Status.TIME_LIMIT)
            break
        initial = None
        try:
            initial = make_initial()
            res = vesicle.solve_vesicle(nu, lam_ratio=lam_ratio, ca_b=ca_b, initial=initial,
                                        max_time=left,
                                        **(options if label == "own" else deeper))
        except InvalidParameterError as exc:
            if initial is None and label == "own":
                raise
            # the neighbour's shape or density does not carry over to this point (e.g. its
            # density turns negative on the new curve): the next start
            failures.append(f"{label}: cannot start ({exc})")
            found.append(Status.REJECTED_START)
            continue
        seed = res.seed if initial is None else label
        bie += res.bie_solves
        if res.success:
            break
        failures.append(f"{label}: {res.message}")
        found.append(res.status)
    if res is None:                  # no start could run: a failed point
        return _failed_fields(leading_status(found), "; ".join(failures)), None
    status = Status.CONVERGED if res.success else leading_status(found)
    message = res.message if res.success else "; ".join(failures)
    d = res.to_dict(shape=False)
    est = res.error_estimate if res.success else {}
    fields = {"lam": d["lam"], "lam_c": d["lam_c"], "ca_s": d.get("ca_s"),
              "reference": d.get("reference"), "success": bool(res.success),
              "status": status.value, "message": message, **{q: d.get(q) for q in QUANTITIES},
              "shape_class": d["shape_class"], "failed_starts": failures if res.success else [],
              "error_estimate": {q: (None if est.get(q) is None or not math.isfinite(est[q])
                                     else float(est[q])) for q in QUANTITIES},
              "residual": d["residual"], "bie_solves": bie, "seed": seed,
              "shape": ({"modes": res.modes.tolist(), "density": res.density.tolist()}
                        if res.success else None),
              "solver": {"name": "bem.vesicle.solve_vesicle", "panels": d["panels"],
                         "modes": int(res.modes.size),
                         "refinement_modes": [lev[0] for lev in d["refinement"]],
                         "tol": d["tol"], "residual_tol": d["residual_tol"],
                         "options": options, "max_time": max_time}}
    warm_next = {"nu": nu, "lam_ratio": lam_ratio, "ca_b": ca_b, "shape": fields["shape"]}
    return fields, (warm_next if res.success else None)


def _faster_point(folder: Path, nu: float, lam_ratio: float, ca_b: float) -> dict | None:
    """The converged BEM point of a red-cell build stored at (ν, λ/λc) with the smallest Ca_B
    above ``ca_b``: the same cell at the next velocity up, the warm start of a red cell
    slowing down (on the red-cell slice at 0.1 mm/s, 20 of 40 points converged from the
    solver's own starts; from the 0.2 mm/s shapes they converge at 32 modes in about a
    second). None if there is none."""
    best = None
    pattern = point_filename("bem", nu, lam_ratio, 1.0).replace("caB1.json", "caB*.json")
    for f in Path(folder).glob(pattern):
        try:
            rec = json.loads(f.read_text())
        except (OSError, ValueError):
            continue
        if (rec.get("success") and rec.get("shape") and rec["ca_b"] > ca_b
                and (best is None or rec["ca_b"] < best["ca_b"])):
            best = rec
    return best


def _solve_lubrication(nu, lam_ratio, ca_b, warm, options, max_time):
    """One lubrication point (bending model at ``ca_b``). ``warm``: a LubricationResult or
    None (stored records hold no solver state: cold start)."""
    from lubrication.solve import solve_lubrication  # lazy: scipy off the build's input checks
    initial = None if isinstance(warm, dict) else warm
    try:
        res = solve_lubrication(nu, lam_ratio=lam_ratio, ca_b=ca_b, initial=initial,
                                max_time=max_time, **options)
    except InvalidParameterError as exc:
        # outside the model's domain (its range, checked before any work): the model has no
        # solution there
        return {**_failed_fields(Status.NO_STEADY_STATE, f"outside the lubrication model: {exc}"),
                "residual": None, "bie_solves": None, "seed": "",
                "solver": {"name": "lubrication.solve.solve_lubrication", "options": options,
                           "max_time": max_time}}, None
    d = res.to_dict()
    wall = None
    if res.success and len(res.shear_wall):
        # under the vesicle from the model; Poiseuille flow (tau_w R/(eta U) = 4) elsewhere
        wall = max(4.0, float(max(abs(float(v)) for v in res.shear_wall)))
    fields = {"lam": d["lam"], "lam_c": d["lam_c"], "success": bool(res.success),
              "status": res.status.value, "message": res.message,
              **{q: d.get(q) for q in QUANTITIES}, "wall_shear_max": wall,
              "shape_class": d["shape_class"],
              "error_estimate": dict.fromkeys(QUANTITIES), "residual": d["max_residual"],
              "bie_solves": None, "seed": "previous point" if initial is not None else "cold",
              "shape": None,
              "solver": {"name": "lubrication.solve.solve_lubrication", "model": d["model"],
                         "nodes": d["n_nodes"], "tol": d["tol"], "options": options,
                         "max_time": max_time}}
    return fields, (res if res.success else None)


#: method -> point solver ``f(nu, lam_ratio, ca_b, warm, options, max_time) -> (fields, warm)``
SOLVERS = {"bem": _solve_bem, "lubrication": _solve_lubrication}


def _failed_fields(status: Status, message: str) -> dict:
    """Record fields of a point without a solution: its status, the reason, no numbers."""
    return {"success": False, "status": status.value, "message": message,
            **dict.fromkeys(QUANTITIES), "shape_class": None,
            "error_estimate": dict.fromkeys(QUANTITIES), "shape": None}


def _point(method, nu, lam_ratio, ca_b, warm, options, max_time, provenance, **start):
    """Solve one point and return (its record, the next warm start); ``start``: keywords of the
    method's solver (``neighbour_first`` of :func:`_solve_bem`). A solver exception is a
    failed point with the exception as reason (it is stored, not raised): status
    REJECTED_START for an InvalidParameterError (the solver's own start refused, e.g. a seed
    density that is not positive), NOT_CONVERGED for any other."""
    clock = time.perf_counter()
    try:
        fields, warm_next = SOLVERS[method](nu, lam_ratio, ca_b, warm, options, max_time,
                                            **start)
    except Exception as exc:        # noqa: BLE001 - stored as the failure reason
        status = (Status.REJECTED_START if isinstance(exc, InvalidParameterError)
                  else Status.NOT_CONVERGED)
        fields, warm_next = _failed_fields(status, f"{type(exc).__name__}: {exc}"), None
    seconds = time.perf_counter() - clock
    solver = fields.pop("solver", {})
    record = {"format": POINT_FORMAT, "method": method, "nu": nu, "lam_ratio": lam_ratio,
              "ca_b": ca_b, **fields, "seconds": seconds,
              "provenance": {**provenance, "solver": solver, "date": _now()}}
    return record, warm_next


# --------------------------------------------------------------------------- one line

#: prctl option of Linux that sends a signal to a process when its parent dies
PR_SET_PDEATHSIG = 1


def _init_worker(parent: int, lock_fd: int | None = None) -> None:
    """A pool worker ignores Ctrl-C (the parent stops its workers; a terminal sends SIGINT to
    all) and dies with its parent, also when the parent is killed (SIGKILL leaves it no chance
    to stop them): on Linux the kernel kills the worker then (``PR_SET_PDEATHSIG``); a parent
    already gone when the worker starts ends it at once. A forked worker closes its copy of
    the build lock's descriptor ``lock_fd`` (a lock lasts while any copy is open; closing a
    copy does not release it), so that only the build holds the lock."""
    if lock_fd is not None:
        with contextlib.suppress(OSError):
            os.close(lock_fd)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL))
    if os.getppid() != parent:
        os._exit(1)


def _share_cores(threads: int | None) -> None:
    """Run this thread's BEM work on ``threads`` numba threads (the assembly and the concurrent
    Jacobian points of :func:`bem.vesicle.level._residuals`; numba's setting is per thread), so that
    the parallel workers of a build do not ask for more threads than the cores. Measured with
    ``bench_map_build.py`` (2 cores, 8 BEM points, one run each): 2 pool workers of 2 threads
    13.3 s, of 1 thread 12.3 s; a Dask LocalCluster of 2 processes 15.1 s and 13.6 s."""
    if threads:
        import numba  # lazy: numba

        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))


def solve_line(folder, method, ca_b, points, stored, options, max_time, provenance,
               parent_pid=None, on_point=None, threads=None) -> list[dict]:
    """Solve the missing points of one line (method, Ca_B, [(ν, λ/λc), ...]) in its order.

    ``stored`` maps (ν, λ/λc), rounded to 9 digits, to the records already stored (skipped; a
    converged BEM one is the warm start of the next). Each new point is written to ``folder``
    at once. Stops early if the process's parent is no longer ``parent_pid`` (the build was
    killed). ``threads``: numba threads of this line's solves (default: numba's setting).
    Returns the new records.
    """
    _share_cores(threads)
    folder = Path(folder)
    warm, new = None, []
    for nu, r in points:
        if parent_pid is not None and os.getppid() != parent_pid:
            break
        done = stored.get((round(nu, 9), round(r, 9)))
        if done is not None:
            if done.get("success"):
                warm = done if done.get("shape") else None
            continue
        start = warm
        if method == "bem" and SHEAR_RATIO in options.get(method, {}):
            start = _faster_point(folder, nu, r, ca_b) or warm
        record, warm_next = _point(method, nu, r, ca_b, start, options.get(method, {}),
                                   max_time, provenance)
        write_json(folder / point_filename(method, nu, r, ca_b), record, indent=1,
                   sort_keys=False)
        if warm_next is not None:
            warm = warm_next
        new.append(record)
        if on_point is not None:
            on_point(record)
    return new


# --------------------------------------------------------------------------- the build

def _connect(scheduler: str):
    """A Dask client of the scheduler at ``scheduler``; InvalidParameterError if unreachable."""
    try:
        from dask.distributed import Client  # lazy: dask.distributed, optional, for --scheduler
    except ImportError:
        raise InvalidParameterError("scheduler", scheduler, "the address of a Dask scheduler",
                                    "dask.distributed is not installed (pip install "
                                    "'vesicle-tube[distributed]')") from None
    try:
        return Client(scheduler, timeout=f"{SCHEDULER_TIMEOUT_S}s")
    except (OSError, TimeoutError, ValueError) as exc:
        raise InvalidParameterError("scheduler", scheduler, "the address of a reachable Dask "
                                    "scheduler", f"cannot connect ({exc})") from None


def _dask_threads(client) -> int:
    """numba threads per Dask task: on each host its cores over the task threads of the
    workers there (the smallest over the hosts)."""
    workers = client.scheduler_info(n_workers=-1)["workers"]
    cores = client.run(os.cpu_count)
    slots: dict = {}
    for info in workers.values():
        slots[info["host"]] = slots.get(info["host"], 0) + int(info.get("nthreads", 1))
    per_host = {workers[a]["host"]: c or 1 for a, c in cores.items() if a in workers}
    return max(1, min((per_host.get(h, 1) // n for h, n in slots.items()), default=1))


def _stop(executor) -> None:
    """Stop a process pool at once: cancel queued lines and terminate the running workers
    (their finished points are complete files; the point being solved is lost)."""
    workers = list((getattr(executor, "_processes", None) or {}).values())
    executor.shutdown(wait=False, cancel_futures=True)
    for proc in workers:
        proc.terminate()
    for proc in workers:
        proc.join(timeout=5)
    # wait for the pool's manager thread to see the ended workers and close its pipes: left
    # running, it races the interpreter's exit hook ("OSError: Bad file descriptor" at exit)
    executor.shutdown(wait=True)


def _read_build(folder: Path):
    """``(build.json's content, its grid)`` of a build folder, or ``(None, None)`` without
    one. A stored grid or stored solver options that this version refuses
    (:func:`make_grid`, :func:`check_build`) are reported with what to do: its points were
    solved with values no solver accepts now, so the build cannot be resumed as recorded."""
    path = folder / "build.json"
    if not os.path.lexists(path):          # a dangling link is an unreadable build.json
        return None, None
    info = read_build(folder, name="out")
    g = info["grid"]
    try:
        grid = make_grid(g["nu"], g["lam_ratio"], g["ca_b"], g["methods"])
        check_build(grid, info.get("parameters", {}).get("options", {}))
    except InvalidParameterError as exc:
        raise InvalidParameterError(
            "out", str(folder), "a new folder, or a build folder whose build.json this version "
            "accepts", f"its build.json records a value the solvers refuse, {exc.name}: "
            f"{exc}; a build with these values cannot be resumed: build into a new folder (or "
            "delete this one and build again)") from None
    return info, grid


def _lock_holder(fd: int) -> str:
    """`` (pid N)`` of the build that holds the lock file open as ``fd``, if it wrote it."""
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    except OSError:
        return ""
    return f" (pid {text})" if text.isdigit() else ""


@contextlib.contextmanager
def _locked(folder: Path):
    """Hold the build lock of ``folder`` (module docstring) for the ``with`` block; yields the
    lock file's descriptor. Another build holding it: :class:`InvalidParameterError` at once.
    The file is removed on exit while still locked; a build that opened it before the removal
    finds, once it holds the lock, that the name no longer leads to its file and tries again."""
    path = folder / LOCK_NAME
    valid = "a folder no other build is writing"
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            raise InvalidParameterError("out", str(folder), valid, "cannot create its lock "
                                        f"file {LOCK_NAME} ({exc.strerror or exc})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            holder = _lock_holder(fd)
            os.close(fd)
            if isinstance(exc, BlockingIOError):
                raise InvalidParameterError(
                    "out", str(folder), valid, f"another build{holder} is writing there; wait "
                    "for it to end, or build into another folder") from None
            raise InvalidParameterError("out", str(folder), valid, f"cannot lock {LOCK_NAME} "
                                        f"({exc.strerror or exc})") from None
        try:
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)
    try:
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode("ascii"))
        yield fd
    finally:
        path.unlink(missing_ok=True)
        os.close(fd)


def build_map(folder, grid=None, *, options=None, workers=None, scheduler=None,
              max_time=None, retry_failed=False, progress=None, pack=True) -> dict:
    """Build (or resume) the solution map in ``folder``; see the module docstring.

    Parameters
    ----------
    folder : str or Path
        Build folder: ``build.json`` and one JSON file per finished point.
    grid : dict, optional
        From :func:`make_grid`. Default: the grid of an existing ``build.json`` (resume), else
        :data:`DEFAULT_GRID`. A grid that contains the stored one extends the build (its
        points are kept, ``build.json`` records the new grid and the date); another grid, or
        options different from the stored ones, are refused (start a new folder).
    options : dict, optional
        Solver options per method, merged over :data:`DEFAULT_OPTIONS`: for ``bem`` those of
        :func:`bem.vesicle.check_vesicle_inputs` (``n_modes``, ``tol``, ...), for
        ``lubrication`` ``tol``.
    workers : int, optional
        Local worker processes, 1 to :func:`max_workers` (default: the number of cores); 1
        solves in this process. Not with ``scheduler``.
    scheduler : str, optional
        Address of a Dask distributed scheduler; the lines run there instead.
    max_time : float, optional
        Wall-time budget of each point [s], > 0; None: no limit.
    retry_failed : bool
        Solve again the points stored as failed (default: finished points are never recomputed).
    progress : callable, optional
        ``progress(state)`` with ``state`` = dict(done, total, failed, new, running, eta_s)
        whenever a point is stored (at most every 0.5 s in parallel runs).
    pack : bool
        Pack the finished points into ``<folder>/solution_map.json`` at the end.

    Returns
    -------
    dict
        ``total``, ``done``, ``failed``, ``missing`` point counts, ``new`` (solved now),
        ``timed_out`` (of those, stopped at ``max_time``), ``seconds``, ``errors`` (lines that
        raised) and ``map`` (the packed file or None).

    Raises
    ------
    InvalidParameterError
        Before the folder is touched: a grid point or option the solvers refuse
        (:func:`check_build`), ``workers`` out of range or given with ``scheduler``, an
        unreachable scheduler. After taking the folder's lock (nothing written): another build
        holds it, or its ``build.json`` is unreadable, of another grid or options, or records
        values the solvers refuse.
    """
    folder = Path(folder)
    options = {m: {**DEFAULT_OPTIONS.get(m, {}), **(options or {}).get(m, {})} for m in METHODS}
    check_build(grid if grid is not None else make_grid(), options, max_time)
    if workers is not None:
        if scheduler:
            raise InvalidParameterError("workers", workers, "none with a scheduler (the "
                                        "cluster's workers run the lines)")
        check_range("workers", workers, 1, max_workers(), reason="one process per core")
        if int(workers) != workers:
            raise InvalidParameterError("workers", workers, f"an integer, 1 <= workers <= "
                                        f"{max_workers()}")
    client = _connect(scheduler) if scheduler else None
    try:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InvalidParameterError("out", str(folder), "a folder that can be created",
                                        exc.strerror or str(exc)) from None
        with _locked(folder) as lock_fd:
            old, old_grid = _read_build(folder)
            if old is not None:
                extended = grid is not None and grid != old_grid
                if extended and not _contains(grid, old_grid):
                    raise InvalidParameterError(
                        "out", str(folder), "a new folder, the grid it was built with, or a "
                        "grid that contains it (an extension)", "it holds a build of another "
                        "grid")
                stored = old.get("parameters", {}).get("options")
                if stored != json.loads(json.dumps(options)):
                    raise InvalidParameterError("out", str(folder), "a new folder, or the "
                                                "solver options it was built with", "it holds "
                                                f"a build with options {stored}")
                if extended:             # the stored points stay; only the new ones are solved
                    old["grid"] = grid
                    old.setdefault("extended", []).append(_now())
                    write_json(folder / "build.json", old, indent=1, sort_keys=False)
                grid = grid or old_grid
                provenance = old.get("provenance", {})
            else:
                grid = grid or make_grid()
                info = {"grid": grid, "parameters": {"options": options, "max_time": max_time},
                        "provenance": run_provenance()}      # its date: the build's start
                write_json(folder / "build.json", info, indent=1, sort_keys=False)
                provenance = info["provenance"]
            provenance = {k: v for k, v in provenance.items() if k not in ("created", "date")}
            return _run(folder, grid, options, workers, client, max_time, retry_failed,
                        progress, pack, provenance, lock_fd)
    finally:
        if client is not None:
            client.close()


def _own_temporaries(folder: Path) -> list[Path]:
    """The temporaries of :func:`lubrication.io.atomic_write` (``.NAME.XXXXXXXX.tmp``) of the
    files a build writes (``build.json`` and the point files): other files in the folder, and
    temporaries of files of other names, are not the build's to remove."""
    def own(name: str) -> bool:
        target = temporary_target(name)
        return target is not None and (target == "build.json"
                                       or fnmatch.fnmatchcase(target, POINT_GLOB))
    return [p for p in folder.glob(".*.tmp") if own(p.name) and p.is_file()]


def _run(folder, grid, options, workers, client, max_time, retry_failed, progress, pack,
         provenance, lock_fd=None) -> dict:
    started = time.monotonic()
    for tmp in _own_temporaries(folder):   # left by a killed build
        tmp.unlink(missing_ok=True)
    stored: dict = {}
    for p in read_points(folder, "out"):
        if p["success"] or not retry_failed:
            key = (p["method"], round(p["ca_b"], 9))
            stored.setdefault(key, {})[(round(p["nu"], 9), round(p["lam_ratio"], 9))] = p
    lines = line_tasks(grid)
    total = sum(len(points) for _, _, points in lines)
    state = {"total": total, "new": 0, "failed": 0, "timed_out": 0, "running": 0, "errors": []}

    def missing(method, ca, points) -> int:
        have = stored.get((method, round(ca, 9)), {})
        return sum((round(nu, 9), round(r, 9)) not in have for nu, r in points)

    jobs = [(m, ca, points, stored.get((m, round(ca, 9)), {})) for m, ca, points in lines
            if missing(m, ca, points)]
    done_before = total - sum(missing(m, ca, points) for m, ca, points, _ in jobs)

    def report() -> None:
        state["done"] = done_before + state["new"]
        rate = state["new"] / max(time.monotonic() - started, 1e-9)
        left = total - state["done"]
        state["eta_s"] = left / rate if rate > 0 else None
        if progress is not None:
            progress({k: state[k] for k in ("done", "total", "failed", "new", "running",
                                            "eta_s")})

    state["failed"] = sum(1 for by_point in stored.values() for p in by_point.values()
                          if not p["success"])
    report()

    def on_point(record) -> None:
        state["new"] += 1
        state["failed"] += not record["success"]
        state["timed_out"] += status_of(record) is Status.TIME_LIMIT
        report()

    args = (options, max_time, provenance)
    if client is None and (workers or os.cpu_count() or 1) <= 1:
        state["running"] = 1
        for method, ca, points, have in jobs:
            solve_line(str(folder), method, ca, points, have, *args, on_point=on_point)
    else:
        _parallel(folder, jobs, args, workers, client, state, report, lock_fd)
    state["running"] = 0
    packed = pack_map(folder) if pack else None
    missing = total - done_before - state["new"]
    return {"total": total, "done": total - missing, "failed": state["failed"],
            "timed_out": state["timed_out"],
            "missing": missing, "new": state["new"], "errors": state["errors"],
            "seconds": time.monotonic() - started, "map": str(packed) if packed else None}


def _point_names(folder) -> set[str]:
    return {p.name for p in Path(folder).glob(POINT_GLOB)
            if not p.name.startswith(".")}


def _pool_context():
    """Start method of the local pool: fork (cheap; workers inherit the parent's state), but
    spawn once this process has started numba's parallel threading layer (a BEM solve in the
    same process): forking after GNU OpenMP has started aborts the workers ("fork() called
    from a process already using GNU OpenMP")."""
    numba = sys.modules.get("numba")
    if numba is not None:
        try:
            numba.threading_layer()        # ValueError until a parallel kernel has run
            return multiprocessing.get_context("spawn")
        except ValueError:
            pass
    return multiprocessing.get_context("fork")


def _parallel(folder, jobs, args, workers, client, state, report, lock_fd=None) -> None:
    """Run the line jobs on a process pool or a Dask client, polling the build folder for
    progress; Ctrl-C stops the workers and propagates. ``lock_fd``: the build lock's
    descriptor, which forked workers close (:func:`_init_worker`)."""
    executor = None
    if client is None:
        cores = os.cpu_count() or 1
        n = min(workers or cores, max(len(jobs), 1))
        parent = os.getpid()
        context = _pool_context()
        inherited = lock_fd if context.get_start_method() == "fork" else None
        executor = ProcessPoolExecutor(n, mp_context=context, initializer=_init_worker,
                                       initargs=(parent, inherited))
        threads = max(1, cores // n)
        submit = executor.submit
    else:
        def submit(*a, **k):
            return client.submit(*a, pure=False, **k)
        parent, threads = None, _dask_threads(client)
    seen = _point_names(folder)
    pending: dict = {}
    try:
        pending = {submit(solve_line, str(folder), m, ca, points, have, *args,
                          parent_pid=parent, threads=threads): (m, ca, points[0])
                   for m, ca, points, have in jobs}
        while pending:
            time.sleep(0.5)
            finished = [f for f in pending if f.done()]
            for f in finished:
                line = pending.pop(f)
                try:
                    for record in f.result():
                        path = Path(folder) / point_filename(record["method"], record["nu"],
                                                             record["lam_ratio"], record["ca_b"])
                        if not path.exists():
                            write_json(path, record, indent=1, sort_keys=False)
                except Exception as exc:    # noqa: BLE001 - a crashed line is reported
                    state["errors"].append(f"line {line}: {type(exc).__name__}: {exc}")
                    log.error("map build: line %s raised %s", line, exc)
            now = _point_names(folder)
            fresh = now - seen
            if fresh or finished:
                seen |= fresh
                state["new"] += len(fresh)
                records = [read_point(Path(folder) / n, "out") for n in fresh]
                state["failed"] += sum(not r["success"] for r in records)
                state["timed_out"] += sum(status_of(r) is Status.TIME_LIMIT for r in records)
                state["running"] = len(pending)
                report()
    except BaseException:
        if executor is not None:
            _stop(executor)
        elif client is not None:
            client.cancel(list(pending))
        raise
    if executor is not None:
        executor.shutdown(wait=True)


# --------------------------------------------------------------------------- seed bank

def write_seed_bank(folder, out) -> Path:
    """Write the converged BEM shapes of the build ``folder`` as a :class:`bem.seed_bank.SeedBank`
    to ``out`` (``.npz``); returns the path. Densities are padded with zero terms to the longest
    one (a zero term leaves the density unchanged)."""
    from bem.seed_bank import SeedBank  # lazy: numpy-only, but off the build's input checks
    shapes = [p for p in read_points(folder) if p["method"] == "bem" and p["success"]
              and p.get("shape")]
    width = max((len(p["shape"]["density"]) for p in shapes), default=0)
    SeedBank.from_shapes(
        (p["nu"], p["lam_ratio"], p["ca_b"], p["shape_class"], p["shape"]["modes"],
         list(p["shape"]["density"]) + [0.0] * (width - len(p["shape"]["density"])))
        for p in shapes).save(out)
    return Path(out)
