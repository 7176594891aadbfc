"""Steady vesicle in a tube (BEM): limits, conservation, convergence, lubrication, bad input.

Units: R = 1, U the mean velocity, lam = R0/R, Ca_B = eta U R0^2/kappa (50 unless stated),
tension in eta U. Measured numbers in the comments come from this solver (16-point panels).
"""

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from bem.results import VESICLE_PROFILE_COLUMNS, VesicleResult
from bem.vesicle import solve_vesicle
from bem.vesicle.operator import _tension_max
from correlations.cli import main
from lubrication.checks import CannotPassError, InvalidParameterError
from lubrication.geometry import critical_confinement
from lubrication.results import Status

pytestmark = pytest.mark.numerics   # re-run on another code path by make test-portable

# (0.9, 1.0), Ca_B = 50: levels 16/24/32 modes (measured)
#   residual 5.0e-3, 3.3e-4, 2.3e-5   (/~14 per +8 modes, spectral)
#   V/U      1.2573307, 1.2574625, 1.2574636
#   dp+R0/(eta U) 13.716093, 13.716093, 13.716092
REF_09_10 = {"V_over_U": 1.2574636, "dp_plus_R0": 13.716092}


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize("kwargs, exc", [
    ({"nu": 1.0, "lam": 0.5}, InvalidParameterError),
    ({"nu": 0.0, "lam": 0.5}, InvalidParameterError),
    ({"nu": math.nan, "lam": 0.5}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.4}, CannotPassError),                     # lam_c(0.9) = 1.3239
    ({"nu": 0.9, "lam_ratio": 1.0}, CannotPassError),
    ({"nu": 0.9}, InvalidParameterError),                           # neither lam nor ratio
    ({"nu": 0.9, "lam": 1.0, "lam_ratio": 0.5}, InvalidParameterError),
    ({"nu": 0.9, "lam": -1.0}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "ca_b": 0.0}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "ca_b": math.inf}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "n_modes": 3}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "n_modes": 10**21}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "max_modes": 161}, InvalidParameterError),
    ({"nu": 0.98, "lam": 0.3, "max_modes": 12}, InvalidParameterError),  # no refinement pair
    ({"nu": 0.9, "lam": 1.0, "ca_b": 1e308}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "ca_b": 1e-300}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "tol": math.nan}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "max_time": 0.0}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "initial": "sphere"}, InvalidParameterError),
    ({"nu": 0.9, "lam": 1.0, "density": "gap"}, InvalidParameterError),
])
def test_bad_input_is_rejected_before_any_work(kwargs, exc):
    with pytest.raises(exc):
        solve_vesicle(**kwargs)


def test_mode_convergence_rejects_bad_input():
    from benchmarks.vesicle_modes import mode_convergence
    shaped = VesicleResult(nu=0.9, lam=1.0, lam_c=critical_confinement(0.9), ca_b=50.0,
                           status=Status.CONVERGED, modes=np.zeros(8))
    with pytest.raises(InvalidParameterError, match="result"):
        mode_convergence("not a result", (16,))
    with pytest.raises(InvalidParameterError, match="result"):
        mode_convergence(replace(shaped, modes=np.empty(0)), (16,))
    with pytest.raises(InvalidParameterError, match="modes"):
        mode_convergence(shaped, (4,))
    with pytest.raises(InvalidParameterError, match="modes"):
        mode_convergence(shaped, ())
    with pytest.raises(InvalidParameterError, match="density"):
        mode_convergence(shaped, (16,), density="gap")


def test_cli_bad_input_exits_2(capsys):
    try:
        code = main(["bem", "vesicle", "--nu", "0.9", "--lam", "1.4", "--json"])
    except SystemExit as e:
        code = e.code
    _, err = capsys.readouterr()
    assert code == 2 and "lam_c" in err and len(err.strip().splitlines()) == 1


# ------------------------------------------------------------------ a cheap solve (fast)
@pytest.fixture(scope="module")
def coarse():
    """(0.9, 1.0) with the pair 11/16 modes (~15 s; the pair differs by 1.5 % in dp+)."""
    return solve_vesicle(0.9, 1.0, n_modes=16, tol=5e-2, residual_tol=1e-2)


