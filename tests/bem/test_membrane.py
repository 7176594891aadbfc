"""Membrane forces: sphere, spheroids against sympy, virtual-work (area-rate, energy) identities.

Closed forms are derived here with sympy for the spheroid x = -a cos t, r = b sin t:
H = (kappa_1 + kappa_2)/2, K = kappa_1 kappa_2 and the surface Laplacian
Delta_s f = (r |X_t|)^-1 d/dt (r f_t / |X_t|). Measured numbers in comments come from this code.
"""

import math

import numpy as np
import pytest
import sympy as sp

from bem.membrane import (
    bending_energy,
    bending_force,
    mean_curvature_series,
    surface_laplacian_H,
    tension_basis,
    tension_force,
)
from bem.shape import SpectralCurve, equidistributing_density, fit_curve, spheroid_curve

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable


def _spheroid_closed_form(a, b):
    """Numerical functions H(t), K(t), Delta_s H(t) of the spheroid, derived symbolically."""
    t = sp.symbols("t", real=True)
    x, r = -a * sp.cos(t), b * sp.sin(t)
    xt, rt = sp.diff(x, t), sp.diff(r, t)
    speed = sp.sqrt(xt**2 + rt**2)
    psi = sp.atan2(rt, xt)
    k1 = -sp.diff(psi, t) / speed
    k2 = sp.cos(psi) / r
    H = sp.simplify((k1 + k2) / 2)
    K = sp.simplify(k1 * k2)
    lap = sp.diff(r * sp.diff(H, t) / speed, t) / (r * speed)
    return tuple(sp.lambdify(t, e, "numpy") for e in (H, K, lap))


def _spheroid(a, b, n=64):
    base = fit_curve(spheroid_curve(a, b), 0.0, math.pi, 24)
    return fit_curve(spheroid_curve(a, b), 0.0, math.pi, n,
                     density=equidistributing_density(base, 16))


def test_sphere_has_no_bending_force_and_energy_8_pi_kappa(report):
    force, energy = 0.0, 0.0
    for a in (0.3, 0.8, 1.7):
        c = SpectralCurve.sphere(a, 12)
        tau = np.concatenate([[0.0, 1e-9, 1e-4], np.linspace(0.01, 0.99, 41), [1 - 1e-6, 1.0]])
        fx, fr = bending_force(c, tau, kappa=1.0)
        scale = 1.0 / a**3                                   # kappa/a^3
        force = max(force, np.max(np.abs(fx)) / scale, np.max(np.abs(fr)) / scale)
        energy = max(energy, abs(bending_energy(c) / (8 * math.pi) - 1))
        assert np.max(np.abs(fx)) < 1e-10 * scale and np.max(np.abs(fr)) < 1e-10 * scale
        assert abs(bending_energy(c) / (8 * math.pi) - 1) < 1e-13
    report.value("mem.sphere_force", force, reference=0.0, tol="1e-10 κ/a³",
                 source="0 on a sphere")
    report.value("mem.sphere_energy", energy, reference=0.0, tol="1e-13 rel", source="8 pi kappa")


@pytest.mark.parametrize("a, b", [(1.0, 0.6), (0.6, 1.0), (1.3, 0.7)])
def test_spheroid_curvature_terms_match_sympy(a, b, report):
    """H, K and Delta_s H of prolate and oblate spheroids against the symbolic closed form.
    Measured max relative errors of Delta_s H: ~1e-10 (64 modes)."""
    Hf, Kf, lapf = _spheroid_closed_form(a, b)
    c = _spheroid(a, b)
    tau = np.concatenate([np.linspace(1e-3, 1 - 1e-3, 201)])
    x, _ = c.position(tau)
    t = np.arccos(np.clip(-x / a, -1.0, 1.0))
    H, K, lap = surface_laplacian_H(c, tau)
    scale = np.max(np.abs(lapf(t)))
    report.value(f"mem.lap_H_{a}_{b}", np.max(np.abs(lap - lapf(t))) / scale, reference=0.0,
                 tol="1e-7 (of the largest value)", source="sympy closed form")
    report.value(f"mem.H_{a}_{b}", np.max(np.abs(H - Hf(t))) / np.max(np.abs(Hf(t))),
                 reference=0.0, tol="1e-9 (of the largest value)", source="sympy closed form")
    assert np.max(np.abs(H - Hf(t))) < 1e-9 * np.max(np.abs(Hf(t)))
    assert np.max(np.abs(K - Kf(t))) < 1e-9 * np.max(np.abs(Kf(t)))
    assert np.max(np.abs(lap - lapf(t))) < 1e-7 * scale, np.max(np.abs(lap - lapf(t))) / scale
    # pole limits: Delta_s H at t -> 0 from the closed form (a series in t)
    Hp, Kp, lapp = surface_laplacian_H(c, np.array([0.0, 1.0]))
    ref = lapf(np.array([1e-4, math.pi - 1e-4]))            # O(t^2) from the pole value
    assert np.max(np.abs(lapp - ref)) < 1e-6 * scale
    assert np.allclose(Hp, a / b**2, rtol=1e-10) and np.allclose(Kp, (a / b**2) ** 2, rtol=1e-9)


def test_mean_curvature_series_is_resolved():
    """Doubling the DCT points changes Delta_s H by less than 1e-9 of its scale."""
    c = _spheroid(1.3, 0.7)
    tau = np.linspace(0.0, 1.0, 101)
    lap1 = surface_laplacian_H(c, tau)[2]
    lap2 = surface_laplacian_H(c, tau, n_points=2 * (4 * 80 + 64))[2]
    assert np.max(np.abs(lap1 - lap2)) < 1e-9 * np.max(np.abs(lap2))
    h = mean_curvature_series(c)
    assert np.max(np.abs(h[-10:])) < 1e-12 * np.max(np.abs(h))


