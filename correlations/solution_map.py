r"""The shipped solution map: stored steady solutions over (ν, λ/λc, Ca_B), packed, and queried
with an error bar.

Scalings (project conventions): R0 volume radius, R tube radius, λ = R0/R, λc(ν) the critical
confinement, δ = 1 − λ/λc, U the mean velocity; V/U, Δp⁺R0/(ηU) (``dp_plus_R0``), lengths in R,
tensions in ηU, wall shear stress in ηU/R, curvatures in 1/R, Ca_B = ηUR0²/κ.

Three layers, in the order of the data's life:

1. **Points** (written by :mod:`correlations.map_build`): one JSON file per finished grid point
   of a build folder, named by :func:`point_filename`, with the inputs, the method, ``success``,
   ``status`` (a :class:`lubrication.results.Status` value), the reason of a failure, the
   quantities of :data:`QUANTITIES`, the solver's own error estimates, diagnostics, the BEM
   shape (for warm starts) and provenance. A failed point is stored as failed, never filled
   in.
2. **Pack** (:func:`pack_map`): the converged points of a build folder as one compact JSON file
   (format :data:`FORMAT`): the grid, provenance, column units, one list per column (no shapes),
   the holes (failed or missing points with their reasons) and the leave-one-out interpolation
   errors of every node, measured at pack time.
3. **Query** (:func:`query_map`, :func:`query_map_many` for many points at once): every
   quantity at (ν, λ/λc, Ca_B) with its value, an interpolation-error estimate, the solver's
   own error, the BEM–lubrication model error where lubrication points are used, and the
   methods of the neighbouring points. Which nodes enter (the stencil) is found once per
   position in the grid for all quantities and all points there, their weights per point
   (:class:`SolutionMap`); a query at one point is a query of many with one point.

Which method a node uses (the rule)
-----------------------------------
At each grid node (ν, λ/λc, Ca_B) the map takes the BEM point if it converged, else the
lubrication point if it converged, else the node is a hole (with both reasons). Lubrication is
thus used only where BEM has no converged point, in practice next to λc where BEM is hardest
and lubrication becomes exact (Secomb et al. 1986; Barakat & Shaqfeh 2018b). Below the largest
λ/λc of a (ν, Ca_B) line with a converged BEM point, a node off the BEM grid (the
lubrication-only nodes 0.92, 0.94, … between the BEM nodes 0.9, 0.95, 0.98) is left out of that
line (:meth:`SolutionMap.superseded`): interpolating the BEM neighbours is more accurate there
than lubrication, whose Δp⁺ is 5–15 % low at δ = 0.02–0.1
(tests/benchmarks/lubrication_overlap.py). A lubrication
value carries a *model error*: the difference between lubrication and BEM measured at the
largest λ/λc of the same (ν, Ca_B) line where both converged (the default grids overlap at
λ/λc = 0.9–0.98 for this). Lubrication approaches the full Stokes solution as δ → 0, so the
difference at the last common point bounds it above that point. A line without a common point
reports the model error as unknown (None, with a note) rather than guessing.

Interpolation variables
-----------------------
Near λc the solutions are expansions in powers of δ^(1/2) (lubrication structure, Barakat &
Shaqfeh 2018a; physics notes §4: Q = δ[1 − kδ^(1/2)/ℓb + …]), with leading singular or vanishing
powers of δ. The map therefore interpolates, along λ, in the coordinate x = δ^(1/2), and
interpolates the *scaled* quantities that stay finite and smooth as δ → 0 (:data:`TRANSFORMS`):

* (V/U − 1)/δ → 1 (V/U = 1 + δ + O(δ^(3/2)), Barakat & Shaqfeh 2018a; Chen et al. 2020
  eq:vel2), which also tends to 1 as λ → 0 (V/U → 2, Chen et al. 2020 eq:small1);
* δ·Δp⁺R0/(ηU)·(λ/λc)^(−6): δΔp⁺ → 4λ(X − 1), X = λc²ν^(−2/3) (Chen et al. 2020 eq:asmyp2),
  and Δp⁺R0/(ηU) ∝ λ⁶ as λ → 0 (small sphere, Chen et al. 2020 eq:small2), so the factor
  (λ/λc)^(−6) takes the small-λ power out (Δp⁺ changes tenfold between λ/λc = 0.2 and 0.3);
* film/δ (uniform film h/R = Q ≈ δ; Chen et al. 2020 eq. sfilm2);
* ℓ/(λ/λc) (ℓ ≈ ℓc λ/λc near λc, Chen et al. 2020 eq:sL; ℓ → 2λ for a small sphere);
* δ^(3/2)·γ for γ_max and γ_front (Bretherton-type film h/R = 2.123 Ca_v^(2/3) with Ca_v =
  ηV/γ_F, Secomb et al. 1986, Chen et al. 2020 eq. sfilm4, and h ≈ δ give γ ∝ δ^(−3/2));
* δ·τ_w,max (gap shear ≈ V/h with h ≈ δ);
* the rear-pole curvature as it is (it changes sign at the bullet–parachute transition).

Positive scaled quantities are interpolated in their logarithm (relative accuracy over decades),
the curvature (or any quantity whose neighbours are not all positive) linearly. Across ν the
coordinate is ν, across Ca_B it is log Ca_B. Each axis uses local Lagrange interpolation of
degree 2, tensor-product fashion (λ first, then Ca_B, then ν): the two nodes that bracket the
query and the nearest third node whose points share the method and the shape class of the
bracketing pair's; without such a node the interpolation on that axis is linear. A quadratic
through a bullet–parachute branch change (at small λ/λc the low-ν vesicles are elongated
bullets at Ca_B = 15 and parachutes at Ca_B = 50) or through a BEM–lubrication change of method
is worse than a line (measured on the off-grid points of tests/benchmarks/map_offgrid.py: with
the third node taken across such changes V/U was off by up to 1.75 % and Δp⁺ by 30 %).
Between such nodes the elongated and the parachute states can both be steady
(tests/benchmarks/map_bistability.py): each node holds the branch its build reached, and the
query's shape class is None where the nodes around it differ. A query
on a grid node on some axis takes that node's values on that axis exactly.

Error bar
---------
``interpolation_error``: at pack time every node is left out in turn along each axis and
re-interpolated from the others (extrapolating at the ends of an axis); the difference is its
leave-one-out (LOO) error on that axis, in the interpolated (transformed) variable. A query adds,
over the axes it does not sit on, the largest LOO error on that axis of the points at the
corners of its grid cell (the nodes that bracket it on every axis; on each line the λ/λc nodes
it uses), taking the corners at interior nodes of the axis where there are any (an end node's
LOO is an extrapolation), plus the weighted errors of the inner axes, and divides the sum by
:data:`LOO_RATIO` = 2. Removing a node doubles the local spacing; interpolation of degree p
has an error ∝ h^(p+1), so where the data are smooth LOO overestimates the full grid's error
4× (linear stencils) to 8× (quadratic). The map's data are not everywhere that smooth (branch
changes, a coarse Ca_B axis), so only the factor 2 is taken out. Measured on the off-grid
points of tests/benchmarks/map_offgrid.py (where the bar is pessimistic, several times the
error in the median) and on maps with every other ν node, or some λ/λc nodes, left out
(tests/benchmarks/map_error_bars.py, where LOO spans four grid steps and the bar covers less);
the coverage numbers of both are in docs/validation.md (solution map). Dividing by 4 instead
lowered the coverage on the coarsened maps to about half of the points.
``solver_error``: the solver's own error estimate (BEM refinement
pair ``|fine − coarse|`` for V/U, Δp⁺ and γ_max; none otherwise) propagated with the interpolation
weights; None when a neighbour has none. ``model_error``: see the rule above (and the Ca_B clamp
below). ``error`` = the sum of the known parts, in the quantity's units.

Files read (what is refused)
----------------------------
Every file is read through :mod:`correlations.files` (a regular file, size, nesting depth and
integer-length limits, strict JSON) and then checked against its schema: a point file
(:func:`read_point`: coordinates in range, known method and status, ``success`` that agrees
with the status, numbers or null where numbers are stored, a shape of number lists), the
``build.json`` of a build folder and the grid of a packed map (:func:`_check_grid`: distinct
values in range), and the packed map (:func:`_check_packed`: every column the queries read,
one value of the right kind per node). A converged point whose quantity is missing, not finite
or outside :data:`lubrication.checks.OUTPUT_BOUNDS` (:func:`_rejection`; e.g. V/U = 7, a
negative film) is no node: :func:`pack_map` makes it a hole and lists it under ``rejected``,
and :func:`load_map` refuses a packed map holding such a node, or no node at all. Failures
raise :class:`~correlations.files.UnreadableFile` naming the option (``map``, ``folder``) and
the file, which the command line answers with exit 2.

Range (what is refused)
-----------------------
A quantity is None with its reason, never extrapolated, when the query lies outside the map's ν
range, below its smallest or above its largest λ/λc, below its smallest Ca_B, or next to a hole
(a bracketing node on some axis is a hole). Above the largest Ca_B of the map (500 by default)
and up to :data:`CA_B_CLAMP_MAX` = 1e4 the values at the largest Ca_B are returned when that is
at least 50: Chen et al. (2020) §IV.A (fig. shapes1) find the steady shape "virtually independent
of Ca_B" for Ca_B ≥ 50 and their phase diagram spans 10 < Ca_B < 1e4. The clamp is not trusted
blindly: its model error is the measured change of the (scaled) quantity between the two
largest Ca_B of the map (e.g. 50 and 500), added to the error bar. Beyond 1e4 the query is refused.

Membrane: a vesicle map or a red-cell map
-----------------------------------------
A map knows the membrane of its points (:attr:`SolutionMap.membrane`, from the packed
``parameters``): None for a vesicle (bending, local inextensibility, no shear elasticity),
``{"shear_ratio": β, "reference": name}`` for a red cell built with the BEM option
``shear_ratio`` β = G_s R0²/κ = Ca_B/Ca_S (:data:`SHEAR_RATIO`, the build option; Evans's
area-incompressible shear law, Evans 1973, about a stress-free shape ``reference``). A line in
Ca_B of a red-cell map is one cell (one β) at different velocities, so the Ca_S of a query is
Ca_B/β. Its answers hold for that β only: the caller compares the cell's β with the map's
(:func:`correlations.estimate.estimate`). Every query result carries the membrane
(:attr:`MapQuery.membrane`), so that a red-cell answer is never read as a vesicle's. The Ca_B
clamp above is a vesicle result (Chen et al. 2020 §IV.A) and does not apply to a red-cell map:
along a red-cell line Ca_S grows with Ca_B and the solution keeps changing (docs/red-cell.md:
Δp⁺ changes by 4–19 % per doubling of U at 4–8 mm/s), so above its largest Ca_B a red-cell map
refuses, as below its smallest.
"""

from __future__ import annotations

import bisect
import functools
import itertools
import json
import math
import operator
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import NamedTuple

import numpy as np

from lubrication.checks import (OUTPUT_BOUNDS, CannotPassError, InvalidParameterError, as_finite,
                                check_output, check_positive)
from lubrication.io import atomic_write, clean_json
from lubrication.results import Status, status_of

from .files import check_input_file, expect, read_json

__all__ = ["FORMAT", "POINT_FORMAT", "POINT_GLOB", "QUANTITIES", "TRANSFORMS", "DEFAULT_MAP",
           "RED_CELL_MAP", "SHEAR_RATIO", "CA_B_CLAMP_MAX", "CA_B_NODE_ATOL", "membrane_of", "require_vesicle_map", "MapValue", "MapQuery", "SolutionMap", "point_filename", "read_point",
           "read_points", "read_build", "pack_map", "load_map", "query_map", "query_map_many"]

