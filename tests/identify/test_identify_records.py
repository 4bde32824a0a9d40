"""Cutting a record into settle / fitted / held-back cycles (pihyst.identify._cycles)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst._reference import turning_points_loop
from pihyst.exceptions import FitError
from pihyst.identify._cycles import checked_signals, layout, starts_at_rest, turning_points


def ramps(levels, n=20):
    levels = np.asarray(levels, dtype=float)
    return np.concatenate([np.linspace(a, b, n, endpoint=False) for a, b in
                           zip(levels[:-1], levels[1:])] + [levels[-1:]])



@settings(max_examples=200, deadline=None)
@given(levels=st.lists(st.floats(-50, 50), min_size=1, max_size=15),
       n=st.integers(1, 40), noise=st.sampled_from([0.0, 0.1, 1.0, 5.0]),
       tol=st.sampled_from([0.0, 0.5, 1.0, 3.0]), seed=st.integers(0, 10**6),
       quantum=st.sampled_from([0.0, 1.0]))
def test_turning_points_match_the_per_sample_loop(levels, n, noise, tol, seed, quantum):
    v = ramps(levels, n=n)
    v = v + noise * np.random.default_rng(seed).normal(size=v.size)
    if quantum:                          # plateaus and ties: first-occurrence extremes
        v = np.round(v / quantum) * quantum
    assert turning_points(v, tol) == turning_points_loop(v, tol)


def test_turning_points_match_the_loop_on_long_noisy_signals():
    rng = np.random.default_rng(0)
    for k in range(5):
        v = np.cumsum(rng.normal(size=20000)) + 30 * np.sin(np.arange(20000) / (50 + 300 * k))
        for tol in (0.5, 3.0, 20.0):
            assert turning_points(v, tol) == turning_points_loop(v, tol)
    assert turning_points(np.array([1.0]), 0.1) == [] == turning_points_loop(np.array([1.0]),
                                                                             0.1)
    flat = np.zeros(1000)
    assert turning_points(flat, 0.0) == [] == turning_points_loop(flat, 0.0)


def test_turning_points_of_a_known_signal():
    v = ramps([0, 10, 2, 8, 0], n=10)
    pts = turning_points(v, 0.5)
    assert pts == [(10, 1), (20, -1), (30, 1)]


def test_small_wiggles_are_not_reversals():
    v = ramps([0, 10, 0], n=50)
    v = v + 0.01 * np.sin(np.arange(v.size) * 2.0)
    assert [k for _, k in turning_points(v, 0.1)] == [1]


@settings(max_examples=50, deadline=None)
@given(levels=st.lists(st.floats(0, 100), min_size=3, max_size=12))
def test_turning_points_alternate(levels):
    v = ramps(levels)
    pts = turning_points(v, 1.0)
    kinds = [k for _, k in pts]
    assert all(a != b for a, b in zip(kinds[:-1], kinds[1:]))
    for i, k in pts:
        # a maximum is the largest value between its neighbours, a minimum the smallest
        lo, hi = max(i - 1, 0), min(i + 2, v.size)
        assert (v[i] >= v[lo:hi].max()) if k > 0 else (v[i] <= v[lo:hi].min())


def test_alternate_holdout_on_decaying_triangles():
    v = ramps([0, 100, 0, 70, 0, 50, 0, 35, 0, 25, 0])
    lay = layout(v, 100.0, settle=False, holdout="alternate")
    roles = [r for *_, r in lay.segments]
    # one major cycle (fitted) and four minor ones: 1st and 3rd held back
    assert roles == ["fit", "held_back", "fit", "held_back", "fit"]
    assert lay.n_cycles == 5 and lay.n_minor == 4
    covered = np.concatenate([np.arange(a, z) for a, z, _ in lay.segments])
    assert np.array_equal(covered, np.arange(v.size))


def test_settle_ends_at_the_first_valley_after_both_ends():
    v = ramps([50, 100, 0, 100, 0, 100, 0])
    lay = layout(v, 100.0, settle=True, holdout="alternate")
    assert lay.segments[0][2] == "settle"
    assert v[lay.settle_end - 1] == 0.0
    assert lay.settle_end == 41
    assert [r for *_, r in lay.segments[1:]] == ["fit", "held_back"]


def test_fraction_holdout_cuts_at_a_cycle_boundary():
    v = ramps([0, 100] * 8 + [0])
    lay = layout(v, 100.0, settle=False, holdout=0.25)
    held = [(a, z) for a, z, r in lay.segments if r == "held_back"]
    assert len(held) == 2
    assert v[held[0][0] - 1] == 0.0        # the cut follows a valley
    with pytest.raises(ValueError):
        layout(v, 100.0, settle=False, holdout=1.5)


def test_no_holdout():
    v = ramps([0, 100, 0, 100, 0])
    lay = layout(v, 100.0, settle=False, holdout=None)
    assert lay.count("held_back") == 0 and lay.holdout == "none"


def test_rest_detection():
    assert starts_at_rest(np.array([0.0, 5, 10]), 10.0)
    assert not starts_at_rest(np.array([5.0, 10, 0]), 10.0)


def test_checked_signals_errors():
    with pytest.raises(FitError, match="input sample 3"):
        checked_signals([0, 1, 2, np.inf] + [0] * 30, np.zeros(34))
    with pytest.raises(FitError, match="one-dimensional"):
        checked_signals(np.zeros((30, 2)), np.zeros(30))
    with pytest.raises(FitError, match="sequence of numbers"):
        checked_signals(["a"] * 30, np.zeros(30))
    with pytest.raises(FitError, match="output is constant"):
        checked_signals(np.arange(30.0), np.ones(30))
