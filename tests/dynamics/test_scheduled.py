"""The amplitude-scheduled state-space model and its fit (pihyst.dynamics._scheduled,
_fit_scheduled)."""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pihyst.dynamics import (
    ScheduledStateSpace,
    StateSpace,
    fit_scheduled_state_space,
    fit_state_space,
    running_amplitude,
)
from pihyst.exceptions import InvalidArgumentError


def random_modal(rng, K, P=2, R=1, p=2, m=2, window=50.0, amplitudes=None):
    """A scheduled model with random stable modes at K anchors."""
    radius = rng.uniform(0.3, 0.95, (K, P))
    angle = rng.uniform(0.1, 3.0, (K, P))
    cplx = lambda *s: rng.normal(size=s) + 1j * rng.normal(size=s)   # noqa: E731
    a = np.sort(rng.uniform(0.1, 5.0, K)) + np.arange(K) if amplitudes is None else amplitudes
    return ScheduledStateSpace(a, radius * np.exp(1j * angle), cplx(K, P, p), cplx(K, P, m),
                               rng.uniform(-0.9, 0.9, (K, R)), rng.normal(size=(K, R, p)),
                               rng.normal(size=(K, R, m)), rng.normal(size=(K, p, m)),
                               window=window)


def test_running_amplitude_of_a_sine_is_its_rms():
    u = 3.0 * np.sin(2 * np.pi * np.arange(40000) / 80) + 7.0     # offset removed
    assert running_amplitude(u, 800)[-1] == pytest.approx(3.0 / np.sqrt(2), rel=0.01)
    assert running_amplitude(np.zeros((10, 2)), 5).tolist() == [0.0] * 10


def test_one_anchor_predicts_as_its_state_space_twin():
    """The time-varying modal recursion against the plain matrix recursion."""
    rng = np.random.default_rng(1)
    model = random_modal(rng, K=1)
    u = rng.normal(size=(300, 2))
    lti = model.at(0.0)
    assert isinstance(lti, StateSpace)
    np.testing.assert_allclose(model.predict(u), lti.predict(u), atol=1e-10)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), K=st.integers(1, 4),
       a=st.floats(-1.0, 20.0, allow_nan=False))
def test_at_any_amplitude_is_stable_and_clamped(seed, K, a):
    model = random_modal(np.random.default_rng(seed), K)
    lti = model.at(a)
    assert lti.spectral_radius < 1
    omega = np.array([0.3, 1.1])
    if a <= model.amplitudes[0]:
        end = model.at(model.amplitudes[0])
        np.testing.assert_allclose(lti.response(omega), end.response(omega), rtol=1e-9)
    if a >= model.amplitudes[-1]:
        end = model.at(model.amplitudes[-1])
        np.testing.assert_allclose(lti.response(omega), end.response(omega), rtol=1e-9)


def test_at_an_anchor_is_that_anchors_modes():
    rng = np.random.default_rng(2)
    model = random_modal(rng, K=3)
    z = np.exp(1j * np.array([0.2, 0.9, 2.5]))
    for k, a in enumerate(model.amplitudes):
        T = 1 / (z[:, None] - model.poles[k])
        Tr = 1 / (z[:, None] - model.real_poles[k])
        G = (np.einsum("zq,qj,qi->zji", T, model.c[k], model.b[k])
             + np.einsum("zq,qj,qi->zji", 1 / (z[:, None] - model.poles[k].conj()),
                         model.c[k].conj(), model.b[k].conj())
             + np.einsum("zq,qj,qi->zji", Tr, model.real_c[k], model.real_b[k]) + model.D[k])
        np.testing.assert_allclose(model.at(a).response(np.angle(z)), G, rtol=1e-9)


def test_invalid_models_are_refused():
    rng = np.random.default_rng(3)
    good = random_modal(rng, K=2)
    with pytest.raises(InvalidArgumentError, match="increasing"):
        random_modal(rng, K=2, amplitudes=np.array([2.0, 1.0]))
    with pytest.raises(InvalidArgumentError, match="unit circle"):
        ScheduledStateSpace(good.amplitudes, 1.5j * np.ones((2, 2)), good.c, good.b,
                            good.real_poles, good.real_c, good.real_b, good.D, window=5)
    with pytest.raises(InvalidArgumentError, match="window"):
        ScheduledStateSpace(good.amplitudes, good.poles, good.c, good.b, good.real_poles,
                            good.real_c, good.real_b, good.D, window=0.5)
    with pytest.raises(InvalidArgumentError, match="columns"):
        good.predict(np.zeros((5, 3)))


