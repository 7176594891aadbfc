"""Result of a BEM computation: a frozen dataclass with inputs, outputs, accuracy and provenance.

Saved as JSON through a temporary file in the target directory and :func:`os.replace`, so an
interrupted run never leaves a half-written file; non-finite numbers are written as null and
the provenance is that of :func:`lubrication.io.provenance` (:mod:`lubrication.io`).

Output hygiene: a result that did not converge keeps its best numbers as attributes (for
diagnosis in Python), but every *output* of it -- :meth:`to_dict`, the JSON and CSV files of
``save``, the CLI tables built from them -- reports its physical quantities as None (JSON
null, CSV without profile rows) next to ``"converged": false`` and the message; only
diagnostics (residuals, error estimates of the refinement pair, timings) are kept.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from lubrication.io import clean_json, provenance, save_json, save_result

__all__ = ["DROP_PROFILE_COLUMNS", "VESICLE_PROFILE_COLUMNS", "DropResult", "SphereResult",
           "VesicleResult"]


@dataclass(frozen=True)
class SphereResult:
    """Rigid sphere of radius a = lam R on the axis of a tube (BEM).

    Scalings: U the mean velocity of the undisturbed Poiseuille flow, eta the viscosity.

    Attributes
    ----------
    lam : float
        a/R [-].
    V_over_U : float
        Velocity of the force-free sphere in Poiseuille flow over U [-].
    dp_plus_R, dp_plus_R0 : float
        Extra pressure drop at fixed flow rate, Δp⁺R/(ηU) and Δp⁺a/(ηU) [-].
    drag_K : float
        Drag of the sphere translating at V through fluid at rest far away (zero net flux),
        K = F/(6π η a V) [-].
    dp_translating_R : float
        Pressure rise Δp R/(ηV) across the translating sphere (upstream minus downstream;
        negative: the sphere pushes the fluid) [-].
    *_err : float
        Error estimates: absolute difference between the reported (fine) solution and the
        coarse one of the refinement pair (conservative for the observed high order).
    converged : bool
        Whether every relative error estimate met ``tol``.
    panels, panels_coarse : dict
        Panel counts (body, wall, inlet) and Gauss order of the fine and coarse meshes.
    residual : float
        max ``|A z - b|`` / max ``|b|`` of the fine linear system.
    null_multiplier : float
        Multiplier of the null-vector bordering column (0 for the exact solution).
    """

    lam: float
    V_over_U: float
    dp_plus_R: float
    dp_plus_R0: float
    drag_K: float
    dp_translating_R: float
    V_over_U_err: float
    dp_plus_R_err: float
    drag_K_err: float
    converged: bool
    tol: float
    panels: dict
    panels_coarse: dict
    half_length: float
    residual: float
    null_multiplier: float
    timings: dict
    provenance: dict = field(default_factory=provenance)
    message: str = ""

    #: physical outputs, None in the output of an unconverged result
    PHYSICAL = ("V_over_U", "dp_plus_R", "dp_plus_R0", "drag_K", "dp_translating_R")

    def to_dict(self) -> dict:
        """Plain dict of JSON-compatible values (non-finite floats become None; the physical
        outputs are None when the result did not converge)."""
        out = clean_json(dataclasses.asdict(self))
        if not self.converged:
            out.update(dict.fromkeys(self.PHYSICAL))
        return out

    def save(self, directory, name: str | None = None) -> Path:
        """Write ``<directory>/<name>.json`` atomically; returns the path."""
        return save_json(directory, name or f"bem_sphere_lam{self.lam:.6g}", self.to_dict())


class _SpectralSolution:
    """What the spectral BEM results (:class:`DropResult`, :class:`VesicleResult`) share: the
    ``converged`` alias, the fine solution's curve and the scalar part of ``to_dict``."""

    @property
    def converged(self) -> bool:
        """Alias of ``success`` (the CLI's key)."""
        return self.success

    def curve(self):
        """The fine solution's :class:`bem.shape.SpectralCurve` (centroid at x = 0)."""
        from .shape import SpectralCurve
        return SpectralCurve.closed(self.modes, volume=4.0 / 3.0 * math.pi * self.lam**3,
                                    density=self.density)

    def _scalar_dict(self) -> dict:
        """``_SCALARS`` as JSON values and ``converged``; the ``PHYSICAL`` outputs None unless
        ``success``."""
        out = {k: clean_json(getattr(self, k)) for k in self._SCALARS}
        out["converged"] = bool(self.success)
        if not self.success:
            out.update(dict.fromkeys(self.PHYSICAL))
        return out


