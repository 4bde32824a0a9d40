"""Feedforward compensation of an amplitude-scheduled state-space model
(pihyst.dynamics._compensate_scheduled)."""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst.dynamics import (
    ScheduledCompensation,
    ScheduledStateSpace,
    StateSpace,
    StateSpaceHammerstein,
    compensate_mimo,
    compensate_scheduled,
)
from pihyst.dynamics._compensate_scheduled import (
    output_bound,
    periodic_response,
    periodic_schedule,
)
from pihyst.exceptions import InvalidArgumentError
from pihyst.model import ClassicalPI

N = 200            # samples per period
WINDOW = 50.0      # of the schedule
SETTLE = 40        # periods played before the one compared (the schedule and modes settle)


def softening_3x3():
    """3 inputs, 3 outputs, coupled; anchors at 0.5, 1.5 and 3 (RMS): from the first to
    the last the two resonances move down by 15 % and 25 %, lose damping, and the gain
    rises by a third (as a piezo's compliance grows with the drive)."""
    amplitudes = np.array([0.5, 1.5, 3.0])
    s = np.array([0.0, 0.5, 1.0])[:, None]               # 0 at the first anchor, 1 at the last
    theta = np.array([0.25, 0.9]) * (1 - np.array([0.15, 0.25]) * s)
    radius = np.array([0.93, 0.9]) + np.array([0.03, 0.05]) * s
    poles = radius * np.exp(1j * theta)
    c = np.array([[[0.10, 0.03 + 0.02j, 0.00], [0.02j, 0.08, 0.03]]], complex)
    b = np.array([[[1.0, 0.2, 0.1], [0.3j, 1.0, 0.4]]], complex)
    gain = 1 + s[:, :, None] / 3
    D = np.array([[0.6, 0.1, 0.0], [0.05, 0.5, 0.1], [0.0, 0.1, 0.7]])[None] * gain
    return ScheduledStateSpace(amplitudes, poles, np.repeat(c, 3, 0) * gain,
                               np.repeat(b, 3, 0), [[0.6], [0.65], [0.7]],
                               np.repeat([[[0.1, 0.0, 0.2]]], 3, 0),
                               np.repeat([[[0.3, 0.3, 0.3]]], 3, 0), D, window=WINDOW)


def non_minimum_phase():
    """SISO, G(z) = D + c b / (z - lambda) with D < 0: a zero outside the unit circle
    (at about 3.8 at the first anchor), moving with amplitude."""
    return ScheduledStateSpace([0.2, 1.0], np.zeros((2, 0)), np.zeros((2, 0, 1)),
                               np.zeros((2, 0, 1)), [[0.5], [0.6]], [[[1.0]], [[1.1]]],
                               [[[1.0]], [[1.0]]], [[[-0.3]], [[-0.35]]], window=WINDOW)


def smooth_drive(m, level, n=N):
    """A smooth periodic drive of m inputs with RMS about ``level``."""
    t = np.arange(n) / n
    cols = [np.sin(2 * np.pi * (k + 1) * t + k) + 0.5 * np.cos(2 * np.pi * (k + 3) * t)
            for k in range(m)]
    return level * np.column_stack(cols) / np.sqrt(0.625)


def steady(model, u):
    """The model's output for ``u`` repeated, its last period (model.predict from rest)."""
    return model.predict(np.tile(u, (SETTLE, 1)))[-u.shape[0]:]


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), level=st.floats(0.05, 5.0))
def test_periodic_response_is_the_steady_state_of_predict(seed, level):
    """The periodic solution against model.predict played until it settles."""
    model = softening_3x3()
    u = level * np.random.default_rng(seed).normal(size=(N, 3))
    np.testing.assert_allclose(periodic_schedule(model, u),
                               model.schedule(np.tile(u, (SETTLE, 1)))[-N:], rtol=1e-9)
    y = steady(model, u)
    np.testing.assert_allclose(periodic_response(model, u), y, atol=1e-9 * np.ptp(y))


@pytest.mark.parametrize("exponent", [0.0, 0.5, 2.0])
def test_the_compensation_follows_the_schedules_shape(exponent):
    """Interpolated in log a, sqrt a or a^2 between the anchors: the compensator runs the
    model's own schedule, whatever its shape."""
    model = dataclasses.replace(softening_3x3(), exponent=exponent)
    desired = steady(model, smooth_drive(3, 1.0))
    res = compensate_scheduled(model, desired, u_min=-20.0, u_max=20.0)
    assert res.converged and not res.saturated
    assert np.max(np.abs(steady(model, res.voltage) - desired)) < 1e-8 * np.ptp(desired)


