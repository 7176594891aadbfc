r"""Infer a vesicle or red cell from its measured speed and length in a tube.

The inverse of the solution map (:mod:`correlations.solution_map`). Scalings (project
conventions): R0 volume radius, R = d/2 tube radius, λ = R0/R, λc(ν) the critical confinement,
δ = 1 − λ/λc, U the mean velocity, V the cell velocity, ℓ = L/R the full axial length in R,
film h/R, Δp⁺R0/(ηU), tensions in ηU, Ca_B = ηUR0²/κ.

Method
------
1. **Inputs.** The measured V/U (or V and U), the length L and the tube diameter d, with their
   absolute uncertainties (default :data:`DEFAULT_RELATIVE_ERROR` of each value), give the two
   targets V/U and ℓ = 2L/d with their propagated uncertainties.
2. **Fit.** (ν, λ/λc) is found such that the map's V/U and ℓ match the targets: a bounded
   least-squares fit (:func:`scipy.optimize.least_squares`, trust-region reflective) inside the
   map's box (ν and λ/λc within the map's nodes), each residual divided by the combined
   uncertainty (measurement ⊕ the map's own error bar at that point). Two equations, two
   unknowns: a consistent measurement is matched exactly (residual ≈ 0). V/U and ℓ are not
   always monotone together, so the fit starts from the local minima of the misfit over the map's nodes (at most
   :data:`MAX_STARTS`) and every
   distinct acceptable solution is reported. Ca_B = ηUR0²/κ with R0 = λd/2 when η and κ are
   given (it then changes with λ during the fit), else :data:`DEFAULT_CA_B` (stated as an
   assumption).
3. **Verdict.** The best fit's residual χ = (Σ r²)^(1/2) above :data:`CHI_MAX` (3 σ), or no fit
   inside the map, means the data are *inconsistent with any steady axisymmetric vesicle in the
   map's range*.
4. **Uncertainty.** ``linear`` (default): every uncertain input — the measurements and the
   map's error on V/U and ℓ at the solution — is moved by ± its standard deviation in turn and
   (ν, λ/λc) follows by one Newton step with the map's Jacobian ∂(V/U, ℓ)/∂(ν, λ/λc) at the
   fit (central differences: a linearisation of the inverse map; a step longer than
   :data:`NEWTON_MAX_STEP` repeats the fit in full); the
   contributions are added in quadrature, together with the map's own error of each output.
   ``sampling``: ``samples`` Gaussian draws of the same inputs (fixed seed), each refitted; the
   standard deviation and the 16/84 percentiles are reported, plus the map's own output error
   in quadrature. When several distinct fits are acceptable (χ ≤ :data:`CHI_MAX`), the data
   do not single out one vesicle: every fit is listed, and the largest difference between the
   best fit's value and another fit's is added in quadrature to each uncertainty. The
   uncertainty of η and κ is not propagated (they enter through Ca_B, where
   the map changes little for Ca_B ≥ 50, Chen et al. 2020 §IV.A).

From (ν, λ): R0 = λd/2, volume Ω = 4/3 πR0³, area A = 4πR0² ν^(−2/3) (from ν = 6√π Ω A^(−3/2),
Seifert 1997, doi:10.1080/00018739700101488), and the map's film, Δp⁺ and tensions.

References
----------
Chen et al. 2020 (as cited in :mod:`correlations.solution_map`) for the map's scalings and the
weak Ca_B dependence; Barakat & Shaqfeh 2018a, J. Fluid Mech. 835, 721-761,
doi:10.1017/jfm.2017.717, for the near-critical structure the map interpolates.
"""

from __future__ import annotations

import enum
import logging
import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from lubrication.checks import InvalidParameterError, check_positive, check_range
from lubrication.geometry import critical_confinement

from .estimate import PHYSICAL_BOUNDS, physical_scales
from .posterior import mixture, nested_intervals, posterior
from .solution_map import (SolutionMap, load_map, outside_reason, query_map,
                           require_vesicle_map)

__all__ = ["Verdict", "InferredValue", "Fit", "Inference", "infer_map", "infer_cell",
           "mean_velocity_from_gradient",
           "DEFAULT_CA_B", "DEFAULT_RELATIVE_ERROR", "CHI_MAX", "MAX_SAMPLES"]

log = logging.getLogger(__name__)

#: Ca_B assumed when η and κ are not both given: the map's reference value; shapes are nearly
#: independent of Ca_B ≥ 50 (Chen et al. 2020 §IV.A).
DEFAULT_CA_B = 50.0
#: Uncertainty of a measurement when the user gives none (relative, 1 σ).
DEFAULT_RELATIVE_ERROR = 0.02
#: Largest χ = (Σ r²)^(1/2) of a fit still consistent with the data (3 σ).
CHI_MAX = 3.0
#: Largest number of starts of the multi-start fit (local minima of χ over the map's nodes).
MAX_STARTS = 4
#: Longest Newton step (in ν or λ/λc) trusted as linear; beyond it the fit is repeated in full
#: (half the map's grid spacing of 0.05 in ν, about that of λ/λc below 0.9).
NEWTON_MAX_STEP = 0.025
#: The map's own error in units of its error bar, for the posterior's likelihood
#: (correlations.posterior: classes of points, each a mixture of zero-mean Gaussians, weight
#: and standard deviation in bars), fitted by maximum likelihood to the map's errors against
#: 151 direct BEM solves (50 off its nodes, docs/data/map_offgrid.json, and 101 at random points
#: of its domain, docs/data/infer_truth.json; tests/benchmarks/map_error_model.py). At 89 % of
#: points the errors of V/U and ℓ are small (a tenth of the bar or less), each on its own; at
#: 11 % both are large together (0.76 bar, up to 2.7). Its standard deviation is 0.28 bar.
MAP_ERROR_MODEL = ((0.889, ((0.31, 0.028), (0.69, 0.146))), (0.111, ((1.0, 0.757),)))
#: The ways to find the uncertainty when no refitted draws are asked for.
UNCERTAINTY_METHODS = ("posterior", "linear")
#: Map evaluations the posterior may spend (about 0.3 ms each; shared among the Ca_B nodes
#: when Ca_B is unknown).
POSTERIOR_MAX_POINTS = 20000
#: Draws of the posterior at which the outputs other than ν and λ are evaluated.
POSTERIOR_OUTPUT_DRAWS = 200
#: The data cannot separate ν from λ when the posterior correlation of ν and λ/λc is at least
#: DEGENERATE_CORRELATION and ν's 95 % interval at least DEGENERATE_WIDTH wide (40 % of the
#: map's spacing in ν).
DEGENERATE_CORRELATION = 0.9
DEGENERATE_WIDTH = 0.02
#: Two fits are distinct when they differ by more than this in ν or in λ/λc.
DISTINCT = 0.02
#: Outputs of the map carried to the result (map key -> result key).
_MAP_OUTPUTS = {"film_min": "film", "dp_plus_R0": "dp_plus_R0", "tension_max": "tension_max",
                "tension_front": "tension_front"}
