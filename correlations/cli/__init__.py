"""The ``vesicle-tube`` command line.

Every command follows the contract of :mod:`correlations.cli.contract` (table or strict JSON;
exit 0 ok, 2 invalid input, 1 not converged or output not written, 130 interrupted).
Out-of-range warnings go to stderr, one line each, and into the JSON under ``"warnings"``; the
files a command wrote are named on stderr.

Heavy imports (matplotlib, scipy, numba) happen only inside the commands that need them, so that
``vesicle-tube estimate`` starts fast.
"""

from __future__ import annotations

import argparse
import sys
import warnings

from lubrication import geometry
from lubrication.checks import (InvalidParameterError, OutOfRangeWarning, check_fraction,
                                check_output, check_positive, check_range)
from lubrication.io import forget_written_files, written_files
from correlations import viscosity
from correlations.cli.bem import add_bem_parser
from correlations.cli.check import add_check_parser
from correlations.cli.contract import (EXIT_CHECK_FAILED, EXIT_INTERRUPTED, EXIT_INVALID,
                                      EXIT_NOT_CONVERGED, EXIT_NOT_WRITTEN, EXIT_OK,
                                      Parser, UsageError, check_output_dir, check_plot_path,
                                      check_report_path, command_streams,
                                      dump_json, format_rows, format_value_error,
                                      interrupted_message, is_interrupt,
                                      non_finite_keys, one_line, options_named, os_error_message,
                                      not_written_message, output_failed, quiet_broken_pipe,
                                      save_plot, saved)
from correlations.cli.figures import add_figures_parser
from correlations.cli.infer import add_infer_parser
from correlations.cli.lubrication import add_parser as add_lubrication_parser
from correlations.cli.map import add_map_parser
from correlations.estimate import (PHYSICAL_BOUNDS, RBC_DEFAULTS, estimate,
                                   estimate_dimensionless, single_file_viscosity)
from correlations.plotting import (plot_estimate, plot_relative_viscosity,
                                   plot_single_file_viscosity)
from correlations.registry import DEFAULT_MEMBRANE, MEMBRANES, QUANTITIES, SOLVERS

# Human labels of the output keys (key -> label); keys not listed are printed as they are. A
# label names the quantity; the "unit" column says what its value is measured in (below).
LABELS = {
    "nu": "reduced volume nu", "lam": "confinement lam = R0/R", "lam_c": "critical confinement lam_c",
    "ell_c": "critical length L_c", "delta": "clearance delta = 1 - lam/lam_c",
    "passes": "passes the tube intact", "R0_um": "volume radius R0", "d_c_um": "critical diameter d_c",
    "L_c_um": "critical length L_c", "ca_b": "bending capillary number Ca_B = eta U R0^2/kappa",
    "ca_s": "shear capillary number Ca_S = eta U/G_s",
    "shear_ratio": "shear ratio beta = G_s R0^2/kappa = Ca_B/Ca_S",
    "V_over_U": "speed V/U", "V_mm_s": "cell speed V", "film": "film thickness h",
    "film_nm": "film thickness h", "ell": "length L", "length_um": "length L",
    "dp_plus_R0": "extra pressure drop dp+", "dp_plus_R": "extra pressure drop dp+",
    "dp_plus_Pa": "extra pressure drop dp+", "shape_class": "shape class",
    "tension_front": "front tension gamma_F", "tension_front_etaU": "front tension gamma_F",
    "tension_front_mN_m": "front tension gamma_F", "tension_max": "maximum tension gamma_max",
    "tension_max_etaU": "maximum tension gamma_max",
    "tension_max_mN_m": "maximum tension gamma_max",
    "tube_hematocrit": "tube hematocrit H_T",
    "discharge_hematocrit": "discharge hematocrit H_D", "eta_rel": "relative apparent viscosity",
    "reduced_area_excess": "reduced excess area 4pi(nu^-2/3 - 1)", "nu_c": "largest nu passing (nu_c)",
    "diameter_um": "tube diameter d", "ratio_HT_over_HD": "Fahraeus ratio H_T/H_D",
    "velocity_mm_s": "mean velocity U", "membrane": "membrane",
}