PERIOD = 256


def multisines(seed, scale, m=2, R=4, periods=2):
    """R random-phase multisine records of m inputs on lines 1..90 of PERIOD."""
    rng = np.random.default_rng(seed)
    t, k = np.arange(periods * PERIOD), np.arange(1, 91)
    return [scale * np.stack([np.cos(2 * np.pi * np.outer(t, k) / PERIOD
                                     + rng.uniform(0, 2 * np.pi, k.size)).sum(axis=1)
                              for _ in range(m)], axis=1) / np.sqrt(k.size / 2)
            for _ in range(R)]


def plant_at(level):
    """A 2 x 2 system whose resonance softens and whose gain rises with the level
    (0 .. 1): the mode's pole moves in radius and angle, its residue grows."""
    radius, angle = 0.97 - 0.01 * level, 0.50 - 0.04 * level
    lam = radius * np.exp(1j * angle)
    A = np.array([[lam.real, -lam.imag, 0.0], [lam.imag, lam.real, 0.0], [0.0, 0.0, 0.6]])
    g = 1.0 + 0.1 * level
    B = g * np.array([[1.0, 0.4], [0.2, -0.7], [0.5, 0.5]])
    C = np.array([[0.3, 0.1, 1.0], [-0.2, 0.4, 0.6]])
    return StateSpace(A, B, C, np.zeros((2, 2)))


def records_at(level, seed):
    """Steady-state records at drive RMS 0.1 + 0.2 level (the plant seen at that level)."""
    plant = plant_at(level)
    out = []
    for u in multisines(seed, 0.1 + 0.2 * level):
        y = plant.predict(np.vstack([u, u]))[u.shape[0]:]     # steady state: played twice
        out.append((u, y))
    return out


def steady_error(model, records):
    err = []
    for u, y in records:
        yh = model.predict(np.vstack([u, u]))[u.shape[0]:]
        err.append(yh - y)
    return float(np.sqrt(np.mean(np.concatenate(err) ** 2)))


def test_fit_recovers_each_level_and_interpolates_between():
    """Fitted at the lowest and highest level, the model recovers both and predicts the
    middle level (not fitted) far better than one linear model of both."""
    low, high = records_at(0.0, 1), records_at(1.0, 2)
    model = fit_scheduled_state_space([high, low], PERIOD, order=3, window=PERIOD,
                                      discard=0, max_nfev=200, penalty=0)
    assert model.amplitudes == pytest.approx([0.1, 0.3], rel=0.05)
    omega = np.linspace(0.05, 3.0, 7)
    for level, a in ((0.0, model.amplitudes[0]), (1.0, model.amplitudes[1])):
        np.testing.assert_allclose(model.at(a).response(omega),
                                   plant_at(level).response(omega), atol=1e-6)
    middle = records_at(0.5, 3)
    joint = fit_state_space(low + high, PERIOD, order=3, discard=0)
    scale = np.sqrt(np.mean(np.concatenate([y for _, y in middle]) ** 2))
    e_sched, e_joint = steady_error(model, middle), steady_error(joint, middle)
    assert e_sched < 0.2 * e_joint
    assert e_sched < 0.02 * scale
    # the default penalty: a little off at the levels, still far better between them
    kept = fit_scheduled_state_space([high, low], PERIOD, order=3, window=PERIOD,
                                     discard=0, max_nfev=200)
    assert steady_error(kept, middle) < 0.2 * e_joint
    assert steady_error(kept, low) < 0.1 * steady_error(joint, low)


def test_fit_needs_two_different_levels():
    low = records_at(0.0, 1)
    with pytest.raises(InvalidArgumentError, match="two levels"):
        fit_scheduled_state_space([low], PERIOD, order=3, discard=0)
    with pytest.raises(InvalidArgumentError, match="differ"):
        fit_scheduled_state_space([low, low], PERIOD, order=3, discard=0)


