r"""Engineering estimate for a vesicle or red blood cell in a narrow tube.

Scalings (stated once): lengths by the tube radius R where named ``/R`` (film h/R, length
:math:`\ell = L/R`), otherwise by the volume radius R0; velocities by the mean Poiseuille
velocity U; extra pressure drop :math:`\Delta p^+ R_0/(\eta U)` (``dp_plus_R0``) and
:math:`\Delta p^+ R/(\eta U)` (``dp_plus_R``); front and maximum tension by :math:`\eta V`
(``tension_front``, the inverse vesicle capillary number 1/Ca_v, Chen et al. 2020 eqs. sfilm4,
tension2; ``tension_max``) and by :math:`\eta U` (``tension_front_etaU``, ``tension_max_etaU``).

Every number carries the method that produced it (a row of :mod:`correlations.registry`),
whether the case lies inside that method's validity range, and its absolute error bar where the
method has one (``error``, same unit; the solution map's rows, None for the closed forms).
Numbers derived from another by a change of unit carry its error scaled alike. Where no method
is valid the number is reported as unavailable with the reasons, unless ``extrapolate=True`` is
asked for, in which case the least-extrapolated method is used and the number is flagged
``valid=False``.

By default the shipped solution map (:mod:`correlations.solution_map`) answers inside its range
ahead of the closed forms (rows of :mod:`correlations.registry`); ``solution_map=False`` turns it
off, and a path or :class:`~correlations.solution_map.SolutionMap` uses another map.

Defaults describe a human red blood cell in a capillary (physics-notes §6 and sources there):
volume 90 fL and area 135 µm² (Evans & Fung 1972; nu = 0.61, Chen et al. 2020 use 0.6), bending
modulus 2e-19 J (Evans 1983; Chen et al. 2020), plasma viscosity 1.2 mPa·s at 37 °C (Késmárky et
al. 2008), capillary red-cell velocity 1 mm/s (Ivanov et al. 1981; Pries & Secomb 2003), tube
diameter 4 µm (a narrow capillary; capillaries are 4-8 µm). Bilayer rupture tension 3-10 mN/m
(Evans et al. 2003; Rawicz et al. 2000).
"""

from __future__ import annotations

import math
import os
import warnings
from dataclasses import dataclass, field

import numpy as np

from lubrication.checks import (CannotPassError, InvalidParameterError, OutOfRangeWarning,
                                check_choice, check_fraction, check_positive, check_range)
from lubrication.io import provenance
from lubrication.geometry import (cell_from_volume_area, check_passes, check_reduced_volume,
                                  critical_diameter_um, volume_radius,
                                  critical_length, critical_length_um)

from . import viscosity
from .formatting import format_value_error
from .registry import (BEM_DEFAULT_CA_B, LUBRICATION_DEFAULT_CA_B, MAP, MAP_DEFAULT_CA_B,
                       DEFAULT_MEMBRANE, MEMBRANES, METHODS, QUANTITIES, SHEAR_RATIO_RTOL, SOLVER_COST, SOLVERS,
                       Answer, MethodNotApplicable, SolverNotConverged, check_output,
                       membrane_mismatch, resolve_solution_map)
from .solution_map import RED_CELL_MAP, SolutionMap, load_map

__all__ = ["RBC_DEFAULTS", "PHYSICAL_BOUNDS", "RUPTURE_TENSION_MN_M", "UNITS", "Quantity",
           "Estimate", "estimate", "estimate_dimensionless", "physical_scales",
           "SingleFileViscosity", "single_file_viscosity"]

RBC_DEFAULTS = {
    "volume_fl": 90.0,            # Evans & Fung 1972 (mean corpuscular volume ~90 fL)
    "area_um2": 135.0,            # Evans & Fung 1972
    "diameter_um": 4.0,           # narrow capillary
    "velocity_mm_s": 1.0,         # mean flow velocity U; capillary RBC speeds ~1 mm/s
    "plasma_viscosity_mpas": 1.2,  # plasma at 37 degC
    "bending_modulus_j": 2e-19,   # Chen et al. 2020, Evans 1983
    "shear_modulus_un_m": 6.0,    # membrane shear modulus G_s, Hochmuth & Waugh 1987
}

#: Accepted range of each physical input, ``name: (lo, hi, reason)`` (closed bounds). They are
#: wide (many decades around every physical case) and exist so that absurd values are refused
#: with a message instead of overflowing: inside them every derived number of the estimate
#: (Ca_B between ~1e-35 and ~1e32, pressures, tensions, lengths) is a finite double.
PHYSICAL_BOUNDS = {
    "volume_fl": (1e-6, 1e12, "from R0 = 6 nm (the smallest closed bilayer vesicles have "
                              "R0 ~ 10 nm) to R0 = 6 mm (giant vesicles are < 0.1 mm)"),
    "diameter_um": (1e-3, 1e7, "from 1 nm to 10 m"),
    "velocity_mm_s": (1e-9, 1e6, "from 1 pm/s to 1 km/s (Stokes flow needs far less than the "
                                 "upper bound: capillary red cells move at ~1 mm/s)"),
    "plasma_viscosity_mpas": (1e-3, 1e12, "from gases (~0.02 mPa s) to bitumen-like liquids; "
                                          "plasma is 1.2 mPa s"),
    "bending_modulus_j": (1e-24, 1e-12, "from 1e-3 kT to 1e8 kT; lipid bilayers and red cells "
                                        "have 1e-20 to 1e-18 J"),
    "shear_modulus_un_m": (1e-6, 1e6, "from 1 pN/m to 1 N/m; red cells have 4-10 uN/m "
                                      "(Hochmuth & Waugh 1987)"),
}

#: Lysis tension range of lipid bilayers and RBC membranes [mN/m] (Rawicz et al. 2000; Evans et al. 2003).
RUPTURE_TENSION_MN_M = (3.0, 10.0)

# Regime boundaries: the validity limits of the small-object and near-critical laws.
_SMALL_LAM, _NEAR_CRITICAL_DELTA = 0.5, 0.1

_HEMATOCRIT_KEYS = ("tube_hematocrit", "discharge_hematocrit", "eta_rel")
NO_HEMATOCRIT = "not computed: give a hematocrit (--hematocrit)"

#: Unit or scale of every quantity of the estimate (the table's "unit / scaling" column and the
#: JSON ``methods[key].unit``). Convention: a physical unit ("um", "mm/s", "Pa", "nm", "mN/m"),
#: or the scale a dimensionless number is measured in ("R": the value is h/R; "eta U/R0": the
#: value is dp+ R0/(eta U)); "-" for a plain dimensionless number (nu, V/U, a hematocrit);
#: "" for a non-number (a shape class, yes/no).
UNITS = {
    "nu": "-", "lam": "-", "lam_c": "-", "delta": "-", "ell_c": "R_c", "passes": "",
    "ca_b": "-", "V_over_U": "-", "film": "R", "ell": "R", "dp_plus_R0": "eta U/R0",
    "dp_plus_R": "eta U/R", "shape_class": "", "tension_front": "eta V",
    "tension_front_etaU": "eta U", "tension_max": "eta V", "tension_max_etaU": "eta U",
    "tube_hematocrit": "-", "discharge_hematocrit": "-",
    "eta_rel": "-", "R0_um": "um", "d_c_um": "um", "L_c_um": "um", "V_mm_s": "mm/s",
    "dp_plus_Pa": "Pa", "film_nm": "nm", "length_um": "um", "tension_front_mN_m": "mN/m",
    "tension_max_mN_m": "mN/m", "ca_s": "-", "shear_ratio": "-",
}


