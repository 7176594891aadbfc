"""Plots of the apparent-viscosity laws (library code: returns Axes, never shows)."""

from __future__ import annotations

import warnings

import numpy as np

from lubrication.checks import InvalidParameterError, OutOfRangeWarning
from lubrication.geometry import cell_from_volume_area, critical_confinement, critical_diameter_um
from lubrication.plotting import plot_dp_plus_asymptotics, plot_speed_asymptotics

from . import viscosity
from .estimate import RBC_DEFAULTS, single_file_viscosity
from .registry import DEFAULT_MEMBRANE
from .viscosity import VISCOSITY_LAWS, relative_viscosity

__all__ = ["plot_relative_viscosity", "plot_single_file_viscosity", "plot_estimate", "plot_check"]

#: Mean velocities U [mm/s] of the curves of :func:`plot_single_file_viscosity`: capillary
#: red-cell speeds, about three per decade (those outside the membrane's map are left out).
SINGLE_FILE_VELOCITIES_MM_S = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0)


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


def _diameter_bound(validity, index: int) -> float:
    """Lower (``index`` 1) or upper (2) diameter bound [µm] of a validity range."""
    return next(b[index] for b in validity.bounds if b[0] == "diameter_um")


def _single_file_curve(diameters_um, hematocrit, velocity_mm_s, membrane, **kw):
    """η_rel(d) of :func:`~correlations.estimate.single_file_viscosity`, NaN where it has no
    value (a gap in the line), or None where the map of ``membrane`` does not take this
    velocity (the estimate refuses it, naming ``velocity_mm_s``)."""
    values = []
    with warnings.catch_warnings():     # d > 8 µm is drawn; the plot marks the law's limit
        warnings.simplefilter("ignore", OutOfRangeWarning)
        for d in diameters_um:
            try:
                r = single_file_viscosity(d, hematocrit, velocity_mm_s=velocity_mm_s,
                                          membrane=membrane, **kw)
            except InvalidParameterError as exc:
                if exc.name == "velocity_mm_s":
                    return None
                raise
            values.append(np.nan if r.eta_rel is None else r.eta_rel)
    return np.array(values)


