"""The red-cell membrane of the lubrication model (lubrication.membrane): law, reference shapes,
material map, and the load's sign conventions judged by virtual work.

The virtual-work tests build axisymmetric shapes from the squared radius u(a) = r(a)^2 as a
polynomial in the area coordinate a (0 <= a <= A): then every geometric quantity is exact
(dr/ds = pi u', cos psi = sqrt(1 - pi^2 u'^2), ds/da = 1/(2 pi r)), a perturbation
u + eps du keeps the local area by construction (a stays the area coordinate), and the axial
position follows from x'(a) = cos psi/(2 pi r). The shear energy W = int w(lam_phi) da depends
on u alone; its derivative by finite differences must equal the work -int F.dX da of the load of
:func:`lubrication.membrane.membrane_load`, to <= 1e-6 relative.
"""

import math

import numpy as np
import pytest
from numpy.polynomial import Polynomial, chebyshev
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from lubrication.checks import InvalidParameterError
from lubrication.equations import (
    capillary_number,
    gap_flow,
    rhs_bending,
    rhs_high_ca,
    shear_modulus,
)
from lubrication.membrane import (
    BICONCAVE_NU_MAX,
    EVANS_FUNG_1972,
    REFERENCE_SHAPES,
    MembraneShear,
    evans_fung_profile,
    membrane_load,
    reference_shape,
    shear_energy_density,
    spheroid_profile,
    tension_difference,
)

AREA = 4.0 * math.pi                       # area radius 1
GAUSS = np.polynomial.legendre.leggauss(300)


def _gauss(f):
    """Integral over 0 <= a <= AREA of f(a) (vectorised) by Gauss-Legendre."""
    x, w = GAUSS
    a = 0.5 * AREA * (x + 1.0)
    return float(np.sum(0.5 * AREA * w * f(a)))


# --------------------------------------------------------------------------- the law
def test_tension_difference_is_the_work_conjugate_of_the_energy():
    """An area-preserving stretch d lam_phi does work (tau_phi - tau_s) d lam_phi/lam_phi:
    f = -(lam/2) dw/dlam, by central differences of shear_energy_density."""
    lam = np.linspace(0.3, 3.0, 28)
    h = 1e-6
    dw = (shear_energy_density(lam + h) - shear_energy_density(lam - h)) / (2 * h)
    np.testing.assert_allclose(tension_difference(lam), -0.5 * lam * dw, rtol=1e-8, atol=1e-9)


def test_small_strain_modulus_is_gs():
    """lam_s = 1 + e, lam_phi = 1/(1 + e): tau_s - tau_phi = 4 G_s e + O(e^2), the shear
    modulus G_s of linear two-dimensional elasticity (tau_1 - tau_2 = 2 G_s (eps_1 - eps_2))."""
    e = 1e-6
    assert 2 * tension_difference(1 / (1 + e)) == pytest.approx(4 * e, rel=1e-5)


# --------------------------------------------------------------------------- reference shapes
def test_evans_fung_disc_has_the_published_area_and_volume():
    """Evans & Fung 1972: area ~135 µm², volume ~94 µm³ of their mean cell (reference values
    quoted to 2-3 digits; our quadrature gives 134.1 and 94.09)."""
    x, w = np.polynomial.legendre.leggauss(400)
    theta, wt = 0.5 * math.pi * (x + 1), 0.5 * math.pi * w
    r, _, r_t, z_t = evans_fung_profile(theta)
    R = EVANS_FUNG_1972["R"]
    area = R**2 * np.sum(wt * 2 * math.pi * r * np.hypot(r_t, z_t))
    volume = R**3 * np.sum(wt * -math.pi * r * r * z_t)
    assert area == pytest.approx(135.0, rel=0.01)
    assert volume == pytest.approx(94.0, rel=0.01)
    nu = 6 * math.sqrt(math.pi) * volume / area**1.5
    assert reference_shape("biconcave", nu).aspect == pytest.approx(1.0, abs=1e-10)


@pytest.mark.parametrize("nu", [0.5, 0.61, 0.8, 0.95])
def test_spheroid_reference_against_closed_forms(nu):
    """Oblate spheroid: area 2 pi a^2 (1 + (1 - e^2) atanh(e)/e), volume 4/3 pi a^2 c; the
    reduced volume from them equals nu, and the equator radius is the scale."""
    ref = reference_shape("spheroid", nu)
    k = ref.aspect
    e = math.sqrt(1 - k * k)
    area = 2 * math.pi * (1 + (1 - e * e) * math.atanh(e) / e)
    volume = 4 / 3 * math.pi * k
    assert 6 * math.sqrt(math.pi) * volume / area**1.5 == pytest.approx(nu, rel=1e-11)
    assert ref.scale == pytest.approx(math.sqrt(4 * math.pi / area), rel=1e-12)
    assert float(ref.radius_sq(AREA / 2)) == pytest.approx(ref.scale**2, rel=1e-11)