def test_coarse_solution_conserves_volume_and_area_and_is_near_the_reference(coarse):
    res = coarse
    assert res.success, res.message
    assert res.volume_error <= 1e-8 and res.area_error <= 1e-8
    assert res.residual < 1e-2
    # the 16-mode error against the 32-mode values: measured V/U +1.78e-5, dp+ -4.05e-5
    # relative (the pair estimate, 5e-5 and 1.1e-3, is pessimistic); bounds 2x these at this
    # coarse default resolution, the slow test_residual_falls_spectrally_... holds 2e-6
    assert res.V_over_U == pytest.approx(REF_09_10["V_over_U"], rel=4e-5)
    assert res.dp_plus_R0 == pytest.approx(REF_09_10["dp_plus_R0"], rel=8e-5)
    assert res.shape_class == "bullet" and res.curvature_front < 0
    assert 0 < res.film_min < 1 - 1.0 / critical_confinement(0.9) + 0.5
    # the membrane is at rest in its frame, so the tension rises toward the front on average
    assert res.tension_front > res.tension_rear
    # the shear stress is -dgamma/ds: its integral over s is the tension drop
    drop = -np.trapezoid(res.shear_membrane, res.s)
    assert drop == pytest.approx(res.tension_front - res.tension_rear, rel=1e-3)


def test_wall_shear_balances_the_extra_pressure_drop(coarse, report):
    """Force balance on the fluid in the tube: the extra wall shear integrates to the extra
    pressure force, int (tau_w - 4) 2 pi R dx = pi R^2 dp+ (dp+ here from the reciprocal
    theorem on the membrane load, an independent route). Measured at (0.9, 1.0), 16 modes:
    ratio 1 - 4e-13; tau_w peaks at 7.32 eta U/R beside the vesicle (Poiseuille: 4; the film
    h = 0.183 sheared at V/h = 6.87)."""
    from bem.vesicle_dynamics import vesicle_operator
    op = vesicle_operator(coarse)
    x, tw = op.wall_shear(coarse.curve(), coarse.tension_modes)
    extra = np.sum((tw - 4.0) * 2 * math.pi * op.wall.w.ravel())
    report.value("ves.wall_shear_balance", abs(extra / (math.pi * coarse.dp_plus_R) - 1),
                 reference=0.0, tol="1e-8 rel", source="reciprocal-theorem dp+ (force balance)")
    report.value("ves.wall_shear_max", coarse.wall_shear_max, reference="4 < τ < 4 + 2V/h",
                 tol="inside", source="Poiseuille wall shear 4 and the film's shear bound")
    assert extra == pytest.approx(math.pi * coarse.dp_plus_R, rel=1e-8)
    assert coarse.wall_shear_max == pytest.approx(np.max(tw), rel=1e-3)   # other wall mesh
    assert 4.0 < coarse.wall_shear_max < 4.0 + 2 * coarse.V_over_U / coarse.film_min
    assert abs(tw[0] - 4.0) < 1e-6 and abs(tw[-1] - 4.0) < 1e-6      # Poiseuille far away
    peak = coarse.wall_x[np.argmax(coarse.wall_shear)]
    assert 0.0 < peak < coarse.ell                                    # beside the vesicle


def test_vesicle_wall_mesh_is_converged(coarse, report):
    """The vesicle's wall mesh (WALL_REFINEMENT = 0.25 of the drop's rule) against the drop's
    own 4x finer wall at the same shape: V/U and dp+ agree to 1e-7 relative (measured 2e-11;
    1e-7 also at nu = 0.6, lam/lam_c = 0.98, see docs/validation.md)."""
    from bem.vesicle import WALL_REFINEMENT, VesicleOperator
    from bem.vesicle_dynamics import vesicle_operator
    op = vesicle_operator(coarse)
    assert op.disc.wall_refinement == WALL_REFINEMENT
    fine = VesicleOperator(coarse.nu, coarse.lam, coarse.ca_b,
                           replace(op.disc, wall_refinement=1.0), coarse.curve(), op.n_tension)
    assert fine.wall.x.size > 2 * op.wall.x.size
    a, b = (o.evaluate(coarse.curve()) for o in (op, fine))
    report.value("ves.wall_mesh", max(abs(b["V"] / a["V"] - 1), abs(b["dp"] / a["dp"] - 1)),
                 reference=0.0, tol="1e-7 rel", source="the drop's 4x finer wall")
    assert b["V"] == pytest.approx(a["V"], rel=1e-7)
    assert b["dp"] == pytest.approx(a["dp"], rel=1e-7)


def _stored_long_shape() -> VesicleResult:
    """The stored default 64-mode shape at (0.6, 1.94) (lam/lam_c = 0.979, extent 10.8 R)."""
    data = json.loads((Path(__file__).parent / "data" /
                       "vesicle_nu0.6_lam1.94_64modes.json").read_text())
    return VesicleResult(nu=data["nu"], lam=data["lam"], lam_c=data["lam_c"],
                         ca_b=data["ca_b"], status=Status.NOT_CONVERGED,
                         message="stored default shape",
                         modes=np.array(data["modes"]), density=np.array(data["density"]))


