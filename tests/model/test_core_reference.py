"""The C core against its pure-NumPy twin (pihyst._reference) on many signals."""

import numpy as np
import pytest

from pihyst import _core, _reference

from strategies import U, random_walk, triangles

SIGNALS = {
    "random_walk": random_walk(3000, seed=1),
    "random_walk_small_steps": random_walk(3000, seed=2, step=0.5),
    "triangles": triangles(3),
    "decaying_triangles": np.concatenate(
        [np.r_[np.linspace(0, a, 40), np.linspace(a, 0, 40)] for a in (150, 120, 90, 60, 30)]),
    "constant": np.full(50, 42.0),
    "one_sample": np.array([77.0]),
    "limits": np.array([0.0, U, 0.0, U, U, 0.0]),
    "uniform_noise": np.random.default_rng(3).uniform(0, U, 2000),
}


def classical_params(k):
    r = np.linspace(0.0, U, k, endpoint=k == 1) if k > 1 else np.array([0.0])
    if k > 1:
        r[-1] = U  # threshold at the top of the range
    w = np.random.default_rng(k).uniform(-0.2, 0.5, k)
    return {"family": "classical", "thresholds": r, "weights": w}


def multislope_params(k):
    r = np.linspace(0.0, 50.0, k) if k > 1 else np.array([50.0])  # 50 V: the limit
    w = np.random.default_rng(k + 100).uniform(0.0, 0.5, k)
    return {"family": "multislope", "thresholds": r, "weights": w, "shape": (U, 0.8, 1.2, 0.5)}


def pwl_params(k):
    rng = np.random.default_rng(k + 200)
    rising, falling = [], []
    for _ in range(k):
        x = np.r_[0.0, np.sort(rng.uniform(1, U - 1, 3)), U]
        r = np.cumsum(rng.uniform(0, 30, x.size)) - 10
        f = np.maximum.accumulate(r + rng.uniform(0, 25, x.size))
        rising.append((x, r))
        falling.append((x, f))
    return {"family": "pwl", "thresholds": None, "weights": rng.uniform(0, 1, k),
            "rising": rising, "falling": falling}


PARAMS = [(f.__name__.split("_")[0], k, f(k)) for f in (classical_params, multislope_params)
          for k in (1, 4, 16, 64)] + [("pwl", k, pwl_params(k)) for k in (1, 3, 8)]


def banks(params, initial_state=None):
    args = dict(params, offset=0.25, u_min=0.0, u_max=U, initial_state=initial_state)
    return _core.Bank(**args), _reference.Bank(**args)


@pytest.mark.parametrize("signal", SIGNALS, ids=str)
@pytest.mark.parametrize("family,k,params", PARAMS, ids=[f"{f}-K{k}" for f, k, _ in PARAMS])
def test_run_matches_reference(family, k, params, signal):
    fast, slow = banks(params)
    u = SIGNALS[signal]
    np.testing.assert_allclose(fast.run(u), slow.run(u), rtol=1e-12, atol=1e-12,
                               err_msg=f"{family} K={k} on {signal}")
    np.testing.assert_allclose(fast.state, slow.state, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("family,k,params", PARAMS, ids=[f"{f}-K{k}" for f, k, _ in PARAMS])
def test_operators_gram_envelopes_match_reference(family, k, params):
    u = SIGNALS["random_walk"][:500]
    d = np.sin(u)
    state0 = np.random.default_rng(0).uniform(0, 20, k)
    fast, slow = banks(params, initial_state=state0)
    np.testing.assert_allclose(fast.operators(u), slow.operators(u), rtol=1e-12, atol=1e-12)
    fast.reset(state0)
    slow.reset(state0)
    for got, want in zip(fast.gram(u, d), slow.gram(u, d)):
        np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-9)
    for u0 in (0.0, 13.7, 75.0, 149.9, U):
        for got, want in zip(fast.envelopes(u0), slow.envelopes(u0)):
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("family,k,params", PARAMS[:4], ids=[f"K{k}" for _, k, _ in PARAMS[:4]])
def test_step_matches_reference(family, k, params):
    fast, slow = banks(params)
    for v in SIGNALS["random_walk"][:300]:
        assert fast.step(v) == pytest.approx(slow.step(v), rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("family,k,params", PARAMS, ids=[f"K{k}" for _, k, _ in PARAMS])
def test_blocked_gram_matches_the_c_accumulation(family, k, params):
    """Bank.gram (operator matrix in blocks, BLAS updates) against pihyst_model_gram, for
    block sizes that split the record anywhere, and the state it leaves."""
    u = SIGNALS["random_walk"][:700]
    d = np.cos(u)
    fast, _ = banks(params)
    want = fast.gram(u, d)
    state_after = fast.state
    for block in (1, 7, 64, 700, 5000):
        fast.reset()
        got = fast.gram(u, d, block=block)
        for g, w in zip(got, want):
            np.testing.assert_allclose(g, w, rtol=1e-12, atol=1e-12 * len(u))
        assert np.array_equal(got[0], got[0].T)
        assert np.array_equal(fast.state, state_after)
    with pytest.raises(ValueError):
        fast.gram(u, d, block=0)


@pytest.mark.parametrize("family,k,params", PARAMS, ids=[f"K{k}" for _, k, _ in PARAMS])
@pytest.mark.parametrize("seed", range(3))
def test_segment_grams_are_the_per_segment_grams_summed(family, k, params, seed):
    """Bank.gram_segments (one call for a cut record) against gram() per segment, added
    up per role in order, and run() over the settling segments: the same G, rhs and sums
    bit for bit, the data sums to rounding, the same state after."""
    rng = np.random.default_rng(seed)
    u = SIGNALS["random_walk"][:900]
    d = np.cos(u) + rng.normal(0, 0.1, u.size)
    cuts = np.unique(np.r_[0, np.sort(rng.integers(0, u.size, 12)), u.size])
    starts, stops = cuts[:-1], cuts[1:]
    roles = rng.integers(0, 3, starts.size)
    fast, _ = banks(params)
    got = fast.gram_segments(u, d, starts, stops, roles)
    after = fast.state
    fast.reset()
    want = [[np.zeros((k, k)), np.zeros(k), np.zeros(k), 0.0, 0.0, 0] for _ in range(2)]
    for a, z, r in zip(starts, stops, roles):
        if r == 0:
            fast.run(u[a:z])
            continue
        acc = want[r - 1]
        for i, part in enumerate(fast.gram(u[a:z], d[a:z])):
            acc[i] = acc[i] + part
        acc[3] += float(d[a:z].sum())
        acc[4] += float(d[a:z] @ d[a:z])
        acc[5] += int(z - a)
    assert np.array_equal(fast.state, after)
    for g, w in zip(got, want):
        for i in range(3):
            assert np.array_equal(g[i], w[i])
        np.testing.assert_allclose(g[3:5], w[3:5], rtol=1e-12, atol=1e-9)
        assert g[5] == w[5]
    with pytest.raises(ValueError, match="segment 0"):
        fast.gram_segments(u, d, [5], [4], [1])
    with pytest.raises(ValueError, match="one entry per segment"):
        fast.gram_segments(u, d, [0, 5], [5], [1])
