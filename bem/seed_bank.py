r"""Converged steady vesicle shapes to start new solves from: the seed bank.

A steady vesicle shape changes smoothly with (ν, λ/λc, Ca_B) along a branch, so a converged
shape at a nearby point lies inside the basin of the Levenberg–Marquardt solve of
:func:`bem.vesicle.solve_vesicle`, where a shape built from a model (lubrication theory, a
spheroid) may not: at moderate confinement (λ/λc ≈ 0.3–0.65, ν ≤ 0.89) the model seeds end in
non-steady least-squares minima at about one random point in five, while the nearest stored
shape converges there in 1–5 s (docs/vesicle-solver.md).

The bank holds the converged BEM shapes of the shipped solution map's build (ν 0.6–0.98,
λ/λc 0.2–0.98, Ca_B 5–500; :func:`correlations.map_build.write_seed_bank` writes it from the
build folder): per point its (ν, λ/λc, Ca_B), its shape class and the spectral curve (tangent-
angle modes and arc-length density of :class:`bem.shape.SpectralCurve`). A shape is stored at
unit scale; :meth:`Seed.curve` scales it to the volume of the target.

Distance between points: Euclidean in (ν/0.05, (λ/λc)/0.1, log10(Ca_B)/0.3), about one grid
step of the map's build per unit on each axis, so that "nearest" weighs the three axes alike.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

import numpy as np

from lubrication.checks import InvalidParameterError
from lubrication.io import atomic_write

from .shape import SpectralCurve

__all__ = ["BANK_PATH", "SHAPE_CLASSES", "Seed", "SeedBank", "load_seed_bank"]

#: The shipped bank (written by :func:`correlations.map_build.write_seed_bank`).
BANK_PATH = Path(__file__).resolve().parent / "data" / "seed_bank.npz"
#: Shape classes, in the order of the bank's ``shape_class`` codes.
SHAPE_CLASSES = ("bullet", "parachute")
#: Scales of the distance: one unit is about one grid step of the map's build on each axis.
SCALE_NU, SCALE_RATIO, SCALE_LOG_CA = 0.05, 0.1, 0.3


@dataclass(frozen=True)
class Seed:
    """One stored converged shape and the point it was solved at."""

    nu: float
    lam_ratio: float
    ca_b: float
    shape_class: str
    modes: np.ndarray = field(repr=False)
    density: np.ndarray = field(repr=False)
    distance: float = math.nan

    def curve(self, lam: float) -> SpectralCurve:
        """The stored shape with the volume of a vesicle of confinement ``lam`` (R0 = lam R).
        Raises InvalidParameterError if the stored modes do not close to a positive volume."""
        return SpectralCurve.with_volume_radius(self.modes, lam, density=self.density)

    def label(self) -> str:
        return (f"seed bank ({self.shape_class} at nu={self.nu:g}, lam/lam_c={self.lam_ratio:g}, "
                f"Ca_B={self.ca_b:g})")


class SeedBank:
    """Stored shapes with their points; :meth:`nearest` ranks them by distance to a point."""

    def __init__(self, nu, lam_ratio, ca_b, shape_class, offsets, modes, density):
        self.nu = np.asarray(nu, dtype=float)
        self.lam_ratio = np.asarray(lam_ratio, dtype=float)
        self.ca_b = np.asarray(ca_b, dtype=float)
        self.shape_class = np.asarray(shape_class, dtype=np.int8)
        self.offsets = np.asarray(offsets, dtype=np.int64)
        self.modes = np.asarray(modes, dtype=float)
        self.density = np.asarray(density, dtype=float)
        n = self.nu.size
        if not (self.lam_ratio.size == self.ca_b.size == self.shape_class.size == n
                and self.offsets.size == n + 1 and self.density.shape[0] == n
                and self.offsets[-1] == self.modes.size):
            raise InvalidParameterError("seed bank", "arrays of inconsistent sizes",
                                        "one entry per stored point")

    def __len__(self) -> int:
        return self.nu.size

    def distances(self, nu: float, lam_ratio: float, ca_b: float) -> np.ndarray:
        """Distance of every stored point to (ν, λ/λc, Ca_B), in the scales of the module."""
        return np.sqrt(((self.nu - nu) / SCALE_NU) ** 2
                       + ((self.lam_ratio - lam_ratio) / SCALE_RATIO) ** 2
                       + (np.log10(self.ca_b / ca_b) / SCALE_LOG_CA) ** 2)

    def seed(self, i: int, distance: float = math.nan) -> Seed:
        return Seed(nu=float(self.nu[i]), lam_ratio=float(self.lam_ratio[i]),
                    ca_b=float(self.ca_b[i]), shape_class=SHAPE_CLASSES[self.shape_class[i]],
                    modes=self.modes[self.offsets[i]:self.offsets[i + 1]].copy(),
                    density=self.density[i].copy(), distance=float(distance))

    def nearest(self, nu: float, lam_ratio: float, ca_b: float, k: int = 1,
                shape_class: str | None = None, within: float = math.inf) -> list[Seed]:
        """The ``k`` stored shapes nearest to the point (of ``shape_class`` if given), nearest
        first, at most ``within`` away."""
        d = self.distances(nu, lam_ratio, ca_b)
        if shape_class is not None:
            d = np.where(self.shape_class == SHAPE_CLASSES.index(shape_class), d, np.inf)
        order = np.argsort(d, kind="stable")[:k]
        return [self.seed(i, d[i]) for i in order if np.isfinite(d[i]) and d[i] <= within]

    def save(self, path) -> None:
        """Write the bank atomically as a compressed ``.npz`` (no pickled objects)."""
        atomic_write(path, lambda f: np.savez_compressed(
            f, nu=self.nu, lam_ratio=self.lam_ratio, ca_b=self.ca_b, shape_class=self.shape_class,
            offsets=self.offsets, modes=self.modes, density=self.density), binary=True)

    @classmethod
    def from_shapes(cls, points) -> SeedBank:
        """A bank from ``(nu, lam_ratio, ca_b, shape_class, modes, density)`` tuples; every
        density has the same number of terms."""
        points = list(points)
        sizes = [len(p[4]) for p in points]
        return cls(nu=[p[0] for p in points], lam_ratio=[p[1] for p in points],
                   ca_b=[p[2] for p in points],
                   shape_class=[SHAPE_CLASSES.index(p[3]) for p in points],
                   offsets=np.concatenate([[0], np.cumsum(sizes, dtype=np.int64)]),
                   modes=np.concatenate([np.asarray(p[4], float) for p in points])
                   if points else np.empty(0),
                   density=np.array([p[5] for p in points], dtype=float).reshape(len(points), -1))


@cache
def load_seed_bank(path=None) -> SeedBank:
    """The bank at ``path`` (default: the shipped :data:`BANK_PATH`), read once."""
    with np.load(BANK_PATH if path is None else path, allow_pickle=False) as f:
        return SeedBank(**{k: f[k] for k in ("nu", "lam_ratio", "ca_b", "shape_class",
                                             "offsets", "modes", "density")})
