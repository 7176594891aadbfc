r"""Equations of the lubrication ("parallel-flow") model of a vesicle in a tube.

Model (Secomb, Skalak, Özkaya & Gross 1986; Barakat & Shaqfeh 2018b). Steady, axisymmetric,
inertialess. In the frame of the vesicle the shape is steady, and an inextensible membrane with
no tangential velocity at the poles is **at rest** in that frame, so the viscosity of the
interior drops out. At every axial station the gap between the membrane (radius :math:`r`, at
rest) and the wall (radius 1, moving at :math:`-1`) carries fully developed annular
Couette-Poiseuille flow.

Nondimensionalisation (stated once, used in this module and in :mod:`lubrication.solve`)
------------------------------------------------------------------------------------------
* lengths by the tube radius :math:`R`; velocities by the vesicle velocity :math:`V`;
* :math:`Q \equiv 1 - U/V` with :math:`U` the mean velocity of the undisturbed Poiseuille flow:
  the flux through every cross-section of the gap, in the vesicle frame, is :math:`-\pi Q`
  (:math:`V/U = 1/(1 - Q)`; for a uniform film :math:`Q \approx h/R`);
* high-Ca model: pressure :math:`p` (gap minus inside) in :math:`\eta V/R`, tension
  :math:`\sigma` in :math:`\eta V`;
* bending model: :math:`p` in :math:`\kappa/R^3`, :math:`\sigma` in :math:`\kappa/R^2`,
  transverse shear tension :math:`q_s` in :math:`\kappa/R^3`, and the capillary number
  :math:`\mathrm{Ca} = \eta V R^2/\kappa = \mathrm{Ca}_B/(\lambda^2(1 - Q))`
  (:func:`capillary_number`, the only place where the conversion is made).

* red-cell membrane (optional, :mod:`lubrication.membrane`): shear modulus :math:`G_s` through
  the shear capillary number :math:`\mathrm{Ca}_S = \eta U/G_s`, in the model's tension unit
  :math:`G_s/(\eta V) = (1 - Q)/\mathrm{Ca}_S` (high-Ca) or
  :math:`G_s R^2/\kappa = \mathrm{Ca}_B/(\lambda^2\mathrm{Ca}_S)` (bending)
  (:func:`shear_modulus`, the only place where that conversion is made).

The module reads in the order of the method: (1) the local gap flow, exact and as series near
the wall, (2) the capillary and shear numbers, (3) the polar caps, (4) the right-hand sides of the
two boundary-value problems, with or without shear elasticity.

References
----------
* Secomb, Skalak, Özkaya & Gross 1986, J. Fluid Mech. 163, 405-423,
  doi:10.1017/S0022112086002355.
* Barakat & Shaqfeh 2018b, J. Fluid Mech. 835, 721-761 and 2018a, J. Fluid Mech. 851, 606-635
  (lubrication equations, the series of the membrane shear rate, the polar treatment).
* Chen, Lyu, Jaeger & Leonetti 2020, appendix "Lubrication theory" (eq. lubp, eq. shear).
"""

from __future__ import annotations

import math

import numpy as np

from .checks import as_finite, check_range, scalar_or_array

__all__ = [
    "SERIES_GAP",
    "gap_velocity",
    "pressure_gradient",
    "membrane_shear_rate",
    "wall_shear_rate",
    "pressure_gradient_series",
    "membrane_shear_rate_series",
    "wall_shear_rate_series",
    "capillary_number",
    "shear_modulus",
    "spherical_cap",
    "rhs_high_ca",
    "rhs_bending",
    "HIGH_CA_STATE",
    "BENDING_STATE",
]

