r"""Consistency check of steady results for a sphere, a drop or a vesicle in tube flow.

Users with their own results (BEM, lattice Boltzmann, DPD, immersed boundary, experiments) give
one row per steady state; every row is checked against the physics and against references of
known accuracy, each check with a verdict (pass, warn, fail) and the tolerance it used.

Scalings (project conventions): R0 volume radius, R tube radius, λ = R0/R (``lam``), λc(ν)
the critical confinement (Chen et al. 2020 eq. critic), δ = 1 − λ/λc, U the **mean** velocity
of the undisturbed Poiseuille flow (centreline 2U), V/U (``V_over_U``), Δp⁺R0/(ηU)
(``dp_plus_R0``) or Δp⁺R/(ηU) (``dp_plus_R``), ℓ = L/R (``ell``), smallest gap h/R
(``film_min``), Ca_B = ηUR0²/κ (``ca_b``, vesicles), Ca = ηU/γ (``ca``, drops of viscosity
ratio 1). Columns with physical units carry the unit in their name (:data:`COLUMNS`) and are
converted with :func:`correlations.estimate.physical_scales` and
:func:`lubrication.geometry.cell_from_volume_area`.

Input
-----
:func:`read_rows` reads a CSV file (header row, comma separated), a JSON file (a list of
objects or ``{"rows": [...]}``) or a list of dicts; :func:`parse_row` turns one row into a
checked :class:`Row` of dimensionless values. An empty cell or null means "not given". Bad input
(malformed file, unknown or missing column, a number that is not one, a dimensional column
without what converts it, a column that does not apply to the row's ``kind``) raises
:class:`InputError` naming the row and the column: nothing is checked silently. Files pass the
gate of :mod:`correlations.files` (a regular file: a FIFO or a device is refused unread); a CSV
file is read as a stream, each record at most :data:`MAX_CSV_RECORD_CHARS` characters, a JSON
file whole, at most :data:`MAX_JSON_ROWS_BYTES` (a larger table goes in CSV).

Any number of rows
------------------
:func:`check_summary` checks the rows as they are read and keeps, besides the verdict counts,
the reports of at most :data:`MAX_LISTED_ROWS` rows (the worst) and about 60 bytes per row for
the series checks (step 4), which need every row of a series: a million rows take about
0.1 GB. :func:`check_results` keeps every row. The rows are read in chunks of
:data:`CHUNK_ROWS`; what their checks ask of λc, the solution map and the closed-form laws is
computed for a whole chunk at once (:class:`_Batched`: one code path with a row checked alone,
the same values), and with more than one core the chunks are checked in worker processes while
the next are read.

Checks, in the order they are made (module constants hold the measured numbers)
---------------------------------------------------------------------------------
1. **Hard bounds** (verdict fail when violated by more than the row's uncertainty, warn when
   within it): λ < λc(ν) (vesicle; λ < 1 for a rigid sphere; none for a drop, which deforms
   into a slug; λ ≥ λc as given fails and leaves only the bounds); 1 ≤ V/U < 2 (between the mean and the centreline velocity,
   :data:`lubrication.checks.OUTPUT_BOUNDS`); Δp⁺ > 0 (extra dissipation of a force-free
   object at fixed flow rate); 0 < h/R ≤ δ for a vesicle (:func:`film_upper_bound`) and
   h/R ≥ 1 − √2 λ_A (:func:`film_lower_bound`); ℓ ≥ (4/3)λ³/(1 − h/R)²
   (:func:`length_lower_bound`).
2. **References**, the most accurate one available for each quantity: for a vesicle the
   solution map (:func:`map_reference`), else the near-critical asymptotics (δ ≤ 0.1,
   :func:`near_critical_reference`), else the small rigid sphere (λ ≤ 0.5, ν ≥ 0.9,
   :func:`small_object_reference`); for a rigid sphere (and a vesicle of ν = 1, which cannot
   deform) the BEM (:func:`bem.solve.solve_sphere`), else the small-sphere law; for a drop the
   BEM (:func:`bem.drop.solve_drop`, needs ``ca``), else the small-drop law. The BEM solves
   take about a second each, are made only for rows that need them, cached per (λ, Ca) and
   skipped with ``bem=False``.
3. **Relations between columns** that hold whatever the method: Δp⁺R0 = λ Δp⁺R when both are
   given; near λc Chen et al.'s Δp⁺R0/(ηU) ≈ (3/2)λℓ/δ (:func:`chen_film_scaling_check`); the
   volume and the area of the spherocylinder of the reported ℓ and h
   (:func:`shape_volume_area_checks`), which see a volume drift of 1 % near λc.
4. **Series** (rows of one kind sharing ν and Ca_B, sorted by λ): V/U decreases, Δp⁺R0
   increases (:func:`trend_checks`); the shape class against the solution map or the
   transition line of Chen et al. (:func:`shape_class_check`).

Tolerance and verdict
---------------------
A reference check has deviation = value − reference and tolerance = reference error + the
row's uncertainty: the linear sum (both are treated as bounds, as the map adds its own error
parts), so that two results that are each within their stated error never fail. The row's
uncertainty of a value is its ``<column>_err`` cell when given (absolute, same unit), else
half a unit of the last digit written (a value written "1.4218" is known to ±5e-5). Verdict:
pass when ``|deviation|`` ≤ tolerance, warn when ≤ :data:`WARN_FACTOR` × tolerance, fail beyond.
The row's verdict is its worst check; the report's, its worst row.
"""

from __future__ import annotations

import array
import collections
import concurrent.futures
import csv
import dataclasses
import decimal
import difflib
import enum
import functools
import gc
import heapq
import itertools
import math
import multiprocessing
import numbers
import operator
import os
import signal
import warnings
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from lubrication import asymptotics
from lubrication.checks import OUTPUT_BOUNDS, InvalidParameterError, OutOfRangeWarning, check_range
from lubrication.geometry import (NU_MIN, cell_from_volume_area, check_reduced_volume,
                                  confinement_from_diameter, critical_confinement, volume_radius)
from lubrication.io import provenance
from bem.solve import check_sphere_inputs, solve_sphere

from .estimate import PHYSICAL_BOUNDS, physical_scales
from .files import UnreadableFile, check_input_file, open_text, read_json
from .pressure import dp_plus_film_chen2020
from .registry import (MAP_DEFAULT_CA_B, SMALL_VESICLE_RANGE, MethodNotApplicable, guarded,
                       map_method_name, resolve_solution_map)
from .shape import SHAPE_CLASS_RANGE_CHEN2020, shape_class_chen2020
from .solution_map import outside_reason, query_map_many, require_vesicle_map

__all__ = ["COLUMNS", "ERROR_COLUMNS", "KINDS", "WARN_FACTOR", "Verdict", "InputError", "Row",
           "Reference", "CheckResult", "RowReport", "CheckReport", "TOLERANCE_RULE", "format_cell",
           "REQUIRED", "read_rows", "parse_row",
           "parse_rows", "map_reference", "near_critical_reference", "small_object_reference",
           "sphere_reference", "drop_reference", "film_upper_bound", "film_lower_bound",
           "length_lower_bound", "chen_film_scaling_check", "shape_volume_area_checks",
           "trend_checks", "shape_class_check", "check_summary", "check_results",
           "assert_consistent", "MAX_LISTED_ROWS", "MAX_CSV_RECORD_CHARS", "MAX_JSON_ROWS_BYTES"]

KINDS = ("vesicle", "sphere", "drop")

#: Every column a row may have: name -> (role, meaning with unit). Roles: ``text``; ``input``
#: (a parameter of the case); ``output`` (a result, checked); ``physical`` (an input with a
#: unit, converted); ``physical output`` (a result with a unit, converted and checked).
COLUMNS = {
    "name": ("text", "label of the row"),
    "kind": ("text", "vesicle (default), sphere (rigid) or drop (clean, viscosity ratio 1)"),
    "nu": ("input", "reduced volume 6 sqrt(pi) Omega A^(-3/2) [-] (vesicle)"),
    "lam": ("input", "confinement R0/R [-]"),
    "ca_b": ("input", "bending capillary number eta U R0^2/kappa [-] (vesicle)"),
    "ca": ("input", "capillary number eta U/gamma [-] (drop)"),
    "V_over_U": ("output", "velocity over the mean velocity of the undisturbed flow [-]"),
    "dp_plus_R0": ("output", "extra pressure drop dp+ R0/(eta U) [-]"),
    "dp_plus_R": ("output", "extra pressure drop dp+ R/(eta U) [-]"),
    "ell": ("output", "length L/R [-]"),
    "film_min": ("output", "smallest gap between the object and the wall h/R [-]"),
    "shape_class": ("text", "bullet or parachute (vesicle)"),
    "diameter_um": ("physical", "tube diameter d = 2R [um]"),
    "volume_fl": ("physical", "volume [fL = um^3]"),
    "area_um2": ("physical", "membrane area [um^2] (vesicle)"),
    "U_mm_s": ("physical", "mean velocity U of the undisturbed flow [mm/s]"),
    "eta_mpas": ("physical", "viscosity of the suspending fluid [mPa s]"),
    "kappa_j": ("physical", "bending modulus [J] (vesicle)"),
    "V_mm_s": ("physical output", "velocity V [mm/s]"),
    "dp_plus_Pa": ("physical output", "extra pressure drop dp+ [Pa]"),
    "length_um": ("physical output", "length L [um]"),
    "film_nm": ("physical output", "smallest gap h [nm]"),
}
#: ``<column>_err``: the absolute uncertainty of an output column, in its unit.
ERROR_COLUMNS = {f"{c}_err": f"uncertainty of {c} (absolute, same unit)"
                 for c, (role, _) in COLUMNS.items() if role in ("output", "physical output")}

#: Columns that apply to one kind only (the others refuse them: nothing is ignored silently).
_ONLY_FOR = {"nu": ("vesicle", "sphere"), "area_um2": ("vesicle",), "ca_b": ("vesicle",),
             "kappa_j": ("vesicle",), "shape_class": ("vesicle",), "ca": ("drop",)}
#: The physical inputs and the name of their accepted range in estimate.PHYSICAL_BOUNDS.
_PHYSICAL_INPUTS = {"volume_fl": "volume_fl", "diameter_um": "diameter_um",
                    "U_mm_s": "velocity_mm_s", "eta_mpas": "plasma_viscosity_mpas",
                    "kappa_j": "bending_modulus_j", "area_um2": None}
#: Results given in physical units: dimensionless quantity <- (column, physical_scales key).
_CONVERTED = {"V_over_U": "V_mm_s", "dp_plus_R0": "dp_plus_Pa", "ell": "length_um",
              "film_min": "film_nm"}
#: Column sets of :func:`parse_row`: every known column, the text columns, the dimensionless
#: inputs and outputs, the uncertainties, the columns with a unit, and per kind the columns it
#: may not have.
_KNOWN = frozenset(COLUMNS) | frozenset(ERROR_COLUMNS)
_TEXT_COLUMNS = frozenset(c for c, (role, _) in COLUMNS.items() if role == "text")
_DIMENSIONLESS = frozenset(c for c, (role, _) in COLUMNS.items() if role in ("input", "output"))
_ERROR_OF = {f"{c}_err": c for c in COLUMNS if f"{c}_err" in ERROR_COLUMNS}
_UNIT_COLUMNS = frozenset(c for c, (role, _) in COLUMNS.items() if role.startswith("physical"))
_NOT_FOR = {kind: frozenset(c for c, kinds in _ONLY_FOR.items() if kind not in kinds)
            for kind in KINDS}
#: What each conversion needs besides its column, for the message when it is missing.
_NEEDS = {"V_mm_s": "U_mm_s", "dp_plus_Pa": "U_mm_s, eta_mpas and the volume radius (volume_fl, "
          "or lam with diameter_um)", "length_um": "the tube diameter (diameter_um, or lam "
          "with volume_fl)", "film_nm": "the tube diameter (diameter_um, or lam with volume_fl)"}

#: verdict factor: warn up to this many tolerances, fail beyond
WARN_FACTOR = 3.0

