"""learn_periodic: limits and slew on every trial, accepted trials never worse, undone
trials halve the gain, convergence on linear plants, and the stage targets (slow)."""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from pihyst.dynamics import HammersteinModel
from pihyst.exceptions import InvalidArgumentError
from pihyst.learn import cyclic_steps, learn_periodic
from pihyst.model import ClassicalPI


def _smooth_period(n, amplitudes, phases, mean):
    t = np.arange(n) / n
    return mean + sum(a * np.cos(2 * np.pi * (k + 1) * t + p)
                      for k, (a, p) in enumerate(zip(amplitudes, phases)))


class LinearPlant:
    """y[n] = sum_m g (1 - p) p^m u[n - d - m] in periodic steady state (a first-order lag of
    static gain g after d samples of delay), computed exactly per harmonic; records every
    drive it is sent."""

    def __init__(self, gain, pole, delay, noise=0.0, seed=0):
        self.gain, self.pole, self.delay, self.noise = gain, pole, delay, noise
        self.rng = np.random.default_rng(seed)
        self.sent = []

    def __call__(self, u):
        self.sent.append(np.array(u))
        n = u.size
        z = np.exp(-2j * np.pi * np.arange(n // 2 + 1) / n)
        G = self.gain * (1 - self.pole) / (1 - self.pole * z) * z ** self.delay
        y = np.fft.irfft(G * np.fft.rfft(u), n)
        return y + self.noise * self.rng.standard_normal(n)


@settings(max_examples=40)
# a dead plant with subnormal noise: the probe and the step overflow (found by Hypothesis)
@example(np.array([0., 1, 1, 1, 1, 1, 1, 1]), 0.0, 10.0, None, 0.0, 2.2250738585e-313, 0)
@given(arrays(float, st.integers(8, 64), elements=st.floats(-50, 80)),
       st.floats(0.0, 100.0), st.floats(10.0, 150.0), st.one_of(st.none(), st.floats(1.0, 1e5)),
       st.floats(-2, 2), st.floats(0, 1.0), st.integers(0, 5))
def test_every_trial_is_within_the_limits_and_accepted_trials_never_worsen(
        desired, u_min, width, slew, gain, noise, seed):
    """Whatever the desired period (reachable or not) and the plant (gain of either sign,
    noise up to the signal), no trial leaves the limits or the slew limit round the cycle,
    the accepted trials' errors never grow, an undone trial halves the gain, and the
    result is the best trial."""
    u_max, dt = u_min + width, 1e-4
    plant = LinearPlant(gain, 0.5, 1, noise, seed)
    res = learn_periodic(plant, desired, dt, u_min=u_min, u_max=u_max, slew_rate=slew,
                         trials=5, keep_trials=True)
    assert len(plant.sent) == res.trials
    for u in plant.sent:
        assert np.all(u >= u_min) and np.all(u <= u_max)
        if slew is not None:
            assert np.all(cyclic_steps(u) <= slew * dt)
    kept = res.rms[res.accepted]
    assert np.all(np.diff(kept) <= 0)
    gamma = 1.0
    for j in range(1, res.trials):
        if res.kinds[j] == "probe":
            assert np.isnan(res.gain[j])
            continue
        assert res.kinds[j] == "learn" and res.gain[j] == gamma
        if not res.accepted[j]:
            gamma /= 2
    assert res.rms[res.best_trial] == res.rms.min()
    np.testing.assert_array_equal(res.voltage, plant.sent[res.best_trial])


@settings(max_examples=30)
@given(st.floats(0.1, 1.0), st.floats(0.0, 0.8), st.integers(0, 3),
       st.lists(st.floats(0.2, 1.0), min_size=1, max_size=3),
       st.lists(st.floats(0, 2 * np.pi), min_size=3, max_size=3), st.booleans())
def test_learning_converges_on_a_linear_plant(gain, pole, delay, amps, phases, with_model):
    """Noise-free linear plant, desired within reach: the error falls below a thousandth of
    the starting feedforward's in 10 trials, from no model or from a static linear model
    whose gain is 30 % off."""
    n = 64
    desired = gain * _smooth_period(n, [10 * a for a in amps], phases, 75.0)
    model = ClassicalPI([0.0], [0.7 * gain]) if with_model else None
    res = learn_periodic(LinearPlant(gain, pole, delay), desired, 1e-4, model=model,
                         trials=10)
    assert res.rms[-1] <= 1e-3 * res.rms[0] or res.rms.min() < 1e-9 * gain
    assert res.rms.min() <= 1e-3 * res.rms[0]


def test_a_hammerstein_model_starts_close_and_learns_on():
    """The plant is the model's own resonant second-order dynamics plus a repeating
    disturbance neither model knows: the Hammerstein inverse starts far closer than the
    static model's, and the learning removes the disturbance too."""
    a = np.array([1.0, -1.6, 0.8])
    b = np.array([[0.0, 0.1, 0.1]])
    model = HammersteinModel((ClassicalPI([0.0], [1.0]),), (a,), (b,))
    n = 80
    z = np.exp(-2j * np.pi * np.arange(n // 2 + 1) / n)
    G = (b[0, 1] * z + b[0, 2] * z * z) / (1 + a[1] * z + a[2] * z * z)
    disturbance = 0.5 * np.sin(2 * np.pi * 7 * np.arange(n) / n)

    def plant(u):
        return np.fft.irfft(G * np.fft.rfft(u), n) + disturbance

    desired = _smooth_period(n, [30.0, 5.0, 3.0, 2.0], [0.0, 1.0, 2.0, 3.0], 80.0)
    dyn = learn_periodic(plant, desired, 1e-4, model=model, trials=6)
    static = learn_periodic(plant, desired, 1e-4, model=ClassicalPI([0.0], [1.0]), trials=6)
    assert dyn.rms[0] < 0.5 * static.rms[0]
    assert dyn.rms.min() < 1e-3 * dyn.rms[0]


def test_bad_arguments_say_what_is_wrong():
    plant = LinearPlant(1.0, 0.0, 0)
    with pytest.raises(InvalidArgumentError, match="u_min < u_max"):
        learn_periodic(plant, np.ones(8), 1e-3, u_min=10, u_max=0)
    with pytest.raises(InvalidArgumentError, match="sample_period"):
        learn_periodic(plant, np.ones(8), 0.0)
    with pytest.raises(InvalidArgumentError, match="returned"):
        learn_periodic(lambda u: u[:-1], np.ones(8), 1e-3)


def test_the_stage_target_at_100_hz_from_a_static_model():
    """The resonant stage of the issue (800 Hz, 4 %, one tick of delay, 20 kHz, 0.005 um
    noise) at a 100 Hz band-limited triangle over 80 % of its range, learned from a
    classical PI model fitted to a slow record: within 3 times the noise after 10 trials,
    measured again with the learned voltages (fresh noise)."""
    import pihyst
    from pihyst.sim import make_stage
    from pihyst.sim.signals import band_limited_triangle, decaying_triangles
    stage = make_stage(seed=3)
    stage.hold(72.0)                   # on for long: creep settled near the scan's middle
    _, u = decaying_triangles(0, 150, period_s=1.0, n_triangles=3, dt=5e-3)
    slow = make_stage(seed=4, rate_hz=200.0, modes=((800.0, 0.04),))
    model = pihyst.fit(u, slow.run(u), family="classical").model
    _, desired = band_limited_triangle(4.5, 40.5, period_s=0.01, max_hz=400.0, dt=5e-5)
    res = learn_periodic(stage.run_periodic, desired, 5e-5, model=model, trials=10)
    replay = stage.run_periodic(res.voltage)
    assert np.sqrt(np.mean((replay - desired) ** 2)) <= 3 * 0.005