#: Units (or the scale of a dimensionless value) of every result quantity.
UNITS = {"nu": "-", "lam": "-", "lam_ratio": "-", "delta": "-", "lam_c": "-", "ca_b": "-",
         "V_over_U": "-", "ell": "R", "film": "R", "dp_plus_R0": "eta U/R0",
         "tension_max": "eta U", "tension_front": "eta U", "R0_um": "um", "volume_fl": "fL",
         "area_um2": "um^2", "film_nm": "nm", "dp_plus_Pa": "Pa", "tension_max_mN_m": "mN/m",
         "tension_front_mN_m": "mN/m"}


class Verdict(enum.Enum):
    """Outcome of an inference: whether a cell of the map is consistent with the measurements."""
    CONSISTENT = "consistent"
    INCONSISTENT = "inconsistent"


@dataclass(frozen=True)
class InferredValue:
    """One inferred quantity: value (at the best fit), 1-σ uncertainty (for the posterior half
    the 68 % interval), the 68 % interval (posterior: the shortest; sampling: the 16/84
    percentiles) and the posterior's shortest 95 % interval; ``unit`` as :data:`UNITS`."""
    value: float | None
    error: float | None
    unit: str
    low: float | None = None
    high: float | None = None
    low95: float | None = None
    high95: float | None = None

    def to_dict(self) -> dict:
        d = {"value": self.value, "error": self.error, "unit": self.unit}
        if self.low is not None:
            d.update(low68=self.low, high68=self.high)
        if self.low95 is not None:
            d.update(low95=self.low95, high95=self.high95)
        return d


@dataclass(frozen=True)
class Fit:
    """One solution (ν, λ/λc) of the fit and its residual χ (in combined σ)."""
    nu: float
    lam_ratio: float
    chi: float
    residuals: tuple


@dataclass(frozen=True)
class Inference:
    """Result of :func:`infer_map` / :func:`infer_cell`.

    ``status`` CONSISTENT or INCONSISTENT, ``message`` the verdict in words, ``fit`` the best
    fit (None when no fit lies inside the map), ``alternatives`` the other distinct acceptable
    fits, ``quantities`` the :class:`InferredValue` of every output, ``inputs`` the targets and
    their uncertainties, ``method`` how the uncertainty was propagated, ``assumptions``."""
    status: Verdict
    message: str
    fit: Fit | None
    alternatives: tuple
    quantities: dict
    inputs: dict
    method: str
    assumptions: tuple = ()
    notes: tuple = field(default=())

    @property
    def consistent(self) -> bool:
        return self.status is Verdict.CONSISTENT

    def to_dict(self) -> dict:
        return {"status": self.status.value, "message": self.message,
                "fit": None if self.fit is None else
                {"nu": self.fit.nu, "lam_ratio": self.fit.lam_ratio, "chi": self.fit.chi},
                "alternatives": [{"nu": a.nu, "lam_ratio": a.lam_ratio, "chi": a.chi}
                                 for a in self.alternatives],
                "quantities": {k: v.to_dict() for k, v in self.quantities.items()},
                "inputs": dict(self.inputs), "method": self.method,
                "assumptions": list(self.assumptions), "notes": list(self.notes)}


# --------------------------------------------------------------------------- forward model

def _query(m, nu: float, ratio: float, ca_of):
    """The map at (ν, λ/λc) with Ca_B = ``ca_of(λ)``; None when the point is outside the map
    or next to a hole."""
    ca_b = ca_of(ratio * float(critical_confinement(nu)))
    if outside_reason(m, nu, ratio, ca_b):
        return None
    q = query_map(nu, ratio, ca_b, map=m)
    if q["V_over_U"] is None or q["ell"] is None:
        return None
    return q


def _speed_length_many(m, nus, ratios, ca_of) -> list:
    """The map's (V/U, ℓ) :class:`MapValue` pairs at the points (ν, λ/λc), Ca_B =
    ``ca_of(λ)``; None outside the map or next to a hole. Only these two of the map's
    quantities are interpolated, and all the points inside at once
    (:meth:`SolutionMap.quantities_many`): the fit asks hundreds of times, the posterior
    thousands of points in rounds (query_map computes all eight)."""
    cas = [ca_of(r * float(critical_confinement(nu))) for nu, r in zip(nus, ratios)]
    inside = [i for i, (nu, r, c) in enumerate(zip(nus, ratios, cas))
              if not outside_reason(m, nu, r, c)]
    out = [None] * len(cas)
    if inside:
        pairs = m.quantities_many([nus[i] for i in inside], [ratios[i] for i in inside],
                                  [cas[i] for i in inside], ("V_over_U", "ell"))
        for i, pair in zip(inside, pairs):
            v, ell = pair["V_over_U"], pair["ell"]
            if v.value is not None and ell.value is not None:
                out[i] = (v, ell)
    return out