# ---- tolerances of the references: measured on our own solutions by
# ---- tests/benchmarks/check_tolerances.py; tests/correlations/test_check.py checks that our
# ---- converged solutions pass with them
#: Stand-in relative solver error of a map value whose solver part is unknown (ell, film_min and
#: the lubrication points carry none): the refinement tolerance tol = 1e-4 of
#: bem.vesicle.solve_vesicle with which the map points are built (map_build.DEFAULT_OPTIONS).
MAP_UNKNOWN_SOLVER_RTOL = 1e-4
#: Ca_B at which the map is queried when a vesicle row gives none: 50, Chen et al. 2020's value,
#: as in the estimate.
DEFAULT_CA_B = MAP_DEFAULT_CA_B
#: eq. asmyp1: the error is the slope's difference from the lubrication slope 1 (physics notes
#: §4) plus the next term K δ^(3/2) of V/U = 1 + δ − kδ^(3/2); k ≤ 2.0 measured on every
#: converged map point with δ ≤ 0.1 (ν 0.6-0.98, Ca_B 5-500, BEM and lubrication).
NEAR_CRITICAL_SPEED_K = 2.5
#: eq. asmyp2: its O(1) remainder is in fact O(λδ^(-1/2)) (the printed δ^(-1/2) coefficient is
#: too small): |Δp⁺R0/(ηU) − asmyp2| ≤ 20.6 λδ^(-1/2) measured as above; K λ δ^(-1/2) is used.
NEAR_CRITICAL_DP_K = 25.0
#: Chen et al. 2020 fig. dpa_film, Δp⁺R0/(ηU) ≈ (3/2)λℓ/δ with δ = 1 − λ/λc: our converged
#: solutions give 0.884-1.311 times it for 0.02 <= δ <= 0.1 (ν 0.6-0.98, Ca_B 5-500); it
#: leaves that band below δ = 0.02 (0.35 at ν = 0.98, δ = 1e-4).
CHEN_FILM_SCALING_RANGE = (0.02, 0.1)
CHEN_FILM_SCALING_RTOL = 0.35
#: Spherocylinder of radius 1 − h/R and length ℓ near λc: its volume over the vesicle's is
#: 1 + ε_V, its area over the vesicle's 1 + ε_A; measured on every converged map point with
#: δ <= 0.05: 0.31δ <= ε_V <= 0.55δ and 0.11δ <= ε_A <= 0.31δ (the caps are not hemispheres,
#: the film not uniform). Stored as (centre, half-width) in units of δ, each band widened by
#: 0.05δ on both sides.
SHAPE_RANGE_DELTA = 0.05
SHAPE_VOLUME_BAND = (0.43, 0.17)
SHAPE_AREA_BAND = (0.21, 0.15)
#: The transition line of Chen et al. 2020 lies within 0.049 in ν of both ends of the
#: parachute-bullet brackets of our map (BEM lines at Ca_B = 15 and 50): the tolerance of a
#: class disagreeing with the line, in ν − ν_T.
TRANSITION_BAND_NU = 0.05
#: Below this λ/λc a second steady branch, the elongated bullet, coexists with the parachute
#: (tests/benchmarks/map_bistability.py at ν = 0.8, λ/λc 0.2–0.3; the map build's elongated
#: point (0.65, 0.35 λc, Ca_B 15), ℓ 3.51 between parachutes of ℓ 2.64 and 2.15, 0.29 below the
#: line): a bullet there far below the line is a warning (which branch a time-dependent run
#: reaches depends on its start), not a failure. Chen et al. found parachutes there.
ELONGATED_BRANCH_LAM_RATIO = 0.5
#: Small rigid sphere: V/U = 2 − (4/3)λ² + c_V λ⁵, Δp⁺a/(ηU) = 16λ⁶(1 + c_P λ⁵); our BEM sphere
#: (tol 1e-10) gives c_V = 0.32-0.42 and c_P = 1.40-1.82 for λ = 0.05-0.5: the next terms
#: are taken as K λ⁵ with K = 1 and 2.
SMALL_SPHERE_SPEED_K, SMALL_SPHERE_DP_K = 1.0, 2.0
#: Small clean drop (Hetsroni et al. 1970, viscosity ratio 1): |V/U − (2 − 0.8λ²)| <= 0.48λ⁵ and
#: |Δp⁺/(4.8λ⁶) − 1| <= 2.7λ⁵ measured with our BEM for λ <= 0.5 and Ca <= 0.5 (the drop
#: deforms at larger Ca: −18.6λ⁵ at Ca = 1, λ = 0.2).
SMALL_DROP_CA_MAX = 0.5
#: smallest Ca_B at which the small-sphere laws are a reference for a quasi-spherical vesicle
#: (measured on the map's BEM points, :func:`small_object_reference`)
SMALL_VESICLE_CA_B_MIN = 50.0
SMALL_DROP_SPEED_K, SMALL_DROP_DP_K = 1.0, 3.0


class Verdict(enum.Enum):
    """Outcome of a check, in increasing severity."""
    PASS = "pass"
    WARN = "warn"
    FAIL = "fail"

    @property
    def rank(self) -> int:
        return _RANK[self._value_]


_RANK = {"pass": 0, "warn": 1, "fail": 2}


def _worst(verdicts) -> Verdict:
    verdicts = list(verdicts)
    return (Verdict.FAIL if Verdict.FAIL in verdicts else Verdict.WARN if Verdict.WARN in
            verdicts else Verdict.PASS)


def _verdict(deviation: float, tolerance: float) -> Verdict:
    """Pass within one tolerance, warn within :data:`WARN_FACTOR`, fail beyond."""
    if tolerance <= 0.0:
        return Verdict.PASS if deviation == 0.0 else Verdict.FAIL
    r = abs(deviation) / tolerance
    return Verdict.PASS if r <= 1.0 else Verdict.WARN if r <= WARN_FACTOR else Verdict.FAIL


class InputError(InvalidParameterError):
    """A row, a column or the whole input cannot be read (the message names where)."""

    def __init__(self, where: str, column: str, value, expected: str, reason: str = ""):
        what = "missing" if value is None else f"{value!r} is invalid"
        ValueError.__init__(self, f"{where}, column {column!r}: {what}: expected {expected}"
                            + (f"; {reason}" if reason else ""))
        self.name, self.value, self.valid, self.where = column, value, expected, where


# --------------------------------------------------------------------------- reading rows

def _suggest(name: str) -> str:
    close = difflib.get_close_matches(name, [*COLUMNS, *ERROR_COLUMNS], n=1, cutoff=0.6)
    return f"did you mean {close[0]!r}? " if close else ""


def _unknown_column(where: str, name: str) -> InputError:
    return InputError(where, name, name, "a known column",
                      _suggest(name) + "known: " + ", ".join(COLUMNS) + " and <output>_err "
                      "(units are part of the name: diameter_um, volume_fl, area_um2, U_mm_s, "
                      "eta_mpas, kappa_j, V_mm_s, dp_plus_Pa, length_um, film_nm)")


#: The name under which messages refer to the input file (the command's argument FILE).
FILE = "FILE"
#: What the input file must be (messages).
_WHAT = "a CSV or JSON file of rows"
#: Longest record of a CSV file (a line, or the lines of a record whose quoted cell holds line
#: breaks) [characters]: a row of every column written with 17 digits and a long name has
#: about 2000. A file of one endless line (a copy of /dev/zero) is refused at this length
#: instead of being read into memory; it also bounds every cell, below the csv module's own
#: field limit (131072 characters).
MAX_CSV_RECORD_CHARS = 65536
#: Largest JSON file of rows [bytes]. JSON is parsed whole, which takes about five times the
#: file's size in memory at once (text and objects: 32 MiB, about 100 000 rows, ~170 MB);
#: larger tables go in a CSV file, which is read row by row.
MAX_JSON_ROWS_BYTES = 32 * 2**20


class _Lines:
    """The lines of an open text file for :func:`csv.reader`, each record (the lines read
    since :attr:`record` was last set to 0) at most :data:`MAX_CSV_RECORD_CHARS` characters;
    :attr:`line` counts the lines read."""

    __slots__ = ("f", "line", "path", "record")

    def __init__(self, f, path):
        self.f, self.path, self.record, self.line = f, path, 0, 0

    def __iter__(self):
        return self

    def __next__(self) -> str:
        text = self.f.readline(MAX_CSV_RECORD_CHARS + 1 - self.record)
        if not text:
            raise StopIteration
        self.line += 1
        self.record += len(text)
        if self.record > MAX_CSV_RECORD_CHARS:
            raise UnreadableFile(FILE, self.path, _WHAT, f"line {self.line} makes a record "
                                 f"longer than {MAX_CSV_RECORD_CHARS} characters (not a table "
                                 "of results)")
        return text


def _csv_header(path, line: int, cells: list) -> list[str]:
    header = [h.strip() for h in cells]
    for k, h in enumerate(header):
        if not h:
            raise InputError(f"{path} header (line {line})", f"#{k + 1}", h,
                             "a column name", "empty column name")
        if header.count(h) > 1:
            raise InputError(f"{path} header (line {line})", h, h, "each column once",
                             "repeated column")
    if len(header) == 1 and (";" in header[0] or "\t" in header[0]):
        raise InputError(f"{path} header (line {line})", header[0], header[0],
                         "comma-separated columns", "the separator must be a comma")
    return header


def _csv_rows(path):
    """``(row number, line, cells)`` of each data row of the CSV file ``path``, read as a
    stream (:func:`correlations.files.open_text`: a regular file; records bounded by
    :data:`MAX_CSV_RECORD_CHARS`). Blank lines are skipped; ``line`` is where the row starts."""
    with open_text(path, name=FILE, what=_WHAT) as f:
        lines = _Lines(f, path)
        reader = csv.reader(lines)
        header, n = None, 0
        while True:
            start, lines.record = lines.line + 1, 0
            try:
                cells = next(reader, None)
            except (OSError, UnicodeDecodeError, csv.Error) as exc:
                raise UnreadableFile(FILE, path, _WHAT, f"line {lines.line}: {exc}") from None
            if cells is None:
                break
            if not "".join(cells).strip():
                continue
            if header is None:
                header = _csv_header(path, start, cells)
                continue
            n += 1
            if len(cells) != len(header):
                raise InputError(f"row {n} (line {start})", "*", f"{len(cells)} cells",
                                 f"{len(header)} cells, one per header column")
            yield n, start, dict(zip(header, cells))
    if header is None:
        raise InputError(str(path), FILE, str(path), "a header row and data rows",
                         "the file is empty")
    if n == 0:
        raise InputError(str(path), FILE, str(path), "data rows after the header",
                         "no data rows")


def _list_rows(data, source: str):
    """``(row number, None, cells)`` of a list of dicts (rows given in Python or read from a
    JSON file)."""
    if not data:
        raise InputError(source, "rows", "[]", "at least one row")
    for n, row in enumerate(data, 1):
        if not isinstance(row, dict):
            raise InputError(f"row {n}", "*", type(row).__name__, "an object of column: value")
        yield n, None, row


def _json_list(path) -> list:
    """The rows of a JSON file (:func:`correlations.files.read_json`, at most
    :data:`MAX_JSON_ROWS_BYTES`)."""
    check_input_file(path, name=FILE, max_bytes=MAX_JSON_ROWS_BYTES,
                     what="a JSON file of rows; give a larger table as CSV, which is read row "
                          "by row")
    data = read_json(path, name=FILE, what="a JSON file of rows", max_bytes=MAX_JSON_ROWS_BYTES)
    if isinstance(data, dict) and set(data) >= {"rows"}:
        data = data["rows"]
    if not isinstance(data, list):
        raise InputError(str(path), FILE, str(path), 'a list of objects or {"rows": [...]}',
                         f"the top level is a {type(data).__name__}")
    return data


def _starts_like_json(path) -> bool:
    """Whether the text file ``path`` starts (after white space) with ``[`` or ``{``."""
    with open_text(path, name=FILE, what=_WHAT) as f:
        try:
            while True:
                chunk = f.read(65536)
                if not chunk or chunk.strip():
                    return chunk.lstrip()[:1] in ("[", "{")
        except (OSError, UnicodeDecodeError) as exc:
            raise UnreadableFile(FILE, path, _WHAT, f"not readable UTF-8 text ({exc})") from None


def _where(n: int, line: int | None) -> str:
    return f"row {n}" if line is None else f"row {n} (line {line})"


def _source(source):
    """``(description, rows, path)`` of ``source`` (:func:`read_rows`): each call ``rows()``
    starts a pass over ``(row number, line or None, cells)``; a CSV file (``path``) is read
    again on each pass, JSON and Python rows are held in memory (``path`` None)."""
    if isinstance(source, (list, tuple)):
        data = list(source)
        return f"{len(data)} rows given in Python", lambda: _list_rows(data, "rows"), None
    path = check_input_file(source, name=FILE, what=_WHAT)
    suffix = path.suffix.lower()
    if suffix not in (".csv", ".json"):
        suffix = ".json" if _starts_like_json(path) else ".csv"
    if suffix == ".json":
        data = _json_list(path)
        return str(path), lambda: _list_rows(data, str(path)), None
    return str(path), lambda: _csv_rows(path), path


def read_rows(source) -> tuple[list[tuple[str, dict]], str]:
    """The raw rows of ``source`` and a description of it.

    ``source``: a CSV file (``.csv``; header row, comma-separated; each record at most
    :data:`MAX_CSV_RECORD_CHARS` characters), a JSON file (``.json``: a list of objects or
    ``{"rows": [...]}``, at most :data:`MAX_JSON_ROWS_BYTES`; another extension is read as JSON
    if it starts with ``[`` or ``{``, else as CSV), or a list of dicts. Returns ``([(where,
    cells), ...], description)`` with ``where`` naming the row (and the line of a CSV file) for
    messages. Raises :class:`correlations.files.UnreadableFile` for a file that cannot be read
    (missing, not a regular file, too large, not UTF-8, not JSON, an endless line) and
    :class:`InputError` for a malformed table. Holds every row in memory; :func:`check_summary`
    reads a CSV file row by row.
    """
    description, rows, _ = _source(source)
    return [(_where(n, line), cells) for n, line, cells in rows()], description


#: Largest power of ten of a last written digit whose half is a double.
_MAX_DIGIT_EXPONENT = 300


