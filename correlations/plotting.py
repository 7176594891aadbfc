"""Plots of the apparent-viscosity laws (library code: returns Axes, never shows)."""

from __future__ import annotations

import numpy as np

from .viscosity import VISCOSITY_LAWS, relative_viscosity

__all__ = ["plot_relative_viscosity"]


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