def _speed_length(m, nu: float, ratio: float, ca_of):
    """:func:`_speed_length_many` at one point."""
    return _speed_length_many(m, [nu], [ratio], ca_of)[0]


def _residuals(p, m, target, sigma, ca_of):
    """Weighted residuals (model − target)/(σ_meas ⊕ σ_map) of V/U and ℓ at p = (ν, λ/λc)."""
    # a point the map cannot answer (a hole) gets a residual far beyond any 3-sigma test, so
    # the trust region steps back from it
    pair = _speed_length(m, float(p[0]), float(p[1]), ca_of)
    if pair is None:
        return np.array([1e3, 1e3])
    return np.array([(v.value - t) / math.hypot(s, v.error or 0.0)
                     for v, t, s in zip(pair, target, sigma)])


def _starts(m, target, sigma, ca_of) -> list:
    """Starting points: the local minima of χ over the map's nodes (cheap: no interpolation
    along ν and λ there), best first, at most :data:`MAX_STARTS`."""
    nus, ratios = list(m.nus), [r for r in m.ratios if r <= 0.99]
    chi = np.full((len(nus), len(ratios)), np.inf)
    for i, nu in enumerate(nus):
        for j, r in enumerate(ratios):
            chi[i, j] = np.sum(_residuals((nu, r), m, target, sigma, ca_of)**2)
    minima = []
    for i in range(len(nus)):
        for j in range(len(ratios)):
            around = chi[max(i - 1, 0):i + 2, max(j - 1, 0):j + 2]
            if np.isfinite(chi[i, j]) and chi[i, j] <= around.min():
                minima.append((chi[i, j], nus[i], ratios[j]))
    minima.sort()
    return [(nu, r) for _, nu, r in minima[:MAX_STARTS]]


def _jacobian(m, fit: Fit, ca_of):
    """∂(V/U, ℓ)/∂(ν, λ/λc) of the map at ``fit`` by central differences (one-sided at the
    box's edges); None when singular or the map has no value next to it."""
    # step 1e-4: well inside a grid cell (nodes 0.01-0.1 apart), far above round-off
    h = 1e-4
    lo, hi = (m.nus[0], m.ratios[0]), (m.nus[-1], m.ratios[-1])
    p = np.array([fit.nu, fit.lam_ratio])
    jac = np.empty((2, 2))
    for k in range(2):
        a, b = p.copy(), p.copy()
        a[k], b[k] = min(p[k] + h, hi[k]), max(p[k] - h, lo[k])
        fa, fb = (_speed_length(m, *x, ca_of) for x in (a, b))
        if fa is None or fb is None:
            return None
        jac[:, k] = [(va.value - vb.value) / (a[k] - b[k]) for va, vb in zip(fa, fb)]
    if abs(np.linalg.det(jac)) < 1e-12 * np.abs(jac).max()**2:
        return None
    return jac


def _fit(m, target, sigma, ca_of, starts=None) -> list[Fit]:
    """Every distinct fit from ``starts`` (default :func:`_starts`), best first."""
    lo = (m.nus[0], m.ratios[0])
    hi = (m.nus[-1], m.ratios[-1])
    fits = []
    for s in (_starts(m, target, sigma, ca_of) if starts is None else starts):
        x0 = np.clip(s, lo, hi)
        # diff_step: the map is piecewise polynomial between nodes 0.05 apart; steps of 1e-4
        # resolve its slope; tolerances 1e-8 are far below any measurement's uncertainty
        r = least_squares(_residuals, x0, bounds=(lo, hi), args=(m, target, sigma, ca_of),
                          method="trf", diff_step=1e-4, xtol=1e-8, ftol=1e-8, max_nfev=40)
        chi = float(np.sqrt(np.sum(r.fun**2)))
        fits.append(Fit(float(r.x[0]), float(r.x[1]), chi, tuple(map(float, r.fun))))
    fits.sort(key=lambda f: f.chi)
    distinct = []
    for f in fits:
        if all(abs(f.nu - g.nu) > DISTINCT or abs(f.lam_ratio - g.lam_ratio) > DISTINCT
               for g in distinct):
            distinct.append(f)
    return distinct


def _outputs(m, nu, ratio, ca_of, diameter_um=None, scales_in=None) -> dict | None:
    """Every output at the fit (ν, λ/λc): value and the map's own error (None: no error)."""
    q = _query(m, nu, ratio, ca_of)
    if q is None:
        return None
    lam_c = float(critical_confinement(nu))
    lam = ratio * lam_c
    ca_b = ca_of(lam)
    out = {"nu": (nu, 0.0), "lam": (lam, 0.0), "lam_ratio": (ratio, 0.0),
           "delta": (1.0 - ratio, 0.0), "ca_b": (ca_b, 0.0),
           "V_over_U": (q["V_over_U"], q.quantities["V_over_U"].error),
           "ell": (q["ell"], q.quantities["ell"].error)}
    for key, name in _MAP_OUTPUTS.items():
        v = q.quantities[key]
        out[name] = (v.value, v.error)
    if diameter_um is not None:
        R0 = lam * diameter_um / 2
        out["R0_um"] = (R0, 0.0)
        out["volume_fl"] = (4.0 / 3.0 * math.pi * R0**3, 0.0)
        out["area_um2"] = (4.0 * math.pi * R0**2 * nu**(-2.0 / 3.0), 0.0)
        s = physical_scales(R0, diameter_um, *scales_in)
        pairs = (("film", "film_nm", "film_nm"), ("dp_plus_R0", "dp_plus_Pa", "dp_plus_Pa"),
                 ("tension_max", "tension_max_mN_m", "tension_mN_m"),
                 ("tension_front", "tension_front_mN_m", "tension_mN_m"))
        for src, dst, scale in pairs:
            if scale in s and out[src][0] is not None:
                out[dst] = (out[src][0] * s[scale],
                            None if out[src][1] is None else out[src][1] * s[scale])
    return out