@functools.lru_cache(maxsize=4096)
def _decimal(text: str) -> tuple[float, float]:
    """``(value, half a unit of its last written digit)`` of a number written as ``text``
    (stripped, not empty); ValueError(expected, hint) when it is not a finite one. Cached: the
    columns of a table repeat their inputs and uncertainties."""
    try:
        value = float(text)
        if text.isascii() and "_" not in text:
            # float() took it: [sign] digits [. digits] [e exponent], the Decimal exponent
            mantissa, _, power = text.partition("e" if "e" in text else "E")
            dot = mantissa.find(".")
            exponent = (int(power) if power else 0) - (len(mantissa) - dot - 1 if dot >= 0
                                                        else 0)
        else:
            exponent = decimal.Decimal(text).as_tuple().exponent
    except (ValueError, decimal.InvalidOperation):
        raise ValueError("a number", "write a decimal point, not a comma" if "," in text
                         else "") from None
    if not math.isfinite(value):
        raise ValueError("a finite number", "NaN and infinity are not accepted; leave the cell "
                         "empty for a value not given")
    if exponent > _MAX_DIGIT_EXPONENT:
        raise ValueError(f"a number whose last written digit is at most "
                         f"1e{_MAX_DIGIT_EXPONENT}", "its rounding is beyond double precision")
    return value, 0.5 * 10.0 ** exponent


def _number(where: str, column: str, cell):
    """``(value, half a unit of its last written digit)``, or None for an empty cell."""
    if cell.__class__ is str:
        text = cell.strip()
        if text == "":
            return None
    elif cell is None:
        return None
    elif isinstance(cell, bool) or not isinstance(cell, numbers.Real):
        raise InputError(where, column, cell, "a number")
    else:
        text = str(int(cell)) if isinstance(cell, numbers.Integral) else repr(float(cell))
    try:
        return _decimal(text)
    except ValueError as exc:
        raise InputError(where, column, text, *exc.args) from None


# --------------------------------------------------------------------------- one row

@dataclass(frozen=True)
class Row:
    """One checked input row in dimensionless form (module docstring for the scalings).

    ``values`` holds the given or converted ``nu`` (1 for a sphere), ``lam``, ``ca_b``, ``ca``,
    ``V_over_U``, ``dp_plus_R0``, ``dp_plus_R``, ``ell``, ``film_min`` (floats) and
    ``shape_class`` (text); ``errors`` the absolute uncertainty of each value (stated
    ``*_err`` or the rounding of the written value); ``converted`` the quantities obtained from
    physical columns; ``cells`` the row as given.
    """
    index: int
    where: str
    kind: str
    name: str
    values: dict
    errors: dict
    converted: tuple = ()
    cells: dict = dataclasses.field(default_factory=dict, repr=False)

    def get(self, key, default=None):
        return self.values.get(key, default)


def _text(where: str, column: str, cell, choices=None) -> str | None:
    if cell is None or (isinstance(cell, str) and not cell.strip()):
        return None
    if not isinstance(cell, str):
        raise InputError(where, column, cell, "text")
    text = cell.strip()
    if choices is not None and text.lower() not in choices:
        raise InputError(where, column, text, "one of " + ", ".join(choices))
    return text.lower() if choices is not None else text


class _Named:
    """Re-raise an InvalidParameterError of a conversion as an InputError naming the row and
    the column that carried the parameter."""

    def __init__(self, where: str, columns: dict):
        self.where, self.columns = where, columns

    def __enter__(self):
        return self

    def __exit__(self, kind, exc, tb):
        if isinstance(exc, InvalidParameterError) and not isinstance(exc, InputError):
            column = self.columns.get(exc.name, exc.name)
            raise InputError(self.where, column, exc.value, exc.valid,
                             str(exc).split("; ", 1)[1] if "; " in str(exc) else "") from None
        return False


def _convert_physical(where: str, kind: str, cells: dict, raw: dict, values: dict,
                      errors: dict) -> list[str]:
    """Add to ``values`` and ``errors`` the dimensionless quantities given by physical columns
    (:data:`COLUMNS`, :func:`correlations.estimate.physical_scales`); returns their names.
    ``raw``: column -> (value, rounding) of the row's numbers."""
    if _UNIT_COLUMNS.isdisjoint(raw):
        if values.get("lam", 1.0) <= 0:
            raise InputError(where, "lam", cells["lam"], "lam > 0")
        return []
    physical = {c: raw[c][0] for c in _PHYSICAL_INPUTS if c in raw}
    with _Named(where, {v: k for k, v in _PHYSICAL_INPUTS.items() if v}):
        for column, bound_name in _PHYSICAL_INPUTS.items():
            if column in physical and bound_name is not None:
                lo, hi, reason = PHYSICAL_BOUNDS[bound_name]
                check_range(bound_name, physical[column], lo, hi, reason=reason)
    converted = []

    def take(quantity: str, value: float, error: float, sources: str):
        if quantity in values:
            raise InputError(where, quantity, cells[quantity], f"either {quantity} or {sources}",
                             "both are given")
        values[quantity], errors[quantity] = value, error
        converted.append(quantity)

    R0 = d = None
    with _Named(where, {"volume": "volume_fl", "R0_um": "volume_fl"}):
        if "volume_fl" in physical:
            R0 = float(volume_radius(physical["volume_fl"]))
            if kind == "vesicle" and "area_um2" in physical:
                take("nu", float(cell_from_volume_area(physical["volume_fl"],
                                                       physical["area_um2"])[0]), 0.0,
                     "volume_fl with area_um2")
        elif "area_um2" in physical:
            raise InputError(where, "area_um2", cells["area_um2"], "volume_fl beside it",
                             "the reduced volume needs both the volume and the area")
        if "diameter_um" in physical:
            d = physical["diameter_um"]
            if R0 is not None:
                take("lam", float(confinement_from_diameter(R0, d)), 0.0,
                     "volume_fl with diameter_um")
    if values.get("lam", 1.0) <= 0:
        raise InputError(where, "lam", cells["lam"], "lam > 0")
    if "lam" in values and (R0 is None) != (d is None):
        R0, d = (values["lam"] * d / 2.0, d) if R0 is None else (R0, 2.0 * R0 / values["lam"])
    scale = ({"V_mm_s": physical["U_mm_s"]} if "U_mm_s" in physical else {})
    if R0 is not None and d is not None:
        scale = physical_scales(R0, d, physical.get("U_mm_s"), physical.get("eta_mpas"),
                                physical.get("kappa_j") if kind == "vesicle" else None)
    for quantity, column in _CONVERTED.items():
        if column in raw:
            if column not in scale:
                raise InputError(where, column, cells[column], f"{_NEEDS[column]} beside it",
                                 f"needed to convert it to {quantity}")
            take(quantity, raw[column][0] / scale[column], errors[column] / scale[column], column)
    if kind == "vesicle" and "kappa_j" in physical:
        if "ca_b" not in scale:
            raise InputError(where, "kappa_j", cells["kappa_j"], "U_mm_s, eta_mpas and the "
                             "volume radius beside it", "needed to compute ca_b")
        take("ca_b", scale["ca_b"], 0.0, "kappa_j with U_mm_s and eta_mpas")
    return converted


#: Columns a row of each kind must give (directly or through physical columns).
REQUIRED = {"vesicle": ("nu", "lam", "V_over_U", "dp_plus_R0"),
            "sphere": ("lam", "V_over_U", "dp_plus_R0"), "drop": ("lam", "V_over_U", "dp_plus_R0")}


def parse_row(cells: dict, index: int = 1, where: str | None = None,
              required: dict | None = None) -> Row:
    """One raw row (column -> cell) as a checked :class:`Row` (columns: :data:`COLUMNS`).

    Physical columns are converted (module docstring); a dimensionless value and the physical
    columns that would give it may not both be given. ``required``: the columns each kind must
    give (default :data:`REQUIRED`; ``dp_plus_R0`` is also met by ``dp_plus_R``). Raises
    :class:`InputError` naming the row and the column for anything it cannot use.
    """
    where = where or f"row {index}"
    return Row(index, where, *_parse(cells, where, required), dict(cells))


def _parse(cells: dict, where: str, required: dict | None = None) -> tuple:
    """:func:`parse_row` without the :class:`Row`: ``(kind, name, values, errors,
    converted)``."""
    if not _KNOWN.issuperset(cells):
        for column in cells:
            if column not in _KNOWN:
                raise _unknown_column(where, str(column))
    kind = _text(where, "kind", cells.get("kind"), KINDS) or "vesicle"
    name = _text(where, "name", cells.get("name")) or ""
    shape = _text(where, "shape_class", cells.get("shape_class"), ("bullet", "parachute"))
    raw, values, errors, stated = {}, {}, {}, []
    for c, v in cells.items():
        if c not in _TEXT_COLUMNS:
            number = _number(where, c, v)
            if number is not None:
                raw[c] = number
                if c in _ERROR_OF:
                    stated.append(c)
                else:
                    if c in _DIMENSIONLESS:
                        values[c] = number[0]
                    errors[c] = number[1]
    if not _NOT_FOR[kind].isdisjoint(raw) or (shape and "shape_class" in _NOT_FOR[kind]):
        for column in (*raw, *(["shape_class"] if shape else [])):
            allowed = _ONLY_FOR.get(column, KINDS)
            if kind not in allowed:
                hint = ("ca is a drop's capillary number: set kind=drop for a drop"
                        if column == "ca" else f"it applies to kind={' or '.join(allowed)} only")
                raise InputError(where, column, cells[column], f"no {column} for kind={kind}",
                                 hint)
    for column in stated:
        value, base = raw[column][0], _ERROR_OF[column]
        if base not in raw:
            raise InputError(where, column, value, f"a {base} column beside it",
                             "an uncertainty without its value")
        if value < 0:
            raise InputError(where, column, value, "an uncertainty >= 0")
        errors[base] = value
    converted = _convert_physical(where, kind, cells, raw, values, errors)
    for column in (required or REQUIRED)[kind]:
        if column not in values and not (column == "dp_plus_R0" and "dp_plus_R" in values):
            source = {"nu": " (or volume_fl and area_um2)", "lam": " (or volume_fl and "
                      "diameter_um)", "V_over_U": " (or V_mm_s and U_mm_s)",
                      "dp_plus_R0": " (or dp_plus_R, or dp_plus_Pa)"}.get(column, "")
            hint = " (a drop? set kind=drop)" if column == "nu" else ""
            raise InputError(where, column, None, f"a value{source}", f"required for a {kind}"
                             + hint)
    nu = values.get("nu")
    if nu is not None:
        if not NU_MIN <= nu <= 1.0:
            with _Named(where, {}):
                check_reduced_volume(nu)
        if kind == "sphere" and nu != 1.0:
            raise InputError(where, "nu", cells.get("nu"), "1 for a sphere (or no nu)")
    for column in ("ca_b", "ca"):
        if column in values and values[column] <= 0:
            raise InputError(where, column, cells[column], f"{column} > 0")
    if kind == "sphere":
        values["nu"], errors["nu"] = 1.0, 0.0
    if shape:
        values["shape_class"] = shape
    return kind, name, values, errors, tuple(converted)


def parse_rows(source) -> list[Row]:
    """Every row of ``source`` (see :func:`read_rows`) as a checked :class:`Row`."""
    raw, _ = read_rows(source)
    return [parse_row(cells, n, where) for n, (where, cells) in enumerate(raw, 1)]


# --------------------------------------------------------------------------- references

class _Batched:
    """A function of a row's numbers that is computed for many rows at once and asked for one
    row at a time. ``batch(*columns)`` takes one list per argument and returns one value per
    argument tuple; :meth:`fill` computes it for the tuples of a chunk of rows not known yet
    (:func:`check_summary` reads rows in chunks), a call looks one tuple up, or computes it
    alone as a batch of one: a row alone and a row in a chunk take one code path (numpy's
    elementwise functions give an element the same value in an array of any length). At
    most ``size`` values are kept (all are forgotten when one more would exceed it): a few
    chunks' worth."""

    def __init__(self, batch, size: int = 1 << 13):
        self.batch, self.size, self.known = batch, size, {}

    def fill(self, *columns) -> None:
        """Compute the values of the argument tuples ``zip(*columns)`` not known yet. A batch
        that raises is left to the calls (each row then raises where it would alone)."""
        keys = [k for k in dict.fromkeys(zip(*columns)) if k not in self.known]
        if not keys:
            return
        if len(self.known) + len(keys) > self.size:
            self.known.clear()
        try:
            values = self.batch(*map(list, zip(*keys)))
        except (ValueError, ArithmeticError):
            return
        self.known.update(zip(keys, values))

    def __call__(self, *args):
        value = self.known.get(args)
        if value is None and args not in self.known:
            if len(self.known) >= self.size:
                self.known.clear()
            value = self.known[args] = self.batch(*([a] for a in args))[0]
        return value


def _floats(f):
    """``f`` of float arrays, as lists of floats (for :class:`_Batched`), with the
    :class:`OutOfRangeWarning` of a law used outside its range silenced (the checks state the
    ranges they use)."""
    def batch(*columns):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", OutOfRangeWarning)
            out = f(*(np.array(c, dtype=float) for c in columns))
        if isinstance(out, tuple):
            return list(zip(*(np.asarray(o, dtype=float).tolist() for o in out)))
        return np.asarray(out, dtype=float).tolist()
    return batch


#: λc(ν) (:func:`lubrication.geometry.critical_confinement`): every check of a row needs it.
_lam_c = _Batched(_floats(critical_confinement))


@dataclass(frozen=True)
class Reference:
    """A reference value with its absolute error bar (same unit), what it is (``source``),
    why it is valid for the row (``why``) and a note (stand-ins used for unknown error parts)."""
    value: float | str
    error: float
    source: str
    why: str
    note: str = ""


class _NoMap(str):
    """Why there is no map (a resolved choice, not a path)."""