#: identifiers of the packed file and of a stored point (checked on load)
FORMAT, FORMAT_VERSION = "vesicle-tube solution map", 1
POINT_FORMAT = "vesicle-tube map point"

#: where the shipped map lives (package data); absent until a build has been packed there
DEFAULT_MAP = Path(__file__).with_name("data") / "solution_map.json"

#: where the shipped red-cell slice lives (package data; a map whose membrane is a red cell's,
#: :attr:`SolutionMap.membrane`); absent until its build has been packed there
RED_CELL_MAP = Path(__file__).with_name("data") / "rbc_slice_map.json"

#: the BEM build option of a red-cell map (correlations.map_build.point_options): the cell's
#: β = G_s R0²/κ = Ca_B/Ca_S, stored in the packed ``parameters.options.bem``
SHEAR_RATIO = "shear_ratio"
#: stress-free shape of a red-cell map built without a ``reference`` option: the default of
#: :func:`bem.vesicle.solve_vesicle` (the Evans–Fung disc, :mod:`lubrication.membrane`)
DEFAULT_REFERENCE = "biconcave"

#: largest Ca_B answered by clamping to the map's largest Ca_B (see the module docstring)
CA_B_CLAMP_MAX = 1e4

#: The quantities a point stores and the map interpolates, with their units.
QUANTITIES = {
    "V_over_U": "vesicle velocity over the mean velocity V/U [-]",
    "dp_plus_R0": "extra pressure drop dp+ R0/(eta U) [-]",
    "ell": "length L/R as the solver reports it [-]",
    "film_min": "smallest gap between membrane and wall h/R [-]",
    "tension_max": "largest membrane tension gamma_max/(eta U) [-]",
    "tension_front": "front-pole tension gamma_F/(eta U) [-]",
    "wall_shear_max": "largest wall shear stress tau_w R/(eta U) [-]",
    "curvature_rear": "rear-pole curvature times R, negative where convex [-]",
}

#: Interpolated variable of each quantity q (module docstring):
#: y = (q - offset) * delta**power * (lam/lam_c)**(-ratio_power), in its logarithm when ``log``
#: and every neighbour is positive.
TRANSFORMS = {
    "V_over_U": {"offset": 1.0, "power": -1.0, "log": True},
    "dp_plus_R0": {"offset": 0.0, "power": 1.0, "ratio_power": 6.0, "log": True},
    "ell": {"offset": 0.0, "power": 0.0, "ratio_power": 1.0, "log": True},
    "film_min": {"offset": 0.0, "power": -1.0, "log": True},
    "tension_max": {"offset": 0.0, "power": 1.5, "log": True},
    "tension_front": {"offset": 0.0, "power": 1.5, "log": True},
    "wall_shear_max": {"offset": 0.0, "power": 1.0, "log": True},
    "curvature_rear": {"offset": 0.0, "power": 0.0, "log": False},
}

#: columns of the packed file besides the quantities and their errors, with units
_BASE_COLUMNS = {
    "method": "solver: bem or lubrication",
    "nu": "reduced volume [-]",
    "lam_ratio": "lam/lam_c [-]",
    "ca_b": "bending capillary number eta U R0^2/kappa [-]",
    "lam": "confinement R0/R [-]",
    "shape_class": "bullet or parachute",
    "residual": "solver residual (BEM: max|u - V e_x| [U]; lubrication: largest relative "
                "collocation residual) [-]",
    "bie_solves": "boundary-integral solves of the point (BEM; None for lubrication)",
    "seconds": "wall-clock time of the point [s]",
}
#: What the error bar divides the leave-one-out errors by (module docstring, error bar).
LOO_RATIO = 2.0
_DIGITS = {"residual": 3, "seconds": 3}   # significant digits of a packed column (default 10)
_PACK_RTOL = 5e-10                          # relative rounding of a 10-digit packed value
_AXES = ("lam", "nu", "ca")      # order of interpolation: lam (x = delta^1/2), ca (log), nu
_ON_NODE = 1e-12                 # a coordinate this close (relative) to a node is that node
#: A Ca_B this close (absolute) to a Ca_B node is that node: builds store the Ca_B of a velocity
#: rounded to 4 decimals (tests/benchmarks/rbc_slice_build.py), so the Ca_B a user's velocity
#: gives differs from its node by up to 5e-5; moving it there changes a quantity by at most
#: 5e-5/Ca_B relative per unit of d ln Q/d ln Ca_B (≤ 2e-5 at the red-cell slice's smallest
#: Ca_B), far below every error bar.
CA_B_NODE_ATOL = 5e-5


# --------------------------------------------------------------------------- file schemas

_METHODS = ("bem", "lubrication")
_POINT_WHAT = "a point file of 'vesicle-tube map build'"
_BUILD_WHAT = "a build folder of 'vesicle-tube map build' (build.json and point files)"
_MAP_WHAT = "a packed map of 'vesicle-tube map pack'"

#: The quantities of a map node held to :data:`lubrication.checks.OUTPUT_BOUNDS`, with the name
#: of their bound (the tensions have none).
_BOUNDED = {"V_over_U": "V_over_U", "dp_plus_R0": "dp_plus_R0", "ell": "ell", "film_min": "film"}


def _number(v) -> bool:
    """A finite JSON number (``true`` is no number; a literal such as 1e999 parses as inf)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _numbers(v, nonempty: bool = False) -> bool:
    """A list of finite numbers (non-empty if ``nonempty``)."""
    return isinstance(v, list) and (bool(v) or not nonempty) and all(map(_number, v))


_NUMBER_TYPES = frozenset((int, float, type(None)))
_not_none = functools.partial(operator.is_not, None)


def _null_or_numbers(column: list) -> bool:
    """Every value of ``column`` null or a finite number (the kind "number" of :data:`_KIND`),
    tested in C: a packed map's columns hold tens of thousands of values, read at every
    start of the estimate. False also where the per-value test would accept (a subclass of
    float); the caller then makes that test."""
    return (_NUMBER_TYPES.issuperset(map(type, column))
            and all(map(math.isfinite, filter(_not_none, column))))


def _show(v) -> str:
    """A JSON value for a message: its repr, at most 40 characters."""
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


#: Kinds of the fields of a point file and of a packed map: (test, what the message expects).
_KIND = {
    "nu": (lambda v: _number(v) and 0.0 < v <= 1.0, "a number with 0 < nu <= 1"),
    "lam_ratio": (lambda v: _number(v) and 0.0 < v < 1.0, "a number with 0 < lam_ratio < 1"),
    "ca_b": (lambda v: _number(v) and v > 0.0, "a number > 0"),
    "method": (lambda v: v in _METHODS, "'bem' or 'lubrication'"),
    "success": (lambda v: isinstance(v, bool), "true or false"),
    "status": (lambda v: v is None or v in tuple(s.value for s in Status),
               "null or one of " + ", ".join(repr(s.value) for s in Status)),
    "shape_class": (lambda v: v in (None, "bullet", "parachute"),
                    "'bullet', 'parachute' or null"),
    "text": (lambda v: v is None or isinstance(v, str), "text or null"),
    "number": (lambda v: v is None or _number(v), "a finite number or null"),
    "positive": (lambda v: v is None or (_number(v) and v > 0), "a number > 0 or null"),
    "count": (lambda v: v is None or (isinstance(v, int) and not isinstance(v, bool) and v >= 0),
              "an integer >= 0 or null"),
    "object": (lambda v: v is None or isinstance(v, dict), "an object or null"),
}

#: The fields of a point file its readers use (packing, resuming a build, the figures), with
#: their kinds; the first five are required, the others may be absent.
_POINT_FIELDS = {"method": "method", "nu": "nu", "lam_ratio": "lam_ratio", "ca_b": "ca_b",
                 "success": "success", "status": "status", "message": "text",
                 "shape_class": "shape_class", "lam": "positive", "lam_c": "positive",
                 **dict.fromkeys(QUANTITIES, "number"), "residual": "number",
                 "bie_solves": "count", "seconds": "number", "error_estimate": "object",
                 "shape": "object"}
_REQUIRED = ("method", "nu", "lam_ratio", "ca_b", "success")


def _schema(name: str, path, what: str):
    """``check(condition, reason)``: :func:`correlations.files.expect` for one file."""
    def check(condition: bool, reason: str) -> None:
        expect(condition, name=name, path=path, what=what, reason=reason)
    return check


def _check_fields(data: dict, kinds: dict, check, where: str = "") -> None:
    """Every field of ``kinds`` present in ``data`` is of its kind."""
    for key, kind in kinds.items():
        if key in data:
            ok, expected = _KIND[kind]
            check(ok(data[key]), f"the field '{where}{key}' is {_show(data[key])}, not "
                                 f"{expected}")


def _check_point(data, check) -> None:
    """Schema of a point file: the header, the fields of :data:`_POINT_FIELDS`, the solver's
    error estimates, the stored shape, and a ``success`` that agrees with ``status``."""
    check(isinstance(data, dict) and data.get("format") == POINT_FORMAT,
          "not a map point file (no 'format' header)")
    for key in _REQUIRED:
        check(key in data, f"point file without {key!r}")
    _check_fields(data, _POINT_FIELDS, check)
    _check_fields(data.get("error_estimate") or {}, dict.fromkeys(QUANTITIES, "number"), check,
                  "error_estimate.")
    shape = data.get("shape")
    if shape is not None:
        check(_numbers(shape.get("modes"), nonempty=True) and _numbers(shape.get("density")),
              "the field 'shape' has no lists of numbers 'modes' and 'density'")
        check(data.get("lam") is not None, "a point with a 'shape' has no 'lam'")
    status = data.get("status")
    check(status is None or data["success"] == (status == Status.CONVERGED.value),
          f"'success' {data['success']} contradicts 'status' {status!r}")


def _check_grid(grid, check) -> None:
    """Schema of a grid (of ``build.json`` or of a packed map): distinct known methods, and
    non-empty lists of distinct values in range for ν, Ca_B and each method's λ/λc."""
    check(isinstance(grid, dict), "no 'grid' object")
    methods = grid.get("methods")
    check(isinstance(methods, list) and bool(methods) and all(m in _METHODS for m in methods)
          and len(set(methods)) == len(methods),
          "'grid.methods' is not a non-empty list of distinct 'bem', 'lubrication'")
    ratios = grid.get("lam_ratio")
    check(isinstance(ratios, dict) and all(m in ratios for m in methods),
          "'grid.lam_ratio' is not an object with a list for each method")
    for field_, values in [("nu", grid.get("nu")), ("ca_b", grid.get("ca_b"))] + [
            (f"lam_ratio.{m}", ratios[m]) for m in methods]:
        ok, expected = _KIND[field_.split(".")[0]]
        check(isinstance(values, list) and bool(values) and all(map(ok, values)),
              f"'grid.{field_}' is not a non-empty list of values, each {expected}")
        check(len({round(v, 9) for v in values}) == len(values), f"'grid.{field_}' repeats a "
              "value")


