"""Feasible periodic drives: within the limits and the slew limit round the cycle."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pihyst.learn import cyclic_steps, feasible_periodic

drives = arrays(float, st.integers(1, 80),
               elements=st.floats(-1e4, 1e4) | st.sampled_from([np.nan, np.inf, -np.inf]))


@settings(max_examples=200)
@given(drives, st.floats(-100, 100), st.floats(1e-3, 300), st.floats(1e-4, 500))
def test_any_drive_is_made_feasible(u, lo, width, step):
    hi = lo + width
    v = feasible_periodic(u, lo, hi, step)
    assert v.shape == u.shape
    assert np.all(v >= lo) and np.all(v <= hi)
    assert np.all(cyclic_steps(v) <= step)


@given(drives, st.floats(-100, 100), st.floats(1e-3, 300))
def test_without_a_slew_limit_it_is_the_clipped_drive(u, lo, width):
    expected = np.clip(np.where(np.isnan(u), lo, u), lo, lo + width)     # NaN: the low limit
    np.testing.assert_array_equal(feasible_periodic(u, lo, lo + width), expected)


def test_a_feasible_drive_is_left_alone():
    u = 75 + 50 * np.sin(2 * np.pi * np.arange(100) / 100)
    np.testing.assert_array_equal(feasible_periodic(u, 0, 150, 4.0), u)


def test_the_wrap_of_the_cycle_counts():
    u = np.linspace(0.0, 99.0, 100)          # 1 V per step, but 99 V from the end to the start
    v = feasible_periodic(u, 0.0, 150.0, 2.0)
    assert np.all(cyclic_steps(v) <= 2.0)