def _resolve_map(choice):
    """The map to read: None the shipped one, False none, a path or a SolutionMap (as the
    estimate's map rows, :mod:`correlations.registry`); the reason (:class:`_NoMap`) when there
    is none. A path that is not a map raises InvalidParameterError (``map``)."""
    if isinstance(choice, _NoMap):
        return choice
    if choice is False:
        return _NoMap("the solution map is switched off")
    try:
        return require_vesicle_map(resolve_solution_map(choice), "the checker's references "
                                   "are vesicles")
    except MethodNotApplicable as exc:
        return _NoMap(str(exc))


def map_reference(nu: float, lam: float, ca_b: float, quantity: str,
                  solution_map=None) -> Reference | str:
    r"""The solution map's value of ``quantity`` for a vesicle, with its error bar.

    :func:`correlations.solution_map.query_map` at (ν, λ/λc, Ca_B): stored steady BEM and
    lubrication solutions interpolated in δ^(1/2), log Ca_B and ν, error = interpolation +
    solver + model error. Where the map cannot say a part, a stand-in is added and named in
    the note: an unknown solver error is :data:`MAP_UNKNOWN_SOLVER_RTOL` × ``|value|`` (the
    map's BEM tolerance); an unknown lubrication model error (a Ca_B line without a BEM point
    to compare with) is the relative model error at Ca_B = :data:`DEFAULT_CA_B` plus the change
    of the value from that Ca_B. Returns the reason (str) when the map has no usable value.

    ``quantity``: ``V_over_U``, ``dp_plus_R0``, ``ell``, ``film_min`` or ``shape_class``;
    ``solution_map`` as in :func:`check_results`.
    """
    return _map_ref(nu, lam, ca_b, quantity, _resolve_map(solution_map))


def _map_ref(nu: float, lam: float, ca_b: float, quantity: str, m) -> Reference | str:
    """:func:`map_reference` on the resolved map ``m`` (or why there is none)."""
    return str(m) if isinstance(m, _NoMap) else _map_reference(nu, lam, ca_b, quantity, m)


def _answers(nu: list, ratio: list, ca_b: list, maps: list) -> list:
    """Per point (ν, λ/λc, Ca_B) of map ``maps[i]``: why it lies outside the map
    (:func:`correlations.solution_map.outside_reason`), else the map's quantities there
    (:func:`correlations.solution_map.query_map_many`, the points of each map together)."""
    out = [outside_reason(*p) for p in zip(maps, nu, ratio, ca_b)]
    for m in set(maps):
        at = [i for i, k in enumerate(maps) if k is m and not out[i]]
        for i, q in zip(at, query_map_many([nu[i] for i in at], [ratio[i] for i in at],
                                           [ca_b[i] for i in at], m, _MAP_QUANTITIES)):
            out[i] = q.quantities
    return out


#: The quantities of the solution map that the checks compare (besides the shape class).
_MAP_QUANTITIES = ("V_over_U", "dp_plus_R0", "ell", "film_min")
#: The solution map's quantities at (ν, λ/λc, Ca_B, map), or why there are none.
_map_queries = _Batched(_answers)


@functools.cache
def _map_source(methods: tuple) -> str:
    """The source of a map reference from the methods of its nodes (a few sets of them)."""
    return f"solution map, {map_method_name(methods)}"


@functools.lru_cache(maxsize=64)
def _inside(nu: float, ratio: float, ca_b: float) -> str:
    """Where a map reference is taken (the quantities of a row share it)."""
    return f"inside the map at nu={nu:.4g}, lam/lam_c={ratio:.4g}, Ca_B={ca_b:.4g}"


@functools.lru_cache(maxsize=1024)
def _map_reference(nu: float, lam: float, ca_b: float, quantity: str, m) -> Reference | str:
    """:func:`map_reference` on the resolved map ``m``, cached: rows of a table often repeat
    their case."""
    ratio = lam / _lam_c(nu)
    answer = _map_queries(nu, ratio, ca_b, m)
    if isinstance(answer, str):
        return f"outside the solution map ({answer})"
    v = answer[quantity]
    if v.value is None:
        return f"solution map: {v.note}"
    source = _map_source(v.methods)
    where = _inside(nu, ratio, ca_b)
    if isinstance(v.value, str):
        return Reference(v.value, 0.0, source, where + "; the neighbouring solutions are all "
                         "of this class")
    why = where + "; error = interpolation + solver + model error (correlations.solution_map)"
    if v.interpolation_error is None:
        return "solution map: interpolation error unknown here"
    error, notes = v.error, []
    if v.solver_error is None:
        error += MAP_UNKNOWN_SOLVER_RTOL * abs(v.value)
        notes.append(f"solver error unknown: {MAP_UNKNOWN_SOLVER_RTOL:g} x value used")
    if v.model_error is None:
        w = None if ca_b == DEFAULT_CA_B else _map_queries(nu, ratio, DEFAULT_CA_B, m)
        w = None if isinstance(w, str) or w is None else w[quantity]
        if w is None or w.value is None or w.model_error is None:
            return f"solution map: lubrication model error unknown at Ca_B={ca_b:g}"
        stand_in = w.model_error / abs(w.value) * abs(v.value) + abs(v.value - w.value)
        error += stand_in
        notes.append(f"lubrication model error unknown at Ca_B={ca_b:g}: the one at Ca_B="
                     f"{DEFAULT_CA_B:g} plus the change from there used ({stand_in:.2g})")
    return Reference(v.value, error, source, why, "; ".join(notes))


#: eq. asmyp1 (V/U and its slope) and eq. asmyp2 (Δp⁺R0/(ηU)) at (ν, λ).
_near_critical_laws = _Batched(_floats(lambda nu, lam: (
    asymptotics.speed_near_critical(nu, lam), asymptotics.speed_slope_near_critical(nu),
    asymptotics.dp_plus_near_critical(nu, lam))))


def near_critical_reference(nu: float, lam: float, quantity: str) -> Reference | str:
    r"""Near-critical asymptote of V/U or Δp⁺R0/(ηU) for δ = 1 − λ/λc ≤ 0.1, with its error.

    V/U: Chen et al. 2020 eq. asmyp1 (Barakat & Shaqfeh 2018a), error ``|s − 1| δ`` +
    :data:`NEAR_CRITICAL_SPEED_K` δ^(3/2) with s its slope
    (:func:`lubrication.asymptotics.speed_slope_near_critical`): our lubrication and BEM
    solutions have slope 1 (physics notes §4). Δp⁺: eq. asmyp2, error
    :data:`NEAR_CRITICAL_DP_K` λ δ^(-1/2). Both error models were measured on the converged
    points of the map (0.6 ≤ ν ≤ 0.98); outside that ν range the note says so.
    """
    if quantity not in ("V_over_U", "dp_plus_R0"):
        return f"no near-critical law for {quantity}"
    delta = 1.0 - lam / _lam_c(nu)
    hi = asymptotics.NEAR_CRITICAL_RANGE.bounds[0][2]
    if delta > hi:
        return f"not near lam_c (delta={delta:.3g} > {hi:g})"
    speed, slope, dp = _near_critical_laws(nu, lam)
    if quantity == "V_over_U":
        value = speed
        error = abs(slope - 1.0) * delta + NEAR_CRITICAL_SPEED_K * delta**1.5
        source = "Barakat & Shaqfeh 2018a as Chen et al. 2020 eq. asmyp1"
        model = f"|slope - 1| delta + {NEAR_CRITICAL_SPEED_K:g} delta^(3/2)"
    else:
        value = dp
        error = NEAR_CRITICAL_DP_K * lam / math.sqrt(delta)
        source = "Barakat & Shaqfeh 2018a as Chen et al. 2020 eq. asmyp2"
        model = f"{NEAR_CRITICAL_DP_K:g} lam delta^(-1/2)"
    note = "" if 0.6 <= nu <= 0.98 else (f"nu={nu:.3g}: error model measured for 0.6 <= nu <= "
                                          "0.98, extrapolated")
    return Reference(value, error, source, f"delta={delta:.3g} <= {hi:g}; error {model} "
                     "(measured on our converged solutions)", note)


def small_object_reference(kind: str, lam: float, quantity: str, nu: float = 1.0,
                           ca: float | None = None, ca_b: float | None = None) -> Reference | str:
    r"""Small-object law of V/U or Δp⁺R0/(ηU) on the axis, with the size of the next term.

    * rigid sphere (``kind`` sphere): V/U = 2 − (4/3)λ² + O(λ⁵), Δp⁺a/(ηU) = 16λ⁶(1 + O(λ⁵))
      (Chen et al. 2020 eq. small1, small2; Haberman & Sayre 1958), error
      :data:`SMALL_SPHERE_SPEED_K` λ⁵ resp. :data:`SMALL_SPHERE_DP_K` λ⁵ × 16λ⁶; λ ≤ 0.5
      (:data:`lubrication.asymptotics.SMALL_SPHERE_RANGE`).
    * vesicle, 0.9 ≤ ν < 1, λ ≤ 0.5 (Chen et al. 2020 §IV.C; registry SMALL_VESICLE_RANGE): the
      sphere's laws, error the sphere's plus (1 − ν) × the leading deviation ((4/3)λ²
      resp. 16λ⁶): a vesicle at rest is not a sphere. On our BEM vesicles (ν = 0.9-0.98, λ/λc
      = 0.2-0.4) the deviation beyond the sphere's next term is at most 0.2 (1 − ν) × the
      leading term at Ca_B ≥ :data:`SMALL_VESICLE_CA_B_MIN` = 50; below it the vesicle keeps
      more of its prolate rest shape (V/U 0.9 % above the sphere's at ν = 0.95, λ/λc = 0.2,
      Ca_B = 15, 3.6× that error), so the law is not used for a row with a smaller ``ca_b``.
    * clean drop of viscosity ratio 1 (``kind`` drop): V/U = 2 − 0.8λ², Δp⁺R0/(ηU) = 4.8λ⁶
      (Hetsroni, Haber & Wacholder 1970), error :data:`SMALL_DROP_SPEED_K` λ⁵ resp.
      :data:`SMALL_DROP_DP_K` λ⁵ × 4.8λ⁶, measured with our BEM for λ ≤ 0.5, Ca ≤
      :data:`SMALL_DROP_CA_MAX` (needs ``ca``).
    """
    if quantity not in ("V_over_U", "dp_plus_R0"):
        return f"no small-object law for {quantity}"
    validity = asymptotics.SMALL_DROP_RANGE if kind == "drop" else asymptotics.SMALL_SPHERE_RANGE
    hi = validity.bounds[0][2]
    if lam > hi:
        return f"not a small object (lam={lam:.3g} > {hi:g})"
    speed = quantity == "V_over_U"
    if kind == "drop":
        if ca is None or ca > SMALL_DROP_CA_MAX:
            return (f"small-drop law measured for Ca <= {SMALL_DROP_CA_MAX:g}: "
                    + ("no ca given" if ca is None else f"ca={ca:.3g}"))
        lead = 0.8 * lam**2 if speed else 4.8 * lam**6
        value = 2.0 - lead if speed else lead
        error = (SMALL_DROP_SPEED_K * lam**5 if speed
                 else SMALL_DROP_DP_K * lam**5 * lead)
        return Reference(value, error, "small clean drop, Hetsroni, Haber & Wacholder 1970",
                         f"lam={lam:.3g} <= {hi:g}, Ca={ca:.3g} <= {SMALL_DROP_CA_MAX:g}; "
                         "error: next term, measured with our BEM drop")
    if kind == "vesicle" and not SMALL_VESICLE_RANGE.contains(lam=lam, nu=nu):
        return f"small-sphere law not valid for a vesicle here ({SMALL_VESICLE_RANGE.describe()})"
    if kind == "vesicle" and ca_b is not None and ca_b < SMALL_VESICLE_CA_B_MIN:
        return (f"small-sphere law measured for a vesicle at Ca_B >= {SMALL_VESICLE_CA_B_MIN:g} "
                f"(ca_b={ca_b:.3g})")
    lead = 4.0 / 3.0 * lam**2 if speed else 16.0 * lam**6
    value = 2.0 - lead if speed else lead
    error = (SMALL_SPHERE_SPEED_K * lam**5 if speed else SMALL_SPHERE_DP_K * lam**5 * lead) \
        + (1.0 - nu) * lead
    source = "small rigid sphere, Chen et al. 2020 eq. " + ("small1" if speed else "small2")
    why = f"lam={lam:.3g} <= {hi:g}; error: the next term K lam^5 (K measured, BEM sphere)"
    if nu < 1.0:
        why = f"nu={nu:.3g} >= 0.9, {why} + (1 - nu) x the leading deviation (asphericity)"
    return Reference(value, error, source, why)


@functools.lru_cache(maxsize=256)
def _sphere_solution(lam: float):
    return guarded(solve_sphere, lam)


@functools.lru_cache(maxsize=256)
def _drop_solution(lam: float, ca: float):
    from bem.drop import solve_drop  # lazy: scipy.linalg, only for drop rows
    return guarded(solve_drop, lam, ca)


def _exact(value: float, what: str) -> Reference:
    return Reference(value, 0.0, f"rigid sphere: {what} (exact)", "a rigid sphere keeps its shape")


