r"""The posterior of a vesicle's (ν, λ/λc) given its measured speed and length, over the whole
solution map.

Bayes' rule with a flat prior over the map's box (ν and λ/λc uniform between the map's
nodes) and a likelihood that convolves the measurement's Gaussian with the map's own error at
each point. That error is a mixture over classes of points m (weight W_m: a point where the
map is good, one where it is poor, errors of V/U and ℓ large or small together), within a
class independent for V/U and ℓ, each a mixture of Gaussians whose widths are multiples
c_{mj} of the map's error bar ε:

.. math::

    p(\nu, r \mid y) \propto \sum_m W_m \prod_{k \in \{V/U,\,\ell\}} \sum_j
        \frac{w_{mj}}{s_{mjk}} \exp\!\left(-\frac{(f_k(\nu, r) - y_k)^2}{2 s_{mjk}^2}
        \right), \qquad s_{mjk}^2 = \sigma_k^2 + c_{mj}^2\,\epsilon_k(\nu, r)^2,

with f the map's V/U and ℓ = L/R at Ca_B = ``ca_of(λ)``. A local
least-squares fit sees only the neighbourhood of one minimum; where V/U and ℓ change together
along a valley (two different cells, the same speed and length) the consistent set is long
and thin, or falls apart in branches. It is therefore integrated on an adaptive grid over the
whole box (:func:`posterior`): cells in (ν, x = √(1 − λ/λc)) (the map's own coordinates),
split in four while the data could be met inside them (the targets within the range of the
cell's corners, widened by 4 s_k of the widest component and by a quarter of that range for
curvature) and their corners do not yet resolve the likelihood (corners more than s_k of the
narrowest component apart in V/U or ℓ). Work is bounded by ``max_points`` map evaluations;
a posterior not resolved within them says so.

Summaries (:class:`Posterior`): the shortest 68 % and 95 % intervals of ν, λ/λc and λ from
draws of the cells by weight (shortest rather than central: a posterior piled against an edge
of the map, ν = 0.6 say, keeps that edge inside its intervals), the separate branches
(connected parts of the 95 % highest-density region) with their mass, and the correlation of
ν and λ/λc.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from lubrication.geometry import critical_confinement

__all__ = ["Branch", "Posterior", "mixture", "nested_intervals", "posterior",
           "shortest_interval"]

#: probability of the intervals reported
LEVELS = (0.68, 0.95)
#: starting cells in ν and in x = √(1 − λ/λc): 0.024 and 0.037 over the shipped map's box
START = (16, 24)
#: halvings of the starting cells at most: 0.0002 and 0.0003 after 7
MAX_LEVELS = 7


@dataclass(frozen=True)
class Branch:
    """One connected part of the 95 % highest-density region: its probability mass and the
    ranges of ν and λ/λc it spans."""
    mass: float
    nu: tuple
    lam_ratio: tuple


@dataclass(frozen=True)
class Posterior:
    """Draws of (ν, λ/λc, λ) from the posterior and their summaries.

    ``intervals[name][level]`` holds the shortest interval of ``nu``, ``lam_ratio`` or
    ``lam`` that contains the fraction ``level`` (:data:`LEVELS`) of the draws;
    ``branches`` the parts of the 95 % region, largest first; ``correlation`` that of ν and
    λ/λc; ``evaluations`` the map points evaluated; ``resolved`` False when ``max_points`` was
    reached before every cell that could hold the data resolved the likelihood; ``empty`` True
    when no point of the map comes within reach of the data; ``evidence`` the integral of the
    likelihood over the box (for weighing posteriors at several Ca_B, :func:`mixture`);
    ``edges`` the box's (low, high, finest cell width) in ν and in λ/λc."""
    samples: dict
    intervals: dict
    branches: tuple
    correlation: float
    evaluations: int
    resolved: bool
    empty: bool = False
    evidence: float = 0.0
    edges: tuple = ()

    def interval(self, name: str, level: float) -> tuple:
        """The shortest ``level`` (0.68 or 0.95) interval of ``name``."""
        return self.intervals[name][level]


def nested_intervals(values) -> dict:
    """{level: interval} for :data:`LEVELS`, each the shortest holding that fraction of
    ``values``, widened to contain the intervals of the lower levels (the shortest intervals of
    a many-peaked sample need not nest)."""
    out, lo, hi = {}, math.inf, -math.inf
    for level in sorted(LEVELS):
        a, b = shortest_interval(values, level)
        lo, hi = min(lo, a), max(hi, b)
        out[level] = (lo, hi)
    return out


