"""Make the cached vesicle solves of tests/bem/test_vesicle_sweep.py (about 25 s on 2 cores).

A real two-point sweep, nu = 0.98, lam = 0.3 then 0.4 (the second continued from the first),
Ca_B = 50, 16 modes (refinement pair 11/16), tol = 1e-2, residual_tol = 1e-3: cheap and
converged. Each point is stored as ``VesicleResult.save`` writes it (JSON + CSV profiles); the
test rebuilds the VesicleResult from the two files and its fake solver returns copies of it, so
the sweep tests run in seconds.

Run from the repository root: ``.venv/bin/python tests/bem/data/make_vesicle_sweep_fixture.py``
"""

from __future__ import annotations

import logging
from pathlib import Path

from bem.sweep import sweep_vesicle

HERE = Path(__file__).resolve().parent
NU, LAMS, CA_B = 0.98, (0.3, 0.4), 50.0
SOLVER = {"n_modes": 16, "tol": 1e-2, "residual_tol": 1e-3}


def main() -> None:
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    for res in sweep_vesicle(NU, LAMS, ca_b=CA_B, **SOLVER):
        assert res.success, res.message
        res.save(HERE, f"vesicle_nu{NU:g}_lam{res.lam:g}")


if __name__ == "__main__":
    main()