#: The "unit" column of every table holds either a physical unit (um, mm/s, Pa, nm, mN/m) or
#: the scale a dimensionless value is measured in ("R": the value is h/R; "eta U/R0": the value
#: is dp+ R0/(eta U); "R_c", "eta V", "eta U"), "-" for a plain dimensionless number and "" for
#: a non-number (yes/no, a name). The estimate's units are correlations.estimate.UNITS.
UNIT_CONVENTION = ('unit column: a physical unit, or the scale of a dimensionless value (e.g. '
                   '"R": h is given as h/R); "-": plain dimensionless')

# Order of rows in the human estimate table.
ESTIMATE_ROWS = ("nu", "lam", "lam_c", "delta", "ell_c", "passes", "R0_um", "d_c_um", "L_c_um",
                 "ca_b", "ca_s", "shear_ratio", "shape_class", "V_over_U", "V_mm_s", "dp_plus_R0", "dp_plus_R",
                 "dp_plus_Pa", "film", "film_nm", "ell", "length_um", "tension_front",
                 "tension_front_etaU", "tension_front_mN_m", "tension_max", "tension_max_etaU",
                 "tension_max_mN_m", "tube_hematocrit", "discharge_hematocrit", "eta_rel")

# The option a user types for each parameter name of the library (messages name the option).
OPTIONS = {
    "nu": "--nu", "lam": "--lam", "ca_b": "--ca-b", "volume_fl": "--volume-fl",
    "area_um2": "--area-um2", "diameter_um": "--diameter-um", "velocity_mm_s": "--velocity-mm-s",
    "plasma_viscosity_mpas": "--plasma-viscosity-mpas", "bending_modulus_j": "--bending-modulus-j",
    "hematocrit": "--hematocrit", "hematocrit_kind": "--hematocrit-kind", "solvers": "--solver",
    "shear_modulus_un_m": "--shear-modulus-uN-m", "membrane": "--membrane", "ca_s": "--ca-s",
    "law": "--law", "constants": "--constants",
}


def _options(args, **renamed):
    """:func:`correlations.cli.contract.options_named` with this module's :data:`OPTIONS`
    (``renamed``: further parameter names, e.g. ``tube_hematocrit="--hematocrit"``)."""
    return options_named({**OPTIONS, **renamed}, args)


def _quantity_rows(quantities: dict, keys) -> list:
    """Table rows of estimate quantities: a value with an error bar as ``value ± error``, and
    the note of such a value (what its error bar leaves out) as its flag."""
    rows = []
    for key in keys:
        if key not in quantities:
            continue
        q = quantities[key]
        flag = "" if q.valid or q.method in (None, "input") else "EXTRAPOLATED (outside validity)"
        if q.value is None and q.method is None:
            flag = "no valid method" if q.note.startswith("no valid") else q.note
        value = q.value
        if q.error is not None and q.value is not None:
            value = format_value_error(q.value, q.error)
            flag = flag or q.note
        rows.append((LABELS.get(key, key), value, q.unit, q.method or "", flag))
    return rows


def _unphysical(quantity: str, value) -> str:
    """Why ``value`` may not be reported as ``quantity`` ("" if it may): the output checks of
    :func:`lubrication.checks.check_output` (finite, within the physical bounds)."""
    return check_output(quantity, value, {}) if value is not None else ""


# --------------------------------------------------------------------------- commands

def cmd_geometry(args) -> dict:
    if args.nu is not None and (args.volume_fl is not None or args.area_um2 is not None):
        raise UsageError("give either --nu or --volume-fl/--area-um2, not both")
    with _options(args):
        if args.nu is None:
            if args.volume_fl is None or args.area_um2 is None:
                raise UsageError("give --nu NU, or both --volume-fl V and --area-um2 A")
            for name in ("volume_fl", "diameter_um"):
                value = getattr(args, name)
                if value is not None:
                    lo, hi, reason = PHYSICAL_BOUNDS[name]
                    check_range(name, check_positive(name, value), lo, hi, reason=reason)
            nu, R0 = geometry.cell_from_volume_area(args.volume_fl, args.area_um2)
            lam = (None if args.diameter_um is None
                   else geometry.confinement_from_diameter(R0, args.diameter_um))
        else:
            nu, R0 = float(geometry.check_reduced_volume(args.nu)), None
            if args.diameter_um is not None:
                raise UsageError("--diameter-um goes with --volume-fl/--area-um2; use --lam with --nu")
            lam = None if args.lam is None else float(check_positive("lam", args.lam))
        lam_c, ell_c = geometry.critical_confinement(nu), geometry.critical_length(nu)
    out = {"command": "geometry", "converged": True, "nu": nu, "lam_c": lam_c, "ell_c": ell_c,
           "reduced_area_excess": geometry.reduced_area_excess(nu)}
    if R0 is not None:
        out.update(R0_um=R0, d_c_um=geometry.critical_diameter_um(nu, R0),
                   L_c_um=geometry.critical_length_um(nu, R0))
    if lam is not None:
        passes = bool(lam < lam_c)
        out.update(lam=lam, passes=passes, delta=(1.0 - lam / lam_c) if passes else None)
        if lam >= 1.0:
            out["nu_c"] = geometry.critical_reduced_volume(lam)
    units = {"R0_um": "um", "d_c_um": "um", "L_c_um": "um", "ell_c": "R_c", "passes": ""}
    inputs = {"nu", "lam"} if R0 is None else set()
    rows = [(LABELS.get(k, k), v, units.get(k, "-"),
             "input" if k in inputs else "Chen et al. 2020 §IV.A", "")
            for k, v in out.items() if k not in ("command", "converged")]
    return out, format_rows(rows, "Geometry of confinement") + "\n" + UNIT_CONVENTION