# --------------------------------------------------------------------------- 1. local gap flow
# Below the gap d = 1 - r = SERIES_GAP the exact forms are replaced by their Taylor series in d.
# The exact forms subtract O(1) terms to leave an O(d^2) denominator, so they lose ~ eps/d^2 of
# relative accuracy (measured against 40-digit mpmath with ln r = log1p(-d): 1.7e-8 at d = 1e-4,
# 1.5e-12 at d = 1e-2; with log(r) 7.5e-5 at d = 1e-4); the series truncated after 7 terms errs
# by ~ 0.2 d^6 relative (the next coefficients are ~ 0.4). The two errors cross near d = 0.013. Measured over 1e-7 <= d < 1 and
# 1e-4 <= Q <= 0.45: largest relative error 2.5e-12 (G, e_m, e_w), just above the switch.
# Near the axis nothing cancels (ln r is taken from r itself there): error ~ 3e-16 down to
# r = 1e-8.
SERIES_GAP = 0.0125

# Taylor coefficients in d = 1 - r, each (a_k, b_k) for the coefficient a_k + b_k Q of d^k from
# the lowest power up. Derived with sympy from the exact forms below (the derivation is repeated
# in tests/lubrication/test_equations.py). Barakat & Shaqfeh's published code has 32/20 in place
# of 23/20 in the d^1 coefficient of e_m; sympy gives 23/20.
_G_SERIES = (-3, ((0.0, 6.0), (-6.0, 3.0), (-2.0, 7 / 5), (-9 / 10, 3 / 5),
                  (-2 / 5, 299 / 1400), (-229 / 1400, 19 / 560), (-73 / 1400, -39 / 875)))
_EM_SERIES = (-2, ((0.0, -3.0), (2.0, -2.0), (1.0, -29 / 20), (7 / 10, -23 / 20),
                   (11 / 20, -2749 / 2800), (657 / 1400, -309 / 350), (237 / 560, -45967 / 56000)))
_EW_SERIES = (-2, ((0.0, 3.0), (-4.0, 1.0), (0.0, 9 / 20), (-1 / 5, 1 / 5),
                   (-1 / 10, 229 / 2800), (-31 / 700, 73 / 2800), (-23 / 1400, 27 / 56000)))


def _series(coefficients, d, Q):
    """Evaluate sum_k (a_k + b_k Q) d^k by Horner's rule (d > 0)."""
    lowest, ab = coefficients
    acc = np.zeros(np.broadcast(d, Q).shape)
    for a, b in reversed(ab):
        acc = acc * d + (a + b * Q)
    return acc * d**lowest


def _gap_flow_exact(r, d, Q):
    """Exact G, e_m, e_w for 0 < r < 1 given both r and d = 1 - r (no checks)."""
    # ln r from whichever of r, d is exact: log1p(-d) near the wall, log(r) near the axis.
    L = np.where(r > 0.5, np.log1p(-d), np.log(r))
    a = d * (1.0 + r)                                     # 1 - r^2 without cancellation
    G = 8.0 / a * (Q - 1.0 - a / (2.0 * L)) / (1.0 + r * r + a / L)
    e_m = 0.25 * G * (2.0 * r + a / (r * L)) + 1.0 / (r * L)
    e_w = 0.25 * G * (2.0 + a / L) + 1.0 / L
    return G, e_m, e_w


def gap_flow(r, Q):
    """G, e_m, e_w of the annular gap, exact or series below SERIES_GAP (no checks, 0 < r < 1)."""
    r, Q = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(Q, dtype=float))
    d = 1.0 - r
    near = d < SERIES_GAP
    # Evaluate each branch where it is accurate; fill the other points with a harmless r = 1/2.
    r_far = np.where(near, 0.5, r)
    G, e_m, e_w = _gap_flow_exact(r_far, 1.0 - r_far, Q)
    if near.any():
        d_near = np.where(near, d, SERIES_GAP)
        G = np.where(near, _series(_G_SERIES, d_near, Q), G)
        e_m = np.where(near, _series(_EM_SERIES, d_near, Q), e_m)
        e_w = np.where(near, _series(_EW_SERIES, d_near, Q), e_w)
    return G, e_m, e_w


