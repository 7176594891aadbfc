r"""Solver results: the outcome :class:`Status`, the :class:`SolverResult` base every result of
every package derives from, and the lubrication solver's :class:`LubricationResult`.

**Outcome.** Every result and solver report carries ``status``, a :class:`Status` that says why
the solve ended (converged, not converged, unresolved, time limit, no steady state, rejected
start), and ``message``, the same in words with the numbers. ``success`` (and its alias
``converged``) is ``status is Status.CONVERGED``. Code that needs the reason compares the
status, never the message text.

**Output hygiene.** A result that did not converge keeps its best numbers as attributes (for
diagnosis in Python), but every *output* of it -- :meth:`SolverResult.to_dict`, the files of
:meth:`SolverResult.save`, the CLI tables built from them -- reports its physical quantities
(``PHYSICAL``) as None (JSON null; CSV without profile rows, or no CSV) next to ``"status"``,
``"success": false``, ``"converged": false`` and the message.

**Files.** ``to_dict`` holds strict JSON values: NaN and infinity are written as None (the
policy of :mod:`lubrication.io`), so the one infinite input, ``ca_b = inf`` of the high-Ca
model, is ``"ca_b": null`` beside ``"model": "high-Ca"``. ``save`` writes the JSON and the
profile CSV atomically through :mod:`lubrication.io`. Stored result dicts are read back with
:func:`status_of`, which also gives the status of files that hold none (only ``success`` and
``message``).

Units of :class:`LubricationResult` (project scaling, see :mod:`lubrication.geometry`): lengths
in tube radii :math:`R` (``dp_plus_R0`` is the exception its name states), velocities by the
mean velocity :math:`U`, stresses and pressures by :math:`\eta U/R`, tensions by
:math:`\eta U`, curvatures in :math:`1/R` with the sign convention of the model (negative where
the surface is convex). A failed lubrication solve carries NaN in every physical scalar and
empty profiles; its :meth:`~SolverResult.save` writes only the JSON (no profile CSV).
"""

from __future__ import annotations

import dataclasses
import enum
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from .io import clean_json, provenance, save_json, save_result

__all__ = ["LubricationResult", "NOT_IN_DICT", "Outcome", "PRECEDENCE", "PROFILE_COLUMNS",
           "SolverResult", "Status", "VesicleSolution", "leading_status", "profile_field",
           "status_of"]


class Status(str, enum.Enum):
    """Why a solve ended: the machine-readable outcome of every solver result and report.

    The values are the short strings written as ``"status"`` in the JSON of a result.
    """

    #: every acceptance test passed: residual, constraints and discretisation error
    CONVERGED = "converged"
    #: the iterations ended without meeting the residual (or steady-state) tolerance
    NOT_CONVERGED = "not converged"
    #: converged at each resolution, but the discretisation error estimate is above tolerance
    UNRESOLVED = "unresolved"
    #: stopped at the wall-time budget ``max_time``
    TIME_LIMIT = "time limit"
    #: none on this path: film closes, body touches the wall, membrane self-intersects, breakup
    NO_STEADY_STATE = "no steady state"
    #: the operator rejected every starting shape, so no iteration could start
    REJECTED_START = "rejected start"


#: The order in which one status explains a failure of several reasons (:func:`leading_status`):
#: a path without a steady state first (nothing else can help), then the time limit (more time
#: may), iterations that fell short, a discretisation error estimate, last a rejected start
#: (of several starts, e.g. of a map point, only when none could start).
PRECEDENCE = (Status.NO_STEADY_STATE, Status.TIME_LIMIT, Status.NOT_CONVERGED,
              Status.UNRESOLVED, Status.REJECTED_START)


def leading_status(found) -> Status:
    """The status of a solve whose checks found the statuses ``found`` (CONVERGED ones and
    repeats allowed): the first failure in :data:`PRECEDENCE`, CONVERGED if none.

    >>> leading_status([Status.UNRESOLVED, Status.NOT_CONVERGED])
    <Status.NOT_CONVERGED: 'not converged'>
    >>> leading_status([])
    <Status.CONVERGED: 'converged'>
    """
    found = set(found)
    return next((s for s in PRECEDENCE if s in found), Status.CONVERGED)


