"""MIMO compensation of a square state-space Hammerstein model for periodic trajectories."""

import numpy as np
import pytest

from pihyst.dynamics import StateSpace, StateSpaceHammerstein, compensate_mimo
from pihyst.model import ClassicalPI


def two_by_two():
    """Two inputs, two outputs, coupled, order 4 (two lightly damped modes)."""
    def block(r, theta):
        return r * np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    A = np.zeros((4, 4))
    A[:2, :2], A[2:, 2:] = block(0.97, 0.2), block(0.95, 0.5)
    B = np.array([[1.0, 0.2], [0.0, 0.1], [0.3, 1.0], [0.1, 0.0]])
    C = np.array([[0.05, 0.02, 0.01, 0.0], [0.01, 0.0, 0.06, 0.03]])
    D = np.array([[0.5, 0.1], [0.05, 0.4]])
    H = tuple(ClassicalPI([0, 15, 30], w, input_range=(0.0, 150.0))
              for w in ([0.6, 0.2, 0.1], [0.5, 0.3, 0.1]))
    return StateSpaceHammerstein(hysteresis=H, dynamics=StateSpace(A, B, C, D))


def test_the_model_follows_its_periodic_compensation():
    model = two_by_two()
    n = 400
    t = np.arange(n)
    u_try = np.column_stack([60 + 40 * np.sin(2 * np.pi * t / n),
                             70 + 30 * np.cos(2 * np.pi * 3 * t / n)])
    desired = model.predict_steady(np.tile(u_try, (3, 1)), n)     # reachable by design
    u, h_d, results = compensate_mimo(model, desired, u_min=0.0, u_max=150.0)
    assert u.shape == (n, 2) and all(r.n_saturated == 0 for r in results)
    y = model.predict_steady(np.tile(u, (3, 1)), n)
    assert np.max(np.abs(y - desired)) < 1e-6 * np.ptp(desired)


def test_limits_hold_per_input_whatever_the_trajectory():
    model = two_by_two()
    rng = np.random.default_rng(1)
    desired = rng.normal(0, 100, size=(64, 2))
    # 5e4 V/s at 1e-4 s per sample: at most 5 V per sample
    u, _, _ = compensate_mimo(model, desired, u_min=[0.0, 10.0], u_max=[100.0, 50.0],
                              slew_rate=5e4, sample_period=1e-4)
    assert np.all((u[:, 0] >= 0) & (u[:, 0] <= 100) & (u[:, 1] >= 10) & (u[:, 1] <= 50))
    assert np.all(np.abs(np.diff(u, axis=0)) <= 5.0 + 1e-9)


@pytest.mark.parametrize("desired, limits, message", [
    (np.zeros((10, 3)), {}, "desired must be (N, 2)"),
    (np.zeros((10, 2)), {"u_min": [0.0, 1.0, 2.0]}, "u_min: one value or one per input (2)"),
])
def test_bad_arguments_are_refused(desired, limits, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        compensate_mimo(two_by_two(), desired, **limits)


def test_non_square_models_are_refused():
    model = two_by_two()
    narrow = StateSpaceHammerstein(hysteresis=model.hysteresis[:1], dynamics=StateSpace(
        model.dynamics.A, model.dynamics.B[:, :1], model.dynamics.C, model.dynamics.D[:, :1]))
    with pytest.raises(ValueError, match="as many inputs as outputs"):
        compensate_mimo(narrow, np.zeros((10, 2)))