def test_long_vesicle_wall_beside_the_body_is_converged(report):
    """A long vesicle's wall panels beside the body are lengthened by WALL_BODY_LENGTH/extent
    (the drop's rule follows the membrane's panel count, which grows with the vesicle's
    length) and follow at most WALL_BODY_PANELS membrane panels. At the stored 64-mode shape
    of (0.6, 1.94), extent 10.8 R, against the drop's rule (2.3 times the wall nodes): V/U and
    dp+ agree to 1e-7 relative (measured 1.1e-8 and 1.4e-8; the length rule alone 3.7e-9; with
    WALL_BODY_LENGTH 5 R, 2e-9 at 88 modes and 4.5e-8 at 48), the tension maximum to 1e-6
    (1.0e-8), the residual (a maximum over the nodes, 2.7e-3 here) to 1e-7 absolute (3.4e-8),
    and the wall shear at the ends of the meshed tube to 1e-6 (8e-8; both within 1e-4 of
    Poiseuille, 4)."""
    from bem.vesicle import VesicleOperator, vesicle_discretisation
    from bem.vesicle.operator import WALL_BODY_LENGTH
    seed = _stored_long_shape()
    curve = seed.curve()
    xr, xf = curve.extent()
    assert xf - xr > 1.5 * WALL_BODY_LENGTH
    disc = vesicle_discretisation(curve.n_modes)
    ops = [VesicleOperator(seed.nu, seed.lam, seed.ca_b, d, curve, curve.n_modes)
           for d in (disc, replace(disc, wall_body_length=None, wall_body_panels=None))]
    assert ops[0].wall.x.size < 0.5 * ops[1].wall.x.size
    states = [o.evaluate(curve) for o in ops]
    a, b = states
    rel = max(abs(b["V"] / a["V"] - 1), abs(b["dp"] / a["dp"] - 1))
    report.value("ves.long_wall_mesh", rel, reference=0.0, tol="1e-7 rel",
                 source="the drop's wall rule beside the body (2.3x the nodes)")
    assert rel < 1e-7
    assert abs(a["residual"] - b["residual"]) < 1e-7
    tmax = [_tension_max(curve, st["g"]) for st in states]
    assert tmax[0] == pytest.approx(tmax[1], rel=1e-6)
    ends = [o.wall_shear(curve, st["g"])[1][[0, -1]] for o, st in zip(ops, states)]
    assert np.allclose(ends[0], ends[1], rtol=0.0, atol=1e-6), ends
    assert np.all(np.abs(ends[0] - 4.0) < 1e-4), ends


def test_result_dict_and_atomic_save(coarse, tmp_path):
    d = coarse.to_dict()
    for key in ("nu", "lam", "lam_c", "V_over_U", "dp_plus_R0", "ell", "film_min",
                "tension_max", "shape_class", "converged", "volume_error", "area_error"):
        assert key in d, key
    json.dumps(d, allow_nan=False)
    jp, cp = coarse.save(tmp_path)
    saved = json.loads(jp.read_text())
    assert saved["V_over_U"] == coarse.V_over_U
    assert cp.read_text().startswith(",".join(n for n, _ in VESICLE_PROFILE_COLUMNS))
    assert not list(tmp_path.glob(".*tmp"))                    # no temporary file left
    assert isinstance(coarse, VesicleResult)
    assert abs(coarse.curve().volume() / (4 / 3 * math.pi) - 1) < 1e-12


@pytest.mark.slow          # ~17 s
def test_warm_start_from_a_result_reaches_the_same_state(coarse):
    """Started from a converged result, the solve rebuilds its density on that BEM shape (a
    different discretisation of the same state): the two answers agree within the sum of their
    own (absolute) error estimates (measured: V/U 3.1e-5 apart, estimates 6.6e-5 and 1.3e-4)."""
    res = solve_vesicle(0.9, 1.0, n_modes=16, tol=5e-2, residual_tol=1e-2, initial=coarse)
    assert res.success and res.seed == "initial"
    for q in ("V_over_U", "dp_plus_R0"):
        bound = res.error_estimate[q] + coarse.error_estimate[q]
        assert abs(getattr(res, q) - getattr(coarse, q)) <= bound, q


# ------------------------------------------------------------------ seeds and continuation
@pytest.mark.parametrize("nu, lam", [(0.6, 1.78), (0.6, 1.94), (0.9, 1.0), (0.98, 0.3)])
def test_capsule_seed_has_the_critical_cubics_radius(nu, lam):
    """Capsule of the vesicle's area and volume: its radius is lam/lam_c(nu) (the larger root of
    the critical cubic with a in place of R), so it fits whenever the vesicle passes. The
    spectral fit overshoots the radius at the cap/cylinder junctions (curvature jumps), by
    O(N^-2): measured at (0.6, 1.94) +6.6e-3, +7.9e-4 with 16, 48 modes. Volume exact, area
    within 1e-4 (the area is imposed exactly by the solver's parametrisation anyway)."""
    from bem.vesicle import capsule_seed
    a = lam / critical_confinement(nu)
    err = [capsule_seed(nu, lam, n).max_radius() - a for n in (16, 48)]
    assert 0 <= err[0] < 1e-2 and abs(err[1]) < abs(err[0]) / 5
    c = capsule_seed(nu, lam, 16)
    assert c.volume() == pytest.approx(4 / 3 * math.pi * lam**3, rel=1e-12)
    assert c.area() == pytest.approx(4 * math.pi * (lam * nu ** (-1 / 3)) ** 2, rel=1e-4)