#: Phrases of the messages of stored results that hold no ``"status"``, by the status they
#: stand for, in the order of :data:`PRECEDENCE` (a message may join several reasons).
_MESSAGE_PHRASES = (
    (Status.NO_STEADY_STATE, ("film closes", "self-intersects", "no steady shape:",
                              "outside the lubrication model")),
    (Status.TIME_LIMIT, ("time limit",)),
    (Status.NOT_CONVERGED, ("not converged", "did not converge", "no convergence",
                            "steady residual", "Levenberg–Marquardt failed", "stuck")),
    (Status.UNRESOLVED, ("refinement pair differs", "discretisation error above")),
    (Status.REJECTED_START, ("initial shape rejected", "a shape rejected by the operator",
                             "cannot start", "InvalidParameterError: ")),
)


def status_of(record: dict) -> Status:
    """The :class:`Status` of a stored result dict (a result's ``to_dict``, a map point).

    Its ``"status"`` if it has one; otherwise (files that store only ``success`` or
    ``converged`` and ``message``) CONVERGED for a success, else the status whose phrase the
    message holds first in order of precedence (:data:`_MESSAGE_PHRASES`), NOT_CONVERGED if
    none. Raises ValueError for a ``"status"`` that is not a :class:`Status` value.

    Examples
    --------
    >>> status_of({"status": "time limit"}) is Status.TIME_LIMIT
    True
    >>> status_of({"success": False, "message": "own: the film closes (min gap 4e-04 R)"})
    <Status.NO_STEADY_STATE: 'no steady state'>
    """
    if record.get("status") is not None:
        return Status(record["status"])
    if record.get("success", record.get("converged")):
        return Status.CONVERGED
    message = str(record.get("message") or "")
    for status, phrases in _MESSAGE_PHRASES:
        if any(p in message for p in phrases):
            return status
    return Status.NOT_CONVERGED


class Outcome:
    """``success`` and ``converged`` of anything with a ``status`` (results, solver reports)."""

    status: Status

    @property
    def success(self) -> bool:
        """Whether the solve converged: ``status is Status.CONVERGED``."""
        return self.status is Status.CONVERGED

    @property
    def converged(self) -> bool:
        """Alias of ``success`` (the key of the command line's JSON)."""
        return self.success


#: metadata of the fields that :meth:`SolverResult.to_dict` leaves out (profiles, solver state)
NOT_IN_DICT = {"in_dict": False}


def _empty() -> np.ndarray:
    return np.empty(0)


def profile_field():
    """A dataclass field for an array (a profile or spectral coefficients): empty by default,
    left out of ``repr`` and of :meth:`SolverResult.to_dict`."""
    return field(default_factory=_empty, repr=False, metadata=NOT_IN_DICT)


@dataclass(frozen=True, eq=False, kw_only=True)    # eq=False: arrays have no truth value
class SolverResult(Outcome):
    r"""What every solver result shares: the outcome, the body's confinement, speed and extra
    pressure drop, the tolerance, timings and provenance; ``to_dict`` and ``save``.

    Scalings: R the tube radius, U the mean velocity of the undisturbed Poiseuille flow, eta
    the viscosity. Fields are keyword-only.

    Attributes
    ----------
    status : Status
        Why the solve ended (a :class:`Status` or its value).
    message : str
        The reason in words.
    lam : float
        Confinement: the body's radius (the volume radius R0 of a deformable one) over R [-].
    V_over_U : float
        Speed of the body over U [-].
    dp_plus_R, dp_plus_R0 : float
        Extra pressure drop at fixed flow rate, Δp⁺R/(ηU) and Δp⁺R0/(ηU) [-].
    tol : float
        Relative tolerance of the solve.
    timings : dict
        Wall-clock seconds per stage [s].
    provenance : dict
        Versions, commit and date (:func:`lubrication.io.provenance`).

    Class constants: ``PHYSICAL`` (outputs written as None unless converged),
    ``PROFILE_COLUMNS`` ((name, unit) of the CSV of :meth:`save`; empty: JSON only),
    ``DERIVED`` (properties written by :meth:`to_dict` besides the fields) and
    ``CSV_WHEN_FAILED`` (whether a failed result still writes its CSV, header only).
    """

    status: Status
    message: str = ""
    lam: float
    V_over_U: float = math.nan
    dp_plus_R: float = math.nan
    dp_plus_R0: float = math.nan
    tol: float = math.nan
    timings: dict = field(default_factory=dict)
    provenance: dict = field(default_factory=provenance, repr=False)

    PHYSICAL: ClassVar[tuple[str, ...]] = ("V_over_U", "dp_plus_R", "dp_plus_R0")
    PROFILE_COLUMNS: ClassVar[tuple[tuple[str, str], ...]] = ()
    DERIVED: ClassVar[tuple[str, ...]] = ()
    CSV_WHEN_FAILED: ClassVar[bool] = True

    def __post_init__(self):
        object.__setattr__(self, "status", Status(self.status))

    def default_stem(self) -> str:
        """File stem of :meth:`save` when none is given."""
        raise NotImplementedError

    def to_dict(self) -> dict:
        """Every field (but arrays and solver state) and the ``DERIVED`` properties as strict
        JSON values (non-finite numbers become None), with ``"status"`` (its value),
        ``"success"`` and ``"converged"``; the ``PHYSICAL`` outputs are None unless the solve
        converged."""
        out = {f.name: clean_json(getattr(self, f.name)) for f in dataclasses.fields(self)
               if f.metadata.get("in_dict", True)}
        out.update({name: clean_json(getattr(self, name)) for name in self.DERIVED})
        out.update(status=self.status.value, success=self.success, converged=self.success)
        if not self.success:
            out.update(dict.fromkeys(self.PHYSICAL))
        return out

    def profile(self, name: str) -> np.ndarray:
        """Profile column ``name`` for the CSV: empty (header only) unless converged."""
        return np.asarray(getattr(self, name)) if self.success else np.empty(0)

    def save(self, directory, stem: str | None = None) -> tuple[Path, ...]:
        """Write ``<stem>.json`` (:meth:`to_dict`) and, with ``PROFILE_COLUMNS``,
        ``<stem>.csv`` (the profiles, one row per point) into ``directory``.

        Each file is written to a temporary file in the same directory and renamed, so an
        interrupted run never leaves a half-written file. A result that did not converge
        writes the CSV with its header only, or no CSV if ``CSV_WHEN_FAILED`` is False.
        Default stem: :meth:`default_stem`. Returns the paths written.
        """
        stem = stem or self.default_stem()
        if not self.PROFILE_COLUMNS or not (self.success or self.CSV_WHEN_FAILED):
            return (save_json(directory, stem, self.to_dict()),)
        return save_result(directory, stem, self.to_dict(), self.PROFILE_COLUMNS, self.profile)


