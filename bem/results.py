"""Result of a BEM computation: a frozen dataclass with inputs, outputs, accuracy and provenance.

Every result derives from :class:`lubrication.results.SolverResult`: ``status`` (a
:class:`lubrication.results.Status`) and ``message`` say how the solve ended, ``success`` is
``status is Status.CONVERGED``; :meth:`~lubrication.results.SolverResult.to_dict` and
:meth:`~lubrication.results.SolverResult.save` (atomic JSON and CSV through
:mod:`lubrication.io`, non-finite numbers as null) are that class's. The vesicle result also
has the fields of :class:`lubrication.results.VesicleSolution`, which the lubrication result
shares.

Output hygiene: a result that did not converge keeps its best numbers as attributes (for
diagnosis in Python), but every *output* of it -- :meth:`to_dict`, the JSON and CSV files of
``save``, the CLI tables built from them -- reports its physical quantities as None (JSON
null, CSV without profile rows) next to ``"converged": false``, the status and the message;
only diagnostics (residuals, error estimates of the refinement pair, timings) are kept.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from lubrication.io import clean_json
from lubrication.results import SolverResult, VesicleSolution, profile_field

from .shape import SpectralCurve

__all__ = ["DROP_PROFILE_COLUMNS", "VESICLE_PROFILE_COLUMNS", "DropResult", "SphereResult",
           "VesicleResult"]


@dataclass(frozen=True, kw_only=True)
class SphereResult(SolverResult):
    """Rigid sphere of radius a = lam R on the axis of a tube (BEM).

    Scalings: U the mean velocity of the undisturbed Poiseuille flow, eta the viscosity.
    ``lam`` = a/R; ``dp_plus_R0`` is Δp⁺a/(ηU). ``status`` is CONVERGED when every relative
    error estimate met ``tol`` (fields of :class:`lubrication.results.SolverResult`).

    Attributes
    ----------
    drag_K : float
        Drag of the sphere translating at V through fluid at rest far away (zero net flux),
        K = F/(6π η a V) [-].
    dp_translating_R : float
        Pressure rise Δp R/(ηV) across the translating sphere (upstream minus downstream;
        negative: the sphere pushes the fluid) [-].
    *_err : float
        Error estimates: absolute difference between the reported (fine) solution and the
        coarse one of the refinement pair (conservative for the observed high order).
    panels, panels_coarse : dict
        Panel counts (body, wall, inlet) and Gauss order of the fine and coarse meshes.
    residual : float
        max ``|A z - b|`` / max ``|b|`` of the fine linear system.
    null_multiplier : float
        Multiplier of the null-vector bordering column (0 for the exact solution).
    """

    drag_K: float = math.nan
    dp_translating_R: float = math.nan
    V_over_U_err: float = math.nan
    dp_plus_R_err: float = math.nan
    drag_K_err: float = math.nan
    panels: dict = field(default_factory=dict)
    panels_coarse: dict = field(default_factory=dict)
    half_length: float = math.nan
    residual: float = math.nan
    null_multiplier: float = math.nan

    PHYSICAL: ClassVar[tuple[str, ...]] = SolverResult.PHYSICAL + ("drag_K", "dp_translating_R")

    def default_stem(self) -> str:
        """``bem_sphere_lam<lam>``."""
        return f"bem_sphere_lam{self.lam:.6g}"


@dataclass(frozen=True, eq=False, kw_only=True)
class _SpectralSolution(SolverResult):
    """What the spectral BEM results (:class:`DropResult`, :class:`VesicleResult`) share: the
    refinement's accuracy and cost, the spectral shape of the fine solution and its
    :meth:`curve`, and the ``shape`` entry of :meth:`to_dict` (the ``SHAPE`` fields).

    Attributes
    ----------
    error_estimate : dict
        Estimated discretisation error (absolute) of the main outputs.
    residual : float
        Steady-state residual of the fine solution, largest over its nodes [U].
    residual_tol : float
        Largest accepted ``residual`` [U].
    panels : dict
        Panel counts, Gauss order and shape modes of the fine mesh.
    iterations : dict
        Newton iterations, BEM evaluations and difference Jacobians per stage.
    modes, density : ndarray
        Spectral shape of the fine solution (:class:`bem.shape.SpectralCurve`), for warm
        starts.
    """

    error_estimate: dict = field(default_factory=dict)
    residual: float = math.nan
    residual_tol: float = math.nan
    panels: dict = field(default_factory=dict)
    iterations: dict = field(default_factory=dict)
    modes: np.ndarray = profile_field()
    density: np.ndarray = profile_field()

    #: arrays written as the ``shape`` entry of :meth:`to_dict`
    SHAPE: ClassVar[tuple[str, ...]] = ("x", "r", "modes", "density")

    def curve(self):
        """The fine solution's :class:`bem.shape.SpectralCurve` (centroid at x = 0)."""
        return SpectralCurve.with_volume_radius(self.modes, self.lam, density=self.density)

    def to_dict(self, shape: bool = True) -> dict:
        """:meth:`lubrication.results.SolverResult.to_dict`; with ``shape`` also the ``SHAPE``
        arrays as lists under ``"shape"`` (None unless converged)."""
        out = super().to_dict()
        if shape:
            out["shape"] = (clean_json({k: getattr(self, k) for k in self.SHAPE})
                            if self.success else None)
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


