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
from .checks import OutOfRangeWarning
from .geometry import check_reduced_volume, critical_confinement

__all__ = ["plot_speed_asymptotics", "plot_dp_plus_asymptotics"]

_LAM_LABEL = "λ = R0/R [-]"


def _new_axes(ax):
    if ax is None:
        from matplotlib.figure import Figure   # lazy: importing the package needs no matplotlib
        ax = Figure().add_subplot()
    return ax


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
