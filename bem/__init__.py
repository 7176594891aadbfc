"""Axisymmetric Stokes boundary element method for objects in a tube.

Layout: :mod:`bem.kernels` (numba back-end: elliptic integrals, ring Stokeslet, influence
matrix), :mod:`bem.quadrature` (panels, singular and near-singular rules), :mod:`bem.geometry`
(generating curves and meshes), :mod:`bem.shape` (spectral tangent-angle curves with exact
curvatures), :mod:`bem.assembly` (bordered single-layer system), :mod:`bem.solve` (rigid
sphere), :mod:`bem.drop` (clean drop: direct Newton steady state, time relaxation),
:mod:`bem.membrane` (bending and tension forces), :mod:`bem.shear` (shear elasticity of a
red-cell membrane), :mod:`bem.newton` (Levenberg–Marquardt with
Broyden updates, shared by drop and vesicle), :mod:`bem.vesicle` (steady vesicle),
:mod:`bem.vesicle_dynamics` (time integration of a vesicle), :mod:`bem.sweep` (vesicle sweeps
over the confinement by continuation), :mod:`bem.results` (result dataclasses),
:mod:`bem.plotting`; the ``vesicle-tube bem`` commands are in :mod:`correlations.cli.bem`.
Units: R = eta = U = 1.

Public entry points: :func:`bem.solve.solve_sphere`, :func:`bem.solve.sphere_drag`,
:func:`bem.drop.solve_drop`, :func:`bem.vesicle.solve_vesicle`, :func:`bem.sweep.sweep_vesicle`
and :func:`bem.vesicle_dynamics.relax_vesicle`.
"""

from .results import DropResult, SphereResult, VesicleResult
from .solve import solve_sphere, sphere_drag

__all__ = ["DropResult", "SphereResult", "VesicleResult", "solve_drop", "solve_sphere",
           "solve_vesicle", "sphere_drag", "sweep_vesicle"]


def __getattr__(name):
    """The drop and vesicle solvers on first use: they load scipy.linalg, scipy.interpolate
    and scipy.fft (~0.3 s), which the sphere solver and ``import bem.shape`` do without."""
    if name == "solve_drop":
        from .drop import solve_drop  # lazy: scipy.linalg off `import bem`
        return solve_drop
    if name == "sweep_vesicle":
        from .sweep import sweep_vesicle  # lazy: scipy (bem.vesicle) off `import bem`
        return sweep_vesicle
    if name == "solve_vesicle":
        from .vesicle import solve_vesicle  # lazy: scipy (bem.vesicle) off `import bem`
        return solve_vesicle
    raise AttributeError(f"module 'bem' has no attribute {name!r}")