# --------------------------------------------------------------------------- the inference

def _check_uncertainty(uncertainty: str) -> None:
    if uncertainty not in UNCERTAINTY_METHODS:
        raise InvalidParameterError("uncertainty", uncertainty,
                                    " or ".join(map(repr, UNCERTAINTY_METHODS)))


#: Most refitted draws of ``samples``: about 20 ms each, so 2000 take some 40 s; the sampled
#: standard deviation is then known to 1/√(2N) = 1.6 %, and more draws add nothing to it worth
#: the time.
MAX_SAMPLES = 2000


def _check_samples(samples) -> int:
    """``samples`` as an int, 0 <= samples <= :data:`MAX_SAMPLES`."""
    if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)):
        raise InvalidParameterError("samples", samples, f"an integer, 0 <= samples <= "
                                    f"{MAX_SAMPLES}")
    return int(check_range("samples", samples, 0, MAX_SAMPLES,
                           reason="refitted draws (0: the uncertainty method decides)"))


def _inverse_map(solution_map) -> SolutionMap:
    """The map to invert (default the shipped one), refused unless it spans at least two ν
    and two λ/λc nodes: two unknowns cannot be fitted inside a single node (a map packed
    from a build of one line or point is read, but cannot be inverted)."""
    m = require_vesicle_map(solution_map if isinstance(solution_map, SolutionMap)
                            else load_map(solution_map), "the inverse estimate is a vesicle's")
    if len(m.nus) < 2 or len(m.ratios) < 2:
        raise InvalidParameterError(
            "map", m.source or "the given map", "a map with at least two nu and two lam/lam_c "
            f"nodes to invert (this one has {len(m.nus)} and {len(m.ratios)})")
    return m


def _check_inputs(values: dict) -> None:
    """Every value positive and finite; each error non-negative and finite."""
    for name, value in values.items():
        if value is None:
            continue
        if name.endswith("_err"):
            check_range(name, value, 0.0, math.inf)
        else:
            check_positive(name, value)


def _posterior_quantities(m, target, sigma, ca_of, d, scales, centre, seed, ca_free):
    """The posterior over the map's box (:func:`correlations.posterior.posterior`; with
    ``ca_free`` also over its Ca_B nodes, log-uniform, :func:`correlations.posterior.mixture`)
    and every output's value at the best fit with its posterior intervals: ν, λ/λc, λ (and
    Ca_B) from the draws, the other outputs evaluated at :data:`POSTERIOR_OUTPUT_DRAWS` of
    them. Returns (quantities, notes, method, posterior)."""


    def values(pair):
        return None if pair is None else tuple((v.value, v.error or 0.0) for v in pair)

    def model_at(ca):
        def model(nu, ratio):
            return values(_speed_length(m, nu, ratio, ca))

        def model_many(nus, ratios):
            return [values(p) for p in _speed_length_many(m, nus, ratios, ca)]
        return {"model": model, "model_many": model_many}

    start = time.perf_counter()
    box = (m.nus[0], m.nus[-1], m.ratios[0], m.ratios[-1])
    if ca_free:
        logs = np.log(m.cas)
        share = np.gradient(logs) if len(logs) > 1 else np.ones(1)   # trapezoid in log Ca_B
        # the evaluation budget of one posterior shared among the Ca_B nodes
        budget = POSTERIOR_MAX_POINTS // len(m.cas)
        parts = {c: posterior(target=target, sigma=sigma, box=box, seed=seed,
                              error_model=MAP_ERROR_MODEL, max_points=budget,
                              **model_at(lambda lam, c=c: c)) for c in m.cas}
        post = mixture(parts, dict(zip(m.cas, share)), seed=seed)
    else:
        post = posterior(target=target, sigma=sigma, box=box, seed=seed,
                         error_model=MAP_ERROR_MODEL, max_points=POSTERIOR_MAX_POINTS,
                         **model_at(ca_of))
    if post.empty:
        return None, [], "", post
    n = min(POSTERIOR_OUTPUT_DRAWS, post.samples["nu"].size)
    cas = post.samples.get("ca_b")
    draws = [o for o in (_outputs(m, float(a), float(b),
                                  ca_of if cas is None else (lambda lam, c=float(cas[i]): c),
                                  d, scales)
                         for i, (a, b) in enumerate(zip(post.samples["nu"][:n],
                                                        post.samples["lam_ratio"][:n])))
             if o is not None]
    quantities, notes = {}, []
    own_sd = math.sqrt(sum(weight * w * c * c for weight, parts in MAP_ERROR_MODEL
                           for w, c in parts))                     # in map error bars
    for k, (value, own) in centre.items():
        if value is None:
            continue
        if k in post.samples:
            vals = post.samples[k]
        elif k == "delta":
            vals = 1.0 - post.samples["lam_ratio"]
        else:
            vals = np.array([o[k][0] for o in draws if o.get(k, (None,))[0] is not None])
        e = (own or 0.0) * own_sd
        if vals.size < 2 or (vals.max() == vals.min() and e == 0.0):
            quantities[k] = InferredValue(value, own, UNITS[k])
            continue
        # the value stays that of the best fit (one cell: its outputs are consistent with each
        # other), which in a valley can lie near an edge of the intervals; the map's own error
        # of an output (e, one standard deviation) adds to each interval's half-width in
        # quadrature, once for 68 % and twice for 95 %
        if k in post.intervals:
            iv = post.intervals[k]
        elif k == "delta":                       # those of lam/lam_c, the box's edge kept
            iv = {lv: (1.0 - b, 1.0 - a) for lv, (a, b) in post.intervals["lam_ratio"].items()}
        else:
            iv = nested_intervals(vals)
        bounds = []
        for level, k_e in ((0.68, 1.0), (0.95, 2.0)):
            lo, hi = iv[level]
            half = math.hypot(0.5 * (hi - lo), k_e * e)
            # without a map error the interval is kept as it is (the box's edge exactly)
            bounds += [lo, hi] if e == 0.0 else [0.5 * (lo + hi) - half, 0.5 * (lo + hi) + half]
        quantities[k] = InferredValue(value, 0.5 * (bounds[1] - bounds[0]), UNITS[k], *bounds)
    nu95, r95 = post.interval("nu", 0.95), post.interval("lam_ratio", 0.95)
    if (abs(post.correlation) >= DEGENERATE_CORRELATION
            and nu95[1] - nu95[0] >= DEGENERATE_WIDTH):
        notes.append(
            f"degenerate: nu between {nu95[0]:.3f} and {nu95[1]:.3f} (with lam/lam_c between "
            f"{r95[0]:.3f} and {r95[1]:.3f}, correlation {post.correlation:.2f}) fits the data "
            "(95 %): V/U and ell change together along this valley of the map, so they cannot "
            "separate nu from lam" + _separating_measurement(draws, centre))
    if len(post.branches) > 1:
        notes.append("the consistent cells fall apart in branches: " + "; ".join(
            f"{b.mass:.0%} at nu {b.nu[0]:.3f}-{b.nu[1]:.3f}, lam/lam_c {b.lam_ratio[0]:.3f}-"
            f"{b.lam_ratio[1]:.3f}" for b in post.branches if b.mass >= 0.01))
    if not post.resolved:
        notes.append(f"the posterior was not resolved within {post.evaluations} map points: "
                     "its intervals are approximate")
    method = ("posterior over the whole map (flat prior in nu and lam/lam_c"
              + (" and log Ca_B" if ca_free else "") + "; likelihood of V/U and ell: the "
              "measurement's Gaussian with the map's own error, a mixture fitted to its errors "
              f"against direct BEM solves; {post.evaluations} map points, "
              f"{time.perf_counter() - start:.1f} s): the value is the best fit's, the "
              "intervals the shortest holding 68 % and 95 % of the posterior (outputs widened by "
              "their map error), the error half the 68 % interval")
    return quantities, notes, method, post


