"""Plots of BEM results (library code: returns Axes, never shows).

Lengths in units of the tube radius R; the flow goes toward +x.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["plot_shape"]


def plot_shape(result, ax=None):
    """Meridional section of the drop (or rigid sphere) in the tube, mirrored about the axis.

    Parameters
    ----------
    result : DropResult or SphereResult
        A drop draws its computed shape (``x``, ``r``), a sphere the circle of radius lam.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new headless figure (``matplotlib.figure.Figure``, no pyplot) is
        made if None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    if ax is None:
        from matplotlib.figure import Figure  # lazy: importing bem needs no matplotlib
        ax = Figure(figsize=(7.0, 3.0)).add_subplot()
    x = np.asarray(getattr(result, "x", np.empty(0)), dtype=float)
    r = np.asarray(getattr(result, "r", np.empty(0)), dtype=float)
    if x.size == 0:                                    # rigid sphere: a circle of radius lam
        th = np.linspace(0.0, math.pi, 201)
        x, r = -result.lam * np.cos(th), result.lam * np.sin(th)
    half = max(2.0, 1.3 * float(np.max(np.abs(x))) if x.size else 2.0)
    ax.fill(np.concatenate([x, x[::-1]]), np.concatenate([r, -r[::-1]]), color="tab:blue",
            alpha=0.25, lw=0)
    ax.plot(x, r, "-", color="tab:blue", lw=1.5)
    ax.plot(x, -r, "-", color="tab:blue", lw=1.5)
    for y in (1.0, -1.0):
        ax.plot([-half, half], [y, y], "k-", lw=2)
    ax.axhline(0.0, color="0.6", lw=0.6, ls="-.")
    ax.annotate("", xy=(-0.6 * half, 0.0), xytext=(-0.95 * half, 0.0),
                arrowprops={"arrowstyle": "->", "color": "0.4"})
    ax.set_xlim(-half, half)
    ax.set_ylim(-1.15, 1.15)
    ax.set_aspect("equal")
    ax.set_xlabel("x/R [-]")
    ax.set_ylabel("r/R [-]")
    title = f"λ = {result.lam:.4g}"
    if hasattr(result, "ca"):
        title += f", Ca = {result.ca:.4g}"
    if math.isfinite(getattr(result, "V_over_U", math.nan)):
        title += f": V/U = {result.V_over_U:.5g}, Δp⁺R/(ηU) = {result.dp_plus_R:.5g}"
    if not result.converged:
        title += " (NOT CONVERGED)"
    ax.set_title(title, fontsize="small")
    return ax