@dataclass(frozen=True)
class Quantity:
    """A number of the estimate with its provenance.

    ``value`` is None when no valid method exists (and extrapolation was not asked for).
    ``error`` is its absolute error bar in ``unit`` where the method gives one (the solution
    map), None where it is unknown (the closed forms, the solvers).
    """

    value: float | str | None
    unit: str
    method: str | None
    valid: bool
    source: str = ""
    note: str = ""
    error: float | None = None


@dataclass(frozen=True)
class Estimate:
    """Result of :func:`estimate` or :func:`estimate_dimensionless` (frozen; inputs included)."""

    inputs: dict
    quantities: dict
    regime: str
    notes: tuple = ()
    provenance: dict = field(default_factory=dict)
    converged: bool = True

    def __getitem__(self, key):
        return self.quantities[key].value

    def to_dict(self) -> dict:
        """Flat JSON-ready dict: each key its value, plus ``methods`` (provenance per key).

        When an enabled solver failed, ``converged`` is False and ``message`` says why (the
        numbers shown then come from the other methods of the table, never from the failed
        solve)."""
        out = {"command": "estimate", "converged": self.converged, "regime": self.regime}
        if not self.converged:
            out["message"] = "; ".join(n for n in self.notes if "did not converge" in n)
        out.update({k: q.value for k, q in self.quantities.items()})
        out["methods"] = {k: {"method": q.method, "valid": q.valid, "source": q.source,
                              "unit": q.unit, "error": q.error,
                              **({"note": q.note} if q.note else {})}
                          for k, q in self.quantities.items()}
        out["inputs"] = dict(self.inputs)
        out["notes"] = list(self.notes)
        out["provenance"] = dict(self.provenance)
        return out


def _select(quantity: str, known: dict, extrapolated: dict, extrapolate: bool,
            solvers: tuple = (), log: dict | None = None) -> Quantity:
    """Evaluate ``quantity`` with the first valid method of the table (see module docstring).

    Only the rows of the case's membrane (``known["membrane"]``, a vesicle when absent) take
    part. Rows of an enabled solver come first, then the map rows when ``solvers`` holds
    :data:`~correlations.registry.MAP` (in table order), then the closed forms; rows of other
    solvers are skipped, but when one would have been valid that is recorded per quantity in
    ``log["covers"]``. Solver failures go to ``log["failures"]``, rows without a value here to
    the reasons, and the next row is tried. The map rows are never an extrapolation fallback.
    """
    log = {} if log is None else log
    reasons, fallback = [], None
    membrane = known.get("membrane", "vesicle")     # rows of the other membrane never answer
    rows = sorted((m for m in METHODS if m.quantity == quantity and membrane in m.membranes and
                   (m.solver is None or m.solver in solvers)), key=lambda m: m.solver is None)
    for m in METHODS:
        if (m.quantity == quantity and m.solver in SOLVERS and m.solver not in solvers
                and membrane in m.membranes and m.validity.contains(**known)):
            log.setdefault("covers", {}).setdefault(quantity, set()).add(m.solver)
    for m in rows:
        missing = [r for r in m.requires if r not in known]
        if missing:
            reasons.append(f"{m.name}: needs a valid {', '.join(missing)}")
            if extrapolate and all(r in known or r in extrapolated for r in m.requires):
                fallback = fallback or (math.inf, m)
            continue
        bad = m.validity.violations(**known)
        if not bad:
            answer, failure = _evaluate(m, quantity, known, log)
            if not failure:
                return Quantity(answer.value, UNITS[quantity], answer.name or m.name, True,
                                m.source, answer.note, answer.error)
            reasons.append(f"{m.name}: {failure}")
            continue
        reasons.append(f"{m.name}: {'; '.join(bad)}")
        dist = m.validity.distance(**known)
        if extrapolate and m.solver != MAP and (fallback is None or dist < fallback[0]):
            fallback = (dist, m)
    note = "no valid method (" + " | ".join(reasons) + ")" if reasons else "no method"
    if not reasons and membrane == "red-cell":
        note = ("no valid method (for a red cell only the red-cell map and the solvers answer; "
                "the closed-form laws are vesicle results)")
    if fallback is None:
        return Quantity(None, UNITS[quantity], None, False, "", note)
    m = fallback[1]
    answer, failure = _evaluate(m, quantity, {**extrapolated, **known}, log)
    if failure:
        return Quantity(None, UNITS[quantity], None, False, "", f"{note}; {m.name}: {failure}")
    return Quantity(answer.value, UNITS[quantity], answer.name or m.name, False, m.source,
                    "EXTRAPOLATED; " + note, answer.error)


def _evaluate(m, quantity: str, state: dict, log: dict):
    """``(Answer, "")`` from method ``m``, or ``(None, reason)`` when it fails, has no value
    here, or its value breaks the bounds of :func:`correlations.registry.check_output` (never a
    number from a failure). A map row that answers is logged in ``log["ran"]``, one without a
    value in ``log["map_refused"]`` (quantity: reason)."""
    if m.solver in SOLVERS:
        log.setdefault("ran", set()).add(m.solver)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutOfRangeWarning)
            answer = m.evaluate(state)
    except SolverNotConverged as exc:
        log.setdefault("failures", {})[m.solver] = str(exc)
        return None, str(exc)
    except (MethodNotApplicable, InvalidParameterError) as exc:
        # InvalidParameterError: e.g. a fit evaluated where it is unphysical, a corrupt map
        reason = str(exc) if isinstance(exc, MethodNotApplicable) else f"not applicable: {exc}"
        if m.solver == MAP:
            log.setdefault("map_refused", {})[quantity] = reason
        return None, reason
    if not isinstance(answer, Answer):
        answer = Answer(answer)
    if not isinstance(answer.value, str):
        answer = Answer(float(answer.value), answer.error, answer.name, answer.note)
    problem = check_output(quantity, answer.value, state)
    if problem:
        if m.solver in SOLVERS:
            log.setdefault("failures", {})[m.solver] = f"rejected output: {problem}"
        if m.solver == MAP:
            log.setdefault("map_refused", {})[quantity] = f"rejected output: {problem}"
        return None, f"rejected output: {problem}"
    if m.solver == MAP:
        log.setdefault("ran", set()).add(MAP)
    return answer, ""