def _separating_measurement(draws, centre) -> str:
    """The sentence naming the measurable output that varies most across the consistent
    cells, in units of the map's own error of it (empty when none varies by more than that)."""
    best, name = 1.0, ""
    for key, label in (("film", "the film thickness"), ("dp_plus_R0", "the extra pressure drop"),
                       ("tension_max", "the maximum tension")):
        vals = np.array([o[key][0] for o in draws if o.get(key, (None,))[0] is not None])
        own = centre.get(key, (None, None))[1]
        if vals.size < 2 or not own:
            continue
        lo, hi = np.quantile(vals, [0.025, 0.975])
        if (hi - lo) / own > best:
            best, name = (hi - lo) / own, (f"; measuring {label} would (it ranges over "
                                          f"{lo:.4g}-{hi:.4g} across them, {(hi - lo) / own:.0f}"
                                          " times the map's error there)")
    return name


def _run(m, measured: dict, errors: dict, derive, samples: int, seed: int,
         assumptions: list, uncertainty: str = "posterior", ca_free: bool = False) -> Inference:
    """The fit and its uncertainty. ``derive(measured) -> (target, sigma, ca_of,
    diameter_um, scales)`` turns a set of measurements into the fit's targets, the function
    λ -> Ca_B, and the inputs of the unit conversions (None, None: dimensionless only).
    ``ca_free``: Ca_B is not known; the fit takes ``ca_of``, the posterior integrates over the
    map's Ca_B."""
    target, sigma, ca_of, d, scales = derive(measured)
    inputs = {"V_over_U": target[0], "V_over_U_err": sigma[0], "ell": target[1],
              "ell_err": sigma[1], **measured, **{f"{k}_err": v for k, v in errors.items()}}
    fits = _fit(m, target, sigma, ca_of)
    best = fits[0]
    good = [f for f in fits if f.chi <= CHI_MAX]
    box = (f"{m.nus[0]:g} <= nu <= {m.nus[-1]:g}, {m.ratios[0]:g} <= lam/lam_c <= "
           f"{m.ratios[-1]:g}")
    if not good:
        msg = (f"inconsistent with any steady axisymmetric vesicle in the map's range ({box}): "
               f"the best fit nu={best.nu:.4g}, lam/lam_c={best.lam_ratio:.4g} misses V/U="
               f"{target[0]:.4g} and ell={target[1]:.4g} by chi={best.chi:.3g} combined "
               f"standard deviations (> {CHI_MAX:g})")
        return Inference(Verdict.INCONSISTENT, msg, best, (), {}, inputs, "none",
                         tuple(assumptions))
    best = good[0]
    centre = _outputs(m, best.nu, best.lam_ratio, ca_of, d, scales)
    notes = []
    if len(good) > 1:
        notes.append("more than one steady vesicle matches the data: " + "; ".join(
            f"nu={f.nu:.4g}, lam/lam_c={f.lam_ratio:.4g} (chi={f.chi:.2g})" for f in good)
            + "; the best fit is reported")

    # the uncertain inputs: the measurements, and the map's error on V/U and ell at the fit
    # (moved as an offset of the target, which is what the map error does to the fit)
    names = [k for k in errors if errors[k] > 0]
    map_err = (centre["V_over_U"][1] or 0.0, centre["ell"][1] or 0.0)

    def refit(meas, offset):
        t, s, c, dd, sc = derive(meas)
        t = (t[0] - offset[0], t[1] - offset[1])
        f = _fit(m, t, s, c, [(best.nu, best.lam_ratio)])[0]
        if f.chi > CHI_MAX:
            return None
        return _outputs(m, f.nu, f.lam_ratio, c, dd, sc)

    jac = _jacobian(m, best, ca_of)

    def newton(meas, offset):
        # one Newton step from the best fit: the first-order change of (nu, lam/lam_c) for a
        # small change of the targets (the linearisation of the inverse map)
        t, s, c, dd, sc = derive(meas)
        pair = _speed_length(m, best.nu, best.lam_ratio, c)
        if pair is None:
            return None
        rhs = np.array([t[0] - offset[0] - pair[0].value, t[1] - offset[1] - pair[1].value])
        step = np.linalg.solve(jac, rhs)
        nu, ratio = best.nu + step[0], best.lam_ratio + step[1]
        # a step longer than NEWTON_MAX_STEP, or one leaving the map's box, is outside the
        # linear regime (a nearly singular Jacobian): the fit is repeated in full instead
        if (np.abs(step).max() > NEWTON_MAX_STEP or not m.nus[0] <= nu <= m.nus[-1]
                or not m.ratios[0] <= ratio <= m.ratios[-1]):
            return refit(meas, offset)
        return _outputs(m, float(nu), float(ratio), c, dd, sc)

    keys = [k for k, (v, _) in centre.items() if v is not None]
    if not samples and uncertainty == "posterior":
        quantities, more, method, _ = _posterior_quantities(m, target, sigma, ca_of, d, scales,
                                                            centre, seed, ca_free)
        if quantities is None:
            uncertainty = "linear"
            notes.append("no point of the map comes within reach of the data under the "
                         "posterior's error model: the uncertainty is linearised instead")
        notes += more
    if samples:
        rng = np.random.default_rng(seed)
        draws, failed = [], 0
        for _ in range(samples):
            meas = dict(measured)
            for k in names:
                # draws at or below zero are redrawn at the value (a 2-sigma-scale error bar
                # of a positive measurement would otherwise make it negative)
                meas[k] = max(measured[k] + errors[k] * rng.standard_normal(), 1e-6 * measured[k])
            off = (map_err[0] * rng.standard_normal(), map_err[1] * rng.standard_normal())
            o = refit(meas, off)
            if o is None:
                failed += 1
                continue
            draws.append(o)
        method = (f"sampling: {samples} Gaussian draws of the measurements and of the map's "
                  f"V/U and ell errors (seed {seed}), each refitted; std and 16/84 percentiles, "
                  "the map's own output error added in quadrature")
        if failed:
            notes.append(f"{failed} of {samples} draws had no consistent fit and were left out")
        quantities = {}
        for k in keys:
            vals = np.array([o[k][0] for o in draws if k in o and o[k][0] is not None])
            own = centre[k][1] or 0.0
            if vals.size < 2:
                quantities[k] = InferredValue(centre[k][0], None, UNITS[k])
                continue
            p16, p84 = np.percentile(vals, [16, 84])
            quantities[k] = InferredValue(centre[k][0], float(math.hypot(np.std(vals), own)),
                                          UNITS[k], float(p16), float(p84))
    elif uncertainty == "linear":
        method = ("linearisation: each measurement and the map's V/U and ell errors moved by "
                  "+-1 sigma in turn, (nu, lam/lam_c) moved by one Newton step with the map's "
                  "Jacobian at the fit (central differences); contributions and the map's own "
                  "output error added in quadrature")
        var = {k: (centre[k][1] or 0.0)**2 for k in keys}
        moves = [("meas", k) for k in names] + [("map", 0), ("map", 1)]
        for kind, k in moves:
            pair = []
            for sign in (1.0, -1.0):
                meas, off = dict(measured), [0.0, 0.0]
                if kind == "meas":
                    meas[k] = measured[k] + sign * errors[k]
                else:
                    off[k] = sign * map_err[k]
                pair.append(newton(meas, off) if jac is not None else refit(meas, off))
            what = k if kind == "meas" else ("V/U", "ell")[k]
            if pair[0] is None and pair[1] is None:
                notes.append(f"moving {what} by 1 sigma either way leaves the map or meets a "
                             "hole of it; its contribution is left out")
                continue
            if None in pair:
                # one-sided difference: the other side of the point is a hole of the map
                notes.append(f"{what}: one-sided difference (a hole of the map on one side)")
                pair = [pair[0] or centre, pair[1] or centre]
                scale = 1.0
            else:
                scale = 0.5
            for q in keys:
                a, b = pair[0].get(q, (None,))[0], pair[1].get(q, (None,))[0]
                if a is not None and b is not None:
                    var[q] += (scale * (a - b))**2
        quantities = {k: InferredValue(centre[k][0], float(math.sqrt(var[k])), UNITS[k])
                      for k in keys}
    if len(good) > 1 and (samples or uncertainty == "linear"):
        # the data do not single out one vesicle: the largest distance from the best fit to
        # another acceptable fit is added in quadrature to every quantity (an error bar that
        # covers all the vesicles the data allow, not only the neighbourhood of one)
        others = [o for o in (_outputs(m, f.nu, f.lam_ratio, ca_of, d, scales)
                              for f in good[1:]) if o is not None]
        for k, q in list(quantities.items()):
            spread = max((abs(o[k][0] - q.value) for o in others
                          if k in o and o[k][0] is not None), default=0.0)
            quantities[k] = InferredValue(q.value, math.hypot(q.error or 0.0, spread), q.unit,
                                          q.low, q.high)
        method += ("; the spread to the other acceptable fits (chi <= "
                   f"{CHI_MAX:g}) added in quadrature")
    msg = (f"consistent: nu={best.nu:.4g}, lam/lam_c={best.lam_ratio:.4g} match V/U and ell "
           f"to chi={best.chi:.2g} combined standard deviations"
           + (f" ({len(good)} distinct vesicles match: ambiguous)" if len(good) > 1 else ""))
    log.info(msg)
    return Inference(Verdict.CONSISTENT, msg, best, tuple(good[1:]), quantities, inputs,
                     method, tuple(assumptions), tuple(notes))