def shortest_interval(values, level: float) -> tuple:
    """The shortest interval holding the fraction ``level`` of ``values`` (at least two)."""
    v = np.sort(np.asarray(values, float))
    k = min(v.size - 1, max(1, math.ceil(level * v.size) - 1))
    i = int(np.argmin(v[k:] - v[:v.size - k]))
    return float(v[i]), float(v[i + k])


def posterior(model, target, sigma, box, *, error_model=((1.0, ((1.0, 1.0),)),),
              max_points: int = 20000, draws: int = 20000, seed: int = 0,
              model_many=None) -> Posterior:
    """Integrate the posterior of the module docstring over ``box``.

    Parameters
    ----------
    model : callable
        ``model(nu, lam_ratio) -> ((V/U, ε_V), (ℓ, ε_ℓ))`` or None where the map has no value.
    target, sigma : pair of float
        Measured (V/U, ℓ) and their 1-σ errors.
    error_model : tuple of (class weight, tuple of (weight, scale))
        The distribution of the model's error (module docstring): classes of points, each
        with its weight and its mixture of Gaussians of standard deviation ``scale`` × ε
        (default: one class, ε is one standard deviation).
    box : tuple
        (ν_min, ν_max, r_min, r_max) of λ/λc = r.
    max_points, draws, seed : int
        Bound on the map evaluations, number of posterior draws and their seed.
    model_many : callable, optional
        ``model_many(nus, lam_ratios) -> list`` of what ``model`` gives at each point: the
        corners of every cell of a refinement round are then evaluated in one call (the map
        answers many points at once for little more than one). Same result as without.
    """
    nu_lo, nu_hi, r_lo, r_hi = box
    x_lo, x_hi = math.sqrt(1.0 - r_hi), math.sqrt(1.0 - r_lo)
    y = np.asarray(target, float)
    sig = np.asarray(sigma, float)
    scales = [scale for _, parts in error_model for _, scale in parts]
    widest, narrowest = max(scales), min(scales)
    cache: dict = {}

    def key(nu, x):
        return round(nu, 12), round(x, 12)

    def corner_points(cell):
        nu0, nu1, x0, x1 = cell
        return [(a, b) for a in (nu0, nu1) for b in (x0, x1)]

    def point(nu, x):
        k = key(nu, x)
        if k not in cache:
            cache[k] = model(nu, 1.0 - x * x)            # ((f, eps), (f, eps)) or None
        return cache[k]

    def prefetch(cells):
        """The corners of ``cells`` not yet known, evaluated together in the order
        :func:`point` would meet them."""
        if model_many is None:
            return
        new = {}
        for cell in cells:
            for a, b in corner_points(cell):
                k = key(a, b)
                if k not in cache and k not in new:
                    new[k] = (a, b)
        if new:
            cache.update(zip(new, model_many([a for a, _ in new.values()],
                                             [1.0 - b * b for _, b in new.values()])))

    def corners(cell):
        return [point(a, b) for a, b in corner_points(cell)]

    def status(cell):
        """(could the data be met inside, is the likelihood resolved)."""
        vals = [c for c in corners(cell) if c is not None]
        if not vals:
            return False, True
        possible, fine = True, True
        for k in range(2):
            f = [v[k][0] for v in vals]
            eps = max(v[k][1] for v in vals)
            lo, hi = min(f), max(f)
            reach = 4.0 * math.hypot(sig[k], widest * eps) + 0.25 * (hi - lo)
            possible &= lo - reach <= y[k] <= hi + reach
            fine &= hi - lo <= math.hypot(sig[k], narrowest * eps)
        return possible, fine

    # start: START cells, uniform in nu and in x
    nus = np.linspace(nu_lo, nu_hi, START[0] + 1)
    xs = np.linspace(x_lo, x_hi, START[1] + 1)
    todo = [(a, b, c, d) for a, b in zip(nus[:-1], nus[1:]) for c, d in zip(xs[:-1], xs[1:])]
    leaves, resolved, level = [], True, 0
    while todo:
        prefetch(todo)
        split = []
        for cell in todo:
            possible, fine = status(cell)
            if not possible:
                continue
            if fine or level == MAX_LEVELS:
                leaves.append(cell)
            else:
                split.append(cell)
        # a split costs five new points at most: stop splitting where the budget would end
        if len(cache) + 5 * len(split) > max_points:
            resolved = not split
            leaves += split
            break
        todo = []
        for nu0, nu1, x0, x1 in split:
            nm, xm = 0.5 * (nu0 + nu1), 0.5 * (x0 + x1)
            todo += [(nu0, nm, x0, xm), (nm, nu1, x0, xm), (nu0, nm, xm, x1), (nm, nu1, xm, x1)]
        level += 1

    values = [corners(cell) for cell in leaves]
    like = np.array([[_likelihood(v, y, sig, error_model) for v in vs] for vs in values]
                    ).reshape(-1, 4)
    cells = np.array(leaves).reshape(-1, 4)
    # a cell's mass: the mean of its valid corners' likelihoods (the integral of their
    # bilinear interpolant) times its area in (nu, lam/lam_c), 2 x dx dnu (the prior is flat in
    # lam/lam_c = 1 - x^2)
    valid = np.array([[v is not None for v in vs] for vs in values]).reshape(-1, 4)
    mean = np.where(valid.any(axis=1), like.sum(axis=1) / np.maximum(valid.sum(axis=1), 1), 0.0)
    weights = mean * (cells[:, 1] - cells[:, 0]) * (cells[:, 3] - cells[:, 2]) * (
        cells[:, 2] + cells[:, 3])
    if not leaves or not np.isfinite(weights).any() or weights.max() <= 0.0:
        nan = {level: (math.nan, math.nan) for level in LEVELS}
        return Posterior({}, {k: dict(nan) for k in ("nu", "lam_ratio", "lam")}, (), math.nan,
                         len(cache), resolved, empty=True)
    evidence = float(weights.sum())
    weights /= evidence
    rng = np.random.default_rng(seed)
    nu, x = _draw(cells, like, weights, draws, rng)
    ratio = 1.0 - x * x
    lam = ratio * np.asarray(critical_confinement(nu), float)
    samples = {"nu": nu, "lam_ratio": ratio, "lam": lam}
    edges = ((box[0], box[1], float((cells[:, 1] - cells[:, 0]).min())),
             (box[2], box[3], float((cells[:, 3]**2 - cells[:, 2]**2).min())))
    return _summarise(samples, _branches(cells, weights), len(cache), resolved, evidence, edges)