def _check_radius(r) -> np.ndarray:
    return check_range("r", r, 0.0, 1.0, lo_open=True, hi_open=True,
                       reason="the membrane radius lies between the axis and the wall (units of R)")


def _check_gap(d) -> np.ndarray:
    return check_range("d", d, 0.0, 1.0, lo_open=True, hi_open=True,
                       reason="the gap d = 1 - r lies between 0 (wall) and 1 (axis), units of R")


def gap_velocity(rho, r, Q):
    r"""Axial velocity :math:`u(\rho)` in the gap, vesicle frame, units of :math:`V`.

    .. math:: u = \frac{G}{4}(\rho^2 - r^2) + B\ln\frac{\rho}{r}, \qquad
              B = \frac{1 + \frac{G}{4}(1 - r^2)}{\ln r}

    so that :math:`u(r) = 0` (membrane at rest) and :math:`u(1) = -1` (wall), with
    :math:`G` from :func:`pressure_gradient`. Chen et al. 2020 eq. lub.

    Parameters
    ----------
    rho : float or array_like
        Radial position, r <= rho <= 1 [R].
    r : float
        Membrane radius, 0 < r < 1 [R].
    Q : float
        Leak-back flux parameter 1 - U/V [-].

    Returns
    -------
    u : float or ndarray
        Axial velocity [V].

    Examples
    --------
    >>> float(gap_velocity(1.0, 0.5, 0.1))
    -1.0
    """
    r = float(_check_radius(r))
    Q = float(as_finite("Q", Q))
    rho = check_range("rho", rho, r, 1.0, reason="rho lies in the gap between membrane and wall")
    G = float(gap_flow(r, Q)[0])
    B = (1.0 + 0.25 * G * (1.0 - r * r)) / math.log(r)
    return scalar_or_array(0.25 * G * (rho**2 - r * r) + B * np.log(rho / r))


def pressure_gradient(r, Q):
    r"""Axial pressure gradient :math:`G = \mathrm{d}p/\mathrm{d}x` in the gap [ηV/R²].

    .. math:: G = \frac{8}{1 - r^2}\,
              \frac{Q - 1 - (1 - r^2)/(2\ln r)}{1 + r^2 + (1 - r^2)/\ln r}

    The Reynolds equation of the annular gap with the membrane at rest and the wall at
    :math:`-V` carrying the flux :math:`-\pi Q` (Chen et al. 2020 eq. lubp; Secomb et al. 1986).
    :math:`G \to -8(1 - Q)` as :math:`r \to 0` (Poiseuille at the mean velocity U). For
    ``1 - r < SERIES_GAP`` the series :func:`pressure_gradient_series` is used.

    Parameters
    ----------
    r : float or array_like
        Membrane radius, 0 < r < 1 [R].
    Q : float or array_like
        Leak-back flux parameter 1 - U/V [-].

    Returns
    -------
    G : float or ndarray
        dp/dx [eta V / R^2].

    Examples
    --------
    >>> pressure_gradient([0.5, 0.9], 0.05).round(4)
    array([ -25.9709, -305.2106])
    """
    return scalar_or_array(gap_flow(_check_radius(r), as_finite("Q", Q))[0])


def membrane_shear_rate(r, Q):
    r"""Shear rate of the gap flow at the membrane, :math:`e_m = \partial u/\partial\rho|_{\rho=r}` [V/R].

    .. math:: e_m = \frac{G}{4}\left[2r + \frac{1 - r^2}{r\ln r}\right] + \frac{1}{r\ln r}

    Chen et al. 2020 eq. shear (there multiplied by η). Positive when the fluid next to the
    membrane moves forward (+x). Diverges like :math:`1/(r\ln r)` at the poles. For
    ``1 - r < SERIES_GAP`` the series :func:`membrane_shear_rate_series` is used. ``r``, ``Q``
    and the form of the result (float or ndarray) as in :func:`pressure_gradient`.

    Examples
    --------
    >>> round(membrane_shear_rate(0.9, 0.05), 6)
    4.997226
    """
    return scalar_or_array(gap_flow(_check_radius(r), as_finite("Q", Q))[1])