def test_constant_tension_force_on_a_sphere_is_minus_2_gamma_H_n():
    a, gamma = 0.7, 3.2
    c = SpectralCurve.sphere(a, 6)
    tau = np.linspace(0.0, 1.0, 33)
    fx, fr = tension_force(c, [gamma], tau)
    nx, nr = c.normal(tau)
    assert np.allclose(fx, -2 * gamma / a * nx, atol=1e-13)
    assert np.allclose(fr, -2 * gamma / a * nr, atol=1e-13)


def _virtual_displacement(modes, j, volume, h=1e-6):
    """Curves at modes +- h e_j (closed, fixed volume, centred) and the displacement dX/dh at
    fixed tau on the Gauss rule used for the surface integrals."""
    m1, m2 = modes.copy(), modes.copy()
    m1[j] += h
    m2[j] -= h
    c1 = SpectralCurve.closed(m1, volume=volume)
    c2 = SpectralCurve.closed(m2, volume=volume)
    return c1, c2


def _surface_rule(curve, n=200):
    t, w = np.polynomial.legendre.leggauss(n)
    t, w = 0.5 * (t + 1), 0.5 * w
    _, r = curve.position(t)
    return t, 2 * math.pi * r * curve.length * curve.g(t) * w


@pytest.mark.parametrize("j", [1, 2, 4])
def test_area_rate_and_bending_virtual_work(j, report):
    """int f_gamma . dX dA = -gamma dA (constant gamma) and int f_b . dX dA = -dE for shape
    variations of a bullet-like curve (central differences, h = 1e-6)."""
    modes = np.array([0.0, 0.25, -0.08, 0.05, 0.02, -0.01])
    vol = 2.0
    c = SpectralCurve.closed(modes, volume=vol)
    h = 1e-5
    c1, c2 = _virtual_displacement(c.modes, j, vol, h)
    t, dA = _surface_rule(c)
    x1, r1 = c1.position(t)
    x2, r2 = c2.position(t)
    dX = ((x1 - x2) / (2 * h), (r1 - r2) / (2 * h))
    gamma = 1.7
    fx, fr = tension_force(c, [gamma], t)
    work = np.sum((fx * dX[0] + fr * dX[1]) * dA)
    dArea = (c1.area() - c2.area()) / (2 * h)
    report.value(f"mem.work_tension_{j}", abs(work + gamma * dArea) / (1 + abs(gamma * dArea)),
                 reference=0.0, tol=1e-7, source="virtual work: -gamma dA")
    assert abs(work + gamma * dArea) < 1e-7 * (1 + abs(gamma * dArea)), (work, dArea)
    bx, br = bending_force(c, t, kappa=1.0)
    work_b = np.sum((bx * dX[0] + br * dX[1]) * dA)
    dE = (bending_energy(c1) - bending_energy(c2)) / (2 * h)
    report.value(f"mem.work_bending_{j}", abs(work_b + dE) / (1 + abs(dE)), reference=0.0,
                 tol=1e-6, source="virtual work: -dE")
    assert abs(work_b + dE) < 1e-6 * (1 + abs(dE)), (work_b, dE)


def test_variable_tension_virtual_work():
    """int f_gamma . dX dA = -int gamma div_s dX dA for gamma = 1 + 0.5 cos(pi tau) + 0.2
    cos(2 pi tau), with div_s dX = dA-rate density from the finite-difference area element."""
    modes = np.array([0.0, 0.2, -0.05, 0.03])
    c = SpectralCurve.closed(modes, volume=1.5)
    h = 1e-5
    c1, c2 = _virtual_displacement(c.modes, 2, 1.5, h)
    t, dA = _surface_rule(c)
    _, dA1 = _surface_rule(c1)
    _, dA2 = _surface_rule(c2)
    x1, r1 = c1.position(t)
    x2, r2 = c2.position(t)
    dX = ((x1 - x2) / (2 * h), (r1 - r2) / (2 * h))
    g = [1.0, 0.5, 0.2]
    gam = 1.0 + 0.5 * np.cos(np.pi * t) + 0.2 * np.cos(2 * np.pi * t)
    fx, fr = tension_force(c, g, t)
    lhs = np.sum((fx * dX[0] + fr * dX[1]) * dA)
    rhs = -np.sum(gam * (dA1 - dA2) / (2 * h))
    assert abs(lhs - rhs) < 1e-7 * (1 + abs(rhs)), (lhs, rhs)


def test_tension_basis_combined_with_coefficients_is_the_tension_force():
    """The basis of the M tension modes (the solver's load columns) combined with
    coefficients g against the tension force summed directly from the series (two code
    paths), on a rough 32-mode curve with a density: equal to rounding."""
    rng = np.random.default_rng(5)
    c = SpectralCurve.closed(rng.normal(size=32) * 0.02, volume=2.0,
                             density=rng.normal(size=8) * 0.05)
    tau = np.linspace(0.0, 1.0, 97)
    g = rng.normal(size=32)
    fx, fr = tension_force(c, g, tau)
    B = tension_basis(c, tau, g.size)
    scale = np.max(np.abs(fx)) + np.max(np.abs(fr))
    assert np.max(np.abs(np.tensordot(g, B[:, 0], axes=1) - fx)) < 1e-12 * scale
    assert np.max(np.abs(np.tensordot(g, B[:, 1], axes=1) - fr)) < 1e-12 * scale