def cmd_estimate(args) -> dict:
    physical = any(getattr(args, k) is not None for k in
                   ("volume_fl", "area_um2", "diameter_um", "velocity_mm_s",
                    "plasma_viscosity_mpas", "bending_modulus_j", "shear_modulus_uN_m",
                    "membrane"))
    if args.nu is not None or args.lam is not None:
        if physical:
            raise UsageError("give either --nu/--lam or physical inputs (--volume-fl ..., "
                             "--shear-modulus-uN-m, --membrane), not both; the dimensionless "
                             "estimate is a red cell when --ca-s is given")
        if args.nu is None or args.lam is None:
            raise UsageError("give both --nu and --lam for the dimensionless estimate")
        h = {f"{args.hematocrit_kind}_hematocrit": args.hematocrit} if args.hematocrit is not None else {}
        with _options(args, tube_hematocrit="--hematocrit", discharge_hematocrit="--hematocrit"):
            est = estimate_dimensionless(args.nu, args.lam, args.ca_b, ca_s=args.ca_s,
                                         extrapolate=args.extrapolate,
                                         solvers=tuple(args.solver),
                                         solution_map=False if args.no_map else None, **h)
        title = f"Dimensionless estimate: nu = {args.nu:g}, lam = {args.lam:g}" + (
            f"; red cell, Ca_S = {args.ca_s:g}" if args.ca_s is not None else "")
    else:
        if args.ca_b is not None:
            raise UsageError("--ca-b goes with --nu/--lam (physical inputs determine Ca_B)")
        if args.ca_s is not None:
            raise UsageError("--ca-s goes with --nu/--lam (physical inputs determine Ca_S: "
                             "--shear-modulus-uN-m)")
        kw = {k: getattr(args, k) for k in ("volume_fl", "area_um2", "diameter_um", "velocity_mm_s",
                                            "plasma_viscosity_mpas", "bending_modulus_j")
              if getattr(args, k) is not None}
        if args.shear_modulus_uN_m is not None:
            kw["shear_modulus_un_m"] = args.shear_modulus_uN_m
        if args.membrane is not None:
            kw["membrane"] = args.membrane
        with _options(args):
            est = estimate(**kw, hematocrit=args.hematocrit, hematocrit_kind=args.hematocrit_kind,
                           extrapolate=args.extrapolate, solvers=tuple(args.solver),
                           solution_map=False if args.no_map else None)
        i = est.inputs
        membrane = (f"red cell, G_s = {i['shear_modulus_un_m']:g} uN/m"
                    if i.get("membrane") == "red-cell" else "vesicle (no shear elasticity)")
        title = (f"Engineering estimate: cell {i['volume_fl']:g} fL, {i['area_um2']:g} um^2 in a "
                 f"{i['diameter_um']:g} um tube; U = {i['velocity_mm_s']:g} mm/s, eta = "
                 f"{i['plasma_viscosity_mpas']:g} mPa s, kappa = {i['bending_modulus_j']:g} J; "
                 f"{membrane}")
    out = est.to_dict()
    why = [f"  {k}: {est.quantities[k].note}" for k in QUANTITIES
           if est.quantities[k].value is None and est.quantities[k].note.startswith("no valid")]
    human = "\n".join([format_rows(_quantity_rows(est.quantities, ESTIMATE_ROWS), title),
                       UNIT_CONVENTION, f"\nregime: {est.regime}"] +
                      [f"note: {n}" for n in est.notes] +
                      (["why no value:"] + why if why else []) +
                      ["methods and validity ranges: correlations/registry.py, docs/user-guide.md"])
    if args.plot:
        saved(out, "--plot", lambda: save_plot(plot_estimate(est), args.plot))
    return out, human