def wall_shear_rate(r, Q):
    r"""Shear rate of the gap flow at the wall, :math:`e_w = \partial u/\partial\rho|_{\rho=1}` [V/R].

    .. math:: e_w = \frac{G}{4}\left[2 + \frac{1 - r^2}{\ln r}\right] + \frac{1}{\ln r}

    Momentum balance of the gap fluid: :math:`e_w = r e_m + G(1 - r^2)/2`. ``r``, ``Q`` and the
    form of the result as in :func:`pressure_gradient`.

    Examples
    --------
    >>> r, Q = 0.9, 0.05
    >>> round(wall_shear_rate(r, Q), 5)
    -24.4975
    >>> round(r * membrane_shear_rate(r, Q) + pressure_gradient(r, Q) * (1 - r**2) / 2, 5)
    -24.4975
    """
    return scalar_or_array(gap_flow(_check_radius(r), as_finite("Q", Q))[2])


def pressure_gradient_series(d, Q):
    r"""Taylor series of :func:`pressure_gradient` in the gap :math:`d = 1 - r`, through :math:`d^3`.

    .. math:: G = \frac{6Q}{d^3} - \frac{6 - 3Q}{d^2} - \frac{2 - \frac{7}{5}Q}{d}
              - \frac{9}{10} + \frac{3}{5}Q + \dots

    Each ``*_series`` function sums seven terms, whose coefficients (``_G_SERIES``,
    ``_EM_SERIES``, ``_EW_SERIES``) were derived with sympy from the exact form; the exact
    functions switch to them for ``1 - r < SERIES_GAP``.

    Parameters
    ----------
    d : float or array_like
        Gap 1 - r, 0 < d < 1 [R].
    Q : float or array_like
        Leak-back flux parameter, as in :func:`pressure_gradient` [-].

    Examples
    --------
    >>> round(pressure_gradient_series(0.01, 0.005), 2) == round(pressure_gradient(0.99, 0.005), 2)
    True
    """
    return scalar_or_array(_series(_G_SERIES, _check_gap(d), as_finite("Q", Q)))


def membrane_shear_rate_series(d, Q):
    r"""Taylor series of :func:`membrane_shear_rate` in the gap :math:`d = 1 - r`, through :math:`d^4`.

    .. math:: e_m \approx -\frac{3Q}{d^2} + \frac{2(1 - Q)}{d} + \left(1 - \frac{29}{20}Q\right)
              + d\left(\frac{7}{10} - \frac{23}{20}Q\right)
              + d^2\left(\frac{11}{20} - \frac{2749}{2800}Q\right)
              + d^3\left(\frac{657}{1400} - \frac{309}{350}Q\right)
              + d^4\left(\frac{237}{560} - \frac{45967}{56000}Q\right)

    Barakat & Shaqfeh 2018b (their code has 32/20 for 23/20; the coefficients here were derived
    with sympy). Finite at the axis (d = 1), unlike the exact form. ``d`` and ``Q`` as in
    :func:`pressure_gradient_series`.

    Examples
    --------
    >>> round(membrane_shear_rate_series(0.5, 0.1), 6)
    3.729401
    """
    return scalar_or_array(_series(_EM_SERIES, _check_gap(d), as_finite("Q", Q)))


def wall_shear_rate_series(d, Q):
    r"""Taylor series of :func:`wall_shear_rate` in :math:`d = 1 - r`, through :math:`d^4`.

    .. math:: e_w = \frac{3Q}{d^2} - \frac{4 - Q}{d} + \frac{9}{20}Q + \dots

    ``d``, ``Q`` and the source of the coefficients (``_EW_SERIES``) as in
    :func:`pressure_gradient_series`.

    Examples
    --------
    >>> round(wall_shear_rate_series(0.01, 0.005), 2) == round(wall_shear_rate(0.99, 0.005), 2)
    True
    """
    return scalar_or_array(_series(_EW_SERIES, _check_gap(d), as_finite("Q", Q)))