def read_build(folder, name: str = "folder") -> dict:
    """The ``build.json`` of a build folder, its schema checked (a grid of :func:`_check_grid`,
    ``parameters`` with ``options`` and ``provenance`` objects); raises
    :class:`~correlations.files.UnreadableFile` naming ``name`` otherwise."""
    path = Path(folder) / "build.json"
    build = read_json(path, name=name, what=_BUILD_WHAT)
    check = _schema(name, path, _BUILD_WHAT)
    check(isinstance(build, dict), "build.json is not a JSON object")
    _check_grid(build.get("grid"), check)
    for key in ("parameters", "provenance"):
        check(isinstance(build.get(key, {}), dict), f"the field {key!r} is not an object")
    check(isinstance(build.get("parameters", {}).get("options", {}), dict),
          "the field 'parameters.options' is not an object")
    return build


def _rejection(point: dict) -> str:
    """Why a converged point (a stored point, or a row of a packed map) cannot be a map node
    ('' if it can): a quantity of :data:`QUANTITIES` missing or not finite, or outside its
    physical bound (:data:`_BOUNDED`, :func:`lubrication.checks.check_output`)."""
    for q in QUANTITIES:
        v = point.get(q)
        if not _number(v):
            return f"{q} = {_show(v)} is not a finite number"
        why = check_output(_BOUNDED[q], float(v), {}) if q in _BOUNDED else ""
        if why:
            return why if _BOUNDED[q] == q else f"{q}: {why}"
    return ""


# --------------------------------------------------------------------------- points on disk

def _num(x) -> str:
    """A grid value in a file name: shortest exact-enough text (10 significant digits)."""
    return f"{float(x):.10g}"


#: the names :func:`point_filename` gives, as a glob pattern
POINT_GLOB = "*_nu*_lr*_caB*.json"


def point_filename(method: str, nu: float, lam_ratio: float, ca_b: float) -> str:
    """File name of a stored point, e.g. ``bem_nu0.9_lr0.95_caB50.json``.

    >>> point_filename("lubrication", 0.6, 0.9999, 500)
    'lubrication_nu0.6_lr0.9999_caB500.json'
    """
    return f"{method}_nu{_num(nu)}_lr{_num(lam_ratio)}_caB{_num(ca_b)}.json"


def read_point(path, name: str = "folder") -> dict:
    """One stored point (a dict), read by :func:`correlations.files.read_json` and checked
    against the point schema (:func:`_check_point`); raises
    :class:`~correlations.files.UnreadableFile` naming ``name`` (the option or parameter that
    gave the build folder) and the file otherwise. Its ``"status"`` is a
    :class:`lubrication.results.Status` value: the stored one, or for a point file without
    one, the status :func:`lubrication.results.status_of` derives from ``success`` and
    ``message``."""
    data = read_json(path, name=name, what=_POINT_WHAT)
    _check_point(data, _schema(name, path, _POINT_WHAT))
    data["status"] = status_of(data).value
    return data


def read_points(folder, name: str = "folder") -> list[dict]:
    """Every stored point of a build folder (files named like :func:`point_filename`), each
    read by :func:`read_point` (``name``: the option that gave the folder)."""
    folder = Path(folder)
    return [read_point(p, name) for p in sorted(folder.glob(POINT_GLOB))
            if not p.name.startswith(".")]


# --------------------------------------------------------------------------- the map in memory

def _key(*values) -> tuple:
    """Dictionary key of grid coordinates (rounded: file names keep 10 digits)."""
    return tuple(round(float(v), 9) for v in values)


def _scale(q: str, ratio: float) -> float:
    """The factor δ^power (λ/λc)^(−ratio_power) of quantity ``q``'s interpolated variable."""
    t = TRANSFORMS[q]
    return (1.0 - ratio) ** t["power"] * ratio ** -t.get("ratio_power", 0.0)


def _transform(q: str, value, ratio: float, log: bool):
    """Interpolated variable of quantity ``q`` at λ/λc = ``ratio`` (None if the value is
    missing or, with ``log``, not positive after scaling)."""
    if value is None:
        return None
    y = (value - TRANSFORMS[q]["offset"]) * _scale(q, ratio)
    if log:
        return math.log(y) if y > 0 else None
    return y


def _inverse(q: str, y: float, ratio: float, log: bool) -> float:
    return (math.exp(y) if log else y) / _scale(q, ratio) + TRANSFORMS[q]["offset"]


def _locate(coords, x) -> tuple[int, range]:
    """Where ``x`` lies among the ascending ``coords``: ``pos`` with coords[:pos] < x <=
    coords[pos:], and the positions of the nodes within the on-node tolerance of x (next to pos
    and consecutive, since |coord − x| grows away from x; empty off the nodes)."""
    pos = bisect.bisect_left(coords, x)
    tol = _ON_NODE * max(1.0, abs(x))
    lo = hi = pos
    while lo > 0 and abs(coords[lo - 1] - x) <= tol:
        lo -= 1
    while hi < len(coords) and abs(coords[hi] - x) <= tol:
        hi += 1
    return pos, range(lo, hi)


#: The note of a value whose error lacks parts, by which parts (interpolation, solver, model)
#: are unknown.
_UNKNOWN = {unknown: "error without the unknown " + ", ".join(
    name for name, u in zip(("interpolation", "solver", "model"), unknown) if u) + " part"
    for unknown in itertools.product((False, True), repeat=3)}


def _add(a, b):
    return None if a is None or b is None else a + b


class _Leaf:
    """A grid node where the map has a point (the rule of :meth:`SolutionMap.node`): its index
    in the node tables of the map, its grid coordinates, the key of its (ν, Ca_B) line, its
    row, and (as a :class:`_Stencil` has them) the rows used and their kinds (method, shape
    class)."""
    __slots__ = ("node", "row", "nu", "ratio", "ca", "line", "rows", "kinds")

    def __init__(self, node: int, row: int, nu: float, ratio: float, ca: float, line: tuple,
                 kind: tuple):
        self.node, self.row, self.nu, self.ratio, self.ca = node, row, nu, ratio, ca
        self.line, self.rows, self.kinds = line, frozenset((row,)), frozenset((kind,))


class _Stencil:
    """An interpolation along one axis without its values (the same for every quantity): the
    coordinates of the nodes used (ascending; their Lagrange weights at the query's coordinate
    are taken when the stencil is evaluated), what each node gives (an inner
    :class:`_Stencil` or a :class:`_Leaf`), the rows whose leave-one-out errors on this axis
    enter its interpolation error (None: no error bar is formed, as in a LOO extrapolation),
    and every row used with their kinds."""
    __slots__ = ("axis", "coords", "parts", "corners", "rows", "kinds")
    node = None                        # a leaf's is its index: the plan tells them apart by it

    def __init__(self, axis: str, coords: list, parts: list, rows: frozenset,
                 corners: tuple | None):
        self.axis, self.coords, self.parts, self.rows, self.corners = (axis, coords, parts,
                                                                       rows, corners)
        self.kinds = frozenset().union(*[p.kinds for p in parts])


@dataclass
class _Table:
    """Quantity ``q`` at the grid nodes in its interpolated variable (in its logarithm if
    ``log``), filled one (ν, Ca_B) line at a time as queries reach them (a query uses a few of
    the map's lines). By node index: ``y`` the value scaled with the node's own δ, ``solver``
    and ``model`` its errors in y (NaN where unknown, at a hole and on lines not filled; one
    more entry, 0, for the padding of a :class:`_Plan`); ``failed`` {node: reason} where the
    node has a point but no y (missing, or not positive where ``log``); ``notes`` {node: notes}
    where there are any; ``lines`` the lines filled; ``has_solver`` whether a node of these
    lines has a solver error. ``y``, ``solver`` and ``model`` are the columns ``column``,
    ``column + 1`` and ``column + 2`` of the map's node values (:class:`SolutionMap`), which
    the plans of many quantities read at once."""
    q: str
    log: bool
    column: int
    y: np.ndarray
    solver: np.ndarray
    model: np.ndarray
    failed: dict = field(default_factory=dict)
    notes: dict = field(default_factory=dict)
    lines: set = field(default_factory=set)
    has_solver: bool = False


# A stencil flattened (:class:`_Plan`): the tensor product of at most three nodes along ν,
# three along Ca_B under each and three along λ under each of those, in slots: slot 0 the ν
# axis, slots 1-3 the Ca_B axis under its nodes, slots 4-12 the λ axis under theirs
# (4 + 3 i_ν + i_Ca), the 27 leaves 9 i_ν + 3 i_Ca + i_λ. A slot of fewer than three nodes has
# the padding coordinates _FAR (second node) and -_FAR (third): far beyond any coordinate, so
# that (t - x_j)/(x_i - x_j) is exactly 1 for a padding x_j and the Lagrange weights of the
# nodes that exist are exactly theirs (1 for a single node: an axis on which the query sits on
# a node); the padding parts get tiny weights and the padding node, whose values are 0.
_PAD = -1                        # the padding node: the last entry of a table (0)
_FAR = 1e300
_SLOT_AXIS = [0] + [1] * 3 + [2] * 9     # the coordinate of each slot: ν, log Ca_B, x
#: Most plans a map keeps (about 2 kB each; random points over the shipped map make about
#: 6000); beyond, a query starts afresh.
_MAX_PLANS = 50_000


class _NoPlan(NamedTuple):
    """Where a point has no stencil: the reason, and the node indices looked at and the lines
    reached while finding that out."""
    reason: str
    looked: frozenset
    reached: frozenset


class _Plan:
    """A stencil (:meth:`SolutionMap._stencil`) flattened into the slots above, without the
    query's coordinates: the leaves' node indices, the coordinates of each slot's nodes (the
    Lagrange weights are taken at each query), the interpolation-error rows of each slot
    (``terms``: (axis, corner rows or None) where the slot interpolates, else None), whether
    every node is a BEM point, the rows used (sorted) and their methods, the node indices
    looked at and the (ν, Ca_B) lines reached while finding it, and the leaves in summing
    order; ``termed`` the quantities whose terms are worked out (:meth:`SolutionMap._terms`).
    Stencils found at points whose discrete position in the grid is the same
    (:meth:`SolutionMap._codes`) are the same but for the weights: a plan serves them all."""
    __slots__ = ("bem_only", "coords", "index", "leaves", "looked", "methods", "nodes", "reached",
                 "rows", "termed", "terms")

    def __init__(self, st, looked, reached, method_of):
        self.nodes = [_PAD] * 27
        self.coords, self.terms = [[0.0, _FAR, -_FAR] for _ in range(13)], [None] * 13

        def take(p, axis: str, slot: int) -> list:
            """The parts of ``p`` along ``axis``, put in ``slot``."""
            if isinstance(p, _Stencil) and p.axis == axis:
                self.coords[slot][:len(p.parts)] = p.coords
                self.terms[slot] = (axis, p.corners)
                return p.parts
            return [p]                     # on a node of this axis: the part itself

        leaves = []
        for i, p in enumerate(take(st, "nu", 0)):
            for j, q in enumerate(take(p, "ca", 1 + i)):
                for k, leaf in enumerate(take(q, "lam", 4 + 3 * i + j)):
                    self.nodes[9 * i + 3 * j + k] = leaf.node
                    leaves.append(leaf.node)
        self.leaves = tuple(leaves)
        self.rows = tuple(sorted(st.rows))
        self.methods = tuple(sorted({method_of[r] for r in st.rows}))
        self.bem_only = all(method == "bem" for method, _ in st.kinds)
        self.looked, self.reached, self.index, self.termed = looked, reached, None, set()


_OTHERS = np.array([[1, 2], [0, 2], [0, 1]])      # the nodes j ≠ i of three, in order


