r"""Plots of the small-object and near-critical asymptotic laws (:mod:`lubrication.asymptotics`).

Each function draws on the given Axes (or a new headless :class:`matplotlib.figure.Figure`) and
returns the Axes; library code never calls ``plt.show()``. A law is drawn solid inside the range
where its source established it and dashed where it is extrapolated.
"""

from __future__ import annotations

import warnings

import numpy as np

from .asymptotics import (NEAR_CRITICAL_RANGE, SMALL_SPHERE_RANGE, dp_plus_near_critical,
                          dp_plus_small_sphere, speed_near_critical, speed_small_sphere)
from .checks import InvalidParameterError, OutOfRangeWarning
from .geometry import check_reduced_volume, critical_confinement

__all__ = ["plot_speed_asymptotics", "plot_dp_plus_asymptotics", "plot_shape", "plot_sweep"]

_LAM_LABEL = "λ = R0/R [-]"


def _figure(**kwargs):
    """A new headless :class:`matplotlib.figure.Figure` (no pyplot)."""
    from matplotlib.figure import Figure  # lazy: matplotlib
    return Figure(**kwargs)


def _new_axes(ax):
    return _figure().add_subplot() if ax is None else ax


def _draw(ax, nu, law, ylabel, log):
    nu = np.atleast_1d(check_reduced_volume(nu))
    # Small-sphere law: up to lam = 0.6, solid inside its range (lam <= 0.5).
    (lam_hi,) = [hi for name, lo, hi in SMALL_SPHERE_RANGE.bounds if name == "lam"]
    lam_in = np.linspace(0.02, lam_hi, 100)
    lam_out = np.linspace(lam_hi, 0.6, 30)
    small, near = law
    with warnings.catch_warnings():
        # The dashed parts are extrapolations on purpose: silence their OutOfRangeWarning.
        warnings.simplefilter("ignore", OutOfRangeWarning)
        ax.plot(lam_in, small(lam_in), "k-", label="small sphere (Chen eq. small)")
        ax.plot(lam_out, small(lam_out), "k--")
        # Near-critical law: from 0.8 lam_c to lam_c, solid where delta <= 0.1.
        (d_hi,) = [hi for name, lo, hi in NEAR_CRITICAL_RANGE.bounds if name == "delta"]
        for n in nu:
            lam_c = critical_confinement(n)
            frac_in = np.linspace(1.0 - d_hi, 1.0 - 1e-3, 100)   # stop short of the pole at lam_c
            frac_out = np.linspace(0.8, 1.0 - d_hi, 40)
            (line,) = ax.plot(lam_c * frac_in, near(n, lam_c * frac_in), "-",
                              label=f"ν = {n:.3g} (Chen eq. asmyp)")
            ax.plot(lam_c * frac_out, near(n, lam_c * frac_out), "--", color=line.get_color())
    ax.set_xlabel(_LAM_LABEL)
    ax.set_ylabel(ylabel)
    if log:
        ax.set_yscale("log")
    ax.legend(fontsize="small")
    return ax


def plot_speed_asymptotics(nu=(0.6, 0.8, 0.98), ax=None):
    r"""Plot V/U against lam: eq. small1 for lam <= 0.6 and eq. asmyp1 from 0.8 lam_c to lam_c.

    Solid inside the validity range of each law (lam <= 0.5; delta <= 0.1), dashed outside.

    Parameters
    ----------
    nu : sequence of float
        Reduced volumes, 0 < nu <= 1 [-], one near-critical curve each.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure (no GUI) is created when None.

    Returns
    -------
    ax : matplotlib.axes.Axes
        With 2 + 2 len(nu) lines.

    Examples
    --------
    >>> ax = plot_speed_asymptotics()
    >>> len(ax.get_lines()), ax.get_ylabel()
    (8, 'V/U [-]')
    """
    return _draw(_new_axes(ax), nu, (speed_small_sphere, speed_near_critical), "V/U [-]",
                 log=False)