def cmd_viscosity(args) -> dict:
    law = args.law
    d, h, kind = args.diameter_um, args.hematocrit, args.hematocrit_kind
    if law == "single-file":
        return _single_file_viscosity(args)
    given = [OPTIONS[p] for p in _cell_options_given(args)]
    if given:
        raise UsageError(f"{', '.join(given)}: only with --law single-file (the {law} law does "
                         "not depend on the cell's velocity or membrane)")
    notes = []
    with _options(args, tube_hematocrit="--hematocrit", discharge_hematocrit="--hematocrit"):
        d = float(check_positive("diameter_um", d))
        if kind == "tube":      # H_D is needed by the law: an unphysical conversion is an error
            h_t = float(check_fraction("tube_hematocrit", h))
            h_d = viscosity.discharge_hematocrit_fahraeus(d, h_t, constants=args.constants)
        else:                   # H_T is only reported: where the fit is unphysical it is missing
            h_d = float(check_fraction("discharge_hematocrit", h))
            h_t = None
            if d > viscosity.FAHRAEUS_MIN_DIAMETER_UM[args.constants]:
                h_t = viscosity.tube_hematocrit_fahraeus(d, h_d, constants=args.constants)
            else:
                notes.append(f"no tube hematocrit: below d = "
                             f"{viscosity.FAHRAEUS_MIN_DIAMETER_UM[args.constants]:.4g} um the "
                             f"{args.constants} Fahraeus fit gives H_T > H_D, which is impossible")
        eta = viscosity.relative_viscosity(d, h_d, law=law)
    problem = _unphysical("eta_rel", eta)
    if problem:
        notes.append(f"no eta_rel: {problem}")
        eta = None
    out = {"command": "viscosity", "converged": True, "law": law, "diameter_um": d,
           "discharge_hematocrit": h_d, "tube_hematocrit": h_t, "eta_rel": eta,
           "fahraeus_constants": args.constants}
    if notes:
        out["warnings"] = notes
    fahraeus = f"Fahraeus ({args.constants})"
    rows = [("law", law, "", "", ""), (LABELS["diameter_um"], d, "um", "input", ""),
            (LABELS["discharge_hematocrit"], h_d, "-", "input" if kind == "discharge" else
             fahraeus, ""),
            (LABELS["tube_hematocrit"], h_t, "-", "input" if kind == "tube" else fahraeus,
             "" if h_t is not None else "Fahraeus fit not meaningful here"),
            (LABELS["eta_rel"], eta, "-", law, "" if eta is not None else "rejected")]
    if args.plot:
        saved(out, "--plot", lambda: save_plot(plot_relative_viscosity(hematocrits=(h_d,)),
                                               args.plot))
    return out, format_rows(rows, f"Relative apparent viscosity ({law})") + "\n" + UNIT_CONVENTION


def _cell_options_given(args) -> dict:
    """The options of :func:`_add_cell_options` the user gave, by library parameter name."""
    values = {p: getattr(args, OPTIONS[p].lstrip("-").replace("-", "_")) for p in CELL_PARAMETERS}
    return {p: v for p, v in values.items() if v is not None}