def _scaled(q: Quantity, factor: float, unit: str, times: Quantity | None = None) -> Quantity:
    """``q`` (times ``times``) rescaled: a derived number inherits method, validity, note and
    error bar (scaled alike).

    ``times`` is V/U, the scale that turns a tension in eta V into eta U: its own error is not
    propagated. The tensions with an error bar are the map's, natively in eta U and divided by
    the same V/U (:mod:`correlations.registry`), so the round trip carries exactly the map's
    error.
    """
    parts = [q] if times is None else [q, times]
    missing = [p for p in parts if p.value is None]
    if missing:
        return Quantity(None, unit, None, False, "", missing[0].note)
    scale = factor * (1.0 if times is None else times.value)
    value = q.value * scale
    if not math.isfinite(value):    # cannot happen inside PHYSICAL_BOUNDS; never report it
        return Quantity(None, unit, None, False, "", f"not representable ({value!r})")
    valid = all(p.valid for p in parts)
    note = next((p.note for p in parts if p.note), "")
    error = None if q.error is None else q.error * abs(scale)
    return Quantity(value, unit, q.method, valid, q.source, note, error)


def _regime(lam: float, delta: float) -> str:
    if lam <= _SMALL_LAM:
        return f"small object (lam <= {_SMALL_LAM})"
    if delta <= _NEAR_CRITICAL_DELTA:
        return f"near-critical (delta = 1 - lam/lam_c <= {_NEAR_CRITICAL_DELTA})"
    return "intermediate confinement (no closed-form law is established here)"


def _scalar(name: str, x):
    """``x`` itself if it is a single number (or None); the estimate is computed for one case."""
    if x is not None and not isinstance(x, str) and np.ndim(x) != 0:
        raise InvalidParameterError(name, x, f"a single number (got an array of shape "
                                             f"{np.shape(x)})", "the estimate is for one case")
    return x


def _hematocrits(tube_hematocrit, discharge_hematocrit) -> dict:
    """Checked hematocrit inputs (at most one of the two kinds)."""
    if tube_hematocrit is not None and discharge_hematocrit is not None:
        raise InvalidParameterError("discharge_hematocrit", discharge_hematocrit,
                                    "unset when tube_hematocrit is given",
                                    "give one hematocrit; the other follows from V/U or Fahraeus")
    out = {}
    if tube_hematocrit is not None:
        out["tube_hematocrit"] = float(check_fraction("tube_hematocrit", tube_hematocrit))
    if discharge_hematocrit is not None:
        out["discharge_hematocrit"] = float(check_fraction("discharge_hematocrit", discharge_hematocrit))
    return out


def _core(nu: float, lam: float, ca_b, hematocrits: dict, diameter_um, extrapolate: bool,
          solvers: tuple, log: dict, solution_map=None, cell: dict | None = None):
    """Geometry state, then every quantity of the table; returns (state, quantities).

    ``log`` collects which disabled solvers would apply and which enabled ones failed, and
    where the map had no value. The map rows take part unless ``solution_map`` is False.
    ``cell``: the red cell's entries of the state (:func:`_red_cell`), None for a vesicle.
    """
    lam_c = check_passes(nu, lam)
    state = {"nu": nu, "lam": lam, "lam_c": lam_c, "delta": 1.0 - lam / lam_c,
             "ell_c": critical_length(nu), **hematocrits, **(cell or {})}
    if ca_b is not None:
        state["ca_b"] = ca_b
    if solution_map is not False:
        state["solution_map"] = solution_map
        solvers = (*solvers, MAP)
    if diameter_um is not None:
        state["diameter_um"] = diameter_um
    known, extrapolated, quantities = dict(state), {}, {}
    for name in QUANTITIES:
        if name in hematocrits:
            quantities[name] = Quantity(hematocrits[name], UNITS[name], "input", True)
            continue
        if name in _HEMATOCRIT_KEYS and not hematocrits:
            quantities[name] = Quantity(None, UNITS[name], None, False, "", NO_HEMATOCRIT)
            continue
        q = quantities[name] = _select(name, known, extrapolated, extrapolate, solvers, log)
        if q.value is not None:
            (known if q.valid else extrapolated)[name] = q.value
    geometric = {k: Quantity(state[k], UNITS[k], "geometry (Chen 2020 §IV.A)", True)
                 for k in ("lam_c", "ell_c", "delta")}
    dp = quantities["dp_plus_R0"]
    # dp+ R/(eta U) = (dp+ R0/(eta U)) / lam: a division, since 1/lam overflows for tiny lam.
    dp_R = (Quantity(dp.value / lam, UNITS["dp_plus_R"], dp.method, dp.valid, dp.source, dp.note,
                     None if dp.error is None else dp.error / lam)
            if dp.value is not None else Quantity(None, UNITS["dp_plus_R"], None, False, "",
                                                  dp.note))
    # gamma/(eta U) = (gamma/(eta V)) (V/U)
    derived = {"dp_plus_R": dp_R,
               **{f"{t}_etaU": _scaled(quantities[t], 1.0, UNITS[f"{t}_etaU"],
                                       quantities["V_over_U"])
                  for t in ("tension_front", "tension_max")}}
    return state, {"nu": Quantity(nu, "-", "input", True), "lam": Quantity(lam, "-", "input", True),
                   "passes": Quantity(True, "", "lam < lam_c", True),
                   **geometric, **quantities, **derived}


