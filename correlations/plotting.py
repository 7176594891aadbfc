"""Plots of the apparent-viscosity laws (library code: returns Axes, never shows)."""

from __future__ import annotations

import numpy as np

from .viscosity import VISCOSITY_LAWS, relative_viscosity

__all__ = ["plot_relative_viscosity", "plot_estimate"]


def plot_relative_viscosity(diameters_um=None, hematocrits=(0.2, 0.45), laws=VISCOSITY_LAWS,
                            ax=None):
    """Relative apparent viscosity against tube diameter, one line per law and hematocrit.

    Parameters
    ----------
    diameters_um : array_like, optional
        Tube diameters [µm]; default 400 points log-spaced over 3.3-1978 µm, the range of the
        Pries et al. 1992 data base (no extrapolation warnings).
    hematocrits : sequence of float
        Discharge hematocrits H_D, 0 <= H_D < 1 [-].
    laws : sequence of str
        Laws from :data:`~correlations.viscosity.VISCOSITY_LAWS`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new headless figure (``matplotlib.figure.Figure``, no pyplot) is
        made if None.

    Returns
    -------
    ax : matplotlib.axes.Axes
        With log-scaled x axis, labels ``d [µm]`` and ``η_rel [-]`` and a legend.

    Examples
    --------
    >>> ax = plot_relative_viscosity(hematocrits=(0.45,), laws=("pries1992", "pries2005"))
    >>> len(ax.get_lines())
    2
    """
    if ax is None:
        from matplotlib.figure import Figure   # lazy: importing this module needs no matplotlib
        ax = Figure(figsize=(6.0, 4.0)).add_subplot()
    d = np.geomspace(3.3, 1978.0, 400) if diameters_um is None else np.asarray(diameters_um,
                                                                                 dtype=float)
    for law in laws:
        for hd in hematocrits:
            ax.plot(d, relative_viscosity(d, hd, law=law), label=f"{law}, H_D = {hd:g}")
    ax.set_xscale("log")
    ax.set_xlabel("d [µm]")
    ax.set_ylabel("η_rel [-]")
    ax.legend()
    return ax


def plot_estimate(est, ax=None):
    """V/U and dp+ R0/(eta U) against confinement for the case's nu, with the case marked.

    Two panels (the asymptotic laws of :mod:`lubrication.plotting`, solid where valid, dashed
    where extrapolated); the estimate's values are marked where available, hollow when flagged
    as extrapolated.

    Parameters
    ----------
    est : correlations.estimate.Estimate
        The estimate to mark.
    ax : sequence of two matplotlib Axes, optional
        Axes for V/U and dp+; a new headless figure with two panels if None.

    Returns
    -------
    ax : matplotlib.axes.Axes
        The V/U panel (``ax.figure`` holds both).

    Examples
    --------
    >>> from correlations.estimate import estimate_dimensionless
    >>> ax = plot_estimate(estimate_dimensionless(0.9, 1.25))
    >>> len(ax.figure.axes)
    2
    """
    from lubrication.plotting import plot_dp_plus_asymptotics, plot_speed_asymptotics
    if ax is None:
        from matplotlib.figure import Figure
        ax = Figure(figsize=(10.0, 4.0)).subplots(1, 2)
    nu, lam = est["nu"], est["lam"]
    plot_speed_asymptotics(nu=(nu,), ax=ax[0])
    plot_dp_plus_asymptotics(nu=(nu,), ax=ax[1])
    for panel, key in zip(ax, ("V_over_U", "dp_plus_R0")):
        q = est.quantities[key]
        if q.value is not None:
            panel.plot([lam], [q.value], "o", ms=8, color="C3",
                       mfc="C3" if q.valid else "none", label=f"this case ({q.method})")
        else:
            panel.axvline(lam, color="C3", ls=":", label="this case (no valid method)")
        panel.legend(fontsize="small")
    ax[0].set_title(f"ν = {nu:.3g}, λ = {lam:.3g}, λc = {est['lam_c']:.3g}")
    return ax[0]
