"""``vesicle-tube infer``: a cell's reduced volume, size, film, Δp⁺ and tension from its
measured speed and length in a tube (:mod:`correlations.infer`).

Follows :mod:`correlations.cli.contract`: a table or ``--json``; exit 0 when a steady vesicle of
the solution map matches the data, 1 when none does (the verdict and the residual on stderr),
2 for bad input (one line naming the option, its value and the valid range, before any work),
130 on Ctrl-C. Light at start: scipy and the map load only inside the command.
"""

from __future__ import annotations

from correlations.cli.contract import (UsageError, add_map_option, finite_float, format_rows,
                                      format_value, format_value_error, options_named,
                                      positive_int)

__all__ = ["add_infer_parser", "cmd_infer"]

#: the option a user types for each parameter of :func:`correlations.infer.infer_cell`
OPTIONS = {"v_mm_s": "--v-mm-s", "v_over_u": "--v-over-u", "length_um": "--length-um",
           "diameter_um": "--diameter-um", "u_mm_s": "--u-mm-s", "eta_mpas": "--eta-mpas",
           "dpdx_pa_m": "--dpdx-pa-m",
           "kappa_j": "--kappa-j", "v_err": "--v-err", "length_err": "--length-err",
           "diameter_err": "--diameter-err", "u_err": "--u-err", "map": "--map",
           "samples": "--samples", "dpdx_err": "--dpdx-err"}
#: U and its error computed from the pressure gradient (``--dpdx-pa-m``) come from that option
#: and ``--dpdx-err``, not from ``--u-mm-s`` and ``--u-err``: a message about them names those
#: (``options_named`` would otherwise mark the untyped ``--u-mm-s`` "(default)", an option
#: that has no default)
FROM_GRADIENT = {"u_mm_s": "--dpdx-pa-m", "u_err": "--dpdx-err"}

#: rows of the table, in order, with their labels
ROWS = (("nu", "reduced volume nu"), ("lam", "confinement lam = R0/R"),
        ("lam_ratio", "lam/lam_c"), ("delta", "clearance delta = 1 - lam/lam_c"),
        ("R0_um", "volume radius R0"), ("volume_fl", "volume"), ("area_um2", "membrane area"),
        ("ca_b", "Ca_B = eta U R0^2/kappa"), ("V_over_U", "speed V/U (fit)"),
        ("ell", "length L/R (fit)"), ("film", "film thickness h"), ("film_nm", "film thickness h"),
        ("dp_plus_R0", "extra pressure drop dp+"), ("dp_plus_Pa", "extra pressure drop dp+"),
        ("tension_max", "maximum tension"), ("tension_max_mN_m", "maximum tension"),
        ("tension_front", "front tension"), ("tension_front_mN_m", "front tension"))


def cmd_infer(args):
    from correlations.infer import (  # lazy: correlations.infer off the estimate's start-up
        infer_cell, mean_velocity_from_gradient)
    from_gradient = FROM_GRADIENT if args.dpdx_pa_m is not None else {}
    with options_named({**OPTIONS, **from_gradient}, args):
        u_mm_s, u_err = args.u_mm_s, args.u_err
        if args.dpdx_pa_m is not None:
            if args.eta_mpas is None:
                raise UsageError("--dpdx-pa-m: needs --eta-mpas (U = G R^2/(8 eta))")
            u_mm_s, u_err = mean_velocity_from_gradient(args.dpdx_pa_m, args.diameter_um,
                                                        args.eta_mpas, args.dpdx_err,
                                                        args.diameter_err)
        r = infer_cell(length_um=args.length_um, diameter_um=args.diameter_um,
                       u_mm_s=u_mm_s, v_mm_s=args.v_mm_s, v_over_u=args.v_over_u,
                       length_err=args.length_err, diameter_err=args.diameter_err,
                       u_err=u_err, v_err=args.v_err, eta_mpas=args.eta_mpas,
                       kappa_j=args.kappa_j, samples=args.samples or 0,
                       solution_map=args.map, uncertainty=args.uncertainty)
    out = {"command": "infer", "converged": True, **r.to_dict()}
    rows = []
    for key, label in ROWS:
        q = r.quantities.get(key)
        if q is not None:
            shown = (format_value_error(q.value, q.error) if q.low95 is None
                     else format_value(q.value))
            rows.append((label, shown, q.unit,
                         "map fit", _intervals(q)))
    lines = [format_rows(rows, f"Inferred cell: {r.message}")] if rows else [r.message]
    lines += [f"fit residual chi = {r.fit.chi:.3g} combined standard deviations"
              if r.fit else "no fit", f"uncertainty: {r.method}"]
    lines += [f"assumption: {a}" for a in r.assumptions] + [f"note: {n}" for n in r.notes]
    return out, "\n".join(lines)


def _intervals(q) -> str:
    """The 68 % and 95 % intervals of an inferred value, where it has them."""
    if q.low is None:
        return ""
    text = f"68 %: {q.low:.4g} to {q.high:.4g}"
    if q.low95 is None:
        return text
    return f"posterior {text}; 95 %: {q.low95:.4g} to {q.high95:.4g}"


def add_infer_parser(subparsers) -> None:
    """Add ``infer`` to the subcommands."""
    p = subparsers.add_parser(
        "infer", help="infer a cell (nu, lam, volume, area, film, dp+, tension) from its "
                      "measured speed and length in a tube, with uncertainties")
    speed = p.add_mutually_exclusive_group(required=True)
    speed.add_argument("--v-mm-s", type=finite_float, help="measured cell speed V [mm/s]")
    speed.add_argument("--v-over-u", type=finite_float, help="measured V/U [-]")
    p.add_argument("--length-um", type=finite_float, required=True,
                   help="measured full axial cell length L [um]")
    p.add_argument("--diameter-um", type=finite_float, required=True, help="tube diameter d [um]")
    flow = p.add_mutually_exclusive_group(required=True)
    flow.add_argument("--u-mm-s", type=finite_float, help="mean flow velocity U [mm/s]")
    flow.add_argument("--dpdx-pa-m", type=finite_float, metavar="G",
                      help="imposed pressure gradient -dp/dx of the Poiseuille flow [Pa/m] "
                           "(needs --eta-mpas): U = G R^2/(8 eta)")
    p.add_argument("--dpdx-err", type=finite_float,
                   help="absolute 1-sigma uncertainty of G [Pa/m] (default 2 %% of the value)")
    p.add_argument("--eta-mpas", type=finite_float,
                   help="suspending viscosity [mPa s] (dp+ in Pa, tensions in mN/m; with "
                        "--kappa-j: Ca_B, else Ca_B = 50 is assumed)")
    p.add_argument("--kappa-j", type=finite_float, help="bending modulus kappa [J]")
    for name, unit, what in (("v", "mm/s, or - with --v-over-u", "V or V/U"),
                             ("length", "um", "L"), ("diameter", "um", "d"),
                             ("u", "mm/s", "U")):
        p.add_argument(f"--{name}-err", type=finite_float,
                       help=f"absolute 1-sigma uncertainty of {what} [{unit}] (default 2 %% of "
                            "the value)")
    p.add_argument("--uncertainty", choices=("posterior", "linear"), default="posterior",
                   help="posterior: the cells consistent with the data over the whole map, with "
                        "68 %% and 95 %% intervals that follow valleys and branches (default; "
                        "seconds); linear: linearisation at the best fit (under a second, blind "
                        "to valleys)")
    p.add_argument("--samples", type=positive_int, metavar="N",
                   help="propagate the uncertainty by N refitted Gaussian draws instead")
    add_map_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.set_defaults(func=cmd_infer)
