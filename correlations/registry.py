r"""The method table of the engineering estimate: which formula gives which quantity, where.

This is the one place that decides how :func:`correlations.estimate.estimate` obtains each
number. For every output quantity the table lists candidate methods in order of preference; the
estimate takes the first one whose validity range contains the case (and whose inputs are
themselves valid). Where no method is valid the quantity is reported as unavailable, with the
reason; it is extrapolated (and flagged ``valid=False``) only when the caller asks for it.

A row either returns a value or an :class:`Answer` (value, absolute error bar, the method name
to report, a note), or raises :class:`MethodNotApplicable` with the reason it has no value here
(the next row is tried and the reason joins the "no valid method" explanation).

State passed to the methods (dimensionless unless named): ``nu``, ``lam``, ``lam_c``, ``delta``
(= 1 - lam/lam_c), ``ell_c``, ``ca_b`` (= eta U R0^2/kappa, absent when unknown),
``solution_map`` (the map the map rows read, below), the quantities computed earlier in table
order, and the optional hematocrits.

Numerical solvers (the lubrication BVP, :mod:`lubrication.solve`; the BEM vesicle,
:mod:`bem.vesicle`) extend the table with opt-in rows, and the shipped solution map
(:mod:`correlations.solution_map`) with rows used by default. Order of use: enabled solver rows
(BEM, then lubrication), then the map rows, then the closed forms.

Map rows (used unless the caller disables the map: ``solution_map=False``, ``--no-map``)
--------------------------------------------------------------------------------------------
One :func:`~correlations.solution_map.query_map` per (nu, lam/lam_c, Ca_B) serves every map row
(:func:`map_query`, cached); the file is read only when an estimate runs. Ca_B is the case's
(eta U R0^2/kappa from the physical inputs), or :data:`MAP_DEFAULT_CA_B` = 50 (Chen et al.
2020's value) when the dimensionless estimate has none; the estimate states which. A row has a
value wherever the query returns one; elsewhere its reason (outside the map's nu, lam/lam_c or
Ca_B range, next to a hole, no map shipped) goes into the explanation and the closed forms
below apply as without a map. The map's own range rules hold: below its smallest Ca_B it
refuses; above its largest Ca_B (when that is >= 50) and up to
:data:`~correlations.solution_map.CA_B_CLAMP_MAX` = 1e4 it returns the values at its largest
Ca_B, with the measured change between its two largest Ca_B added as model error (Chen et al.
2020 §IV.A: shapes virtually independent of Ca_B >= 50); beyond 1e4 it refuses. The reported
method is "map (BEM, interpolated)", "map (lubrication, interpolated)" or "map (BEM +
lubrication, interpolated)" after the methods of the nodes used, and the error bar is the
map's: interpolation + solver + model error, the parts that are known (module docstring of
:mod:`correlations.solution_map`).

::

    ====================  =============================  ==============================================
    quantity              methods, in order of preference  validity (range constant, with its source)
    ====================  =============================  ==============================================
    V_over_U              solution_map                   inside the map (query_map returns a value)
                          small_sphere_faxen             lam <= 0.5, nu >= 0.9 (SMALL_VESICLE_RANGE)
                          near_critical_barakat2018a     delta <= 0.1 (asymptotics.NEAR_CRITICAL_RANGE)
    film                  solution_map (minimum gap)     inside the map
                          geometric_chen2020             delta <= 0.1 (film.FILM_RANGE_CHEN2020)
    ell                   solution_map                   inside the map
                          length_chen2020                delta <= 0.1, nu >= 0.6 (shape.LENGTH_RANGE_CHEN2020)
    dp_plus_R0            solution_map                   inside the map
                          small_sphere_faxen             lam <= 0.5, nu >= 0.9
                          film_scaling_chen2020          delta <= 0.1 (pressure.DP_PLUS_FILM_RANGE_CHEN2020)
                          near_critical_barakat2018a     delta <= 0.1
    shape_class           solution_map                   inside the map, neighbours of one class
                          transition_chen2020            0.6 <= nu, 0.6 <= lam <= 1.94, 10 <= Ca_B <= 1e4
    tension_front         solution_map                   inside the map
                          film_inverse_chen2020          Ca_v <= 1e-2, i.e. film <= 0.093
    tension_max           solution_map                   inside the map (no closed form)
    tube_hematocrit       single_file_flux               d <= 8 um (viscosity.CHEN2020_RANGE)
                          fahraeus_pries1992             3.3 <= d <= 1978 um (viscosity.FAHRAEUS_RANGE)
    discharge_hematocrit  single_file_flux, fahraeus...  as tube_hematocrit
    eta_rel               single_file_chen2020           d <= 8 um, dp_plus_R0 and H_T valid
                          pries1992_in_vitro             3.3 <= d <= 1978 um, H_D <= 0.9
    ====================  =============================  ==============================================

Tensions are in eta V in the table (``tension_front`` is Chen et al.'s inverse vesicle capillary
number 1/Ca_v = gamma_F/(eta V), eqs. sfilm4, tension2). The map and the solvers give gamma/(eta
U); their rows divide by V/U: gamma/(eta V) = (gamma/(eta U))/(V/U), a solver by its own, the
map rows by the estimate's (the map's own wherever the map gives V/U; they need a valid V/U).
That V/U is taken as exact in the conversion (its relative error is typically an order of
magnitude below the tension's), so the estimate's tensions in eta U and mN/m, which multiply
back by the same V/U, carry exactly the map's error bar.

Opt-in solver rows (used first when the caller enables the solver, e.g. ``--solver
lubrication``; otherwise the estimate only notes that the solver covers the case). With both
enabled the BEM rows come first (most accurate, slowest), then the lubrication rows::

    ====================  =============================  ==============================================
    V/U, film (minimum     bem_vesicle                    0.6 <= nu <= 0.98, delta >= 0.02, i.e.
    gap), ell, dp+, shape,                                lam/lam_c <= 0.98 (BEM_RANGE), tol 1e-2; Ca_B
    front and max tension                                 from the case, 50 if unknown; minutes/point
    V/U, film (minimum     lubrication_solver             0.6 <= nu <= 0.98, delta <= 0.05
    gap), ell, dp+, shape,                                (LUBRICATION_RANGE); Ca_B from the case, 50 if
    front and max tension                                 unknown; seconds per point
    ====================  =============================  ==============================================

The BEM is never run unless the caller enables it, not even where no other method is valid:
there the estimate only says that the BEM covers the case (a solve takes minutes). One solve per
(nu, lam, Ca_B) serves all rows of a solver (:func:`_solver_rows`).

A red cell
----------
The state of a red cell (``membrane`` = "red-cell", :data:`MEMBRANES`) also holds ``ca_s`` =
eta U/G_s and ``shear_ratio`` beta = G_s R0^2/kappa = Ca_B/Ca_S (Evans's area-incompressible
shear law, Evans 1973; G_s the membrane shear modulus). Then:

* the solver rows solve the red cell (``ca_s`` passed to :func:`bem.vesicle.solve_vesicle` and
  :func:`lubrication.solve.solve_lubrication`, stress-free shape their default, the Evans–Fung
  disc). The lubrication range is the vesicle's: near lam_c the red cell's BEM and lubrication
  agree as closely as the vesicle's (docs/red-cell.md: Delta p+ 2.6 % apart at lam/lam_c =
  0.95, nu = 0.65, Ca_S = 0.2);
* the map rows read the red-cell map (:data:`~correlations.solution_map.RED_CELL_MAP` unless
  another is given) and answer only when the cell's beta equals the map's within
  :data:`SHEAR_RATIO_RTOL` = 1e-3 (:func:`membrane_mismatch`); a vesicle map never answers for
  a red cell, nor a red-cell map for a vesicle. The tolerance: at fixed Ca_B a relative change
  of beta is the same relative change of Ca_S, and the red cell's answers change with Ca_S
  by at most ``|d ln dp+ / d ln Ca_S|`` ~ 0.5 and ``|d ln V/U / d ln Ca_S|`` ~ 0.1
  (docs/red-cell.md, the largest changes of its table: from 0.2 to 0.5 mm/s in the 6 um tube, Ca_B and Ca_S both
  x2.5, dp+ falls by 34.5 % and V/U rises by 5.5 %, the vesicle's by less than 0.2 %); so
  1e-3 in beta moves dp+ by at most 5e-4 and V/U by 1e-4 relative, well inside the map's
  error bars. Another modulus, bending modulus or cell size needs its own slice or the BEM;
* the closed-form laws of V/U, dp+, film, length, shape class and front tension are not used
  (``membranes`` = vesicle only). The near-critical asymptotes (Barakat & Shaqfeh 2018a), the
  film and tension laws and the transition line (Chen et al. 2020) are derived or fitted for a
  membrane whose only in-plane stress is an isotropic tension; a red cell's shear stress
  enters the normal-stress balance of the film (Secomb et al. 1986), and our BEM puts the
  default red cell's dp+ at 1.3-2.9 times the vesicle's at 0.1-1 mm/s in a 4 um tube
  (docs/red-cell.md). They are the red cell's high-velocity limit (Ca_S -> inf) only, which
  the caller gets with membrane "vesicle". The small rigid sphere needs nu >= 0.9, which is no
  red cell. The geometry (lam_c, passage), the hematocrit conversions and the apparent
  viscosity laws (the single-file model with the red cell's own dp+; Pries et al.'s fits,
  measured on blood) hold for both membranes.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

from numpy.linalg import LinAlgError

from lubrication import asymptotics
from lubrication.checks import OUTPUT_BOUNDS, ValidityRange, check_output

from . import film, pressure, shape, viscosity
from . import solution_map as sm   # its attributes read at call time (tests patch query_map)

__all__ = ["Answer", "BEM_RANGE", "MAP", "MAP_DEFAULT_CA_B", "DEFAULT_MEMBRANE", "MEMBRANES", "Method",
           "MethodNotApplicable", "SHEAR_RATIO_RTOL",
           "METHODS", "OUTPUT_BOUNDS", "QUANTITIES", "SOLVERS", "SOLVER_COST",
           "SolverNotConverged", "check_output", "map_method_name"]

#: Opt-in numerical solvers that rows of the table may name.
SOLVERS = ("lubrication", "bem")
#: The membranes of the estimate (module docstring, "A red cell"): a vesicle (bending, local
#: inextensibility) and a red cell (also in-plane shear elasticity, Ca_S = eta U/G_s).
MEMBRANES = ("vesicle", "red-cell")
#: The membrane of the physical estimate when none is named: a human red cell, with its shear
#: elasticity (answered from the shipped red-cell slice of the map).
DEFAULT_MEMBRANE = "red-cell"
#: Largest ``|beta/beta_map - 1|`` at which a red-cell map answers for a cell (module docstring).
SHEAR_RATIO_RTOL = 1e-3
#: ``Method.solver`` of the map rows: used unless the caller disables the map.
MAP = "map"

#: Typical cost of one estimate with each solver (quoted in the estimate's notes; BEM: 1.4 s at
#: (0.9, 1.0) to about a minute near lam_c, tests/benchmarks/bench_vesicle.py).
SOLVER_COST = {"lubrication": "seconds per case", "bem": "seconds to minutes per case"}


@dataclass(frozen=True)
class Method:
    """One row of the method table.

    Attributes
    ----------
    quantity : str
        Output key the method produces.
    name : str
        Short method name, reported beside every number it produces.
    source : str
        Citation with equation label.
    validity : ValidityRange
        Box of state variables (names as in the module docstring) where the method holds.
    evaluate : callable
        ``evaluate(state) -> value`` with ``state`` the dict described in the module docstring.
    requires : tuple of str
        Quantities that must already be available *and valid* in the state.
    solver : str or None
        Name of the numerical solver behind the row (``"lubrication"``, ``"bem"``); such rows
        are used only when the caller enables that solver, and then ahead of the closed forms
        (in the order of :data:`METHODS`: BEM first). :data:`MAP` (``"map"``) for the rows of
        the solution map, used unless the caller disables the map, after enabled solvers.
    membranes : tuple of str
        The membranes (:data:`MEMBRANES`) the method holds for: both for the solvers, the map
        and the hematocrit and viscosity laws; ``("vesicle",)`` for the closed-form vesicle
        laws (module docstring, "A red cell").
    """

    quantity: str
    name: str
    source: str
    validity: ValidityRange
    evaluate: Callable[[dict], float | str]
    requires: tuple[str, ...] = ()
    solver: str | None = None
    membranes: tuple[str, ...] = MEMBRANES


class SolverNotConverged(RuntimeError):
    """A solver row could not produce a converged solution (the message says why)."""


class MethodNotApplicable(LookupError):
    """A row has no value for this case (the message says why); the next row is tried."""


@dataclass(frozen=True)
class Answer:
    """What a row may return instead of a bare value: the value, its absolute error bar in the
    same unit (None when unknown), the method name to report (None: the row's name) and a
    note."""

    value: float | str
    error: float | None = None
    name: str | None = None
    note: str = ""


# Chen et al. 2020 state that their vesicle V/U and dp+ agree with the small rigid-sphere laws to
# within 1 % for lam < 0.5 "particularly for nearly spherical vesicles", nu = 0.6 being a clear
# exception; we accept the laws for a vesicle only from nu >= 0.9 (our conservative choice).
SMALL_VESICLE_RANGE = ValidityRange.of(
    "Chen et al. 2020 §IV.C (small rigid sphere applied to a quasi-spherical vesicle)",
    lam=(0.0, 0.5), nu=(0.9, 1.0))

# Single-file flow (d up to ~8 um). In the dimensionless estimate (no diameter known) only the
# requirements on dp+ and V/U apply.
SINGLE_FILE_RANGE = viscosity.CHEN2020_RANGE


# eq. sfilm4 is fitted for Ca_v <= 1e-2; with delta = c0 Ca_v^(2/3) that is a bound on the film.
_TENSION_RANGE = ValidityRange.of(
    film.CAPILLARY_RANGE_CHEN2020.source,
    film=(0.0, film.film_from_capillary_chen2020(film.CAPILLARY_RANGE_CHEN2020.bounds[0][2])))


def _eta_single_file(s: dict) -> float:
    # Lengths in units of the tube radius: d = 2, R0 = lam.
    return viscosity.viscosity_single_file_chen2020(s["dp_plus_R0"], 2.0, s["lam"], s["tube_hematocrit"])

# Lubrication solver (lubrication.solve): valid where it agrees with our BEM to Delta p+ within
# 10 % and V/U, ell within 0.5 %. Measured in the map's overlap (tests/benchmarks/
# lubrication_overlap.py, every (nu, Ca_B) line with both methods converged): the largest
# |lubrication - BEM|/BEM in Delta p+ is 5.7 % at delta = 0.02, 10.0 % at 0.05 and 15.2 % at 0.1
# (lubrication low; V/U within 0.1 % and ell within 0.11 % for delta <= 0.05), so delta <= 0.05. (Chen
# et al. 2020 §IV.C find "very good agreement" for lam > 1.4 at nu ~ 0.6, delta <~ 0.3, by eye
# on a figure; our BEM has Delta p+ 21-27 % apart at delta = 0.29.) nu from 0.6 to 0.98 is the
# range the solver is tested on.
LUBRICATION_RANGE = ValidityRange.of(
    "BEM vs lubrication in the solution map's overlap (Delta p+ within 10 %)",
    nu=(0.6, 0.98), delta=(0.0, 0.05))
#: Ca_B used by the lubrication rows when the estimate has none (Chen et al. 2020 use 50).
LUBRICATION_DEFAULT_CA_B = 50.0


@dataclass(frozen=True)
class _Failed:
    """A solver call that raised instead of returning a result (cached like a result)."""

    success = False
    message: str


def guarded(solve, *args, **kwargs):
    """``solve(*args, **kwargs)``, or a :class:`_Failed` carrying the reason when it raises.

    A solver that raises (bad state, a linear-algebra or floating-point failure) produces no
    numbers: the rows of the table fall back to the next method, as for a non-converged
    result. KeyboardInterrupt is not caught (the command exits 130 naming no number).
    """
    try:
        return solve(*args, **kwargs)
    except (ArithmeticError, ValueError, RuntimeError, LinAlgError) as exc:
        return _Failed(f"{type(exc).__name__}: {exc}")


@functools.lru_cache(maxsize=16)
def _lubrication_solution(nu: float, lam: float, ca_b: float, ca_s: float | None = None):
    """One :func:`lubrication.solve.solve_lubrication` per case; ``ca_s`` for a red cell (its
    default stress-free shape, the Evans–Fung disc), absent for a vesicle."""
    from lubrication.solve import (  # lazy: scipy.integrate off the estimate's start-up
        solve_lubrication)
    if ca_s is None:
        return guarded(solve_lubrication, nu, lam, ca_b=ca_b)
    return guarded(solve_lubrication, nu, lam, ca_b=ca_b, ca_s=ca_s)


# BEM vesicle (bem.vesicle): the full Stokes problem, no lubrication approximation. Validated for
# nu = 0.9 up to lam/lam_c = 0.98, nu = 0.98, and long vesicles (nu = 0.6-0.8, "bend" density):
# (0.61, 1.39) the RBC in 4 um, (0.7, 1.5), (0.6, 1.78-1.84), (0.8, 0.97 lam_c) converge to
# ~1 %; at nu = 0.6 near lam_c (delta = 0.02) gamma_max is not converged and the solve reports
# it (docs/validation.md).
BEM_RANGE = ValidityRange.of("validated range of bem.vesicle.solve_vesicle (docs/validation.md)",
                             nu=(0.6, 0.98), delta=(0.02, 1.0))
#: tolerances of the estimate's BEM solve (engineering accuracy, ~1 %): refinement pair and
#: steady residual max|u - V e_x| [U]
BEM_TOLERANCES = {"tol": 1e-2, "residual_tol": 5e-3}
#: Ca_B used by the BEM rows when the estimate has none (Chen et al. 2020 use 50).
BEM_DEFAULT_CA_B = 50.0


@functools.lru_cache(maxsize=16)
def _bem_result(nu: float, lam: float, ca_b: float, ca_s: float | None = None):
    """One :func:`bem.vesicle.solve_vesicle` per (nu, lam, Ca_B[, Ca_S]) to BEM_TOLERANCES,
    converged or not (minutes); ``ca_s`` for a red cell (default stress-free shape, the
    Evans–Fung disc), absent for a vesicle."""
    from bem import vesicle  # lazy: bem and scipy off the estimate's start-up
    if ca_s is None:
        return guarded(vesicle.solve_vesicle, nu, lam, ca_b=ca_b, **BEM_TOLERANCES)
    return guarded(vesicle.solve_vesicle, nu, lam, ca_b=ca_b, ca_s=ca_s, **BEM_TOLERANCES)


#: Table quantities a solver or the map gives, with the name of each in their results.
_SOLUTION_KEYS = (("V_over_U", "V_over_U"), ("film", "film_min"), ("ell", "ell"),
                  ("dp_plus_R0", "dp_plus_R0"), ("shape_class", "shape_class"),
                  ("tension_front", "tension_front"), ("tension_max", "tension_max"))
#: Tensions: gamma/(eta U) in the results, gamma/(eta V) in the table (module docstring).
_TENSIONS = ("tension_front", "tension_max")


def _solver_rows(solver: str, name: str, reference: str, rng: ValidityRange, solve,
                 default_ca_b: float) -> tuple[Method, ...]:
    """Rows of one numerical solver for V/U, film (minimum gap), ell, dp+, shape class, front
    and maximum tension; ``solve(nu, lam, ca_b)`` is cached, so one solve serves all rows (failures
    included, so a solve that did not converge is not repeated for every row)."""
    def values(res) -> dict:
        """Every table quantity of a solve, or SolverNotConverged: a solve that failed, or
        returned one non-finite or unphysical number, gives no number at all."""
        if not res.success:
            raise SolverNotConverged(f"{solver} solver did not converge: {res.message}")
        out = {}
        for q, key in _SOLUTION_KEYS:
            value = getattr(res, key, None)
            if q in _TENSIONS and value is not None:   # table unit: eta V (result: eta U)
                value = value / res.V_over_U
            problem = check_output(q, value, {})
            if problem:
                raise SolverNotConverged(f"{solver} solver reported success but its result is "
                                         f"rejected: {problem}")
            out[q] = value
        return out

    def row(quantity: str):
        def evaluate(s: dict):
            red_cell = (s["ca_s"],) if "ca_s" in s else ()     # a vesicle: no Ca_S
            return values(solve(s["nu"], s["lam"], s.get("ca_b", default_ca_b),
                                *red_cell))[quantity]
        return evaluate
    return tuple(
        Method(q, name, reference + (" (minimum gap)" if q == "film" else ""), rng, row(q),
               solver=solver)
        for q, _ in _SOLUTION_KEYS)


_LUBRICATION_ROWS = _solver_rows(
    "lubrication", "lubrication_solver", "Secomb et al. 1986 / Barakat & Shaqfeh 2018b "
    "lubrication model, lubrication.solve", LUBRICATION_RANGE,
    lambda *a: _lubrication_solution(*a), LUBRICATION_DEFAULT_CA_B)   # looked up at call time
_BEM_ROWS = _solver_rows("bem", "bem_vesicle", "BEM vesicle, bem.vesicle.solve_vesicle", BEM_RANGE,
                         lambda *a: _bem_result(*a), BEM_DEFAULT_CA_B)


# Solution map (correlations.solution_map): stored steady BEM and lubrication solutions over
# (nu, lam/lam_c, Ca_B), interpolated with an error bar. The query decides where it has a value,
# so the rows' validity box has no bounds.
#: Ca_B used by the map rows when the estimate has none (Chen et al. 2020 use 50).
MAP_DEFAULT_CA_B = 50.0
_MAP_RANGE = ValidityRange.of("the box of the solution map, holes excluded (query_map decides)")
_MAP_SOURCE = ("solution map (correlations.solution_map): stored BEM and lubrication solutions, "
               "interpolated")


def resolve_solution_map(choice, membrane: str = "vesicle"):
    """The map the rows read: ``choice`` None for the shipped map of ``membrane`` (the vesicle
    map :data:`~correlations.solution_map.DEFAULT_MAP`, the red-cell slice
    :data:`~correlations.solution_map.RED_CELL_MAP`; the rows have no value when none is
    shipped), or a path or :class:`~correlations.solution_map.SolutionMap`."""
    if isinstance(choice, sm.SolutionMap):
        return choice
    if membrane == "vesicle":
        if choice is None and not sm.DEFAULT_MAP.exists():
            raise MethodNotApplicable(f"no solution map shipped ({sm.DEFAULT_MAP} absent)")
        return sm.load_map(choice)
    if choice is None and not sm.RED_CELL_MAP.exists():
        raise MethodNotApplicable(f"no red-cell map shipped ({sm.RED_CELL_MAP.name} absent): "
                                  "give --solver bem or --membrane vesicle")
    return sm.load_map(sm.RED_CELL_MAP if choice is None else choice)


def membrane_mismatch(m, state: dict) -> str:
    """Why map ``m`` cannot answer for the cell of ``state`` ('' if it can): a vesicle map for
    a red cell or a red-cell map for a vesicle, or a red-cell map of another shear ratio
    beta = G_s R0^2/kappa than the cell's (tolerance :data:`SHEAR_RATIO_RTOL`, module
    docstring)."""
    red_cell = state.get("membrane", "vesicle") == "red-cell"
    if m.membrane is None:
        return ("the map is a vesicle map (no shear elasticity): it gives no red-cell value"
                if red_cell else "")
    beta_map = m.membrane["shear_ratio"]
    if not red_cell:
        return (f"the map is a red-cell map (beta = {beta_map:.4g}): it gives no vesicle value")
    beta = state["shear_ratio"]
    if abs(beta / beta_map - 1.0) > SHEAR_RATIO_RTOL:
        cell = state.get("default_cell")    # (beta, "G_s ..., kappa ..., volume") of the default
        known = cell is not None and abs(cell[0] / beta_map - 1.0) <= SHEAR_RATIO_RTOL
        return (f"the red-cell map holds beta = G_s R0^2/kappa = {beta_map:.4g}"
                + (f" ({cell[1]})" if known else "")
                + f"; this cell has beta = {beta:.4g} (|beta/beta_map - 1| = "
                f"{abs(beta / beta_map - 1.0):.2g} > {SHEAR_RATIO_RTOL:g}): give --solver bem "
                "or --membrane vesicle")
    return ""


@functools.lru_cache(maxsize=32)
def map_query(nu: float, lam_ratio: float, ca_b: float, solution_map):
    """One :func:`~correlations.solution_map.query_map` per case and map: serves every map row."""
    return sm.query_map(nu, lam_ratio, ca_b, solution_map)


def map_method_name(methods) -> str:
    """Reported name of a map value from the methods of the nodes it used.

    >>> map_method_name(("bem", "lubrication"))
    'map (BEM + lubrication, interpolated)'
    """
    labels = {"bem": "BEM", "lubrication": "lubrication"}
    return "map (" + " + ".join(labels.get(m, m) for m in sorted(methods)) + ", interpolated)"


def _map_row(quantity: str, key: str):
    """``evaluate`` of the map row of ``quantity`` (``key`` its name in the map)."""
    def evaluate(s: dict) -> Answer:
        m = resolve_solution_map(s.get("solution_map"), s.get("membrane", "vesicle"))
        mismatch = membrane_mismatch(m, s)
        if mismatch:
            raise MethodNotApplicable(mismatch)
        ca_b = s.get("ca_b", MAP_DEFAULT_CA_B)
        res = map_query(s["nu"], s["lam"] / s["lam_c"], ca_b, m)
        v = res.quantities[key]
        if v.value is None:
            raise MethodNotApplicable(v.note)
        if isinstance(v.value, str):
            return Answer(v.value, None, map_method_name(v.methods))
        value, error = v.value, v.error
        if quantity in _TENSIONS:       # gamma/(eta V) = (gamma/(eta U))/(V/U), module docstring
            if "V_over_U" not in s:
                raise MethodNotApplicable(f"needs a valid V_over_U to express {key} in eta V")
            value, error = value / s["V_over_U"], None if error is None else error / s["V_over_U"]
        notes = []
        if ca_b > m.cas[-1]:
            notes.append(f"Ca_B={ca_b:.4g} above the map's largest {m.cas[-1]:g}: its values "
                         "there, the change from the next Ca_B added as model error")
        unknown = [part for part, e in (("interpolation", v.interpolation_error),
                                        ("solver", v.solver_error), ("model", v.model_error))
                   if e is None]
        if unknown:
            notes.append(f"error bar without the unknown {' and '.join(unknown)} error"
                         + ("s" if len(unknown) > 1 else ""))
        return Answer(value, error, map_method_name(v.methods), "; ".join(notes))
    return evaluate


_MAP_ROWS = tuple(Method(q, "solution_map",
                         _MAP_SOURCE + (" (minimum gap)" if q == "film" else ""), _MAP_RANGE,
                         _map_row(q, key), solver=MAP)
                  for q, key in _SOLUTION_KEYS)


def _fahraeus_tube(s: dict) -> float:
    return viscosity.tube_hematocrit_fahraeus(s["diameter_um"], s["discharge_hematocrit"], constants="pries1992")


def _fahraeus_discharge(s: dict) -> float:
    return viscosity.discharge_hematocrit_fahraeus(s["diameter_um"], s["tube_hematocrit"], constants="pries1992")


def _eta_pries1992(s: dict) -> float:
    return viscosity.viscosity_vitro_pries1992(s["diameter_um"], s["discharge_hematocrit"])


#: The closed-form laws of V/U, dp+, film, length, shape class and front tension are vesicle
#: results (module docstring, "A red cell"): they answer for a vesicle only.
_VESICLE = ("vesicle",)

METHODS: tuple[Method, ...] = (
    *_BEM_ROWS,
    *_LUBRICATION_ROWS,
    *_MAP_ROWS,
    Method("V_over_U", "small_sphere_faxen", "Chen et al. 2020 eq. small1 (Faxen)",
           SMALL_VESICLE_RANGE, lambda s: asymptotics.speed_small_sphere(s["lam"]), membranes=_VESICLE),
    Method("V_over_U", "near_critical_barakat2018a",
           "Barakat & Shaqfeh 2018a as Chen et al. 2020 eq. asmyp1",
           asymptotics.NEAR_CRITICAL_RANGE,
           lambda s: asymptotics.speed_near_critical(s["nu"], s["lam"]), membranes=_VESICLE),
    Method("dp_plus_R0", "small_sphere_faxen", "Chen et al. 2020 eq. small2",
           SMALL_VESICLE_RANGE, lambda s: asymptotics.dp_plus_small_sphere(s["lam"]), membranes=_VESICLE),
    Method("dp_plus_R0", "film_scaling_chen2020", "Chen et al. 2020 fig. dpa_film: (3/2) lam ell/delta",
           pressure.DP_PLUS_FILM_RANGE_CHEN2020,
           lambda s: pressure.dp_plus_film_chen2020(s["lam"], s["ell"], s["film"]),
           requires=("ell", "film"), membranes=_VESICLE),
    Method("dp_plus_R0", "near_critical_barakat2018a",
           "Barakat & Shaqfeh 2018a as Chen et al. 2020 eq. asmyp2",
           asymptotics.NEAR_CRITICAL_RANGE,
           lambda s: asymptotics.dp_plus_near_critical(s["nu"], s["lam"]), membranes=_VESICLE),
    Method("film", "geometric_chen2020", "Chen et al. 2020 eq. sfilm2: h/R = 1 - lam/lam_c",
           film.FILM_RANGE_CHEN2020, lambda s: film.film_thickness_chen2020(s["nu"], s["lam"]), membranes=_VESICLE),
    Method("ell", "length_chen2020", "Chen et al. 2020 eq. sL: ell = ell_c lam/lam_c",
           shape.LENGTH_RANGE_CHEN2020, lambda s: shape.length_chen2020(s["nu"], s["lam"]), membranes=_VESICLE),
    Method("shape_class", "transition_chen2020", "Chen et al. 2020 eq. transition",
           shape.SHAPE_CLASS_RANGE_CHEN2020, lambda s: shape.shape_class_chen2020(s["nu"], s["lam"]), membranes=_VESICLE),
    Method("tension_front", "film_inverse_chen2020",
           "Chen et al. 2020 eqs. sfilm4, tension2: gamma_F/(eta V) = (delta/c0)^(-3/2), c0 = 2",
           _TENSION_RANGE,
           lambda s: 1.0 / film.capillary_from_film_chen2020(s["film"]), requires=("film",), membranes=_VESICLE),
    # Cell-flux conservation in single file: H_D U = H_T V, i.e. H_D/H_T = V/U (physics-notes §6).
    Method("tube_hematocrit", "single_file_flux", "cell flux conservation: H_T = H_D/(V/U)",
           SINGLE_FILE_RANGE, lambda s: s["discharge_hematocrit"] / s["V_over_U"],
           requires=("V_over_U", "discharge_hematocrit")),
    Method("tube_hematocrit", "fahraeus_pries1992", "Pries et al. 1992 Fahraeus relation",
           viscosity.FAHRAEUS_RANGE, _fahraeus_tube, requires=("diameter_um", "discharge_hematocrit")),
    Method("discharge_hematocrit", "single_file_flux", "cell flux conservation: H_D = H_T V/U",
           SINGLE_FILE_RANGE, lambda s: s["tube_hematocrit"] * s["V_over_U"],
           requires=("V_over_U", "tube_hematocrit")),
    Method("discharge_hematocrit", "fahraeus_pries1992", "Pries et al. 1992 Fahraeus relation, inverted",
           viscosity.FAHRAEUS_RANGE, _fahraeus_discharge, requires=("diameter_um", "tube_hematocrit")),
    Method("eta_rel", "single_file_chen2020", "Chen et al. 2020 §IV.D",
           SINGLE_FILE_RANGE, _eta_single_file, requires=("dp_plus_R0", "tube_hematocrit")),
    Method("eta_rel", "pries1992_in_vitro", "Pries, Neuhaus & Gaehtgens 1992",
           viscosity.PRIES1992_RANGE, _eta_pries1992, requires=("diameter_um", "discharge_hematocrit")),
)


#: Output quantities in evaluation order (later rows may require earlier ones).
QUANTITIES = ("V_over_U", "film", "ell", "dp_plus_R0", "shape_class", "tension_front",
              "tension_max", "tube_hematocrit", "discharge_hematocrit", "eta_rel")