def test_biconcave_family_peaks_just_above_its_stated_maximum():
    """BICONCAVE_NU_MAX is the family's largest reduced volume, rounded down."""
    def nu_of(k):
        x, w = np.polynomial.legendre.leggauss(400)
        theta, wt = 0.5 * math.pi * (x + 1), 0.5 * math.pi * w
        r, _, r_t, z_t = evans_fung_profile(theta, k)
        area = np.sum(wt * 2 * math.pi * r * np.hypot(r_t, z_t))
        return 6 * math.sqrt(math.pi) * np.sum(wt * -math.pi * r * r * z_t) / area**1.5

    peak = -minimize_scalar(lambda k: -nu_of(k), bounds=(1, 4), method="bounded").fun
    assert BICONCAVE_NU_MAX < peak < BICONCAVE_NU_MAX + 1e-3
    reference_shape("biconcave", BICONCAVE_NU_MAX)
    with pytest.raises(InvalidParameterError, match="nu=0.75.*reference='spheroid'"):
        reference_shape("biconcave", 0.75)


@pytest.mark.parametrize("name, nu", [("biconcave", 0.61), ("biconcave", 0.7),
                                      ("spheroid", 0.61), ("spheroid", 0.9)])
def test_material_map_against_direct_quadrature(name, nu):
    """r_ref^2(a) of the Chebyshev series equals the parametric profile at the area a(theta)
    found by adaptive quadrature (scipy.quad), an independent route, to 1e-11."""
    ref = reference_shape(name, nu)
    profile = evans_fung_profile if name == "biconcave" else spheroid_profile

    def density(t):
        r, _, r_t, z_t = profile(t, ref.aspect)
        return 2 * math.pi * r * math.hypot(r_t, z_t) * ref.scale**2

    for theta in np.random.default_rng(1).uniform(0.01, math.pi - 0.01, 12):
        a = quad(density, 0.0, theta, epsabs=1e-13, epsrel=1e-13, limit=200)[0]
        r = ref.scale * profile(theta, ref.aspect)[0]
        assert float(ref.radius_squared(a, AREA)) == pytest.approx(r * r, rel=1e-11, abs=1e-13)


@pytest.mark.parametrize("name", REFERENCE_SHAPES)
def test_reference_shape_carries_no_shear_load(name):
    """On the reference itself (geometry from the parametric profile, area by quadrature) the
    stretch is 1 and the load of membrane_load vanishes to round-off."""
    ref = reference_shape(name, 0.61)
    shear = MembraneShear(1.0, ref, AREA)
    profile = evans_fung_profile if name == "biconcave" else spheroid_profile
    theta = np.linspace(0.05, math.pi - 0.05, 40)
    cheb = chebyshev.Chebyshev.interpolate(
        lambda t: 2 * math.pi * profile(t, ref.aspect)[0]
        * np.hypot(*profile(t, ref.aspect)[2:]) * ref.scale**2, 300, domain=[0, math.pi])
    a = cheb.integ(lbnd=0.0)(theta)
    r, _, r_t, z_t = profile(theta, ref.aspect)
    r = ref.scale * r
    np.testing.assert_allclose(shear.stretch_squared(r, a), 1.0, rtol=0, atol=1e-12)
    f = shear.tension_difference(r, a)
    psi = np.arctan2(-r_t, -z_t)        # dr/ds = -sin psi, dx/ds = cos psi with x = -z
    F_n, F_t = membrane_load(r, psi, np.zeros_like(r), f, -f, np.zeros_like(r))
    assert np.max(np.abs(F_n)) < 1e-11 and np.max(np.abs(F_t)) < 1e-11


# --------------------------------------------------------------------------- virtual work
def _sphere(area):
    """u = r^2 of a sphere of area ``area`` as a polynomial in a: a (A - a)/(pi A)."""
    return Polynomial([0.0, 1.0 / math.pi, -1.0 / (math.pi * area)])


def _shape_quantities(u, a):
    """r, psi, c_s and x'(a) of the shape u(a) = r^2 at the points a (cos psi > 0)."""
    du, d2u = u.deriv()(a), u.deriv(2)(a)
    r = np.sqrt(u(a))
    sin = -math.pi * du
    cos = np.sqrt(1.0 - sin * sin)
    psi = np.arctan2(sin, cos)
    c_s = 2 * math.pi**2 * r * d2u / cos          # -dpsi/ds = -2 pi r dpsi/da
    return r, psi, c_s, cos / (2 * math.pi * r)