def infer_map(V_over_U: float, ell: float, V_over_U_err: float | None = None,
              ell_err: float | None = None, ca_b: float = DEFAULT_CA_B, samples: int = 0,
              seed: int = 0, solution_map=None, uncertainty: str = "posterior") -> Inference:
    r"""Infer (ν, λ) from the dimensionless speed V/U and length ℓ = L/R at a given Ca_B.

    The method of the module docstring: a bounded least-squares fit of the solution map's V/U
    and ℓ in (ν, λ/λc), weighted by measurement ⊕ map error, from several starts; uncertainty
    from the posterior over the whole map (``uncertainty="posterior"``, seconds), by
    linearisation at the best fit (``"linear"``, fast, blind to valleys and branches) or by
    ``samples`` refitted Gaussian draws.

    Parameters
    ----------
    V_over_U, ell : float
        Measured cell speed over the mean velocity and full axial length over R [-].
    V_over_U_err, ell_err : float, optional
        Their absolute 1-σ uncertainties [-] (default :data:`DEFAULT_RELATIVE_ERROR` × value).
    ca_b : float or None
        Bending capillary number ηUR0²/κ [-] (held fixed); None: unknown, the fit takes
        :data:`DEFAULT_CA_B` and the posterior integrates over the map's Ca_B (log-uniform).
    samples, seed : int
        Number of refitted draws (0: ``uncertainty`` decides) and the seed of the draws.
    solution_map : SolutionMap, str or Path, optional
        The map (default the shipped one).
    uncertainty : {"posterior", "linear"}
        How the uncertainty is found when ``samples`` is 0.

    Returns
    -------
    Inference
    """
    _check_uncertainty(uncertainty)
    samples = _check_samples(samples)
    errors = {"V_over_U": V_over_U_err, "ell": ell_err}
    _check_inputs({"V_over_U": V_over_U, "ell": ell, "ca_b": ca_b, "V_over_U_err": V_over_U_err,
                   "ell_err": ell_err})
    ca_free = ca_b is None
    ca_b = DEFAULT_CA_B if ca_free else ca_b
    errors = {k: DEFAULT_RELATIVE_ERROR * v if errors[k] is None else float(errors[k])
              for k, v in (("V_over_U", V_over_U), ("ell", ell))}
    m = _inverse_map(solution_map)
    measured = {"V_over_U": float(V_over_U), "ell": float(ell)}

    def derive(meas):
        return ((meas["V_over_U"], meas["ell"]), (errors["V_over_U"], errors["ell"]),
                lambda lam: float(ca_b), None, None)

    assumptions = ([f"Ca_B unknown: the best fit takes Ca_B = {DEFAULT_CA_B:g}, the posterior "
                    "integrates over the map's Ca_B (log-uniform)"] if ca_free else [])
    return _run(m, measured, errors, derive, samples, seed, assumptions, uncertainty, ca_free)