def test_the_penalty_keeps_the_modes_near_the_common_ones():
    """fit_modes: without penalty the level's system is recovered; with a heavy one the
    parameters stay near the start, and the error lies in between."""
    from pihyst.dynamics import estimate_bla
    from pihyst.dynamics._refine import fit_modes

    start = plant_at(0.0)
    frf = estimate_bla(records_at(1.0, 2), PERIOD, discard=0)
    free = fit_modes(start, frf.omega, frf.G, max_nfev=200)
    held = fit_modes(start, frf.omega, frf.G, max_nfev=200, penalty=1e6)
    some = fit_modes(start, frf.omega, frf.G, max_nfev=200, penalty=1.0)
    assert free[4] < 1e-12 * free[3]
    assert np.max(np.abs(held[2] - held[1])) < 0.01 * np.max(np.abs(free[2] - free[1]))
    assert free[4] < some[4] < held[4] <= held[3]


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), scale=st.floats(1e-6, 1e3),
       sign=st.sampled_from([-1.0, 1.0]), window=st.floats(1.0, 500.0))
def test_running_amplitude_scales_with_the_input(seed, scale, sign, window):
    """a(c u) = |c| a(u), a >= 0, and a constant input has none."""
    u = np.random.default_rng(seed).normal(size=(400, 3))
    a = running_amplitude(u, window)
    assert np.all(a >= 0)
    np.testing.assert_allclose(running_amplitude(sign * scale * u, window), scale * a,
                               rtol=1e-9, atol=1e-12 * scale)
    held = running_amplitude(np.full((400, 3), sign * scale), window)
    # the start from rest, forgotten (to the rounding of the running mean, ulps of it)
    assert held[-1] <= scale * ((1 - 1 / window) ** 200 + 1e-12)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2 ** 32 - 1), p=st.sampled_from([2.0, 1.0, 0.5, 0.0, -1.0]),
       f=st.floats(0.0, 1.0))
def test_the_shape_interpolates_in_a_to_the_p(seed, p, f):
    """Between two anchors the model at a is the anchors' blend with the weight f of the
    upper one where g(a) = (1 - f) g(a_1) + f g(a_2), g = a^p (log a for p = 0): at the
    anchors it is their own system whatever p, and D is exactly the blend."""
    rng = np.random.default_rng(seed)
    lo, hi = rng.uniform(0.05, 1.0), rng.uniform(1.5, 4.0)
    linear = random_modal(rng, K=2, amplitudes=np.array([lo, hi]))
    model = dataclasses.replace(linear, exponent=p)
    g = (lambda a: np.log(a)) if p == 0 else (lambda a: a ** p)     # noqa: E731
    target = (1 - f) * g(lo) + f * g(hi)
    a = np.exp(target) if p == 0 else target ** (1 / p)
    np.testing.assert_allclose(model.at(a).D, (1 - f) * model.D[0] + f * model.D[1],
                               rtol=1e-9, atol=1e-12)
    omega = np.array([0.4, 1.7])
    for end in (lo, hi):
        np.testing.assert_allclose(model.at(end).response(omega),
                                   linear.at(end).response(omega), rtol=1e-9)
    assert model.at(a).spectral_radius < 1


def test_the_shape_moves_the_middle_level_only():
    """log a puts the geometric mean of the anchors half-way and a^1 the arithmetic
    mean; from rest (a = 0) the log shape holds the lowest anchor, no warning."""
    rng = np.random.default_rng(4)
    base = random_modal(rng, K=2, amplitudes=np.array([1.0, 4.0]))
    log = dataclasses.replace(base, exponent=0.0)
    half = (base.D[0] + base.D[1]) / 2
    np.testing.assert_allclose(log.at(2.0).D, half, rtol=1e-12)
    np.testing.assert_allclose(base.at(2.5).D, half, rtol=1e-12)
    np.testing.assert_allclose(log.at(0.0).D, base.D[0], rtol=1e-12)
    u = rng.normal(size=(50, 2))
    assert np.all(np.isfinite(log.predict(u)))
    with pytest.raises(InvalidArgumentError, match="above 0"):
        ScheduledStateSpace(np.array([0.0, 1.0]), base.poles, base.c, base.b, base.real_poles,
            base.real_c, base.real_b, base.D, window=5, exponent=0.0)
    with pytest.raises(InvalidArgumentError, match="finite"):
        dataclasses.replace(base, exponent=float("nan"))


def test_fit_passes_the_exponent_to_the_model():
    low, high = records_at(0.0, 1), records_at(1.0, 2)
    model = fit_scheduled_state_space([low, high], PERIOD, order=3, window=PERIOD,
                                      discard=0, max_nfev=20, exponent=0.5)
    assert model.exponent == 0.5