def _weights(coords, t):
    """Lagrange weights (..., 3) at ``t`` (...) of the three nodes ``coords`` (..., 3):
    w_i = Π_{j≠i} (t − x_j)/(x_i − x_j), factor by factor in the order of j."""
    xj = coords[..., _OTHERS]                                     # (..., 3, 2)
    f = (t[..., None, None] - xj) / (coords[..., None] - xj)
    return f[..., 0] * f[..., 1]


def _dot(w, v):
    """Σ_i w_i v_i over the nodes (the second last axis, three terms), in the nodes' order."""
    return w[..., 0, :] * v[..., 0, :] + w[..., 1, :] * v[..., 1, :] + w[..., 2, :] * v[..., 2, :]


def _evaluate(plans, at, values, tables: list, terms) -> tuple:
    """(y, interpolation error, solver error, model error) of K quantities at N points (arrays
    (N, K), NaN where unknown) by their plans: ``plans`` (nodes (N, 27), coords (N, 13, 3),
    bem_only (N,)), ``at`` (N, 3) the points' ν, log Ca_B and x = δ^½, ``values`` the map's
    node values (column 0 zeros), ``tables`` the quantities' :class:`_Table` (their columns),
    ``terms`` (N, 13, K) the interpolation-error term of each slot (:meth:`SolutionMap._terms`).

    Each is summed as the interpolation defines it, term by term in the nodes' order, along
    λ, then Ca_B, then ν: y = Σ w_i y_i; the interpolation error Σ |w_i| e_i (0 at the leaves)
    plus the slot's largest leave-one-out error of its corner rows over :data:`LOO_RATIO`; the
    solver and model errors Σ |w_i| e_i (the model error 0 where every node is a BEM point, the
    solver error unknown where no node of the lines reached has one). The 4K sums are taken
    together."""
    nodes, coords, bem_only = plans
    n, k = len(nodes), len(tables)
    w = _weights(coords, at[:, _SLOT_AXIS])[..., None]
    w = np.where(np.arange(4 * k) < k, w, np.abs(w))             # w for y, |w| for the errors
    columns = [t.column for t in tables]
    v = values[nodes[..., None], columns + [0] * k + [c + 1 for c in columns]
               + [c + 2 for c in columns]]                         # (N, 27, 4K)
    add = np.zeros((n, 13, 4 * k))
    add[..., k:2 * k] = terms
    v = _dot(w[:, 4:], v.reshape(n, 9, 3, -1)) + add[:, 4:]
    v = _dot(w[:, 1:4], v.reshape(n, 3, 3, -1)) + add[:, 1:4]
    v = _dot(w[:, 0], v) + add[:, 0]
    y, interp, solver, model = v[:, :k], v[:, k:2 * k], v[:, 2 * k:3 * k], v[:, 3 * k:]
    solver[:, [not t.has_solver for t in tables]] = np.nan
    model[bem_only] = 0.0
    return y, interp, solver, model


class _Plans:
    """The plans of a map in arrays, by index (grown as plans are added), for the arithmetic
    of many points at once; ``terms``: the interpolation-error term of each slot of each plan
    for each quantity of :data:`QUANTITIES` (their order), where worked out
    (:meth:`SolutionMap._terms`)."""

    def __init__(self):
        self.plans = []
        self.nodes = np.empty((0, 27), dtype=np.intp)
        self.coords = np.empty((0, 13, 3))
        self.bem_only = np.empty(0, dtype=bool)
        self.terms = np.empty((0, 13, len(QUANTITIES)))

    def add(self, plan: _Plan) -> _Plan:
        """Store ``plan`` (its terms are worked out when asked, :meth:`SolutionMap._terms`);
        returns it, indexed."""
        n = len(self.plans)
        if n == len(self.bem_only):        # full: double the arrays
            self.nodes, self.coords, self.bem_only, self.terms = (
                np.concatenate([a, np.empty_like(a, shape=(max(n, 16),) + a.shape[1:])])
                for a in (self.nodes, self.coords, self.bem_only, self.terms))
        self.nodes[n], self.coords[n], self.bem_only[n] = plan.nodes, plan.coords, plan.bem_only
        plan.index = n
        plan.nodes = plan.coords = None         # held here from now on
        self.plans.append(plan)
        return plan

    def arrays(self, index):
        """(nodes, coords, bem_only) of the plans ``index``."""
        return self.nodes[index], self.coords[index], self.bem_only[index]