def _summarise(samples, branches, evaluations, resolved, evidence, edges) -> Posterior:
    """The intervals of the draws. ``edges``: (low, high, finest cell width) of ν and of λ/λc;
    an interval end within one finest cell of the box's edge is the edge (the grid cannot tell
    them apart, and a posterior piled against the edge keeps it inside)."""
    nu, ratio = samples["nu"], samples["lam_ratio"]
    intervals = {k: nested_intervals(v) for k, v in samples.items()}
    for name, (lo_edge, hi_edge, width) in zip(("nu", "lam_ratio"), edges):
        intervals[name] = {level: (lo_edge if lo - lo_edge < width else lo,
                                   hi_edge if hi_edge - hi < width else hi)
                           for level, (lo, hi) in intervals[name].items()}
    corr = float(np.corrcoef(nu, ratio)[0, 1]) if nu.std() > 0 and ratio.std() > 0 else 0.0
    return Posterior(samples, intervals, branches, corr, evaluations, resolved,
                     evidence=evidence, edges=tuple(edges))


def mixture(parts: dict, prior: dict, *, seed: int = 0) -> Posterior:
    """The posterior with a third unknown c (Ca_B) on nodes: ``parts[c]`` the posterior at
    node c, ``prior[c]`` the node's prior weight (its share of the range of c). Each part
    weighs its evidence times its prior; the draws are resampled from the parts by that
    weight and carry c as ``samples["ca_b"]``; the branches are those of the heaviest part."""
    live = {c: p for c, p in parts.items() if not p.empty}
    if not live:
        return next(iter(parts.values()))
    w = np.array([p.evidence * prior[c] for c, p in live.items()])
    w /= w.sum()
    rng = np.random.default_rng(seed)
    n = next(iter(live.values())).samples["nu"].size
    counts = rng.multinomial(n, w)
    samples = {k: np.concatenate([p.samples[k][:m] for p, m in zip(live.values(), counts)])
               for k in ("nu", "lam_ratio", "lam")}
    samples["ca_b"] = np.concatenate([np.full(m, c) for c, m in zip(live, counts)])
    order = rng.permutation(n)                 # the parts' draws interleaved
    samples = {k: v[order] for k, v in samples.items()}
    heaviest = list(live.values())[int(np.argmax(w))]
    return _summarise(samples, heaviest.branches, sum(p.evaluations for p in parts.values()),
                      all(p.resolved for p in live.values()),
                      float(sum(p.evidence * prior[c] for c, p in live.items())), heaviest.edges)