@pytest.mark.parametrize("level", [0.3, 1.0, 2.2, 4.0])
def test_the_model_follows_its_compensation_at_every_amplitude(level):
    """Below, between and beyond the anchors; reachable by design. The compensator of one
    linear model (the scheduled model at the middle anchor) is 100x worse or more
    (measured: 3-7 % of the range against 1e-11 or less)."""
    model = softening_3x3()
    desired = steady(model, smooth_drive(3, level))
    res = compensate_scheduled(model, desired, u_min=-20.0, u_max=20.0)
    assert isinstance(res, ScheduledCompensation)
    assert res.converged and not res.saturated and res.voltage.shape == (N, 3)
    y = steady(model, res.voltage)
    error = np.max(np.abs(y - desired))
    assert error < 1e-8 * np.ptp(desired)
    linear = StateSpaceHammerstein(
        tuple(ClassicalPI([0.0], [1.0], input_range=(-20.0, 20.0)) for _ in range(3)),
        model.at(model.amplitudes[1]))
    u_lin, _, _ = compensate_mimo(linear, desired, u_min=-20.0, u_max=20.0)
    assert np.max(np.abs(steady(model, u_lin) - desired)) > max(100 * error, 0.01 * np.ptp(desired))


@pytest.mark.parametrize("level", [0.1, 0.6, 2.0])
def test_non_minimum_phase_dynamics_are_inverted_exactly(level):
    """A zero outside the unit circle: the whole period is the preview."""
    model = non_minimum_phase()
    desired = steady(model, smooth_drive(1, level))
    res = compensate_scheduled(model, desired, u_min=-10.0, u_max=10.0)
    assert res.converged and not res.saturated
    assert np.max(np.abs(steady(model, res.voltage) - desired)) < 1e-8 * np.ptp(desired)


@pytest.mark.parametrize("top", [8.0, 20.0])
def test_a_gain_that_grows_faster_than_the_amplitude_still_converges(top):
    """The gain rises ``top``-fold from the first anchor to the second (6x the amplitude):
    the plain fixed point on the schedule oscillates and diverges there (measured: from
    top = 8); the mixed one converges."""
    model = ScheduledStateSpace([0.5, 3.0], [[0.9 * np.exp(0.3j)], [0.95 * np.exp(0.2j)]],
                                [[[0.1]], [[0.1 * top]]], [[[1.0]], [[1.0]]],
                                np.zeros((2, 0)), np.zeros((2, 0, 1)), np.zeros((2, 0, 1)),
                                [[[1.0]], [[top]]], window=WINDOW)
    desired = steady(model, smooth_drive(1, 1.5))
    res = compensate_scheduled(model, desired, u_min=-100.0, u_max=100.0)
    assert res.converged and not res.saturated
    assert np.max(np.abs(steady(model, res.voltage) - desired)) < 1e-8 * np.ptp(desired)


def test_compensate_mimo_takes_a_scheduled_model():
    model = softening_3x3()
    desired = steady(model, smooth_drive(3, 1.0))
    u, h, results = compensate_mimo(model, desired, u_min=-20.0, u_max=20.0)
    np.testing.assert_array_equal(u, h)
    np.testing.assert_array_equal(
        u, compensate_scheduled(model, desired, u_min=-20.0, u_max=20.0).voltage)
    assert results[0].converged


def test_unreachable_voltages_are_clipped_and_said():
    """The exact voltages need 3x the limits: clipped, saturated, the error reported."""
    model = softening_3x3()
    u_true = smooth_drive(3, 2.0)
    desired = steady(model, u_true)
    limit = np.max(np.abs(u_true)) / 3
    res = compensate_scheduled(model, desired, u_min=-limit, u_max=limit)
    assert res.saturated and not res.converged
    assert np.all(np.abs(res.voltage) <= limit)
    assert res.rms_error == pytest.approx(
        np.sqrt(np.mean((steady(model, res.voltage) - desired) ** 2)), rel=1e-6)
    # better than clipping the exact voltages
    clipped = np.clip(compensate_scheduled(model, desired, u_min=-50, u_max=50).voltage,
                      -limit, limit)
    assert res.rms_error < np.sqrt(np.mean((steady(model, clipped) - desired) ** 2))


def small_model():
    """2 x 2, for the fast property tests."""
    model = softening_3x3()
    return ScheduledStateSpace(model.amplitudes, model.poles, model.c[:, :, :2],
                               model.b[:, :, :2], model.real_poles, model.real_c[:, :, :2],
                               model.real_b[:, :, :2], model.D[:, :2, :2], window=10.0)


