"""Plots of the apparent-viscosity laws (library code: returns Axes, never shows)."""

from __future__ import annotations

import numpy as np

from lubrication.geometry import critical_confinement
from lubrication.plotting import plot_dp_plus_asymptotics, plot_speed_asymptotics

from .viscosity import VISCOSITY_LAWS, relative_viscosity

__all__ = ["plot_relative_viscosity", "plot_estimate", "plot_check"]


def _figure(**kwargs):
    """A new headless :class:`matplotlib.figure.Figure` (no pyplot)."""
    from matplotlib.figure import Figure  # lazy: matplotlib
    return Figure(**kwargs)


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
        ax = _figure(figsize=(6.0, 4.0)).add_subplot()
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
    if ax is None:
        ax = _figure(figsize=(10.0, 4.0)).subplots(1, 2)
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


def plot_check(report, ax=None):
    r"""The rows of a consistency check over their references: V/U and Δp⁺R0/(ηU) against λ.

    Filled markers are the rows, coloured by verdict (pass green, warn orange, fail red); hollow
    black markers the reference each was compared with; lines the solution map along λ for each
    (ν, Ca_B) of the vesicle rows (at most six), the small rigid-sphere and clean-drop laws
    (Chen et al. 2020 eq. small1/small2; Hetsroni et al. 1970) where sphere or drop rows are
    present.

    Parameters
    ----------
    report : correlations.check.CheckReport
        The checked rows.
    ax : pair of matplotlib Axes, optional
        Where to draw V/U and Δp⁺ (default: two panels of a new headless figure).

    Returns
    -------
    ax : matplotlib.axes.Axes
        The V/U panel; its ``figure`` holds the two.

    Examples
    --------
    >>> from correlations.check import check_results
    >>> rep = check_results([{"kind": "sphere", "lam": 0.1, "V_over_U": 1.9867,
    ...                       "dp_plus_R0": 1.6e-5}], bem=False, solution_map=False)
    >>> len(plot_check(rep).figure.axes)
    2
    """
    from .check import (  # lazy: correlations.check off the estimate's start-up
        DEFAULT_CA_B, map_reference)
    if ax is None:
        ax = _figure(figsize=(11.0, 4.5)).subplots(1, 2)
    colours = {"pass": "C2", "warn": "C1", "fail": "C3"}
    series = sorted({(r.row.get("nu"), r.row.get("ca_b", DEFAULT_CA_B)) for r in report.rows
                     if r.row.kind == "vesicle" and r.row.get("nu") < 1.0})[:6]
    delta = np.geomspace(1e-4, 0.8, 80)
    for k, (nu, ca_b) in enumerate(series):
        lam = (1.0 - delta) * float(critical_confinement(nu))
        for panel, q in zip(ax, ("V_over_U", "dp_plus_R0")):
            refs = [map_reference(nu, x, ca_b, q, report.solution_map) for x in lam]
            pts = [(x, r.value) for x, r in zip(lam, refs) if not isinstance(r, str)]
            if pts:
                panel.plot(*zip(*pts), "-", color=f"C{4 + k}", lw=1,
                           label=f"map ν = {nu:.3g}, Ca_B = {ca_b:.3g}")
    kinds = {r.row.kind for r in report.rows}
    small = np.linspace(0.1, 0.5, 50)
    if "sphere" in kinds:
        ax[0].plot(small, 2 - 4 / 3 * small**2, ":", color="k", label="small rigid sphere")
        ax[1].plot(small, 16 * small**6, ":", color="k")
    if "drop" in kinds:
        ax[0].plot(small, 2 - 0.8 * small**2, "--", color="grey", label="small clean drop")
        ax[1].plot(small, 4.8 * small**6, "--", color="grey")
    seen = set()
    for r in report.rows:
        lam = r.row.get("lam")
        for c in r.checks:
            if not c.name.endswith("vs reference") or c.quantity not in (
                    "V_over_U", "dp_plus_R0", "dp_plus_R"):
                continue
            panel, to_R0 = (ax[0], 1.0) if c.quantity == "V_over_U" else (
                ax[1], lam if c.quantity == "dp_plus_R" else 1.0)
            label = r.verdict.value if r.verdict.value not in seen else None
            seen.add(r.verdict.value)
            panel.plot([lam], [c.value * to_R0], "o", color=colours[r.verdict.value], label=label)
            panel.plot([lam], [c.reference * to_R0], "o", mfc="none", color="k", ms=9,
                       label="reference" if "reference" not in seen else None)
            seen.add("reference")
    ax[0].set_xlabel("λ = R0/R [-]")
    ax[0].set_ylabel("V/U [-]")
    ax[1].set_xlabel("λ = R0/R [-]")
    ax[1].set_ylabel("Δp⁺R0/(ηU) [-]")
    if any(line.get_ydata().size and np.all(np.asarray(line.get_ydata()) > 0)
           for line in ax[1].get_lines()):
        ax[1].set_yscale("log")
    ax[0].legend(fontsize="small")
    ax[0].set_title(f"{report.source}: {report.verdict.value.upper()}", fontsize="medium")
    return ax[0]