def _single_file_viscosity(args) -> dict:
    """Chen et al. 2020's single-file law with the estimate's dp+ for the default cell at this
    diameter, velocity and membrane (:func:`correlations.estimate.single_file_viscosity`).

    Only this law is used: where the estimate has no valid dp+ the result is null with the
    reason (or a flagged extrapolation with --extrapolate), never another law's number. The
    law's diameter range is its stored validity range, viscosity.CHEN2020_RANGE.
    """
    given = _cell_options_given(args)
    with _options(args):
        res = single_file_viscosity(args.diameter_um, args.hematocrit,
                                    hematocrit_kind=args.hematocrit_kind,
                                    extrapolate=args.extrapolate, **given)
    est, red_cell = res.estimate, res.membrane == "red-cell"
    dp, h_t, i = est.quantities["dp_plus_R0"], est.quantities["tube_hematocrit"], est.inputs
    ca_s = est.quantities.get("ca_s")
    out = {"command": "viscosity", "converged": True, "law": "single-file (Chen et al. 2020 §IV.D)",
           "diameter_um": args.diameter_um, "velocity_mm_s": i["velocity_mm_s"],
           "membrane": res.membrane,
           "shear_modulus_un_m": i["shear_modulus_un_m"] if red_cell else None,
           "ca_b": est["ca_b"], "ca_s": ca_s.value if ca_s else None,
           "eta_rel": res.eta_rel, "eta_rel_error": res.error, "valid": res.valid,
           "tube_hematocrit": h_t.value, "discharge_hematocrit": est["discharge_hematocrit"],
           "dp_plus_R0": dp.value, "dp_plus_R0_error": dp.error, "dp_plus_method": dp.method,
           "note": res.note, "validity": viscosity.CHEN2020_RANGE.describe(),
           "cell": "RBC defaults (90 fL, 135 um^2)"}
    if res.note:
        out["warnings"] = [res.note]
    if args.plot:
        saved(out, "--plot", lambda: save_plot(plot_single_file_viscosity(
            args.hematocrit, args.hematocrit_kind, **given), args.plot))
    membrane = (f"red cell, G_s = {i['shear_modulus_un_m']:g} uN/m" if red_cell
                else "vesicle (no shear elasticity)")
    eta = (res.eta_rel if res.error is None or res.eta_rel is None
           else format_value_error(res.eta_rel, res.error))
    flag = "" if res.valid else res.note or "EXTRAPOLATED (outside validity)"
    rows = [("law", out["law"], "", "", ""),
            (LABELS["diameter_um"], args.diameter_um, "um", "input", ""),
            (LABELS["velocity_mm_s"], i["velocity_mm_s"], "mm/s",
             "input" if args.velocity_mm_s is not None else "default", ""),
            (LABELS["membrane"], membrane, "", "input" if args.membrane is not None else
             "default", ""),
            *_quantity_rows(est.quantities, ("ca_b", "ca_s", "tube_hematocrit",
                                             "discharge_hematocrit", "dp_plus_R0")),
            (LABELS["eta_rel"], eta, "-", "single-file (Chen 2020)", flag)]
    return out, (format_rows(rows, "Apparent viscosity (single-file model, RBC defaults)")
                 + "\n" + UNIT_CONVENTION)


def cmd_fahraeus(args) -> dict:
    d = args.diameter_um
    if (args.discharge_hematocrit is None) == (args.tube_hematocrit is None):
        raise UsageError("give exactly one of --discharge-hematocrit H, --tube-hematocrit H")
    with _options(args, discharge_hematocrit="--discharge-hematocrit",
                  tube_hematocrit="--tube-hematocrit"):
        if args.discharge_hematocrit is not None:
            h_d = args.discharge_hematocrit
            h_t = viscosity.tube_hematocrit_fahraeus(d, h_d, constants=args.constants)
        else:
            h_t = args.tube_hematocrit
            h_d = viscosity.discharge_hematocrit_fahraeus(d, h_t, constants=args.constants)
        # the ratio from the fit itself (exact even for tiny hematocrits), always <= 1
        ratio = viscosity.hematocrit_ratio_fahraeus(d, h_d, constants=args.constants)
    out = {"command": "fahraeus", "converged": True, "constants": args.constants, "diameter_um": d,
           "discharge_hematocrit": h_d, "tube_hematocrit": h_t, "ratio_HT_over_HD": ratio}
    method = f"Fahraeus ({args.constants})"
    rows = [(LABELS["diameter_um"], d, "um", "input", ""),
            (LABELS["discharge_hematocrit"], h_d, "-",
             "input" if args.discharge_hematocrit is not None else method, ""),
            (LABELS["tube_hematocrit"], h_t, "-",
             "input" if args.tube_hematocrit is not None else method, ""),
            (LABELS["ratio_HT_over_HD"], ratio, "-", method, "")]
    return out, format_rows(rows, f"Fahraeus effect in a {d:g} um tube") + "\n" + UNIT_CONVENTION


# --------------------------------------------------------------------------- parser

def _bounds(name: str) -> str:
    """The accepted range of a physical input, ``lo to hi`` (:data:`PHYSICAL_BOUNDS`)."""
    lo, hi, _ = PHYSICAL_BOUNDS[name]
    return f"{lo:g} to {hi:g}"