@dataclass(frozen=True, eq=False, kw_only=True)
class DropResult(_SpectralSolution):
    r"""Steady clean drop (viscosity ratio 1, constant tension) on the axis of a tube (BEM).

    Scalings: R = 1, U the mean velocity of the undisturbed Poiseuille flow, eta the viscosity;
    ``lam`` = R0/R with R0 the drop's volume radius, ``ca`` = ηU/γ.

    A result that did not converge carries the best numbers found (NaN where there are none);
    ``status`` and ``message`` say why (no convergence, no steady shape, a drop touching the
    wall, refinement pair disagreeing, the time limit) and callers must not use the numbers as
    converged.

    Attributes
    ----------
    lam, ca : float
        Inputs [-].
    status : Status
        CONVERGED: steady state found on both meshes of the refinement pair, pair agreement
        within ``tol`` and pointwise residual within ``residual_tol``.
    V_over_U, dp_plus_R, dp_plus_R0 : float
        Drop velocity over U, extra pressure drop at fixed flow rate Δp⁺R/(ηU) and
        Δp⁺R0/(ηU) [-].
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
    iterations, timings : dict
        Newton iterations, BEM evaluations and difference Jacobians per stage; wall-clock
        seconds per stage and in total.
    modes, density : ndarray
        Spectral shape of the fine solution, for warm starts.
    """

    ca: float
    length: float = math.nan
    max_radius: float = math.nan
    film: float = math.nan
    curvature_front: float = math.nan
    curvature_rear: float = math.nan
    volume_error: float = math.nan
    panels_coarse: dict = field(default_factory=dict)
    half_length: float = math.nan
    x: np.ndarray = profile_field()
    r: np.ndarray = profile_field()
    s: np.ndarray = profile_field()
    psi: np.ndarray = profile_field()
    kappa1: np.ndarray = profile_field()
    kappa2: np.ndarray = profile_field()
    shape_length: float = field(default=math.nan, metadata={"in_dict": False})

    PHYSICAL: ClassVar[tuple[str, ...]] = SolverResult.PHYSICAL + (
        "length", "max_radius", "film", "curvature_front", "curvature_rear")
    PROFILE_COLUMNS: ClassVar[tuple[tuple[str, str], ...]] = DROP_PROFILE_COLUMNS

    def default_stem(self) -> str:
        """``bem_drop_lam<lam>_ca<ca>``."""
        return f"bem_drop_lam{self.lam:.6g}_ca{self.ca:.6g}"


# Columns of the CSV written by VesicleResult.save, with their units.
VESICLE_PROFILE_COLUMNS = (
    ("s", "arc length from the rear pole [R]"),
    ("x", "axial position from the rear pole [R]"),
    ("r", "membrane radius [R]"),
    ("psi", "tangent angle from the axis [rad]"),
    ("tension", "membrane tension gamma, Lagrange multiplier of inextensibility [eta U]"),
    ("shear_membrane", "viscous shear stress on the membrane, -dgamma/ds [eta U / R]"),
)