def mean_velocity_from_gradient(dpdx_pa_m: float, diameter_um: float, eta_mpas: float,
                                dpdx_err: float | None = None,
                                diameter_err: float | None = None) -> tuple[float, float]:
    r"""Mean velocity U [mm/s] of the undisturbed Poiseuille flow driven by the pressure
    gradient G = −dp/dx [Pa/m] in a tube of diameter d: U = G R²/(8η), R = d/2 (Hagen–
    Poiseuille), and its 1-σ error from those of G and d (default
    :data:`DEFAULT_RELATIVE_ERROR` × value; η taken as exact): δU/U = ((δG/G)² + (2δd/d)²)^(1/2).
    Raises :class:`~lubrication.checks.InvalidParameterError` for a G, d or η that is not
    positive and finite, an error that is negative, or a G whose U lies outside the velocity
    range of :data:`correlations.estimate.PHYSICAL_BOUNDS` (named ``dpdx_pa_m``: the input
    behind U).

    >>> round(mean_velocity_from_gradient(8.0e5, 4.0, 1.0)[0], 9)    # G R^2/(8 eta), mm/s
    0.4
    """
    for name, value in (("dpdx_pa_m", dpdx_pa_m), ("diameter_um", diameter_um),
                        ("eta_mpas", eta_mpas)):
        check_range(name, value, 0.0, math.inf, lo_open=True, hi_open=True,
                    reason="a positive finite number")
    _check_inputs({"dpdx_err": dpdx_err, "diameter_err": diameter_err})
    g_err = DEFAULT_RELATIVE_ERROR * dpdx_pa_m if dpdx_err is None else float(dpdx_err)
    d_err = DEFAULT_RELATIVE_ERROR * diameter_um if diameter_err is None else float(diameter_err)
    radius_m = 0.5 * diameter_um * 1e-6
    u = dpdx_pa_m * radius_m**2 / (8.0 * eta_mpas * 1e-3) * 1e3
    lo, hi, why = PHYSICAL_BOUNDS["velocity_mm_s"]
    if not lo <= u <= hi:
        # the gradient is the input: the message names it, with the mean velocity it gives
        raise InvalidParameterError(
            "dpdx_pa_m", dpdx_pa_m, f"a gradient for which {lo:g} <= U <= {hi:g} mm/s",
            f"U = G R^2/(8 eta) = {u:.4g} mm/s with d = {diameter_um:g} um and eta = "
            f"{eta_mpas:g} mPa s; velocities {why}")
    return u, u * math.hypot(g_err / dpdx_pa_m, 2.0 * d_err / diameter_um)


