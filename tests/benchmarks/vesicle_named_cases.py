"""Default BEM vesicle solves of the named cases, timed, optionally against another revision.

Run with ``python tests/benchmarks/vesicle_named_cases.py [--against REV]``. The cases: the seven
of ``default_cases.py``, (0.9, 1.0) and the red blood cell in a 4 µm capillary (0.61, 1.39),
Ca_B = 50, default options, one after the other after a warm-up solve (numba compiled). Printed
per case: wall time, BIE solves, modes of the fine level, V/U, Δp⁺R0/(ηU), γ_max. With
``--against REV`` the same cases run first at that git revision (a temporary worktree, the
same interpreter), then at this checkout, back to back, so that both see the same machine
(its speed drifts by up to 30 % over an hour). Not a test: about two minutes per revision.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CASES = [("0.8:1.0", {"nu": 0.8, "lam": 1.0}), ("0.7:1.2", {"nu": 0.7, "lam": 1.2}),
         ("0.6:1.5", {"nu": 0.6, "lam": 1.5}), ("0.7:1.5", {"nu": 0.7, "lam": 1.5}),
         ("0.9:r0.98", {"nu": 0.9, "lam_ratio": 0.98}),
         ("0.7:r0.95", {"nu": 0.7, "lam_ratio": 0.95}), ("0.6:1.94", {"nu": 0.6, "lam": 1.94}),
         ("0.9:1.0", {"nu": 0.9, "lam": 1.0}), ("rbc 0.61:1.39", {"nu": 0.61, "lam": 1.39})]


def run(label: str) -> None:
    """Solve and print every case with the ``bem`` importable in this process."""
    from bem.vesicle import solve_vesicle
    solve_vesicle(0.9, 1.0)                                # numba compiled, caches warm
    print(f"{'revision':>10} {'case':>14} {'s':>6} {'BIE':>5} {'modes':>5} {'V/U':>14} "
          f"{'dp+R0/(eta U)':>13} {'gamma_max':>10}", flush=True)
    for name, kw in CASES:
        t = time.perf_counter()
        r = solve_vesicle(**kw)
        print(f"{label:>10} {name:>14} {time.perf_counter() - t:6.1f} {r.bie_solves:5d} "
              f"{r.modes.size:5d} {r.V_over_U:14.10f} {r.dp_plus_R0:13.8g} {r.tension_max:10.8g}"
              + ("" if r.success else "  NOT CONVERGED"), flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", metavar="REV", help="git revision to time first, back to back")
    ap.add_argument("--label", default="this", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.against:
        with tempfile.TemporaryDirectory() as tmp:
            tree = Path(tmp) / "tree"
            subprocess.run(["git", "worktree", "add", "-q", "--detach", str(tree), args.against],
                           cwd=ROOT, check=True)
            try:
                env = {**os.environ, "PYTHONPATH": str(tree)}
                subprocess.run([sys.executable, __file__, "--label", args.against[:10]],
                               cwd=tree, env=env, check=True)
            finally:
                subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT,
                               check=False)
    run(args.label)
    return 0


if __name__ == "__main__":
    from bench_store import run_script

    run_script(main)