# Columns of the CSV written by DropResult.save, with their units.
DROP_PROFILE_COLUMNS = (
    ("s", "arc length from the rear pole [R]"),
    ("x", "axial position, drop centroid at 0 [R]"),
    ("r", "interface radius [R]"),
    ("psi", "tangent angle from the axis [rad]"),
    ("kappa1", "meridional curvature, positive for a sphere [1/R]"),
    ("kappa2", "azimuthal curvature, positive for a sphere [1/R]"),
)


@dataclass(frozen=True, eq=False)      # eq=False: arrays have no truth value
class DropResult(_SpectralSolution):
    r"""Steady clean drop (viscosity ratio 1, constant tension) on the axis of a tube (BEM).

    Scalings: R = 1, U the mean velocity of the undisturbed Poiseuille flow, eta the viscosity;
    ``lam`` = R0/R with R0 the drop's volume radius, ``ca`` = ηU/γ.

    A result whose ``success`` is False carries the best numbers found (NaN where there are
    none); ``message`` says why it failed (no convergence, no steady shape, a drop touching the
    wall, refinement pair disagreeing) and callers must not use the numbers as converged.

    Attributes
    ----------
    lam, ca : float
        Inputs [-].
    success : bool
        Steady state found on both meshes of the refinement pair, pair agreement within
        ``tol`` and pointwise residual within ``residual_tol``.
    V_over_U : float
        Drop velocity over U [-].
    dp_plus_R, dp_plus_R0 : float
        Extra pressure drop at fixed flow rate, Δp⁺R/(ηU) and Δp⁺R0/(ηU) [-].
    error_estimate : dict
        ``|fine − coarse|`` of the refinement pair for V_over_U, dp_plus_R and dp_plus_R0: an upper
        bound of the fine result's error when the error falls at least like N^-1.7 in the
        number N of modes (observed: faster, ~spectral; the Richardson estimate
        ``|f − c|``/((N_f/N_c)^p − 1) with the observed order p is much smaller).
    length, max_radius, film : float
        Drop length x_front − x_rear, largest radius and smallest gap 1 − max r [R].
    curvature_front, curvature_rear : float
        Curvature at the front and rear pole (both principal curvatures are equal there)
        [1/R]; negative = concave.
    x, r, s, psi, kappa1, kappa2 : ndarray
        Shape from rear to front pole (poles included), see :data:`DROP_PROFILE_COLUMNS`.
    volume_error : float
        Relative error of the volume computed by the panel quadrature of the fine mesh against
        4πλ³/3 (the parametrisation imposes the volume; this measures the geometry).
    residual : float
        Steady-state residual max ``|u·n − V n_x|`` over the fine mesh's nodes [U].
    panels, panels_coarse : dict
        Drop, wall and inlet panel counts, Gauss order and shape modes of the two meshes.
    iterations : dict
        Newton iterations, BEM evaluations and difference Jacobians per stage.
    timings : dict
        Wall-clock seconds per stage and in total.
    modes, density : ndarray
        Spectral shape of the fine solution (:class:`bem.shape.SpectralCurve`), for warm
        starts.
    """

    # Declared field by field like the other results on purpose: declarations, not repeated logic.
    lam: float
    ca: float
    success: bool
    message: str
    V_over_U: float = math.nan
    dp_plus_R: float = math.nan
    dp_plus_R0: float = math.nan
    error_estimate: dict = field(default_factory=dict)
    length: float = math.nan
    max_radius: float = math.nan
    film: float = math.nan
    curvature_front: float = math.nan
    curvature_rear: float = math.nan
    volume_error: float = math.nan
    residual: float = math.nan
    tol: float = math.nan
    residual_tol: float = math.nan
    panels: dict = field(default_factory=dict)
    panels_coarse: dict = field(default_factory=dict)
    half_length: float = math.nan
    iterations: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    x: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    r: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    s: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    psi: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    kappa1: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    kappa2: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    modes: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    density: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    shape_length: float = math.nan
    provenance: dict = field(default_factory=provenance, repr=False)

    _SCALARS = ("lam", "ca", "success", "message", "V_over_U", "dp_plus_R", "dp_plus_R0",
                "error_estimate", "length", "max_radius", "film", "curvature_front",
                "curvature_rear", "volume_error", "residual", "tol", "residual_tol", "panels",
                "panels_coarse", "half_length", "iterations", "timings", "provenance")
    #: physical outputs, None in the output of an unconverged result
    PHYSICAL = ("V_over_U", "dp_plus_R", "dp_plus_R0", "length", "max_radius", "film",
                "curvature_front", "curvature_rear")

    def to_dict(self, shape: bool = True) -> dict:
        """Scalars, diagnostics and provenance as a JSON-ready dict (non-finite -> None; the
        physical outputs and the shape are None when ``success`` is False).

        With ``shape`` the profile arrays x, r and the modes are included as lists.
        """
        out = self._scalar_dict()
        if shape:
            out["shape"] = (clean_json({"x": self.x, "r": self.r, "modes": self.modes,
                                        "density": self.density}) if self.success else None)
        return out

    def save(self, directory, stem: str | None = None) -> tuple[Path, Path]:
        """Write ``<stem>.json`` (scalars, with the modes) and ``<stem>.csv`` (shape profile).

        Each file goes to a temporary file in ``directory`` and is renamed, so an interrupted
        run never leaves a half-written file. Default stem ``bem_drop_lam<lam>_ca<ca>``.
        """
        stem = stem or f"bem_drop_lam{self.lam:.6g}_ca{self.ca:.6g}"
        return save_result(directory, stem, self.to_dict(), DROP_PROFILE_COLUMNS,
                           lambda name: _profile_column(self, name))