def test_lubrication_seed_of_a_parachute_is_kept_with_the_bend_density():
    """nu = 0.6, lam = 1.78 (deep parachute, gap 0.0694): the 16-mode uniform fit closes the
    film to 0.021 and is rejected (the capsule fallback then converges to a spurious symmetric
    state, residual 1.5e-2 at every level); the 16-mode "bend" fit keeps the gap (0.0699)."""
    from bem.vesicle import lubrication_seed
    uniform, lub = lubrication_seed(0.6, 1.78, 50.0, 16)
    bend, _ = lubrication_seed(0.6, 1.78, 50.0, 16, "bend")
    gap = 1 - max(lub.r)
    assert uniform is None and bend is not None
    assert 1 - bend.max_radius() == pytest.approx(gap, rel=0.05)


def test_continuation_rungs_halve_the_distance_to_lam_c():
    from bem.vesicle import NEAR_CRITICAL
    from bem.vesicle.ladder import _rungs
    assert NEAR_CRITICAL == 0.9
    assert _rungs(0.9) == [] and _rungs(0.95) == [0.9]
    assert _rungs(0.98) == [0.9, 0.95, 0.975]
    assert _rungs(0.99) == [0.9, 0.95, 0.975, 0.9875]


def test_self_intersection_and_wall_contact_are_detected():
    """The checks behind "the membrane self-intersects" and "touching the wall (closing
    film)": a figure-eight meridian crosses itself, a half circle does not; a membrane of
    radius R is rejected before any BEM work."""
    from bem.drop import DropDiscretisation
    from bem.shape import SpectralCurve
    from bem.vesicle import VesicleOperator
    from bem.vesicle.operator import self_intersects
    th = np.linspace(0.0, math.pi, 201)
    assert not self_intersects(-np.cos(th), np.sin(th))
    # up the diagonal from the rear pole (-1, 0) to (1, 0.5), back along r = 0.2 to x = -0.5,
    # down to the axis: the return leg crosses the diagonal at x = -0.2
    x = np.concatenate([np.linspace(-1, 1, 50), np.linspace(1, -0.5, 50), [-0.5]])
    r = np.concatenate([np.linspace(0, 0.5, 50), np.full(50, 0.2), [0.0]])
    assert self_intersects(x, r)
    touching = SpectralCurve.sphere(1.0, 8)
    op = VesicleOperator(0.99, 1.0, 50.0, DropDiscretisation(n_modes=8, n_panels=8), touching)
    with pytest.raises(InvalidParameterError, match="touching the wall"):
        op.evaluate(touching)


# ------------------------------------------------------------------ validation (slow)
@pytest.mark.slow
def test_small_vesicle_moves_like_a_sphere(report):
    """nu = 0.98, lam = 0.3: V/U near 2 - (4/3) lam^2 (1 %), dp+R0 near 16 lam^6 (few %).
    Measured: V/U = 1.881379 (+0.07 %), dp+R0/(eta U) = 0.0117214 (+0.5 %), residual 6e-8."""
    lam = 0.3
    res = solve_vesicle(0.98, lam)
    assert res.success, res.message
    report.value("ves.small_V", res.V_over_U, reference=2 - 4 / 3 * lam**2, tol="1 %",
                 source="rigid sphere, Faxén: 2 - (4/3) lam^2")
    report.value("ves.small_dp", res.dp_plus_R0, reference=16 * lam**6, tol="3 %",
                 source="Chen et al. eq. small2: 16 lam^6")
    assert res.V_over_U == pytest.approx(2 - 4 / 3 * lam**2, rel=0.01)
    assert res.dp_plus_R0 == pytest.approx(16 * lam**6, rel=0.03)
    assert res.volume_error <= 1e-8 and res.area_error <= 1e-8


