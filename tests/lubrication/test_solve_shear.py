"""solve_lubrication with a red-cell membrane (ca_s, reference): the vesicle limit, the rate of
the high-velocity limit, the polar stretch, results, input checks and the self-intersection
check; slow: Secomb et al.'s red cell in a 5 µm tube."""

import csv
import math

import numpy as np
import pytest

from lubrication.checks import InvalidParameterError
from lubrication.membrane import reference_shape, tension_difference
from lubrication.solve import (
    CA_S_RANGE,
    CAP_RADIUS,
    _self_intersects,
    solve_lubrication,
)

# Today's vesicle results, recorded before the red-cell membrane was added to the solver
# (commit 548492c, this machine): (nu, lam/lam_c, ca_b) -> V/U, dp+ R0/(eta U),
# tension_front [eta U], ell [R], printed with repr by
#   res = solve_lubrication(nu, lam_ratio=r, **({} if ca_b is None else {"ca_b": ca_b}))
VESICLE = {
    (0.6, 0.95, None): (1.0503593010086476, 661.9145514374646, 237.31647275389875,
                        10.42769347524922),
    (0.9, 0.99, None): (1.0096450555579077, 668.5924242367599, 3163.9689390275785,
                        3.7220509556559502),
    (0.61, 0.97, 50.0): (1.0300990415886728, 1122.1893509336267, 541.0923434286693,
                         10.288797938177483),
    (0.9, 0.9, 10.0): (1.1004306872384044, 57.632527982309554, 74.92629807245015,
                       3.369353424503145),
}


@pytest.mark.parametrize("point", list(VESICLE), ids=lambda p: f"nu{p[0]}_r{p[1]}_caB{p[2]}")
@pytest.mark.parametrize("ca_s", [None, math.inf])
def test_infinite_ca_s_reproduces_the_vesicle(point, ca_s):
    """Gs = 0 (ca_s None or inf) gives today's vesicle numbers to <= 1e-10 (same code path)."""
    nu, ratio, ca_b = point
    res = solve_lubrication(nu, lam_ratio=ratio, ca_s=ca_s,
                            **({} if ca_b is None else {"ca_b": ca_b}))
    assert res.success, res.message
    got = (res.V_over_U, res.dp_plus_R0, res.tension_front, res.ell)
    np.testing.assert_allclose(got, VESICLE[point], rtol=1e-10, atol=0)
    assert res.reference is None and res.to_dict()["ca_s"] is None
    assert np.array_equal(res.tension_s, res.tension) and np.array_equal(res.tension_phi,
                                                                         res.tension)
    assert np.all(np.isnan(res.stretch_phi))


@pytest.fixture(scope="module")
def high_ca_family():
    """The cell's nu = 0.61 at lam/lam_c = 0.95, high-Ca: the vesicle and Ca_S = 10, 100, 1000."""
    vesicle = solve_lubrication(0.61, lam_ratio=0.95)
    cells = {c: solve_lubrication(0.61, lam_ratio=0.95, ca_s=c) for c in (10.0, 100.0, 1000.0)}
    return vesicle, cells


def test_high_velocity_limit_is_the_vesicle_at_first_order(high_ca_family):
    """Raising Ca_S = eta U/G_s (G_s -> 0) the red cell tends to the vesicle of the same nu,
    the departure falling like 1/Ca_S (first order in the elastic tensions): observed order
    1 +- 0.05 per decade in V/U and dp+."""
    vesicle, cells = high_ca_family
    assert vesicle.success and all(c.success for c in cells.values())
    ca = np.array(sorted(cells))
    for key in ("V_over_U", "dp_plus_R0"):
        dev = np.array([abs(getattr(cells[c], key) / getattr(vesicle, key) - 1) for c in ca])
        order = np.log(dev[:-1] / dev[1:]) / np.log(ca[1:] / ca[:-1])
        assert np.all(np.abs(order - 1) < 0.05), f"{key}: {dev=}, {order=}"
        assert dev[-1] < 1e-5


def test_principal_tensions_of_the_result(high_ca_family):
    """tension is the mean of tension_s and tension_phi; their difference is 2 G_s f(lam_phi)
    in eta U (G_s/(eta U) = 1/Ca_S), isotropic at the poles; the stretch is 1 at the poles."""
    _, cells = high_ca_family
    res = cells[10.0]
    np.testing.assert_allclose(0.5 * (res.tension_s + res.tension_phi), res.tension, rtol=1e-13)
    np.testing.assert_allclose(res.tension_s - res.tension_phi,
                               2 / 10.0 * tension_difference(res.stretch_phi), rtol=1e-9,
                               atol=1e-12)
    assert res.stretch_phi[0] == res.stretch_phi[-1] == 1.0
    assert res.ca_s == 10.0 and res.reference == "biconcave"
    assert res.to_dict()["reference"] == "biconcave"


