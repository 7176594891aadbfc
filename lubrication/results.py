r"""Result of the lubrication solver: scalars, profiles, diagnostics and provenance.

Units of the fields (project scaling, see :mod:`lubrication.geometry`): lengths in tube radii
:math:`R` (``dp_plus_R0`` is the exception its name states), velocities by the mean velocity
:math:`U`, stresses and pressures by :math:`\eta U/R`, tensions by :math:`\eta U`, curvatures in
:math:`1/R` with the sign convention of the model (negative where the surface is convex).

A result whose ``success`` is False carries NaN in every physical scalar and empty profiles:
only the inputs, ``message`` and the diagnostics are meaningful then. Its :meth:`to_dict` holds
None for those scalars, and :meth:`LubricationResult.save` writes only the JSON (no profile CSV).

In :meth:`LubricationResult.to_dict` (and the saved JSON) every number is finite: NaN and
infinity are written as None (JSON null; the policy of :mod:`lubrication.io`). The one infinite
input, ``ca_b = inf`` of the high-Ca model, is therefore ``"ca_b": null`` beside ``"model":
"high-Ca"``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .io import clean_json, save_json, save_result

__all__ = ["LubricationResult", "PROFILE_COLUMNS"]

# Columns of the CSV written by LubricationResult.save, with their units.
PROFILE_COLUMNS = (
    ("s", "arc length from the rear pole [R]"),
    ("x", "axial position from the rear pole [R]"),
    ("r", "membrane radius [R]"),
    ("psi", "tilt angle [rad]"),
    ("pressure", "gap pressure minus inside pressure [eta U / R]"),
    ("tension", "isotropic membrane tension [eta U]"),
    ("shear_membrane", "viscous shear stress on the membrane [eta U / R]"),
    ("shear_wall", "viscous shear stress on the wall [eta U / R]"),
)


@dataclass(frozen=True, eq=False)      # eq=False: arrays have no truth value; compare fields
class LubricationResult:
    r"""Steady vesicle in a tube from the lubrication model (:func:`lubrication.solve.solve_lubrication`).

    Inputs
        ``nu`` reduced volume, ``lam`` = R0/R, ``lam_c`` critical confinement, ``ca_b`` =
        ηUR0²/κ (``inf`` for the high-Ca model; None in :meth:`to_dict`), ``model``
        ("high-Ca" or "bending").
    Outcome
        ``success`` (all acceptance checks passed), ``message``.
    Scalars
        ``V_over_U``; ``Q`` = 1 − U/V; ``dp_plus_R0`` = Δp⁺R0/(ηU); ``dp_plus_R`` = Δp⁺R/(ηU);
        ``ell`` = L/R, front pole to rearmost point; ``film_min`` minimum gap h/R;
        ``tension_front``, ``tension_rear``,
        ``tension_max`` [ηU]; ``curvature_rear``, ``curvature_front`` principal curvature at the
        poles [1/R] (negative = convex); ``shape_class`` "parachute" if the rear is concave
        (curvature_rear > 0, or the rear pole lies ahead of the rearmost point of the membrane,
        as in deep parachutes whose cavity floor is convex again), else "bullet".
    Profiles (from rear pole to front pole, poles included)
        ``s``, ``x``, ``r``, ``psi``, ``pressure``, ``tension``, ``shear_membrane``,
        ``shear_wall`` (units in :data:`PROFILE_COLUMNS`).
    Diagnostics
        ``force_balance_residual`` (net axial force on the vesicle over the scale of its
        pressure force), ``area_error`` and ``volume_error`` (relative, by quadrature of the
        solution), ``n_nodes``, ``max_residual`` (largest relative collocation residual),
        ``tol``, ``timings`` [s], ``provenance`` (versions), ``solver_state`` (mesh, unknowns
        and parameters in model units, for warm starts).
    """

    # Declared field by field like the other results on purpose: declarations, not repeated logic.
    nu: float
    lam: float
    lam_c: float
    ca_b: float
    model: str
    success: bool
    message: str
    V_over_U: float = math.nan
    Q: float = math.nan
    dp_plus_R0: float = math.nan
    dp_plus_R: float = math.nan
    ell: float = math.nan
    film_min: float = math.nan
    tension_front: float = math.nan
    tension_rear: float = math.nan
    tension_max: float = math.nan
    curvature_rear: float = math.nan
    curvature_front: float = math.nan
    shape_class: str = ""
    s: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    x: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    r: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    psi: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    pressure: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    tension: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    shear_membrane: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    shear_wall: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    force_balance_residual: float = math.nan
    area_error: float = math.nan
    volume_error: float = math.nan
    n_nodes: int = 0
    max_residual: float = math.nan
    tol: float = math.nan
    timings: dict = field(default_factory=dict, repr=False)
    provenance: dict = field(default_factory=dict, repr=False)
    solver_state: Any = field(default=None, repr=False, compare=False)

    @property
    def lam_ratio(self) -> float:
        """lam / lam_c."""
        return self.lam / self.lam_c

    @property
    def delta(self) -> float:
        """Clearance parameter 1 - lam/lam_c."""
        return 1.0 - self.lam / self.lam_c

    @property
    def converged(self) -> bool:
        """Alias of ``success``."""
        return self.success

    def to_dict(self) -> dict:
        """Scalars, diagnostics and provenance as a strict-JSON-ready dict.

        NaN and infinity become None: the physical scalars of a failed solve, and ``ca_b`` of
        the high-Ca model (``"ca_b": None, "model": "high-Ca"``).
        """
        keys = ("nu", "lam", "lam_c", "ca_b", "model", "success", "message", "V_over_U", "Q",
                "dp_plus_R0", "dp_plus_R", "ell", "film_min", "tension_front", "tension_rear",
                "tension_max", "curvature_rear", "curvature_front", "shape_class",
                "force_balance_residual", "area_error", "volume_error", "n_nodes",
                "max_residual", "tol", "timings", "provenance")
        out = {k: clean_json(getattr(self, k)) for k in keys}
        if not self.success:
            out["shape_class"] = None          # no shape from a failed solve
        out["lam_ratio"] = clean_json(self.lam_ratio)
        out["delta"] = clean_json(self.delta)
        out["converged"] = bool(self.success)
        return out

    def profiles(self) -> dict[str, np.ndarray]:
        """The profiles of :data:`PROFILE_COLUMNS` as a dict of equal-length arrays."""
        return {name: np.asarray(getattr(self, name)) for name, _ in PROFILE_COLUMNS}

    def save(self, directory, stem: str | None = None) -> tuple[Path, ...]:
        """Write ``<stem>.json`` (scalars) and ``<stem>.csv`` (profiles) into ``directory``.

        Each file is written to a temporary file in the same directory and renamed, so an
        interrupted run never leaves a half-written file. The default stem encodes the inputs,
        e.g. ``lubrication_nu0.9_lam1.2000_high-Ca``. A failed solve (``success`` False) has no
        profiles: only the JSON is written (``"converged": false``, the reason, null physical
        values), with ``_failed`` in the stem. Returns the paths written.
        """
        if stem is None:
            stem = f"lubrication_nu{self.nu:.4g}_lam{self.lam:.6g}_{self.model}"
            if self.model == "bending":
                stem += f"_caB{self.ca_b:.4g}"
            if not self.success:
                stem += "_failed"
        if not self.success:
            return (save_json(directory, stem, self.to_dict()),)
        return save_result(directory, stem, self.to_dict(), PROFILE_COLUMNS,
                           lambda name: np.asarray(getattr(self, name)))
