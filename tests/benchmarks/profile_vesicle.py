"""Where the time of a steady BEM vesicle solve goes (prints tables; not a test).

Run with ``python tests/benchmarks/profile_vesicle.py [--case NU LAM] [--modes 16,24,32,48,64]``.

(a) One default :func:`bem.vesicle.solve_vesicle` per ``--case`` (default (0.9, 1.0)) with
timers wrapped around the pieces of :class:`bem.vesicle.VesicleOperator` and of the
Levenberg–Marquardt driver (:mod:`bem.newton`): influence-matrix assembly (membrane on itself,
membrane and wall on each other, wall sources, inlet), wall LU back-substitution, tension/V least
squares, curve construction (closed curve and area secant), membrane panels (curve sampling),
bending and tension forces, the dense products of the operator, the fixed-load points of
directional updates, the linearised points of difference Jacobians (each point's displacements
and inlet; once per Jacobian the expansion of the far pairs and near blocks and the products and
wall solve of all its points), Newton linear algebra, level set-up, seed and outputs. Times are *exclusive*
(a timer's time minus that of the timers called inside it), so the rows add up to the wall
time; "unaccounted" is the rest (driver code). The evaluations are split by what asked for
them (difference-Jacobian columns, prolonged Jacobians' new columns included; directional
Jacobian updates; damped LM trial steps; other: initial point and extrapolation) per level.
The SpectralCurve rows below the table are inclusive and count every caller.

(b) The cost of ONE evaluation (``VesicleOperator.evaluate`` of a fixed shape: the lubrication
shape at ``--scaling-case`` (default (0.9, 1.0)), Ca_B = 50, fitted with N modes) and of one
Newton step (one difference Jacobian, its points evaluated concurrently as in the solver, plus
one damped LM step), with the solver's BLAS threading (:mod:`bem.threads`), against N, with
the panels of :func:`bem.vesicle.vesicle_discretisation` (N), and the fitted exponent p of
time ~ N^p. The evaluation times are minima over ``--repeats``; the per-category columns are
minima per category (their sum can be below the minimum total). ``--json
docs/data/bench_evaluation_scaling.json`` stores the table for docs/validation.md.

With concurrent evaluations (numba's thread count > 1) the per-category rows of (a) are thread
times and the Newton rows include the wait for the worker threads, so the rows add up to
more than the wall time.

Timings are wall-clock and depend on the load of the machine: compare BIE solves and evaluation
counts, which do not. Numba is compiled (warm cache) before anything is timed. The library is
not modified: the timers are installed by replacing module attributes for the duration of the
run and removed afterwards.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import threading
import time
from collections import defaultdict
from pathlib import Path

#: what asked for an evaluation (the innermost of these on the timer stack)
_PHASES = {"Newton: difference Jacobian": "Jacobian columns",
           "Newton: directional update": "directional updates",
           "Newton: damped LM step": "LM trial steps"}

#: row order of the exclusive-time table
_ORDER = ["assembly: membrane on itself", "assembly: membrane and wall on each other",
          "assembly: wall sources",
          "assembly: inlet", "wall LU back-substitution", "tension/V least squares (lstsq)",
          "curve construction (closed curve, area secant)", "membrane panels (curve sampling)",
          "bending force", "tension basis", "operator products (A@Q, B@qw, ...)",
          "evaluate: rest", "fixed-load point: rest",
          "linearised point: displacements, inlet",
          "linearised Jacobian: expansion (far pairs, near blocks)",
          "linearised Jacobian: products, wall solve", "Newton: difference Jacobian",
          "Newton: directional update",
          "Newton: damped LM step", "Newton: Gauss-Newton promise",
          "level set-up (wall matrix + LU, breaks, area mode)", "seed (lubrication solve + fit)",
          "shape fits (fit_curve)", "outputs (level_outputs, profile, wall shear)"]


class Profiler:
    """Stacks of wall-clock timers installed by replacing attributes (restored by
    ``restore``), one stack per thread: the solver evaluates the points of a difference
    Jacobian on worker threads, whose evaluations are classified by the main thread's stack
    and whose times are thread times (the rows then add up to more than the wall time)."""

    def __init__(self):
        self._patches = []
        self._local = threading.local()
        self._main = threading.get_ident()
        self._stacks = {}
        self._lock = threading.Lock()
        self.level = None
        self.reset()

    @property
    def stack(self) -> list:
        st = getattr(self._local, "stack", None)
        if st is None:
            st = self._local.stack = []
            self._stacks[threading.get_ident()] = st
        return st

    def _phase(self) -> str:
        main = self._stacks.get(self._main, [])
        for c, _ in [*reversed(self.stack), *reversed(main)]:
            if c in _PHASES:
                return _PHASES[c]
        return "other (initial point, extrapolation)"

    def reset(self):
        self.excl = defaultdict(float)
        self.calls = defaultdict(int)
        self.tally = defaultdict(float)
        self.tally_calls = defaultdict(int)
        self.evals = defaultdict(int)
        self.eval_time = defaultdict(float)

    def _set(self, owner, attr, value):
        self._patches.append((owner, attr, owner.__dict__[attr]))
        setattr(owner, attr, value)

    def timer(self, owner, attr, name, classify=None, evaluation=False):
        """Replace ``owner.attr`` by a timed version (category ``name`` or ``classify(args)``)."""
        fn = getattr(owner, attr)

        def wrapped(*args, **kwargs):
            cat = classify(*args) if classify else name
            phase = self._phase() if evaluation else None
            stack = self.stack
            stack.append([cat, 0.0])
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                el = time.perf_counter() - t0
                _, child = stack.pop()
                with self._lock:
                    self.excl[cat] += el - child
                    self.calls[cat] += 1
                    if stack:
                        stack[-1][1] += el
                    if evaluation:
                        self.evals[(self.level, phase)] += 1
                        self.eval_time[(self.level, phase)] += el
        self._set(owner, attr, wrapped)

    def tallied(self, owner, attr, name):
        """Replace ``owner.attr`` by a version whose inclusive time is tallied (no stack)."""
        fn = getattr(owner, attr)

        def wrapped(*args, **kwargs):
            t0 = time.perf_counter()
            try:
                return fn(*args, **kwargs)
            finally:
                with self._lock:
                    self.tally[name] += time.perf_counter() - t0
                    self.tally_calls[name] += 1
        self._set(owner, attr, wrapped)

    def level_marker(self, owner, attr):
        """Record the shape modes of the level being solved (``solve_level``'s disc)."""
        fn = getattr(owner, attr)

        def wrapped(nu, lam, ca_b, disc, *args, **kwargs):
            outer, self.level = self.level, disc.n_modes
            try:
                return fn(nu, lam, ca_b, disc, *args, **kwargs)
            finally:
                self.level = outer
        self._set(owner, attr, wrapped)

    def restore(self):
        for owner, attr, value in reversed(self._patches):
            setattr(owner, attr, value)
        self._patches.clear()


def install(prof: Profiler) -> None:
    """Timers around the pieces of one vesicle solve (see the module docstring)."""
    import scipy.linalg

    import bem.drop
    import bem.newton
    import bem.shape
    import bem.vesicle
    from bem.vesicle import ladder, level, operator, seeds

    def source(tx, tr, panels, **_):
        if (panels.r == 1.0).all():
            return "assembly: wall sources"
        if (panels.tx == 0.0).all():
            return "assembly: inlet"
        return "assembly: membrane on itself"

    V, D = bem.vesicle.VesicleOperator, bem.drop.DropOperator
    prof.timer(operator, "influence", None, classify=source)
    prof.timer(operator, "influence_pair", "assembly: membrane and wall on each other")
    prof.timer(scipy.linalg, "lu_solve", "wall LU back-substitution")
    prof.timer(scipy.linalg, "lstsq", "tension/V least squares (lstsq)")
    prof.timer(V, "curve", "curve construction (closed curve, area secant)")
    prof.timer(D, "panels", "membrane panels (curve sampling)")
    prof.timer(operator, "bending_force", "bending force")
    prof.timer(operator, "tension_basis", "tension basis")
    prof.timer(V, "_flow", "operator products (A@Q, B@qw, ...)")
    prof.timer(V, "evaluate", "evaluate: rest", evaluation=True)
    prof.timer(V, "fixed_residual", "fixed-load point: rest", evaluation=True)
    prof.timer(V, "linearised_residual", "linearised point: displacements, inlet",
               evaluation=True)
    prof.timer(V, "taylor", "linearised Jacobian: expansion (far pairs, near blocks)")
    prof.timer(V, "linearised_finish", "linearised Jacobian: products, wall solve")
    for owner in (bem.newton, level):              # the vesicle's prolonged Jacobians too
        prof.timer(owner, "difference_jacobian", "Newton: difference Jacobian")
    prof.timer(bem.newton, "_directional_update", "Newton: directional update")
    prof.timer(bem.newton, "_damped_step", "Newton: damped LM step")
    prof.timer(bem.newton, "_promised", "Newton: Gauss-Newton promise")
    prof.timer(V, "__init__", "level set-up (wall matrix + LU, breaks, area mode)")
    prof.timer(ladder, "lubrication_seed", "seed (lubrication solve + fit)")
    for owner in (seeds, level, ladder):            # every module of the solver that fits curves
        prof.timer(owner, "fit_curve", "shape fits (fit_curve)")
    for name in ("level_outputs", "membrane_profile"):
        prof.timer(ladder, name, "outputs (level_outputs, profile, wall shear)")
    prof.timer(V, "wall_shear", "outputs (level_outputs, profile, wall shear)")
    prof.level_marker(ladder, "solve_level")
    S = bem.shape.SpectralCurve
    for attr in ("position", "curvatures", "_integrals", "volume_and_centroid", "area"):
        prof.tallied(S, attr, f"SpectralCurve.{attr}")
    prof.tallied(bem.shape, "_closing_mode", "shape._closing_mode")
    prof.tallied(V, "_raw_curve", "VesicleOperator._raw_curve (one closed curve)")


def warm_up() -> None:
    """Compile numba and fill the caches (not timed)."""
    from bem.vesicle import solve_vesicle
    solve_vesicle(0.98, 0.3, n_modes=8, tol=0.5, residual_tol=10)


def _load() -> str:
    try:
        return "load average " + " ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:                                  # pragma: no cover - not on every system
        return "load average unknown"


# ---------------------------------------------------------------------------- (a) one solve
def profile_solve(nu: float, lam: float, kwargs: dict) -> dict:
    """One solve under the timers; returns the tables' data."""
    from bem.vesicle import solve_vesicle

    prof = Profiler()
    install(prof)
    try:
        t0 = time.perf_counter()
        res = solve_vesicle(nu, lam, **kwargs)
        wall = time.perf_counter() - t0
    finally:
        prof.restore()
    return {"nu": nu, "lam": lam, "kwargs": kwargs, "wall_s": wall,
            "bie_solves": res.bie_solves, "success": res.success, "message": res.message,
            "V_over_U": res.V_over_U, "dp_plus_R0": res.dp_plus_R0,
            "tension_max": res.tension_max, "residual": res.residual,
            "iterations": res.iterations, "timings": res.timings,
            "excl": dict(prof.excl), "calls": dict(prof.calls),
            "tally": dict(prof.tally), "tally_calls": dict(prof.tally_calls),
            "evals": {f"{k[0]}|{k[1]}": v for k, v in prof.evals.items()},
            "eval_time": {f"{k[0]}|{k[1]}": v for k, v in prof.eval_time.items()}}


def print_solve(d: dict) -> None:
    wall = d["wall_s"]
    print(f"\n(a) solve_vesicle({d['nu']:g}, {d['lam']:g}"
          + "".join(f", {k}={v!r}" for k, v in d["kwargs"].items()) + ")")
    print(f"    wall {wall:.2f} s, BIE solves {d['bie_solves']}, success {d['success']}; "
          f"V/U {d['V_over_U']:.10f}, dp+R0 {d['dp_plus_R0']:.8g}, gamma_max "
          f"{d['tension_max']:.6g}, residual {d['residual']:.2e}")
    print(f"    {d['message']}")
    print(f"\n    {'category (exclusive time)':<58} {'s':>8} {'%':>6} {'calls':>7}")
    rows = sorted(d["excl"], key=lambda c: _ORDER.index(c) if c in _ORDER else 99)
    for c in rows:
        print(f"    {c:<58} {d['excl'][c]:8.3f} {100 * d['excl'][c] / wall:6.1f} "
              f"{d['calls'][c]:7d}")
    rest = wall - sum(d["excl"].values())
    if rest >= 0.0:
        print(f"    {'unaccounted (driver)':<58} {rest:8.3f} {100 * rest / wall:6.1f}")
    else:
        print(f"    {'(rows are thread times: Jacobian points evaluated concurrently)':<58} "
              f"{-rest:8.3f} {-100 * rest / wall:6.1f}  more than the wall time")
    print(f"    {'total wall':<58} {wall:8.3f} {100.0:6.1f}")
    groups = {"influence assembly (all)": [c for c in rows if c.startswith("assembly")],
              "curve work in evaluations (curve + panels + forces)":
                  ["curve construction (closed curve, area secant)",
                   "membrane panels (curve sampling)", "bending force", "tension basis"],
              "linear algebra in evaluations (LU + lstsq + products + rest)":
                  ["wall LU back-substitution", "tension/V least squares (lstsq)",
                   "operator products (A@Q, B@qw, ...)", "evaluate: rest",
                   "fixed-load point: rest"],
              "linearised Jacobian points (points + expansion + finish)":
                  [c for c in rows if c.startswith("linearised")]}
    for g, cs in groups.items():
        s = sum(d["excl"].get(c, 0.0) for c in cs)
        print(f"    = {g:<56} {s:8.3f} {100 * s / wall:6.1f}")
    print(f"\n    {'inclusive, every caller':<58} {'s':>8} {'%':>6} {'calls':>7}")
    for c, t in sorted(d["tally"].items(), key=lambda kv: -kv[1]):
        print(f"    {c:<58} {t:8.3f} {100 * t / wall:6.1f} {d['tally_calls'][c]:7d}")
    # evaluations per level and phase
    levels = sorted({k.split("|")[0] for k in d["evals"]},
                    key=lambda s: (s == "None", int(s) if s.isdigit() else 0))
    phases = ["Jacobian columns", "directional updates", "LM trial steps",
              "other (initial point, extrapolation)"]
    print("\n    evaluations by level and purpose (count / seconds incl.)")
    print(f"    {'level':>8} " + " ".join(f"{p[:22]:>22}" for p in phases)
          + f" {'total':>12} {'level s':>8} {'s/eval':>7} {'jac':>4} {'it':>4}")
    tot = defaultdict(lambda: [0, 0.0])
    for lv in levels:
        cells, n_lv, t_lv = [], 0, 0.0
        for p in phases:
            n = d["evals"].get(f"{lv}|{p}", 0)
            t = d["eval_time"].get(f"{lv}|{p}", 0.0)
            tot[p][0] += n
            tot[p][1] += t
            n_lv, t_lv = n_lv + n, t_lv + t
            cells.append(f"{n:5d} / {t:7.2f} s    ")
        info = d["iterations"].get(f"modes{lv}", {})
        secs = d["timings"].get(f"modes{lv}_s", math.nan)
        print(f"    {lv:>8} " + " ".join(f"{c:>22}" for c in cells)
              + f" {n_lv:4d}/{t_lv:6.2f}s {secs:8.2f} {t_lv / max(n_lv, 1):7.3f} "
              f"{info.get('jacobians', 0):4d} {info.get('iterations', 0):4d}")
    n_all = sum(v[0] for v in tot.values())
    t_all = sum(v[1] for v in tot.values())
    print(f"    {'all':>8} " + " ".join(f"{f'{tot[p][0]:5d} / {tot[p][1]:7.2f} s    ':>22}"
                                      for p in phases)
          + f" {n_all:4d}/{t_all:6.2f}s")
    print("    (rung levels of a continuation are listed under their mode count as well)")


# ---------------------------------------------------------------------------- (b) scaling
def _solver_blas():
    """The BLAS threading that solve_vesicle uses (bem.threads, where it exists)."""
    try:
        from bem.threads import single_threaded_blas
    except ImportError:                              # older versions of the package
        from contextlib import nullcontext
        return nullcontext()
    return single_threaded_blas()


def _fit(ns, ts) -> float:
    import numpy as np
    ok = [(n, t) for n, t in zip(ns, ts) if t > 0 and math.isfinite(t)]
    if len(ok) < 2:
        return math.nan
    x, y = np.log([n for n, _ in ok]), np.log([t for _, t in ok])
    return float(np.polyfit(x, y, 1)[0])


def profile_scaling(modes, repeats: int, newton: bool, nu=0.9, lam=1.0, ca_b=50.0) -> list:
    """Time one evaluation and one Newton step at each mode count (see the module docstring)."""
    import numpy as np

    import bem.newton as newton_mod
    from bem.vesicle import (VesicleOperator, level_function, lubrication_seed,
                             vesicle_discretisation)

    _, lub = lubrication_seed(nu, lam, ca_b, 16)
    from bem.vesicle import seed_from_lubrication

    rows = []
    for n in modes:
        seed = seed_from_lubrication(lub, n)
        disc = vesicle_discretisation(n)
        op = VesicleOperator(nu, lam, ca_b, disc, seed)
        template = op.curve(seed.modes).modes.copy()
        z0 = op.free(template)

        fun = level_function(op, template)                # as bem.vesicle.level.solve_level
        prof = Profiler()
        install(prof)
        blas = _solver_blas()
        blas.__enter__()
        try:
            fun(z0)                                       # first call: caches
            best, per = math.inf, defaultdict(lambda: math.inf)
            for _ in range(repeats):
                prof.reset()
                t0 = time.perf_counter()
                F, state = fun(z0)
                el = time.perf_counter() - t0
                best = min(best, el)
                for c, t in prof.excl.items():
                    per[c] = min(per[c], t)
            t_newton, n_newton = math.nan, 0
            if newton:
                ev0 = op.evaluations
                t0 = time.perf_counter()
                J, _ = newton_mod.difference_jacobian(fun, z0, F, 1e-7, {}, state)
                newton_mod._damped_step(fun, z0, J, F, float(np.linalg.norm(F)), 1e-8, True)
                t_newton = time.perf_counter() - t0
                n_newton = op.evaluations - ev0
        finally:
            blas.__exit__(None, None, None)
            prof.restore()
        rows.append({"modes": n, "panels": disc.n_panels, "nodes": op.tau.size,
                     "wall_nodes": op.wall.n_nodes, "inlet_nodes": op.inlet.n_nodes,
                     "eval_s": best, "per": dict(per), "newton_s": t_newton,
                     "newton_evals": n_newton})
        print(f"    ... {n} modes: evaluation {best:.3f} s"
              + (f", Newton step {t_newton:.2f} s ({n_newton} evaluations)" if newton else ""),
              flush=True)
    return rows


def print_scaling(rows: list, repeats: int) -> None:
    cols = [("memb src", ["assembly: membrane on itself"]),
            ("wall src", ["assembly: wall sources"]), ("inlet", ["assembly: inlet"]),
            ("LU solve", ["wall LU back-substitution"]),
            ("lstsq", ["tension/V least squares (lstsq)"]),
            ("curve", ["curve construction (closed curve, area secant)"]),
            ("panels", ["membrane panels (curve sampling)"]),
            ("forces", ["bending force", "tension basis"]),
            ("products", ["operator products (A@Q, B@qw, ...)", "evaluate: rest"])]
    print(f"\n(b) one evaluation (min of {repeats}) and one Newton step (difference Jacobian + "
          f"one damped LM step) against the shape modes N; times in ms unless marked s")
    print(f"    {'N':>3} {'panels':>6} {'nodes':>5} {'wall':>5} {'eval':>7} "
          + " ".join(f"{h:>8}" for h, _ in cols) + f" {'Newton s':>9} {'evals':>5}")
    for r in rows:
        vals = [sum(r["per"].get(c, 0.0) for c in cs) * 1e3 for _, cs in cols]
        print(f"    {r['modes']:3d} {r['panels']:6d} {r['nodes']:5d} {r['wall_nodes']:5d} "
              f"{r['eval_s'] * 1e3:7.1f} " + " ".join(f"{v:8.1f}" for v in vals)
              + f" {r['newton_s']:9.2f} {r['newton_evals']:5d}")
    ns = [r["modes"] for r in rows]
    exps = [_fit(ns, [sum(r["per"].get(c, 0.0) for c in cs) for r in rows]) for _, cs in cols]
    print(f"    {'p':>3} {'':>6} {_fit(ns, [r['nodes'] for r in rows]):5.2f} "
          f"{_fit(ns, [r['wall_nodes'] for r in rows]):5.2f} "
          f"{_fit(ns, [r['eval_s'] for r in rows]):7.2f} "
          + " ".join(f"{p:8.2f}" for p in exps)
          + f" {_fit(ns, [r['newton_s'] for r in rows]):9.2f} "
          f"{_fit(ns, [r['newton_evals'] for r in rows]):5.2f}")
    print("    p: fitted exponent of time ~ N^p (least squares in log-log over the rows)")


# ---------------------------------------------------------------------------- command line
def main(argv=None) -> None:
    ap = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="Example: profile_vesicle.py --case 0.9 1.0 --case 0.61 1.39 --tol 2e-2 "
               "--residual-tol 5e-3 --modes 16,24,32,48,64")
    ap.add_argument("--case", nargs=2, type=float, action="append", metavar=("NU", "LAM"),
                    help="profile a default solve at reduced volume NU [-] and confinement "
                         "LAM = R0/R [-] (repeatable; default 0.9 1.0)")
    ap.add_argument("--ca-b", type=float, default=50.0, help="Ca_B = eta U R0^2/kappa [-] (default 50)")
    ap.add_argument("--tol", type=float, default=None,
                    help="refinement-pair tolerance of every --case solve [-] (default: the "
                         "solver's)")
    ap.add_argument("--residual-tol", type=float, default=None,
                    help="steady residual tolerance of every --case solve [U] (default: the "
                         "solver's)")
    ap.add_argument("--scaling-case", nargs=2, type=float, default=(0.9, 1.0),
                    metavar=("NU", "LAM"),
                    help="(nu, lam) of the scaling table (b): its lubrication shape is fitted "
                         "with each mode count (default 0.9 1.0)")
    ap.add_argument("--modes", default="16,24,32,48,64",
                    help="shape modes of the scaling table (b), comma separated (default "
                         "16,24,32,48,64)")
    ap.add_argument("--repeats", type=int, default=3,
                    help="repeats of one evaluation in (b); the minimum is reported "
                         "(default 3)")
    ap.add_argument("--no-newton", action="store_true",
                    help="(b) without the Newton step (N evaluations each: minutes at N=64)")
    ap.add_argument("--no-solve", action="store_true", help="skip the solve profile (a)")
    ap.add_argument("--no-scaling", action="store_true", help="skip the scaling table (b)")
    ap.add_argument("--json", help="also write the raw numbers to this JSON file")
    args = ap.parse_args(argv)

    import numba
    warm_up()
    print(f"numba {numba.__version__}: {numba.get_num_threads()} threads "
          f"({numba.config.THREADING_LAYER} layer), {os.cpu_count()} CPUs, {_load()}")
    out = {"solves": [], "scaling": []}
    kwargs = {"ca_b": args.ca_b}
    if args.tol is not None:
        kwargs["tol"] = args.tol
    if args.residual_tol is not None:
        kwargs["residual_tol"] = args.residual_tol
    if not args.no_solve:
        for nu, lam in args.case or [(0.9, 1.0)]:
            d = profile_solve(nu, lam, kwargs)
            print_solve(d)
            out["solves"].append(d)
    if not args.no_scaling:
        modes = [int(m) for m in args.modes.split(",")]
        nu, lam = args.scaling_case
        print(f"\n(b) scaling at ({nu:g}, {lam:g}), Ca_B = {args.ca_b:g} ({_load()})")
        out["scaling"] = profile_scaling(modes, args.repeats, not args.no_newton,
                                         nu=nu, lam=lam, ca_b=args.ca_b)
        out["scaling_case"] = {"nu": nu, "lam": lam, "ca_b": args.ca_b,
                               "threads": numba.get_num_threads(), "load": _load()}
        ns = [r["modes"] for r in out["scaling"]]
        out["scaling_exponent"] = {k: _fit(ns, [r[k] for r in out["scaling"]])
                                   for k in ("eval_s", "newton_s")}
        print_scaling(out["scaling"], args.repeats)
    print(f"\n{_load()}")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1, default=str))


if __name__ == "__main__":
    main()
