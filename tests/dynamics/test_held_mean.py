"""The voltage's mean of the periodic Hammerstein inverse (held_mean,
HammersteinModel.static_offset; docs/theory/hammerstein.md, "The voltage's mean")."""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.signal import lfilter

from pihyst.dynamics import (
    HammersteinModel,
    compensate_hammerstein,
    fit_dynamics,
    held_mean,
    mean_error_share,
)
from pihyst.inverse import compensate
from pihyst.model import ClassicalPI

finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


def worst_mean_error(E, s, x):
    """max over lambda in [0, 1] of |E + s - x - lambda s|: the stage's mean error when x
    of the model's shift s (output units) is held back."""
    return max(abs(E - x), abs(E + s - x))


@settings(max_examples=300, deadline=None)
@given(E=finite, du=st.floats(-5.0, 5.0, allow_nan=False),
       gain=st.floats(0.01, 10.0), seed=st.integers(0, 2 ** 16))
@example(E=0.0, du=1.0, gain=1.0, seed=0)
@example(E=1.0, du=0.0, gain=1.0, seed=0)
def test_the_mean_error_is_never_worse_than_the_static_inverses_for_any_stage_between_the_two(
        E, du, gain, seed):
    """Whatever share lambda of the model's mean shift the stage follows, the mean error
    is at most the static inverse's |E| when g |du| <= 2 |E|, else at most g |du| / 2;
    and the shift held back lies between none and all of it."""
    rng = np.random.default_rng(seed)
    n = 64
    u_static = 50 + 40 * np.sin(2 * np.pi * np.arange(n) / n) + rng.normal(0, 1, n)
    r = gain * (u_static - u_static.mean())
    shape = rng.normal(0, 0.5, n)
    u_ham = u_static + shape - shape.mean() + du
    out = held_mean(u_ham, u_static, r, E)
    g = np.ptp(r) / np.ptp(u_static)
    s = g * (u_ham.mean() - u_static.mean())
    x = g * (u_ham.mean() - out.mean())
    tol = 1e-9 * (1 + abs(E) + abs(s))
    assert min(0, s) - tol <= x <= max(0, s) + tol
    assert np.allclose(out - out.mean(), u_ham - u_ham.mean())      # only the mean moves
    bound = abs(E) if abs(s) <= 2 * abs(E) else abs(s) / 2
    assert worst_mean_error(E, s, x) <= bound + tol


@settings(max_examples=100, deadline=None)
@given(E=finite, lo=st.floats(0.0, 40.0), hi=st.floats(60.0, 150.0),
       du=st.floats(-50.0, 50.0))
def test_the_voltages_stay_within_the_limits(E, lo, hi, du):
    n = 40
    u_static = np.clip(50 + 10 * np.sin(2 * np.pi * np.arange(n) / n), lo, hi)
    u_ham = np.clip(u_static + du, lo, hi)
    out = held_mean(u_ham, u_static, 0.3 * u_static, E, u_min=lo, u_max=hi)
    assert np.all((out >= lo) & (out <= hi))


def test_without_the_measurement_the_voltage_is_the_inverses():
    u = np.array([1.0, 11.0, 21.0, 11.0])
    assert held_mean(u, u - 1, [0.0, 1.0, 2.0, 1.0], None) is u
    flat = np.full(4, 5.0)
    assert np.array_equal(held_mean(u, flat, [0.0, 1.0, 2.0, 1.0], 1.0), u)   # no span


def test_fit_dynamics_records_the_static_models_mean_error_on_the_slow_record():
    H = ClassicalPI([0, 15, 30, 45], [0.3, 0.25, 0.15, 0.1], input_range=(0.0, 150.0))
    a, b = np.poly([0.97 * np.exp(0.2j), 0.97 * np.exp(-0.2j)]).real, np.array([0.0, 0.9])
    b = b * np.sum(a) / np.sum(b)

    def record(n, offset=0.0):
        u = 75 + 60 * np.sin(2 * np.pi * np.arange(n) / n)
        h = H.predict(np.tile(u, 2))[n:] + offset
        return u, lfilter(b, a, np.tile(h, 60))[-n:]
    model = fit_dynamics(H, record(4000, 0.25), [record(n, 0.25) for n in (100, 200, 400)],
                         orders=((2, 2),), validation=None)
    assert model.static_offset == pytest.approx(0.25, abs=1e-6)
    assert fit_dynamics(H, record(4000), [record(100), record(200)], orders=((2, 2),),
                        validation=None, fade=False).static_offset is None