class SolutionMap:
    """A packed solution map in memory, indexed for queries (see :func:`load_map`).

    Queries are answered in two steps, for many points at once (:meth:`quantities_many`).
    :meth:`_stencil` finds, once for all quantities, which nodes are interpolated (the rule,
    the third node of each axis, the holes and the corners of the grid cell): that depends on
    which nodes exist and on their method and shape class, not on the quantity, and on the
    point only through its position in the grid (:meth:`_codes`), so it is found once per
    position and kept flattened (:class:`_Plan`). :func:`_evaluate` then does the arithmetic
    of all points and quantities at once from the map's table of the nodes' values
    (:meth:`_table`) and the plans' LOO terms (:meth:`_terms`), with each point's Lagrange
    weights, in the order the interpolation defines. A quantity that has no interpolated value
    at some node (a value that is not positive where its logarithm is interpolated) gets a
    stencil of its own when the shared one looked at such a node."""

    def __init__(self, data: dict, source: str = ""):
        self.source = source
        self.grid = data["grid"]
        self.provenance = data.get("provenance", {})
        self.parameters = data.get("parameters", {})
        #: None for a vesicle map, ``{"shear_ratio": β, "reference": name}`` for a red-cell map
        #: (:func:`membrane_of`; module docstring)
        self.membrane = membrane_of(self.parameters)
        self.holes = data.get("holes", [])
        self.columns = data["columns"]
        self.n = len(self.columns["nu"])
        self.nus = sorted(float(v) for v in self.grid["nu"])
        self.cas = sorted(float(v) for v in self.grid["ca_b"])
        ratios = set()
        for method in self.grid["methods"]:
            ratios.update(float(v) for v in self.grid["lam_ratio"][method])
        self.ratios = sorted(ratios)
        # x = delta^1/2 of each lam_ratio node, ascending (lam_ratio descending)
        self._ratio_of = sorted(self.ratios, reverse=True)
        self.xs = [math.sqrt(1.0 - r) for r in self._ratio_of]
        self._cs = [math.log(v) for v in self.cas]
        self._row = {_key(*k[1:]) + (k[0],): i for i, k in enumerate(zip(
            self.columns["method"], self.columns["nu"], self.columns["lam_ratio"],
            self.columns["ca_b"]))}
        self._on_grid = {m: {round(float(r), 9) for r in self.grid["lam_ratio"][m]}
                         for m in self.grid["methods"]}
        self._hole = {_key(h["nu"], h["lam_ratio"], h["ca_b"]) + (h["method"],): h["reason"]
                      for h in self.holes}
        self._overlap = {}
        self._superseded = {}    # memo of superseded()
        self._bem_top = {}       # (nu, Ca_B) -> largest lam_ratio with a converged BEM point
        for m, nu, r, ca in zip(self.columns["method"], self.columns["nu"],
                                self.columns["lam_ratio"], self.columns["ca_b"]):
            if m == "bem":
                k = _key(nu, ca)
                self._bem_top[k] = max(self._bem_top.get(k, 0.0), float(r))
        # Tables of the grid, made once so that a query only looks things up. Node index
        # (i_nu * len(xs) + k) * len(cas) + i_ca (:meth:`_node`): a _Leaf where the map has a
        # point, else the reason of the hole; per (nu, Ca_B) line the nodes not superseded
        # (ascending in x) and their x.
        kind = list(zip(self.columns["method"], self.columns["shape_class"]))
        lines = {(nu, ca): _key(nu, ca) for nu in self.nus for ca in self.cas}
        self._leaves = []
        for nu in self.nus:
            for ratio in self._ratio_of:
                for ca in self.cas:
                    row, reason = self.node(nu, ratio, ca)
                    self._leaves.append(reason if row is None else _Leaf(
                        len(self._leaves), row, nu, ratio, ca, lines[nu, ca], kind[row]))
        ks = [[[k for k, r in enumerate(self._ratio_of) if not self.superseded(nu, r, ca)]
               for ca in self.cas] for nu in self.nus]
        self._line = [[[self._node(i_nu, k, i_ca) for k in ks[i_nu][i_ca]]
                       for i_ca in range(len(self.cas))] for i_nu in range(len(self.nus))]
        self._line_xs = [[[self.xs[k] for k in line] for line in by_ca] for by_ca in ks]
        self._axis_nodes = {"nu": list(range(len(self.nus))), "ca": list(range(len(self.cas)))}
        # per line its lam_ratio nodes ascending (for the corners), and the rows of each line by
        # their nu and Ca_B as the columns hold them
        self._line_ratios = [[sorted(self._ratio_of[k] for k in line) for line in by_ca]
                             for by_ca in ks]
        self._line_rows = {}
        for row, key in enumerate(zip(self.columns["nu"], self.columns["ca_b"])):
            self._line_rows.setdefault(key, []).append(row)
        # per row: whether its node is inside each axis (not at an end)
        self._interior = {axis: self._interior_rows(axis) for axis in _AXES}
        self._tables = {}        # (q, log) -> _table(q, log)
        self._loos = {}          # q -> _loo_table(q)
        self._q_index = {q: i for i, q in enumerate(QUANTITIES)}
        # For the plans (:meth:`_codes`): per position g of x among the nodes xs (bisect), the
        # pairs of nodes (k above, k below) whose distances to x choose the third node of a
        # line; the plans made so far, by code (:meth:`_plans_at`).
        pairs = [sorted({(line[p + 1], line[p - 2]) for by_ca in ks for line in by_ca
                         for p in [bisect.bisect_left(line, g)] if 2 <= p and p + 1 < len(line)})
                 for g in range(len(self.xs) + 1)]
        width = max(map(len, pairs))
        axes = (self.nus, self._cs, self.xs, self.cas, self.ratios)
        size = np.array([len(a) for a in axes])
        # states: 3 (pos) + on-node below/at; times 2 where the third node is chosen (ν, Ca_B)
        states = (3 * size + 3) * [2, 2, 1, 1, 1]
        self._code_tables = (
            np.array([list(a) + [math.inf] * (size.max() + 2 - len(a)) for a in axes]), size,
            np.array([math.prod(states[i + 1:]) for i in range(5)], dtype=np.int64),
            np.array([p + [(0, 0)] * (width - len(p)) for p in pairs], dtype=np.intp
                     ).reshape(len(pairs), width, 2))
        self._plans, self._plan_of, self._shapes = _Plans(), {}, {}
        # the values of the nodes: column 0 zeros, then y, solver and model error of each
        # quantity in its variable and its logarithm (the :class:`_Table` columns); the last
        # row is the padding node's (0)
        self._values = np.full((len(self._leaves) + 1, 1 + 6 * len(QUANTITIES)), np.nan)
        self._values[:, 0] = self._values[_PAD] = 0.0

    # ---------------------------------------------------------------- nodes and the rule
    def node_ca_b(self, ca_b: float) -> float:
        """``ca_b``, or the Ca_B node within :data:`CA_B_NODE_ATOL` of it."""
        i = bisect.bisect_left(self.cas, ca_b)
        for j in (i - 1, i):
            if 0 <= j < len(self.cas) and abs(self.cas[j] - ca_b) <= CA_B_NODE_ATOL:
                return self.cas[j]
        return ca_b

    def node(self, nu: float, lam_ratio: float, ca_b: float) -> tuple[int | None, str]:
        """Row used at a grid node (BEM if converged, else lubrication if converged) and ''; or
        (None, the reason it is a hole)."""
        reasons = []
        for method in ("bem", "lubrication"):
            if round(lam_ratio, 9) not in self._on_grid.get(method, ()):
                continue
            k = _key(nu, lam_ratio, ca_b) + (method,)
            if k in self._row:
                return self._row[k], ""
            reasons.append(f"{method}: {self._hole.get(k, 'not computed')}")
        why = "; ".join(reasons) or "no point"
        return None, f"hole at nu={nu:.6g}, lam/lam_c={lam_ratio:.6g}, Ca_B={ca_b:.6g} ({why})"

    def superseded(self, nu: float, lam_ratio: float, ca_b: float) -> bool:
        """True at a node that is not on the BEM grid (a lubrication-only λ/λc) and lies below
        the largest λ/λc of its (ν, Ca_B) line with a converged BEM point: there the line is
        interpolated between BEM points and the node is left out (module docstring, the rule).
        A failed BEM point on the BEM grid stays a hole."""
        k = (nu, lam_ratio, ca_b)
        if k not in self._superseded:
            self._superseded[k] = (round(lam_ratio, 9) not in self._on_grid.get("bem", ()) and
                                   lam_ratio < self._bem_top.get(_key(nu, ca_b), 0.0) - _ON_NODE)
        return self._superseded[k]

    def value(self, row: int, q: str):
        v = self.columns[q][row]
        return None if v is None else float(v)

    def _model_error(self, row: int, q: str, log: bool, line: tuple):
        """Model error (in y) of a lubrication row on the (ν, Ca_B) line of key ``line``
        (:func:`_key`): |y_lub − y_bem| at the largest lam_ratio of the line where both
        converged; 0 for BEM; None when unknown."""
        if self.columns["method"][row] != "lubrication":
            return 0.0
        nu, ca = self.columns["nu"][row], self.columns["ca_b"][row]
        k = (line, q, log)
        if k not in self._overlap:
            self._overlap[k] = None
            for r in sorted(self.ratios, reverse=True):
                rb = self._row.get(_key(nu, r, ca) + ("bem",))
                rl = self._row.get(_key(nu, r, ca) + ("lubrication",))
                if rb is None or rl is None:
                    continue
                yb, yl = (_transform(q, self.value(i, q), r, log) for i in (rb, rl))
                if yb is not None and yl is not None:
                    self._overlap[k] = abs(yl - yb)
                    break
        return self._overlap[k]

    def _solver_error(self, row: int, q: str, log: bool, ratio: float):
        column = self.columns.get(f"err_{q}")
        err = None if column is None else column[row]
        v = self.value(row, q)
        if err is None or v is None:
            return None
        t = TRANSFORMS[q]
        err = float(err) + _PACK_RTOL * abs(v)         # with the packed value's rounding
        if log:
            base = abs(v - t["offset"])
            return err / base if base > 0 else None
        return err * _scale(q, ratio)

    def _bracket(self, coords, x) -> set:
        """The node coordinates (ascending) around x (the node itself when x is on one)."""
        pos, on = _locate(coords, x)
        if on:
            return {coords[j] for j in on}
        return set(coords[max(pos - 1, 0):pos + 1])

    def _corners(self, nu: float, ca_b: float, lam_ratio: float) -> set:
        """The rows at the corners of the grid cell around a query (for its interpolation
        error): their ν and Ca_B are the nodes that bracket the query's, and their λ/λc, on
        their line, brackets the query's among the nodes not superseded."""
        corners = set()
        for nu_ in self._bracket(self.nus, nu):
            for ca in self._bracket(self.cas, ca_b):
                rows = self._line_rows.get((nu_, ca), ())
                if rows:
                    ratios = self._bracket(
                        self._line_ratios[self.nus.index(nu_)][self.cas.index(ca)], lam_ratio)
                    corners.update(r for r in rows if self.columns["lam_ratio"][r] in ratios)
        return corners

    def _interior_rows(self, axis: str) -> list:
        """Per row: True if its node is not at an end of the axis (its LOO is an
        interpolation)."""
        name, (lo, hi) = {"lam": ("lam_ratio", (self._ratio_of[0], self._ratio_of[-1])),
                          "nu": ("nu", (self.nus[0], self.nus[-1])),
                          "ca": ("ca_b", (self.cas[0], self.cas[-1]))}[axis]
        tol_lo, tol_hi = (_ON_NODE * max(1.0, abs(e)) for e in (lo, hi))
        return [abs(v - lo) > tol_lo and abs(v - hi) > tol_hi for v in self.columns[name]]

    # ---------------------------------------------------------------- the values of the nodes
    def _table(self, q: str, log: bool, lines=frozenset()) -> _Table:
        """The :class:`_Table` of ``q`` (made on first use), filled for ``lines`` (line
        indices i_nu * len(cas) + i_ca)."""
        table = self._tables.get((q, log))
        if table is None:
            k = 1 + 3 * (2 * self._q_index[q] + log)
            v = self._values
            table = self._tables[q, log] = _Table(q, log, k, v[:, k], v[:, k + 1], v[:, k + 2])
        if not lines <= table.lines:
            for line in lines - table.lines:
                self._fill(table, line)
        return table

    def _fill(self, table: _Table, line: int) -> None:
        """Fill ``table`` on one (ν, Ca_B) line (index i_nu * len(cas) + i_ca)."""
        q, log = table.q, table.log
        i_nu, i_ca = divmod(line, len(self.cas))
        for k in range(len(self.xs)):
            leaf = self._leaves[self._node(i_nu, k, i_ca)]
            if isinstance(leaf, str):
                continue
            v = self.value(leaf.row, q)
            y = _transform(q, v, leaf.ratio, log)
            if y is None:
                table.failed[leaf.node] = (f"{q} missing at nu={leaf.nu:.6g}, lam/lam_c="
                                           f"{leaf.ratio:.6g}, Ca_B={leaf.ca:.6g}" if v is None
                                           else "not positive")
                continue
            model = self._model_error(leaf.row, q, log, leaf.line)
            solver = self._solver_error(leaf.row, q, log, leaf.ratio)
            table.y[leaf.node] = y
            table.solver[leaf.node] = np.nan if solver is None else solver
            table.model[leaf.node] = np.nan if model is None else model
            table.has_solver = table.has_solver or solver is not None
            if model is None:
                table.notes[leaf.node] = (
                    f"lubrication at nu={leaf.nu:.6g}, Ca_B={leaf.ca:.6g} is not checked "
                    "against BEM (no common point on this line): model error unknown",)
        table.lines.add(line)

    def _loo_table(self, q: str) -> dict:
        """{axis: the LOO error of ``q`` along it per row (None where there is none)}."""
        if q not in self._loos:
            self._loos[q] = {axis: [None if v is None else float(v) for v in
                                    self.columns.get(f"loo_{axis}_{q}", [None] * self.n)]
                             for axis in _AXES}
        return self._loos[q]

    # ---------------------------------------------------------------- the stencil
    def _along(self, axis, nodes, coords, x, inner, extrapolate, corners):
        """The stencil along one axis: ``nodes`` the indices of the nodes that exist on this
        line (a node left out for LOO excluded: then ``extrapolate``), ``coords`` their
        coordinates (ascending), ``inner(i)`` the stencil at node i (or the reason there is
        none), ``corners`` the rows at the corners of the query's grid cell (None: no
        interpolation error). Returns a :class:`_Stencil`, the inner stencil of the node the
        query sits on, or a reason."""
        n = len(nodes)
        pos, on = _locate(coords, x)
        if on:                         # on a node (the lowest, should two be that close)
            return inner(nodes[on[0]])
        if not extrapolate:
            if pos == 0 or pos == n:
                return "outside"
            below = inner(nodes[pos - 1])
            if isinstance(below, str):
                return below
            above = inner(nodes[pos])
            if isinstance(above, str):
                return above
            order, ps = [pos - 1, pos], [below, above]     # positions on the line, stencils
            # the third node: the nearest usable one whose rows share the method and shape
            # class of the bracketing pair's; without one the interpolation is linear (a
            # quadratic through a branch change or a method change is worse than a line)
            kinds = below.kinds | above.kinds
            extra = [j for j in (pos - 2, pos + 1) if 0 <= j < n]
            if len(extra) == 2 and abs(coords[pos + 1] - x) < abs(coords[pos - 2] - x):
                extra.reverse()        # nearest first (the lower one on a tie)
            for j in extra:
                p = inner(nodes[j])
                if not isinstance(p, str) and p.kinds <= kinds:
                    at = 0 if j < pos else 2
                    order.insert(at, j)
                    ps.insert(at, p)
                    break
        else:
            parts = {}
            for j in sorted(range(n), key=lambda j: abs(coords[j] - x)):
                p = inner(nodes[j])
                if not isinstance(p, str):
                    parts[j] = p
                if len(parts) == 3:
                    break
            if not parts:
                return "no neighbour"
            order = sorted(parts)
            ps = [parts[j] for j in order]
        rows = frozenset().union(*[p.rows for p in ps])
        use = None
        if not extrapolate and corners is not None:
            # interpolation error: the largest leave-one-out error along this axis of the
            # rows at the corners of the query's grid cell, interior nodes of the axis first
            # (module docstring, error bar)
            at = rows & corners
            interior = self._interior[axis]
            use = tuple([r for r in at if interior[r]] or at or rows)
        return _Stencil(axis, [coords[j] for j in order], ps, rows, use)

    def _stencil(self, nu, x, c, corners=None, exclude=None, table=None) -> tuple:
        """The stencil at (nu, x = δ^½, c = log Ca_B), tensor-product fashion (λ first, then
        Ca_B, then ν), or the reason there is none; the node indices it looked at; the indices
        of the (ν, Ca_B) lines it reached. ``corners``: of :meth:`_corners` (None: no
        interpolation error); ``exclude`` = (axis, node index) leaves that node out and
        extrapolates along that axis (LOO); ``table``: a :class:`_Table` whose failed nodes
        count as holes (filled on the lines reached)."""
        failed = {} if table is None else table.failed
        leaves, looked, reached = self._leaves, [], []
        left_out = dict([exclude]) if exclude else {}

        def line(axis, nodes, coords, node):
            """The nodes of a line and their coordinates, without ``node`` if left out."""
            if axis not in left_out or node not in nodes:
                return nodes, coords
            j = nodes.index(node)
            return nodes[:j] + nodes[j + 1:], coords[:j] + coords[j + 1:]

        def leaf(node):
            looked.append(node)
            return failed.get(node, leaves[node])

        def along_lam(i_nu, i_ca):
            reached.append(i_nu * len(self.cas) + i_ca)
            if table is not None and reached[-1] not in table.lines:
                self._fill(table, reached[-1])
            nodes, coords = line("lam", self._line[i_nu][i_ca], self._line_xs[i_nu][i_ca],
                                 self._node(i_nu, left_out.get("lam"), i_ca))
            return self._along("lam", nodes, coords, x, leaf, "lam" in left_out, corners)

        def along_ca(i_nu):
            nodes, coords = line("ca", self._axis_nodes["ca"], self._cs, left_out.get("ca"))
            return self._along("ca", nodes, coords, c, lambda j: along_lam(i_nu, j),
                               "ca" in left_out, corners)

        nodes, coords = line("nu", self._axis_nodes["nu"], self.nus, left_out.get("nu"))
        st = self._along("nu", nodes, coords, nu, along_ca, "nu" in left_out, corners)
        return st, frozenset(looked), frozenset(reached)

    def _node(self, i_nu: int, k: int | None, i_ca: int) -> int | None:
        """Index of the grid node (ν, λ/λc, Ca_B) = (nus[i_nu], _ratio_of[k], cas[i_ca]) in
        the node tables (None for k None)."""
        return None if k is None else (i_nu * len(self.xs) + k) * len(self.cas) + i_ca

    # ---------------------------------------------------------------- plans
    def _codes(self, nu, x, c, ca, r) -> np.ndarray:
        """An integer per point (arrays ν, x = δ^½, c = log Ca_B as the stencil takes them,
        ``ca`` and ``r`` = λ/λc as the corners take them) that says where it lies in the grid:
        on each axis the node interval (bisect) and the node it sits on (:func:`_locate`),
        which third node is the nearer where the stencil compares them (ν, Ca_B, and on every
        line at this x), and the same intervals of Ca_B and λ/λc for the corners
        (:meth:`_corners`). Every choice :meth:`_stencil` makes is fixed by these: points of
        one code have one stencil but for the weights (one :class:`_Plan`)."""
        axes, size, place, pairs = self._code_tables
        t = np.array((nu, c, x, ca, r), dtype=float)[..., None]     # (5, N, 1)
        pos = (axes[:, None, :] < t).sum(-1, keepdims=True)           # bisect_left
        tol = _ON_NODE * np.maximum(1.0, np.abs(t))
        near = np.take_along_axis(axes, (pos + [-2, -1, 0, 1]).clip(0).reshape(5, -1),
                                  axis=1).reshape(5, -1, 4) - t      # nodes pos-2 ... pos+1
        state = 3 * pos[..., 0] + (pos[..., 0] > 0) * (np.abs(near[..., 1]) <= tol[..., 0]) \
            + 2 * (np.abs(near[..., 2]) <= tol[..., 0])
        third = ((pos[..., 0] >= 2) & (pos[..., 0] + 1 < size[:, None])
                 & (np.abs(near[..., 3]) < np.abs(near[..., 0])))
        state[:2] = 2 * state[:2] + third[:2]                         # ν and Ca_B choose
        # the third node on every line at this x: nearer of each pair (up, down)
        up, down = pairs[pos[2, :, 0]].T                              # (P, N) node indices
        xs, x = axes[2], t[2, :, 0]
        nearer = (np.abs(xs[up] - x) < np.abs(xs[down] - x)).T @ (1 << np.arange(len(up)))
        return place @ state * (1 << len(up)) + nearer

    def _plans_at(self, at, r, ca, codes, corners: bool, table=None) -> list:
        """Per point (rows of ``at``: ν, c = log Ca_B, x = δ^½; ``r``, ``ca``, ``codes`` as
        :meth:`_codes` takes and gives them) its :class:`_Plan`, or a :class:`_NoPlan` with the
        reason it has none; with the corners of its cell (``corners``: an error bar) or
        without; with ``table``, that quantity's failed nodes count as holes. A plan is found
        by :meth:`_stencil` at the first point of its code and kept for the others."""
        tag = (corners, None if table is None else (table.q, table.log))
        found, out = {}, []
        for i, code in enumerate(codes.tolist()):
            plan = found.get(code)
            if plan is None:
                plan = found[code] = self._plan_of.get((code, tag))
            if plan is None:
                nu, c, x = at[i].tolist()
                cells = self._corners(nu, float(ca[i]), float(r[i])) if corners else None
                st, looked, reached = self._stencil(nu, x, c, cells, table=table)
                plan = found[code] = self._plan_of[code, tag] = (
                    _NoPlan(st, looked, reached) if isinstance(st, str) else
                    self._plans.add(_Plan(st, looked, reached, self.columns["method"])))
            out.append(plan)
        return out

    def _terms(self, plans: list, names: list) -> np.ndarray:
        """The interpolation-error terms (N, 13, K) of the stored ``plans`` for the quantities
        ``names``: per slot the largest LOO error along the slot's axis of its corner rows over
        :data:`LOO_RATIO` (NaN where one is unknown or no error bar is formed; 0 where the
        slot does not interpolate), worked out for a plan and a quantity when first asked."""
        columns = [self._q_index[q] for q in names]
        store = self._plans
        for plan in plans:
            if not plan.termed.issuperset(names):
                for q, k in zip(names, columns):
                    loo = self._loo_table(q)
                    for slot, term in enumerate(plan.terms):
                        errors = (None if term is None or term[1] is None
                                  else [loo[term[0]][r] for r in term[1]])
                        store.terms[plan.index, slot, k] = (
                            0.0 if term is None else math.nan if errors is None
                            or None in errors else max(errors) / LOO_RATIO)
                plan.termed.update(names)
        return store.terms[np.array([p.index for p in plans], dtype=np.intp)][..., columns]

    # ---------------------------------------------------------------- the arithmetic
    def _parts(self, keys: list, at, r, ca, codes, shared: list, corners: bool) -> dict:
        """Quantities ``keys`` = [(q, log)] (transformed; in the logarithm where ``log``) at the
        points ``at``: {(q, log): per point (y, interpolation, solver, model error (in y, None
        where unknown), the :class:`_Plan` used, the notes of its leaves), or the reason there
        is none}.
        ``shared``: the points' plans (:meth:`_plans_at`) with no failed node, used unless q
        fails at one of the nodes a plan looked at (then the point gets q's own: with none of
        them failed the stencil would take the same steps to the same plan). Quantities of the
        same plans are summed together."""
        lines = frozenset().union(*{p.reached for p in shared})
        groups = {}                      # id of a list of plans -> (the list, its keys)
        for q, log in keys:
            table, plans = self._table(q, log, lines), shared
            own = ([i for i, p in enumerate(shared)
                    if not table.failed.keys().isdisjoint(p.looked)] if table.failed else [])
            if own:
                plans = list(shared)
                for i, p in zip(own, self._plans_at(at[own], r[own], ca[own], codes[own],
                                                    corners, table)):
                    plans[i] = p
            groups.setdefault(id(plans), (plans, []))[1].append((q, log))
        out = {}
        for plans, group in groups.values():
            reasons = [p.reason if isinstance(p, _NoPlan) else None for p in plans]
            out.update((key, list(reasons)) for key in group)
            good = [i for i, p in enumerate(plans) if isinstance(p, _Plan)]
            if not good:
                continue
            used = [plans[i] for i in good]
            index = np.array([p.index for p in used], dtype=np.intp)
            tables = [self._tables[key] for key in group]
            values = _evaluate(self._plans.arrays(index), at[good], self._values, tables,
                               self._terms(used, [q for q, _ in group]))
            for j, key in enumerate(group):
                parts, notes = out[key], tables[j].notes
                y, *errors = (v[:, j].tolist() for v in values)
                # the notes of the leaves, each once, in the order of the leaves
                noted = ([tuple(dict.fromkeys(n for leaf in plan.leaves
                                              for n in notes.get(leaf, ()))) for plan in used]
                         if notes else itertools.repeat(()))
                for i, *part in zip(good, y, *([None if math.isnan(e) else e for e in column]
                                               for column in errors), used, noted):
                    parts[i] = part
        return out

    def _loo_value(self, q: str, log: bool, nu: float, x: float, c: float, exclude):
        """y of quantity ``q`` at (nu, x, c) with the node ``exclude`` = (axis, index) left
        out, extrapolated along that axis (pack time), or the reason there is none."""
        st, looked, reached = self._stencil(nu, x, c, exclude=exclude,
                                            table=self._table(q, log))
        if isinstance(st, str):
            return st
        plan = _Plan(st, looked, reached, self.columns["method"])
        arrays = (np.array([plan.nodes]), np.array([plan.coords]), np.array([plan.bem_only]))
        # only y is wanted: no interpolation-error terms
        return _evaluate(arrays, np.array([[nu, c, x]]), self._values, [self._table(q, log)],
                         np.zeros((1, 13, 1)))[0][0, 0]

    # ---------------------------------------------------------------- queries
    def quantities_many(self, nu, lam_ratio, ca_b, names=tuple(QUANTITIES)) -> list[dict]:
        """The quantities ``names`` at points inside the map's box (see :func:`query_map`),
        given as sequences ``nu``, ``lam_ratio``, ``ca_b``: per point {name: :class:`MapValue`}.

        The points are answered together: each point's stencil is a :class:`_Plan` found once
        per position in the grid (:meth:`_codes`) for every point there and every quantity,
        and the sums of all points are taken at once (:func:`_evaluate`), in the same order
        and with the same operations as for one point (:meth:`quantities` is this with one
        point)."""
        nu = [float(v) for v in nu]
        r = [float(v) for v in lam_ratio]
        ca = ca_b = [float(v) for v in ca_b]
        if len(self._plans.plans) > _MAX_PLANS:      # bounded memory: start afresh
            self._plans, self._plan_of, self._shapes = _Plans(), {}, {}
        top = self.cas[-1]
        clamp = [v > top * (1 + _ON_NODE) for v in ca]
        c = [math.log(top) if k else math.log(v) for v, k in zip(ca, clamp)]
        x = [math.sqrt(1.0 - v) for v in r]
        at = np.array([nu, c, x]).T.reshape(len(nu), 3)
        ratios, ca = r, [math.exp(v) for v in c]
        codes = self._codes(nu, x, c, ca, r)
        r, ca = np.array(r), np.array(ca)
        shared = self._plans_at(at, r, ca, codes, corners=True)
        keys = [(q, TRANSFORMS[q]["log"]) for q in names]
        found = self._parts(keys, at, r, ca, codes, shared, True)
        # the clamp's model error: the change to the second largest Ca_B (its value only)
        second = np.flatnonzero(clamp) if any(clamp) else np.empty(0, dtype=np.intp)
        if len(second) and len(self.cas) > 1:
            at2, r2, ca2 = at[second], r[second], np.full(len(second), self.cas[-2])
            at2[:, 1] = math.log(self.cas[-2])
            codes2 = self._codes(at2[:, 0], at2[:, 2], at2[:, 1], ca2, r2)
            shared2 = self._plans_at(at2, r2, ca2, codes2, corners=False)
            found2 = self._parts(keys, at2, r2, ca2, codes2, shared2, False)
        where2 = {i: j for j, i in enumerate(second.tolist())}
        out = [{} for _ in nu]
        for q, log in keys:
            parts, logs = found[q, log], [log] * len(nu)
            others = found2[q, log] if len(second) and len(self.cas) > 1 else None
            again = [i for i, p in enumerate(parts) if log and p == "not positive"]
            if again:
                index = np.array(again, dtype=np.intp)
                for i, p in zip(again, self._parts([(q, False)], at[index], r[index],
                                                   ca[index], codes[index],
                                                   [shared[i] for i in again], True)[q, False]):
                    parts[i], logs[i] = p, False
                back = [i for i in again if i in where2 and others is not None]
                if back:
                    index = np.array([where2[i] for i in back], dtype=np.intp)
                    others = list(others)
                    for i, p in zip(back, self._parts(
                            [(q, False)], at2[index], r2[index], ca2[index], codes2[index],
                            [shared2[j] for j in index.tolist()], False)[q, False]):
                        others[where2[i]] = p
            for i, part in enumerate(parts):
                if isinstance(part, str):
                    out[i][q] = MapValue(None, note=part if part != "outside"
                                         else "outside the map")
                    continue
                notes = []
                if clamp[i]:
                    notes.append(f"Ca_B={ca_b[i]:.6g} above the map's largest {top:g}: value "
                                 f"at Ca_B={top:g} (shapes nearly independent of Ca_B >= 50, "
                                 "Chen et al. 2020), with the measured change between the two "
                                 "largest Ca_B as model error")
                    other = "no second Ca_B" if others is None else others[where2[i]]
                    if isinstance(other, str):
                        part[3] = None
                        notes.append(f"clamp error unknown ({other})")
                    else:
                        part[3] = _add(part[3], abs(part[0] - other[0]))
                out[i][q] = self._map_value(q, part, ratios[i], logs[i], notes)
        return out

    def quantities(self, nu: float, lam_ratio: float, ca_b: float,
                   names=tuple(QUANTITIES)) -> dict:
        """The quantities ``names`` at a point inside the map's box (see :func:`query_map`):
        {name: :class:`MapValue`} (:meth:`quantities_many` at one point)."""
        return self.quantities_many((nu,), (lam_ratio,), (ca_b,), names)[0]

    def quantity(self, q: str, nu: float, lam_ratio: float, ca_b: float) -> MapValue:
        """One quantity at a point inside the map's box (see :func:`query_map`)."""
        return self.quantities(nu, lam_ratio, ca_b, (q,))[q]

    def _map_value(self, q: str, part: list, lam_ratio: float, log: bool,
                   notes: list) -> MapValue:
        """The :class:`MapValue` of an interpolation ``part`` (:meth:`_parts`): value and
        error parts in q's units."""
        y, interp, solver, model, plan, leaf_notes = part
        value = _inverse(q, y, lam_ratio, log)
        if log:
            base = abs(value - TRANSFORMS[q]["offset"])
            errors = [None if e is None else base * math.expm1(e)
                      for e in (interp, solver, model)]
        else:
            scale = _scale(q, lam_ratio)
            errors = [None if e is None else e / scale for e in (interp, solver, model)]
        if None in errors:
            notes.append(_UNKNOWN[errors[0] is None, errors[1] is None, errors[2] is None])
        return MapValue(value, error=sum([e for e in errors if e is not None]),
                        interpolation_error=errors[0], solver_error=errors[1],
                        model_error=errors[2], methods=plan.methods, rows=plan.rows,
                        note="; ".join(leaf_notes + tuple(notes)) if notes or leaf_notes
                        else "")

    def shape_class(self, rows) -> "MapValue":
        classes = {self.columns["shape_class"][r] for r in rows}
        methods = tuple(sorted({self.columns["method"][r] for r in rows}))
        if len(classes) == 1 and None not in classes:
            return MapValue(classes.pop(), methods=methods, rows=tuple(sorted(rows)))
        return MapValue(None, methods=methods, rows=tuple(sorted(rows)),
                        note="the neighbouring points differ (" + ", ".join(
                            sorted(map(str, classes))) + "): a bullet-parachute transition")

    # ---------------------------------------------------------------- LOO (pack time)
    def leave_one_out(self) -> dict:
        """Columns ``loo_<axis>_<q>``: the LOO error (in the interpolated variable) of every
        row that is a node's chosen point (None for the others and where no estimate exists)."""
        out = {f"loo_{a}_{q}": [None] * self.n for a in _AXES for q in QUANTITIES}
        for i_nu, nu in enumerate(self.nus):
            for i_ca, ca in enumerate(self.cas):
                for k, (x, ratio) in enumerate(zip(self.xs, self._ratio_of)):
                    row, _ = self.node(nu, ratio, ca)
                    if row is None or self.superseded(nu, ratio, ca):
                        continue
                    for q in QUANTITIES:
                        log = TRANSFORMS[q]["log"]
                        y0 = _transform(q, self.value(row, q), ratio, log)
                        if y0 is None:
                            log = False
                            y0 = _transform(q, self.value(row, q), ratio, log)
                        if y0 is None:
                            continue
                        for axis, index in (("lam", k), ("nu", i_nu), ("ca", i_ca)):
                            y = self._loo_value(q, log, nu, x, self._cs[i_ca],
                                                exclude=(axis, index))
                            if not isinstance(y, str):
                                out[f"loo_{axis}_{q}"][row] = float(f"{abs(y - y0):.3g}")
        return out


