r"""Steady vesicle (inextensible Helfrich membrane, viscosity ratio 1) in a tube, solved directly.

Nondimensionalisation (stated once for the package): tube radius R = 1, outer viscosity eta = 1,
mean velocity of the undisturbed Poiseuille flow U = 1 (:math:`u^\infty = 2(1 - r^2)e_x`). The
vesicle has the volume of a sphere of radius :math:`R_0 = \lambda R` and the area of a sphere of
radius :math:`R_A = R_0\nu^{-1/3}`; bending modulus :math:`\kappa = \lambda^2/\mathrm{Ca}_B` in
:math:`\eta U R^2` (Ca_B = ηUR0²/κ); tension in ηU.

Physics: in the frame moving with the vesicle a steady, axisymmetric, inextensible membrane is
at rest, so the steady state is a shape, a tension γ(τ) and a speed V with u = V e_x at every
membrane node, the volume, area and centroid fixed; the velocity is the single layer of the
membrane load (bending and tension) plus the wall and inlet layers of the tube.

Method: the shape is N sine modes of the tangent angle (volume, area and centring exact), the
tension and V the linear least-squares solution for each shape (variable projection), and the
N - 2 free modes minimise the steady residual by Levenberg–Marquardt.

The pipeline of :func:`~bem.vesicle.solve_vesicle`, one module a step:

1. :mod:`bem.vesicle.inputs`: every input checked before any BEM work (resource envelope);
2. :mod:`bem.vesicle.pipeline`: the starts (stored shapes of the seed bank, the solver's own
   seed) tried in turn, and the probe of a converged point for a second steady state;
3. :mod:`bem.vesicle.ladder`: one start, its seed (:mod:`bem.vesicle.seeds`) or continuation
   near lam_c, refined by a ladder of levels 16, 24, ... modes until the error estimated from
   three levels is within the tolerances;
4. :mod:`bem.vesicle.level`: one level, Levenberg–Marquardt with a variable-projection
   Jacobian evaluated concurrently;
5. :mod:`bem.vesicle.operator`: the BEM operator of one shape (velocity, tension and V, the
   linearised Jacobian points, the mesh, the outputs).

The solver paths measured and replaced or not adopted, with their numbers, are in
docs/vesicle-solver.md.
"""

from .inputs import (
    CA_B_MAX,
    CA_B_MIN,
    CA_S_RANGE,
    MAX_MODES,
    VesicleInputs,
    check_vesicle_case,
    check_vesicle_inputs,
)
from .level import level_function
from .operator import WALL_REFINEMENT, VesicleOperator, vesicle_discretisation
from .pipeline import solve_vesicle
from .seeds import (
    NEAR_CRITICAL,
    capsule_seed,
    fit_lubrication,
    lubrication_seed,
    seed_from_lubrication,
    spheroid_seed,
)

__all__ = ["CA_B_MAX", "CA_B_MIN", "CA_S_RANGE", "MAX_MODES", "NEAR_CRITICAL",
           "WALL_REFINEMENT", "VesicleInputs", "VesicleOperator", "capsule_seed",
           "check_vesicle_case", "check_vesicle_inputs", "fit_lubrication", "level_function",
           "lubrication_seed", "seed_from_lubrication", "solve_vesicle", "spheroid_seed",
           "vesicle_discretisation"]