def sphere_reference(lam: float, quantity: str, bem: bool = True) -> Reference | str:
    r"""Free rigid sphere of radius a = λR on the axis: h/R = 1 − λ and ℓ = 2λ exactly; V/U and
    Δp⁺a/(ηU) from :func:`bem.solve.solve_sphere` (default tolerance 1e-8, error: the
    refinement pair's difference), about a second per λ, cached. Returns the reason (str) when
    there is none (``bem`` False, λ outside the BEM's envelope, no convergence)."""
    if quantity == "film_min":
        return _exact(1.0 - lam, "h/R = 1 - lam")
    if quantity == "ell":
        return _exact(2.0 * lam, "L/R = 2 lam")
    if not bem:
        return "BEM references skipped"
    try:
        check_sphere_inputs(lam)
    except InvalidParameterError as exc:
        return f"BEM sphere: {exc}"
    res = _sphere_solution(lam)
    if not getattr(res, "converged", False):
        return f"BEM sphere did not converge: {res.message}"
    value, error = ((res.V_over_U, res.V_over_U_err) if quantity == "V_over_U"
                    else (res.dp_plus_R0, res.dp_plus_R_err * lam))
    return Reference(value, error, "BEM rigid sphere (bem.solve.solve_sphere)",
                     f"a/R={lam:.4g}: full Stokes solution; error = refinement-pair difference")


def drop_reference(lam: float, ca: float | None, quantity: str,
                   bem: bool = True) -> Reference | str:
    r"""Steady clean drop of viscosity ratio 1 from :func:`bem.drop.solve_drop` (seconds per
    (λ, Ca), cached): V/U and Δp⁺R0/(ηU) with the refinement pair's difference as error; ℓ and
    h/R (length, smallest gap) with the solver's relative tolerance as error (it reports none
    for them). Returns the reason (str) when there is none."""
    if not bem:
        return "BEM references skipped"
    if ca is None:
        return "no ca given (the drop BEM needs the capillary number)"
    from bem.drop import check_drop_inputs  # lazy: scipy.linalg, only for drop rows
    try:
        check_drop_inputs(lam, ca)
    except InvalidParameterError as exc:
        return f"BEM drop: {exc}"
    res = _drop_solution(lam, ca)
    if not getattr(res, "success", False):
        return f"BEM drop has no converged steady state: {res.message}"
    attribute = {"V_over_U": "V_over_U", "dp_plus_R0": "dp_plus_R0", "ell": "length",
                 "film_min": "film"}[quantity]
    value = getattr(res, attribute)
    error = res.error_estimate.get(quantity, res.tol * abs(value))
    return Reference(value, error, "BEM clean drop (bem.drop.solve_drop)",
                     f"lam={lam:.4g}, Ca={ca:.4g}: full Stokes solution; error = refinement-pair "
                     "difference (length and gap: the solver tolerance)")


# --------------------------------------------------------------------------- bounds

def film_upper_bound(nu: float, lam: float) -> float:
    r"""Largest smallest gap of a vesicle, h/R ≤ δ = 1 − λ/λc(ν).

    A membrane of area A encloses at most the volume of the spherocylinder of its area inside
    a cylinder of radius ρ, the critical shape that defines λc (Canham 1968; Barakat & Shaqfeh
    2018a; Chen et al. 2020 eq. critic). The vesicle fits inside the cylinder of radius
    ρ = R − h that touches it, so it is at most critical there: λR/ρ ≤ λc, i.e. h/R ≤ 1 − λ/λc.
    (Chen et al. eq. sfilm2 is this bound to leading order; our solutions have h/R =
    0.60-0.97 δ.)

    >>> round(film_upper_bound(0.6, 1.94), 4)
    0.0208
    """
    return 1.0 - lam / _lam_c(nu)


def film_lower_bound(nu: float, lam: float) -> float:
    r"""Smallest possible gap of a vesicle, h/R ≥ 1 − √2 λ_A, λ_A = λν^(−1/3).

    Both faces of the membrane cover the disc of its largest radius r_max, so A ≥ 2πr_max²
    and r_max/R ≤ √(A/2π)/R = √2 λ_A (equality for a flat disc; geometry).

    >>> round(film_lower_bound(1.0, 0.5), 4)
    0.2929
    """
    return 1.0 - math.sqrt(2.0) * lam * nu ** (-1.0 / 3.0)


def length_lower_bound(lam: float, film: float = 0.0) -> float:
    r"""Shortest length of an object of volume (4/3)πR0³ whose largest radius is R − h:
    ℓ ≥ (4/3)λ³/(1 − h/R)², the cylinder of that radius holding the volume (a closed body with
    rounded ends, e.g. the spherocylinder, is longer).

    >>> round(length_lower_bound(1.0), 4)
    1.3333
    """
    return 4.0 / 3.0 * lam**3 / (1.0 - film) ** 2


# --------------------------------------------------------------------------- checks

class CheckResult(NamedTuple):
    """One check of one row: ``value`` of the row, ``reference`` (a bound or a reference
    value), ``deviation`` = value − reference (signed, in the value's unit), ``tolerance`` (the
    absolute deviation that still passes), the reference's ``source`` and ``why`` it is valid
    for the row, and a ``note``. A named tuple (immutable, as a frozen dataclass, and made in
    a quarter of its time: a row has a dozen checks, a table up to millions of rows)."""
    name: str
    quantity: str
    verdict: Verdict
    value: float | str | None
    reference: float | str | None
    deviation: float | None
    tolerance: float | None
    source: str
    why: str
    note: str = ""

    def to_dict(self) -> dict:
        return {"name": self.name, "quantity": self.quantity, "verdict": self.verdict.value,
                "value": self.value, "reference": self.reference, "deviation": self.deviation,
                "tolerance": self.tolerance, "source": self.source, "why": self.why,
                "note": self.note}


_VERDICT_OF = operator.attrgetter("verdict")


def _bound(name: str, quantity: str, value: float, bound: float, err: float, *, upper: bool,
           strict: bool, source: str, why: str) -> CheckResult:
    """``value`` below (``upper``) or above ``bound``: fail when past it by more than ``err``
    (the row's uncertainty), warn within it (``err`` 0: fail at once); on a ``strict`` bound
    equality counts as past."""
    excess = value - bound if upper else bound - value
    if excess < 0 or (excess == 0 and not strict):
        verdict = Verdict.PASS
    else:
        verdict = Verdict.WARN if excess < err or (excess == 0 and err > 0) else Verdict.FAIL
    return CheckResult(name, quantity, verdict, value, bound, value - bound, err, source, why)


def _worse(a: CheckResult, b: CheckResult) -> CheckResult:
    """Of two checks of one value against its two bounds, the one to report: the worse
    verdict, else the nearer bound (``a`` on a tie)."""
    ra, rb = a.verdict.rank, b.verdict.rank
    if ra != rb:
        return a if ra > rb else b
    return a if abs(a.deviation) <= abs(b.deviation) else b


def _compare(name: str, quantity: str, value: float, err: float, ref: Reference,
             scale: float = 1.0) -> CheckResult:
    """``value`` (uncertainty ``err``) against ``ref`` times ``scale``: tolerance = both
    errors, verdict by :func:`_verdict`."""
    reference, ref_error = ref.value * scale, ref.error * abs(scale)
    deviation, tolerance = value - reference, ref_error + err
    return CheckResult(name, quantity, _verdict(deviation, tolerance), value, reference,
                       deviation, tolerance, ref.source, ref.why, ref.note)


def _dp(row: Row) -> tuple[str, float, float, float]:
    """The row's extra pressure drop as given: (column, value, uncertainty, factor from
    Δp⁺R0/(ηU) to it), dp_plus_R0 when given, else dp_plus_R."""
    key = "dp_plus_R0" if "dp_plus_R0" in row.values else "dp_plus_R"
    factor = 1.0 if key == "dp_plus_R0" else 1.0 / row.values["lam"]
    return key, row.values[key], row.errors[key], factor


def _dp_R0(values: dict, errors: dict) -> tuple[float, float]:
    """Δp⁺R0/(ηU) and its uncertainty of a row's ``values`` and ``errors`` (from dp_plus_R with
    λ's rounding when only it is given)."""
    if "dp_plus_R0" in values:
        return values["dp_plus_R0"], errors["dp_plus_R0"]
    lam, value, err = values["lam"], values["dp_plus_R"], errors["dp_plus_R"]
    return value * lam, err * lam + abs(value) * errors.get("lam", 0.0)


#: Texts of the hard bounds (:func:`_bound_checks`).
_LAM_WHY = {"sphere": "geometry: a rigid sphere fits the tube only if a < R",
            "vesicle": "geometry: lam >= lam_c: the vesicle cannot pass this tube intact"}
_V_BOUNDS = OUTPUT_BOUNDS["V_over_U"]
_V_WHY = (_V_BOUNDS[2], _V_BOUNDS[2] + "; a finite object lags the centreline")
_DP_WHY = OUTPUT_BOUNDS["dp_plus_R0"][2] + "; positive for a finite object"
_FILM_TOP = {"vesicle": (False, "h/R <= 1 - lam/lam_c (film_upper_bound)",
                         ("a membrane of this area and volume fits only a tube of radius above "
                          "R0/lam_c")),
             "other": (True, "h/R < 1", "the object has a size")}


def _bound_checks(row: Row) -> tuple[list[CheckResult], bool]:
    """The hard bounds of the module docstring; returns (checks, whether the object passes the
    tube so that references apply)."""
    v, e, checks = row.values, row.errors, []
    lam, nu, kind = v["lam"], v.get("nu", 1.0), row.kind
    passes = True
    if kind != "drop":
        # no warning zone: at or beyond lam_c as given, nothing else can be checked
        c = _bound("lam < lam_c", "lam", lam, _lam_c(nu), 0.0, upper=True, strict=True,
                   source="critical confinement, Chen et al. 2020 eq. critic",
                   why=_LAM_WHY[kind])
        checks.append(c)
        passes = c.verdict is Verdict.PASS
    lo, hi, _ = _V_BOUNDS
    V, eV = v["V_over_U"], e["V_over_U"]
    checks.append(_worse(
        _bound("1 <= V/U < 2", "V_over_U", V, lo, eV, upper=False, strict=False,
               source="bound of Poiseuille flow", why=_V_WHY[0]),
        _bound("1 <= V/U < 2", "V_over_U", V, hi, eV, upper=True, strict=True,
               source="bound of Poiseuille flow", why=_V_WHY[1])))
    for key in ("dp_plus_R0", "dp_plus_R"):
        if key in v:
            checks.append(_bound("dp+ > 0", key, v[key], 0.0, e[key], upper=False, strict=True,
                                 source="sign of the extra dissipation", why=_DP_WHY))
    film = v.get("film_min")
    if film is not None:
        strict, top_source, why = _FILM_TOP["vesicle" if kind == "vesicle" else "other"]
        top = film_upper_bound(nu, lam) if kind == "vesicle" else 1.0
        err = e["film_min"]
        checks.append(_worse(
            _bound("0 < h/R <= bound", "film_min", film, 0.0, err, upper=False, strict=True,
                   source="h/R > 0", why="a steady object does not touch the wall"),
            _bound("0 < h/R <= bound", "film_min", film, top, err, upper=True, strict=strict,
                   source=top_source, why=why)))
        if kind == "vesicle":
            checks.append(_bound("h/R >= 1 - sqrt(2) lam_A", "film_min", film,
                                 film_lower_bound(nu, lam), err, upper=False, strict=False,
                                 source="film_lower_bound",
                                 why="both faces of the membrane cover its widest disc"))
    ell = v.get("ell")
    if ell is not None:
        h = film if film is not None and 0.0 <= film < 1.0 else 0.0
        checks.append(_bound("ell >= volume bound", "ell", ell, length_lower_bound(lam, h),
                             e["ell"], upper=False, strict=False,
                             source="length_lower_bound: (4/3) lam^3/(1 - h/R)^2",
                             why="the volume fits in the cylinder of the largest radius"))
    if "dp_plus_R0" in v and "dp_plus_R" in v:
        R0, R = v["dp_plus_R0"], v["dp_plus_R"]
        tol = e["dp_plus_R0"] + lam * e["dp_plus_R"] + abs(R) * e.get("lam", 0.0)
        checks.append(CheckResult("dp+R0 = lam dp+R", "dp_plus_R0", _verdict(R0 - lam * R, tol),
                                  R0, lam * R, R0 - lam * R, tol, "definition of the scalings",
                                  "dp+ R0/(eta U) = (R0/R) dp+ R/(eta U) whatever the method"))
    return checks, passes


#: Chen et al.'s Δp⁺R0/(ηU) ≈ (3/2)λℓ/δ per unit ℓ (:func:`dp_plus_film_chen2020`, linear
#: in ℓ) at (λ, δ).
_chen_film_slope = _Batched(_floats(lambda lam, delta: dp_plus_film_chen2020(lam, 1.0, delta)))