def _case(seed, name):
    """A current shape (prolate-ish, cos psi > 0), a random area-preserving perturbation du and
    a random isotropic tension sigma(a) (it must do no work), for the reference ``name``."""
    rng = np.random.default_rng(seed)
    xi = Polynomial([0.0, 1.0 / AREA])                               # a / A
    bump = Polynomial([1.0]) - 1.2 * xi * (1 - xi) + rng.uniform(-0.2, 0.2) * xi**2 * (1 - xi)
    u = _sphere(AREA) * bump
    a = np.linspace(1e-9, AREA - 1e-9, 2001)
    assert np.all(np.abs(math.pi * u.deriv()(a)) < 1.0) and np.all(u(a) > 0)   # a valid shape
    q = Polynomial(rng.normal(size=5))(xi)                           # a polynomial in a/A
    du = _sphere(AREA) * xi * (1 - xi) * q                            # O(a^2) at both poles
    sigma = Polynomial(rng.normal(size=4))(xi)
    return u, du, sigma, reference_shape(name, 0.61)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("name", REFERENCE_SHAPES)
def test_shear_load_is_the_variation_of_the_strain_energy(seed, name):
    """dW/deps (central differences) = -int F.dX dA for random area-preserving
    perturbations, with F from membrane_load of tau_s = sigma + G_s f, tau_phi = sigma - G_s f
    and a random isotropic sigma(a); G_s = 1. Agreement <= 1e-6 relative (measured 1e-12 - 1e-11)."""
    u, du, sigma, ref = _case(seed, name)
    shear = MembraneShear(1.0, ref, AREA)
    ref_sq = ref.radius_sq                                # area 4 pi: no rescaling

    def energy(eps):
        v = u + eps * du
        return _gauss(lambda a: shear_energy_density(np.sqrt(v(a) / ref_sq(a))))

    eps = 1e-4                      # fourth-order central differences: error ~ eps^4
    dW = (8 * (energy(eps) - energy(-eps)) - (energy(2 * eps) - energy(-2 * eps))) / (12 * eps)

    def stretch_sq_and_slope(a):
        L = u(a) / ref_sq(a)
        return L, (u.deriv()(a) * ref_sq(a) - u(a) * ref_sq.deriv()(a)) / ref_sq(a) ** 2

    # axial displacement dx(a) = int_0^a d(x')/d eps (an analytic function of a)
    def dx_prime(a):
        up, dup = u.deriv()(a), du.deriv()(a)
        root = np.sqrt(1 - (math.pi * up) ** 2)
        return (-(math.pi**2) * up * dup / root / (2 * math.pi * np.sqrt(u(a)))
                - root * du(a) / (4 * math.pi * u(a) ** 1.5))

    dx = chebyshev.Chebyshev.interpolate(dx_prime, 200, domain=[0, AREA]).integ(lbnd=0.0)

    def work_density(a):
        r, psi, c_s, _ = _shape_quantities(u, a)
        L, dL = stretch_sq_and_slope(a)
        f = shear.tension_difference(r, a)
        df_da = -0.5 * (1 / L**2 + 1) * dL
        tau_s, tau_phi = sigma(a) + f, sigma(a) - f
        dtau_ds = 2 * math.pi * r * (sigma.deriv()(a) + df_da)
        F_n, F_t = membrane_load(r, psi, c_s, tau_s, tau_phi, dtau_ds)
        dr = du(a) / (2 * r)
        dX_n = dx(a) * np.sin(psi) + dr * np.cos(psi)
        dX_t = dx(a) * np.cos(psi) - dr * np.sin(psi)
        return F_n * dX_n + F_t * dX_t

    work = -_gauss(work_density)
    assert abs(dW) > 1e-3                                  # a perturbation that does work
    assert work == pytest.approx(dW, rel=1e-6), f"{work=}, {dW=}"


def test_wrong_sign_of_the_hoop_term_fails_virtual_work():
    """The same check with tau_phi's role flipped in the tangential balance misses by O(1):
    the test can tell the conventions apart."""
    u, _, _, ref = _case(0, "biconcave")
    shear = MembraneShear(1.0, ref, AREA)
    a = np.linspace(0.5, AREA - 0.5, 7)
    r, psi, c_s, _ = _shape_quantities(u, a)
    f = shear.tension_difference(r, a)
    _, F_t = membrane_load(r, psi, c_s, f, -f, np.zeros_like(a))
    _, F_t_flipped = membrane_load(r, psi, c_s, -f, f, np.zeros_like(a))
    assert np.max(np.abs(F_t - F_t_flipped)) > 0.1


