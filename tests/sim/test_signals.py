"""Test signals (pihyst.sim.signals)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst import paper
from pihyst.sim import signals
from pihyst.sim.signals import decaying_triangles, random_ramps, sine, staircase, triangle

ALL = [triangle, sine, decaying_triangles, random_ramps, staircase]


def extrema(u):
    """Values at the turning points of a piecewise-monotone signal."""
    d = np.sign(np.diff(u))
    d = d[d != 0]
    keep = np.flatnonzero(d[1:] != d[:-1])
    moving = np.flatnonzero(np.diff(u) != 0)
    return u[moving[keep] + 1]


def test_the_papers_triangle():
    t, u = triangle()
    assert t[0] == 0 and t[-1] == pytest.approx(300.0) and np.allclose(np.diff(t), 0.1)
    assert u[0] == 0 and u[-1] == 0 and u.max() == 150.0 and u[np.argmax(u)] == 150.0
    assert t[np.argmax(u)] == pytest.approx(150.0)
    np.testing.assert_allclose(np.diff(u[:1501]), 0.1, atol=1e-9)    # 1 V/s up
    np.testing.assert_allclose(np.diff(u[1500:]), -0.1, atol=1e-9)   # 1 V/s down


def test_triangle_cycles_and_custom_range():
    t, u = triangle(u_min=5.0, u_max=25.0, period_s=10.0, n_cycles=3, dt=0.5)
    assert t[-1] == 30.0 and u.min() == 5.0 and u.max() == 25.0
    np.testing.assert_array_equal(extrema(u), [25.0, 5.0, 25.0, 5.0, 25.0])


def test_sine_starts_at_its_minimum():
    t, u = sine(u_min=-10.0, u_max=30.0, period_s=20.0, n_cycles=2, dt=0.01)
    assert u[0] == pytest.approx(-10.0) and u[1000] == pytest.approx(30.0)
    np.testing.assert_allclose(u, 10 - 20 * np.cos(2 * np.pi * t / 20.0), atol=1e-12)


def test_decaying_triangles_make_nested_minor_loops():
    t, u = decaying_triangles(n_triangles=4, ratio=0.6, dt=0.1)
    np.testing.assert_allclose(extrema(u), [150, 0, 90, 0, 54, 0, 32.4], atol=1e-9)
    rate = np.abs(np.diff(u)).max() / 0.1
    assert rate == pytest.approx(1.0, rel=0.05)          # the triangle's slope throughout
    assert u[-1] == 0.0


def test_random_ramps_are_seeded_and_reverse_inside_the_range():
    t1, u1 = random_ramps(n_ramps=30, seed=11)
    t2, u2 = random_ramps(n_ramps=30, seed=11)
    t3, u3 = random_ramps(n_ramps=30, seed=12)
    np.testing.assert_array_equal(u1, u2)
    assert u1.size != u3.size or np.any(u1 != u3)
    ext = extrema(u1)
    assert ext.size >= 10
    assert np.sum((ext > 5) & (ext < 145)) >= 8          # reversals well inside
    assert u1[0] == 0 and u1.min() >= 0 and u1.max() <= 150
    assert np.abs(np.diff(u1)).max() <= 1.0 * 0.1 + 1e-9  # never faster than the rate


def test_random_ramps_rate_option():
    t, u = random_ramps(n_ramps=5, rate=10.0, dt=0.01, seed=0)
    assert np.abs(np.diff(u)).max() <= 10.0 * 0.01 + 1e-9


def test_staircase_up_and_down():
    t, u = staircase(n_steps=4, step_s=5.0, dt=1.0)
    levels = u[::5]
    np.testing.assert_allclose(levels, [0, 37.5, 75, 112.5, 150, 112.5, 75, 37.5, 0])
    assert t.size == 45
    t, u = staircase(n_steps=4, step_s=5.0, dt=1.0, down=False)
    assert u[-1] == 150.0 and t.size == 25


@settings(max_examples=60, deadline=None)
@given(fn=st.sampled_from(ALL), lo=st.floats(-200, 200), span=st.floats(0.1, 300),
       dt=st.sampled_from([0.05, 0.1, 0.5, 1.0]))
def test_every_signal_stays_in_range_and_starts_at_u_min(fn, lo, span, dt):
    t, u = fn(u_min=lo, u_max=lo + span, dt=dt)
    assert t.shape == u.shape and t[0] == 0
    np.testing.assert_allclose(np.diff(t), dt, rtol=1e-9)
    assert u[0] == pytest.approx(lo, abs=1e-9 * max(1.0, abs(lo)))
    assert u.min() >= lo and u.max() <= lo + span
    assert np.all(np.isfinite(u))


@pytest.mark.parametrize("fn", ALL)
@pytest.mark.parametrize("kwargs, message", [
    ({"u_min": 10.0, "u_max": 10.0}, "u_max must be above u_min"),
    ({"dt": 0.0}, "dt must be positive"),
    ({"u_max": float("nan")}, "u_max must be a finite number"),
])
def test_bad_parameters_are_rejected(fn, kwargs, message):
    with pytest.raises(ValueError, match=message):
        fn(**kwargs)


@pytest.mark.parametrize("call, message", [
    (lambda: triangle(period_s=-1.0), "period_s must be a positive number"),
    (lambda: sine(n_cycles=0), "n_cycles must be a whole number >= 1"),
    (lambda: decaying_triangles(ratio=1.0), "ratio must be between 0 and 1"),
    (lambda: random_ramps(n_ramps=2.5), "n_ramps must be a whole number"),
    (lambda: random_ramps(rate=0.0), "rate must be a positive number"),
    (lambda: staircase(step_s=0.0), "step_s must be a positive number"),
    (lambda: staircase(step_s=0.01, dt=1.0), "a step of 0.01 s is shorter than dt = 1 s"),
])
def test_bad_shape_parameters_are_rejected(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_default_triangle_is_the_papers_drive():
    t, u = signals.triangle()
    peak = int(np.argmax(u))
    assert u[0] == paper.DRIVE_U_MIN_V and u[-1] == paper.DRIVE_U_MIN_V
    assert u[peak] == paper.DRIVE_U_MAX_V
    assert t[peak] == pytest.approx(paper.DRIVE_PERIOD_S / 2)
    assert t[-1] == pytest.approx(paper.DRIVE_PERIOD_S)