def estimate_dimensionless(nu: float, lam: float, ca_b: float | None = None, *,
                           ca_s: float | None = None, tube_hematocrit: float | None = None,
                           discharge_hematocrit: float | None = None,
                           extrapolate: bool = False, solvers: tuple = (),
                           solution_map=None) -> Estimate:
    r"""Dimensionless estimate for reduced volume ``nu`` and confinement ``lam = R0/R``.

    Parameters
    ----------
    nu : float
        Reduced volume, 0 < nu <= 1 [-].
    lam : float
        Confinement R0/R, 0 < lam < lam_c(nu) [-].
    ca_b : float, optional
        Bending capillary number eta U R0^2/kappa [-]; when omitted the correlations of Chen et
        al. 2020 are assumed to apply (they hold for Ca_B >= ~10), and the solution map and the
        solvers use Ca_B = 50 (Chen et al. 2020's value), as the output states.
    ca_s : float, optional
        Shear capillary number eta U/G_s of a red-cell membrane [-] (needs ``ca_b``): the case
        is then a red cell with beta = Ca_B/Ca_S, estimated as in :func:`estimate` (the
        red-cell map where its beta matches, an enabled solver, no closed-form vesicle law).
        Default None: a vesicle.
    tube_hematocrit, discharge_hematocrit : float, optional
        At most one, a fraction in [0, 1); enables the single-file apparent viscosity.
    extrapolate : bool
        Fill quantities that no method covers with the least-extrapolated method, flagged.
    solvers : tuple of str
        Numerical solvers the method table may use, ``"lubrication"`` (seconds) and/or
        ``"bem"`` (the BEM vesicle: most accurate, minutes); they take precedence over the
        closed forms where valid, the BEM ahead of the lubrication solver. A solver that fails
        to converge is reported in ``notes`` and makes ``converged`` False. A solver that is not
        enabled is never run, not even where no other method is valid: ``notes`` then says
        which solver covers the case and how to enable it.
    solution_map : None, False, str, Path or SolutionMap
        The solution map whose rows answer inside its range, after enabled solvers and ahead of
        the closed forms (:mod:`correlations.registry`): None for the shipped map
        (:data:`correlations.solution_map.DEFAULT_MAP`; where none is shipped the map rows have
        no value and say so), a packed map file or a loaded map (a bad file raises
        InvalidParameterError naming ``map`` before any work), or False for none (closed forms
        and solvers only).

    Raises
    ------
    CannotPassError
        If lam >= lam_c(nu).

    Examples
    --------
    >>> e = estimate_dimensionless(0.9, 1.25, solution_map=False)     # closed forms only
    >>> e.regime.split(" (")[0], round(e["V_over_U"], 3), e.quantities["V_over_U"].method
    ('near-critical', 1.06, 'near_critical_barakat2018a')
    """
    for name, x in (("nu", nu), ("lam", lam), ("ca_b", ca_b), ("ca_s", ca_s),
                    ("tube_hematocrit", tube_hematocrit),
                    ("discharge_hematocrit", discharge_hematocrit)):
        _scalar(name, x)
    hematocrits = _hematocrits(tube_hematocrit, discharge_hematocrit)
    nu, lam = float(check_reduced_volume(nu)), float(check_positive("lam", lam))
    if ca_b is not None:
        ca_b = float(check_positive("ca_b", ca_b))
    solvers, log = _check_solvers(solvers), {}
    cell = None
    if ca_s is not None:
        ca_s = float(check_positive("ca_s", ca_s))
        if ca_b is None:
            raise InvalidParameterError("ca_s", ca_s, "given with ca_b",
                                        "a red cell's beta = Ca_B/Ca_S needs both: give --ca-b")
        _check_red_cell_solve(nu, ca_s, solvers, "ca_s", "nu")
        cell = {"membrane": "red-cell", "ca_s": ca_s, "shear_ratio": ca_b / ca_s,
                "default_cell": _default_cell()}
    solution_map = _check_solution_map(solution_map)
    _check_map_membrane(solution_map, cell)
    state, quantities = _core(nu, lam, ca_b, hematocrits, None, extrapolate, solvers, log,
                              solution_map, cell)
    quantities["ca_b"] = _ca_b_quantity(ca_b, solvers, log)
    inputs = {"nu": nu, "lam": lam, "ca_b": ca_b, **hematocrits}
    if cell is not None:    # a vesicle's inputs stay those of the estimate without red cells
        quantities.update(_red_cell_quantities(ca_s, cell["shear_ratio"], given_ca_s=True))
        inputs.update(ca_s=ca_s, membrane="red-cell")
    return Estimate(inputs=inputs, quantities=quantities, regime=_regime(lam, state["delta"]),
                    notes=_notes(quantities, ca_b, log, state), provenance=provenance(),
                    converged=not log.get("failures"))


def _ca_b_quantity(ca_b, solvers: tuple, log: dict) -> Quantity:
    """The Ca_B the estimate used, stated: the input, or what stands in when none is given.

    The closed forms of the table do not take Ca_B: they are correlations at Chen et al.'s
    Ca_B = 50 and assume 10 <= Ca_B <= 1e4. The solver and map rows take the case's Ca_B, and
    50 (Chen et al. 2020) when none is given.
    """
    if ca_b is not None:
        return Quantity(ca_b, UNITS["ca_b"], "input", True)
    ran = sorted(s for s in (*solvers, MAP) if s in log.get("ran", ()))
    if ran:
        default = {"lubrication": LUBRICATION_DEFAULT_CA_B, "bem": BEM_DEFAULT_CA_B,
                   MAP: MAP_DEFAULT_CA_B}
        values = {default[s] for s in ran}
        if len(values) == 1:
            who = " and ".join("the solution map" if s == MAP else f"the {s} solver" for s in ran)
            return Quantity(values.pop(), UNITS["ca_b"],
                            f"assumed by {who} (not given; Chen et al. 2020 value)", True)
    return Quantity(None, UNITS["ca_b"], None, False, "",
                    "not given: the closed forms assume Chen et al. 2020's regime 10 <= Ca_B <= "
                    "1e4 (their results are at Ca_B = 50); give --ca-b to state it")


def _check_solvers(solvers) -> tuple:
    for name in solvers:
        check_choice("solvers", name, SOLVERS)
    return tuple(solvers)


def _check_solution_map(choice):
    """``choice`` checked before any work: None or False as they are, a path loaded (raises
    InvalidParameterError naming ``map`` for a missing or foreign file), a map as it is."""
    if choice is None or choice is False or isinstance(choice, SolutionMap):
        return choice
    if isinstance(choice, (str, os.PathLike)):
        return load_map(choice)
    raise InvalidParameterError("solution_map", choice, "None (the shipped map), False (no map), "
                                "a packed map file or a SolutionMap")


def _check_map_membrane(solution_map, cell: dict | None) -> None:
    """A map given by the caller (a path or a map, loaded by :func:`_check_solution_map`) is
    of the case's membrane, checked before any work: a vesicle map never answers for a red
    cell, nor a red-cell map for a vesicle (InvalidParameterError naming ``solution_map``). A
    red-cell map of another shear ratio is no error: its rows have no value and say why."""
    if not isinstance(solution_map, SolutionMap):
        return
    red_cell = cell is not None
    if (solution_map.membrane is not None) != red_cell:
        kind = "a red-cell map" if solution_map.membrane is not None else "a vesicle map"
        raise InvalidParameterError(
            "solution_map", solution_map.source,
            f"a {'red-cell' if red_cell else 'vesicle'} map for a "
            f"{'red cell' if red_cell else 'vesicle'}",
            f"it is {kind}; give the map of the cell's membrane, or change the membrane")


def _default_cell() -> tuple:
    """``(beta, description)`` of the default red cell (:data:`RBC_DEFAULTS`), the cell the
    shipped red-cell slice was built for: named in the reason when a cell's beta differs."""
    d = RBC_DEFAULTS
    R0 = volume_radius(d["volume_fl"])                                   # [µm]
    beta = physical_scales(R0, 1.0, 1.0, 1.0, d["bending_modulus_j"],
                           d["shear_modulus_un_m"])["shear_ratio"]
    return beta, (f"G_s {d['shear_modulus_un_m']:g} uN/m, kappa {d['bending_modulus_j']:g} J, "
                  f"{d['volume_fl']:g} fL, the default red cell")