def test_stretch_at_the_rims_follows_the_polar_expansion(high_ca_family):
    """Near a pole lam_phi^2 = 1 - (k^2 - k_ref^2) a/(4 pi) (lubrication.membrane, item 3): at the
    rim of the excised cap (r = CAP_RADIUS, a = pi eps^2 to leading order)
    1 - lam_phi = (k^2 - k_ref^2) eps^2/8, with k the cap curvature of the solution and k_ref the
    reference's pole curvature from r_ref^2 = a/pi - k_ref^2 a^2/(4 pi^2) + ..."""
    _, cells = high_ca_family
    res = cells[10.0]
    ref = reference_shape("biconcave", 0.61)
    area = 4 * math.pi * (res.lam * 0.61 ** (-1 / 3)) ** 2        # cell area in R^2
    unit = area / (4 * math.pi)
    k_ref_sq = -2 * math.pi**2 * float(ref.radius_sq.deriv(2)(0.0)) / unit
    for k, lam_phi in ((res.curvature_rear, res.stretch_phi[1]),
                       (res.curvature_front, res.stretch_phi[-2])):
        expected = (k * k - k_ref_sq) * CAP_RADIUS**2 / 8
        assert 1 - lam_phi == pytest.approx(expected, rel=0.02), (k, k_ref_sq)


def test_profiles_and_stem_of_a_red_cell(tmp_path, high_ca_family):
    """The CSV carries the principal tensions and the stretch; the file stem names Ca_S and the
    reference shape."""
    _, cells = high_ca_family
    res = cells[100.0]
    json_path, csv_path = res.save(tmp_path)
    assert json_path.name.endswith("_high-Ca_caS100_biconcave.json")
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(res.s)
    assert {"tension_s", "tension_phi", "stretch_phi"} <= set(rows[0])
    assert float(rows[0]["stretch_phi"]) == 1.0


@pytest.mark.parametrize("kwargs, name", [
    ({"ca_s": 0.0}, "ca_s"), ({"ca_s": math.nan}, "ca_s"), ({"ca_s": -1.0}, "ca_s"),
    ({"ca_s": CA_S_RANGE[1] * 10}, "ca_s"), ({"ca_s": 1.0, "reference": "disc"}, "reference"),
    ({"reference": "disc"}, "reference")])
def test_bad_membrane_inputs_are_named(kwargs, name):
    with pytest.raises(InvalidParameterError, match=f"^{name}="):
        solve_lubrication(0.61, lam_ratio=0.95, **kwargs)


def test_reference_outside_its_family_is_refused_before_any_work():
    """nu = 0.8 has no biconcave reference (the family ends at 0.743): an error naming nu and
    pointing to the spheroid; a vesicle at that nu ignores the reference."""
    with pytest.raises(InvalidParameterError, match=r"^nu=0.8 .*0.45 <= nu <= 0.743.*spheroid"):
        solve_lubrication(0.8, lam_ratio=0.99, ca_s=1.0)
    assert solve_lubrication(0.8, lam_ratio=0.99, ca_s=None).success


# --------------------------------------------------------------------------- Secomb et al. 1986
@pytest.mark.slow
def test_red_cell_in_a_5_micron_tube_secomb_trends():
    """Default red cell, d = 5 µm, G_s = 6 µN/m, kappa = 1.8e-19 J, eta = 1.2 mPa s, by the path
    of tests/benchmarks/rbc_shear_lubrication.py (0.4 mm/s, then continuation in U). Secomb et
    al. 1986: as the velocity falls the apparent viscosity (dp+) rises and the tension at the
    rear grows against the nose's; measured (docs/data/rbc_shear_lubrication.json): dp+ R0/(eta U)
    36.3, 25.9, 19.8 and rear/nose 0.36, 0.25, 0.175 at 0.2, 0.4, 1 mm/s. The hoop tension turns
    compressive at the rear rim (elastic: the disc's rim is squeezed into the tube)."""
    from benchmarks import rbc_shear_lubrication as bench  # lazy: imports correlations
    start, why = bench.start_in_tube(max_time=600)
    assert start.success, why
    solved = {bench.START_MM_S: start}
    for targets in ((1.0,), (0.2,)):
        reached, why = bench.continue_in_velocity((bench.START_MM_S, start), targets, 600)
        assert not why, why
        solved.update({u: r for u, (r, _, _) in reached.items()})
    low, mid, high = (solved[u] for u in (0.2, bench.START_MM_S, 1.0))
    assert low.dp_plus_R0 > mid.dp_plus_R0 > high.dp_plus_R0
    ratios = [r.tension_rear / r.tension_front for r in (low, mid, high)]
    assert ratios[0] > ratios[1] > ratios[2] and ratios[2] < 0.2, ratios
    assert high.dp_plus_R0 == pytest.approx(19.82, rel=0.01)
    assert high.V_over_U == pytest.approx(1.1845, rel=1e-3)
    assert min(float(np.min(r.tension_phi)) for r in (low, mid, high)) < 0


def test_self_intersection_of_a_meridian():
    """A meridian with a loop at its rim crosses itself; a half circle and a curve that comes
    within 1e-6 of itself without crossing do not."""
    theta = np.linspace(0, np.pi, 400)
    circle_x, circle_r = 1 - np.cos(theta), np.sin(theta)
    assert not _self_intersects(circle_x, circle_r)
    t = np.linspace(-np.pi, np.pi, 400)                 # prolate cycloid: one loop at t = 0
    assert _self_intersects(t - 2 * np.sin(t), 2 - 1.5 * np.cos(t))
    assert not _self_intersects(t - 0.5 * np.sin(t), 2 - 0.5 * np.cos(t))     # no loop
    near_x = np.array([0.0, 1.0, 1.0, 0.0])
    near_r = np.array([0.0, 0.0, 1e-6, 1e-6])
    assert not _self_intersects(near_x, near_r)