@dataclass(frozen=True)
class MapValue:
    """One quantity of a map query: the value and its error parts in the quantity's units
    (None where unknown), the methods and rows of the points used, and a note (the reason
    when ``value`` is None)."""
    value: float | str | None
    error: float | None = None
    interpolation_error: float | None = None
    solver_error: float | None = None
    model_error: float | None = None
    methods: tuple = ()
    rows: tuple = field(default=(), repr=False)
    note: str = ""

    def to_dict(self) -> dict:
        return {"value": self.value, "error": self.error,
                "interpolation_error": self.interpolation_error,
                "solver_error": self.solver_error, "model_error": self.model_error,
                "methods": list(self.methods), "note": self.note}


@dataclass(frozen=True)
class MapQuery:
    """Result of :func:`query_map`: the inputs, the map file, one :class:`MapValue` per
    quantity (``quantities``, keyed like :data:`QUANTITIES` plus ``shape_class``) and the map's
    membrane (:attr:`SolutionMap.membrane`: None for a vesicle map, β and the reference shape
    for a red-cell map)."""
    nu: float
    lam_ratio: float
    ca_b: float
    source: str
    quantities: dict
    membrane: dict | None = None

    def __getitem__(self, key):
        return self.quantities[key].value

    def to_dict(self) -> dict:
        return {"nu": self.nu, "lam_ratio": self.lam_ratio, "ca_b": self.ca_b,
                "map": self.source, "membrane": self.membrane,
                "quantities": {k: v.to_dict() for k, v in self.quantities.items()}}