def _solvers_ca_s_range(solvers: tuple) -> tuple[float, float]:
    """The Ca_S every enabled solver takes: :data:`lubrication.solve.CA_S_RANGE`,
    :data:`bem.vesicle.CA_S_RANGE` (the BEM reaches lower Ca_S by continuation along the
    velocity), intersected."""
    from bem.vesicle.inputs import CA_S_RANGE as BEM   # lazy: scipy
    from lubrication.solve import CA_S_RANGE as LUBRICATION  # lazy: scipy
    ranges = [{"lubrication": LUBRICATION, "bem": BEM}[s] for s in solvers if s != MAP]
    return (max((r[0] for r in ranges), default=0.0),
            min((r[1] for r in ranges), default=math.inf))


def _check_red_cell_solve(nu: float, ca_s: float, solvers: tuple, ca_s_name: str, nu_name: str,
                          ca_s_range=None) -> None:
    """With a solver enabled, a red cell the solvers can take, checked before any work: Ca_S
    within :func:`_solvers_ca_s_range` (``ca_s_range(lo, hi)`` -> ``(value, lo, hi, reason)``:
    the same range expressed in the caller's input) and nu where the stress-free Evans–Fung
    disc exists (:func:`lubrication.membrane.reference_nu_range`)."""
    if not solvers:
        return
    from lubrication.membrane import reference_nu_range   # lazy: scipy, numba
    lo, hi = _solvers_ca_s_range(solvers)
    if not lo <= ca_s <= hi:
        value, vlo, vhi, reason = ca_s_range(lo, hi) if ca_s_range else (ca_s, lo, hi, "")
        raise InvalidParameterError(
            ca_s_name, value, f"{vlo:.4g} to {vhi:.4g}",
            f"the shear capillary number Ca_S = {ca_s:.4g} is outside the solvers' range "
            f"{lo:g} <= Ca_S <= {hi:g} (--solver {'/'.join(solvers)})" + reason)
    nu_lo, nu_hi = reference_nu_range("biconcave")
    if not nu_lo <= nu <= nu_hi:
        raise InvalidParameterError(
            nu_name, nu, f"a reduced volume {nu_lo:g} <= nu <= {nu_hi:g} for a red-cell solve",
            f"nu = {nu:.4g}: the red cell's stress-free Evans-Fung disc exists for "
            f"{nu_lo:g} <= nu <= {nu_hi:g}; give --membrane vesicle")


def _check_red_cell_velocity(solution_map, cell: dict, ca_b: float, u_per_ca_b: float) -> None:
    """Without a solver, a red cell's velocity must lie in the red-cell map's Ca_B range, checked
    before any work (InvalidParameterError naming ``velocity_mm_s``, the range in mm/s for this
    cell: U = Ca_B κ/(η R0²), ``u_per_ca_b`` in mm/s). A cell the map is not made for (another
    β), or no map, is no error: its rows say why they have no value."""
    if solution_map is False:
        return
    try:
        m = resolve_solution_map(solution_map, "red-cell")
    except MethodNotApplicable:
        return
    if membrane_mismatch(m, cell):
        return
    lo, hi = m.cas[0], m.cas[-1]
    if not lo <= m.node_ca_b(ca_b) <= hi:
        raise InvalidParameterError(
            "velocity_mm_s", ca_b * u_per_ca_b,
            f"{lo * u_per_ca_b:.3g} to {hi * u_per_ca_b:.3g} mm/s for this cell and plasma",
            f"outside the red-cell map ({lo:.4g} <= Ca_B <= {hi:.4g}, Ca_B = {ca_b:.4g}); "
            "--solver bem solves this red cell, --membrane vesicle gives the vesicle")


def _red_cell_quantities(ca_s: float, beta: float, given_ca_s: bool = False) -> dict:
    """The rows Ca_S and beta of a red cell (units and sources, like Ca_B's)."""
    if given_ca_s:
        return {"ca_s": Quantity(ca_s, UNITS["ca_s"], "input", True),
                "shear_ratio": Quantity(beta, UNITS["shear_ratio"], "Ca_B/Ca_S (from the inputs)",
                                        True, "Evans 1973 (area-incompressible shear law)")}
    return {"ca_s": Quantity(ca_s, UNITS["ca_s"], "eta U/G_s (from the inputs)", True,
                             "Evans 1973; G_s default 6 uN/m, Hochmuth & Waugh 1987"),
            "shear_ratio": Quantity(beta, UNITS["shear_ratio"],
                                    "G_s R0^2/kappa (from the inputs)", True,
                                    "Evans 1973; = Ca_B/Ca_S")}


def _red_cell_notes(quantities: dict, state: dict, log: dict) -> list:
    """The notes of a red cell: what answered, and where nothing did, why and what would."""
    notes = []
    beta, ca_s = state["shear_ratio"], state["ca_s"]
    mapped = [k for k in QUANTITIES if (quantities[k].method or "").startswith("map (")]
    if mapped:
        notes.append(f"{', '.join(mapped)} from the red-cell map (shear ratio beta = "
                     f"{beta:.4g}) at Ca_B = {state['ca_b']:.4g}, Ca_S = {ca_s:.4g}, "
                     "interpolated between stored steady solutions; ± is its error bar "
                     "(interpolation + solver + model error, the parts it knows).")
    missing = [k for k in QUANTITIES if quantities[k].value is None
               and quantities[k].note.startswith("no valid")]
    reasons = sorted(set(log.get("map_refused", {}).values()))
    if missing:
        why = f" ({'; '.join(reasons)})" if reasons else ""
        notes.append(f"No red-cell value for {', '.join(missing)} here{why}. The closed-form "
                     "laws are vesicle results and are not used for a red cell; --solver bem "
                     "solves this red cell (Ca_S = eta U/G_s), --membrane vesicle gives the "
                     "vesicle, the red cell's high-velocity limit.")
    return notes


def _notes(quantities: dict, ca_b, log: dict, state: dict | None = None) -> tuple:
    notes = []
    red_cell = state is not None and state.get("membrane") == "red-cell"
    if red_cell:
        notes += _red_cell_notes(quantities, state, log)
    mapped = [k for k in QUANTITIES if (quantities[k].method or "").startswith("map (")]
    if mapped and not red_cell:
        used = f"{ca_b:.4g}" if ca_b is not None else f"{MAP_DEFAULT_CA_B:g} (assumed: not given)"
        notes.append(f"{', '.join(mapped)} from the solution map at Ca_B = {used}, "
                     "interpolated between stored steady solutions; ± is its error bar "
                     "(interpolation + solver + model error, the parts it knows).")
    refused = {}        # where the map had no value and a later row answered (else: "why")
    for k, reason in log.get("map_refused", {}).items():
        if quantities[k].value is not None:
            refused.setdefault(reason, []).append(k)
    for reason, keys in refused.items():
        notes.append(f"The solution map gives no {', '.join(keys)} here ({reason}): "
                     "the next method of the table answers.")
    for solver, message in sorted(log.get("failures", {}).items()):
        notes.append(f"The {solver} solver was enabled but did not converge: {message}")
    covers = log.get("covers", {})
    available = sorted(set().union(*covers.values()))
    if available:
        plural = len(available) > 1
        notes.append("The " + " and ".join(available) + (" solvers cover" if plural else
                     " solver covers") + " this case: enable " + ("them" if plural else "it")
                     + " with " + " and/or ".join(f"--solver {a}" for a in available) + " ("
                     + ", ".join(f"{a}: {SOLVER_COST[a]}" for a in available) + ").")
    missing = [k for k in QUANTITIES if quantities[k].value is None
               and quantities[k].note.startswith("no valid")]
    if missing and not red_cell:
        covering = sorted(set().union(*(covers.get(k, ()) for k in missing)))
        hint = ("; " + " or ".join(f"--solver {a}" for a in covering) + " would compute "
                "them (not run unless enabled)" if covering else "")
        notes.append(f"No closed-form method is valid for {', '.join(missing)} here{hint}; use "
                     "extrapolate=True (--extrapolate) for flagged extrapolations.")
    if ca_b is not None and ca_b < 10 and not red_cell:
        notes.append(f"Ca_B = {ca_b:.3g} < 10: bending matters; Chen et al. 2020 correlations were "
                     "established for 10 <= Ca_B <= 1e4 (Ca_B = 50 for most).")
    return tuple(notes)