# --------------------------------------------------------------------------- 2. capillary number
def capillary_number(ca_b, lam, Q):
    r"""Capillary number of the bending model, :math:`\mathrm{Ca} = \eta V R^2/\kappa`.

    .. math:: \mathrm{Ca} = \frac{\mathrm{Ca}_B}{\lambda^2 (1 - Q)},
              \qquad \mathrm{Ca}_B = \eta U R_0^2/\kappa,\ \lambda = R_0/R,\ V/U = 1/(1 - Q)

    The single place where the user's :math:`\mathrm{Ca}_B` (built on U and R0) is converted
    to the model's scale (V and R). Q is an unknown of the boundary-value problem, so the
    right-hand side :func:`rhs_bending` calls this with the current iterate of Q.

    Examples
    --------
    >>> capillary_number(50.0, 1.0, 0.5)
    100.0
    """
    return ca_b / (lam * lam * (1.0 - Q))


def shear_modulus(ca_s, Q, ca=1.0):
    r"""Membrane shear modulus :math:`G_s` in the model's tension unit.

    .. math:: \frac{G_s}{\eta V} = \frac{U}{V}\,\frac{G_s}{\eta U}
              = \frac{1 - Q}{\mathrm{Ca}_S}, \qquad
              \frac{G_s R^2}{\kappa} = \mathrm{Ca}\,\frac{G_s}{\eta V}
              = \frac{\mathrm{Ca}_B}{\lambda^2\,\mathrm{Ca}_S},
              \qquad \mathrm{Ca}_S = \frac{\eta U}{G_s}

    with :math:`\mathrm{Ca} = \eta V R^2/\kappa` of :func:`capillary_number` (``ca=1``: the
    high-Ca model, tensions in ηV). The single place where the user's
    :math:`\mathrm{Ca}_S` (built, like :math:`\mathrm{Ca}_B`, on the mean velocity U) is
    converted to the model's scale; Q is the current iterate of the boundary-value problem.

    Examples
    --------
    >>> shear_modulus(0.2, 0.5)                 # G_s = 5 eta U = 2.5 eta V
    2.5
    >>> shear_modulus(0.2, 0.5, capillary_number(50.0, 1.0, 0.5)) == 50.0 / 0.2
    True
    """
    return ca * (1.0 - Q) / ca_s


# --------------------------------------------------------------------------- 3. polar caps
def spherical_cap(curvature, rim_radius):
    r"""Polar angle, area and volume of a spherical cap cut at the radius ``rim_radius``.

    The cap has curvature ``k`` (1/radius; > 0 convex, < 0 concave, as seen from outside) and
    rim radius :math:`\varepsilon`: :math:`\sin\theta = \varepsilon k`,
    area :math:`2\pi(1 - \cos\theta)/k^2`, volume of revolution swept from the pole to the rim
    :math:`\pi(1 - \cos\theta)^2(2 + \cos\theta)/(3k^3)` (negative for a concave cap: its rim
    lies behind the pole). Used to excise the polar caps, where the parallel-flow model does not
    hold and its membrane shear rate is singular, from the boundary-value problem: inside the
    cap the pressure and tension are taken uniform, so the cap is spherical.

    Parameters
    ----------
    curvature : float or ndarray
        Cap curvature k [1/R], with ``|k rim_radius|`` < 1.
    rim_radius : float
        Rim radius epsilon [R].

    Returns
    -------
    theta, area, volume : float or ndarray
        Polar angle of the rim [rad] (signed like k), area [R^2], volume [R^3].

    Examples
    --------
    >>> theta, area, volume = spherical_cap(1.0, 1.0)      # hemisphere of radius 1
    >>> [round(float(x) / math.pi, 12) for x in (theta, area, volume)]
    [0.5, 2.0, 0.666666666667]
    """
    k = np.asarray(curvature, dtype=float)
    sin_t = np.clip(k * rim_radius, -1.0, 1.0)
    cos_t = np.sqrt(1.0 - sin_t * sin_t)
    one_minus_cos = sin_t * sin_t / (1.0 + cos_t)          # 1 - cos(theta) without cancellation
    # area and volume as series in k when the cap is nearly flat (k -> 0 is a flat disc)
    k_safe = np.where(np.abs(k) * rim_radius > 1e-4, k, 1.0)
    flat = np.abs(k) * rim_radius <= 1e-4
    area = np.where(flat, math.pi * rim_radius**2 * (1.0 + 0.25 * (k * rim_radius) ** 2),
                    2.0 * math.pi * one_minus_cos / k_safe**2)
    volume = np.where(flat, 0.25 * math.pi * k * rim_radius**4,
                      math.pi * one_minus_cos**2 * (2.0 + cos_t) / (3.0 * k_safe**3))
    return np.arcsin(sin_t), area, volume


