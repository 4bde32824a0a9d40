"""The product-form kernel fit (pihyst.identify._kernel_product) and its use by kp."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst import fit
from pihyst.identify import KrasnoselskiiPokrovskii
from pihyst.identify._gram import Gram
from pihyst.identify._kernel_product import product_density_fit
from pihyst.sim._preisach import Preisach
from pihyst.sim.signals import decaying_triangles, triangle


def _problem(grid, seed, product=True, noise=0.0):
    """A Gram of random kernel outputs (and an offset column) whose data come from
    weights of product form (or not), a smooth diagonal and an offset."""
    rng = np.random.default_rng(seed)
    pairs = KrasnoselskiiPokrovskii(grid).pairs()
    f, g = rng.uniform(0.2, 2.0, grid), rng.uniform(0.2, 2.0, grid)
    w = np.array([0.5 + 0.1 * i if i == j else
                  (f[i] * g[j] if product else rng.uniform(0.0, 4.0)) for i, j in pairs])
    x = np.r_[w, rng.normal()]
    A = np.c_[rng.uniform(0.0, 1.0, (400, len(pairs))), np.ones(400)]
    d = A @ x + noise * rng.normal(size=400)
    gram = Gram(A.T @ A, A.T @ d, float(d @ d), 400)
    lower = np.r_[np.zeros(len(pairs)), -np.inf]
    upper = np.full(len(pairs) + 1, np.inf)
    return pairs, gram, lower, upper


def _off_diagonal(pairs, x, grid):
    W = np.full((grid, grid), np.nan)
    for k, (i, j) in enumerate(pairs):
        if i < j:
            W[i, j] = x[k]
    return W


@settings(max_examples=15, deadline=None)
@given(grid=st.integers(3, 7), seed=st.integers(0, 10_000), product=st.booleans())
def test_the_fit_is_of_product_form_and_admissible(grid, seed, product):
    pairs, gram, lower, upper = _problem(grid, seed, product)
    x = product_density_fit(gram, pairs, grid, lower, upper)
    n = len(pairs)
    assert np.all(x[:n] >= -1e-9)
    # every 2 x 2 minor of the off-diagonal weights vanishes: w_ij = f_i g_j
    W = _off_diagonal(pairs, x, grid)
    for i in range(grid):
        for j in range(i + 2, grid):
            for k in range(i + 1, j):
                for m in range(j + 1, grid):
                    a, b, c, d = W[i, j], W[i, m], W[k, j], W[k, m]
                    assert abs(a * d - b * c) <= 1e-6 * max(1.0, abs(a * d), abs(b * c))


@settings(max_examples=10, deadline=None)
@given(grid=st.integers(3, 6), seed=st.integers(0, 10_000))
def test_data_of_product_form_are_fitted_closely(grid, seed):
    # the alternating fit is not convex; from a constant density it still finds
    # weights that are of its form (exact data: measured to 1e-7 relative)
    pairs, gram, lower, upper = _problem(grid, seed, product=True)
    cols = list(range(len(pairs) + 1))
    x = product_density_fit(gram, pairs, grid, lower, upper, smoothing=0.0)
    baseline = gram.rms(cols, np.zeros(len(cols)))
    assert gram.rms(cols, x) <= 1e-4 * baseline


def test_kp_reports_the_product_fit_only_when_the_record_has_no_minor_loops():
    h = Preisach(150.0, [(60.0, -1.0, 2.0)], reversible=(10.0, 4.0))
    for signal, expect in ((triangle(period_s=8.0, n_cycles=2, dt=2e-3), True),
                           (decaying_triangles(period_s=8.0, dt=2e-3), False)):
        _, u = signal
        h.reset()
        res = fit(u, h.run(u), family="kp", input_range=(0.0, 150.0), delay=0)
        prod = res.report.family("kp")["regularization"]["product_density"]
        assert (prod is not None) == expect
        reg = res.report.family("kp")["regularization"]
        if expect:       # a product-form density was found and judged
            assert prod["held_back_rms"] > 0 and reg["penalty_shape"] == "separable"


@settings(max_examples=10, deadline=None)
@given(grid=st.integers(3, 6), seed=st.integers(0, 10_000))
def test_equality_constraints_hold_exactly_after_the_joint_solve(grid, seed):
    # a model made to pass through given points ('through'): the least-squares stage
    # ignores them, the closing alternating sweeps restore them
    pairs, gram, lower, upper = _problem(grid, seed, product=False, noise=0.1)
    rng = np.random.default_rng(seed)
    A_eq = np.c_[rng.uniform(0.0, 1.0, (2, len(pairs))), np.ones(2)]
    b_eq = A_eq @ np.r_[np.full(len(pairs), 0.5), 0.0]
    x = product_density_fit(gram, pairs, grid, lower, upper, A_eq=A_eq, b_eq=b_eq)
    assert np.allclose(A_eq @ x, b_eq, atol=1e-7 * max(1.0, np.abs(b_eq).max()))


def test_constraints_no_product_meets_give_none():
    # w_01 = 1, w_02 = 0, w_12 = 1: f0 g1 = 1 and f0 g2 = 0 force g2 = 0, so f1 g2 = 0
    pairs, gram, lower, upper = _problem(3, 0)
    rows = np.zeros((3, len(pairs) + 1))
    for r, p in enumerate(((0, 1), (0, 2), (1, 2))):
        rows[r, pairs.index(p)] = 1.0
    assert product_density_fit(gram, pairs, 3, lower, upper, A_eq=rows,
                               b_eq=np.array([1.0, 0.0, 1.0])) is None