def plot_dp_plus_asymptotics(nu=(0.6, 0.8, 0.98), ax=None):
    r"""Plot Δp⁺R0/(ηU) (log scale) against lam: eq. small2 and eq. asmyp2.

    Small-sphere law for lam <= 0.6, near-critical law from 0.8 lam_c to lam_c; solid inside the
    validity range of each law (lam <= 0.5; delta <= 0.1), dashed outside.

    Parameters
    ----------
    nu : sequence of float
        Reduced volumes, 0 < nu <= 1 [-].
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new figure (no GUI) is created when None.

    Returns
    -------
    ax : matplotlib.axes.Axes
        With 2 + 2 len(nu) lines, logarithmic y axis.

    Examples
    --------
    >>> ax = plot_dp_plus_asymptotics(nu=(0.6,))
    >>> len(ax.get_lines()), ax.get_yscale()
    (4, 'log')
    """
    return _draw(_new_axes(ax), nu, (dp_plus_small_sphere, dp_plus_near_critical),
                 "Δp⁺R0/(ηU) [-]", log=True)


def plot_shape(result, ax=None):
    """Steady shape of a lubrication solution in the tube, coloured by membrane tension.

    Parameters
    ----------
    result : lubrication.results.LubricationResult
        A converged solution (lengths in tube radii).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new headless figure if None.

    Returns
    -------
    ax : matplotlib.axes.Axes

    Raises
    ------
    InvalidParameterError
        ``result`` did not converge (it has no shape to draw).
    """
    if not result.success:
        raise InvalidParameterError("result", "not converged", "a converged LubricationResult",
                                    f"no shape to draw ({result.message})")
    ax = _new_axes(ax)
    x = np.asarray(result.x) - 0.5 * (np.max(result.x) + np.min(result.x))
    r = np.asarray(result.r)
    points = ax.scatter(np.concatenate([x, x]), np.concatenate([r, -r]), s=2,
                        c=np.concatenate([result.tension, result.tension]), cmap="viridis")
    ax.figure.colorbar(points, ax=ax, label="tension γ/(ηU) [-]")
    span = max(1.5, 0.6 * (np.max(x) - np.min(x)) + 0.5)
    for side in (1.0, -1.0):
        ax.plot([-span, span], [side, side], "k-", lw=2)
    ax.annotate("flow →", (0.02, 0.9), xycoords="axes fraction")
    ax.set_aspect("equal")
    ax.set_xlabel("x/R [-]")
    ax.set_ylabel("r/R [-]")
    ax.set_title(f"ν = {result.nu:.3g}, λ/λc = {result.lam_ratio:.4g}, {result.model}: "
                 f"V/U = {result.V_over_U:.4g}, {result.shape_class}", fontsize="small")
    return ax


def plot_sweep(results, axes=None):
    """V/U, Δp⁺R0/(ηU), minimum film h/R and length L/R against λ for a lubrication sweep.

    The near-critical asymptotes (Chen et al. 2020 eqs. asmyp1/asmyp2, sfilm2 and sL) are drawn
    dashed for comparison. Failed points are left out.

    Returns
    -------
    ax : matplotlib.axes.Axes
        The first of the four panels (``ax.figure`` holds all).
    """
    if axes is None:
        axes = _figure(figsize=(10, 7)).subplots(2, 2).ravel()
    ok = [r for r in results if r.success]
    lam = np.array([r.lam for r in ok])
    nu, lam_c = results[0].nu, results[0].lam_c
    lam_a = lam_c * np.linspace(0.9, 0.9995, 80)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OutOfRangeWarning)
        reference = {
            "V_over_U": (speed_near_critical(nu, lam_a), "eq. asmyp1"),
            "dp_plus_R0": (dp_plus_near_critical(nu, lam_a), "eq. asmyp2"),
            "film_min": (1.0 - lam_a / lam_c, "1 − λ/λc (eq. sfilm2)"),
            "ell": (2.0 * nu ** (-2.0 / 3.0) * lam_c * lam_a, "ℓc λ/λc (eq. sL)"),
        }
    labels = {"V_over_U": "V/U [-]", "dp_plus_R0": "Δp⁺R0/(ηU) [-]", "film_min": "h_min/R [-]",
              "ell": "L/R [-]"}
    for ax, key in zip(axes, labels):
        ax.plot(lam, [getattr(r, key) for r in ok], "o-", ms=3, label=f"lubrication ({results[0].model})")
        ref, name = reference[key]
        ax.plot(lam_a, ref, "k--", label=name)
        ax.set_xlabel(_LAM_LABEL)
        ax.set_ylabel(labels[key])
        ax.legend(fontsize="small")
    axes[1].set_yscale("log")
    axes[0].set_title(f"ν = {nu:.3g}, λc = {lam_c:.4g}", fontsize="small")
    return axes[0]
