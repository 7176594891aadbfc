"""The fast part of the domain benchmark (tests/benchmarks/vesicle_domain.py): the default solve
converges at the benchmark's first random points, at a loose tolerance."""

from __future__ import annotations

import pytest

from benchmarks.vesicle_domain import DEFAULT_SEED, draw, solve_point, summarise

#: The first points of the benchmark's fixed draw; tolerances loose enough for ~2 s a point.
POINTS = draw(8, DEFAULT_SEED)
LOOSE = {"tol": 1e-2, "tension_tol": 0.1}


@pytest.mark.slow
@pytest.mark.ci             # ~25 s on 2 cores: the pipeline over the domain in the default suite
def test_default_solve_converges_at_random_points_of_the_domain():
    rows = [solve_point(*p, **LOOSE) for p in POINTS]
    summary = summarise(rows)
    assert summary["converged"] == 1.0, summary["failures"]
    for row in rows:
        # every converged point is on the map's scale: V/U within the map's bar, or within
        # 0.3 % where the map's cell mixes shape classes and so has no bar to offer
        m, d = row["map"]["V_over_U"], row["direct"]["V_over_U"]
        if m["value"] is not None:
            assert abs(m["value"] - d) <= max(m["error"] or 0.0, 3e-3 * d), row