def infer_cell(length_um: float, diameter_um: float, u_mm_s: float,
               v_mm_s: float | None = None, v_over_u: float | None = None,
               length_err: float | None = None, diameter_err: float | None = None,
               u_err: float | None = None, v_err: float | None = None,
               eta_mpas: float | None = None, kappa_j: float | None = None,
               samples: int = 0, seed: int = 0, solution_map=None,
               uncertainty: str = "posterior") -> Inference:
    r"""Infer a cell (ν, λ, volume, area) and its film, Δp⁺ and tensions from V, L, d and U.

    Targets V/U = V/U (or the given V/U) and ℓ = 2L/d; the fit and the uncertainty are those of
    the module docstring. Errors are absolute, in the unit of their value (default
    :data:`DEFAULT_RELATIVE_ERROR` × value); ``v_err`` is the error of ``v_mm_s`` or, when
    ``v_over_u`` is given, of V/U.

    Parameters
    ----------
    length_um, diameter_um : float
        Cell length L and tube diameter d [µm].
    u_mm_s : float
        Mean flow velocity U [mm/s].
    v_mm_s, v_over_u : float
        Cell speed V [mm/s] or V/U [-] (exactly one).
    eta_mpas, kappa_j : float, optional
        Suspending viscosity [mPa·s] and bending modulus [J]: Ca_B = ηUR0²/κ (both), Δp⁺ in Pa
        and tensions in mN/m (η). Without both, Ca_B = :data:`DEFAULT_CA_B` is assumed.
    samples, seed, solution_map, uncertainty
        As :func:`infer_map`.

    Returns
    -------
    Inference
        Quantities in :data:`UNITS`; ``R0_um``, ``volume_fl``, ``area_um2``, ``film_nm`` and,
        with η, ``dp_plus_Pa``, ``tension_max_mN_m``, ``tension_front_mN_m``.
    """
    _check_uncertainty(uncertainty)
    samples = _check_samples(samples)
    if (v_mm_s is None) == (v_over_u is None):
        raise InvalidParameterError("v_mm_s", v_mm_s, "exactly one of v_mm_s and v_over_u")
    b = PHYSICAL_BOUNDS
    for name, value, bound in (("diameter_um", diameter_um, "diameter_um"),
                               ("u_mm_s", u_mm_s, "velocity_mm_s"),
                               ("v_mm_s", v_mm_s, "velocity_mm_s"),
                               ("length_um", length_um, "diameter_um"),
                               ("eta_mpas", eta_mpas, "plasma_viscosity_mpas"),
                               ("kappa_j", kappa_j, "bending_modulus_j")):
        if value is not None:
            check_range(name, value, b[bound][0], b[bound][1], reason=b[bound][2])
    _check_inputs({"v_over_u": v_over_u, "length_err": length_err, "diameter_err": diameter_err,
                   "u_err": u_err, "v_err": v_err})
    speed = "v_mm_s" if v_over_u is None else "v_over_u"
    measured = {speed: float(v_mm_s if v_over_u is None else v_over_u),
                "length_um": float(length_um), "diameter_um": float(diameter_um),
                "u_mm_s": float(u_mm_s)}
    given = {speed: v_err, "length_um": length_err, "diameter_um": diameter_err,
             "u_mm_s": u_err}
    if speed == "v_over_u":
        given["u_mm_s"] = u_err if u_err is not None else DEFAULT_RELATIVE_ERROR * u_mm_s
    errors = {k: DEFAULT_RELATIVE_ERROR * measured[k] if e is None else float(e)
              for k, e in given.items()}
    assumptions = [f"{k}_err = {DEFAULT_RELATIVE_ERROR:.0%} of the value (not given)"
                   for k, e in given.items() if e is None]
    ca_free = eta_mpas is None or kappa_j is None
    if ca_free:
        assumptions.append(
            f"Ca_B unknown (eta and kappa not both given): the best fit takes Ca_B = "
            f"{DEFAULT_CA_B:g} (shapes change little for Ca_B >= 50, Chen et al. 2020)"
            + (", the posterior integrates over the map's Ca_B (log-uniform)"
               if uncertainty == "posterior" and not samples else ""))
    m = _inverse_map(solution_map)

    def derive(meas):
        d, U, L = meas["diameter_um"], meas["u_mm_s"], meas["length_um"]
        R = d / 2
        if speed == "v_mm_s":
            vu = meas["v_mm_s"] / U
            s_vu = vu * math.hypot(errors["v_mm_s"] / measured["v_mm_s"],
                                   errors["u_mm_s"] / measured["u_mm_s"])
        else:
            vu, s_vu = meas["v_over_u"], errors["v_over_u"]
        ell = L / R
        s_ell = ell * math.hypot(errors["length_um"] / measured["length_um"],
                                 errors["diameter_um"] / measured["diameter_um"])
        def ca_of(lam):
            return DEFAULT_CA_B
        if eta_mpas is not None and kappa_j is not None:
            # Ca_B = eta U R0^2 / kappa = (eta U R^2 / kappa) lam^2, R0 = lam R
            scale = physical_scales(R, d, U, eta_mpas, kappa_j)["ca_b"]

            def ca_of(lam):
                return scale * lam**2
        return (vu, ell), (s_vu, s_ell), ca_of, d, (U, eta_mpas, kappa_j)

    return _run(m, measured, errors, derive, samples, seed, assumptions, uncertainty, ca_free)