# --------------------------------------------------------------------------- equations
def _random_states(rng, n, area):
    r = rng.uniform(0.1, 0.95, n)
    psi = rng.uniform(-1.2, 1.2, n)
    A = rng.uniform(0.05, 0.95, n) * area
    return r, psi, A


@pytest.mark.parametrize("name", REFERENCE_SHAPES)
def test_high_ca_right_hand_side_is_the_membrane_balance(name):
    """rhs_high_ca with shear: p = F_n and -e_m = F_t of membrane_load with tau_s the state,
    tau_phi = tau_s - 2 G_s f, c_s = -psi'/S and tau_s' from the right-hand side."""
    rng = np.random.default_rng(3)
    area = 4 * math.pi * 1.3**2
    shear = MembraneShear(0.3, reference_shape(name, 0.61), area)
    r, psi, A = _random_states(rng, 50, area)
    p, tau_s = rng.normal(size=50) * 10, rng.uniform(5, 50, 50)
    Q, S = 0.1, 7.0
    y = np.vstack((r, psi, p, tau_s, A, np.zeros(50)))
    dy = rhs_high_ca(np.linspace(0, 1, 50), y, np.array([Q, S]), shear)
    tau_phi = tau_s - 2 * shear_modulus(0.3, Q) * shear.tension_difference(r, A)
    F_n, F_t = membrane_load(r, psi, -dy[1] / S, tau_s, tau_phi, dy[3] / S)
    np.testing.assert_allclose(F_n, p, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(F_t, -gap_flow(r, Q)[1], rtol=1e-12, atol=1e-12)


def test_bending_right_hand_side_adds_the_elastic_load():
    """rhs_bending with shear minus without: the normal balance gains -(F_n(tau, tau_phi) -
    F_n(tau, tau)) and the tangential balance is F_t = -Ca e_m with tau_s' from the rhs."""
    rng = np.random.default_rng(4)
    lam, ca_b, Q, S = 1.1, 50.0, 0.15, 6.0
    area = 4 * math.pi * (lam * 0.61 ** (-1 / 3)) ** 2
    shear = MembraneShear(0.2, reference_shape("biconcave", 0.61), area)
    r, psi, A = _random_states(rng, 40, area)
    c_s, q_s, p = rng.normal(size=(3, 40))
    tau = rng.uniform(10, 100, 40)
    y = np.vstack((r, psi, c_s, q_s, p, tau, A, np.zeros(40)))
    t, params = np.linspace(0, 1, 40), np.array([Q, S])
    with_shear = rhs_bending(t, y, params, ca_b, lam, shear)
    vesicle = rhs_bending(t, y, params, ca_b, lam)
    ca = capillary_number(ca_b, lam, Q)
    tau_phi = tau - 2 * shear_modulus(0.2, Q, ca) * shear.tension_difference(r, A)
    F_n, F_t = membrane_load(r, psi, c_s, tau, tau_phi, with_shear[5] / S)
    F_n_iso, _ = membrane_load(r, psi, c_s, tau, tau, 0 * tau)
    np.testing.assert_allclose((with_shear[3] - vesicle[3]) / S, -(F_n - F_n_iso), atol=1e-10)
    np.testing.assert_allclose(F_t, vesicle[5] / S, rtol=1e-12)
    for i in (0, 1, 2, 4, 6, 7):
        assert np.array_equal(with_shear[i], vesicle[i])


def test_zero_modulus_gives_the_vesicle_equations_bit_for_bit():
    """G_s = 0 (Ca_S = inf) through the shear branch reproduces both right-hand sides exactly."""
    rng = np.random.default_rng(5)
    area = 4 * math.pi * 1.2**2
    shear = MembraneShear(math.inf, reference_shape("biconcave", 0.61), area)
    r, psi, A = _random_states(rng, 30, area)
    t, params = np.linspace(0, 1, 30), np.array([0.1, 5.0])
    y6 = np.vstack((r, psi, rng.normal(size=30), rng.uniform(1, 9, 30), A, np.zeros(30)))
    assert np.array_equal(rhs_high_ca(t, y6, params, shear), rhs_high_ca(t, y6, params))
    y8 = np.vstack((r, psi, *rng.normal(size=(3, 30)), rng.uniform(1, 9, 30), A, np.zeros(30)))
    assert np.array_equal(rhs_bending(t, y8, params, 50.0, 1.2, shear),
                          rhs_bending(t, y8, params, 50.0, 1.2))