def physical_scales(R0_um: float, diameter_um: float, velocity_mm_s: float | None = None,
                    plasma_viscosity_mpas: float | None = None,
                    bending_modulus_j: float | None = None,
                    shear_modulus_un_m: float | None = None) -> dict:
    r"""The physical value of one unit of each dimensionless quantity, and Ca_B, Ca_S and β.

    With R0 the volume radius, R = d/2 the tube radius, U the mean velocity, η the viscosity,
    κ the bending modulus and G_s the membrane shear modulus (the scalings of the module
    docstring): ``V_mm_s`` = U [mm/s] (V/U → V), ``dp_plus_Pa`` = ηU/R0 [Pa] (Δp⁺R0/(ηU) →
    Δp⁺), ``film_nm`` = R [nm] (h/R → h), ``length_um`` = R [µm] (L/R → L), ``tension_mN_m`` =
    ηU [mN/m] (γ/(ηU) → γ), ``ca_b`` = ηUR0²/κ (Chen et al. 2020 §II), ``ca_s`` = ηU/G_s (the
    shear capillary number of a red-cell membrane, Evans 1973's area-incompressible law; user
    guide §8) and ``shear_ratio`` β = G_s R0²/κ = Ca_B/Ca_S (the cell's ratio of shear to
    bending stiffness, independent of the flow). A key whose inputs are not given is left out.
    Inputs are taken as checked (positive and finite).

    Parameters
    ----------
    R0_um, diameter_um : float
        Volume radius and tube diameter [µm].
    velocity_mm_s, plasma_viscosity_mpas, bending_modulus_j : float, optional
        U [mm/s], η [mPa·s], κ [J].
    shear_modulus_un_m : float, optional
        G_s [µN/m] (6 for a human red cell, Hochmuth & Waugh 1987).

    Examples
    --------
    >>> s = physical_scales(2.78, 4.0, 1.0, 1.2, 2e-19)
    >>> s["film_nm"], round(s["dp_plus_Pa"], 4), round(s["ca_b"], 2)
    (2000.0, 0.4317, 46.37)
    >>> s = physical_scales(2.78, 4.0, 1.0, 1.2, 2e-19, 6.0)
    >>> round(s["ca_s"], 4), round(s["shear_ratio"], 1), round(s["ca_b"] / s["ca_s"], 1)
    (0.2, 231.9, 231.9)
    """
    R0_m, R_m = R0_um * 1e-6, diameter_um / 2 * 1e-6
    out = {"film_nm": R_m * 1e9, "length_um": R_m * 1e6}
    if velocity_mm_s is not None:
        out["V_mm_s"] = float(velocity_mm_s)
        if plasma_viscosity_mpas is not None:
            eta_U = plasma_viscosity_mpas * 1e-3 * velocity_mm_s * 1e-3     # [Pa m]
            out.update(dp_plus_Pa=eta_U / R0_m, tension_mN_m=eta_U * 1e3)
            if bending_modulus_j is not None:
                out["ca_b"] = eta_U * R0_m**2 / bending_modulus_j
            if shear_modulus_un_m is not None:
                out["ca_s"] = eta_U / (shear_modulus_un_m * 1e-6)
    if bending_modulus_j is not None and shear_modulus_un_m is not None:
        out["shear_ratio"] = shear_modulus_un_m * 1e-6 * R0_m**2 / bending_modulus_j
    return out