def plot_single_file_viscosity(hematocrit, hematocrit_kind="tube",
                               velocity_mm_s=RBC_DEFAULTS["velocity_mm_s"], membrane=DEFAULT_MEMBRANE,
                               shear_modulus_un_m=RBC_DEFAULTS["shear_modulus_un_m"],
                               velocities_mm_s=SINGLE_FILE_VELOCITIES_MM_S,
                               diameter_max_um=12.0, points=60, ax=None, **cell):
    r"""η_rel(d) of the single-file model (Chen et al. 2020 §IV.D) at several mean velocities.

    One solid line per velocity, labelled ``U = … mm/s`` (the user's ``velocity_mm_s`` is
    added to ``velocities_mm_s`` and drawn thicker, "this case"); velocities the membrane's
    map does not take, and lines without any value, are left out; points without a value are
    gaps (NaN), never zeros. For a red cell, the vesicle at ``velocity_mm_s`` (no shear
    elasticity: its high-velocity limit) dashed; for reference Pries et al. 1992 in vitro
    (dotted; discharge hematocrit given, or from the tube hematocrit by the Fåhræus relation
    with Pries et al. 1992's constants, in each tube, on 3.3 µm and up) and the single-file
    law's limit, 8 µm (dash-dotted, :data:`correlations.viscosity.CHEN2020_RANGE`). Each point
    is :func:`correlations.estimate.single_file_viscosity`, about 1 ms on the map.

    Parameters
    ----------
    hematocrit : float
        Hematocrit, a fraction in [0, 1) [-].
    hematocrit_kind : {"tube", "discharge"}
        Whether ``hematocrit`` is H_T or H_D.
    velocity_mm_s : float
        The case's mean velocity U [mm/s], marked.
    membrane : {"red-cell", "vesicle"}
        The cell's membrane, as in :func:`correlations.estimate.estimate` (default: a red cell).
    shear_modulus_un_m : float
        Red-cell membrane shear modulus G_s [µN/m].
    velocities_mm_s : sequence of float
        The other velocities drawn [mm/s].
    diameter_max_um : float
        Widest tube [µm]; the narrowest is just above the cell's critical diameter d_c
        (``points`` tubes, denser near d_c: d = d_c/x, x evenly spaced from 0.99).
    points : int
        Number of tube diameters.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; a new headless figure if None.
    **cell
        Cell inputs of :func:`correlations.estimate.estimate` (``volume_fl``, ``area_um2``,
        ``plasma_viscosity_mpas``, ``bending_modulus_j``, ``solution_map``).

    Returns
    -------
    ax : matplotlib.axes.Axes
        Labels ``d [µm]`` and ``η_rel [-]``, linear x and logarithmic y, a legend.

    Examples
    --------
    >>> ax = plot_single_file_viscosity(0.3, membrane="vesicle", velocities_mm_s=(5.0,),
    ...                                 points=8)
    >>> [line.get_label() for line in ax.get_lines() if line.get_label().startswith("U =")]
    ['U = 1 mm/s (this case)', 'U = 5 mm/s']
    """
    from matplotlib import colormaps  # lazy: matplotlib
    if ax is None:
        ax = _figure(figsize=(7.0, 4.5)).add_subplot()
    nu, R0 = cell_from_volume_area(cell.get("volume_fl", RBC_DEFAULTS["volume_fl"]),
                                   cell.get("area_um2", RBC_DEFAULTS["area_um2"]))
    d_c = float(critical_diameter_um(nu, R0))
    d = d_c / np.linspace(0.99, d_c / diameter_max_um, points)
    kw = dict(hematocrit_kind=hematocrit_kind, shear_modulus_un_m=shear_modulus_un_m, **cell)
    speeds = sorted({*velocities_mm_s, velocity_mm_s})
    colour = colormaps["viridis"]
    span = np.log(speeds[-1] / speeds[0]) or 1.0
    for U in speeds:
        eta = _single_file_curve(d, hematocrit, U, membrane, **kw)
        if eta is None or np.isnan(eta).all():
            continue
        mine = U == velocity_mm_s
        ax.plot(d, eta, color=colour(0.9 * np.log(U / speeds[0]) / span),
                lw=2.5 if mine else 1.2, label=f"U = {U:g} mm/s" + (" (this case)" if mine else ""))
    if membrane == "red-cell":
        eta = _single_file_curve(d, hematocrit, velocity_mm_s, "vesicle", **kw)
        if eta is not None:
            ax.plot(d, eta, "--", color="k", lw=1.2,
                    label=f"vesicle (no shear elasticity), U = {velocity_mm_s:g} mm/s")
    d_p = d[d >= _diameter_bound(viscosity.PRIES1992_RANGE, 1)]
    h_d = (hematocrit if hematocrit_kind == "discharge" else
           viscosity.discharge_hematocrit_fahraeus(d_p, hematocrit, constants="pries1992"))
    ax.plot(d_p, viscosity.viscosity_vitro_pries1992(d_p, h_d), ":", color="0.35", lw=1.5,
            label="Pries et al. 1992 in vitro" + ("" if hematocrit_kind == "discharge" else
                                                  " (H_D from Fåhræus)"))
    ax.axvline(_diameter_bound(viscosity.CHEN2020_RANGE, 2), color="0.6", ls="-.", lw=0.8,
               label="single-file limit (Chen et al. 2020)")
    # log y: eta_rel rises steeply towards d_c, and the spread between velocities stays legible
    ax.set_yscale("log")
    lo, hi = ax.get_ylim()
    ticks = [t for t in (1, 1.2, 1.5, 2, 3, 5, 10, 20, 50, 100) if lo <= t <= hi]
    ax.set_yticks(ticks, [f"{t:g}" for t in ticks])
    ax.set_yticks([], minor=True)
    ax.set_xlabel("d [µm]")
    ax.set_ylabel("η_rel [-]")
    name = "red cell" if membrane == "red-cell" else "vesicle"
    ax.set_title(f"single-file model, {name}, {'H_T' if hematocrit_kind == 'tube' else 'H_D'}"
                 f" = {hematocrit:g}", fontsize="medium")
    ax.legend(fontsize="small")
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