@pytest.mark.slow          # ~30 s; in make validation (CI's ci subset covers lubrication and drop)
def test_residual_falls_spectrally_with_the_modes_at_nu09_lam1(report):
    """Residual floor of the least squares against the number of modes N (16, 24, 32): it
    must fall geometrically (measured: /15 and /14 per +8 modes); V/U and dp+ converge."""
    res = solve_vesicle(0.9, 1.0, tol=1e-12, max_modes=32)
    n, resid, V, dp, _gmax = (np.array(c) for c in zip(*res.refinement))
    assert list(n) == [16, 24, 32]
    factor = resid[:-1] / resid[1:]
    for k, (ni, r, v, d) in enumerate(zip(n, resid, V, dp)):
        report.value(f"ves.spectral_residual_{ni}", r, source="max|u - V e_x|, (0.9, 1.0)")
        report.value(f"ves.spectral_V_{ni}", v, source="(0.9, 1.0)")
        report.value(f"ves.spectral_dp_{ni}", d, source="(0.9, 1.0)")
    for k, f in enumerate(factor):
        report.value(f"ves.spectral_factor_{k}", f, reference="geometric", tol="> 8",
                     source="residual per +8 modes")
    report.value("ves.spectral_V_ref", V[-1], reference=REF_09_10["V_over_U"], tol="±2e-6",
                 kind="regression", source="REF_09_10")
    report.value("ves.spectral_dp_ref", dp[-1], reference=REF_09_10["dp_plus_R0"], tol="1e-6 rel",
                 kind="regression", source="REF_09_10")
    assert np.all(factor > 8), f"{resid=}, {factor=}"
    assert resid[-1] < 1e-4
    assert res.volume_error <= 1e-8 and res.area_error <= 1e-8
    assert abs(V[-1] - V[-2]) < 1e-5 and abs(dp[-1] - dp[-2]) < 1e-4 * dp[-1]
    assert V[-1] == pytest.approx(REF_09_10["V_over_U"], abs=2e-6)
    assert dp[-1] == pytest.approx(REF_09_10["dp_plus_R0"], rel=1e-6)


def test_cli_reports_an_unconverged_run_with_exit_1(capsys, tmp_path):
    """8 modes cannot reach the default residual tolerance 1e-4 at (0.9, 1.0): exit 1, the
    JSON is still printed with "converged": false and the contract's keys, files are saved."""
    try:
        code = main(["bem", "vesicle", "--nu", "0.9", "--lam", "1.0", "--modes", "8", "--json",
                     "--out", str(tmp_path)])
    except SystemExit as e:
        code = e.code
    out, _ = capsys.readouterr()
    obj = json.loads(out)
    assert code == 1 and obj["converged"] is False and obj["status"] == "not converged"
    assert "residual" in obj["message"]                  # names the tolerance not met
    for key in ("nu", "lam", "lam_c", "V_over_U", "dp_plus_R0", "ell", "film_min",
                "tension_max", "shape_class", "converged", "volume_error", "area_error"):
        assert key in obj, key
    for key in ("V_over_U", "dp_plus_R0", "ell", "film_min", "tension_max", "shape_class"):
        assert obj[key] is None, key                      # no numbers from a failed solve
    assert len(list(tmp_path.glob("*.json"))) == 1 and len(list(tmp_path.glob("*.csv"))) == 1
    saved = json.loads(next(tmp_path.glob("*.json")).read_text())
    assert saved["V_over_U"] is None and saved["converged"] is False


@pytest.mark.slow          # ~35 s
def test_parachute_bullet_transition_at_nu_0p9_near_chen_line(report):
    """The rear curvature changes sign (concave rear: parachute) at lam_T; Chen et al. 2020
    eq. transition gives lam_T(0.9) = 0.779. Measured with 32 modes (residual 2e-5): rear
    curvature +0.0015 at lam = 0.80, -0.092 at 0.82, so lam_T = 0.800 (+2.7 %); asserted within
    5 % (the line is a linear fit through Chen's transition points)."""
    from correlations.shape import transition_confinement_chen2020
    a = solve_vesicle(0.9, 0.78, n_modes=32, tol=1e-2, residual_tol=1e-3)
    b = solve_vesicle(0.9, 0.82, n_modes=32, tol=1e-2, residual_tol=1e-3, initial=a)
    assert a.success and b.success, (a.message, b.message)
    assert a.shape_class == "parachute" and b.shape_class == "bullet"
    ka, kb = a.curvature_rear, b.curvature_rear
    lam_t = a.lam + (b.lam - a.lam) * ka / (ka - kb)
    report.value("ves.lam_T_0.9", lam_t, reference=transition_confinement_chen2020(0.9),
                 tol="5 %", source="Chen et al. 2020 eq. transition")
    assert lam_t == pytest.approx(transition_confinement_chen2020(0.9), rel=0.05)