def estimate(volume_fl: float = RBC_DEFAULTS["volume_fl"],
             area_um2: float = RBC_DEFAULTS["area_um2"],
             diameter_um: float = RBC_DEFAULTS["diameter_um"],
             velocity_mm_s: float = RBC_DEFAULTS["velocity_mm_s"],
             plasma_viscosity_mpas: float = RBC_DEFAULTS["plasma_viscosity_mpas"],
             bending_modulus_j: float = RBC_DEFAULTS["bending_modulus_j"],
             shear_modulus_un_m: float = RBC_DEFAULTS["shear_modulus_un_m"], *,
             membrane: str = DEFAULT_MEMBRANE,
             hematocrit: float | None = None, hematocrit_kind: str = "tube",
             extrapolate: bool = False, solvers: tuple = (), solution_map=None) -> Estimate:
    r"""Engineering estimate from physical inputs (defaults: human RBC in a 4 µm capillary).

    **A red cell** (``membrane="red-cell"``, the default): a membrane with bending, local
    inextensibility and in-plane shear elasticity (Evans 1973's area-incompressible law, modulus
    G_s; user guide §8). The estimate reports Ca_S = ηU/G_s and β = G_s R0²/κ = Ca_B/Ca_S
    (:func:`physical_scales`). V/U, Δp⁺, film, length, tensions and shape class come from an
    enabled solver (``solvers=("bem",)`` solves this red cell, Ca_S from the inputs), else from
    the red-cell map (:data:`correlations.solution_map.RED_CELL_MAP` for ``solution_map=None``)
    when the cell's β equals the map's within
    :data:`~correlations.registry.SHEAR_RATIO_RTOL` = 1e-3 and the case lies in the map's box:
    a line of that map is one cell (one β) at different velocities, and 1e-3 in β moves Δp⁺ by
    at most 5e-4 relative, well inside the map's error bars (derivation in
    :mod:`correlations.registry`, "A red cell"). Otherwise they are unavailable, with the
    reason (another modulus, bending modulus or volume: ``--solver bem``). The closed-form
    vesicle laws (near-critical asymptotes, small sphere, Chen et al.'s film, length, tension
    and transition laws) are *not* used for a red cell: they are derived or fitted for a
    membrane without shear elasticity, whose effect on Δp⁺ our BEM measures at a factor 1.3-2.9
    for the default cell at 0.1-1 mm/s in a 4 µm tube (docs/red-cell.md); they are the red
    cell's high-velocity limit, which ``membrane="vesicle"`` gives, labelled as such. The
    geometry, hematocrit conversions and apparent viscosity hold for both (the single-file
    viscosity with the red cell's Δp⁺).

    **A vesicle** (``membrane="vesicle"``): bending and local inextensibility only (lipid
    vesicles; for a red cell the high-velocity limit Ca_S → ∞). ``shear_modulus_un_m`` is
    checked but unused.

    Parameters
    ----------
    volume_fl : float
        Cell volume [fL = µm³].
    area_um2 : float
        Membrane area [µm²].
    diameter_um : float
        Tube diameter [µm].
    velocity_mm_s : float
        Mean velocity U of the undisturbed flow [mm/s] (centreline 2U).
    plasma_viscosity_mpas : float
        Suspending-fluid viscosity eta [mPa·s].
    bending_modulus_j : float
        Membrane bending modulus kappa [J].
    shear_modulus_un_m : float
        Membrane shear modulus G_s of a red cell [µN/m] (default 6, Hochmuth & Waugh 1987;
        measured values 4-10).
    membrane : {"red-cell", "vesicle"}
        The cell's membrane (above).
    hematocrit : float, optional
        Volume fraction in [0, 1) (not %); enables the apparent viscosity eta_rel.
    hematocrit_kind : {"tube", "discharge"}
        Whether ``hematocrit`` is the tube (H_T) or discharge (H_D) hematocrit.
    extrapolate, solvers, solution_map :
        See :func:`estimate_dimensionless`; the map and the solvers take Ca_B = eta U R0^2/kappa
        (and for a red cell Ca_S = eta U/G_s) from the inputs. ``solution_map=None`` is the
        shipped map of the membrane; a given map must be of the cell's membrane.

    Returns
    -------
    Estimate
        Dimensionless quantities as in :func:`estimate_dimensionless` plus ``R0_um``, ``d_c_um``,
        ``L_c_um``, ``ca_b``, ``V_mm_s``, ``dp_plus_Pa``, ``film_nm``, ``length_um``,
        ``tension_front_mN_m`` and ``tension_max_mN_m`` (a red cell also ``ca_s`` and
        ``shear_ratio``), each with its method, validity and error bar.

    Raises
    ------
    CannotPassError
        If the tube is narrower than the critical diameter d_c.
    InvalidParameterError
        For a bad input, before any work; for a red cell, a velocity (named
        ``velocity_mm_s``) whose Ca_S is outside the enabled solvers' range (from 1e-3 for the
        BEM, 1e-2 for lubrication, to 1e4), or without one, outside the Ca_B range of the
        red-cell map that answers for this cell (0.01-10 mm/s for the default cell and
        plasma).

    Examples
    --------
    >>> e = estimate()             # a red cell in a 4 µm capillary at 1 mm/s: the red-cell map
    >>> round(e["nu"], 3), round(e["lam"], 3), round(e["d_c_um"], 2), e["passes"]
    (0.61, 1.39, 2.85, True)
    >>> round(e["ca_s"], 3), round(e["shear_ratio"], 1)
    (0.2, 231.9)
    >>> e.regime.split(" (")[0]
    'intermediate confinement'
    >>> v = estimate(membrane="vesicle", solution_map=False)  # the vesicle, closed forms only
    >>> v["V_over_U"] is None
    True
    """
    kind = check_choice("hematocrit_kind", hematocrit_kind, ("tube", "discharge"))
    membrane = check_choice("membrane", membrane, MEMBRANES)
    given = {"volume_fl": volume_fl, "diameter_um": diameter_um, "velocity_mm_s": velocity_mm_s,
             "plasma_viscosity_mpas": plasma_viscosity_mpas, "bending_modulus_j": bending_modulus_j,
             "shear_modulus_un_m": shear_modulus_un_m}
    for name, x in (*given.items(), ("area_um2", area_um2), ("hematocrit", hematocrit)):
        _scalar(name, x)
    for name, value in given.items():      # absurd values are refused before any work
        lo, hi, reason = PHYSICAL_BOUNDS[name]
        check_range(name, check_positive(name, value), lo, hi, reason=reason)
    nu, R0 = cell_from_volume_area(volume_fl, area_um2)
    diameter_um = float(diameter_um)
    U = float(velocity_mm_s) * 1e-3                       # [m/s]
    eta = float(plasma_viscosity_mpas) * 1e-3             # [Pa s]
    kappa = float(bending_modulus_j)                      # [J]
    d_c = critical_diameter_um(nu, R0)
    if diameter_um <= d_c:
        raise CannotPassError("diameter_um", diameter_um, f"diameter_um > d_c = {d_c:.4g} um",
                              f"the cell (nu={nu:.3g}, R0={R0:.3g} um) cannot pass this tube intact")
    lam = 2.0 * R0 / diameter_um
    G_s = float(shear_modulus_un_m)                       # [µN/m]
    red_cell = membrane == "red-cell"
    scale = physical_scales(R0, diameter_um, velocity_mm_s, plasma_viscosity_mpas, kappa,
                            G_s if red_cell else None)
    ca_b = scale["ca_b"]
    hematocrits = {}
    if hematocrit is not None:
        hematocrits[f"{kind}_hematocrit"] = float(check_fraction("hematocrit", hematocrit))
    solvers, log = _check_solvers(solvers), {}
    cell = None
    if red_cell:
        ca_s, beta = scale["ca_s"], scale["shear_ratio"]
        # the velocities of the solvers' Ca_S range for this cell: U = Ca_S G_s/eta [mm/s]
        u_of = G_s * 1e-6 / eta * 1e3
        _check_red_cell_solve(nu, ca_s, solvers, "velocity_mm_s", "area_um2", lambda lo, hi: (
            U * 1e3, lo * u_of, hi * u_of,
            f" for G_s = {G_s:g} uN/m and eta = {eta * 1e3:g} mPa s"))
        cell = {"membrane": "red-cell", "ca_s": ca_s, "shear_ratio": beta,
                "default_cell": _default_cell()}
    solution_map = _check_solution_map(solution_map)
    _check_map_membrane(solution_map, cell)
    if cell is not None and not solvers:
        _check_red_cell_velocity(solution_map, cell, ca_b, U * 1e3 / ca_b)
    state, q = _core(nu, lam, ca_b, hematocrits, diameter_um, extrapolate, solvers, log,
                     solution_map, cell)
    inputs = {"volume_fl": float(volume_fl), "area_um2": float(area_um2), "diameter_um": diameter_um,
              "velocity_mm_s": U * 1e3, "plasma_viscosity_mpas": eta * 1e3, "bending_modulus_j": kappa,
              "hematocrit": hematocrit, "hematocrit_kind": kind}
    if red_cell:        # a vesicle's inputs stay those of the estimate without red cells
        inputs.update(shear_modulus_un_m=G_s, membrane=membrane)
    geo = "geometry (Chen 2020 §IV.A)"
    physical = {"R0_um": Quantity(R0, "um", geo, True), "d_c_um": Quantity(d_c, "um", geo, True),
                "L_c_um": Quantity(critical_length_um(nu, R0), "um", geo, True),
                "ca_b": Quantity(ca_b, "-", "eta U R0^2/kappa (from the inputs)", True)}
    if red_cell:
        physical.update(_red_cell_quantities(ca_s, beta))
    physical.update(V_mm_s=_scaled(q["V_over_U"], scale["V_mm_s"], "mm/s"),
                    dp_plus_Pa=_scaled(q["dp_plus_R0"], scale["dp_plus_Pa"], "Pa"),
                    film_nm=_scaled(q["film"], scale["film_nm"], "nm"),
                    length_um=_scaled(q["ell"], scale["length_um"], "um"),
                    # gamma = (gamma/(eta V)) eta (V/U) U, in mN/m
                    **{f"{t}_mN_m": _scaled(q[t], scale["tension_mN_m"], "mN/m", q["V_over_U"])
                       for t in ("tension_front", "tension_max")})
    notes = list(_notes(q, ca_b, log, state))
    for name, key in (("Front", "tension_front_mN_m"), ("Maximum", "tension_max_mN_m")):
        tension = physical[key]
        if tension.value is not None:
            lo, hi = RUPTURE_TENSION_MN_M
            verdict = ("below" if tension.value < lo else "within" if tension.value <= hi
                       else "ABOVE")
            flag = "" if tension.valid else " (EXTRAPOLATED value)"
            value = (format_value_error(tension.value, tension.error) if tension.error is not None
                     else f"{tension.value:.3g}")
            notes.append(f"{name} tension {value} mN/m{flag} is {verdict} the bilayer rupture "
                         f"(lysis) range {lo:g}-{hi:g} mN/m.")
    return Estimate(inputs=inputs, quantities={**q, **physical}, regime=_regime(lam, state["delta"]),
                    notes=tuple(notes), provenance=provenance(), converged=not log.get("failures"))