@settings(max_examples=60, deadline=None)
@given(data=st.data(), n=st.integers(2, 24))
def test_limits_hold_whatever_the_desired(data, n):
    """Any finite desired, any limits: the voltages stay within the limits, or a one-line
    error (unreachable by the model's bound) and nothing else."""
    model = small_model()
    lo = np.array(data.draw(st.lists(st.floats(-100, 100), min_size=2, max_size=2)))
    width = np.array(data.draw(st.lists(st.floats(1e-3, 200), min_size=2, max_size=2)))
    hi = lo + width
    bound = output_bound(model, lo, hi)
    scale = data.draw(st.sampled_from([1e-6, 0.1, 1.0, 10.0, 1e3, 1e300]))
    values = data.draw(st.lists(st.floats(-1.0, 1.0), min_size=2 * n, max_size=2 * n))
    desired = scale * np.array(values).reshape(n, 2) * bound
    try:
        res = compensate_scheduled(model, desired, u_min=lo, u_max=hi, max_iterations=5)
    except InvalidArgumentError as err:
        assert "\n" not in str(err) and "beyond what the model can reach" in str(err)
        assert np.any(np.abs(desired) > bound)
        return
    assert np.all(np.isfinite(res.voltage))
    assert np.all((res.voltage >= lo) & (res.voltage <= hi))


@pytest.mark.parametrize("desired, kwargs, message", [
    (np.zeros((10, 2)), {}, "desired must be (N, 3)"),
    (np.zeros((1, 3)), {}, "desired must be (N, 3)"),
    (np.array([[0.0, 0, 0], [0, np.nan, 0]]), {}, "desired[1, 1] is nan"),
    (np.array([[0.0, 0, 0], [0, 0, -np.inf]]), {}, "desired[1, 2] is -inf"),
    (np.full((4, 3), 1e300), {}, "desired[0, 0] = 1e+300 is beyond what the model can reach"),
    ("abc", {}, "desired must be an (N, p) array of numbers"),
    (np.zeros((4, 3)), {"u_min": None}, "u_min is needed"),
    (np.zeros((4, 3)), {"u_max": [1.0, 2.0]}, "u_max: one value or one per input (3)"),
    (np.zeros((4, 3)), {"u_max": np.nan}, "u_max must be finite"),
    (np.zeros((4, 3)), {"u_min": 5.0}, "u_min must be below u_max"),
    (np.zeros((4, 3)), {"tol": 0.0}, "tol must be in (0, 1)"),
    (np.zeros((4, 3)), {"max_iterations": 0}, "max_iterations must be an integer >= 1"),
])
def test_bad_arguments_are_refused_in_one_line(desired, kwargs, message):
    limits = {"u_min": -1.0, "u_max": 1.0, **kwargs}
    with pytest.raises(InvalidArgumentError) as err:
        compensate_scheduled(softening_3x3(), desired, **limits)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_non_square_models_and_slew_are_refused():
    model = softening_3x3()
    narrow = ScheduledStateSpace(model.amplitudes, model.poles, model.c, model.b[:, :, :2],
                                 model.real_poles, model.real_c, model.real_b[:, :, :2],
                                 model.D[:, :, :2], window=WINDOW)
    with pytest.raises(InvalidArgumentError, match="as many inputs as outputs"):
        compensate_scheduled(narrow, np.zeros((4, 3)), u_min=-1, u_max=1)
    with pytest.raises(InvalidArgumentError, match="needs a ScheduledStateSpace"):
        compensate_scheduled(model.at(1.0), np.zeros((4, 3)), u_min=-1, u_max=1)
    with pytest.raises(InvalidArgumentError, match="slew_rate is not supported"):
        compensate_mimo(model, np.zeros((4, 3)), u_min=-1, u_max=1, slew_rate=1.0,
                        sample_period=1.0)


def test_zero_desired_gives_zero_voltage_or_the_nearest_limit():
    model = softening_3x3()
    res = compensate_scheduled(model, np.zeros((8, 3)), u_min=[-1, 0.5, -1], u_max=1.0)
    assert res.voltage[:, 0].tolist() == [0.0] * 8 and np.all(res.voltage[:, 1] == 0.5)
    assert res.saturated


def test_the_bound_holds_for_any_voltages_within_the_limits():
    model = small_model()
    rng = np.random.default_rng(3)
    bound = output_bound(model, [-1.0, -2.0], [1.0, 2.0])
    for _ in range(20):
        u = rng.choice([-1.0, 1.0], size=(60, 2)) * [1.0, 2.0]
        assert np.all(np.abs(model.predict(u)) <= bound)
    assert isinstance(model.at(1.0), StateSpace)