def chen_film_scaling_check(row: Row) -> CheckResult | str:
    r"""Δp⁺R0/(ηU) against Chen et al. 2020's correlation (3/2)λℓ/δ (fig. dpa_film), with
    δ = 1 − λ/λc (their eq. sfilm2: the film at the vesicle's midplane to leading order; the
    smallest gap is 0.6-0.97 δ in our solutions, so the reported ``film_min`` is not used).
    Valid for 0.02 ≤ δ ≤ 0.1 (:data:`CHEN_FILM_SCALING_RANGE`) with tolerance
    :data:`CHEN_FILM_SCALING_RTOL` × the correlation (the scatter of our converged solutions).
    A vesicle row with ℓ; returns the reason (str) when it does not apply."""
    v = row.values
    nu, lam, ell = v.get("nu"), v["lam"], v.get("ell")
    if row.kind != "vesicle" or nu >= 1.0 or ell is None or ell <= 0:
        return "needs a vesicle with ell"
    delta = 1.0 - lam / _lam_c(nu)
    lo, hi = CHEN_FILM_SCALING_RANGE
    if not lo <= delta <= hi:
        return f"Chen et al.'s (3/2) lam ell/delta holds for {lo:g} <= delta <= {hi:g}"
    pred = _chen_film_slope(lam, delta) * ell
    value, err = _dp_R0(row.values, row.errors)
    tol = CHEN_FILM_SCALING_RTOL * pred + err + pred * row.errors["ell"] / ell
    return CheckResult("dp+ vs (3/2) lam ell/delta", "dp_plus_R0", _verdict(value - pred, tol),
                       value, pred, value - pred, tol,
                       "Chen et al. 2020 fig. dpa_film (delta = 1 - lam/lam_c)",
                       f"delta={delta:.3g} in [{lo:g}, {hi:g}]; tolerance "
                       f"{CHEN_FILM_SCALING_RTOL:g} x value: the scatter of our solutions")


def shape_volume_area_checks(row: Row) -> list[CheckResult] | str:
    r"""Volume and area of the spherocylinder of radius ρ = 1 − h/R and length ℓ against the
    vesicle's, near λc.

    Spherocylinder: volume πρ²(L − 2ρ/3), area 2πρL (Archimedes), i.e. relative to the vesicle
    ε_V = (3ρ²ℓ − 2ρ³)/(4λ³) − 1 and ε_A = ρℓ/(2λ_A²) − 1, λ_A = λν^(−1/3). Near λc a vesicle
    is nearly this spherocylinder: for δ ≤ :data:`SHAPE_RANGE_DELTA` our converged solutions
    lie in the bands :data:`SHAPE_VOLUME_BAND` and :data:`SHAPE_AREA_BAND` (centre ± half-width,
    × δ). A result whose volume (area) drifted by 1 % moves ε_V (ε_A) by 1 %, several half-widths
    for δ ≲ 0.01: the check sees it where ℓ and h hardly tell otherwise. The row's
    uncertainties of ℓ and h are propagated. A vesicle row with ℓ and h; returns the reason
    (str) when it does not apply.
    """
    v = row.values
    nu, lam, ell, h = v.get("nu"), v["lam"], v.get("ell"), v.get("film_min")
    if row.kind != "vesicle" or nu >= 1.0 or ell is None or h is None or not 0 <= h < 1:
        return "needs a vesicle with ell and film_min"
    delta = 1.0 - lam / _lam_c(nu)
    if not 0.0 < delta <= SHAPE_RANGE_DELTA:
        return f"the spherocylinder bands hold for delta <= {SHAPE_RANGE_DELTA:g}"
    rho, lam_a2 = 1.0 - h, lam**2 * nu ** (-2.0 / 3.0)
    e_ell, e_h = row.errors["ell"], row.errors["film_min"]
    eps_v = (3 * rho**2 * ell - 2 * rho**3) / (4 * lam**3) - 1.0
    err_v = (3 * rho**2 * e_ell + (6 * rho * ell - 6 * rho**2) * e_h) / (4 * lam**3)
    eps_a = rho * ell / (2 * lam_a2) - 1.0
    err_a = (rho * e_ell + ell * e_h) / (2 * lam_a2)
    out = []
    for name, eps, err, (centre, half) in (("volume of the shape", eps_v, err_v,
                                            SHAPE_VOLUME_BAND),
                                           ("area of the shape", eps_a, err_a, SHAPE_AREA_BAND)):
        ref, tol = centre * delta, half * delta + err
        out.append(CheckResult(name, "ell", _verdict(eps - ref, tol), eps, ref, eps - ref, tol,
                               "spherocylinder of radius 1 - h/R and length ell",
                               f"delta={delta:.3g} <= {SHAPE_RANGE_DELTA:g}: relative excess in "
                               f"[{centre - half:g}, {centre + half:g}] delta on our solutions"))
    return out


def shape_class_check(row: Row, solution_map=None) -> CheckResult | str:
    r"""The row's ``shape_class`` against the solution map where its neighbouring solutions
    share one class (disagreement fails), else against the transition line ν_T = 1.126 −
    0.29λ of Chen et al. 2020 (eq. transition) inside its range
    (:data:`correlations.shape.SHAPE_CLASS_RANGE_CHEN2020`): a disagreement is judged by the
    distance ν − ν_T with tolerance :data:`TRANSITION_BAND_NU` (where our map's transitions
    lie; both shapes occur near the line)."""
    v = row.values
    given = v.get("shape_class")
    if given is None:
        return "no shape_class given"
    nu, lam, ca_b = v.get("nu"), v["lam"], v.get("ca_b", DEFAULT_CA_B)
    ref = map_reference(nu, lam, ca_b, "shape_class", solution_map)
    if isinstance(ref, Reference):
        verdict = Verdict.PASS if given == ref.value else Verdict.FAIL
        return CheckResult("shape class", "shape_class", verdict, given, ref.value, None, None,
                           ref.source, ref.why)
    if not SHAPE_CLASS_RANGE_CHEN2020.contains(nu=nu, lam=lam, ca_b=ca_b):
        return f"{ref}; outside the range of Chen et al.'s transition line " \
               f"({SHAPE_CLASS_RANGE_CHEN2020.describe()})"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutOfRangeWarning)
        expected = str(shape_class_chen2020(nu, lam))
    distance = nu - (1.126 - 0.29 * lam)
    verdict = (Verdict.PASS if given == expected else _verdict(distance, TRANSITION_BAND_NU))
    why = (f"inside its range; a disagreement is judged by the distance nu - nu_T to the line, "
           f"tolerance {TRANSITION_BAND_NU:g} (where our map's transitions lie)")
    if (verdict is Verdict.FAIL and given == "bullet"
            and lam < ELONGATED_BRANCH_LAM_RATIO * _lam_c(nu)):
        verdict = Verdict.WARN
        why += (f"; below lam/lam_c = {ELONGATED_BRANCH_LAM_RATIO:g} an elongated bullet branch "
                "is also steady (our map build), Chen et al. found parachutes")
    return CheckResult("shape class", "shape_class", verdict, given, expected, distance,
                       TRANSITION_BAND_NU, "Chen et al. 2020 eq. transition", why, ref)


#: Monotone trends along a series at fixed nu and Ca_B: (quantity, +1 increasing / −1
#: decreasing with lam, check name). Not ell and h/R: at a bullet-parachute switch the length
#: drops (our map at Ca_B = 15: bullet at lam/lam_c = 0.3, shorter parachute at 0.4, nu
#: 0.6-0.75).
_TRENDS = (("V_over_U", -1, "V/U decreases with lam"),
           ("dp_plus_R0", +1, "dp+R0 increases with lam"))


def _series_key(kind: str, values: dict):
    """The series of a row of ``kind`` and ``values`` (:func:`trend_checks`), None for a
    drop."""
    if kind == "drop":
        return None
    ca_b = values.get("ca_b")
    return kind, round(values["nu"], 9), None if ca_b is None else round(ca_b, 9)


def _series_values(values: dict, errors: dict) -> tuple:
    """(λ, V/U, its uncertainty, Δp⁺R0/(ηU), its uncertainty): what a trend check needs of a
    row's ``values`` and ``errors``."""
    return (values["lam"], values["V_over_U"], errors["V_over_U"], *_dp_R0(values, errors))


def _trend_rank(step, tol):
    """Rank (0 pass, 1 warn, 2 fail) of a step along the trend (> 0: with it) whose two rows
    have the uncertainties ``tol`` together: a step against the trend warns within ``tol``
    (and a zero step with ``tol`` > 0), fails beyond. Floats or arrays."""
    warn = (-step < tol) | ((step == 0) & (tol > 0))
    return (step <= 0) * (2 - warn)


_BY_RANK = (Verdict.PASS, Verdict.WARN, Verdict.FAIL)


def _trend_pair(a: tuple, a_where: str, b: tuple) -> list[CheckResult]:
    """The trend checks of a row (series values ``b``) against the previous row of its series
    (values ``a``, named ``a_where``); values as :func:`_series_values`."""
    out = []
    for (quantity, sign, name), k in zip(_TRENDS, (1, 3)):
        va, ea, vb, eb = a[k], a[k + 1], b[k], b[k + 1]
        verdict = _BY_RANK[_trend_rank(sign * (vb - va), ea + eb)]
        out.append(CheckResult(name, quantity, verdict, vb, va, vb - va, ea + eb,
                               f"{a_where} (lam={a[0]:.4g})",
                               "series at fixed nu and Ca_B: a larger object in the same tube"))
    return out


def trend_checks(rows) -> dict:
    r"""Monotonicity along each series: rows of kind vesicle sharing ν and Ca_B (or both
    without Ca_B), and the rigid spheres, sorted by λ. A larger object in the same tube moves
    slower and disturbs the flow more: V/U decreases, Δp⁺R0/(ηU) increases (Chen et al. 2020
    figs. vel and dpa; every line of our map). A pair of rows against the trend fails, or warns
    when the step is within the two rows' uncertainties. Drops are not checked (the trends
    with λ at fixed Ca are not established for them). Returns {row index: [CheckResult of the
    row against the previous one of its series]}; :func:`check_summary` makes the same checks
    from a compact copy of the series values.
    """
    series = {}
    for row in rows:
        key = _series_key(row.kind, row.values)
        if key is not None:
            series.setdefault(key, []).append(row)
    out = {}
    for members in series.values():
        members = sorted(members, key=lambda r: r.get("lam"))
        for a, b in zip(members, members[1:]):
            if b.get("lam") > a.get("lam"):
                out[b.index] = _trend_pair(_series_values(a.values, a.errors), a.where,
                                           _series_values(b.values, b.errors))
    return out


# --------------------------------------------------------------------------- the report

@dataclass(frozen=True)
class RowReport:
    """The checks of one row, the notes (references that do not apply and why, assumptions),
    and its verdict (the worst check)."""
    row: Row
    checks: tuple
    notes: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "_verdict", _worst(map(_VERDICT_OF, self.checks)))

    @property
    def verdict(self) -> Verdict:
        return self._verdict

    def to_dict(self) -> dict:
        return {"row": self.row.index, "where": self.row.where, "name": self.row.name,
                "kind": self.row.kind, "verdict": self.verdict.value,
                "values": dict(self.row.values), "uncertainties": dict(self.row.errors),
                "converted": list(self.row.converted),
                "checks": [c.to_dict() for c in self.checks], "notes": list(self.notes)}


#: Most rows a summary lists (:func:`check_summary`: table, JSON, report): the failing rows
#: first, then those with warnings, then passing ones, each in file order. A table of
#: results has hundreds of rows; a million would make a JSON object of gigabytes.
MAX_LISTED_ROWS = 1000
#: Most failed checks quoted one per line (``failures`` of the JSON output).
MAX_FAILURE_LINES = 20


def _failure_line(r: RowReport, c: CheckResult) -> str:
    """One failed (or warning) check of a row, on one line."""
    return (f"{r.row.where}{' ' + r.row.name if r.row.name else ''}: {c.name} "
            f"{c.verdict.value.upper()}: value {format_cell(c.value)}, reference "
            f"{format_cell(c.reference)} ({c.source}), deviation {format_cell(c.deviation)}, "
            f"tolerance {format_cell(c.tolerance)}")