#: What each membrane of ``--membrane`` is (its help).
MEMBRANE_HELP = {
    "red-cell": "bending and shear elasticity (V/U, dp+, film, length and tensions from the "
                "red-cell map when the cell's beta = G_s R0^2/kappa is the map's, or estimate "
                "--solver bem)",
    "vesicle": "bending only (lipid vesicles, or a red cell's high-velocity limit)",
}

#: The library parameters of the options of :func:`_add_cell_options` (options: :data:`OPTIONS`).
CELL_PARAMETERS = ("velocity_mm_s", "shear_modulus_un_m", "membrane")


def _add_cell_options(parser, where: str = "") -> None:
    """``--velocity-mm-s``, ``--shear-modulus-uN-m`` and ``--membrane``, defined once for
    ``estimate`` and ``viscosity`` (``where``: appended to each help). Their default is None,
    so that a command sees whether they were given; the library's defaults apply
    (:data:`RBC_DEFAULTS`, :data:`correlations.registry.DEFAULT_MEMBRANE`) and the library
    checks the values (before any work; the message names the option, :data:`OPTIONS`)."""
    d, default = RBC_DEFAULTS, DEFAULT_MEMBRANE
    parser.add_argument("--velocity-mm-s", type=float,
                        help=f"mean flow velocity U [mm/s], {_bounds('velocity_mm_s')} "
                             f"(default {d['velocity_mm_s']:g}; a red cell answered by the "
                             f"red-cell map: within its velocities, 0.2 to 10 for the default "
                             f"cell){where}")
    parser.add_argument("--shear-modulus-uN-m", type=float,
                        help=f"membrane shear modulus G_s of a red cell [uN/m], "
                             f"{_bounds('shear_modulus_un_m')} (default "
                             f"{d['shear_modulus_un_m']:g}, Hochmuth & Waugh 1987; measured "
                             f"4-10); sets Ca_S = eta U/G_s{where}")
    parser.add_argument("--membrane", choices=MEMBRANES, help="; ".join(
        f"{m}{' (default)' if m == default else ''}: {MEMBRANE_HELP[m]}"
        for m in sorted(MEMBRANES, key=lambda m: m != default)) + where)