@dataclass(frozen=True, eq=False, kw_only=True)
class VesicleSolution(SolverResult):
    r"""What a steady vesicle in a tube reports, whichever the solver (lubrication or BEM).

    Inputs: ``nu`` reduced volume, ``lam`` = R0/R, ``lam_c`` critical confinement, ``ca_b`` =
    ηUR0²/κ (``inf`` for the high-Ca lubrication model); a red-cell membrane
    (:mod:`lubrication.membrane`) has ``ca_s`` = ηU/G_s and ``reference``, the name of its
    stress-free shape (``inf`` and None for a vesicle; ``ca_s`` None in ``to_dict``).

    Attributes
    ----------
    ell : float
        Length L/R, front pole to rearmost point (the rim of a parachute) [-].
    film_min : float
        Smallest gap h/R between membrane and wall [-].
    tension_front, tension_rear, tension_max : float
        Membrane tension at the poles and its largest value [ηU].
    curvature_rear, curvature_front : float
        Principal curvature at the poles, negative where convex [1/R].
    shape_class : str
        "parachute" (concave rear, or the rear pole ahead of the rearmost point) or "bullet".
    area_error, volume_error : float
        Relative errors of area and volume recomputed by quadrature of the solution.
    s, x, r, tension, shear_membrane : ndarray
        Profiles from the rear pole to the front pole: arc length and axial position from the
        rear pole [R], membrane radius [R], tension [ηU], viscous shear stress on the membrane
        [ηU/R].
    """

    nu: float
    lam_c: float
    ca_b: float
    ca_s: float = math.inf
    reference: str | None = None
    ell: float = math.nan
    film_min: float = math.nan
    tension_front: float = math.nan
    tension_rear: float = math.nan
    tension_max: float = math.nan
    curvature_rear: float = math.nan
    curvature_front: float = math.nan
    shape_class: str = ""
    area_error: float = math.nan
    volume_error: float = math.nan
    s: np.ndarray = profile_field()
    x: np.ndarray = profile_field()
    r: np.ndarray = profile_field()
    tension: np.ndarray = profile_field()
    shear_membrane: np.ndarray = profile_field()

    PHYSICAL: ClassVar[tuple[str, ...]] = SolverResult.PHYSICAL + (
        "ell", "film_min", "tension_front", "tension_rear", "tension_max", "curvature_rear",
        "curvature_front", "shape_class")
    DERIVED: ClassVar[tuple[str, ...]] = ("lam_ratio",)

    @property
    def lam_ratio(self) -> float:
        """lam / lam_c."""
        return self.lam / self.lam_c

    @property
    def delta(self) -> float:
        """Clearance parameter 1 - lam/lam_c."""
        return 1.0 - self.lam / self.lam_c