@dataclass(frozen=True)
class CheckReport:
    """Result of :func:`check_results` or :func:`check_summary`: the :class:`RowReport` of every
    row or of the rows listed (:data:`MAX_LISTED_ROWS`), the verdict counts of every row
    (``counts``: pass, warn, fail; computed from ``rows`` when not given), where the rows came
    from, the map used, the assumptions made and provenance."""
    rows: tuple
    source: str
    map_source: str
    assumptions: tuple = ()
    provenance: dict = dataclasses.field(default_factory=dict)
    #: the map the references were read from (a SolutionMap, or why there was none)
    solution_map: object = dataclasses.field(default=None, repr=False, compare=False)
    counts: dict = None

    def __post_init__(self):
        if self.counts is None:
            object.__setattr__(self, "counts", {v.value: sum(r.verdict is v for r in self.rows)
                                                for v in Verdict})

    @property
    def verdict(self) -> Verdict:
        return (Verdict.FAIL if self.counts["fail"] else Verdict.WARN if self.counts["warn"]
                else Verdict.PASS)

    @property
    def n_rows(self) -> int:
        """Number of rows checked."""
        return sum(self.counts.values())

    @property
    def omitted(self) -> int:
        """Number of rows checked but not listed in ``rows``."""
        return self.n_rows - len(self.rows)

    def listing(self) -> str:
        """Which rows ``rows`` holds, in a sentence ("" when it holds every row)."""
        if not self.omitted:
            return ""
        listed = {v.value: sum(r.verdict is v for r in self.rows) for v in Verdict}
        left = ", ".join(f"{self.counts[v] - listed[v]} {v}" for v in listed)
        return (f"{len(self.rows)} of the {self.n_rows} rows are listed (failing rows first, "
                f"then rows with warnings, then passing rows, each in file order); the other "
                f"{self.omitted} rows ({left}) are counted only")

    def failures(self, include_warnings: bool = False) -> list[tuple[RowReport, CheckResult]]:
        """(row, check) of every failed check (and warning, if asked) of the rows in
        ``rows``, in row order."""
        bad = {Verdict.FAIL, Verdict.WARN} if include_warnings else {Verdict.FAIL}
        return [(r, c) for r in self.rows for c in r.checks if c.verdict in bad]

    def failure_lines(self, limit: int | None = MAX_FAILURE_LINES) -> list[str]:
        """The first ``limit`` failed checks, one line each (:meth:`failures`)."""
        return [_failure_line(r, c) for r, c in self.failures()[:limit]]

    def to_dict(self) -> dict:
        out = {"verdict": self.verdict.value, "counts": self.counts, "source": self.source,
               "map": self.map_source, "assumptions": list(self.assumptions),
               "tolerance_rule": TOLERANCE_RULE, "rows": [r.to_dict() for r in self.rows],
               "rows_total": self.n_rows, "rows_omitted": self.omitted}
        if self.omitted:
            out["rows_note"] = self.listing()
        out["failures"] = self.failure_lines()
        out["provenance"] = dict(self.provenance)
        return out

    def format_table(self) -> str:
        """A fixed-width table, one line per check of the rows in ``rows`` (row, check,
        verdict, value, reference, deviation, tolerance, reference used), then their notes and
        a summary (with :meth:`listing` when rows were left out)."""
        head = ("row", "check", "verdict", "value", "reference", "deviation", "tolerance",
                "reference used")
        cells = [head]
        for r in self.rows:
            label = str(r.row.index) + (f" {r.row.name}" if r.row.name else "")
            for c in r.checks:
                cells.append((label, c.name, c.verdict.value.upper() if c.verdict is not
                              Verdict.PASS else "pass", *(format_cell(x) for x in (
                                  c.value, c.reference, c.deviation, c.tolerance)), c.source))
        widths = [max(len(str(line[i])) for line in cells) for i in range(len(head) - 1)]
        lines = []
        for k, line in enumerate(cells):
            lines.append("  ".join(str(x).ljust(w) for x, w in zip(line, widths)) + "  "
                         + line[-1])
            if k == 0:
                lines.append("  ".join("-" * w for w in widths) + "  " + "-" * 14)
        notes = [f"row {r.row.index}: {n}" for r in self.rows for n in r.notes]
        counts = ", ".join(f"{n} {v}" for v, n in self.counts.items())
        return "\n".join([f"Consistency check of {self.source} (map: {self.map_source})",
                          *lines, "", *(["notes:"] + notes if notes else []),
                          *[f"assumption: {a}" for a in self.assumptions],
                          f"rule: {TOLERANCE_RULE}",
                          *([f"listed: {self.listing()}"] if self.omitted else []),
                          f"rows: {counts}; verdict: {self.verdict.value.upper()}"])


def format_cell(x) -> str:
    """A value of a check in a table: 6 significant digits (enough to see a deviation of
    1e-4 relative), "—" when there is none."""
    if x is None:
        return "—"
    return f"{x:.6g}" if isinstance(x, float) else str(x)


#: The tolerance and verdict rule in one line (reports and tables print it).
TOLERANCE_RULE = (f"tolerance = reference error + the row's uncertainty (its *_err, else half a "
                  f"unit of the last digit written); pass within 1x, warn within "
                  f"{WARN_FACTOR:g}x, fail beyond; a hard bound fails when violated by more "
                  f"than the row's uncertainty")

#: Names of the reference checks of the columns.
_VS_REFERENCE = {"V_over_U": "V/U vs reference", "dp_plus_R0": "dp+R0 vs reference",
                 "dp_plus_R": "dp+R vs reference", "ell": "ell vs reference",
                 "film_min": "h/R vs reference"}


def _reference(row: Row, quantity: str, bem: bool, m) -> Reference | str:
    """The most accurate reference of ``quantity`` for the row (module docstring, step 2), or
    the reasons there is none; ``m`` the resolved map (:func:`_resolve_map`)."""
    v, reasons = row.values, []
    lam, nu = v["lam"], v.get("nu", 1.0)
    if row.kind == "drop":
        tries = ((drop_reference, (lam, v.get("ca"), quantity, bem)),
                 (small_object_reference, ("drop", lam, quantity, 1.0, v.get("ca"))))
    elif row.kind == "sphere" or nu == 1.0:
        tries = ((sphere_reference, (lam, quantity, bem)),
                 (small_object_reference, ("sphere", lam, quantity)))
    else:
        ref = _map_ref(nu, lam, v.get("ca_b", DEFAULT_CA_B), quantity, m)
        if isinstance(ref, Reference):         # most vesicle rows: inside the map
            return ref
        reasons.append(ref)
        tries = ((near_critical_reference, (nu, lam, quantity)),
                 (small_object_reference, ("vesicle", lam, quantity, nu, None, v.get("ca_b"))))
    for attempt, args in tries:
        ref = attempt(*args)
        if isinstance(ref, Reference):
            return ref
        reasons.append(ref)
    return "; ".join(reasons)


def _row_checks(row: Row, bem: bool, solution_map) -> tuple[list, list, bool]:
    """Every check of one row except the series (module docstring), the notes, and whether
    the object fits the tube (else only the bounds are checked)."""
    checks, passes = _bound_checks(row)
    notes = []
    if not passes:
        return checks, ["references skipped: the object cannot be in this tube"], False
    for quantity in ("V_over_U", "dp_plus_R0", "ell", "film_min"):
        if quantity == "dp_plus_R0":
            key, value, err, factor = _dp(row)
        elif quantity in row.values:
            key, value, err, factor = quantity, row.values[quantity], row.errors[quantity], 1.0
        else:
            continue
        ref = _reference(row, quantity, bem, solution_map)
        if isinstance(ref, Reference):
            checks.append(_compare(_VS_REFERENCE[key], key, value, err, ref, factor))
        else:
            notes.append(f"{quantity}: no reference ({ref})")
    for relation in (chen_film_scaling_check, shape_volume_area_checks):
        result = relation(row)
        if isinstance(result, CheckResult):
            checks.append(result)
        elif isinstance(result, list):
            checks.extend(result)
    if "shape_class" in row.values:
        result = shape_class_check(row, solution_map)
        if isinstance(result, CheckResult):
            checks.append(result)
        else:
            notes.append(f"shape_class: no reference ({result})")
    return checks, notes, True


# --------------------------------------------------------------------------- reading and checking

#: Rank of a row whose check waits for the second pass (:func:`check_summary`): it needs a
#: solver.
_DEFERRED = 3


def _needs_solver(kind: str, nu: float, bem: bool) -> bool:
    """Whether a row's references come from a BEM solve (a rigid sphere, a vesicle of ν = 1,
    a drop; :func:`sphere_reference`, :func:`drop_reference`)."""
    return bem and (kind != "vesicle" or nu == 1.0)


#: Codes of the kinds of rows in a series (:func:`_series_key`; 0: in none).
_SERIES_KINDS = {"vesicle": 1, "sphere": 2}


def _series_numbers(kind, nu, ca_b) -> np.ndarray:
    """The series number of each row (−1: in none) from its series key (:func:`_series_key`)
    as arrays: the kind's code (0: in none), ν and Ca_B (−1: none), all rounded as the key
    is. Rows of equal keys share a number; a million rows of distinct keys take a few arrays,
    not a million keys."""
    order = np.lexsort((ca_b, nu, kind))
    k, a, b = kind[order], nu[order], ca_b[order]
    new = np.ones(len(order), dtype=bool)
    new[1:] = (k[1:] != k[:-1]) | (a[1:] != a[:-1]) | (b[1:] != b[:-1])
    numbers = np.empty(len(order), dtype=np.int64)
    numbers[order] = np.cumsum(new) - 1
    numbers[kind == 0] = -1
    return numbers


def _previous(series, lam) -> np.ndarray:
    """For each row, the index (0-based) of the row it is checked against in its series (-1:
    none), as :func:`trend_checks` pairs them: ``series`` the series number of each row (-1:
    in none), ``lam`` its λ."""
    inside = np.flatnonzero(series >= 0)
    order = inside[np.lexsort((lam[inside], series[inside]))]   # stable: file order for ties
    before, after = order[:-1], order[1:]
    step = (series[after] == series[before]) & (lam[after] > lam[before])
    previous = np.full(len(series), -1, dtype=np.int64)
    previous[after[step]] = before[step]
    return previous


class _Part(NamedTuple):
    """The first pass over one chunk of rows (:func:`_survey_part`): per row its rank (0 pass,
    1 warn, 2 fail, :data:`_DEFERRED`), its series key (:func:`_series_key`) in three arrays
    (``series``: the kind's code in :data:`_SERIES_KINDS`, 0 in none; ν; Ca_B, −1 for none),
    what its series checks need (5 numbers) and its line (0 for none); the vesicle rows
    without ca_b (their number and the first 10), whether a row is a sphere, a drop or of
    ν = 1, and the reports that may be listed: ``kept``, a list of ((rank, −n), (row, checks,
    notes)), the ``keep`` of highest rank among the failing or warning rows and the passing
    rows among the first ``keep`` of the file (the rows listed in the end are among these
    unless a series check makes them worse)."""
    last: int
    ranks: bytes
    series: tuple
    values: array.array
    lines: array.array
    default_ca: tuple
    solid: bool
    kept: list


def _survey_part(chunk: list, bem: bool, m, keep: int | None) -> _Part:
    """The first pass over ``chunk`` = [(row number, line, cells)]: each row parsed (an
    :class:`InputError` names the first bad one) and, unless it needs a solver, checked, after
    the batched functions were filled for all of them (:func:`_prepare`)."""
    parsed = [(n, line, parse_row(cells, n, _where(n, line))) for n, line, cells in chunk]
    _prepare([row for _, _, row in parsed], bem, m)
    kinds, nus, cas = array.array("b"), array.array("d"), array.array("d")
    values, lines, ranks = array.array("d"), array.array("q"), array.array("b")
    kept, default_ca, first, solid = [], 0, [], False
    none = (math.nan,) * 5
    for n, line, row in parsed:
        v, kind = row.values, row.kind
        nu, lam = v.get("nu", 1.0), v["lam"]
        if kind == "vesicle" and nu < 1.0 and "ca_b" not in v:
            default_ca += 1
            if len(first) < 10:
                first.append(n)
        solid = solid or kind != "vesicle" or nu == 1.0
        key = None if kind == "drop" or lam >= _lam_c(nu) else _series_key(kind, v)
        kinds.append(0 if key is None else _SERIES_KINDS[key[0]])
        nus.append(0.0 if key is None else key[1])
        cas.append(-1.0 if key is None or key[2] is None else key[2])
        values.extend(none if key is None else _series_values(v, row.errors))
        lines.append(line or 0)
        if _needs_solver(kind, nu, bem):
            ranks.append(_DEFERRED)
            continue
        checks, notes, _ = _row_checks(row, bem, m)
        rank = _worst(map(_VERDICT_OF, checks)).rank
        ranks.append(rank)
        if rank or keep is None or n <= keep:
            _offer(kept, keep, (rank, -n), (row, checks, notes))
    return _Part(parsed[-1][0], ranks.tobytes(), (kinds, nus, cas), values, lines,
                 (default_ca, first), solid, kept)


#: Rows read, parsed and prepared together (:func:`_parts`): enough that the batched
#: computations cost little per row, few enough that a chunk takes a few MB.
CHUNK_ROWS = 2048
#: The arguments (bem, map, keep) of the chunks a worker process checks (:func:`_parts`): set
#: before the processes are forked, which inherit them (a map is not sent to each).
_WORKER = None


def _workers() -> int:
    """Processes that check chunks besides the one that reads them: the cores this process
    may use, at most 2 (none with one core, or where processes cannot be forked)."""
    if "fork" not in multiprocessing.get_all_start_methods():
        return 0
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return min(2, cores or 1) if (cores or 1) > 1 else 0


