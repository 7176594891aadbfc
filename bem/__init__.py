"""Axisymmetric Stokes boundary element method for objects in a tube.

Layout: :mod:`bem.kernels` (numba back-end: elliptic integrals, ring Stokeslet, influence
matrix), :mod:`bem.quadrature` (panels, singular and near-singular rules), :mod:`bem.geometry`
(generating curves and meshes), :mod:`bem.assembly` (bordered single-layer system),
:mod:`bem.solve` (user API), :mod:`bem.results` (result dataclass). Units: R = eta = U = 1.

Public entry points: :func:`bem.solve.solve_sphere` and :func:`bem.solve.sphere_drag`.
"""

__all__ = ["SphereResult", "solve_sphere", "sphere_drag"]


def __getattr__(name):          # lazy: importing bem does not load numba
    if name in ("solve_sphere", "sphere_drag"):
        from . import solve
        return getattr(solve, name)
    if name == "SphereResult":
        from .results import SphereResult
        return SphereResult
    raise AttributeError(name)