@pytest.mark.slow
@pytest.mark.ci            # ~1 min: the long-vesicle route (bend density, lubrication seed) in CI
def test_parachute_bullet_transition_at_nu_0p7_near_chen_line(report):
    """nu = 0.7 (long: l_c lam/lam_c ~ 6.4): parachute at lam = 1.46 (rear curvature +0.1315),
    bullet at 1.48 (-0.1158), 32 modes each (residual 4.3e-4, 2.5e-4), so lam_T = 1.4706
    against Chen et al. 2020 eq. transition 1.469 (+0.1 %), measured with the earlier 8-mode
    ladder (the carrier ladder now ends at 40 modes). Asserted within 5 %, as at nu = 0.9."""
    from correlations.shape import transition_confinement_chen2020
    a = solve_vesicle(0.7, 1.46, tol=1e-2, residual_tol=5e-3, seed_bank=False)
    b = solve_vesicle(0.7, 1.48, tol=1e-2, residual_tol=5e-3, seed_bank=False)
    assert a.success and b.success, (a.message, b.message)
    assert a.seed == b.seed == "lubrication"
    assert a.shape_class == "parachute" and b.shape_class == "bullet"
    ka, kb = a.curvature_rear, b.curvature_rear
    lam_t = a.lam + (b.lam - a.lam) * ka / (ka - kb)
    report.value("ves.lam_T_0.7", lam_t, reference=transition_confinement_chen2020(0.7),
                 tol="5 %", source="Chen et al. 2020 eq. transition")
    assert lam_t == pytest.approx(transition_confinement_chen2020(0.7), rel=0.05)


@pytest.mark.slow          # ~8 min (two long vesicles, 16..56 modes each)
def test_parachute_bullet_transition_at_nu_0p6_near_chen_line(report):
    """nu = 0.6 (long vesicles, "bend" density, started from lubrication): parachute at
    lam = 1.78 (rear curvature +0.762, gap 6.96 % of R), bullet at 1.84 (-0.511, 5.53 %), so
    lam_T = 1.816 against Chen et al. 2020 eq. transition 1.814 (+0.1 %; their text: ~1.8, gap
    ~7 %; a third solve at 1.81, rear curvature +0.043, narrows it to 1.812). Asserted within
    5 %, as at nu = 0.9; the gap at lam_T between 5 and 7 % of R."""
    from correlations.shape import transition_confinement_chen2020
    # 56 and 64 modes (carrier ladder; with the earlier 8-mode ladder both stopped at 56)
    a = solve_vesicle(0.6, 1.78, tol=2e-2, residual_tol=5e-3)
    b = solve_vesicle(0.6, 1.84, tol=1e-2, residual_tol=5e-3)
    assert a.success and b.success, (a.message, b.message)
    assert a.shape_class == "parachute" and b.shape_class == "bullet"
    ka, kb = a.curvature_rear, b.curvature_rear
    w = ka / (ka - kb)
    lam_t = a.lam + (b.lam - a.lam) * w
    report.value("ves.lam_T_0.6", lam_t, reference=transition_confinement_chen2020(0.6),
                 tol="5 %", source="Chen et al. 2020 eq. transition")
    gap = report.value("ves.gap_at_lam_T_0.6", a.film_min + (b.film_min - a.film_min) * w,
                       reference=0.07, tol="inside (0.05, 0.07)",
                       source="Chen et al. 2020: ≈ 7 %")
    assert lam_t == pytest.approx(transition_confinement_chen2020(0.6), rel=0.05)
    assert 0.05 < gap < 0.07


@pytest.mark.slow          # ~7 min
def test_near_critical_discrepancy_with_lubrication_shrinks(report):
    """nu = 0.9, Ca_B = 50: lam/lam_c = 0.95 (automatic continuation from lubrication at 0.9)
    then 0.97 continued from it, 48 modes, against solve_lubrication at the same Ca_B.
    Measured: V/U 1.048257 / 1.028833 (lubrication 1.048661 / 1.028948: -0.039 %, -0.011 %);
    dp+R0 146.2 / 245.8 (136.9 / 234.9: +6.8 %, +4.65 %); residual 3.2e-4 / 1.2e-3;
    l/l_c = 0.9478 / 0.9690 (Chen et al. eq. sL: lam/lam_c)."""
    from lubrication.geometry import critical_length
    from lubrication.solve import solve_lubrication
    kw = {"max_modes": 48, "tol": 5e-3, "residual_tol": 2e-3}
    a = solve_vesicle(0.9, lam_ratio=0.95, **kw)
    b = solve_vesicle(0.9, lam_ratio=0.97, initial=a, **kw)
    err = []
    for res, ratio in ((a, 0.95), (b, 0.97)):
        assert res.success, res.message
        assert res.volume_error <= 1e-8 and res.area_error <= 1e-8
        lub = solve_lubrication(0.9, lam_ratio=ratio, ca_b=50.0)
        report.value(f"ves.nc_V_{ratio}", res.V_over_U, reference=lub.V_over_U, tol="1e-3 rel",
                     source="lubrication solver, same Ca_B")
        report.value(f"ves.nc_ell_ratio_{ratio}", res.ell / critical_length(0.9),
                     reference=ratio, tol="5e-3 rel", source="Chen et al. eq. sL: lam/lam_c")
        report.value(f"ves.nc_dp_{ratio}", res.dp_plus_R0, reference=lub.dp_plus_R0,
                     tol="0 < gap, shrinking, < 10 %", source="lubrication solver, same Ca_B")
        assert res.V_over_U == pytest.approx(lub.V_over_U, rel=1e-3)
        assert res.ell / critical_length(0.9) == pytest.approx(ratio, rel=5e-3)
        assert 0 < res.film_min < 1 - ratio
        err.append(res.dp_plus_R0 / lub.dp_plus_R0 - 1)
    assert 0 < err[1] < err[0] < 0.1, err          # lubrication is the limit: the gap closes