def _start_worker() -> None:
    """A worker process ignores Ctrl-C (the reading process stops it) and collects reference
    cycles less often: what it inherited is set aside (``gc.freeze``) and a collection waits
    for 20 000 new objects instead of 700. A chunk makes about a hundred short-lived objects a
    row and no cycles; the default made the collector a tenth of a worker's time."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    gc.freeze()
    gc.set_threshold(20_000, *gc.get_threshold()[1:])


def _survey_in_worker(chunk: list) -> _Part | None:
    """:func:`_survey_part` in a worker process; None where it raised (the reading process
    then checks the chunk itself, which raises the same error at the same row)."""
    try:
        return _survey_part(chunk, *_WORKER)
    except Exception:               # noqa: BLE001 - redone by the reading process, which raises
        return None


def _chunks(rows, progress, size: int = CHUNK_ROWS):
    """``rows`` (``(row number, line, cells)``) in lists of ``size``; ``progress(n)`` is
    called as row n is read for every n divisible by :data:`PROGRESS_ROWS`."""
    rows = iter(rows)
    while True:
        chunk = list(itertools.islice(rows, size))
        if not chunk:
            return
        if progress is not None:
            for n in range(chunk[0][0] + -chunk[0][0] % PROGRESS_ROWS, chunk[-1][0] + 1,
                           PROGRESS_ROWS):
                progress(n)
        yield chunk


def _parts(rows, bem: bool, m, keep: int | None, progress=None):
    """The :class:`_Part` of each chunk of ``rows`` (:func:`_chunks`), in order. The first chunk
    is checked here; from the second on, with more than one core, worker processes (forked:
    they share the map read) check the chunks while this one reads the next, a few chunks
    ahead at most (bounded memory); a chunk whose worker raised, or whose worker died, is
    checked here. Ctrl-C stops the workers (they ignore it themselves)."""
    global _WORKER
    chunks = _chunks(rows, progress)
    for chunk in itertools.islice(chunks, 1):
        yield _survey_part(chunk, bem, m, keep)
    workers = _workers()
    if not workers:
        yield from (_survey_part(chunk, bem, m, keep) for chunk in chunks)
        return
    _WORKER = (bem, m, keep)
    pool = concurrent.futures.ProcessPoolExecutor(
        workers, mp_context=multiprocessing.get_context("fork"), initializer=_start_worker)
    pending = collections.deque()

    def done() -> _Part:
        chunk, future = pending.popleft()
        try:
            part = future.result()
        except concurrent.futures.process.BrokenProcessPool:
            part = None
        return _survey_part(chunk, bem, m, keep) if part is None else part
    try:
        for chunk in chunks:
            pending.append((chunk, pool.submit(_survey_in_worker, chunk)))
            if len(pending) > 2 * workers:
                yield done()
        while pending:
            yield done()
    except BaseException:
        # stopped (Ctrl-C, an error, the reader gone): the chunks on their way are of no use,
        # so the workers end now instead of finishing them (terminate_workers from Python
        # 3.14; before, the executor's own table of its processes)
        stop = getattr(pool, "terminate_workers", None)
        for process in [] if stop else list(pool._processes.values()):
            process.terminate()
        if stop:
            stop()
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        _WORKER = None


class _Survey:
    """The first pass over the rows (:func:`check_summary`), chunk by chunk (:func:`_parts`):
    each row parsed (an :class:`InputError` before anything is printed or solved) and, unless
    it needs a solver, checked; kept per row, in arrays: its rank (0 pass, 1 warn, 2 fail,
    :data:`_DEFERRED`), its series, what its series checks need (:func:`_series_values`) and
    its line, about 60 bytes a row. ``kept``: row number -> (row, checks, notes) of the
    ``keep`` checked rows of highest rank before the series checks (None: all), most of which
    are listed in the end."""

    def __init__(self, rows, bem: bool, m, keep: int | None, progress=None):
        ranked, self.solid = [], False
        self.default_ca = [0, []]           # vesicle rows without ca_b: number, the first 10
        series = array.array("b"), array.array("d"), array.array("d")
        self.values, self.lines, ranks = array.array("d"), array.array("q"), array.array("b")
        n = 0
        for part in _parts(rows, bem, m, keep, progress):
            n = part.last
            count, first = part.default_ca
            self.default_ca[0] += count
            self.default_ca[1] += first[:10 - len(self.default_ca[1])]
            self.solid = self.solid or part.solid
            for whole, chunk in zip(series, part.series):
                whole.extend(chunk)
            self.values.extend(part.values)
            self.lines.extend(part.lines)
            ranks.frombytes(part.ranks)
            for key, item in part.kept:
                _offer(ranked, keep, key, item)
        self.n = n
        self.kept = {-key[1]: item for key, item in ranked}
        values = np.frombuffer(self.values, dtype=float).reshape(n, 5)
        self.previous = _previous(_series_numbers(*(np.frombuffer(a, dtype=a.typecode)
                                                    for a in series)), values[:, 0])
        self.rank = np.frombuffer(ranks, dtype=np.int8).astype(np.int64)
        b = np.flatnonzero((self.previous >= 0) & (self.rank != _DEFERRED))
        a = self.previous[b]
        for (_, sign, _), k in zip(_TRENDS, (1, 3)):       # as _trend_pair, for every row
            step = sign * (values[b, k] - values[a, k])
            self.rank[b] = np.maximum(self.rank[b], _trend_rank(step, values[a, k + 1]
                                                                + values[b, k + 1]))

    def trend(self, n: int) -> list[CheckResult]:
        """The series checks of row ``n`` (:func:`_trend_pair`)."""
        a = int(self.previous[n - 1])
        if a < 0:
            return []
        return _trend_pair(tuple(self.values[5 * a:5 * a + 5]),
                           _where(a + 1, self.lines[a] or None),
                           tuple(self.values[5 * n - 5:5 * n]))


def _prepare(rows: list, bem: bool, m) -> None:
    """Fill the batched functions (:class:`_Batched`) for the checks of ``rows``: λc of every
    row, and for the vesicle rows that fit the tube and need no solver the map's quantities
    where the row lies inside the map (``m`` the resolved map), else the near-critical laws
    where δ ≤ 0.1, and Chen et al.'s film scaling where a length is given and 0.02 ≤ δ ≤ 0.1:
    the values :func:`_row_checks` then asks of them one row at a time."""
    _lam_c.fill([r.values.get("nu", 1.0) for r in rows])
    vesicles = []
    for r in rows:
        v = r.values
        nu, lam = v.get("nu", 1.0), v["lam"]
        if r.kind == "vesicle" and nu < 1.0 and lam < _lam_c(nu):
            vesicles.append((nu, lam, lam / _lam_c(nu), v.get("ca_b", DEFAULT_CA_B), v))
    if not isinstance(m, _NoMap):
        _map_queries.fill(*zip(*[(nu, ratio, ca_b, m) for nu, _, ratio, ca_b, _ in vesicles]))
    near, film = [], []
    hi = asymptotics.NEAR_CRITICAL_RANGE.bounds[0][2]
    lo_film, hi_film = CHEN_FILM_SCALING_RANGE
    for nu, lam, ratio, ca_b, v in vesicles:
        delta = 1.0 - lam / _lam_c(nu)
        if delta <= hi and (isinstance(m, _NoMap)
                            or isinstance(_map_queries(nu, ratio, ca_b, m), str)):
            near.append((nu, lam))
        ell = v.get("ell")
        if ell is not None and ell > 0 and lo_film <= delta <= hi_film:
            film.append((lam, delta))
    for batched, points in ((_near_critical_laws, near), (_chen_film_slope, film)):
        batched.fill(*zip(*points))


def _offer(ranked: list, keep: int | None, key: tuple, item) -> None:
    """Keep ``item`` in ``ranked`` if its ``key`` is among the ``keep`` highest so far (a heap
    of (key, item), the lowest on top; None: keep all)."""
    if keep is None:
        ranked.append((key, item))
    elif len(ranked) < keep:
        heapq.heappush(ranked, (key, item))
    elif keep and key > ranked[0][0]:
        heapq.heapreplace(ranked, (key, item))


#: Rows between two calls of :func:`check_summary`'s ``progress`` (a second or less of rows
#: that need a map query).
PROGRESS_ROWS = 2000


def check_summary(rows_or_path, *, bem: bool = True, solution_map=None,
                  keep: int | None = MAX_LISTED_ROWS, progress=None) -> CheckReport:
    r"""The consistency check of ``rows_or_path`` in bounded memory: the verdict counts of
    every row and the :class:`RowReport` of at most ``keep`` rows (None: all), the failing ones
    first, then those with warnings, then passing ones, each in file order (listed in file
    order).

    The first pass reads, converts and checks the rows as they come, in chunks of
    :data:`CHUNK_ROWS` (a CSV file as a stream, :func:`correlations.files.open_text`; a JSON
    file whole, at most :data:`MAX_JSON_ROWS_BYTES`; the chunks checked in worker processes
    where there are cores for them, :func:`_parts`) and keeps of each row only its verdict and
    what the series checks need (λ, V/U, Δp⁺R0/(ηU), their uncertainties: about 60 bytes a
    row), besides the reports of the ``keep`` worst rows so far. A row that needs a solver (a
    BEM reference of a sphere or a drop) waits, so that bad input anywhere raises
    :class:`InputError` before any solver runs. Then the series checks of all rows are made together, which completes every verdict.
    A second pass, only if needed, reads the rows again up to the last one it needs: those to
    be listed whose report was not kept (a series check made them worse) and the rows that
    need a solver (a second or so per (λ, Ca), cached), each checked once.

    Parameters and errors as :func:`check_results`; ``keep`` >= 0 or None; ``progress(n)``, if
    given, is called in the first pass after every :data:`PROGRESS_ROWS` rows read. A file that
    changes between the two passes raises :class:`InputError`.
    """
    if keep is not None and keep < 0:
        raise InvalidParameterError("keep", keep, "keep >= 0 or None")
    source, rows, path = _source(rows_or_path)
    m = _resolve_map(solution_map)
    stat = None if path is None else os.stat(path)
    survey = _Survey(rows(), bem, m, keep, progress)
    deferred = survey.rank == _DEFERRED
    counts = np.bincount(survey.rank[~deferred], minlength=3)
    checked = np.flatnonzero(~deferred)
    listed = checked[np.argsort(-survey.rank[checked], kind="stable")[:keep]] + 1
    needed = deferred.copy()
    ranked = []                     # the reports listed: a heap of ((rank, -index), report)
    for n in listed.tolist():
        if n in survey.kept:
            row, checks, notes = survey.kept[n]
            r = RowReport(row, tuple(checks + survey.trend(n)), tuple(notes))
            _offer(ranked, keep, (r.verdict.rank, -n), r)
        else:
            needed[n - 1] = True
    survey.kept = None
    last = int(np.flatnonzero(needed)[-1]) + 1 if needed.any() else 0
    for n, line, cells in (rows() if last else ()):
        if needed[n - 1]:
            row = parse_row(cells, n, _where(n, line))
            checks, notes, _ = _row_checks(row, bem, m)
            r = RowReport(row, tuple(checks + survey.trend(n)), tuple(notes))
            if deferred[n - 1]:
                counts[r.verdict.rank] += 1
            _offer(ranked, keep, (r.verdict.rank, -n), r)
        if n >= last:
            break
    if stat is not None:
        now = os.stat(path)
        if (now.st_size, now.st_mtime_ns) != (stat.st_size, stat.st_mtime_ns):
            raise InputError(source, FILE, source, "a file that stays unchanged while it is "
                             "checked", "it changed between the two readings")
    assumptions = []
    count, first = survey.default_ca
    if count:
        shown = ", ".join(map(str, first)) + (", ..." if count > len(first) else "")
        assumptions.append(f"{count} vesicle rows without ca_b (rows {shown}): the "
                           f"map was read at Ca_B = {DEFAULT_CA_B:g} (Chen et al. 2020 §IV.A: "
                           "shapes virtually independent of Ca_B >= 50); give ca_b")
    if not bem and survey.solid:
        assumptions.append("BEM references skipped (bem=False): spheres and drops are checked "
                           "against the small-object laws only, where they are valid")
    return CheckReport(tuple(sorted((r for _, r in ranked), key=lambda r: r.row.index)), source,
                       str(m) if isinstance(m, _NoMap) else m.source, tuple(assumptions),
                       provenance(), m, {v.value: int(counts[v.rank]) for v in Verdict})


def check_results(rows_or_path, *, bem: bool = True, solution_map=None) -> CheckReport:
    r"""Check every row of ``rows_or_path`` against the physics and the references.

    Parameters
    ----------
    rows_or_path : str, Path or list of dict
        A CSV or JSON file or the rows themselves (:func:`read_rows`; columns :data:`COLUMNS`
        and :data:`ERROR_COLUMNS`). Every row is read and converted before any check.
    bem : bool
        Compute the BEM references of sphere and drop rows (about a second per (λ, Ca),
        cached); False skips them (the small-object laws remain where valid).
    solution_map : None, False, str, Path or SolutionMap
        The map of the vesicle references: None the shipped one, False none, or a packed map
        file (InvalidParameterError naming ``map`` if it is not one).

    Returns
    -------
    CheckReport
        Per row its checks (:class:`CheckResult`), notes and verdict; the module docstring
        gives the checks, tolerances and verdicts. It holds every row: for a large file,
        :func:`check_summary` keeps a bounded part.

    Raises
    ------
    InputError
        For any row or column that cannot be used (naming the row and column), before any
        check; :class:`correlations.files.UnreadableFile` for a file that cannot be read.
        Both are :class:`~lubrication.checks.InvalidParameterError`.

    Examples
    --------
    >>> rep = check_results([{"kind": "sphere", "lam": 0.1, "V_over_U": 1.9867,
    ...                       "dp_plus_R0": 1.6e-5}], bem=False, solution_map=False)
    >>> rep.verdict.value, [c.name for c in rep.rows[0].checks][:3]
    ('pass', ['lam < lam_c', '1 <= V/U < 2', 'dp+ > 0'])
    """
    return check_summary(rows_or_path, bem=bem, solution_map=solution_map, keep=None)


def assert_consistent(rows_or_path, *, allow_warnings: bool = True, **options) -> CheckReport:
    """:func:`check_results`, raising AssertionError that lists every failed check (and every
    warning when ``allow_warnings`` is False); returns the report otherwise. For a user's own
    tests::

        def test_my_solver_agrees_with_vesicle_tube():
            assert_consistent("my_results.csv", bem=False)
    """
    report = check_results(rows_or_path, **options)
    bad = report.failures(include_warnings=not allow_warnings)
    if bad:
        lines = [_failure_line(r, c) for r, c in bad]
        raise AssertionError(f"{len({id(r) for r, _ in bad})} of {len(report.rows)} rows not "
                             f"consistent ({report.source}):\n" + "\n".join(lines))
    return report