def test_a_stage_whose_mean_follows_the_voltage_is_not_made_worse():
    """The stage's loop is a little straighter than the model's and 3.5 um below it on
    the slow record (the static model off at DC, random stage 7306's case): the
    correction's change of shape moves the inverse's mean voltage, and this stage's mean
    output follows it further from the trajectory (static_offset None: the mean error
    grows at every rate the correction acts at). With the mean held as static_offset
    allows, the whole error is not above the static inverse's at any rate and the mean
    error not above it by more than 0.1 % (the stage's response to the change of shape
    is not exactly between the model's and the mean voltage's)."""
    model_H = ClassicalPI([0, 15, 30, 45], [0.3, 0.25, 0.15, 0.1], input_range=(0.0, 150.0))
    stage_H = ClassicalPI([0, 15, 30, 45], [0.33, 0.2, 0.15, 0.1], input_range=(0.0, 150.0))
    a = np.poly([0.97 * np.exp(0.2j), 0.97 * np.exp(-0.2j)]).real
    b = np.array([0.0, 0.9, 0.5])
    b = b * np.sum(a) / np.sum(b)

    def stage(u):
        n = u.size
        return lfilter(b, a, np.tile(stage_H.predict(np.tile(u, 2))[n:] - 2.0, 60))[-n:]

    def shape(n):
        t = 2 * np.pi * np.arange(n) / n
        return 75 + 60 * np.sin(t) + 8 * np.sin(3 * t)
    slow = (shape(4000), stage(shape(4000)))
    fast = [(shape(n), stage(shape(n))) for n in (100, 200, 250, 400, 500)]
    held = fit_dynamics(model_H, slow, fast, orders=((2, 3),), validation=None)
    assert held.static_offset == pytest.approx(-3.5, abs=0.01)
    moved = HammersteinModel(held.hysteresis, held.a, held.b, held.trusted_from,
                             held.order_trusted_from)
    grew = 0
    for n in (1000, 400, 200, 100, 60):
        r = 0.25 * shape(n) + 2
        u_static = compensate(model_H, np.tile(r, 2), u_min=0.0, u_max=150.0).voltage[n:]
        u_held = compensate_hammerstein(held, r, u_min=0.0, u_max=150.0, periodic=True)[0]
        u_moved = compensate_hammerstein(moved, r, u_min=0.0, u_max=150.0, periodic=True)[0]
        assert np.all((u_held >= 0.0) & (u_held <= 150.0))
        e_static, e_held, e_moved = (stage(u) - r for u in (u_static, u_held, u_moved))
        assert abs(e_held.mean()) <= abs(e_static.mean()) * (1 + 1e-3)
        assert np.sqrt(np.mean(e_held ** 2)) <= np.sqrt(np.mean(e_static ** 2)) * (1 + 1e-9)
        grew += abs(e_moved.mean()) > abs(e_static.mean()) * (1 + 1e-4)
    assert grew == 4                                    # all but the slowest


@settings(max_examples=300, deadline=None)
@given(E=finite, seed=st.integers(0, 2 ** 16), size=st.floats(1e-6, 1e3),
       coupling=st.floats(-1.0, 1.0))
@example(E=0.0, seed=0, size=1.0, coupling=1.0)
def test_the_share_of_the_correction_never_makes_the_error_worse(E, seed, size, coupling):
    """A stage whose static-inverse error is its mean E plus what the correction d = h_d - r
    removes (zero mean), and whose mean output the share W of the correction moves by
    c' W rms(d), |c'| <= MEAN_COUPLING: its RMS error with W is never above the static
    inverse's (docs/theory/hammerstein.md, "The mean error")."""
    from pihyst.dynamics._compensate import MEAN_COUPLING
    rng = np.random.default_rng(seed)
    r = rng.normal(0, 1, 32)
    d = rng.normal(0, 1, 32)
    d = size * (d - d.mean()) / np.sqrt(np.mean((d - d.mean()) ** 2))
    W = mean_error_share(r, r + d, E)
    assert 0.0 <= W <= 1.0
    c = coupling * MEAN_COUPLING
    static = np.sqrt(E ** 2 + np.mean(d ** 2))
    ham = np.sqrt((E + c * W * size) ** 2 + np.mean(((1 - W) * d) ** 2))
    assert ham <= static * (1 + 1e-9) + 1e-12
    if E == 0.0:
        assert W == 1.0                       # nothing at DC to protect: the whole correction


def test_a_coupling_of_0_applies_the_whole_correction_and_a_negative_one_is_refused():
    from pihyst.exceptions import InvalidArgumentError
    r, h = [0.0, 1.0, 2.0, 1.0], [0.1, 1.1, 1.9, 0.9]
    assert mean_error_share(r, h, 100.0, coupling=0.0) == 1.0
    assert mean_error_share(r, h, 100.0) == 0.0
    with pytest.raises(InvalidArgumentError, match="mean_coupling must be >= 0"):
        mean_error_share(r, h, 1.0, coupling=-0.1)
    model = HammersteinModel(hysteresis=(ClassicalPI([0.0, 2.0], [1.0, 0.5]),),
                             a=([1.0, -0.5],), b=([[0.5]],), static_offset=100.0)
    r = 10 + 5 * np.sin(2 * np.pi * np.arange(50) / 50)
    _, h_none, _ = compensate_hammerstein(model, r, periodic=True)
    _, h_all, _ = compensate_hammerstein(model, r, periodic=True, mean_coupling=0.0)
    assert np.array_equal(h_none, r) and not np.allclose(h_all, r)
