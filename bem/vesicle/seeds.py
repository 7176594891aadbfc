r"""Seeds of the steady vesicle solver, and the arc-length densities of its shape parametrisation.

A start of :func:`bem.vesicle.solve_vesicle` without a converged shape begins from a seed built
from a model (:func:`bem.vesicle.ladder.solve_from` tries them in this order):

* the lubrication shape at the target (:func:`~bem.vesicle.lubrication_seed`, the BVP solved to
  :data:`SEED_LUBRICATION_TOL`), fitted with the first level's modes and density and centred
  at x = 0, where the solver keeps every shape (:func:`~bem.vesicle.seed_from_lubrication`,
  :func:`~bem.vesicle.fit_lubrication`). Where the lubrication branch ends above λ (e.g. at
  λ/λc = 0.875 for ν = 0.7, Ca_B = 50) and λ/λc ≥ :data:`LUBRICATION_ANCHOR_FROM`, the
  lubrication shape at :data:`NEAR_CRITICAL` λc, its volume re-imposed at λ by the solver: it
  is on the branch of the genuine steady state.
* a prolate spheroid (:func:`~bem.vesicle.spheroid_seed`), or a capsule where the spheroid is too
  fat (:func:`~bem.vesicle.capsule_seed`). Fore-aft symmetric, they can end in a symmetric
  least-squares minimum that is not a steady state (at (0.7, 1.2): residual 1.5e-2 at 40–64 modes,
  V/U 1.386, where the lubrication-anchored seed gives residual 4e-5 at 48 modes, V/U 1.2591); they
  remain the last resort, and the residual test reports such a minimum.

Near lam_c (λ/λc > :data:`NEAR_CRITICAL`) most vesicles are reached by continuation in λ/λc
instead (:mod:`bem.vesicle.ladder`), and the pipeline tries converged shapes of the seed bank
(:mod:`bem.seed_bank`) before these seeds below NEAR_CRITICAL (:mod:`bem.vesicle.pipeline`).

Arc-length densities (:data:`DENSITIES`; "uniform" is none). The density of the shape
parametrisation, and hence of modes and panels, is part of the discretisation:

* "film" (the default from λ/λc = NEAR_CRITICAL, unless the vesicle is long). Near the critical
  confinement (thin film, gap h ≪ R) the velocity is set by the gap to a small *relative* error
  along the film and its entrance/exit transitions (length ~ sqrt(hR)), where the curvature is
  small: uniform arc length or a curvature-equidistributing density leave a residual floor
  ~5e-2 at 16–24 modes (λ/λc = 0.97). "film" builds the arc-length density from the
  lubrication weight (h + h_min)^(-1/2) (:func:`bem.shape.film_density`); the panel breaks
  (graded by sqrt(gap) in τ) then also cluster there. The quadrature is not the limit (V/U of
  a fixed shape changes by 1e-7 from 8 to 24 membrane panels at λ/λc = 0.97). Measured at
  ν = 0.9, Ca_B = 50, 48 modes (docs/validation.md): λ/λc = 0.95, 0.97, 0.98 reach residuals
  3.2e-4, 1.2e-3, 2.9e-3, V/U within 0.04 % and Δp⁺ 6.8, 4.65, 3.2 % above lubrication.
* "bend" (the default for every vesicle that is not near lam_c). Long vesicles (Chen's length
  estimate ℓc λ/λc > 5 R, i.e. ν ≲ 0.75 at moderate to high confinement) have caps, a sharp
  parachute rim and the junctions where a cap meets the thin film, each on scales ≪ their
  length. "bend" adds a curvature-gradient term to the curvature weight
  (:func:`bem.shape.equidistributing_density`), which resolves all three (fitted lubrication
  shape at ν = 0.6, λ/λc = 0.98: relative gap error 1e-4 with 64 modes, against 8e-3 with the
  curvature weight alone); built on a BEM shape it also beats uniform arc length on short
  vesicles (at (0.8, 1.0), 40 modes, residual 2.5e-6 against 8.7e-4).
* "curvature": the curvature weight alone.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
from scipy.interpolate import CubicSpline

from lubrication.checks import Deadline, InvalidParameterError
from lubrication.geometry import critical_confinement
from lubrication.solve import solve_lubrication

from ..shape import (
    SpectralCurve,
    equidistributing_density,
    film_density,
    fit_curve,
    spheroid_curve,
)

__all__ = ["DENSITIES", "LUBRICATION_ANCHOR_FROM", "NEAR_CRITICAL", "SEED_LUBRICATION_TOL",
           "capsule_seed", "fit_lubrication", "lubrication_seed", "seed_from_lubrication",
           "spheroid_seed"]

log = logging.getLogger(__name__)

#: lam/lam_c from which :func:`bem.vesicle.solve_vesicle` uses the film density and
#: continuation by default, and at which a lubrication seed is anchored where the lubrication
#: branch ends above the target λ (:func:`~bem.vesicle.lubrication_seed`)
NEAR_CRITICAL = 0.9

#: arc-length densities of the shape parametrisation: curve -> density coefficients
DENSITIES = {
    "curvature": equidistributing_density,
    "bend": lambda curve, n: equidistributing_density(curve, n, gradient=1.0),
    "film": film_density,
}

#: BVP tolerance of the lubrication solution that seeds a solve: the seed is a fit with 16-24
#: modes, far coarser; against the default 1e-7, V/U changes by < 1e-8 at (0.9, 1.0),
#: (0.61, 1.39) and (0.6, 1.94) while the solve of (0.61, 1.39) takes 2.4 s instead of 6.3 s
#: (a continuation in lam/lam_c with fewer mesh nodes)
SEED_LUBRICATION_TOL = 1e-4

#: lam/lam_c from which a failed lubrication seed is replaced by the lubrication shape at
#: NEAR_CRITICAL lam_c (:func:`~bem.vesicle.lubrication_seed`); below, the spheroid: measured, (0.7,
#: 0.69 lam_c) needs the anchored shape, while at (0.95, 0.2 lam_c) the anchored shape could not be
#: carried to 24 modes (its curve did not close) where a spheroid seed converges
LUBRICATION_ANCHOR_FROM = 0.5


def lubrication_seed(nu: float, lam: float, ca_b: float, n_modes: int,
                     density: str = "uniform", density_terms: int = 16,
                     max_time: float | None = None):
    """Spectral curve fitted to the lubrication solution at (nu, lam, ca_b) (see
    :func:`~bem.vesicle.seed_from_lubrication`) or, where the lubrication branch ends above lam
    (e.g. at lam/lam_c = 0.875 for nu = 0.7, Ca_B = 50) and lam/lam_c >= LUBRICATION_ANCHOR_FROM, at
    lam/lam_c = NEAR_CRITICAL: its shape, with the volume re-imposed at lam by the solver, is on the
    branch of the genuine steady state (at (0.7, 1.2): residual 3.8e-5 at 48 modes, geometric
    convergence), where a prolate spheroid or a capsule ends in a fore-aft symmetric least-squares
    minimum that is not a steady state (residual 1.5e-2 at every mode count from 40 to 64). None if
    the solver fails (or runs out of ``max_time`` seconds) or the fit is rejected. Returns (curve,
    lubrication result), the latter solved to the BVP tolerance ``SEED_LUBRICATION_TOL``."""
    deadline = Deadline(max_time)
    lub = None
    for target in (lam, NEAR_CRITICAL * critical_confinement(nu)):
        if lub is not None and (lub.success or target <= lam or deadline.expired()
                                or lam < LUBRICATION_ANCHOR_FROM * target / NEAR_CRITICAL):
            break
        try:
            lub = solve_lubrication(nu, target, ca_b=ca_b, tol=SEED_LUBRICATION_TOL,
                                    max_time=deadline.remaining())
        except InvalidParameterError as exc:         # outside the lubrication model's range
            log.info("no lubrication seed: %s", exc)
            return None, None
    if not lub.success:
        return None, lub
    return seed_from_lubrication(lub, n_modes, density, density_terms), lub


def seed_from_lubrication(lub, n_modes: int, density: str = "uniform",
                          density_terms: int = 16) -> SpectralCurve | None:
    """``n_modes`` fit of a converged lubrication shape with the arc-length ``density`` (a key
    of ``DENSITIES`` or "uniform", built from a 128-mode fit); None if the fit closes more
    than half of the lubrication gap (a sharp parachute rim the modes cannot carry)."""
    dens = (() if density == "uniform"
            else DENSITIES[density](fit_lubrication(lub, 128), density_terms))
    curve = fit_lubrication(lub, n_modes, dens)
    gap = 1.0 - float(np.max(lub.r))
    if 1.0 - curve.max_radius() < 0.5 * gap:
        log.info("lubrication seed rejected: %d-mode %s fit has gap %.3g (lubrication %.3g)",
                 n_modes, density, 1.0 - curve.max_radius(), gap)
        return None
    return curve


def fit_lubrication(lub, n_modes: int, density=()) -> SpectralCurve:
    """Spectral curve with ``n_modes`` modes (and arc-length ``density`` coefficients) fitted to
    a converged LubricationResult's shape, moved along the axis so that its centroid is at
    x = 0, where the solver centres every shape (the lubrication shape starts at x = 0: as a
    seed it placed the first level's wall, whose finest panels follow the reference curve,
    beside the front half of the vesicle only)."""
    s = np.asarray(lub.s)
    keep = np.concatenate([[True], np.diff(s) > 1e-12])
    s, x, r, psi = s[keep], np.asarray(lub.x)[keep], np.asarray(lub.r)[keep], \
        np.asarray(lub.psi)[keep]
    sx, sr, sp = CubicSpline(s, x), CubicSpline(s, r), CubicSpline(s, psi)

    def curve(t):
        t = np.asarray(t, dtype=float)
        p = sp(t)
        return sx(t), np.clip(sr(t), 0.0, None), np.cos(p), -np.sin(p)

    fit = fit_curve(curve, float(s[0]), float(s[-1]), n_modes, density=density)
    return dataclasses.replace(fit, x0=fit.x0 - fit.centroid())


def spheroid_seed(nu: float, lam: float, n_modes: int) -> SpectralCurve:
    """Prolate spheroid (axis along the tube) of reduced volume ``nu`` and volume 4/3 pi lam^3."""
    def nu_of(e):                                         # e = b/a <= 1, prolate
        c = fit_curve(spheroid_curve(1.0, e), 0.0, math.pi, 32)
        return 6.0 * math.sqrt(math.pi) * c.volume() * c.area() ** -1.5
    lo, hi = 0.05, 1.0
    for _ in range(50):                                   # bisection: nu increases with e
        mid = 0.5 * (lo + hi)
        if nu_of(mid) < nu:
            lo = mid
        else:
            hi = mid
    e = 0.5 * (lo + hi)
    c = fit_curve(spheroid_curve(1.0, e), 0.0, math.pi, n_modes)
    return SpectralCurve.with_volume_radius(c.modes, lam)


def capsule_seed(nu: float, lam: float, n_modes: int) -> SpectralCurve:
    r"""Cylinder with hemispherical caps of reduced volume ``nu`` and volume 4/3 pi lam^3.

    Cap radius a and cylinder length L from :math:`V = \pi a^2 L + \tfrac43\pi a^3`,
    :math:`A = 2\pi a L + 4\pi a^2`, i.e. :math:`\tfrac23\pi a^3 - \tfrac12 A a + V = 0`, the
    cubic of the critical confinement (Chen et al. 2020 eq. lamc) with a in place of R: its
    larger root is :math:`a = \lambda/\lambda_c(\nu) < 1`, so the capsule fits in the tube
    whenever the vesicle can pass (a prolate spheroid of small nu and large lam does not).
    """
    a = lam / critical_confinement(nu)
    length = (4.0 * math.pi * (lam * nu ** (-1.0 / 3.0)) ** 2 - 4.0 * math.pi * a * a) \
        / (2.0 * math.pi * a)
    q = 0.5 * math.pi * a                                 # arc length of one cap

    def curve(t):
        t = np.asarray(t, dtype=float)
        rear, front = t < q, t > q + length
        th = np.where(rear, t / a, np.where(front, (t - q - length) / a + 0.5 * math.pi,
                                            0.5 * math.pi))
        x = np.where(rear, -a * np.cos(th), np.where(front, length - a * np.cos(th),
                                                     t - q))
        return x, a * np.sin(th), np.sin(th), np.cos(th)

    c = fit_curve(curve, 0.0, 2.0 * q + length, n_modes)
    return SpectralCurve.with_volume_radius(c.modes, lam)

