"""``correlations.posterior``: the adaptive-grid posterior against closed forms.

Independent reference: for a model linear in (ν, λ/λc) with Gaussian errors and a flat prior,
the posterior is the Gaussian of the least-squares problem (mean and covariance in closed form)
as long as the box holds it; its shortest 68 % and 95 % intervals are the mean ± 0.994σ and
± 1.960σ. Two errors move the ends: the sampling of 20000 draws (the shortest interval's ends
scatter by ~0.03σ) and the grid, whose cells are up to one σ of the data across and whose
draws follow the bilinear interpolant of the corners' likelihoods, below a Gaussian's concave
top (mass moves outward): the spread grows by up to ~6 % (sd ratio 1.01-1.05 measured over 20000 draws). Asserted
one-sided: an end may lie 0.25σ outside the closed form's (wide: the grid) but only 0.1σ
inside it (narrow: the sampling alone), so the test fails an overconfident posterior.
"""

import math

import numpy as np
import pytest

from correlations.posterior import mixture, posterior, shortest_interval

BOX = (0.6, 0.98, 0.2, 0.9999)
A = np.array([[1.5, -0.8], [2.0, 6.0]])           # d(V/U, ell)/d(nu, lam/lam_c)
CENTRE = np.array([0.8, 0.6])


def _linear(eps=(0.0, 0.0)):
    def model(nu, r):
        f = A @ (np.array([nu, r]) - CENTRE) + np.array([1.2, 5.0])
        return ((f[0], eps[0]), (f[1], eps[1]))
    return model


@pytest.mark.parametrize("sigma, eps", [((0.01, 0.05), (0.0, 0.0)),
                                        ((0.002, 0.004), (0.0, 0.0)),
                                        ((0.004, 0.02), (0.003, 0.01))])
def test_linear_gaussian_posterior_has_the_closed_form_intervals(sigma, eps):
    target = np.array([1.2, 5.0])
    s = np.hypot(sigma, eps)
    cov = np.linalg.inv(A.T @ np.diag(1 / s**2) @ A)
    post = posterior(_linear(eps), target, sigma, BOX)
    assert post.resolved and not post.empty
    for k, name in enumerate(("nu", "lam_ratio")):
        sd = math.sqrt(cov[k, k])
        for level, z in ((0.68, 0.9945), (0.95, 1.96)):
            lo, hi = post.interval(name, level)
            wide = (CENTRE[k] - z * sd - lo, hi - (CENTRE[k] + z * sd))   # > 0: wider
            assert all(-0.1 * sd < w < 0.25 * sd for w in wide), (name, level, lo, hi, sd)
    rho = cov[0, 1] / math.sqrt(cov[0, 0] * cov[1, 1])
    assert abs(post.correlation - rho) < 0.05, (post.correlation, rho)
    assert len(post.branches) == 1


def test_two_separate_minima_make_two_branches_with_their_masses():
    """A model whose speed is the same at two places (|nu - 0.7| enters): the posterior falls
    apart in two equal branches, each about its own nu."""
    def model(nu, r):
        return ((1.0 + abs(nu - 0.79), 0.0), (5.0 + 4.0 * (r - 0.5), 0.0))
    post = posterior(model, (1.1, 5.0), (0.004, 0.01), BOX)
    assert len(post.branches) == 2
    for b in post.branches:
        assert abs(b.mass - 0.475) < 0.03, b
    centres = sorted(0.5 * sum(b.nu) for b in post.branches)
    assert abs(centres[0] - 0.69) < 0.01 and abs(centres[1] - 0.89) < 0.01, centres


def test_branches_mirrored_in_lam_ratio_hold_equal_mass():
    """A length that is the same at lam/lam_c = 0.3 and 0.9 (|r - 0.6| enters): with the prior
    flat in lam/lam_c the two branches are mirror images and hold equal mass, although the
    grid's cells (uniform in x = sqrt(1 - r)) are three times narrower in r at 0.9. Equal up to
    the granularity of the 95 % cut, about one cell's weight (the heaviest cell holds 0.5 %):
    0.01. Ranking cells by density per area of (nu, x) instead cuts the branch at 0.9 deeper
    (masses 0.489 and 0.461)."""
    def model(nu, r):
        return ((1.0 + 2.0 * (nu - 0.8), 0.0), (5.0 + 4.0 * abs(r - 0.6), 0.0))
    post = posterior(model, (1.0, 6.2), (0.004, 0.16), BOX)
    assert len(post.branches) == 2
    a, b = post.branches
    assert abs(a.mass - b.mass) < 0.01, post.branches
    assert a.mass + b.mass >= 0.95


def test_data_out_of_reach_give_an_empty_posterior():
    post = posterior(_linear(), (9.0, 50.0), (0.01, 0.01), BOX)
    assert post.empty


def test_mixture_weighs_the_parts_by_evidence_and_prior():
    """Two Ca_B nodes whose linear models differ in steepness (the second 4 times steeper in
    both outputs): a linear Gaussian's evidence is 2π σ_V σ_ell/|det A| times the likelihood's
    normalisation, so the second weighs 1/16 of the first; with priors 1/3 and 2/3 its share
    of the draws is (2/16)/(1/3 + 2/16) x ... = 2/(16/3 + 2) of them (binomial sampling error
    ~0.005)."""
    def steep(nu, r):
        (v, e), (ell, e2) = _linear()(nu, r)
        return ((1.2 + 4 * (v - 1.2), e), (5.0 + 4 * (ell - 5.0), e2))
    gentle = posterior(_linear(), (1.2, 5.0), (0.01, 0.05), BOX)
    sharp = posterior(steep, (1.2, 5.0), (0.01, 0.05), BOX)
    assert abs(sharp.evidence / gentle.evidence - 1 / 16) < 0.1 / 16
    mixed = mixture({5.0: gentle, 50.0: sharp}, {5.0: 1 / 3, 50.0: 2 / 3})
    share = np.mean(mixed.samples["ca_b"] == 50.0)
    expected = (2 / 3 / 16) / (1 / 3 + 2 / 3 / 16)
    assert abs(share - expected) < 0.02, (share, expected)


def test_shortest_interval_of_a_skewed_sample_keeps_its_edge():
    """Exponential draws: the shortest 95 % interval is [0, -ln 0.05] (closed form)."""
    v = np.random.default_rng(0).exponential(size=20000)
    lo, hi = shortest_interval(v, 0.95)
    assert lo < 1e-3 and abs(hi + math.log(0.05)) < 0.1