# Columns of the CSV written by LubricationResult.save, with their units.
PROFILE_COLUMNS = (
    ("s", "arc length from the rear pole [R]"),
    ("x", "axial position from the rear pole [R]"),
    ("r", "membrane radius [R]"),
    ("psi", "tilt angle [rad]"),
    ("pressure", "gap pressure minus inside pressure [eta U / R]"),
    ("tension", "isotropic membrane tension (mean of the principal tensions) [eta U]"),
    ("shear_membrane", "viscous shear stress on the membrane [eta U / R]"),
    ("shear_wall", "viscous shear stress on the wall [eta U / R]"),
    ("tension_s", "meridional principal tension [eta U]"),
    ("tension_phi", "azimuthal principal tension [eta U]"),
    ("stretch_phi", "azimuthal stretch r/r_ref of a red-cell membrane, empty for a vesicle [-]"),
)


@dataclass(frozen=True, eq=False, kw_only=True)
class LubricationResult(VesicleSolution):
    r"""Steady vesicle in a tube from the lubrication model (:func:`lubrication.solve.solve_lubrication`).

    The fields of :class:`VesicleSolution` (inputs, scalars, the profiles s, x, r, tension,
    shear_membrane) and:

    Inputs
        ``model`` ("high-Ca" or "bending"); ``ca_b`` is None in :meth:`to_dict` for the
        high-Ca model (inf); ``ca_s`` and ``reference`` as for every :class:`VesicleSolution`.
    Outcome
        ``status`` (CONVERGED when all acceptance checks passed), ``message``.
    Scalars
        ``Q`` = 1 − U/V; ``shape_class`` "parachute" if the rear is concave (curvature_rear >
        0, or the rear pole lies ahead of the rearmost point of the membrane, as in deep
        parachutes whose cavity floor is convex again), else "bullet".
    Profiles (from rear pole to front pole, poles included)
        ``psi``, ``pressure``, ``shear_wall`` besides the shared ones; the principal tensions
        ``tension_s`` (meridional) and ``tension_phi`` (azimuthal), whose mean is ``tension``
        (all three equal for a vesicle), and the azimuthal stretch ``stretch_phi`` =
        :math:`\lambda_\varphi = 1/\lambda_s` of a red-cell membrane (NaN for a vesicle; 1 at
        the poles). Units in :data:`PROFILE_COLUMNS`.
    Diagnostics
        ``force_balance_residual`` (net axial force on the vesicle over the scale of its
        pressure force), ``area_error`` and ``volume_error`` (relative, by quadrature of the
        solution), ``n_nodes``, ``max_residual`` (largest relative collocation residual),
        ``tol``, ``timings`` [s], ``provenance`` (versions), ``solver_state`` (mesh, unknowns
        and parameters in model units, for warm starts).
    """

    model: str
    Q: float = math.nan
    psi: np.ndarray = profile_field()
    pressure: np.ndarray = profile_field()
    shear_wall: np.ndarray = profile_field()
    tension_s: np.ndarray = profile_field()
    tension_phi: np.ndarray = profile_field()
    stretch_phi: np.ndarray = profile_field()
    force_balance_residual: float = math.nan
    n_nodes: int = 0
    max_residual: float = math.nan
    solver_state: Any = field(default=None, repr=False, compare=False, metadata=NOT_IN_DICT)

    PHYSICAL: ClassVar[tuple[str, ...]] = VesicleSolution.PHYSICAL + ("Q",)
    PROFILE_COLUMNS: ClassVar[tuple[tuple[str, str], ...]] = PROFILE_COLUMNS
    DERIVED: ClassVar[tuple[str, ...]] = ("lam_ratio", "delta")
    CSV_WHEN_FAILED: ClassVar[bool] = False

    def default_stem(self) -> str:
        """``lubrication_nu<nu>_lam<lam>_<model>[_caB<ca_b>][_caS<ca_s>_<reference>][_failed]``,
        e.g. ``lubrication_nu0.9_lam1.2000_high-Ca``."""
        stem = f"lubrication_nu{self.nu:.4g}_lam{self.lam:.6g}_{self.model}"
        if self.model == "bending":
            stem += f"_caB{self.ca_b:.4g}"
        if self.reference is not None:
            stem += f"_caS{self.ca_s:.4g}_{self.reference}"
        return stem if self.success else stem + "_failed"

    def profiles(self) -> dict[str, np.ndarray]:
        """The profiles of :data:`PROFILE_COLUMNS` as a dict of equal-length arrays."""
        return {name: np.asarray(getattr(self, name)) for name, _ in PROFILE_COLUMNS}