# --------------------------------------------------------------------------- load

def require_vesicle_map(m: "SolutionMap", purpose: str) -> "SolutionMap":
    """``m`` if it is a vesicle map; a red-cell map raises InvalidParameterError naming ``map``
    (its nodes are red cells of one shear ratio, which ``purpose`` would read as vesicles)."""
    if m.membrane is not None:
        raise InvalidParameterError(
            "map", m.source or "the given map", f"a vesicle map ({purpose})",
            f"it is a red-cell map (shear ratio beta = {m.membrane['shear_ratio']:.4g}), whose "
            "nodes are red cells, not vesicles")
    return m


def membrane_of(parameters: dict) -> dict | None:
    """The membrane of a map from its packed ``parameters`` (module docstring, Membrane): None
    for a vesicle map, ``{"shear_ratio": β, "reference": name}`` for a red-cell map (a BEM
    option :data:`SHEAR_RATIO`; ``reference`` the BEM option, else :data:`DEFAULT_REFERENCE`).

    Examples
    --------
    >>> membrane_of({"options": {"bem": {"shear_ratio": 231.859}}})
    {'shear_ratio': 231.859, 'reference': 'biconcave'}
    >>> membrane_of({}) is None
    True
    """
    options = parameters.get("options") if isinstance(parameters, dict) else None
    bem = options.get("bem") if isinstance(options, dict) else None
    if not isinstance(bem, dict) or SHEAR_RATIO not in bem:
        return None
    return {"shear_ratio": float(bem[SHEAR_RATIO]),
            "reference": str(bem.get("reference", DEFAULT_REFERENCE))}


def _check_packed(data, check) -> None:
    """Schema of a packed map: the header, the grid, every column the queries read (one value
    per node, each of its kind), every node inside the physical bounds (:func:`_rejection`),
    at least one node, and the holes."""
    check(isinstance(data, dict) and data.get("format") == FORMAT,
          "not a vesicle-tube solution map (no 'format' header)")
    version = data.get("version")
    check(type(version) is int and version == FORMAT_VERSION,
          f"map format version {_show(version)}; this version reads {FORMAT_VERSION} (an "
          "integer)")
    # its leave-one-out errors are in other interpolation variables than this version's
    check(json.dumps(data.get("transforms"), sort_keys=True)
          == json.dumps(TRANSFORMS, sort_keys=True), "packed with other interpolation "
          "variables than this version uses: pack it again with 'vesicle-tube map pack'")
    _check_grid(data.get("grid"), check)
    check(isinstance(data.get("provenance", {}), dict), "'provenance' is not an object")
    parameters = data.get("parameters", {})
    check(isinstance(parameters, dict), "'parameters' is not an object")
    bem = (parameters.get("options") or {}).get("bem") if isinstance(
        parameters.get("options"), dict) else None
    if isinstance(bem, dict) and SHEAR_RATIO in bem:
        beta, reference = bem[SHEAR_RATIO], bem.get("reference", DEFAULT_REFERENCE)
        check(_number(beta) and 0.0 < beta < math.inf,
              f"parameters.options.bem.{SHEAR_RATIO} {_show(beta)} is not a positive finite "
              "number (the red-cell ratio G_s R0^2/kappa)")
        check(isinstance(reference, str), f"parameters.options.bem.reference {_show(reference)} "
                                          "is not the name of a stress-free shape")
    cols = data.get("columns")
    check(isinstance(cols, dict), "no 'columns' object")
    needed = ["method", "nu", "lam_ratio", "ca_b", "shape_class", *QUANTITIES]
    missing = [c for c in needed if c not in cols]
    check(not missing, "missing columns " + ", ".join(missing))
    check(all(isinstance(v, list) for v in cols.values()), "a column is not a list")
    n = len(cols["nu"])
    check(all(len(v) == n for v in cols.values()), "columns of unequal length")
    kinds = {"method": "method", "nu": "nu", "lam_ratio": "lam_ratio", "ca_b": "ca_b",
             "shape_class": "shape_class", "lam": "positive", "residual": "number",
             "bie_solves": "count", "seconds": "number", **dict.fromkeys(QUANTITIES, "number"),
             **{c: "number" for c in cols if c.startswith(("err_", "loo_"))}}
    for c, kind in kinds.items():
        if kind == "number" and _null_or_numbers(cols.get(c, ())):
            continue
        ok, expected = _KIND[kind]
        bad = next((i for i, v in enumerate(cols.get(c, ())) if not ok(v)), None)
        check(bad is None, f"column {c!r}, row {bad}: "
                           f"{_show(None if bad is None else cols[c][bad])} is not {expected}")
    # the bounds of every column at once (min and max in C); a column that breaks one is
    # searched row by row for the first node and its reason
    physical = n == 0 or all(
        None not in cols[q] and (q not in _BOUNDED or OUTPUT_BOUNDS[_BOUNDED[q]][0]
                                 <= min(cols[q]) <= max(cols[q])
                                 <= OUTPUT_BOUNDS[_BOUNDED[q]][1])
        for q in QUANTITIES)
    for i in range(0 if physical else n):
        row = {c: cols[c][i] for c in QUANTITIES}
        why = _rejection(row)
        check(not why, f"the node of row {i} ({cols['method'][i]}, nu={cols['nu'][i]:g}, "
                       f"lam/lam_c={cols['lam_ratio'][i]:g}, Ca_B={cols['ca_b'][i]:g}) is "
                       f"unphysical: {why}")
    holes = data.get("holes", [])
    check(isinstance(holes, list), "'holes' is not a list")
    for i, h in enumerate(holes):
        check(isinstance(h, dict) and all(k in h for k in ("method", "nu", "lam_ratio", "ca_b",
                                                            "reason")),
              f"hole {i} is not an object with method, nu, lam_ratio, ca_b and reason")
        _check_fields(h, {"method": "method", "nu": "nu", "lam_ratio": "lam_ratio",
                          "ca_b": "ca_b", "reason": "text"}, check, f"holes[{i}].")
    check(n > 0, f"the map has no node: no grid point converged ({len(holes)} holes: failed, "
                 "rejected or not computed); expected at least one converged point")


