r"""The inputs of the steady vesicle solver, checked before any BEM work, and its resource envelope.

:func:`~bem.vesicle.check_vesicle_inputs` checks every number :func:`bem.vesicle.solve_vesicle`
takes (ranges, and the envelope below) without loading numba, and returns them as a
:class:`~bem.vesicle.VesicleInputs`; the solver, the sweep (:mod:`bem.sweep`) and the map build
(:mod:`correlations.map_build`) call it first, so that bad input fails at once, naming the value.

Resource envelope:

* shape modes 8 <= n_modes, max_modes, rung_modes <= :data:`MAX_MODES` = 160 (the long vesicle at
  (0.6, 0.98 λc) needs 88–96; a slow, confined red cell more: (0.6, 0.9 λc, Ca_B 2.78,
  Ca_S 0.012) converges at 152 modes, 69 s from the same cell at 0.2 mm/s). A level of N modes
  has max(8, ceil(N/3)) panels; a level costs 2–6 s at 96–152 modes on 2 cores, and peak memory
  stays about 1 GB (measured 553 MB for the default solve at (0.6, 0.98 λc), 0.99 GB for that
  red cell at 152 modes).
* :data:`CA_B_MIN` = 0.01 <= Ca_B <= :data:`CA_B_MAX` = 1e5, the range of the lubrication
  solver that provides the initial shape (:mod:`lubrication.solve`; at 1e5 bending is within
  1e-6 of the high-Ca model). Ca_B = ηUR0²/κ is ~1–1000 for red blood cells (Chen et al.
  2020 use 50). Measured at (0.9, 1.0), 16 modes: Ca_B = 0.01 converges in 21 s; Ca_B = 1e308
  (bending load ~1e-308) used to run to a failed solve.
* ``max_time`` (:class:`lubrication.checks.Deadline`) is tested between BEM evaluations of
  Levenberg–Marquardt, between levels and between continuation rungs; when spent the result
  has status TIME_LIMIT and the deadline's message. Each level does at most ``max_iter``
  (40; valley: 320) iterations and 4–8 difference Jacobians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from lubrication.checks import Deadline, InvalidParameterError, check_positive, check_range
from lubrication.geometry import resolve_confinement
from lubrication.membrane import MembraneShear, reference_shape
from lubrication.solve import check_shear_inputs

from ..drop import mode_count as _drop_mode_count  # one check, the vesicle's MAX_MODES

__all__ = ["CA_B_MAX", "CA_B_MIN", "CA_S_RANGE", "MAX_MODES", "VesicleInputs",
           "check_vesicle_case", "check_vesicle_inputs", "mode_count"]

#: most shape modes of one level (resource envelope, module docstring)
MAX_MODES = 160
#: bending capillary numbers accepted (module docstring)
CA_B_MIN, CA_B_MAX = 1e-2, 1e5
#: shear capillary numbers ηU/G_s of a red cell accepted: from 1e-3 (0.005 mm/s for the
#: default cell, G_s = 6 µN/m in plasma), reached by continuation along the velocity
#: (:mod:`bem.vesicle.pipeline`; converged at (0.6, 0.3 λc, Ca_B 0.464, Ca_S 0.002) in 7 s), to
#: 1e4, above which the red cell is the vesicle within the tolerances (as for the lubrication
#: solver, :data:`lubrication.solve.CA_S_RANGE`)
CA_S_RANGE = (1e-3, 1e4)


@dataclass(frozen=True)
class VesicleInputs:
    """The checked inputs of one steady vesicle solve (:func:`~bem.vesicle.check_vesicle_inputs`),
    as Python numbers; the meaning of each is that of the parameter of
    :func:`bem.vesicle.solve_vesicle`.

    Attributes
    ----------
    nu, lam, lam_c, ca_b : float
        Reduced volume, confinement R0/R, its critical value lam_c(nu), Ca_B = ηUR0²/κ.
    n_modes, max_modes : int or None
        Shape modes of a single refinement pair, and of the ladder's last level (None: chosen
        from the vesicle's length).
    tol, tension_tol, residual_tol : float
        Tolerances of the error estimate (V/U and Δp⁺, γ_max) and of the steady residual.
    rung_modes, density_terms, max_iter : int
        Modes of each continuation rung, cosine terms of the arc-length density, iteration
        budget of each Levenberg–Marquardt level.
    ca_s, reference : float, str
        Shear capillary number ηU/G_s of a red-cell membrane (inf: a vesicle) and the name of
        its stress-free shape (:mod:`lubrication.membrane`).
    """

    nu: float
    lam: float
    lam_c: float
    ca_b: float
    n_modes: int | None
    tol: float
    tension_tol: float
    residual_tol: float
    max_modes: int | None
    rung_modes: int
    density_terms: int
    max_iter: int
    ca_s: float = math.inf
    reference: str = "biconcave"

    @property
    def lam_ratio(self) -> float:
        """λ/λc."""
        return self.lam / self.lam_c

    @property
    def shear(self) -> MembraneShear | None:
        """The membrane's shear elasticity in the solver's units (area in R²), None for a
        vesicle."""
        if math.isinf(self.ca_s):
            return None
        area = 4.0 * math.pi * (self.lam * self.nu ** (-1.0 / 3.0)) ** 2
        return MembraneShear(self.ca_s, reference_shape(self.reference, self.nu), area)

    @property
    def membrane(self) -> dict:
        """``ca_s`` and ``reference`` as a result stores them (reference None for a vesicle)."""
        return {"ca_s": self.ca_s,
                "reference": None if math.isinf(self.ca_s) else self.reference}


def check_vesicle_case(nu, lam, lam_ratio, ca_b):
    """The checked point (nu, lam, lam_c, ca_b) of a vesicle solve from ``lam`` or ``lam_ratio``
    (exactly one, :func:`lubrication.geometry.resolve_confinement`) and Ca_B within
    [CA_B_MIN, CA_B_MAX]; raises :class:`InvalidParameterError` (CannotPassError for
    lam >= lam_c) naming the input."""
    nu, lam, lam_c = resolve_confinement(
        nu, lam, lam_ratio, nu_reason="a vesicle with excess area (nu < 1) is needed")
    ca_b = float(check_positive("ca_b", ca_b, reason="Ca_B = eta U R0^2/kappa"))
    if not CA_B_MIN <= ca_b <= CA_B_MAX:
        raise InvalidParameterError(
            "ca_b", ca_b, f"{CA_B_MIN:g} <= ca_b <= {CA_B_MAX:g}",
            "Ca_B = eta U R0^2/kappa; outside it the membrane is rigid, or bending negligible, "
            "to within the solver's accuracy (red blood cells: Ca_B ~ 1-1000)")
    return nu, lam, lam_c, ca_b


def mode_count(name, value) -> int:
    """An integer number of shape modes, 8 <= value <= MAX_MODES (the vesicle's envelope)."""
    return _drop_mode_count(name, value, 8, MAX_MODES)


def check_vesicle_inputs(nu, lam=None, *, lam_ratio=None, ca_b=50.0, n_modes=None,
                         tol=1e-4, tension_tol=1e-2, residual_tol=1e-3, max_modes=None,
                         rung_modes=32, density_terms=16, max_iter=40, max_time=None,
                         ca_s=None, reference="biconcave") -> VesicleInputs:
    """Check the inputs of :func:`bem.vesicle.solve_vesicle` (ranges and the resource envelope
    of the module docstring) without any BEM work. Returns them as a
    :class:`~bem.vesicle.VesicleInputs` of Python numbers (``max_modes`` None stays None: chosen
    from the vesicle's length; ``max_time`` is checked, not returned). Raises
    :class:`InvalidParameterError` (or CannotPassError for lam >= lam_c) naming the input.

    Examples
    --------
    >>> case = check_vesicle_inputs(0.9, lam_ratio=0.5)
    >>> case.lam == 0.5 * case.lam_c, case.max_modes, case.rung_modes
    (True, None, 32)
    """
    nu, lam, lam_c, ca_b = check_vesicle_case(nu, lam, lam_ratio, ca_b)
    tol = float(check_range("tol", tol, 1e-12, 0.5))
    tension_tol = float(check_range("tension_tol", tension_tol, 1e-12, 0.5))
    residual_tol = float(check_range("residual_tol", residual_tol, 1e-14, 10.0))
    if max_modes is not None:
        max_modes = mode_count("max_modes", max_modes)
    if n_modes is not None:
        n_modes = mode_count("n_modes", n_modes)
    elif max_modes is not None and max_modes < 24:
        raise InvalidParameterError("max_modes", max_modes, f"24 <= max_modes <= {MAX_MODES}",
                                    "the automatic refinement solves 16, 24, ... modes and "
                                    "needs a pair; for a single coarse solve give n_modes")
    rung_modes = mode_count("rung_modes", rung_modes)
    density_terms = int(check_range("density_terms", density_terms, 1, 64))
    max_iter = int(check_range("max_iter", max_iter, 1, 1000))
    if max_time is not None:
        Deadline(max_time)                               # 0 < max_time < inf
    ca_s, reference = check_shear_inputs(nu, ca_s, reference, ca_s_range=CA_S_RANGE)
    return VesicleInputs(nu=nu, lam=lam, lam_c=lam_c, ca_b=ca_b, n_modes=n_modes, tol=tol,
                         tension_tol=tension_tol, residual_tol=residual_tol,
                         max_modes=max_modes, rung_modes=rung_modes,
                         density_terms=density_terms, max_iter=max_iter, ca_s=ca_s,
                         reference=reference)