# --------------------------------------------------------------------------- 4. right-hand sides
# Order of the unknowns in the state vector y of each model (the parameters are [Q, S]).
HIGH_CA_STATE = ("r", "psi", "p", "sigma", "A", "Omega")
BENDING_STATE = ("r", "psi", "c_s", "q_s", "p", "sigma", "A", "Omega")

# Guards for Newton iterates that leave the physical domain. Converged solutions never reach
# them: the solver excises polar caps of rim radius 2e-3 > POLE_RADIUS, and its thinnest films
# (7e-5 at lam/lam_c = 0.9999) are far above D_FLOOR. Below POLE_RADIUS
# the spherical-cap limit replaces cos(psi)/r (Barakat & Shaqfeh use 2e-3, high-Ca); the gap flow
# is evaluated at r >= R_FLOOR and d = 1 - r >= D_FLOOR (so no division by zero or log of 0).
POLE_RADIUS = 5e-4
R_FLOOR = 1e-6
D_FLOOR = 1e-8


def _clipped_gap_flow(r, Q):
    r_eval = np.clip(r, R_FLOOR, 1.0 - D_FLOOR)
    return gap_flow(r_eval, Q)


def _shear_terms(shear, r, a, polar, modulus):
    """tau_s - tau_phi = 2 G_s f at radius r and area coordinate a (0 inside POLE_RADIUS, where
    f ~ r^2 vanishes and Newton iterates may carry any a)."""
    return np.where(polar, 0.0, 2.0 * modulus * shear.tension_difference(r, a))