@pytest.mark.slow          # ~6 min (three 64-80-mode minima)
def test_mode_convergence_is_geometric_at_nu_0p6_lam_1p94(report):
    """(0.6, 1.94), lam/lam_c = 0.979, Ca_B = 50: with the density built once on the
    default 64-mode BEM shape (stored) the levels 64, 72, 80 converge geometrically. Measured
    (docs/validation.md): V/U 1.0209209, 1.0208119, 1.0207880 (ratio of successive
    differences 0.22), gamma_max 999.60, 1007.30, 1009.85 (0.33), dp+R0 1778.211, 1778.395,
    1778.364 (0.17), residual 7.7e-4, 3.9e-4, 1.9e-4. Asserted: contraction below 0.5 per +8
    modes in V/U and gamma_max, a residual that falls by > 1.5x per level, dp+ settled to 1e-4."""
    from benchmarks.vesicle_modes import mode_convergence

    rows = mode_convergence(_stored_long_shape(), (64, 72, 80))
    for r in rows:
        for key in ("V_over_U", "dp_plus_R0", "tension_max", "residual"):
            report.value(f"ves.modes_{key}_{r['modes']}", r[key], kind="regression",
                         source="mode_convergence on the stored 64-mode shape")
    for key in ("V_over_U", "tension_max"):
        report.value(f"ves.modes_ratio_{key}", rows[-1][f"ratio_{key}"], reference=0.5,
                     tol="< 0.5", source="geometric convergence")
    report.value("ves.modes_dp_settled",
                 abs(rows[-1]["dp_plus_R0"] / rows[1]["dp_plus_R0"] - 1), reference=0.0,
                 tol="1e-4 rel", source="72 vs 80 modes")
    assert all(r["success"] for r in rows), [r["message"] for r in rows]
    last = rows[-1]
    assert last["ratio_V_over_U"] < 0.5 and last["ratio_tension_max"] < 0.5, last
    assert rows[1]["residual"] < rows[0]["residual"] / 1.5
    assert rows[2]["residual"] < rows[1]["residual"] / 1.5
    assert abs(last["dp_plus_R0"] - rows[1]["dp_plus_R0"]) < 1e-4 * last["dp_plus_R0"]


#: mode-converged values at (0.6, 1.94), Ca_B = 50 (test_mode_convergence_is_geometric_...,
#: docs/validation.md): the 80-mode level on the density built on the stored BEM shape plus
#: the tail of its geometric contraction (V/U 0.22, dp+ 0.17, gamma_max 0.33 per +8 modes); the
#: tail itself is the uncertainty of the reference
MODE_CONVERGED_06_194 = {"V_over_U": (1.0207879 - 2.40e-5 * 0.22 / 0.78, 6.8e-6),
                         "dp_plus_R0": (1778.364 - 0.031 * 0.17 / 0.83, 6.4e-3),
                         "tension_max": (1009.85 + 2.55 * 0.33 / 0.67, 1.26)}


@pytest.mark.slow          # ~2 min on 2 cores
def test_default_solve_converges_at_nu_0p6_lam_1p94(report):
    """The hardest default case, (0.6, 1.94), lam/lam_c = 0.979, Ca_B = 50, with default
    options: converged, and the estimated error of each output is at least its distance from
    the mode-converged value (less that reference's own uncertainty) and within 10 times that
    distance (plus the uncertainty)."""
    res = solve_vesicle(0.6, 1.94)
    assert res.success, res.message
    assert res.volume_error <= 1e-8 and res.area_error <= 1e-8
    for key, (ref, unc) in MODE_CONVERGED_06_194.items():
        value, est = getattr(res, key), res.error_estimate[key]
        true = abs(value - ref)
        report.value(f"ves.default_long_{key}", value, reference=ref,
                     tol=f"estimate {est:.2g}", source="mode-converged (own, extrapolated)")
        assert true - unc <= est <= 10.0 * (true + unc), (key, value, ref, est)


