r"""Linear system of a rigid axisymmetric body in a tube (single-layer, Nyström collocation).

Units: tube radius R = 1, viscosity eta = 1, mean velocity of the undisturbed Poiseuille flow
U = 1, so :math:`u^\infty = 2(1 - r^2)\,e_x`, flow rate Q = pi.

Representation (Pozrikidis 1992 §2.3, §7.2; total traction on rigid bodies): the disturbance
:math:`u' = u - u^\infty` is

.. math:: u'_\alpha(x_0) = \frac{1}{8\pi}\Big[\int_{S} M_{\alpha\beta} q_\beta\,dl
          + \int_{\rm wall} M_{\alpha\beta} q_\beta\,dl
          + \Delta p^+\!\int_{\rm inlet} M_{\alpha x}\,dl\Big],

with ``q`` the force per unit area that the boundary exerts **on the fluid**
(``q = -f``, f = sigma.n the traction the fluid exerts on the body, n into the fluid). On the
inlet disc the outside fluid pushes with the extra pressure Δp⁺ (q = Δp⁺ e_x); the outlet
carries zero extra pressure. The disturbance velocity decays like exp(-4.47|x|), so its double
layer over the end discs is dropped.

Unknowns: q on the body and the wall (node values), the body velocity V (free body), Δp⁺ and a
multiplier mu of the null vector. Equations:

* body nodes: u' + mu n = V e_x - u^inf (free) or V e_x (translating body, quiescent tube);
* wall nodes: u' = 0;
* free body: zero net force, :math:`\int_S q_x\,dS = 0`;
* closure of Δp⁺ by the reciprocal theorem with Poiseuille flow as the auxiliary solution:
  :math:`Q\,\Delta p^+ = \int_S u^\infty\cdot f\,dS`, i.e.
  :math:`\Delta p^+ = -4\int_S r(1 - r^2) q_x\,dl` (equivalent to zero net disturbance flux);
* null vector of the single layer on the closed body: :math:`\int_S q\cdot n\,dS = 0`; the
  bordering column mu n keeps the system square (mu -> 0 with the discretisation error).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lubrication.checks import check_choice

from .geometry import TubeGeometry
from .quadrature import DEFAULT_TOL, NEAR_FACTOR, influence

__all__ = [
    "MODES",
    "InfluenceBlocks",
    "TubeSystem",
    "assemble_influence",
    "bordered_system",
    "poiseuille",
]

MODES = ("free", "translating")


def poiseuille(r):
    """Undisturbed axial velocity 2(1 - r^2) at mean velocity 1 (R = 1)."""
    r = np.asarray(r, dtype=float)
    return 2.0 * (1.0 - r * r)


@dataclass(frozen=True)
class TubeSystem:
    """Matrix, right-hand side and the layout of the unknowns."""

    A: np.ndarray
    b: np.ndarray
    mode: str
    n_body: int          # body nodes
    n_wall: int          # wall nodes
    i_V: int | None      # column of V (free body) or None
    i_dp: int            # column of the extra pressure drop
    i_mu: int            # column of the null-vector multiplier
    V_given: float | None


@dataclass(frozen=True)
class InfluenceBlocks:
    """Single-layer operator of body + wall on the body and wall nodes, and the inlet column.

    ``S`` maps node densities (body nodes first, then wall nodes) to disturbance velocities at
    the same nodes, already divided by 8 pi; ``col_dp`` is the velocity per unit extra inlet
    pressure. Both do not depend on the problem solved, so one assembly serves the free body
    and the translating body.
    """

    S: np.ndarray
    col_dp: np.ndarray
    n_body: int
    n_wall: int


def assemble_influence(geom: TubeGeometry, *, near: float | None = NEAR_FACTOR,
                       tol: float = DEFAULT_TOL) -> InfluenceBlocks:
    """Assemble the influence blocks of a tube geometry (the costly step)."""
    body, wall, inlet = geom.body, geom.wall, geom.inlet
    tx = np.concatenate([body.x.ravel(), wall.x.ravel()])
    tr = np.concatenate([body.r.ravel(), wall.r.ravel()])
    S = influence(tx, tr, body.concat(wall), near=near, tol=tol)
    S /= 8.0 * math.pi
    inl = influence(tx, tr, inlet, near=near, tol=tol) / (8.0 * math.pi)
    col_dp = inl[:, 0::2].sum(axis=1)                  # q = dp * e_x on every inlet node
    return InfluenceBlocks(S=S, col_dp=col_dp, n_body=body.n_nodes, n_wall=wall.n_nodes)


def bordered_system(blocks: InfluenceBlocks, geom: TubeGeometry, mode: str = "free", *,
                    V: float = 1.0) -> TubeSystem:
    """Bordered linear system for ``mode`` 'free' (Poiseuille flow, force-free body, unknown
    V) or 'translating' (body moving at ``V`` through fluid at rest far away)."""
    check_choice("mode", mode, MODES)
    body = geom.body
    nb, nw = blocks.n_body, blocks.n_wall
    n_extra = 3 if mode == "free" else 2
    m = 2 * (nb + nw)
    n = m + n_extra
    A = np.zeros((n, n))
    A[:m, :m] = blocks.S
    b = np.zeros(n)
    rb, wb = body.r.ravel(), body.w.ravel()
    nxb, nrb = body.nx.ravel(), body.nr.ravel()
    rows_x = np.arange(nb) * 2
    if mode == "free":
        i_V, i_dp, i_mu = m, m + 1, m + 2
        A[rows_x, i_V] = -1.0
        b[rows_x] = -poiseuille(rb)
        # zero net force on the body: int q_x dS = 0
        A[i_V, 0: 2 * nb: 2] = 2.0 * math.pi * rb * wb
        V_given = None
    else:
        i_V, i_dp, i_mu = None, m, m + 1
        b[rows_x] = V
        V_given = float(V)
    A[:m, i_dp] = blocks.col_dp
    A[: 2 * nb: 2, i_mu] = nxb
    A[1: 2 * nb: 2, i_mu] = nrb
    # reciprocal theorem: dp + 4 int r (1 - r^2) q_x dl = 0
    A[i_dp, i_dp] = 1.0
    A[i_dp, 0: 2 * nb: 2] = 4.0 * rb * (1.0 - rb * rb) * wb
    # null vector: int q.n dS = 0
    A[i_mu, 0: 2 * nb: 2] = 2.0 * math.pi * rb * wb * nxb
    A[i_mu, 1: 2 * nb: 2] = 2.0 * math.pi * rb * wb * nrb
    return TubeSystem(A=A, b=b, mode=mode, n_body=nb, n_wall=nw, i_V=i_V, i_dp=i_dp,
                      i_mu=i_mu, V_given=V_given)

