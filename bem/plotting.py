"""Plots of BEM results (library code: returns Axes, never shows).

Lengths in units of the tube radius R; the flow goes toward +x.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["plot_shape", "plot_vesicle_sweep"]


def _new_axes(ax, figsize):
    """``ax``, or the Axes of a new headless :class:`matplotlib.figure.Figure` (no pyplot)."""
    if ax is None:
        from matplotlib.figure import Figure  # lazy: matplotlib
        ax = Figure(figsize=figsize).add_subplot()
    return ax


def draw_tube(ax, half: float) -> None:
    """Tube wall r = ±R over |x| <= half, axis, flow arrow, equal axes with labels."""
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


def plot_shape(result, ax=None):
    """Meridional section of the drop (or rigid sphere) in the tube, mirrored about the axis.

    Parameters
    ----------
    result : DropResult, VesicleResult or SphereResult
        A drop or vesicle draws its computed shape (``x``, ``r``), a sphere the circle of
        radius lam. The title gives V/U and Δp⁺ in the scaling of the CLI table (R0 for a
        vesicle, R otherwise), and no numbers for a result that did not converge.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new headless figure (``matplotlib.figure.Figure``, no pyplot) is
        made if None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    ax = _new_axes(ax, (7.0, 3.0))
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
    draw_tube(ax, half)
    title = f"λ = {result.lam:.4g}"
    if hasattr(result, "nu"):
        title = f"ν = {result.nu:.4g}, " + title
    if hasattr(result, "ca"):
        title += f", Ca = {result.ca:.4g}"
    if hasattr(result, "ca_b"):
        title += f", Ca_B = {result.ca_b:.4g}"
    # the pressure drop in the scaling of the CLI table: R0 (volume radius) for a vesicle
    # (Chen et al. 2020), R for a drop or a rigid sphere
    dp, scale = ((result.dp_plus_R0, "Δp⁺R0/(ηU)") if hasattr(result, "nu")
                 else (result.dp_plus_R, "Δp⁺R/(ηU)"))
    if result.converged and math.isfinite(result.V_over_U) and math.isfinite(dp):
        title += f": V/U = {result.V_over_U:.5g}, {scale} = {dp:.5g}"
    if not result.converged:
        title += " (NOT CONVERGED: no values)"
    ax.set_title(title, fontsize="small")
    return ax


def plot_vesicle_sweep(results, ax=None):
    """Meridional sections of the vesicles of a sweep, overlaid in one tube, coloured by λ.

    Each shape is centred at the middle of its length (x_rear + x_front)/2 and mirrored about
    the axis; the wall r = ±R is drawn. Points that did not converge are dashed; points without
    a shape (the solver produced none) are left out and counted in the title.

    Parameters
    ----------
    results : sequence of VesicleResult
        The points of :func:`bem.sweep.sweep_vesicle` (one ν and Ca_B).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new headless figure (no pyplot) is made if None.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib as mpl  # lazy: matplotlib

    ax = _new_axes(ax, (7.5, 3.2))
    results = list(results)
    lams = np.array([r.lam for r in results], dtype=float)
    lo, hi = (float(lams.min()), float(lams.max())) if lams.size else (0.0, 1.0)
    norm = mpl.colors.Normalize(lo, hi if hi > lo else lo + 1e-9)
    cmap = mpl.colormaps["viridis"]
    half, drawn = 1.5, 0
    for res in sorted(results, key=lambda r: r.lam):
        x = np.asarray(res.x, dtype=float)
        r = np.asarray(res.r, dtype=float)
        if x.size == 0:
            continue
        x = x - 0.5 * (x.min() + x.max())
        half = max(half, 0.6 * float(np.ptp(x)) + 0.3)
        style = {"color": cmap(norm(res.lam)), "lw": 1.4, "ls": "-" if res.success else "--"}
        ax.plot(x, r, **style)
        ax.plot(x, -r, **style)
        drawn += 1
    draw_tube(ax, half)
    ax.figure.colorbar(mpl.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax,
                       label="λ = R0/R [-]", shrink=0.8)
    title = ""
    if results:
        r0 = results[0]
        n_bad = sum(not r.success for r in results)
        title = (f"ν = {r0.nu:.4g}, Ca_B = {r0.ca_b:.4g}: {drawn} of {len(results)} shapes"
                 + (f", {n_bad} NOT CONVERGED (dashed)" if n_bad else ""))
    ax.set_title(title, fontsize="small")
    return ax