def test_prolonged_jacobian_columns_match_difference_columns():
    """The coarse level's Jacobian interpolated to the next level's nodes (the start of every
    level above the first) agrees with the difference Jacobian there, column by column."""
    from bem.newton import difference_jacobian
    from bem.shape import fit_curve
    from bem.vesicle import VesicleOperator, lubrication_seed, vesicle_discretisation
    from bem.vesicle.level import _prolonged_columns

    seed, _ = lubrication_seed(0.9, 1.0, 50.0, 24)
    ops, states, jacs = [], [], []
    for n in (16, 24):
        ref = fit_curve(seed.sample, 0.0, 1.0, n)
        op = VesicleOperator(0.9, 1.0, 50.0, vesicle_discretisation(n), ref)
        template = op.curve(ref.modes).modes.copy()

        def fun(z, op=op, template=template):
            st = op.evaluate(op.curve(op.full(z, template)))
            return st["F"], st

        z0 = op.free(template)
        F0, st0 = fun(z0)
        J, _ = difference_jacobian(fun, z0, F0, 1e-7, {})
        st0["jacobian"] = J
        ops.append(op)
        states.append(st0)
        jacs.append(J)
    cols = _prolonged_columns(ops[0], states[0], ops[1], states[1])
    assert sorted(cols) == list(range(len(cols))) and len(cols) == jacs[0].shape[1]
    scale = np.linalg.norm(jacs[1], axis=0).max()
    err = max(np.linalg.norm(c - jacs[1][:, j]) for j, c in cols.items()) / scale
    assert err < 0.05, err



def test_fixed_load_jacobian_has_the_gradient_of_the_full_one():
    """The Jacobian from residuals at fixed tension and V, projected off their columns
    (Kaufman 1975), against the full difference Jacobian (every point re-solving the tension
    and V): J^T F agrees at any shape (F is orthogonal to those columns), here the
    lubrication seed far from the minimum, to the difference error; the columns themselves
    differ there by a term proportional to |F|, and agree near the minimum."""
    from bem.newton import difference_jacobian
    from bem.vesicle import (
        VesicleOperator,
        level_function,
        lubrication_seed,
        vesicle_discretisation,
    )

    def both(curve):
        op = VesicleOperator(0.9, 1.0, 50.0, vesicle_discretisation(24), curve)
        fun = level_function(op, op.curve(curve.modes).modes.copy())
        z0 = op.free(op.curve(curve.modes).modes)
        F0, st = fun(z0)
        fixed, n_fixed = difference_jacobian(fun, z0, F0, 1e-7, {}, st)
        del fun.fixed
        full, n_full = difference_jacobian(fun, z0, F0, 1e-7, {}, st)
        assert n_fixed == n_full == z0.size
        col = np.linalg.norm(fixed - full, axis=0) / np.linalg.norm(full, axis=0)
        return F0, fixed, full, col.max()

    seed, _ = lubrication_seed(0.9, 1.0, 50.0, 24)
    F0, fixed, full, col = both(seed)
    g_full, g_fixed = full.T @ F0, fixed.T @ F0
    assert np.linalg.norm(g_fixed - g_full) <= 1e-5 * np.linalg.norm(g_full)   # 3.7e-7
    assert col > 1e-4                     # far from the minimum the columns differ (5 %)
    _, _, _, col = both(solve_vesicle(0.9, 1.0, n_modes=24).curve())  # a 24-mode minimum
    assert col < 1e-4, col                                                 # 6e-6


def test_concurrent_evaluations_equal_the_sequential_ones():
    """The difference-Jacobian points evaluated two at a time on threads (serial assembly, the
    LAPACK calls under one lock) give the residuals of one-by-one evaluations with the same
    area-secant start, to rounding (without the lock this failed intermittently: concurrent
    ``lu_solve`` calls on the shared wall factorisation were wrong by O(1))."""
    import numba

    from bem.vesicle import VesicleOperator, lubrication_seed, vesicle_discretisation
    from bem.vesicle.level import _residuals

    seed, _ = lubrication_seed(0.9, 1.0, 50.0, 24)
    op = VesicleOperator(0.9, 1.0, 50.0, vesicle_discretisation(24), seed)
    base = op.curve(seed.modes).modes
    points = []
    for j in range(2, 24):
        m = base.copy()
        m[j] += 1e-7 * (1 + j)
        points.append(m)
    slope = op._area_slope
    one_by_one = [op.evaluate(op.curve(m, slope=slope))["F"] for m in points]
    threads = numba.get_num_threads()
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    try:
        together = _residuals(op, points)
    finally:
        numba.set_num_threads(threads)
    scale = max(np.max(np.abs(F)) for F in one_by_one)
    for a, b in zip(one_by_one, together):
        assert np.max(np.abs(a - b)) <= 1e-12 * scale
    assert op._area_slope == slope                       # the batch leaves the operator as it was