def _likelihood(value, y, sig, error_model) -> float:
    """The likelihood of the data y at a map point ``value`` ((f, ε) per output; 0 if None):
    the measurement's Gaussian convolved with the error model (module docstring)."""
    if value is None:
        return 0.0
    r2 = [(value[k][0] - y[k])**2 for k in range(2)]
    total = 0.0
    for weight, parts in error_model:
        for k in range(2):
            weight *= sum(w * math.exp(-0.5 * r2[k] / s2) / math.sqrt(s2) for w, s2 in
                          ((w, sig[k]**2 + (scale * value[k][1])**2) for w, scale in parts))
        total += weight
    return total


def _draw(cells, like, weights, n, rng):
    """n draws (ν, x) from the bilinear interpolant of the cells' corner likelihoods (corners
    ordered (ν0, x0), (ν0, x1), (ν1, x0), (ν1, x1)), by rejection: a cell proposed with the
    mass of its envelope, its weight times largest over mean corner, a point of it accepted
    with probability interpolant over largest."""
    mean = like.mean(axis=1)
    envelope = np.where(mean > 0, weights * like.max(axis=1) / np.where(mean > 0, mean, 1), 0)
    envelope /= envelope.sum()
    nu, x = np.empty(0), np.empty(0)
    while nu.size < n:
        pick = rng.choice(len(cells), size=2 * (n - nu.size), p=envelope)
        u, v, accept = rng.random(pick.size), rng.random(pick.size), rng.random(pick.size)
        c = like[pick]
        top = c.max(axis=1)
        bilinear = ((1 - u) * (1 - v) * c[:, 0] + (1 - u) * v * c[:, 1] + u * (1 - v) * c[:, 2]
                    + u * v * c[:, 3])
        keep = accept * top <= bilinear
        cell = cells[pick[keep]]
        nu = np.concatenate([nu, cell[:, 0] + u[keep] * (cell[:, 1] - cell[:, 0])])
        x = np.concatenate([x, cell[:, 2] + v[keep] * (cell[:, 3] - cell[:, 2])])
    return nu[:n], x[:n]


def _branches(cells, weights) -> tuple:
    """The connected parts of the 95 % highest-density region of the weighted cells, largest
    first: cells ranked by density, the densest holding 95 % of the mass kept, and kept cells
    that touch (share a stretch of edge or a corner) joined. The density is per area of
    (ν, λ/λc), where the prior is flat: a cell's weight over dν·d(λ/λc) = 2x dν dx."""
    density = weights / ((cells[:, 1] - cells[:, 0]) * (cells[:, 3] - cells[:, 2])
                         * (cells[:, 2] + cells[:, 3]))
    order = np.argsort(density)[::-1]
    keep = order[:int(np.searchsorted(np.cumsum(weights[order]), 0.95)) + 1]
    kept = cells[keep]
    tol = 1e-12
    parent = list(range(len(keep)))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(len(keep)):
        a = kept[i]
        touch = ((kept[:, 0] <= a[1] + tol) & (kept[:, 1] >= a[0] - tol)
                 & (kept[:, 2] <= a[3] + tol) & (kept[:, 3] >= a[2] - tol))
        for j in np.nonzero(touch)[0]:
            parent[root(int(j))] = root(i)
    groups: dict = {}
    for i in range(len(keep)):
        groups.setdefault(root(i), []).append(i)
    out = []
    for members in groups.values():
        c = kept[members]
        out.append(Branch(float(weights[keep][members].sum()),
                          (float(c[:, 0].min()), float(c[:, 1].max())),
                          (float(1 - c[:, 3].max()**2), float(1 - c[:, 2].min()**2))))
    return tuple(sorted(out, key=lambda b: -b.mass))