def build_parser() -> argparse.ArgumentParser:
    p = Parser(prog="vesicle-tube", description="Vesicles and red blood cells in narrow tubes "
                "(Stokes flow): geometry, engineering estimates, apparent viscosity.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=Parser)

    def common(sp):
        sp.add_argument("--json", action="store_true", help="print one JSON object on stdout")

    g = sub.add_parser("geometry", help="critical confinement, length and diameter")
    g.add_argument("--nu", type=float, help="reduced volume, 0 < nu <= 1 [-]")
    g.add_argument("--lam", type=float, help="confinement R0/R > 0 [-] (with --nu)")
    g.add_argument("--volume-fl", type=float, help="cell volume [fL = um^3], 1e-6 to 1e12")
    g.add_argument("--area-um2", type=float, help="membrane area [um^2]")
    g.add_argument("--diameter-um", type=float,
                   help="tube diameter [um], 1e-3 to 1e7 (with --volume-fl/--area-um2)")
    common(g)
    g.set_defaults(func=cmd_geometry)

    e = sub.add_parser("estimate", help="engineering estimate (default: human RBC in a 4 um capillary)")
    d, bounds = RBC_DEFAULTS, _bounds
    e.add_argument("--volume-fl", type=float,
                   help=f"cell volume [fL], {bounds('volume_fl')} (default {d['volume_fl']:g})")
    e.add_argument("--area-um2", type=float, help=f"membrane area [um^2], from the sphere of that "
                   f"volume to reduced volume 1e-6 (default {d['area_um2']:g})")
    e.add_argument("--diameter-um", type=float, help=f"tube diameter [um], above the cell's "
                   f"critical diameter, {bounds('diameter_um')} (default {d['diameter_um']:g})")
    e.add_argument("--plasma-viscosity-mpas", type=float,
                   help=f"suspending viscosity [mPa s], {bounds('plasma_viscosity_mpas')} "
                        f"(default {d['plasma_viscosity_mpas']:g})")
    e.add_argument("--bending-modulus-j", type=float,
                   help=f"bending modulus kappa [J], {bounds('bending_modulus_j')} "
                        f"(default {d['bending_modulus_j']:g})")
    _add_cell_options(e)
    e.add_argument("--nu", type=float, help="reduced volume [-] (dimensionless estimate, with --lam)")
    e.add_argument("--lam", type=float, help="confinement R0/R [-] (dimensionless estimate)")
    e.add_argument("--ca-b", type=float, help="bending capillary number eta U R0^2/kappa > 0 [-] "
                   "(with --nu/--lam; when omitted the closed forms assume Chen et al. 2020's "
                   "10 <= Ca_B <= 1e4 and the solvers use 50)")
    e.add_argument("--ca-s", type=float, help="shear capillary number eta U/G_s > 0 [-] of a "
                   "red cell (with --nu/--lam and --ca-b; default: a vesicle)")
    e.add_argument("--hematocrit", type=float, help="hematocrit, a fraction in [0, 1) [-]")
    e.add_argument("--hematocrit-kind", choices=("tube", "discharge"), default="tube",
                   help="whether --hematocrit is the tube (H_T) or discharge (H_D) value (default tube)")
    e.add_argument("--extrapolate", action="store_true",
                   help="fill quantities no method covers with flagged extrapolations")
    e.add_argument("--solver", action="append", default=[], choices=SOLVERS,
                   help="let the method table use this numerical solver where it is valid, "
                        "ahead of the closed forms (repeatable; lubrication: seconds, bem: the "
                        "BEM vesicle, most accurate, seconds to minutes per case)")
    e.add_argument("--no-map", action="store_true",
                   help="do not use the shipped solution map (stored BEM and lubrication "
                        "solutions, used by default inside its range, after enabled solvers): "
                        "closed forms and enabled solvers only")
    e.add_argument("--plot", metavar="FILE", help="write V/U and dp+ vs lam with this case marked (PNG)")
    common(e)
    e.set_defaults(func=cmd_estimate)

    v = sub.add_parser("viscosity", help="relative apparent viscosity of blood in a tube")
    v.add_argument("--diameter-um", type=float, required=True, help="tube diameter [um]")
    v.add_argument("--hematocrit", type=float, required=True, help="hematocrit, a fraction in [0, 1) [-]")
    v.add_argument("--hematocrit-kind", choices=("discharge", "tube"), default="discharge",
                   help="kind of --hematocrit (default discharge); converted with Fahraeus")
    v.add_argument("--law", choices=("pries1992", "pries1994", "pries2005", "single-file"),
                   default="pries1992", help="viscosity law (default pries1992, in vitro)")
    v.add_argument("--constants", choices=("pries1990", "pries1992"), default="pries1992",
                   help="Fahraeus constants for hematocrit conversion (default pries1992)")
    v.add_argument("--extrapolate", action="store_true", help="single-file: allow flagged extrapolation")
    _add_cell_options(v, " (--law single-file only)")
    v.add_argument("--plot", metavar="FILE", help="write eta_rel(d) for the laws (PNG); with "
                   "--law single-file, at several velocities")
    common(v)
    v.set_defaults(func=cmd_viscosity)

    f = sub.add_parser("fahraeus", help="tube <-> discharge hematocrit (Fahraeus effect)")
    f.add_argument("--diameter-um", type=float, required=True, help="tube diameter [um]")
    f.add_argument("--discharge-hematocrit", type=float, help="discharge hematocrit H_D, fraction [-]")
    f.add_argument("--tube-hematocrit", type=float, help="tube hematocrit H_T, fraction [-]")
    f.add_argument("--constants", choices=("pries1990", "pries1992"), default="pries1992",
                   help="fit constants (a, b) of the Fahraeus relation (default pries1992, as the "
                        "viscosity command and the estimate)")
    common(f)
    f.set_defaults(func=cmd_fahraeus)

    # each command module is light: its solvers load inside its commands
    for add in (add_lubrication_parser, add_bem_parser, add_map_parser, add_check_parser,
                add_infer_parser, add_figures_parser):
        add(sub)
    return p


def _prog(args) -> str:
    """``vesicle-tube COMMAND [SUBCOMMAND]`` for messages."""
    sub = getattr(args, "bem_command", None)
    return " ".join(["vesicle-tube", args.command] + ([sub] if sub else []))


def _check_outputs(args) -> None:
    """Every output option is checked before any work: the folder of ``--out``, the folder
    and format of ``--plot`` and of ``--report``."""
    check_output_dir("--out", getattr(args, "out", None))
    check_plot_path("--plot", getattr(args, "plot", None))
    check_report_path("--report", getattr(args, "report", None))


# Result keys of every command checked against the physical bounds
# (lubrication.checks.OUTPUT_BOUNDS), with the quantity whose bound applies.
#
# The membrane tensions have no bound (their sign is not a law: OUTPUT_BOUNDS).
_BOUNDED_KEYS = (("V_over_U", "V_over_U"), ("dp_plus_R0", "dp_plus_R0"),
                 ("dp_plus_R", "dp_plus_R0"), ("film_min", "film"), ("film", "film"),
                 ("ell", "ell"), ("eta_rel", "eta_rel"))


def _unphysical_flags(out: dict) -> list[str]:
    """Every reported number outside the bounds the physics sets, at the top level of the
    result and in its sweep ``points``: flagged, never silent (a model used beyond its meaning,
    e.g. the lubrication model for a short vesicle)."""
    flags = []
    points = out.get("points")
    rows = [("", out)] + [(f"point {i + 1}: ", p) for i, p in
                          enumerate(points if isinstance(points, list) else [])
                          if isinstance(p, dict)]
    for where, row in rows:
        for key, quantity in _BOUNDED_KEYS:
            value = row.get(key)
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                problem = check_output(quantity, float(value), {})
                if problem:
                    flags.append(f"UNPHYSICAL {where}{key}: {problem}")
    return flags


def _run(args) -> int:
    """Run the command of ``args`` under the contract of :mod:`correlations.cli.contract`."""
    prog = _prog(args)
    forget_written_files()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", OutOfRangeWarning)
        try:
            _check_outputs(args)
            out, human = args.func(args)
        except (InvalidParameterError, UsageError) as exc:
            print(f"{prog}: error: {one_line(exc)}", file=sys.stderr)
            return EXIT_INVALID
        except BrokenPipeError:
            raise
        except OSError as exc:      # a file the command writes as it works (map build, figures)
            for path in written_files():
                print(f"wrote {path}", file=sys.stderr)
            print(f"{prog}: error: {os_error_message(exc)}; the work stopped there",
                  file=sys.stderr)
            return EXIT_NOT_WRITTEN
    bad = non_finite_keys(out)
    if bad:     # a safety net: every command reports missing values as None, never NaN/inf
        print(f"{prog}: error: the result has non-finite values ({', '.join(bad[:5])}): the "
              "computation overflowed or failed; no numbers are reported", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    flags = _unphysical_flags(out)
    if flags:
        out["unphysical"] = flags
        human += "\n" + "\n".join(flags)
    messages = out.get("warnings", []) + [str(w.message) for w in caught
                                          if issubclass(w.category, OutOfRangeWarning)] + flags
    for m in messages:
        print(f"warning: {m}", file=sys.stderr)
    if messages:
        out["warnings"] = messages
    for path in written_files():
        print(f"wrote {path}", file=sys.stderr)
    print(dump_json(out, sys.stdout) if args.json else human, flush=True)
    converged = out.get("converged", True)
    if not converged and out.get("message"):
        print(f"{prog}: not converged: {out['message']}", file=sys.stderr)
    for entry in out.get("not_written", []):
        print(f"{prog}: error: {not_written_message(entry)}", file=sys.stderr)
    if out.get("not_written"):
        return EXIT_NOT_WRITTEN
    if out.get("command") == "check" and out.get("verdict") == "fail":
        return EXIT_CHECK_FAILED
    if out.get("command") == "infer" and out.get("status") == "inconsistent":
        print(f"{prog}: {out['message']}", file=sys.stderr)
        return EXIT_CHECK_FAILED
    return EXIT_OK if converged else EXIT_NOT_CONVERGED


def main(argv=None) -> int:
    """Entry point of ``vesicle-tube``: exit status per :mod:`correlations.cli.contract`."""
    prog = "vesicle-tube"
    with command_streams():
        try:
            args = build_parser().parse_args(argv)
            prog = _prog(args)
            return _run(args)
        except (KeyboardInterrupt, SystemError) as exc:     # SystemError: see is_interrupt
            if not is_interrupt(exc):
                raise
            print(interrupted_message(prog), file=sys.stderr)
            return EXIT_INTERRUPTED
        except BrokenPipeError:
            return quiet_broken_pipe()
        except OSError as exc:      # stdout (the result, --help): a full disk, an I/O error
            return output_failed(prog, exc)