def rhs_high_ca(t, y, params, shear=None):
    r"""Right-hand side of the high-Ca (κ → 0) model, vectorised for :func:`scipy.integrate.solve_bvp`.

    Arc length from the rear pole, :math:`s = S t`; :math:`\psi` tilt angle
    (:math:`\mathrm{d}r/\mathrm{d}s = -\sin\psi`, :math:`\mathrm{d}x/\mathrm{d}s = \cos\psi`);
    normal balance :math:`p = \sigma(c_s + c_\varphi)` with :math:`c_s = -\mathrm{d}\psi/\mathrm{d}s`,
    :math:`c_\varphi = -\cos\psi/r`; tangential balance :math:`\mathrm{d}\sigma/\mathrm{d}s = -e_m`:

    .. math:: r' = -S\sin\psi,\quad \psi' = S\left(-\frac{p}{\sigma} - \frac{\cos\psi}{r}\right),\quad
              p' = S G\cos\psi,\quad \sigma' = -S e_m,\quad A' = 2\pi S r,\quad
              \Omega' = \pi S r^2\cos\psi

    (Secomb et al. 1986; Barakat & Shaqfeh 2018b). Below ``POLE_RADIUS`` the spherical-cap
    limit :math:`\psi' = -S p/(2\sigma)` is used.

    **Red-cell membrane** (``shear`` given, :mod:`lubrication.membrane`): the slot ``sigma``
    holds the meridional tension :math:`\tau_s`, and :math:`\tau_\varphi = \tau_s - 2G_s f`
    with :math:`f` the deviatoric tension at the stretch :math:`\lambda_\varphi = r/
    r_\mathrm{ref}(A)` and :math:`G_s` from :func:`shear_modulus`. The normal balance
    :math:`p = \tau_s c_s + \tau_\varphi c_\varphi` and the tangential balance
    :math:`\mathrm{d}\tau_s/\mathrm{d}s + (\tau_s - \tau_\varphi)r^{-1}\mathrm{d}r/
    \mathrm{d}s = -e_m` (:func:`lubrication.membrane.membrane_load`) give

    .. math:: \psi' = -S\,\frac{p + \tau_\varphi\cos\psi/r}{\tau_s}, \qquad
              \tau_s' = S\left[-e_m + (\tau_s - \tau_\varphi)\frac{\sin\psi}{r}\right],

    which reduce to the equations above for :math:`G_s = 0`. Carrying :math:`\tau_s` rather
    than :math:`\sigma` keeps derivatives of the reference shape out of the equations.

    Parameters
    ----------
    t : ndarray, shape (m,)
        Mesh in [0, 1].
    y : ndarray, shape (6, m)
        State ``HIGH_CA_STATE`` = (r, psi, p, sigma, A, Omega); p in eta V/R, sigma (or tau_s)
        in eta V.
    params : ndarray, shape (2,)
        (Q, S).
    shear : lubrication.membrane.MembraneShear, optional
        Shear elasticity of a red-cell membrane, area in R^2; None (default): a vesicle.

    Returns
    -------
    dydt : ndarray, shape (6, m)
    """
    r, psi, p, sigma = y[0], y[1], y[2], y[3]
    Q, S = params
    sin, cos = np.sin(psi), np.cos(psi)
    G, e_m, _ = _clipped_gap_flow(r, Q)
    polar = r < POLE_RADIUS
    r_safe = np.where(polar, 1.0, r)
    if shear is None:
        mean = sigma
    else:
        diff = _shear_terms(shear, r, y[4], polar, shear_modulus(shear.ca_s, Q))
        mean = sigma - 0.5 * diff                 # isotropic part (tau_s + tau_phi)/2
    cos_over_r = np.where(polar, -p / (2.0 * mean), cos / r_safe)
    dpsi = -p / sigma - cos_over_r
    dsigma = -e_m
    if shear is not None:
        dpsi = dpsi + diff / sigma * cos_over_r
        dsigma = dsigma + diff * sin / r_safe
    return S * np.vstack((-sin,
                          dpsi,
                          G * cos,
                          dsigma,
                          2.0 * math.pi * r,
                          math.pi * r * r * cos))


