"""Simulated stages (pihyst.sim.Stage): modes, converter delay, amplifier slew, the
periodic player, random stages, and the band-limited triangle."""

import numpy as np
import pytest

from pihyst.exceptions import InvalidArgumentError
from pihyst.sim import make_stage, random_plant
from pihyst.sim._lti import modes_filter
from pihyst.sim.signals import band_limited_triangle


def _steady_gain(filt, hz, rate=50_000.0, periods=60):
    """Complex gain of a filter at hz from its steady response to a unit sine."""
    n = int(round(rate / hz))
    t = np.arange(periods * n) / rate
    filt.rest(0.0)
    y = filt.run(np.sin(2 * np.pi * hz * t), t)[-n:]
    ref = np.exp(-2j * np.pi * hz * t[-n:])
    return 2j * np.mean(y * ref)             # Y / X for x = sin = Im exp(i w t)


def test_modes_filter_has_unit_static_gain_and_the_modes_response():
    modes = [(800.0, 0.04, 0.7), (2400.0, 0.02, 0.3)]
    f = modes_filter(modes)
    assert f.dc_gain == pytest.approx(1.0)
    for hz in (200.0, 800.0, 1500.0):
        s = 2j * np.pi * hz
        expected = sum(g * (2 * np.pi * fm) ** 2 / (s * s + 2 * z * 2 * np.pi * fm * s
                                                     + (2 * np.pi * fm) ** 2)
                       for fm, z, g in modes)
        # sample n holds its input over (t[n-1], t[n]]: half a sample ahead
        expected *= np.exp(1j * np.pi * hz / 50_000.0)
        assert abs(_steady_gain(f, hz) / expected - 1) < 0.01


def test_the_converter_delay_shifts_the_response_by_whole_ticks():
    base = make_stage(noise_um=0.0, delay_samples=0, creep=False)
    late = make_stage(noise_um=0.0, delay_samples=3, creep=False)
    u = np.r_[np.zeros(5), np.linspace(0, 120, 200), np.full(100, 120.0)]
    y0, y3 = base.run(u), late.run(u)
    np.testing.assert_allclose(y3[3:], y0[:-3], atol=1e-12)
    assert np.all(y3[:8] == y3[0])


def test_the_amplifier_slew_limit_turns_a_step_into_a_ramp():
    rate, slew = 20_000.0, 1e5                       # 5 V per tick
    limited = make_stage(noise_um=0.0, delay_samples=0, slew_V_per_s=slew, creep=False)
    free = make_stage(noise_um=0.0, delay_samples=0, creep=False)
    step = np.r_[0.0, np.full(99, 100.0)]
    ramp = np.minimum(np.arange(100) * slew / rate, 100.0)
    np.testing.assert_allclose(limited.run(step), free.run(ramp), atol=1e-12)


def test_run_periodic_returns_the_steady_period():
    u = 75 + 50 * np.sin(2 * np.pi * np.arange(200) / 200)
    fresh = make_stage(noise_um=0.0, creep=False).run_periodic(u)   # from rest at 0 V
    steady = make_stage(noise_um=0.0, creep=False).run_periodic(u, periods=40)
    assert fresh.size == 200 and np.ptp(steady) > 20
    # the 75 V jump at the start rings the 800 Hz mode; settle_time_s leaves < 1 % of it
    assert np.max(np.abs(fresh - steady)) < 0.005 * np.ptp(steady)


def test_a_stage_runs_at_its_clock():
    stage = make_stage()
    with pytest.raises(InvalidArgumentError, match="clock"):
        stage.run(np.zeros(3), t=np.array([0.0, 0.1, 0.2]))
    with pytest.raises(InvalidArgumentError, match="delay_samples"):
        make_stage(delay_samples=-1)


def test_random_stages_keep_the_plant_and_add_dynamics_in_range():
    for seed in range(8):
        plain, d_plain = random_plant(seed)
        stage, d = random_plant(seed, dynamics=True)
        assert {k: d[k] for k in d_plain if k != "rate_hz"} == \
            {k: v for k, v in d_plain.items() if k != "rate_hz"}
        assert 100 <= d["modes"][0][0] <= 5000
        assert all(0.01 <= z <= 0.10 for _, z, _ in d["modes"])
        assert 10_000 <= d["rate_hz"] <= 100_000 and d["rate_hz"] >= 10 * d["modes"][0][0]
        assert d["delay_samples"] in (0, 1, 2) and 5e4 <= d["slew_V_per_s"] <= 5e5
        assert type(plain).__name__ == "Plant" and stage.rate_hz == d["rate_hz"]


def test_band_limited_triangle_keeps_the_odd_harmonics_below_the_limit():
    t, x = band_limited_triangle(2.0, 30.0, period_s=0.01, max_hz=400.0, dt=1 / 20_000)
    assert x.size == 200 and x[0] == pytest.approx(2.0) and x.max() == pytest.approx(30.0)
    X = np.abs(np.fft.rfft(x))
    present = np.flatnonzero(X[1:] > 1e-9 * X[1:].max()) + 1
    np.testing.assert_array_equal(present, [1, 3])    # 100 and 300 Hz; 500 Hz is above


def test_a_held_stage_does_not_creep():
    stage = make_stage(noise_um=0.0)
    stage.hold(80.0)
    y = stage.run(np.full(4000, 80.0))
    assert np.ptp(y) < 1e-9 and y[0] > 15
    moved = make_stage(noise_um=0.0)          # from rest at 0 V: the jump rings and creeps
    assert np.ptp(moved.run(np.full(4000, 80.0))[2000:]) > 1e-3


def test_a_stage_settled_on_a_scan_repeats_it():
    u = 75 + 60 * np.sin(2 * np.pi * np.arange(200) / 200)
    drift = []
    for settle in (True, False):
        stage = make_stage(noise_um=0.0)
        if settle:
            stage.settle_on(u)
        first = stage.run_periodic(u)
        drift.append(np.max(np.abs(stage.run_periodic(u, periods=20) - first)))
    # settled: 20 periods later the scan is where it was but for the fast creep lags;
    # started from rest, the creep of the whole scan shows
    assert drift[0] < 3e-4 * np.ptp(first) and drift[1] > 10 * drift[0]