@dataclass(frozen=True, eq=False, kw_only=True)
class VesicleResult(_SpectralSolution, VesicleSolution):
    r"""Steady vesicle (inextensible Helfrich membrane, viscosity ratio 1) in a tube (BEM).

    Scalings: R = 1, U the mean velocity of the undisturbed Poiseuille flow, eta the viscosity;
    ``nu`` reduced volume, ``lam`` = R0/R, ``lam_c`` critical confinement, ``ca_b`` = ηUR0²/κ;
    a red-cell membrane (shear elasticity, :mod:`bem.shear`) has ``ca_s`` = ηU/G_s and its
    stress-free shape ``reference`` (inf and None for a vesicle).
    The fields of :class:`lubrication.results.VesicleSolution` (V/U, Δp⁺, length, film,
    tensions, curvatures in the convention of
    :class:`lubrication.results.LubricationResult`, shape class, the profiles s, x, r,
    tension, shear_membrane) and of the spectral BEM results, and:

    A result that did not converge carries the best numbers found (NaN where there are none)
    and must not be used as converged; ``status`` and ``message`` say why.

    Attributes
    ----------
    ell, ell_poles : float
        Length L/R, the full axial extent from the front pole to the rearmost point (the rim
        of a parachute; what a microscope measures and Chen et al.'s ℓ), and the pole-to-pole
        distance [R].
    wall_shear_max : float
        Largest shear stress on the tube wall [ηU/R], equal to the largest wall shear rate
        [U/R] (η = 1); Poiseuille flow alone gives 4.
    wall_x, wall_shear : ndarray
        Wall shear stress profile τ_w(x) at the wall nodes (x from the rear pole, as ``x``)
        [R, ηU/R] (:meth:`bem.vesicle.VesicleOperator.wall_shear`).
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
        Origin of the initial shape that converged ("seed bank (...)", "lubrication",
        "spheroid", "initial", "continuation ...").
    failed_starts : list
        The starts tried before it, each with the reason it failed (:func:`bem.vesicle.solve_vesicle`).
    other_branch : dict
        Where a steady state of the other shape class also exists at this point (a bistable
        point): its ``shape_class``, ``seed`` and V_over_U, dp_plus_R0, ell, film_min; else
        empty.
    psi : ndarray
        Tangent angle from the axis, rear to front pole, see :data:`VESICLE_PROFILE_COLUMNS`.
    tension_modes : ndarray
        Spectral tension coefficients of the fine solution (warm starts).
    """

    ell_poles: float = math.nan
    wall_shear_max: float = math.nan
    refinement: list = field(default_factory=list)
    seed: str = ""
    failed_starts: list = field(default_factory=list)
    other_branch: dict = field(default_factory=dict)
    psi: np.ndarray = profile_field()
    tension_modes: np.ndarray = profile_field()
    wall_x: np.ndarray = profile_field()
    wall_shear: np.ndarray = profile_field()

    PHYSICAL: ClassVar[tuple[str, ...]] = VesicleSolution.PHYSICAL + ("ell_poles",
                                                                        "wall_shear_max")
    PROFILE_COLUMNS: ClassVar[tuple[tuple[str, str], ...]] = VESICLE_PROFILE_COLUMNS
    DERIVED: ClassVar[tuple[str, ...]] = ("lam_ratio", "bie_solves")
    SHAPE: ClassVar[tuple[str, ...]] = ("x", "r", "tension", "modes", "density",
                                        "tension_modes", "wall_x", "wall_shear")

    @property
    def bie_solves(self) -> int:
        """Boundary-integral solves (BEM evaluations) of the whole solve, continuation rungs
        included (to compare with the time steps of a time-marching solver)."""
        return int(sum(v.get("evaluations", 0) for v in self.iterations.values()))

    def default_stem(self) -> str:
        """``bem_vesicle_nu<nu>_lam<lam>_cab<ca_b>[_cas<ca_s>_<reference>]``."""
        stem = f"bem_vesicle_nu{self.nu:.6g}_lam{self.lam:.6g}_cab{self.ca_b:.6g}"
        return stem if self.reference is None else f"{stem}_cas{self.ca_s:.6g}_{self.reference}"

    def to_dict(self, shape: bool = True) -> dict:
        """As for every spectral result; the ``refinement`` history of a result that did not
        converge keeps only (modes, residual) per level."""
        out = super().to_dict(shape)
        if not self.success:
            out["refinement"] = [[clean_json(level[0]), clean_json(level[1]), None, None, None]
                                 for level in self.refinement]
        return out