@functools.lru_cache(maxsize=8)
def _load(path: str, mtime_ns: int, size: int) -> SolutionMap:
    """The map at ``path`` (the file as it is at ``mtime_ns`` and ``size``: the cache key)."""
    data = read_json(path, name="map", what=_MAP_WHAT)
    _check_packed(data, _schema("map", path, _MAP_WHAT))
    return SolutionMap(data, path)


def load_map(path=None) -> SolutionMap:
    """The packed map at ``path`` (default :data:`DEFAULT_MAP`), cached while the file is
    unchanged. Read by :func:`correlations.files.read_json` (a regular file, size, depth and
    integer limits) and checked by :func:`_check_packed`; raises
    :class:`~correlations.files.UnreadableFile` (name ``map``) for a missing, unreadable,
    malformed or foreign file, or one whose nodes are unphysical; "no map shipped" when the
    default is absent."""
    if path is None and not DEFAULT_MAP.exists():
        raise InvalidParameterError(
            "map", str(DEFAULT_MAP), "a packed map", "no map shipped with this installation: "
            "build one with 'vesicle-tube map build' and give it with --map")
    p = check_input_file(DEFAULT_MAP if path is None else path, name="map", what=_MAP_WHAT)
    st = os.stat(p)
    return _load(str(p), st.st_mtime_ns, st.st_size)


# --------------------------------------------------------------------------- query

def query_map(nu: float, lam_ratio: float, ca_b: float, map=None) -> MapQuery:
    r"""Every quantity of the solution map at (ν, λ/λc, Ca_B), with an error bar.

    Interpolation variables, the BEM/lubrication rule, the error parts and the range are those
    of the module docstring: inside the map's box the value is interpolated in x = δ^(1/2)
    (δ = 1 − λ/λc), log Ca_B and ν on δ-scaled quantities whose limits as δ → 0 are finite
    (Chen et al. 2020 eq:asmyp1, eq:asmyp2, eq:sL, eq. sfilm2; Barakat & Shaqfeh 2018a).
    Outside it (ν beyond the map's range, λ/λc below or above its nodes, Ca_B below its smallest
    value or above :data:`CA_B_CLAMP_MAX`) and next to holes a quantity is None with the reason;
    nothing is extrapolated. Between the largest Ca_B of the map (≥ 50) and 1e4 the values at
    the largest Ca_B are returned with the measured Ca_B change as model error (Chen et al. 2020
    §IV.A: shapes virtually independent of Ca_B ≥ 50).

    Parameters
    ----------
    nu : float
        Reduced volume, 0 < nu <= 1 [-].
    lam_ratio : float
        λ/λc, 0 < lam_ratio < 1 [-] (λ ≥ λc raises :class:`~lubrication.checks.CannotPassError`).
    ca_b : float
        Bending capillary number ηUR0²/κ > 0 [-].
    map : SolutionMap, str or Path, optional
        The map, or its packed file; default the shipped one (:data:`DEFAULT_MAP`).

    Returns
    -------
    MapQuery
        ``quantities[q]`` a :class:`MapValue` for each of :data:`QUANTITIES` and
        ``shape_class``.
    """
    return query_map_many((nu,), (lam_ratio,), (ca_b,), map)[0]


def _point(nu, lam_ratio, ca_b) -> tuple[float, float, float]:
    """A query's (ν, λ/λc, Ca_B) as floats, checked (:func:`query_map`'s errors; floats in
    range pass at once: a map is queried at many points)."""
    if (nu.__class__ is lam_ratio.__class__ is ca_b.__class__ is float
            and 0.0 < nu <= 1.0 and 0.0 < lam_ratio < 1.0 and 0.0 < ca_b < math.inf):
        return nu, lam_ratio, ca_b
    nu = float(as_finite("nu", nu))
    if not 0.0 < nu <= 1.0:
        raise InvalidParameterError("nu", nu, "0 < nu <= 1")
    lam_ratio = float(as_finite("lam_ratio", lam_ratio))
    if lam_ratio >= 1.0:
        raise CannotPassError("lam_ratio", lam_ratio, "0 < lam_ratio < 1",
                              "lam >= lam_c: the vesicle cannot pass the tube intact")
    if lam_ratio <= 0.0:
        raise InvalidParameterError("lam_ratio", lam_ratio, "0 < lam_ratio < 1")
    return nu, lam_ratio, float(check_positive("ca_b", ca_b))


def query_map_many(nu, lam_ratio, ca_b, map=None, names=tuple(QUANTITIES)) -> list[MapQuery]:
    """:func:`query_map` at many points, given as sequences of equal length: one
    :class:`MapQuery` per point, in their order, with the quantities ``names`` (default all;
    with ``V_over_U`` or ``ell`` for the shape class) and ``shape_class``. Every point is
    checked first (the errors of :func:`query_map`); the points inside the map are answered
    together (:meth:`SolutionMap.quantities_many`), each exactly as alone."""
    points = [_point(*p) for p in zip(nu, lam_ratio, ca_b, strict=True)]
    m = map if isinstance(map, SolutionMap) else load_map(map)
    points = [(n, r, m.node_ca_b(c)) for n, r, c in points]
    reasons = [outside_reason(m, *p) for p in points]
    inside = [p for p, reason in zip(points, reasons) if not reason]
    answers = iter(m.quantities_many(*zip(*inside), names) if inside else ())
    out = []
    for p, reason in zip(points, reasons):
        if reason:
            values = {q: MapValue(None, note=reason) for q in (*names, "shape_class")}
        else:
            values = next(answers)
            first = values.get("V_over_U") or values["ell"]
            rows = first.rows or values.get("ell", first).rows
            if not rows:
                values["shape_class"] = MapValue(None, note=first.note)
            else:
                shape = m._shapes.get(rows)
                if shape is None:
                    shape = m._shapes[rows] = m.shape_class(rows)
                values["shape_class"] = shape
        out.append(MapQuery(*p, m.source, values, m.membrane))
    return out


def outside_reason(m: SolutionMap, nu: float, lam_ratio: float, ca_b: float) -> str:
    """Why (nu, lam_ratio, ca_b) lies outside the box of map ``m`` ('' if inside), naming the
    parameter and the map's range (a Ca_B within :data:`CA_B_NODE_ATOL` of a node is on it)."""
    ca_b = m.node_ca_b(ca_b)
    eps = _ON_NODE
    if not m.nus[0] * (1 - eps) <= nu <= m.nus[-1] * (1 + eps):
        return f"nu={nu:.6g} outside the map's range {m.nus[0]:g} <= nu <= {m.nus[-1]:g}"
    lo, hi = m.ratios[0], m.ratios[-1]
    if not lo * (1 - eps) <= lam_ratio <= hi * (1 + eps):
        return (f"lam_ratio={lam_ratio:.6g} outside the map's range {lo:g} <= lam/lam_c <= "
                f"{hi:g}")
    # the clamp is a vesicle result: a red-cell map refuses above its largest Ca_B (module
    # docstring, Membrane)
    top = CA_B_CLAMP_MAX if m.cas[-1] >= 50.0 and m.membrane is None else m.cas[-1]
    if not m.cas[0] * (1 - eps) <= ca_b <= top * (1 + eps):
        return (f"ca_b={ca_b:.6g} outside the map's range {m.cas[0]:g} <= Ca_B <= {top:g}"
                + (" (values above the largest map Ca_B are clamped)" if top > m.cas[-1] else ""))
    return ""


# --------------------------------------------------------------------------- pack

def pack_map(folder, out=None, points=None) -> Path:
    """Pack the finished points of build folder ``folder`` into one file (format
    :data:`FORMAT`), atomically; default ``<folder>/solution_map.json``. Returns the path.
    ``points``: the folder's points as :func:`read_points` gives them, when the caller has
    read them already (default: read here).

    The file holds ``grid``, ``parameters`` and ``provenance`` (from ``build.json``), the
    ``units`` of every column, ``columns`` (the converged points, one list per column, no
    shapes), ``holes`` (failed, rejected or missing grid points with their reasons), the LOO
    errors ``loo_<axis>_<q>`` (see the module docstring) and ``rejected``: the converged
    points left out as unphysical (:func:`_rejection`: a quantity missing, not finite or
    outside :data:`lubrication.checks.OUTPUT_BOUNDS`), each with its coordinates and reason;
    they are holes too (reason "rejected: ..."). ``build.json`` and every point file are read
    through :mod:`correlations.files` and checked against their schemas; a file that fails
    raises :class:`~correlations.files.UnreadableFile` (name ``folder``) before anything is
    written. A folder without a converged point packs into a map of holes only, which
    :func:`load_map` refuses (it names what failed; ``map build`` packs at its end whatever
    its points gave).
    """
    folder = Path(folder)
    build = read_build(folder)
    grid = build["grid"]
    stored = {_key(p["nu"], p["lam_ratio"], p["ca_b"]) + (p["method"],): p
              for p in (read_points(folder) if points is None else points)}
    errors = sorted({f"err_{q}" for p in stored.values()
                     for q in (p.get("error_estimate") or {}) if q in QUANTITIES})
    names = [*_BASE_COLUMNS, *QUANTITIES, *errors]
    cols = {c: [] for c in names}
    holes, rejected = [], []
    for method in grid["methods"]:
        for nu in grid["nu"]:
            for ca in grid["ca_b"]:
                for r in grid["lam_ratio"][method]:
                    p = stored.get(_key(nu, r, ca) + (method,))
                    where = {"method": method, "nu": nu, "lam_ratio": r, "ca_b": ca}
                    why = p is not None and p["success"] and _rejection(p)
                    if why:
                        rejected.append({**where, "reason": why})
                        holes.append({**where, "reason": f"rejected: {why}"})
                        continue
                    if p is None or not p["success"]:
                        holes.append({**where, "reason": "not computed" if p is None else
                                      (p.get("message") or "failed")})
                        continue
                    est = p.get("error_estimate") or {}
                    for c in names:
                        v = est.get(c[4:]) if c.startswith("err_") else p.get(c)
                        if isinstance(v, float) and math.isfinite(v):
                            # the solvers' accuracy is 1e-9 relative at best; errors, residuals
                            # and times need no more than 3 digits (a smaller file)
                            v = float(f"{v:.{_DIGITS.get(c, 3 if c.startswith('err_') else 10)}g}")
                        cols[c].append(v)
    units = {**_BASE_COLUMNS, **QUANTITIES,
             **{e: f"solver error estimate of {e[4:]} (same units)" for e in errors}}
    data = {"format": FORMAT, "version": FORMAT_VERSION, "grid": grid,
            "parameters": build.get("parameters", {}), "provenance": build.get("provenance", {}),
            "transforms": TRANSFORMS, "units": units, "columns": cols, "holes": holes,
            "rejected": rejected}
    loo = SolutionMap(data, str(folder)).leave_one_out()
    data["columns"].update(loo)
    data["units"].update({k: f"leave-one-out error of {k.split('_', 2)[2]} along "
                             f"{k.split('_')[1]}, in its interpolated variable" for k in loo})
    path = Path(out) if out is not None else folder / "solution_map.json"
    data = clean_json(data)
    atomic_write(path, lambda f: json.dump(data, f, separators=(",", ":"), allow_nan=False))
    return path