# --------------------------------------------------------------------------- single-file viscosity

@dataclass(frozen=True)
class SingleFileViscosity:
    """Result of :func:`single_file_viscosity`.

    ``eta_rel`` [-] with its absolute error bar ``error`` [-] (None where Δp⁺ has none), or
    None with the reason in ``note``; ``valid`` is False for a flagged extrapolation (Δp⁺ or
    H_T outside its method's range, or d outside the law's range
    :data:`correlations.viscosity.CHEN2020_RANGE`); ``membrane`` the membrane used;
    ``estimate`` the estimate whose Δp⁺ and H_T were used (inputs, Ca_B, Ca_S, methods, error
    bars).
    """

    eta_rel: float | None
    error: float | None
    valid: bool
    note: str
    membrane: str
    estimate: Estimate


def single_file_viscosity(diameter_um: float, hematocrit: float, *,
                          hematocrit_kind: str = "tube",
                          velocity_mm_s: float = RBC_DEFAULTS["velocity_mm_s"],
                          membrane: str = DEFAULT_MEMBRANE,
                          shear_modulus_un_m: float = RBC_DEFAULTS["shear_modulus_un_m"],
                          extrapolate: bool = False, **cell) -> SingleFileViscosity:
    r"""Relative apparent viscosity of single-file flow of a cell at mean velocity U.

    Chen et al. 2020, §IV.D (their equation for the relative viscosity of a dilute train of
    cells):

    .. math::
        \eta_{rel} = 1 + \frac{3}{32}\left(\frac{R}{R_0}\right)^4
                     \frac{\Delta p^+ R_0}{\eta U}\,H_T,

    (:func:`correlations.viscosity.viscosity_single_file_chen2020`) with Δp⁺ and H_T from
    :func:`estimate` of this cell at this velocity: the map, with its error bar, for the
    vesicle or the red cell (shear elasticity: Δp⁺ and so η_rel depend on U, Secomb et al.
    1986). As η_rel − 1 is linear in Δp⁺, the error bar is
    (η_rel − 1)·err(Δp⁺)/Δp⁺ (the error of H_T, which is given or from the map's V/U, is not
    added). Without a Δp⁺ or H_T the value is None with the reason, never another law's
    number.

    Parameters
    ----------
    diameter_um : float
        Tube diameter d = 2R [µm], above the cell's critical diameter.
    hematocrit : float
        Hematocrit, a fraction in [0, 1) [-].
    hematocrit_kind : {"tube", "discharge"}
        Whether ``hematocrit`` is H_T or H_D (converted as in :func:`estimate`).
    velocity_mm_s : float
        Mean velocity U [mm/s] (default 1).
    membrane : {"red-cell", "vesicle"}, optional
        The cell's membrane, as in :func:`estimate` (default: a red cell).
    shear_modulus_un_m : float
        Red-cell membrane shear modulus G_s [µN/m] (default 6, Hochmuth & Waugh 1987).
    extrapolate : bool
        Let the estimate fill Δp⁺ or H_T with flagged extrapolations.
    **cell
        ``volume_fl`` [fL], ``area_um2`` [µm²], ``plasma_viscosity_mpas`` [mPa·s],
        ``bending_modulus_j`` [J], ``solution_map``: as in :func:`estimate` (default: the
        human red cell of :data:`RBC_DEFAULTS`).

    Returns
    -------
    SingleFileViscosity

    Raises
    ------
    InvalidParameterError, CannotPassError
        As :func:`estimate`, before any work (for a red cell without a solver, a velocity
        outside the red-cell map's range).

    Examples
    --------
    >>> r = single_file_viscosity(5.0, 0.3, membrane="vesicle")
    >>> r.membrane, round(r.eta_rel, 2), r.valid
    ('vesicle', 1.33, True)
    """
    est = estimate(diameter_um=diameter_um, velocity_mm_s=velocity_mm_s,
                   shear_modulus_un_m=shear_modulus_un_m, membrane=membrane,
                   hematocrit=hematocrit, hematocrit_kind=hematocrit_kind,
                   extrapolate=extrapolate, **cell)
    dp, h_t = est.quantities["dp_plus_R0"], est.quantities["tube_hematocrit"]
    d = est.inputs["diameter_um"]

    def missing(note: str) -> SingleFileViscosity:
        return SingleFileViscosity(None, None, False, note, membrane, est)
    if dp.value is None:
        return missing(f"no dp+ for this cell and tube: {dp.note}")
    if h_t.value is None:
        return missing(f"no tube hematocrit: {h_t.note}")
    eta = float(viscosity.viscosity_single_file_chen2020(dp.value, d, est["R0_um"], h_t.value))
    problem = check_output("eta_rel", eta, {})
    if problem:
        return missing(f"no eta_rel: {problem}")
    error = None if dp.error is None or dp.value <= 0 else (eta - 1.0) * dp.error / dp.value
    valid = dp.valid and h_t.valid and viscosity.CHEN2020_RANGE.contains(diameter_um=d)
    return SingleFileViscosity(eta, error, valid, "", membrane, est)
