"""Hypothesis strategies and signal generators shared by the test modules."""

import numpy as np
from hypothesis import strategies as st

from pihyst.model import ClassicalPI, MultislopePI, PiecewiseLinearPI

U = 150.0


@st.composite
def thresholds(draw, r_max, max_ops=8):
    k = draw(st.integers(1, max_ops))
    r = draw(st.lists(st.floats(0.0, r_max, allow_nan=False), min_size=k, max_size=k,
                      unique=True))
    return np.sort(np.array(r))


def weights(k, nonneg=True):
    lo = 0.0 if nonneg else -1.0
    return st.lists(st.floats(lo, 1.0, allow_nan=False), min_size=k, max_size=k).map(np.array)


@st.composite
def classical_models(draw, nonneg=True, max_ops=8):
    r = draw(thresholds(U, max_ops))
    return ClassicalPI(r, draw(weights(r.size, nonneg)), offset=draw(st.floats(-5, 5)))


@st.composite
def multislope_models(draw, nonneg=True, max_ops=8, paper_shape=False):
    if paper_shape:
        a, b, h = 0.8, 1.2, 0.5
    else:
        a = draw(st.floats(0.5, 0.95))
        b = draw(st.floats(1.05, 1.6))
        h = draw(st.floats(0.0, 1.0))
    r_max = (1 - a) * U / (1 - a * h)
    r = draw(thresholds(r_max, max_ops))
    return MultislopePI(r, draw(weights(r.size, nonneg)), a=a, b=b, h=h,
                        offset=draw(st.floats(-5, 5)))


@st.composite
def pwl_models(draw, nonneg=True, max_ops=4):
    """Random non-decreasing polylines R <= F on a shared grid over [0, U]."""
    k = draw(st.integers(1, max_ops))
    rising, falling = [], []
    for _ in range(k):
        n = draw(st.integers(2, 6))
        inner = draw(st.lists(st.floats(1.0, U - 1.0), min_size=n - 2, max_size=n - 2,
                              unique=True))
        x = np.concatenate([[0.0], np.sort(inner), [U]])
        x = np.unique(x)
        rise = np.cumsum(draw(st.lists(st.floats(0.0, 40.0), min_size=x.size,
                                       max_size=x.size))) - 20.0
        gap = np.array(draw(st.lists(st.floats(0.0, 30.0), min_size=x.size, max_size=x.size)))
        fall = np.maximum.accumulate(rise + gap)
        rising.append((x, rise))
        falling.append((x, fall))
    return PiecewiseLinearPI(rising, falling, draw(weights(k, nonneg)), input_range=(0.0, U))


def any_model(nonneg=True):
    return st.one_of(classical_models(nonneg), multislope_models(nonneg), pwl_models(nonneg))


@st.composite
def signals(draw, lo=0.0, hi=U, min_size=1, max_size=200):
    """Voltage sequences in [lo, hi]: random points, so many reversals and minor loops."""
    values = draw(st.lists(st.floats(lo, hi, allow_nan=False), min_size=min_size,
                           max_size=max_size))
    return np.array(values)


def random_walk(n, seed, lo=0.0, hi=U, step=5.0):
    """A reflected random walk in [lo, hi]: many minor loops at every scale."""
    rng = np.random.default_rng(seed)
    u = np.empty(n)
    x = rng.uniform(lo, hi)
    for i in range(n):
        x += rng.normal(0.0, step)
        x = lo + abs(x - lo)
        x = hi - abs(hi - x)
        x = min(max(x, lo), hi)
        u[i] = x
    return u


def triangles(n_cycles=2, lo=0.0, hi=U, n_per_leg=150):
    up = np.linspace(lo, hi, n_per_leg + 1)
    cycle = np.concatenate([up, up[-2::-1]])
    return np.concatenate([cycle] + [cycle[1:]] * (n_cycles - 1))