def _profile_column(result, name: str) -> np.ndarray:
    """Profile column ``name`` for the CSV: empty (header only) for an unconverged result."""
    return np.asarray(getattr(result, name)) if result.success else np.empty(0)


# Columns of the CSV written by VesicleResult.save, with their units.
VESICLE_PROFILE_COLUMNS = (
    ("s", "arc length from the rear pole [R]"),
    ("x", "axial position from the rear pole [R]"),
    ("r", "membrane radius [R]"),
    ("psi", "tangent angle from the axis [rad]"),
    ("tension", "membrane tension gamma, Lagrange multiplier of inextensibility [eta U]"),
    ("shear_membrane", "viscous shear stress on the membrane, -dgamma/ds [eta U / R]"),
)


@dataclass(frozen=True, eq=False)      # eq=False: arrays have no truth value
class VesicleResult(_SpectralSolution):
    r"""Steady vesicle (inextensible Helfrich membrane, viscosity ratio 1) in a tube (BEM).

    Scalings: R = 1, U the mean velocity of the undisturbed Poiseuille flow, eta the viscosity;
    ``nu`` reduced volume, ``lam`` = R0/R, ``lam_c`` critical confinement, ``ca_b`` = ηUR0²/κ.

    A result whose ``success`` is False carries the best numbers found (NaN where there are
    none) and must not be used as converged; ``message`` says why.

    Attributes
    ----------
    V_over_U : float
        Vesicle velocity over U [-].
    dp_plus_R0, dp_plus_R : float
        Extra pressure drop at fixed flow rate, Δp⁺R0/(ηU) and Δp⁺R/(ηU) [-].
    ell, ell_poles, film_min : float
        Length L/R, the full axial extent from the front pole to the rearmost point (the rim
        of a parachute; what a microscope measures and Chen et al.'s ℓ), the pole-to-pole
        distance, and the smallest gap 1 − max r [R].
    tension_max, tension_rear, tension_front : float
        Largest tension and its pole values [ηU].
    wall_shear_max : float
        Largest shear stress on the tube wall [ηU/R], equal to the largest wall shear rate
        [U/R] (η = 1); Poiseuille flow alone gives 4.
    wall_x, wall_shear : ndarray
        Wall shear stress profile τ_w(x) at the wall nodes (x from the rear pole, as ``x``)
        [R, ηU/R] (:meth:`bem.vesicle.VesicleOperator.wall_shear`).
    curvature_rear, curvature_front : float
        Principal curvature at the poles in the convention of
        :class:`lubrication.results.LubricationResult` (negative where convex) [1/R].
    shape_class : str
        "parachute" (concave rear, or the rear pole ahead of the rearmost point) or "bullet".
    error_estimate : dict
        Estimated discretisation error (absolute) of V_over_U, dp_plus_R0, tension_max: the
        extrapolated tail of the consistent ladder's differences (module docstring of
        :mod:`bem.vesicle`), or ``|fine − coarse|`` of the pair for a given ``n_modes``.
    volume_error, area_error : float
        Relative errors of the volume and area by panel quadrature of the fine mesh.
    residual : float
        max ``|u − V e_x|`` over the membrane nodes of the fine mesh (both components) [U].
    refinement : list
        (modes, residual, V/U, Δp⁺R0/(ηU), γ_max) of every level solved.
    seed : str
        Origin of the initial shape ("lubrication", "spheroid", "initial", "continuation ...").
    s, x, r, psi, tension, shear_membrane : ndarray
        Profiles from rear to front pole, see :data:`VESICLE_PROFILE_COLUMNS`.
    modes, density, tension_modes : ndarray
        Spectral shape and tension coefficients of the fine solution (warm starts).
    """

    # Declared field by field like the other results on purpose: declarations, not repeated logic.
    nu: float
    lam: float
    lam_c: float
    ca_b: float
    success: bool
    message: str
    V_over_U: float = math.nan
    dp_plus_R0: float = math.nan
    dp_plus_R: float = math.nan
    ell: float = math.nan
    ell_poles: float = math.nan
    film_min: float = math.nan
    tension_max: float = math.nan
    wall_shear_max: float = math.nan
    tension_rear: float = math.nan
    tension_front: float = math.nan
    curvature_rear: float = math.nan
    curvature_front: float = math.nan
    shape_class: str = ""
    error_estimate: dict = field(default_factory=dict)
    volume_error: float = math.nan
    area_error: float = math.nan
    residual: float = math.nan
    tol: float = math.nan
    residual_tol: float = math.nan
    panels: dict = field(default_factory=dict)
    refinement: list = field(default_factory=list)
    seed: str = ""
    iterations: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    s: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    x: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    r: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    psi: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    tension: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    shear_membrane: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    modes: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    density: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    tension_modes: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    wall_x: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    wall_shear: np.ndarray = field(default_factory=lambda: np.empty(0), repr=False)
    provenance: dict = field(default_factory=provenance, repr=False)

    @property
    def lam_ratio(self) -> float:
        return self.lam / self.lam_c

    @property
    def bie_solves(self) -> int:
        """Boundary-integral solves (BEM evaluations) of the whole solve, continuation rungs
        included (to compare with the time steps of a time-marching solver)."""
        return int(sum(v.get("evaluations", 0) for v in self.iterations.values()))

    _SCALARS = ("nu", "lam", "lam_c", "ca_b", "success", "message", "V_over_U", "dp_plus_R0",
                "dp_plus_R", "ell", "ell_poles", "film_min", "tension_max", "wall_shear_max",
                "tension_rear", "tension_front",
                "curvature_rear", "curvature_front", "shape_class", "error_estimate",
                "volume_error", "area_error", "residual", "tol", "residual_tol", "panels",
                "refinement", "seed", "iterations", "timings", "provenance")
    #: physical outputs, None in the output of an unconverged result
    PHYSICAL = ("V_over_U", "dp_plus_R0", "dp_plus_R", "ell", "ell_poles", "film_min",
                "tension_max",
                "wall_shear_max", "tension_rear", "tension_front", "curvature_rear",
                "curvature_front", "shape_class")

    def to_dict(self, shape: bool = True) -> dict:
        """Scalars, diagnostics and provenance as a JSON-ready dict (non-finite -> None; the
        physical outputs and the shape are None when ``success`` is False, and the
        ``refinement`` history keeps only (modes, residual) per level).

        With ``shape`` the profiles x, r, tension and the spectral coefficients are included.
        """
        out = self._scalar_dict()
        out["lam_ratio"] = clean_json(self.lam_ratio)
        out["bie_solves"] = self.bie_solves
        if not self.success:
            out["refinement"] = [[clean_json(level[0]), clean_json(level[1]), None, None, None]
                                 for level in self.refinement]
        if shape:
            out["shape"] = (clean_json({k: getattr(self, k) for k in
                                        ("x", "r", "tension", "modes", "density",
                                         "tension_modes", "wall_x", "wall_shear")})
                            if self.success else None)
        return out

    def save(self, directory, stem: str | None = None) -> tuple[Path, Path]:
        """Write ``<stem>.json`` and ``<stem>.csv`` (profiles) atomically into ``directory``.
        Default stem ``bem_vesicle_nu<nu>_lam<lam>_cab<ca_b>``."""
        stem = stem or f"bem_vesicle_nu{self.nu:.6g}_lam{self.lam:.6g}_cab{self.ca_b:.6g}"
        return save_result(directory, stem, self.to_dict(), VESICLE_PROFILE_COLUMNS,
                           lambda name: _profile_column(self, name))
