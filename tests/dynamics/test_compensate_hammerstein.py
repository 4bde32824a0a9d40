"""Hammerstein compensation: ZPETC inverse of the dynamics, hysteresis inverse, limits."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import lfilter, lfilter_zi

from pihyst.dynamics import HammersteinModel, compensate_hammerstein, zpetc
from pihyst.model import ClassicalPI


def mode(r=0.97, theta=0.2):
    return np.poly([r * np.exp(1j * theta), r * np.exp(-1j * theta)]).real


@pytest.mark.parametrize("b", [[0.0, 0.9, 0.5],       # zero inside: exact inverse
                               [0.0, 0.5, 0.9],       # zero outside: zero-phase
                               [0.0, 0.0, 1.0, 0.3]])  # delay of two samples
def test_zpetc_inverts_the_dynamics(b):
    a = mode()
    b = np.array(b) * a.sum() / np.sum(b)               # unit static gain
    t = np.arange(4000)
    ref = 20 + 10 * np.sin(2 * np.pi * t / 400)
    h = zpetc(a, b, ref)
    y, _ = lfilter(b, a, h, zi=lfilter_zi(b, a) * ref[0])   # the plant at rest at ref[0]
    minimum_phase = np.all(np.abs(np.roots(np.trim_zeros(b, "f"))) < 1)
    tol = 1e-9 if minimum_phase else 0.02             # zero phase, gain error at 1/400
    # after the start-up transient of the lightly damped mode (0.97^1000 ~ 6e-14)
    assert np.max(np.abs(y - ref)[1000:-200]) < tol * np.ptp(ref) + 1e-9


def test_a_hammerstein_plant_follows_its_compensation():
    H = ClassicalPI([0, 15, 30, 45], [0.3, 0.25, 0.15, 0.1], input_range=(0.0, 150.0))
    a = mode()
    b = np.array([[0.0, 0.9, 0.5]]) * a.sum() / 1.4
    model = HammersteinModel(hysteresis=(H,), a=(a,), b=(b,))
    t = np.arange(3000)
    ref = 40 + 15 * np.sin(2 * np.pi * t / 300) * np.exp(-t / 3000)
    u, h_d, res = compensate_hammerstein(model, ref)
    assert res.n_saturated == 0
    y = model.predict(u)[:, 0]
    # the model starts at rest at 0, the reference at 40: after that start-up transient
    assert np.max(np.abs(y - ref)[1200:]) < 1e-8 * np.ptp(ref)


@settings(max_examples=25)
@given(desired=st.lists(st.floats(-1e4, 1e4), min_size=5, max_size=200),
       slew=st.one_of(st.none(), st.floats(0.01, 20)), lo=st.floats(0, 60),
       width=st.floats(1, 90))
def test_limits_and_slew_hold_whatever_the_trajectory(desired, slew, lo, width):
    H = ClassicalPI([0, 15, 30], [0.3, 0.2, 0.1], input_range=(0.0, 150.0))
    a = mode()
    model = HammersteinModel(hysteresis=(H,), a=(a,), b=(np.array([[0.0, 0.5, 0.9]]) *
                                                           a.sum() / 1.4,))
    u, _, res = compensate_hammerstein(model, desired, u_min=lo, u_max=lo + width,
                                       slew_rate=slew, sample_period=1.0)
    assert np.all((u >= lo) & (u <= lo + width))
    if slew is not None:
        assert np.all(np.abs(np.diff(np.r_[res.initial_voltage, u])) <= slew)


def test_mimo_models_are_refused():
    H = ClassicalPI([0], [1.0])
    m = HammersteinModel(hysteresis=(H, H), a=(np.r_[1.0],), b=(np.ones((2, 1)),))
    with pytest.raises(ValueError, match="single-input"):
        compensate_hammerstein(m, [1.0, 2.0])