def rhs_bending(t, y, params, ca_b, lam, shear=None):
    r"""Right-hand side of the bending (Helfrich) model, vectorised for :func:`scipy.integrate.solve_bvp`.

    .. math::
        r' &= -S\sin\psi, \qquad \psi' = -S c_s, \\
        c_s' &= S\left[\frac{\sin\psi\cos\psi}{r^2} + \frac{c_s\sin\psi}{r} - q_s\right], \\
        q_s' &= S\left[p - \sigma\left(c_s - \frac{\cos\psi}{r}\right)
               + \tfrac12\left(c_s + \frac{\cos\psi}{r}\right)\left(c_s^2 - \frac{\cos^2\psi}{r^2}\right)
               + \frac{q_s\sin\psi}{r}\right], \\
        p' &= S\,\mathrm{Ca}\,G\cos\psi, \qquad \sigma' = -S\,\mathrm{Ca}\,e_m, \qquad
        A' = 2\pi S r, \qquad \Omega' = \pi S r^2\cos\psi

    in bending units (p, q_s in κ/R³, σ in κ/R², curvatures in 1/R), with
    :math:`\mathrm{Ca} = \mathrm{Ca}_B/(\lambda^2(1 - Q))` from :func:`capillary_number` at the
    current iterate of Q.
    Below ``POLE_RADIUS`` the spherical-cap limits (:math:`\cos\psi/r \to -c_s`,
    :math:`q_s \sin\psi/r \to -(p - 2\sigma c_s)/2` at either pole) are used.

    **Red-cell membrane** (``shear`` given): the elastic principal tensions add to the Helfrich
    stresses, whose tangential divergence vanishes for the multiplier :math:`\sigma` (hence
    :math:`\sigma' = -S\,\mathrm{Ca}\,e_m` above). The slot ``sigma`` then holds
    :math:`\tilde\tau_s = \sigma + G_s f` and :math:`\tilde\tau_\varphi = \sigma - G_s f`
    (:func:`rhs_high_ca`; :math:`G_s` in κ/R² from :func:`shear_modulus`); the normal balance
    has :math:`\tilde\tau_s c_s + \tilde\tau_\varphi c_\varphi` in place of
    :math:`\sigma(c_s + c_\varphi)`, the tangential balance that of
    :func:`lubrication.membrane.membrane_load`:

    .. math:: q_s' \mathrel{+}= -S(\tilde\tau_s - \tilde\tau_\varphi)\frac{\cos\psi}{r},
              \qquad
              \tilde\tau_s' = S\left[-\mathrm{Ca}\,e_m
              + (\tilde\tau_s - \tilde\tau_\varphi)\frac{\sin\psi}{r}\right].

    Parameters
    ----------
    t : ndarray, shape (m,)
        Mesh in [0, 1].
    y : ndarray, shape (8, m)
        State ``BENDING_STATE`` = (r, psi, c_s, q_s, p, sigma, A, Omega).
    params : ndarray, shape (2,)
        (Q, S).
    ca_b : float
        :math:`\mathrm{Ca}_B = \eta U R_0^2/\kappa` [-].
    lam : float
        Confinement :math:`\lambda = R_0/R` [-].
    shear : lubrication.membrane.MembraneShear, optional
        Shear elasticity of a red-cell membrane, area in R^2; None (default): a vesicle.

    Returns
    -------
    dydt : ndarray, shape (8, m)
    """
    r, psi, c_s, q_s, p, sigma = y[0], y[1], y[2], y[3], y[4], y[5]
    Q, S = params
    ca = capillary_number(ca_b, lam, Q)
    sin, cos = np.sin(psi), np.cos(psi)
    G, e_m, _ = _clipped_gap_flow(r, Q)
    polar = r < POLE_RADIUS
    r_safe = np.where(polar, 1.0, r)
    cos_over_r = np.where(polar, -c_s, cos / r_safe)
    sin_over_r = sin / r_safe
    dc_s = np.where(polar, -q_s, sin_over_r * (cos_over_r + c_s) - q_s)
    shear_term = np.where(polar, -0.5 * (p - 2.0 * sigma * c_s), q_s * sin_over_r)
    dq_s = (p - sigma * (c_s - cos_over_r)
            + 0.5 * (c_s + cos_over_r) * (c_s * c_s - cos_over_r * cos_over_r) + shear_term)
    dsigma = -ca * e_m
    if shear is not None:
        diff = _shear_terms(shear, r, y[6], polar, shear_modulus(shear.ca_s, Q, ca))
        dq_s = dq_s - diff * cos_over_r
        dsigma = dsigma + diff * sin_over_r
    return S * np.vstack((-sin,
                          -c_s,
                          dc_s,
                          dq_s,
                          ca * G * cos,
                          dsigma,
                          2.0 * math.pi * r,
                          math.pi * r * r * cos))
